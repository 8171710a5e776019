//! Format stability (issue 14): `tests/data/golden/` holds one golden scene file
//! (`scene-vN.ron`) and one golden history file (`history-vN.history.ron`) for every format
//! version this build reads, and these tests hold every build to four rules:
//!
//! * every golden file loads, passes `ductile check` and evaluates; a history replays every
//!   step;
//! * an old version migrates to the document its newer twin holds, less what the newer
//!   version added (the newer golden files describe the same scene and the same steps, plus
//!   what only the newer version can hold);
//! * a document read from an old file is saved in the current version, and reads back equal;
//! * a file of a version newer than this build is refused with a message naming the file
//!   and the version, never half read.
//!
//! A format change raises its version and adds a golden file of the new version here; the
//! golden files already here are never edited (`docs/scene-format.md`, "Versions and
//! migration"; `docs/history-format.md`, "Versioning and migration"). The older version 1
//! history `tests/data/golden-history.ron` is checked step by step against a hand-written
//! document in `history.rs`.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use std::path::PathBuf;

use common::{cli, data};
use ductile_core::mesh::Deformed;
use ductile_io::error::SUPPORTED_VERSIONS;
use ductile_io::history_file::{HISTORY_VERSION, SUPPORTED_HISTORY_VERSIONS};
use ductile_io::scene::CURRENT_VERSION;
use ductile_io::{
    Base, IoError, SaveBase, check_history, check_scene, load_scene, read_history, read_scene,
    save_history, save_scene,
};
use ductile_scene::prelude::*;
use glam::Vec3;

/// A file of `tests/data/golden/`.
fn golden(name: &str) -> PathBuf {
    data("golden").join(name)
}

/// The golden scene file of format version `version`.
fn scene_file(version: u64) -> PathBuf {
    golden(&format!("scene-v{version}.ron"))
}

/// The golden history file of format version `version`.
fn history_file(version: u64) -> PathBuf {
    golden(&format!("history-v{version}.history.ron"))
}

/// The text of `path`; a missing golden file names itself.
fn read_text(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The nodes `scene-v2.ron` holds besides the scene of `scene-v1.ron`: a mesh with a soloed
/// layer, a tube volume and a curve falloff, which came with version 2.
const ADDED_IN_V2: [&str; 3] = ["tetra", "tube", "squeeze"];

/// `doc` without what the version 2 golden files add to the version 1 ones: the animation,
/// the variants and the nodes of [`ADDED_IN_V2`]. A version 1 golden file migrates to
/// exactly this.
fn as_version_1(doc: &Document) -> Document {
    let mut d = doc.clone();
    d.nodes.retain(|n| !ADDED_IN_V2.contains(&n.name.as_str()));
    d.animation = Animation::default();
    d.variants.clear();
    d
}

/// The format version a file's text declares: the value of its first `version:` line.
fn declared_version(text: &str) -> u64 {
    text.lines()
        .find_map(|l| l.trim_start().strip_prefix("version:"))
        .and_then(|v| v.trim().trim_end_matches(',').parse().ok())
        .unwrap_or_else(|| panic!("no `version:` line in:\n{text}"))
}

/// `text` with its `version:` line set to `version`.
fn with_version(text: &str, version: u64) -> String {
    let mut done = false;
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            if !done && l.trim_start().starts_with("version:") {
                done = true;
                format!("    version: {version},")
            } else {
                l.to_owned()
            }
        })
        .collect();
    assert!(done, "no `version:` line in:\n{text}");
    lines.join("\n")
}

