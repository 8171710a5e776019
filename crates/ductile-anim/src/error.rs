//! The errors of `ductile-anim`.

use glam::Vec3;

/// Everything that can go wrong with channels, keys and blends. Messages name the parameter
/// (its path) and the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnimError {
    /// A path names no channel of the tool or shape.
    #[error("{owner} has no animatable parameter '{path}'")]
    NoSuchChannel {
        /// The path asked for.
        path: String,
        /// What was asked (a tool kind's name, "volume shape", …).
        owner: String,
    },
    /// A value of the wrong kind for a channel.
    #[error("parameter '{path}' holds {expected}, not {found}")]
    WrongValue {
        /// The channel's path.
        path: String,
        /// The kind the channel holds.
        expected: &'static str,
        /// The kind (and size) given.
        found: String,
    },
    /// A plane curve given for a sketch tool whose plane has another normal.
    #[error("parameter '{path}' is a curve in the plane of normal {normal}, not of normal {found}")]
    OtherPlane {
        /// The channel's path.
        path: String,
        /// The tool's plane normal.
        normal: Vec3,
        /// The value's normal.
        found: Vec3,
    },
    /// Blend weights that do not sum to 1.
    #[error("blend weights must sum to 1, these sum to {sum}")]
    WeightsSum {
        /// Their sum.
        sum: f32,
    },
    /// A blend or random draw without sources.
    #[error("a blend needs at least one source")]
    NoSources,
    /// A number outside its range.
    #[error("{what} = {value} is out of range: must be {expected}")]
    OutOfRange {
        /// What was given.
        what: String,
        /// The value.
        value: f32,
        /// The range.
        expected: &'static str,
    },
}

/// `Result` with [`AnimError`].
pub type Result<T, E = AnimError> = std::result::Result<T, E>;
