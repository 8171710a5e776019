//! [`CurvePieces::closest`] for a lane group of points at a time: the closest-point search of
//! the curve binds, in [`pulp`]'s runtime dispatch, and the bind's data written straight from
//! it ([`CurvePieces::bind_each`]).
//!
//! The seed is the boundary polyline's closest point (`polyline_lanes.rs`); the Gauss–Newton
//! steps `u ← u − (C − x)·C' / |C'|²` then run in every lane at once, each lane on its own
//! piece. Where the CPU has AVX2 they run in registers (`curve_lanes/steps.rs`): a piece's
//! coefficients are broadcast when every lane is on it, a run of pieces is loaded by columns
//! and each lane picks its own by a register permutation where the lanes' pieces lie within
//! 16 of each other, and are gathered lane by lane otherwise. Elsewhere they run on
//! `lane.rs`'s lanes, broadcast or gathered lane by lane. A lane stops where the scalar
//! search stops (a zero or non-finite tangent, a NaN step, a step that brings the point no
//! closer) and keeps its answer while the others go on. The piece a step lands in is computed in `f32`, where
//! piece indices are exact integers (fewer than `2²⁴` pieces), with the scalar code's `min`s
//! and clamps. Every lane does the scalar operations in their order, so each answer has the
//! bits of [`CurvePieces::closest`]; a lane whose seed is not finite is answered by it.

use glam::Vec3;

use crate::curve_pieces::{Closest, CurvePieces, REFINE_STEPS};
use crate::frames::BOUND_BATCH;
use crate::lane::{LANES, Lane, Lanes3, Mask, copy_prefix};
use crate::polyline_lanes::Bounds;

#[cfg(target_arch = "x86_64")]
mod steps;

impl CurvePieces {
    /// [`CurvePieces::closest`] of every point of `xs`, written to `out` (as long as `xs`):
    /// the same bits, a lane group at a time.
    ///
    /// # Panics
    /// When `out` and `xs` differ in length.
    pub fn closest_each(&self, xs: &[Vec3], out: &mut [(Closest, f32)]) {
        assert_eq!(xs.len(), out.len(), "one answer per point");
        pulp::Arch::new().dispatch(ClosestEach {
            pieces: self,
            xs,
            out,
            permute: Permute::detect(),
        });
    }

    /// [`CurvePieces::closest_each`] on the lanes, as where the CPU has no AVX2 (so that the
    /// tests check the lane form on every CPU).
    #[cfg(test)]
    fn closest_each_on_lanes(&self, xs: &[Vec3], out: &mut [(Closest, f32)]) {
        assert_eq!(xs.len(), out.len(), "one answer per point");
        pulp::Arch::new().dispatch(ClosestEach {
            pieces: self,
            xs,
            out,
            permute: Permute::NONE,
        });
    }

    /// What a curve bind keeps of the closest curve point of each point `x` of `xs`
    /// ([`CurvePieces::closest`]), written to `out`: its parameter `t`, the offset `x − C`,
    /// the first control point of its piece ([`CurvePieces::first`]) and its `2p + 1`
    /// weights ([`CurvePieces::weights`]). The same bits as those functions, a lane group at
    /// a time, each answer written where it is found instead of going through a
    /// [`Closest`] (`docs/performance.md`, thirty-first session).
    ///
    /// # Panics
    /// When `out` does not hold one entry (and `2p + 1` weights) per point.
    pub(crate) fn bind_each(&self, xs: &[Vec3], out: BoundPoints<'_>) {
        let n = xs.len();
        assert!(
            out.params.len() == n
                && out.offsets.len() == n
                && out.firsts.len() == n
                && out.weights.len() == n * (2 * self.degree + 1),
            "one entry per point"
        );
        self.bind_each_with(xs, out, Permute::detect());
    }

    /// [`CurvePieces::bind_each`] with the steps in registers where `permute` has them, on
    /// the lanes otherwise.
    fn bind_each_with(&self, xs: &[Vec3], out: BoundPoints<'_>, permute: Permute) {
        pulp::Arch::new().dispatch(BindEach {
            pieces: self,
            xs,
            out,
            permute,
        });
    }

