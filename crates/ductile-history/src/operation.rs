//! Operations: every edit of a scene [`Document`] as plain, serialisable data with an exact
//! inverse.
//!
//! Each operation stores the value it replaces next to the value it sets (`old` / `new`),
//! or the whole item it inserts or removes. [`Operation::apply`] checks that the document
//! holds the `old` value (else [`HistoryError::Stale`]) and that the result is valid (else
//! the error of the rule broken), and only then mutates; [`Operation::revert`] does the
//! reverse. Hence, for every accepted operation `op` on a document `d`:
//!
//! `revert(apply(d)) == d`, bit for bit, and `apply(op.inverse())` is `revert(op)`.
//!
//! A refused operation leaves the document untouched.
//!
//! ## Removal and references
//! A node, area or macro that is still referenced by name cannot be removed
//! ([`HistoryError::StillReferenced`]): removal operations never edit other parts of the
//! document behind the user's back, so that each stays a small exact inverse of an
//! addition. To delete a node together with everything that refers to it, build the
//! [`Operation::Group`] made by [`Operation::remove_node_and_references`].
//!
//! ## What undo checks
//! Applying checks the *new* state (validity of the edited part, as
//! [`Document::problems`] would). Reverting checks only that the document is the one the
//! operation produced (the `new` values are there, indices exist, names are free): it
//! restores exactly what was there before, even where the base document had problems.

use ductile_anim::key::Key;
use ductile_core::ffsd::FfsdMacro;
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_scene::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::{
    check_area, check_influence, check_layer, check_macro_definition, check_macro_value,
    check_new_node, check_shape, check_tool, check_transform, check_weight, first_reference,
    in_range, mesh_at, mesh_mut, node_index, same, wrong_kind,
};
use crate::error::{HistoryError, Result};
use crate::time_ops;

/// One undoable edit of a scene document. Node, mesh, area and macro references are by name
/// (names are unique in a document); layer positions are 0 = bottom of the stack.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Operation {
    /// Inserts `node` at position `index` of the node list (`index = len` appends).
    AddNode {
        /// Position in the node list.
        index: usize,
        /// The node, complete.
        node: Node,
    },
    /// Removes the node at `index`, which must equal `node` and must not be referenced.
    RemoveNode {
        /// Position in the node list.
        index: usize,
        /// The node as it was (restored by undo).
        node: Node,
    },
    /// Renames a node and every reference to it ([`Document::rename`]).
    Rename {
        /// Current name.
        old: String,
        /// New name: non-empty, not used by a node, not referenced anywhere.
        new: String,
    },
    /// Changes a node's parent (its local transform is kept).
    Reparent {
        /// The node.
        node: String,
        /// Parent before.
        old: Option<String>,
        /// Parent after (must exist and must not be the node or one of its descendants).
        new: Option<String>,
    },
    /// Sets a node's local transform.
    SetTransform {
        /// The node.
        node: String,
        /// Transform before.
        old: Transform,
        /// Transform after (finite, non-zero scales, non-zero rotation).
        new: Transform,
    },
    /// Sets a tool node's whole tool value: any parameter of any tool kind.
    SetTool {
        /// The tool node.
        node: String,
        /// Tool before.
        old: Tool,
        /// Tool after (validated by the tool kind's rules).
        new: Tool,
    },
    /// Sets a volume node's shape.
    SetVolume {
        /// The volume node.
        node: String,
        /// Shape before.
        old: Shape,
        /// Shape after.
        new: Shape,
    },
    /// Sets a macro tool's user value γ (the identikit slider).
    SetMacroValue {
        /// The macro tool node.
        node: String,
        /// Value before.
        old: f32,
        /// Value after (finite).
        new: f32,
    },
    /// Inserts a layer into a mesh's stack at `index` (`index = len` puts it on top).
    AddLayer {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// The layer (its tool, volumes and area must exist).
        layer: LayerSpec,
    },
    /// Removes the layer at `index`, which must equal `layer`.
    RemoveLayer {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// The layer as it was.
        layer: LayerSpec,
    },
    /// Moves the layer at `from` so that it ends up at `to` (remove, then insert).
    MoveLayer {
        /// The mesh node.
        mesh: String,
        /// Position before.
        from: usize,
        /// Position after.
        to: usize,
    },
    /// Enables or disables a layer.
    SetLayerEnabled {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// Flag before.
        old: bool,
        /// Flag after.
        new: bool,
    },
    /// Solos or unsolos a layer (when any layer of a stack is soloed, only the soloed layers
    /// evaluate).
    SetLayerSolo {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// Flag before.
        old: bool,
        /// Flag after.
        new: bool,
    },
    /// Sets a layer's blend weight.
    SetLayerWeight {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// Weight before.
        old: f32,
        /// Weight after, in `[0, 1]`.
        new: f32,
    },
    /// Sets (or removes, with `None`) a layer's influence.
    SetLayerInfluence {
        /// The mesh node.
        mesh: String,
        /// Position in the stack.
        index: usize,
        /// Influence before.
        old: Option<InfluenceSpec>,
        /// Influence after.
        new: Option<InfluenceSpec>,
    },
    /// Defines, redefines (`old`, `new` both `Some`) or deletes (`new: None`) a named area of
    /// a mesh. A deleted area must not be used by a layer of the mesh.
    DefineArea {
        /// The mesh node.
        mesh: String,
        /// The area's name.
        name: String,
        /// Definition before (`None`: the area did not exist).
        old: Option<Area>,
        /// Definition after (`None`: the area is deleted).
        new: Option<Area>,
    },
    /// Adds, changes or deletes (`new: None`) a macro of the document's library. A deleted
    /// macro must not be used by a macro tool.
    SetMacroDefinition {
        /// The macro's name.
        name: String,
        /// Definition before (`None`: the macro did not exist).
        old: Option<FfsdMacro>,
        /// Definition after (`None`: the macro is deleted).
        new: Option<FfsdMacro>,
    },
    /// Sets, changes or deletes the key at `time` of node `node`'s channel `param`. Setting a
    /// key on a channel without a track makes the track; deleting its last key removes it.
    SetKey {
        /// The animated node.
        node: String,
        /// The channel's path (see `docs/scene-format.md`, "Animation").
        param: String,
        /// The key's time in seconds (both keys, when present, are at this time).
        time: f32,
        /// The key before (`None`: there was none at `time`).
        old: Option<Key>,
        /// The key after (`None`: deleted).
        new: Option<Key>,
    },
    /// Moves the key at `from` to `to` (no key may be at `to`), keeping its value and
    /// interpolation.
    MoveKey {
        /// The animated node.
        node: String,
        /// The channel's path.
        param: String,
        /// Time before (seconds).
        from: f32,
        /// Time after (seconds, finite).
        to: f32,
    },
    /// Sets, replaces or removes (`new: None`) a whole track.
    SetTrack {
        /// The animated node.
        node: String,
        /// The channel's path.
        param: String,
        /// The keys before (`None`: no track).
        old: Option<Vec<Key>>,
        /// The keys after (`None`: no track).
        new: Option<Vec<Key>>,
    },
    /// Sets the timeline's frame rate and frame range.
    SetTimeline {
        /// Settings before.
        old: Timeline,
        /// Settings after (fps finite and > 0, start ≤ end).
        new: Timeline,
    },
    /// Saves, overwrites or deletes (`new: None`) a named variant.
    SetVariant {
        /// The variant's name.
        name: String,
        /// The variant before (`None`: there was none).
        old: Option<Variant>,
        /// The variant after (`None`: deleted). Its nodes must exist and be of the kinds
        /// it holds.
        new: Option<Variant>,
    },
    /// Renames a variant.
    RenameVariant {
        /// Current name.
        old: String,
        /// New name: non-empty, not used by another variant.
        new: String,
    },
    /// Several operations as one step: applied in order, undone in reverse order, all or
    /// nothing.
    Group {
        /// What the group does, for the history panel.
        label: String,
        /// The operations, in application order.
        ops: Vec<Operation>,
    },
}

