//! Constructors of the Studio's authoring steps: each is one undo step (a `Group`) made of
//! elementary operations — a new tool node with its layer, a new volume (masking a layer),
//! a new group, a duplicated layer.

use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_scene::prelude::*;

use crate::check::{mesh_at, node_index};
use crate::error::Result;
use crate::operation::Operation;

impl Operation {
    /// A new tool node (a unique name from `stem`, parented to mesh `mesh`, at `transform`
    /// in the mesh's frame) with a layer on top of the mesh's stack, as one step. Returns the
    /// step and the node's name.
    pub fn add_tool_layer(
        doc: &Document,
        mesh: &str,
        stem: &str,
        tool: Tool,
        transform: Transform,
    ) -> Result<(Self, String)> {
        let (_, m) = mesh_at(doc, mesh)?;
        let name = doc.unique_name(stem);
        let kind = tool.kind_name();
        let node = Node {
            name: name.clone(),
            parent: Some(mesh.to_owned()),
            transform,
            kind: NodeKind::Tool(tool),
        };
        let ops = vec![
            Operation::add_node(doc, node),
            Operation::add_layer(mesh, m.stack.len(), LayerSpec::new(name.clone())),
        ];
        Ok((
            Operation::Group {
                label: format!("add {kind} '{name}' to '{mesh}'"),
                ops,
            },
            name,
        ))
    }

    /// A new volume node (a unique name from `stem`, under `parent`, at `transform` in the
    /// parent's frame) and, with `mask = Some((mesh, layer))`, the volume added to that
    /// layer's influence (a new influence when it has none), as one step. Returns the step and
    /// the node's name.
    pub fn add_volume(
        doc: &Document,
        parent: Option<&str>,
        stem: &str,
        shape: Shape,
        transform: Transform,
        mask: Option<(&str, usize)>,
    ) -> Result<(Self, String)> {
        if let Some(p) = parent {
            node_index(doc, p)?;
        }
        let name = doc.unique_name(stem);
        let node = Node {
            name: name.clone(),
            parent: parent.map(str::to_owned),
            transform,
            kind: NodeKind::Volume(VolumeNode { shape }),
        };
        let mut ops = vec![Operation::add_node(doc, node)];
        let mut label = format!("add volume '{name}'");
        if let Some((mesh, index)) = mask {
            let (_, m) = mesh_at(doc, mesh)?;
            let old = m
                .stack
                .get(index)
                .ok_or_else(|| SceneError::IndexOutOfRange {
                    what: format!("mesh '{mesh}': layer"),
                    index,
                    len: m.stack.len(),
                })?;
            let mut influence = old.influence.clone().unwrap_or_default();
            influence.volumes.push(name.clone());
            ops.push(Operation::SetLayerInfluence {
                mesh: mesh.to_owned(),
                index,
                old: old.influence.clone(),
                new: Some(influence),
            });
            label = format!(
                "mask layer '{}' of '{mesh}' with new volume '{name}'",
                old.tool
            );
        }
        Ok((Operation::Group { label, ops }, name))
    }

    /// A new empty group under `parent` (a unique name from `stem`). Returns the step and
    /// the group's name.
    pub fn add_group(doc: &Document, parent: Option<&str>, stem: &str) -> Result<(Self, String)> {
        if let Some(p) = parent {
            node_index(doc, p)?;
        }
        let name = doc.unique_name(stem);
        let node = Node {
            name: name.clone(),
            parent: parent.map(str::to_owned),
            transform: Transform::IDENTITY,
            kind: NodeKind::Group,
        };
        Ok((
            Operation::Group {
                label: format!("add group '{name}'"),
                ops: vec![Operation::add_node(doc, node)],
            },
            name,
        ))
    }

    /// Duplicates layer `index` of mesh `mesh`: a copy of its tool node (named
    /// `<tool>-copy`, `-copy-2`, …, same parent and transform) and a layer just above the
    /// original with the same influence, weight and flags, as one step. Returns the step and
    /// the copy's name.
    pub fn duplicate_layer(doc: &Document, mesh: &str, index: usize) -> Result<(Self, String)> {
        let (_, m) = mesh_at(doc, mesh)?;
        let layer = m
            .stack
            .get(index)
            .ok_or_else(|| SceneError::IndexOutOfRange {
                what: format!("mesh '{mesh}': layer"),
                index,
                len: m.stack.len(),
            })?;
        let original = &doc.nodes[node_index(doc, &layer.tool)?];
        let name = doc.unique_name(&format!("{}-copy", layer.tool));
        let node = Node {
            name: name.clone(),
            ..original.clone()
        };
        let copy = LayerSpec {
            tool: name.clone(),
            ..layer.clone()
        };
        Ok((
            Operation::Group {
                label: format!("duplicate layer '{}' of '{mesh}'", layer.tool),
                ops: vec![
                    Operation::add_node(doc, node),
                    Operation::add_layer(mesh, index + 1, copy),
                ],
            },
            name,
        ))
    }
}

