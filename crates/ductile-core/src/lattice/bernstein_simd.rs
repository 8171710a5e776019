//! Bernstein lattices deformed many points at a time.
//!
//! A Bernstein lattice has no knot spans: every point inside it reads all `L³` control
//! points, so a block of points (one per SIMD lane) shares every control value and the tensor
//! sum `Σₖ Bₖ(u₃) Σⱼ Bⱼ(u₂) Σᵢ Bᵢ(u₁) c_ijk` runs on whole registers, the control values
//! broadcast once per call. The register width is chosen when the program runs ([`pulp`]'s
//! dispatch): 8 lanes with fused multiply–add where the CPU has AVX2 and FMA, 4 lanes (SSE)
//! or scalar code elsewhere, so one binary runs everywhere and uses what it finds.
//!
//! Each lane's arithmetic depends only on its own point (no lane ever reads another), so a
//! point gets the same bits whatever block it is in; [`PreparedLattice::deform_point`] runs
//! the same kernel on one point. The lattice coordinates are computed exactly as the scalar
//! path computes them (the same unfused products and sums), so inside and outside are decided
//! identically, and points outside take the scalar path (identity or falloff).
//!
//! The Bernstein values are `Bᵢⁿ(t) = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ` (power form); they differ from
//! the de Casteljau recurrence of [`crate::basis::bernstein_all`] by a few ulps.

use glam::Vec3;
use pulp::{Simd, WithSimd};

use super::PreparedLattice;

/// The most lanes a block holds (AVX-512 has 16 `f32` lanes).
const MAX_LANES: usize = 16;

/// Components of the dense control data: `(ΔP, 0)` or `(W(P − U₀), W)`.
const COMPONENTS: usize = 4;

impl PreparedLattice {
    /// Deforms the `active` vertices of `positions` into `out` with the block kernel; `L` is
    /// the number of control points on every axis (the caller checked that the lattice is
    /// Bernstein with `L` points per axis).
    pub(super) fn deform_slice_bernstein<const L: usize>(
        &self,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
    ) {
        if self.rational {
            pulp::Arch::new().dispatch(Kernel::<L, 4> {
                lattice: self,
                positions,
                active,
                out,
            });
        } else {
            pulp::Arch::new().dispatch(Kernel::<L, 3> {
                lattice: self,
                positions,
                active,
                out,
            });
        }
    }
}

/// One call's work: `L` control points per axis, `C` components summed (3, or 4 when
/// rational).
struct Kernel<'a, const L: usize, const C: usize> {
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