/// Which way an operation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dir {
    /// Apply: from `old` to `new`, checking the result.
    Forward,
    /// Revert: from `new` back to `old`, checking consistency only.
    Backward,
}

impl Dir {
    /// `(expected, target)` for this direction.
    fn pick<'a, T: ?Sized>(self, old: &'a T, new: &'a T) -> (&'a T, &'a T) {
        match self {
            Dir::Forward => (old, new),
            Dir::Backward => (new, old),
        }
    }

    fn flip(self) -> Self {
        match self {
            Dir::Forward => Dir::Backward,
            Dir::Backward => Dir::Forward,
        }
    }
}

impl Operation {
    /// Applies the operation to `doc`. On error `doc` is unchanged.
    pub fn apply(&self, doc: &mut Document) -> Result<()> {
        self.run(doc, Dir::Forward)
    }

    /// Undoes the operation on `doc`, which must be in the state the operation left it in.
    /// On error `doc` is unchanged.
    pub fn revert(&self, doc: &mut Document) -> Result<()> {
        self.run(doc, Dir::Backward)
    }

    /// The operation that undoes this one: `old` and `new` swapped, additions and removals
    /// exchanged, moves reversed, groups reversed with each member inverted.
    #[must_use]
    pub fn inverse(&self) -> Operation {
        use Operation as O;
        match self.clone() {
            O::AddNode { index, node } => O::RemoveNode { index, node },
            O::RemoveNode { index, node } => O::AddNode { index, node },
            O::Rename { old, new } => O::Rename { old: new, new: old },
            O::Reparent { node, old, new } => O::Reparent {
                node,
                old: new,
                new: old,
            },
            O::SetTransform { node, old, new } => O::SetTransform {
                node,
                old: new,
                new: old,
            },
            O::SetTool { node, old, new } => O::SetTool {
                node,
                old: new,
                new: old,
            },
            O::SetVolume { node, old, new } => O::SetVolume {
                node,
                old: new,
                new: old,
            },
            O::SetMacroValue { node, old, new } => O::SetMacroValue {
                node,
                old: new,
                new: old,
            },
            O::AddLayer { mesh, index, layer } => O::RemoveLayer { mesh, index, layer },
            O::RemoveLayer { mesh, index, layer } => O::AddLayer { mesh, index, layer },
            O::MoveLayer { mesh, from, to } => O::MoveLayer {
                mesh,
                from: to,
                to: from,
            },
            O::SetLayerEnabled {
                mesh,
                index,
                old,
                new,
            } => O::SetLayerEnabled {
                mesh,
                index,
                old: new,
                new: old,
            },
            O::SetLayerWeight {
                mesh,
                index,
                old,
                new,
            } => O::SetLayerWeight {
                mesh,
                index,
                old: new,
                new: old,
            },
            O::SetLayerSolo {
                mesh,
                index,
                old,
                new,
            } => O::SetLayerSolo {
                mesh,
                index,
                old: new,
                new: old,
            },
            O::SetLayerInfluence {
                mesh,
                index,
                old,
                new,
            } => O::SetLayerInfluence {
                mesh,
                index,
                old: new,
                new: old,
            },
            O::DefineArea {
                mesh,
                name,
                old,
                new,
            } => O::DefineArea {
                mesh,
                name,
                old: new,
                new: old,
            },
            O::SetMacroDefinition { name, old, new } => O::SetMacroDefinition {
                name,
                old: new,
                new: old,
            },
            O::SetKey {
                node,
                param,
                time,
                old,
                new,
            } => O::SetKey {
                node,
                param,
                time,
                old: new,
                new: old,
            },
            O::MoveKey {
                node,
                param,
                from,
                to,
            } => O::MoveKey {
                node,
                param,
                from: to,
                to: from,
            },
            O::SetTrack {
                node,
                param,
                old,
                new,
            } => O::SetTrack {
                node,
                param,
                old: new,
                new: old,
            },
            O::SetTimeline { old, new } => O::SetTimeline { old: new, new: old },
            O::SetVariant { name, old, new } => O::SetVariant {
                name,
                old: new,
                new: old,
            },
            O::RenameVariant { old, new } => O::RenameVariant { old: new, new: old },
            O::Group { label, ops } => O::Group {
                label,
                ops: ops.iter().rev().map(Operation::inverse).collect(),
            },
        }
    }

