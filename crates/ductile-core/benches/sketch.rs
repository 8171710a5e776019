//! Sketch deformation (Kho & Garland) on a 100,000-vertex region of interest: a closed tube
//! of 600 rings × 200 vertices, the middle 500 rings being the region (the first 50 static,
//! the last 50 rigid), a 100-node reference stroke along the axis and 100-node U-shaped
//! targets.
//!
//! * `sketch/bind` — skinning, rigid virtual vertex, adjacency and the sparse Cholesky
//!   factorisation of the smoothing system (targets: ≤ 500 ms).
//! * `sketch/evaluate` — one re-evaluation after a target-curve change, with smoothing
//!   (targets: ≤ 50 ms).

use std::f32::consts::PI;

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::prelude::*;
use ductile_core::primitives;
use ductile_core::sketch::partition::Partition;
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};
use glam::Vec3;

const RINGS: usize = 600;
const SEGMENTS: usize = 200;
const STEP: f32 = 0.02;

fn tube() -> RestMesh {
    let mesh = primitives::grid(RINGS, SEGMENTS, true, |r, s| {
        let a = 2.0 * PI * s as f32 / SEGMENTS as f32;
        Vec3::new(r as f32 * STEP, 0.3 * a.cos(), 0.3 * a.sin())
    });
    RestMesh::new(mesh, "tube").expect("valid tube")
}

/// A U of length `len` starting at `start` along +x, bending with radius `len / (2 + π)`...
/// scaled by `bend` ∈ (0, 1] (1 = a full half circle), 100 nodes.
fn u_curve(start: Vec3, len: f32, bend: f32) -> Vec<Vec3> {
    let straight = 0.25 * len;
    let arc = len - 2.0 * straight;
    let angle = PI * bend;
    let radius = arc / angle;
    let mut pts = vec![start];
    for k in 1..=20 {
        pts.push(start + Vec3::X * straight * k as f32 / 20.0);
    }
    let c = start + Vec3::new(straight, radius, 0.0);
    for k in 1..=60 {
        let a = angle * k as f32 / 60.0;
        pts.push(c + Vec3::new(radius * a.sin(), -radius * a.cos(), 0.0));
    }
    let end = pts[pts.len() - 1];
    let dir = Vec3::new(angle.cos(), angle.sin(), 0.0);
    for k in 1..=19 {
        pts.push(end + dir * straight * k as f32 / 19.0);
    }
    pts
}

fn layer(rest: &RestMesh, bend: f32) -> Layer {
    let (x0, x1) = (50.0 * STEP, 549.0 * STEP);
    let mut roi = Vec::new();
    let mut rigid = Vec::new();
    for (i, p) in rest.welded_positions().iter().enumerate() {
        if p.x >= x0 - 1e-4 && p.x <= x1 + 1e-4 {
            roi.push(i as u32);
        } else if p.x > x1 {
            rigid.push(i as u32);
        }
    }
    assert_eq!(roi.len(), 100_000);
    let reference = (0..100)
        .map(|k| Vec3::new(x0 + (x1 - x0) * k as f32 / 99.0, 0.0, 0.0))
        .collect();
    Layer::new(
        "sketch",
        Tool::Sketch(Box::new(SketchTool {
            partition: Some(Partition {
                roi,
                rigid: vec![rigid],
            }),
            reference: Curve::Points(reference),
            normal: Some(Vec3::Z),
            mode: SketchMode::Bend {
                target: Curve::Points(u_curve(Vec3::new(x0, 0.0, 0.0), x1 - x0, bend)),
                turning: None,
            },
            scale: None,
            smooth: true,
            refine: None,
        })),
    )
}

fn bench(c: &mut Criterion) {
    let rest = tube();
    let positions = rest.welded_positions().to_vec();
    let layers = [layer(&rest, 1.0), layer(&rest, 0.7)];
    let mut group = c.benchmark_group("sketch");
    group.sample_size(10);
    group.bench_function("bind", |b| {
        b.iter(|| LayerBinding::bind(&layers[0], &positions, rest.topology()).expect("bind"))
    });
    let binding = LayerBinding::bind(&layers[0], &positions, rest.topology()).expect("bind");
    let mut k = 0;
    group.bench_function("evaluate", |b| {
        b.iter(|| {
            k = 1 - k;
            let mut out = positions.clone();
            binding.apply(&layers[k], &mut out).expect("apply");
            out
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
