//! Lattices deformed many points at a time, one point per SIMD lane.
//!
//! The tensor sum `Σₖ Bₖ(u₃) Σⱼ Bⱼ(u₂) Σᵢ Bᵢ(u₁) c_ijk` runs on whole registers when every
//! lane of a block reads the same control points:
//!
//! * **Bernstein** lattices have no knot spans: every point inside reads all `L³` control
//!   points, so a block shares every control value (broadcast once per call).
//! * **B-spline** lattices read the `(p+1)³` control points of the point's cell (its knot
//!   spans). A block runs once per distinct cell among its lanes — on a mesh, neighbouring
//!   vertices mostly share a cell, so that is once — and each lane keeps the result computed
//!   with its own cell.
//!
//! The register width is chosen when the program runs ([`pulp`]'s dispatch): 8 lanes with
//! fused multiply–add where the CPU has AVX2 and FMA, one lane of scalar code elsewhere
//! (`pulp` 0.22 has no SSE level on x86), so one binary runs everywhere and uses what it
//! finds.
//!
//! Each lane's arithmetic depends only on its own point (and, for B-splines, its own cell):
//! no lane reads another, so a point gets the same bits whatever block it is in, and
//! [`PreparedLattice::deform_point`] runs the same kernel on one point. The lattice coordinates
//! are computed exactly as the scalar path computes them (the same unfused products and sums),
//! so inside and outside are decided identically, and points outside take the scalar path
//! (identity or falloff).
//!
//! The Bernstein values are `Bᵢⁿ(t) = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ` (power form; a few ulps from the
//! de Casteljau recurrence of [`crate::basis::bernstein_all`]); the B-spline values are the
//! Cox–de Boor recurrence of [`crate::basis::KnotVector::basis`] with the same operations, so
//! the same bits. No closures in the kernels: they would not inherit the dispatched target
//! features, and every SIMD operation in them would become a call.

use glam::Vec3;
use pulp::{Simd, WithSimd};

use super::{AxisBasis, PreparedLattice};

/// The most lanes a block holds (AVX-512 has 16 `f32` lanes).
pub(super) const MAX_LANES: usize = 16;

/// Components of the dense control data: `(ΔP, 0)` or `(W(P − U₀), W)`.
const COMPONENTS: usize = 4;

/// Which basis a kernel evaluates.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Bernstein,
    BSpline,
}

impl PreparedLattice {
    /// The kind of block kernel that evaluates this lattice and its number `L` of non-zero
    /// basis functions per axis (`2 ≤ L ≤ 8`, the same on every axis): Bernstein with `L`
    /// control points on every axis, or B-spline of degree `L − 1` on every axis.
    fn block_kernel(&self) -> Option<(Kind, usize)> {
        let l = match &self.axes[0] {
            AxisBasis::Bernstein(n) => n + 1,
            AxisBasis::BSpline(kv) => kv.degree() + 1,
        };
        if !(2..=8).contains(&l) {
            return None;
        }
        let bernstein = self
            .axes
            .iter()
            .zip(self.counts)
            .all(|(a, c)| matches!(a, AxisBasis::Bernstein(n) if n + 1 == l && c == l));
        let bspline = self
            .axes
            .iter()
            .all(|a| matches!(a, AxisBasis::BSpline(kv) if kv.degree() + 1 == l));
        match (bernstein, bspline) {
            (true, _) => Some((Kind::Bernstein, l)),
            (_, true) => Some((Kind::BSpline, l)),
            _ => None,
        }
    }

    /// Whether [`PreparedLattice::deform_slice_blocks`] evaluates this lattice.
    pub(super) fn has_block_kernel(&self) -> bool {
        self.block_kernel().is_some()
    }

    /// Deforms the `active` vertices of `positions` into `out` with the block kernel, when
    /// the lattice has one; returns false (and writes nothing) otherwise.
    pub(super) fn deform_slice_blocks(
        &self,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
    ) -> bool {
        let Some((kind, l)) = self.block_kernel() else {
            return false;
        };
        match l {
            2 => self.dispatch::<2>(kind, positions, active, out),
            3 => self.dispatch::<3>(kind, positions, active, out),
            4 => self.dispatch::<4>(kind, positions, active, out),
            5 => self.dispatch::<5>(kind, positions, active, out),
            6 => self.dispatch::<6>(kind, positions, active, out),
            7 => self.dispatch::<7>(kind, positions, active, out),
            _ => self.dispatch::<8>(kind, positions, active, out),
        }
        true
    }

