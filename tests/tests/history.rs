//! History files: the golden file keeps loading and replaying to the hand-checked document;
//! save → load → replay round trips (inline and referenced bases) give the live document
//! and bit-identical meshes; a changed base scene is refused; the CLI commands `history`,
//! `replay` and `apply` (with a history) work end to end.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use std::collections::BTreeMap;

use common::{cli, data};
use ductile_core::ffsd::{ControlPoint, FfsdMacro, FfsdTool};
use ductile_core::influence::{Falloff, Shape};
use ductile_core::tool::Tool;
use ductile_history::prelude::*;
use ductile_io::{Base, IoError, SaveBase, read_history, read_scene, save_history, save_scene};
use ductile_scene::prelude::*;
use glam::Vec3;

/// The final document of `tests/data/golden-history.ron`, written out by hand from its
/// steps: the macro value 0.75, the tool moved up and renamed, the corner layer disabled,
/// a ball volume limiting the tool's layer (weight halved and moved on top), and a centre
/// area.
fn golden_final() -> Document {
    let mut areas = BTreeMap::new();
    areas.insert("corner".to_owned(), Area::Vertices(vec![8, 5, 7]));
    areas.insert(
        "centre".to_owned(),
        Area::Region(vec![RegionShape {
            shape: Shape::Box {
                half_extents: Vec3::splat(0.5),
            },
            transform: Transform::IDENTITY,
        }]),
    );
    let tip = LayerSpec {
        weight: 0.5,
        enabled: false,
        influence: Some(InfluenceSpec {
            area: Some("corner".to_owned()),
            ..InfluenceSpec::default()
        }),
        ..LayerSpec::new("tip")
    };
    let puller = LayerSpec {
        weight: 0.5,
        influence: Some(InfluenceSpec {
            volumes: vec!["ball".to_owned()],
            falloff: Falloff::Linear,
            ..InfluenceSpec::default()
        }),
        ..LayerSpec::new("puller")
    };
    let mut macros = BTreeMap::new();
    macros.insert(
        "lift".to_owned(),
        FfsdMacro {
            label: "Lift the corner".to_owned(),
            group: "Test".to_owned(),
            area: Some("corner".to_owned()),
            points: vec![ControlPoint::basic(Vec3::new(1.0, 1.0, 0.4), 0.3, 2.0, 0.5)],
            height: None,
            range: (-1.0, 1.0),
        },
    );
    let node = |name: &str, parent: Option<&str>, transform, kind| Node {
        name: name.to_owned(),
        parent: parent.map(str::to_owned),
        transform,
        kind,
    };
    Document {
        nodes: vec![
            node(
                "grid",
                None,
                Transform::IDENTITY,
                NodeKind::Mesh(MeshNode {
                    source: "golden-grid.obj".to_owned(),
                    stack: vec![tip, puller],
                    areas,
                }),
            ),
            node(
                "puller",
                Some("grid"),
                Transform::from_translation(Vec3::new(0.0, 0.0, 0.25)),
                NodeKind::Tool(Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
                    Vec3::new(0.0, 0.0, 0.5),
                    -0.2,
                    2.0,
                    0.6,
                )]))),
            ),
            node(
                "tip",
                Some("grid"),
                Transform::IDENTITY,
                NodeKind::Macro(MacroUse {
                    name: "lift".to_owned(),
                    value: 0.75,
                }),
            ),
            node(
                "ball",
                Some("grid"),
                Transform::IDENTITY,
                NodeKind::Volume(VolumeNode {
                    shape: Shape::Sphere { radius: 1.2 },
                }),
            ),
        ],
        macros,
        ..Document::default()
    }
}

