//! Lattices with few moved control points, summed over those points alone.
//!
//! A non-rational lattice is evaluated in the displacement form
//! `D(X) = X + Σᵢⱼₖ ΔP_ijk Bᵢ(u₁) Bⱼ(u₂) Bₖ(u₃)` (module `lattice`), where every control
//! point at rest has `ΔP = 0`. When only a few control points are moved — an artist drags a
//! handful of handles — the sum over the moved points `m` alone,
//!
//! `D(X) = X + Σₘ ΔPₘ · ((B_{iₘ}(u₁) · B_{jₘ}(u₂)) · B_{kₘ}(u₃))`,
//!
//! is the same function and needs only the basis functions those points read, not all
//! `(p+1)³` of a point's cell. Each function is evaluated on its own:
//!
//! * **Bernstein** `Bᵢⁿ(t) = (C(n, i) · tⁱ) · (1 − t)ⁿ⁻ⁱ`, the powers by repeated products;
//! * **B-spline** `N_{i,p}(t)` by the triangular table of one basis function (Piegl & Tiller,
//!   *The NURBS Book*, algorithm A2.4): the degree-0 functions `N_{i+j,0}` of the `p + 1` knot
//!   spans under the support (1 on `[u_{i+j}, u_{i+j+1})`, the last non-empty span closed
//!   so that `t = 1` is inside), then
//!   `N_{i+j,k} = ((t − u_{i+j}) · r) · N_{i+j,k−1} + ((u_{i+j+k+1} − t) · r') · N_{i+j+1,k−1}`
//!   with `r`, `r'` the reciprocals of the knot differences, computed once (0 where a
//!   difference is 0: that function is zero everywhere, the textbook's `0/0 = 0`).
//!
//! A point outside a moved point's support gets an exact zero from it, so a B-spline point
//! no moved control point reaches keeps its input (bit for bit, but for a `−0` coordinate,
//! which `−0 + 0` makes `+0`, as the dense kernels do). Every lane of the kernel performs
//! the operations of the one-lane form (`pulp::Scalar`, the same generic code) in the same
//! order, with products and sums kept apart (no fused multiply–add), so a point has the
//! same bits in any block, on any CPU, and through [`PreparedLattice::deform_point`].
//! These are not the bits of the dense kernels (`simd.rs`): a lattice takes one form or the
//! other from its data alone ([`Sparse::new`]), so a given lattice always gives the same
//! bits.

use glam::{Vec3, Vec4};
use pulp::{Simd, WithSimd};

use super::simd::{Block, frame, load};
use super::{AxisBasis, PreparedLattice};
use crate::basis::MAX_DEGREE;

/// The most moved control points the sparse form takes. More, or more than a quarter of
/// the lattice's points, and the dense kernels are faster.
const MOST_MOVED: usize = 8;

/// One basis function of one axis, with what its evaluation needs computed once.
#[derive(Debug, Clone, PartialEq)]
enum Function {
    /// `Bᵢⁿ(t)`: the degree `n`, the index `i` and `C(n, i)`.
    Bernstein { n: usize, i: usize, binomial: f32 },
    /// `N_{i,p}(t)`: per degree-0 span `j = 0..=p` its knots and whether it is closed on the
    /// right (so `p + 1` spans); per step of the table (`k = 1..=p`, `j = 0..=p−k`, in that
    /// order) `(u_{i+j}, r, u_{i+j+k+1}, r')`.
    BSpline {
        spans: Vec<(f32, f32, bool)>,
        steps: Vec<[f32; 4]>,
    },
}

impl Function {
    /// The function of index `i` on `axis`.
    fn new(axis: &AxisBasis, i: usize) -> Self {
        match axis {
            AxisBasis::Bernstein(n) => {
                // C(n, i) in f64, then rounded: exact for the degrees a lattice takes, as
                // the dense kernels' f32 products are.
                let mut c = 1.0_f64;
                for r in 0..i {
                    c = c * (n - r) as f64 / (r + 1) as f64;
                }
                Self::Bernstein {
                    n: *n,
                    i,
                    binomial: c as f32,
                }
            }
            AxisBasis::BSpline(kv) => {
                let (p, u) = (kv.degree(), kv.knots());
                let last = u[u.len() - 1];
                let spans = (0..=p)
                    .map(|j| {
                        let (lo, hi) = (u[i + j], u[i + j + 1]);
                        (lo, hi, hi == last && lo < hi)
                    })
                    .collect();
                let reciprocal = |d: f32| if d > 0.0 { 1.0 / d } else { 0.0 };
                let mut steps = Vec::with_capacity(p * (p + 1) / 2);
                for k in 1..=p {
                    for j in 0..=p - k {
                        steps.push([
                            u[i + j],
                            reciprocal(u[i + j + k] - u[i + j]),
                            u[i + j + k + 1],
                            reciprocal(u[i + j + k + 1] - u[i + j + 1]),
                        ]);
                    }
                }
                Self::BSpline { spans, steps }
            }
        }
    }

