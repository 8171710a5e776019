//! FFSD stack evaluation on a synthetic head-sized mesh: 30 layers of 3 control points, each
//! limited to an area of influence, as in the paper's Table 1 case "30 predefined
//! deformations". Runs on one thread.

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::prelude::*;
use ductile_core::primitives;
use glam::Vec3;

/// A UV sphere of radius 0.1 (head-sized in metres) with `rings × segments` vertices.
fn sphere(rings: usize, segments: usize) -> RestMesh {
    let mesh = primitives::grid(rings, segments, true, |r, s| {
        let theta = std::f32::consts::PI * (r as f32 + 0.5) / rings as f32;
        let phi = std::f32::consts::TAU * s as f32 / segments as f32;
        0.1 * Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    });
    RestMesh::new(mesh, "sphere").expect("valid sphere")
}

fn stack(rest: &RestMesh) -> Stack {
    let positions = rest.welded_positions();
    let layers = (0..30)
        .map(|k| {
            // Feature centres spread over the front half, areas of ~3 cm radius.
            let phi = 0.3 + 2.5 * (k as f32 / 30.0);
            let y = -0.07 + 0.14 * ((k * 7 % 30) as f32 / 30.0);
            let centre = Vec3::new(phi.cos() * 0.09, y, phi.sin() * 0.09).normalize() * 0.1;
            let area: Vec<u32> = (0..positions.len() as u32)
                .filter(|&i| positions[i as usize].distance(centre) < 0.03)
                .collect();
            let points = (0..3)
                .map(|j| {
                    let offset = Vec3::new(0.004 * j as f32, -0.003 * j as f32, 0.0);
                    ControlPoint::basic(centre * 1.1 + offset, 0.3, 0.8, 0.02)
                })
                .collect();
            let mut tool = FfsdTool::new(points);
            tool.height = Some(HeightLimit::Above { theta: 0.85 });
            let mut layer = Layer::new(format!("macro {k}"), Tool::Ffsd(tool));
            layer.influence = Some(Influence {
                area: Some(area),
                ..Influence::default()
            });
            layer
        })
        .collect();
    Stack { layers }
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let rest = sphere(94, 94);
    let stack = stack(&rest);
    let active: usize = stack
        .layers
        .iter()
        .map(|l| {
            l.influence
                .as_ref()
                .map_or(0, |i| i.area.as_ref().map_or(0, Vec::len))
        })
        .sum();
    eprintln!(
        "{} welded vertices, {} active vertex-layers",
        rest.welded_positions().len(),
        active
    );
    c.bench_function(
        "ffsd/30 layers x 3 points, 8.8k vertices, positions only",
        |b| {
            b.iter(|| pool.install(|| stack.evaluate_welded(&rest).expect("evaluates")));
        },
    );
    c.bench_function(
        "ffsd/30 layers x 3 points, 8.8k vertices, with normals",
        |b| {
            b.iter(|| pool.install(|| stack.evaluate(&rest).expect("evaluates")));
        },
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
