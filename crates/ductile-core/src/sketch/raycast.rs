//! Ray casting against a triangle mesh with a bounding-volume hierarchy (BVH).
//!
//! Sketching (Kho & Garland 2005, §4.1 and §5.2) needs the first hit of the ray through a
//! stroke point, and for twisting the first *two* hits (front and back face). [`Bvh`] is a
//! compact binary BVH over triangles built top-down with the surface area heuristic (SAH)
//! evaluated on 16 centroid bins per axis, with at most [`MAX_LEAF`] triangles per leaf.
//!
//! Why not a crate: `bvh` depends on nalgebra and `obvhs` 0.4 requires glam ≥ 0.33 (the
//! workspace uses 0.32) plus `rdst`, `bytemuck` and `half`; a 200-line builder is cheaper
//! than a second linear-algebra stack. The intersection test is Möller–Trumbore and is
//! two-sided (back faces are hit too, which twisting needs).

use glam::Vec3;

use crate::error::{CoreError, Result};
use crate::sketch::camera::Ray;

/// Most triangles in a leaf.
pub const MAX_LEAF: usize = 4;

/// Number of centroid bins per axis for the SAH split search.
const BINS: usize = 16;

/// One ray–triangle intersection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter: the hit point is `origin + t·direction` (world units, since the
    /// direction is unit length), `t ≥ 0`.
    pub t: f32,
    /// Index of the triangle in the triangle list given to [`Bvh::build`].
    pub triangle: u32,
    /// Barycentric weights `(w0, w1, w2)` of the triangle's corners, summing to 1; the hit
    /// point is `w0·a + w1·b + w2·c`.
    pub barycentric: Vec3,
}

impl Hit {
    /// The hit point on the ray.
    #[must_use]
    pub fn point(&self, ray: &Ray) -> Vec3 {
        ray.origin + ray.direction * self.t
    }
}

/// A node: an axis-aligned box and either two children (`count == 0`, children at `first`
/// and `first + 1`) or a leaf of `count` triangles starting at `first` in the reordered
/// triangle list.
#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    first: u32,
    count: u32,
}

/// A bounding-volume hierarchy over the triangles of a mesh (welded positions and
/// triangles). It owns a reordered copy of the triangle corners, so queries need no other
/// data.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    corners: Vec<[Vec3; 3]>,
    /// Original triangle index of each entry of `corners`.
    ids: Vec<u32>,
}

/// Axis-aligned box helper used while building.
#[derive(Debug, Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Self = Self {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, other: &Self) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Half the surface area (enough for SAH ratios); 0 for an empty box.
    fn half_area(&self) -> f32 {
        let d = self.max - self.min;
        if d.min_element() < 0.0 {
            0.0
        } else {
            d.x * d.y + d.y * d.z + d.z * d.x
        }
    }
}