    /// A short description for history panels when the caller gives no label, such as
    /// `"set transform of 'nose'"`.
    #[must_use]
    pub fn describe(&self) -> String {
        use Operation as O;
        match self {
            O::AddNode { node, .. } => format!("add {} '{}'", node.kind.name(), node.name),
            O::RemoveNode { node, .. } => format!("remove {} '{}'", node.kind.name(), node.name),
            O::Rename { old, new } => format!("rename '{old}' to '{new}'"),
            O::Reparent { node, new, .. } => match new {
                Some(p) => format!("parent '{node}' to '{p}'"),
                None => format!("unparent '{node}'"),
            },
            O::SetTransform { node, .. } => format!("set transform of '{node}'"),
            O::SetTool { node, .. } => format!("edit tool '{node}'"),
            O::SetVolume { node, .. } => format!("edit volume '{node}'"),
            O::SetMacroValue { node, new, .. } => format!("set '{node}' to {new}"),
            O::AddLayer { mesh, layer, .. } => format!("add layer '{}' to '{mesh}'", layer.tool),
            O::RemoveLayer { mesh, layer, .. } => {
                format!("remove layer '{}' from '{mesh}'", layer.tool)
            }
            O::MoveLayer { mesh, from, to } => format!("move layer {from} to {to} on '{mesh}'"),
            O::SetLayerEnabled {
                mesh, index, new, ..
            } => format!(
                "{} layer {index} of '{mesh}'",
                if *new { "enable" } else { "disable" }
            ),
            O::SetLayerWeight {
                mesh, index, new, ..
            } => format!("set weight of layer {index} of '{mesh}' to {new}"),
            O::SetLayerSolo {
                mesh, index, new, ..
            } => format!(
                "{} layer {index} of '{mesh}'",
                if *new { "solo" } else { "unsolo" }
            ),
            O::SetLayerInfluence { mesh, index, .. } => {
                format!("set influence of layer {index} of '{mesh}'")
            }
            O::DefineArea {
                mesh, name, new, ..
            } => match new {
                Some(_) => format!("define area '{name}' of '{mesh}'"),
                None => format!("delete area '{name}' of '{mesh}'"),
            },
            O::SetMacroDefinition { name, new, .. } => match new {
                Some(_) => format!("define macro '{name}'"),
                None => format!("delete macro '{name}'"),
            },
            O::SetKey {
                node,
                param,
                time,
                old,
                new,
            } => match (old, new) {
                (None, Some(_)) => format!("key '{node}' {param} at {time} s"),
                (Some(_), None) => format!("delete key of '{node}' {param} at {time} s"),
                (Some(a), Some(b)) if a.value == b.value => format!(
                    "set interpolation of '{node}' {param} at {time} s to {}",
                    b.interpolation.name()
                ),
                _ => format!("set key '{node}' {param} at {time} s"),
            },
            O::MoveKey {
                node,
                param,
                from,
                to,
            } => format!("move key of '{node}' {param} from {from} s to {to} s"),
            O::SetTrack {
                node, param, new, ..
            } => match new {
                Some(k) => format!("set track '{node}' {param} ({} keys)", k.len()),
                None => format!("delete track '{node}' {param}"),
            },
            O::SetTimeline { new, .. } => format!(
                "set timeline to frames {}–{} at {} fps",
                new.start, new.end, new.fps
            ),
            O::SetVariant { name, old, new } => match (old, new) {
                (None, Some(_)) => format!("save variant '{name}'"),
                (Some(_), Some(_)) => format!("update variant '{name}'"),
                (_, None) => format!("delete variant '{name}'"),
            },
            O::RenameVariant { old, new } => format!("rename variant '{old}' to '{new}'"),
            O::Group { label, .. } => label.clone(),
        }
    }

