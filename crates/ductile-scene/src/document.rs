//! The scene document and its nodes.

use std::collections::BTreeMap;

use ductile_core::ffsd::FfsdMacro;
use ductile_core::influence::{Falloff, Shape};
use ductile_core::tool::Tool;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
use crate::time::Animation;
use crate::transform::Transform;
use crate::variant::Variant;

/// A whole scene: the node graph and the macro library. This is the single source of truth
/// that history operations edit and that every view (CLI, Studio) reads.
///
/// Nodes are identified by their unique names; references (parents, layer tools, influence
/// volumes, macros, areas) are by name, and renaming a node updates them
/// ([`Document::rename`]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Document {
    /// Nodes in outliner order.
    #[serde(default)]
    pub nodes: Vec<Node>,
    /// The macro library, by name.
    #[serde(default, deserialize_with = "unique_keys")]
    pub macros: BTreeMap<String, FfsdMacro>,
    /// Keyframe tracks and the timeline (not written when it is the default, empty one).
    #[serde(default, skip_serializing_if = "Animation::is_default")]
    pub animation: Animation,
    /// Named variants: snapshots of the tools' states (the identikit's suspects), by name.
    #[serde(
        default,
        skip_serializing_if = "BTreeMap::is_empty",
        deserialize_with = "unique_keys"
    )]
    pub variants: BTreeMap<String, Variant>,
}

/// A node of the scene graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    /// Unique name.
    pub name: String,
    /// Parent node's name; `None` for a root.
    #[serde(default)]
    pub parent: Option<String>,
    /// Placement relative to the parent.
    #[serde(default)]
    pub transform: Transform,
    /// What the node is.
    pub kind: NodeKind,
}

/// The kinds of node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum NodeKind {
    /// A mesh with its deformation stack.
    Mesh(MeshNode),
    /// A deformation tool, given in the node's local frame.
    Tool(Tool),
    /// A tool driven by a macro of the library with one user value.
    Macro(MacroUse),
    /// An influence volume, placed by the node's transform.
    Volume(VolumeNode),
    /// A group: only a transform for its children.
    Group,
}

impl NodeKind {
    /// The kind's name for messages.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            NodeKind::Mesh(_) => "mesh",
            NodeKind::Tool(_) => "tool",
            NodeKind::Macro(_) => "macro tool",
            NodeKind::Volume(_) => "volume",
            NodeKind::Group => "group",
        }
    }

    /// True for tools and macro tools (what a layer may name).
    #[must_use]
    pub fn is_tool(&self) -> bool {
        matches!(self, NodeKind::Tool(_) | NodeKind::Macro(_))
    }
}

/// A mesh node: where its rest mesh comes from, its stack and its named areas.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshNode {
    /// Path of the mesh file, relative to the scene file (glTF or OBJ).
    pub source: String,
    /// The deformation stack, bottom first.
    #[serde(default)]
    pub stack: Vec<LayerSpec>,
    /// Named vertex areas.
    #[serde(default, deserialize_with = "unique_keys")]
    pub areas: BTreeMap<String, Area>,
}

/// A named vertex area of a mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Area {
    /// Explicit stored vertex indices (as in the mesh file).
    Vertices(Vec<u32>),
    /// Every vertex of the rest mesh inside any of these shapes (mesh space), evaluated
    /// once on the rest mesh.
    Region(Vec<RegionShape>),
}

/// One shape of an [`Area::Region`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionShape {
    /// The shape.
    pub shape: Shape,
    /// Its placement in mesh space.
    #[serde(default)]
    pub transform: Transform,
}

/// One layer of a mesh's stack.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// Name of the tool (or macro tool) node.
    pub tool: String,
    /// Optional influence.
    #[serde(default)]
    pub influence: Option<InfluenceSpec>,
    /// Blend weight in `[0, 1]`.
    #[serde(default = "one")]
    pub weight: f32,
    /// Disabled layers are skipped.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Soloed layers: when any layer of a stack is soloed, only the soloed (and enabled)
    /// layers are evaluated, to look at a few layers alone.
    #[serde(default, skip_serializing_if = "is_false")]
    pub solo: bool,
}

