//! Recognising the region of interest of a sketch deformation from the reference curve
//! (Kho & Garland 2005, §4.2).
//!
//! At each end point of the 3-D reference curve a cutting plane perpendicular to the curve
//! meets the surface in loops of triangles. We pick the loop containing the triangle
//! nearest to the end point; on higher-genus meshes further loops of the same plane are kept
//! when removing them would merge the two sides of the first one (the paper's loop-removal
//! rule). The edges crossed by the kept loops are cut and the welded vertices are flood
//! filled into three parts:
//!
//! * **static**: beyond the start plane, the part the curve starts from (unchanged);
//! * **region of interest**: between the planes, the part the curve covers (deformed);
//! * **rigid**: beyond the end plane (moved rigidly with the end of the curve).
//!
//! The paper: "The static component will be the region bounded by the loop created by the
//! starting point of the reference curve and the rigid component is bounded by its ending
//! point" (the leg example: body static, leg deformed, foot rigid). So the direction of the
//! stroke matters: draw from the part that stays towards the part that moves.

use std::collections::{HashMap, VecDeque};

use glam::Vec3;
use petgraph::unionfind::UnionFind;

use crate::error::{CoreError, Result};
use crate::mesh::Topology;
use crate::sketch::partition::Partition;

/// Which side of a cutting plane a vertex is on: `true` for `n · (p − c) ≥ 0` (the side the
/// plane normal points to). Vertices exactly on the plane count as positive, so every edge
/// either crosses the plane or not, without a third case.
#[must_use]
pub fn plane_side(normal: Vec3, point: Vec3, p: Vec3) -> bool {
    normal.dot(p - point) >= 0.0
}

/// Vertex adjacency in compressed sparse row form (each undirected edge appears in both
/// directions, possibly more than once).
#[derive(Debug, Clone)]
pub(crate) struct VertexGraph {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl VertexGraph {
    /// Builds the adjacency of `vertex_count` vertices from triangle edges.
    pub(crate) fn new(vertex_count: usize, triangles: &[[u32; 3]]) -> Self {
        let mut degree = vec![0u32; vertex_count + 1];
        for t in triangles {
            for &v in t {
                degree[v as usize] += 2;
            }
        }
        let mut offsets = Vec::with_capacity(vertex_count + 1);
        let mut acc = 0u32;
        for d in &degree[..vertex_count] {
            offsets.push(acc);
            acc += d;
        }
        offsets.push(acc);
        let mut fill = offsets.clone();
        let mut neighbours = vec![0u32; acc as usize];
        for t in triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                neighbours[fill[a as usize] as usize] = b;
                fill[a as usize] += 1;
                neighbours[fill[b as usize] as usize] = a;
                fill[b as usize] += 1;
            }
        }
        Self {
            offsets,
            neighbours,
        }
    }

    /// Neighbours of `v`.
    pub(crate) fn neighbours(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.neighbours[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Breadth-first flood fill from `seeds` over edges for which `blocked(a, b)` is false,
    /// writing `label` into every reached vertex whose label is `u32::MAX`. Returns the
    /// number of vertices labelled.
    pub(crate) fn flood(
        &self,
        seeds: impl IntoIterator<Item = u32>,
        labels: &mut [u32],
        label: u32,
        mut blocked: impl FnMut(u32, u32) -> bool,
    ) -> usize {
        let mut queue = VecDeque::new();
        let mut count = 0;
        for s in seeds {
            if labels[s as usize] == u32::MAX {
                labels[s as usize] = label;
                count += 1;
                queue.push_back(s);
            }
        }
        while let Some(v) = queue.pop_front() {
            for &w in self.neighbours(v) {
                if labels[w as usize] == u32::MAX && !blocked(v, w) {
                    labels[w as usize] = label;
                    count += 1;
                    queue.push_back(w);
                }
            }
        }
        count
    }

    /// Whether `to` (any of them) is reachable from `from` over unblocked edges.
    fn reaches(
        &self,
        from: &[u32],
        to: &[u32],
        scratch: &mut Vec<u32>,
        blocked: impl Fn(u32, u32) -> bool,
    ) -> bool {
        scratch.clear();
        scratch.resize(self.offsets.len() - 1, u32::MAX);
        for &t in to {
            scratch[t as usize] = 1;
        }
        let mut queue = VecDeque::new();
        for &s in from {
            if scratch[s as usize] == 1 {
                return true;
            }
            if scratch[s as usize] == u32::MAX {
                scratch[s as usize] = 0;
                queue.push_back(s);
            }
        }
        while let Some(v) = queue.pop_front() {
            for &w in self.neighbours(v) {
                let lw = scratch[w as usize];
                if lw == 0 || blocked(v, w) {
                    continue;
                }
                if lw == 1 {
                    return true;
                }
                scratch[w as usize] = 0;
                queue.push_back(w);
            }
        }
        false
    }
}

/// Checks that `positions` holds one welded position per topological vertex.
pub(crate) fn check_positions(what: &str, positions: &[Vec3], topology: &Topology) -> Result<()> {
    if positions.len() == topology.vertex_count() {
        Ok(())
    } else {
        Err(CoreError::Degenerate {
            what: what.to_owned(),
            problem: format!(
                "{} positions given for {} welded vertices",
                positions.len(),
                topology.vertex_count()
            ),
        })
    }
}

/// Key of an undirected edge.
pub(crate) fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// One cutting plane of the reference curve and the triangle loops it cuts out of the mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct CuttingPlane {
    /// The curve end point the plane passes through.
    pub point: Vec3,
    /// Unit normal: the curve's direction at that end (first segment at the start, last
    /// segment at the end), so the positive side is "further along the curve".
    pub normal: Vec3,
    /// Every loop of triangles the plane crosses (triangle indices into
    /// `Topology::triangles`, in the order they were found).
    pub loops: Vec<Vec<u32>>,
    /// Indices into `loops` of the loops kept for the cut; the first is the loop containing
    /// the triangle nearest to `point`. Empty when the plane misses the mesh.
    pub kept: Vec<usize>,
}

