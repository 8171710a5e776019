//! Ray casting against a triangle mesh with a bounding-volume hierarchy (BVH).
//!
//! Sketching (Kho & Garland 2005, §4.1 and §5.2) needs the first hit of the ray through a
//! stroke point, and for twisting the first *two* hits (front and back face). [`Bvh`] is a
//! compact binary BVH over triangles built top-down with the surface area heuristic (SAH)
//! evaluated on 16 centroid bins along the axis of largest centroid extent (large nodes are
//! binned on an even sample of at most 4096 triangles), with at most [`MAX_LEAF`] triangles
//! per leaf.
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

/// Ranges with at least this many triangles are split and their halves built in parallel.
const PARALLEL_MIN: usize = 32_768;

/// Number of centroid bins for the SAH split search.
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

/// A triangle while building: its box and original index (kept together, 28 bytes, so the
/// in-place partitioning streams memory sequentially). The split key is the box centre
/// (stored doubled as `min + max`, see [`Prim::centroid`]), as usual for binned builders.
#[derive(Debug, Clone, Copy)]
struct Prim {
    bounds: Aabb,
    id: u32,
}

impl Prim {
    /// Twice the centre of the triangle's box (the factor 2 does not change any split).
    #[inline]
    fn centroid(&self) -> Vec3 {
        self.bounds.min + self.bounds.max
    }
}

impl Bvh {
    /// Builds the hierarchy over `triangles` (indices into `positions`).
    ///
    /// # Errors
    /// [`CoreError::IndexOutOfRange`] when a triangle refers to a missing position and
    /// [`CoreError::NotFinite`] when a referenced position is NaN or infinite.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<Self> {
        let mut prims: Vec<Prim> = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let mut bounds = Aabb::EMPTY;
            for &v in t {
                let p = positions
                    .get(v as usize)
                    .ok_or_else(|| CoreError::IndexOutOfRange {
                        what: "ray-casting hierarchy".to_owned(),
                        triangle: i,
                        index: v,
                        vertices: positions.len(),
                    })?;
                if !p.is_finite() {
                    return Err(CoreError::NotFinite {
                        what: format!("ray-casting hierarchy: position of vertex {v}"),
                        value: format!("{p}"),
                    });
                }
                bounds.grow_point(*p);
            }
            prims.push(Prim {
                bounds,
                id: i as u32,
            });
        }
        let (bounds, cbounds) = range_bounds(&prims);
        let nodes = build_nodes(&mut prims, 0, bounds, cbounds, PARALLEL_MIN);
        Ok(Self {
            nodes,
            corners: prims
                .iter()
                .map(|p| triangles[p.id as usize].map(|v| positions[v as usize]))
                .collect(),
            ids: prims.iter().map(|p| p.id).collect(),
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
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index as usize];
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
            // Push the farther child first so that the nearer one is visited next.
            match (ta, tb) {
                (Some(x), Some(y)) if x <= y => stack.extend([b, a]),
                (Some(_), Some(_)) => stack.extend([a, b]),
                (Some(_), None) => stack.push(a),
                (None, Some(_)) => stack.push(b),
                (None, None) => {}
            }
        }
    }
}

/// Most triangles binned when searching a split: larger nodes are sub-sampled evenly (the
/// SAH cost curve of a large node is smooth, so a sample finds practically the same plane
/// while the build stays linear per level with a small constant).
const MAX_BINNED: usize = 4096;

