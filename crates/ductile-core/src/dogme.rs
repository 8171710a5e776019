//! DOGME constraint points (the survey's 0-D tool, Bechmann §5.1, after Borrel & Bechmann):
//!
//! `D(U) = U + M f(U)`, with `M` a `3 × m` matrix and `f : ℝ³ → ℝᵐ` the extrusion function,
//! one component per constraint point. Constraint `j` sits at `c_j` (a free point or a mesh
//! vertex), asks for the displacement `δ_j`, and has a support (box or sphere) centred on
//! `c_j`; its extrusion component is a product (box) or radial (sphere) B-spline bump of
//! degree `d ≥ 2` that is 1 at `c_j` and exactly 0 outside the support, so the support *is*
//! the deformed area. `M` solves `M F = Δ` (`F_ij = f_j(c_i)`, `Δ = [δ₁ … δ_m]`) by the
//! pseudo-inverse, `M = Δ F⁺`: every constraint is met exactly when the constraints are
//! compatible, in the least-squares sense otherwise (the survey: "unless two opposite
//! constraints are applied to a unique point in space. In that case, the system computes the
//! best approximation"). `docs/algorithms/dogme.md` gives the details.

use faer::Mat;
use glam::{Affine3A, Mat3, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::basis::MAX_DEGREE;
use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::tool::{BindInput, Deformer, uniform_scale};

/// Where a constraint sits: a free point or a mesh vertex (welded index, taken at the
/// layer's input positions when binding).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Anchor {
    /// A point in tool space.
    Point(Vec3),
    /// A welded mesh vertex.
    Vertex(u32),
}

impl Anchor {
    /// The anchor's position given the layer input.
    pub fn resolve(&self, positions: &[Vec3], what: &str) -> Result<Vec3> {
        match *self {
            Anchor::Point(p) => Ok(p),
            Anchor::Vertex(i) => {
                positions
                    .get(i as usize)
                    .copied()
                    .ok_or_else(|| CoreError::NoSuchVertex {
                        what: what.to_string(),
                        index: i,
                        vertices: positions.len(),
                    })
            }
        }
    }

    fn validate(&self, what: &str) -> Result<()> {
        match self {
            Anchor::Point(p) => check_finite_vec3(|| format!("{what}: point"), *p),
            Anchor::Vertex(_) => Ok(()),
        }
    }

    fn transformed(&self, m: &Affine3A) -> Self {
        match *self {
            Anchor::Point(p) => Anchor::Point(m.transform_point3(p)),
            v => v,
        }
    }
}

/// The support of a constraint's extrusion function, centred on the constraint point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Support {
    /// A ball: `f(U) = β(|U − c| / r)`.
    Sphere {
        /// Radius `r > 0`.
        radius: f32,
    },
    /// A box: `f(U) = β(l_x) β(l_y) β(l_z)` with `l = R⁻¹(U − c) / h`.
    Box {
        /// Half extents `h` along the box axes (each > 0).
        half_extents: Vec3,
        /// Orientation `R` of the box axes (identity: axis-aligned).
        #[serde(default)]
        rotation: Quat,
    },
}

impl Support {
    fn validate(&self, what: &str) -> Result<()> {
        let positive = |name: &str, v: f32| -> Result<()> {
            check_finite(|| format!("{what}: {name}"), v)?;
            if v <= 0.0 {
                return Err(CoreError::Degenerate {
                    what: format!("{what}: {name}"),
                    problem: format!("the support has zero size ({v}); it must be > 0"),
                });
            }
            Ok(())
        };
        match *self {
            Support::Sphere { radius } => positive("radius", radius),
            Support::Box {
                half_extents,
                rotation,
            } => {
                positive("half_extents.x", half_extents.x)?;
                positive("half_extents.y", half_extents.y)?;
                positive("half_extents.z", half_extents.z)?;
                if !rotation.is_finite() || rotation.length_squared() < 1e-12 {
                    return Err(CoreError::Degenerate {
                        what: format!("{what}: rotation"),
                        problem: format!("{rotation} is not a rotation"),
                    });
                }
                Ok(())
            }
        }
    }

