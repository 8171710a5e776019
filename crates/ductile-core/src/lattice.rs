//! Lattice free-form deformation (the survey's 3-D tools, Bechmann §2): Sederberg–Parry FFD
//! with a Bernstein basis (§2.1), B-spline ("NURBS-based") lattices with local support
//! (§2.4) and rational weights per control point (§2.3). `docs/algorithms/lattice.md` gives
//! the equations and every decision taken.
//!
//! The lattice is an oriented parallelepiped: origin `U₀` and edge vectors `S, T, U`. A
//! point `X` has lattice coordinates (Sederberg & Parry; the survey prints `S∧T` in all three
//! formulas, a typo)
//!
//! `u₁ = (T∧U)·(X − U₀) / ((T∧U)·S)`, `u₂ = (U∧S)·(X − U₀) / ((U∧S)·T)`,
//! `u₃ = (S∧T)·(X − U₀) / ((S∧T)·U)`,
//!
//! and, inside the lattice (`0 ≤ uᵢ ≤ 1`), the deformed position is (survey §2.3)
//!
//! `D(X) = Σᵢⱼₖ W_ijk P_ijk Bᵢ(u₁) Bⱼ(u₂) Bₖ(u₃) / Σᵢⱼₖ W_ijk Bᵢ(u₁) Bⱼ(u₂) Bₖ(u₃)`,
//!
//! which with all weights 1 is the plain FFD `D(X) = Σ P_ijk Bᵢ Bⱼ Bₖ` (§2.1), because the
//! bases are a partition of unity. The rest control points sit at the Greville abscissae
//! of each axis (`i/p` for Bernstein), so the undeformed lattice is the identity. The
//! non-rational case is evaluated in the equivalent displacement form
//! `D(X) = X + Σ ΔP_ijk Bᵢ Bⱼ Bₖ` (`ΔP` = control point offsets), which makes the
//! undeformed lattice the identity bit for bit.

use glam::{Affine3A, Vec3, Vec4};
use serde::{Deserialize, Serialize};

mod simd;
mod sparse;

use crate::basis::{KnotVector, MAX_DEGREE, bernstein_all};
use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::tool::{BindInput, Deformer, uniform_scale};

/// Largest number of control points a lattice may have in total.
pub const MAX_CONTROL_POINTS: usize = 1 << 18;

/// The oriented parallelepiped of a lattice: origin `U₀` and edge vectors `S, T, U`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeFrame {
    /// The corner `U₀` (lattice coordinates `(0, 0, 0)`).
    pub origin: Vec3,
    /// Edge vector `S` (from `U₀` to lattice coordinates `(1, 0, 0)`).
    pub s: Vec3,
    /// Edge vector `T` (to `(0, 1, 0)`).
    pub t: Vec3,
    /// Edge vector `U` (to `(0, 0, 1)`).
    pub u: Vec3,
}

impl LatticeFrame {
    /// An axis-aligned frame spanning the box `[min, max]`.
    #[must_use]
    pub fn from_box(min: Vec3, max: Vec3) -> Self {
        let d = max - min;
        Self {
            origin: min,
            s: Vec3::new(d.x, 0.0, 0.0),
            t: Vec3::new(0.0, d.y, 0.0),
            u: Vec3::new(0.0, 0.0, d.z),
        }
    }

    /// The point of lattice coordinates `c`: `U₀ + c₁ S + c₂ T + c₃ U`.
    #[must_use]
    pub fn point(&self, c: Vec3) -> Vec3 {
        self.origin + self.s * c.x + self.t * c.y + self.u * c.z
    }

    /// The rows `(T∧U)/((T∧U)·S)`, `(U∧S)/((U∧S)·T)`, `(S∧T)/((S∧T)·U)` of the inverse frame,
    /// or an error when the frame is degenerate (`|S·(T∧U)| ≤ 10⁻⁶ |S||T||U|`).
    pub fn inverse_rows(&self, what: &str) -> Result<[Vec3; 3]> {
        check_finite_vec3(|| format!("{what}: origin"), self.origin)?;
        check_finite_vec3(|| format!("{what}: s"), self.s)?;
        check_finite_vec3(|| format!("{what}: t"), self.t)?;
        check_finite_vec3(|| format!("{what}: u"), self.u)?;
        let tu = self.t.cross(self.u);
        let us = self.u.cross(self.s);
        let st = self.s.cross(self.t);
        let det = self.s.dot(tu);
        let scale = self.s.length() * self.t.length() * self.u.length();
        if !det.is_finite() || det.abs() <= 1e-6 * scale {
            return Err(CoreError::Degenerate {
                what: what.to_string(),
                problem: format!(
                    "the lattice frame is degenerate (S·(T∧U) = {det}, |S||T||U| = {scale}); \
                     the edge vectors S, T, U must be non-zero and not coplanar"
                ),
            });
        }
        // (T∧U)·S = (U∧S)·T = (S∧T)·U = det.
        Ok([tu / det, us / det, st / det])
    }
}

