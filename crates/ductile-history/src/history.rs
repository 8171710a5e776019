//! The undo history: a base document, the list of applied operations and a cursor.
//!
//! The history does not own the live document: every call takes it (`&mut Document`), and
//! the caller must always pass the document the history is at, that is the base with the
//! first [`History::cursor`] operations applied. Undo and redo run one operation
//! ([`Operation::revert`] / [`Operation::apply`]): their cost is that operation's, never the
//! history's length (no replay from the base, no copy of the document).

use ductile_scene::document::Document;
use serde::{Deserialize, Serialize};

use crate::error::{HistoryError, Result};
use crate::operation::Operation;

/// One step of a history: an operation and how to show it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// Text for the history panel (for example "move 'nose'").
    pub label: String,
    /// When the step was made, in milliseconds since the UNIX epoch, as supplied by the
    /// caller (the crate never reads the clock, so that it stays deterministic). For a
    /// merged gesture, the time of its first edit.
    #[serde(default)]
    pub time_ms: u64,
    /// The gesture (drag, slider movement) the step belongs to, if any: consecutive edits of
    /// the same target with the same gesture id are merged into one step.
    #[serde(default)]
    pub gesture: Option<u64>,
    /// The edit.
    pub op: Operation,
}

/// An undo history: the document it starts from, the steps, and how many of them are
/// applied.
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    base: Document,
    entries: Vec<Entry>,
    cursor: usize,
}

impl History {
    /// An empty history starting at `base` (usually a copy of the document being edited).
    #[must_use]
    pub fn new(base: Document) -> Self {
        Self {
            base,
            entries: Vec::new(),
            cursor: 0,
        }
    }

    /// A history of recorded steps, all applied (for example loaded from a file). Check it
    /// with [`replay`] (or [`History::document_at`]) before use: its steps are not checked
    /// here.
    #[must_use]
    pub fn from_entries(base: Document, entries: Vec<Entry>) -> Self {
        let cursor = entries.len();
        Self {
            base,
            entries,
            cursor,
        }
    }

    /// The document the history starts from.
    #[must_use]
    pub fn base(&self) -> &Document {
        &self.base
    }

    /// Every step, applied or not (the redo tail follows the cursor).
    #[must_use]
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// Number of steps applied: the live document is the base plus `entries()[..cursor]`.
    #[must_use]
    pub fn cursor(&self) -> usize {
        self.cursor
    }

    /// Number of steps, applied or not.
    #[must_use]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when there are no steps.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// True when a step can be undone.
    #[must_use]
    pub fn can_undo(&self) -> bool {
        self.cursor > 0
    }

    /// True when a step can be redone.
    #[must_use]
    pub fn can_redo(&self) -> bool {
        self.cursor < self.entries.len()
    }

    /// Splits the history into its base, steps and cursor.
    #[must_use]
    pub fn into_parts(self) -> (Document, Vec<Entry>, usize) {
        (self.base, self.entries, self.cursor)
    }

    /// Applies `op` to `doc` and records it as the next step, dropping the redo tail. With a
    /// `gesture` id equal to the previous step's, and an operation that continues it on the
    /// same target ([`Operation::can_merge`]), the previous step absorbs it instead (it keeps
    /// its time and first `old` value, and takes the new value and the new label, which
    /// describes the gesture's end: "morph 'a' to 'b' at 0.50", not where the drag began). An
    /// empty `label` is replaced by [`Operation::describe`]. On error nothing changes.
    pub fn push(
        &mut self,
        doc: &mut Document,
        op: Operation,
        label: impl Into<String>,
        time_ms: u64,
        gesture: Option<u64>,
    ) -> Result<()> {
        op.apply(doc)?;
        self.entries.truncate(self.cursor);
        let mut label = label.into();
        if label.is_empty() {
            label = op.describe();
        }
        if let (Some(g), Some(last)) = (gesture, self.entries.last_mut())
            && last.gesture == Some(g)
            && last.op.merge(&op)
        {
            last.label = label;
            return Ok(());
        }
        self.entries.push(Entry {
            label,
            time_ms,
            gesture,
            op,
        });
        self.cursor += 1;
        Ok(())
    }

    /// Undoes the last applied step. Returns `false` (and does nothing) at the start.
    pub fn undo(&mut self, doc: &mut Document) -> Result<bool> {
        if self.cursor == 0 {
            return Ok(false);
        }
        let entry = &self.entries[self.cursor - 1];
        entry
            .op
            .revert(doc)
            .map_err(|e| at_step(self.cursor, entry, e))?;
        self.cursor -= 1;
        Ok(true)
    }

