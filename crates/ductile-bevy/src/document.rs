//! The scene document as a bevy resource, edited only through history operations.
//!
//! [`SceneDocument`] owns the live [`Document`] and its [`History`]; views read it and ask
//! for edits with [`DocumentCommand`] messages, which [`apply_document_commands`] applies in
//! [`DuctileSystems::Edit`](crate::DuctileSystems::Edit). Nothing else mutates the document,
//! so the ECS mirror and the deformed meshes always follow it.
//!
//! The document has a current time ([`SceneDocument::time`]). Views show and edit the
//! **pose** at that time ([`SceneDocument::shown`], the document with every animated
//! channel at its track's value); an edit built against the pose is recorded as the edit of
//! the document that has the same effect at that time ([`Operation::onto_base`]): a changed
//! animated channel gets a key there.

use bevy::prelude::*;
use ductile_history::history::History;
use ductile_history::operation::Operation;
use ductile_scene::document::Document;

use crate::error::{DuctileBevyError, Result};

/// The live document, its undo history and a revision counter that changes on every edit.
#[derive(Resource, Debug, Clone)]
pub struct SceneDocument {
    document: Document,
    history: History,
    revision: u64,
    /// The document as last loaded or saved, to tell whether the live one differs.
    saved: Document,
    modified: bool,
    next_gesture: u64,
    /// Moves on when the document and its history are replaced (another file opened), so
    /// that what views remember per history step can be forgotten.
    epoch: u64,
    /// The current time in seconds.
    time: f32,
    /// The document at `time` when it has tracks (`None`: the document is its own pose).
    posed: Option<Document>,
    /// Why the document could not be posed at `time` (a bad track), if it could not.
    pose_error: Option<String>,
}

impl Default for SceneDocument {
    fn default() -> Self {
        Self::new(Document::default())
    }
}

impl SceneDocument {
    /// A document with an empty history that starts at it.
    #[must_use]
    pub fn new(document: Document) -> Self {
        Self::with_history(History::new(document.clone()), document)
    }

    /// A document reached by `history` (the caller checked that `document` is the history's
    /// base with its first `history.cursor()` steps applied, as a loaded project is).
    #[must_use]
    pub fn with_history(history: History, document: Document) -> Self {
        Self {
            saved: document.clone(),
            document,
            history,
            revision: 0,
            modified: false,
            next_gesture: 1,
            epoch: 0,
            time: 0.0,
            posed: None,
            pose_error: None,
        }
        .posed_again()
    }

    /// `self` with its pose computed.
    fn posed_again(mut self) -> Self {
        self.pose();
        self
    }

    /// Recomputes the pose at the current time.
    fn pose(&mut self) {
        self.pose_error = None;
        self.posed = if self.document.animation.is_static() {
            None
        } else {
            match self.document.at(self.time) {
                Ok(d) => Some(d),
                Err(e) => {
                    self.pose_error = Some(e.to_string());
                    None
                }
            }
        };
    }

    /// Replaces the document and its history (another file was opened, or saving rewrote
    /// mesh sources). The revision moves on, so everything re-synchronises.
    pub fn replace(&mut self, history: History, document: Document) {
        self.document = document;
        self.history = history;
        self.epoch += 1;
        let a = &self.document.animation;
        self.time = a.frame_time(a.start as f32);
        self.changed();
    }

    /// A number that changes when the document and its history are replaced (not by edits).
    #[must_use]
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// Moves the revision on, poses the document again and compares the live document
    /// with the saved one.
    fn changed(&mut self) {
        self.revision += 1;
        self.pose();
        self.modified = self.document != self.saved;
    }

    /// The document as shown at the current time: the pose when the document has tracks,
    /// else the document itself. Views draw this and build their edits against it.
    #[must_use]
    pub fn shown(&self) -> &Document {
        self.posed.as_ref().unwrap_or(&self.document)
    }

    /// The current time in seconds.
    #[must_use]
    pub fn time(&self) -> f32 {
        self.time
    }

    /// The current frame at the timeline's rate (`time · fps`, rounded to the nearest frame).
    #[must_use]
    pub fn frame(&self) -> f32 {
        (self.time * self.document.animation.fps).round()
    }

    /// Why the document cannot be posed at the current time (a track that does not fit its
    /// channel), if it cannot; it is then shown with its base values.
    #[must_use]
    pub fn pose_error(&self) -> Option<&str> {
        self.pose_error.as_deref()
    }