    /// Exact for similarity transforms: the sphere radius and the box extents scale by the
    /// length each box axis gets; under a shear or non-uniform scale the sphere uses the
    /// uniform scale and the box is re-orthonormalised (Gram–Schmidt from its X axis).
    fn transformed(&self, m: &Affine3A) -> Self {
        match *self {
            Support::Sphere { radius } => Support::Sphere {
                radius: radius * uniform_scale(m),
            },
            Support::Box {
                half_extents,
                rotation,
            } => {
                let r = Mat3::from_quat(rotation.normalize());
                let a = [0, 1, 2].map(|i| m.transform_vector3(r.col(i) * half_extents[i]));
                let x = a[0].normalize_or_zero();
                let y = (a[1] - x * x.dot(a[1])).normalize_or_zero();
                let z = x.cross(y);
                let basis = Mat3::from_cols(x, y, z);
                let rotation = if basis.determinant() > 0.5 {
                    Quat::from_mat3(&basis)
                } else {
                    rotation
                };
                Support::Box {
                    half_extents: Vec3::new(a[0].length(), a[1].length(), a[2].length()),
                    rotation,
                }
            }
        }
    }
}

/// One DOGME constraint: a point, its target displacement and its support.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constraint {
    /// The constraint point.
    pub at: Anchor,
    /// The displacement `δ` the point must receive (tool space).
    pub displacement: Vec3,
    /// The support: exactly the deformed area of this constraint.
    pub support: Support,
}

/// A DOGME tool: constraint points and the degree of the B-spline extrusion functions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DogmeTool {
    /// The constraints.
    pub constraints: Vec<Constraint>,
    /// Degree `d` of the B-spline bump, `2 ≤ d ≤ 15` (default 3: C² at the support boundary).
    #[serde(default = "three")]
    pub degree: u32,
}

fn three() -> u32 {
    3
}

/// The 1-D extrusion profile `β(t)`, `t ∈ [−1, 1]`: the uniform B-spline of degree `d` on
/// `d + 2` equally spaced knots over `[−1, 1]`, scaled so that `β(0) = 1`; 0 for `|t| ≥ 1`.
/// It is the middle basis function `N_{d,d}` of the clamped uniform knot vector of `2d + 1`
/// control points (whose knots `κ_d … κ_{2d+1}` are exactly uniform on `[0, 1]`), and is
/// evaluated as the cardinal B-spline on the integer knots `0, 1, …, d + 1` at
/// `x = (t + 1)(d + 1)/2` (`docs/algorithms/dogme.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// The degree `d`.
    degree: usize,
    /// `(d + 1)/2`, the knot spans per unit of `t`.
    half: f32,
    /// `d! N(x)` at the centre `x = (d + 1)/2`, by which [`Profile::eval`] divides.
    peak: f32,
}

impl Profile {
    /// The profile of degree `d ∈ [2, 15]`; `None` outside that range.
    #[must_use]
    pub fn new(degree: usize) -> Option<Self> {
        if !(2..=MAX_DEGREE).contains(&degree) {
            return None;
        }
        let half = 0.5 * (degree + 1) as f32;
        let mut me = Self {
            degree,
            half,
            peak: 1.0,
        };
        let peak = me.unscaled(half);
        if !(peak > 0.0 && peak.is_finite()) {
            return None;
        }
        me.peak = peak;
        Some(me)
    }

    /// `d! N(x)`, the cardinal B-spline of degree `d` on the knots `0, 1, …, d + 1` at
    /// `x ∈ [0, d + 1]`, times `d!`: de Boor's recurrence on integer knots without its
    /// divisions by `p`, `U_{i,0}(x) = [i ≤ x < i + 1]` (the last span closed) and
    /// `U_{i,p} = (x − i) U_{i,p−1} + (i + p + 1 − x) U_{i+1,p−1}`, up to `U_{0,d}`. Every
    /// term is a product of non-negative factors (a factor of the wrong sign meets a zero
    /// function), so nothing cancels.
    fn unscaled(&self, x: f32) -> f32 {
        // The cubic (the default) written out, the others by the loop: the same operations.
        if self.degree == 3 {
            unscaled_cubic(x)
        } else {
            unscaled_any(self.degree, x)
        }
    }

