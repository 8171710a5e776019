//! Twisting about the joint curve (Kho & Garland §5.2, Eq. 7):
//! `v' = v_r + R(t_r(s), θ(v)) (v − v_r)` with `θ(v) = F(s(v)) · θ_max` (`F(s) = s` unless a
//! twist-speed control is set, §5.3).
//!
//! The joint curve is not planar, so the tangent `t_r(s)` is blended as a direction rather
//! than as an angle: at node `i` the tangent is the normalised sum of the two incident
//! segment directions, and on segment `[sᵢ, sᵢ₊₁]` it turns at constant angular speed from
//! the node tangent to the segment direction on the first half and on to the next node
//! tangent on the second half — the same blend as Eq. (2) with `b` of Eq. (4). In a plane it
//! is exactly the tangent of angle `Φ(s)`.

use glam::{Quat, Vec3};

use crate::sketch::bend::blend;
use crate::sketch::skin::Polyline;

/// Unit node tangents of a polyline: the end segments' directions at the ends, the
/// normalised sum of the incident directions inside (the segment direction when they are
/// opposite).
#[must_use]
pub fn node_tangents(curve: &Polyline) -> Vec<Vec3> {
    let n = curve.points().len();
    (0..n)
        .map(|i| {
            if i == 0 {
                curve.direction(0)
            } else if i == n - 1 {
                curve.direction(n - 2)
            } else {
                let (a, b) = (curve.direction(i - 1), curve.direction(i));
                (a + b).try_normalize().unwrap_or(b)
            }
        })
        .collect()
}

/// Turns unit `a` towards unit `b` by the fraction `x ∈ [0, 1]` of the angle between them.
#[must_use]
fn turn(a: Vec3, b: Vec3, x: f32) -> Vec3 {
    if x <= 0.0 {
        return a;
    }
    Quat::IDENTITY.slerp(Quat::from_rotation_arc(a, b), x) * a
}

/// A joint curve with its node tangents.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The curve.
    pub curve: Polyline,
    /// Unit node tangents (see [`node_tangents`]).
    pub tangents: Vec<Vec3>,
}

impl Axis {
    /// Prepares the tangents of `curve`.
    #[must_use]
    pub fn new(curve: Polyline) -> Self {
        let tangents = node_tangents(&curve);
        Self { curve, tangents }
    }

    /// The blended unit tangent `t_r(s)` (see the module documentation).
    #[must_use]
    pub fn tangent_at(&self, s: f32) -> Vec3 {
        let (i, alpha) = self.curve.locate(s);
        let d = self.curve.direction(i);
        if alpha <= 0.5 {
            turn(self.tangents[i], d, blend(2.0 * alpha))
        } else {
            turn(d, self.tangents[i + 1], blend(2.0 * alpha - 1.0))
        }
    }
}

/// The twist map of one vertex (Eq. 7 with the scale control of §5.3):
/// `v' = v_r + R(t, θ) · k · (v − v_r)`, right-handed about the unit tangent `t`.
#[must_use]
pub fn twist_point(v: Vec3, v_r: Vec3, t: Vec3, theta: f32, k: f32) -> Vec3 {
    v_r + Quat::from_axis_angle(t, theta) * ((v - v_r) * k)
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

    use super::*;

    #[test]
    fn tangents_blend_like_eq2() {
        // Unit segments along +x then +y.
        let axis = Axis::new(
            Polyline::new(&[Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)], "a").unwrap(),
        );
        let diag = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((axis.tangents[1] - diag).length() < 1e-6);
        // Middle of segment 0: the segment direction.
        assert!((axis.tangent_at(0.25) - Vec3::X).length() < 1e-6);
        // Node 1: 45°.
        assert!((axis.tangent_at(0.5) - diag).length() < 1e-6);
        // Three quarters into segment 0: halfway (22.5°) between +x and the node tangent.
        let t = axis.tangent_at(0.375);
        let expect = Vec3::new((FRAC_PI_4 / 2.0).cos(), (FRAC_PI_4 / 2.0).sin(), 0.0);
        assert!((t - expect).length() < 1e-5, "{t}");
    }

    #[test]
    fn twist_rotates_about_the_tangent() {
        let p = twist_point(
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::X,
            FRAC_PI_2,
            1.0,
        );
        assert!((p - Vec3::new(2.0, 0.0, 1.0)).length() < 1e-6, "{p}");
    }
}