    /// The function's values at `t`, one per lane (module documentation).
    #[inline(always)]
    fn value<S: Simd>(&self, simd: S, t: S::f32s) -> S::f32s {
        let one = simd.splat_f32s(1.0);
        match self {
            &Self::Bernstein { n, i, binomial } => {
                let s = simd.sub_f32s(one, t);
                let mut tp = one;
                for _ in 0..i {
                    tp = simd.mul_f32s(tp, t);
                }
                let mut sp = one;
                for _ in 0..n - i {
                    sp = simd.mul_f32s(sp, s);
                }
                simd.mul_f32s(simd.mul_f32s(simd.splat_f32s(binomial), tp), sp)
            }
            Self::BSpline { spans, steps } => match spans.len() {
                2 => bspline_value::<S, 2>(simd, spans, steps, t),
                3 => bspline_value::<S, 3>(simd, spans, steps, t),
                4 => bspline_value::<S, 4>(simd, spans, steps, t),
                _ => bspline_value::<S, { MAX_DEGREE + 1 }>(simd, spans, steps, t),
            },
        }
    }
}

/// `N_{i,p}(t)` in each lane by the triangular table (module documentation), for a table
/// of `spans.len() = p + 1 ≤ L` entries: `L = p + 1` for the common degrees (the loops
/// unroll and the table stays in registers), `L = MAX_DEGREE + 1` for any other. The same
/// operations in the same order for every `L`.
#[inline(always)]
fn bspline_value<S: Simd, const L: usize>(
    simd: S,
    spans: &[(f32, f32, bool)],
    steps: &[[f32; 4]],
    t: S::f32s,
) -> S::f32s {
    let (zero, one) = (simd.splat_f32s(0.0), simd.splat_f32s(1.0));
    // A compile-time `p` for the common degrees, so that the loops unroll.
    let p = if L <= MAX_DEGREE {
        L - 1
    } else {
        spans.len() - 1
    };
    debug_assert_eq!(
        spans.len(),
        p + 1,
        "one degree-0 span per function of the table"
    );
    let mut n = [zero; L];
    for (v, &(lo, hi, closed)) in n.iter_mut().zip(spans) {
        let (lo, hi) = (simd.splat_f32s(lo), simd.splat_f32s(hi));
        let below = if closed {
            simd.less_than_or_equal_f32s(t, hi)
        } else {
            simd.less_than_f32s(t, hi)
        };
        let inside = simd.and_m32s(simd.greater_than_or_equal_f32s(t, lo), below);
        *v = simd.select_f32s(inside, one, zero);
    }
    let mut s = 0;
    for k in 1..=p {
        for j in 0..=p - k {
            let [a, ra, b, rb] = steps[s];
            s += 1;
            let left = simd.mul_f32s(
                simd.mul_f32s(simd.sub_f32s(t, simd.splat_f32s(a)), simd.splat_f32s(ra)),
                n[j],
            );
            let right = simd.mul_f32s(
                simd.mul_f32s(simd.sub_f32s(simd.splat_f32s(b), t), simd.splat_f32s(rb)),
                n[j + 1],
            );
            n[j] = simd.add_f32s(left, right);
        }
    }
    n[0]
}

/// The moved control points of a non-rational lattice and the basis functions they read
/// (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Sparse {
    /// Per axis, the distinct functions the moved points read, with their indices.
    functions: [Vec<(usize, Function)>; 3],
    /// Per moved point, in the order of the dense data: its function on each axis (an index
    /// into `functions`) and its offset `ΔP`.
    moved: Vec<([usize; 3], Vec3)>,
}