/// The result of [`region_from_curve`]: the partition and the cutting planes that made it.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveRegion {
    /// Region of interest and the rigid component (at most one) beyond the end.
    pub partition: Partition,
    /// Cutting plane at the start point of the curve (bounds the static component).
    pub start: CuttingPlane,
    /// Cutting plane at the end point of the curve (bounds the rigid component).
    pub end: CuttingPlane,
}

/// The partition of the welded mesh for a reference curve (Kho & Garland §4.2): region of
/// interest between the cutting planes at the curve's ends, one rigid component beyond the
/// end plane, static elsewhere. See [`region_from_curve`] for the rules.
///
/// # Errors
/// As [`region_from_curve`].
pub fn partition_from_curve(
    positions: &[Vec3],
    topology: &Topology,
    curve: &[Vec3],
) -> Result<Partition> {
    region_from_curve(positions, topology, curve).map(|r| r.partition)
}

/// [`partition_from_curve`] with the cutting planes and loops (for display, Fig. 3c).
///
/// Rules (decisions where the paper is silent are marked *):
/// * Plane at the start: through `curve[0]`, normal = direction of the first non-zero
///   segment; at the end: through the last node, normal = direction of the last non-zero
///   segment.
/// * A triangle is in a loop when its corners are on both sides ([`plane_side`]); loops are
///   the connected sets of such triangles sharing crossed edges.
/// * Per plane, the first kept loop contains the crossed triangle nearest to the end point
///   (exact point–triangle distance). The other loops are then considered in order of
///   increasing distance* and removed from the cut unless that merges the two sides of the
///   first loop (higher genus, §4.2).
/// * Flood fill with every kept loop's crossed edges removed: the region of interest is the
///   component(s) reached from the positive-side corners of the start loop; the rigid
///   component is reached from the positive-side corners of the end loop; all other
///   vertices are static.
/// * *A plane that misses the mesh bounds nothing: no start loop → no static part beyond
///   it (the region grows from the negative side of the end loop); no end loop → no rigid
///   part (the curve was drawn past the tip, Fig. 14). If neither plane meets the mesh the
///   region is the connected part containing the vertex nearest to the curve's start.
///
/// # Errors
/// [`CoreError::StrokeTooShort`] for fewer than two distinct curve nodes,
/// [`CoreError::NotFinite`] naming a bad node, [`CoreError::Degenerate`] when `positions`
/// does not match the topology, and [`CoreError::RegionOfInterest`] when the planes do not
/// separate the mesh: the region reaches beyond the end plane (the curve turns back), or the
/// end loop does not touch the region (it lies on another part).
pub fn region_from_curve(
    positions: &[Vec3],
    topology: &Topology,
    curve: &[Vec3],
) -> Result<CurveRegion> {
    if let Some(i) = curve.iter().position(|p| !p.is_finite()) {
        return Err(CoreError::NotFinite {
            what: format!("reference curve node {i}"),
            value: format!("{}", curve[i]),
        });
    }
    check_positions("region of interest", positions, topology)?;
    let n = topology.vertex_count();
    let (start_dir, end_dir) = end_directions(curve)?;
    let start_point = curve[0];
    let end_point = curve[curve.len() - 1];
    let graph = VertexGraph::new(n, &topology.triangles);

    let mut scratch = Vec::new();
    let start = cutting_plane(
        positions,
        topology,
        &graph,
        start_point,
        start_dir,
        &mut scratch,
    );
    let end = cutting_plane(
        positions,
        topology,
        &graph,
        end_point,
        end_dir,
        &mut scratch,
    );

    let side0: Vec<bool> = positions
        .iter()
        .map(|&p| plane_side(start.plane.normal, start.plane.point, p))
        .collect();
    let side1: Vec<bool> = positions
        .iter()
        .map(|&p| plane_side(end.plane.normal, end.plane.point, p))
        .collect();
    let blocked = |a: u32, b: u32| {
        (side0[a as usize] != side0[b as usize] && start.is_cut(a, b))
            || (side1[a as usize] != side1[b as usize] && end.is_cut(a, b))
    };

    const ROI: u32 = 0;
    const RIGID: u32 = 1;
    let mut labels = vec![u32::MAX; n];
    let (start_pos, _) = start.first_loop_sides(&side0);
    let (end_pos, end_neg) = end.first_loop_sides(&side1);
    if !start_pos.is_empty() {
        graph.flood(start_pos.iter().copied(), &mut labels, ROI, blocked);
    } else if !end_neg.is_empty() {
        graph.flood(end_neg.iter().copied(), &mut labels, ROI, blocked);
    } else {
        // Neither plane meets the mesh: the connected part nearest to the curve's start.
        let used = used_vertices(n, &topology.triangles);
        let nearest = (0..n)
            .filter(|&v| used[v])
            .min_by(|&a, &b| {
                positions[a]
                    .distance_squared(start_point)
                    .total_cmp(&positions[b].distance_squared(start_point))
            })
            .map(|v| v as u32);
        graph.flood(nearest, &mut labels, ROI, |_, _| false);
    }
    if !start_pos.is_empty() && !end_pos.is_empty() {
        if end_pos.iter().any(|&v| labels[v as usize] == ROI) {
            return Err(CoreError::RegionOfInterest {
                what: "reference curve".to_owned(),
                problem: "the region between the cutting planes reaches past the end plane (does the curve turn back on itself?); the planes do not separate the mesh".to_owned(),
            });
        }
        if !end_neg.iter().any(|&v| labels[v as usize] == ROI) {
            return Err(CoreError::RegionOfInterest {
                what: "reference curve".to_owned(),
                problem: "the cutting plane at the end of the curve meets the mesh nearest to the end point on a part that the region starting at the start plane does not reach; the planes do not bound a region".to_owned(),
            });
        }
    }
    graph.flood(end_pos.iter().copied(), &mut labels, RIGID, blocked);

    let roi: Vec<u32> = (0..n as u32)
        .filter(|&v| labels[v as usize] == ROI)
        .collect();
    let rigid: Vec<u32> = (0..n as u32)
        .filter(|&v| labels[v as usize] == RIGID)
        .collect();
    if roi.is_empty() {
        return Err(CoreError::RegionOfInterest {
            what: "reference curve".to_owned(),
            problem: "the region of interest is empty".to_owned(),
        });
    }
    Ok(CurveRegion {
        partition: Partition {
            roi,
            rigid: if rigid.is_empty() {
                Vec::new()
            } else {
                vec![rigid]
            },
        },
        start: start.plane,
        end: end.plane,
    })
}

