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
//!
//! Keys are set as the artist edits only with **auto-key** on ([`SceneDocument::auto_key`],
//! as Blender's record button). With it off (the default, as in Blender), an edit that would
//! add a key to an animated channel at a frame where it has none is held as a
//! [`PendingEdit`]: shown in the pose, offered to be keyed ([`DocumentCommand::KeyPending`])
//! or reverted ([`DocumentCommand::RevertPending`]); further edits join it until then, and
//! moving in time, undo or another file drops it. Edits of channels at their keys and of
//! channels without a track are recorded at once either way.

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
    /// Key animated channels as they are edited (else such edits are offered to be keyed).
    auto_key: bool,
    /// An edit of animated channels waiting to be keyed or reverted.
    pending: Option<PendingEdit>,
}

/// Edits of animated channels at a time where they have no key, made with auto-key off:
/// shown in the pose until the artist keys them (one undo step) or reverts them.
#[derive(Debug, Clone)]
pub struct PendingEdit {
    /// The edits of the pose, in order (a gesture's edits merged into one).
    ops: Vec<Operation>,
    /// The label of the first edit.
    label: String,
    /// The gesture of the last edit (a drag goes on joining its own edit).
    gesture: Option<u64>,
    /// The edit of the document that keys them: keys at `time`, base edits for the rest.
    keyed: Operation,
    /// The pose with the edits applied (what is shown).
    posed: Document,
    /// The time the edits were made at, in seconds.
    time: f32,
    /// The channels that would get a new key, as (node, channel path).
    channels: Vec<(String, String)>,
}

impl PendingEdit {
    /// The channels the edit would add a key to, as (node, channel path).
    #[must_use]
    pub fn channels(&self) -> &[(String, String)] {
        &self.channels
    }

