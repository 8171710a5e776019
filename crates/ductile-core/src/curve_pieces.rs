//! A Bézier or B-spline curve cut into short polynomial pieces in power form, for fast
//! closest-point queries and basis weights (the binds of the curve tools).
//!
//! The parameter domain `[0, 1]` is cut into `m` pieces of equal length `h = 1/m`; for a
//! B-spline every knot is a piece boundary (each of the `S = count − p` knot spans holds
//! `q = ⌈16·count / S⌉` pieces), so on each piece the curve and every basis function is one
//! polynomial. In the piece's local parameter `u = (t − k h) / h ∈ [0, 1]`:
//!
//! * the curve `C(u) = Σⱼ aⱼ uʲ` and its derivative `dC/du = Σⱼ (j+1) aⱼ₊₁ uʲ`,
//! * the `p + 1` non-zero point basis functions `Nᵢ(u)` (Bernstein `Bᵢⁿ` or B-spline `Nᵢ,ₚ`)
//!   and the `p` segment basis functions `Mᵢ(u)` of degree `p − 1`
//!   ([`CurveEvaluator::segment_weights`]),
//!
//! are evaluated by Horner's rule: a handful of fused operations instead of a knot search and
//! the divisions of the Cox–de Boor recurrence. The coefficients are computed once per curve
//! in `f64` — each function is evaluated in `f64` at `p + 1` evenly spaced nodes of the piece
//! and interpolated (Newton's divided differences, expanded to powers) — then rounded to
//! `f32`.
//! A piece is short (`h ≤ 1/32`), so its coefficients fall off like `hʲ/j!` and the power
//! form is well conditioned even at degree 15.
//!
//! Closest points: the piece boundaries form a polyline (indexed by [`PolylineIndex`]); its
//! closest point seeds Gauss–Newton steps `u ← u − (C − x)·C' / |C'|²` that move from piece to
//! piece and are kept only while they bring the point closer — the search
//! `docs/algorithms/curve-deformation.md` describes.

use glam::{Vec3, Vec4};

use crate::basis::{basis_at_span, bernstein_all};
use crate::curve::{CurveBasis, CurveEvaluator};
use crate::frames::PolylineIndex;
use crate::lane::{LANES, Lane, copy_prefix};

/// Pieces per control point (at least; a B-spline rounds up to whole knot spans).
const PIECES_PER_POINT: usize = 16;

/// The most coefficients (`f32`) a piece table is meant to hold, 16 MiB: a B-spline of many
/// control points and a high degree gets fewer pieces per knot span (at least 2, which
/// keeps a degree-15 power form well conditioned at the clamped ends). The piece count is
/// chosen from these tables alone; the transposed copies for evaluating a point's functions
/// at once ([`CurvePieces::weight_rows`], [`BasisPieces::rows`]) come on top, at most about
/// as much again, and live only as long as the pieces (during a bind).
const TABLE_BUDGET: usize = 1 << 22;

/// Pieces per knot span: [`PIECES_PER_POINT`] per control point, fewer where the table of
/// `floats` coefficients per piece would pass [`TABLE_BUDGET`], and never fewer than 2.
fn pieces_per_span(count: usize, spans: usize, floats: usize) -> usize {
    let wanted = (PIECES_PER_POINT * count).div_ceil(spans);
    wanted.min(TABLE_BUDGET / (spans * floats)).max(2)
}

/// Gauss–Newton refinements of a closest-point parameter.
pub(crate) const REFINE_STEPS: usize = 4;

/// The point of a curve closest to a query point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Closest {
    /// The piece holding it.
    pub piece: usize,
    /// Its local parameter `u ∈ [0, 1]` in the piece.
    pub u: f32,
    /// Its curve parameter `t = (piece + u) / m ∈ [0, 1]`, rounded to `f32`: next to a
    /// knot it may round onto the knot while the piece (whose weights a bind keeps) is the
    /// one before it.
    pub t: f32,
    /// The curve point `C(t)`.
    pub point: Vec3,
}

/// The zeros after each of [`CurvePieces::columns`]' columns: a load of 16 pieces' values
/// from any piece stays in the column.
const COLUMN_PAD: usize = 16;

