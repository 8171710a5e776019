//! The partition of a mesh for a sketch deformation (Kho & Garland §4.2).

use serde::{Deserialize, Serialize};

/// Which welded vertices a sketch deformation moves: the region of interest (deformed by
/// bending and twisting) and rigid components (moved rigidly with one virtual vertex each).
/// Every other vertex is static.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Partition {
    /// Welded vertex indices of the region of interest, ascending.
    pub roi: Vec<u32>,
    /// Rigid components: each a list of welded vertex indices, ascending.
    pub rigid: Vec<Vec<u32>>,
}
