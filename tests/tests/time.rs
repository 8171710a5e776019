//! Time end to end: keyframes, skeleton-style in-betweens on the real arm, variants, the
//! history of time edits, and the glTF files of `export-anim` and `export-morphs` read back.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use common::{cli, root};
use ductile_anim::key::{Interpolation, Key, sample};
use ductile_anim::value::Value;
use ductile_core::mesh::Deformed;
use ductile_history::operation::Operation;
use ductile_io::{LoadedScene, Project, load_scene};
use ductile_scene::prelude::*;
use glam::Vec3;

fn scene(name: &str) -> LoadedScene {
    load_scene(root().join("scenes").join(name)).unwrap()
}

fn bits(d: &Deformed) -> Vec<[u32; 3]> {
    d.positions
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn length(p: &[Vec3]) -> f32 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// The animation demo's keyed targets of the bend: straight at frame 0, elbow at 90° at 24.
fn arm_keys(s: &LoadedScene) -> Vec<Key> {
    s.document
        .animation
        .track("bend-arm", "mode.target")
        .unwrap()
        .to_vec()
}

fn points(v: &Value) -> Vec<Vec3> {
    match v {
        Value::PlaneCurve { points, .. } => points.clone(),
        other => panic!("not a plane curve: {other:?}"),
    }
}

/// The limb test, on the curve the tool bends along: halfway between the straight
/// arm and the arm bent 90° at the elbow, the skeleton-style in-between keeps the arm's
/// length within 1 %, where a lerp of the curve's points shortens it by more than 5 %.
#[test]
fn a_limb_bent_90_degrees_keeps_its_length_halfway() {
    let s = scene("animation-demo.ron");
    let keys = arm_keys(&s);
    let (a, b) = (points(&keys[0].value), points(&keys[1].value));
    let rest_length = length(&a);
    assert!((length(&b) - rest_length).abs() < 1e-4);
    for interpolation in [Interpolation::Linear, Interpolation::Smooth] {
        let mut two = keys[..2].to_vec();
        two[0].interpolation = interpolation;
        let mid = 0.5 * (two[0].time + two[1].time);
        let skeleton = points(&sample(&two, mid).unwrap());
        let kept = length(&skeleton) / rest_length;
        assert!((kept - 1.0).abs() < 0.01, "{interpolation:?}: {kept}");
    }
    let lerped: Vec<Vec3> = a.iter().zip(&b).map(|(p, q)| p.lerp(*q, 0.5)).collect();
    let shortened = 1.0 - length(&lerped) / rest_length;
    assert!(shortened > 0.05, "a lerp shortens the arm by {shortened}");
}

/// The same on the deformed mesh. The arm's centre line is measured as the centroids of thin
/// slices of the arm across each reference node, followed through the deformation. The bend
/// itself changes that length a little (the Eq. 9 smoothing spreads the turn around the
/// elbow: +4.7 % at 90°), so the in-between at frame 12 is compared with the two keyed
/// frames: it stays within 1 % of their mean, while a target made by lerping the keys'
/// points makes the arm more than 5 % shorter than either key.
#[test]
fn the_bent_arm_mesh_keeps_its_length_at_the_middle_frame() {
    let s = scene("animation-demo.ron");
    let doc = &s.document;
    let body = s.mesh("body").unwrap();
    let rest = body.rest.welded_positions();
    let keys = arm_keys(&s);
    let reference = points(&keys[0].value);
    // The welded vertices of a thin slice of the arm across each reference node.
    let slices: Vec<Vec<usize>> = (0..reference.len())
        .map(|k| {
            let a = reference[k.saturating_sub(1)];
            let b = reference[(k + 1).min(reference.len() - 1)];
            let dir = (b - a).normalize();
            (0..rest.len())
                .filter(|&i| {
                    let d = rest[i] - reference[k];
                    d.dot(dir).abs() < 0.06 && d.length() < 0.6
                })
                .collect()
        })
        .collect();
    assert!(
        slices.iter().all(|s| s.len() >= 8),
        "{:?}",
        slices.iter().map(Vec::len).collect::<Vec<_>>()
    );
    let centroids = |positions: &dyn Fn(usize) -> Vec3| -> Vec<Vec3> {
        slices
            .iter()
            .map(|s| s.iter().map(|&i| positions(i)).sum::<Vec3>() / s.len() as f32)
            .collect()
    };
    let topo = body.rest.topology();
    let welded = |d: &Deformed| -> Vec<Vec3> {
        centroids(&|w| d.positions[topo.representative[w] as usize])
    };
    let rest_len = length(&centroids(&|w| rest[w]));
    let mid_time = 12.0 / doc.animation.fps;
    let skeleton = doc
        .at(mid_time)
        .unwrap()
        .evaluate("body", &body.rest)
        .unwrap();
    let at_key = |t: f32| {
        length(&welded(
            &doc.at(t).unwrap().evaluate("body", &body.rest).unwrap(),
        ))
    };
    let (k0, k1) = (at_key(0.0), at_key(1.0));
    let mean = 0.5 * (k0 + k1);
    let mid = length(&welded(&skeleton));
    assert!(
        (mid / mean - 1.0).abs() < 0.01,
        "skeleton-style: {mid} vs keys {k0}, {k1}"
    );
    // The same frame with the target lerped point by point.
    let lerped: Vec<Vec3> = reference
        .iter()
        .zip(points(&keys[1].value))
        .map(|(p, q)| p.lerp(q, 0.5))
        .collect();
    let mut linear = doc.at(mid_time).unwrap();
    let normal = match &keys[0].value {
        Value::PlaneCurve { normal, .. } => *normal,
        _ => unreachable!(),
    };
    linear
        .set_channel(
            "bend-arm",
            "mode.target",
            &Value::PlaneCurve {
                points: lerped,
                normal,
            },
        )
        .unwrap();
    let lerp_mesh = linear.evaluate("body", &body.rest).unwrap();
    let shortened = 1.0 - length(&welded(&lerp_mesh)) / k0.min(k1);
    assert!(shortened > 0.05, "lerped target: shortened by {shortened}");
    assert!(
        (k0 / rest_len - 1.0).abs() < 1e-5,
        "frame 0 is the rest pose"
    );
}

#[test]
fn keys_are_hit_exactly_on_the_mesh() {
    let s = scene("animation-demo.ron");
    let doc = &s.document;
    let body = &s.mesh("body").unwrap().rest;
    // At frame 24 the document is the key's state bit for bit.
    let at = doc.at(1.0).unwrap();
    assert_eq!(
        points(&at.channel("bend-arm", "mode.target").unwrap()),
        points(&arm_keys(&s)[1].value)
    );
    assert_eq!(
        at.channel("swell", "points[0].gamma").unwrap(),
        Value::Scalar(0.35)
    );
    // Frame 0 is the rest pose of the scene file.
    assert_eq!(
        bits(&doc.at(0.0).unwrap().evaluate("body", body).unwrap()),
        bits(&doc.evaluate("body", body).unwrap())
    );
}

#[test]
fn variants_blend_to_themselves_at_0_and_1_bit_for_bit() {
    let s = scene("identikit-variants.ron");
    let doc = &s.document;
    let head = &s.mesh("head").unwrap().rest;
    let mesh_of = |states: &std::collections::BTreeMap<String, NodeState>| {
        doc.with_states(states)
            .unwrap()
            .evaluate("head", head)
            .unwrap()
    };
    let a = mesh_of(&doc.variants["suspect-a"].states);
    let b = mesh_of(&doc.variants["suspect-b"].states);
    let at0 = mesh_of(&doc.blend_two("suspect-a", "suspect-b", 0.0).unwrap().states);
    let at1 = mesh_of(&doc.blend_two("suspect-a", "suspect-b", 1.0).unwrap().states);
    assert_eq!(bits(&at0), bits(&a));
    assert_eq!(bits(&at1), bits(&b));
    assert_ne!(bits(&a), bits(&b));
    // The same seed gives the same face; another seed another.
    let opts = |seed| RandomOptions {
        seed,
        spread: 0.8,
        asymmetry: Some(0.1),
    };
    let sources = ["suspect-a", "suspect-b", "suspect-c", "suspect-d"];
    let r1 = doc.random_variant(&sources, &opts(7)).unwrap();
    assert_eq!(r1, doc.random_variant(&sources, &opts(7)).unwrap());
    assert_ne!(
        r1.states,
        doc.random_variant(&sources, &opts(8)).unwrap().states
    );
}

/// A history with keys, interpolation changes, a saved, a random and an applied variant,
/// saved and reopened: replaying it gives the live document, and bit-identical meshes at
/// every frame.
#[test]
fn a_history_of_time_edits_replays_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("v.ron");
    std::fs::copy(root().join("scenes/identikit-variants.ron"), &scene_path).unwrap();
    // The scene's mesh source is relative to scenes/: point it at the asset.
    let text = std::fs::read_to_string(&scene_path).unwrap().replace(
        "../assets/meshes/lee-perry-smith-head.glb",
        root()
            .join("assets/meshes/lee-perry-smith-head.glb")
            .to_str()
            .unwrap(),
    );
    std::fs::write(&scene_path, text).unwrap();
    let (mut p, _) = Project::open(&scene_path).unwrap();
    let push = |p: &mut Project, op: Operation| {
        let label = op.describe();
        p.push(op, label, 0, None).unwrap();
    };
    let op = Operation::apply_variant(p.document(), "suspect-a").unwrap();
    push(&mut p, op);
    let op = Operation::key_current(p.document(), "nose-length", "value", 0.0).unwrap();
    push(&mut p, op);
    let op = Operation::set_key(
        p.document(),
        "nose-length",
        "value",
        Key::new(1.0, Value::Scalar(-0.6)),
    );
    push(&mut p, op);
    let op = Operation::set_key(
        p.document(),
        "jaw-width",
        "value",
        Key::new(0.5, Value::Scalar(0.9)),
    );
    push(&mut p, op);
    let op = Operation::set_interpolation(
        p.document(),
        "nose-length",
        "value",
        0.0,
        Interpolation::Linear,
    )
    .unwrap();
    push(&mut p, op);
    let random = p
        .document()
        .random_variant(
            &["suspect-b", "suspect-c"],
            &RandomOptions {
                seed: 11,
                ..RandomOptions::default()
            },
        )
        .unwrap();
    let op = Operation::put_variant(p.document(), "witness-1", Some(random));
    push(&mut p, op);
    let op =
        Operation::set_macro_value_symmetric(p.document(), "left-ear-protrusion", 0.4).unwrap();
    push(&mut p, op);
    let op = Operation::save_variant(p.document(), "suspect-e");
    push(&mut p, op);
    let op = Operation::rename_variant("suspect-e", "suspect-a2");
    push(&mut p, op);
    let live = p.document().clone();
    p.save().unwrap();
    let (q, _) = Project::open(dir.path().join("v.history.ron")).unwrap();
    assert_eq!(q.document(), &live);
    let head = load_scene(&scene_path).unwrap().meshes[0].rest.clone();
    for frame in [0.0_f32, 6.0, 12.0, 24.0, 30.0] {
        let t = frame / live.animation.fps;
        let a = live.at(t).unwrap().evaluate("head", &head).unwrap();
        let b = q.document().at(t).unwrap().evaluate("head", &head).unwrap();
        assert_eq!(bits(&a), bits(&b), "frame {frame}");
    }
}