/// The basis of a lattice.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum LatticeBasis {
    /// Sederberg–Parry: Bernstein polynomials of degree `count − 1` per axis.
    #[default]
    Bernstein,
    /// B-splines of the given degree per axis over clamped uniform knots (local support).
    BSpline {
        /// Degree per axis `(p₁, p₂, p₃)`, each in `1..count` (order = degree + 1).
        degree: (u32, u32, u32),
    },
}

/// An edit of one control point: its offset from the rest position and its rational weight.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlEdit {
    /// Control point index `(i, j, k)` along `S, T, U`.
    pub at: (u32, u32, u32),
    /// Offset of the control point from its rest position (tool space).
    #[serde(default)]
    pub offset: Vec3,
    /// Rational weight `W_ijk > 0` (1: non-rational).
    #[serde(default = "one")]
    pub weight: f32,
}

fn one() -> f32 {
    1.0
}

/// A lattice FFD tool: frame, control point counts, basis, control point edits and an
/// optional outside falloff.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeTool {
    /// The rest parallelepiped.
    pub frame: LatticeFrame,
    /// Control points per axis `(l + 1, m + 1, n + 1)`, each ≥ 2.
    pub counts: (u32, u32, u32),
    /// Bernstein (default) or B-spline basis.
    #[serde(default)]
    pub basis: LatticeBasis,
    /// Moved or weighted control points; all others stay at rest with weight 1.
    #[serde(default)]
    pub points: Vec<ControlEdit>,
    /// Outside falloff distance (tool units, ≥ 0): points outside the lattice closer than
    /// this to it move by the displacement at the nearest lattice point, scaled by a smooth
    /// step from 1 (on the lattice) to 0 (at the distance). 0: points outside stay put.
    #[serde(default)]
    pub falloff: f32,
}

impl LatticeTool {
    /// An undeformed Bernstein lattice over `frame` with `counts` control points.
    #[must_use]
    pub fn bernstein(frame: LatticeFrame, counts: (u32, u32, u32)) -> Self {
        Self {
            frame,
            counts,
            basis: LatticeBasis::Bernstein,
            points: Vec::new(),
            falloff: 0.0,
        }
    }

    /// An undeformed B-spline lattice of the given degree per axis.
    #[must_use]
    pub fn bspline(frame: LatticeFrame, counts: (u32, u32, u32), degree: (u32, u32, u32)) -> Self {
        Self {
            basis: LatticeBasis::BSpline { degree },
            ..Self::bernstein(frame, counts)
        }
    }

    /// Sets the offset of control point `at` (adds an edit or changes the existing one).
    pub fn set_offset(&mut self, at: (u32, u32, u32), offset: Vec3) {
        match self.points.iter_mut().find(|e| e.at == at) {
            Some(e) => e.offset = offset,
            None => self.points.push(ControlEdit {
                at,
                offset,
                weight: 1.0,
            }),
        }
    }

    /// Sets the rational weight of control point `at`.
    pub fn set_weight(&mut self, at: (u32, u32, u32), weight: f32) {
        match self.points.iter_mut().find(|e| e.at == at) {
            Some(e) => e.weight = weight,
            None => self.points.push(ControlEdit {
                at,
                offset: Vec3::ZERO,
                weight,
            }),
        }
    }

    /// Counts as an array.
    #[must_use]
    pub fn count_array(&self) -> [usize; 3] {
        [
            self.counts.0 as usize,
            self.counts.1 as usize,
            self.counts.2 as usize,
        ]
    }

    /// Validates and prepares the lattice for evaluation (what the bind holds).
    pub fn prepare(&self, what: &str) -> Result<PreparedLattice> {
        self.validate(what)?;
        PreparedLattice::new(self, what)
    }
}

/// The basis of one lattice axis, ready to evaluate.
#[derive(Debug, Clone, PartialEq)]
enum AxisBasis {
    Bernstein(usize),
    BSpline(KnotVector),
}

impl AxisBasis {
    fn new(basis: &LatticeBasis, axis: usize, count: usize) -> Option<Self> {
        match basis {
            LatticeBasis::Bernstein => {
                (count >= 2 && count - 1 <= MAX_DEGREE).then_some(Self::Bernstein(count - 1))
            }
            LatticeBasis::BSpline { degree } => {
                let p = [degree.0, degree.1, degree.2][axis] as usize;
                if p > MAX_DEGREE {
                    return None;
                }
                KnotVector::clamped_uniform(p, count).map(Self::BSpline)
            }
        }
    }

    /// Writes the non-zero basis values at `t ∈ [0, 1]` into `out` and returns
    /// `(first index, number of values)`.
    #[inline]
    fn eval(&self, t: f32, out: &mut [f32; MAX_DEGREE + 1]) -> (usize, usize) {
        match self {
            AxisBasis::Bernstein(n) => {
                bernstein_all(*n, t, out);
                (0, n + 1)
            }
            AxisBasis::BSpline(kv) => {
                let p = kv.degree();
                let s = kv.basis(t, out);
                (s - p, p + 1)
            }
        }
    }