    /// [`CurvePieces::weights`] of piece `k` at `u` for degree `p`, written to `out`
    /// (`2p + 1` values): every function at once on the lanes where the degree allows
    /// (`2p + 1 ≤ 16`). Row `i` of the piece's table ([`CurvePieces::weight_rows`]) holds
    /// coefficient `i` of every function, so Horner's rule runs on all of them at once, from
    /// zero, `acc · u + cᵢ` as the scalar `horner` does. A segment function has one
    /// coefficient fewer: its lane starts with `0 · u + 0 = +0`, the scalar start (a NaN or
    /// infinite `u` gives NaN either way). A point at the curve's end takes the table of
    /// exact end weights, as the scalar form does.
    #[inline(always)]
    fn weights_lanes(&self, p: usize, k: usize, u: f32, out: &mut [f32]) {
        debug_assert_eq!(p, self.degree);
        if self.weight_rows.is_empty() {
            self.weights(k, u, out);
            return;
        }
        if u >= 1.0 && k + 1 == self.count {
            out.copy_from_slice(&self.end);
            return;
        }
        let u = Lane::splat(u);
        let mut acc = Lane::ZERO;
        for &row in self.weight_rows[k * (p + 1)..(k + 1) * (p + 1)]
            .iter()
            .rev()
        {
            acc = acc * u + row;
        }
        copy_prefix(out, acc.as_array());
    }

    /// The closest points of the lane group `x` (module documentation): each lane's piece
    /// and local parameter (`f32`), point and squared distance, and which lanes had a finite
    /// seed (the others must be answered by [`CurvePieces::closest`]). `p` is the degree
    /// (a literal where the caller names it, so that the steps' loops have known lengths).
    #[inline(always)]
    fn closest_group(&self, p: usize, x: &Lanes3, bounds: &mut Bounds, permute: Permute) -> Group {
        let seeds = self.index.closest_lanes(x, bounds);
        // With AVX2 the steps run on registers, else on the lanes (the same bits).
        #[cfg(target_arch = "x86_64")]
        let (k, u, c, d2) = match permute.v3 {
            Some(v3) => self.closest_registers(v3, p, x, seeds.segment, seeds.fraction),
            None => self.closest_lanes(x, seeds.segment, seeds.fraction),
        };
        #[cfg(not(target_arch = "x86_64"))]
        let (k, u, c, d2) = {
            let _ = (p, permute);
            self.closest_lanes(x, seeds.segment, seeds.fraction)
        };
        Group {
            k,
            u,
            c,
            d2,
            finite: seeds.d2.is_finite(),
        }
    }

    /// `(C(u), dC/du)` in each lane, on each lane's piece `k` (Horner's rule, as
    /// [`CurvePieces::point_and_tangent`]), the coefficients broadcast when every lane is on
    /// one piece and gathered lane by lane otherwise (the lane form runs where there is no
    /// AVX2, hence no register permutation).
    #[inline(always)]
    fn point_and_tangent_lanes(&self, k: Lane, u: Lane) -> (Lanes3, Lanes3) {
        let p = self.degree;
        let q = p.max(1);
        let pieces = Pieces::new(k, self.count);
        let mut c = Lanes3::ZERO;
        for i in (0..=p).rev() {
            c = c.scale(u).add(pieces.gather(&self.curve, p + 1, i));
        }
        let mut d = Lanes3::ZERO;
        for i in (0..q).rev() {
            d = d.scale(u).add(pieces.gather(&self.tangent, q, i));
        }
        (c, d)
    }

    /// `(k, u)` with the end of an inner piece written as the start of the next one (the
    /// lane form of `settled`).
    #[inline(always)]
    fn settled_lanes(&self, k: Lane, u: Lane) -> (Lane, Lane) {
        let one = Lane::splat(1.0);
        let next = k + one;
        let m = u.simd_ge(one) & next.simd_lt(Lane::splat(self.count as f32));
        (m.select(next, k), m.select(Lane::ZERO, u))
    }