    /// Number of elementary (non-group) operations inside.
    #[must_use]
    pub fn elementary_count(&self) -> usize {
        match self {
            Operation::Group { ops, .. } => ops.iter().map(Operation::elementary_count).sum(),
            _ => 1,
        }
    }

    /// True when `next` edits the same target in the same way and starts where `self` ends
    /// (its `old` is `self`'s `new`), so that both can be one step (a drag, a slider
    /// movement). Groups merge when they have the same length and merge member by member.
    #[must_use]
    pub fn can_merge(&self, next: &Operation) -> bool {
        use Operation as O;
        match (self, next) {
            (O::SetTransform { node: a, new, .. }, O::SetTransform { node: b, old, .. }) => {
                a == b && new == old
            }
            (O::SetTool { node: a, new, .. }, O::SetTool { node: b, old, .. }) => {
                a == b && new == old
            }
            (O::SetVolume { node: a, new, .. }, O::SetVolume { node: b, old, .. }) => {
                a == b && new == old
            }
            (O::SetMacroValue { node: a, new, .. }, O::SetMacroValue { node: b, old, .. }) => {
                a == b && new == old
            }
            (
                O::SetLayerWeight {
                    mesh: a,
                    index: i,
                    new,
                    ..
                },
                O::SetLayerWeight {
                    mesh: b,
                    index: j,
                    old,
                    ..
                },
            ) => a == b && i == j && new == old,
            (
                O::SetLayerInfluence {
                    mesh: a,
                    index: i,
                    new,
                    ..
                },
                O::SetLayerInfluence {
                    mesh: b,
                    index: j,
                    old,
                    ..
                },
            ) => a == b && i == j && new == old,
            (
                O::DefineArea {
                    mesh: a,
                    name: m,
                    new,
                    ..
                },
                O::DefineArea {
                    mesh: b,
                    name: n,
                    old,
                    ..
                },
            ) => a == b && m == n && new == old,
            (
                O::SetMacroDefinition { name: a, new, .. },
                O::SetMacroDefinition { name: b, old, .. },
            ) => a == b && new == old,
            (
                O::SetKey {
                    node: a,
                    param: p,
                    time: t,
                    new,
                    ..
                },
                O::SetKey {
                    node: b,
                    param: q,
                    time: u,
                    old,
                    ..
                },
            ) => a == b && p == q && t == u && new.is_some() && new == old,
            (
                O::MoveKey {
                    node: a,
                    param: p,
                    to,
                    ..
                },
                O::MoveKey {
                    node: b,
                    param: q,
                    from,
                    ..
                },
            ) => a == b && p == q && to == from,
            (O::SetTimeline { new, .. }, O::SetTimeline { old, .. }) => new == old,
            (
                O::SetTrack {
                    node: a,
                    param: p,
                    new,
                    ..
                },
                O::SetTrack {
                    node: b,
                    param: q,
                    old,
                    ..
                },
            ) => a == b && p == q && new == old,
            (O::Group { ops: a, .. }, O::Group { ops: b, .. }) => {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.can_merge(y))
            }
            // An edit of a tool just added, in the same gesture (the Studio's "Adjust last
            // operation" panel), is folded into the step that added it.
            (O::AddNode { node, .. }, O::SetTool { node: b, old, .. }) => {
                node.name == *b && matches!(&node.kind, NodeKind::Tool(t) if t == old)
            }
            (O::Group { ops, .. }, next @ O::SetTool { .. }) => {
                ops.iter().any(|o| o.can_merge(next))
            }
            _ => false,
        }
    }

    /// Merges `next` into `self` when [`Operation::can_merge`] allows it: the result keeps
    /// `self`'s `old` and takes `next`'s `new`. Returns whether it merged.
    pub fn merge(&mut self, next: &Operation) -> bool {
        if !self.can_merge(next) {
            return false;
        }
        use Operation as O;
        match (self, next) {
            (O::SetTransform { new, .. }, O::SetTransform { new: n, .. }) => *new = *n,
            (O::SetTool { new, .. }, O::SetTool { new: n, .. }) => new.clone_from(n),
            (O::SetVolume { new, .. }, O::SetVolume { new: n, .. }) => new.clone_from(n),
            (O::SetMacroValue { new, .. }, O::SetMacroValue { new: n, .. }) => *new = *n,
            (O::SetLayerWeight { new, .. }, O::SetLayerWeight { new: n, .. }) => *new = *n,
            (O::SetLayerInfluence { new, .. }, O::SetLayerInfluence { new: n, .. }) => {
                new.clone_from(n)
            }
            (O::DefineArea { new, .. }, O::DefineArea { new: n, .. }) => new.clone_from(n),
            (O::SetMacroDefinition { new, .. }, O::SetMacroDefinition { new: n, .. }) => {
                new.clone_from(n)
            }
            (O::SetKey { new, .. }, O::SetKey { new: n, .. }) => new.clone_from(n),
            (O::MoveKey { to, .. }, O::MoveKey { to: n, .. }) => *to = *n,
            (O::SetTimeline { new, .. }, O::SetTimeline { new: n, .. }) => *new = *n,
            (O::SetTrack { new, .. }, O::SetTrack { new: n, .. }) => new.clone_from(n),
            (O::Group { ops, .. }, O::Group { ops: n, .. }) => {
                for (a, b) in ops.iter_mut().zip(n) {
                    a.merge(b);
                }
            }
            (O::AddNode { node, .. }, O::SetTool { new: n, .. }) => {
                node.kind = NodeKind::Tool(n.clone());
            }
            (O::Group { ops, .. }, next @ O::SetTool { .. }) => {
                if let Some(o) = ops.iter_mut().find(|o| o.can_merge(next)) {
                    o.merge(next);
                }
            }
            _ => return false,
        }
        true
    }

    fn run(&self, doc: &mut Document, dir: Dir) -> Result<()> {
        use Operation as O;
        let fwd = dir == Dir::Forward;
        match self {
            O::AddNode { index, node } => {
                if fwd {
                    insert_node(doc, *index, node, true)
                } else {
                    remove_node(doc, *index, node, false)
                }
            }
            O::RemoveNode { index, node } => {
                if fwd {
                    remove_node(doc, *index, node, true)
                } else {
                    insert_node(doc, *index, node, false)
                }
            }
            O::Rename { old, new } => {
                let (from, to) = dir.pick(old, new);
                rename(doc, from, to)
            }
            O::Reparent { node, old, new } => {
                let (expected, target) = dir.pick(old, new);
                let i = node_index(doc, node)?;
                same(&doc.nodes[i].parent, expected, || {
                    format!("node '{node}': parent")
                })?;
                if fwd && let Some(p) = target {
                    if doc.index_of(p).is_none() {
                        return Err(SceneError::UnknownParent {
                            node: node.clone(),
                            parent: p.clone(),
                        }
                        .into());
                    }
                    if doc.is_ancestor(node, p) {
                        return Err(SceneError::Cycle { node: node.clone() }.into());
                    }
                }
                doc.nodes[i].parent.clone_from(target);
                Ok(())
            }
            O::SetTransform { node, old, new } => {
                let (expected, target) = dir.pick(old, new);
                let i = node_index(doc, node)?;
                same(&doc.nodes[i].transform, expected, || {
                    format!("node '{node}': transform")
                })?;
                if fwd {
                    check_transform(|| format!("node '{node}'"), target)?;
                }
                doc.nodes[i].transform = *target;
                Ok(())
            }
            O::SetTool { node, old, new } => {
                let (expected, target) = dir.pick(old, new);
                let i = node_index(doc, node)?;
                let NodeKind::Tool(tool) = &doc.nodes[i].kind else {
                    return Err(wrong_kind(node, &doc.nodes[i].kind, "tool"));
                };
                same(tool, expected, || format!("tool '{node}'"))?;
                if fwd {
                    check_tool(node, target)?;
                }
                if let NodeKind::Tool(tool) = &mut doc.nodes[i].kind {
                    tool.clone_from(target);
                }
                Ok(())
            }
            O::SetVolume { node, old, new } => {
                let (expected, target) = dir.pick(old, new);
                let i = node_index(doc, node)?;
                let NodeKind::Volume(v) = &doc.nodes[i].kind else {
                    return Err(wrong_kind(node, &doc.nodes[i].kind, "volume"));
                };
                same(&v.shape, expected, || format!("volume '{node}': shape"))?;
                if fwd {
                    check_shape(&format!("volume '{node}'"), target)?;
                }
                if let NodeKind::Volume(v) = &mut doc.nodes[i].kind {
                    v.shape.clone_from(target);
                }
                Ok(())
            }
            O::SetMacroValue { node, old, new } => {
                let (expected, target) = dir.pick(old, new);
                let i = node_index(doc, node)?;
                let NodeKind::Macro(m) = &doc.nodes[i].kind else {
                    return Err(wrong_kind(node, &doc.nodes[i].kind, "macro tool"));
                };
                same(&m.value, expected, || format!("macro tool '{node}': value"))?;
                if fwd {
                    check_macro_value(node, *target)?;
                }
                if let NodeKind::Macro(m) = &mut doc.nodes[i].kind {
                    m.value = *target;
                }
                Ok(())
            }
            O::AddLayer { mesh, index, layer } => {
                if fwd {
                    insert_layer(doc, mesh, *index, layer, true)
                } else {
                    remove_layer(doc, mesh, *index, layer)
                }
            }
            O::RemoveLayer { mesh, index, layer } => {
                if fwd {
                    remove_layer(doc, mesh, *index, layer)
                } else {
                    insert_layer(doc, mesh, *index, layer, false)
                }
            }
            O::MoveLayer { mesh, from, to } => {
                let (from, to) = dir.pick(from, to);
                let (i, m) = mesh_at(doc, mesh)?;
                let len = m.stack.len();
                in_range(*from, len, false, || format!("mesh '{mesh}': layer"))?;
                in_range(*to, len, false, || format!("mesh '{mesh}': layer"))?;
                if let Some(m) = mesh_mut(doc, i) {
                    let layer = m.stack.remove(*from);
                    m.stack.insert(*to, layer);
                }
                Ok(())
            }
            O::SetLayerEnabled {
                mesh,
                index,
                old,
                new,
            } => set_layer_flag(doc, mesh, *index, dir.pick(old, new), "enabled", |l| {
                &mut l.enabled
            }),
            O::SetLayerSolo {
                mesh,
                index,
                old,
                new,
            } => set_layer_flag(doc, mesh, *index, dir.pick(old, new), "solo", |l| {
                &mut l.solo
            }),
            O::SetLayerWeight {
                mesh,
                index,
                old,
                new,
            } => {
                let (expected, target) = dir.pick(old, new);
                let (i, m) = mesh_at(doc, mesh)?;
                let layer = layer_at(m, mesh, *index)?;
                same(&layer.weight, expected, || {
                    format!("mesh '{mesh}', layer {index}: weight")
                })?;
                if fwd {
                    check_weight(mesh, *index, *target)?;
                }
                if let Some(m) = mesh_mut(doc, i) {
                    m.stack[*index].weight = *target;
                }
                Ok(())
            }
            O::SetLayerInfluence {
                mesh,
                index,
                old,
                new,
            } => {
                let (expected, target) = dir.pick(old, new);
                let (i, m) = mesh_at(doc, mesh)?;
                let layer = layer_at(m, mesh, *index)?;
                same(&layer.influence, expected, || {
                    format!("mesh '{mesh}', layer {index}: influence")
                })?;
                if fwd && let Some(inf) = target {
                    check_influence(doc, mesh, &m.areas, *index, inf)?;
                }
                if let Some(m) = mesh_mut(doc, i) {
                    m.stack[*index].influence.clone_from(target);
                }
                Ok(())
            }
            O::DefineArea {
                mesh,
                name,
                old,
                new,
            } => {
                let (expected, target) = dir.pick(old, new);
                let (i, m) = mesh_at(doc, mesh)?;
                same(&m.areas.get(name), &expected.as_ref(), || {
                    format!("mesh '{mesh}': area '{name}'")
                })?;
                if fwd {
                    match target {
                        Some(area) => check_area(mesh, name, area)?,
                        None => {
                            if let Some(k) = m.stack.iter().position(|l| {
                                l.influence
                                    .as_ref()
                                    .is_some_and(|inf| inf.area.as_ref() == Some(name))
                            }) {
                                return Err(HistoryError::StillReferenced {
                                    what: format!("area '{name}' of mesh '{mesh}'"),
                                    by: format!("layer {k} (its influence)"),
                                });
                            }
                        }
                    }
                }
                if let Some(m) = mesh_mut(doc, i) {
                    match target {
                        Some(area) => {
                            m.areas.insert(name.clone(), area.clone());
                        }
                        None => {
                            m.areas.remove(name);
                        }
                    }
                }
                Ok(())
            }
            O::SetMacroDefinition { name, old, new } => {
                let (expected, target) = dir.pick(old, new);
                same(&doc.macros.get(name), &expected.as_ref(), || {
                    format!("macro '{name}'")
                })?;
                if fwd {
                    match target {
                        Some(def) => check_macro_definition(name, def)?,
                        None => {
                            if let Some(user) = doc
                                .nodes
                                .iter()
                                .find(|n| matches!(&n.kind, NodeKind::Macro(m) if &m.name == name))
                            {
                                return Err(HistoryError::StillReferenced {
                                    what: format!("macro '{name}'"),
                                    by: format!("macro tool '{}'", user.name),
                                });
                            }
                        }
                    }
                }
                match target {
                    Some(def) => {
                        doc.macros.insert(name.clone(), def.clone());
                    }
                    None => {
                        doc.macros.remove(name);
                    }
                }
                Ok(())
            }
            O::SetKey {
                node,
                param,
                time,
                old,
                new,
            } => {
                let (expected, target) = dir.pick(old, new);
                time_ops::set_key(
                    doc,
                    node,
                    param,
                    *time,
                    expected.as_ref(),
                    target.as_ref(),
                    fwd,
                )
            }
            O::MoveKey {
                node,
                param,
                from,
                to,
            } => {
                let (from, to) = dir.pick(from, to);
                time_ops::move_key(doc, node, param, *from, *to)
            }
            O::SetTrack {
                node,
                param,
                old,
                new,
            } => {
                let (expected, target) = dir.pick(old, new);
                time_ops::set_track(
                    doc,
                    node,
                    param,
                    expected.as_deref(),
                    target.as_deref(),
                    fwd,
                )
            }
            O::SetTimeline { old, new } => {
                let (expected, target) = dir.pick(old, new);
                time_ops::set_timeline(doc, expected, target, fwd)
            }
            O::SetVariant { name, old, new } => {
                let (expected, target) = dir.pick(old, new);
                time_ops::set_variant(doc, name, expected.as_ref(), target.as_ref(), fwd)
            }
            O::RenameVariant { old, new } => {
                let (from, to) = dir.pick(old, new);
                time_ops::rename_variant(doc, from, to)
            }
            O::Group { label, ops } => run_group(doc, label, ops, dir),
        }
    }
}

