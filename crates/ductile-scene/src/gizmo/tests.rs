use ductile_core::curve::CurveEvaluator;
use ductile_core::influence::{Falloff, Shape};
use ductile_core::tool::Tool;
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

use super::*;
use crate::document::{InfluenceSpec, LayerSpec};
use crate::test_tools::{self, document};

fn lines(g: &Gizmo, role: Role) -> Vec<&Line> {
    g.lines.iter().filter(|l| l.role == role).collect()
}

fn circles(g: &Gizmo, role: Role) -> Vec<&Circle> {
    g.circles.iter().filter(|c| c.role == role).collect()
}

fn points(g: &Gizmo, role: Role) -> Vec<Vec3> {
    g.points
        .iter()
        .filter(|p| p.role == role)
        .map(|p| p.position)
        .collect()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn every_tool_gives_finite_non_empty_geometry() {
    let doc = document();
    for (name, _) in test_tools::every_tool() {
        let g = gizmo(&doc, name).unwrap();
        assert!(!g.is_empty(), "{name}");
        assert!(g.is_finite(), "{name}");
        assert!(g.lines.iter().all(|l| l.points.len() >= 2), "{name}");
    }
}

#[test]
fn ffsd_points_reference_and_epsilon_circles() {
    let g = tool_gizmo(&Tool::Ffsd(test_tools::ffsd()), "t").unwrap();
    assert_eq!(points(&g, Role::ControlPoint).len(), 3);
    assert_eq!(
        points(&g, Role::ReferencePoint),
        vec![Vec3::new(1.0, 0.0, 0.5)]
    );
    let d = lines(&g, Role::Displacement);
    assert_eq!(d.len(), 1);
    assert_eq!(
        d[0].points,
        vec![Vec3::new(1.0, 0.0, 0.5), Vec3::new(1.0, 0.0, 1.0)]
    );
    let eps = circles(&g, Role::EpsilonRadius);
    assert_eq!(eps.len(), 9);
    // Point 0: α = 2, ε = 0.3 around C; point 1: α = 1, ε = 0.5 → 0.25 around R.
    assert!(
        eps[..3]
            .iter()
            .all(|c| c.radius == 0.3 && c.center == Vec3::Z)
    );
    assert!(
        eps[3..6]
            .iter()
            .all(|c| (c.radius - 0.25).abs() < 1e-7 && c.center == Vec3::new(1.0, 0.0, 0.5))
    );
    let normals: Vec<Vec3> = eps[..3].iter().map(|c| c.normal).collect();
    assert_eq!(normals, vec![Vec3::X, Vec3::Y, Vec3::Z]);
}

#[test]
fn curve_samples_are_the_tools_own_evaluation() {
    let t = test_tools::curve();
    let g = tool_gizmo(&Tool::Curve(t.clone()), "c").unwrap();
    let ev = CurveEvaluator::new(t.basis, t.rest.len(), "c").unwrap();
    let c = lines(&g, Role::Curve);
    assert_eq!(c.len(), 1);
    let m = c[0].points.len() - 1;
    assert!(m >= 32);
    for (k, p) in c[0].points.iter().enumerate() {
        assert!(
            close(*p, ev.point(&t.deformed, k as f32 / m as f32)),
            "sample {k}"
        );
    }
    // A Bézier curve starts and ends at its end control points.
    assert!(close(c[0].points[0], t.deformed[0]));
    assert!(close(c[0].points[m], t.deformed[3]));
    let r = lines(&g, Role::RestCurve);
    assert!(close(r[0].points[m], t.rest[3]));
    assert_eq!(lines(&g, Role::ControlPolygon)[0].points, t.deformed);
    assert_eq!(lines(&g, Role::RestPolygon)[0].points, t.rest);
    assert_eq!(points(&g, Role::ControlPoint), t.deformed);
    assert_eq!(points(&g, Role::RestPoint), t.rest);
    // One frame per control point, each orthonormal, the first axis along the curve.
    let (x, y, z) = (
        lines(&g, Role::FrameX),
        lines(&g, Role::FrameY),
        lines(&g, Role::FrameZ),
    );
    assert_eq!((x.len(), y.len(), z.len()), (4, 4, 4));
    let start_tangent = (t.deformed[1] - t.deformed[0]).normalize();
    let dir = |l: &Line| l.points[1] - l.points[0];
    assert!(dir(x[0]).normalize().dot(start_tangent) > 0.9999);
    for f in 0..4 {
        let (a, b, c) = (dir(x[f]), dir(y[f]), dir(z[f]));
        assert!(a.dot(b).abs() < 1e-5 && a.dot(c).abs() < 1e-5 && b.dot(c).abs() < 1e-5);
        assert!((a.length() - b.length()).abs() < 1e-5);
        assert!(a.cross(b).dot(c) > 0.0, "right-handed");
    }
}

#[test]
fn axial_axes_frames_and_zone() {
    let t = test_tools::axial();
    let g = tool_gizmo(&Tool::Axial(t.clone()), "a").unwrap();
    let c = lines(&g, Role::Curve);
    let r = lines(&g, Role::RestCurve);
    assert_eq!((c.len(), r.len()), (1, 1));
    // Clamped B-splines interpolate their end points.
    assert!(close(c[0].points[0], t.deformed[0].position));
    assert!(close(*c[0].points.last().unwrap(), t.deformed[2].position));
    assert!(close(*r[0].points.last().unwrap(), t.rest[2].position));
    assert_eq!(lines(&g, Role::ControlPolygon)[0].points.len(), 3);
    // Frames at the 3 axis points; across-axis lengths carry the scale θ (1 at the ends).
    let len = 0.5 * t.radius;
    let x = lines(&g, Role::FrameX);
    let y = lines(&g, Role::FrameY);
    assert_eq!(x.len(), 3);
    let dir = |l: &Line| l.points[1] - l.points[0];
    for f in 0..3 {
        assert!((dir(x[f]).length() - len).abs() < 1e-5);
        assert!(dir(x[f]).dot(dir(y[f])).abs() < 1e-5);
    }
    assert!((dir(y[0]).length() - len).abs() < 1e-5);
    assert!((dir(y[2]).length() - len).abs() < 1e-5);
    assert!(
        dir(y[1]).length() > len * 1.01,
        "the middle point's scale 1.5 shows"
    );
    // The zone of influence: circles of radius r around the rest axis, facing along it.
    let z = circles(&g, Role::InfluenceRadius);
    assert_eq!(z.len(), 3);
    for c in &z {
        assert_eq!(c.radius, 0.4);
        assert!(c.normal.dot(Vec3::Y) > 0.999, "rest axis runs along Y");
    }
}

#[test]
fn lattice_points_edges_and_frame() {
    let t = test_tools::lattice();
    let g = tool_gizmo(&Tool::Lattice(t.clone()), "l").unwrap();
    let (l, m, n) = (3, 2, 4);
    assert_eq!(points(&g, Role::ControlPoint).len(), l * m * n);
    let edges = lines(&g, Role::LatticeEdge);
    assert_eq!(edges.len(), m * n + l * n + l * m);
    let segments: usize = edges.iter().map(|e| e.points.len() - 1).sum();
    assert_eq!(
        segments,
        (l - 1) * m * n + l * (m - 1) * n + l * m * (n - 1)
    );
    let frame = lines(&g, Role::LatticeFrame);
    assert_eq!(frame.len(), 12);
    let corners = [-1.0_f32, 1.0];
    for e in &frame {
        for p in &e.points {
            assert!(corners.iter().any(|&c| (p.x - c).abs() < 1e-6));
            assert!([-1.0_f32, 2.0].iter().any(|&c| (p.y - c).abs() < 1e-6));
            assert!(corners.iter().any(|&c| (p.z - c).abs() < 1e-6));
        }
    }
    // Unmoved, every edge joins neighbours: one Greville step (2/2, 3/1, 2/3) along one axis.
    let mut rest = t.clone();
    rest.points.clear();
    let g0 = tool_gizmo(&Tool::Lattice(rest), "l").unwrap();
    for e in lines(&g0, Role::LatticeEdge) {
        for w in e.points.windows(2) {
            let d = (w[1] - w[0]).abs();
            let steps = [1.0, 3.0, 2.0 / 3.0];
            let axis = (0..3).find(|&a| d[a] > 1e-6).unwrap();
            assert!((d[axis] - steps[axis]).abs() < 1e-5, "{d}");
            assert!((d.length() - d[axis]).abs() < 1e-6, "{d}");
        }
    }
    // The moved point appears, displaced.
    assert!(
        points(&g, Role::ControlPoint)
            .iter()
            .any(|p| close(*p, Vec3::new(0.0, -0.7, 1.0 / 3.0)))
    );
}

#[test]
fn rest_surface_grid_reproduces_the_plane() {
    // A planar, unmoved surface has linear precision: S(u, v) = O + u·U + v·V.
    let mut t = test_tools::surface();
    t.moves.clear();
    let g = tool_gizmo(&Tool::ShapeSurface(t.clone()), "s").unwrap();
    let grid = lines(&g, Role::SurfaceGrid);
    // 2 spans along u, 1 along v: 5 lines of constant u and 3 of constant v.
    assert_eq!(grid.len(), 5 + 3);
    for (a, line) in grid[..5].iter().enumerate() {
        let u = a as f32 / 4.0;
        let k = line.points.len() - 1;
        for (b, p) in line.points.iter().enumerate() {
            let v = b as f32 / k as f32;
            let expected = t.frame.origin + t.frame.u_edge * u + t.frame.v_edge * v;
            assert!(close(*p, expected), "u {u}, v {v}: {p} vs {expected}");
        }
    }
    let nets = lines(&g, Role::ControlPolygon);
    assert_eq!(nets.len(), 4 + 5);
}

#[test]
fn moved_surface_grid_bulges_within_the_hull() {
    let t = test_tools::surface();
    let g = tool_gizmo(&Tool::ShapeSurface(t), "s").unwrap();
    let zs: Vec<f32> = lines(&g, Role::SurfaceGrid)
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.z))
        .collect();
    let max = zs.iter().copied().fold(f32::MIN, f32::max);
    assert!(zs.iter().all(|&z| z >= -1e-6));
    assert!(max > 0.05 && max < 0.4, "max height {max}");
    assert_eq!(points(&g, Role::ControlPoint).len(), 20);
    assert_eq!(points(&g, Role::RestPoint).len(), 20);
}