    /// The closest points of a lane group whose seeds are finite (module documentation):
    /// each lane's piece, local parameter, point and squared distance.
    #[inline(always)]
    fn closest_lanes(&self, x: &Lanes3, seg: Lane, frac: Lane) -> (Lane, Lane, Lanes3, Lane) {
        let (zero, one) = (Lane::ZERO, Lane::splat(1.0));
        let last = Lane::splat((self.count - 1) as f32);
        let (mut k, mut u) = self.settled_lanes(seg, frac);
        let (mut c, mut dc) = self.point_and_tangent_lanes(k, u);
        let mut best = c.sub(*x).length_squared();
        let mut going = !Mask::NONE;
        for _ in 0..REFINE_STEPS {
            let l2 = dc.length_squared();
            going = going & l2.simd_gt(zero) & l2.is_finite();
            if !going.any() {
                break;
            }
            let next = u - dot(c.sub(*x), dc) / l2;
            going = going & next.simd_eq(next);
            // Back `min(⌈−next⌉, k)` pieces, or ahead `min(⌊next⌋, last − k)`; with none
            // to go the clamp gives the scalar code's 0 or 1.
            let back = (-next).ceil().min(k);
            let ahead = next.floor().min(last - k);
            let below = next.simd_lt(zero);
            let above = next.simd_gt(one);
            let kn = below.select(k - back, above.select(k + ahead, k));
            let un = below.select(
                (next + back).clamp01(),
                above.select((next - ahead).clamp01(), next),
            );
            let (kn, un) = self.settled_lanes(kn, un);
            let (cn, dn) = self.point_and_tangent_lanes(kn, un);
            let d = cn.sub(*x).length_squared();
            going = going & d.simd_lt(best);
            best = going.select(d, best);
            k = going.select(kn, k);
            u = going.select(un, u);
            c = c.select(going, cn);
            dc = dc.select(going, dn);
        }
        (k, u, c, best)
    }
}

/// Each lane's piece index (`f32` integers), clamped into `0..count`.
#[inline(always)]
fn indices(k: Lane, count: usize) -> [usize; LANES] {
    let k = k.as_array();
    let mut out = [0; LANES];
    for (o, &k) in out.iter_mut().zip(k) {
        *o = (k as usize).min(count - 1);
    }
    out
}

/// AVX2, where the CPU has it (x86-64): the Gauss–Newton steps then run in registers
/// (`curve_lanes/steps.rs`) and take the coefficients of lanes whose pieces lie within 16 of
/// each other from [`CurvePieces::columns`], loading the run of pieces and letting each lane
/// pick its own (`vpermps`), in place of a load per lane and the shuffles that put the
/// values in place.
#[derive(Clone, Copy)]
pub(crate) struct Permute {
    #[cfg(target_arch = "x86_64")]
    v3: Option<pulp::x86::V3>,
}

impl Permute {
    /// None: the steps run on the lanes, as where the CPU has no AVX2 (for the tests).
    #[cfg(test)]
    pub(crate) const NONE: Self = Self {
        #[cfg(target_arch = "x86_64")]
        v3: None,
    };

    /// The permutation where this CPU has it.
    pub(crate) fn detect() -> Self {
        Self {
            #[cfg(target_arch = "x86_64")]
            v3: pulp::x86::V3::try_new(),
        }
    }
}

/// The pieces of a lane group, for gathering their coefficients.
struct Pieces {
    /// Each lane's piece.
    k: [usize; LANES],
    /// The least of them.
    first: usize,
    /// Whether every lane is on piece `first`.
    same: bool,
    /// With AVX2, where the pieces lie within 16 of `first`: each lane's piece less `first`
    /// (lanes 0–7, then 8–15), and whether some lie 8 or more past it.
    #[cfg(target_arch = "x86_64")]
    window: Option<(pulp::x86::V3, [core::arch::x86_64::__m256i; 2], bool)>,
}