/// The versions as the error messages list them: "1, 2".
fn listed(versions: &[u64]) -> String {
    versions
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The bits of every deformed position, to compare evaluations exactly.
fn bits(d: &Deformed) -> Vec<[u32; 3]> {
    d.positions
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn every_format_version_has_its_golden_files() {
    // The newest version read is the one written, and each version read has a golden file
    // that declares it: adding a version without its golden files fails here.
    assert_eq!(SUPPORTED_VERSIONS.last(), Some(&CURRENT_VERSION));
    assert_eq!(SUPPORTED_HISTORY_VERSIONS.last(), Some(&HISTORY_VERSION));
    for &v in SUPPORTED_VERSIONS {
        let path = scene_file(v);
        assert_eq!(declared_version(&read_text(&path)), v, "{}", path.display());
    }
    for &v in SUPPORTED_HISTORY_VERSIONS {
        let path = history_file(v);
        assert_eq!(declared_version(&read_text(&path)), v, "{}", path.display());
    }
}

#[test]
fn golden_scenes_load_check_and_evaluate() {
    for &v in SUPPORTED_VERSIONS {
        let path = scene_file(v);
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let problems: Vec<String> = check_scene(&path).iter().map(ToString::to_string).collect();
        assert!(problems.is_empty(), "{problems:?}");
        let (r, out) = cli(&["check", path.to_str().unwrap()]);
        assert_eq!(r, Ok(0), "{}: {out}", path.display());
        for mesh in &scene.meshes {
            let deformed = scene.evaluate(&mesh.name).unwrap();
            assert!(
                deformed.positions.iter().all(|p| p.is_finite()),
                "{}: mesh '{}'",
                path.display(),
                mesh.name
            );
        }
        // The tools move the flat grid out of its plane: the golden scene does deform.
        let grid = scene.evaluate("grid").unwrap();
        assert!(
            grid.positions.iter().any(|p| p.z != 0.0),
            "{}",
            path.display()
        );
    }
}

#[test]
fn a_version_1_scene_migrates_to_the_version_2_document() {
    let v1 = read_scene(scene_file(1)).unwrap();
    let v2 = read_scene(scene_file(2)).unwrap();
    // Migration gives the default timeline, no tracks and no variants, and keeps the rest.
    assert_eq!(v1.animation, Animation::default());
    assert!(v1.variants.is_empty());
    assert_eq!(v1, as_version_1(&v2));
    // What the version 2 file adds is all there.
    assert_eq!(
        v2.animation.timeline(),
        Timeline {
            fps: 30.0,
            start: 0,
            end: 60
        }
    );
    let tracks: Vec<(&str, &str)> = v2.animation.iter().map(|(n, p, _)| (n, p)).collect();
    assert_eq!(
        tracks,
        [
            ("ball", "radius"),
            ("pull", "points[0].gamma"),
            ("rig", "transform.rotation"),
            ("tip", "value"),
        ]
    );
    let variants: Vec<&str> = v2.variants.keys().map(String::as_str).collect();
    assert_eq!(variants, ["drawn", "halfway", "lifted"]);
    assert!(matches!(
        v2.variants["drawn"].origin,
        Some(Origin::Random { seed: 7, .. })
    ));
    let tetra = v2.mesh("tetra").unwrap();
    assert!(tetra.stack[0].solo && !tetra.stack[1].solo);
    // Both versions deform the grid they share to the same bits.
    let s1 = load_scene(scene_file(1)).unwrap();
    let s2 = load_scene(scene_file(2)).unwrap();
    assert_eq!(
        bits(&s1.evaluate("grid").unwrap()),
        bits(&s2.evaluate("grid").unwrap())
    );
}

#[test]
fn a_version_1_scene_is_read_with_the_version_1_layout() {
    // The version decides the layout: the fields version 2 added are unknown fields in a
    // file that says it is version 1, not silently read.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene-v2-as-v1.ron");
    std::fs::write(&path, with_version(&read_text(&scene_file(2)), 1)).unwrap();
    let err = read_scene(&path).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, IoError::Ron { .. }), "{message}");
    assert!(
        message.starts_with(&path.display().to_string())
            && message.contains("Unexpected field named `animation`"),
        "{message}"
    );
}

#[test]
fn saving_an_old_scene_writes_the_current_version() {
    let dir = tempfile::tempdir().unwrap();
    for &v in SUPPORTED_VERSIONS {
        let golden_text = read_text(&scene_file(v));
        let doc = read_scene(scene_file(v)).unwrap();
        let out = dir.path().join(format!("saved-v{v}.ron"));
        save_scene(&out, &doc).unwrap();
        let text = read_text(&out);
        assert_eq!(declared_version(&text), CURRENT_VERSION, "{text}");
        assert_eq!(read_scene(&out).unwrap(), doc, "version {v}");
        // Reading never rewrites the old file.
        assert_eq!(read_text(&scene_file(v)), golden_text);
    }
}

