//! Validation of the part of a document an operation edits.
//!
//! An operation checks only what it changes, with the same rules as
//! [`Document::problems`]: names, parents and cycles, finite transforms, tool, volume,
//! influence and macro parameters, and references by name. A document without problems
//! therefore stays without problems after any accepted operation, and checking costs the
//! size of the edit (plus name look-ups), not the size of the document or the history.

use std::collections::BTreeMap;
use std::fmt::Debug;

use ductile_core::error::CoreError;
use ductile_core::ffsd::FfsdMacro;
use ductile_core::tool::Tool;
use ductile_scene::prelude::*;

use crate::error::{HistoryError, Result};

/// Position of node `name`, or [`SceneError::NoSuchNode`].
pub(crate) fn node_index(doc: &Document, name: &str) -> Result<usize> {
    doc.index_of(name).ok_or_else(|| {
        SceneError::NoSuchNode {
            name: name.to_owned(),
        }
        .into()
    })
}

/// The mesh node at `i` (named `name`), or [`SceneError::WrongKind`].
pub(crate) fn mesh_at<'a>(doc: &'a Document, name: &str) -> Result<(usize, &'a MeshNode)> {
    let i = node_index(doc, name)?;
    match &doc.nodes[i].kind {
        NodeKind::Mesh(m) => Ok((i, m)),
        other => Err(wrong_kind(name, other, "mesh")),
    }
}

/// The mesh at node index `i`, mutably. Only called after [`mesh_at`] succeeded.
pub(crate) fn mesh_mut(doc: &mut Document, i: usize) -> Option<&mut MeshNode> {
    match &mut doc.nodes.get_mut(i)?.kind {
        NodeKind::Mesh(m) => Some(m),
        _ => None,
    }
}

pub(crate) fn wrong_kind(name: &str, found: &NodeKind, expected: &'static str) -> HistoryError {
    SceneError::WrongKind {
        node: name.to_owned(),
        found: found.name(),
        expected,
    }
    .into()
}

/// Longest printed value kept in a [`HistoryError::Stale`] message.
const MAX_PRINTED: usize = 160;

fn printed<T: Debug>(v: &T) -> String {
    let mut s = format!("{v:?}");
    if s.len() > MAX_PRINTED {
        let mut cut = MAX_PRINTED;
        while !s.is_char_boundary(cut) {
            cut -= 1;
        }
        s.truncate(cut);
        s.push('…');
    }
    s
}

/// `Ok` when the document's value `found` equals the operation's `expected` one, else
/// [`HistoryError::Stale`].
pub(crate) fn same<T: PartialEq + Debug + ?Sized>(
    found: &T,
    expected: &T,
    what: impl FnOnce() -> String,
) -> Result<()> {
    if found == expected {
        Ok(())
    } else {
        Err(HistoryError::Stale {
            what: what(),
            expected: printed(&expected),
            found: printed(&found),
        })
    }
}

/// `Ok` when `index < len` (or `≤ len` for insertion positions).
pub(crate) fn in_range(
    index: usize,
    len: usize,
    insert: bool,
    what: impl FnOnce() -> String,
) -> Result<()> {
    if index < len || (insert && index == len) {
        Ok(())
    } else {
        Err(SceneError::IndexOutOfRange {
            what: what(),
            index,
            len,
        }
        .into())
    }
}

/// A node transform must be finite, with non-zero scales and a non-zero rotation
/// quaternion, so that it can be inverted (tools are carried into mesh space through the
/// inverse of the mesh's world transform).
pub(crate) fn check_transform(what: impl Fn() -> String, t: &Transform) -> Result<()> {
    if !t.is_finite() {
        return Err(SceneError::NotFinite {
            what: format!("{}: transform", what()),
            value: format!("{t:?}"),
        }
        .into());
    }
    match t.degeneracy() {
        Some(problem) => Err(HistoryError::DegenerateTransform {
            what: what(),
            problem,
        }),
        None => Ok(()),
    }
}

