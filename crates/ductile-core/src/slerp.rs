//! Spherical interpolation between two fixed rotations at many fractions: glam's
//! [`Quat::slerp`] with the steps that depend only on the two ends done once.
//!
//! `slerp(r₀, r₁, s) = (r₀ sin((1 − s) θ) + r₁ sin(s θ)) / sin θ`, `θ = acos(r₀ · r₁)` after
//! `r₁` is negated onto `r₀`'s side (`r₀ · r₁ ≥ 0`), so `θ ∈ [0, π/2]`. glam computes the dot
//! product, the arc cosine (its polynomial `acos_approx`, a square root) and the three sines at
//! every call. An axial tool's bind and deform call it once per vertex between the frames of
//! a sample segment, so [`SlerpArc::new`] keeps the far end on the near side, `θ` and `sin θ`
//! per segment, and [`SlerpArc::at`] computes the two sines that depend on `s`.
//!
//! Arithmetic: the same operations in the same order as glam 0.32's SSE2 `Quat::slerp` (the
//! build's x86-64 path): `θ` is read through [`Quat::angle_between`] (twice glam's
//! `acos_approx` of the same dot product, so halving it is exact), and the sines are glam's
//! 11-degree minimax polynomial (DirectXMath's `XMVectorSin`), whose angle reduction leaves an
//! angle in `[0, π/2]` unchanged. A test checks the bits against [`Quat::slerp`].

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Quat, Vec4};

/// glam's threshold above which the ends are so close that it interpolates linearly.
const DOT_THRESHOLD: f32 = 1.0 - f32::EPSILON;

/// The slerp from one rotation to another, prepared for many fractions. Equal ends give the
/// start itself at every fraction (glam's slerp moves it by rounding when its squared length
/// is not exactly 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SlerpArc {
    /// Equal ends: every fraction gives the start itself.
    Same,
    /// Ends closer than glam's threshold: normalised linear interpolation to `end`.
    Lerp {
        /// The far end, on the start's side.
        end: Quat,
    },
    /// Spherical interpolation to `end` over the angle `theta`.
    Arc {
        /// The far end, on the start's side (`start · end ≥ 0`).
        end: Quat,
        /// `θ`, radians, in `[0, π/2]`.
        theta: f32,
        /// `sin θ` by glam's polynomial.
        sin_theta: f32,
    },
}

impl SlerpArc {
    /// The arc from `start` to `end` (unit quaternions).
    #[must_use]
    pub fn new(start: Quat, end: Quat) -> Self {
        if start == end {
            return Self::Same;
        }
        let (mut end, mut dot) = (end, start.dot(end));
        if dot < 0.0 {
            end = -end;
            dot = -dot;
        }
        if dot > DOT_THRESHOLD {
            return Self::Lerp { end };
        }
        // `angle_between` is `2 acos_approx(|start · end|)`, the `θ` of glam's slerp doubled.
        let theta = start.angle_between(end) * 0.5;
        Self::Arc {
            end,
            theta,
            sin_theta: sin_poly(theta),
        }
    }

    /// `slerp(start, end, s)` for `s ∈ [0, 1]`, with `start` the rotation given to
    /// [`SlerpArc::new`]: the bits of `start.slerp(end, s)`.
    #[must_use]
    #[inline]
    pub fn at(&self, start: Quat, s: f32) -> Quat {
        match *self {
            Self::Same => start,
            Self::Lerp { end } => (start * (1.0 - s) + end * s).normalize(),
            Self::Arc {
                end,
                theta,
                sin_theta,
            } => {
                let scale1 = sin_poly(theta * (1.0 - s));
                let scale2 = sin_poly(theta * s);
                let q = (Vec4::from(start) * scale1 + Vec4::from(end) * scale2) / sin_theta;
                Quat::from_vec4(q)
            }
        }
    }
}

/// `sin x` for `x ∈ [0, π)` as glam's SSE2 `m128_sin` computes it: the reflection
/// `x ↦ π − x` above `π/2`, then the odd polynomial of degree 11 in Horner form, each step a
/// product then a sum (no fused multiply-add, as in glam without `fast-math`). glam's reduction
/// to `[−π, π]` subtracts `2π · round(x / 2π) = 0` here, which leaves `x` unchanged.
#[must_use]
#[inline]
fn sin_poly(x: f32) -> f32 {
    let x = if x <= FRAC_PI_2 { x } else { PI - x };
    let x2 = x * x;
    let mut r = SIN[0] * x2 + SIN[1];
    for c in &SIN[2..] {
        r = r * x2 + c;
    }
    r * x
}

/// The coefficients of glam's sine polynomial in `x²`, highest power first (also in
/// `axial_lanes.rs`'s registers).
pub(crate) const SIN: [f32; 6] = [
    -2.388_985_9e-8,
    2.752_556_2e-6,
    -0.000_198_408_74,
    0.008_333_331,
    -0.166_666_67,
    1.0,
];

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn bits(q: Quat) -> [u32; 4] {
        q.to_array().map(f32::to_bits)
    }

    /// A deterministic spread of unit quaternions: random axes and angles, and pairs close
    /// together, far apart, on opposite sides and equal.
    fn pairs() -> Vec<(Quat, Quat)> {
        let mut seed = 0x9e37_79b9_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let mut out = Vec::new();
        for k in 0..400 {
            let axis = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let a = Quat::from_axis_angle(axis, next() * 6.0);
            let turn = [1e-4, 1e-3, 0.05, 0.5, 1.5, 3.0, 3.1][k % 7];
            let other = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let b = a * Quat::from_axis_angle(other, turn * (0.5 + next()));
            out.push((a, b));
            out.push((a, -b));
            out.push((a, a));
            out.push((a, (a + Quat::from_xyzw(1e-7, 0.0, 0.0, 0.0)).normalize()));
        }
        out
    }

    #[test]
    fn the_bits_of_glams_slerp_at_every_fraction() {
        let mut arcs = 0;
        for (a, b) in pairs() {
            let arc = SlerpArc::new(a, b);
            arcs += usize::from(matches!(arc, SlerpArc::Arc { .. }));
            for k in 0..=64 {
                let s = k as f32 / 64.0;
                // Equal ends give the start itself, where glam interpolates from a start whose
                // squared length rounds below its threshold.
                let want = if a == b { a } else { a.slerp(b, s) };
                assert_eq!(
                    bits(arc.at(a, s)),
                    bits(want),
                    "{a:?} → {b:?} at {s}: {arc:?}"
                );
            }
        }
        // Most pairs take the arc path (the others are equal or nearly so).
        assert!(arcs > 600, "{arcs} arcs");
    }

    #[test]
    fn the_polynomial_is_glams_sine_over_the_quarter_and_half_turn() {
        for k in 0..=1000 {
            let x = k as f32 / 1000.0 * 3.1;
            assert!((sin_poly(x) - x.sin()).abs() < 2e-6, "sin {x}");
        }
    }
}
