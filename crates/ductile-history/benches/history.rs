//! History benchmarks.
//!
//! * `replay/10k ops + 1 evaluation`: replay 10,000 mixed operations (macro values,
//!   transforms, layer toggles) on an identikit-like head document — the Lee Perry-Smith
//!   head with 30 FFSD macro tools of 3 points, each limited to its own area — then evaluate
//!   the head once. Target: ≤ 1 s.
//! * `undo+redo/N`: one undo followed by one redo at the end of a history of N steps, for
//!   N = 1,000 and 100,000: the times must be about equal (cost of the operation, not of the
//!   history).
//!
//! Evaluation runs on one thread, as in core's FFSD benchmark.

use std::collections::BTreeMap;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ductile_core::ffsd::{ControlPoint, FfsdMacro, HeightLimit};
use ductile_core::influence::Shape;
use ductile_core::mesh::{Mesh, RestMesh};
use ductile_history::prelude::*;
use ductile_scene::prelude::*;
use glam::Vec3;

const HEAD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../assets/meshes/lee-perry-smith-head.glb"
);
const MACROS: usize = 30;

/// Every triangle primitive of the glTF file, merged into one mesh (node transforms are
/// ignored: the head is a single mesh in its own space).
fn load_head() -> RestMesh {
    let (doc, buffers, _) = gltf::import(HEAD).expect("the head mesh is in assets/meshes");
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let base = positions.len() as u32;
            let p: Vec<Vec3> = reader
                .read_positions()
                .expect("positions")
                .map(Vec3::from)
                .collect();
            let n = p.len() as u32;
            positions.extend(p);
            match reader.read_indices() {
                Some(i) => indices.extend(i.into_u32().map(|i| base + i)),
                None => indices.extend(base..base + n),
            }
        }
    }
    RestMesh::new(
        Mesh {
            positions,
            normals: None,
            uvs: None,
            indices,
        },
        "head",
    )
    .expect("valid head mesh")
}

/// The identikit-like document: mesh "head", macro tools `m0..m29` (macros `f0..f29`), each
/// on its own layer limited to area `a0..a29`, a sphere of 8 % of the head's size around a
/// surface point.
fn head_document(rest: &RestMesh) -> Document {
    let welded = rest.welded_positions();
    let (lo, hi) = ductile_core::mesh::bounds(welded).expect("non-empty");
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).max_element();
    let mut areas = BTreeMap::new();
    let mut macros = BTreeMap::new();
    let mut stack = Vec::new();
    let mut nodes = Vec::new();
    for k in 0..MACROS {
        let v = welded[(k * 7919) % welded.len()];
        let out = (v - centre).normalize_or_zero();
        areas.insert(
            format!("a{k}"),
            Area::Region(vec![RegionShape {
                shape: Shape::Sphere {
                    radius: 0.08 * size,
                },
                transform: Transform::from_translation(v),
            }]),
        );
        let points = (0..3)
            .map(|j| {
                let offset = Vec3::new(0.01 * j as f32, -0.008 * j as f32, 0.0) * size;
                ControlPoint::basic(v + out * 0.05 * size + offset, 0.3, 0.8, 0.05 * size)
            })
            .collect();
        macros.insert(
            format!("f{k}"),
            FfsdMacro {
                label: format!("feature {k}"),
                group: "Bench".to_owned(),
                area: Some(format!("a{k}")),
                points,
                height: Some(HeightLimit::Above { theta: 0.85 }),
                range: (-1.0, 1.0),
            },
        );
        stack.push(LayerSpec {
            influence: Some(InfluenceSpec {
                area: Some(format!("a{k}")),
                ..InfluenceSpec::default()
            }),
            ..LayerSpec::new(format!("m{k}"))
        });
        nodes.push(Node {
            name: format!("m{k}"),
            parent: Some("head".to_owned()),
            transform: Transform::IDENTITY,
            kind: NodeKind::Macro(MacroUse {
                name: format!("f{k}"),
                value: 0.0,
            }),
        });
    }
    nodes.insert(
        0,
        Node {
            name: "head".to_owned(),
            parent: None,
            transform: Transform::IDENTITY,
            kind: NodeKind::Mesh(MeshNode {
                source: "lee-perry-smith-head.glb".to_owned(),
                stack,
                areas,
            }),
        },
    );
    Document { nodes, macros }
}

/// `n` steps: mostly macro slider values, some small macro tool moves, some layer toggles,
/// as recorded by a history (deterministic pseudo-random choice).
fn mixed_history(base: &Document, n: usize) -> History {
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    let mut seed = 0x2545_f491_u32;
    for step in 0..n {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        let k = (seed >> 8) as usize % MACROS;
        let x = ((seed & 0xff) as f32 / 255.0) * 2.0 - 1.0;
        let node = format!("m{k}");
        let op = match seed % 10 {
            0..=5 => Operation::set_macro_value(&doc, &node, x),
            6..=8 => Operation::set_transform(
                &doc,
                &node,
                Transform::from_translation(Vec3::new(0.0, 0.0, 0.002 * x)),
            ),
            _ => {
                let enabled = doc.mesh("head").expect("head").stack[k].enabled;
                Operation::set_layer_enabled(&doc, "head", k, !enabled)
            }
        }
        .expect("valid operation");
        history
            .push(&mut doc, op, "", step as u64, None)
            .expect("accepted");
    }
    history
}

/// A history of `n` slider steps on the head document.
fn slider_history(base: &Document, n: usize) -> (Document, History) {
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    for step in 0..n {
        let node = format!("m{}", step % MACROS);
        let v = (step % 200) as f32 / 100.0 - 1.0;
        let op = Operation::set_macro_value(&doc, &node, v).expect("macro node");
        history
            .push(&mut doc, op, "", step as u64, None)
            .expect("accepted");
    }
    (doc, history)
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let rest = load_head();
    let base = head_document(&rest);
    assert!(base.problems().is_empty(), "{:?}", base.problems());
    let history = mixed_history(&base, 10_000);
    eprintln!(
        "head: {} welded vertices; history of {} steps",
        rest.welded_positions().len(),
        history.len()
    );

    c.bench_function("replay/10k ops, no evaluation", |b| {
        b.iter(|| replay(history.base(), history.entries(), history.len()).expect("replays"));
    });
    c.bench_function("replay/10k ops + 1 evaluation", |b| {
        b.iter(|| {
            let doc = replay(history.base(), history.entries(), history.len()).expect("replays");
            pool.install(|| doc.evaluate("head", &rest).expect("evaluates"))
        });
    });

    let mut group = c.benchmark_group("undo+redo");
    for n in [1_000usize, 100_000] {
        let (mut doc, mut history) = slider_history(&base, n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                history.undo(&mut doc).expect("undo");
                history.redo(&mut doc).expect("redo");
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
