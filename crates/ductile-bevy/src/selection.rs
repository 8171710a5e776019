//! What the user has selected: a node, and a layer of a mesh's stack.

use bevy::prelude::*;

/// The selection. Views read and write it directly: it is view state, not document state,
/// so it is not part of the history.
#[derive(Resource, Debug, Default, Clone, PartialEq, Eq)]
pub struct Selection {
    /// The selected node, by name.
    pub node: Option<String>,
    /// The selected layer: mesh node name and index in its stack.
    pub layer: Option<(String, usize)>,
}

impl Selection {
    /// True when `node` is the selected node.
    #[must_use]
    pub fn is_selected(&self, node: &str) -> bool {
        self.node.as_deref() == Some(node)
    }
}
