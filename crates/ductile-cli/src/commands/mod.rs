//! One module per subcommand.

pub mod apply;
pub mod apply_batch;
pub mod bench;
pub mod blend;
pub mod check;
pub mod export_anim;
pub mod export_morphs;
pub mod history;
pub mod info;
pub mod replay;
pub mod variants;

use std::path::Path;

use anyhow::Context as _;
use ductile_io::LoadedScene;

/// Loads the scene a command works on, with every mesh.
///
/// This is the one place that decides what kind of input file a scene-consuming command
/// accepts: a scene file, or a history file (recognised by its content: a top-level
/// `entries` field), which is replayed to the step it was saved at, every step checked.
pub fn load_input(path: &Path) -> anyhow::Result<LoadedScene> {
    if ductile_io::is_history_file(path) {
        let loaded = ductile_io::read_history(path)
            .with_context(|| format!("cannot load history {}", path.display()))?;
        let document = loaded
            .replay(loaded.cursor)
            .with_context(|| format!("cannot replay history {}", path.display()))?;
        let problems = document.problems();
        if !problems.is_empty() {
            return Err(ductile_io::IoError::Scene {
                path: path.to_owned(),
                problems,
            })
            .with_context(|| format!("cannot load history {}", path.display()));
        }
        return loaded
            .scene(document)
            .with_context(|| format!("cannot load history {}", path.display()));
    }
    ductile_io::load_scene(path).with_context(|| format!("cannot load scene {}", path.display()))
}

/// The time in seconds of frame `frame` at `fps` frames per second (default: the scene's),
/// checked against the scene's timeline.
pub fn frame_time(scene: &LoadedScene, frame: f32, fps: Option<f32>) -> anyhow::Result<f32> {
    let anim = &scene.document.animation;
    let fps = fps.unwrap_or(anim.fps);
    if !(fps.is_finite() && fps > 0.0) {
        anyhow::bail!("--fps {fps} must be a number > 0");
    }
    let time = frame / fps;
    // The timeline's frames are at the scene's rate: compare times.
    let in_scene_frames = time * anim.fps;
    anim.check_frame(in_scene_frames)
        .map_err(|e| anyhow::anyhow!("{}: {e}", scene.path.display()))?;
    Ok(time)
}

/// Milliseconds of a duration, for reports.
#[must_use]
pub fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
