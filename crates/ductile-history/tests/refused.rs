//! Operations that would make the document invalid are refused with the documented error,
//! and the document is left exactly as it was.

mod common;

use common::{node, point, ron_text, scene};
use ductile_core::error::CoreError;
use ductile_core::ffsd::{ControlPoint, FfsdTool};
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_history::prelude::*;
use ductile_scene::prelude::*;
use glam::Vec3;

/// Applies `op` to the test scene, asserts that it fails and that the scene is unchanged
/// (also in its RON text), and returns the error.
fn refused(op: Operation) -> HistoryError {
    let before = scene();
    let mut doc = before.clone();
    let err = op
        .apply(&mut doc)
        .expect_err("the operation must be refused");
    assert_eq!(doc, before, "a refused operation changed the document");
    assert_eq!(ron_text(&doc), ron_text(&before));
    // The same through the history: nothing recorded.
    let mut history = History::new(before.clone());
    assert!(history.push(&mut doc, op, "x", 0, None).is_err());
    assert_eq!(history.len(), 0);
    assert_eq!(doc, before);
    err
}

fn ffsd(points: Vec<ControlPoint>) -> Tool {
    Tool::Ffsd(FfsdTool::new(points))
}

#[test]
fn unknown_node() {
    let doc = scene();
    let op = Operation::SetTransform {
        node: "nobody".into(),
        old: Transform::IDENTITY,
        new: Transform::from_translation(Vec3::X),
    };
    assert!(Operation::set_transform(&doc, "nobody", Transform::IDENTITY).is_err());
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::NoSuchNode { name }) if name == "nobody"
    ));
}

#[test]
fn nan_transform() {
    let doc = scene();
    let op = Operation::set_transform(
        &doc,
        "pinch",
        Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
    )
    .unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::NotFinite { what, .. }) if what.contains("pinch")
    ));
}

#[test]
fn zero_scale_transform() {
    let doc = scene();
    let t = Transform {
        scale: Vec3::new(1.0, 0.0, 1.0),
        ..Transform::IDENTITY
    };
    let op = Operation::set_transform(&doc, "grid", t).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::DegenerateTransform { what, .. } if what.contains("grid")
    ));
}

#[test]
fn epsilon_not_positive() {
    let doc = scene();
    let mut p = point(0.0, 0.0, 0.5);
    p.epsilon = 0.0;
    let op = Operation::set_tool(&doc, "pinch", ffsd(vec![p])).unwrap();
    match refused(op) {
        HistoryError::Scene(SceneError::Core(CoreError::OutOfRange { what, .. })) => {
            assert!(what.contains("epsilon"), "{what}");
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn nan_macro_value_and_gamma() {
    let doc = scene();
    let op = Operation::set_macro_value(&doc, "mac", f32::NAN).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::NotFinite { .. })
    ));
    let op = Operation::set_tool(&doc, "pinch", ffsd(vec![point(0.0, 0.0, f32::NAN)])).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::Core(CoreError::NotFinite { .. }))
    ));
}

#[test]
fn zero_volume_radius() {
    let doc = scene();
    let op = Operation::set_volume(&doc, "vol", Shape::Sphere { radius: 0.0 }).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::Core(CoreError::OutOfRange { .. }))
    ));
}

#[test]
fn cycles() {
    let doc = scene();
    // "pinch" is a child of "grid": making "grid" a child of "pinch" closes a loop.
    let op = Operation::reparent(&doc, "grid", Some("pinch")).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::Cycle { node }) if node == "grid"
    ));
    let op = Operation::reparent(&doc, "grp", Some("grp")).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::Cycle { .. })
    ));
    let op = Operation::reparent(&doc, "grp", Some("ghost")).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::UnknownParent { .. })
    ));
}