#[test]
fn a_scene_of_a_newer_version_is_refused_naming_the_file_and_the_version() {
    let next = CURRENT_VERSION + 1;
    let dir = tempfile::tempdir().unwrap();
    for &v in SUPPORTED_VERSIONS {
        let path = dir.path().join(format!("scene-v{v}-as-v{next}.ron"));
        std::fs::write(&path, with_version(&read_text(&scene_file(v)), next)).unwrap();
        let err = read_scene(&path).unwrap_err();
        assert!(
            matches!(&err, IoError::UnsupportedVersion { found, .. } if *found == next),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            format!(
                "{}: scene format version {next} is not supported (supported versions: {})",
                path.display(),
                listed(SUPPORTED_VERSIONS)
            )
        );
        assert!(load_scene(&path).is_err());
        // `ductile check` fails with the same message.
        let (r, out) = cli(&["check", path.to_str().unwrap()]);
        assert_eq!(r, Ok(1), "{out}");
        assert!(
            out.contains(&format!("scene format version {next} is not supported")),
            "{out}"
        );
    }
}

#[test]
fn golden_histories_load_and_replay_every_step() {
    for &v in SUPPORTED_HISTORY_VERSIONS {
        let path = history_file(v);
        let loaded = read_history(&path).unwrap_or_else(|e| panic!("{e}"));
        let end = loaded.replay(loaded.history.len()).unwrap();
        assert_eq!(end.problems(), vec![], "{}", path.display());
        let problems: Vec<String> = check_history(&path)
            .iter()
            .map(ToString::to_string)
            .collect();
        assert!(problems.is_empty(), "{problems:?}");
        let (r, out) = cli(&["check", path.to_str().unwrap()]);
        assert_eq!(r, Ok(0), "{}: {out}", path.display());
        // The replayed scene evaluates on its meshes (relative to the base's file).
        let scene = loaded.scene(loaded.replay(loaded.cursor).unwrap()).unwrap();
        for mesh in &scene.meshes {
            let deformed = scene.evaluate(&mesh.name).unwrap();
            assert!(deformed.positions.iter().all(|p| p.is_finite()));
        }
    }
}

#[test]
fn a_version_1_history_replays_to_the_documents_of_its_version_2_twin() {
    let v1 = read_history(history_file(1)).unwrap();
    let v2 = read_history(history_file(2)).unwrap();
    // Version 1 refers to `scene-v1.ron` by path and hash; version 2 holds the document of
    // `scene-v2.ron` inline.
    assert!(
        matches!(&v1.base_source, Base::Reference { path, .. } if path == "scene-v1.ron"),
        "{:?}",
        v1.base_source
    );
    assert_eq!(v1.history.base(), &read_scene(scene_file(1)).unwrap());
    assert!(matches!(v2.base_source, Base::Inline(_)));
    assert_eq!(v2.history.base(), &read_scene(scene_file(2)).unwrap());
    // Version 2 records the same steps first, then steps only version 2 can hold.
    let n = v1.history.len();
    assert_eq!((n, v1.cursor), (16, 16));
    assert_eq!(&v2.history.entries()[..n], v1.history.entries());
    // Step by step, the version 1 file gives the version 2 file's document less what
    // version 2 added.
    for step in 0..=n {
        assert_eq!(
            v1.replay(step).unwrap(),
            as_version_1(&v2.replay(step).unwrap()),
            "step {step}"
        );
    }
}