fn read_glb(path: &std::path::Path) -> gltf::Document {
    gltf::Gltf::from_slice(&std::fs::read(path).unwrap())
        .unwrap()
        .document
}

#[test]
fn export_anim_writes_targets_and_a_weights_animation() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("arm.glb");
    let scene = root().join("scenes/animation-demo.ron");
    let (r, text) = cli(&[
        "export-anim",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--fps",
        "12",
    ]);
    assert_eq!(r, Ok(0), "{text}");
    // Frames 0..=48 at 12 samples/s over 2 s: 25 samples, the keys among them.
    assert!(text.contains("sampled 25 times"), "{text}");
    let doc = read_glb(&out);
    let mesh = doc.meshes().next().unwrap();
    let prim = mesh.primitives().next().unwrap();
    let targets = prim.morph_targets().count();
    assert!((2..=25).contains(&targets), "{targets}");
    assert!(
        text.contains(&format!("mesh 'body': {targets} morph targets")),
        "{text}"
    );
    assert_eq!(mesh.weights().unwrap().len(), targets);
    let names = mesh.extras().as_ref().unwrap().get();
    assert!(names.contains("targetNames"), "{names}");
    let anim = doc.animations().next().unwrap();
    let channel = anim.channels().next().unwrap();
    assert_eq!(
        channel.target().property(),
        gltf::animation::Property::MorphTargetWeights
    );
    let sampler = channel.sampler();
    assert_eq!(sampler.input().count(), 25);
    assert_eq!(sampler.output().count(), 25 * targets);
    assert_eq!(
        sampler.interpolation(),
        gltf::animation::Interpolation::Linear
    );
    // One file per frame.
    let frames = dir.path().join("frames");
    let (r, text) = cli(&[
        "export-anim",
        scene.to_str().unwrap(),
        "--frames",
        frames.to_str().unwrap(),
        "--from",
        "20",
        "--to",
        "24",
    ]);
    assert_eq!(r, Ok(0), "{text}");
    assert_eq!(std::fs::read_dir(&frames).unwrap().count(), 5);
}