/// Builds the nodes over `prims` (which start at `offset` in the final primitive order),
/// root first. Ranges of at least `parallel_min` primitives are split once and their two
/// halves built in parallel (rayon), smaller ones sequentially.
fn build_nodes(
    prims: &mut [Prim],
    offset: usize,
    bounds: Aabb,
    cbounds: Aabb,
    parallel_min: usize,
) -> Vec<Node> {
    let n = prims.len();
    if n >= parallel_min.max(2 * MAX_LEAF)
        && let Some(split) = sah_split(prims, &cbounds)
    {
        let (lp, rp) = prims.split_at_mut(split.mid);
        let (left, right) = rayon::join(
            || build_nodes(lp, offset, split.left, split.left_centroids, parallel_min),
            || {
                build_nodes(
                    rp,
                    offset + split.mid,
                    split.right,
                    split.right_centroids,
                    parallel_min,
                )
            },
        );
        return join_subtrees(bounds, left, right);
    }
    let mut nodes = Vec::with_capacity(2 * n.div_ceil(MAX_LEAF).max(1));
    nodes.push(Node {
        min: bounds.min,
        max: bounds.max,
        first: offset as u32,
        count: n as u32,
    });
    // Work list: node index, range of `prims`, and the centroid bounds of that range (the
    // node's own box is already stored; children's boxes are gathered while splitting).
    let mut stack = vec![(0usize, 0usize, n, cbounds)];
    while let Some((node, start, end, cbounds)) = stack.pop() {
        if end - start <= MAX_LEAF {
            continue;
        }
        let Some(split) = sah_split(&mut prims[start..end], &cbounds) else {
            continue;
        };
        let mid = start + split.mid;
        let left = nodes.len();
        for (bounds, first, count) in [
            (split.left, start, split.mid),
            (split.right, mid, end - mid),
        ] {
            nodes.push(Node {
                min: bounds.min,
                max: bounds.max,
                first: (offset + first) as u32,
                count: count as u32,
            });
        }
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        stack.push((left, start, mid, split.left_centroids));
        stack.push((left + 1, mid, end, split.right_centroids));
    }
    nodes
}

/// A root over two subtrees built separately: `[root, left root, right root, rest of left,
/// rest of right]`, with the interior nodes' child indices renumbered (children stay
/// adjacent).
fn join_subtrees(bounds: Aabb, left: Vec<Node>, right: Vec<Node>) -> Vec<Node> {
    let l = left.len() as u32;
    let map_left = |i: u32| if i == 0 { 1 } else { i + 2 };
    let map_right = |i: u32| if i == 0 { 2 } else { i + l + 1 };
    let remap = |node: &Node, map: &dyn Fn(u32) -> u32| {
        let mut out = *node;
        if out.count == 0 {
            out.first = map(out.first);
        }
        out
    };
    let mut out = Vec::with_capacity(1 + left.len() + right.len());
    out.push(Node {
        min: bounds.min,
        max: bounds.max,
        first: 1,
        count: 0,
    });
    out.push(remap(&left[0], &map_left));
    out.push(remap(&right[0], &map_right));
    out.extend(left[1..].iter().map(|n| remap(n, &map_left)));
    out.extend(right[1..].iter().map(|n| remap(n, &map_right)));
    out
}

/// Boxes of a range of primitives: `(bounds of the triangles, bounds of the centroids)`.
fn range_bounds(prims: &[Prim]) -> (Aabb, Aabb) {
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for p in prims {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid());
    }
    (bounds, cbounds)
}

/// A split of a range: the position and both children's triangle and centroid boxes.
struct Split {
    mid: usize,
    left: Aabb,
    right: Aabb,
    left_centroids: Aabb,
    right_centroids: Aabb,
}

/// Binned SAH split of `prims` in place along the axis of largest centroid extent;
/// returns the split with both children's boxes (gathered in the partitioning pass), or
/// `None` when all centroids coincide and the range is small enough for one (oversized)
/// leaf. Falls back to a median split when no bin boundary separates the centroids.
fn sah_split(prims: &mut [Prim], cbounds: &Aabb) -> Option<Split> {
    let extent = cbounds.max - cbounds.min;
    let n = prims.len();
    let axis = extent.max_position();
    if extent[axis] <= 0.0 {
        if n <= 4 * MAX_LEAF {
            return None;
        }
        // Coincident centroids: any halving terminates.
        return Some(split_at(prims, n / 2));
    }
    let stride = n.div_ceil(MAX_BINNED).max(1);
    let scale = BINS as f32 / extent[axis];
    let lo = cbounds.min[axis];
    let bin_of = |p: &Prim| (((p.centroid()[axis] - lo) * scale) as usize).min(BINS - 1);
    let mut bins = [(Aabb::EMPTY, 0usize); BINS];
    for p in prims.iter().step_by(stride) {
        let b = bin_of(p);
        bins[b].0.grow(&p.bounds);
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
    let mut best: Option<(f32, usize)> = None;
    let mut acc = Aabb::EMPTY;
    let mut cnt = 0;
    for b in 0..BINS - 1 {
        acc.grow(&bins[b].0);
        cnt += bins[b].1;
        if cnt == 0 || right_count[b + 1] == 0 {
            continue;
        }
        let cost = acc.half_area() * cnt as f32 + right_area[b + 1] * right_count[b + 1] as f32;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, b));
        }
    }
    let Some((_, bin)) = best else {
        return Some(split_at_median(prims, axis));
    };
    let mut split = Split {
        mid: 0,
        left: Aabb::EMPTY,
        right: Aabb::EMPTY,
        left_centroids: Aabb::EMPTY,
        right_centroids: Aabb::EMPTY,
    };
    for k in 0..n {
        let p = prims[k];
        if bin_of(&p) <= bin {
            split.left.grow(&p.bounds);
            split.left_centroids.grow_point(p.centroid());
            prims.swap(k, split.mid);
            split.mid += 1;
        } else {
            split.right.grow(&p.bounds);
            split.right_centroids.grow_point(p.centroid());
        }
    }
    if split.mid == 0 || split.mid == n {
        return Some(split_at_median(prims, axis));
    }
    Some(split)
}