#[test]
fn dogme_constraints_targets_and_supports() {
    let t = test_tools::dogme();
    let g = tool_gizmo(&Tool::Dogme(t), "d").unwrap();
    assert_eq!(points(&g, Role::ConstraintPoint), vec![Vec3::Z, Vec3::X]);
    assert_eq!(
        points(&g, Role::ConstraintTarget),
        vec![Vec3::new(0.0, 0.0, 1.2), Vec3::new(1.1, 0.0, 0.0)]
    );
    assert_eq!(lines(&g, Role::Displacement).len(), 2);
    let s = circles(&g, Role::Support);
    assert_eq!(s.len(), 3);
    assert!(
        s.iter()
            .all(|c| c.center == Vec3::Z && (c.radius - 0.5).abs() < 1e-6)
    );
    let edges = lines(&g, Role::Support);
    assert_eq!(edges.len(), 12);
    let inv = Quat::from_rotation_z(0.3).inverse();
    let h = Vec3::new(0.2, 0.3, 0.4);
    for e in &edges {
        for &p in &e.points {
            let local = (inv * (p - Vec3::X)).abs();
            assert!((local - h).abs().max_element() < 1e-5, "{local}");
        }
    }
}

#[test]
fn direct_ffd_lattice_and_constraints() {
    let g = tool_gizmo(&Tool::DirectFfd(test_tools::direct_ffd()), "d").unwrap();
    assert_eq!(points(&g, Role::ControlPoint).len(), 12);
    assert_eq!(
        points(&g, Role::ConstraintPoint),
        vec![Vec3::new(0.2, 0.1, 0.0)]
    );
    assert_eq!(
        points(&g, Role::ConstraintTarget),
        vec![Vec3::new(0.2, 0.4, 0.0)]
    );
    assert_eq!(lines(&g, Role::LatticeFrame).len(), 12);
}

