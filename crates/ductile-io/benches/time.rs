//! Criterion benchmark: time (issue 12's speed targets).
//!
//! * `anim/identikit-30-keyed/export-48` — sampling and exporting a 48-frame animation of
//!   the identikit head (8,844 welded vertices) with 30 keyed macros (keys at frames 0, 24 and
//!   48, smooth): all 49 frames evaluated with one incremental evaluator, baked into morph
//!   targets and written as `.glb`. Target ≤ 1 s. `…/sample-48` times the sampling alone.
//! * `anim/limb/frame` — one frame of `scenes/animation-demo.ron` (MakeHuman's arm bent by
//!   keyed sketch-bend targets, 13,380 welded vertices), after the first bind: the document
//!   posed at the next frame and the mesh brought up to date. Target ≤ 20 ms per frame.
//! * `anim/head-221k-30-keyed/frame` — one frame of Studio playback of that animation on
//!   the head split 5×5 (221,052 welded vertices, as in the authoring benchmark): the
//!   document posed at the next frame ([`Document::pose_at`], what the Studio's timeline
//!   does) and the incremental evaluator brought up to date. Issue 16 asks that playback
//!   keeps the display rate.
//! * `variants/blend-two/…` — blending two suspects of `scenes/identikit-variants.ron` and
//!   evaluating the head: `full` blends and runs a fresh `Document::evaluate` (what
//!   `ductile blend` does), `scrub` moves an A/B slider: the blend written into a working copy
//!   and the incremental evaluator brought up to date. `states` is the blend alone. Target
//!   ≤ 2 ms.
//!
//! The rayon pool is the default one (both cores of the reference machine).

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_anim::key::Key;
use ductile_anim::value::Value;
use ductile_core::mesh::RestMesh;
use ductile_core::primitives::subdivided_n;
use ductile_io::LoadedScene;
use ductile_io::bake::{BakeOptions, export_animation};
use ductile_scene::prelude::*;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scene(name: &str) -> LoadedScene {
    ductile_io::load_scene(root().join("scenes").join(name)).expect("scene")
}

/// The identikit head with 30 of its macros keyed at frames 0, 24 and 48.
fn keyed_head() -> LoadedScene {
    let mut s = scene("identikit-head.ron");
    let fps = s.document.animation.fps;
    let names: Vec<String> = s
        .document
        .nodes
        .iter()
        .filter(|n| matches!(n.kind, NodeKind::Macro(_)))
        .map(|n| n.name.clone())
        .take(30)
        .collect();
    assert_eq!(names.len(), 30);
    for (k, name) in names.iter().enumerate() {
        let v = |frame: f32, x: f32| Key::new(frame / fps, Value::Scalar(x));
        let a = if k % 2 == 0 { 0.6 } else { -0.5 };
        s.document
            .animation
            .tracks
            .entry(name.clone())
            .or_default()
            .insert(
                "value".to_owned(),
                vec![v(0.0, 0.0), v(24.0, a), v(48.0, -0.5 * a)],
            );
    }
    assert!(s.document.problems().is_empty());
    s
}

fn anim(c: &mut Criterion) {
    let head = keyed_head();
    let dir = tempfile::tempdir().expect("temporary directory");
    let out = dir.path().join("head.glb");
    let options = BakeOptions::timeline(&head.document);
    c.bench_function("anim/identikit-30-keyed/export-48", |b| {
        b.iter(|| {
            black_box(export_animation(&head, &out, &options, &mut |_, _| {}).expect("export"))
        })
    });
    c.bench_function("anim/identikit-30-keyed/sample-48", |b| {
        let doc = &head.document;
        let rest = head.meshes[0].rest.clone();
        b.iter(|| {
            let mut ev = MeshEvaluator::new("head", rest.clone());
            let mut posed = doc.clone();
            for f in 0..=48 {
                posed
                    .pose_at(doc, f as f32 / doc.animation.fps)
                    .expect("pose");
                ev.update(&posed).expect("update");
            }
            black_box(ev.deformed().map(|d| d.positions.len()))
        })
    });

    let big = RestMesh::new(
        subdivided_n(head.meshes[0].rest.mesh(), 5),
        "head split 5×5",
    )
    .expect("subdivided head");
    let doc = &head.document;
    let mut ev = MeshEvaluator::new("head", big);
    let mut posed = doc.clone();
    ev.update(&posed).expect("first bind");
    let mut frame = 0;
    c.bench_function("anim/head-221k-30-keyed/frame", |b| {
        b.iter(|| {
            frame = frame % 48 + 1;
            posed
                .pose_at(doc, frame as f32 / doc.animation.fps)
                .expect("pose");
            black_box(ev.update(&posed).expect("update"))
        })
    });

    let limb = scene("animation-demo.ron");
    let doc = &limb.document;
    let rest = limb.mesh("body").expect("body").rest.clone();
    let mut ev = MeshEvaluator::new("body", rest);
    let mut posed = doc.clone();
    ev.update(&posed).expect("first bind");
    let binds = ev.binds();
    let mut frame = 0;
    let mut frames = 0_usize;
    c.bench_function("anim/limb/frame", |b| {
        b.iter(|| {
            frame = frame % 48 + 1;
            frames += 1;
            posed
                .pose_at(doc, frame as f32 / doc.animation.fps)
                .expect("pose");
            black_box(ev.update(&posed).expect("update"))
        })
    });
    // Only the FFSD layer above the bend is bound again (its γ is keyed), never the
    // sketch's region of interest, skinning or Eq. 9 factor: one binding per frame.
    eprintln!(
        "anim/limb/frame: {} bindings in {frames} frames after the first",
        ev.binds() - binds
    );
}

fn variants(c: &mut Criterion) {
    let s = scene("identikit-variants.ron");
    let doc = &s.document;
    let rest = s.mesh("head").expect("head").rest.clone();
    let mut t = 0.25_f32;
    c.bench_function("variants/blend-two/full", |b| {
        b.iter(|| {
            t = 1.0 - t;
            let v = doc.blend_two("suspect-a", "suspect-b", t).expect("blend");
            let d = doc.with_states(&v.states).expect("states");
            black_box(d.evaluate("head", &rest).expect("evaluate"))
        })
    });
    c.bench_function("variants/blend-two/states", |b| {
        b.iter(|| {
            t = 1.0 - t;
            let v = doc.blend_two("suspect-a", "suspect-b", t).expect("blend");
            black_box(doc.with_states(&v.states).expect("states"))
        })
    });
    let mut ev = MeshEvaluator::new("head", rest.clone());
    ev.update(doc).expect("first update");
    let mut working = doc.clone();
    c.bench_function("variants/blend-two/scrub", |b| {
        b.iter(|| {
            t = 1.0 - t;
            let v = doc.blend_two("suspect-a", "suspect-b", t).expect("blend");
            working.set_states(&v.states).expect("states");
            black_box(ev.update(&working).expect("update"))
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(4));
    targets = anim, variants
}
criterion_main!(benches);
