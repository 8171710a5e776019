//! Constructors that read the `old` values from a document, so that callers (the Studio,
//! scripts, tests) only say what the new value is. They check only that the edited place
//! exists; the full checks happen when the operation is applied.

use ductile_core::ffsd::FfsdMacro;
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_scene::prelude::*;

use crate::check::{mesh_at, node_index, wrong_kind};
use crate::error::{HistoryError, Result};
use crate::operation::Operation;

impl Operation {
    /// Appends `node` to the document's node list.
    #[must_use]
    pub fn add_node(doc: &Document, node: Node) -> Self {
        Operation::AddNode {
            index: doc.nodes.len(),
            node,
        }
    }

    /// Removes node `name` (refused on apply while it is referenced).
    pub fn remove_node(doc: &Document, name: &str) -> Result<Self> {
        let index = node_index(doc, name)?;
        Ok(Operation::RemoveNode {
            index,
            node: doc.nodes[index].clone(),
        })
    }

    /// A group that removes node `name`, its whole subtree (deepest first), every layer whose
    /// tool is one of the removed nodes, every reference to a removed volume from layer
    /// influences, the removed nodes' animation tracks and their states in variants.
    pub fn remove_node_and_references(doc: &Document, name: &str) -> Result<Self> {
        node_index(doc, name)?;
        // Work on a scratch copy so that each generated operation sees the state left by
        // the ones before it (indices shift as layers and nodes go).
        let mut scratch = doc.clone();
        let mut ops = Vec::new();
        let mut doomed = vec![name.to_owned()];
        let mut k = 0;
        while k < doomed.len() {
            let children: Vec<String> = scratch
                .children(&doomed[k])
                .iter()
                .map(|n| n.name.clone())
                .collect();
            doomed.extend(children);
            k += 1;
        }
        let meshes: Vec<String> = scratch
            .mesh_names()
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        for mesh in &meshes {
            let mut index = 0;
            while let Ok((_, m)) = mesh_at(&scratch, mesh) {
                let Some(layer) = m.stack.get(index) else {
                    break;
                };
                let op = if doomed.contains(&layer.tool) {
                    Operation::RemoveLayer {
                        mesh: mesh.clone(),
                        index,
                        layer: layer.clone(),
                    }
                } else if let Some(inf) = &layer.influence
                    && inf.volumes.iter().any(|v| doomed.contains(v))
                {
                    let mut new = inf.clone();
                    new.volumes.retain(|v| !doomed.contains(v));
                    index += 1;
                    Operation::SetLayerInfluence {
                        mesh: mesh.clone(),
                        index: index - 1,
                        old: Some(inf.clone()),
                        new: Some(new),
                    }
                } else {
                    index += 1;
                    continue;
                };
                op.apply(&mut scratch)?;
                ops.push(op);
            }
        }
        // Tracks of the removed nodes, and their states in variants.
        for doomed_name in &doomed {
            let params: Vec<String> = scratch
                .animation
                .tracks
                .get(doomed_name)
                .map(|t| t.keys().cloned().collect())
                .unwrap_or_default();
            for param in params {
                let op = Operation::set_track(&scratch, doomed_name, &param, None);
                op.apply(&mut scratch)?;
                ops.push(op);
            }
        }
        let variants: Vec<String> = scratch.variants.keys().cloned().collect();
        for v in variants {
            let old = scratch.variants[&v].clone();
            let mut new = old.clone();
            new.states.retain(|n, _| !doomed.contains(n));
            if new != old {
                let op = Operation::SetVariant {
                    name: v,
                    old: Some(old),
                    new: Some(new),
                };
                op.apply(&mut scratch)?;
                ops.push(op);
            }
        }
        for doomed_name in doomed.iter().rev() {
            let op = Operation::remove_node(&scratch, doomed_name)?;
            op.apply(&mut scratch)?;
            ops.push(op);
        }
        Ok(Operation::Group {
            label: format!("delete '{name}'"),
            ops,
        })
    }

    /// Renames node `old` to `new`.
    #[must_use]
    pub fn rename(old: &str, new: &str) -> Self {
        Operation::Rename {
            old: old.to_owned(),
            new: new.to_owned(),
        }
    }

    /// Gives node `node` the parent `parent` (`None`: a root).
    pub fn reparent(doc: &Document, node: &str, parent: Option<&str>) -> Result<Self> {
        Ok(Operation::Reparent {
            node: node.to_owned(),
            old: doc.node(node)?.parent.clone(),
            new: parent.map(str::to_owned),
        })
    }

    /// Sets the local transform of node `node`.
    pub fn set_transform(doc: &Document, node: &str, new: Transform) -> Result<Self> {
        Ok(Operation::SetTransform {
            node: node.to_owned(),
            old: doc.node(node)?.transform,
            new,
        })
    }

