//! `ductile export-morphs SCENE -o OUT.glb`: the rest meshes with one morph target per
//! variant, named after it, so that any glTF viewer blends the faces live; prints how far a
//! 50/50 morph blend of each pair lies from the blend of their parameters.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context as _;
use ductile_io::bake::{export_variant_morphs, morph_blend_error};

/// Arguments of `ductile export-morphs`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON), or a history file.
    pub scene: PathBuf,
    /// Output file, `.glb` or `.gltf`.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let scene = super::load_input(&args.scene)?;
    let names = export_variant_morphs(&scene, &args.output, &mut |_, _| {})
        .with_context(|| format!("cannot export morph targets to {}", args.output.display()))?;
    writeln!(
        out,
        "wrote {} ({} morph targets: {})",
        args.output.display(),
        names.len(),
        names.join(", ")
    )?;
    writeln!(
        out,
        "morph blend vs parameter blend at t = 0.5 (largest vertex distance, rms, share of the mesh size):"
    )?;
    for (i, a) in names.iter().enumerate() {
        for b in &names[i + 1..] {
            let e = morph_blend_error(&scene, a, b, 0.5)?;
            writeln!(
                out,
                "  {a} + {b}: max {:.3e}, rms {:.3e}, {:.4} %",
                e.max,
                e.rms,
                100.0 * e.relative
            )?;
        }
    }
    Ok(0)
}
