//! Direct FFD (the survey's §5.2, after Hsu, Hughes & Kaufman): "move this point of the
//! object to there", solved on a lattice.
//!
//! Inside the lattice the FFD is linear in the control points:
//! `D(x) = Σ_ijk a_ijk(x) P_ijk` with `a_ijk = W_ijk Bᵢ Bⱼ Bₖ / Σ W B B B` (plain FFD: all
//! `W = 1`). For constraint points `x_c` with displacements `δ_c` the tool finds the
//! minimum-norm change `ΔP` of the control points with
//!
//! `Σ_ijk a_ijk(x_c) ΔP_ijk = x_c + δ_c − D(x_c)` for every `c`, i.e. `A ΔP = R`,
//! `ΔP = A⁺ R`
//!
//! (exact when the constraints are compatible, least squares otherwise), then deforms with
//! the changed lattice. `D` here is the lattice as edited by the user, so both kinds of
//! edit combine. See `docs/algorithms/direct-ffd.md`.

use faer::Mat;
use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::dogme::{Anchor, min_norm_solve};
use crate::error::{CoreError, Result, check_finite_vec3};
use crate::lattice::{LatticeTool, PreparedLattice};
use crate::tool::{BindInput, Deformer};

/// One Direct FFD constraint: move the point `at` by `displacement`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectConstraint {
    /// The point of the object (a free point or a welded mesh vertex).
    pub at: Anchor,
    /// Where it must go, relative to where it is (tool space).
    pub displacement: Vec3,
}

/// A Direct FFD tool: a lattice and point constraints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectFfdTool {
    /// The lattice the constraints are solved on (its own edits apply too).
    pub lattice: LatticeTool,
    /// The constraints; every constraint point must lie inside the lattice.
    pub constraints: Vec<DirectConstraint>,
}

impl DirectFfdTool {
    /// Adds the constraint "move the point `from` to `to`".
    pub fn move_point_to(&mut self, from: Vec3, to: Vec3) {
        self.constraints.push(DirectConstraint {
            at: Anchor::Point(from),
            displacement: to - from,
        });
    }
}

/// Bind of a [`DirectFfdTool`]: the lattice with the solved control point change.
#[derive(Debug, Clone)]
pub struct DirectFfdBind {
    lattice: PreparedLattice,
    rank: usize,
    residual: f32,
    change_norm: f32,
}

impl DirectFfdBind {
    /// The solved lattice.
    #[must_use]
    pub fn lattice(&self) -> &PreparedLattice {
        &self.lattice
    }

    /// The rank of the constraint system `A`.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// `max_c |D'(x_c) − (x_c + δ_c)|`: 0 (to rounding) when every constraint is met.
    #[must_use]
    pub fn residual(&self) -> f32 {
        self.residual
    }

    /// The Frobenius norm `‖ΔP‖` of the solved control point change.
    #[must_use]
    pub fn change_norm(&self) -> f32 {
        self.change_norm
    }
}

impl Deformer for DirectFfdTool {
    type Bind = DirectFfdBind;

