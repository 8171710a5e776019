//! Smoothing of the deformation parameters (Kho & Garland §5.4, Eq. 9).
//!
//! For the unknowns `u'ᵢ` of the region of interest `Ω` and the parameters `uᵢ` computed
//! from the user's curves, minimise
//!
//! `E = Σ_{i∈Ω} ( Σ_{j∈Nᵢ} w_ij (u'ᵢ − u'ⱼ)² + w_c,i (uᵢ − u'ᵢ)² )`,
//! `w_ij = 1 / |vⱼ − vᵢ|`, `w_c,i = (Σ_{j∈Nᵢ} w_ij) / 10`,
//!
//! where a neighbour `j ∉ Ω` keeps a fixed value (identity parameters for static vertices,
//! the virtual vertex's parameters for rigid ones). `E` is quadratic, so the paper's Newton
//! iteration converges in one step: `∂E/∂u'_k = 0` gives the sparse symmetric positive
//! definite system (halved)
//!
//! `(Σ_{j∈N_k} w_kj + Σ_{j∈N_k∩Ω} w_kj + w_c,k) u'_k − Σ_{j∈N_k∩Ω} 2 w_kj u'_j
//!  = w_c,k u_k + Σ_{j∈N_k∖Ω} w_kj u_j`.
//!
//! Its matrix depends only on the bind-time positions, so it is factorised once (sparse
//! Cholesky, faer, f64) and every re-evaluation is a pair of triangular solves (per
//! parameter column; the columns are solved in parallel).

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use glam::Vec3;

use crate::error::{CoreError, Result};

/// Ratio `Σ_j w_ij / w_c` chosen by the paper (§5.4).
pub const FIDELITY_RATIO: f64 = 10.0;

/// The factorised system of Eq. (9) for one region of interest.
pub struct Smoother {
    /// Unknown index (row) of each welded vertex, `u32::MAX` outside the region.
    row: Vec<u32>,
    /// `w_c,k` per row.
    wc: Vec<f64>,
    /// Edges from a row to a fixed vertex: `(row, vertex, w)`.
    fixed: Vec<(u32, u32, f64)>,
    llt: faer::sparse::linalg::solvers::Llt<usize, f64>,
}

impl std::fmt::Debug for Smoother {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Smoother")
            .field("unknowns", &self.wc.len())
            .field("fixed_edges", &self.fixed.len())
            .finish_non_exhaustive()
    }
}

impl Smoother {
    /// Builds and factorises the system for the unknowns `roi` (welded indices, no
    /// duplicates) over `adjacency` (neighbours of every welded vertex) at `positions`.
    /// `what` names the tool in errors.
    pub fn new(
        roi: &[u32],
        positions: &[Vec3],
        adjacency: &[Vec<u32>],
        what: &str,
    ) -> Result<Self> {
        let n = roi.len();
        let mut row = vec![u32::MAX; positions.len()];
        for (k, &v) in roi.iter().enumerate() {
            row[v as usize] = k as u32;
        }
        let mut wc = vec![0.0; n];
        let mut fixed = Vec::new();
        let mut triplets = Vec::with_capacity(n * 4);
        for (k, &v) in roi.iter().enumerate() {
            let pv = positions[v as usize].as_dvec3();
            let mut all = 0.0;
            let mut inside = 0.0;
            for &j in &adjacency[v as usize] {
                let len = pv.distance(positions[j as usize].as_dvec3());
                let w = 1.0 / len;
                if !w.is_finite() {
                    return Err(CoreError::Degenerate {
                        what: what.to_owned(),
                        problem: format!(
                            "smoothing: the edge between vertices {v} and {j} has zero length"
                        ),
                    });
                }
                all += w;
                let rj = row[j as usize];
                if rj == u32::MAX {
                    fixed.push((k as u32, j, w));
                } else {
                    inside += w;
                    if (rj as usize) < k {
                        triplets.push(Triplet::new(k, rj as usize, -2.0 * w));
                    }
                }
            }
            wc[k] = all / FIDELITY_RATIO;
            let diag = all + inside + wc[k];
            if diag.is_nan() || diag <= 0.0 {
                return Err(CoreError::Degenerate {
                    what: what.to_owned(),
                    problem: format!("smoothing: vertex {v} of the region of interest has no edge"),
                });
            }
            triplets.push(Triplet::new(k, k, diag));
        }
        let singular = |problem: String| CoreError::Degenerate {
            what: what.to_owned(),
            problem: format!("smoothing: {problem}"),
        };
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
            .map_err(|e| singular(format!("cannot build the sparse matrix ({e:?})")))?;
        let llt = matrix
            .sp_cholesky(Side::Lower)
            .map_err(|e| singular(format!("the system is not positive definite ({e:?})")))?;
        Ok(Self {
            row,
            wc,
            fixed,
            llt,
        })
    }

