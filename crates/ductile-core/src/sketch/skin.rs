//! Skinning (Kho & Garland §4.3): every vertex of the region of interest is tied to its
//! closest point on the 3-D reference curve, represented by its normalised arc length
//! `s ∈ [0, 1]`; every rigid component gets one virtual vertex, placed at the centre of its
//! boundary with the region of interest and skinned the same way.

use glam::Vec3;
use rayon::prelude::*;

use crate::error::{CoreError, Result, check_finite_vec3};

/// Below this many vertices skinning runs on one thread.
const PARALLEL_SKIN: usize = 8_192;

/// A 3-D polyline with its normalised arc length: node `i` sits at
/// `sᵢ = (Σ_{j<i} |p_{j+1} − p_j|) / L`, `L` the total length, so `s₀ = 0` and `s_n = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    points: Vec<Vec3>,
    s: Vec<f32>,
    length: f32,
}

impl Polyline {
    /// Builds the polyline from its nodes. Consecutive duplicate nodes (zero-length
    /// segments) are dropped. Errors when a node is not finite or fewer than two distinct
    /// nodes remain. `what` names the curve in errors.
    pub fn new(points: &[Vec3], what: &str) -> Result<Self> {
        let mut kept: Vec<Vec3> = Vec::with_capacity(points.len());
        for (i, &p) in points.iter().enumerate() {
            check_finite_vec3(|| format!("{what}: point {i}"), p)?;
            if kept.last().is_none_or(|&q| q != p) {
                kept.push(p);
            }
        }
        if kept.len() < 2 {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "a curve needs at least two distinct points, found {}",
                    kept.len()
                ),
            });
        }
        let mut cumulative = Vec::with_capacity(kept.len());
        let mut acc = 0.0_f64;
        cumulative.push(0.0_f64);
        for w in kept.windows(2) {
            acc += f64::from(w[0].distance(w[1]));
            cumulative.push(acc);
        }
        let s = cumulative.iter().map(|&c| (c / acc) as f32).collect();
        Ok(Self {
            points: kept,
            s,
            length: acc as f32,
        })
    }

    /// The nodes.
    #[must_use]
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Normalised arc length of every node (`s₀ = 0`, last `= 1`).
    #[must_use]
    pub fn node_s(&self) -> &[f32] {
        &self.s
    }

    /// Total length `L` (same units as the points).
    #[must_use]
    pub fn length(&self) -> f32 {
        self.length
    }

    /// Number of segments.
    #[must_use]
    pub fn segment_count(&self) -> usize {
        self.points.len() - 1
    }

    /// Unit direction of segment `i` (from node `i` to node `i + 1`).
    #[must_use]
    pub fn direction(&self, i: usize) -> Vec3 {
        (self.points[i + 1] - self.points[i]).normalize_or_zero()
    }

    /// The segment `i` with `sᵢ ≤ s ≤ sᵢ₊₁` and the local parameter
    /// `α = (s − sᵢ) / (sᵢ₊₁ − sᵢ)` (Eq. 3), `s` clamped to `[0, 1]`.
    #[must_use]
    pub fn locate(&self, s: f32) -> (usize, f32) {
        let s = s.clamp(0.0, 1.0);
        // First node with sᵢ > s, minus one, is the segment; s = 1 belongs to the last one.
        let upper = self.s.partition_point(|&x| x <= s);
        let i = upper.saturating_sub(1).min(self.segment_count() - 1);
        let (a, b) = (self.s[i], self.s[i + 1]);
        let alpha = if b > a {
            ((s - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (i, alpha)
    }

    /// The point at normalised arc length `s` (clamped to `[0, 1]`).
    #[must_use]
    pub fn point_at(&self, s: f32) -> Vec3 {
        let (i, alpha) = self.locate(s);
        self.points[i].lerp(self.points[i + 1], alpha)
    }

    /// Normalised arc length of the point of the curve closest to `p` (the first one when
    /// several are equally close).
    #[must_use]
    pub fn closest_s(&self, p: Vec3) -> f32 {
        let mut best = (f32::INFINITY, 0.0_f32);
        for i in 0..self.segment_count() {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            let d = (a + ab * t).distance_squared(p);
            if d < best.0 {
                best = (d, self.s[i] + t * (self.s[i + 1] - self.s[i]));
            }
        }
        best.1
    }

    /// The same polyline moved by `offset`.
    #[must_use]
    pub fn translated(&self, offset: Vec3) -> Self {
        Self {
            points: self.points.iter().map(|&p| p + offset).collect(),
            s: self.s.clone(),
            length: self.length,
        }
    }
}

/// `s(v)` for every vertex of `vertices` (welded indices into `positions`): the normalised
/// arc length of its closest point on `curve` (§4.3).
#[must_use]
pub fn skin(curve: &Polyline, positions: &[Vec3], vertices: &[u32]) -> Vec<f32> {
    let one = |&i: &u32| curve.closest_s(positions[i as usize]);
    if vertices.len() >= PARALLEL_SKIN {
        vertices.par_iter().map(one).collect()
    } else {
        vertices.iter().map(one).collect()
    }
}

/// The virtual vertex of a rigid component (§4.3): the centroid of the component's vertices
/// that share an edge with a vertex of `roi_flags`; the centroid of the whole component when
/// none does (a component not touching the region of interest).
#[must_use]
pub fn virtual_vertex(
    component: &[u32],
    positions: &[Vec3],
    adjacency: &[Vec<u32>],
    in_roi: &[bool],
) -> Vec3 {
    let centroid = |it: &mut dyn Iterator<Item = u32>| {
        let (sum, n) = it.fold((glam::DVec3::ZERO, 0_usize), |(s, n), i| {
            (s + positions[i as usize].as_dvec3(), n + 1)
        });
        (n > 0).then(|| (sum / n as f64).as_vec3())
    };
    let mut boundary = component.iter().copied().filter(|&i| {
        adjacency[i as usize]
            .iter()
            .any(|&j| in_roi.get(j as usize).copied().unwrap_or(false))
    });
    centroid(&mut boundary)
        .or_else(|| centroid(&mut component.iter().copied()))
        .unwrap_or(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_curve() -> Polyline {
        // Two segments of lengths 3 and 1: nodes at s = 0, 0.75, 1.
        Polyline::new(
            &[
                Vec3::ZERO,
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(3.0, 1.0, 0.0),
            ],
            "l",
        )
        .unwrap()
    }

    #[test]
    fn arc_length_is_normalised() {
        let c = l_curve();
        assert_eq!(c.node_s(), &[0.0, 0.75, 1.0]);
        assert!((c.length() - 4.0).abs() < 1e-6);
        assert!((c.point_at(0.5) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        assert!((c.point_at(0.875) - Vec3::new(3.0, 0.5, 0.0)).length() < 1e-6);
        assert_eq!(c.locate(1.0), (1, 1.0));
        assert_eq!(c.locate(0.0), (0, 0.0));
    }

    #[test]
    fn closest_point_lies_on_the_curve_not_on_a_node() {
        let c = l_curve();
        // Above the middle of the first segment.
        assert!((c.closest_s(Vec3::new(1.5, 0.4, 2.0)) - 0.375).abs() < 1e-6);
        // Beyond the end: clamps to s = 1.
        assert!((c.closest_s(Vec3::new(3.0, 5.0, 0.0)) - 1.0).abs() < 1e-6);
        // Right of the second segment.
        assert!((c.closest_s(Vec3::new(4.0, 0.5, 0.0)) - 0.875).abs() < 1e-6);
    }

    #[test]
    fn degenerate_curves_are_errors() {
        assert!(Polyline::new(&[Vec3::ONE, Vec3::ONE], "c").is_err());
        assert!(Polyline::new(&[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0)], "c").is_err());
        // Duplicates are dropped, not fatal.
        let c = Polyline::new(&[Vec3::ZERO, Vec3::ZERO, Vec3::X], "c").unwrap();
        assert_eq!(c.segment_count(), 1);
    }

    #[test]
    fn virtual_vertex_is_the_centre_of_the_boundary() {
        // Path 0 - 1 - 2 - 3; ROI = {0, 1}; rigid = {2, 3}; boundary of rigid = {2}.
        let positions = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
        ];
        let adjacency = vec![vec![1], vec![0, 2], vec![1, 3], vec![2]];
        let in_roi = [true, true, false, false];
        let v = virtual_vertex(&[2, 3], &positions, &adjacency, &in_roi);
        assert_eq!(v, Vec3::new(2.0, 0.0, 0.0));
        let lone = virtual_vertex(&[3], &positions, &[vec![], vec![], vec![], vec![]], &in_roi);
        assert_eq!(lone, Vec3::new(3.0, 0.0, 0.0));
    }
}