    /// `β(t)`: 1 at 0, 0 for `|t| ≥ 1`, `C^{d−1}` everywhere.
    #[must_use]
    pub fn eval(&self, t: f32) -> f32 {
        if t.is_nan() || t.abs() >= 1.0 {
            return 0.0;
        }
        (self.unscaled((t + 1.0) * self.half) / self.peak).max(0.0)
    }
}

/// [`Profile::unscaled`] of degree `d ∈ [1, MAX_DEGREE]`: in span `j = ⌊x⌋` the non-zero
/// functions of level `p` are `U_{j−p+r,p}`, `r = 0..=p`, kept as `n[r]`. Only for
/// `0 ≤ x ≤ d + 1` (what [`Profile::eval`] passes): outside the support the span's
/// polynomial is not zero (`x^d` below 0).
fn unscaled_any(d: usize, x: f32) -> f32 {
    debug_assert!(
        (0.0..=(d + 1) as f32).contains(&x),
        "x = {x} outside [0, {}]",
        d + 1
    );
    // `x ≥ 0` here; the cast saturates, and `x = d + 1` falls in the last span.
    let j = (x as usize).min(d);
    let mut n = [0.0_f32; MAX_DEGREE + 1];
    n[0] = 1.0;
    for p in 1..=d {
        // Down from `r = p`, so that `n[r − 1]` is still level `p − 1` when `n[r]` is written.
        for r in (0..=p).rev() {
            // `U_{i,p} = (x − i) U_{i,p−1} + (i + p + 1 − x) U_{i+1,p−1}` with `i = j − p + r`.
            let i = (j + r) as f32 - p as f32;
            let left = if r > 0 { (x - i) * n[r - 1] } else { 0.0 };
            let right = if r < p {
                (i + (p + 1) as f32 - x) * n[r]
            } else {
                0.0
            };
            n[r] = left + right;
        }
    }
    n[d - j]
}

/// [`unscaled_any`] of degree 3 written out: the same operations on values in registers.
/// The loop keeps its array in memory, where reading a value back after the stores that
/// zeroed it stalls: [`Profile::eval`] took 17 ns a call with the loop and 8.3 with this
/// (25 with the recurrence of [`KnotVector::basis`](crate::basis::KnotVector::basis), which
/// the profile used before).
#[inline]
fn unscaled_cubic(x: f32) -> f32 {
    debug_assert!((0.0..=4.0).contains(&x), "x = {x} outside [0, 4]");
    let j = (x as usize).min(3);
    // `i` of step `(p, r)` is `j + r − p`: `jr(r)` is `j + r` as `f32`, less `p` below.
    let jr = |k: usize| (j + k) as f32;
    let step = |p: usize, r: usize, below: f32, at: f32| {
        let i = jr(r) - p as f32;
        let left = if r > 0 { (x - i) * below } else { 0.0 };
        let right = if r < p {
            (i + (p + 1) as f32 - x) * at
        } else {
            0.0
        };
        left + right
    };
    // Level 1 from `n = [1, 0, 0, 0]`, then levels 2 and 3, each from `r = p` down.
    let (n0, n1) = (1.0, 0.0);
    let n1 = step(1, 1, n0, n1);
    let n0 = step(1, 0, 0.0, n0);
    let n2 = step(2, 2, n1, 0.0);
    let n1 = step(2, 1, n0, n1);
    let n0 = step(2, 0, 0.0, n0);
    let n3 = step(3, 3, n2, 0.0);
    let n2 = step(3, 2, n1, n2);
    let n1 = step(3, 1, n0, n1);
    let n0 = step(3, 0, 0.0, n0);
    match j {
        0 => n3,
        1 => n2,
        2 => n1,
        _ => n0,
    }
}