impl Sparse {
    /// The sparse form of `lattice`, when it is not rational and has at most
    /// [`MOST_MOVED`] moved control points, and at most a quarter of them.
    pub(super) fn new(lattice: &PreparedLattice) -> Option<Self> {
        if lattice.rational {
            return None;
        }
        let [l, m, _] = lattice.counts;
        let total = lattice.offsets.len();
        let mut functions: [Vec<(usize, Function)>; 3] = Default::default();
        let mut moved = Vec::new();
        for (idx, &d) in lattice.offsets.iter().enumerate() {
            if d == Vec3::ZERO {
                continue;
            }
            if moved.len() == MOST_MOVED || 4 * (moved.len() + 1) > total {
                return None;
            }
            let at = [idx % l, (idx / l) % m, idx / (l * m)];
            let mut slots = [0; 3];
            for a in 0..3 {
                let fs = &mut functions[a];
                slots[a] = fs.iter().position(|(i, _)| *i == at[a]).unwrap_or_else(|| {
                    fs.push((at[a], Function::new(&lattice.axes[a], at[a])));
                    fs.len() - 1
                });
            }
            moved.push((slots, d));
        }
        Some(Self { functions, moved })
    }

    /// `Σₘ ΔPₘ · ((B_{iₘ}(u₁) · B_{jₘ}(u₂)) · B_{kₘ}(u₃))` in each lane, by axis.
    #[inline(always)]
    fn displacement<S: Simd>(&self, simd: S, u: &[S::f32s; 3]) -> [S::f32s; 3] {
        let zero = simd.splat_f32s(0.0);
        let mut values = [[zero; MOST_MOVED]; 3];
        for a in 0..3 {
            for (v, (_, f)) in values[a].iter_mut().zip(&self.functions[a]) {
                *v = f.value(simd, u[a]);
            }
        }
        let mut acc = [zero; 3];
        for &([i, j, k], d) in &self.moved {
            let w = simd.mul_f32s(simd.mul_f32s(values[0][i], values[1][j]), values[2][k]);
            for (c, acc) in acc.iter_mut().enumerate() {
                *acc = simd.add_f32s(*acc, simd.mul_f32s(simd.splat_f32s(d[c]), w));
            }
        }
        acc
    }
}

impl PreparedLattice {
    /// The tensor sum of the sparse form at `u` (`(Σ ΔP B B B, 0)`), in one lane: the bits
    /// of every lane of [`PreparedLattice::deform_slice_sparse`].
    ///
    /// # Panics
    /// When the lattice has no sparse form.
    pub(super) fn sparse_tensor(&self, u: Vec3) -> Vec4 {
        let Some(sparse) = &self.sparse else {
            panic!("sparse_tensor on a lattice without a sparse form");
        };
        let [x, y, z] = sparse.displacement(pulp::Scalar, &[u.x, u.y, u.z]);
        Vec4::new(x, y, z, 0.0)
    }

    /// Deforms the `active` vertices of `positions` into `out` with the sparse form, when the
    /// lattice has one; returns false (and writes nothing) otherwise.
    pub(super) fn deform_slice_sparse(
        &self,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
    ) -> bool {
        let Some(sparse) = &self.sparse else {
            return false;
        };
        pulp::Arch::new().dispatch(Kernel {
            lattice: self,
            sparse,
            positions,
            active,
            out,
        });
        true
    }
}

/// One call's work of the sparse form.
struct Kernel<'a> {
    lattice: &'a PreparedLattice,
    sparse: &'a Sparse,
    positions: &'a [Vec3],
    active: &'a [u32],
    out: &'a mut [Vec3],
}

