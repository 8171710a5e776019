//! `ductile blend SCENE (--variants A,B --t T | --weights A=w,B=w,… | --random A,B,… --seed S)
//! -o OUT.glb`: blend variants (skeleton-style for curve tools) and export the meshes.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context as _, bail};
use ductile_io::ExportMesh;
use ductile_scene::variant::{Origin, RandomOptions};

/// Arguments of `ductile blend`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("how").required(true).args(["variants", "weights", "random"])))]
pub struct Args {
    /// The scene file (RON), or a history file.
    pub scene: PathBuf,
    /// Two variants, blended `(1 − t)·A + t·B` with `--t`.
    #[arg(long, value_name = "A,B", value_delimiter = ',', requires = "t")]
    pub variants: Option<Vec<String>>,
    /// The blend factor of `--variants`: 0 gives A, 1 gives B, outside [0, 1] extrapolates
    /// (a caricature).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub t: Option<f32>,
    /// Any number of variants with weights summing to 1, as `A=0.2,B=0.5,C=0.3`.
    #[arg(long, value_name = "A=W,...", value_delimiter = ',')]
    pub weights: Option<Vec<String>>,
    /// A seeded random convex combination of these variants (with `--seed`).
    #[arg(long, value_name = "A,B,...", value_delimiter = ',', requires = "seed")]
    pub random: Option<Vec<String>>,
    /// Seed of `--random`: the same seed gives the same face on every machine.
    #[arg(long)]
    pub seed: Option<u64>,
    /// `--random`: how far from the mean of the variants the face may go, in [0, 1].
    #[arg(long, default_value_t = 1.0, requires = "random")]
    pub spread: f32,
    /// `--random`: largest difference between the values of a left/right macro pair.
    #[arg(long, requires = "random")]
    pub asymmetry: Option<f32>,
    /// Output file, `.glb` or `.gltf`.
    #[arg(short, long)]
    pub output: PathBuf,
}

fn parse_weights(items: &[String]) -> anyhow::Result<Vec<(String, f32)>> {
    items
        .iter()
        .map(|item| {
            let Some((name, w)) = item.split_once('=') else {
                bail!("--weights: '{item}' is not NAME=WEIGHT");
            };
            let w: f32 = w
                .trim()
                .parse()
                .with_context(|| format!("--weights: '{w}' is not a number"))?;
            Ok((name.trim().to_owned(), w))
        })
        .collect()
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let mut scene = super::load_input(&args.scene)?;
    let doc = &scene.document;
    let what = || format!("{}: cannot blend", args.scene.display());
    let variant = match (&args.variants, &args.weights, &args.random) {
        (Some(v), None, None) => {
            let [a, b] = v.as_slice() else {
                bail!("--variants takes two variants, as A,B (found {})", v.len());
            };
            let t = args.t.unwrap_or(0.0);
            doc.blend_two(a, b, t).with_context(what)?
        }
        (None, Some(w), None) => {
            let pairs = parse_weights(w)?;
            let refs: Vec<(&str, f32)> = pairs.iter().map(|(n, w)| (n.as_str(), *w)).collect();
            doc.blend_variants(&refs).with_context(what)?
        }
        (None, None, Some(sources)) => {
            let refs: Vec<&str> = sources.iter().map(String::as_str).collect();
            let options = RandomOptions {
                seed: args.seed.unwrap_or(0),
                spread: args.spread,
                asymmetry: args.asymmetry,
            };
            doc.random_variant(&refs, &options).with_context(what)?
        }
        _ => bail!("give exactly one of --variants, --weights and --random"),
    };
    match &variant.origin {
        Some(Origin::Blend { weights }) => {
            let w: Vec<String> = weights.iter().map(|(n, w)| format!("{n}={w}")).collect();
            writeln!(out, "weights: {}", w.join(", "))?;
        }
        Some(Origin::Random {
            seed,
            sources,
            weights,
            ..
        }) => {
            let w: Vec<String> = sources
                .iter()
                .zip(weights)
                .map(|(n, w)| format!("{n}={w}"))
                .collect();
            writeln!(out, "seed {seed}: weights {}", w.join(", "))?;
        }
        None => {}
    }
    scene.document = doc.with_states(&variant.states).with_context(what)?;
    let deformed = scene
        .meshes
        .iter()
        .map(|m| scene.evaluate(&m.name))
        .collect::<Result<Vec<_>, _>>()
        .with_context(what)?;
    let exports: Vec<ExportMesh<'_>> = scene
        .meshes
        .iter()
        .zip(&deformed)
        .map(|(m, d)| ExportMesh::deformed(&m.name, &m.rest, d))
        .collect();
    ductile_io::export_gltf(&args.output, &exports)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    writeln!(out, "wrote {}", args.output.display())?;
    Ok(0)
}
