//! One module per subcommand.

pub mod apply;
pub mod bench;
pub mod check;
pub mod info;

use std::path::Path;

use anyhow::Context as _;
use ductile_io::LoadedScene;

/// Loads the scene a command works on, with every mesh.
///
/// This is the one place that decides what kind of input file a scene-consuming command
/// accepts; a history file (replayed to its final document) is to be dispatched here by
/// extension.
pub fn load_input(path: &Path) -> anyhow::Result<LoadedScene> {
    ductile_io::load_scene(path).with_context(|| format!("cannot load scene {}", path.display()))
}

/// Milliseconds of a duration, for reports.
#[must_use]
pub fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
