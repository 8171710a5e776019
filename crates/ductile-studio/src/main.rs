//! Ductile Studio: the interactive editor for non-destructive mesh deformation.
//!
//! `ductile-studio` opens the embedded identikit head scene; `--scene FILE` opens a scene
//! or history file; `--screenshot OUT.png [--frames N]` renders N frames, writes a PNG and
//! exits (for automated checks, also under `xvfb-run` with software Vulkan).

mod authoring;
mod autosave;
mod box_select;
mod camera;
mod compare;
mod ctrl_text;
mod files;
mod panels;
mod pointer;
mod screenshot;
mod sketch;
mod studio;
mod ui;

use std::path::PathBuf;

use anyhow::Context as _;
use bevy::prelude::*;
use bevy::window::WindowResolution;
use clap::Parser;
use ductile_io::project::Project;

/// Command-line arguments.
#[derive(Parser, Debug)]
#[command(
    name = "ductile-studio",
    version,
    about = "Ductile Studio: non-destructive mesh deformation",
    after_help = "The built-in identikit head is \"Infinite, 3D Head Scan\" by Lee Perry-Smith \
                  (Infinite-Realities, www.ir-ltd.net), based on a work at www.triplegangers.com, \
                  licensed CC BY 3.0 (https://creativecommons.org/licenses/by/3.0/)."
)]
struct Args {
    /// A scene (`.ron`) or history (`.history.ron`) file to open instead of the embedded
    /// identikit head.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Render, save a PNG screenshot of the window to this path and exit.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,
    /// Frames to run before the screenshot is taken.
    #[arg(long, default_value_t = 30, requires = "screenshot")]
    frames: u32,
    /// Window size in logical pixels, `WIDTHxHEIGHT`.
    #[arg(long, default_value = "1280x800", value_parser = parse_size)]
    size: (u32, u32),
    /// Select this node when the scene opens (its gizmo and handles are highlighted).
    #[arg(long, value_name = "NODE")]
    select: Option<String>,
    /// Restore the unsaved work an earlier session left (after a crash or a kill) without
    /// asking. Without it the Studio asks, except with --screenshot.
    #[arg(long)]
    recover: bool,
    /// Autosave unsaved work to the recovery file at least every this many seconds.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u64).range(1..=3600))]
    autosave_seconds: u64,
    /// And after every this many steps.
    #[arg(long, default_value_t = 50, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    autosave_steps: u32,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, for example 1280x800"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("'{s}': bad width"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("'{s}': bad height"))?;
    if !(200..=8192).contains(&w) || !(200..=8192).contains(&h) {
        return Err(format!("'{s}': width and height must be in 200..=8192"));
    }
    Ok((w, h))
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    // Open the project before the window, so that a bad file is a clear error and no window.
    let (project, warnings) = match &args.scene {
        Some(path) => {
            Project::open(path).with_context(|| format!("cannot open '{}'", path.display()))?
        }
        None => (
            Project::embedded_default().context("cannot open the embedded identikit scene")?,
            Vec::new(),
        ),
    };
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    if let Some(out) = &args.screenshot {
        screenshot::check_writable(out)?;
    }
    // A recovery file of this project is what a session that did not close normally left.
    // A screenshot run has no one to ask, so it offers nothing unless told to recover.
    let recovery_file = ductile_io::recovery::recovery_path(&project);
    let found = (args.recover || args.screenshot.is_none())
        .then(|| ductile_io::recovery::find_recovery(&recovery_file))
        .flatten();
    if args.recover && found.is_none() {
        eprintln!(
            "warning: --recover: there is no recovery file {}",
            recovery_file.display()
        );
    }
    let title = format!("Ductile Studio — {}", project.display_name());
    let mut app = App::new();
    app.add_plugins(DefaultPlugins.set(WindowPlugin {
        primary_window: Some(Window {
            title,
            resolution: WindowResolution::new(args.size.0, args.size.1),
            ..default()
        }),
        ..default()
    }))
    .add_plugins(studio::StudioPlugin {
        project,
        warnings: warnings.iter().map(ToString::to_string).collect(),
        select: args.select.clone(),
        recovery: studio::RecoveryOptions {
            every: std::time::Duration::from_secs(args.autosave_seconds),
            every_steps: args.autosave_steps,
            found,
            recover_now: args.recover,
        },
    });
    if let Some(out) = args.screenshot {
        app.add_plugins(screenshot::ScreenshotPlugin {
            path: out,
            frames: args.frames,
        });
    }
    match app.run() {
        AppExit::Success => Ok(()),
        AppExit::Error(code) => std::process::exit(i32::from(code.get())),
    }
}