/// A curve in power-form pieces (module documentation).
#[derive(Debug, Clone)]
pub struct CurvePieces {
    /// The curve degree `p`.
    pub(crate) degree: usize,
    /// Number of pieces `m`.
    pub(crate) count: usize,
    /// Per piece, `p + 1` coefficients of `C(u)`.
    pub(crate) curve: Vec<Vec3>,
    /// Per piece, `p` coefficients of `dC/du` (at least one, zero for a constant).
    pub(crate) tangent: Vec<Vec3>,
    /// The coefficients of `curve`, then of `tangent`, by column: column `3i + c` holds
    /// coordinate `c` of coefficient `i` of every piece (the tangent's coefficients numbered
    /// after the curve's `p + 1`), then [`COLUMN_PAD`] zeros, so that the lanes can load the
    /// coefficients of a run of consecutive pieces at once (`curve_lanes.rs`).
    pub(crate) columns: Vec<f32>,
    /// Per piece, `p + 1` functions × `p + 1` coefficients of the point basis.
    point_basis: Vec<f32>,
    /// Per piece, `p` functions × `p` coefficients of the segment basis.
    segment_basis: Vec<f32>,
    /// Per piece, `p + 1` rows: row `i` holds coefficient `i` of the `p + 1` point functions
    /// and then of the `p` segment functions (0 where a segment function has none), for
    /// evaluating them all at once (`curve_lanes.rs`); empty when `2p + 1` passes the lanes.
    pub(crate) weight_rows: Vec<Lane>,
    /// Per piece, the index of its first non-zero point and segment function.
    pub(crate) firsts: Vec<u32>,
    /// The `2p + 1` weights at the curve's end `t = 1`, exactly as the recurrence gives them
    /// (every function but the last 0): the power form's sum there is only nearly 0.
    pub(crate) end: Vec<f32>,
    /// The piece boundaries `C(k/m)`, `k = 0..=m`.
    pub(crate) index: PolylineIndex,
}

impl CurvePieces {
    /// Cuts the curve of `evaluator` with control points `ctrl` (as many as the evaluator's
    /// count) into pieces.
    ///
    /// # Panics
    /// When `ctrl.len()` differs from the evaluator's count.
    #[must_use]
    pub fn new(evaluator: &CurveEvaluator, ctrl: &[Vec3]) -> Self {
        assert_eq!(
            ctrl.len(),
            evaluator.count(),
            "one control point per basis function"
        );
        let p = evaluator.degree();
        let n = evaluator.count();
        // Knot spans: one Bézier span, or the `n − p` spans of a clamped uniform B-spline.
        let spans = match evaluator.basis() {
            CurveBasis::Bezier => 1,
            CurveBasis::BSpline { .. } => n - p,
        };
        let per_span = pieces_per_span(n, spans, (p + 1) * (p + 1) + p * p + 6 * (p + 1));
        let count = spans * per_span;
        let knots = knots_f64(p, spans);
        let (nodes, seg_nodes) = (interpolation_nodes(p + 1), interpolation_nodes(p.max(1)));
        let basis = |lower: usize, span: usize| {
            let knots = &knots;
            move |t: f64, out: &mut [f64]| {
                basis_f64(evaluator.basis(), n, knots, lower, span, t, out);
            }
        };
        let mut curve = Vec::with_capacity(count * (p + 1));
        let mut tangent = Vec::with_capacity(count * p.max(1));
        let mut point_basis = Vec::with_capacity(count * (p + 1) * (p + 1));
        let mut segment_basis = Vec::with_capacity(count * p * p);
        let mut firsts = Vec::with_capacity(count);
        let mut boundaries = Vec::with_capacity(count + 1);
        let vec3 = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
        for k in 0..count {
            let span = k / per_span;
            let (t0, h) = (k as f64 / count as f64, 1.0 / count as f64);
            let first = match evaluator.basis() {
                CurveBasis::Bezier => 0,
                CurveBasis::BSpline { .. } => span,
            };
            let point = piece_functions(&nodes, p + 1, t0, h, basis(0, span));
            // C(u) = Σᵢ Nᵢ(u) Pᵢ, coefficient by coefficient, in f64.
            let coeffs: Vec<[f64; 3]> = (0..=p)
                .map(|j| {
                    let mut a = [0.0_f64; 3];
                    for (i, b) in point.iter().enumerate() {
                        let q = ctrl[first + i];
                        a[0] += b[j] * f64::from(q.x);
                        a[1] += b[j] * f64::from(q.y);
                        a[2] += b[j] * f64::from(q.z);
                    }
                    a
                })
                .collect();
            boundaries.push(vec3(coeffs[0]));
            if k + 1 == count {
                let end = coeffs
                    .iter()
                    .fold([0.0; 3], |s, a| [s[0] + a[0], s[1] + a[1], s[2] + a[2]]);
                boundaries.push(vec3(end));
            }
            curve.extend(coeffs.iter().map(|&a| vec3(a)));
            if p == 0 {
                tangent.push(Vec3::ZERO);
            }
            for (j, a) in coeffs.iter().enumerate().skip(1) {
                let c = j as f64;
                tangent.push(vec3([c * a[0], c * a[1], c * a[2]]));
            }
            point_basis.extend(point.iter().flatten().map(|&c| c as f32));
            // The segment basis: degree p − 1 over the n − 1 segments.
            if p >= 1 {
                let seg = piece_functions(&seg_nodes, p, t0, h, basis(1, span));
                segment_basis.extend(seg.iter().flatten().map(|&c| c as f32));
            }
            firsts.push(first as u32);
        }
        // The weights at t = 1 from the recurrence, exact.
        let mut values = [0.0_f64; 17];
        let mut end = vec![0.0; 2 * p + 1];
        basis(0, spans - 1)(1.0, &mut values);
        for (e, v) in end.iter_mut().zip(&values[..=p]) {
            *e = *v as f32;
        }
        if p >= 1 {
            basis(1, spans - 1)(1.0, &mut values);
            for (e, v) in end[p + 1..].iter_mut().zip(&values[..p]) {
                *e = *v as f32;
            }
        }
        let mut weight_rows = Vec::new();
        if 2 * p < LANES {
            for k in 0..count {
                let point = &point_basis[k * (p + 1) * (p + 1)..(k + 1) * (p + 1) * (p + 1)];
                let segment = &segment_basis[k * p * p..(k + 1) * p * p];
                for i in 0..=p {
                    let mut row = Lane::ZERO;
                    for (r, c) in point.chunks_exact(p + 1).enumerate() {
                        row.0[r] = c[i];
                    }
                    if i < p {
                        for (r, c) in segment.chunks_exact(p).enumerate() {
                            row.0[p + 1 + r] = c[i];
                        }
                    }
                    weight_rows.push(row);
                }
            }
        }
        let q = p.max(1);
        let mut columns = Vec::with_capacity(3 * (p + 1 + q) * (count + COLUMN_PAD));
        for (table, per_piece) in [(&curve, p + 1), (&tangent, q)] {
            for i in 0..per_piece {
                for c in 0..3 {
                    columns.extend((0..count).map(|k| table[k * per_piece + i][c]));
                    columns.extend([0.0; COLUMN_PAD]);
                }
            }
        }
        Self {
            degree: p,
            count,
            curve,
            tangent,
            columns,
            point_basis,
            segment_basis,
            weight_rows,
            firsts,
            end,
            // At least two boundaries: the index always exists.
            index: PolylineIndex::new(boundaries).unwrap_or_else(|| unreachable!()),
        }
    }

