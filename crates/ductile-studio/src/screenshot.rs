//! `--screenshot OUT.png [--frames N]`: wait for N frames (and for background evaluations
//! to finish), capture the window, save it and exit; a failure exits with status 1.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use ductile_bevy::prelude::*;

/// Takes one screenshot and exits.
pub struct ScreenshotPlugin {
    /// Where to write the PNG.
    pub path: PathBuf,
    /// Frames to run first.
    pub frames: u32,
}

#[derive(Resource)]
struct ScreenshotRequest {
    path: PathBuf,
    frames: u32,
    counted: u32,
    taken: bool,
}

impl Plugin for ScreenshotPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ScreenshotRequest {
            path: self.path.clone(),
            frames: self.frames,
            counted: 0,
            taken: false,
        })
        .add_systems(Last, take_screenshot);
    }
}

/// Fails early when the screenshot's directory does not exist.
pub fn check_writable(path: &Path) -> anyhow::Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(dir) = dir {
        anyhow::ensure!(
            dir.is_dir(),
            "--screenshot '{}': the directory '{}' does not exist",
            path.display(),
            dir.display()
        );
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    anyhow::ensure!(
        ext.as_deref() == Some("png"),
        "--screenshot '{}': the file must end in .png",
        path.display()
    );
    Ok(())
}

fn take_screenshot(
    mut commands: Commands,
    mut request: ResMut<ScreenshotRequest>,
    evaluations: Query<&MeshEvaluation>,
    rests: Res<RestMeshes>,
    doc: Res<SceneDocument>,
) {
    if request.taken {
        return;
    }
    request.counted += 1;
    let busy = evaluations.iter().any(MeshEvaluation::is_running)
        || !rests.missing(doc.document()).is_empty();
    // Wait for the frames asked for, and (up to 40 × as many) for evaluation to settle.
    if request.counted < request.frames || (busy && request.counted < request.frames * 40) {
        return;
    }
    request.taken = true;
    let path = request.path.clone();
    commands.spawn(Screenshot::primary_window()).observe(
        move |captured: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| match save(
            &captured.image,
            &path,
        ) {
            Ok(()) => {
                info!("screenshot saved to {}", path.display());
                exit.write(AppExit::Success);
            }
            Err(e) => {
                error!("{e:#}");
                exit.write(AppExit::error());
            }
        },
    );
}

fn save(image: &Image, path: &Path) -> anyhow::Result<()> {
    let dynamic = image
        .clone()
        .try_into_dynamic()
        .with_context(|| format!("screenshot '{}': unsupported image format", path.display()))?;
    dynamic
        .to_rgb8()
        .save(path)
        .with_context(|| format!("cannot write the screenshot '{}'", path.display()))
}