#[test]
fn golden_history_loads_and_replays_to_the_hand_checked_document() {
    let loaded = read_history(data("golden-history.ron")).unwrap();
    assert!(matches!(loaded.base_source, Base::Inline(_)));
    assert_eq!(loaded.history.len(), 8);
    assert_eq!(loaded.cursor, 8);
    let labels: Vec<&str> = loaded
        .history
        .entries()
        .iter()
        .map(|e| e.label.as_str())
        .collect();
    assert_eq!(labels[0], "lift the corner");
    assert_eq!(labels[7], "define a centre area");
    assert_eq!(loaded.history.base().problems(), vec![]);
    let end = loaded.replay(8).unwrap();
    assert_eq!(end, golden_final());
    // Undoing everything from the end gives the base back.
    let (base, entries, _) = loaded.history.clone().into_parts();
    let mut doc = end.clone();
    let mut history = History::from_entries(base.clone(), entries);
    history.jump(&mut doc, 0).unwrap();
    assert_eq!(doc, base);
    // Step 3 disabled the corner layer; step 2 moved the tool.
    let after2 = loaded.replay(2).unwrap();
    assert_eq!(
        after2.node("pull").unwrap().transform.translation,
        Vec3::new(0.0, 0.0, 0.25)
    );
    assert!(after2.mesh("grid").unwrap().stack[1].enabled);
    // The replayed scene evaluates on its mesh (loaded relative to the history file).
    let scene = loaded.scene(end).unwrap();
    let deformed = scene.evaluate("grid").unwrap();
    assert_eq!(deformed.positions.len(), 9);
    assert!(deformed.positions.iter().all(|p| p.is_finite()));
}

/// The live editing session of the round-trip tests: a few steps on the golden base.
fn session() -> (Document, History) {
    let base = read_history(data("golden-history.ron"))
        .unwrap()
        .history
        .base()
        .clone();
    let mut doc = base.clone();
    let mut history = History::new(base);
    for (k, v) in [0.1f32, 0.2, 0.35].into_iter().enumerate() {
        let op = Operation::set_macro_value(&doc, "tip", v).unwrap();
        history.push(&mut doc, op, "", k as u64, Some(1)).unwrap();
    }
    let op = Operation::set_transform(
        &doc,
        "pull",
        Transform::from_translation(Vec3::new(0.1, -0.05, 0.3)),
    )
    .unwrap();
    history.push(&mut doc, op, "move", 10, None).unwrap();
    let op = Operation::set_layer_weight(&doc, "grid", 0, 0.7).unwrap();
    history.push(&mut doc, op, "weight", 20, None).unwrap();
    (doc, history)
}

fn positions_bits(scene: &ductile_io::LoadedScene) -> Vec<[u32; 3]> {
    scene
        .evaluate("grid")
        .unwrap()
        .positions
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn saved_history_replays_to_the_live_document_with_identical_meshes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("golden-grid.obj"), dir.path().join("golden-grid.obj")).unwrap();
    let (live, history) = session();
    assert_eq!(history.len(), 3, "the slider gesture is one step");
    let live_scene = {
        let path = dir.path().join("live.ron");
        save_scene(&path, &live).unwrap();
        ductile_io::load_scene(&path).unwrap()
    };
    // Inline base.
    let inline = dir.path().join("inline-history.ron");
    save_history(&inline, &history, SaveBase::Inline).unwrap();
    // Referenced base.
    let scene_path = dir.path().join("base.ron");
    save_scene(&scene_path, history.base()).unwrap();
    let referenced = dir.path().join("sub").join("ref-history.ron");
    std::fs::create_dir_all(referenced.parent().unwrap()).unwrap();
    save_history(&referenced, &history, SaveBase::Reference(&scene_path)).unwrap();
    let text = std::fs::read_to_string(&referenced).unwrap();
    assert!(text.contains("path: \"../base.ron\""), "{text}");
    for path in [&inline, &referenced] {
        let loaded = read_history(path).unwrap();
        assert_eq!(loaded.history.entries(), history.entries());
        let end = loaded.replay(loaded.cursor).unwrap();
        assert_eq!(end, live);
        let scene = loaded.scene(end).unwrap();
        assert_eq!(positions_bits(&scene), positions_bits(&live_scene));
        // `apply` takes the history file like a scene.
        let out = dir.path().join("out.glb");
        let (r, _) = cli(&["apply", path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert_eq!(r, Ok(0));
        assert!(out.exists());
    }
}

#[test]
fn a_changed_base_scene_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, history) = session();
    let scene_path = dir.path().join("base.ron");
    save_scene(&scene_path, history.base()).unwrap();
    let path = dir.path().join("history.ron");
    save_history(&path, &history, SaveBase::Reference(&scene_path)).unwrap();
    assert!(read_history(&path).is_ok());
    // The same document rewritten with comments and another layout still matches.
    let text = std::fs::read_to_string(&scene_path).unwrap();
    std::fs::write(&scene_path, format!("// A comment.\n{text}\n")).unwrap();
    assert!(read_history(&path).is_ok());
    // A changed value does not.
    let mut changed = read_scene(&scene_path).unwrap();
    if let NodeKind::Macro(m) = &mut changed.node_mut("tip").unwrap().kind {
        m.value = 0.5;
    }
    save_scene(&scene_path, &changed).unwrap();
    let err = read_history(&path).unwrap_err();
    assert!(matches!(err, IoError::BaseMismatch { .. }), "{err}");
    let message = err.to_string();
    assert!(message.contains("does not match"), "{message}");
    assert!(message.contains("base.ron"), "{message}");
    let (r, _) = cli(&["history", path.to_str().unwrap()]);
    assert!(r.unwrap_err().contains("does not match"));
}