impl Pieces {
    /// The pieces of the lanes `k`, for the lane form: gathered lane by lane unless every
    /// lane is on one piece (the register form builds its own, with the window:
    /// `Pieces::from_registers`).
    #[inline(always)]
    fn new(k: Lane, count: usize) -> Self {
        let k = indices(k, count);
        let (mut first, mut last) = (k[0], k[0]);
        for &kj in &k[1..] {
            first = first.min(kj);
            last = last.max(kj);
        }
        Self {
            k,
            first,
            same: first == last,
            #[cfg(target_arch = "x86_64")]
            window: None,
        }
    }

    /// Coefficient `i` of each lane's piece in `table` (`stride` vectors per piece): one
    /// load when every lane is on the same piece (as the neighbouring vertices of a lane
    /// group often are), else lane by lane.
    #[inline(always)]
    fn gather(&self, table: &[Vec3], stride: usize, i: usize) -> Lanes3 {
        if self.same {
            return Lanes3::splat(table[self.first * stride + i]);
        }
        // The coefficients side by side, then split as a load splits them (vector shuffles):
        // written lane by lane into the coordinate arrays, each register loaded from them
        // waited for its sixteen stores.
        let mut points = [Vec3::ZERO; LANES];
        for (p, &k) in points.iter_mut().zip(&self.k) {
            *p = table[k * stride + i];
        }
        Lanes3::load(&points)
    }
}

/// `a·b` in glam's order: `(ax bx + ay by) + az bz`.
#[inline(always)]
fn dot(a: Lanes3, b: Lanes3) -> Lane {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// [`CurvePieces::closest_each`]'s kernel.
struct ClosestEach<'a> {
    pieces: &'a CurvePieces,
    xs: &'a [Vec3],
    out: &'a mut [(Closest, f32)],
    /// Whether the steps run in registers (x86-64 only; elsewhere on the lanes).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    permute: Permute,
}

impl pulp::WithSimd for ClosestEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let pieces = self.pieces;
        if !pieces.index.has_lanes() {
            for (o, &x) in self.out.iter_mut().zip(self.xs) {
                *o = pieces.closest(x);
            }
            return;
        }
        let mut bounds = [Lane::ZERO; BOUND_BATCH];
        for (xs, out) in self.xs.chunks(LANES).zip(self.out.chunks_mut(LANES)) {
            let g =
                pieces.closest_group(pieces.degree, &Lanes3::load(xs), &mut bounds, self.permute);
            for (j, o) in out.iter_mut().enumerate() {
                if !g.finite.lane(j) {
                    *o = pieces.closest(xs[j]);
                    continue;
                }
                let (piece, u) = (g.k.as_array()[j] as usize, g.u.as_array()[j]);
                let t = pieces.param(piece, u);
                let point = g.c.lane(j);
                *o = (Closest { piece, u, t, point }, g.d2.as_array()[j]);
            }
        }
    }
}

/// A lane group's closest points ([`CurvePieces::closest_group`]).
struct Group {
    /// Each lane's piece, an `f32` integer.
    k: Lane,
    /// Each lane's local parameter in its piece.
    u: Lane,
    /// Each lane's curve point.
    c: Lanes3,
    /// Each lane's squared distance.
    d2: Lane,
    /// The lanes whose seed was finite (the others answered by the scalar search).
    finite: Mask,
}

/// Where [`CurvePieces::bind_each`] writes: one entry per point, `2p + 1` weights per point.
pub(crate) struct BoundPoints<'a> {
    /// Each point's curve parameter `t` ([`Closest::t`]).
    pub(crate) params: &'a mut [f32],
    /// Each point less its closest curve point.
    pub(crate) offsets: &'a mut [Vec3],
    /// The first control point of each closest point's piece.
    pub(crate) firsts: &'a mut [u32],
    /// Each point's `2p + 1` weights.
    pub(crate) weights: &'a mut [f32],
}

/// [`CurvePieces::bind_each`]'s kernel.
struct BindEach<'a> {
    pieces: &'a CurvePieces,
    xs: &'a [Vec3],
    out: BoundPoints<'a>,
    /// Whether the steps run in registers (x86-64 only; elsewhere on the lanes).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    permute: Permute,
}