#[test]
fn sketch_curves_and_strokes() {
    let t = test_tools::sketch();
    let g = tool_gizmo(&Tool::Sketch(Box::new(t)), "s").unwrap();
    assert_eq!(
        lines(&g, Role::RestCurve)[0].points,
        vec![Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 2.0, 0.0)]
    );
    assert_eq!(
        lines(&g, Role::Curve)[0].points[2],
        Vec3::new(0.5, 1.8, 0.0)
    );
    assert_eq!(points(&g, Role::ControlPoint).len(), 3);
    // A stroke lies on the view-parallel plane through the camera target (z = 0 here) and
    // projects back onto its pixels.
    let t = test_tools::sketch_stroke();
    let g = tool_gizmo(&Tool::Sketch(Box::new(t.clone())), "s").unwrap();
    let r = lines(&g, Role::RestCurve);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].points.len(), 3);
    let ductile_core::sketch::tool::Curve::Stroke(s) = &t.reference else {
        unreachable!()
    };
    for (p, px) in r[0].points.iter().zip(&s.pixels) {
        assert!(p.z.abs() < 1e-4, "{p}");
        let (back, _) = s.camera.project(*p).unwrap();
        assert!((back - *px).length() < 1e-2, "{back} vs {px}");
    }
}

#[test]
fn macro_nodes_show_their_ffsd_points_at_the_current_value() {
    let doc = document();
    let g = gizmo(&doc, "nose").unwrap();
    let expected = tool_gizmo(&Tool::Ffsd(doc.macros["nose-longer"].tool(0.6)), "nose").unwrap();
    assert_eq!(g, expected);
    assert_eq!(points(&g, Role::ControlPoint).len(), 3);
}

