//! Benchmarks of the first half of the sketch deformation (Kho & Garland 2005, §4): the
//! ray-casting hierarchy, the region of interest from a reference curve, and one cut line,
//! on a closed cylinder of about 100,000 vertices.

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::mesh::{Mesh, Topology};
use ductile_core::sketch::camera::{Camera, Projection};
use ductile_core::sketch::cut::cut_with_line;
use ductile_core::sketch::raycast::Bvh;
use ductile_core::sketch::roi::partition_from_curve;
use glam::{Vec2, Vec3};
use std::hint::black_box;

/// A closed cylinder along +Y (radius 0.5, height 4) with `segments × (rings + 1)` side
/// vertices and two cap centres.
fn cylinder(segments: u32, rings: u32) -> (Vec<Vec3>, Topology) {
    let mut positions = Vec::new();
    for r in 0..=rings {
        let y = 4.0 * r as f32 / rings as f32;
        for s in 0..segments {
            let a = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(Vec3::new(0.5 * a.cos(), y, 0.5 * a.sin()));
        }
    }
    let idx = |r: u32, s: u32| r * segments + s % segments;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (idx(r, s), idx(r, s + 1), idx(r + 1, s + 1), idx(r + 1, s));
            indices.extend([a, c, b, a, d, c]);
        }
    }
    let bottom = positions.len() as u32;
    positions.push(Vec3::ZERO);
    let top = positions.len() as u32;
    positions.push(Vec3::new(0.0, 4.0, 0.0));
    for s in 0..segments {
        indices.extend([bottom, idx(0, s), idx(0, s + 1)]);
        indices.extend([top, idx(rings, s + 1), idx(rings, s)]);
    }
    let mesh = Mesh {
        positions,
        normals: None,
        uvs: None,
        indices,
    };
    let topology = Topology::weld(&mesh);
    (topology.gather(&mesh.positions), topology)
}

fn sketch_roi(c: &mut Criterion) {
    // 250 × 400 = 100,250 vertices, 200,000 triangles.
    let (positions, topology) = cylinder(250, 400);
    assert!(positions.len() >= 100_000);
    let mut group = c.benchmark_group("sketch_roi_100k");
    group.sample_size(20);
    group.bench_function("bvh_build", |b| {
        b.iter(|| Bvh::build(black_box(&positions), black_box(&topology.triangles)))
    });
    // A reference curve over the upper half: the region is a 100 × 250 band... in fact the
    // whole band between y = 1.0 and y = 3.5 (62,500 vertices).
    let curve: Vec<Vec3> = (0..=50)
        .map(|i| Vec3::new(0.0, 1.0 + 2.5 * i as f32 / 50.0, 0.5))
        .collect();
    group.bench_function("partition_from_curve", |b| {
        b.iter(|| partition_from_curve(black_box(&positions), &topology, black_box(&curve)))
    });
    let bvh = Bvh::build(&positions, &topology.triangles).expect("valid mesh");
    let camera = Camera {
        eye: Vec3::new(0.0, 2.0, 10.0),
        target: Vec3::new(0.0, 2.0, 0.0),
        up: Vec3::Y,
        projection: Projection::Perspective { fov_y: 0.6 },
        near: 0.1,
        far: 100.0,
        viewport: Vec2::new(1920.0, 1080.0),
    };
    let rays: Vec<_> = (0..1000)
        .map(|i| {
            camera.ray(Vec2::new(
                960.0 + (i % 40) as f32,
                200.0 + (i / 40) as f32 * 25.0,
            ))
        })
        .collect();
    group.bench_function("1000_rays_intersect_all", |b| {
        b.iter(|| {
            rays.iter()
                .map(|r| bvh.intersect_all(r).len())
                .sum::<usize>()
        })
    });
    let a = camera
        .project(Vec3::new(-1.0, 1.1, 0.0))
        .expect("in front")
        .0;
    let e = camera
        .project(Vec3::new(1.0, 1.1, 0.0))
        .expect("in front")
        .0;
    group.bench_function("cut_with_line", |b| {
        b.iter(|| cut_with_line(&camera, black_box([a, e]), &positions, &topology))
    });
    group.finish();
}

criterion_group!(benches, sketch_roi);
criterion_main!(benches);