impl BindEach<'_> {
    /// The kernel for degree `p` (the pieces' own: a literal where the caller names a
    /// common degree, so that the weights' loops have known lengths).
    #[inline(always)]
    fn run(self, p: usize) {
        let Self {
            pieces,
            xs,
            out,
            permute,
        } = self;
        debug_assert_eq!(p, pieces.degree);
        let stride = 2 * p + 1;
        let BoundPoints {
            params,
            offsets,
            firsts,
            weights,
        } = out;
        let mut bounds = [Lane::ZERO; BOUND_BATCH];
        let lanes = pieces.index.has_lanes();
        for ((((xs, params), offsets), firsts), weights) in xs
            .chunks(LANES)
            .zip(params.chunks_mut(LANES))
            .zip(offsets.chunks_mut(LANES))
            .zip(firsts.chunks_mut(LANES))
            .zip(weights.chunks_mut(LANES * stride))
        {
            // (No closure: it would not inherit the kernel's target features.)
            let g = if lanes {
                Some(pieces.closest_group(p, &Lanes3::load(xs), &mut bounds, permute))
            } else {
                None
            };
            for (j, &x) in xs.iter().enumerate() {
                let (k, u, point) = match &g {
                    Some(g) if g.finite.lane(j) => {
                        (g.k.as_array()[j] as usize, g.u.as_array()[j], g.c.lane(j))
                    }
                    _ => {
                        let (c, _) = pieces.closest(x);
                        (c.piece, c.u, c.point)
                    }
                };
                params[j] = pieces.param(k, u);
                offsets[j] = x - point;
                firsts[j] = pieces.firsts[k];
                pieces.weights_lanes(p, k, u, &mut weights[j * stride..(j + 1) * stride]);
            }
        }
    }
}

