use glam::Vec3;

use super::*;
use crate::test_tools::{self, document};

/// Applies an edit to a copy of the document.
fn apply(doc: &Document, node: &str, edit: NodeEdit) -> Document {
    let mut doc = doc.clone();
    let n = doc.node_mut(node).unwrap();
    match edit {
        NodeEdit::Tool(t) => n.kind = NodeKind::Tool(t),
        NodeEdit::Transform(t) => n.transform = t,
        NodeEdit::Volume(shape) => n.kind = NodeKind::Volume(crate::document::VolumeNode { shape }),
    }
    doc
}

fn all_nodes(doc: &Document) -> Vec<String> {
    doc.nodes.iter().map(|n| n.name.clone()).collect()
}

#[test]
fn counts_per_kind() {
    let doc = document();
    let count = |n: &str| handles(&doc, n).unwrap().len();
    // Tool handles + the origin.
    assert_eq!(count("ffsd"), 3 + 1 + 1);
    assert_eq!(count("axial"), 6 + 1);
    assert_eq!(count("curve"), 8 + 1);
    assert_eq!(count("lattice"), 3 * 2 * 4 + 1);
    assert_eq!(count("surface"), 2 * 5 * 4 + 1);
    // Two free-point constraints (point and target); the vertex-anchored one has none.
    assert_eq!(count("dogme"), 2 * 2 + 1);
    assert_eq!(count("direct"), 2 + 2 * 3 * 2 + 1);
    assert_eq!(count("sketch"), 3 + 3 + 1);
    assert_eq!(count("stroke"), 1);
    for n in ["nose", "ball", "head", "grp"] {
        let h = handles(&doc, n).unwrap();
        assert_eq!(h.len(), 1, "{n}");
        assert_eq!(h[0].id, HandleId::Origin);
        assert_eq!(h[0].position, Vec3::new(0.1, 0.2, 0.3));
    }
}

#[test]
fn origin_comes_last_and_controls_before_rest_points() {
    let doc = document();
    for n in all_nodes(&doc) {
        let h = handles(&doc, &n).unwrap();
        assert_eq!(h.last().unwrap().id, HandleId::Origin, "{n}");
        let first_rest = h.iter().position(|h| h.role == HandleRole::Rest);
        let last_control = h.iter().rposition(|h| h.role == HandleRole::Control);
        if let (Some(r), Some(c)) = (first_rest, last_control) {
            assert!(c < r, "{n}: a control handle comes after a rest handle");
        }
    }
}

#[test]
fn moving_a_handle_to_its_own_position_changes_nothing() {
    let doc = document();
    for n in all_nodes(&doc) {
        let node = doc.node(&n).unwrap();
        for h in handles(&doc, &n).unwrap() {
            let edit = moved(&doc, &n, &h.id, h.position).unwrap();
            match (edit, &node.kind) {
                (NodeEdit::Tool(t), NodeKind::Tool(old)) => assert_eq!(&t, old, "{n} {}", h.id),
                (NodeEdit::Volume(s), NodeKind::Volume(old)) => {
                    assert_eq!(s, old.shape, "{n} {}", h.id);
                }
                (NodeEdit::Transform(t), _) => {
                    assert_eq!(h.id, HandleId::Origin);
                    assert_eq!(t, node.transform, "{n}");
                }
                (e, _) => panic!("{n} {}: unexpected edit {e:?}", h.id),
            }
        }
    }
}

/// Handles that legitimately follow a moved handle: a constraint's target follows its
/// point, a moved surface point follows its rest point.
fn follower(id: HandleId) -> Option<HandleId> {
    match id {
        HandleId::Source(k) => Some(HandleId::Target(k)),
        HandleId::SurfaceRest(i, j) => Some(HandleId::SurfaceMoved(i, j)),
        _ => None,
    }
}

#[test]
fn a_moved_handle_is_read_back_where_it_was_put() {
    let doc = document();
    let delta = Vec3::new(0.05, -0.03, 0.02);
    for n in all_nodes(&doc) {
        let before = handles(&doc, &n).unwrap();
        for h in &before {
            let to = h.position + delta;
            let after = apply(&doc, &n, moved(&doc, &n, &h.id, to).unwrap());
            let now = handles(&after, &n).unwrap();
            assert_eq!(now.len(), before.len(), "{n} {}", h.id);
            for (b, a) in before.iter().zip(&now) {
                assert_eq!(a.id, b.id);
                let expected = if b.id == h.id || Some(b.id) == follower(h.id) {
                    b.position + delta
                } else {
                    b.position
                };
                assert!(
                    (a.position - expected).length() < 1e-5,
                    "{n}: moving {} put {} at {}, expected {expected}",
                    h.id,
                    a.id,
                    a.position
                );
            }
        }
    }
}