#[test]
fn volumes_meshes_groups_and_missing_nodes() {
    let doc = document();
    let g = gizmo(&doc, "ball").unwrap();
    assert_eq!(circles(&g, Role::VolumeOutline).len(), 3);
    assert!(gizmo(&doc, "head").unwrap().is_empty());
    assert!(gizmo(&doc, "grp").unwrap().is_empty());
    assert!(matches!(
        gizmo(&doc, "nobody"),
        Err(SceneError::NoSuchNode { .. })
    ));
    let mut bad = doc.clone();
    if let NodeKind::Tool(Tool::Curve(c)) = &mut bad.node_mut("curve").unwrap().kind {
        c.deformed[1] = c.deformed[0];
    }
    assert!(matches!(gizmo(&bad, "curve"), Err(SceneError::Core(_))));
}

#[test]
fn box_outline_has_twelve_axis_edges_at_the_corners() {
    let h = Vec3::new(1.0, 2.0, 3.0);
    let g = volume_outline(&Shape::Box { half_extents: h }, 0.5);
    assert_eq!(g.lines.len(), 12);
    let mut per_axis = [0; 3];
    for l in &g.lines {
        assert_eq!(l.points.len(), 2);
        let d = (l.points[1] - l.points[0]).abs();
        let axis = (0..3).find(|&a| d[a] > 0.0).unwrap();
        assert!(
            (d[axis] - h[axis]).abs() < 1e-6,
            "edge length is 2 · 0.5 · h"
        );
        assert_eq!(d.length(), d[axis], "edges are axis-parallel");
        per_axis[axis] += 1;
        for p in &l.points {
            assert_eq!(p.abs(), h * 0.5);
        }
    }
    assert_eq!(per_axis, [4, 4, 4]);
}

#[test]
fn capsule_outline_keeps_its_axis_when_scaled() {
    let g = volume_outline(
        &Shape::Capsule {
            radius: 1.0,
            half_height: 2.0,
        },
        0.5,
    );
    assert_eq!(g.circles.len(), 2);
    assert!(
        g.circles
            .iter()
            .all(|c| c.radius == 0.5 && c.center.y.abs() == 2.0)
    );
    assert_eq!(g.lines.len(), 2);
    let top = g.lines[0]
        .points
        .iter()
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    assert!((top - 2.5).abs() < 1e-6);
}

/// Points on a circle, for checking outlines against the shape's normalised distance.
fn circle_points(c: &Circle) -> Vec<Vec3> {
    let a = c.normal.any_orthonormal_vector();
    let b = c.normal.cross(a);
    (0..12)
        .map(|k| {
            let t = k as f32 * std::f32::consts::TAU / 12.0;
            c.center + (a * t.cos() + b * t.sin()) * c.radius
        })
        .collect()
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        (0.1_f32..5.0).prop_map(|radius| Shape::Sphere { radius }),
        (0.1_f32..5.0, 0.1_f32..5.0, 0.1_f32..5.0).prop_map(|(x, y, z)| Shape::Box {
            half_extents: Vec3::new(x, y, z)
        }),
        (0.1_f32..5.0, 0.0_f32..5.0).prop_map(|(radius, half_height)| Shape::Capsule {
            radius,
            half_height
        }),
    ]
}