    /// Sets the tool of tool node `node`.
    pub fn set_tool(doc: &Document, node: &str, new: Tool) -> Result<Self> {
        match &doc.node(node)?.kind {
            NodeKind::Tool(old) => Ok(Operation::SetTool {
                node: node.to_owned(),
                old: old.clone(),
                new,
            }),
            other => Err(wrong_kind(node, other, "tool")),
        }
    }

    /// Sets the shape of volume node `node`.
    pub fn set_volume(doc: &Document, node: &str, new: Shape) -> Result<Self> {
        match &doc.node(node)?.kind {
            NodeKind::Volume(v) => Ok(Operation::SetVolume {
                node: node.to_owned(),
                old: v.shape.clone(),
                new,
            }),
            other => Err(wrong_kind(node, other, "volume")),
        }
    }

    /// Sets the user value γ of macro tool `node`.
    pub fn set_macro_value(doc: &Document, node: &str, new: f32) -> Result<Self> {
        match &doc.node(node)?.kind {
            NodeKind::Macro(m) => Ok(Operation::SetMacroValue {
                node: node.to_owned(),
                old: m.value,
                new,
            }),
            other => Err(wrong_kind(node, other, "macro tool")),
        }
    }

    /// Inserts `layer` at `index` of mesh `mesh`'s stack.
    #[must_use]
    pub fn add_layer(mesh: &str, index: usize, layer: LayerSpec) -> Self {
        Operation::AddLayer {
            mesh: mesh.to_owned(),
            index,
            layer,
        }
    }

    /// Removes layer `index` of mesh `mesh`.
    pub fn remove_layer(doc: &Document, mesh: &str, index: usize) -> Result<Self> {
        Ok(Operation::RemoveLayer {
            mesh: mesh.to_owned(),
            index,
            layer: layer(doc, mesh, index)?.clone(),
        })
    }

    /// Moves layer `from` of mesh `mesh` to position `to`.
    #[must_use]
    pub fn move_layer(mesh: &str, from: usize, to: usize) -> Self {
        Operation::MoveLayer {
            mesh: mesh.to_owned(),
            from,
            to,
        }
    }

    /// Enables or disables layer `index` of mesh `mesh`.
    pub fn set_layer_enabled(doc: &Document, mesh: &str, index: usize, new: bool) -> Result<Self> {
        Ok(Operation::SetLayerEnabled {
            mesh: mesh.to_owned(),
            index,
            old: layer(doc, mesh, index)?.enabled,
            new,
        })
    }

    /// Solos (or unsolos) the layer at `index` of mesh `mesh`.
    pub fn set_layer_solo(doc: &Document, mesh: &str, index: usize, new: bool) -> Result<Self> {
        Ok(Operation::SetLayerSolo {
            mesh: mesh.to_owned(),
            index,
            old: layer(doc, mesh, index)?.solo,
            new,
        })
    }

    /// Sets the weight of layer `index` of mesh `mesh`.
    pub fn set_layer_weight(doc: &Document, mesh: &str, index: usize, new: f32) -> Result<Self> {
        Ok(Operation::SetLayerWeight {
            mesh: mesh.to_owned(),
            index,
            old: layer(doc, mesh, index)?.weight,
            new,
        })
    }

    /// Sets the influence of layer `index` of mesh `mesh`.
    pub fn set_layer_influence(
        doc: &Document,
        mesh: &str,
        index: usize,
        new: Option<InfluenceSpec>,
    ) -> Result<Self> {
        Ok(Operation::SetLayerInfluence {
            mesh: mesh.to_owned(),
            index,
            old: layer(doc, mesh, index)?.influence.clone(),
            new,
        })
    }

    /// Defines (or with `None` deletes) area `name` of mesh `mesh`.
    pub fn define_area(doc: &Document, mesh: &str, name: &str, new: Option<Area>) -> Result<Self> {
        Ok(Operation::DefineArea {
            mesh: mesh.to_owned(),
            name: name.to_owned(),
            old: mesh_at(doc, mesh)?.1.areas.get(name).cloned(),
            new,
        })
    }

    /// Defines (or with `None` deletes) macro `name` of the library.
    #[must_use]
    pub fn set_macro_definition(doc: &Document, name: &str, new: Option<FfsdMacro>) -> Self {
        Operation::SetMacroDefinition {
            name: name.to_owned(),
            old: doc.macros.get(name).cloned(),
            new,
        }
    }
}

fn layer<'a>(doc: &'a Document, mesh: &str, index: usize) -> Result<&'a LayerSpec> {
    let (_, m) = mesh_at(doc, mesh)?;
    m.stack.get(index).ok_or_else(|| {
        HistoryError::from(SceneError::IndexOutOfRange {
            what: format!("mesh '{mesh}': layer"),
            index,
            len: m.stack.len(),
        })
    })
}
