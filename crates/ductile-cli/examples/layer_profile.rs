//! Per-layer profile of the standard suite's million-vertex mixed stack
//! (`ductile_cli::suite`): for each layer in order, its active vertices and the time of its
//! mask, its tool's bind and its deformation (without normals), then the output (normals
//! and the stored vertex order, as `Stack::evaluate` makes it) and the totals.
//!
//! `cargo run --release -p ductile-cli --example layer_profile -- [THREADS] [ROUNDS]`
//! (default 2 threads, 1 round). Every round evaluates the stack from the rest positions
//! again; the per-layer lines are the last round's (with several rounds, the steady state:
//! allocator and caches warm), and each round prints its totals. The figures move by
//! 10–20 % between runs; run it twice on a quiet machine. Where `ductile bench --suite`
//! says how long, this says where.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use ductile_cli::suite::{Fixtures, MIXED_NODE};
use ductile_core::influence::{ChunkBounds, Mask};
use ductile_core::mesh::RestMesh;
use ductile_core::stack::{LayerBinding, Stack};

/// The allocator of the `ductile` binary, whose figures this explains.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    let number = |k: usize, default: usize, what: &str| -> anyhow::Result<usize> {
        match std::env::args().nth(k) {
            Some(s) => s
                .parse()
                .with_context(|| format!("{what} must be a number")),
            None => Ok(default),
        }
    };
    let threads = number(1, 2, "THREADS")?;
    let rounds = number(2, 1, "ROUNDS")?.max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let (doc, rest) = Fixtures::default().mixed()?;
    let stack = doc.resolve_stack(MIXED_NODE, &rest)?;
    pool.install(|| -> anyhow::Result<()> {
        for round in 1..=rounds {
            let t = profile(&stack, &rest, round == rounds)?;
            println!(
                "{:<32} {:>8} {:>8.1} {:>8.1} {:>9.1} {:>9.1}",
                format!("total, round {round}"),
                "",
                t[0],
                t[1],
                t[2],
                t[3]
            );
        }
        Ok(())
    })
}

/// Evaluates `stack` once from the rest positions, printing each layer's line when `print`,
/// and returns the milliseconds of the masks, the binds, the deformations and the output.
fn profile(stack: &Stack, rest: &RestMesh, print: bool) -> anyhow::Result<[f64; 4]> {
    let mut positions = rest.welded_positions().to_vec();
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    let mut totals = [0.0; 4];
    let mut bounds = ChunkBounds::new(&positions);
    if print {
        println!(
            "{:<32} {:>8} {:>8} {:>8} {:>9} {:>9}",
            "layer", "active", "mask ms", "bind ms", "deform ms", "output ms"
        );
    }
    let mut scratch = Vec::new();
    for layer in &stack.layers {
        let t0 = Instant::now();
        // As `Stack::evaluate_surface` weighs a volume over every vertex: over the boxes
        // of the vertex chunks, those of the last layer's vertices refreshed.
        let mask = match &layer.influence {
            Some(inf) if inf.reads_chunk_bounds(positions.len()) => {
                bounds.refresh(&positions);
                inf.mask_bounded(&positions, &bounds)
            }
            Some(inf) => inf.mask(&positions),
            None => Mask::all(positions.len()),
        };
        bounds.mark(&mask.indices);
        let t1 = Instant::now();
        let active = mask.indices.len();
        let binding =
            LayerBinding::bind_masked(&layer.tool, Arc::new(mask), &positions, rest.topology())?;
        let t2 = Instant::now();
        binding.apply_with(layer, &mut positions, &mut scratch)?;
        let t3 = Instant::now();
        let times = [ms(t0, t1), ms(t1, t2), ms(t2, t3)];
        for (t, x) in totals.iter_mut().zip(times) {
            *t += x;
        }
        if print {
            let name = format!("{} ({})", layer.name, layer.tool.kind_name());
            println!(
                "{name:<32} {active:>8} {:>8.2} {:>8.2} {:>9.2}",
                times[0], times[1], times[2]
            );
        }
    }
    let t0 = Instant::now();
    std::hint::black_box(rest.output(&positions));
    totals[3] = ms(t0, Instant::now());
    Ok(totals)
}
