//! Document behaviour: references by name, validation, resolution into mesh space.

use ductile_core::prelude::*;
use ductile_scene::prelude::*;
use glam::Vec3;

fn quad() -> RestMesh {
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
        normals: None,
        uvs: None,
        indices: vec![0, 1, 2, 1, 3, 2],
    };
    RestMesh::new(mesh, "quad").unwrap()
}

fn doc() -> Document {
    let tool = Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
        Vec3::new(0.0, 0.0, 1.0),
        0.5,
        2.0,
        1.0,
    )]));
    Document {
        nodes: vec![
            Node {
                name: "mesh".into(),
                parent: None,
                transform: Transform::default(),
                kind: NodeKind::Mesh(MeshNode {
                    source: "quad.obj".into(),
                    stack: vec![LayerSpec {
                        tool: "push".into(),
                        influence: Some(InfluenceSpec {
                            volumes: vec!["ball".into()],
                            area: Some("left".into()),
                            ..InfluenceSpec::default()
                        }),
                        weight: 1.0,
                        enabled: true,
                        solo: false,
                    }],
                    areas: [("left".to_string(), Area::Vertices(vec![0, 2]))].into(),
                }),
            },
            Node {
                name: "push".into(),
                parent: Some("mesh".into()),
                transform: Transform::from_translation(Vec3::new(0.0, 0.0, 1.0)),
                kind: NodeKind::Tool(tool),
            },
            Node {
                name: "ball".into(),
                parent: Some("mesh".into()),
                transform: Transform::default(),
                kind: NodeKind::Volume(VolumeNode {
                    shape: Shape::Sphere { radius: 10.0 },
                }),
            },
        ],
        macros: Default::default(),
        ..Document::default()
    }
}

#[test]
fn a_valid_document_has_no_problems() {
    assert_eq!(doc().problems(), vec![]);
}

#[test]
fn rename_updates_every_reference() {
    let mut d = doc();
    d.rename("mesh", "head").unwrap();
    d.rename("push", "nose").unwrap();
    d.rename("ball", "zone").unwrap();
    assert_eq!(d.problems(), vec![]);
    assert_eq!(d.node("nose").unwrap().parent.as_deref(), Some("head"));
    let layer = &d.mesh("head").unwrap().stack[0];
    assert_eq!(layer.tool, "nose");
    assert_eq!(
        layer.influence.as_ref().unwrap().volumes,
        vec!["zone".to_string()]
    );
    assert!(matches!(
        d.rename("nose", "zone"),
        Err(SceneError::DuplicateName { .. })
    ));
}

#[test]
fn problems_lists_every_problem_at_once() {
    let mut d = doc();
    d.mesh_mut("mesh")
        .unwrap()
        .stack
        .push(LayerSpec::new("missing"));
    d.node_mut("ball").unwrap().parent = Some("push".into());
    d.node_mut("push").unwrap().parent = Some("ball".into());
    if let NodeKind::Tool(Tool::Ffsd(t)) = &mut d.node_mut("push").unwrap().kind {
        t.points[0].epsilon = 0.0;
    }
    let problems: Vec<String> = d.problems().iter().map(ToString::to_string).collect();
    assert!(
        problems
            .iter()
            .any(|p| p.contains("tool 'missing' does not exist")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.contains("own ancestor")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.contains("epsilon")),
        "{problems:?}"
    );
}

#[test]
#[allow(irrefutable_let_patterns)] // Refutable once more tool kinds exist.
fn resolve_maps_tools_into_mesh_space_and_areas_to_welded_vertices() {
    let d = doc();
    let rest = quad();
    let stack = d.resolve_stack("mesh", &rest).unwrap();
    let Tool::Ffsd(t) = &stack.layers[0].tool else {
        panic!("not ffsd")
    };
    // The tool node sits at z = 1 under the mesh, so its point (0, 0, 1) is at z = 2.
    assert_eq!(t.points[0].position, Vec3::new(0.0, 0.0, 2.0));
    assert_eq!(
        stack.layers[0].influence.as_ref().unwrap().area,
        Some(vec![0, 2])
    );
    let out = d.evaluate("mesh", &rest).unwrap();
    assert_eq!(out.positions[1], Vec3::X, "vertex 1 is outside the area");
    assert_ne!(out.positions[0], Vec3::ZERO, "vertex 0 is in the area");
}

#[test]
fn region_areas_select_vertices_inside_their_shapes() {
    let mut d = doc();
    let region = Area::Region(vec![RegionShape {
        shape: Shape::Box {
            half_extents: Vec3::new(0.5, 2.0, 1.0),
        },
        transform: Transform::default(),
    }]);
    d.mesh_mut("mesh")
        .unwrap()
        .areas
        .insert("x0".into(), region);
    assert_eq!(d.area_vertices("mesh", "x0", &quad()).unwrap(), vec![0, 2]);
}

#[test]
fn a_macro_area_missing_on_the_mesh_that_uses_it_is_a_warning() {
    let macro_def = |area: &str| ductile_core::ffsd::FfsdMacro {
        label: "Nose".into(),
        group: String::new(),
        area: Some(area.into()),
        points: vec![ControlPoint::basic(Vec3::ZERO, 0.1, 2.0, 0.1)],
        height: None,
        range: (-1.0, 1.0),
    };
    // Not used by any macro tool yet: the area must exist on some mesh.
    let mut d = doc();
    d.macros.insert("nose".into(), macro_def("left"));
    assert!(d.warnings().is_empty(), "{:?}", d.warnings());
    d.macros.insert("nose".into(), macro_def("tip"));
    // A warning, not a problem: the scene evaluates (layers name their own areas), but a
    // new layer of the macro would be refused.
    assert!(d.problems().is_empty(), "{:?}", d.problems());
    assert_eq!(
        d.warnings(),
        vec!["macro 'nose': its area 'tip' is not defined on any mesh".to_owned()]
    );
    // Used by a macro tool on the mesh's stack: the area must be that mesh's.
    d.nodes.push(Node {
        name: "nose-length".into(),
        parent: Some("mesh".into()),
        transform: Transform::default(),
        kind: NodeKind::Macro(MacroUse {
            name: "nose".into(),
            value: 0.5,
        }),
    });
    let NodeKind::Mesh(m) = &mut d.nodes[0].kind else {
        panic!()
    };
    m.stack.push(LayerSpec::new("nose-length"));
    assert_eq!(
        d.warnings(),
        vec!["macro 'nose': its area 'tip' is not defined on mesh 'mesh'".to_owned()]
    );
}

#[test]
fn vertex_index_areas_in_stack_names_what_only_the_same_mesh_can_use() {
    let mut d = doc();
    assert_eq!(d.vertex_index_areas_in_stack("mesh").unwrap(), ["left"]);
    // A region area carries over to any mesh; an area no layer reads is not named.
    let NodeKind::Mesh(m) = &mut d.node_mut("mesh").unwrap().kind else {
        unreachable!()
    };
    m.areas.insert(
        "left".into(),
        Area::Region(vec![RegionShape {
            shape: Shape::Sphere { radius: 1.0 },
            transform: Transform::default(),
        }]),
    );
    m.areas.insert("unused".into(), Area::Vertices(vec![1]));
    assert!(d.vertex_index_areas_in_stack("mesh").unwrap().is_empty());
    assert!(d.vertex_index_areas_in_stack("push").is_err());
}