impl LayerSpec {
    /// An enabled, full-weight layer without influence.
    #[must_use]
    pub fn new(tool: impl Into<String>) -> Self {
        Self {
            tool: tool.into(),
            influence: None,
            weight: 1.0,
            enabled: true,
            solo: false,
        }
    }
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference.
fn is_false(b: &bool) -> bool {
    !*b
}

fn one() -> f32 {
    1.0
}

fn yes() -> bool {
    true
}

/// A layer's influence, by names.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InfluenceSpec {
    /// Names of volume nodes (their union).
    #[serde(default)]
    pub volumes: Vec<String>,
    /// Name of an area of the mesh.
    #[serde(default)]
    pub area: Option<String>,
    /// Falloff inside the volumes.
    #[serde(default)]
    pub falloff: Falloff,
    /// Normalised distance up to which the weight stays 1, in `[0, 1)`.
    #[serde(default)]
    pub inner: f32,
    /// The area minus the volumes.
    #[serde(default)]
    pub invert: bool,
}

/// A macro tool: which macro, and the user value γ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MacroUse {
    /// Name of the macro in the document's library.
    pub name: String,
    /// The user's γ (multiplies every point's γ).
    pub value: f32,
}

/// An influence volume node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeNode {
    /// The shape in the node's local frame.
    pub shape: Shape,
}

/// `stem`, or `stem-2`, `stem-3`, …: the first name `taken` says is free (node names,
/// variant names).
#[must_use]
pub fn unique_among(stem: &str, taken: impl Fn(&str) -> bool) -> String {
    if !taken(stem) {
        return stem.to_owned();
    }
    (2..)
        .map(|k| format!("{stem}-{k}"))
        .find(|n| !taken(n))
        .unwrap_or_else(|| stem.to_owned())
}