#[test]
fn the_version_2_history_replays_its_time_steps() {
    let loaded = read_history(history_file(2)).unwrap();
    assert_eq!((loaded.history.len(), loaded.cursor), (27, 26));
    let saved = loaded.replay(loaded.cursor).unwrap();
    // Two keys on the added slab, the second moved from 1.5 s to 2 s.
    assert_eq!(
        saved.animation.track("slab", "half_extents"),
        Some(
            &[
                Key::new(0.5, Value::Vector(Vec3::new(1.5, 1.5, 0.5))),
                Key::new(2.0, Value::Vector(Vec3::new(1.5, 1.5, 0.25))),
            ][..]
        )
    );
    // The tip's track replaced, the timeline changed, a group of two keys.
    assert_eq!(
        saved.animation.track("tip", "value"),
        Some(
            &[
                Key {
                    time: 0.0,
                    value: Value::Scalar(0.0),
                    interpolation: Interpolation::Step,
                },
                Key::new(2.0, Value::Scalar(1.0)),
            ][..]
        )
    );
    assert_eq!(
        saved.animation.timeline(),
        Timeline {
            fps: 24.0,
            start: 12,
            end: 96
        }
    );
    assert_eq!(saved.animation.track("ball", "radius").unwrap().len(), 3);
    assert_eq!(
        saved.animation.track("rig", "transform.translation"),
        Some(&[Key::new(0.0, Value::Vector(Vec3::new(0.0, 0.0, 0.1)))][..])
    );
    // The rename of step 8 took the tool's track and variant state with it.
    assert!(saved.animation.track("puller", "points[0].gamma").is_some());
    assert!(saved.animation.track("pull", "points[0].gamma").is_none());
    // A variant saved, one renamed, one deleted.
    let variants: Vec<&str> = saved.variants.keys().map(String::as_str).collect();
    assert_eq!(variants, ["halfway", "raised", "sunk"]);
    let raised: Vec<&str> = saved.variants["raised"]
        .states
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(raised, ["puller", "tip"]);
    // The tetra's layer is no longer soloed.
    assert!(!saved.mesh("tetra").unwrap().stack[0].solo);
    // The undone last step is still there to redo: a third key on the tip's track.
    let end = loaded.replay(loaded.history.len()).unwrap();
    assert_eq!(end.animation.track("tip", "value").unwrap().len(), 3);
}

#[test]
fn saving_an_old_history_writes_the_current_version() {
    let dir = tempfile::tempdir().unwrap();
    for &v in SUPPORTED_HISTORY_VERSIONS {
        let loaded = read_history(history_file(v)).unwrap();
        // The history at the file's saved step, so that the cursor is written too.
        let mut history = loaded.history.clone();
        let mut doc = loaded.replay(history.len()).unwrap();
        history.jump(&mut doc, loaded.cursor).unwrap();
        let out = dir.path().join(format!("saved-v{v}.history.ron"));
        save_history(&out, &history, SaveBase::Inline).unwrap();
        let text = read_text(&out);
        assert_eq!(declared_version(&text), HISTORY_VERSION, "{text}");
        let back = read_history(&out).unwrap();
        assert_eq!(back.history.base(), loaded.history.base(), "version {v}");
        assert_eq!(
            back.history.entries(),
            loaded.history.entries(),
            "version {v}"
        );
        assert_eq!(back.cursor, loaded.cursor, "version {v}");
        assert_eq!(back.replay(back.cursor).unwrap(), doc, "version {v}");
    }
}

#[test]
fn a_history_of_a_newer_version_is_refused_naming_the_file_and_the_version() {
    let next = HISTORY_VERSION + 1;
    let dir = tempfile::tempdir().unwrap();
    for &v in SUPPORTED_HISTORY_VERSIONS {
        let path = dir
            .path()
            .join(format!("history-v{v}-as-v{next}.history.ron"));
        std::fs::write(&path, with_version(&read_text(&history_file(v)), next)).unwrap();
        let err = read_history(&path).unwrap_err();
        assert!(
            matches!(&err, IoError::UnsupportedHistoryVersion { found, .. } if *found == next),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            format!(
                "{}: history format version {next} is not supported (supported versions: {})",
                path.display(),
                listed(SUPPORTED_HISTORY_VERSIONS)
            )
        );
        // `ductile check` and `ductile history` fail with the same message.
        let (r, out) = cli(&["check", path.to_str().unwrap()]);
        assert_eq!(r, Ok(1), "{out}");
        let refused = format!("history format version {next} is not supported");
        assert!(out.contains(&refused), "{out}");
        let (r, _) = cli(&["history", path.to_str().unwrap()]);
        assert!(r.unwrap_err().contains(&refused));
    }
}

#[test]
fn a_version_1_history_holding_version_2_operations_is_refused() {
    // The layout of the two versions is the same, so the time and variant operations used to
    // be read from a file that says version 1, which docs/history-format.md rules out.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("history-v2-as-v1.history.ron");
    std::fs::write(&path, with_version(&read_text(&history_file(2)), 1)).unwrap();
    let err = read_history(&path).unwrap_err();
    assert!(
        matches!(&err, IoError::OperationTooNew { step, .. } if *step > 1),
        "{err}"
    );
    assert!(
        err.to_string()
            .contains("which came with history version 2"),
        "{err}"
    );
}
