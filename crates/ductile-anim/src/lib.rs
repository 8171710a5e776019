//! `ductile-anim`: time for Ductile — the animatable parameters of tools and volumes
//! ([`channel`]), keys and their interpolation ([`key`]: step, linear and monotone smooth),
//! skeleton-style in-betweens of curve tools ([`skeleton`], after Kho & Garland §6.1),
//! one blending rule for key in-betweens and variant blends ([`blend`]), and seeded random
//! weights ([`random`]).
//!
//! The crate is pure computation on tool values; the scene document (`ductile-scene`) keeps
//! the tracks and variants and applies what this crate computes. See
//! `docs/algorithms/animation.md` for the decisions taken where the paper is silent.

#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod blend;
pub mod channel;
pub mod error;
pub mod key;
pub mod random;
pub mod skeleton;
pub mod value;

/// The types most users need.
pub mod prelude {
    pub use crate::blend::combine;
    pub use crate::channel::{
        set_shape_channel, set_tool_channel, shape_channels, tool_channel, tool_channels,
    };
    pub use crate::error::{AnimError, Result};
    pub use crate::key::{Interpolation, Key, sample};
    pub use crate::random::random_weights;
    pub use crate::value::{Value, ValueKind};
}

/// Checks that weights sum to 1 (within `1e-4`, to allow for decimal input such as
/// `0.2, 0.5, 0.3`) and are finite.
pub fn check_weights(weights: &[f32]) -> error::Result<()> {
    if weights.is_empty() {
        return Err(error::AnimError::NoSources);
    }
    let sum: f32 = weights.iter().sum();
    if !sum.is_finite() || (sum - 1.0).abs() > 1e-4 {
        return Err(error::AnimError::WeightsSum { sum });
    }
    Ok(())
}
