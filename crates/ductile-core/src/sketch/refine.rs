//! Adaptive refinement by edge splits (Kho & Garland §5.5).
//!
//! An edge `{a, b}` touching the region of interest is split at its midpoint when both
//!
//! 1. it is stretched: `|a' − b'| > ρ · |a − b|` (deformed over input length, `ρ = 1.5`: "an
//!    edge will be split if it is stretched by more than 50%"), and
//! 2. it is bent: the tentative midpoint `m = (a + b) / 2`, deformed with the parameters
//!    interpolated from its ends, makes an angle `∠(a' − m', b' − m') < π − π/24`.
//!
//! New edges (the two halves and the edges to the opposite corners) are tested again, up to
//! a maximum subdivision level, so the refinement always terminates.

use std::collections::VecDeque;
use std::f32::consts::PI;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::refinement::{EdgePoint, SplitMesh};

/// Options of the adaptive refinement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefineOptions {
    /// Stretch ratio above which an edge may be split (paper: 1.5).
    #[serde(default = "default_stretch")]
    pub stretch: f32,
    /// Angle (radians) at the tentative midpoint below which the split is accepted
    /// (paper: π − π/24).
    #[serde(default = "default_angle")]
    pub angle: f32,
    /// Maximum number of times an original edge is halved (≥ 1).
    #[serde(default = "default_levels")]
    pub max_levels: u8,
}

fn default_stretch() -> f32 {
    1.5
}

fn default_angle() -> f32 {
    PI - PI / 24.0
}

fn default_levels() -> u8 {
    4
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            stretch: default_stretch(),
            angle: default_angle(),
            max_levels: default_levels(),
        }
    }
}

/// The per-vertex state the refinement grows as it splits: input positions, deformed
/// positions, deformation parameters (interpolated linearly for new vertices), whether the
/// vertex is deformed by the tool (region of interest or new), and its subdivision level.
#[derive(Debug, Clone, Default)]
pub struct Vertices {
    /// Input (bind-time layer input) positions.
    pub input: Vec<Vec3>,
    /// Deformed positions.
    pub deformed: Vec<Vec3>,
    /// Deformation parameters `(s, θ)`.
    pub params: Vec<[f32; 2]>,
    /// True for vertices of the region of interest (and new vertices).
    pub free: Vec<bool>,
    /// Subdivision level (0 for existing vertices).
    pub level: Vec<u8>,
}

/// The angle at `m` between `a − m` and `b − m` (radians, `π` when straight, `π` as well
/// when degenerate so that nothing is split).
#[must_use]
pub fn angle_at(a: Vec3, m: Vec3, b: Vec3) -> f32 {
    let (u, v) = (a - m, b - m);
    let d = u.length() * v.length();
    if d <= 0.0 {
        return PI;
    }
    (u.dot(v) / d).clamp(-1.0, 1.0).acos()
}

