//! `ductile export-anim SCENE -o OUT.glb [--fps F] [--from F --to F] [--tolerance T]` (or
//! `--frames DIR`): the scene's animation baked as morph targets with a weights animation that
//! plays in any glTF viewer, or one `.glb` per frame.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, bail};
use ductile_io::bake::{BakeOptions, DEFAULT_TOLERANCE, export_animation, export_frames};

/// Arguments of `ductile export-anim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON), or a history file.
    pub scene: PathBuf,
    /// Output file, `.glb` or `.gltf`: the rest mesh, one morph target per distinct sampled
    /// frame and the weights animation.
    #[arg(
        short,
        long,
        required_unless_present = "frames",
        conflicts_with = "frames"
    )]
    pub output: Option<PathBuf>,
    /// Write one `.glb` per sampled frame into DIR instead (`frame-0000.glb`, …).
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Samples per second (default: the scene's frame rate).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// First frame of the scene's timeline to export (default: its start).
    #[arg(long, value_name = "F")]
    pub from: Option<i32>,
    /// Last frame of the scene's timeline to export (default: its end).
    #[arg(long, value_name = "F")]
    pub to: Option<i32>,
    /// Frames whose vertices all lie within this fraction of the mesh's size of the previous
    /// target share it (default 1e-5).
    #[arg(long, value_name = "T", default_value_t = DEFAULT_TOLERANCE)]
    pub tolerance: f32,
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let scene = super::load_input(&args.scene)?;
    let anim = &scene.document.animation;
    if anim.is_static() {
        bail!(
            "{}: the scene has no animation (no keyframe tracks) to export",
            args.scene.display()
        );
    }
    let options = BakeOptions {
        fps: args.fps.unwrap_or(anim.fps),
        from: args.from.unwrap_or(anim.start),
        to: args.to.unwrap_or(anim.end),
        tolerance: args.tolerance,
    };
    let start = Instant::now();
    let mut progress = |_done: usize, _total: usize| {};
    if let Some(dir) = &args.frames {
        let files = export_frames(&scene, dir, &options, &mut progress)
            .with_context(|| format!("cannot export frames to {}", dir.display()))?;
        writeln!(
            out,
            "wrote {} files to {} (frames {} to {} at {} samples/s) in {:.0} ms",
            files.len(),
            dir.display(),
            options.from,
            options.to,
            options.fps,
            super::ms(start.elapsed())
        )?;
        return Ok(0);
    }
    let Some(output) = &args.output else {
        bail!("give -o OUT.glb or --frames DIR");
    };
    let report = export_animation(&scene, output, &options, &mut progress)
        .with_context(|| format!("cannot export the animation to {}", output.display()))?;
    let keys = report.samples.iter().filter(|s| s.key).count();
    writeln!(
        out,
        "sampled {} times (frames {} to {} at {} samples/s, {keys} at keys)",
        report.samples.len(),
        options.from,
        options.to,
        options.fps
    )?;
    for (mesh, targets) in &report.targets {
        writeln!(out, "mesh '{mesh}': {targets} morph targets")?;
    }
    writeln!(
        out,
        "wrote {} in {:.0} ms",
        output.display(),
        super::ms(start.elapsed())
    )?;
    Ok(0)
}