/// A tool's parameters (core's `validate`).
pub(crate) fn check_tool(node: &str, tool: &Tool) -> Result<()> {
    Ok(tool
        .validate(&format!("tool '{node}'"))
        .map_err(SceneError::Core)?)
}

/// A macro tool's value and macro reference.
pub(crate) fn check_macro_use(doc: &Document, node: &str, m: &MacroUse) -> Result<()> {
    if !doc.macros.contains_key(&m.name) {
        return Err(SceneError::UnknownMacro {
            node: node.to_owned(),
            name: m.name.clone(),
        }
        .into());
    }
    check_macro_value(node, m.value)
}

/// A macro tool's value γ must be finite.
pub(crate) fn check_macro_value(node: &str, value: f32) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SceneError::NotFinite {
            what: format!("macro tool '{node}': value"),
            value: value.to_string(),
        }
        .into())
    }
}

/// A volume's shape.
pub(crate) fn check_shape(what: &str, shape: &ductile_core::influence::Shape) -> Result<()> {
    Ok(shape.validate(what).map_err(SceneError::Core)?)
}

/// A library macro: its points and height limit, and its slider range.
pub(crate) fn check_macro_definition(name: &str, m: &FfsdMacro) -> Result<()> {
    if name.is_empty() {
        return Err(HistoryError::EmptyName {
            what: "macro definition".to_owned(),
        });
    }
    Tool::Ffsd(m.tool(1.0))
        .validate(&format!("macro '{name}'"))
        .map_err(SceneError::Core)?;
    if !(m.range.0.is_finite() && m.range.1.is_finite() && m.range.0 < m.range.1) {
        return Err(SceneError::NotFinite {
            what: format!("macro '{name}': range (must be finite, min < max)"),
            value: format!("{:?}", m.range),
        }
        .into());
    }
    Ok(())
}

/// An area definition: region shapes must be valid. (Vertex indices are checked against the
/// rest mesh when the stack is resolved; the document does not hold the mesh.)
pub(crate) fn check_area(mesh: &str, name: &str, area: &Area) -> Result<()> {
    if name.is_empty() {
        return Err(HistoryError::EmptyName {
            what: format!("mesh '{mesh}': area"),
        });
    }
    if let Area::Region(shapes) = area {
        for (k, s) in shapes.iter().enumerate() {
            check_shape(
                &format!("mesh '{mesh}', area '{name}', shape {k}"),
                &s.shape,
            )?;
            check_transform(
                || format!("mesh '{mesh}', area '{name}', shape {k}"),
                &s.transform,
            )?;
        }
    }
    Ok(())
}

/// A layer's weight must be finite and in `[0, 1]`.
pub(crate) fn check_weight(mesh: &str, index: usize, weight: f32) -> Result<()> {
    if weight.is_finite() && (0.0..=1.0).contains(&weight) {
        Ok(())
    } else {
        Err(SceneError::Core(CoreError::OutOfRange {
            what: format!("mesh '{mesh}', layer {index}: weight"),
            value: f64::from(weight),
            expected: "must be in [0, 1]",
        })
        .into())
    }
}

/// A layer's influence: its volumes exist and are volumes, its area is defined on the mesh
/// (`areas`), `inner` is in `[0, 1)`.
pub(crate) fn check_influence(
    doc: &Document,
    mesh: &str,
    areas: &BTreeMap<String, Area>,
    index: usize,
    inf: &InfluenceSpec,
) -> Result<()> {
    for v in &inf.volumes {
        match doc.node(v) {
            Err(_) => {
                return Err(SceneError::UnknownVolume {
                    mesh: mesh.to_owned(),
                    layer: index,
                    volume: v.clone(),
                }
                .into());
            }
            Ok(n) if !matches!(n.kind, NodeKind::Volume(_)) => {
                return Err(wrong_kind(v, &n.kind, "volume"));
            }
            Ok(_) => {}
        }
    }
    if let Some(a) = &inf.area
        && !areas.contains_key(a)
    {
        return Err(SceneError::UnknownArea {
            mesh: mesh.to_owned(),
            layer: index,
            area: a.clone(),
        }
        .into());
    }
    if !(inf.inner.is_finite() && (0.0..1.0).contains(&inf.inner)) {
        return Err(SceneError::Core(CoreError::OutOfRange {
            what: format!("mesh '{mesh}', layer {index}: influence inner"),
            value: f64::from(inf.inner),
            expected: "must be in [0, 1)",
        })
        .into());
    }
    Ok(())
}

