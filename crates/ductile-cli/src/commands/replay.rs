//! `ductile replay HISTORY [--to N] [-o OUT] [--every K --out-dir DIR]`: replay a history
//! file step by step from its base, write the final meshes (and optionally one glTF file
//! every K steps), printing progress for long histories.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, bail};
use ductile_core::mesh::RestMesh;
use ductile_history::history::replay_with;
use ductile_io::{ExportMesh, LoadedHistory};
use ductile_scene::document::{Document, NodeKind};

/// Arguments of `ductile replay`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The history file (RON).
    pub history: PathBuf,
    /// Replay up to step N (0 = the base; default: the step the history was saved at).
    #[arg(long, value_name = "N")]
    pub to: Option<usize>,
    /// Output file for the final meshes, `.glb` or `.gltf` (default: `<history stem>.glb` in
    /// the current directory).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the meshes every K steps (and at the last step) into `--out-dir`, as
    /// `step-NNNNNN.glb`.
    #[arg(long, value_name = "K", requires = "out_dir")]
    pub every: Option<usize>,
    /// Directory for the `--every` files (created if missing).
    #[arg(long, value_name = "DIR", requires = "every")]
    pub out_dir: Option<PathBuf>,
}

/// Histories at least this long get progress lines (every tenth of the way).
const PROGRESS_FROM: usize = 1_000;

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let loaded = ductile_io::read_history(&args.history)
        .with_context(|| format!("cannot load history {}", args.history.display()))?;
    let len = loaded.history.len();
    let to = args.to.unwrap_or(loaded.cursor);
    if to > len {
        bail!(
            "{}: --to {to} is past the end (the history has {len} steps)",
            args.history.display()
        );
    }
    let every = match args.every {
        Some(0) => bail!("--every must be at least 1"),
        other => other,
    };
    if let Some(dir) = &args.out_dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| super::apply::default_output(&args.history));
    writeln!(
        out,
        "{}: {len} steps, replaying to step {to}",
        args.history.display()
    )?;
    let mut meshes = MeshCache::new(&loaded);
    let progress_step = (to >= PROGRESS_FROM).then(|| to.div_ceil(10));
    let start = Instant::now();
    let base = loaded.history.base();
    let entries = loaded.history.entries();
    let doc = replay_with::<anyhow::Error>(base, entries, to, |n, doc| {
        if let Some(p) = progress_step
            && (n % p == 0 || n == to)
        {
            writeln!(
                out,
                "step {n}/{to} ({:.0} %) after {:.1} ms",
                100.0 * n as f64 / to as f64,
                super::ms(start.elapsed())
            )?;
        }
        if let (Some(k), Some(dir)) = (every, &args.out_dir)
            && (n % k == 0 || n == to)
        {
            let path = dir.join(format!("step-{n:06}.glb"));
            let count = meshes.export(doc, &path)?;
            writeln!(out, "step {n}: wrote {} ({count} meshes)", path.display())?;
        }
        Ok(())
    })
    .with_context(|| format!("cannot replay {}", args.history.display()))?;
    let replay_time = start.elapsed();
    let count = meshes.export(&doc, &output)?;
    writeln!(
        out,
        "replayed {to} steps in {:.2} ms; wrote {} ({count} meshes)",
        super::ms(replay_time),
        output.display()
    )?;
    Ok(0)
}

/// The rest meshes of a history's documents, loaded once per (node, source) relative to the
/// history's mesh root (mesh nodes added by the history load when first met).
struct MeshCache<'a> {
    loaded: &'a LoadedHistory,
    /// (node name, source as written, rest mesh).
    meshes: Vec<(String, String, RestMesh)>,
}

impl<'a> MeshCache<'a> {
    fn new(loaded: &'a LoadedHistory) -> Self {
        Self {
            loaded,
            meshes: Vec::new(),
        }
    }

    /// The rest mesh of mesh node `name` with source `source`.
    fn get(&mut self, name: &str, source: &str) -> anyhow::Result<RestMesh> {
        if let Some((_, _, rest)) = self
            .meshes
            .iter()
            .find(|(n, s, _)| n == name && s == source)
        {
            return Ok(rest.clone());
        }
        let loaded = ductile_io::scene::load_node_mesh(&self.loaded.mesh_root, name, source)?;
        self.meshes
            .push((name.to_owned(), source.to_owned(), loaded.rest.clone()));
        Ok(loaded.rest)
    }

    /// Evaluates every mesh of `doc` and writes them to `path`. Returns the mesh count.
    fn export(&mut self, doc: &Document, path: &Path) -> anyhow::Result<usize> {
        let mut rests = Vec::new();
        for node in &doc.nodes {
            if let NodeKind::Mesh(m) = &node.kind {
                rests.push((node.name.as_str(), self.get(&node.name, &m.source)?));
            }
        }
        let mut deformed = Vec::with_capacity(rests.len());
        for (name, rest) in &rests {
            deformed.push(
                doc.evaluate(name, rest)
                    .with_context(|| format!("cannot evaluate mesh '{name}'"))?,
            );
        }
        let exports: Vec<ExportMesh<'_>> = rests
            .iter()
            .zip(&deformed)
            .map(|((name, rest), d)| ExportMesh::deformed(name, rest, d))
            .collect();
        ductile_io::export_gltf(path, &exports)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(exports.len())
    }
}