    /// The 16 values of coordinate `c` of coefficient `column` ([`CurvePieces::columns`]) for
    /// the pieces `first..first + 16` (zeros past the last piece).
    #[inline(always)]
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // The curve steps' (x86-64).
    pub(crate) fn column_run(&self, column: usize, c: usize, first: usize) -> &[f32] {
        let start = (3 * column + c) * (self.count + COLUMN_PAD) + first;
        &self.columns[start..start + 16]
    }

    /// Number of pieces `m`.
    #[must_use]
    pub fn count(&self) -> usize {
        self.count
    }

    /// `(C(u), dC/du)` on piece `k` by Horner's rule.
    #[must_use]
    pub fn point_and_tangent(&self, k: usize, u: f32) -> (Vec3, Vec3) {
        let p = self.degree;
        let a = &self.curve[k * (p + 1)..(k + 1) * (p + 1)];
        let d = &self.tangent[k * p.max(1)..(k + 1) * p.max(1)];
        (horner3(a, u), horner3(d, u))
    }

    /// The curve point at `u` of piece `k`.
    #[must_use]
    pub fn point(&self, k: usize, u: f32) -> Vec3 {
        let p = self.degree;
        horner3(&self.curve[k * (p + 1)..(k + 1) * (p + 1)], u)
    }

    /// The closest curve point to `x`: the closest point of the boundary polyline, refined by
    /// Gauss–Newton steps kept only while they bring the point closer (module
    /// documentation). Returns it and its squared distance.
    #[must_use]
    pub fn closest(&self, x: Vec3) -> (Closest, f32) {
        let (k, u, _) = self.index.closest(x);
        let (mut k, mut u) = self.settled(k, u);
        let (mut c, mut dc) = self.point_and_tangent(k, u);
        let mut best = c.distance_squared(x);
        let last = self.count - 1;
        for _ in 0..REFINE_STEPS {
            // `dC/du = h·dC/dt` is small on short pieces: only a zero (or non-finite)
            // tangent stops the steps; a step that overshoots is refused below.
            let l2 = dc.length_squared();
            if !(l2 > 0.0 && l2.is_finite()) {
                break;
            }
            // The step in this piece's parameter, then the piece it lands in.
            let next = u - (c - x).dot(dc) / l2;
            let (kn, un) = if next.is_nan() {
                break;
            } else if next < 0.0 {
                let back = ((-next).ceil() as usize).min(k);
                if back == 0 {
                    (k, 0.0)
                } else {
                    (k - back, (next + back as f32).clamp(0.0, 1.0))
                }
            } else if next > 1.0 {
                let ahead = ((next.floor()) as usize).min(last - k);
                if ahead == 0 {
                    (k, 1.0)
                } else {
                    (k + ahead, (next - ahead as f32).clamp(0.0, 1.0))
                }
            } else {
                (k, next)
            };
            let (kn, un) = self.settled(kn, un);
            let (cn, dn) = self.point_and_tangent(kn, un);
            let d = cn.distance_squared(x);
            if d < best {
                (best, k, u, c, dc) = (d, kn, un, cn, dn);
            } else {
                break;
            }
        }
        let t = self.param(k, u);
        (
            Closest {
                piece: k,
                u,
                t,
                point: c,
            },
            best,
        )
    }

    /// The curve parameter `t = (k + u) / m` of local parameter `u` on piece `k` (in `f64`,
    /// rounded once).
    #[inline(always)]
    pub(crate) fn param(&self, k: usize, u: f32) -> f32 {
        ((k as f64 + f64::from(u)) / self.count as f64) as f32
    }

