//! `ductile bench SCENE`: time the evaluation of every mesh's stack (the command-line half of
//! "speed targets are checked by benchmarks"; the criterion benchmarks are the other half).

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context as _;

/// The most worker threads `--threads` may ask for: more than any machine this runs on has
/// cores, few enough that starting them cannot exhaust the system.
pub const MAX_THREADS: i64 = 1024;
/// The most evaluations per mesh `--iterations` may ask for.
pub const MAX_ITERATIONS: i64 = 1_000_000;

/// Arguments of `ductile bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Evaluations per mesh (1 to 1,000,000).
    #[arg(long, default_value_t = 50, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS))]
    pub iterations: u32,
    /// Worker threads of the rayon pool the evaluation runs in (1 to 1024).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS))]
    pub threads: u32,
}

/// Minimum, median and maximum of a non-empty sample.
#[must_use]
pub fn summary(mut times: Vec<Duration>) -> Option<(Duration, Duration, Duration)> {
    times.sort_unstable();
    let n = times.len();
    let median = if n == 0 {
        return None;
    } else if n % 2 == 1 {
        times[n / 2]
    } else {
        (times[n / 2 - 1] + times[n / 2]) / 2
    };
    Some((times[0], median, times[n - 1]))
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let scene = super::load_input(&args.scene)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads as usize)
        .build()
        .context("cannot start the thread pool")?;
    writeln!(
        out,
        "{}: {} iterations, {} thread{}",
        args.scene.display(),
        args.iterations,
        args.threads,
        if args.threads == 1 { "" } else { "s" }
    )?;
    for m in &scene.meshes {
        // Resolving (world transforms, areas, volumes) happens once per edit in an
        // interactive session; the loop times what runs on every change: `Stack::evaluate`
        // (bind every layer, deform, recompute normals).
        let start = Instant::now();
        let stack = scene
            .document
            .resolve_stack(&m.name, &m.rest)
            .with_context(|| format!("cannot resolve the stack of mesh '{}'", m.name))?;
        let resolve = start.elapsed();
        let times = pool.install(|| -> anyhow::Result<Vec<Duration>> {
            let mut times = Vec::with_capacity(args.iterations as usize);
            for _ in 0..args.iterations {
                let start = Instant::now();
                let d = stack
                    .evaluate(&m.rest)
                    .with_context(|| format!("cannot evaluate mesh '{}'", m.name))?;
                times.push(start.elapsed());
                std::hint::black_box(d);
            }
            Ok(times)
        })?;
        if let Some((lo, med, hi)) = summary(times) {
            writeln!(
                out,
                "mesh '{}' ({} vertices, {} layers): resolve {:.3} ms; evaluate min {:.3} ms, median {:.3} ms, max {:.3} ms",
                m.name,
                m.rest.topology().vertex_count(),
                stack.layers.len(),
                super::ms(resolve),
                super::ms(lo),
                super::ms(med),
                super::ms(hi)
            )?;
        }
    }
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_takes_min_median_max() {
        let ms = |v: u64| Duration::from_millis(v);
        assert_eq!(
            summary(vec![ms(5), ms(1), ms(3)]),
            Some((ms(1), ms(3), ms(5)))
        );
        assert_eq!(
            summary(vec![ms(4), ms(1), ms(2), ms(8)]),
            Some((ms(1), ms(3), ms(8)))
        );
        assert_eq!(summary(vec![]), None);
    }
}