/// Runs the members of a group in `dir` (reverse order when reverting); on the first
/// failure, the members already run are run back and the error names the member.
fn run_group(doc: &mut Document, label: &str, ops: &[Operation], dir: Dir) -> Result<()> {
    let order: Vec<usize> = match dir {
        Dir::Forward => (0..ops.len()).collect(),
        Dir::Backward => (0..ops.len()).rev().collect(),
    };
    for (done, &k) in order.iter().enumerate() {
        if let Err(e) = ops[k].run(doc, dir) {
            for &j in order[..done].iter().rev() {
                // Running back what was just run cannot fail: each member left the
                // document in exactly the state its reverse expects.
                let _ = ops[j].run(doc, dir.flip());
            }
            return Err(HistoryError::InGroup {
                label: label.to_owned(),
                index: k,
                source: Box::new(e),
            });
        }
    }
    Ok(())
}

/// Sets one on/off flag of layer `index` of `mesh` (enabled, solo) to `target` after
/// checking it holds `expected`.
fn set_layer_flag(
    doc: &mut Document,
    mesh: &str,
    index: usize,
    (expected, target): (&bool, &bool),
    name: &str,
    flag: fn(&mut LayerSpec) -> &mut bool,
) -> Result<()> {
    let (i, m) = mesh_at(doc, mesh)?;
    layer_at(m, mesh, index)?;
    if let Some(m) = mesh_mut(doc, i) {
        let value = flag(&mut m.stack[index]);
        same(&*value, expected, || {
            format!("mesh '{mesh}', layer {index}: {name}")
        })?;
        *value = *target;
    }
    Ok(())
}