#[test]
fn unknown_history_version_and_broken_steps_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let golden = std::fs::read_to_string(data("golden-history.ron")).unwrap();
    let path = dir.path().join("v9.ron");
    std::fs::write(&path, golden.replace("version: 1,", "version: 9,")).unwrap();
    let err = read_history(&path).unwrap_err();
    assert!(
        matches!(err, IoError::UnsupportedHistoryVersion { found: 9, .. }),
        "{err}"
    );
    // A step whose `old` value does not match is reported with its number and label.
    let path = dir.path().join("stale.ron");
    std::fs::copy(data("golden-grid.obj"), dir.path().join("golden-grid.obj")).unwrap();
    std::fs::write(
        &path,
        golden.replace("old: true, new: false", "old: false, new: true"),
    )
    .unwrap();
    let loaded = read_history(&path).unwrap();
    let err = loaded.replay(8).unwrap_err().to_string();
    assert!(err.contains("step 3"), "{err}");
    assert!(err.contains("disable the corner layer"), "{err}");
    assert!(loaded.replay(2).is_ok());
}

#[test]
fn cli_lists_and_replays_histories() {
    let golden = data("golden-history.ron");
    let (r, out) = cli(&["history", golden.to_str().unwrap()]);
    assert_eq!(r, Ok(0));
    assert!(out.contains("8 steps"), "{out}");
    assert!(
        out.contains("2025-11-21 14:00:00  lift the corner"),
        "{out}"
    );
    assert!(out.contains("*8"), "the saved step is marked: {out}");

    let dir = tempfile::tempdir().unwrap();
    let final_glb = dir.path().join("final.glb");
    let steps = dir.path().join("steps");
    let (r, out) = cli(&[
        "replay",
        golden.to_str().unwrap(),
        "-o",
        final_glb.to_str().unwrap(),
        "--every",
        "3",
        "--out-dir",
        steps.to_str().unwrap(),
    ]);
    assert_eq!(r, Ok(0), "{out}");
    assert!(final_glb.exists());
    let mut written: Vec<String> = std::fs::read_dir(&steps)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(
        written,
        ["step-000003.glb", "step-000006.glb", "step-000008.glb"]
    );
    let (r, _) = cli(&["replay", golden.to_str().unwrap(), "--to", "9"]);
    assert!(r.unwrap_err().contains("past the end"));
    // `apply` on the golden history writes the replayed meshes.
    let applied = dir.path().join("applied.glb");
    let (r, out) = cli(&[
        "apply",
        golden.to_str().unwrap(),
        "-o",
        applied.to_str().unwrap(),
    ]);
    assert_eq!(r, Ok(0), "{out}");
    assert_eq!(
        std::fs::read(&applied).unwrap(),
        std::fs::read(&final_glb).unwrap(),
        "apply and replay write the same file"
    );
}