    fn dispatch<const L: usize>(
        &self,
        kind: Kind,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
    ) {
        let arch = pulp::Arch::new();
        match (kind, self.rational) {
            (Kind::Bernstein, false) => arch.dispatch(Bernstein::<L, 3> {
                lattice: self,
                positions,
                active,
                out,
            }),
            (Kind::Bernstein, true) => arch.dispatch(Bernstein::<L, 4> {
                lattice: self,
                positions,
                active,
                out,
            }),
            (Kind::BSpline, false) => arch.dispatch(BSpline::<L, 3> {
                lattice: self,
                positions,
                active,
                out,
            }),
            (Kind::BSpline, true) => arch.dispatch(BSpline::<L, 4> {
                lattice: self,
                positions,
                active,
                out,
            }),
        }
    }
}

/// One call's work on a Bernstein lattice: `L` control points per axis, `C` components summed
/// (3, or 4 when rational).
struct Bernstein<'a, const L: usize, const C: usize> {
    lattice: &'a PreparedLattice,
    positions: &'a [Vec3],
    active: &'a [u32],
    out: &'a mut [Vec3],
}

/// One call's work on a B-spline lattice of degree `L − 1`.
struct BSpline<'a, const L: usize, const C: usize> {
    lattice: &'a PreparedLattice,
    positions: &'a [Vec3],
    active: &'a [u32],
    out: &'a mut [Vec3],
}

/// The binomial coefficients `C(n, i)`, `i = 0..=n`, `n = L − 1`.
fn binomials<const L: usize>() -> [f32; L] {
    let mut c = [1.0_f32; L];
    for i in 1..L {
        c[i] = c[i - 1] * (L - i) as f32 / i as f32;
    }
    c
}

/// A block of up to [`MAX_LANES`] points: their coordinates by axis, as registers and as
/// arrays, and their lattice coordinates.
pub(super) struct Block<S: Simd> {
    /// The number of points.
    pub(super) n: usize,
    p: [[f32; MAX_LANES]; 3],
    /// The points by axis.
    pub(super) x: [S::f32s; 3],
    /// Their lattice coordinates by axis.
    pub(super) u: [S::f32s; 3],
    uc: [[f32; MAX_LANES]; 3],
}

/// The frame as registers: origin and the inverse rows.
pub(super) struct Frame<S: Simd> {
    origin: [S::f32s; 3],
    rows: [[S::f32s; 3]; 3],
}

/// The frame of `lat` as registers.
#[inline(always)]
pub(super) fn frame<S: Simd>(simd: S, lat: &PreparedLattice) -> Frame<S> {
    let zero = simd.splat_f32s(0.0);
    let o = lat.frame.origin;
    let mut rows = [[zero; 3]; 3];
    for a in 0..3 {
        for c in 0..3 {
            rows[a][c] = simd.splat_f32s(lat.rows[a][c]);
        }
    }
    Frame {
        origin: [
            simd.splat_f32s(o.x),
            simd.splat_f32s(o.y),
            simd.splat_f32s(o.z),
        ],
        rows,
    }
}

/// Loads the points `idx` of `positions` and computes their lattice coordinates
/// `u_a = (r_a.x·dx + r_a.y·dy) + r_a.z·dz`, unfused: glam's `dot`, bit for bit.
#[inline(always)]
pub(super) fn load<S: Simd>(simd: S, f: &Frame<S>, positions: &[Vec3], idx: &[u32]) -> Block<S> {
    let zero = simd.splat_f32s(0.0);
    let n = idx.len();
    let mut p = [[0.0_f32; MAX_LANES]; 3];
    let mut x = [zero; 3];
    if n == S::F32_LANES {
        // A whole register: each axis's values gathered into an array of its own that the
        // compiler builds in a register, then stored for the lanes' reads. Written into `p`
        // one value at a time, a register loaded from it waited for those stores (and the
        // partial load is a call).
        for (a, x) in x.iter_mut().enumerate() {
            let mut lanes = [0.0_f32; MAX_LANES];
            for (v, &i) in lanes[..S::F32_LANES].iter_mut().zip(idx) {
                *v = positions[i as usize][a];
            }
            *x = bytemuck::pod_read_unaligned(bytemuck::cast_slice(&lanes[..S::F32_LANES]));
            bytemuck::cast_slice_mut::<f32, u8>(&mut p[a][..n])
                .copy_from_slice(bytemuck::bytes_of(x));
        }
    } else {
        for (l, &i) in idx.iter().enumerate() {
            let v = positions[i as usize];
            p[0][l] = v.x;
            p[1][l] = v.y;
            p[2][l] = v.z;
        }
        for a in 0..3 {
            x[a] = simd.partial_load_f32s(&p[a][..n]);
        }
    }
    let mut d = [zero; 3];
    for a in 0..3 {
        d[a] = simd.sub_f32s(x[a], f.origin[a]);
    }
    let mut u = [zero; 3];
    let mut uc = [[0.0_f32; MAX_LANES]; 3];
    for a in 0..3 {
        let r = f.rows[a];
        u[a] = simd.add_f32s(
            simd.add_f32s(simd.mul_f32s(r[0], d[0]), simd.mul_f32s(r[1], d[1])),
            simd.mul_f32s(r[2], d[2]),
        );
        simd.partial_store_f32s(&mut uc[a][..n], u[a]);
    }
    Block { n, p, x, u, uc }
}

