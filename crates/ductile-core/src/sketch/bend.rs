//! Sketch-based bending (Kho & Garland §5.1, Eq. 1–6, and the turning-angle control of
//! §5.3, Eq. 8).
//!
//! Sign convention (see `docs/algorithms/sketch-deform.md`): with `n` the unit normal of
//! the sketch plane (pointing towards the viewer) and rotations right-handed about `n`, the
//! exterior turning angle `φᵢ` at node `i` is measured *clockwise*:
//! `φᵢ = −∠_n(dᵢ₋₁, dᵢ)`, where `∠_n(a, b) = atan2(n·(a × b), a·b)` is the counter-clockwise
//! angle from `a` to `b`. The end nodes have `φ₀ = φ_n = 0`. With this convention Eq. (5),
//! `θ = Φ_r − Φ_t + θ_g`, rotates the reference tangent onto the target tangent as printed,
//! `θ_g = ∠_n(d₀^r, d₀^t)` being the counter-clockwise angle between the initial segments.

use glam::{Quat, Vec3};

use crate::sketch::skin::Polyline;

/// The counter-clockwise angle from `a` to `b` about the unit axis `n`, in radians in
/// `(−π, π]`: `atan2(n·(a × b), a·b)` on the components of `a` and `b` orthogonal to `n`.
#[must_use]
pub fn signed_angle(a: Vec3, b: Vec3, n: Vec3) -> f32 {
    let a = a - n * a.dot(n);
    let b = b - n * b.dot(n);
    n.dot(a.cross(b)).atan2(a.dot(b))
}

/// The signed exterior turning angles `φ₀ … φ_n` of a polyline about `n`, clockwise
/// positive, `φ₀ = φ_n = 0` (radians).
#[must_use]
pub fn turning_angles(curve: &Polyline, n: Vec3) -> Vec<f32> {
    let nodes = curve.points().len();
    let mut phi = vec![0.0; nodes];
    for i in 1..nodes - 1 {
        phi[i] = -signed_angle(curve.direction(i - 1), curve.direction(i), n);
    }
    phi
}

/// Total turning angles at the nodes (Eq. 1): `Φᵢ = Σ_{j<i} φⱼ + φᵢ / 2`.
#[must_use]
pub fn total_turning(phi: &[f32]) -> Vec<f32> {
    let mut acc = 0.0;
    phi.iter()
        .map(|&p| {
            let total = acc + 0.5 * p;
            acc += p;
            total
        })
        .collect()
}

/// The blending function of Eq. (4): `b(x) = 0` for `x < 0`, `x` on `[0, 1]`, `1` for
/// `x > 1`.
#[must_use]
pub fn blend(x: f32) -> f32 {
    x.clamp(0.0, 1.0)
}

/// A polyline with its turning angles: everything Eq. (2) needs.
#[derive(Debug, Clone, PartialEq)]
pub struct TurningCurve {
    /// The curve.
    pub curve: Polyline,
    /// `φᵢ` per node (clockwise positive, radians).
    pub phi: Vec<f32>,
    /// `Φᵢ` per node (Eq. 1).
    pub total: Vec<f32>,
}

impl TurningCurve {
    /// Measures the turning angles of `curve` about `n`.
    #[must_use]
    pub fn new(curve: Polyline, n: Vec3) -> Self {
        let phi = turning_angles(&curve, n);
        Self::from_angles(curve, phi)
    }

    /// A curve with the given turning angles (Eq. 1 computes `Φ`).
    #[must_use]
    pub fn from_angles(curve: Polyline, phi: Vec<f32>) -> Self {
        let total = total_turning(&phi);
        Self { curve, phi, total }
    }

    /// The interpolated total turning angle at normalised arc length `s` (Eq. 2–3):
    /// `Φ(s) = Φᵢ + φᵢ/2 · b(2α) + φᵢ₊₁/2 · b(2α − 1)` on the segment `[sᵢ, sᵢ₊₁]`.
    #[must_use]
    pub fn total_at(&self, s: f32) -> f32 {
        let (i, alpha) = self.curve.locate(s);
        self.total[i]
            + 0.5 * self.phi[i] * blend(2.0 * alpha)
            + 0.5 * self.phi[i + 1] * blend(2.0 * alpha - 1.0)
    }
}