    /// [`AxisBasis::eval`] for exactly `L` non-zero values (the caller checked `L`).
    #[inline(always)]
    fn eval_fixed<const L: usize>(&self, t: f32) -> ([f32; L], usize) {
        let mut out = [0.0_f32; L];
        match self {
            AxisBasis::Bernstein(_) => {
                bernstein_all(L - 1, t, &mut out);
                (out, 0)
            }
            AxisBasis::BSpline(kv) => {
                let mut b = [0.0_f32; MAX_DEGREE + 1];
                let s = kv.basis(t, &mut b);
                out.copy_from_slice(&b[..L]);
                (out, s + 1 - L)
            }
        }
    }

    /// The Greville abscissa of control point `i`: `i/p` for Bernstein,
    /// `(κ_{i+1} + … + κ_{i+p}) / p` for B-splines. Placing the rest control points there
    /// makes the rest lattice reproduce linear functions exactly (linear precision).
    fn greville(&self, i: usize) -> f32 {
        match self {
            AxisBasis::Bernstein(n) => i as f32 / *n as f32,
            AxisBasis::BSpline(kv) => {
                let p = kv.degree();
                let k = kv.knots();
                k[i + 1..=i + p].iter().sum::<f32>() / p as f32
            }
        }
    }
}

/// A validated lattice ready to evaluate: inverse frame, per-axis bases and dense control
/// data. It is the bind of a [`LatticeTool`] and the evaluator Direct FFD reuses.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedLattice {
    frame: LatticeFrame,
    rows: [Vec3; 3],
    axes: [AxisBasis; 3],
    counts: [usize; 3],
    /// Non-rational: `(ΔP, 0)`; rational: `(W·(P − U₀), W)`; index `i + l(j + m k)`.
    data: Vec<Vec4>,
    /// Dense offsets `ΔP` (kept to rebuild `data`).
    offsets: Vec<Vec3>,
    /// Dense weights `W`.
    weights: Vec<f32>,
    rational: bool,
    falloff: f32,
    /// The sum over the few moved control points, where it applies (`lattice/sparse.rs`).
    sparse: Option<sparse::Sparse>,
}

impl PreparedLattice {
    fn new(tool: &LatticeTool, what: &str) -> Result<Self> {
        let rows = tool.frame.inverse_rows(what)?;
        let counts = tool.count_array();
        let mut axes = Vec::with_capacity(3);
        for (a, &c) in counts.iter().enumerate() {
            axes.push(
                AxisBasis::new(&tool.basis, a, c).ok_or_else(|| CoreError::Degenerate {
                    what: what.to_string(),
                    problem: format!(
                        "axis {a}: {c} control points do not fit the basis {:?}",
                        tool.basis
                    ),
                })?,
            );
        }
        let axes: [AxisBasis; 3] = match axes.try_into() {
            Ok(a) => a,
            Err(_) => unreachable!("three axes were pushed"),
        };
        let total = counts[0] * counts[1] * counts[2];
        let mut offsets = vec![Vec3::ZERO; total];
        let mut weights = vec![1.0_f32; total];
        for e in &tool.points {
            let idx = e.at.0 as usize + counts[0] * (e.at.1 as usize + counts[1] * e.at.2 as usize);
            offsets[idx] = e.offset;
            weights[idx] = e.weight;
        }
        let mut me = Self {
            frame: tool.frame,
            rows,
            axes,
            counts,
            data: Vec::new(),
            offsets,
            weights,
            rational: false,
            falloff: tool.falloff,
            sparse: None,
        };
        me.rebuild();
        Ok(me)
    }

    /// Recomputes the dense evaluation data from `offsets` and `weights`.
    fn rebuild(&mut self) {
        self.rational = self.weights.iter().any(|&w| w != 1.0);
        let [l, m, _] = self.counts;
        self.data = (0..self.offsets.len())
            .map(|idx| {
                let d = self.offsets[idx];
                if self.rational {
                    let (i, j, k) = (idx % l, (idx / l) % m, idx / (l * m));
                    let w = self.weights[idx];
                    let q = self.rest_control_point(i, j, k) - self.frame.origin + d;
                    (q * w).extend(w)
                } else {
                    d.extend(0.0)
                }
            })
            .collect();
        self.sparse = sparse::Sparse::new(self);
    }

    /// Forces the rational evaluation path even when every weight is 1 (for tests).
    #[cfg(test)]
    fn force_rational(&mut self) {
        self.rebuild();
        self.rational = true;
        self.sparse = None;
        let [l, m, _] = self.counts;
        self.data = (0..self.offsets.len())
            .map(|idx| {
                let (i, j, k) = (idx % l, (idx / l) % m, idx / (l * m));
                let w = self.weights[idx];
                let q = self.rest_control_point(i, j, k) - self.frame.origin + self.offsets[idx];
                (q * w).extend(w)
            })
            .collect();
    }

    /// Control points per axis.
    #[must_use]
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    /// Total number of control points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    /// True when the lattice has no control points (never, once validated).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }

    /// The dense control point offsets `ΔP`, index `i + l(j + m k)`.
    #[must_use]
    pub fn offsets(&self) -> &[Vec3] {
        &self.offsets
    }

    /// Adds `delta[idx]` to every control point offset (Direct FFD's solved change).
    pub fn add_offsets(&mut self, delta: &[Vec3]) {
        for (o, d) in self.offsets.iter_mut().zip(delta) {
            *o += *d;
        }
        self.rebuild();
    }