impl Document {
    /// Position of the node called `name`.
    #[must_use]
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.name == name)
    }

    /// `stem`, or `stem-2`, `stem-3`, …: the first name no node has.
    #[must_use]
    pub fn unique_name(&self, stem: &str) -> String {
        unique_among(stem, |n| self.index_of(n).is_some())
    }

    /// Every node's index by name (the first, should a name repeat): for walks over many
    /// nodes, where [`Document::index_of`]'s linear search per step would be quadratic.
    #[must_use]
    pub fn name_index(&self) -> std::collections::HashMap<&str, usize> {
        let mut index = std::collections::HashMap::with_capacity(self.nodes.len());
        for (i, n) in self.nodes.iter().enumerate() {
            index.entry(n.name.as_str()).or_insert(i);
        }
        index
    }

    /// The node called `name`.
    pub fn node(&self, name: &str) -> Result<&Node> {
        self.nodes
            .iter()
            .find(|n| n.name == name)
            .ok_or_else(|| no_such(name))
    }

    /// The node called `name`, mutably.
    pub fn node_mut(&mut self, name: &str) -> Result<&mut Node> {
        self.nodes
            .iter_mut()
            .find(|n| n.name == name)
            .ok_or_else(|| no_such(name))
    }

    /// The mesh node called `name`.
    pub fn mesh(&self, name: &str) -> Result<&MeshNode> {
        match &self.node(name)?.kind {
            NodeKind::Mesh(m) => Ok(m),
            other => Err(wrong_kind(name, other, "mesh")),
        }
    }

    /// The mesh node called `name`, mutably.
    pub fn mesh_mut(&mut self, name: &str) -> Result<&mut MeshNode> {
        let node = self.node_mut(name)?;
        match &mut node.kind {
            NodeKind::Mesh(m) => Ok(m),
            other => Err(wrong_kind(name, other, "mesh")),
        }
    }

    /// Names of all mesh nodes, in document order.
    #[must_use]
    pub fn mesh_names(&self) -> Vec<&str> {
        self.nodes
            .iter()
            .filter(|n| matches!(n.kind, NodeKind::Mesh(_)))
            .map(|n| n.name.as_str())
            .collect()
    }

    /// Direct children of `name`, in document order.
    #[must_use]
    pub fn children(&self, name: &str) -> Vec<&Node> {
        self.nodes
            .iter()
            .filter(|n| n.parent.as_deref() == Some(name))
            .collect()
    }

    /// True when `ancestor` is `node` or one of its ancestors. Stops on cycles.
    #[must_use]
    pub fn is_ancestor(&self, ancestor: &str, node: &str) -> bool {
        let mut current = Some(node);
        for _ in 0..=self.nodes.len() {
            match current {
                Some(c) if c == ancestor => return true,
                Some(c) => current = self.node(c).ok().and_then(|n| n.parent.as_deref()),
                None => return false,
            }
        }
        false
    }

    /// Renames a node and every reference to it (children's parents, layer tools, influence
    /// volumes, its keyframe tracks, its state in every variant). Fails when `old` does not
    /// exist or `new` is taken, empty, only white space or holds a control character.
    pub fn rename(&mut self, old: &str, new: &str) -> Result<()> {
        if old == new {
            return self.node(old).map(|_| ());
        }
        if new.is_empty() {
            return Err(SceneError::EmptyName {
                index: self.index_of(old).unwrap_or(0),
            });
        }
        if let Some(problem) = crate::validate::name_problem(new) {
            return Err(SceneError::BadName {
                index: self.index_of(old).unwrap_or(0),
                name: new.to_owned(),
                problem,
            });
        }
        if self.index_of(new).is_some() {
            return Err(SceneError::DuplicateName {
                name: new.to_owned(),
            });
        }
        self.node_mut(old)?.name = new.to_owned();
        let fix = |s: &mut String| {
            if s == old {
                *s = new.to_owned();
            }
        };
        for n in &mut self.nodes {
            if let Some(p) = &mut n.parent {
                fix(p);
            }
            if let NodeKind::Mesh(m) = &mut n.kind {
                for layer in &mut m.stack {
                    fix(&mut layer.tool);
                    if let Some(inf) = &mut layer.influence {
                        inf.volumes.iter_mut().for_each(fix);
                    }
                }
            }
        }
        if let Some(tracks) = self.animation.tracks.remove(old) {
            self.animation.tracks.insert(new.to_owned(), tracks);
        }
        for v in self.variants.values_mut() {
            if let Some(state) = v.states.remove(old) {
                v.states.insert(new.to_owned(), state);
            }
        }
        Ok(())
    }
}

pub(crate) fn no_such(name: &str) -> SceneError {
    SceneError::NoSuchNode {
        name: name.to_owned(),
    }
}

pub(crate) fn wrong_kind(name: &str, found: &NodeKind, expected: &'static str) -> SceneError {
    SceneError::WrongKind {
        node: name.to_owned(),
        found: found.name(),
        expected,
    }
}

/// Deserialises a map by name, refusing a key that appears twice (a plain `BTreeMap` would
/// keep the last one silently): for `macros`, `areas` and `variants` of scene files.
///
/// # Errors
/// The deserialiser's errors, and "the key … appears twice".
pub fn unique_keys<'de, D, V>(d: D) -> std::result::Result<BTreeMap<String, V>, D::Error>
where
    D: serde::Deserializer<'de>,
    V: Deserialize<'de>,
{
    struct Unique<V>(std::marker::PhantomData<V>);
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Unique<V> {
        type Value = BTreeMap<String, V>;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a map with unique names")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> std::result::Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some((key, value)) = map.next_entry::<String, V>()? {
                if out.contains_key(&key) {
                    return Err(serde::de::Error::custom(format!(
                        "the name {key:?} appears twice in the map"
                    )));
                }
                out.insert(key, value);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Unique(std::marker::PhantomData))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique() {
        let mut doc = Document::default();
        assert_eq!(doc.unique_name("lattice"), "lattice");
        for name in ["lattice", "lattice-2"] {
            doc.nodes.push(Node {
                name: name.into(),
                parent: None,
                transform: Transform::IDENTITY,
                kind: NodeKind::Group,
            });
        }
        assert_eq!(doc.unique_name("lattice"), "lattice-3");
    }
}