/// Median split along `axis`.
fn split_at_median(prims: &mut [Prim], axis: usize) -> Split {
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.centroid()[axis].total_cmp(&b.centroid()[axis])
    });
    split_at(prims, mid)
}

/// Split at `mid` as the primitives are ordered now.
fn split_at(prims: &[Prim], mid: usize) -> Split {
    let (left, left_centroids) = range_bounds(&prims[..mid]);
    let (right, right_centroids) = range_bounds(&prims[mid..]);
    Split {
        mid,
        left,
        right,
        left_centroids,
        right_centroids,
    }
}

/// Slab test: the entry distance of the ray into the node's box if it enters before
/// `t_max`. Conservative: the interval is widened by `1e-5` of its magnitude so that a hit
/// exactly on a box face (a ray through a shared vertex) is never lost to rounding, and an
/// axis the ray is parallel to (`0 · ∞ = NaN`) counts as inside when the origin lies within
/// the slab.
fn slab(node: &Node, origin: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let mut near = 0.0f32;
    let mut far = t_max;
    for a in 0..3 {
        let t0 = (node.min[a] - origin[a]) * inv[a];
        let t1 = (node.max[a] - origin[a]) * inv[a];
        if t0.is_nan() || t1.is_nan() {
            if origin[a] < node.min[a] || origin[a] > node.max[a] {
                return None;
            }
            continue;
        }
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    let pad = 1e-5 * near.abs().max(far.abs().min(f32::MAX)).max(1.0);
    (near - pad <= far + pad).then_some(near)
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

    #[test]
    fn parallel_build_finds_the_same_hits() {
        let (p, t) = cylinder(24, 10, 0.5, 4.0);
        let mut prims: Vec<Prim> = t
            .iter()
            .enumerate()
            .map(|(i, tri)| {
                let mut bounds = Aabb::EMPTY;
                for &v in tri {
                    bounds.grow_point(p[v as usize]);
                }
                Prim {
                    bounds,
                    id: i as u32,
                }
            })
            .collect();
        let (bounds, cbounds) = range_bounds(&prims);
        // Split in parallel down to ranges of 16 triangles.
        let nodes = build_nodes(&mut prims, 0, bounds, cbounds, 16);
        let bvh = Bvh {
            nodes,
            corners: prims
                .iter()
                .map(|q| t[q.id as usize].map(|v| p[v as usize]))
                .collect(),
            ids: prims.iter().map(|q| q.id).collect(),
        };
        let mut sorted = bvh.ids.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..t.len() as u32).collect::<Vec<_>>());
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let origin = Vec3::new(3.0 * a.cos(), (k % 11) as f32 * 0.45 - 0.5, 3.0 * a.sin());
            let target = Vec3::new(0.1 * a.sin(), (k % 7) as f32 * 0.6, 0.0);
            let ray = Ray {
                origin,
                direction: (target - origin).normalize(),
            };
            let all: Vec<(f32, u32)> = bvh
                .intersect_all(&ray)
                .iter()
                .map(|h| (h.t, h.triangle))
                .collect();
            assert_eq!(all, brute(&ray, &p, &t), "ray {k}");
        }
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