    /// Moves to time `t` seconds (non-finite times are ignored). The document is unchanged;
    /// the revision moves on when the pose does, so that meshes re-evaluate.
    pub fn set_time(&mut self, t: f32) {
        if !t.is_finite() || t == self.time {
            return;
        }
        self.time = t;
        if self.document.animation.is_static() {
            return;
        }
        self.revision += 1;
        // Playback moves the time every frame: pose the copy in place (every animated
        // channel is written again) instead of cloning the document.
        match &mut self.posed {
            Some(posed) => {
                if let Err(e) = posed.pose_at(&self.document, t) {
                    self.pose_error = Some(e.to_string());
                    self.posed = None;
                }
            }
            None => self.pose(),
        }
    }

    /// The live document.
    #[must_use]
    pub fn document(&self) -> &Document {
        &self.document
    }

    /// The undo history.
    #[must_use]
    pub fn history(&self) -> &History {
        &self.history
    }

    /// A number that changes with every applied edit, undo, redo or jump.
    #[must_use]
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// True when the document differs from the one last loaded or marked saved (undoing
    /// back to the saved state makes it unmodified again).
    #[must_use]
    pub fn is_modified(&self) -> bool {
        self.modified
    }

    /// Records that the current state is what is on disk.
    pub fn mark_saved(&mut self) {
        self.saved = self.document.clone();
        self.modified = false;
    }

    /// A new gesture id: edits pushed with the same id (a drag, a slider movement) merge
    /// into one undo step.
    pub fn new_gesture(&mut self) -> u64 {
        let g = self.next_gesture;
        self.next_gesture += 1;
        g
    }

    /// Applies `op`, an edit of the pose ([`SceneDocument::shown`]), and records it (merged
    /// into the previous step when `gesture` continues it). On error nothing changes.
    pub fn apply(
        &mut self,
        op: Operation,
        label: impl Into<String>,
        gesture: Option<u64>,
    ) -> Result<()> {
        let mut label = label.into();
        if label.is_empty() {
            label = op.describe();
        }
        let keys_before = key_count(&op);
        let op = op.onto_base(&self.document, self.shown(), self.time)?;
        if key_count(&op) > keys_before {
            // The edit changed animated channels: say so in the history (auto-key).
            label = format!("{label} (keyed at frame {})", self.frame());
        }
        self.history
            .push(&mut self.document, op, label, now_ms(), gesture)?;
        self.changed();
        Ok(())
    }

    /// Undoes the last step; `false` when there is none.
    pub fn undo(&mut self) -> Result<bool> {
        let done = self.history.undo(&mut self.document)?;
        if done {
            self.changed();
        }
        Ok(done)
    }

    /// Redoes the next step; `false` when there is none.
    pub fn redo(&mut self) -> Result<bool> {
        let done = self.history.redo(&mut self.document)?;
        if done {
            self.changed();
        }
        Ok(done)
    }

    /// Moves to the state after step `n` (0 = the history's base).
    pub fn jump(&mut self, n: usize) -> Result<()> {
        if n > self.history.len() {
            return Err(DuctileBevyError::NoSuchStep {
                step: n,
                len: self.history.len(),
            });
        }
        self.history.jump(&mut self.document, n)?;
        self.changed();
        Ok(())
    }
}

/// How many key edits `op` holds (groups counted through).
fn key_count(op: &Operation) -> usize {
    match op {
        Operation::SetKey { .. } => 1,
        Operation::Group { ops, .. } => ops.iter().map(key_count).sum(),
        _ => 0,
    }
}

fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX))
}

/// A request to edit the document. Panels, gizmos and shortcuts write these; they never
/// touch the document themselves.
#[derive(Message, Debug, Clone, PartialEq)]
pub enum DocumentCommand {
    /// Apply an operation and record it.
    Apply {
        /// The edit (boxed: an operation can hold a whole node).
        op: Box<Operation>,
        /// The history label ("" = the operation's own description).
        label: String,
        /// The gesture the edit belongs to (consecutive edits of one gesture are one step).
        gesture: Option<u64>,
    },
    /// Undo the last step.
    Undo,
    /// Redo the next step.
    Redo,
    /// Go to the state after step `n` of the history (0 = its base).
    Jump(usize),
    /// Go to time `t` seconds (view state: not recorded in the history).
    SetTime(f32),
}

impl DocumentCommand {
    /// An operation to apply as its own step.
    #[must_use]
    pub fn apply(op: Operation) -> Self {
        Self::Apply {
            op: Box::new(op),
            label: String::new(),
            gesture: None,
        }
    }
}

/// What an applied [`DocumentCommand`] did to the history, for views that remember something
/// per step (the Studio restores the selection that went with an undone or redone step).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub enum DocumentChange {
    /// A new step was recorded at this index (0-based); later steps were dropped.
    Pushed(usize),
    /// An edit merged into the step at this index (the same gesture).
    Merged(usize),
    /// The step at this index was undone.
    Undone(usize),
    /// The step at this index was redone.
    Redone(usize),
    /// The history cursor jumped (possibly over many steps).
    Jumped,
}

