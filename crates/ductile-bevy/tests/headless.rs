//! Headless `App::update()` tests of the plugin with `MinimalPlugins`: the ECS mirrors the
//! document, an edit re-evaluates exactly the meshes it affects (once), undo restores the
//! mesh bit for bit, a drag is one undo step, and background evaluation gives the inline
//! result.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap (house rules).

use bevy::mesh::VertexAttributeValues;
use bevy::prelude::*;
use ductile_bevy::handles::handle_operation;
use ductile_bevy::prelude::*;
use ductile_core::ffsd::{ControlPoint, FfsdTool};
use ductile_core::mesh::RestMesh;
use ductile_core::primitives::grid;
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, LayerSpec, MeshNode, Node, NodeKind};
use ductile_scene::handles::HandleId;
use ductile_scene::transform::Transform as DocTransform;

fn sheet() -> RestMesh {
    let mesh = grid(21, 21, false, |r, c| {
        Vec3::new(c as f32 / 20.0 - 0.5, r as f32 / 20.0 - 0.5, 0.0)
    });
    RestMesh::new(mesh, "sheet").unwrap()
}

fn pull(z: f32) -> Tool {
    Tool::Ffsd(FfsdTool {
        points: vec![ControlPoint::basic(Vec3::new(0.0, 0.0, z), 0.5, 1.0, 0.4)],
        height: None,
        gain: 1.0,
    })
}

fn node(name: &str, kind: NodeKind) -> Node {
    Node {
        name: name.to_owned(),
        parent: None,
        transform: DocTransform::IDENTITY,
        kind,
    }
}

fn mesh_node(name: &str, tool: &str) -> Node {
    node(
        name,
        NodeKind::Mesh(MeshNode {
            source: "sheet".to_owned(),
            stack: vec![LayerSpec::new(tool)],
            areas: Default::default(),
        }),
    )
}

/// Two meshes on the same rest sheet, each deformed by its own tool.
fn document() -> Document {
    Document {
        nodes: vec![
            mesh_node("a", "pull-a"),
            mesh_node("b", "pull-b"),
            node("pull-a", NodeKind::Tool(pull(0.3))),
            node("pull-b", NodeKind::Tool(pull(-0.3))),
        ],
        macros: Default::default(),
        ..Document::default()
    }
}

fn app(doc: Document, background_threshold: usize) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default()))
        .init_asset::<Mesh>()
        .add_plugins(DuctilePlugin);
    app.insert_resource(SceneDocument::new(doc));
    app.insert_resource(EvaluationSettings {
        background_threshold,
    });
    app.world_mut()
        .resource_mut::<RestMeshes>()
        .insert("sheet", sheet());
    app.update();
    app.update();
    app
}

fn entity(app: &App, name: &str) -> Entity {
    app.world().resource::<NodeEntities>().get(name).unwrap()
}

fn positions(app: &mut App, name: &str) -> Vec<[f32; 3]> {
    let e = entity(app, name);
    let handle = app
        .world()
        .get::<MeshEvaluation>(e)
        .expect("mesh evaluation attached")
        .mesh
        .clone();
    let meshes = app.world().resource::<Assets<Mesh>>();
    match meshes
        .get(&handle)
        .unwrap()
        .attribute(Mesh::ATTRIBUTE_POSITION)
    {
        Some(VertexAttributeValues::Float32x3(v)) => v.clone(),
        other => panic!("unexpected positions {other:?}"),
    }
}

fn revision_evaluated(app: &App, name: &str) -> Option<u64> {
    app.world()
        .get::<MeshEvaluation>(entity(app, name))
        .and_then(|m| m.last.as_ref().map(|r| r.revision))
}

fn send(app: &mut App, command: DocumentCommand) {
    app.world_mut().write_message(command);
    app.update();
}

#[test]
fn adding_a_tool_to_the_document_spawns_its_entity() {
    let mut app = app(document(), usize::MAX);
    assert_eq!(app.world().resource::<NodeEntities>().len(), 4);
    let doc = app.world().resource::<SceneDocument>().document().clone();
    let op = Operation::add_node(&doc, node("extra", NodeKind::Tool(pull(0.1))));
    send(&mut app, DocumentCommand::apply(op));
    let e = entity(&app, "extra");
    let scene_node = app.world().get::<SceneNode>(e).unwrap();
    assert_eq!(scene_node.name, "extra");
    assert!(matches!(scene_node.node.kind, NodeKind::Tool(_)));
    // Undo removes it again.
    send(&mut app, DocumentCommand::Undo);
    assert!(
        app.world()
            .resource::<NodeEntities>()
            .get("extra")
            .is_none()
    );
    assert!(app.world().get_entity(e).is_err(), "entity despawned");
}