/// Directions of the first and last non-zero segments.
fn end_directions(curve: &[Vec3]) -> Result<(Vec3, Vec3)> {
    let too_short = || CoreError::StrokeTooShort {
        what: "reference curve (distinct nodes)".to_owned(),
        found: 1.min(curve.len()),
        needed: 2,
    };
    let first = *curve.first().ok_or_else(too_short)?;
    let last = *curve.last().ok_or_else(too_short)?;
    let start = curve
        .iter()
        .map(|&p| p - first)
        .find(|d| d.length_squared() > 0.0)
        .ok_or_else(too_short)?
        .normalize();
    let end = curve
        .iter()
        .rev()
        .map(|&p| last - p)
        .find(|d| d.length_squared() > 0.0)
        .ok_or_else(too_short)?
        .normalize();
    Ok((start, end))
}

/// Vertices referenced by at least one triangle.
fn used_vertices(n: usize, triangles: &[[u32; 3]]) -> Vec<bool> {
    let mut used = vec![false; n];
    for t in triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    used
}

/// A cutting plane with its crossed edges indexed for the flood fill.
struct PlaneCut {
    plane: CuttingPlane,
    /// Loop index of every crossed edge.
    edge_loop: HashMap<u64, usize>,
    /// Whether each loop is part of the cut.
    in_cut: Vec<bool>,
}