impl pulp::WithSimd for BindEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        // The Add menu's curves: a cubic B-spline and a quartic Bézier.
        match self.pieces.degree {
            3 => self.run(3),
            4 => self.run(4),
            p => self.run(p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::{CurveBasis, CurveEvaluator};
    use proptest::prelude::*;

    fn bits(a: &(Closest, f32)) -> (usize, u32, u32, [u32; 3], u32) {
        let (c, d) = a;
        (
            c.piece,
            c.u.to_bits(),
            c.t.to_bits(),
            c.point.to_array().map(f32::to_bits),
            d.to_bits(),
        )
    }

    /// Both forms of the steps (registers where the CPU has AVX2, and the lanes) give
    /// every point the scalar search's bits.
    fn check(basis: CurveBasis, ctrl: &[Vec3], xs: &[Vec3]) -> Result<(), TestCaseError> {
        let evaluator = CurveEvaluator::new(basis, ctrl.len(), "test").unwrap();
        let pieces = CurvePieces::new(&evaluator, ctrl);
        let mut out = vec![(pieces.closest(Vec3::ZERO).0, 0.0); xs.len()];
        let mut lanes = out.clone();
        pieces.closest_each(xs, &mut out);
        pieces.closest_each_on_lanes(xs, &mut lanes);
        for ((x, o), l) in xs.iter().zip(&out).zip(&lanes) {
            let scalar = bits(&pieces.closest(*x));
            prop_assert_eq!(bits(o), scalar, "x = {}", x);
            prop_assert_eq!(bits(l), scalar, "lanes, x = {}", x);
        }
        for permute in [Permute::detect(), Permute::NONE] {
            let got = bound(&pieces, xs, permute);
            prop_assert_eq!(got, scalar_bound(&pieces, xs));
        }
        Ok(())
    }

    /// One point's bind data as bits: `t`, offset, first control point, weights.
    type BoundBits = (u32, [u32; 3], u32, Vec<u32>);

    /// [`CurvePieces::bind_each`] of `xs` (the steps in registers where `permute` has them).
    fn bound(pieces: &CurvePieces, xs: &[Vec3], permute: Permute) -> Vec<BoundBits> {
        let (n, stride) = (xs.len(), 2 * pieces.degree + 1);
        let (mut params, mut offsets, mut firsts) = (vec![0.0; n], vec![Vec3::ZERO; n], vec![0; n]);
        let mut weights = vec![0.0; n * stride];
        let out = BoundPoints {
            params: &mut params,
            offsets: &mut offsets,
            firsts: &mut firsts,
            weights: &mut weights,
        };
        pieces.bind_each_with(xs, out, permute);
        (0..n)
            .map(|i| {
                (
                    params[i].to_bits(),
                    offsets[i].to_array().map(f32::to_bits),
                    firsts[i],
                    weights[i * stride..(i + 1) * stride]
                        .iter()
                        .map(|w| w.to_bits())
                        .collect(),
                )
            })
            .collect()
    }

    /// The same from the scalar functions: [`CurvePieces::closest`], then
    /// [`CurvePieces::first`] and [`CurvePieces::weights`] of its answer.
    fn scalar_bound(pieces: &CurvePieces, xs: &[Vec3]) -> Vec<BoundBits> {
        let mut w = vec![0.0; 2 * pieces.degree + 1];
        xs.iter()
            .map(|&x| {
                let (c, _) = pieces.closest(x);
                pieces.weights(c.piece, c.u, &mut w);
                (
                    c.t.to_bits(),
                    (x - c.point).to_array().map(f32::to_bits),
                    pieces.first(c.piece) as u32,
                    w.iter().map(|w| w.to_bits()).collect(),
                )
            })
            .collect()
    }

    fn bases() -> Vec<CurveBasis> {
        vec![
            CurveBasis::Bezier,
            CurveBasis::BSpline { degree: 1 },
            CurveBasis::BSpline { degree: 2 },
            CurveBasis::BSpline { degree: 3 },
        ]
    }

    /// Nine control points of a curve that turns in every direction.
    fn wiggly() -> Vec<Vec3> {
        (0..9)
            .map(|i| {
                let s = i as f32;
                Vec3::new(s, (s * 1.7).sin() * 2.0, (s * 0.6).cos())
            })
            .collect()
    }

    #[test]
    fn lanes_give_the_scalar_bits_near_and_far_from_wiggly_curves() {
        let ctrl = wiggly();
        let xs: Vec<Vec3> = (0..3001)
            .map(|i| {
                let s = i as f32 * 0.003;
                Vec3::new(
                    s * 3.0 - 0.5,
                    (i as f32 * 0.71).cos() * 3.0,
                    (i as f32 * 0.13).sin() * 2.0,
                )
            })
            .chain([Vec3::splat(f32::NAN), Vec3::new(-1e30, 0.0, 0.0), ctrl[4]])
            .collect();
        for basis in bases() {
            check(basis, &ctrl, &xs).unwrap();
        }
        // A curve folded onto itself (repeated control points): zero tangents.
        let folded = [Vec3::ZERO, Vec3::X, Vec3::X, Vec3::X, Vec3::ZERO];
        for basis in bases() {
            check(basis, &folded, &xs).unwrap();
        }
    }

    /// A curve of 39 spans (17 or 18 pieces each) and lane groups of points spread along it
    /// over 0 to 40 pieces in half-piece steps and over 34 and 85, each also with a NaN lane:
    /// the steps take the lanes' coefficients from one piece, from a window of 8 pieces,
    /// from one of 16 (a second run of 8 and a blend), and lane by lane, all with the scalar
    /// bits, the windows' edges (a spread of 7 or 8 pieces, 15 or 16) included.
    #[test]
    fn lane_groups_over_many_pieces_have_the_scalar_bits() {
        let ctrl: Vec<Vec3> = (0..40)
            .map(|i| {
                let s = i as f32;
                Vec3::new(s, (s * 0.9).sin() * 0.5, (s * 0.4).cos() * 0.3)
            })
            .collect();
        // A point near the control polygon at `t ∈ [0, 39]`.
        let near = |t: f32| {
            let k = (t as usize).min(38);
            let f = t - k as f32;
            ctrl[k].lerp(ctrl[k + 1], f) + Vec3::new(0.0, 0.04, -0.03)
        };
        let spreads = (0..=80).map(|h| h as f32 * 0.5 / 17.0).chain([2.0, 5.0]);
        let mut xs = Vec::new();
        for spread in spreads {
            for start in [0.2, 3.7, 20.3] {
                let group: Vec<Vec3> = (0..LANES)
                    .map(|j| near(start + spread * j as f32 / (LANES - 1) as f32))
                    .collect();
                xs.extend_from_slice(&group);
                let mut with_nan = group;
                with_nan[5] = Vec3::NAN;
                xs.extend(with_nan);
            }
        }
        // And a last group that is not a whole one.
        xs.extend((0..7).map(|j| near(2.0 + 4.0 * j as f32)));
        for basis in [
            CurveBasis::BSpline { degree: 1 },
            CurveBasis::BSpline { degree: 3 },
        ] {
            check(basis, &ctrl, &xs).unwrap();
        }
    }

    /// The bind data of points along a curve and past both ends (whose closest points are
    /// the ends, where the exact end weights apply), and the lane weights of parameters no
    /// search gives, have the bits of the scalar functions.
    #[test]
    fn lane_weights_have_the_scalar_bits() {
        let ctrl = wiggly();
        let xs: Vec<Vec3> = (0..1001)
            .map(|i| {
                let s = i as f32 * 0.011 - 1.5;
                Vec3::new(s, (s * 1.7).sin() * 2.0 + 0.3, (s * 0.6).cos() - 0.2)
            })
            .collect();
        // Five points (a quartic Bézier in the lanes), eight (degree 7, the widest that fits
        // them) and nine (an octic Bézier is too wide and goes through the scalar form); with
        // B-splines up to degree 7.
        let wide = [4, 5, 7].map(|degree| CurveBasis::BSpline { degree });
        for (n, basis) in [5, 8, 9]
            .into_iter()
            .flat_map(|n| bases().into_iter().chain(wide).map(move |b| (n, b)))
        {
            if let CurveBasis::BSpline { degree } = basis
                && degree >= n
            {
                continue;
            }
            let ctrl = &ctrl[..n];
            let evaluator = CurveEvaluator::new(basis, ctrl.len(), "test").unwrap();
            let pieces = CurvePieces::new(&evaluator, ctrl);
            let want = scalar_bound(&pieces, &xs);
            for permute in [Permute::detect(), Permute::NONE] {
                assert_eq!(bound(&pieces, &xs, permute), want, "{basis:?}, {n} points");
            }
            // Parameters no search gives: an inner piece's end, signed zeros, values past
            // the piece, infinities and NaN.
            let stride = 2 * pieces.degree + 1;
            let (mut lanes, mut one) = (vec![0.0; stride], vec![0.0; stride]);
            for piece in [0, pieces.count / 2, pieces.count - 1] {
                for u in [
                    1.0,
                    0.0,
                    -0.0,
                    -0.5,
                    1.5,
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                    f32::NAN,
                ] {
                    pieces.weights_lanes(pieces.degree, piece, u, &mut lanes);
                    pieces.weights(piece, u, &mut one);
                    assert_eq!(
                        lanes.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
                        one.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
                        "{basis:?}, piece {piece}, u = {u}"
                    );
                }
            }
        }
    }

    proptest! {
        #[test]
        fn lanes_match_the_scalar_search(
            pts in prop::collection::vec(prop::array::uniform3(-5.0f32..5.0), 2..9),
            xs in prop::collection::vec(prop::array::uniform3(-8.0f32..8.0), 1..40),
            which in 0usize..4,
        ) {
            let ctrl: Vec<Vec3> = pts.into_iter().map(Vec3::from).collect();
            let xs: Vec<Vec3> = xs.into_iter().map(Vec3::from).collect();
            let basis = match which {
                0 => CurveBasis::Bezier,
                d => CurveBasis::BSpline { degree: d.min(ctrl.len() - 1) },
            };
            check(basis, &ctrl, &xs)?;
        }
    }
}