fn layer_at<'a>(m: &'a MeshNode, mesh: &str, index: usize) -> Result<&'a LayerSpec> {
    m.stack.get(index).ok_or_else(|| {
        SceneError::IndexOutOfRange {
            what: format!("mesh '{mesh}': layer"),
            index,
            len: m.stack.len(),
        }
        .into()
    })
}

fn insert_node(doc: &mut Document, index: usize, node: &Node, check: bool) -> Result<()> {
    in_range(index, doc.nodes.len(), true, || "node list".to_owned())?;
    if check {
        check_new_node(doc, index, node)?;
    } else if doc.index_of(&node.name).is_some() {
        return Err(SceneError::DuplicateName {
            name: node.name.clone(),
        }
        .into());
    }
    doc.nodes.insert(index, node.clone());
    Ok(())
}

fn remove_node(doc: &mut Document, index: usize, node: &Node, check: bool) -> Result<()> {
    in_range(index, doc.nodes.len(), false, || "node list".to_owned())?;
    same(&doc.nodes[index], node, || format!("node {index}"))?;
    if check && let Some(by) = first_reference(doc, &node.name) {
        return Err(HistoryError::StillReferenced {
            what: format!("node '{}'", node.name),
            by,
        });
    }
    doc.nodes.remove(index);
    Ok(())
}