impl<S: Simd> Block<S> {
    /// Lane `l`'s point and lattice coordinates.
    #[inline(always)]
    pub(super) fn lane(&self, l: usize) -> (Vec3, Vec3) {
        (
            Vec3::new(self.p[0][l], self.p[1][l], self.p[2][l]),
            Vec3::new(self.uc[0][l], self.uc[1][l], self.uc[2][l]),
        )
    }
}

/// The tensor sum over `control` (the `L³` control values of the cell, broadcast, index
/// `(i + L(j + L k))·4 + component`) and the deformed positions: `X + Σ ΔP B B B`, or
/// `U₀ + Σ W(P − U₀) B B B / Σ W B B B` when rational (`C = 4`), stored by axis.
#[inline(always)]
fn tensor<S: Simd, const L: usize, const C: usize>(
    simd: S,
    control: &[S::f32s],
    basis: &[[S::f32s; L]; 3],
    block: &Block<S>,
    origin: &[S::f32s; 3],
) -> [[f32; MAX_LANES]; 3] {
    let zero = simd.splat_f32s(0.0);
    let mut acc = [zero; C];
    for k in 0..L {
        let mut acc_j = [zero; C];
        for j in 0..L {
            let mut acc_i = [zero; C];
            for i in 0..L {
                let base = (i + L * (j + L * k)) * COMPONENTS;
                for c in 0..C {
                    acc_i[c] = simd.mul_add_e_f32s(control[base + c], basis[0][i], acc_i[c]);
                }
            }
            for c in 0..C {
                acc_j[c] = simd.mul_add_e_f32s(acc_i[c], basis[1][j], acc_j[c]);
            }
        }
        for c in 0..C {
            acc[c] = simd.mul_add_e_f32s(acc_j[c], basis[2][k], acc[c]);
        }
    }
    let mut q = [[0.0_f32; MAX_LANES]; 3];
    for a in 0..3 {
        let moved = if C == 4 {
            simd.add_f32s(origin[a], simd.div_f32s(acc[a], acc[C - 1]))
        } else {
            simd.add_f32s(block.x[a], acc[a])
        };
        simd.partial_store_f32s(&mut q[a][..block.n], moved);
    }
    q
}

impl<const L: usize, const C: usize> WithSimd for Bernstein<'_, L, C> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let lat = self.lattice;
        let lanes = S::F32_LANES.min(MAX_LANES);
        let zero = simd.splat_f32s(0.0);
        // Every control value broadcast once: index (i + L(j + L k))·4 + component.
        let mut control: Vec<S::f32s> = Vec::with_capacity(lat.data.len() * COMPONENTS);
        for d in &lat.data {
            for c in 0..COMPONENTS {
                control.push(simd.splat_f32s(d[c]));
            }
        }
        let bin = binomials::<L>();
        let mut binomial = [zero; L];
        for i in 0..L {
            binomial[i] = simd.splat_f32s(bin[i]);
        }
        let one = simd.splat_f32s(1.0);
        let f = frame(simd, lat);

        for (idx, out) in self.active.chunks(lanes).zip(self.out.chunks_mut(lanes)) {
            let block = load(simd, &f, self.positions, idx);
            // Bᵢ(t) = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ on each axis.
            let mut basis = [[zero; L]; 3];
            for a in 0..3 {
                let t = block.u[a];
                let s = simd.sub_f32s(one, t);
                let mut tp = [one; L];
                let mut sp = [one; L];
                for i in 1..L {
                    tp[i] = simd.mul_f32s(tp[i - 1], t);
                    sp[i] = simd.mul_f32s(sp[i - 1], s);
                }
                for i in 0..L {
                    basis[a][i] = simd.mul_f32s(simd.mul_f32s(binomial[i], tp[i]), sp[L - 1 - i]);
                }
            }
            let q = tensor::<S, L, C>(simd, &control, &basis, &block, &f.origin);
            for l in 0..block.n {
                let (x, u) = block.lane(l);
                out[l] = if PreparedLattice::inside(u) {
                    Vec3::new(q[0][l], q[1][l], q[2][l])
                } else {
                    // Outside: the identity, or the falloff (scalar, rare).
                    lat.deform_with(x, PreparedLattice::tensor_fixed::<L>)
                };
            }
        }
    }
}