#[test]
fn export_morphs_writes_one_named_target_per_variant() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("faces.glb");
    let scene = root().join("scenes/identikit-variants.ron");
    let (r, text) = cli(&[
        "export-morphs",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r, Ok(0), "{text}");
    let doc = read_glb(&out);
    let mesh = doc.meshes().next().unwrap();
    assert_eq!(mesh.primitives().next().unwrap().morph_targets().count(), 4);
    let names = mesh.extras().as_ref().unwrap().get().to_owned();
    for v in ["suspect-a", "suspect-b", "suspect-c", "suspect-d"] {
        assert!(names.contains(v), "{names}");
    }
    assert!(text.contains("suspect-a + suspect-b: max"), "{text}");
}

#[test]
fn bad_time_input_gets_a_clear_error() {
    let anim = root().join("scenes/animation-demo.ron");
    let variants = root().join("scenes/identikit-variants.ron");
    let (a, v) = (anim.to_str().unwrap(), variants.to_str().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.glb");
    let o = out.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (
            &["apply", a, "--frame", "49", "-o", o],
            "frame 49 is outside the timeline (frames 0 to 48)",
        ),
        (
            &["export-anim", a, "-o", o, "--from", "0", "--to", "60"],
            "frame 60 is outside the timeline",
        ),
        (
            &[
                "export-anim",
                a,
                "-o",
                o,
                "--fps",
                "240",
                "--tolerance",
                "0",
            ],
            "more than 256 morph targets",
        ),
        (
            &[
                "blend",
                v,
                "--variants",
                "suspect-a,nobody",
                "--t",
                "0.5",
                "-o",
                o,
            ],
            "no variant named 'nobody'",
        ),
        (
            &[
                "blend",
                v,
                "--weights",
                "suspect-a=0.5,suspect-b=0.6",
                "-o",
                o,
            ],
            "must sum to 1",
        ),
        (&["export-anim", v, "-o", o], "no animation"),
    ];
    for (args, expected) in cases {
        let (r, _) = cli(args);
        let e = r.unwrap_err();
        assert!(e.contains(expected), "{args:?}: {e}");
    }
    assert!(!out.exists(), "a failed export leaves no file");
}

