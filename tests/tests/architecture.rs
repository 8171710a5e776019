//! Architecture invariants of the workspace, checked from the crates' manifests and sources.
//!
//! The rules (see `docs/ARCHITECTURE.md`):
//! 1. `ductile-core` depends (normal dependencies) only on [`CORE_ALLOWED`].
//! 2. `ductile-core` and `ductile-scene` never depend on an engine, UI or file-format crate
//!    ([`PURE_FORBIDDEN`]).
//! 3. Only [`ENGINE_CRATES`] depend on bevy / bevy_egui / egui.
//! 4. `ductile-history` (when present) depends only on core, scene and [`HISTORY_ALLOWED`].
//! 5. `ductile-anim` depends only on [`ANIM_ALLOWED`].
//! 6. The sources of `ductile-core`, `ductile-anim`, `ductile-scene` and `ductile-bevy` do no
//!    file I/O (`std::fs`, `File::`).

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::path::Path;

mod common;

/// Normal dependencies `ductile-core` may have: math, serialisation, errors, parallelism, and
/// the numeric/graph crates its solvers use (faer for linear algebra, petgraph for the
/// sketch tool's minimum cut, pulp to pick the SIMD width of the lane kernels when the
/// program runs), and bytemuck for zeroed allocations of plain vectors. (`wide` is only a
/// dev-dependency: the oracle of the lanes' exp and ln.)
const CORE_ALLOWED: &[&str] = &[
    "glam",
    "serde",
    "thiserror",
    "rayon",
    "faer",
    "petgraph",
    "pulp",
    "bytemuck",
];
/// Normal dependencies `ductile-anim` may have: core, math, serialisation, errors, and a
/// portable seeded generator for random variants.
const ANIM_ALLOWED: &[&str] = &["ductile-core", "glam", "serde", "thiserror", "chacha20"];
/// The pure crates: no engine, UI or file-format dependency.
const PURE_CRATES: &[&str] = &["ductile-core", "ductile-anim", "ductile-scene"];
/// Dependencies the pure crates must never have.
const PURE_FORBIDDEN: &[&str] = &["bevy", "egui", "bevy_egui", "gltf", "ron"];
/// Engine and UI crates.
const ENGINE_DEPS: &[&str] = &["bevy", "bevy_egui", "egui", "egui-file-dialog"];
/// The only crates that may depend on [`ENGINE_DEPS`].
const ENGINE_CRATES: &[&str] = &["ductile-bevy", "ductile-studio"];
/// What `ductile-history` may depend on besides core and scene: small pure crates.
const HISTORY_ALLOWED: &[&str] = &[
    "ductile-core",
    "ductile-anim",
    "ductile-scene",
    "serde",
    "thiserror",
    "glam",
];
/// Text that means file I/O in a pure crate's source.
const FILE_IO: &[&str] = &["std::fs", "File::"];

/// A crate's name and its normal (non-dev, non-build) dependency names, including
/// target-specific ones.
struct Manifest {
    name: String,
    deps: Vec<String>,
}

fn dep_names(table: Option<&toml::Value>) -> Vec<String> {
    table
        .and_then(toml::Value::as_table)
        .map(|t| {
            t.iter()
                .map(|(k, v)| {
                    // `alias = { package = "real" }` depends on `real`.
                    v.get("package")
                        .and_then(toml::Value::as_str)
                        .unwrap_or(k)
                        .to_owned()
                })
                .collect()
        })
        .unwrap_or_default()
}

fn parse_manifest(text: &str) -> Manifest {
    let v: toml::Value = toml::from_str(text).expect("valid Cargo.toml");
    let name = v["package"]["name"]
        .as_str()
        .expect("package.name")
        .to_owned();
    let mut deps = dep_names(v.get("dependencies"));
    if let Some(targets) = v.get("target").and_then(toml::Value::as_table) {
        for t in targets.values() {
            deps.extend(dep_names(t.get("dependencies")));
        }
    }
    Manifest { name, deps }
}

/// Every rule broken by a set of manifests, as messages.
fn violations(manifests: &[Manifest]) -> Vec<String> {
    let mut out = Vec::new();
    for m in manifests {
        let has = |d: &str| m.deps.iter().any(|x| x == d);
        if m.name == "ductile-core" {
            for d in &m.deps {
                if !CORE_ALLOWED.contains(&d.as_str()) {
                    out.push(format!(
                        "ductile-core depends on '{d}' (allowed: {CORE_ALLOWED:?})"
                    ));
                }
            }
        }
        if m.name == "ductile-anim" {
            for d in &m.deps {
                if !ANIM_ALLOWED.contains(&d.as_str()) {
                    out.push(format!(
                        "ductile-anim depends on '{d}' (allowed: {ANIM_ALLOWED:?})"
                    ));
                }
            }
        }
        if PURE_CRATES.contains(&m.name.as_str()) {
            for d in PURE_FORBIDDEN.iter().filter(|d| has(d)) {
                out.push(format!("{} depends on '{d}'", m.name));
            }
        }
        if !ENGINE_CRATES.contains(&m.name.as_str()) {
            for d in ENGINE_DEPS.iter().filter(|d| has(d)) {
                out.push(format!("{} depends on engine/UI crate '{d}'", m.name));
            }
        }
        if m.name == "ductile-history" {
            for d in &m.deps {
                if !HISTORY_ALLOWED.contains(&d.as_str()) {
                    out.push(format!(
                        "ductile-history depends on '{d}' (allowed: {HISTORY_ALLOWED:?})"
                    ));
                }
            }
        }
    }
    out
}

/// Every file-I/O use in the `.rs` files under `dir`, as `path:line: text`.
fn file_io_uses(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.extend(file_io_in(
                    &p.display().to_string(),
                    &std::fs::read_to_string(&p).unwrap(),
                ));
            }
        }
    }
    out
}

