//! Autosave and crash recovery: while the scene has unsaved edits, its whole history is
//! written to a recovery file ([`ductile_io::recovery`]) every 30 seconds and every 50 steps
//! (both configurable); saving, undoing back to the saved state, or quitting after "Discard"
//! removes it. A recovery file found at the next start is what a crash or a kill left: the
//! Studio offers to restore it (or restores it at once with `--recover`).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_egui::{EguiContexts, egui};
use ductile_bevy::prelude::*;
use ductile_io::recovery::{self, FoundRecovery};

use crate::studio::{Notices, OpenProject};

/// When the recovery file is written, and what this session wrote.
#[derive(Resource, Debug)]
pub struct Autosave {
    /// Write at least this often while there are unsaved edits.
    pub every: Duration,
    /// Write after this many new steps (edits, undos, redos), however soon.
    pub every_steps: u32,
    /// A recovery file from an earlier session, offered until the user answers.
    pub offer: Option<FoundRecovery>,
    /// The user chose to discard the unsaved edits on quitting: remove the file at exit.
    pub discard_on_exit: bool,
    written: Option<PathBuf>,
    last_write: Instant,
    last_step: (usize, usize),
    steps_since: u32,
    last_revision: u64,
    failed: bool,
}

impl Autosave {
    /// Autosave every `every` and every `every_steps` steps, offering `offer` first.
    #[must_use]
    pub fn new(every: Duration, every_steps: u32, offer: Option<FoundRecovery>) -> Self {
        Self {
            every,
            every_steps: every_steps.max(1),
            offer,
            discard_on_exit: false,
            written: None,
            last_write: Instant::now(),
            last_step: (0, 0),
            steps_since: 0,
            last_revision: 0,
            failed: false,
        }
    }

    fn discard_written(&mut self, notices: &mut Notices) {
        if let Some(path) = self.written.take()
            && let Err(e) = recovery::discard_recovery(&path)
        {
            notices.push_result(Err(ductile_io::report(&e)));
        }
    }
}

/// Writes the recovery file when it is due, and removes it once nothing is unsaved.
pub fn autosave(
    mut state: ResMut<Autosave>,
    doc: Res<SceneDocument>,
    project: Res<OpenProject>,
    mut notices: ResMut<Notices>,
) {
    if state.offer.is_some() {
        // The file of the earlier session is still waiting for an answer: never overwrite it.
        return;
    }
    let history = doc.history();
    let step = (history.len(), history.cursor());
    if step != state.last_step {
        state.last_step = step;
        state.steps_since += 1;
    }
    if !doc.is_modified() {
        state.discard_written(&mut notices);
        state.steps_since = 0;
        state.last_revision = doc.revision();
        state.last_write = Instant::now();
        return;
    }
    let due = state.steps_since >= state.every_steps || state.last_write.elapsed() >= state.every;
    if doc.revision() == state.last_revision || !due {
        return;
    }
    let path = recovery::recovery_path(&project.0);
    if state.written.as_ref().is_some_and(|w| *w != path) {
        // Saved under another name since: the old file would be offered for the wrong scene.
        state.discard_written(&mut notices);
    }
    state.last_write = Instant::now();
    state.last_revision = doc.revision();
    state.steps_since = 0;
    match recovery::write_recovery(&path, history) {
        Ok(()) => {
            state.written = Some(path);
            state.failed = false;
        }
        Err(e) if !state.failed => {
            state.failed = true;
            notices.push_result(Err(format!("autosave failed: {}", ductile_io::report(&e))));
        }
        Err(_) => {}
    }
}

/// At a normal exit: the recovery file stays only when there are unsaved edits the user did
/// not choose to discard (the window closed without asking), so that the next start offers
/// them; otherwise it is removed.
pub fn autosave_at_exit(
    mut exits: MessageReader<AppExit>,
    mut state: ResMut<Autosave>,
    doc: Res<SceneDocument>,
    project: Res<OpenProject>,
    mut notices: ResMut<Notices>,
) {
    if exits.read().next().is_none() {
        return;
    }
    if doc.is_modified() && !state.discard_on_exit && state.offer.is_none() {
        let path = recovery::recovery_path(&project.0);
        if recovery::write_recovery(&path, doc.history()).is_ok() {
            state.written = Some(path);
        }
    } else {
        state.discard_written(&mut notices);
    }
}

/// Restores the recovery file `found` into the open document (unsaved, so that Save writes
/// it to the scene file).
fn recover(found: &FoundRecovery, doc: &mut SceneDocument, notices: &mut Notices) {
    match recovery::read_recovery(&found.path) {
        Ok((history, document)) => {
            // The same scene, so the view stays where it is (as after an undo).
            doc.replace(history, document);
            notices.push_result(Ok(format!(
                "recovered {} of unsaved work from {}",
                steps(found.steps),
                found.path.display()
            )));
        }
        Err(e) => notices.push_result(Err(ductile_io::report(&e))),
    }
}

/// "1 step", "N steps".
fn steps(n: usize) -> String {
    if n == 1 {
        "1 step".to_owned()
    } else {
        format!("{n} steps")
    }
}

/// `--recover`: restores the recovery file at start, without asking.
pub fn recover_at_start(
    mut state: ResMut<Autosave>,
    mut doc: ResMut<SceneDocument>,
    mut notices: ResMut<Notices>,
) {
    if let Some(found) = state.offer.take() {
        recover(&found, &mut doc, &mut notices);
        state.written = Some(found.path);
    }
}

/// The offer to restore a recovery file, until the user answers it.
pub fn recovery_offer(
    mut contexts: EguiContexts,
    mut state: ResMut<Autosave>,
    mut doc: ResMut<SceneDocument>,
    mut notices: ResMut<Notices>,
) -> Result {
    let Some(found) = state.offer.clone() else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    let age = found.written.elapsed().unwrap_or_default().as_secs();
    let when = if age < 120 {
        format!("{age} s ago")
    } else if age < 2 * 3600 {
        format!("{} min ago", age / 60)
    } else {
        format!("{} h ago", age / 3600)
    };
    let mut answer = None;
    egui::Window::new("Recover unsaved work?")
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
        .show(ctx, |ui| {
            ui.label(format!(
                "Ductile did not close normally. Unsaved work on this scene was autosaved \
                 {when}: {}.",
                steps(found.steps)
            ));
            let name = found.path.file_name().unwrap_or_default().to_string_lossy();
            ui.label(format!("Recovery file: {name}"))
                .on_hover_text(found.path.display().to_string());
            ui.horizontal(|ui| {
                if ui.button("Recover").clicked() {
                    answer = Some(true);
                }
                if ui.button("Discard").clicked() {
                    answer = Some(false);
                }
            });
        });
    match answer {
        Some(true) => {
            recover(&found, &mut doc, &mut notices);
            state.offer = None;
            state.written = Some(found.path);
        }
        Some(false) => {
            if let Err(e) = recovery::discard_recovery(&found.path) {
                notices.push_result(Err(ductile_io::report(&e)));
            }
            state.offer = None;
        }
        None => {}
    }
    Ok(())
}