#[cfg(test)]
mod tests {
    use ductile_core::influence::Shape;
    use ductile_scene::create::{NewTool, Placement, tool};
    use glam::Vec3;

    use super::*;
    use crate::history::History;

    fn doc() -> Document {
        Document {
            nodes: vec![Node {
                name: "spot".into(),
                parent: None,
                transform: Transform::IDENTITY,
                kind: NodeKind::Mesh(MeshNode {
                    source: "spot.obj".into(),
                    stack: Vec::new(),
                    areas: Default::default(),
                }),
            }],
            ..Document::default()
        }
    }

    fn place() -> Placement {
        Placement::around(&[Vec3::splat(-1.0), Vec3::splat(1.0)]).unwrap()
    }

    fn push(d: &mut Document, h: &mut History, op: Operation) {
        let label = op.describe();
        h.push(d, op, label, 0, None).unwrap();
    }

    #[test]
    fn adding_a_tool_is_one_step_with_a_node_and_a_layer() {
        let mut d = doc();
        let start = d.clone();
        let mut h = History::new(d.clone());
        for _ in 0..2 {
            let t = tool(
                NewTool::Lattice(ductile_scene::create::LatticeKind::Bernstein),
                &place(),
            );
            let (op, _) =
                Operation::add_tool_layer(&d, "spot", "lattice", t, Transform::IDENTITY).unwrap();
            assert_eq!(op.elementary_count(), 2);
            push(&mut d, &mut h, op);
        }
        let m = d.mesh("spot").unwrap();
        assert_eq!(
            m.stack.iter().map(|l| l.tool.as_str()).collect::<Vec<_>>(),
            ["lattice", "lattice-2"]
        );
        assert_eq!(d.node("lattice-2").unwrap().parent.as_deref(), Some("spot"));
        assert!(d.problems().is_empty());
        assert_eq!(h.len(), 2);
        h.undo(&mut d).unwrap();
        h.undo(&mut d).unwrap();
        assert_eq!(d, start);
    }

    #[test]
    fn a_new_volume_can_mask_a_layer_in_the_same_step() {
        let mut d = doc();
        let t = tool(NewTool::FfsdPoint, &place());
        let (op, name) =
            Operation::add_tool_layer(&d, "spot", "point", t, Transform::IDENTITY).unwrap();
        op.apply(&mut d).unwrap();
        let before = d.clone();
        let (op, volume) = Operation::add_volume(
            &d,
            Some("spot"),
            "sphere",
            Shape::Sphere { radius: 0.5 },
            Transform::IDENTITY,
            Some(("spot", 0)),
        )
        .unwrap();
        op.apply(&mut d).unwrap();
        let inf = d.mesh("spot").unwrap().stack[0].influence.clone().unwrap();
        assert_eq!(inf.volumes, vec![volume]);
        assert!(op.describe().contains(&format!("layer '{name}'")));
        op.revert(&mut d).unwrap();
        assert_eq!(d, before);
    }

    #[test]
    fn duplicating_a_layer_copies_its_tool_above_it() {
        let mut d = doc();
        let t = tool(NewTool::BSplineCurve, &place());
        let (op, _) =
            Operation::add_tool_layer(&d, "spot", "curve", t, Transform::IDENTITY).unwrap();
        op.apply(&mut d).unwrap();
        Operation::set_layer_weight(&d, "spot", 0, 0.5)
            .unwrap()
            .apply(&mut d)
            .unwrap();
        let (op, copy) = Operation::duplicate_layer(&d, "spot", 0).unwrap();
        op.apply(&mut d).unwrap();
        assert_eq!(copy, "curve-copy");
        let stack = &d.mesh("spot").unwrap().stack;
        assert_eq!(stack[1].tool, "curve-copy");
        assert_eq!(stack[1].weight, 0.5);
        assert_eq!(d.tool("curve").unwrap(), d.tool("curve-copy").unwrap());
        let (g, name) = Operation::add_group(&d, Some("spot"), "group").unwrap();
        g.apply(&mut d).unwrap();
        assert_eq!(name, "group");
        assert!(d.problems().is_empty());
    }
}
