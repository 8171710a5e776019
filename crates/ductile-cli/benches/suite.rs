//! Criterion benchmark of the standard suite (`ductile bench --suite`, [`ductile_cli::suite`]):
//! the same cases, built the same way, timed by criterion. Targets on the project's 2-core
//! machine are in `docs/performance.md`, "Standard suite".

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_cli::suite::{Case, Fixtures};

/// The allocator of the `ductile` binary, as `ductile bench --suite` runs with it.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn suite(c: &mut Criterion) {
    let mut fixtures = Fixtures::default();
    let mut group = c.benchmark_group("suite");
    group.sample_size(10);
    for case in Case::ALL {
        let mut p = case.prepare(&mut fixtures).expect("case");
        // Timed from inside the case's pool, as `ductile bench --suite` times it.
        group.bench_function(case.name(), |b| {
            b.iter_custom(|iters| {
                let n = usize::try_from(iters).expect("iterations");
                p.time(n).expect("run").into_iter().sum()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, suite);
criterion_main!(benches);
