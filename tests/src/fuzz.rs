//! Fuzz targets: what the coverage-guided fuzzers under `fuzz/` run on every input, and
//! what `tests/tests/fuzz_corpus.rs` runs on every file of their saved corpus.
//!
//! Each target takes arbitrary bytes and must return without panicking, in bounded time
//! and memory, whatever the bytes are. Errors are fine (that is what hostile input should
//! get); a panic, an abort, a hang or a broken invariant is a bug. The invariants checked
//! besides "no panic":
//!
//! * a document that loads and passes [`Document::problems`] evaluates, on every mesh node,
//!   to finite positions and normals or to an error (never NaN or infinity in the output);
//! * an operation that fails leaves the document as it was, and one that succeeds is undone
//!   exactly by [`Operation::revert`].
//!
//! No target reads or writes a file: mesh sources are replaced by small meshes built here,
//! and a history's base given by reference points into a folder that does not exist.

use std::path::Path;
use std::sync::OnceLock;

use ductile_core::mesh::RestMesh;
use ductile_history::prelude::Operation;
use ductile_io::{MeshFormat, load_rest_mesh_from_bytes};
use ductile_scene::document::Document;

/// Inputs longer than this are skipped: the targets look for bugs in parsing and
/// evaluation, not in the time it takes to parse megabytes (libFuzzer's `-max_len` says the
/// same to the fuzzer).
pub const MAX_INPUT: usize = 64 * 1024;

/// The meshes every document is evaluated on: a tetrahedron and a 12 × 12 grid bent into
/// a shallow dome, both spanning about [-1, 1] (the shipped scenes' tools lie around the
/// origin at that scale or smaller).
fn meshes() -> &'static [RestMesh] {
    static MESHES: OnceLock<Vec<RestMesh>> = OnceLock::new();
    MESHES.get_or_init(|| {
        let tetra = include_bytes!("../data/tetra.obj");
        let mut grid = String::new();
        let n = 12;
        for j in 0..n {
            for i in 0..n {
                let x = -1.0 + 2.0 * i as f32 / (n - 1) as f32;
                let y = -1.0 + 2.0 * j as f32 / (n - 1) as f32;
                let z = 0.3 * (1.0 - 0.5 * (x * x + y * y));
                grid.push_str(&format!("v {x} {y} {z}\n"));
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i + 1;
                let (b, c, d) = (a + 1, a + n, a + n + 1);
                grid.push_str(&format!("f {a} {b} {d}\nf {a} {d} {c}\n"));
            }
        }
        vec![
            load_rest_mesh_from_bytes(tetra, MeshFormat::Obj, "tetra.obj").expect("tetra.obj"),
            load_rest_mesh_from_bytes(grid.as_bytes(), MeshFormat::Obj, "grid.obj")
                .expect("the grid"),
        ]
    })
}

/// Where a fuzzed file claims to live: a folder that does not exist, so that nothing it
/// refers to (a history's base scene, a glTF's external buffer) can be read.
const NOWHERE: &str = "/nonexistent-ductile-fuzz/input";

/// A scene file: parse, check, and evaluate every mesh node at rest, at each key time and
/// with each variant applied, on the small meshes.
pub fn scene(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let path = Path::new(NOWHERE).with_extension("ron");
    let Ok(doc) = ductile_io::parse_scene(text, &path) else {
        return;
    };
    evaluate_everything(&doc);
}

/// A history file: parse (the base checked as a scene), replay every step with the
/// apply/revert invariant, and evaluate the document it ends at.
pub fn history(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let path = Path::new(NOWHERE).with_extension("history.ron");
    let Ok(loaded) = ductile_io::history_file::parse_history(text, &path) else {
        return;
    };
    let mut doc = loaded.history.base().clone();
    for entry in loaded.history.entries() {
        if !apply_checked(&entry.op, &mut doc) {
            return;
        }
    }
    evaluate_everything(&doc);
}

/// A list of operations (RON, `[op, op, ...]`) applied to one of the shipped scenes (the
/// first byte picks which), each checked with the apply/revert invariant; the document
/// they lead to is evaluated.
pub fn operations(data: &[u8]) {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let Some(text) = text(rest) else { return };
    let Ok(ops) = ron::Options::default().from_str::<Vec<Operation>>(text) else {
        return;
    };
    let bases = bases();
    let mut doc = bases[usize::from(pick) % bases.len()].clone();
    for op in &ops {
        if !apply_checked(op, &mut doc) {
            break;
        }
    }
    evaluate_everything(&doc);
}

