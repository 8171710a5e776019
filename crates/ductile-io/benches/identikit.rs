//! Criterion benchmark: the whole identikit library (45 FFSD macros, every one at a non-zero
//! value) evaluated at once, on one thread, on the Lee Perry-Smith head (8,844 welded
//! vertices) and on the MakeHuman base mesh (19,158 vertices) with the library mapped onto
//! its head (the similarity of docs/identikit.md). The stack is resolved once; the timed
//! work is `Stack::evaluate` (with normals) and `Stack::evaluate_welded` (without).
//! Target: median ≤ 2 ms per evaluation on one thread.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::ffsd::PointMode;
use ductile_core::influence::Shape;
use ductile_core::mesh::RestMesh;
use ductile_core::stack::Stack;
use ductile_scene::prelude::*;
use glam::Vec3;

/// The head's mirror plane `x = X0` (docs/identikit.md).
const X0: f32 = -0.09;
/// Head → MakeHuman similarity: `p' = S·(p − HEAD_TIP) + MH_TIP`, with the head's nose tip
/// moved onto the mirror plane (docs/identikit.md, "The identikit on the MakeHuman base mesh").
const S: f32 = 0.5522;
const HEAD_TIP: Vec3 = Vec3::new(X0, 1.0975, 2.5904);
const MH_TIP: Vec3 = Vec3::new(0.0, 6.909, 1.6807);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The head scene with every macro at a non-zero value (the demo's where it sets one,
/// alternately ±0.5 elsewhere).
fn all_macros_set() -> Document {
    let mut doc =
        ductile_io::read_scene(root().join("scenes/identikit-demo.ron")).expect("demo scene");
    let mut k = 0;
    for node in &mut doc.nodes {
        if let NodeKind::Macro(m) = &mut node.kind
            && m.value == 0.0
        {
            m.value = if k % 2 == 0 { 0.5 } else { -0.5 };
            k += 1;
        }
    }
    doc
}

fn to_makehuman(p: Vec3) -> Vec3 {
    (p - HEAD_TIP) * S + MH_TIP
}

/// The library mapped onto the MakeHuman head: points, references and area centres as
/// points, ε (α = 2) and shape sizes scaled by `S`.
fn mapped(mut doc: Document, source: &str) -> Document {
    for m in doc.macros.values_mut() {
        for p in &mut m.points {
            p.position = to_makehuman(p.position);
            if let PointMode::Directional { reference } = &mut p.mode {
                *reference = to_makehuman(*reference);
            }
            p.epsilon *= S.powf(0.5 * p.alpha);
        }
    }
    let mesh = doc.mesh_mut("head").expect("head node");
    mesh.source = source.to_owned();
    for area in mesh.areas.values_mut() {
        if let Area::Region(shapes) = area {
            for s in shapes {
                s.transform.translation = to_makehuman(s.transform.translation);
                s.shape = match &s.shape {
                    &Shape::Sphere { radius } => Shape::Sphere { radius: radius * S },
                    &Shape::Box { half_extents } => Shape::Box {
                        half_extents: half_extents * S,
                    },
                    &Shape::Capsule {
                        radius,
                        half_height,
                    } => Shape::Capsule {
                        radius: radius * S,
                        half_height: half_height * S,
                    },
                    Shape::Tube { points, radii } => Shape::Tube {
                        points: points.iter().map(|&p| p * S).collect(),
                        radii: radii.iter().map(|r| r * S).collect(),
                    },
                };
            }
        }
    }
    doc
}

/// Benchmarks every macro of the library at once, and the paper's Table 1 case of exactly 30
/// macros (the first 30 layers of the stack, in the library's group order).
fn bench_mesh(c: &mut Criterion, name: &str, doc: &Document, rest: &RestMesh) {
    let all: Stack = doc.resolve_stack("head", rest).expect("resolve");
    let thirty = Stack {
        layers: all.layers.iter().take(30).cloned().collect(),
    };
    bench_stack(
        c,
        &format!("{name}/{} macros", all.layers.len()),
        &all,
        rest,
    );
    bench_stack(c, &format!("{name}/30 macros"), &thirty, rest);
}

fn bench_stack(c: &mut Criterion, name: &str, stack: &Stack, rest: &RestMesh) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let active: usize = stack
        .layers
        .iter()
        .filter_map(|l| l.influence.as_ref()?.area.as_ref().map(Vec::len))
        .sum();
    eprintln!(
        "{name}: {} layers, {} welded vertices, {active} area vertices in all",
        stack.layers.len(),
        rest.welded_positions().len()
    );
    // Criterion is not `Send`: enter the one-thread pool inside each timed iteration.
    c.bench_function(&format!("identikit/{name}/evaluate"), |b| {
        b.iter(|| pool.install(|| black_box(stack.evaluate(black_box(rest)).expect("evaluate"))))
    });
    c.bench_function(&format!("identikit/{name}/evaluate_welded"), |b| {
        b.iter(|| {
            pool.install(|| black_box(stack.evaluate_welded(black_box(rest)).expect("evaluate")))
        })
    });
}

fn identikit(c: &mut Criterion) {
    let doc = all_macros_set();
    let load = |file: &str| {
        let path = root().join("assets/meshes").join(file);
        ductile_io::load_rest_mesh(&ductile_io::MeshRef::parse(path.to_str().expect("path")))
            .expect("mesh")
    };
    let head = load("lee-perry-smith-head.glb");
    bench_mesh(c, "lee-perry-smith", &doc, &head);
    let mh_doc = mapped(doc, "../assets/meshes/makehuman-base.obj");
    let mh = load("makehuman-base.obj");
    bench_mesh(c, "makehuman", &mh_doc, &mh);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(4));
    targets = identikit
}
criterion_main!(benches);