    /// `(k, u)` with the end of an inner piece written as the start of the next one, so that
    /// a knot belongs to the span after it, as in [`crate::basis::KnotVector::span`].
    #[inline]
    fn settled(&self, k: usize, u: f32) -> (usize, f32) {
        if u >= 1.0 && k + 1 < self.count {
            (k + 1, 0.0)
        } else {
            (k, u)
        }
    }

    /// The first non-zero point and segment function on piece `k` (the same index: the
    /// B-spline's knot span minus the degree, or 0 for Bézier).
    #[must_use]
    pub fn first(&self, k: usize) -> usize {
        self.firsts[k] as usize
    }

    /// The `p + 1` point basis values at `u` of piece `k`, then the `p` segment basis
    /// values, written to `out[..2p + 1]`.
    ///
    /// # Panics
    /// When `out` is shorter than `2p + 1`.
    pub fn weights(&self, k: usize, u: f32, out: &mut [f32]) {
        let p = self.degree;
        if u >= 1.0 && k + 1 == self.count {
            out[..=2 * p].copy_from_slice(&self.end);
            return;
        }
        let pb = &self.point_basis[k * (p + 1) * (p + 1)..(k + 1) * (p + 1) * (p + 1)];
        for (o, c) in out[..=p].iter_mut().zip(pb.chunks_exact(p + 1)) {
            *o = horner(c, u);
        }
        if p >= 1 {
            let sb = &self.segment_basis[k * p * p..(k + 1) * p * p];
            for (o, c) in out[p + 1..=2 * p].iter_mut().zip(sb.chunks_exact(p)) {
                *o = horner(c, u);
            }
        }
    }
}

/// The basis functions of a clamped uniform B-spline knot vector in power-form pieces (as a
/// [`CurvePieces`] holds them): their values and derivatives by Horner's rule. The shape
/// surface binds with one per parameter direction.
#[derive(Debug, Clone)]
pub struct BasisPieces {
    /// The degree `p`.
    degree: usize,
    /// Number of pieces `m`.
    count: usize,
    /// Per piece, `p + 1` functions × `p + 1` coefficients.
    coeffs: Vec<f32>,
    /// Per piece, its first non-zero function.
    firsts: Vec<u32>,
    /// The `p + 1` values at `t = 1` exactly (every function but the last 0).
    end: Vec<f32>,
    /// For a degree up to 3, per piece `p + 1` rows: row `i` holds coefficient `i` of every
    /// function (0 past the last), so that Horner's rule runs on all of them in one SIMD
    /// vector; empty for higher degrees.
    rows: Vec<Vec4>,
}

impl BasisPieces {
    /// The pieces of `knots` (clamped uniform, as [`KnotVector::clamped_uniform`] builds):
    /// 16 per control point, every knot a piece boundary, fewer per span on a long knot
    /// vector. `None` when even 2 pieces per span would pass the table budget (16 MiB;
    /// thousands of control points at a high degree): the caller evaluates the recurrence.
    ///
    /// [`KnotVector::clamped_uniform`]: crate::basis::KnotVector::clamped_uniform
    #[must_use]
    pub fn new(knots: &crate::basis::KnotVector) -> Option<Self> {
        let (p, n) = (knots.degree(), knots.count());
        let spans = n - p;
        let floats = (p + 1) * (p + 1);
        if spans * 2 * floats > TABLE_BUDGET {
            return None;
        }
        let per_span = pieces_per_span(n, spans, floats);
        let count = spans * per_span;
        let kv = knots_f64(p, spans);
        let nodes = interpolation_nodes(p + 1);
        let basis = |span: usize| {
            let kv = &kv;
            move |t: f64, out: &mut [f64]| basis_at_span(kv, p, t, span + p, out)
        };
        let mut coeffs = Vec::with_capacity(count * floats);
        let mut firsts = Vec::with_capacity(count);
        for k in 0..count {
            let span = k / per_span;
            let (t0, h) = (k as f64 / count as f64, 1.0 / count as f64);
            let functions = piece_functions(&nodes, p + 1, t0, h, basis(span));
            coeffs.extend(functions.iter().flatten().map(|&c| c as f32));
            firsts.push(span as u32);
        }
        let mut end = [0.0_f64; 17];
        basis(spans - 1)(1.0, &mut end);
        let mut rows = Vec::new();
        if p < 4 {
            for piece in coeffs.chunks_exact(floats) {
                for i in 0..=p {
                    let mut row = [0.0; 4];
                    for (r, c) in row.iter_mut().zip(piece.chunks_exact(p + 1)) {
                        *r = c[i];
                    }
                    rows.push(Vec4::from_array(row));
                }
            }
        }
        Some(Self {
            degree: p,
            count,
            coeffs,
            firsts,
            end: end[..=p].iter().map(|&v| v as f32).collect(),
            rows,
        })
    }

