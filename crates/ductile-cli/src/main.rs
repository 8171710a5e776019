//! The `ductile` binary: see [`ductile_cli`].

use std::process::ExitCode;

/// mimalloc instead of the system allocator. An evaluation of a large mesh allocates and
/// frees arrays of megabytes per layer; glibc's malloc serves those above its (moving) mmap
/// threshold with fresh pages from the kernel every time, so how many page faults an
/// evaluation takes depended on the sizes of earlier allocations: a change that only made
/// one bind smaller took `mixed-1m/full-1t` from 74,000 to 268,000 faults and ate its gain.
/// mimalloc keeps freed memory for reuse: 18,000 faults, and the same bits (docs/performance.md,
/// 2026-11-29).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let mut stdout = std::io::stdout().lock();
    match ductile_cli::run(std::env::args_os(), &mut stdout) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // Help and version requests come back as clap errors that are not failures.
            if let Some(c) = e.downcast_ref::<clap::Error>() {
                let _ = c.print();
                return ExitCode::from(if c.use_stderr() { 2 } else { 0 });
            }
            eprintln!("error: {}", ductile_cli::error_message(&e));
            ExitCode::from(1)
        }
    }
}
