//! Per-layer profile of the standard suite's million-vertex mixed stack
//! (`ductile_cli::suite`): for each layer in order, its active vertices and the time of its
//! mask, its tool's bind and its deformation (without normals), then the totals.
//!
//! `cargo run --release -p ductile-cli --example layer_profile -- [THREADS]` (default 2).
//! One evaluation, so the figures move by 10–20 % between runs; run it twice on a quiet
//! machine. Where `ductile bench --suite` says how long, this says where.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use ductile_cli::suite::{Fixtures, MIXED_NODE};
use ductile_core::influence::{ChunkBounds, Mask};
use ductile_core::stack::LayerBinding;

fn main() -> anyhow::Result<()> {
    let threads: usize = match std::env::args().nth(1) {
        Some(s) => s.parse().context("THREADS must be a number")?,
        None => 2,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let (doc, rest) = Fixtures::default().mixed()?;
    let stack = doc.resolve_stack(MIXED_NODE, &rest)?;
    pool.install(|| -> anyhow::Result<()> {
        let mut positions = rest.welded_positions().to_vec();
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let mut totals = [0.0; 3];
        let mut bounds = ChunkBounds::new(&positions);
        println!(
            "{:<32} {:>8} {:>8} {:>8} {:>8}",
            "layer", "active", "mask ms", "bind ms", "deform ms"
        );
        for layer in &stack.layers {
            let t0 = Instant::now();
            // As `Stack::evaluate_surface` weighs a volume over every vertex: over the
            // boxes of the vertex chunks, those of the last layer's vertices refreshed.
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
            let binding = LayerBinding::bind_masked(
                &layer.tool,
                Arc::new(mask),
                &positions,
                rest.topology(),
            )?;
            let t2 = Instant::now();
            binding.apply(layer, &mut positions)?;
            let t3 = Instant::now();
            let times = [ms(t0, t1), ms(t1, t2), ms(t2, t3)];
            for (t, x) in totals.iter_mut().zip(times) {
                *t += x;
            }
            let name = format!("{} ({})", layer.name, layer.tool.kind_name());
            println!(
                "{name:<32} {active:>8} {:>8.2} {:>8.2} {:>8.2}",
                times[0], times[1], times[2]
            );
        }
        println!(
            "{:<32} {:>8} {:>8.1} {:>8.1} {:>8.1}",
            "total", "", totals[0], totals[1], totals[2]
        );
        Ok(())
    })
}
