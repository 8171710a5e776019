//! `ductile check FILE`: print every problem of a scene file, or of a history file (its base,
//! every step replayed, and the document it ends at).

use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ductile check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON) to validate, or a history file (`.history.ron`: every step is
    /// replayed and the final document checked).
    pub file: PathBuf,
}

/// Runs the command: prints every problem, one per line, and returns 1 if there is any;
/// prints `ok` and returns 0 otherwise. Warnings (animation tracks that step where their keys
/// cannot be interpolated) are printed first and do not fail the check.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let history = ductile_io::is_history_file(&args.file);
    let problems = if history {
        ductile_io::check_history(&args.file)
    } else {
        ductile_io::check_scene(&args.file)
    };
    let document = if history {
        ductile_io::read_history(&args.file)
            .ok()
            .and_then(|h| h.replay(h.history.len()).ok())
    } else {
        ductile_io::read_scene(&args.file).ok()
    };
    if let Some(doc) = document {
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
