//! `ductile-scene`: the scene document of Ductile — a graph of named nodes (meshes, tools,
//! macro tools, influence volumes, groups), one deformation stack per mesh, named vertex
//! areas and the macro library.
//!
//! The [`Document`](document::Document) is the single source of truth: the history edits
//! it, the CLI and the Studio read it, and [`Document::evaluate`](document::Document)
//! turns it into deformed meshes through `ductile-core`.

#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod document;
pub mod error;
pub mod evaluator;
pub mod gizmo;
pub mod handles;
pub mod resolve;
#[cfg(test)]
mod test_tools;
pub mod transform;
pub mod validate;

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
    pub use crate::transform::Transform;
}