    /// The piece of `t` clamped to `[0, 1]`, its local parameter `u ∈ [0, 1]` and the
    /// clamped `t`. The end of an inner piece is the start of the next (a knot belongs to the
    /// span after it, as in `KnotVector::span`).
    #[inline(always)]
    fn piece_of(&self, t: f32) -> (usize, f32, f32) {
        // Through `u32`, whose conversions from and to `f32` take fewer instructions than
        // those of `usize`: the table budget keeps the count at most `2²⁰`, where both are
        // exact, and `scaled ∈ [0, m]` or NaN truncates to the same `k` either way.
        let m = self.count as u32;
        let t = t.clamp(0.0, 1.0);
        let scaled = t * m as f32;
        let k = (scaled as u32).min(m - 1) as usize;
        let u = (scaled - k as u32 as f32).clamp(0.0, 1.0);
        if u >= 1.0 && k + 1 < self.count {
            (k + 1, 0.0, t)
        } else {
            (k, u, t)
        }
    }

    /// The index of the first non-zero function at `t` (clamped to `[0, 1]`), as
    /// [`BasisPieces::values_and_derivatives`] returns it, without the values.
    #[inline]
    #[must_use]
    pub fn first_at(&self, t: f32) -> usize {
        self.firsts[self.piece_of(t).0] as usize
    }

    /// For a degree up to 3, [`BasisPieces::values_and_derivatives`] in the lanes of two
    /// vectors (lanes past `p` are 0 for a finite `t`) with the index of the first function;
    /// `None` for a higher degree.
    #[inline(always)]
    #[must_use]
    pub fn values_and_derivatives4(&self, t: f32) -> Option<(usize, Vec4, Vec4)> {
        if self.rows.is_empty() {
            return None;
        }
        let p = self.degree;
        let (k, u, t) = self.piece_of(t);
        // Every function at once, each lane doing the scalar loop's operations below.
        let rows = &self.rows[k * (p + 1)..(k + 1) * (p + 1)];
        // Cubic (the Add menu's surfaces) with a length known here, so that the inlined loop
        // is unrolled; the same operations either way.
        let (mut y, dy) = match <&[Vec4; 4]>::try_from(rows) {
            Ok(rows) => horner_with_derivative(rows, u),
            Err(_) => horner_with_derivative(rows, u),
        };
        if t >= 1.0 {
            let mut end = [0.0; 4];
            for (e, &v) in end.iter_mut().zip(&self.end) {
                *e = v;
            }
            y = Vec4::from_array(end);
        }
        Some((self.firsts[k] as usize, y, dy * self.count as u32 as f32))
    }

    /// The `p + 1` non-zero functions at `t` (clamped to `[0, 1]`) and their derivatives
    /// with respect to `t`, written to `values[..=p]` and `derivs[..=p]`; returns the index
    /// of the first.
    ///
    /// # Panics
    /// When `values` or `derivs` is shorter than `p + 1`.
    pub fn values_and_derivatives(&self, t: f32, values: &mut [f32], derivs: &mut [f32]) -> usize {
        let p = self.degree;
        if let Some((first, y, dy)) = self.values_and_derivatives4(t) {
            copy_prefix(&mut values[..=p], &y.to_array());
            copy_prefix(&mut derivs[..=p], &dy.to_array());
            return first;
        }
        let (k, u, t) = self.piece_of(t);
        let m = self.count as f32;
        let c = &self.coeffs[k * (p + 1) * (p + 1)..(k + 1) * (p + 1) * (p + 1)];
        for ((v, d), a) in values[..=p]
            .iter_mut()
            .zip(derivs[..=p].iter_mut())
            .zip(c.chunks_exact(p + 1))
        {
            // Horner for the value and its derivative together.
            let (mut y, mut dy) = (0.0_f32, 0.0_f32);
            for &aj in a.iter().rev() {
                dy = dy * u + y;
                y = y * u + aj;
            }
            *v = y;
            *d = dy * m;
        }
        if t >= 1.0 {
            values[..=p].copy_from_slice(&self.end);
        }
        self.firsts[k] as usize
    }
}

/// `(Σⱼ rⱼ uʲ, Σⱼ j rⱼ uʲ⁻¹)` of the rows `rⱼ` of every function at once, by Horner's rule
/// for the value and its derivative together.
#[inline(always)]
fn horner_with_derivative(rows: &[Vec4], u: f32) -> (Vec4, Vec4) {
    let uu = Vec4::splat(u);
    let (mut y, mut dy) = (Vec4::ZERO, Vec4::ZERO);
    for &a in rows.iter().rev() {
        dy = dy * uu + y;
        y = y * uu + a;
    }
    (y, dy)
}

/// `Σⱼ cⱼ uʲ` by Horner's rule. Separate products and sums, not `mul_add`: the baseline
/// x86-64 target has no fused multiply–add instruction, and `mul_add` becomes a call to a
/// software `fmaf`.
#[inline]
fn horner(c: &[f32], u: f32) -> f32 {
    c.iter().rev().fold(0.0, |acc, &a| acc * u + a)
}