impl Bvh {
    /// Builds the hierarchy over `triangles` (indices into `positions`).
    ///
    /// # Errors
    /// [`CoreError::IndexOutOfRange`] when a triangle refers to a missing position and
    /// [`CoreError::NotFinite`] when a referenced position is NaN or infinite.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<Self> {
        let mut corners = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let mut c = [Vec3::ZERO; 3];
            for k in 0..3 {
                let p = positions
                    .get(t[k] as usize)
                    .ok_or(CoreError::IndexOutOfRange {
                        what: "ray-casting hierarchy".to_owned(),
                        triangle: i,
                        index: t[k],
                        vertices: positions.len(),
                    })?;
                if !p.is_finite() {
                    return Err(CoreError::NotFinite {
                        what: format!("ray-casting hierarchy: position of vertex {}", t[k]),
                        value: format!("{p}"),
                    });
                }
                c[k] = *p;
            }
            corners.push(c);
        }
        let n = corners.len();
        let mut boxes = Vec::with_capacity(n);
        let mut centroids = Vec::with_capacity(n);
        for c in &corners {
            boxes.push(Aabb {
                min: c[0].min(c[1]).min(c[2]),
                max: c[0].max(c[1]).max(c[2]),
            });
            centroids.push((c[0] + c[1] + c[2]) / 3.0);
        }
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n.div_ceil(MAX_LEAF).max(1));
        nodes.push(Node {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            first: 0,
            count: n as u32,
        });
        // Work list of (node index, start, end) ranges of `order`.
        let mut stack = vec![(0usize, 0usize, n)];
        while let Some((node, start, end)) = stack.pop() {
            let mut bounds = Aabb::EMPTY;
            let mut cbounds = Aabb::EMPTY;
            for &i in &order[start..end] {
                bounds.grow(&boxes[i as usize]);
                cbounds.grow_point(centroids[i as usize]);
            }
            nodes[node].min = bounds.min;
            nodes[node].max = bounds.max;
            nodes[node].first = start as u32;
            nodes[node].count = (end - start) as u32;
            if end - start <= MAX_LEAF {
                continue;
            }
            let Some(mid) = sah_split(&mut order[start..end], &boxes, &centroids, &cbounds) else {
                continue;
            };
            let mid = start + mid;
            let left = nodes.len();
            nodes.push(nodes[node]);
            nodes.push(nodes[node]);
            nodes[node].first = left as u32;
            nodes[node].count = 0;
            stack.push((left, start, mid));
            stack.push((left + 1, mid, end));
        }
        if n == 0 {
            nodes[0].min = Vec3::splat(f32::INFINITY);
            nodes[0].max = Vec3::splat(f32::NEG_INFINITY);
        }
        let corners_sorted = order.iter().map(|&i| corners[i as usize]).collect();
        Ok(Self {
            nodes,
            corners: corners_sorted,
            ids: order,
        })
    }

    /// Number of triangles in the hierarchy.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.ids.len()
    }

    /// The closest hit with `t ≥ 0` along `ray`, if any.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.traverse(ray, |hit, t_max| {
            if hit.t < *t_max {
                *t_max = hit.t;
                best = Some(hit);
            }
        });
        best
    }

    /// Every hit with `t ≥ 0` along `ray`, sorted by `t` (ties by triangle index). A ray
    /// through a shared edge or vertex may report each triangle there.
    #[must_use]
    pub fn intersect_all(&self, ray: &Ray) -> Vec<Hit> {
        let mut hits = Vec::new();
        self.traverse(ray, |hit, _| hits.push(hit));
        hits.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.triangle.cmp(&b.triangle)));
        hits
    }

    /// Visits every triangle hit whose box the ray enters before `t_max` (which the visitor
    /// may shrink), children nearest-first.
    fn traverse(&self, ray: &Ray, mut visit: impl FnMut(Hit, &mut f32)) {
        if self.ids.is_empty() || !ray.origin.is_finite() || !ray.direction.is_finite() {
            return;
        }
        if ray.direction.length_squared() == 0.0 {
            return;
        }
        let inv = ray.direction.recip();
        let mut t_max = f32::INFINITY;
        let mut stack = [0u32; 64];
        let mut top = 0usize;
        if slab(&self.nodes[0], ray.origin, inv, t_max).is_none() {
            return;
        }
        stack[top] = 0;
        top += 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if slab(node, ray.origin, inv, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let start = node.first as usize;
                for k in start..start + node.count as usize {
                    if let Some((t, bary)) = triangle_hit(ray, &self.corners[k])
                        && t <= t_max
                    {
                        visit(
                            Hit {
                                t,
                                triangle: self.ids[k],
                                barycentric: bary,
                            },
                            &mut t_max,
                        );
                    }
                }
                continue;
            }
            let (a, b) = (node.first, node.first + 1);
            let ta = slab(&self.nodes[a as usize], ray.origin, inv, t_max);
            let tb = slab(&self.nodes[b as usize], ray.origin, inv, t_max);
            // Push the farther child first so the nearer one is visited next. The depth of
            // a median-or-better split tree stays far below 64 for any realistic mesh; if it
            // did not, the deeper subtrees would be visited through a heap fallback.
            let mut push = |i: u32| {
                if top < stack.len() {
                    stack[top] = i;
                    top += 1;
                    true
                } else {
                    false
                }
            };
            let pushed = match (ta, tb) {
                (Some(x), Some(y)) if x <= y => push(b) && push(a),
                (Some(_), Some(_)) => push(a) && push(b),
                (Some(_), None) => push(a),
                (None, Some(_)) => push(b),
                (None, None) => true,
            };
            if !pushed {
                // Extremely deep tree: finish the remaining subtrees by brute force.
                for k in 0..self.corners.len() {
                    if let Some((t, bary)) = triangle_hit(ray, &self.corners[k])
                        && t <= t_max
                    {
                        visit(
                            Hit {
                                t,
                                triangle: self.ids[k],
                                barycentric: bary,
                            },
                            &mut t_max,
                        );
                    }
                }
                return;
            }
        }
    }
}