impl WithSimd for Kernel<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let lat = self.lattice;
        let lanes = S::F32_LANES.min(super::simd::MAX_LANES);
        let f = frame(simd, lat);
        for (idx, out) in self.active.chunks(lanes).zip(self.out.chunks_mut(lanes)) {
            let block: Block<S> = load(simd, &f, self.positions, idx);
            let d = self.sparse.displacement(simd, &block.u);
            let mut q = [[0.0_f32; super::simd::MAX_LANES]; 3];
            for a in 0..3 {
                simd.partial_store_f32s(&mut q[a][..block.n], simd.add_f32s(block.x[a], d[a]));
            }
            for (l, o) in out.iter_mut().enumerate() {
                let (x, u) = block.lane(l);
                *o = if PreparedLattice::inside(u) {
                    Vec3::new(q[0][l], q[1][l], q[2][l])
                } else {
                    // Outside: the identity, or the falloff (one lane, rare).
                    lat.deform_with(x, PreparedLattice::sparse_tensor)
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::{Function, MOST_MOVED};
    use crate::basis::KnotVector;
    use crate::lattice::simd::tests::{check_the_same_bits_in_any_block, frame, points};
    use crate::lattice::{AxisBasis, LatticeTool, PreparedLattice};

    /// `points` moved control points of `tool` (corners, the middle, the last layer; fewer
    /// where two of them fall on one control point), with a falloff.
    fn moved(mut tool: LatticeTool, points: usize) -> PreparedLattice {
        tool.falloff = 0.3;
        let (a, b, c) = tool.counts;
        let at = [
            (a / 2, b / 2, c - 1),
            (0, 0, 0),
            (a - 1, b - 1, c - 1),
            (1, b - 1, 0),
            (a / 2, 0, c / 2),
            (a - 1, b / 2, 1),
            (0, 1, c - 1),
            (1, 1, 1),
        ];
        for (n, &p) in at.iter().take(points).enumerate() {
            let h = n as f32;
            tool.set_offset(p, Vec3::new(0.03 * h - 0.05, 0.02 + 0.01 * h, -0.04 * h));
        }
        tool.prepare("test").unwrap()
    }

    /// Bernstein 2³…6³ and 2×4×3, B-spline lattices of degree 1…3, 5 and 15 (the table's
    /// general size) and of degrees (1, 2, 3), 1 to 8 moved points where the sparse form takes
    /// them.
    fn lattices() -> Vec<(String, PreparedLattice)> {
        let mut tools = Vec::new();
        for n in 2..=6 {
            tools.push(LatticeTool::bernstein(frame(), (n, n, n)));
        }
        tools.push(LatticeTool::bernstein(frame(), (2, 4, 3)));
        for (counts, degree) in [
            ((4, 4, 4), (2, 2, 2)),
            ((5, 3, 6), (2, 2, 2)),
            ((7, 6, 5), (3, 3, 3)),
            ((3, 4, 2), (1, 1, 1)),
            ((8, 8, 8), (2, 2, 2)),
            ((7, 7, 7), (5, 5, 5)),
            ((16, 16, 16), (15, 15, 15)),
            ((5, 4, 6), (1, 2, 3)),
        ] {
            tools.push(LatticeTool::bspline(frame(), counts, degree));
        }
        let mut out = Vec::new();
        for tool in tools {
            for points in 1..=MOST_MOVED {
                let lat = moved(tool.clone(), points);
                if let Some(sparse) = &lat.sparse {
                    let name = format!(
                        "{:?} {:?}, {} moved",
                        tool.basis,
                        tool.counts,
                        sparse.moved.len()
                    );
                    out.push((name, lat));
                }
            }
        }
        out
    }

    #[test]
    fn the_sparse_form_is_taken_for_a_few_moved_points_only() {
        let b = LatticeTool::bernstein(frame(), (3, 3, 3));
        assert!(moved(b.clone(), 1).sparse.is_some());
        assert!(moved(b.clone(), 6).sparse.is_some());
        // More than a quarter of the 27 points.
        assert!(moved(b.clone(), 7).sparse.is_none());
        // Nothing moved: the sum is empty, every point inside stays put.
        assert!(b.prepare("t").unwrap().sparse.is_some());
        // A weight other than 1 makes the lattice rational.
        let mut r = LatticeTool::bspline(frame(), (8, 8, 8), (2, 2, 2));
        r.set_offset((1, 1, 1), Vec3::X);
        assert!(r.prepare("t").unwrap().sparse.is_some());
        r.set_weight((2, 2, 2), 2.0);
        assert!(r.prepare("t").unwrap().sparse.is_none());
        // More than MOST_MOVED points.
        let mut many = LatticeTool::bspline(frame(), (8, 8, 8), (2, 2, 2));
        for i in 0..=MOST_MOVED as u32 {
            many.set_offset((i % 8, i / 8, 0), Vec3::Y);
        }
        assert!(many.prepare("t").unwrap().sparse.is_none());
        // A zero offset is no move.
        many.set_offset((0, 0, 0), Vec3::ZERO);
        assert!(many.prepare("t").unwrap().sparse.is_some());
    }

    /// Each B-spline function, at knots, ends and between, against the Cox–de Boor values
    /// of `KnotVector::basis`; each Bernstein function against the recurrence.
    #[test]
    fn one_basis_function_matches_the_whole_recurrence() {
        let ts: Vec<f32> = (0..=240)
            .map(|k| k as f32 / 240.0)
            .chain([1e-7, 0.5 - 1e-7, 1.0 - 1e-7])
            .collect();
        for (p, count) in [(1, 3), (2, 4), (2, 7), (3, 5), (3, 9), (4, 12)] {
            let kv = KnotVector::clamped_uniform(p, count).unwrap();
            let axis = AxisBasis::BSpline(kv.clone());
            let fs: Vec<Function> = (0..count).map(|i| Function::new(&axis, i)).collect();
            for &t in &ts {
                let mut all = [0.0; 16];
                let s = kv.basis(t, &mut all);
                for (i, f) in fs.iter().enumerate() {
                    let want = if (s - p..=s).contains(&i) {
                        all[i + p - s]
                    } else {
                        0.0
                    };
                    let got = f.value(pulp::Scalar, t);
                    assert!(
                        (got - want).abs() <= 1e-6,
                        "degree {p}, {count} points, N_{i}({t}) = {got}, recurrence {want}"
                    );
                }
            }
        }
        for n in 1..=7 {
            let axis = AxisBasis::Bernstein(n);
            for &t in &ts {
                let mut all = [0.0; 16];
                crate::basis::bernstein_all(n, t, &mut all);
                for (i, &want) in all.iter().enumerate().take(n + 1) {
                    let got = Function::new(&axis, i).value(pulp::Scalar, t);
                    assert!((got - want).abs() <= 1e-6, "B_{i}^{n}({t}) = {got}, {want}");
                }
            }
        }
    }

    #[test]
    fn the_sparse_form_matches_the_dense_sum() {
        let cases = lattices();
        assert!(cases.len() > 40);
        for (name, lat) in cases {
            let mut dense = lat.clone();
            dense.sparse = None;
            let pts = points(&lat);
            let active: Vec<u32> = (0..pts.len() as u32).collect();
            let mut out = vec![Vec3::ZERO; pts.len()];
            lat.deform_slice(&pts, &active, &mut out);
            let mut want = vec![Vec3::ZERO; pts.len()];
            dense.deform_slice(&pts, &active, &mut want);
            let mut differ = 0;
            for ((p, q), w) in pts.iter().zip(&out).zip(&want) {
                assert!(
                    (*q - *w).length() <= 2e-6 * (1.0 + w.length()),
                    "{name}: {p} → {q} (dense {w})"
                );
                differ += usize::from(q != p);
            }
            assert!(differ > 0, "{name}: nothing moved");
        }
    }

    #[test]
    fn a_point_gets_the_same_bits_in_any_block_and_alone() {
        for (name, lat) in lattices() {
            check_the_same_bits_in_any_block(&name, &lat);
        }
    }

    /// A B-spline lattice moved at one corner: a point beyond that control point's support
    /// keeps its bits, a point within it moves.
    #[test]
    fn a_point_beyond_the_moved_supports_keeps_its_bits() {
        let mut tool = LatticeTool::bspline(frame(), (6, 6, 6), (2, 2, 2));
        tool.set_offset((0, 0, 0), Vec3::new(0.1, -0.2, 0.3));
        let lat = tool.prepare("t").unwrap();
        assert!(lat.sparse.is_some());
        // N₀ of a clamped quadratic with 6 points is non-zero on [0, 1/4).
        let far = tool.frame.point(Vec3::new(0.6, 0.1, 0.1));
        let near = tool.frame.point(Vec3::new(0.1, 0.1, 0.1));
        let got = |x: Vec3| {
            let mut out = [Vec3::ZERO];
            lat.deform_slice(&[x], &[0], &mut out);
            out[0]
        };
        assert_eq!(got(far).to_array(), far.to_array());
        assert_ne!(got(near), near);
    }

    /// Direct FFD moves a lattice further with `add_offsets`: past the limit it leaves the
    /// sparse form, and then gives what the dense kernels give.
    #[test]
    fn a_lattice_moved_further_leaves_the_sparse_form() {
        let mut lat = moved(LatticeTool::bspline(frame(), (6, 6, 6), (2, 2, 2)), 1);
        assert!(lat.sparse.is_some());
        let mut delta = vec![Vec3::ZERO; lat.len()];
        for (k, d) in delta.iter_mut().enumerate().step_by(7) {
            *d = Vec3::new(0.01, -0.02, 0.005 * (k % 5) as f32);
        }
        lat.add_offsets(&delta);
        assert!(lat.sparse.is_none());
        let pts = points(&lat);
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let mut out = vec![Vec3::ZERO; pts.len()];
        lat.deform_slice(&pts, &active, &mut out);
        let mut blocks = vec![Vec3::ZERO; pts.len()];
        assert!(lat.deform_slice_blocks(&pts, &active, &mut blocks));
        let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array()).collect::<Vec<_>>();
        assert_eq!(bits(&out), bits(&blocks));
    }
}
