//! A small scene on a small grid mesh, shared by the integration tests.

#![allow(dead_code)]

use std::collections::BTreeMap;

use ductile_core::ffsd::{ControlPoint, FfsdMacro, FfsdTool};
use ductile_core::influence::Shape;
use ductile_core::mesh::{Mesh, RestMesh};
use ductile_core::tool::Tool;
use ductile_scene::prelude::*;
use glam::Vec3;

/// An `n × n` grid of quads in the XY plane, spanning [-1, 1]².
pub fn grid(n: usize) -> RestMesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(
                -1.0 + 2.0 * i as f32 / n as f32,
                -1.0 + 2.0 * j as f32 / n as f32,
                0.0,
            ));
        }
    }
    let mut indices = Vec::new();
    let w = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * w + i;
            indices.extend([a, a + 1, a + w, a + 1, a + w + 1, a + w]);
        }
    }
    RestMesh::new(
        Mesh {
            positions,
            normals: None,
            uvs: None,
            indices,
        },
        "grid",
    )
    .unwrap()
}

pub fn point(x: f32, y: f32, gamma: f32) -> ControlPoint {
    ControlPoint::basic(Vec3::new(x, y, 0.5), gamma, 2.0, 0.5)
}

pub fn node(name: &str, parent: Option<&str>, kind: NodeKind) -> Node {
    Node {
        name: name.to_owned(),
        parent: parent.map(str::to_owned),
        transform: Transform::IDENTITY,
        kind,
    }
}

/// Mesh "grid" with a free FFSD tool "pinch", a macro tool "mac" (macro "bump") limited to
/// area "left", a volume "vol", and a group "grp".
pub fn scene() -> Document {
    let mut areas = BTreeMap::new();
    areas.insert(
        "left".to_owned(),
        Area::Region(vec![RegionShape {
            shape: Shape::Sphere { radius: 0.9 },
            transform: Transform::from_translation(Vec3::new(-0.5, 0.0, 0.0)),
        }]),
    );
    let mut mac_layer = LayerSpec::new("mac");
    mac_layer.weight = 0.5;
    mac_layer.influence = Some(InfluenceSpec {
        area: Some("left".to_owned()),
        ..InfluenceSpec::default()
    });
    let mut macros = BTreeMap::new();
    macros.insert(
        "bump".to_owned(),
        FfsdMacro {
            label: "Bump".to_owned(),
            group: "Test".to_owned(),
            area: Some("left".to_owned()),
            points: vec![point(-0.5, 0.0, 0.4)],
            height: None,
            range: (-1.0, 1.0),
        },
    );
    Document {
        nodes: vec![
            node(
                "grid",
                None,
                NodeKind::Mesh(MeshNode {
                    source: "grid.obj".to_owned(),
                    stack: vec![LayerSpec::new("pinch"), mac_layer],
                    areas,
                }),
            ),
            node(
                "pinch",
                Some("grid"),
                NodeKind::Tool(Tool::Ffsd(FfsdTool::new(vec![point(0.3, 0.2, -0.3)]))),
            ),
            node(
                "mac",
                Some("grid"),
                NodeKind::Macro(MacroUse {
                    name: "bump".to_owned(),
                    value: 0.3,
                }),
            ),
            node(
                "vol",
                Some("grid"),
                NodeKind::Volume(VolumeNode {
                    shape: Shape::Sphere { radius: 0.8 },
                }),
            ),
            node("grp", None, NodeKind::Group),
        ],
        macros,
        ..Document::default()
    }
}

/// The RON text of a value: distinguishes what `==` does not (−0.0 from 0.0).
pub fn ron_text<T: serde::Serialize>(v: &T) -> String {
    ron::to_string(v).unwrap()
}

/// Evaluated positions and normals of every mesh of `doc` on `rest`, as bits (or the error
/// text), for bit-for-bit comparison.
pub fn evaluated_bits(doc: &Document, rest: &RestMesh) -> Vec<Result<Vec<[u32; 6]>, String>> {
    doc.mesh_names()
        .iter()
        .map(|m| {
            doc.evaluate(m, rest)
                .map(|d| {
                    d.positions
                        .iter()
                        .zip(&d.normals)
                        .map(|(p, n)| {
                            [
                                p.x.to_bits(),
                                p.y.to_bits(),
                                p.z.to_bits(),
                                n.x.to_bits(),
                                n.y.to_bits(),
                                n.z.to_bits(),
                            ]
                        })
                        .collect()
                })
                .map_err(|e| e.to_string())
        })
        .collect()
}