    /// Redoes the next step. Returns `false` (and does nothing) at the end.
    pub fn redo(&mut self, doc: &mut Document) -> Result<bool> {
        let Some(entry) = self.entries.get(self.cursor) else {
            return Ok(false);
        };
        entry
            .op
            .apply(doc)
            .map_err(|e| at_step(self.cursor + 1, entry, e))?;
        self.cursor += 1;
        Ok(true)
    }

    /// Moves to step `n` (0 = the base) by undoing or redoing one step at a time. If a step
    /// fails, the document and cursor stay at the last step reached and the error names the
    /// failing step.
    pub fn jump(&mut self, doc: &mut Document, n: usize) -> Result<()> {
        if n > self.entries.len() {
            return Err(HistoryError::NoSuchStep {
                step: n,
                len: self.entries.len(),
            });
        }
        while self.cursor > n {
            self.undo(doc)?;
        }
        while self.cursor < n {
            self.redo(doc)?;
        }
        Ok(())
    }

    /// The document at step `n`, replayed from the base (see [`replay`]).
    pub fn document_at(&self, n: usize) -> Result<Document> {
        replay(&self.base, &self.entries, n)
    }
}

fn at_step(step: usize, entry: &Entry, e: HistoryError) -> HistoryError {
    HistoryError::AtStep {
        step,
        label: entry.label.clone(),
        source: Box::new(e),
    }
}

/// Applies the first `to` steps of `entries` to a copy of `base`, one by one, each checked
/// as when it was made. Errors name the failing step.
pub fn replay(base: &Document, entries: &[Entry], to: usize) -> Result<Document> {
    replay_with(base, entries, to, |_, _| Ok(()))
}

/// [`replay`], calling `after_step(n, document)` after step `n` (1-based) has been applied,
/// for progress reports or for writing intermediate results. An error returned by the
/// callback stops the replay and is returned as it is.
pub fn replay_with<E>(
    base: &Document,
    entries: &[Entry],
    to: usize,
    mut after_step: impl FnMut(usize, &Document) -> std::result::Result<(), E>,
) -> std::result::Result<Document, E>
where
    E: From<HistoryError>,
{
    if to > entries.len() {
        return Err(HistoryError::NoSuchStep {
            step: to,
            len: entries.len(),
        }
        .into());
    }
    let mut doc = base.clone();
    for (k, entry) in entries[..to].iter().enumerate() {
        entry
            .op
            .apply(&mut doc)
            .map_err(|e| at_step(k + 1, entry, e))?;
        after_step(k + 1, &doc)?;
    }
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ductile_scene::prelude::*;

    fn doc() -> Document {
        Document {
            nodes: vec![Node {
                name: "g".into(),
                parent: None,
                transform: Transform::IDENTITY,
                kind: NodeKind::Group,
            }],
            macros: Default::default(),
            ..Document::default()
        }
    }

    fn moved(doc: &Document, x: f32) -> Operation {
        Operation::set_transform(doc, "g", Transform::from_translation(glam::Vec3::X * x)).unwrap()
    }

    #[test]
    fn undo_of_a_document_that_was_changed_behind_the_history_is_refused() {
        let mut d = doc();
        let mut h = History::new(d.clone());
        let op = moved(&d, 1.0);
        h.push(&mut d, op, "move", 5, None).unwrap();
        // Someone edits the document without the history.
        d.nodes[0].transform = Transform::from_translation(glam::Vec3::Y);
        let before = d.clone();
        let err = h.undo(&mut d).unwrap_err();
        assert!(
            matches!(&err, HistoryError::AtStep { step: 1, label, source }
                if label == "move" && matches!(**source, HistoryError::Stale { .. })),
            "{err:?}"
        );
        assert_eq!(d, before);
        assert_eq!(h.cursor(), 1);
    }

    #[test]
    fn replay_reports_the_failing_step() {
        let mut d = doc();
        let mut h = History::new(d.clone());
        let op = moved(&d, 1.0);
        h.push(&mut d, op, "", 0, None).unwrap();
        let op = moved(&d, 2.0);
        h.push(&mut d, op, "", 0, None).unwrap();
        let mut entries = h.entries().to_vec();
        entries.remove(0);
        let err = replay(h.base(), &entries, 1).unwrap_err();
        assert!(
            matches!(err, HistoryError::AtStep { step: 1, .. }),
            "{err:?}"
        );
        assert!(matches!(
            replay(h.base(), h.entries(), 3),
            Err(HistoryError::NoSuchStep { step: 3, len: 2 })
        ));
        let mut seen = Vec::new();
        let end = replay_with(h.base(), h.entries(), 2, |n, _| {
            seen.push(n);
            Ok::<(), HistoryError>(())
        })
        .unwrap();
        assert_eq!(seen, [1, 2]);
        assert_eq!(end, d);
    }
}
