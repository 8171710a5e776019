//! The error type of `ductile-bevy`.

use ductile_history::error::HistoryError;
use ductile_scene::error::SceneError;
use thiserror::Error;

/// Why an edit, an evaluation or a handle drag was refused. The document is unchanged
/// whenever one is returned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DuctileBevyError {
    /// The history refused the edit (stale or invalid operation).
    #[error(transparent)]
    History(#[from] HistoryError),
    /// The document could not be resolved or evaluated.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A jump to a history step that does not exist.
    #[error("history step {step} does not exist (the history has {len} steps)")]
    NoSuchStep {
        /// The requested step.
        step: usize,
        /// Number of steps.
        len: usize,
    },
    /// A handle cannot be dragged because its node's frame (or its parent's) is singular
    /// (a zero scale).
    #[error("node '{node}': its frame is degenerate (zero scale), its handles cannot be moved")]
    DegenerateFrame {
        /// The node.
        node: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = DuctileBevyError> = std::result::Result<T, E>;
