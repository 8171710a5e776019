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

    /// A primary press on handle `id` of `node`: selects the node and the handle. With
    /// `shift` on the selected node, adds the handle to the selected ones, or removes it if
    /// it was among them; without, a handle already selected keeps the group (a drag of it
    /// moves them all), another one replaces it.
    pub fn press_handle(&mut self, node: &str, id: HandleId, shift: bool) {
        let same_node = self.is_selected(node);
        self.select(Some(node.to_owned()));
        if shift && same_node {
            if !self.handles.remove(&id) {
                self.handles.insert(id);
            }
        } else if !self.handles.contains(&id) {
            self.handles.clear();
            self.handles.insert(id);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn handles(s: &Selection) -> Vec<HandleId> {
        s.handles.iter().copied().collect()
    }

    #[test]
    fn shift_presses_add_and_remove_handles_and_a_plain_press_keeps_or_replaces_the_group() {
        let mut s = Selection::default();
        s.press_handle("lattice", HandleId::Lattice(0, 0, 0), false);
        assert!(s.is_selected("lattice"));
        assert_eq!(handles(&s), [HandleId::Lattice(0, 0, 0)]);
        // Shift adds, on the same node.
        s.press_handle("lattice", HandleId::Lattice(1, 0, 0), true);
        s.press_handle("lattice", HandleId::Lattice(2, 0, 0), true);
        assert_eq!(
            handles(&s),
            [
                HandleId::Lattice(0, 0, 0),
                HandleId::Lattice(1, 0, 0),
                HandleId::Lattice(2, 0, 0)
            ]
        );
        // Shift on a selected handle removes it.
        s.press_handle("lattice", HandleId::Lattice(1, 0, 0), true);
        assert_eq!(
            handles(&s),
            [HandleId::Lattice(0, 0, 0), HandleId::Lattice(2, 0, 0)]
        );
        // A plain press on a selected handle keeps the group (to drag it).
        s.press_handle("lattice", HandleId::Lattice(2, 0, 0), false);
        assert_eq!(s.handles.len(), 2);
        // A plain press on another handle replaces the group.
        s.press_handle("lattice", HandleId::Lattice(3, 1, 0), false);
        assert_eq!(handles(&s), [HandleId::Lattice(3, 1, 0)]);
        // Shift on another node's handle selects that node and that handle alone.
        s.press_handle("curve", HandleId::Deformed(2), true);
        assert!(s.is_selected("curve"));
        assert_eq!(handles(&s), [HandleId::Deformed(2)]);
    }
}
