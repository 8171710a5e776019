//! `ductile variants SCENE`: one variant name per line, then how many tool states it holds
//! and how it was made.

use std::io::Write;
use std::path::PathBuf;

use ductile_scene::variant::Origin;

/// Arguments of `ductile variants`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (RON), or a history file.
    pub scene: PathBuf,
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let scene = super::load_input(&args.scene)?;
    for (name, v) in &scene.document.variants {
        let origin = match &v.origin {
            None => String::new(),
            Some(Origin::Blend { weights }) => {
                let w: Vec<String> = weights.iter().map(|(n, w)| format!("{n}={w}")).collect();
                format!(", blend of {}", w.join(","))
            }
            Some(Origin::Random { seed, sources, .. }) => {
                format!(", random from {} (seed {seed})", sources.join(","))
            }
        };
        writeln!(out, "{name}\t{} tool states{origin}", v.states.len())?;
    }
    Ok(0)
}
