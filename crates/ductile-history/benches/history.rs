//! History benchmarks.
//!
//! * `replay/10k ops + 1 evaluation`: replay 10,000 mixed operations (macro values,
//!   transforms, layer toggles) on the identikit scene `scenes/identikit-head.ron` (the Lee
//!   Perry-Smith head with its FFSD macro tools, each limited to an area), then evaluate the
//!   head once. Target: ≤ 1 s.
//! * `undo+redo/N`: one undo followed by one redo at the end of a history of N steps, for
//!   N = 1,000 and 100,000: the times must be about equal (cost of the operation, not of the
//!   history).
//!
//! Evaluation runs on one thread, as in core's FFSD benchmark.

use std::collections::BTreeMap;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ductile_core::ffsd::FfsdMacro;
use ductile_core::mesh::{Mesh, RestMesh};
use ductile_history::prelude::*;
use ductile_scene::prelude::*;
use glam::Vec3;

const HEAD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../assets/meshes/lee-perry-smith-head.glb"
);
const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenes/identikit-head.ron"
);

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

/// The scene file layout (version 1): the document's fields and `version`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[allow(dead_code)]
    version: u64,
    #[serde(default)]
    nodes: Vec<Node>,
    #[serde(default)]
    macros: BTreeMap<String, FfsdMacro>,
}

/// The identikit scene `scenes/identikit-head.ron`: the head with its macro tools, each on
/// its own layer limited to a named area.
fn identikit_document() -> Document {
    let text = std::fs::read_to_string(SCENE).expect("scenes/identikit-head.ron");
    let file: SceneFile = ron::from_str(&text).expect("a version 1 scene");
    Document {
        nodes: file.nodes,
        macros: file.macros,
        ..Document::default()
    }
}

/// `n` steps: mostly macro slider values, some small macro tool moves, some layer toggles,
/// as recorded by a history (deterministic pseudo-random choice).
fn macro_nodes(doc: &Document) -> Vec<String> {
    doc.nodes
        .iter()
        .filter(|n| matches!(n.kind, NodeKind::Macro(_)))
        .map(|n| n.name.clone())
        .collect()
}

fn mixed_history(base: &Document, n: usize) -> History {
    let macros = macro_nodes(base);
    let layers = base.mesh("head").expect("head").stack.len();
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    let mut seed = 0x2545_f491_u32;
    for step in 0..n {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        let k = (seed >> 8) as usize;
        let x = ((seed & 0xff) as f32 / 255.0) * 2.0 - 1.0;
        let node = &macros[k % macros.len()];
        let op = match seed % 10 {
            0..=5 => Operation::set_macro_value(&doc, node, x),
            6..=8 => Operation::set_transform(
                &doc,
                node,
                Transform::from_translation(Vec3::new(0.0, 0.0, 0.002 * x)),
            ),
            _ => {
                let k = k % layers;
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
    let macros = macro_nodes(base);
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    for step in 0..n {
        let node = &macros[step % macros.len()];
        let v = (step % 200) as f32 / 100.0 - 1.0;
        let op = Operation::set_macro_value(&doc, node, v).expect("macro node");
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
    let base = identikit_document();
    assert!(base.problems().is_empty(), "{:?}", base.problems());
    let history = mixed_history(&base, 10_000);
    eprintln!(
        "head: {} welded vertices, {} layers; history of {} steps",
        rest.welded_positions().len(),
        base.mesh("head").expect("head").stack.len(),
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