fn rename(doc: &mut Document, from: &str, to: &str) -> Result<()> {
    let i = node_index(doc, from)?;
    if to.is_empty() {
        return Err(SceneError::EmptyName { index: i }.into());
    }
    if from == to {
        return Ok(());
    }
    if doc.index_of(to).is_some() {
        return Err(SceneError::DuplicateName {
            name: to.to_owned(),
        }
        .into());
    }
    // A dangling reference to `to` would be indistinguishable from the renamed ones
    // afterwards, and undo could not restore it exactly.
    if let Some(by) = first_reference(doc, to) {
        return Err(HistoryError::StillReferenced {
            what: format!("the name '{to}'"),
            by,
        });
    }
    doc.rename(from, to)?;
    Ok(())
}

fn insert_layer(
    doc: &mut Document,
    mesh: &str,
    index: usize,
    layer: &LayerSpec,
    check: bool,
) -> Result<()> {
    let (i, m) = mesh_at(doc, mesh)?;
    in_range(index, m.stack.len(), true, || {
        format!("mesh '{mesh}': layer")
    })?;
    if check {
        check_layer(doc, mesh, &m.areas, index, layer)?;
    }
    if let Some(m) = mesh_mut(doc, i) {
        m.stack.insert(index, layer.clone());
    }
    Ok(())
}