    /// The rest position of control point `(i, j, k)`: the frame point at the Greville
    /// abscissae `(ξᵢ, ξⱼ, ξₖ)`.
    #[must_use]
    pub fn rest_control_point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.frame.point(Vec3::new(
            self.axes[0].greville(i),
            self.axes[1].greville(j),
            self.axes[2].greville(k),
        ))
    }

    /// The lattice coordinates `(u₁, u₂, u₃)` of `x`.
    #[inline]
    #[must_use]
    pub fn coords(&self, x: Vec3) -> Vec3 {
        let d = x - self.frame.origin;
        Vec3::new(
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        )
    }

    /// True when lattice coordinates `u` lie in the closed unit cube.
    #[inline]
    #[must_use]
    pub fn inside(u: Vec3) -> bool {
        u.cmpge(Vec3::ZERO).all() && u.cmple(Vec3::ONE).all()
    }

    /// The non-zero basis values of the three axes at `u ∈ [0, 1]³`, their first indices
    /// and their numbers.
    #[inline(always)]
    fn bases(&self, u: Vec3) -> ([[f32; MAX_DEGREE + 1]; 3], [usize; 3], [usize; 3]) {
        let mut b = [[0.0_f32; MAX_DEGREE + 1]; 3];
        let (sx, lx) = self.axes[0].eval(u.x, &mut b[0]);
        let (sy, ly) = self.axes[1].eval(u.y, &mut b[1]);
        let (sz, lz) = self.axes[2].eval(u.z, &mut b[2]);
        (b, [sx, sy, sz], [lx, ly, lz])
    }

    /// The tensor sum `Σ c_ijk Bᵢ(u₁) Bⱼ(u₂) Bₖ(u₃)` of the dense data at `u ∈ [0, 1]³`, for
    /// any number of non-zero basis functions per axis.
    #[inline]
    fn tensor(&self, u: Vec3) -> Vec4 {
        let (b, start, len) = self.bases(u);
        let [nx, ny, _] = self.counts;
        let bx = &b[0][..len[0]];
        let mut acc = Vec4::ZERO;
        for (k, &wk) in b[2][..len[2]].iter().enumerate() {
            let mut acc_j = Vec4::ZERO;
            for (j, &wj) in b[1][..len[1]].iter().enumerate() {
                let base = start[0] + nx * (start[1] + j + ny * (start[2] + k));
                let row = &self.data[base..base + len[0]];
                let mut acc_i = Vec4::ZERO;
                for (c, &wi) in row.iter().zip(bx) {
                    acc_i += *c * wi;
                }
                acc_j += acc_i * wj;
            }
            acc += acc_j * wk;
        }
        acc
    }

    /// [`PreparedLattice::tensor`] specialised to `L` non-zero basis functions on every axis
    /// (a compile-time size, so the loops unroll): the hot path of the common lattices.
    #[inline(always)]
    fn tensor_fixed<const L: usize>(&self, u: Vec3) -> Vec4 {
        let (bx, sx) = self.axes[0].eval_fixed::<L>(u.x);
        let (by, sy) = self.axes[1].eval_fixed::<L>(u.y);
        let (bz, sz) = self.axes[2].eval_fixed::<L>(u.z);
        let [nx, ny, _] = self.counts;
        let mut acc = Vec4::ZERO;
        for k in 0..L {
            let mut acc_j = Vec4::ZERO;
            for j in 0..L {
                let base = sx + nx * (sy + j + ny * (sz + k));
                let Ok(row) = <&[Vec4; L]>::try_from(&self.data[base..base + L]) else {
                    continue;
                };
                let mut acc_i = Vec4::ZERO;
                for i in 0..L {
                    acc_i += row[i] * bx[i];
                }
                acc_j += acc_i * by[j];
            }
            acc += acc_j * bz[k];
        }
        acc
    }

    /// The deformed position of the point `x` of lattice coordinates `u ∈ [0, 1]³`, given the
    /// tensor sum `acc` there.
    #[inline(always)]
    fn position_from_tensor(&self, x: Vec3, acc: Vec4) -> Vec3 {
        if self.rational {
            self.frame.origin + acc.truncate() / acc.w
        } else {
            x + acc.truncate()
        }
    }

    /// `D(x)` with the tensor sum `tensor`: the FFD inside the lattice, the outside falloff
    /// (or the identity) outside.
    #[inline(always)]
    fn deform_with(&self, x: Vec3, tensor: impl Fn(&Self, Vec3) -> Vec4) -> Vec3 {
        let u = self.coords(x);
        if Self::inside(u) {
            return self.position_from_tensor(x, tensor(self, u));
        }
        if self.falloff <= 0.0 {
            return x;
        }
        let uc = u.clamp(Vec3::ZERO, Vec3::ONE);
        let xc = self.frame.point(uc);
        let dist = x.distance(xc);
        if dist >= self.falloff {
            return x;
        }
        let s = 1.0 - dist / self.falloff;
        let w = s * s * (3.0 - 2.0 * s);
        x + (self.position_from_tensor(xc, tensor(self, uc)) - xc) * w
    }

    /// The deformed position `D(x)`: the FFD inside the lattice; outside, the identity, or
    /// with a falloff distance `δ > 0`, `x + σ(1 − d/δ)·(D(x_c) − x_c)` where `x_c` is the
    /// lattice point at the clamped coordinates, `d = |x − x_c|` and `σ(s) = 3s² − 2s³`.
    /// The same bits as [`PreparedLattice::deform_slice`] gives the point.
    #[must_use]
    pub fn deform_point(&self, x: Vec3) -> Vec3 {
        if self.sparse.is_some() {
            return self.deform_with(x, Self::sparse_tensor);
        }
        if self.has_block_kernel() {
            let mut out = [x];
            self.deform_slice(&[x], &[0], &mut out);
            return out[0];
        }
        self.deform_with(x, Self::tensor)
    }

    /// The number of non-zero basis functions per axis when it is the same on all three.
    fn uniform_len(&self) -> Option<usize> {
        let len = |a: &AxisBasis| match a {
            AxisBasis::Bernstein(n) => n + 1,
            AxisBasis::BSpline(kv) => kv.degree() + 1,
        };
        let l = len(&self.axes[0]);
        (len(&self.axes[1]) == l && len(&self.axes[2]) == l).then_some(l)
    }

    /// The coefficients `a_ijk(x) = W_ijk Bᵢ Bⱼ Bₖ / Σ W B B B` with which each control point
    /// enters `D(x)` (the row of the Direct FFD system), written densely to `out`
    /// (length [`PreparedLattice::len`]). Returns false when `x` lies outside the lattice.
    pub fn coefficients(&self, x: Vec3, out: &mut [f64]) -> bool {
        out.iter_mut().for_each(|o| *o = 0.0);
        let u = self.coords(x);
        if !Self::inside(u) {
            return false;
        }
        let mut b = [[0.0_f32; MAX_DEGREE + 1]; 3];
        let mut start = [0; 3];
        let mut len = [0; 3];
        for a in 0..3 {
            (start[a], len[a]) = self.axes[a].eval(u[a], &mut b[a]);
        }
        let [nx, ny, _] = self.counts;
        let mut total = 0.0_f64;
        for k in 0..len[2] {
            for j in 0..len[1] {
                for i in 0..len[0] {
                    let idx = start[0] + i + nx * (start[1] + j + ny * (start[2] + k));
                    let v = f64::from(self.weights[idx])
                        * f64::from(b[0][i])
                        * f64::from(b[1][j])
                        * f64::from(b[2][k]);
                    out[idx] = v;
                    total += v;
                }
            }
        }
        if total > 0.0 {
            out.iter_mut().for_each(|o| *o /= total);
        }
        true
    }

    /// Deforms `active` vertices of `positions` into `out`. A non-rational lattice with a few
    /// moved control points is summed over those alone (the `sparse` module); other
    /// lattices with the same number of basis functions (2 to 8) on every axis go through
    /// the block kernels (a point per SIMD lane, the `simd` module); the rest point by point.
    pub fn deform_slice(&self, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        if self.deform_slice_sparse(positions, active, out)
            || self.deform_slice_blocks(positions, active, out)
        {
            return;
        }
        match self.uniform_len() {
            Some(2) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<2>),
            Some(3) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<3>),
            Some(4) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<4>),
            Some(5) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<5>),
            Some(6) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<6>),
            Some(8) => self.deform_slice_with(positions, active, out, Self::tensor_fixed::<8>),
            _ => self.deform_slice_with(positions, active, out, Self::tensor),
        }
    }

    #[inline(always)]
    fn deform_slice_with(
        &self,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
        tensor: impl Fn(&Self, Vec3) -> Vec4 + Copy,
    ) {
        for (o, &i) in out.iter_mut().zip(active) {
            *o = self.deform_with(positions[i as usize], tensor);
        }
    }
}