proptest! {
    #[test]
    fn outlines_lie_on_their_level_set(s in shape(), scale in 0.05_f32..1.0) {
        let g = volume_outline(&s, scale);
        prop_assert!(g.is_finite() && !g.is_empty());
        let pts = g
            .lines
            .iter()
            .flat_map(|l| l.points.clone())
            .chain(g.circles.iter().flat_map(circle_points));
        for p in pts {
            let d = s.normalized_distance(p);
            prop_assert!((d - scale).abs() < 1e-4 * (1.0 + scale), "{p}: {d} vs {scale}");
        }
    }

    #[test]
    fn the_plateau_is_where_the_weight_stops_being_one(
        s in shape(),
        inner in 0.05_f32..0.95,
        smooth in any::<bool>(),
    ) {
        let falloff = if smooth { Falloff::Smooth } else { Falloff::Linear };
        let g = falloff_plateau(&s, &falloff, inner);
        prop_assert!(g.lines.iter().all(|l| l.role == Role::FalloffPlateau));
        prop_assert!(g.circles.iter().all(|c| c.role == Role::FalloffPlateau));
        let pts = g
            .lines
            .iter()
            .flat_map(|l| l.points.clone())
            .chain(g.circles.iter().flat_map(circle_points));
        for p in pts {
            let t = s.normalized_distance(p);
            prop_assert!((falloff.weight(t * 0.999, inner) - 1.0).abs() < 1e-6);
            prop_assert!(falloff.weight(t * 1.01, inner) < 1.0);
        }
    }
}

#[test]
fn plateau_of_each_falloff() {
    let s = Shape::Sphere { radius: 2.0 };
    let g = falloff_plateau(&s, &Falloff::Smooth, 0.5);
    assert!(
        g.circles
            .iter()
            .all(|c| c.radius == 1.0 && c.role == Role::FalloffPlateau)
    );
    let g = falloff_plateau(&s, &Falloff::None, 0.5);
    assert!(g.circles.iter().all(|c| c.radius == 2.0));
    // No plateau beyond the centre: only the centre point is drawn.
    let g = falloff_plateau(&s, &Falloff::Linear, 0.0);
    assert!(g.circles.is_empty() && g.lines.is_empty());
    assert_eq!(
        g.points,
        vec![Point {
            position: Vec3::ZERO,
            role: Role::FalloffPlateau
        }]
    );
}

#[test]
fn layer_falloff_draws_every_volume_of_the_layer() {
    let mut doc = document();
    doc.mesh_mut("head").unwrap().stack = vec![
        LayerSpec::new("ffsd"),
        LayerSpec {
            influence: Some(InfluenceSpec {
                volumes: vec!["ball".into()],
                inner: 0.5,
                ..InfluenceSpec::default()
            }),
            ..LayerSpec::new("curve")
        },
    ];
    assert!(layer_falloff(&doc, "head", 0).unwrap().is_empty());
    let f = layer_falloff(&doc, "head", 1).unwrap();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].0, "ball");
    assert!(
        f[0].1
            .circles
            .iter()
            .all(|c| (c.radius - 0.35).abs() < 1e-6)
    );
    assert!(matches!(
        layer_falloff(&doc, "head", 2),
        Err(SceneError::IndexOutOfRange { .. })
    ));
    doc.mesh_mut("head").unwrap().stack[1]
        .influence
        .as_mut()
        .unwrap()
        .volumes
        .push("gone".into());
    assert!(matches!(
        layer_falloff(&doc, "head", 1),
        Err(SceneError::UnknownVolume { .. })
    ));
}

#[test]
fn transformed_moves_circles_as_a_similarity_does() {
    let mut g = Gizmo::default();
    g.circle(Vec3::X, Vec3::Z, 1.0, Role::Support);
    g.segment(Vec3::ZERO, Vec3::Y, Role::Curve);
    let m = Affine3A::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.0, 0.0, 5.0),
    );
    let t = g.transformed(&m);
    assert!((t.circles[0].radius - 2.0).abs() < 1e-5);
    assert!(close(t.circles[0].center, Vec3::new(2.0, 0.0, 5.0)));
    assert!(close(t.circles[0].normal, Vec3::NEG_Y));
    assert!(close(t.lines[0].points[1], Vec3::new(0.0, 0.0, 7.0)));
    assert_eq!(t.lines[0].role, Role::Curve);
}