    /// Number of unknowns.
    #[must_use]
    pub fn len(&self) -> usize {
        self.wc.len()
    }

    /// True when there are no unknowns.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.wc.is_empty()
    }

    /// The unknown index of welded vertex `v`, if it is in the region of interest.
    #[must_use]
    pub fn row_of(&self, v: u32) -> Option<usize> {
        self.row
            .get(v as usize)
            .copied()
            .filter(|&r| r != u32::MAX)
            .map(|r| r as usize)
    }

    /// Solves Eq. (9) for `K` parameters at once: `u[k]` are the user's parameters of row
    /// `k`, `outside(v)` the fixed parameters of a neighbour `v` outside the region. Returns
    /// the smoothed `u'`.
    #[must_use]
    pub fn solve<const K: usize>(
        &self,
        u: &[[f64; K]],
        outside: impl Fn(u32) -> [f64; K],
    ) -> Vec<[f64; K]> {
        let n = self.len();
        let mut rhs = Mat::<f64>::zeros(n, K);
        for (k, row) in u.iter().enumerate() {
            for c in 0..K {
                rhs[(k, c)] = self.wc[k] * row[c];
            }
        }
        for &(k, v, w) in &self.fixed {
            let value = outside(v);
            for c in 0..K {
                rhs[(k as usize, c)] += w * value[c];
            }
        }
        // The columns are independent solves with the same factor: on two or more cores
        // they run side by side (the triangular solves are memory-bound, one thread each).
        if K >= 2 {
            let (a, b) = rhs.as_mut().split_at_col_mut(K / 2);
            rayon::join(|| self.llt.solve_in_place(a), || self.llt.solve_in_place(b));
        } else {
            self.llt.solve_in_place(rhs.as_mut());
        }
        (0..n)
            .map(|k| std::array::from_fn(|c| rhs[(k, c)]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path 0 − 1 − 2 − 3 with unit edges.
    fn path() -> (Vec<Vec3>, Vec<Vec<u32>>) {
        let p = (0..4).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        (p, vec![vec![1], vec![0, 2], vec![1, 3], vec![2]])
    }

    #[test]
    fn solution_matches_the_hand_solved_system() {
        // Unknowns 1 and 2; fixed neighbours 0 (value 0) and 3 (value 1); u = (1, 0).
        // w = 1 everywhere, w_c = 2/10 = 0.2. Rows (halved system):
        // (2 + 1 + 0.2) u1 − 2 u2 = 0.2·1 + 1·0
        // −2 u1 + (2 + 1 + 0.2) u2 = 0.2·0 + 1·1
        let (p, adj) = path();
        let s = Smoother::new(&[1, 2], &p, &adj, "t").unwrap();
        let out = s.solve(&[[1.0], [0.0]], |v| [if v == 3 { 1.0 } else { 0.0 }]);
        let det = 3.2 * 3.2 - 4.0;
        let u1 = (3.2 * 0.2 + 2.0 * 1.0) / det;
        let u2 = (2.0 * 0.2 + 3.2 * 1.0) / det;
        assert!((out[0][0] - u1).abs() < 1e-12, "{out:?}");
        assert!((out[1][0] - u2).abs() < 1e-12, "{out:?}");
    }

    #[test]
    fn constant_parameters_stay_constant() {
        let (p, adj) = path();
        let s = Smoother::new(&[0, 1, 2, 3], &p, &adj, "t").unwrap();
        let out = s.solve(&[[0.7, -2.0]; 4], |_| [0.0, 0.0]);
        for u in out {
            assert!((u[0] - 0.7).abs() < 1e-12 && (u[1] + 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn zero_length_edges_are_reported() {
        let (mut p, adj) = path();
        p[1] = p[0];
        let err = Smoother::new(&[1], &p, &adj, "tool 'x'").unwrap_err();
        assert!(err.to_string().contains("zero length"), "{err}");
    }
}
