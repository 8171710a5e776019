//! Undo and redo bring back the selection that went with the step, as in Blender: undoing
//! "add volume" selects again the layer's tool that was selected before the volume was
//! added (not a node that no longer exists); redoing it selects what was selected when it
//! was undone. The memory is view state kept beside the history: it is never saved, and it
//! is forgotten when another document is opened.

use bevy::prelude::*;

use crate::document::{DocumentChange, SceneDocument};
use crate::selection::Selection;

/// The selection before and after each history step, by step index.
#[derive(Resource, Debug, Default)]
pub struct SelectionMemory {
    epoch: u64,
    /// The selection as the current frame started (before this frame's input changed it).
    frame_start: Selection,
    before: Vec<Option<Selection>>,
    after: Vec<Option<Selection>>,
}

impl SelectionMemory {
    fn slot(&mut self, k: usize) {
        if self.before.len() <= k {
            self.before.resize(k + 1, None);
            self.after.resize(k + 1, None);
        }
    }

    /// Records `change` with the selection `current` (after the command, before any
    /// restoring) and returns the selection to restore, if any. `start` is the selection as
    /// the frame started: the one a new step was made from.
    pub fn record(
        &mut self,
        change: DocumentChange,
        start: &Selection,
        current: &Selection,
    ) -> Option<Selection> {
        match change {
            DocumentChange::Pushed(k) => {
                self.before.truncate(k);
                self.after.truncate(k);
                self.slot(k);
                self.before[k] = Some(start.clone());
                None
            }
            DocumentChange::Undone(k) => {
                self.slot(k);
                self.after[k] = Some(current.clone());
                self.before[k].clone()
            }
            DocumentChange::Redone(k) => {
                self.slot(k);
                self.before[k] = Some(current.clone());
                self.after[k].clone()
            }
            DocumentChange::Merged(_) | DocumentChange::Jumped => None,
        }
    }
}

/// Remembers the selection as the frame starts (runs in `First`).
pub fn remember_frame_selection(selection: Res<Selection>, mut memory: ResMut<SelectionMemory>) {
    if memory.frame_start != *selection {
        memory.frame_start.clone_from(&selection);
    }
}

/// Restores the selection of undone and redone steps; what no longer exists is left
/// unselected, and hidden nodes stay as they are (hiding is not selection).
pub fn restore_selection_on_undo(
    mut changes: MessageReader<DocumentChange>,
    doc: Res<SceneDocument>,
    mut selection: ResMut<Selection>,
    mut memory: ResMut<SelectionMemory>,
) {
    if memory.epoch != doc.epoch() {
        *memory = SelectionMemory {
            epoch: doc.epoch(),
            frame_start: selection.clone(),
            ..SelectionMemory::default()
        };
    }
    for change in changes.read() {
        let start = memory.frame_start.clone();
        let Some(mut restored) = memory.record(*change, &start, &selection) else {
            continue;
        };
        let document = doc.document();
        restored.hidden.clone_from(&selection.hidden);
        if restored
            .node
            .as_ref()
            .is_some_and(|n| document.node(n).is_err())
        {
            restored.node = None;
            restored.handles.clear();
        }
        if restored
            .layer
            .as_ref()
            .is_some_and(|(mesh, i)| !document.mesh(mesh).is_ok_and(|m| *i < m.stack.len()))
        {
            restored.layer = None;
        }
        selection.set_if_neq(restored);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sel(node: &str) -> Selection {
        let mut s = Selection::default();
        s.select(Some(node.to_owned()));
        s
    }

    #[test]
    fn undo_restores_the_selection_before_the_step_and_redo_the_one_after() {
        let mut m = SelectionMemory::default();
        // Step 0 made with "lattice" selected; the new "sphere" got selected.
        assert_eq!(
            m.record(DocumentChange::Pushed(0), &sel("lattice"), &sel("sphere")),
            None
        );
        assert_eq!(
            m.record(DocumentChange::Undone(0), &sel("sphere"), &sel("sphere")),
            Some(sel("lattice"))
        );
        assert_eq!(
            m.record(DocumentChange::Redone(0), &sel("lattice"), &sel("lattice")),
            Some(sel("sphere"))
        );
        // A new step after an undo drops what was remembered of the dropped steps.
        m.record(DocumentChange::Undone(0), &sel("sphere"), &sel("sphere"));
        m.record(DocumentChange::Pushed(0), &sel("a"), &sel("b"));
        assert_eq!(
            m.record(DocumentChange::Redone(0), &sel("a"), &sel("a")),
            None,
            "nothing known yet of the new step's after-selection"
        );
        // Merges and jumps change nothing.
        assert_eq!(
            m.record(DocumentChange::Merged(0), &sel("x"), &sel("y")),
            None
        );
        assert_eq!(m.record(DocumentChange::Jumped, &sel("x"), &sel("y")), None);
    }

    #[test]
    fn steps_unknown_to_the_memory_restore_nothing() {
        let mut m = SelectionMemory::default();
        assert_eq!(
            m.record(DocumentChange::Undone(5), &sel("a"), &sel("a")),
            None
        );
        assert_eq!(
            m.record(DocumentChange::Redone(5), &sel("a"), &sel("a")),
            Some(sel("a")),
            "redo of a step undone here brings back the selection it was undone with"
        );
    }
}