/// A glTF file (JSON or binary): decode, validate and weld as a scene's mesh is.
pub fn gltf(data: &[u8]) {
    mesh(data, MeshFormat::Gltf, "fuzz.glb");
}

/// An OBJ file: decode, validate and weld as a scene's mesh is.
pub fn obj(data: &[u8]) {
    mesh(data, MeshFormat::Obj, "fuzz.obj");
}

fn mesh(data: &[u8], format: MeshFormat, name: &str) {
    if data.len() > MAX_INPUT {
        return;
    }
    if let Ok(rest) = load_rest_mesh_from_bytes(data, format, name) {
        // A mesh that loads is one the deformers can trust: finite, indices in range.
        let n = rest.mesh().positions.len();
        assert!(
            rest.mesh().positions.iter().all(|p| p.is_finite()),
            "{name}: a non-finite position was accepted"
        );
        assert!(
            rest.mesh().indices.iter().all(|&i| (i as usize) < n),
            "{name}: an index out of range was accepted"
        );
    }
}

/// The shipped scenes, parsed once: the bases the operations target edits.
fn bases() -> &'static [Document] {
    static BASES: OnceLock<Vec<Document>> = OnceLock::new();
    BASES.get_or_init(|| {
        let scenes: [(&str, &str); 6] = [
            (
                "identikit-demo.ron",
                include_str!("../../scenes/identikit-demo.ron"),
            ),
            (
                "lattice-demo.ron",
                include_str!("../../scenes/lattice-demo.ron"),
            ),
            (
                "volume-demo.ron",
                include_str!("../../scenes/volume-demo.ron"),
            ),
            (
                "sketch-demo.ron",
                include_str!("../../scenes/sketch-demo.ron"),
            ),
            (
                "animation-demo.ron",
                include_str!("../../scenes/animation-demo.ron"),
            ),
            (
                "identikit-variants.ron",
                include_str!("../../scenes/identikit-variants.ron"),
            ),
        ];
        scenes
            .iter()
            .map(|(name, text)| {
                ductile_io::parse_scene(text, Path::new(name))
                    .unwrap_or_else(|e| panic!("{name}: {e}"))
            })
            .collect()
    })
}

/// Applies `op` to `doc` and checks the undo invariant; `false` when the operation was
/// refused (and `doc` is unchanged, which is checked too).
fn apply_checked(op: &Operation, doc: &mut Document) -> bool {
    let original = doc.clone();
    if op.apply(doc).is_err() {
        assert!(
            same(doc, &original),
            "a refused operation changed the document: {op:?}"
        );
        return false;
    }
    let mut undone = doc.clone();
    op.revert(&mut undone)
        .unwrap_or_else(|e| panic!("an applied operation cannot be reverted: {e}: {op:?}"));
    assert!(
        same(&undone, &original),
        "revert does not undo the operation exactly: {op:?}"
    );
    true
}

/// Equal as documents (0.0 and -0.0 are the same value: an operation may restore a node
/// written with -0.0 in place of one read as 0.0), or else equal as text (NaN ≠ NaN as a
/// value).
fn same(a: &Document, b: &Document) -> bool {
    let text = |d: &Document| ron::to_string(d).expect("a document serialises");
    a == b || text(a) == text(b)
}

/// Evaluates every mesh node of a document that passes its checks on each small mesh, at
/// rest, at each key time and with each variant applied: the output is finite or an error.
fn evaluate_everything(doc: &Document) {
    if !doc.problems().is_empty() {
        return;
    }
    evaluate_meshes(doc, "at rest");
    for t in doc.animation.key_times().into_iter().take(4) {
        if let Ok(posed) = doc.at(t) {
            evaluate_meshes(&posed, "at a key");
        }
    }
    for (name, variant) in doc.variants.iter().take(3) {
        if let Ok(applied) = doc.with_states(&variant.states) {
            evaluate_meshes(&applied, name);
        }
    }
}

fn evaluate_meshes(doc: &Document, when: &str) {
    for name in doc.mesh_names() {
        for rest in meshes() {
            if let Ok(out) = doc.evaluate(name, rest) {
                assert!(
                    out.positions.iter().all(|p| p.is_finite()),
                    "mesh '{name}' ({when}) evaluated to a non-finite position"
                );
                assert!(
                    out.normals.iter().all(|p| p.is_finite()),
                    "mesh '{name}' ({when}) evaluated to a non-finite normal"
                );
            }
        }
    }
}

fn text(data: &[u8]) -> Option<&str> {
    if data.len() > MAX_INPUT {
        return None;
    }
    std::str::from_utf8(data).ok()
}
