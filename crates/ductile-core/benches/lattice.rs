//! Lattice FFD benchmarks: 1,000,000 points in a Bernstein 4×4×4 (degree 3) lattice, an
//! 8×8×8 Bernstein lattice and a cubic B-spline lattice of 8×8×8 control points, each
//! deformed through `Tool::deform` in rayon chunks (as the stack does) and single-threaded.

#![allow(clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_core::lattice::{LatticeFrame, LatticeTool};
use ductile_core::mesh::Topology;
use ductile_core::tool::{BindInput, Tool};
use glam::Vec3;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Duration;

const N: usize = 1_000_000;
const CHUNK: usize = 4_096;

/// Deterministic points filling the unit cube (a 64-bit LCG).
fn points() -> Vec<Vec3> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..N).map(|_| Vec3::new(next(), next(), next())).collect()
}

/// A lattice over the unit cube with every control point moved a little.
fn lattice(counts: u32, bspline: bool) -> Tool {
    let frame = LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE);
    let mut t = if bspline {
        LatticeTool::bspline(frame, (counts, counts, counts), (3, 3, 3))
    } else {
        LatticeTool::bernstein(frame, (counts, counts, counts))
    };
    for k in 0..counts {
        for j in 0..counts {
            for i in 0..counts {
                let h = (i * 7 + j * 13 + k * 29) % 11;
                t.set_offset(
                    (i, j, k),
                    Vec3::new(0.01 * h as f32, -0.005 * h as f32, 0.02),
                );
            }
        }
    }
    Tool::Lattice(t)
}

/// CPU time of the calling thread in nanoseconds (`/proc/thread-self/schedstat`, Linux),
/// or 0 where it cannot be read. On a loaded machine this measures the work, not the wait.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let active: Vec<u32> = (0..N as u32).collect();
    let topo = Topology {
        weld: Vec::new(),
        representative: Vec::new(),
        triangles: Vec::new(),
    };
    let mut out = vec![Vec3::ZERO; N];
    let mut group = c.benchmark_group("lattice-1M");
    group.sample_size(20);
    for (name, tool) in [
        ("bernstein-4x4x4", lattice(4, false)),
        ("bernstein-8x8x8", lattice(8, false)),
        ("bspline-cubic-8x8x8", lattice(8, true)),
    ] {
        let bind = tool
            .bind(&BindInput {
                positions: &pts,
                topology: &topo,
                active: &active,
            })
            .unwrap();
        group.bench_function(format!("{name}/parallel"), |b| {
            b.iter(|| {
                out.par_chunks_mut(CHUNK)
                    .zip(active.par_chunks(CHUNK))
                    .for_each(|(o, a)| tool.deform(&bind, black_box(&pts), a, o));
                black_box(&out);
            })
        });
        group.bench_function(format!("{name}/single-thread"), |b| {
            b.iter(|| {
                tool.deform(&bind, black_box(&pts), &active, &mut out);
                black_box(&out);
            })
        });
        group.bench_function(format!("{name}/single-thread-cpu-time"), |b| {
            b.iter_custom(|iters| {
                let t0 = thread_cpu_ns();
                for _ in 0..iters {
                    tool.deform(&bind, black_box(&pts), &active, &mut out);
                    black_box(&out);
                }
                Duration::from_nanos(thread_cpu_ns() - t0)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