/// Binned SAH split of `order` (triangle ids) in place; returns the split position, or
/// `None` when no split is better than a leaf and the range is small enough, or when all
/// centroids coincide. Falls back to a median split on the longest axis when SAH finds no
/// useful plane but the range is too big for a leaf.
fn sah_split(
    order: &mut [u32],
    boxes: &[Aabb],
    centroids: &[Vec3],
    cbounds: &Aabb,
) -> Option<usize> {
    let extent = cbounds.max - cbounds.min;
    let n = order.len();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |c: Vec3| (((c[axis] - cbounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for &i in order.iter() {
            let b = bin_of(centroids[i as usize]);
            bins[b].0.grow(&boxes[i as usize]);
            bins[b].1 += 1;
        }
        // Sweep from the right to get the cost of every right part.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in (1..BINS).rev() {
            acc.grow(&bins[b].0);
            cnt += bins[b].1;
            right_area[b] = acc.half_area();
            right_count[b] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in 0..BINS - 1 {
            acc.grow(&bins[b].0);
            cnt += bins[b].1;
            if cnt == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f32 + right_area[b + 1] * right_count[b + 1] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    if let Some((_, axis, bin)) = best {
        let scale = BINS as f32 / extent[axis];
        let mut mid = 0;
        for k in 0..n {
            let c = centroids[order[k] as usize];
            if ((((c[axis] - cbounds.min[axis]) * scale) as usize).min(BINS - 1)) <= bin {
                order.swap(k, mid);
                mid += 1;
            }
        }
        if mid > 0 && mid < n {
            return Some(mid);
        }
    }
    // All centroids in one bin (or coincident): median split on the longest axis.
    let axis = extent.max_position();
    if extent[axis] <= 0.0 && n <= 4 * MAX_LEAF {
        return None;
    }
    let mid = n / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
    });
    Some(mid)
}

/// Slab test: the entry distance of the ray into the node's box if it enters before
/// `t_max`.
fn slab(node: &Node, origin: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (node.min - origin) * inv;
    let t1 = (node.max - origin) * inv;
    // `min`/`max` of glam ignore NaN from 0·∞ on the axis the ray is parallel to when the
    // origin lies on a slab plane, which keeps the test conservative.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max);
    (near <= far).then_some(near)
}

/// Two-sided Möller–Trumbore ray–triangle test: `(t, (w0, w1, w2))` for a hit with
/// `t ≥ 0`, edges and corners included.
#[must_use]
pub fn triangle_hit(ray: &Ray, c: &[Vec3; 3]) -> Option<(f32, Vec3)> {
    let e1 = c[1] - c[0];
    let e2 = c[2] - c[0];
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length_squared().max(e2.length_squared());
    if det.abs() <= 1e-12 * scale || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - c[0];
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t >= 0.0).then_some((t, Vec3::new(1.0 - u - v, u, v)))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A closed cylinder along +Y: `segments` around, `rings` rows of quads between y = 0
    /// and y = `height`, radius `radius`, with fan caps. Returns (positions, triangles).
    pub(crate) fn cylinder(
        segments: u32,
        rings: u32,
        radius: f32,
        height: f32,
    ) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for r in 0..=rings {
            let y = height * r as f32 / rings as f32;
            for s in 0..segments {
                let a = std::f32::consts::TAU * s as f32 / segments as f32;
                p.push(Vec3::new(radius * a.cos(), y, radius * a.sin()));
            }
        }
        let idx = |r: u32, s: u32| r * segments + s % segments;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (idx(r, s), idx(r, s + 1), idx(r + 1, s + 1), idx(r + 1, s));
                // Outward-facing (counter-clockwise seen from outside).
                t.push([a, c, b]);
                t.push([a, d, c]);
            }
        }
        let bottom = p.len() as u32;
        p.push(Vec3::ZERO);
        let top = p.len() as u32;
        p.push(Vec3::new(0.0, height, 0.0));
        for s in 0..segments {
            t.push([bottom, idx(0, s), idx(0, s + 1)]);
            t.push([top, idx(rings, s + 1), idx(rings, s)]);
        }
        (p, t)
    }

    fn brute(ray: &Ray, p: &[Vec3], t: &[[u32; 3]]) -> Vec<(f32, u32)> {
        let mut v: Vec<(f32, u32)> = t
            .iter()
            .enumerate()
            .filter_map(|(i, tri)| {
                let c = [p[tri[0] as usize], p[tri[1] as usize], p[tri[2] as usize]];
                triangle_hit(ray, &c).map(|(tt, _)| (tt, i as u32))
            })
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        v
    }

    #[test]
    fn hit_on_known_triangle_has_expected_t_and_barycentrics() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = Bvh::build(&p, &[[0, 1, 2]]).unwrap();
        let ray = Ray {
            origin: Vec3::new(0.25, 0.5, 2.0),
            direction: -Vec3::Z,
        };
        let hit = bvh.intersect(&ray).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!((hit.barycentric - Vec3::new(0.25, 0.25, 0.5)).length() < 1e-6);
        // Back face is hit too (two-sided).
        let back = Ray {
            origin: Vec3::new(0.25, 0.5, -1.0),
            direction: Vec3::Z,
        };
        assert!(bvh.intersect(&back).is_some());
        let miss = Ray {
            origin: Vec3::new(0.8, 0.8, 2.0),
            direction: -Vec3::Z,
        };
        assert!(bvh.intersect(&miss).is_none());
    }

    #[test]
    fn bad_index_is_an_error() {
        let err = Bvh::build(&[Vec3::ZERO], &[[0, 1, 2]]).unwrap_err();
        assert!(matches!(err, CoreError::IndexOutOfRange { index: 1, .. }));
        let err = Bvh::build(&[Vec3::ZERO, Vec3::X, Vec3::NAN], &[[0, 1, 2]]).unwrap_err();
        assert!(matches!(err, CoreError::NotFinite { .. }));
    }

    #[test]
    fn empty_hierarchy_hits_nothing() {
        let bvh = Bvh::build(&[], &[]).unwrap();
        let ray = Ray {
            origin: Vec3::ZERO,
            direction: Vec3::Z,
        };
        assert!(bvh.intersect(&ray).is_none());
        assert!(bvh.intersect_all(&ray).is_empty());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn hits_equal_brute_force(
            ox in -2.0f32..2.0, oy in -1.0f32..5.0, oz in -2.0f32..2.0,
            tx in -0.6f32..0.6, ty in -0.5f32..4.5, tz in -0.6f32..0.6,
        ) {
            let (p, t) = cylinder(24, 10, 0.5, 4.0);
            let bvh = Bvh::build(&p, &t).unwrap();
            let origin = Vec3::new(ox, oy, oz) * 2.0;
            let dir = (Vec3::new(tx, ty, tz) - origin).normalize_or_zero();
            prop_assume!(dir != Vec3::ZERO);
            let ray = Ray { origin, direction: dir };
            let expected = brute(&ray, &p, &t);
            let all: Vec<(f32, u32)> =
                bvh.intersect_all(&ray).iter().map(|h| (h.t, h.triangle)).collect();
            prop_assert_eq!(&all, &expected);
            let first = bvh.intersect(&ray).map(|h| h.t);
            prop_assert_eq!(first, expected.first().map(|e| e.0));
        }
    }
}