impl Deformer for LatticeTool {
    type Bind = PreparedLattice;

    fn validate(&self, what: &str) -> Result<()> {
        self.frame.inverse_rows(what)?;
        let counts = self.count_array();
        for (a, &c) in counts.iter().enumerate() {
            if c < 2 {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: counts[{a}]"),
                    value: c as f64,
                    expected: "a lattice needs at least 2 control points per axis",
                });
            }
            if AxisBasis::new(&self.basis, a, c).is_none() {
                // Name both numbers: the count alone read as if the count were wrong.
                let problem = match self.basis {
                    LatticeBasis::Bernstein => format!(
                        "axis {a} has {c} control points; a Bernstein lattice has 2 to 16 per \
                         axis (degree = count − 1 ≤ 15)"
                    ),
                    LatticeBasis::BSpline { degree } => {
                        let p = [degree.0, degree.1, degree.2][a];
                        format!(
                            "axis {a} has degree {p} and {c} control points; a B-spline lattice \
                             needs 1 ≤ degree ≤ 15 and more control points than its degree"
                        )
                    }
                };
                return Err(CoreError::Degenerate {
                    what: what.to_owned(),
                    problem,
                });
            }
        }
        let total: usize = counts.iter().product();
        if total > MAX_CONTROL_POINTS {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: number of control points"),
                value: total as f64,
                expected: "must be at most 262144",
            });
        }
        check_finite(|| format!("{what}: falloff"), self.falloff)?;
        if self.falloff < 0.0 {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: falloff"),
                value: f64::from(self.falloff),
                expected: "must be ≥ 0",
            });
        }
        let mut seen = std::collections::HashSet::new();
        for (n, e) in self.points.iter().enumerate() {
            let w = format!("{what}: point edit {n} at {:?}", e.at);
            let at = [e.at.0 as usize, e.at.1 as usize, e.at.2 as usize];
            if at.iter().zip(&counts).any(|(i, c)| i >= c) {
                return Err(CoreError::Degenerate {
                    what: w,
                    problem: format!("the index is outside the {counts:?} control points"),
                });
            }
            if !seen.insert(e.at) {
                return Err(CoreError::Degenerate {
                    what: w,
                    problem: "the same control point is edited twice".to_string(),
                });
            }
            check_finite_vec3(|| format!("{w}: offset"), e.offset)?;
            check_finite(|| format!("{w}: weight"), e.weight)?;
            if e.weight <= 0.0 {
                return Err(CoreError::OutOfRange {
                    what: format!("{w}: weight"),
                    value: f64::from(e.weight),
                    expected: "rational weights must be > 0",
                });
            }
        }
        Ok(())
    }

    fn bind(&self, _input: &BindInput<'_>) -> Result<PreparedLattice> {
        PreparedLattice::new(self, "lattice")
    }

    fn deform(&self, bind: &PreparedLattice, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        bind.deform_slice(positions, active, out);
    }

    /// The frame and the control points map as points (so offsets map by the linear part),
    /// weights are unchanged: lattice coordinates are affine invariants, so this is exact for
    /// every affine map. The falloff distance scales by the uniform scale of `m`.
    fn transformed(&self, m: &Affine3A) -> Self {
        Self {
            frame: LatticeFrame {
                origin: m.transform_point3(self.frame.origin),
                s: m.transform_vector3(self.frame.s),
                t: m.transform_vector3(self.frame.t),
                u: m.transform_vector3(self.frame.u),
            },
            points: self
                .points
                .iter()
                .map(|e| ControlEdit {
                    offset: m.transform_vector3(e.offset),
                    ..*e
                })
                .collect(),
            falloff: self.falloff * uniform_scale(m),
            ..self.clone()
        }
    }

    /// The bind holds the whole prepared lattice, so any change re-binds (it is cheap:
    /// `O(control points)`).
    fn same_rest_state(&self, other: &Self) -> bool {
        self == other
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat3, Quat};
    use proptest::prelude::*;

    fn skew_frame() -> LatticeFrame {
        LatticeFrame {
            origin: Vec3::new(-0.3, 0.2, -0.5),
            s: Vec3::new(1.2, 0.1, 0.0),
            t: Vec3::new(0.2, 0.9, 0.1),
            u: Vec3::new(-0.1, 0.15, 1.1),
        }
    }

    fn run(tool: &LatticeTool, pts: &[Vec3]) -> Vec<Vec3> {
        let lat = tool.prepare("test").unwrap();
        pts.iter().map(|&p| lat.deform_point(p)).collect()
    }

    fn sample_points(frame: &LatticeFrame, n: usize) -> Vec<Vec3> {
        // A deterministic scatter inside and around the lattice.
        (0..n)
            .map(|k| {
                let f = |a: usize| ((k * a + 7) % 97) as f32 / 96.0 * 1.4 - 0.2;
                frame.point(Vec3::new(f(13), f(29), f(53)))
            })
            .collect()
    }

    #[test]
    fn coordinates_use_the_right_cross_products() {
        let f = skew_frame();
        let lat = LatticeTool::bernstein(f, (2, 2, 2)).prepare("t").unwrap();
        for c in [
            Vec3::new(0.2, 0.7, 0.4),
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(-0.3, 1.4, 0.9),
        ] {
            assert!((lat.coords(f.point(c)) - c).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn degree_errors_name_the_degree_and_the_count() {
        // Issue 14: the message printed only the count, as if the count were wrong.
        let e = LatticeTool::bspline(skew_frame(), (4, 6, 5), (5, 2, 3))
            .validate("tool 'cage'")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("axis 0 has degree 5 and 4 control points"),
            "{e}"
        );
        let e = LatticeTool::bernstein(skew_frame(), (4, 17, 4))
            .validate("tool 'cage'")
            .unwrap_err()
            .to_string();
        assert!(e.contains("axis 1 has 17 control points"), "{e}");
    }

    #[test]
    fn undeformed_lattice_is_identity() {
        let f = skew_frame();
        let pts = sample_points(&f, 200);
        for tool in [
            LatticeTool::bernstein(f, (4, 4, 4)),
            LatticeTool::bernstein(f, (2, 5, 8)),
            LatticeTool::bspline(f, (8, 6, 5), (3, 2, 4)),
        ] {
            for (p, q) in pts.iter().zip(run(&tool, &pts)) {
                assert_eq!(*p, q);
            }
            // The rational path (all weights 1) reproduces the identity to 1e-6 relative.
            let mut lat = tool.prepare("t").unwrap();
            lat.force_rational();
            let size = f.s.length() + f.t.length() + f.u.length();
            for p in &pts {
                let q = lat.deform_point(*p);
                assert!((q - *p).length() <= 1e-6 * size, "{p} -> {q}");
            }
        }
    }

    fn affine_moved(tool: &LatticeTool, a: &Affine3A) -> LatticeTool {
        let lat = tool.prepare("t").unwrap();
        let [l, m, n] = lat.counts();
        let mut moved = tool.clone();
        for k in 0..n {
            for j in 0..m {
                for i in 0..l {
                    let p = lat.rest_control_point(i, j, k);
                    moved.set_offset((i as u32, j as u32, k as u32), a.transform_point3(p) - p);
                }
            }
        }
        moved
    }

    #[test]
    fn affine_control_points_apply_the_affine_map() {
        let f = skew_frame();
        let a = Affine3A::from_mat3_translation(
            Mat3::from_cols(
                Vec3::new(1.1, 0.2, -0.1),
                Vec3::new(0.0, 0.8, 0.3),
                Vec3::new(0.25, 0.0, 1.3),
            ),
            Vec3::new(0.4, -0.2, 0.7),
        );
        let pts: Vec<Vec3> = sample_points(&f, 300)
            .into_iter()
            .filter(|p| {
                PreparedLattice::inside(
                    LatticeTool::bernstein(f, (2, 2, 2))
                        .prepare("t")
                        .unwrap()
                        .coords(*p),
                )
            })
            .collect();
        assert!(pts.len() > 50);
        for tool in [
            LatticeTool::bernstein(f, (4, 4, 4)),
            LatticeTool::bernstein(f, (3, 8, 5)),
            LatticeTool::bspline(f, (7, 7, 7), (3, 3, 3)),
            LatticeTool::bspline(f, (5, 6, 4), (2, 3, 1)),
        ] {
            let moved = affine_moved(&tool, &a);
            for (p, q) in pts.iter().zip(run(&moved, &pts)) {
                let e = a.transform_point3(*p);
                assert!((q - e).length() < 1e-5, "{p}: {q} vs {e}");
            }
        }
    }

    #[test]
    fn oracle_single_control_point_bernstein() {
        // 3×3×3 Bernstein (degree 2), move P_{1,1,1} by d: D(X) = X + d·B₁²(u₁)B₁²(u₂)B₁²(u₃),
        // B₁²(t) = 2t(1 − t). At u = (0.5, 0.25, 0.75): 0.5 · 0.375 · 0.375 = 0.0703125.
        let f = LatticeFrame::from_box(Vec3::ZERO, Vec3::new(2.0, 4.0, 1.0));
        let mut tool = LatticeTool::bernstein(f, (3, 3, 3));
        let d = Vec3::new(0.0, 0.0, 1.0);
        tool.set_offset((1, 1, 1), d);
        let x = f.point(Vec3::new(0.5, 0.25, 0.75));
        let q = run(&tool, &[x])[0];
        assert!((q - (x + d * 0.0703125)).length() < 1e-6, "{q}");
    }

    #[test]
    fn oracle_rational_weight() {
        // 2×2×2 unit-cube lattice, W₁₁₁ = 3, no offsets. At u = (½, ½, ½) every B B B = 1/8,
        // so D = Σ W P / Σ W: the eight corners sum to (4, 4, 4), the heavy corner (1, 1, 1)
        // adds 2·(1, 1, 1) more, and Σ W = 10: D = (6, 6, 6) / 10 = (0.6, 0.6, 0.6).
        let f = LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE);
        let mut tool = LatticeTool::bernstein(f, (2, 2, 2));
        tool.set_weight((1, 1, 1), 3.0);
        let q = run(&tool, &[Vec3::splat(0.5)])[0];
        assert!((q - Vec3::splat(0.6)).length() < 1e-6, "{q}");
    }

    #[test]
    fn outside_points_untouched_and_falloff_is_continuous() {
        let f = LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE);
        let mut tool = LatticeTool::bernstein(f, (4, 4, 4));
        for i in 0..4 {
            for j in 0..4 {
                tool.set_offset((i, j, 3), Vec3::new(0.0, 0.0, 0.3));
            }
        }
        let outside = Vec3::new(0.5, 0.5, 1.05);
        assert_eq!(run(&tool, &[outside])[0], outside);
        tool.falloff = 0.2;
        let on = Vec3::new(0.5, 0.5, 1.0);
        let just_out = Vec3::new(0.5, 0.5, 1.0 + 1e-4);
        let r = run(&tool, &[on, just_out, outside, Vec3::new(0.5, 0.5, 1.25)]);
        assert!((r[0] - on - Vec3::new(0.0, 0.0, 0.3)).length() < 1e-5);
        assert!((r[1] - r[0]).length() < 1e-3, "continuous at the boundary");
        let half = r[2] - outside;
        assert!(
            half.z > 0.0 && half.z < 0.3,
            "partial inside the falloff: {half}"
        );
        assert_eq!(r[3], Vec3::new(0.5, 0.5, 1.25), "beyond the falloff");
    }

    #[test]
    fn bspline_local_support() {
        // Cubic, 8 control points per axis: P_{2,2,2} influences u ∈ (κ₂, κ₆)³ only.
        let f = LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE);
        let mut tool = LatticeTool::bspline(f, (8, 8, 8), (3, 3, 3));
        tool.set_offset((2, 2, 2), Vec3::new(0.1, 0.2, 0.3));
        let lat = tool.prepare("t").unwrap();
        let kv = KnotVector::clamped_uniform(3, 8).unwrap();
        let (lo, hi) = (kv.knots()[2], kv.knots()[6]);
        let mut moved = 0;
        for p in sample_points(&f, 500) {
            let u = lat.coords(p);
            let inside_support = u.cmpgt(Vec3::splat(lo)).all() && u.cmplt(Vec3::splat(hi)).all();
            let q = lat.deform_point(p);
            if inside_support {
                moved += usize::from(q != p);
            } else {
                assert_eq!(q, p, "outside the support of P_222: u = {u}");
            }
        }
        assert!(moved > 10);
    }

    #[test]
    fn rational_with_unit_weights_equals_plain() {
        let f = skew_frame();
        let mut tool = LatticeTool::bspline(f, (5, 5, 5), (2, 2, 2));
        tool.set_offset((1, 2, 3), Vec3::new(0.2, -0.1, 0.05));
        tool.set_offset((4, 0, 2), Vec3::new(-0.1, 0.3, 0.0));
        let plain = tool.prepare("t").unwrap();
        let mut rat = plain.clone();
        rat.force_rational();
        for p in sample_points(&f, 200) {
            assert!((plain.deform_point(p) - rat.deform_point(p)).length() < 1e-5);
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        let f = LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE);
        let flat = LatticeFrame {
            u: Vec3::new(1.0, 1.0, 0.0),
            ..f
        };
        assert!(matches!(
            LatticeTool::bernstein(flat, (3, 3, 3)).validate("t"),
            Err(CoreError::Degenerate { .. })
        ));
        let nan = LatticeFrame {
            origin: Vec3::new(f32::NAN, 0.0, 0.0),
            ..f
        };
        assert!(matches!(
            LatticeTool::bernstein(nan, (3, 3, 3)).validate("t"),
            Err(CoreError::NotFinite { .. })
        ));
        assert!(LatticeTool::bernstein(f, (1, 3, 3)).validate("t").is_err());
        assert!(LatticeTool::bernstein(f, (17, 3, 3)).validate("t").is_err());
        assert!(
            LatticeTool::bspline(f, (3, 3, 3), (3, 2, 2))
                .validate("t")
                .is_err()
        );
        assert!(
            LatticeTool::bspline(f, (3, 3, 3), (0, 2, 2))
                .validate("t")
                .is_err()
        );
        let mut t = LatticeTool::bernstein(f, (3, 3, 3));
        t.set_offset((3, 0, 0), Vec3::X);
        assert!(t.validate("t").is_err());
        let mut t = LatticeTool::bernstein(f, (3, 3, 3));
        t.set_weight((1, 0, 0), 0.0);
        assert!(t.validate("t").is_err());
        let mut t = LatticeTool::bernstein(f, (3, 3, 3));
        t.set_offset((1, 0, 0), Vec3::splat(f32::INFINITY));
        assert!(t.validate("t").is_err());
        let mut t = LatticeTool::bernstein(f, (3, 3, 3));
        t.falloff = -1.0;
        assert!(t.validate("t").is_err());
        let mut t = LatticeTool::bernstein(f, (3, 3, 3));
        t.points.push(ControlEdit {
            at: (0, 0, 0),
            offset: Vec3::X,
            weight: 1.0,
        });
        t.points.push(ControlEdit {
            at: (0, 0, 0),
            offset: Vec3::Y,
            weight: 1.0,
        });
        assert!(t.validate("t").is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Deforming in tool space then mapping equals mapping the tool then deforming.
        #[test]
        fn transformed_commutes(
            angle in -3.0f32..3.0,
            scale in 0.5f32..2.0,
            tx in -2.0f32..2.0,
            off in prop::array::uniform3(-0.3f32..0.3),
            w in 0.5f32..3.0,
            c in prop::array::uniform3(-0.1f32..1.1),
        ) {
            let f = skew_frame();
            let mut tool = LatticeTool::bspline(f, (5, 4, 4), (2, 3, 2));
            tool.set_offset((2, 1, 2), Vec3::from(off));
            tool.set_weight((1, 1, 1), w);
            tool.falloff = 0.3;
            let m = Affine3A::from_scale_rotation_translation(
                Vec3::splat(scale),
                Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), angle),
                Vec3::new(tx, 0.5, -tx),
            );
            let x = f.point(Vec3::from(c));
            let a = m.transform_point3(run(&tool, &[x])[0]);
            let b = run(&tool.transformed(&m), &[m.transform_point3(x)])[0];
            prop_assert!((a - b).length() < 1e-3 * (1.0 + a.length()), "{} vs {}", a, b);
        }
    }
}