/// A constraint prepared for evaluation.
#[derive(Debug, Clone, Copy)]
struct Prepared {
    centre: Vec3,
    /// Inverse of `R · diag(h)` for boxes, `1/r` on the diagonal for spheres.
    to_local: Mat3,
    sphere: bool,
    /// Column `j` of `M`.
    column: Vec3,
}

impl Prepared {
    #[inline]
    fn extrusion(&self, profile: &Profile, x: Vec3) -> f32 {
        let l = self.to_local * (x - self.centre);
        if self.sphere {
            profile.eval(l.length())
        } else if l.abs().max_element() >= 1.0 {
            0.0
        } else {
            profile.eval(l.x) * profile.eval(l.y) * profile.eval(l.z)
        }
    }
}

/// Bind of a [`DogmeTool`]: the constraint points, supports and the solved matrix `M`.
#[derive(Debug, Clone)]
pub struct DogmeBind {
    profile: Option<Profile>,
    constraints: Vec<Prepared>,
    rank: usize,
    residual: f32,
}

impl DogmeBind {
    /// The numerical rank of `F` (equal to the number of constraints when they are
    /// independent).
    #[must_use]
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// `max_j |M f(c_j) − δ_j|`: 0 (to rounding) when every constraint is met, the
    /// least-squares misfit otherwise.
    #[must_use]
    pub fn residual(&self) -> f32 {
        self.residual
    }

    /// The columns of `M`, one per constraint.
    #[must_use]
    pub fn columns(&self) -> Vec<Vec3> {
        self.constraints.iter().map(|c| c.column).collect()
    }

    /// `M f(x)`.
    #[inline]
    fn displacement(&self, x: Vec3) -> Vec3 {
        let Some(profile) = &self.profile else {
            return Vec3::ZERO;
        };
        self.constraints.iter().fold(Vec3::ZERO, |acc, c| {
            let f = c.extrusion(profile, x);
            if f == 0.0 { acc } else { acc + c.column * f }
        })
    }
}

/// The minimum-norm least-squares solution `X = A⁺ B` of `A X = B` (`A` is `rows × cols`,
/// `B` is `rows × 3`), by the thin SVD of `A` in f64 (faer). Singular values below
/// `10⁻¹⁰ · σ_max · max(rows, cols)` count as zero. Returns `X` (`cols` rows) and the rank.
pub(crate) fn min_norm_solve(
    a: &Mat<f64>,
    b: &[[f64; 3]],
    what: &str,
) -> Result<(Vec<[f64; 3]>, usize)> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let svd = a.thin_svd().map_err(|e| CoreError::Degenerate {
        what: what.to_string(),
        problem: format!("the singular value decomposition did not converge ({e:?})"),
    })?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    let k = rows.min(cols);
    let smax = (0..k).map(|i| s[i]).fold(0.0_f64, f64::max);
    let tol = 1e-10 * smax * rows.max(cols) as f64;
    let mut x = vec![[0.0_f64; 3]; cols];
    let mut rank = 0;
    for i in 0..k {
        if s[i].is_nan() || s[i] <= tol {
            continue;
        }
        rank += 1;
        // c = (uᵢᵀ B) / σᵢ, X += vᵢ c.
        let mut c = [0.0_f64; 3];
        for r in 0..rows {
            for (cd, bd) in c.iter_mut().zip(b[r]) {
                *cd += u[(r, i)] * bd;
            }
        }
        for cd in &mut c {
            *cd /= s[i];
        }
        for (j, xj) in x.iter_mut().enumerate() {
            for d in 0..3 {
                xj[d] += v[(j, i)] * c[d];
            }
        }
    }
    if x.iter().flatten().any(|v| !v.is_finite()) {
        return Err(CoreError::Degenerate {
            what: what.to_string(),
            problem: "the constraint system is singular (the solution is not finite)".into(),
        });
    }
    Ok((x, rank))
}