#[test]
fn a_parameter_change_re_evaluates_exactly_the_affected_mesh_once() {
    let mut app = app(document(), usize::MAX);
    let before_a = positions(&mut app, "a");
    let before_b = positions(&mut app, "b");
    let evaluated_b = revision_evaluated(&app, "b");
    let count = app.world().resource::<EvaluationStats>().evaluations;

    let doc = app.world().resource::<SceneDocument>().document().clone();
    let op = Operation::set_tool(&doc, "pull-a", pull(0.45)).unwrap();
    send(&mut app, DocumentCommand::apply(op));
    for _ in 0..3 {
        app.update(); // nothing changes any more: no further evaluation
    }

    let stats = app.world().resource::<EvaluationStats>();
    assert_eq!(stats.evaluations, count + 1, "exactly one evaluation");
    assert_eq!(stats.last.as_ref().unwrap().0, "a");
    assert_ne!(positions(&mut app, "a"), before_a, "mesh a deformed anew");
    assert_eq!(positions(&mut app, "b"), before_b);
    // Mesh b looked at the new revision but did not re-evaluate its stack.
    let b = app
        .world()
        .get::<MeshEvaluation>(entity(&app, "b"))
        .unwrap();
    assert_eq!(b.last.as_ref().map(|r| r.revision), evaluated_b);
}

#[test]
fn undo_restores_the_mesh_bit_for_bit() {
    let mut app = app(document(), usize::MAX);
    let before = positions(&mut app, "a");
    let doc = app.world().resource::<SceneDocument>().document().clone();
    let op = Operation::set_tool(&doc, "pull-a", pull(0.7)).unwrap();
    send(&mut app, DocumentCommand::apply(op));
    assert_ne!(positions(&mut app, "a"), before);
    send(&mut app, DocumentCommand::Undo);
    assert_eq!(positions(&mut app, "a"), before, "bit for bit");
    send(&mut app, DocumentCommand::Redo);
    assert_ne!(positions(&mut app, "a"), before);
}

#[test]
fn a_drag_is_one_undo_step() {
    let mut app = app(document(), usize::MAX);
    let before = positions(&mut app, "a");
    let gesture = app
        .world_mut()
        .resource_mut::<SceneDocument>()
        .new_gesture();
    // Three frames of one drag of the tool's first control point.
    for z in [0.35, 0.4, 0.5] {
        let doc = app.world().resource::<SceneDocument>().document().clone();
        let op = handle_operation(
            &doc,
            "pull-a",
            &HandleId::Control(0),
            Vec3::new(0.0, 0.0, z),
        )
        .unwrap();
        send(
            &mut app,
            DocumentCommand::Apply {
                op: Box::new(op),
                label: "drag".to_owned(),
                gesture: Some(gesture),
            },
        );
    }
    let doc = app.world().resource::<SceneDocument>();
    assert_eq!(doc.history().len(), 1, "one step for the whole drag");
    assert_ne!(positions(&mut app, "a"), before);
    send(&mut app, DocumentCommand::Undo);
    assert_eq!(positions(&mut app, "a"), before);
    assert_eq!(
        app.world().resource::<SceneDocument>().document(),
        &document()
    );
}

#[test]
fn background_evaluation_gives_the_inline_result() {
    let mut inline = app(document(), usize::MAX);
    let mut background = app(document(), 0);
    for app in [&mut inline, &mut background] {
        let doc = app.world().resource::<SceneDocument>().document().clone();
        let op = Operation::set_tool(&doc, "pull-b", pull(-0.6)).unwrap();
        send(app, DocumentCommand::apply(op));
    }
    // Let the background task finish.
    for _ in 0..200 {
        let running = background
            .world()
            .get::<MeshEvaluation>(entity(&background, "b"))
            .unwrap()
            .is_running();
        if !running {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
        background.update();
    }
    background.update();
    assert_eq!(positions(&mut background, "b"), positions(&mut inline, "b"));
    assert_eq!(positions(&mut background, "a"), positions(&mut inline, "a"));
    let report = background
        .world()
        .get::<MeshEvaluation>(entity(&background, "b"))
        .unwrap()
        .last
        .clone()
        .unwrap();
    assert!(report.background);
}

#[test]
fn a_refused_edit_leaves_the_document_and_reports_why() {
    let mut app = app(document(), usize::MAX);
    let op = Operation::SetMacroValue {
        node: "no-such-node".to_owned(),
        old: 0.0,
        new: 1.0,
    };
    send(&mut app, DocumentCommand::apply(op));
    let doc = app.world().resource::<SceneDocument>();
    assert_eq!(doc.document(), &document());
    assert!(doc.history().is_empty());
    let status = app.world().resource::<EditStatus>();
    assert!(
        status
            .last_error
            .as_deref()
            .is_some_and(|e| e.contains("no-such-node")),
        "{status:?}"
    );
}
