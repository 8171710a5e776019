//! `ductile-history`: every edit of a Ductile scene document as an undoable, serialisable
//! [`Operation`](operation::Operation), and the [`History`](history::History) that records
//! them, with undo, redo, jump to any step, gesture merging and replay from the base.
//!
//! Operations are plain data (serde): a history can be saved with its base scene and
//! replayed later, producing a document equal to the live one and therefore bit-identical
//! evaluated meshes. The file format is documented in `docs/history-format.md`; reading and
//! writing files is `ductile-io`'s job (this crate does no I/O and never reads the clock).

#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod authoring;
mod check;
pub mod edits;
pub mod error;
pub mod history;
pub mod operation;
pub mod pose;
pub mod time_edits;
mod time_ops;

/// The types most users need.
pub mod prelude {
    pub use crate::error::{HistoryError, Result};
    pub use crate::history::{Entry, History, replay, replay_with};
    pub use crate::operation::Operation;
}