/// The last edit that was refused, for the status bar (cleared by the next successful one).
#[derive(Resource, Debug, Default, Clone, PartialEq)]
pub struct EditStatus {
    /// The error of the last refused command, as a sentence.
    pub last_error: Option<String>,
}

/// Applies every pending [`DocumentCommand`] in order. A refused command leaves the document
/// as it was and its error in [`EditStatus`].
pub fn apply_document_commands(
    mut commands: MessageReader<DocumentCommand>,
    mut doc: ResMut<SceneDocument>,
    mut status: ResMut<EditStatus>,
    mut changes: MessageWriter<DocumentChange>,
) {
    for command in commands.read() {
        let cursor = doc.history().cursor();
        let result = match command.clone() {
            DocumentCommand::Apply { op, label, gesture } => {
                doc.apply(*op, label, gesture).map(|()| {
                    let now = doc.history().cursor();
                    Some(if now > cursor {
                        DocumentChange::Pushed(now - 1)
                    } else {
                        DocumentChange::Merged(now.saturating_sub(1))
                    })
                })
            }
            DocumentCommand::Undo => doc
                .undo()
                .map(|done| done.then(|| DocumentChange::Undone(cursor - 1))),
            DocumentCommand::Redo => doc
                .redo()
                .map(|done| done.then_some(DocumentChange::Redone(cursor))),
            DocumentCommand::Jump(n) => doc.jump(n).map(|()| Some(DocumentChange::Jumped)),
            DocumentCommand::SetTime(t) => {
                doc.set_time(t);
                Ok(None)
            }
        };
        match result {
            Ok(change) => {
                status.last_error = None;
                if let Some(c) = change {
                    changes.write(c);
                }
            }
            Err(e) => {
                warn!("edit refused: {e}");
                status.last_error = Some(e.to_string());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ductile_scene::document::{Node, NodeKind};
    use ductile_scene::transform::Transform;

    fn group(name: &str) -> Operation {
        let node = Node {
            name: name.to_owned(),
            parent: None,
            transform: Transform::IDENTITY,
            kind: NodeKind::Group,
        };
        Operation::add_node(&Document::default(), node)
    }

    #[test]
    fn the_document_is_shown_and_edited_at_the_current_time() -> Result<()> {
        use ductile_scene::prelude::{Key, Value};
        let mut d = Document::default();
        Operation::add_node(&d, {
            let Operation::AddNode { node, .. } = group("g") else {
                unreachable!()
            };
            node
        })
        .apply(&mut d)?;
        let keys = vec![
            Key::new(0.0, Value::Vector(Vec3::ZERO)),
            Key::new(1.0, Value::Vector(Vec3::X)),
        ];
        d.animation
            .tracks
            .entry("g".into())
            .or_default()
            .insert("transform.translation".into(), keys);
        let mut doc = SceneDocument::new(d);
        let r = doc.revision();
        doc.set_time(0.5);
        assert!(doc.revision() > r, "a new pose re-evaluates");
        let at = |doc: &SceneDocument| doc.shown().node("g").unwrap().transform.translation;
        assert_eq!(at(&doc), Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(
            doc.document().node("g").unwrap().transform.translation,
            Vec3::ZERO
        );
        // An edit of the pose keys the animated channel at 0.5 s, in one undo step.
        let mut t = doc.shown().node("g").unwrap().transform;
        t.translation = Vec3::Y;
        doc.apply(Operation::set_transform(doc.shown(), "g", t)?, "", None)?;
        assert_eq!(at(&doc), Vec3::Y);
        assert_eq!(
            doc.history().entries()[0].label,
            "set transform of 'g' (keyed at frame 12)",
            "the history says the edit keyed"
        );
        doc.set_time(1.0);
        assert_eq!(at(&doc), Vec3::X, "the key at 1 s is untouched");
        assert!(doc.undo()?);
        doc.set_time(0.5);
        assert_eq!(at(&doc), Vec3::new(0.5, 0.0, 0.0));
        Ok(())
    }

    #[test]
    fn undoing_back_to_the_saved_state_is_unmodified() -> Result<()> {
        let mut doc = SceneDocument::default();
        assert!(!doc.is_modified());
        doc.apply(group("a"), "", None)?;
        assert!(doc.is_modified());
        assert!(doc.undo()?);
        assert!(!doc.is_modified(), "back at the loaded state");
        assert!(doc.redo()?);
        doc.mark_saved();
        assert!(!doc.is_modified());
        doc.apply(group("b"), "", None)?;
        assert!(doc.is_modified());
        doc.jump(1)?;
        assert!(!doc.is_modified(), "back at the saved state");
        doc.jump(0)?;
        assert!(doc.is_modified(), "before the saved state");
        Ok(())
    }
}