fn remove_layer(doc: &mut Document, mesh: &str, index: usize, layer: &LayerSpec) -> Result<()> {
    let (i, m) = mesh_at(doc, mesh)?;
    same(layer_at(m, mesh, index)?, layer, || {
        format!("mesh '{mesh}', layer {index}")
    })?;
    if let Some(m) = mesh_mut(doc, i) {
        m.stack.remove(index);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn macro_value(node: &str, old: f32, new: f32) -> Operation {
        Operation::SetMacroValue {
            node: node.to_owned(),
            old,
            new,
        }
    }

    #[test]
    fn merge_keeps_the_first_old_and_the_last_new() {
        let mut a = macro_value("m", 0.0, 0.2);
        assert!(a.merge(&macro_value("m", 0.2, 0.5)));
        assert_eq!(a, macro_value("m", 0.0, 0.5));
    }

    #[test]
    fn merge_needs_the_same_target_and_continuity() {
        let a = macro_value("m", 0.0, 0.2);
        assert!(!a.can_merge(&macro_value("n", 0.2, 0.5)), "other node");
        assert!(!a.can_merge(&macro_value("m", 0.3, 0.5)), "not continuous");
        let weight = Operation::SetLayerWeight {
            mesh: "m".into(),
            index: 0,
            old: 0.2,
            new: 0.3,
        };
        assert!(!a.can_merge(&weight), "other kind of edit");
        let mut other_layer = weight.clone();
        if let Operation::SetLayerWeight { index, old, .. } = &mut other_layer {
            *index = 1;
            *old = 0.3;
        }
        assert!(!weight.can_merge(&other_layer));
        // Additions are never merged.
        let add = Operation::add_layer("m", 0, LayerSpec::new("t"));
        assert!(!add.can_merge(&add));
    }

    #[test]
    fn groups_merge_member_by_member() {
        let group = |x: f32, y: f32| Operation::Group {
            label: "drag two".into(),
            ops: vec![macro_value("a", x, y), macro_value("b", -x, -y)],
        };
        let mut g = group(0.0, 0.1);
        assert!(g.merge(&group(0.1, 0.4)));
        assert_eq!(g, group(0.0, 0.4));
        let shorter = Operation::Group {
            label: "one".into(),
            ops: vec![macro_value("a", 0.4, 0.5)],
        };
        assert!(!g.can_merge(&shorter));
    }

    #[test]
    fn an_edit_of_a_tool_just_added_folds_into_the_add() {
        use ductile_core::lattice::{LatticeFrame, LatticeTool};
        let frame = LatticeFrame {
            origin: glam::Vec3::ZERO,
            s: glam::Vec3::X,
            t: glam::Vec3::Y,
            u: glam::Vec3::Z,
        };
        let small = Tool::Lattice(LatticeTool::bernstein(frame, (3, 3, 3)));
        let large = Tool::Lattice(LatticeTool::bernstein(frame, (5, 4, 3)));
        let node = |tool: &Tool| Node {
            name: "lattice".into(),
            parent: Some("m".into()),
            transform: Transform::IDENTITY,
            kind: NodeKind::Tool(tool.clone()),
        };
        let add = |tool: &Tool| Operation::Group {
            label: "add lattice".into(),
            ops: vec![
                Operation::AddNode {
                    index: 1,
                    node: node(tool),
                },
                Operation::add_layer("m", 0, LayerSpec::new("lattice")),
            ],
        };
        let resize = |old: &Tool, new: &Tool| Operation::SetTool {
            node: "lattice".into(),
            old: old.clone(),
            new: new.clone(),
        };
        let mut step = add(&small);
        assert!(step.merge(&resize(&small, &large)));
        assert_eq!(step, add(&large));
        // Only a continuous edit of that very node.
        assert!(!step.can_merge(&resize(&small, &large)), "not continuous");
        let mut other = resize(&large, &small);
        if let Operation::SetTool { node, .. } = &mut other {
            *node = "other".into();
        }
        assert!(!step.can_merge(&other), "another node");
        assert!(!resize(&small, &large).can_merge(&add(&small)));
    }

    #[test]
    fn inverse_of_a_group_reverses_its_members() {
        let g = Operation::Group {
            label: "g".into(),
            ops: vec![macro_value("a", 0.0, 1.0), Operation::move_layer("m", 0, 2)],
        };
        let Operation::Group { ops, .. } = g.inverse() else {
            panic!("a group's inverse is a group")
        };
        assert_eq!(
            ops,
            vec![Operation::move_layer("m", 2, 0), macro_value("a", 1.0, 0.0)]
        );
        assert_eq!(g.elementary_count(), 2);
    }

    #[test]
    fn operations_read_as_ron() {
        let text = "SetLayerEnabled(mesh: \"head\", index: 3, old: true, new: false)";
        let op: Operation = ron::from_str(text).unwrap();
        assert_eq!(op.describe(), "disable layer 3 of 'head'");
        let unknown = "SetLayerEnabled(mesh: \"head\", index: 3, old: true, new: false, x: 1)";
        assert!(ron::from_str::<Operation>(unknown).is_err());
    }
}