#[test]
fn check_replays_every_step_of_a_history_file() {
    let golden = data("golden-history.ron");
    let (r, out) = cli(&["check", golden.to_str().unwrap()]);
    assert_eq!(r, Ok(0), "{out}");
    assert!(out.contains("ok"), "{out}");
    // A step that does not replay is named, with its label; the check fails.
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("golden-grid.obj"), dir.path().join("golden-grid.obj")).unwrap();
    let path = dir.path().join("stale.history.ron");
    let text = std::fs::read_to_string(&golden).unwrap();
    std::fs::write(
        &path,
        text.replace("old: true, new: false", "old: false, new: true"),
    )
    .unwrap();
    let (r, out) = cli(&["check", path.to_str().unwrap()]);
    assert_eq!(r, Ok(1), "{out}");
    assert!(
        out.contains("step 3") && out.contains("disable the corner layer"),
        "{out}"
    );
}

/// A generalised-cylinder (tube) volume and a custom spline falloff, made by operations,
/// survive the history file (inline base) and the scene file bit for bit, and limit the
/// layer they were given to: the replayed scene deforms as the live one, and differently
/// from the scene without them.
#[test]
fn a_tube_volume_and_a_spline_falloff_round_trip_through_history_and_scene_files() {
    use ductile_core::spline::SplineControl;
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("golden-grid.obj"), dir.path().join("golden-grid.obj")).unwrap();
    let (mut live, mut history) = session();
    let before = live.clone();
    let tube = Shape::Tube {
        points: vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.3, 0.1),
            Vec3::new(1.0, 0.0, 0.0),
        ],
        radii: vec![0.4, 0.9, 0.3],
    };
    let (op, name) = Operation::add_volume(
        &live,
        Some("grid"),
        "tube",
        tube.clone(),
        Transform::IDENTITY,
        Some(("grid", 0)),
    )
    .unwrap();
    history.push(&mut live, op, "", 30, None).unwrap();
    let mut influence = live.mesh("grid").unwrap().stack[0]
        .influence
        .clone()
        .unwrap();
    assert!(influence.volumes.contains(&name));
    influence.falloff = Falloff::Curve(SplineControl {
        values: vec![0.0, 0.9, 0.2, 1.0],
        degree: 2,
    });
    influence.inner = 0.1;
    let op = Operation::set_layer_influence(&live, "grid", 0, Some(influence.clone())).unwrap();
    history.push(&mut live, op, "", 40, None).unwrap();
    // The history file.
    let path = dir.path().join("tube-history.ron");
    save_history(&path, &history, SaveBase::Inline).unwrap();
    let loaded = read_history(&path).unwrap();
    assert_eq!(loaded.history.entries(), history.entries());
    let end = loaded.replay(loaded.cursor).unwrap();
    assert_eq!(end, live);
    let NodeKind::Volume(v) = &end.node(&name).unwrap().kind else {
        panic!("a volume")
    };
    assert_eq!(v.shape, tube);
    assert_eq!(
        end.mesh("grid").unwrap().stack[0].influence.as_ref(),
        Some(&influence)
    );
    // The scene file.
    let scene_path = dir.path().join("tube.ron");
    save_scene(&scene_path, &live).unwrap();
    assert_eq!(read_scene(&scene_path).unwrap(), live);
    let replayed = loaded.scene(end).unwrap();
    let saved = ductile_io::load_scene(&scene_path).unwrap();
    assert_eq!(positions_bits(&replayed), positions_bits(&saved));
    let without = dir.path().join("without.ron");
    save_scene(&without, &before).unwrap();
    let without = ductile_io::load_scene(&without).unwrap();
    assert_ne!(
        positions_bits(&saved),
        positions_bits(&without),
        "the tube and the falloff change what the layer moves"
    );
}
