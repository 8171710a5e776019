//! Gizmo geometry of every tool kind, in the tool's own space.

use ductile_core::axial::{AxialTool, AxisPoint, AxisShape, SampledAxis};
use ductile_core::curve::{CurveBasis, CurveEvaluator, CurveTool};
use ductile_core::direct_ffd::DirectFfdTool;
use ductile_core::dogme::{Anchor, DogmeTool, Support};
use ductile_core::ffsd::{FfsdTool, PointMode};
use ductile_core::influence::Shape;
use ductile_core::lattice::LatticeTool;
use ductile_core::sketch::stroke::SketchPlane;
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};
use ductile_core::surface::ShapeSurfaceTool;
use ductile_core::tool::Tool;
use glam::{Affine3A, Vec3};

use super::outline::{parallelepiped, volume_outline};
use super::{Gizmo, Role};
use crate::error::Result;
use crate::handles::{epsilon_radius, lattice_points, surface_nets};

/// Iso-lines per knot span of a shape surface, per direction.
const ISO_PER_SPAN: usize = 2;
/// Samples per knot span along a surface iso-line.
const SAMPLES_PER_SPAN: usize = 8;
/// Most iso-lines per direction, and most samples per iso-line.
const MAX_ISO: usize = 33;
const MAX_SAMPLES: usize = 129;
/// Frame axis length of a curve tool, relative to the deformed curve's length.
const CURVE_FRAME_LENGTH: f32 = 0.1;
/// Frame axis length of an axial tool, relative to its radius.
const AXIAL_FRAME_LENGTH: f32 = 0.5;

/// The gizmo of `tool` in the tool's own space (for a tool node, its local frame). The tool
/// is validated first (`what` names it in errors), so the geometry is finite:
///
/// * FFSD: control points, directional reference points with a line reference → control
///   point, and the ε radius `ε^(2/α)` around each point's centre as three great circles;
/// * axial: rest and deformed axes sampled as the tool samples them
///   ([`SampledAxis`]), their control polygons (spline axes), points, the rotation-minimising
///   frames with twist and scale at the deformed axis points, and circles of the zone's
///   radius around the rest axis;
/// * curve: rest and deformed curves ([`CurveEvaluator::samples`]), control polygons and
///   points, rotation-minimising frames along the deformed curve;
/// * lattice: control points, edges between neighbours, the rest parallelepiped;
/// * shape surface: moved and rest control nets and points, iso-parameter lines of the
///   moved surface;
/// * DOGME: constraint points (free points only), targets, lines to them, supports;
/// * Direct FFD: its lattice's gizmo, constraint points, targets and lines;
/// * sketch: the reference and target curves (strokes drawn on the view-parallel plane
///   through their camera's target).
pub fn tool_gizmo(tool: &Tool, what: &str) -> Result<Gizmo> {
    tool.validate(what)?;
    let mut g = Gizmo::default();
    match tool {
        Tool::Ffsd(t) => ffsd(&mut g, t),
        Tool::Axial(t) => axial(&mut g, t, what)?,
        Tool::Curve(t) => curve(&mut g, t, what)?,
        Tool::Lattice(t) => lattice(&mut g, t, what)?,
        Tool::ShapeSurface(t) => surface(&mut g, t, what)?,
        Tool::Dogme(t) => dogme(&mut g, t),
        Tool::DirectFfd(t) => direct_ffd(&mut g, t, what)?,
        Tool::Sketch(t) => sketch(&mut g, t),
    }
    Ok(g)
}

fn ffsd(g: &mut Gizmo, t: &FfsdTool) {
    for p in &t.points {
        g.point(p.position, Role::ControlPoint);
        if let PointMode::Directional { reference } = p.mode {
            g.point(reference, Role::ReferencePoint);
            g.segment(reference, p.position, Role::Displacement);
        }
        if let Some(r) = epsilon_radius(p) {
            for n in [Vec3::X, Vec3::Y, Vec3::Z] {
                g.circle(p.centre(), n, r, Role::EpsilonRadius);
            }
        }
    }
}

/// Sample indices of `count` frames spread evenly over `len` samples (both ends included).
fn frame_samples(len: usize, count: usize) -> impl Iterator<Item = usize> {
    let k = count.clamp(2, len.max(2));
    (0..k).map(move |f| f * (len - 1) / (k - 1))
}

/// Axis point and local-to-world map `R W S` of sample `i` of `axis` ([`SampledAxis::at`]).
fn sample_frame(axis: &SampledAxis, i: usize) -> (Vec3, glam::Mat3) {
    let n = axis.points.len();
    if i + 1 < n {
        axis.at(i, 0.0)
    } else {
        axis.at(n - 2, 1.0)
    }
}