    fn validate(&self, what: &str) -> Result<()> {
        self.lattice.validate(&format!("{what}: lattice"))?;
        for (k, c) in self.constraints.iter().enumerate() {
            let w = format!("{what}: constraint {k}");
            if let Anchor::Point(p) = c.at {
                check_finite_vec3(|| format!("{w}: point"), p)?;
            }
            check_finite_vec3(|| format!("{w}: displacement"), c.displacement)?;
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<DirectFfdBind> {
        let what = "Direct FFD";
        let mut lattice = self.lattice.prepare(&format!("{what}: lattice"))?;
        let n = lattice.len();
        let m = self.constraints.len();
        if m == 0 {
            return Ok(DirectFfdBind {
                lattice,
                rank: 0,
                residual: 0.0,
                change_norm: 0.0,
            });
        }
        let mut a = Mat::<f64>::zeros(m, n);
        let mut row = vec![0.0_f64; n];
        let mut rhs = Vec::with_capacity(m);
        let mut points = Vec::with_capacity(m);
        for (c, con) in self.constraints.iter().enumerate() {
            let w = format!("{what}: constraint {c}");
            let x = con.at.resolve(input.positions, &w)?;
            if !lattice.coefficients(x, &mut row) {
                return Err(CoreError::Degenerate {
                    what: w,
                    problem: format!(
                        "the point {x} lies outside the lattice, so no control point can move it"
                    ),
                });
            }
            for (j, v) in row.iter().enumerate() {
                if *v != 0.0 {
                    a[(c, j)] = *v;
                }
            }
            let r = x + con.displacement - lattice.deform_point(x);
            rhs.push(r.as_dvec3().to_array());
            points.push((x, x + con.displacement));
        }
        let (dp, rank) = min_norm_solve(&a, &rhs, what)?;
        let delta: Vec<Vec3> = dp
            .iter()
            .map(|d| Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32))
            .collect();
        let change_norm = delta.iter().map(|d| d.length_squared()).sum::<f32>().sqrt();
        lattice.add_offsets(&delta);
        let residual = points
            .iter()
            .map(|(x, target)| (lattice.deform_point(*x) - *target).length())
            .fold(0.0, f32::max);
        Ok(DirectFfdBind {
            lattice,
            rank,
            residual,
            change_norm,
        })
    }

    fn deform(&self, bind: &DirectFfdBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        bind.lattice.deform_slice(positions, active, out);
    }

    /// The lattice maps as in [`LatticeTool`]; points map as points and displacements by the
    /// linear part. Exact for every affine map (the system `A` is affine invariant and the
    /// minimum-norm solution commutes with a similarity; with shear or non-uniform scale
    /// the minimum-norm choice among exact solutions may differ).
    fn transformed(&self, m: &Affine3A) -> Self {
        Self {
            lattice: self.lattice.transformed(m),
            constraints: self
                .constraints
                .iter()
                .map(|c| DirectConstraint {
                    at: match c.at {
                        Anchor::Point(p) => Anchor::Point(m.transform_point3(p)),
                        v => v,
                    },
                    displacement: m.transform_vector3(c.displacement),
                })
                .collect(),
        }
    }

    fn same_rest_state(&self, other: &Self) -> bool {
        self == other
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::LatticeFrame;
    use crate::mesh::Topology;

    fn bind(tool: &DirectFfdTool, positions: &[Vec3]) -> Result<DirectFfdBind> {
        tool.validate("t")?;
        let t = Topology {
            weld: Vec::new(),
            representative: Vec::new(),
            triangles: Vec::new(),
        };
        let active: Vec<u32> = (0..positions.len() as u32).collect();
        tool.bind(&BindInput {
            positions,
            topology: &t,
            active: &active,
        })
    }

    fn unit() -> LatticeFrame {
        LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn single_point_oracle_minimum_norm() {
        // One constraint at x with row a: the minimum-norm solution is ΔP = a δ / |a|², and
        // D'(x) = x + δ. Check both against the hand formula on a 2×2×2 lattice at the
        // centre, where every a = 1/8: ΔP_ijk = δ, the whole lattice translates.
        let mut tool = DirectFfdTool {
            lattice: LatticeTool::bernstein(unit(), (2, 2, 2)),
            constraints: Vec::new(),
        };
        tool.move_point_to(Vec3::splat(0.5), Vec3::new(0.5, 0.5, 0.8));
        let b = bind(&tool, &[]).unwrap();
        assert_eq!(b.rank(), 1);
        assert!(b.residual() < 1e-6);
        for d in b.lattice().offsets() {
            assert!((*d - Vec3::new(0.0, 0.0, 0.3)).length() < 1e-6, "{d}");
        }
        // |ΔP| = √8 · 0.3.
        assert!((b.change_norm() - 8f32.sqrt() * 0.3).abs() < 1e-5);
    }

    #[test]
    fn several_points_are_met_on_bspline_lattice_and_change_is_minimal() {
        let mut tool = DirectFfdTool {
            lattice: LatticeTool::bspline(unit(), (6, 6, 6), (3, 3, 3)),
            constraints: Vec::new(),
        };
        tool.move_point_to(Vec3::new(0.3, 0.4, 0.5), Vec3::new(0.35, 0.45, 0.6));
        tool.move_point_to(Vec3::new(0.7, 0.6, 0.5), Vec3::new(0.7, 0.5, 0.5));
        tool.constraints.push(DirectConstraint {
            at: Anchor::Vertex(0),
            displacement: Vec3::new(0.0, 0.0, -0.1),
        });
        let v0 = Vec3::new(0.5, 0.2, 0.8);
        let b = bind(&tool, &[v0]).unwrap();
        assert_eq!(b.rank(), 3);
        assert!(b.residual() < 1e-5, "residual {}", b.residual());
        let q = b.lattice().deform_point(v0);
        assert!((q - (v0 + Vec3::new(0.0, 0.0, -0.1))).length() < 1e-5);
        // Minimality: ΔP lies in the row space of A, so it is orthogonal to the null space;
        // adding any null-space direction (here: a change of a control point whose support
        // misses every constraint) only increases the norm and keeps the constraints.
        let untouched = b
            .lattice()
            .offsets()
            .iter()
            .filter(|d| d.length() == 0.0)
            .count();
        assert!(
            untouched > 0,
            "local support: far control points do not move"
        );
    }

    #[test]
    fn points_outside_the_lattice_and_bad_values_are_errors() {
        let mut tool = DirectFfdTool {
            lattice: LatticeTool::bernstein(unit(), (3, 3, 3)),
            constraints: Vec::new(),
        };
        tool.move_point_to(Vec3::new(1.5, 0.5, 0.5), Vec3::ONE);
        assert!(matches!(
            bind(&tool, &[]),
            Err(CoreError::Degenerate { .. })
        ));
        tool.constraints[0].at = Anchor::Point(Vec3::splat(0.5));
        tool.constraints[0].displacement = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(matches!(bind(&tool, &[]), Err(CoreError::NotFinite { .. })));
    }

    #[test]
    fn contradictory_constraints_give_least_squares() {
        let mut tool = DirectFfdTool {
            lattice: LatticeTool::bernstein(unit(), (3, 3, 3)),
            constraints: Vec::new(),
        };
        let x = Vec3::new(0.4, 0.5, 0.6);
        tool.move_point_to(x, x + Vec3::new(0.2, 0.0, 0.0));
        tool.move_point_to(x, x - Vec3::new(0.2, 0.0, 0.0));
        let b = bind(&tool, &[]).unwrap();
        assert_eq!(b.rank(), 1);
        assert!((b.lattice().deform_point(x) - x).length() < 1e-6);
        assert!((b.residual() - 0.2).abs() < 1e-5);
    }
}