impl<const L: usize, const C: usize> WithSimd for BSpline<'_, L, C> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let lat = self.lattice;
        let lanes = S::F32_LANES.min(MAX_LANES);
        let zero = simd.splat_f32s(0.0);
        let one = simd.splat_f32s(1.0);
        let f = frame(simd, lat);
        let p = L - 1;
        let [nx, ny, _] = lat.counts;
        // The broadcast control values of the cell in hand (`loaded`): neighbouring
        // vertices, hence consecutive blocks, are mostly in one cell, which is then
        // broadcast once.
        let mut control: Vec<S::f32s> = vec![zero; L * L * L * COMPONENTS];
        let mut loaded: Option<[usize; 3]> = None;

        for (idx, out) in self.active.chunks(lanes).zip(self.out.chunks_mut(lanes)) {
            let block = load(simd, &f, self.positions, idx);
            // Each inside lane's cell (its span on each axis); outside lanes are done here.
            let mut cell = [None::<[usize; 3]>; MAX_LANES];
            for l in 0..block.n {
                let (x, u) = block.lane(l);
                if PreparedLattice::inside(u) {
                    let mut s = [0; 3];
                    for a in 0..3 {
                        if let AxisBasis::BSpline(kv) = &lat.axes[a] {
                            s[a] = kv.span(u[a]);
                        }
                    }
                    cell[l] = Some(s);
                } else {
                    out[l] = lat.deform_with(x, PreparedLattice::tensor_fixed::<L>);
                }
            }
            // Once per distinct cell: every lane computed with that cell, its own lanes kept.
            let mut done = [false; MAX_LANES];
            for first in 0..block.n {
                let Some(span) = cell[first] else { continue };
                if done[first] {
                    continue;
                }
                // N_{s−p..=s}(t) by Cox–de Boor, the scalar recurrence's operations.
                let mut basis = [[zero; L]; 3];
                for a in 0..3 {
                    let AxisBasis::BSpline(kv) = &lat.axes[a] else {
                        continue;
                    };
                    let knots = kv.knots();
                    let (s, t) = (span[a], block.u[a]);
                    let mut left = [zero; L];
                    let mut right = [zero; L];
                    let mut n = [zero; L];
                    n[0] = one;
                    for j in 1..=p {
                        left[j] = simd.sub_f32s(t, simd.splat_f32s(knots[s + 1 - j]));
                        right[j] = simd.sub_f32s(simd.splat_f32s(knots[s + j]), t);
                        let mut saved = zero;
                        for r in 0..j {
                            let tmp = simd.div_f32s(n[r], simd.add_f32s(right[r + 1], left[j - r]));
                            n[r] = simd.add_f32s(saved, simd.mul_f32s(right[r + 1], tmp));
                            saved = simd.mul_f32s(left[j - r], tmp);
                        }
                        n[j] = saved;
                    }
                    basis[a] = n;
                }
                if loaded != Some(span) {
                    let start = (span[0] - p) + nx * ((span[1] - p) + ny * (span[2] - p));
                    for k in 0..L {
                        for j in 0..L {
                            for i in 0..L {
                                let d = lat.data[start + i + nx * (j + ny * k)];
                                let base = (i + L * (j + L * k)) * COMPONENTS;
                                for c in 0..C {
                                    control[base + c] = simd.splat_f32s(d[c]);
                                }
                            }
                        }
                    }
                    loaded = Some(span);
                }
                let q = tensor::<S, L, C>(simd, &control, &basis, &block, &f.origin);
                for l in first..block.n {
                    if cell[l] == Some(span) {
                        out[l] = Vec3::new(q[0][l], q[1][l], q[2][l]);
                        done[l] = true;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use glam::Vec3;

    use crate::lattice::{LatticeFrame, LatticeTool, PreparedLattice};

    /// A skewed frame for the lattices of the tests.
    pub(in crate::lattice) fn frame() -> LatticeFrame {
        LatticeFrame {
            origin: Vec3::new(-1.0, -0.5, 0.2),
            s: Vec3::new(2.0, 0.3, 0.0),
            t: Vec3::new(-0.2, 1.5, 0.1),
            u: Vec3::new(0.1, 0.0, 1.2),
        }
    }

    /// A lattice with every control point moved (and weighted, when `rational`).
    fn moved(mut t: LatticeTool, rational: bool) -> PreparedLattice {
        t.falloff = 0.3;
        let (a, b, c) = t.counts;
        for k in 0..c {
            for j in 0..b {
                for i in 0..a {
                    let h = (i * 7 + j * 13 + k * 29) % 11;
                    t.set_offset(
                        (i, j, k),
                        Vec3::new(0.03 * h as f32, -0.02, 0.01 * h as f32),
                    );
                    if rational {
                        t.set_weight((i, j, k), 0.5 + 0.1 * h as f32);
                    }
                }
            }
        }
        t.prepare("test").unwrap()
    }

    /// Bernstein 2³…6³ and B-spline lattices of degree 1…3 with several counts per axis,
    /// rational or not.
    fn lattices() -> Vec<(String, PreparedLattice)> {
        let mut out = Vec::new();
        for rational in [false, true] {
            for n in 2..=6 {
                let t = LatticeTool::bernstein(frame(), (n, n, n));
                out.push((
                    format!("Bernstein {n}³ rational {rational}"),
                    moved(t, rational),
                ));
            }
            for (counts, degree) in [
                ((4, 4, 4), 2),
                ((5, 3, 6), 2),
                ((7, 6, 5), 3),
                ((3, 4, 2), 1),
            ] {
                let t = LatticeTool::bspline(frame(), counts, (degree, degree, degree));
                out.push((
                    format!("B-spline {counts:?} degree {degree} rational {rational}"),
                    moved(t, rational),
                ));
            }
        }
        out
    }

    /// Points inside, on the boundary and outside (within and beyond the falloff).
    pub(in crate::lattice) fn points(lat: &PreparedLattice) -> Vec<Vec3> {
        let mut pts = Vec::new();
        for a in 0..9 {
            for b in 0..7 {
                for c in 0..5 {
                    let u = Vec3::new(a as f32 / 8.0, b as f32 / 6.0, c as f32 / 4.0);
                    pts.push(lat.frame.point(u * 1.2 - Vec3::splat(0.1)));
                }
            }
        }
        pts
    }

    #[test]
    fn the_block_kernels_match_the_scalar_tensor_sum() {
        for (name, lat) in lattices() {
            assert!(lat.has_block_kernel(), "{name}");
            let pts = points(&lat);
            let active: Vec<u32> = (0..pts.len() as u32).collect();
            let mut out = vec![Vec3::ZERO; pts.len()];
            lat.deform_slice(&pts, &active, &mut out);
            for (p, q) in pts.iter().zip(&out) {
                let scalar = lat.deform_with(*p, PreparedLattice::tensor);
                assert!(
                    (scalar - *q).length() <= 2e-6 * (1.0 + scalar.length()),
                    "{name}: {p} → {q} (scalar {scalar})"
                );
            }
        }
    }

    /// Every third of `lat`'s test points, deformed in shifted blocks and each alone, has
    /// the bits it gets among all the points.
    pub(in crate::lattice) fn check_the_same_bits_in_any_block(name: &str, lat: &PreparedLattice) {
        let pts = points(lat);
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let mut all = vec![Vec3::ZERO; pts.len()];
        lat.deform_slice(&pts, &active, &mut all);
        let some: Vec<u32> = (1..pts.len() as u32).step_by(3).collect();
        let mut part = vec![Vec3::ZERO; some.len()];
        lat.deform_slice(&pts, &some, &mut part);
        for (&i, q) in some.iter().zip(&part) {
            assert_eq!(q.to_array(), all[i as usize].to_array(), "{name}");
            assert_eq!(
                lat.deform_point(pts[i as usize]).to_array(),
                q.to_array(),
                "{name}"
            );
        }
    }

    #[test]
    fn a_point_gets_the_same_bits_in_any_block() {
        for (name, lat) in lattices() {
            check_the_same_bits_in_any_block(&name, &lat);
        }
    }
}