/// Rebuilds a curve in the plane orthogonal to `n` from its first node, first direction,
/// segment lengths and the (adjusted) turning angles `φ'` (Eq. 8): segment `i` points along
/// `R(n, −Σ_{j≤i} φ'ⱼ) d₀`. Used when a turning-angle spline changes the target's shape.
#[must_use]
pub fn rebuild(curve: &Polyline, phi: &[f32], n: Vec3) -> Vec<Vec3> {
    let pts = curve.points();
    let d0 = curve.direction(0);
    let mut out = Vec::with_capacity(pts.len());
    out.push(pts[0]);
    let mut turned = 0.0_f32;
    for i in 0..curve.segment_count() {
        turned += phi[i];
        let len = pts[i].distance(pts[i + 1]);
        let d = Quat::from_axis_angle(n, -turned) * d0;
        out.push(out[i] + d * len);
    }
    out
}

/// The bending map of one vertex (Eq. 6 with the scale control of §5.3):
/// `v' = v_t + R(n, θ) · k · (v − v_r)`, where `R(n, θ)` rotates right-handedly about `n`
/// and `k` scales the offset (1 without a scale control).
#[must_use]
pub fn bend_point(v: Vec3, v_r: Vec3, v_t: Vec3, n: Vec3, theta: f32, k: f32) -> Vec3 {
    v_t + Quat::from_axis_angle(n, theta) * ((v - v_r) * k)
}

/// The reference and target of a bend, ready to evaluate `θ(s)` (Eq. 5) and the points
/// `v_r(s)`, `v_t(s)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bend {
    /// Reference curve with its turning angles.
    pub reference: TurningCurve,
    /// Target curve (already translated to start at the reference's start) with its
    /// (possibly adjusted) turning angles.
    pub target: TurningCurve,
    /// Unit normal of the sketch plane (the rotation axis).
    pub normal: Vec3,
    /// `θ_g`: counter-clockwise angle about `n` from the reference's to the target's initial
    /// segment (radians).
    pub global: f32,
}

impl Bend {
    /// Prepares a bend. `target` must already start at the reference's first node.
    #[must_use]
    pub fn new(reference: TurningCurve, target: TurningCurve, normal: Vec3) -> Self {
        let global = signed_angle(
            reference.curve.direction(0),
            target.curve.direction(0),
            normal,
        );
        Self {
            reference,
            target,
            normal,
            global,
        }
    }