/// `Σⱼ aⱼ uʲ` for vectors, by Horner's rule (separate products and sums, as [`horner`]).
#[inline]
fn horner3(a: &[Vec3], u: f32) -> Vec3 {
    a.iter().rev().fold(Vec3::ZERO, |acc, &c| acc * u + c)
}

/// The `len` functions `eval` writes at a parameter, on the piece `[t0, t0 + h]`: each
/// sampled at `nodes` (in the piece's local parameter) and put in power form, snapped —
/// `len` rows of `nodes.len()` coefficients.
fn piece_functions(
    nodes: &[f64],
    len: usize,
    t0: f64,
    h: f64,
    eval: impl Fn(f64, &mut [f64]),
) -> Vec<Vec<f64>> {
    let mut values = [0.0_f64; 17];
    let mut samples = vec![vec![0.0; nodes.len()]; len];
    for (j, &u) in nodes.iter().enumerate() {
        eval(t0 + h * u, &mut values);
        for (row, v) in samples.iter_mut().zip(&values) {
            row[j] = *v;
        }
    }
    samples
        .iter()
        .map(|s| snapped(power_form(nodes, s)))
        .collect()
}

/// `n` evenly spaced nodes in `(0, 1)`: `(2j + 1) / 2n`. Only additions, products and
/// divisions reach the coefficients, so every platform computes the same bits (a cosine for
/// Chebyshev nodes would depend on the platform's `libm`). At degree 15 even spacing
/// magnifies the `f64` rounding by at most a few thousand — far below an `f32` ulp.
fn interpolation_nodes(n: usize) -> Vec<f64> {
    (0..n)
        .map(|j| (2 * j + 1) as f64 / (2 * n) as f64)
        .collect()
}

/// The power-form coefficients of the polynomial of degree `< nodes.len()` taking
/// `values[j]` at `nodes[j]`: Newton's divided differences, then the Newton form expanded
/// from its innermost factor.
fn power_form(nodes: &[f64], values: &[f64]) -> Vec<f64> {
    let d = nodes.len() - 1;
    let mut c = values.to_vec();
    for k in 1..=d {
        for j in (k..=d).rev() {
            c[j] = (c[j] - c[j - 1]) / (nodes[j] - nodes[j - k]);
        }
    }
    // a(u) ← a(u)·(u − x_k) + c_k, from k = d − 1 down to 0.
    let mut a = vec![0.0; d + 1];
    a[0] = c[d];
    for k in (0..d).rev() {
        let r = d - 1 - k; // the degree of a before this step
        a[r + 1] = a[r];
        for j in (1..=r).rev() {
            a[j] = a[j - 1] - nodes[k] * a[j];
        }
        a[0] = c[k] - nodes[k] * a[0];
    }
    a
}

/// Basis coefficients rounded to 0 below `1e-13`: a basis function (at most 1) that vanishes
/// at a piece's start to some order has those coefficients exactly 0, so it is exactly 0
/// there as the recurrence gives it (the interpolation leaves about `1e-17`). The rounding
/// moves a value by at most `(p + 1)·1e-13` absolute: nothing next to the values near 1 that
/// move a vertex, though a degree-15 function in the first pieces of its support (true values
/// of `1e-26` and less) becomes exactly 0.
fn snapped(mut a: Vec<f64>) -> Vec<f64> {
    for c in &mut a {
        if c.abs() < 1e-13 {
            *c = 0.0;
        }
    }
    a
}

/// The knots of the clamped uniform B-spline of degree `p` with `spans` knot spans, in `f64`
/// (as [`crate::basis::KnotVector::clamped_uniform`] builds them in `f32`).
fn knots_f64(p: usize, spans: usize) -> Vec<f64> {
    let mut knots = vec![0.0; p + 1];
    knots.extend((1..spans).map(|j| j as f64 / spans as f64));
    knots.extend(std::iter::repeat_n(1.0, p + 1));
    knots
}

