//! Benchmarks of the axial (AxDf) and curve (De Boor) deformations on ~100k points: bind
//! (closest axis point and local frame per point) and deform (per-point evaluation with the
//! bind), single-threaded, as one stack layer sees them.

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::axial::{AxialTool, AxisPoint, AxisShape};
use ductile_core::curve::{CurveBasis, CurveEvaluator, CurveTool};
use ductile_core::curve_pieces::CurvePieces;
use ductile_core::mesh::Topology;
use ductile_core::tool::{BindInput, Deformer};
use glam::Vec3;
use std::hint::black_box;

/// A 100 × 32 × 32 grid of points around the x axis (x ∈ [0, 2], |y|, |z| ≤ 0.4).
fn points() -> Vec<Vec3> {
    let mut v = Vec::with_capacity(100 * 32 * 32);
    for i in 0..100 {
        for j in 0..32 {
            for k in 0..32 {
                v.push(Vec3::new(
                    2.0 * i as f32 / 99.0,
                    0.8 * j as f32 / 31.0 - 0.4,
                    0.8 * k as f32 / 31.0 - 0.4,
                ));
            }
        }
    }
    v
}

fn spine(count: usize) -> Vec<Vec3> {
    (0..count)
        .map(|i| Vec3::new(2.0 * i as f32 / (count - 1) as f32, 0.0, 0.0))
        .collect()
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

    for (name, shape) in [
        ("polyline", AxisShape::Polyline),
        ("bspline3", AxisShape::BSpline { degree: 3 }),
    ] {
        let rest: Vec<AxisPoint> = spine(8).into_iter().map(AxisPoint::at).collect();
        let mut deformed = rest.clone();
        for (k, p) in deformed.iter_mut().enumerate().skip(4) {
            p.position += Vec3::new(0.0, 0.1 * (k - 3) as f32, 0.0);
            p.twist = 0.2 * (k - 3) as f32;
            p.scale = 1.1;
        }
        let tool = AxialTool {
            shape,
            deformed,
            ..AxialTool::new(rest, 1.0)
        };
        tool.validate("bench").unwrap();
        c.bench_function(&format!("axial_{name}_bind_100k"), |b| {
            b.iter(|| black_box(tool.bind(black_box(&input)).unwrap()))
        });
        let bind = tool.bind(&input).unwrap();
        c.bench_function(&format!("axial_{name}_deform_100k"), |b| {
            b.iter(|| tool.deform(&bind, black_box(&pts), &active, &mut out))
        });
    }

    let rest = spine(8);
    let mut deformed = rest.clone();
    deformed[5] += Vec3::new(0.0, 0.3, 0.1);
    deformed[7] += Vec3::new(0.0, 0.6, -0.2);
    let tool = CurveTool {
        basis: CurveBasis::BSpline { degree: 3 },
        rest,
        deformed,
    };
    tool.validate("bench").unwrap();
    // The closest-point search alone, point by point and a lane group at a time.
    let evaluator = CurveEvaluator::new(tool.basis, tool.rest.len(), "bench").unwrap();
    let pieces = CurvePieces::new(&evaluator, &tool.rest);
    c.bench_function("curve_bspline3_closest_scalar_100k", |b| {
        b.iter(|| {
            for x in &pts {
                black_box(pieces.closest(black_box(*x)));
            }
        })
    });
    let mut found = vec![pieces.closest(Vec3::ZERO); pts.len()];
    c.bench_function("curve_bspline3_closest_lanes_100k", |b| {
        b.iter(|| pieces.closest_each(black_box(&pts), &mut found))
    });
    c.bench_function("curve_bspline3_bind_100k", |b| {
        b.iter(|| black_box(tool.bind(black_box(&input)).unwrap()))
    });
    let bind = tool.bind(&input).unwrap();
    c.bench_function("curve_bspline3_deform_100k", |b| {
        b.iter(|| tool.deform(&bind, black_box(&pts), &active, &mut out))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