/// A whole layer: its tool exists and is a tool, weight and influence are valid.
pub(crate) fn check_layer(
    doc: &Document,
    mesh: &str,
    areas: &BTreeMap<String, Area>,
    index: usize,
    layer: &LayerSpec,
) -> Result<()> {
    match doc.node(&layer.tool) {
        Err(_) => {
            return Err(SceneError::UnknownTool {
                mesh: mesh.to_owned(),
                layer: index,
                tool: layer.tool.clone(),
            }
            .into());
        }
        Ok(n) if !n.kind.is_tool() => return Err(wrong_kind(&layer.tool, &n.kind, "tool")),
        Ok(_) => {}
    }
    check_weight(mesh, index, layer.weight)?;
    if let Some(inf) = &layer.influence {
        check_influence(doc, mesh, areas, index, inf)?;
    }
    Ok(())
}

/// A node about to be added to `doc`: unique non-empty name, existing parent, valid
/// transform and kind.
pub(crate) fn check_new_node(doc: &Document, index: usize, node: &Node) -> Result<()> {
    if node.name.is_empty() {
        return Err(SceneError::EmptyName { index }.into());
    }
    if let Some(problem) = ductile_scene::validate::name_problem(&node.name) {
        return Err(SceneError::BadName {
            index,
            name: node.name.clone(),
            problem,
        }
        .into());
    }
    if doc.index_of(&node.name).is_some() {
        return Err(SceneError::DuplicateName {
            name: node.name.clone(),
        }
        .into());
    }
    if let Some(p) = &node.parent
        && doc.index_of(p).is_none()
    {
        return Err(SceneError::UnknownParent {
            node: node.name.clone(),
            parent: p.clone(),
        }
        .into());
    }
    check_transform(|| format!("node '{}'", node.name), &node.transform)?;
    match &node.kind {
        NodeKind::Tool(t) => check_tool(&node.name, t),
        NodeKind::Macro(m) => check_macro_use(doc, &node.name, m),
        NodeKind::Volume(v) => check_shape(&format!("volume '{}'", node.name), &v.shape),
        NodeKind::Mesh(m) => {
            for (name, area) in &m.areas {
                check_area(&node.name, name, area)?;
            }
            for (i, layer) in m.stack.iter().enumerate() {
                check_layer(doc, &node.name, &m.areas, i, layer)?;
            }
            Ok(())
        }
        NodeKind::Group => Ok(()),
    }
}

/// The first place that refers to node `name` by name (a child's parent, a layer's tool, a
/// layer's influence volume, an animation track, a variant's state), described for
/// messages.
pub(crate) fn first_reference(doc: &Document, name: &str) -> Option<String> {
    for n in &doc.nodes {
        if n.parent.as_deref() == Some(name) {
            return Some(format!("node '{}' (its parent)", n.name));
        }
        if let NodeKind::Mesh(m) = &n.kind {
            for (i, layer) in m.stack.iter().enumerate() {
                if layer.tool == name {
                    return Some(format!("mesh '{}', layer {i} (its tool)", n.name));
                }
                if let Some(inf) = &layer.influence
                    && inf.volumes.iter().any(|v| v == name)
                {
                    return Some(format!("mesh '{}', layer {i} (its influence)", n.name));
                }
            }
        }
    }
    if let Some(tracks) = doc.animation.tracks.get(name)
        && let Some(param) = tracks.keys().next()
    {
        return Some(format!("animation track '{name}' / '{param}'"));
    }
    if let Some(v) = doc
        .variants
        .iter()
        .find(|(_, v)| v.states.contains_key(name))
    {
        return Some(format!("variant '{}'", v.0));
    }
    None
}