impl PlaneCut {
    fn is_cut(&self, a: u32, b: u32) -> bool {
        self.edge_loop
            .get(&edge_key(a, b))
            .is_some_and(|&l| self.in_cut[l])
    }

    /// Corners of the first kept loop's crossed edges on the positive and negative side.
    fn first_loop_sides(&self, side: &[bool]) -> (Vec<u32>, Vec<u32>) {
        let Some(&first) = self.plane.kept.first() else {
            return (Vec::new(), Vec::new());
        };
        loop_sides(&self.edge_loop, first, side)
    }
}

/// Positive- and negative-side corners of loop `l`'s crossed edges.
fn loop_sides(edge_loop: &HashMap<u64, usize>, l: usize, side: &[bool]) -> (Vec<u32>, Vec<u32>) {
    let mut pos = Vec::new();
    let mut neg = Vec::new();
    for (&key, &el) in edge_loop {
        if el != l {
            continue;
        }
        for v in [(key >> 32) as u32, key as u32] {
            if side[v as usize] {
                pos.push(v);
            } else {
                neg.push(v);
            }
        }
    }
    pos.sort_unstable();
    pos.dedup();
    neg.sort_unstable();
    neg.dedup();
    (pos, neg)
}

/// Finds the loops of the plane through `point` with `normal` and applies the loop
/// selection and loop-removal rules.
fn cutting_plane(
    positions: &[Vec3],
    topology: &Topology,
    graph: &VertexGraph,
    point: Vec3,
    normal: Vec3,
    scratch: &mut Vec<u32>,
) -> PlaneCut {
    let side: Vec<bool> = positions
        .iter()
        .map(|&p| plane_side(normal, point, p))
        .collect();
    // Crossed triangles and, for each crossed edge, the crossed triangles on it.
    let mut crossed: Vec<u32> = Vec::new();
    let mut edge_tris: HashMap<u64, Vec<usize>> = HashMap::new();
    for (ti, t) in topology.triangles.iter().enumerate() {
        let s = t.map(|v| side[v as usize]);
        if s[0] == s[1] && s[1] == s[2] {
            continue;
        }
        let local = crossed.len();
        crossed.push(ti as u32);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if s[k] != s[(k + 1) % 3] {
                edge_tris.entry(edge_key(a, b)).or_default().push(local);
            }
        }
    }
    // Loops: connected components of crossed triangles through crossed edges.
    let mut components = UnionFind::<usize>::new(crossed.len());
    for tris in edge_tris.values() {
        for w in tris.windows(2) {
            components.union(w[0], w[1]);
        }
    }
    let mut root_loop: HashMap<usize, usize> = HashMap::new();
    let mut loops: Vec<Vec<u32>> = Vec::new();
    let mut tri_loop = vec![0usize; crossed.len()];
    for local in 0..crossed.len() {
        let r = components.find_mut(local);
        let next = loops.len();
        let l = *root_loop.entry(r).or_insert(next);
        if l == loops.len() {
            loops.push(Vec::new());
        }
        loops[l].push(crossed[local]);
        tri_loop[local] = l;
    }
    let edge_loop: HashMap<u64, usize> = edge_tris
        .iter()
        .map(|(&k, tris)| (k, tri_loop[tris[0]]))
        .collect();

    // Distance of every loop to the end point (its nearest triangle).
    let loop_distance: Vec<f32> = loops
        .iter()
        .map(|tris| {
            tris.iter()
                .map(|&t| {
                    let [a, b, c] = topology.triangles[t as usize].map(|v| positions[v as usize]);
                    point.distance(closest_point_triangle(point, a, b, c))
                })
                .fold(f32::INFINITY, f32::min)
        })
        .collect();
    let mut order: Vec<usize> = (0..loops.len()).collect();
    order.sort_by(|&a, &b| loop_distance[a].total_cmp(&loop_distance[b]));

    let mut in_cut = vec![true; loops.len()];
    let mut kept = Vec::new();
    if let Some((&first, others)) = order.split_first() {
        kept.push(first);
        let (pos, neg) = loop_sides(&edge_loop, first, &side);
        for &candidate in others {
            in_cut[candidate] = false;
            let merges = graph.reaches(&pos, &neg, scratch, |a, b| {
                side[a as usize] != side[b as usize]
                    && edge_loop.get(&edge_key(a, b)).is_some_and(|&l| in_cut[l])
            });
            if merges {
                in_cut[candidate] = true;
                kept.push(candidate);
            }
        }
    }
    PlaneCut {
        plane: CuttingPlane {
            point,
            normal,
            loops,
            kept,
        },
        edge_loop,
        in_cut,
    }
}

