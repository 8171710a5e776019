//! What the user has selected: a node, a layer of a mesh's stack, some handles of the
//! selected node; and which nodes are hidden in the viewport.

use std::collections::BTreeSet;

use bevy::prelude::*;
use ductile_scene::document::{Document, NodeKind};
use ductile_scene::handles::HandleId;

/// The selection. Views read and write it directly: it is view state, not document state,
/// so it is not part of the history.
#[derive(Resource, Debug, Default, Clone, PartialEq, Eq)]
pub struct Selection {
    /// The selected node, by name.
    pub node: Option<String>,
    /// The selected layer: mesh node name and index in its stack.
    pub layer: Option<(String, usize)>,
    /// Selected handles of the selected node (Shift-click adds or removes one, a box
    /// selects several); dragging one of them moves them all, as one undo step.
    pub handles: BTreeSet<HandleId>,
    /// Nodes hidden in the viewport (their meshes, gizmos and handles are not drawn; they
    /// still deform and export).
    pub hidden: BTreeSet<String>,
}

impl Selection {
    /// True when `node` is the selected node.
    #[must_use]
    pub fn is_selected(&self, node: &str) -> bool {
        self.node.as_deref() == Some(node)
    }

    /// Selects `node` (a different node clears the handle selection).
    pub fn select(&mut self, node: Option<String>) {
        if self.node != node {
            self.handles.clear();
        }
        self.node = node;
    }

    /// True when `node` is hidden.
    #[must_use]
    pub fn is_hidden(&self, node: &str) -> bool {
        self.hidden.contains(node)
    }

    /// The mesh the stack panel shows and new tools go on: the selected layer's mesh, the
    /// selected mesh, the mesh a selected node is under, or the first mesh of `doc`.
    #[must_use]
    pub fn mesh_in_focus(&self, doc: &Document) -> Option<String> {
        if let Some((m, _)) = &self.layer {
            return Some(m.clone());
        }
        let mut current = self.node.as_deref();
        for _ in 0..=doc.nodes.len() {
            let Some(name) = current else { break };
            let Ok(node) = doc.node(name) else { break };
            if matches!(node.kind, NodeKind::Mesh(_)) {
                return Some(name.to_owned());
            }
            current = node.parent.as_deref();
        }
        doc.mesh_names().first().map(|s| (*s).to_owned())
    }
}

/// Hides the entities of hidden nodes.
pub fn apply_hidden(
    selection: Res<Selection>,
    mut nodes: Query<(&crate::components::SceneNode, &mut Visibility)>,
) {
    if !selection.is_changed() {
        return;
    }
    for (node, mut visibility) in &mut nodes {
        let wanted = if selection.is_hidden(&node.name) {
            Visibility::Hidden
        } else {
            Visibility::Inherited
        };
        visibility.set_if_neq(wanted);
    }
}