impl Deformer for DogmeTool {
    type Bind = DogmeBind;

    fn validate(&self, what: &str) -> Result<()> {
        if Profile::new(self.degree as usize).is_none() {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: degree"),
                value: f64::from(self.degree),
                expected: "the extrusion B-spline degree must be in [2, 15]",
            });
        }
        for (k, c) in self.constraints.iter().enumerate() {
            let w = format!("{what}: constraint {k}");
            c.at.validate(&w)?;
            check_finite_vec3(|| format!("{w}: displacement"), c.displacement)?;
            c.support.validate(&w)?;
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<DogmeBind> {
        let what = "DOGME";
        let profile = Profile::new(self.degree as usize).ok_or_else(|| CoreError::OutOfRange {
            what: format!("{what}: degree"),
            value: f64::from(self.degree),
            expected: "the extrusion B-spline degree must be in [2, 15]",
        })?;
        let mut prepared = Vec::with_capacity(self.constraints.len());
        for (k, c) in self.constraints.iter().enumerate() {
            let centre =
                c.at.resolve(input.positions, &format!("{what}: constraint {k}"))?;
            let (to_local, sphere) = match c.support {
                Support::Sphere { radius } => {
                    (Mat3::from_diagonal(Vec3::splat(1.0 / radius)), true)
                }
                Support::Box {
                    half_extents,
                    rotation,
                } => (
                    Mat3::from_diagonal(half_extents.recip())
                        * Mat3::from_quat(rotation.normalize()).transpose(),
                    false,
                ),
            };
            prepared.push(Prepared {
                centre,
                to_local,
                sphere,
                column: Vec3::ZERO,
            });
        }
        let m = prepared.len();
        if m == 0 {
            return Ok(DogmeBind {
                profile: Some(profile),
                constraints: prepared,
                rank: 0,
                residual: 0.0,
            });
        }
        // M F = Δ  ⇔  Fᵀ Mᵀ = Δᵀ, with (Fᵀ)_ij = F_ji = f_i(c_j).
        let ft = Mat::<f64>::from_fn(m, m, |j, i| {
            f64::from(prepared[i].extrusion(&profile, prepared[j].centre))
        });
        let rhs: Vec<[f64; 3]> = self
            .constraints
            .iter()
            .map(|c| c.displacement.as_dvec3().to_array())
            .collect();
        let (mt, rank) = min_norm_solve(&ft, &rhs, what)?;
        for (p, col) in prepared.iter_mut().zip(&mt) {
            p.column = Vec3::new(col[0] as f32, col[1] as f32, col[2] as f32);
        }
        let mut bind = DogmeBind {
            profile: Some(profile),
            constraints: prepared,
            rank,
            residual: 0.0,
        };
        bind.residual = self
            .constraints
            .iter()
            .zip(&bind.constraints)
            .map(|(c, p)| (bind.displacement(p.centre) - c.displacement).length())
            .fold(0.0, f32::max);
        Ok(bind)
    }

    fn deform(&self, bind: &DogmeBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        for (o, &i) in out.iter_mut().zip(active) {
            let x = positions[i as usize];
            *o = x + bind.displacement(x);
        }
    }

    /// Points map as points, displacements by the linear part of `m`; supports as in
    /// [`Support`] (exact for similarity transforms).
    fn transformed(&self, m: &Affine3A) -> Self {
        Self {
            constraints: self
                .constraints
                .iter()
                .map(|c| Constraint {
                    at: c.at.transformed(m),
                    displacement: m.transform_vector3(c.displacement),
                    support: c.support.transformed(m),
                })
                .collect(),
            degree: self.degree,
        }
    }

    /// The bind solves `M` from every parameter (and the input positions of vertex anchors),
    /// so any change re-binds (an `m × m` SVD).
    fn same_rest_state(&self, other: &Self) -> bool {
        self == other
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;
    use proptest::prelude::*;

    fn topo() -> Topology {
        Topology {
            weld: Vec::new(),
            representative: Vec::new(),
            triangles: Vec::new(),
        }
    }

    fn apply(tool: &DogmeTool, positions: &[Vec3]) -> (Vec<Vec3>, DogmeBind) {
        tool.validate("t").unwrap();
        let active: Vec<u32> = (0..positions.len() as u32).collect();
        let t = topo();
        let bind = tool
            .bind(&BindInput {
                positions,
                topology: &t,
                active: &active,
            })
            .unwrap();
        let mut out = vec![Vec3::ZERO; positions.len()];
        tool.deform(&bind, positions, &active, &mut out);
        (out, bind)
    }

    fn grid() -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..11 {
            for j in 0..11 {
                for k in 0..3 {
                    v.push(Vec3::new(
                        i as f32 * 0.2 - 1.0,
                        j as f32 * 0.2 - 1.0,
                        k as f32 * 0.1,
                    ));
                }
            }
        }
        v
    }

    #[test]
    fn profile_oracle_quadratic_and_cubic() {
        // Quadratic uniform B-spline on knots −1, −⅓, ⅓, 1, peak ¾ (in units of the knot
        // spacing h = ⅔): on the middle piece N(s) = ¾ − s² with s = t/h, so β(t) = 1 − (4/3)(1.5t)².
        // On the outer piece N = ½(1.5 − s)², β = ⅔(1.5 − s)².
        let p = Profile::new(2).unwrap();
        for t in [0.0_f32, 0.1, 0.3] {
            let s = 1.5 * t;
            assert!(
                (p.eval(t) - (1.0 - 4.0 / 3.0 * s * s)).abs() < 1e-5,
                "t={t}"
            );
        }
        for t in [0.5_f32, 0.8, -0.9] {
            let s = 1.5 * t.abs();
            assert!(
                (p.eval(t) - 2.0 / 3.0 * (1.5 - s).powi(2)).abs() < 1e-5,
                "t={t}"
            );
        }
        // Cubic: β(±½) = N(±1 knot) / N(0) = (1/6) / (4/6) = ¼.
        let c = Profile::new(3).unwrap();
        assert!((c.eval(0.5) - 0.25).abs() < 1e-6);
        assert!((c.eval(-0.5) - 0.25).abs() < 1e-6);
        assert_eq!(c.eval(0.0), 1.0);
        assert_eq!(c.eval(1.0), 0.0);
        assert_eq!(c.eval(-1.2), 0.0);
    }

    #[test]
    fn the_written_out_cubic_is_the_loop() {
        for k in 0..=40_000 {
            let x = k as f32 / 10_000.0;
            assert_eq!(
                unscaled_cubic(x).to_bits(),
                unscaled_any(3, x).to_bits(),
                "x = {x}"
            );
        }
    }

    #[test]
    fn profile_is_the_middle_function_of_the_clamped_knot_vector() {
        // The definition: `N_{d,d}` of the clamped uniform knot vector of `2d + 1` control
        // points (Cox–de Boor), scaled to 1 at the centre, against the integer-knot form.
        for d in 2..=MAX_DEGREE {
            let knots = crate::basis::KnotVector::clamped_uniform(d, 2 * d + 1).unwrap();
            let n = |s: f32| {
                let mut b = [0.0_f32; MAX_DEGREE + 1];
                let span = knots.basis(s, &mut b);
                if span < d || span - d > d {
                    0.0
                } else {
                    b[d - (span - d)]
                }
            };
            let peak = n(0.5);
            let profile = Profile::new(d).unwrap();
            assert_eq!(profile.eval(0.0), 1.0, "degree {d}");
            for k in -999..=999 {
                let t = k as f32 / 1000.0;
                let (got, want) = (profile.eval(t), n(0.5 * (t + 1.0)) / peak);
                assert!(
                    (got - want).abs() <= 2e-6 * want.max(0.05) + 1e-7,
                    "degree {d}, t = {t}: {got} against {want}"
                );
                assert!((0.0..=1.0).contains(&got), "degree {d}, t = {t}: {got}");
            }
        }
    }

    #[test]
    fn single_constraint_is_met_and_local() {
        let tool = DogmeTool {
            constraints: vec![Constraint {
                at: Anchor::Point(Vec3::ZERO),
                displacement: Vec3::new(0.0, 0.0, 0.3),
                support: Support::Sphere { radius: 0.5 },
            }],
            degree: 3,
        };
        let mut pts = grid();
        pts.push(Vec3::ZERO);
        let (out, bind) = apply(&tool, &pts);
        assert_eq!(bind.rank(), 1);
        assert!((out[pts.len() - 1] - Vec3::new(0.0, 0.0, 0.3)).length() < 1e-6);
        for (p, q) in pts.iter().zip(&out) {
            if p.length() >= 0.5 {
                assert_eq!(p, q, "outside the support nothing moves");
            } else if p.length() < 0.45 {
                assert!(q.z > p.z);
            }
        }
    }

    #[test]
    fn overlapping_box_constraints_are_met_exactly() {
        let tool = DogmeTool {
            constraints: vec![
                Constraint {
                    at: Anchor::Point(Vec3::new(-0.1, 0.0, 0.0)),
                    displacement: Vec3::new(0.0, 0.0, 0.2),
                    support: Support::Box {
                        half_extents: Vec3::new(0.5, 0.4, 0.3),
                        rotation: Quat::IDENTITY,
                    },
                },
                Constraint {
                    at: Anchor::Point(Vec3::new(0.15, 0.1, 0.0)),
                    displacement: Vec3::new(0.1, 0.0, -0.1),
                    support: Support::Box {
                        half_extents: Vec3::new(0.3, 0.6, 0.3),
                        rotation: Quat::from_rotation_z(0.4),
                    },
                },
                Constraint {
                    at: Anchor::Vertex(0),
                    displacement: Vec3::new(0.0, 0.05, 0.0),
                    support: Support::Sphere { radius: 0.4 },
                },
            ],
            degree: 2,
        };
        let pts = vec![
            Vec3::new(0.05, -0.1, 0.05),
            Vec3::new(-0.1, 0.0, 0.0),
            Vec3::new(0.15, 0.1, 0.0),
            Vec3::new(0.9, 0.9, 0.9),
        ];
        let (out, bind) = apply(&tool, &pts);
        assert_eq!(bind.rank(), 3);
        assert!(bind.residual() < 1e-5);
        assert!((out[0] - pts[0] - Vec3::new(0.0, 0.05, 0.0)).length() < 1e-5);
        assert!((out[1] - pts[1] - Vec3::new(0.0, 0.0, 0.2)).length() < 1e-5);
        assert!((out[2] - pts[2] - Vec3::new(0.1, 0.0, -0.1)).length() < 1e-5);
        assert_eq!(out[3], pts[3]);
    }

    #[test]
    fn opposite_constraints_on_one_point_give_least_squares() {
        let c = |d: f32| Constraint {
            at: Anchor::Point(Vec3::ZERO),
            displacement: Vec3::new(0.0, d, 0.0),
            support: Support::Sphere { radius: 1.0 },
        };
        let tool = DogmeTool {
            constraints: vec![c(0.4), c(-0.2)],
            degree: 3,
        };
        let (out, bind) = apply(&tool, &[Vec3::ZERO]);
        assert_eq!(bind.rank(), 1);
        // The best approximation of both: the mean displacement 0.1.
        assert!(
            (out[0] - Vec3::new(0.0, 0.1, 0.0)).length() < 1e-6,
            "{}",
            out[0]
        );
        assert!((bind.residual() - 0.3).abs() < 1e-5);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let ok = Constraint {
            at: Anchor::Point(Vec3::ZERO),
            displacement: Vec3::X,
            support: Support::Sphere { radius: 1.0 },
        };
        let tool = |c: Constraint, degree: u32| DogmeTool {
            constraints: vec![c],
            degree,
        };
        assert!(tool(ok, 3).validate("t").is_ok());
        assert!(tool(ok, 1).validate("t").is_err());
        assert!(tool(ok, 16).validate("t").is_err());
        let zero = Constraint {
            support: Support::Sphere { radius: 0.0 },
            ..ok
        };
        assert!(matches!(
            tool(zero, 3).validate("t"),
            Err(CoreError::Degenerate { .. })
        ));
        let flat = Constraint {
            support: Support::Box {
                half_extents: Vec3::new(1.0, 0.0, 1.0),
                rotation: Quat::IDENTITY,
            },
            ..ok
        };
        assert!(tool(flat, 3).validate("t").is_err());
        let nan = Constraint {
            displacement: Vec3::new(f32::NAN, 0.0, 0.0),
            ..ok
        };
        assert!(matches!(
            tool(nan, 3).validate("t"),
            Err(CoreError::NotFinite { .. })
        ));
        let missing = Constraint {
            at: Anchor::Vertex(7),
            ..ok
        };
        let t = topo();
        let r = tool(missing, 3).bind(&BindInput {
            positions: &[Vec3::ZERO],
            topology: &t,
            active: &[0],
        });
        assert!(matches!(r, Err(CoreError::NoSuchVertex { .. })));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Compatible random constraints (distinct points) are always met.
        #[test]
        fn random_constraints_are_met(
            pts in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 1..6),
            disp in prop::collection::vec(prop::array::uniform3(-0.3f32..0.3), 6),
        ) {
            let mut centres: Vec<Vec3> = Vec::new();
            for p in pts {
                let p = Vec3::from(p);
                if centres.iter().all(|c| c.distance(p) > 0.2) {
                    centres.push(p);
                }
            }
            let tool = DogmeTool {
                constraints: centres.iter().zip(&disp).map(|(c, d)| Constraint {
                    at: Anchor::Point(*c),
                    displacement: Vec3::from(*d),
                    support: Support::Sphere { radius: 0.6 },
                }).collect(),
                degree: 3,
            };
            let (out, _) = apply(&tool, &centres);
            for ((c, d), o) in centres.iter().zip(&disp).zip(&out) {
                prop_assert!((*o - *c - Vec3::from(*d)).length() < 1e-4);
            }
        }

        /// Mapping after deforming equals deforming with the mapped tool (similarities).
        #[test]
        fn transformed_commutes(angle in -3.0f32..3.0, s in 0.5f32..2.0, x in prop::array::uniform3(-0.6f32..0.6)) {
            let tool = DogmeTool {
                constraints: vec![
                    Constraint {
                        at: Anchor::Point(Vec3::new(0.1, 0.0, 0.0)),
                        displacement: Vec3::new(0.0, 0.2, 0.1),
                        support: Support::Box { half_extents: Vec3::new(0.7, 0.5, 0.6), rotation: Quat::from_rotation_y(0.3) },
                    },
                    Constraint {
                        at: Anchor::Point(Vec3::new(-0.2, 0.1, 0.0)),
                        displacement: Vec3::new(0.1, 0.0, 0.0),
                        support: Support::Sphere { radius: 0.5 },
                    },
                ],
                degree: 3,
            };
            let m = Affine3A::from_scale_rotation_translation(
                Vec3::splat(s),
                Quat::from_axis_angle(Vec3::new(1.0, 0.4, -0.3).normalize(), angle),
                Vec3::new(0.3, -1.0, 2.0),
            );
            let x = Vec3::from(x);
            let a = m.transform_point3(apply(&tool, &[x]).0[0]);
            let b = apply(&tool.transformed(&m), &[m.transform_point3(x)]).0[0];
            prop_assert!((a - b).length() < 1e-4 * (1.0 + a.length()), "{} vs {}", a, b);
        }
    }
}
