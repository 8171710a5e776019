//! `ductile apply SCENE [-o OUT]`: evaluate every mesh's stack and export glTF.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use ductile_io::ExportMesh;

/// Arguments of `ductile apply`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Output file, `.glb` or `.gltf` (default: `<scene stem>.glb` in the current directory).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
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
    let scene = super::load_input(&args.scene)?;
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