/// Runs the refinement on `mesh` (welded triangles) and `vertices`; `map(p, params)` is
/// the tool's deformation of an input point with given parameters. Returns the accepted
/// splits in order (the new vertices are appended to `vertices`).
pub fn refine(
    mesh: &mut SplitMesh,
    vertices: &mut Vertices,
    options: &RefineOptions,
    map: impl Fn(Vec3, [f32; 2]) -> Vec3,
) -> Vec<EdgePoint> {
    let mut queue: VecDeque<(u32, u32)> = mesh
        .sorted_edges()
        .into_iter()
        .filter(|&(a, b)| vertices.free[a as usize] || vertices.free[b as usize])
        .collect();
    let mut splits = Vec::new();
    while let Some((a, b)) = queue.pop_front() {
        if !mesh.has_edge(a, b) {
            continue;
        }
        let (ia, ib) = (a as usize, b as usize);
        let level = vertices.level[ia].max(vertices.level[ib]);
        if level >= options.max_levels {
            continue;
        }
        let rest_len = vertices.input[ia].distance(vertices.input[ib]);
        let def_len = vertices.deformed[ia].distance(vertices.deformed[ib]);
        if def_len.is_nan() || def_len <= options.stretch * rest_len {
            continue;
        }
        let e = EdgePoint { a, b, t: 0.5 };
        let input = e.lerp(&vertices.input);
        let params = [
            0.5 * (vertices.params[ia][0] + vertices.params[ib][0]),
            0.5 * (vertices.params[ia][1] + vertices.params[ib][1]),
        ];
        let m_def = map(input, params);
        if !m_def.is_finite()
            || angle_at(vertices.deformed[ia], m_def, vertices.deformed[ib]) >= options.angle
        {
            continue;
        }
        let opposite = mesh.opposite(a, b);
        let m = mesh.split(e);
        vertices.input.push(input);
        vertices.deformed.push(m_def);
        vertices.params.push(params);
        vertices.free.push(true);
        vertices.level.push(level + 1);
        splits.push(e);
        queue.push_back((a, m));
        queue.push_back((m, b));
        for c in opposite {
            queue.push_back((m, c));
        }
    }
    splits
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of two triangles along x: 0 (0,0) 1 (1,0) 2 (0,1) 3 (1,1).
    fn strip() -> (SplitMesh, Vertices) {
        let mesh = SplitMesh::new(&[[0, 1, 2], [1, 3, 2]], 4);
        let input = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
        let v = Vertices {
            deformed: input.clone(),
            input,
            params: vec![[0.0, 0.0]; 4],
            free: vec![true; 4],
            level: vec![0; 4],
        };
        (mesh, v)
    }

    #[test]
    fn angle_at_is_pi_for_straight_lines() {
        assert!((angle_at(Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)) - PI).abs() < 1e-6);
        assert!((angle_at(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)) - PI / 2.0).abs() < 1e-6);
    }

    #[test]
    fn stretched_but_straight_edges_are_not_split() {
        // Uniform stretch by 3 along x: every edge long, every midpoint straight.
        let (mut mesh, mut v) = strip();
        let stretch = |p: Vec3| Vec3::new(3.0 * p.x, p.y, p.z);
        v.deformed = v.input.iter().map(|&p| stretch(p)).collect();
        let splits = refine(&mut mesh, &mut v, &RefineOptions::default(), |p, _| {
            stretch(p)
        });
        assert!(splits.is_empty());
    }

    #[test]
    fn bent_but_unstretched_edges_are_not_split() {
        // The midpoint is pushed sideways (bent) but the edge keeps its length.
        let (mut mesh, mut v) = strip();
        let splits = refine(&mut mesh, &mut v, &RefineOptions::default(), |p, _| {
            p + Vec3::Z * 0.5
        });
        assert!(splits.is_empty());
    }

    #[test]
    fn stretched_and_bent_edges_are_split_recursively() {
        // Map x ↦ (3x, 0, 3x(1 − x)): edges along x triple in length and bow out of plane.
        let (mut mesh, mut v) = strip();
        let f = |p: Vec3| Vec3::new(3.0 * p.x, p.y, 3.0 * p.x * (1.0 - p.x));
        v.deformed = v.input.iter().map(|&p| f(p)).collect();
        let splits = refine(&mut mesh, &mut v, &RefineOptions::default(), |p, _| f(p));
        // Edge 0–1 comes first in the sorted queue and is both stretched (3×) and bent
        // (its midpoint bows out to z = 0.75).
        assert!(splits.len() >= 2, "{splits:?}");
        assert_eq!((splits[0].a, splits[0].b), (0, 1));
        // Recursion: some split has a new vertex as an end.
        assert!(splits.iter().any(|e| e.a >= 4 || e.b >= 4), "{splits:?}");
        // Every split edge really was stretched and bent.
        for (k, e) in splits.iter().enumerate() {
            let m = 4 + k;
            let (a, b) = (e.a as usize, e.b as usize);
            assert!(v.deformed[a].distance(v.deformed[b]) > 1.5 * v.input[a].distance(v.input[b]));
            assert!(angle_at(v.deformed[a], v.deformed[m], v.deformed[b]) < PI - PI / 24.0);
        }
        assert_eq!(mesh.vertex_count(), v.input.len());
        // Levels are bounded.
        assert!(
            v.level
                .iter()
                .all(|&l| l <= RefineOptions::default().max_levels)
        );
    }
}
