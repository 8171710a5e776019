//! `ductile bench SCENE`: time the evaluation of every mesh's stack (the command-line half of
//! "speed targets are checked by benchmarks"; the criterion benchmarks are the other half).
//! `ductile bench --suite [--json]` runs the standard suite ([`crate::suite`]) instead.

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
    /// The scene file (RON); not with --suite.
    #[arg(required_unless_present = "suite", conflicts_with = "suite")]
    pub scene: Option<PathBuf>,
    /// Evaluations per mesh (1 to 1,000,000); with --suite, timed runs of every case
    /// (default: each case's own count).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS))]
    pub iterations: Option<u32>,
    /// Worker threads of the rayon pool the evaluation runs in (1 to 1024; default 1).
    #[arg(long, conflicts_with = "suite", value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS))]
    pub threads: Option<u32>,
    /// Run the standard suite (identikit, million-vertex mixed stack full / incremental / one
    /// thread, lattice, batch) on meshes built from the head the program carries, and print a
    /// table: case, vertices, layers, threads, median ms, p95 ms, target.
    #[arg(long)]
    pub suite: bool,
    /// With --suite: one JSON object per case and line instead of the table.
    #[arg(long, requires = "suite")]
    pub json: bool,
    /// With --suite: only the cases whose name contains this text.
    #[arg(long, value_name = "TEXT", requires = "suite")]
    pub case: Option<String>,
}

/// Default evaluations per mesh.
pub const DEFAULT_ITERATIONS: u32 = 50;

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
    if args.suite {
        return run_suite(args, out);
    }
    let Some(path) = &args.scene else {
        anyhow::bail!("bench needs a SCENE file, or --suite");
    };
    let iterations = args.iterations.unwrap_or(DEFAULT_ITERATIONS);
    let threads = args.threads.unwrap_or(1);
    let scene = super::load_input(path)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads as usize)
        .build()
        .context("cannot start the thread pool")?;
    writeln!(
        out,
        "{}: {} iterations, {} thread{}",
        path.display(),
        iterations,
        threads,
        if threads == 1 { "" } else { "s" }
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
            let mut times = Vec::with_capacity(iterations as usize);
            for _ in 0..iterations {
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

/// `--suite`: every case (or those `--case` names), as a table or JSON lines.
fn run_suite(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    use crate::suite::{Case, Fixtures};
    let cases: Vec<Case> = Case::ALL
        .into_iter()
        .filter(|c| args.case.as_deref().is_none_or(|t| c.name().contains(t)))
        .collect();
    if cases.is_empty() {
        let names: Vec<&str> = Case::ALL.iter().map(|c| c.name()).collect();
        anyhow::bail!(
            "--case '{}' names no case (cases: {})",
            args.case.as_deref().unwrap_or(""),
            names.join(", ")
        );
    }
    if !args.json {
        writeln!(
            out,
            "{:<22} {:>9} {:>6} {:>7} {:>11} {:>11} {:>11}",
            "case", "vertices", "layers", "threads", "median ms", "p95 ms", "target ms"
        )?;
    }
    let mut fixtures = Fixtures::default();
    let mut outcomes = Vec::new();
    let mut missed = 0;
    for case in cases {
        let samples = args.iterations.map_or(case.samples(), |n| n as usize);
        let o = case.measure(&mut fixtures, samples)?;
        if args.json {
            writeln!(out, "{}", o.json())?;
        } else {
            let (target, verdict) = match o.target_ms {
                Some(t) => {
                    let met = o.median_ms <= t;
                    missed += usize::from(!met);
                    (format!("≤ {t}"), if met { "met" } else { "NOT MET" })
                }
                None => ("—".to_owned(), "(by the speed-up)"),
            };
            writeln!(
                out,
                "{:<22} {:>9} {:>6} {:>7} {:>11.3} {:>11.3} {:>9} {}",
                o.case, o.vertices, o.layers, o.threads, o.median_ms, o.p95_ms, target, verdict
            )?;
        }
        out.flush()?;
        outcomes.push(o);
    }
    if !args.json {
        let judged_by_speed_up = outcomes.iter().any(|o| o.target_ms.is_none());
        match crate::suite::speed_up(&outcomes) {
            Some(r) => {
                let met = r >= crate::suite::SPEED_UP_TARGET;
                missed += usize::from(!met);
                writeln!(
                    out,
                    "speed-up of mixed-1m/full, 1 → 2 threads: {r:.2}× (target ≥ {}×) {}",
                    crate::suite::SPEED_UP_TARGET,
                    if met { "met" } else { "NOT MET" }
                )?;
            }
            None if judged_by_speed_up => writeln!(
                out,
                "speed-up of mixed-1m/full, 1 → 2 threads: not judged (it needs both \
                 mixed-1m/full and mixed-1m/full-1t; `--case mixed-1m/full` runs the two)"
            )?,
            None => {}
        }
        writeln!(
            out,
            "peak resident memory {:.0} MB; {missed} target(s) not met",
            crate::suite::peak_rss_bytes().unwrap_or(0) as f64 / 1e6
        )?;
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
