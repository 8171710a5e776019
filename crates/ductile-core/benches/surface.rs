//! Benchmarks of the shape surface on ~100k points: bind (closest surface point, frame and
//! basis values per point) on a planar and on a curved rest surface, and deform, as one
//! stack layer sees them.

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::mesh::Topology;
use ductile_core::surface::{ShapeSurfaceTool, SurfaceEdit, SurfaceFrame};
use ductile_core::tool::{BindInput, Deformer};
use glam::Vec3;
use std::hint::black_box;

/// A 100 × 100 × 10 grid of points through the unit square, `z ∈ [−0.1, 0.1]`.
fn points() -> Vec<Vec3> {
    let mut v = Vec::with_capacity(100 * 100 * 10);
    for i in 0..100 {
        for j in 0..100 {
            for k in 0..10 {
                v.push(Vec3::new(
                    i as f32 / 99.0,
                    j as f32 / 99.0,
                    0.2 * k as f32 / 9.0 - 0.1,
                ));
            }
        }
    }
    v
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let active: Vec<u32> = (0..pts.len() as u32).collect();
    let topo = Topology {
        weld: vec![],
        representative: vec![],
        triangles: vec![],
    };
    let input = BindInput {
        positions: &pts,
        topology: &topo,
        active: &active,
    };
    let mut out = vec![Vec3::ZERO; pts.len()];
    let planar = ShapeSurfaceTool {
        frame: SurfaceFrame {
            origin: Vec3::ZERO,
            u_edge: Vec3::X,
            v_edge: Vec3::Y,
        },
        counts: (4, 4),
        degree: (3, 3),
        rest: Vec::new(),
        moves: vec![SurfaceEdit {
            at: (1, 1),
            offset: Vec3::Z * 0.03,
        }],
        heights: Vec::new(),
    };
    let curved = ShapeSurfaceTool {
        rest: vec![SurfaceEdit {
            at: (2, 1),
            offset: Vec3::Z * 0.1,
        }],
        ..planar.clone()
    };
    for (name, tool) in [("planar", &planar), ("curved", &curved)] {
        tool.validate("bench").unwrap();
        c.bench_function(&format!("surface_{name}_bind_100k"), |b| {
            b.iter(|| black_box(tool.bind(black_box(&input)).unwrap()))
        });
        let bind = tool.bind(&input).unwrap();
        c.bench_function(&format!("surface_{name}_deform_100k"), |b| {
            b.iter(|| tool.deform(&bind, black_box(&pts), &active, &mut out))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
