//! One valid tool of every kind, and a document holding them, for the tests of handles and
//! gizmos.

use ductile_core::axial::{AxialTool, AxisPoint, AxisShape};
use ductile_core::curve::{CurveBasis, CurveTool};
use ductile_core::direct_ffd::{DirectConstraint, DirectFfdTool};
use ductile_core::dogme::{Anchor, Constraint, DogmeTool, Support};
use ductile_core::ffsd::{ControlPoint, FfsdMacro, FfsdTool, PointMode};
use ductile_core::influence::Shape;
use ductile_core::lattice::{LatticeFrame, LatticeTool};
use ductile_core::sketch::camera::{Camera, Projection};
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool, Stroke};
use ductile_core::surface::{ShapeSurfaceTool, SurfaceEdit, SurfaceFrame};
use ductile_core::tool::Tool;
use glam::{Quat, Vec2, Vec3};

use crate::document::{Document, MacroUse, MeshNode, Node, NodeKind, VolumeNode};
use crate::transform::Transform;

pub(crate) fn ffsd() -> FfsdTool {
    FfsdTool::new(vec![
        ControlPoint::basic(Vec3::new(0.0, 0.0, 1.0), 0.5, 2.0, 0.3),
        ControlPoint {
            position: Vec3::new(1.0, 0.0, 1.0),
            mode: PointMode::Directional {
                reference: Vec3::new(1.0, 0.0, 0.5),
            },
            gamma: 0.2,
            alpha: 1.0,
            epsilon: 0.5,
        },
        ControlPoint {
            mode: PointMode::Virtual,
            ..ControlPoint::basic(Vec3::new(-1.0, 0.0, 1.0), -0.3, 2.0, 0.2)
        },
    ])
}

pub(crate) fn axial() -> AxialTool {
    let mut t = AxialTool::new(
        vec![
            AxisPoint::at(Vec3::ZERO),
            AxisPoint::at(Vec3::Y),
            AxisPoint::at(Vec3::new(0.0, 2.0, 0.0)),
        ],
        0.4,
    );
    t.shape = AxisShape::BSpline { degree: 2 };
    t.deformed[2].position = Vec3::new(0.5, 1.8, 0.0);
    t.deformed[2].twist = 0.5;
    t.deformed[1].scale = 1.5;
    t
}

pub(crate) fn curve() -> CurveTool {
    let mut t = CurveTool::new(
        CurveBasis::Bezier,
        vec![
            Vec3::ZERO,
            Vec3::new(1.0, 0.5, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 0.5, 0.0),
        ],
    );
    t.deformed[3] = Vec3::new(3.0, 1.5, 0.5);
    t
}

pub(crate) fn lattice() -> LatticeTool {
    let mut t = LatticeTool::bernstein(
        LatticeFrame::from_box(Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 1.0)),
        (3, 2, 4),
    );
    t.set_offset((1, 0, 2), Vec3::new(0.0, 0.3, 0.0));
    t
}

pub(crate) fn surface() -> ShapeSurfaceTool {
    let mut t = ShapeSurfaceTool::planar(
        SurfaceFrame {
            origin: Vec3::new(-1.0, -1.0, 0.0),
            u_edge: Vec3::new(2.0, 0.0, 0.0),
            v_edge: Vec3::new(0.0, 2.0, 0.0),
        },
        (5, 4),
    );
    t.moves.push(SurfaceEdit {
        at: (2, 1),
        offset: Vec3::new(0.0, 0.0, 0.4),
    });
    t
}

pub(crate) fn dogme() -> DogmeTool {
    DogmeTool {
        constraints: vec![
            Constraint {
                at: Anchor::Point(Vec3::new(0.0, 0.0, 1.0)),
                displacement: Vec3::new(0.0, 0.0, 0.2),
                support: Support::Sphere { radius: 0.5 },
            },
            Constraint {
                at: Anchor::Vertex(3),
                displacement: Vec3::X,
                support: Support::Sphere { radius: 0.5 },
            },
            Constraint {
                at: Anchor::Point(Vec3::new(1.0, 0.0, 0.0)),
                displacement: Vec3::new(0.1, 0.0, 0.0),
                support: Support::Box {
                    half_extents: Vec3::new(0.2, 0.3, 0.4),
                    rotation: Quat::from_rotation_z(0.3),
                },
            },
        ],
        degree: 3,
    }
}