    /// The label of the first edit.
    #[must_use]
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The time the edits were made at, in seconds.
    #[must_use]
    pub fn time(&self) -> f32 {
        self.time
    }
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
            auto_key: false,
            pending: None,
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
        self.pending = None;
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
        match &self.pending {
            Some(p) => &p.posed,
            None => self.pose_of_document(),
        }
    }

    /// The pose of the document alone, without a pending edit.
    fn pose_of_document(&self) -> &Document {
        self.posed.as_ref().unwrap_or(&self.document)
    }

    /// Whether edits of animated channels set keys as they are made (else they are offered,
    /// see [`SceneDocument::pending`]).
    #[must_use]
    pub fn auto_key(&self) -> bool {
        self.auto_key
    }

    /// Turns auto-key on or off (view state: not recorded). Turning it on keys a pending
    /// edit, as the artist asked for edits to be keyed.
    ///
    /// # Errors
    /// Keying the pending edit failed (it is then dropped).
    pub fn set_auto_key(&mut self, on: bool) -> Result<()> {
        self.auto_key = on;
        if on && self.pending.is_some() {
            self.key_pending()?;
        }
        Ok(())
    }

    /// The edit of animated channels waiting to be keyed or reverted, if any.
    #[must_use]
    pub fn pending(&self) -> Option<&PendingEdit> {
        self.pending.as_ref()
    }

    /// Records the pending edit with its keys as one undo step ("… (keyed at frame N)");
    /// `false` when there is none.
    ///
    /// # Errors
    /// The edit no longer applies (it is then dropped and the document is unchanged).
    pub fn key_pending(&mut self) -> Result<bool> {
        let Some(p) = self.pending.take() else {
            return Ok(false);
        };
        let label = format!("{} (keyed at frame {})", p.label, self.frame());
        let result = self
            .history
            .push(&mut self.document, p.keyed, label, now_ms(), None);
        self.changed();
        result?;
        Ok(true)
    }

    /// Drops the pending edit, showing the pose of the document again; `false` when there
    /// was none.
    pub fn revert_pending(&mut self) -> bool {
        let had = self.pending.take().is_some();
        if had {
            self.revision += 1;
        }
        had
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
    /// A pending edit is dropped (its keys would belong to the time it was made at).
    pub fn set_time(&mut self, t: f32) {
        if !t.is_finite() || t == self.time {
            return;
        }
        self.revert_pending();
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
    /// back to the saved state makes it unmodified again), or an edit waits to be keyed.
    #[must_use]
    pub fn is_modified(&self) -> bool {
        self.modified || self.pending.is_some()
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
    /// into the previous step when `gesture` continues it). With auto-key off, an edit that
    /// would add a key to an animated channel is held as the pending edit instead (and an
    /// edit made while one is pending joins it). On error nothing changes.
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
        if self.pending.is_some() {
            return self.join_pending(op, gesture);
        }
        let new_keys_before = new_keys(&op).len();
        let keyed = op
            .clone()
            .onto_base(&self.document, self.shown(), self.time)?;
        let added = new_keys(&keyed);
        if !self.auto_key && added.len() > new_keys_before {
            let mut posed = self.shown().clone();
            op.apply(&mut posed)?;
            self.pending = Some(PendingEdit {
                ops: vec![op],
                label,
                gesture,
                keyed,
                posed,
                time: self.time,
                channels: added,
            });
            self.revision += 1;
            return Ok(());
        }
        if key_count(&keyed) > key_count(&op) {
            // The edit changed animated channels: say so in the history (auto-key).
            label = format!("{label} (keyed at frame {})", self.frame());
        }
        self.history
            .push(&mut self.document, keyed, label, now_ms(), gesture)?;
        self.changed();
        Ok(())
    }

    /// Adds `op` (an edit of the shown pose) to the pending edit.
    fn join_pending(&mut self, op: Operation, gesture: Option<u64>) -> Result<()> {
        let Some(p) = &self.pending else {
            return Ok(());
        };
        let mut posed = p.posed.clone();
        op.apply(&mut posed)?;
        let mut ops = p.ops.clone();
        let merged = gesture.is_some()
            && p.gesture == gesture
            && ops.last_mut().is_some_and(|last| last.merge(&op));
        if !merged {
            ops.push(op);
        }
        let all = Operation::Group {
            label: p.label.clone(),
            ops: ops.clone(),
        };
        let keyed = all.onto_base(&self.document, self.pose_of_document(), self.time)?;
        let channels = new_keys(&keyed);
        if let Some(p) = &mut self.pending {
            p.ops = ops;
            p.gesture = gesture;
            p.keyed = keyed;
            p.posed = posed;
            p.channels = channels;
        }
        self.revision += 1;
        Ok(())
    }

    /// Applies `command` (see [`apply_document_commands`]) and says what it did to the
    /// history, if anything.
    ///
    /// # Errors
    /// The command was refused; nothing changed.
    pub fn run(&mut self, command: DocumentCommand) -> Result<Option<DocumentChange>> {
        let cursor = self.history.cursor();
        Ok(match command {
            DocumentCommand::Apply { op, label, gesture } => {
                self.apply(*op, label, gesture)?;
                let now = self.history.cursor();
                (now != cursor || self.pending.is_none()).then(|| {
                    if now > cursor {
                        DocumentChange::Pushed(now - 1)
                    } else {
                        DocumentChange::Merged(now.saturating_sub(1))
                    }
                })
            }
            // Undo first takes back an edit waiting to be keyed.
            DocumentCommand::Undo if self.revert_pending() => None,
            DocumentCommand::Undo => self.undo()?.then(|| DocumentChange::Undone(cursor - 1)),
            DocumentCommand::Redo => {
                self.revert_pending();
                self.redo()?.then_some(DocumentChange::Redone(cursor))
            }
            DocumentCommand::Jump(n) => {
                self.jump(n)?;
                Some(DocumentChange::Jumped)
            }
            DocumentCommand::SetTime(t) => {
                self.set_time(t);
                None
            }
            DocumentCommand::KeyPending => self
                .key_pending()?
                .then(|| DocumentChange::Pushed(self.history.cursor() - 1)),
            DocumentCommand::RevertPending => {
                self.revert_pending();
                None
            }
            DocumentCommand::SetAutoKey(on) => {
                let keyed = self.pending.is_some() && on;
                self.set_auto_key(on)?;
                keyed.then(|| DocumentChange::Pushed(self.history.cursor() - 1))
            }
        })
    }

    /// Undoes the last step; `false` when there is none.
    pub fn undo(&mut self) -> Result<bool> {
        self.revert_pending();
        let done = self.history.undo(&mut self.document)?;
        if done {
            self.changed();
        }
        Ok(done)
    }

    /// Redoes the next step; `false` when there is none.
    pub fn redo(&mut self) -> Result<bool> {
        self.revert_pending();
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
        self.pending = None;
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

/// The keys `op` adds where its channel had none, as (node, channel path) (groups counted
/// through).
fn new_keys(op: &Operation) -> Vec<(String, String)> {
    match op {
        Operation::SetKey {
            node,
            param,
            old: None,
            new: Some(_),
            ..
        } => vec![(node.clone(), param.clone())],
        Operation::Group { ops, .. } => ops.iter().flat_map(new_keys).collect(),
        _ => Vec::new(),
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
    /// Go to time `t` seconds (view state: not recorded in the history; drops a pending
    /// edit).
    SetTime(f32),
    /// Key the pending edit ([`SceneDocument::pending`]) as one step.
    KeyPending,
    /// Drop the pending edit.
    RevertPending,
    /// Turn auto-key on or off (on keys a pending edit).
    SetAutoKey(bool),
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
        // Moving in time or through the history drops an edit waiting to be keyed: say so.
        let dropped = doc
            .pending()
            .filter(|_| {
                matches!(
                    command,
                    DocumentCommand::SetTime(_) | DocumentCommand::Jump(_)
                )
            })
            .map(|p| (p.label().to_owned(), p.time()));
        let fps = doc.document().animation.fps;
        let result = doc.run(command.clone());
        match result {
            Ok(change) => {
                status.last_error = dropped.filter(|_| doc.pending().is_none()).map(|(l, t)| {
                    format!(
                        "'{l}' was not keyed and is dropped: an edit of animated fields at \
                         frame {} holds only until the frame changes (K keys it; Auto-key \
                         keys as you edit)",
                        (t * fps).round()
                    )
                });
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
        let mut doc = keyed_group()?;
        doc.set_auto_key(true)?;
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

    /// A group "g" whose translation is keyed 0 at 0 s and X at 1 s, at time 0.
    fn keyed_group() -> Result<SceneDocument> {
        use ductile_scene::prelude::{Key, Value};
        let mut d = Document::default();
        group("g").apply(&mut d)?;
        let keys = vec![
            Key::new(0.0, Value::Vector(Vec3::ZERO)),
            Key::new(1.0, Value::Vector(Vec3::X)),
        ];
        d.animation
            .tracks
            .entry("g".into())
            .or_default()
            .insert("transform.translation".into(), keys);
        Ok(SceneDocument::new(d))
    }

    fn moved_to(doc: &SceneDocument, to: Vec3) -> Result<Operation> {
        let mut t = doc.shown().node("g").expect("g").transform;
        t.translation = to;
        Ok(Operation::set_transform(doc.shown(), "g", t)?)
    }

    #[test]
    fn without_auto_key_an_edit_between_keys_is_offered_then_keyed_in_one_step() -> Result<()> {
        let mut doc = keyed_group()?;
        doc.set_time(0.5);
        assert!(!doc.auto_key(), "auto-key is off by default, as in Blender");
        let at = |doc: &SceneDocument| doc.shown().node("g").unwrap().transform.translation;
        // A drag of two edits in one gesture: shown, not recorded, offered as one edit.
        let g = doc.new_gesture();
        doc.apply(moved_to(&doc, Vec3::Y)?, "move g", Some(g))?;
        doc.apply(moved_to(&doc, Vec3::Z)?, "move g", Some(g))?;
        assert_eq!(at(&doc), Vec3::Z, "the pose shows the edit");
        assert!(doc.history().is_empty(), "nothing is recorded yet");
        assert!(
            doc.is_modified(),
            "an edit waiting to be keyed is unsaved work"
        );
        let p = doc.pending().expect("offered");
        assert_eq!(
            p.channels(),
            [("g".to_owned(), "transform.translation".to_owned())]
        );
        // Another edit while the offer is open joins it.
        doc.apply(moved_to(&doc, Vec3::ONE)?, "move g again", None)?;
        assert_eq!(at(&doc), Vec3::ONE);
        assert!(doc.history().is_empty());
        // Keying records one step with the key at 0.5 s; the other keys are untouched.
        assert_eq!(
            doc.run(DocumentCommand::KeyPending)?,
            Some(DocumentChange::Pushed(0))
        );
        assert!(doc.pending().is_none());
        assert_eq!(doc.history().len(), 1);
        assert_eq!(
            doc.history().entries()[0].label,
            "move g (keyed at frame 12)"
        );
        assert_eq!(at(&doc), Vec3::ONE);
        doc.set_time(1.0);
        assert_eq!(at(&doc), Vec3::X);
        doc.set_time(0.75);
        assert_eq!(
            at(&doc),
            (Vec3::ONE + Vec3::X) / 2.0,
            "the new key interpolates"
        );
        // One undo takes the whole keyed edit back.
        assert!(doc.undo()?);
        doc.set_time(0.5);
        assert_eq!(at(&doc), Vec3::new(0.5, 0.0, 0.0));
        Ok(())
    }

    #[test]
    fn an_offered_edit_is_reverted_by_undo_revert_or_a_new_frame() -> Result<()> {
        let mut doc = keyed_group()?;
        doc.set_time(0.5);
        let at = |doc: &SceneDocument| doc.shown().node("g").unwrap().transform.translation;
        let rest = at(&doc);
        let r = doc.revision();
        doc.apply(moved_to(&doc, Vec3::Y)?, "", None)?;
        assert!(doc.revision() > r, "the pose re-evaluates");
        assert_eq!(
            doc.run(DocumentCommand::Undo)?,
            None,
            "undo drops the offer"
        );
        assert_eq!(at(&doc), rest);
        assert!(doc.pending().is_none() && doc.history().is_empty());
        doc.apply(moved_to(&doc, Vec3::Y)?, "", None)?;
        doc.run(DocumentCommand::RevertPending)?;
        assert_eq!(at(&doc), rest);
        doc.apply(moved_to(&doc, Vec3::Y)?, "", None)?;
        doc.set_time(0.25);
        doc.set_time(0.5);
        assert_eq!(at(&doc), rest, "a new frame drops the unkeyed edit");
        assert!(!doc.is_modified());
        // At a key, an edit changes that key at once; so does any edit with auto-key on.
        doc.set_time(1.0);
        doc.apply(moved_to(&doc, Vec3::Y)?, "", None)?;
        assert!(doc.pending().is_none());
        assert_eq!(doc.history().len(), 1);
        doc.set_time(0.5);
        doc.apply(moved_to(&doc, Vec3::Z)?, "", None)?;
        assert!(doc.pending().is_some());
        doc.run(DocumentCommand::SetAutoKey(true))?;
        assert!(
            doc.pending().is_none(),
            "turning auto-key on keys the offered edit"
        );
        assert_eq!(doc.history().len(), 2);
        assert_eq!(at(&doc), Vec3::Z);
        doc.apply(moved_to(&doc, Vec3::X)?, "", None)?;
        assert_eq!(doc.history().len(), 3, "auto-key records at once");
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