/// The point of triangle `abc` closest to `p` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5, by Voronoi regions).
#[must_use]
pub fn closest_point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // Degenerate (zero-area) triangle: nearest corner.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::sketch::raycast::tests::cylinder;

    pub(crate) fn welded(p: Vec<Vec3>, t: &[[u32; 3]]) -> (Vec<Vec3>, Topology) {
        let mesh = Mesh {
            positions: p,
            normals: None,
            uvs: None,
            indices: t.iter().flatten().copied().collect(),
        };
        let topo = Topology::weld(&mesh);
        (topo.gather(&mesh.positions), topo)
    }

    /// A torus around the Y axis: major radius `big`, minor `small`, `u` segments around
    /// the ring and `v` around the tube. Vertex (i, j) is at ring angle 2πi/u.
    pub(crate) fn torus(u: u32, v: u32, big: f32, small: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for i in 0..u {
            let a = std::f32::consts::TAU * (i as f32 + 0.5) / u as f32;
            for j in 0..v {
                let b = std::f32::consts::TAU * j as f32 / v as f32;
                let r = big + small * b.cos();
                p.push(Vec3::new(r * a.cos(), small * b.sin(), r * a.sin()));
            }
        }
        let idx = |i: u32, j: u32| (i % u) * v + j % v;
        let mut t = Vec::new();
        for i in 0..u {
            for j in 0..v {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                t.push([a, b, c]);
                t.push([a, c, d]);
            }
        }
        (p, t)
    }

    fn ring_angle(p: Vec3) -> f32 {
        p.z.atan2(p.x).rem_euclid(std::f32::consts::TAU)
    }

    #[test]
    fn closest_point_on_triangle_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let q = closest_point_triangle(Vec3::new(0.2, 0.2, 3.0), a, b, c);
        assert!((q - Vec3::new(0.2, 0.2, 0.0)).length() < 1e-6);
        assert_eq!(
            closest_point_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c),
            a
        );
        let q = closest_point_triangle(Vec3::new(0.5, -2.0, 0.0), a, b, c);
        assert!((q - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6);
        let q = closest_point_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
    }

    #[test]
    fn cylinder_band_between_planes_is_the_region() {
        // Rings at y = 0, 0.25, ..., 4; curve from y = 2.1 up to y = 3.6 on the front.
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let curve: Vec<Vec3> = (0..=6)
            .map(|i| Vec3::new(0.0, 2.1 + 0.25 * i as f32, 0.5))
            .collect();
        let region = region_from_curve(&pos, &topo, &curve).unwrap();
        let part = &region.partition;
        let expect_roi: Vec<u32> = (0..pos.len() as u32)
            .filter(|&v| (2.1..3.6).contains(&pos[v as usize].y))
            .collect();
        let expect_rigid: Vec<u32> = (0..pos.len() as u32)
            .filter(|&v| pos[v as usize].y >= 3.6)
            .collect();
        assert_eq!(part.roi, expect_roi);
        assert_eq!(part.rigid, vec![expect_rigid]);
        assert_eq!(region.start.loops.len(), 1);
        assert_eq!(region.start.kept, vec![0]);
        // The band holds rings 9..=14 (y = 2.25 .. 3.5): 6 rings of 24.
        assert_eq!(part.roi.len(), 6 * 24);
        // Drawn the other way round, static and rigid swap.
        let reversed: Vec<Vec3> = curve.iter().rev().copied().collect();
        let part = partition_from_curve(&pos, &topo, &reversed).unwrap();
        let expect_rigid_rev: Vec<u32> = (0..pos.len() as u32)
            .filter(|&v| pos[v as usize].y < 2.1)
            .collect();
        assert_eq!(part.rigid, vec![expect_rigid_rev]);
    }

    #[test]
    fn curve_past_the_tip_has_no_rigid_part() {
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let curve = [Vec3::new(0.0, 2.1, 0.5), Vec3::new(0.0, 5.0, 0.5)];
        let part = partition_from_curve(&pos, &topo, &curve).unwrap();
        assert!(part.rigid.is_empty());
        assert_eq!(
            part.roi.len(),
            pos.iter().filter(|p| p.y >= 2.1).count(),
            "the top cap belongs to the region"
        );
    }

    #[test]
    fn curve_past_both_ends_makes_the_whole_part_the_region() {
        // Fig. 11: a curve over the whole cylinder bends all of it.
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let curve = [Vec3::new(0.0, -1.0, 0.5), Vec3::new(0.0, 5.0, 0.5)];
        let region = region_from_curve(&pos, &topo, &curve).unwrap();
        assert!(region.start.loops.is_empty() && region.end.loops.is_empty());
        assert_eq!(region.partition.roi.len(), pos.len());
        assert!(region.partition.rigid.is_empty());
    }

    #[test]
    fn torus_keeps_both_loops_of_each_plane() {
        // Ring angles of vertex columns are 2π(i + ½)/32; the curve follows the ring from
        // angle 0.3 to 1.2 (radians) on its outer equator.
        let (p, t) = torus(32, 12, 2.0, 0.5);
        let (pos, topo) = welded(p, &t);
        let curve: Vec<Vec3> = (0..=12)
            .map(|k| {
                let a = 0.3 + 0.9 * k as f32 / 12.0;
                Vec3::new(2.5 * a.cos(), 0.0, 2.5 * a.sin())
            })
            .collect();
        let region = region_from_curve(&pos, &topo, &curve).unwrap();
        // Each plane cuts the ring twice; one meridian loop leaves a torus connected, so
        // the rule keeps both.
        assert_eq!(region.start.loops.len(), 2);
        assert_eq!(region.start.kept.len(), 2);
        assert_eq!(region.end.kept.len(), 2);
        // The nearest loop is the one at the curve's start angle, not the opposite one.
        let first = &region.start.loops[region.start.kept[0]];
        let centre = topo.triangles[first[0] as usize]
            .map(|v| pos[v as usize])
            .iter()
            .sum::<Vec3>();
        assert!((ring_angle(centre) - 0.3).abs() < 0.3);
        // Region: the vertices between the two planes on this side of the ring (the planes
        // are nearly meridian planes; the wedge between them holds only this arc).
        let in_roi = |q: Vec3| {
            region.start.normal.dot(q - region.start.point) >= 0.0
                && region.end.normal.dot(q - region.end.point) < 0.0
        };
        let expect: Vec<u32> = (0..pos.len() as u32)
            .filter(|&v| in_roi(pos[v as usize]))
            .collect();
        assert!(!expect.is_empty());
        assert!(expect.iter().all(|&v| {
            let a = ring_angle(pos[v as usize]);
            (0.2..1.3).contains(&a)
        }));
        assert_eq!(region.partition.roi, expect);
        // Rigid: beyond the end plane up to the start plane's far loop.
        let rigid = &region.partition.rigid[0];
        for &v in rigid {
            let q = pos[v as usize];
            assert!(region.end.normal.dot(q - region.end.point) >= 0.0);
            assert!(region.start.normal.dot(q - region.start.point) >= 0.0);
        }
        assert!(!rigid.is_empty());
    }

    #[test]
    fn loops_on_a_separate_part_are_removed() {
        // Two tori side by side along Z. A plane that also cuts the second torus far away
        // must not keep the second torus's loops in the cut.
        let (mut p, mut t) = torus(32, 12, 2.0, 0.5);
        let (p2, t2) = torus(32, 12, 2.0, 0.5);
        let off = p.len() as u32;
        p.extend(p2.iter().map(|q| *q + Vec3::new(0.0, 0.0, 8.0)));
        t.extend(t2.iter().map(|tri| tri.map(|v| v + off)));
        let (pos, topo) = welded(p, &t);
        // A curve along +Z through the first torus's front (x = 2.5): planes z = const.
        let curve = [Vec3::new(2.5, 0.0, -0.6), Vec3::new(2.5, 0.0, 0.6)];
        let region = region_from_curve(&pos, &topo, &curve).unwrap();
        // Start plane z = −0.6 cuts only the first torus (two tubes of the ring → 2 loops),
        // plane z = 0.6 likewise; the second torus spans z in [5.5, 10.5]: never cut.
        assert_eq!(region.start.loops.len(), 2);
        assert_eq!(region.start.kept.len(), 2);
        // Now a plane that cuts both tori: a curve along X at z = 0 and z = 8 share
        // planes x = const.
        let curve = [Vec3::new(1.0, 0.0, 2.0), Vec3::new(1.6, 0.0, 2.0)];
        let region = region_from_curve(&pos, &topo, &curve).unwrap();
        // x = 1 cuts each torus in two loops (near z = ±1.7 and z = 8 ± 1.7).
        assert_eq!(region.start.loops.len(), 4);
        // Near loop kept; its partner on the same torus is needed (ring), the two on the
        // other torus are removed.
        assert_eq!(region.start.kept.len(), 2);
        for &l in &region.start.kept {
            for &tri in &region.start.loops[l] {
                let c = topo.triangles[tri as usize].map(|v| pos[v as usize]);
                assert!(c.iter().all(|q| q.z < 4.0), "kept loop on the second torus");
            }
        }
        // The second torus is static.
        let part = &region.partition;
        assert!(part.roi.iter().all(|&v| pos[v as usize].z < 4.0));
        assert!(
            part.rigid
                .iter()
                .flatten()
                .all(|&v| pos[v as usize].z < 4.0)
        );
    }

    #[test]
    fn curve_turning_back_is_an_error() {
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        // Up from 1.1 to 3.1 and then back down to 2.1, ending with a downward segment: the
        // end plane's positive side (below 2.1) contains the start region.
        let curve = [
            Vec3::new(0.0, 1.1, 0.5),
            Vec3::new(0.0, 3.1, 0.5),
            Vec3::new(0.0, 2.1, 0.5),
        ];
        let err = partition_from_curve(&pos, &topo, &curve).unwrap_err();
        assert!(matches!(err, CoreError::RegionOfInterest { .. }), "{err}");
        assert!(err.to_string().contains("do not separate"));
    }

    #[test]
    fn degenerate_curves_are_errors() {
        let (p, t) = cylinder(8, 4, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let err = partition_from_curve(&pos, &topo, &[Vec3::ONE, Vec3::ONE]).unwrap_err();
        assert!(matches!(err, CoreError::StrokeTooShort { .. }));
        let err = partition_from_curve(&pos, &topo, &[Vec3::ONE, Vec3::new(0.0, f32::NAN, 0.0)])
            .unwrap_err();
        assert!(err.to_string().contains("node 1"), "{err}");
    }
}