    /// The rotational angle of Eq. (5): `θ(s) = Φ_r(s) − Φ_t(s) + θ_g` (radians).
    #[must_use]
    pub fn theta(&self, s: f32) -> f32 {
        self.reference.total_at(s) - self.target.total_at(s) + self.global
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    use super::*;

    /// Nodes (0,0), (1,0), (1,1), (2,1) in the xy-plane: a left turn, then a right turn,
    /// unit segments, so sᵢ = 0, 1/3, 2/3, 1.
    fn zigzag() -> Polyline {
        Polyline::new(
            &[
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(2.0, 1.0, 0.0),
            ],
            "z",
        )
        .unwrap()
    }

    #[test]
    fn turning_angles_match_hand_values() {
        // Viewed from +z, the curve turns left (ccw, +90°) at node 1 and right at node 2;
        // clockwise-positive φ gives −π/2 then +π/2.
        let c = TurningCurve::new(zigzag(), Vec3::Z);
        let expect_phi = [0.0, -FRAC_PI_2, FRAC_PI_2, 0.0];
        for (a, b) in c.phi.iter().zip(expect_phi) {
            assert!((a - b).abs() < 1e-6, "{:?}", c.phi);
        }
        // Eq. 1: Φ₀ = 0, Φ₁ = 0 − π/4, Φ₂ = −π/2 + π/4, Φ₃ = 0.
        let expect_total = [0.0, -FRAC_PI_4, -FRAC_PI_4, 0.0];
        for (a, b) in c.total.iter().zip(expect_total) {
            assert!((a - b).abs() < 1e-6, "{:?}", c.total);
        }
    }

    #[test]
    fn interpolated_total_turning_matches_eq2() {
        let c = TurningCurve::new(zigzag(), Vec3::Z);
        let third = 1.0 / 3.0;
        // Segment 0, α = 1/2: Φ₀ + φ₀/2 = 0 (parallel to segment 0).
        assert!(c.total_at(0.5 * third).abs() < 1e-6);
        // Segment 0, α = 3/4: Φ₀ + 0 + φ₁/2 · b(0.5) = −π/8.
        assert!((c.total_at(0.75 * third) - (-PI / 8.0)).abs() < 1e-6);
        // Node 1 from segment 0's end equals Φ₁ = −π/4 (continuity).
        assert!((c.total_at(third - 1e-7) - (-FRAC_PI_4)).abs() < 1e-5);
        // Midpoint of segment 1: Φ₁ + φ₁/2 = −π/2 (segment 1 points along +y, ccw 90°).
        assert!((c.total_at(0.5) - (-FRAC_PI_2)).abs() < 1e-6);
        // Segment 1, α = 1/4: Φ₁ + φ₁/2 · b(1/2) = −π/4 − π/8.
        assert!((c.total_at(third + 0.25 * third) - (-3.0 * PI / 8.0)).abs() < 1e-5);
        // Segment 2, α = 1: Φ₂ + φ₂/2 + φ₃/2 = 0 = Φ₃.
        assert!(c.total_at(1.0).abs() < 1e-6);
    }

    #[test]
    fn theta_maps_reference_tangents_to_target_tangents() {
        // Reference: straight along x. Target: the zigzag, which starts along x too.
        let reference = TurningCurve::new(
            Polyline::new(&[Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0)], "r").unwrap(),
            Vec3::Z,
        );
        let target = TurningCurve::new(zigzag(), Vec3::Z);
        let bend = Bend::new(reference, target, Vec3::Z);
        assert_eq!(bend.global, 0.0);
        // On the middle segment the target goes along +y: a ccw quarter turn.
        assert!((bend.theta(0.5) - FRAC_PI_2).abs() < 1e-6);
        let v = Vec3::new(1.5, 0.2, 0.0);
        let out = bend_point(
            v,
            Vec3::new(1.5, 0.0, 0.0),
            Vec3::new(1.0, 0.5, 0.0),
            Vec3::Z,
            bend.theta(0.5),
            1.0,
        );
        // The offset (0, 0.2) turns ccw to (−0.2, 0).
        assert!((out - Vec3::new(0.8, 0.5, 0.0)).length() < 1e-6, "{out}");
    }

    #[test]
    fn global_rotation_turns_everything() {
        let reference =
            TurningCurve::new(Polyline::new(&[Vec3::ZERO, Vec3::X], "r").unwrap(), Vec3::Z);
        let target = TurningCurve::new(
            Polyline::new(&[Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0)], "t").unwrap(),
            Vec3::Z,
        );
        let bend = Bend::new(reference, target, Vec3::Z);
        for s in [0.0, 0.3, 1.0] {
            assert!((bend.theta(s) - FRAC_PI_2).abs() < 1e-6);
        }
    }

    #[test]
    fn rebuild_reproduces_the_curve_and_applies_offsets() {
        let c = TurningCurve::new(zigzag(), Vec3::Z);
        let same = rebuild(&c.curve, &c.phi, Vec3::Z);
        for (a, b) in same.iter().zip(c.curve.points()) {
            assert!((*a - *b).length() < 1e-6);
        }
        // Straightening node 1 (φ'₁ = 0) and keeping node 2: the curve goes
        // (0,0) → (1,0) → (2,0) → then turns clockwise to (2,−1).
        let phi = [0.0, 0.0, FRAC_PI_2, 0.0];
        let p = rebuild(&c.curve, &phi, Vec3::Z);
        assert!((p[2] - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        assert!(
            (p[3] - Vec3::new(2.0, -1.0, 0.0)).length() < 1e-6,
            "{:?}",
            p
        );
    }
}
