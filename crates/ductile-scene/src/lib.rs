//! `ductile-scene`: the scene document of Ductile — a graph of named nodes (meshes, tools,
//! macro tools, influence volumes, groups), one deformation stack per mesh, named vertex
//! areas and the macro library.
//!
//! The [`Document`](document::Document) is the single source of truth: the history edits
//! it, the CLI and the Studio read it, and [`Document::evaluate`](document::Document)
//! turns it into deformed meshes through `ductile-core`. It also holds time: keyframe
//! tracks on any animatable parameter ([`time`], [`channels`]; `Document::at(t)` is the
//! document at a time) and named variants with their blends ([`variant`]).

#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod channels;
pub mod create;
pub mod document;
pub mod error;
pub mod evaluator;
pub mod gizmo;
pub mod handles;
pub mod resolve;
pub mod sketching;
pub mod symmetry;
#[cfg(test)]
mod test_tools;
pub mod time;
pub mod transform;
pub mod validate;
pub mod variant;

/// The types most users need.
pub mod prelude {
    pub use crate::document::{
        Area, Document, InfluenceSpec, LayerSpec, MacroUse, MeshNode, Node, NodeKind, RegionShape,
        VolumeNode,
    };
    pub use crate::error::{Result, SceneError};
    pub use crate::evaluator::{MeshEvaluator, Update};
    pub use crate::gizmo::{Gizmo, Role, gizmo};
    pub use crate::handles::{Handle, HandleId, HandleRole, NodeEdit, handles, moved};
    pub use crate::time::{Animation, NodeTracks, Timeline};
    pub use crate::transform::Transform;
    pub use crate::variant::{NodeState, Origin, RandomOptions, State, Variant};
    pub use ductile_anim::key::{Interpolation, Key};
    pub use ductile_anim::value::Value;
}
