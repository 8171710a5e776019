//! The error type of `ductile-history`.

use ductile_scene::error::SceneError;
use thiserror::Error;

/// Why an operation, an undo, a redo, a jump or a replay was refused. Whenever one of these is
/// returned, the document is exactly as it was before the call (except for
/// [`History::jump`](crate::history::History::jump) and replays, which stop at the step
/// named in the error; see there).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum HistoryError {
    /// The edit would make the document invalid (unknown node, wrong kind, duplicate or empty
    /// name, cycle, non-finite number, tool parameter out of its domain, index out of range, …).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The operation's recorded "before" value is not what the document holds: the operation
    /// was made for another document (or another state of this one).
    #[error("{what}: the operation expects {expected} but the document has {found}")]
    Stale {
        /// The edited place (node, layer, area, macro).
        what: String,
        /// The value the operation expects, as printed.
        expected: String,
        /// The value the document holds, as printed.
        found: String,
    },
    /// Removing (or renaming into) something that is still referenced. Remove or change the
    /// references first, for example with
    /// [`Operation::remove_node_and_references`](crate::operation::Operation::remove_node_and_references).
    #[error("{what} is still referenced by {by}")]
    StillReferenced {
        /// What was to be removed.
        what: String,
        /// The first reference found.
        by: String,
    },
    /// A transform that cannot be inverted or used as a frame.
    #[error("{what}: degenerate transform ({problem})")]
    DegenerateTransform {
        /// The node (or area shape) whose transform it is.
        what: String,
        /// What is wrong.
        problem: &'static str,
    },
    /// An area or macro name is empty.
    #[error("{what}: the name is empty")]
    EmptyName {
        /// What was to be named.
        what: String,
    },
    /// An operation inside a group failed; the group's earlier operations were rolled back.
    #[error("group '{label}', operation {index}: {source}")]
    InGroup {
        /// The group's label.
        label: String,
        /// Position of the failing operation in the group.
        index: usize,
        /// What went wrong.
        source: Box<HistoryError>,
    },
    /// A history step that does not exist was asked for.
    #[error("step {step} does not exist (the history has {len} steps)")]
    NoSuchStep {
        /// The step asked for.
        step: usize,
        /// Number of steps in the history.
        len: usize,
    },
    /// A step of a replay, redo or jump could not be applied.
    #[error("step {step} ('{label}'): {source}")]
    AtStep {
        /// The 1-based step number (step `n` is the `n`-th operation).
        step: usize,
        /// The step's label.
        label: String,
        /// What went wrong.
        source: Box<HistoryError>,
    },
}

/// Shorthand for results in this crate.
pub type Result<T, E = HistoryError> = std::result::Result<T, E>;