#[test]
fn origin_moves_keep_rotation_and_scale() {
    let mut doc = document();
    let n = doc.node_mut("ball").unwrap();
    n.transform.rotation = glam::Quat::from_rotation_y(0.4);
    n.transform.scale = Vec3::splat(2.0);
    let old = n.transform;
    let edit = moved(&doc, "ball", &HandleId::Origin, Vec3::new(1.0, 2.0, 3.0)).unwrap();
    assert_eq!(
        edit,
        NodeEdit::Transform(Transform {
            translation: Vec3::new(1.0, 2.0, 3.0),
            ..old
        })
    );
    assert!(HandleId::Origin.in_parent_frame());
    assert!(!HandleId::Control(0).in_parent_frame());
}

#[test]
fn unknown_handles_name_node_and_handle() {
    let doc = document();
    for (node, id) in [
        ("ffsd", HandleId::Lattice(0, 0, 0)),
        ("ffsd", HandleId::Control(3)),
        // Point 0 is basic: it has no reference point.
        ("ffsd", HandleId::Reference(0)),
        ("lattice", HandleId::Lattice(3, 0, 0)),
        // Constraint 1 is anchored at a vertex: no handle.
        ("dogme", HandleId::Source(1)),
        ("stroke", HandleId::Rest(0)),
        ("nose", HandleId::Control(0)),
        ("ball", HandleId::Target(0)),
    ] {
        let e = moved(&doc, node, &id, Vec3::ONE).unwrap_err();
        assert_eq!(
            e,
            SceneError::NoSuchHandle {
                node: node.to_owned(),
                handle: id.to_string()
            }
        );
        let msg = e.to_string();
        assert!(msg.contains(node) && msg.contains(&id.to_string()), "{msg}");
    }
    assert!(matches!(
        moved(&doc, "nobody", &HandleId::Origin, Vec3::ONE),
        Err(SceneError::NoSuchNode { .. })
    ));
}

#[test]
fn bad_positions_and_invalid_results_are_errors() {
    let doc = document();
    let e = moved(&doc, "curve", &HandleId::Deformed(1), Vec3::NAN).unwrap_err();
    assert!(matches!(e, SceneError::NotFinite { .. }), "{e}");
    // Deformed point 1 onto point 0: a zero-length segment.
    let p0 = test_tools::curve().deformed[0];
    let e = moved(&doc, "curve", &HandleId::Deformed(1), p0).unwrap_err();
    assert!(matches!(e, SceneError::Core(_)), "{e}");
    let r0 = test_tools::axial().rest[0].position;
    assert!(moved(&doc, "axial", &HandleId::Rest(1), r0).is_err());
    let e = moved(&doc, "ball", &HandleId::Origin, Vec3::INFINITY).unwrap_err();
    assert!(matches!(e, SceneError::NotFinite { .. }), "{e}");
}

#[test]
fn lattice_and_surface_positions_match_hand_derived_values() {
    let doc = document();
    let find = |node: &str, id: HandleId| {
        handles(&doc, node)
            .unwrap()
            .into_iter()
            .find(|h| h.id == id)
            .unwrap()
            .position
    };
    // Bernstein (3, 2, 4) over [-1, 1] × [-1, 2] × [-1, 1]: Greville i/2, j/1, k/3, plus
    // the offset (0, 0.3, 0) of point (1, 0, 2).
    let p = find("lattice", HandleId::Lattice(1, 0, 2));
    assert!(
        (p - Vec3::new(0.0, -0.7, -1.0 + 2.0 * 2.0 / 3.0)).length() < 1e-6,
        "{p}"
    );
    let p = find("lattice", HandleId::Lattice(2, 1, 3));
    assert!((p - Vec3::new(1.0, 2.0, 1.0)).length() < 1e-6, "{p}");
    // Cubic surface, 5 × 4 points: knots u (0,0,0,0,½,1,1,1,1), v (0,0,0,0,1,1,1,1); the
    // Greville abscissae of (2, 1) are ½ and ⅓; moved by (0, 0, 0.4).
    let p = find("surface", HandleId::SurfaceMoved(2, 1));
    assert!((p - Vec3::new(0.0, -1.0 / 3.0, 0.4)).length() < 1e-6, "{p}");
    let p = find("surface", HandleId::SurfaceRest(2, 1));
    assert!((p - Vec3::new(0.0, -1.0 / 3.0, 0.0)).length() < 1e-6, "{p}");
    // DOGME: target = point + displacement; the sphere support's radius on the point.
    let h = handles(&doc, "dogme").unwrap();
    assert_eq!(h[0].id, HandleId::Target(0));
    assert_eq!(h[0].position, Vec3::new(0.0, 0.0, 1.2));
    assert_eq!(h[1].radius, Some(0.5));
}