impl<const L: usize, const C: usize> WithSimd for Kernel<'_, L, C> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let lat = self.lattice;
        let lanes = S::F32_LANES.min(MAX_LANES);
        let zero = simd.splat_f32s(0.0);
        // Every control value broadcast once: index (i + L(j + L k))·4 + component.
        let control: Vec<S::f32s> = lat
            .data
            .iter()
            .flat_map(|d| d.to_array())
            .map(|c| simd.splat_f32s(c))
            .collect();
        if control.len() != L * L * L * COMPONENTS {
            // Not reached through `deform_slice`, which checks the counts; stay exact anyway.
            for (o, &i) in self.out.iter_mut().zip(self.active) {
                *o = lat.deform_with(self.positions[i as usize], PreparedLattice::tensor);
            }
            return;
        }
        // No closures below: they would not inherit the dispatched target features, and
        // every SIMD operation in them would become a call.
        let bin = binomials::<L>();
        let mut binomial = [zero; L];
        for i in 0..L {
            binomial[i] = simd.splat_f32s(bin[i]);
        }
        let one = simd.splat_f32s(1.0);
        let o = lat.frame.origin;
        let origin = [
            simd.splat_f32s(o.x),
            simd.splat_f32s(o.y),
            simd.splat_f32s(o.z),
        ];
        let mut rows = [[zero; 3]; 3];
        for a in 0..3 {
            for c in 0..3 {
                rows[a][c] = simd.splat_f32s(lat.rows[a][c]);
            }
        }

        for (idx, out) in self.active.chunks(lanes).zip(self.out.chunks_mut(lanes)) {
            let n = idx.len();
            let mut p = [[0.0_f32; MAX_LANES]; 3];
            for (l, &i) in idx.iter().enumerate() {
                let v = self.positions[i as usize];
                p[0][l] = v.x;
                p[1][l] = v.y;
                p[2][l] = v.z;
            }
            let mut x = [zero; 3];
            let mut d = [zero; 3];
            for a in 0..3 {
                x[a] = simd.partial_load_f32s(&p[a][..n]);
                d[a] = simd.sub_f32s(x[a], origin[a]);
            }
            // u_a = (r_a.x·dx + r_a.y·dy) + r_a.z·dz, unfused: glam's `dot`, bit for bit.
            let mut u = [zero; 3];
            let mut uc = [[0.0_f32; MAX_LANES]; 3];
            for a in 0..3 {
                let r = rows[a];
                u[a] = simd.add_f32s(
                    simd.add_f32s(simd.mul_f32s(r[0], d[0]), simd.mul_f32s(r[1], d[1])),
                    simd.mul_f32s(r[2], d[2]),
                );
                simd.partial_store_f32s(&mut uc[a][..n], u[a]);
            }

            // Bᵢ(t) = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ on each axis.
            let mut basis = [[zero; L]; 3];
            for a in 0..3 {
                let t = u[a];
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

            let mut acc = [zero; C];
            for k in 0..L {
                let mut acc_j = [zero; C];
                for j in 0..L {
                    let mut acc_i = [zero; C];
                    for i in 0..L {
                        let base = (i + L * (j + L * k)) * COMPONENTS;
                        for c in 0..C {
                            acc_i[c] =
                                simd.mul_add_e_f32s(control[base + c], basis[0][i], acc_i[c]);
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

            // Non-rational: X + Σ ΔP B B B; rational: U₀ + Σ W(P − U₀) B B B / Σ W B B B.
            let mut q = [[0.0_f32; MAX_LANES]; 3];
            for a in 0..3 {
                let moved = if C == 4 {
                    simd.add_f32s(origin[a], simd.div_f32s(acc[a], acc[C - 1]))
                } else {
                    simd.add_f32s(x[a], acc[a])
                };
                simd.partial_store_f32s(&mut q[a][..n], moved);
            }
            for l in 0..n {
                let u = Vec3::new(uc[0][l], uc[1][l], uc[2][l]);
                out[l] = if PreparedLattice::inside(u) {
                    Vec3::new(q[0][l], q[1][l], q[2][l])
                } else {
                    // Outside: the identity, or the falloff (scalar, rare).
                    let x = Vec3::new(p[0][l], p[1][l], p[2][l]);
                    lat.deform_with(x, PreparedLattice::tensor_fixed::<L>)
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use crate::lattice::{LatticeFrame, LatticeTool, PreparedLattice};

    fn lattice(counts: u32, rational: bool) -> PreparedLattice {
        let frame = LatticeFrame {
            origin: Vec3::new(-1.0, -0.5, 0.2),
            s: Vec3::new(2.0, 0.3, 0.0),
            t: Vec3::new(-0.2, 1.5, 0.1),
            u: Vec3::new(0.1, 0.0, 1.2),
        };
        let mut t = LatticeTool::bernstein(frame, (counts, counts, counts));
        t.falloff = 0.3;
        for k in 0..counts {
            for j in 0..counts {
                for i in 0..counts {
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

    /// Points inside, on the boundary and outside (within and beyond the falloff).
    fn points(lat: &PreparedLattice) -> Vec<Vec3> {
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
    fn the_block_kernel_matches_the_scalar_tensor_sum() {
        for counts in 2..=6 {
            for rational in [false, true] {
                let lat = lattice(counts, rational);
                let pts = points(&lat);
                let active: Vec<u32> = (0..pts.len() as u32).collect();
                let mut out = vec![Vec3::ZERO; pts.len()];
                lat.deform_slice(&pts, &active, &mut out);
                for (p, q) in pts.iter().zip(&out) {
                    let scalar = lat.deform_with(*p, PreparedLattice::tensor);
                    assert!(
                        (scalar - *q).length() <= 2e-6 * (1.0 + scalar.length()),
                        "{counts}³ rational {rational}: {p} → {q} (scalar {scalar})"
                    );
                }
            }
        }
    }

    #[test]
    fn a_point_gets_the_same_bits_in_any_block() {
        let lat = lattice(4, false);
        let pts = points(&lat);
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let mut all = vec![Vec3::ZERO; pts.len()];
        lat.deform_slice(&pts, &active, &mut all);
        // Every third point, in shifted blocks, and each point alone.
        let some: Vec<u32> = (1..pts.len() as u32).step_by(3).collect();
        let mut part = vec![Vec3::ZERO; some.len()];
        lat.deform_slice(&pts, &some, &mut part);
        for (&i, q) in some.iter().zip(&part) {
            assert_eq!(q.to_array(), all[i as usize].to_array());
            assert_eq!(lat.deform_point(pts[i as usize]).to_array(), q.to_array());
        }
    }
}