/// Frame axes of length `len` (times the axis scale across) at `count` samples of `axis`.
fn frames(g: &mut Gizmo, axis: &SampledAxis, count: usize, len: f32) {
    for i in frame_samples(axis.points.len(), count) {
        let (a, m) = sample_frame(axis, i);
        for (c, role) in [(0, Role::FrameX), (1, Role::FrameY), (2, Role::FrameZ)] {
            g.segment(a, a + m.col(c) * len, role);
        }
    }
}

fn points(g: &mut Gizmo, pts: &[Vec3], role: Role) {
    for &p in pts {
        g.point(p, role);
    }
}

fn axial(g: &mut Gizmo, t: &AxialTool, what: &str) -> Result<()> {
    let rest = SampledAxis::new(t.shape, &t.rest, None, &format!("{what}: rest axis"))?;
    let deformed = SampledAxis::new(
        t.shape,
        &t.deformed,
        Some(rest.first_frame()),
        &format!("{what}: deformed axis"),
    )?;
    let rest_pts: Vec<Vec3> = t.rest.iter().map(|p| p.position).collect();
    let def_pts: Vec<Vec3> = t.deformed.iter().map(|p| p.position).collect();
    g.line(rest.points.clone(), Role::RestCurve);
    g.line(deformed.points.clone(), Role::Curve);
    if t.shape != AxisShape::Polyline {
        g.line(rest_pts.clone(), Role::RestPolygon);
        g.line(def_pts.clone(), Role::ControlPolygon);
    }
    points(g, &rest_pts, Role::RestPoint);
    points(g, &def_pts, Role::ControlPoint);
    frames(g, &deformed, t.rest.len(), AXIAL_FRAME_LENGTH * t.radius);
    for i in frame_samples(rest.points.len(), t.rest.len()) {
        let (a, m) = sample_frame(&rest, i);
        g.circle(
            a,
            m.col(0).normalize_or(Vec3::X),
            t.radius,
            Role::InfluenceRadius,
        );
    }
    Ok(())
}

fn curve(g: &mut Gizmo, t: &CurveTool, what: &str) -> Result<()> {
    let ev = CurveEvaluator::new(t.basis, t.rest.len(), what)?;
    let rest_curve = ev.samples(&t.rest).points().to_vec();
    let def_curve = ev.samples(&t.deformed).points().to_vec();
    let length: f32 = def_curve.windows(2).map(|w| w[0].distance(w[1])).sum();
    g.line(rest_curve, Role::RestCurve);
    g.line(def_curve, Role::Curve);
    g.line(t.rest.clone(), Role::RestPolygon);
    g.line(t.deformed.clone(), Role::ControlPolygon);
    points(g, &t.rest, Role::RestPoint);
    points(g, &t.deformed, Role::ControlPoint);
    // The frames come from the axial tool's sampling of the same curve (same basis, same
    // parameters); a curve whose start tangent vanishes simply shows no frames.
    let shape = match t.basis {
        CurveBasis::Bezier => AxisShape::Bezier,
        CurveBasis::BSpline { degree } => AxisShape::BSpline { degree },
    };
    let axis = |pts: &[Vec3]| -> Vec<AxisPoint> { pts.iter().map(|&p| AxisPoint::at(p)).collect() };
    if let Ok(rest) = SampledAxis::new(shape, &axis(&t.rest), None, what)
        && let Ok(def) = SampledAxis::new(shape, &axis(&t.deformed), Some(rest.first_frame()), what)
    {
        frames(g, &def, t.rest.len(), CURVE_FRAME_LENGTH * length);
    }
    Ok(())
}

fn lattice(g: &mut Gizmo, t: &LatticeTool, what: &str) -> Result<()> {
    let pts = lattice_points(t, what)?;
    let [l, m, n] = t.count_array();
    let idx = |i: usize, j: usize, k: usize| i + l * (j + m * k);
    for k in 0..n {
        for j in 0..m {
            g.line(
                (0..l).map(|i| pts[idx(i, j, k)]).collect(),
                Role::LatticeEdge,
            );
        }
    }
    for k in 0..n {
        for i in 0..l {
            g.line(
                (0..m).map(|j| pts[idx(i, j, k)]).collect(),
                Role::LatticeEdge,
            );
        }
    }
    for j in 0..m {
        for i in 0..l {
            g.line(
                (0..n).map(|k| pts[idx(i, j, k)]).collect(),
                Role::LatticeEdge,
            );
        }
    }
    points(g, &pts, Role::ControlPoint);
    let f = &t.frame;
    parallelepiped(g, f.origin, [f.s, f.t, f.u], Role::LatticeFrame);
    Ok(())
}