#[test]
fn ffsd_radius_sits_on_the_weight_centre() {
    let doc = document();
    let h = handles(&doc, "ffsd").unwrap();
    // Basic point 0: α = 2, so the radius is ε.
    assert_eq!(h[0].id, HandleId::Control(0));
    assert_eq!(h[0].radius, Some(0.3));
    // Directional point 1: the weight is centred on R; α = 1, ε = 0.5: r = ε² = 0.25.
    assert_eq!(h[1].id, HandleId::Control(1));
    assert_eq!(h[1].radius, None);
    assert_eq!(h[2].id, HandleId::Reference(1));
    assert_eq!(h[2].position, Vec3::new(1.0, 0.0, 0.5));
    assert!((h[2].radius.unwrap() - 0.25).abs() < 1e-7);
}

#[test]
fn epsilon_radius_is_where_the_weight_is_e_to_minus_half() {
    for (alpha, eps) in [(2.0_f32, 0.3_f32), (1.0, 0.5), (3.0, 1.7), (0.5, 0.9)] {
        let p = ductile_core::ffsd::ControlPoint::basic(Vec3::ZERO, 1.0, alpha, eps);
        let r = epsilon_radius(&p).unwrap();
        let w = (-r.powf(alpha) / (2.0 * eps * eps)).exp();
        assert!(
            (w - (-0.5_f32).exp()).abs() < 1e-5,
            "α {alpha}, ε {eps}: W(r) = {w}"
        );
    }
    let p = ductile_core::ffsd::ControlPoint::basic(Vec3::ZERO, 1.0, 1e-3, 2.0);
    assert_eq!(epsilon_radius(&p), None);
}

#[test]
fn an_invalid_tool_has_no_handles_but_an_error() {
    let mut doc = document();
    if let NodeKind::Tool(Tool::Ffsd(t)) = &mut doc.node_mut("ffsd").unwrap().kind {
        t.points[0].position.x = f32::NAN;
    }
    let e = handles(&doc, "ffsd").unwrap_err();
    assert!(e.to_string().contains("ffsd"), "{e}");
    assert!(moved(&doc, "ffsd", &HandleId::Control(1), Vec3::ONE).is_err());
    // The node itself can still be moved.
    assert!(matches!(
        moved(&doc, "ffsd", &HandleId::Origin, Vec3::ONE),
        Ok(NodeEdit::Transform(_))
    ));
}

#[test]
fn a_tube_volume_has_a_handle_per_point() {
    let mut doc = document();
    let shape = ductile_core::influence::Shape::Tube {
        points: vec![Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 2.0, 0.5)],
        radii: vec![0.2, 0.3, 0.2],
    };
    doc.nodes.push(crate::document::Node {
        name: "tube".into(),
        parent: None,
        transform: Transform::IDENTITY,
        kind: NodeKind::Volume(crate::document::VolumeNode { shape }),
    });
    let h = handles(&doc, "tube").unwrap();
    assert_eq!(h.len(), 4, "three points and the origin");
    let edit = moved(&doc, "tube", &HandleId::Spine(1), Vec3::new(0.5, 1.0, 0.0)).unwrap();
    let NodeEdit::Volume(ductile_core::influence::Shape::Tube { points, .. }) = edit else {
        panic!("{edit:?}")
    };
    assert_eq!(points[1], Vec3::new(0.5, 1.0, 0.0));
    assert!(moved(&doc, "tube", &HandleId::Spine(7), Vec3::ZERO).is_err());
}
