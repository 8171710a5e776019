//! `ductile check FILE`: print every problem of a scene file.

use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ductile check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON) to validate.
    pub file: PathBuf,
}

/// Runs the command: prints every problem, one per line, and returns 1 if there is any;
/// prints `ok` and returns 0 otherwise. Warnings (animation tracks that step where their keys
/// cannot be interpolated) are printed first and do not fail the check.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let problems = ductile_io::check_scene(&args.file);
    if let Ok(doc) = ductile_io::read_scene(&args.file) {
        for w in doc.warnings() {
            writeln!(out, "warning: {}: {w}", args.file.display())?;
        }
    }
    if problems.is_empty() {
        writeln!(out, "ok")?;
        return Ok(0);
    }
    for p in &problems {
        writeln!(out, "error: {}", ductile_io::report(p))?;
    }
    writeln!(
        out,
        "{}: {} problem{}",
        args.file.display(),
        problems.len(),
        if problems.len() == 1 { "" } else { "s" }
    )?;
    Ok(1)
}
