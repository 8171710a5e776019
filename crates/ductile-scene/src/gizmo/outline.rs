//! Wireframe outlines of influence volumes and of their falloff plateaus.

use std::f32::consts::PI;

use ductile_core::influence::{Falloff, Shape};
use glam::Vec3;

use super::{Gizmo, Role};

/// Segments per half circle of a capsule's end caps.
const ARC_SEGMENTS: usize = 16;

/// The outline of the level set `normalized_distance = scale` of `shape`
/// ([`Shape::normalized_distance`]), in the shape's local frame, role
/// [`Role::VolumeOutline`]; `scale = 1` is the volume's boundary.
///
/// * sphere of radius `r`: three great circles of radius `scale · r` (normals X, Y, Z);
/// * box of half extents `h`: the 12 edges of the box of half extents `scale · h`;
/// * capsule of radius `r` and half height `a` around Y: the level set is the capsule of
///   radius `scale · r` with the *same* axis segment, drawn as the circles at `y = ±a`
///   (normal Y) and its profile (two sides and two half circles) in the XY and ZY planes.
///
/// A scale that is not positive (a plateau that is only the centre) gives the centre point,
/// or the axis segment of a capsule, with role [`Role::VolumeOutline`].
#[must_use]
pub fn volume_outline(shape: &Shape, scale: f32) -> Gizmo {
    let mut g = Gizmo::default();
    let role = Role::VolumeOutline;
    if !(scale > 0.0 && scale.is_finite()) {
        match shape {
            Shape::Capsule { half_height, .. } if *half_height > 0.0 => {
                g.segment(Vec3::NEG_Y * *half_height, Vec3::Y * *half_height, role);
            }
            Shape::Tube { points, .. } => g.line(points.clone(), role),
            _ => g.point(Vec3::ZERO, role),
        }
        return g;
    }
    match shape.clone() {
        Shape::Tube { points, radii } => tube(&mut g, &points, &radii, scale, role),
        Shape::Sphere { radius } => {
            for n in [Vec3::X, Vec3::Y, Vec3::Z] {
                g.circle(Vec3::ZERO, n, radius * scale, role);
            }
        }
        Shape::Box { half_extents } => {
            let h = half_extents * scale;
            parallelepiped(
                &mut g,
                -h,
                [
                    Vec3::new(2.0 * h.x, 0.0, 0.0),
                    Vec3::new(0.0, 2.0 * h.y, 0.0),
                    Vec3::new(0.0, 0.0, 2.0 * h.z),
                ],
                role,
            );
        }
        Shape::Capsule {
            radius,
            half_height,
        } => {
            let r = radius * scale;
            for y in [-half_height, half_height] {
                g.circle(Vec3::Y * y, Vec3::Y, r, role);
            }
            for side in [Vec3::X, Vec3::Z] {
                g.line(stadium(side, r, half_height), role);
            }
        }
    }
    g
}

/// A tube's outline: a circle across the curve at each point (radius scaled) and four lines
/// along it, offset in a frame carried along the curve.
fn tube(g: &mut Gizmo, points: &[Vec3], radii: &[f32], scale: f32, role: Role) {
    let n = points.len();
    if n < 2 {
        return;
    }
    let tangent = |i: usize| {
        let a = points[i.saturating_sub(1)];
        let b = points[(i + 1).min(n - 1)];
        (b - a).try_normalize().unwrap_or(Vec3::Y)
    };
    let mut side = tangent(0).any_orthonormal_vector();
    let mut rails: [Vec<Vec3>; 4] = Default::default();
    for i in 0..n {
        let t = tangent(i);
        // Carry the side vector along (remove its component along the tangent).
        side = (side - t * side.dot(t))
            .try_normalize()
            .unwrap_or_else(|| t.any_orthonormal_vector());
        let up = t.cross(side);
        let r = radii.get(i).copied().unwrap_or(0.0) * scale;
        g.circle(points[i], t, r, role);
        for (rail, d) in rails.iter_mut().zip([side, up, -side, -up]) {
            rail.push(points[i] + d * r);
        }
    }
    for rail in rails {
        g.line(rail, role);
    }
}

/// The closed profile of a capsule of radius `r` and half height `a` around Y in the plane
/// spanned by the unit vector `side` and Y: up one side, over the top half circle, down the
/// other side, under the bottom half circle.
fn stadium(side: Vec3, r: f32, a: f32) -> Vec<Vec3> {
    let arc = |centre: f32, from: f32| {
        (0..=ARC_SEGMENTS).map(move |k| {
            let t = from + PI * k as f32 / ARC_SEGMENTS as f32;
            side * (r * t.cos()) + Vec3::Y * (centre + r * t.sin())
        })
    };
    let mut pts: Vec<Vec3> = arc(a, 0.0).collect();
    pts.extend(arc(-a, PI));
    pts.push(pts[0]);
    pts
}

/// Adds the 12 edges of the parallelepiped with corner `origin` and edge vectors `edges`.
pub(crate) fn parallelepiped(g: &mut Gizmo, origin: Vec3, edges: [Vec3; 3], role: Role) {
    let corner = |c: usize| {
        origin
            + edges[0] * (c & 1) as f32
            + edges[1] * ((c >> 1) & 1) as f32
            + edges[2] * ((c >> 2) & 1) as f32
    };
    for c in 0..8_usize {
        for bit in [1, 2, 4] {
            if c & bit == 0 {
                g.segment(corner(c), corner(c | bit), role);
            }
        }
    }
}

/// The boundary of the plateau of `shape` where a layer's volume weight is 1
/// ([`Falloff::weight`]: weight 1 up to normalised distance `inner`, and everywhere inside
/// with [`Falloff::None`]): [`volume_outline`] at scale `inner` (1 for `Falloff::None`),
/// role [`Role::FalloffPlateau`]. The ramp of the falloff lies between this and the
/// volume's outline. With an inverted influence the same surface is where the weight
/// reaches 0. `inner` outside `[0, 1]` is clamped, NaN taken as 0.
#[must_use]
pub fn falloff_plateau(shape: &Shape, falloff: &Falloff, inner: f32) -> Gizmo {
    let scale = match falloff {
        Falloff::None => 1.0,
        _ if inner.is_finite() => inner.clamp(0.0, 1.0),
        _ => 0.0,
    };
    volume_outline(shape, scale).with_role(Role::FalloffPlateau)
}