fn file_io_in(name: &str, text: &str) -> Vec<String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| FILE_IO.iter().any(|f| l.contains(f)))
        .map(|(i, l)| format!("{name}:{}: {}", i + 1, l.trim()))
        .collect()
}

fn workspace_manifests() -> Vec<Manifest> {
    let crates = common::root().join("crates");
    let mut v: Vec<Manifest> = std::fs::read_dir(crates)
        .unwrap()
        .map(|e| e.unwrap().path().join("Cargo.toml"))
        .filter(|p| p.exists())
        .map(|p| parse_manifest(&std::fs::read_to_string(p).unwrap()))
        .collect();
    v.sort_by(|a, b| a.name.cmp(&b.name));
    v
}

#[test]
fn crate_dependencies_follow_the_architecture() {
    let manifests = workspace_manifests();
    assert!(manifests.iter().any(|m| m.name == "ductile-core"));
    assert!(manifests.iter().any(|m| m.name == "ductile-scene"));
    let v = violations(&manifests);
    assert!(v.is_empty(), "architecture rules broken:\n{}", v.join("\n"));
}

#[test]
fn pure_crates_do_no_file_io() {
    let root = common::root();
    let mut uses = file_io_uses(&root.join("crates/ductile-core/src"));
    uses.extend(file_io_uses(&root.join("crates/ductile-anim/src")));
    uses.extend(file_io_uses(&root.join("crates/ductile-scene/src")));
    uses.extend(file_io_uses(&root.join("crates/ductile-bevy/src")));
    assert!(
        uses.is_empty(),
        "file I/O in a pure crate:\n{}",
        uses.join("\n")
    );
}

// The rules themselves must be able to fail: each broken manifest below is caught.

fn manifest(name: &str, deps: &str) -> Manifest {
    parse_manifest(&format!(
        "[package]\nname = \"{name}\"\n[dependencies]\n{deps}\n"
    ))
}

#[test]
fn a_core_dependency_outside_the_allow_list_is_caught() {
    let v = violations(&[manifest(
        "ductile-core",
        "glam = \"0.32\"\nnalgebra = \"0.33\"",
    )]);
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].contains("nalgebra"));
    assert!(violations(&[manifest("ductile-core", "glam = \"0.32\"\nfaer = \"0.22\"")]).is_empty());
}

#[test]
fn format_and_engine_crates_in_pure_crates_are_caught() {
    let v = violations(&[manifest("ductile-scene", "ron = \"0.12\"\ngltf = \"1\"")]);
    assert_eq!(v.len(), 2, "{v:?}");
    let v = violations(&[manifest("ductile-core", "bevy = \"0.19\"")]);
    // Outside the allow-list, forbidden in a pure crate, and an engine crate.
    assert_eq!(v.len(), 3, "{v:?}");
}

#[test]
fn engine_crates_outside_the_app_crates_are_caught() {
    let v = violations(&[manifest("ductile-io", "egui = \"0.33\"")]);
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(
        violations(&[manifest(
            "ductile-studio",
            "bevy = \"0.19\"\nbevy_egui = \"0.39\""
        )])
        .is_empty()
    );
    // Renamed and target-specific dependencies count too.
    let renamed = parse_manifest(
        "[package]\nname = \"ductile-cli\"\n[target.'cfg(unix)'.dependencies]\nui = { package = \"egui\", version = \"0.33\" }\n",
    );
    assert_eq!(violations(&[renamed]).len(), 1);
}

#[test]
fn history_dependencies_are_limited() {
    let ok = manifest(
        "ductile-history",
        "ductile-core = { path = \"x\" }\nserde = \"1\"",
    );
    assert!(violations(&[ok]).is_empty());
    let v = violations(&[manifest("ductile-history", "ductile-io = { path = \"x\" }")]);
    assert_eq!(v.len(), 1, "{v:?}");
}

#[test]
fn anim_dependencies_are_limited() {
    let ok = manifest(
        "ductile-anim",
        "ductile-core = { path = \"x\" }\nchacha20 = \"0.10\"",
    );
    assert!(violations(&[ok]).is_empty());
    // Outside the allow-list and a file-format crate in a pure crate.
    let v = violations(&[manifest("ductile-anim", "ron = \"0.12\"")]);
    assert_eq!(v.len(), 2, "{v:?}");
}

#[test]
fn file_io_in_source_is_caught() {
    assert_eq!(
        file_io_in("a.rs", "let s = std::fs::read(p);\nlet x = 1;").len(),
        1
    );
    assert_eq!(file_io_in("a.rs", "let f = File::open(p);").len(), 1);
    assert!(file_io_in("a.rs", "let profile = 1;").is_empty());
}

/// The names of the crate's own modules that a source file imports (`use crate::m…`,
/// `crate::m::` paths and `super::`).
fn crate_modules_used(source: &str) -> Vec<String> {
    let mut out: Vec<String> = source
        .match_indices("crate::")
        .map(|(i, _)| {
            source[i + "crate::".len()..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect();
    if source.contains("super::") {
        out.push("super".to_owned());
    }
    out.sort();
    out.dedup();
    out
}

#[test]
fn the_chunking_helpers_depend_on_no_other_core_module() {
    let text =
        std::fs::read_to_string(common::root().join("crates/ductile-core/src/chunks.rs")).unwrap();
    // Its own unit tests may use `super::`; the module itself names no other module.
    let code = text.split("#[cfg(test)]").next().unwrap_or_default();
    assert_eq!(crate_modules_used(code), Vec::<String>::new());
    // And the check itself catches an import.
    assert_eq!(
        crate_modules_used("use crate::stack::Stack;\nuse crate::tool::{Tool};"),
        ["stack", "tool"]
    );
}