#[test]
fn variants_are_listed_one_per_line() {
    let v = root().join("scenes/identikit-variants.ron");
    let (r, text) = cli(&["variants", v.to_str().unwrap()]);
    assert_eq!(r, Ok(0));
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split('\t').next().unwrap())
        .collect();
    assert_eq!(names, ["suspect-a", "suspect-b", "suspect-c", "suspect-d"]);
}

/// Keys whose values cannot be interpolated (a spline control with another number of values)
/// make the track step, and `ductile check` says so without failing.
#[test]
fn check_warns_where_a_track_steps() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = load_scene(root().join("scenes/animation-demo.ron"))
        .unwrap()
        .document;
    if let Some(NodeKind::Tool(ductile_core::tool::Tool::Sketch(t))) = doc
        .nodes
        .iter_mut()
        .find(|n| n.name == "bend-arm")
        .map(|n| &mut n.kind)
        && let ductile_core::sketch::tool::SketchMode::Bend { turning, .. } = &mut t.mode
    {
        *turning = Some(ductile_core::sketch::tool::SplineControl::identity(4, 3));
    }
    let track = doc.animation.tracks.get_mut("bend-arm").unwrap();
    track.insert(
        "mode.turning.values".to_owned(),
        vec![
            Key::new(0.0, Value::Values(vec![0.0, 0.3, 0.7, 1.0])),
            Key::new(1.0, Value::Values(vec![0.0, 0.5, 1.0])),
        ],
    );
    // Mesh sources are relative to the scene file: write it where the original is read from.
    let path = dir.path().join("steps.ron");
    let text = ductile_io::scene::scene_to_string(&doc).unwrap().replace(
        "../assets/meshes/",
        &format!("{}/", root().join("assets/meshes").display()),
    );
    std::fs::write(&path, text).unwrap();
    let (r, out) = cli(&["check", path.to_str().unwrap()]);
    assert_eq!(r, Ok(0), "{out}");
    assert!(
        out.contains("'bend-arm' / 'mode.turning.values': keys 0 (at 0 s, a list of spline values of 4) and 1 (at 1 s, a list of spline values of 3) cannot be interpolated; the track steps there"),
        "{out}"
    );
    assert!(out.ends_with("ok\n"), "{out}");
}
