//! `ductile apply SCENE [-o OUT] [--frame N [--fps F]]`: evaluate every mesh's stack (at a
//! frame of the animation) and export glTF. `SCENE` may also be a history file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use ductile_io::ExportMesh;

/// Arguments of `ductile apply`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON), or a history file (replayed to the step it was saved at).
    pub scene: PathBuf,
    /// Output file, `.glb` or `.gltf` (default: `<scene stem>.glb` in the current directory).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Evaluate the animation at frame N (may be fractional; must lie in the timeline).
    #[arg(long, value_name = "N")]
    pub frame: Option<f32>,
    /// Frames per second for `--frame` (default: the scene's).
    #[arg(long, value_name = "F", requires = "frame")]
    pub fps: Option<f32>,
}

/// The default output path: the scene's file stem with `.glb`, in the current directory.
#[must_use]
pub fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(format!("{stem}.glb"))
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let mut scene = super::load_input(&args.scene)?;
    if let Some(frame) = args.frame {
        let time = super::frame_time(&scene, frame, args.fps)?;
        scene.document = scene.document.at(time).with_context(|| {
            format!("{}: cannot evaluate at frame {frame}", args.scene.display())
        })?;
        writeln!(out, "frame {frame} ({time} s)")?;
    }
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    let mut deformed = Vec::with_capacity(scene.meshes.len());
    for m in &scene.meshes {
        let start = Instant::now();
        let d = scene
            .evaluate(&m.name)
            .with_context(|| format!("cannot evaluate mesh '{}'", m.name))?;
        let elapsed = start.elapsed();
        writeln!(
            out,
            "mesh '{}': {} vertices ({} welded), {} layers, evaluated in {:.2} ms",
            m.name,
            m.rest.topology().stored_count(),
            m.rest.topology().vertex_count(),
            scene.document.mesh(&m.name).map_or(0, |n| n.stack.len()),
            super::ms(elapsed)
        )?;
        deformed.push(d);
    }
    let exports: Vec<ExportMesh<'_>> = scene
        .meshes
        .iter()
        .zip(&deformed)
        .map(|(m, d)| ExportMesh::deformed(&m.name, &m.rest, d))
        .collect();
    ductile_io::export_gltf(&output, &exports)
        .with_context(|| format!("cannot write {}", output.display()))?;
    writeln!(out, "wrote {} ({} meshes)", output.display(), exports.len())?;
    Ok(0)
}
