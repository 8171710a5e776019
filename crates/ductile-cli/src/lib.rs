//! The `ductile` command line, as a library so that tests can call [`run`] directly.
//!
//! Subcommands live one per file in [`commands`]; adding one means a variant of
//! [`Command`], a match arm in [`run`] and a file.

pub mod batch;
pub mod commands;
pub mod suite;

use std::ffi::OsString;
use std::io::Write;

use clap::{Parser, Subcommand};

/// Ductile: non-destructive mesh deformation from the command line.
#[derive(Debug, Parser)]
#[command(name = "ductile", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Evaluate every mesh's deformation stack (at a frame of the animation) and export the
    /// result as glTF; or, with --input and --out-dir, apply one mesh's stack to many meshes.
    Apply(commands::apply::Args),
    /// Validate a scene file and print every problem found.
    Check(commands::check::Args),
    /// Print statistics of a mesh file (stored and welded vertices, triangles, bounds).
    Info(commands::info::Args),
    /// Time the evaluation of every mesh's stack.
    Bench(commands::bench::Args),
    /// Replay a history file step by step and export the meshes (at the end, or every K
    /// steps).
    Replay(commands::replay::Args),
    /// List the steps of a history file (index, time, label).
    History(commands::history::Args),
    /// Bake the scene's animation into glTF morph targets with a weights animation (or one
    /// file per frame).
    ExportAnim(commands::export_anim::Args),
    /// Export the rest meshes with one morph target per variant.
    ExportMorphs(commands::export_morphs::Args),
    /// Blend variants (two with t, N with weights, or seeded random) and export the meshes.
    Blend(commands::blend::Args),
    /// List the scene's variants, one name per line.
    Variants(commands::variants::Args),
}

/// Parses `args` (the first item is the program name) and runs the command, writing its
/// report to `out`. Returns the process exit status (0 for success, 1 when `check` found
/// problems); errors (bad input, unreadable files) are returned as `Err`.
pub fn run<I, T>(args: I, out: &mut dyn Write) -> anyhow::Result<u8>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = Cli::try_parse_from(args)?;
    match cli.command {
        Command::Apply(a) => commands::apply::run(&a, out),
        Command::Check(a) => commands::check::run(&a, out),
        Command::Info(a) => commands::info::run(&a, out),
        Command::Bench(a) => commands::bench::run(&a, out),
        Command::Replay(a) => commands::replay::run(&a, out),
        Command::History(a) => commands::history::run(&a, out),
        Command::ExportAnim(a) => commands::export_anim::run(&a, out),
        Command::ExportMorphs(a) => commands::export_morphs::run(&a, out),
        Command::Blend(a) => commands::blend::run(&a, out),
        Command::Variants(a) => commands::variants::run(&a, out),
    }
}

/// The error and its causes on one line, without repeating a cause that an outer message
/// already contains.
#[must_use]
pub fn error_message(e: &anyhow::Error) -> String {
    let mut out = e.to_string();
    let mut last = out.clone();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !last.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        last = text;
    }
    out
}