/// The polylines of a dense `nu × nv` net (index `i + nu j`) along both directions.
fn net(g: &mut Gizmo, pts: &[Vec3], nu: usize, nv: usize, role: Role) {
    for j in 0..nv {
        g.line((0..nu).map(|i| pts[i + nu * j]).collect(), role);
    }
    for i in 0..nu {
        g.line((0..nv).map(|j| pts[i + nu * j]).collect(), role);
    }
}

fn surface(g: &mut Gizmo, t: &ShapeSurfaceTool, what: &str) -> Result<()> {
    let (rest, moved) = surface_nets(t, what)?;
    let (nu, nv) = (t.counts.0 as usize, t.counts.1 as usize);
    net(g, &rest, nu, nv, Role::RestPolygon);
    net(g, &moved, nu, nv, Role::ControlPolygon);
    points(g, &rest, Role::RestPoint);
    points(g, &moved, Role::ControlPoint);
    let spans = (nu - t.degree.0 as usize, nv - t.degree.1 as usize);
    let iso = |s: usize| (ISO_PER_SPAN * s + 1).min(MAX_ISO);
    let samples = |s: usize| (SAMPLES_PER_SPAN * s + 1).min(MAX_SAMPLES);
    let unit = |k: usize, n: usize| k as f32 / (n - 1) as f32;
    // Lines of constant u, then of constant v.
    for (lines, along, fixed_is_u) in [
        (iso(spans.0), samples(spans.1), true),
        (iso(spans.1), samples(spans.0), false),
    ] {
        for a in 0..lines {
            let params: Vec<(f32, f32)> = (0..along)
                .map(|b| {
                    let (c, d) = (unit(a, lines), unit(b, along));
                    if fixed_is_u { (c, d) } else { (d, c) }
                })
                .collect();
            if let Some(p) = t.surface_points(&moved, &params) {
                g.line(p, Role::SurfaceGrid);
            }
        }
    }
    Ok(())
}

/// Constraint point, target and the line between them, for a free-point anchor.
fn constraint(g: &mut Gizmo, at: &Anchor, displacement: Vec3) -> Option<Vec3> {
    let Anchor::Point(p) = *at else {
        return None;
    };
    let q = p + displacement;
    g.point(p, Role::ConstraintPoint);
    g.point(q, Role::ConstraintTarget);
    g.segment(p, q, Role::Displacement);
    Some(p)
}

fn dogme(g: &mut Gizmo, t: &DogmeTool) {
    for c in &t.constraints {
        let Some(p) = constraint(g, &c.at, c.displacement) else {
            continue;
        };
        let (shape, placement) = match c.support {
            Support::Sphere { radius } => (Shape::Sphere { radius }, Affine3A::from_translation(p)),
            Support::Box {
                half_extents,
                rotation,
            } => (
                Shape::Box { half_extents },
                Affine3A::from_rotation_translation(rotation.normalize(), p),
            ),
        };
        g.extend(
            volume_outline(&shape, 1.0)
                .transformed(&placement)
                .with_role(Role::Support),
        );
    }
}

fn direct_ffd(g: &mut Gizmo, t: &DirectFfdTool, what: &str) -> Result<()> {
    lattice(g, &t.lattice, &format!("{what}: lattice"))?;
    for c in &t.constraints {
        constraint(g, &c.at, c.displacement);
    }
    Ok(())
}

/// A sketch curve: a polyline with its points, or a stroke drawn on the view-parallel plane
/// through its camera's target (the bind projects it onto the plane through the first mesh
/// hit, which needs the mesh).
fn sketch_curve(g: &mut Gizmo, c: &Curve, line: Role, point: Role) {
    match c {
        Curve::Points(p) => {
            g.line(p.clone(), line);
            points(g, p, point);
        }
        Curve::Stroke(s) | Curve::Joints(s) => {
            let plane = SketchPlane::view_parallel(&s.camera, s.camera.target);
            let pts: Vec<Vec3> = s
                .pixels
                .iter()
                .filter_map(|&px| plane.intersect(&s.camera.ray(px)))
                .filter(|p| p.is_finite())
                .collect();
            g.line(pts, line);
        }
    }
}

fn sketch(g: &mut Gizmo, t: &SketchTool) {
    sketch_curve(g, &t.reference, Role::RestCurve, Role::RestPoint);
    if let SketchMode::Bend { target, .. } = &t.mode {
        sketch_curve(g, target, Role::Curve, Role::ControlPoint);
    }
}
