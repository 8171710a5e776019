//! The `ductile` binary: see [`ductile_cli`].

use std::process::ExitCode;

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