#[test]
fn names() {
    let doc = scene();
    let dup = Operation::add_node(&doc, node("pinch", None, NodeKind::Group));
    assert!(matches!(
        refused(dup),
        HistoryError::Scene(SceneError::DuplicateName { name }) if name == "pinch"
    ));
    let empty = Operation::add_node(&doc, node("", None, NodeKind::Group));
    assert!(matches!(
        refused(empty),
        HistoryError::Scene(SceneError::EmptyName { .. })
    ));
    assert!(matches!(
        refused(Operation::rename("pinch", "vol")),
        HistoryError::Scene(SceneError::DuplicateName { .. })
    ));
    assert!(matches!(
        refused(Operation::rename("pinch", "")),
        HistoryError::Scene(SceneError::EmptyName { .. })
    ));
}

#[test]
fn removing_what_is_referenced() {
    let doc = scene();
    // "pinch" is the tool of layer 0.
    let op = Operation::remove_node(&doc, "pinch").unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::StillReferenced { what, by } if what.contains("pinch") && by.contains("layer 0")
    ));
    // "grid" has children.
    let op = Operation::remove_node(&doc, "grid").unwrap();
    assert!(matches!(refused(op), HistoryError::StillReferenced { .. }));
    // Area "left" is used by layer 1, macro "bump" by "mac".
    let op = Operation::define_area(&doc, "grid", "left", None).unwrap();
    assert!(matches!(refused(op), HistoryError::StillReferenced { .. }));
    let op = Operation::set_macro_definition(&doc, "bump", None);
    assert!(matches!(refused(op), HistoryError::StillReferenced { .. }));
}

#[test]
fn bad_layers() {
    let doc = scene();
    let op = Operation::set_layer_weight(&doc, "grid", 0, 1.5).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::Core(CoreError::OutOfRange { .. }))
    ));
    let op = Operation::add_layer("grid", 0, LayerSpec::new("ghost"));
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::UnknownTool { tool, .. }) if tool == "ghost"
    ));
    let op = Operation::add_layer("grid", 0, LayerSpec::new("vol"));
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::WrongKind { .. })
    ));
    let op = Operation::add_layer("pinch", 0, LayerSpec::new("pinch"));
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::WrongKind {
            expected: "mesh",
            ..
        })
    ));
    let op = Operation::add_layer("grid", 3, LayerSpec::new("pinch"));
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::IndexOutOfRange {
            index: 3,
            len: 2,
            ..
        })
    ));
    let inf = InfluenceSpec {
        area: Some("nowhere".into()),
        ..InfluenceSpec::default()
    };
    let op = Operation::set_layer_influence(&doc, "grid", 0, Some(inf)).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::UnknownArea { .. })
    ));
    let inf = InfluenceSpec {
        volumes: vec!["pinch".into()],
        ..InfluenceSpec::default()
    };
    let op = Operation::set_layer_influence(&doc, "grid", 0, Some(inf)).unwrap();
    assert!(matches!(
        refused(op),
        HistoryError::Scene(SceneError::WrongKind {
            expected: "volume",
            ..
        })
    ));
    assert!(matches!(
        refused(Operation::move_layer("grid", 0, 2)),
        HistoryError::Scene(SceneError::IndexOutOfRange { .. })
    ));
}

#[test]
fn stale_old_value() {
    let op = Operation::SetMacroValue {
        node: "mac".into(),
        old: 0.9,
        new: 0.1,
    };
    assert!(matches!(
        refused(op),
        HistoryError::Stale { what, .. } if what.contains("mac")
    ));
}

#[test]
fn group_is_all_or_nothing() {
    let doc = scene();
    let ops = vec![
        Operation::set_macro_value(&doc, "mac", 0.8).unwrap(),
        Operation::set_transform(&doc, "vol", Transform::from_translation(Vec3::Y)).unwrap(),
        Operation::reparent(&doc, "grid", Some("pinch")).unwrap(),
    ];
    let err = refused(Operation::Group {
        label: "three".into(),
        ops,
    });
    match err {
        HistoryError::InGroup {
            label,
            index,
            source,
        } => {
            assert_eq!((label.as_str(), index), ("three", 2));
            assert!(matches!(
                *source,
                HistoryError::Scene(SceneError::Cycle { .. })
            ));
        }
        other => panic!("unexpected {other:?}"),
    }
}
