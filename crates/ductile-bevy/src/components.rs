//! Components of the ECS mirror of the document.

use bevy::prelude::*;
use ductile_scene::document::Node;

/// An entity mirroring document node `name`; `node` is a copy of the node as the document
/// has it, replaced only when the document's node changes (so `Changed<SceneNode>` means a
/// real edit). The entity's [`Transform`] is the node's world transform.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct SceneNode {
    /// The node's unique name.
    pub name: String,
    /// The node as the document has it.
    pub node: Node,
}

/// Marks the entity of a mesh node; its rendered mesh and evaluation state are in
/// [`MeshEvaluation`](crate::evaluate::MeshEvaluation) once its rest mesh is loaded.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct MeshNodeMarker {
    /// The node's mesh source (path relative to the scene file, with an optional `#name`).
    pub source: String,
}

/// A draggable handle (a small sphere) of a node: a control point, a lattice point, a
/// volume's origin…
#[derive(Component, Debug, Clone, PartialEq)]
pub struct HandleMarker {
    /// The node the handle belongs to.
    pub node: String,
    /// Which handle of the node.
    pub id: ductile_scene::handles::HandleId,
}