pub(crate) fn direct_ffd() -> DirectFfdTool {
    DirectFfdTool {
        lattice: LatticeTool::bernstein(
            LatticeFrame::from_box(Vec3::splat(-1.0), Vec3::ONE),
            (2, 3, 2),
        ),
        constraints: vec![
            DirectConstraint {
                at: Anchor::Point(Vec3::new(0.2, 0.1, 0.0)),
                displacement: Vec3::new(0.0, 0.3, 0.0),
            },
            DirectConstraint {
                at: Anchor::Vertex(7),
                displacement: Vec3::Z,
            },
        ],
    }
}

pub(crate) fn camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: Projection::Perspective { fov_y: 0.8 },
        near: 0.1,
        far: 100.0,
        viewport: Vec2::new(200.0, 100.0),
    }
}

pub(crate) fn sketch() -> SketchTool {
    SketchTool {
        partition: None,
        reference: Curve::Points(vec![Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 2.0, 0.0)]),
        normal: Some(Vec3::Z),
        mode: SketchMode::Bend {
            target: Curve::Points(vec![Vec3::ZERO, Vec3::Y, Vec3::new(0.5, 1.8, 0.0)]),
            turning: None,
        },
        scale: None,
        smooth: true,
        refine: None,
    }
}

pub(crate) fn sketch_stroke() -> SketchTool {
    SketchTool {
        mode: SketchMode::Twist {
            angle: 1.0,
            speed: None,
        },
        reference: Curve::Stroke(Stroke {
            pixels: vec![
                Vec2::new(100.0, 80.0),
                Vec2::new(100.0, 50.0),
                Vec2::new(110.0, 20.0),
            ],
            camera: camera(),
        }),
        ..sketch()
    }
}

/// Every tool kind, by a node name.
pub(crate) fn every_tool() -> Vec<(&'static str, Tool)> {
    vec![
        ("ffsd", Tool::Ffsd(ffsd())),
        ("axial", Tool::Axial(axial())),
        ("curve", Tool::Curve(curve())),
        ("lattice", Tool::Lattice(lattice())),
        ("surface", Tool::ShapeSurface(surface())),
        ("dogme", Tool::Dogme(dogme())),
        ("direct", Tool::DirectFfd(direct_ffd())),
        ("sketch", Tool::Sketch(Box::new(sketch()))),
        ("stroke", Tool::Sketch(Box::new(sketch_stroke()))),
    ]
}

/// A document with a mesh "head", every tool under it, a macro node "nose", a sphere
/// volume "ball" and a group "grp".
pub(crate) fn document() -> Document {
    let node = |name: &str, parent: Option<&str>, kind| Node {
        name: name.to_owned(),
        parent: parent.map(str::to_owned),
        transform: Transform::from_translation(Vec3::new(0.1, 0.2, 0.3)),
        kind,
    };
    let mut doc = Document::default();
    doc.nodes.push(node(
        "head",
        None,
        NodeKind::Mesh(MeshNode {
            source: "head.glb".into(),
            stack: Vec::new(),
            areas: Default::default(),
        }),
    ));
    for (name, tool) in every_tool() {
        doc.nodes
            .push(node(name, Some("head"), NodeKind::Tool(tool)));
    }
    doc.nodes.push(node(
        "nose",
        Some("head"),
        NodeKind::Macro(MacroUse {
            name: "nose-longer".into(),
            value: 0.6,
        }),
    ));
    doc.nodes.push(node(
        "ball",
        Some("head"),
        NodeKind::Volume(VolumeNode {
            shape: Shape::Sphere { radius: 0.7 },
        }),
    ));
    doc.nodes.push(node("grp", None, NodeKind::Group));
    doc.macros.insert(
        "nose-longer".into(),
        FfsdMacro {
            label: "Longer nose".into(),
            group: "Nose".into(),
            area: None,
            points: ffsd().points,
            height: None,
            range: (-1.0, 1.0),
        },
    );
    doc
}
