//! `ductile apply SCENE [-o OUT] [--frame N [--fps F]]`: evaluate every mesh's stack (at a
//! frame of the animation) and export glTF. `SCENE` may also be a history file.
//!
//! With `--input MESH… --out-dir DIR` it applies one mesh node's stack to many other meshes
//! instead, one `.glb` each ([`crate::batch`], `docs/batch.md`).

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
    /// Batch: apply the stack to this mesh (glTF or OBJ, `#name` selects a part; glob
    /// patterns such as 'heads/*.obj' are expanded). Repeat for more meshes.
    #[arg(
        long = "input",
        value_name = "MESH",
        group = "batch",
        conflicts_with = "output"
    )]
    pub inputs: Vec<String>,
    /// Batch: a file listing input meshes, one per line (blank lines and lines starting with
    /// '#' are skipped; relative paths are relative to the current folder).
    #[arg(long, value_name = "FILE", group = "batch", conflicts_with = "output")]
    pub input_list: Option<PathBuf>,
    /// Batch: the folder the outputs are written to, one `<input name>.glb` per input.
    #[arg(long, value_name = "DIR", requires = "batch")]
    pub out_dir: Option<PathBuf>,
    /// Batch: the mesh node whose stack is applied (default: the scene's only mesh node).
    #[arg(long, value_name = "NODE", requires = "batch")]
    pub mesh: Option<String>,
    /// Batch: meshes processed at once (default: the number of cores; 1 to 1024).
    #[arg(long, value_name = "N", requires = "batch",
          value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_THREADS))]
    pub jobs: Option<u32>,
    /// Batch: only the inputs of shard I of N (every N-th input of the sorted list, from the
    /// I-th, I counted from 0), or `auto` to read it from a Kubernetes Indexed Job or a Slurm
    /// job array.
    #[arg(long, value_name = "I/N|auto", requires = "batch")]
    pub shard: Option<String>,
    /// Batch: leave inputs whose output exists already (resume an interrupted batch).
    #[arg(long, requires = "batch")]
    pub skip_existing: bool,
    /// Batch: write one JSON object per input to FILE (input, output, status, vertices, ms,
    /// error).
    #[arg(long, value_name = "FILE", requires = "batch")]
    pub report: Option<PathBuf>,
}

impl Args {
    /// Whether these arguments ask for a batch.
    #[must_use]
    pub fn is_batch(&self) -> bool {
        !self.inputs.is_empty() || self.input_list.is_some()
    }
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
    if args.is_batch() {
        return super::apply_batch::run(args, &scene, out);
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