/// The non-zero basis functions at `t` inside knot span `span`, in `f64`: with `lower = 0`
/// the curve's `p + 1` point functions (Bernstein of degree `n − 1`, or the B-spline of
/// degree `p` on `knots`, the curve's knots from [`knots_f64`]); with `lower = 1` its `p`
/// segment functions (degree one less over the `n − 1` segments: the same interior knots).
fn basis_f64(
    basis: CurveBasis,
    n: usize,
    knots: &[f64],
    lower: usize,
    span: usize,
    t: f64,
    out: &mut [f64],
) {
    match basis {
        CurveBasis::Bezier => bernstein_all(n - 1 - lower, t, out),
        CurveBasis::BSpline { degree } => {
            let q = degree - lower;
            basis_at_span(&knots[lower..knots.len() - lower], q, t, span + q, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn wiggle(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let s = i as f32;
                Vec3::new(s, (1.3 * s).sin() * 0.8, (0.7 * s).cos() * 0.5)
            })
            .collect()
    }

    fn bases() -> Vec<(CurveBasis, usize)> {
        let mut b = vec![
            (CurveBasis::Bezier, 2),
            (CurveBasis::Bezier, 5),
            (CurveBasis::Bezier, 16),
        ];
        for (p, n) in [
            (1, 2),
            (1, 7),
            (2, 5),
            (3, 5),
            (3, 8),
            (3, 40),
            (5, 9),
            (15, 16),
        ] {
            b.push((CurveBasis::BSpline { degree: p }, n));
        }
        b
    }

    #[test]
    fn power_form_interpolates_a_known_polynomial() {
        let nodes = interpolation_nodes(4);
        let f = |u: f64| 2.0 - 3.0 * u + 0.5 * u * u + 7.0 * u * u * u;
        let values: Vec<f64> = nodes.iter().map(|&u| f(u)).collect();
        let a = power_form(&nodes, &values);
        for (got, want) in a.iter().zip([2.0, -3.0, 0.5, 7.0]) {
            assert!((got - want).abs() < 1e-12, "{a:?}");
        }
    }

    #[test]
    fn pieces_match_the_evaluator_points_tangents_and_weights() {
        for (basis, n) in bases() {
            let ctrl = wiggle(n);
            let ev = CurveEvaluator::new(basis, n, "test").unwrap();
            let pieces = CurvePieces::new(&ev, &ctrl);
            let p = ev.degree();
            let m = pieces.count();
            let mut w = vec![0.0; 2 * p + 1];
            for k in 0..m {
                // Interior parameters, and the two ends of the curve (an inner boundary may
                // be a knot, which the evaluator gives to either side by its rounding).
                let mut us = vec![0.3, 0.77];
                if k == 0 {
                    us.push(0.0);
                }
                if k + 1 == m {
                    us.push(1.0);
                }
                for u in us {
                    let t = ((k as f64 + f64::from(u)) / m as f64) as f32;
                    let (c, d) = pieces.point_and_tangent(k, u);
                    let (ce, de) = ev.point_and_derivative(&ctrl, t);
                    assert!(
                        c.distance(ce) < 2e-5 * n as f32,
                        "{basis:?} {n}: C at piece {k} u {u}"
                    );
                    // dC/du = dC/dt · h.
                    let de = de / m as f32;
                    assert!(
                        d.distance(de) < 1e-4 * de.length().max(1e-3),
                        "{basis:?} {n}: C' at piece {k} u {u}: {d} vs {de}"
                    );
                    pieces.weights(k, u, &mut w);
                    let (pw, sw) = (ev.point_weights(t), ev.segment_weights(t));
                    assert_eq!(
                        pieces.first(k),
                        pw.first,
                        "{basis:?} {n}: first at piece {k}"
                    );
                    assert_eq!(pieces.first(k), sw.first, "{basis:?} {n}: segment first");
                    for i in 0..=p {
                        assert!((w[i] - pw.values[i]).abs() < 2e-5, "{basis:?} {n}: N{i}");
                    }
                    for i in 0..p {
                        assert!(
                            (w[p + 1 + i] - sw.values[i]).abs() < 2e-5,
                            "{basis:?} {n}: M{i}"
                        );
                    }
                }
            }
        }
    }

    /// Up to degree 3 the functions run in one SIMD vector: the bits of the scalar loop.
    #[test]
    fn basis_pieces_in_a_vector_have_the_scalar_bits() {
        use crate::basis::KnotVector;
        // Degree 4 has more functions than a vector: no rows.
        let quartic = BasisPieces::new(&KnotVector::clamped_uniform(4, 6).unwrap()).unwrap();
        assert!(quartic.rows.is_empty());
        for (p, n) in [(1, 2), (2, 4), (3, 4), (3, 9)] {
            let pieces = BasisPieces::new(&KnotVector::clamped_uniform(p, n).unwrap()).unwrap();
            assert!(!pieces.rows.is_empty(), "p {p}: in a vector");
            let mut scalar = pieces.clone();
            scalar.rows.clear();
            let (mut v, mut d, mut vs, mut ds) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
            for s in -20..=1020 {
                let t = s as f32 / 1000.0;
                let first = pieces.values_and_derivatives(t, &mut v, &mut d);
                let first_scalar = scalar.values_and_derivatives(t, &mut vs, &mut ds);
                assert_eq!(first, first_scalar, "p {p} n {n} t {t}");
                assert_eq!(
                    v.map(f32::to_bits),
                    vs.map(f32::to_bits),
                    "p {p} n {n} t {t}: N"
                );
                assert_eq!(
                    d.map(f32::to_bits),
                    ds.map(f32::to_bits),
                    "p {p} n {n} t {t}: N'"
                );
            }
        }
    }

    #[test]
    fn basis_pieces_match_the_recurrence() {
        use crate::basis::KnotVector;
        for (p, n) in [(1, 2), (2, 4), (3, 4), (3, 9), (5, 7), (15, 16)] {
            let kv = KnotVector::clamped_uniform(p, n).unwrap();
            let pieces = BasisPieces::new(&kv).unwrap();
            let (mut v, mut d) = ([0.0; 16], [0.0; 16]);
            let (mut ve, mut de) = ([0.0; 16], [0.0; 16]);
            for s in 0..=997 {
                let t = s as f32 / 997.0;
                let first = pieces.values_and_derivatives(t, &mut v, &mut d);
                let span = kv.basis_with_derivative(t, &mut ve, &mut de);
                // Near a knot the two may take the span on either side: compare the functions.
                let mut full = [0.0_f32; 32];
                let mut full_e = [0.0_f32; 32];
                let (mut fd, mut fde) = ([0.0_f32; 32], [0.0_f32; 32]);
                for i in 0..=p {
                    full[first + i] = v[i];
                    fd[first + i] = d[i];
                    full_e[span - p + i] = ve[i];
                    fde[span - p + i] = de[i];
                }
                let scale = (n - p) as f32 * p as f32;
                for i in 0..n {
                    assert!(
                        (full[i] - full_e[i]).abs() < 2e-5,
                        "p {p} n {n} t {t}: N{i}"
                    );
                    assert!(
                        (fd[i] - fde[i]).abs() < 2e-4 * scale.max(1.0),
                        "p {p} n {n} t {t}: N'{i} {} vs {}",
                        fd[i],
                        fde[i]
                    );
                }
            }
            // Exactly 1 and 0 at the ends.
            let first = pieces.values_and_derivatives(0.0, &mut v, &mut d);
            assert_eq!(
                (first, &v[..=p]),
                (
                    0,
                    &{
                        let mut e = [0.0; 16];
                        e[0] = 1.0;
                        e
                    }[..=p]
                )
            );
            let first = pieces.values_and_derivatives(1.0, &mut v, &mut d);
            assert_eq!(first, n - 1 - p);
            assert_eq!(v[p], 1.0);
            assert!(v[..p].iter().all(|&x| x == 0.0));
        }
    }

    #[test]
    fn long_high_degree_knot_vectors_keep_their_tables_small() {
        use crate::basis::KnotVector;
        // A curve at the limits: 4096 points of degree 15 gets 2 pieces per span.
        let n = crate::curve::MAX_CURVE_POINTS;
        let ctrl: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(i as f32 * 0.01, (i as f32 * 0.05).sin(), 0.0))
            .collect();
        let ev = CurveEvaluator::new(CurveBasis::BSpline { degree: 15 }, n, "test").unwrap();
        let pieces = CurvePieces::new(&ev, &ctrl);
        assert_eq!(pieces.count(), 2 * (n - 15));
        let floats = pieces.point_basis.len() + pieces.segment_basis.len();
        assert!(floats * 4 < 40 << 20, "{floats} coefficients");
        for k in 0..50 {
            let q = Vec3::new(k as f32 * 0.8, 0.3, 0.1);
            let (c, d2) = pieces.closest(q);
            assert!(d2.sqrt() <= brute_force_near(&pieces, c.piece, q).sqrt() + 1e-4);
        }
        // A basis too long for a table leaves it to the recurrence.
        let kv = KnotVector::clamped_uniform(15, 32_768).unwrap();
        assert!(BasisPieces::new(&kv).is_none());
        assert!(BasisPieces::new(&KnotVector::clamped_uniform(3, 4096).unwrap()).is_some());
    }

    /// The least squared distance to 65 samples of each piece within 40 of piece `k`.
    fn brute_force_near(pieces: &CurvePieces, k: usize, x: Vec3) -> f32 {
        let mut best = f32::INFINITY;
        for j in k.saturating_sub(40)..(k + 40).min(pieces.count()) {
            for s in 0..=64 {
                best = best.min(pieces.point(j, s as f32 / 64.0).distance_squared(x));
            }
        }
        best
    }

    /// The least squared distance to 65 samples of every piece.
    fn brute_force(pieces: &CurvePieces, x: Vec3) -> f32 {
        let mut best = f32::INFINITY;
        for k in 0..pieces.count() {
            for s in 0..=64 {
                let u = s as f32 / 64.0;
                best = best.min(pieces.point(k, u).distance_squared(x));
            }
        }
        best
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn closest_is_as_close_as_dense_sampling(
            which in 0usize..11,
            x in -2.0f32..9.0, y in -3.0f32..3.0, z in -3.0f32..3.0,
        ) {
            let (basis, n) = bases()[which];
            let ctrl = wiggle(n);
            let ev = CurveEvaluator::new(basis, n, "test").unwrap();
            let pieces = CurvePieces::new(&ev, &ctrl);
            let q = Vec3::new(x * n as f32 / 8.0, y, z);
            let (c, d2) = pieces.closest(q);
            prop_assert!((c.point.distance_squared(q) - d2).abs() <= 1e-6 * d2.max(1.0));
            let dense = brute_force(&pieces, q);
            // Never farther than the dense samples (up to rounding and, where two parts of
            // the curve are nearly as close, the sag of a piece's chord), and t agrees with
            // the piece.
            prop_assert!(d2.sqrt() <= dense.sqrt() + 2e-3, "{d2} vs {dense}");
            let t = (c.piece as f32 + c.u) / pieces.count() as f32;
            prop_assert!((t - c.t).abs() < 1e-6);
        }
    }
}
