//! Interactive partitioning by cut lines (Kho & Garland 2005, §4.2.1, after the fuzzy
//! decomposition of Katz & Tal 2003).
//!
//! The user draws a line on screen. It defines a cutting plane containing the line and the
//! viewing rays through it. Triangles within [`FUZZY_DISTANCE_PX`] of the line on screen form
//! a fuzzy region; a minimum cut on the dual graph of that region, with edge weights
//! "dihedral angle × edge length", gives the actual boundary along mesh edges, which prefers
//! sharp creases over flat areas. Several cuts combine into a [`Partition`]: the part that
//! holds the reference curve stays freely deformable, every other part is rigid ("The freely
//! deformable region is bounded by only one partition. All other parts will be rigidly
//! transformed.").
//!
//! The max-flow/min-cut solver is `petgraph`'s Dinic algorithm on integer capacities.

use std::collections::{BTreeMap, HashMap};

use glam::{Vec2, Vec3};
use petgraph::Directed;
use petgraph::Direction;
use petgraph::algo::dinics;
use petgraph::graph::{Graph, NodeIndex};
use petgraph::unionfind::UnionFind;
use petgraph::visit::EdgeRef;

use crate::error::{CoreError, Result};
use crate::mesh::Topology;
use crate::sketch::camera::Camera;
use crate::sketch::partition::Partition;
use crate::sketch::roi::{VertexGraph, check_positions, edge_key};

/// Screen-space half-width of the fuzzy region around a cut line, in pixels (Kho & Garland
/// §4.2.1: "we typically adopt a 5 pixel distance limit").
pub const FUZZY_DISTANCE_PX: f32 = 5.0;

/// Largest integer capacity of a dual edge; weights are scaled so the heaviest edge gets
/// this value (integer capacities make the residual test exact; 10⁶ keeps the rounding
/// error of every weight below 10⁻⁶ of the largest).
const CAPACITY_SCALE: f64 = 1.0e6;

/// The result of one cut line: the cutting plane, the fuzzy region and the boundary found
/// by the minimum cut, and the welded vertices on each side.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshCut {
    /// A point on the cutting plane (on the ray through the line's first end).
    pub point: Vec3,
    /// Unit normal of the cutting plane. The positive side is on the right of the line when
    /// walking from its first to its second end on screen (pixel y points down).
    pub normal: Vec3,
    /// Triangles (indices into `Topology::triangles`) of the fuzzy region that was cut.
    pub fuzzy: Vec<u32>,
    /// Mesh edges `[a, b]` (`a < b`, welded vertices) along the cut, sorted.
    pub boundary_edges: Vec<[u32; 2]>,
    /// Vertices on the cut (corners of `boundary_edges`), ascending.
    pub boundary: Vec<u32>,
    /// Vertices on the positive side, off the cut, ascending.
    pub positive: Vec<u32>,
    /// Vertices on the negative side, off the cut, ascending. Vertices of mesh parts the
    /// cut does not touch are in neither list.
    pub negative: Vec<u32>,
}

/// Cuts the mesh along the line `line_px` drawn with `camera` (Kho & Garland §4.2.1).
///
/// 1. Plane: through the viewing rays of both line ends (so it contains the line and the eye
///    for a perspective camera, and the view direction for an orthographic one).
/// 2. Fuzzy region: triangles whose projection lies within [`FUZZY_DISTANCE_PX`] of the
///    (infinite) line on screen, all three corners in front of the eye, grouped into
///    connected regions over shared edges. Among the regions that come within 5 px of the
///    drawn *segment* (a decision: the paper says "nearest to the view point", which on its
///    own could pick a part the line's extension merely grazes), the one with the smallest
///    view depth is cut.
/// 3. Dual graph: one node per triangle of the region and per triangle bordering it; the
///    dual edge across a primal edge of length `ℓ` with normals at angle `θ` has weight
///    `(π − θ)·ℓ` — the dihedral angle between the faces (π on a flat area, smaller at a
///    crease of either sign) times the edge length. Bordering triangles connect to the
///    source or the sink (by the plane side of their centroid) with unbounded capacity.
/// 4. Minimum cut (maximum flow by Dinic's algorithm): region triangles reachable from the
///    source in the residual network are on the positive side. The primal edges between the two sides form
///    the boundary.
/// 5. Vertices: a flood fill over the mesh that may not pass through boundary vertices,
///    from the off-cut corners of the triangles on each side.
///
/// # Errors
/// [`CoreError::NotFinite`] / [`CoreError::OutOfRange`] for a bad or too short line
/// (< 1 px), [`CoreError::Degenerate`] when `positions` does not match the topology, and
/// [`CoreError::Cut`] when the line does not cross the mesh, the fuzzy region has triangles
/// on only one side, or the cut does not separate the mesh (a handle or another connection
/// goes around it).
pub fn cut_with_line(
    camera: &Camera,
    line_px: [Vec2; 2],
    positions: &[Vec3],
    topology: &Topology,
) -> Result<MeshCut> {
    for (i, p) in line_px.iter().enumerate() {
        if !p.is_finite() {
            return Err(CoreError::NotFinite {
                what: format!("cut line end {i}"),
                value: format!("{p}"),
            });
        }
    }
    let dir = line_px[1] - line_px[0];
    let len = dir.length();
    if len < 1.0 {
        return Err(CoreError::OutOfRange {
            what: "cut line length (px)".to_owned(),
            value: f64::from(len),
            expected: "must be at least 1 pixel",
        });
    }
    check_positions("cut line", positions, topology)?;
    let n = topology.vertex_count();
    let (point, normal) = cut_plane(camera, line_px)?;
    let unit = dir / len;

    // Screen position (signed distance to the line, parameter along it) and view depth of
    // every vertex; `None` behind the eye.
    let view_proj = camera.projection_matrix() * camera.view();
    let view = camera.view();
    let screen: Vec<Option<(f32, f32, f32)>> = positions
        .iter()
        .map(|&p| {
            let clip = view_proj * p.extend(1.0);
            if clip.w <= 1e-12 {
                return None;
            }
            let ndc = Vec2::new(clip.x, clip.y) / clip.w;
            let px = Vec2::new(
                (ndc.x + 1.0) * 0.5 * camera.viewport.x,
                (1.0 - ndc.y) * 0.5 * camera.viewport.y,
            );
            let rel = px - line_px[0];
            let depth = -(view * p.extend(1.0)).z;
            Some((unit.perp_dot(rel), unit.dot(rel), depth))
        })
        .collect();

    // Fuzzy triangles.
    let tris = &topology.triangles;
    let mut fuzzy_flag = vec![false; tris.len()];
    let mut fuzzy: Vec<u32> = Vec::new();
    for (ti, t) in tris.iter().enumerate() {
        let (Some(a), Some(b), Some(c)) = (
            screen[t[0] as usize],
            screen[t[1] as usize],
            screen[t[2] as usize],
        ) else {
            continue;
        };
        let lo = a.0.min(b.0).min(c.0);
        let hi = a.0.max(b.0).max(c.0);
        if lo <= FUZZY_DISTANCE_PX && hi >= -FUZZY_DISTANCE_PX {
            fuzzy_flag[ti] = true;
            fuzzy.push(ti as u32);
        }
    }
    if fuzzy.is_empty() {
        return Err(CoreError::Cut {
            what: "cut line".to_owned(),
            problem: "the line does not pass over the mesh".to_owned(),
        });
    }

    // Edges of fuzzy triangles → every triangle on them (fuzzy or bordering).
    let mut vertex_fuzzy = vec![false; n];
    for &ti in &fuzzy {
        for v in tris[ti as usize] {
            vertex_fuzzy[v as usize] = true;
        }
    }
    let mut edge_tris: HashMap<u64, Vec<u32>> = HashMap::new();
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if vertex_fuzzy[a as usize] && vertex_fuzzy[b as usize] {
                edge_tris.entry(edge_key(a, b)).or_default().push(ti as u32);
            }
        }
    }
    // Keep edges that touch a fuzzy triangle.
    edge_tris.retain(|_, ts| ts.iter().any(|&t| fuzzy_flag[t as usize]));

    // Connected fuzzy regions (union–find over fuzzy-fuzzy edges).
    let local: HashMap<u32, usize> = fuzzy.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    let mut regions = UnionFind::<usize>::new(fuzzy.len());
    let mut keys: Vec<u64> = edge_tris.keys().copied().collect();
    keys.sort_unstable();
    for key in &keys {
        let ts = &edge_tris[key];
        let fz: Vec<usize> = ts.iter().filter_map(|t| local.get(t).copied()).collect();
        for w in fz.windows(2) {
            regions.union(w[0], w[1]);
        }
    }
    // Per region that comes near the drawn segment (by its root): its nearest depth, and its
    // first triangle near the segment, which breaks ties whatever root the union–find picked.
    let reach = FUZZY_DISTANCE_PX;
    let mut region_depth: HashMap<usize, (f32, usize)> = HashMap::new();
    for (i, &ti) in fuzzy.iter().enumerate() {
        let corners = tris[ti as usize].map(|v| screen[v as usize]);
        let (mut tlo, mut thi, mut dmin) = (f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY);
        for c in corners.into_iter().flatten() {
            tlo = tlo.min(c.1);
            thi = thi.max(c.1);
            dmin = dmin.min(c.2);
        }
        let root = regions.find_mut(i);
        if thi >= -reach && tlo <= len + reach {
            // `i` ascends: when a region is first seen here, `i` is its first such triangle.
            let e = region_depth.entry(root).or_insert((f32::INFINITY, i));
            e.0 = e.0.min(dmin);
        }
    }
    let Some((&chosen, _)) = region_depth
        .iter()
        .min_by(|a, b| a.1.0.total_cmp(&b.1.0).then(a.1.1.cmp(&b.1.1)))
    else {
        return Err(CoreError::Cut {
            what: "cut line".to_owned(),
            problem: "the drawn segment does not pass over the mesh".to_owned(),
        });
    };
    let region: Vec<u32> = (0..fuzzy.len())
        .filter(|&i| regions.find_mut(i) == chosen)
        .map(|i| fuzzy[i])
        .collect();
    let mut in_region = vec![false; tris.len()];
    for &t in &region {
        in_region[t as usize] = true;
    }
    let in_region = |t: &u32| in_region[*t as usize];

    // Network nodes: 0 = source, 1 = sink, then triangles.
    let centroid = |t: u32| {
        tris[t as usize]
            .map(|v| positions[v as usize])
            .iter()
            .sum::<Vec3>()
            / 3.0
    };
    let tri_normal = |t: u32| {
        let [a, b, c] = tris[t as usize].map(|v| positions[v as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let mut node_of: HashMap<u32, usize> = HashMap::new();
    let mut node_tri: Vec<u32> = Vec::new();
    let mut add_node = |t: u32, node_of: &mut HashMap<u32, usize>| -> usize {
        *node_of.entry(t).or_insert_with(|| {
            node_tri.push(t);
            node_tri.len() + 1
        })
    };
    for &t in &region {
        add_node(t, &mut node_of);
    }
    // Dual edges with real weights, and border triangles with their side.
    let mut dual: Vec<(usize, usize, f64, [u32; 2])> = Vec::new();
    let mut border_side: BTreeMap<usize, bool> = BTreeMap::new();
    for key in keys {
        let ts = &edge_tris[&key];
        let (a, b) = ((key >> 32) as u32, key as u32);
        let mine: Vec<u32> = ts
            .iter()
            .copied()
            .filter(|t| in_region(t) || !fuzzy_flag[*t as usize])
            .collect();
        if !mine.iter().any(&in_region) {
            continue;
        }
        let length = f64::from(positions[a as usize].distance(positions[b as usize]));
        for i in 0..mine.len() {
            for j in i + 1..mine.len() {
                let (ti, tj) = (mine[i], mine[j]);
                if !in_region(&ti) && !in_region(&tj) {
                    continue;
                }
                let (ni, nj) = (tri_normal(ti), tri_normal(tj));
                let theta = f64::from(ni.cross(nj).length().atan2(ni.dot(nj)));
                let dihedral = if ni == Vec3::ZERO || nj == Vec3::ZERO {
                    std::f64::consts::PI
                } else {
                    std::f64::consts::PI - theta
                };
                let u = add_node(ti, &mut node_of);
                let w = add_node(tj, &mut node_of);
                for (t, node) in [(ti, u), (tj, w)] {
                    if !in_region(&t) {
                        border_side.insert(node, normal.dot(centroid(t) - point) >= 0.0);
                    }
                }
                dual.push((u, w, dihedral * length, [a, b]));
            }
        }
    }
    let has_pos = border_side.values().any(|&s| s);
    let has_neg = border_side.values().any(|&s| !s);
    if !has_pos || !has_neg {
        return Err(CoreError::Cut {
            what: "cut line".to_owned(),
            problem: format!(
                "the fuzzy region borders the mesh only on the {} side of the line; draw the line across a part so that the mesh continues on both sides",
                if has_pos { "positive" } else { "negative" }
            ),
        });
    }
    let max_w = dual
        .iter()
        .map(|d| d.2)
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let caps: Vec<u64> = dual
        .iter()
        .map(|d| ((d.2 / max_w * CAPACITY_SCALE).round() as u64).max(1))
        .collect();
    let infinite: u64 = caps.iter().sum::<u64>() + 1;
    let node_count = node_tri.len() + 2;
    let mut network: Graph<(), u64, Directed, u32> =
        Graph::with_capacity(node_count, 2 * dual.len() + border_side.len());
    let ids: Vec<NodeIndex<u32>> = (0..node_count).map(|_| network.add_node(())).collect();
    for (d, &c) in dual.iter().zip(&caps) {
        network.add_edge(ids[d.0], ids[d.1], c);
        network.add_edge(ids[d.1], ids[d.0], c);
    }
    for (&node, &side) in &border_side {
        if side {
            network.add_edge(ids[0], ids[node], infinite);
        } else {
            network.add_edge(ids[node], ids[1], infinite);
        }
    }
    let (_, flows) = dinics(&network, ids[0], ids[1]);
    // Source side: reachable from the source in the residual network.
    let mut source_side = vec![false; node_count];
    let mut stack = vec![ids[0]];
    source_side[0] = true;
    while let Some(u) = stack.pop() {
        let forward = network
            .edges_directed(u, Direction::Outgoing)
            .filter(|e| *e.weight() > flows[e.id().index()])
            .map(|e| e.target());
        let backward = network
            .edges_directed(u, Direction::Incoming)
            .filter(|e| flows[e.id().index()] > 0)
            .map(|e| e.source());
        let next: Vec<NodeIndex<u32>> = forward.chain(backward).collect();
        for w in next {
            if !source_side[w.index()] {
                source_side[w.index()] = true;
                stack.push(w);
            }
        }
    }
    if source_side[1] {
        return Err(CoreError::Cut {
            what: "cut line".to_owned(),
            problem: "the maximum flow did not saturate a cut (internal error)".to_owned(),
        });
    }
    // Boundary edges: dual edges whose ends lie on different sides.
    let mut boundary_edges: Vec<[u32; 2]> = dual
        .iter()
        .filter(|d| source_side[d.0] != source_side[d.1])
        .map(|d| d.3)
        .collect();
    boundary_edges.sort_unstable();
    boundary_edges.dedup();
    let mut on_cut = vec![false; n];
    for e in &boundary_edges {
        on_cut[e[0] as usize] = true;
        on_cut[e[1] as usize] = true;
    }
    // Seeds: off-cut corners of the network triangles on each side.
    let mut pos_seeds = Vec::new();
    let mut neg_seeds = Vec::new();
    for (k, &t) in node_tri.iter().enumerate() {
        let node = k + 2;
        for v in tris[t as usize] {
            if !on_cut[v as usize] {
                if source_side[node] {
                    pos_seeds.push(v);
                } else {
                    neg_seeds.push(v);
                }
            }
        }
    }
    let graph = VertexGraph::new(n, tris);
    let mut labels = vec![u32::MAX; n];
    for (v, flag) in on_cut.iter().enumerate() {
        if *flag {
            labels[v] = 2;
        }
    }
    graph.flood(pos_seeds.iter().copied(), &mut labels, 0, |_, _| false);
    if neg_seeds.iter().any(|&v| labels[v as usize] == 0) {
        return Err(CoreError::Cut {
            what: "cut line".to_owned(),
            problem: "the cut does not separate the mesh: the two sides are connected around it (a handle, or the line does not cross the whole part)".to_owned(),
        });
    }
    graph.flood(neg_seeds.iter().copied(), &mut labels, 1, |_, _| false);
    let pick =
        |l: u32| -> Vec<u32> { (0..n as u32).filter(|&v| labels[v as usize] == l).collect() };
    let mut region_sorted = region;
    region_sorted.sort_unstable();
    Ok(MeshCut {
        point,
        normal,
        fuzzy: region_sorted,
        boundary_edges,
        boundary: pick(2),
        positive: pick(0),
        negative: pick(1),
    })
}

/// The cutting plane of a screen line: `(point, unit normal)` through the viewing rays of
/// both ends; see [`MeshCut::normal`] for the orientation.
///
/// # Errors
/// [`CoreError::Degenerate`] when the two rays are (nearly) the same.
pub fn cut_plane(camera: &Camera, line_px: [Vec2; 2]) -> Result<(Vec3, Vec3)> {
    let a = camera.ray(line_px[0]);
    let b = camera.ray(line_px[1]);
    let reach = camera
        .eye
        .distance(camera.target)
        .max(camera.near * 10.0)
        .max(1e-3);
    let a0 = a.origin;
    let a1 = a.origin + a.direction * reach;
    let b1 = b.origin + b.direction * reach;
    let normal = (a1 - a0).cross(b1 - a0);
    let unit = normal.normalize_or_zero();
    if unit == Vec3::ZERO || !unit.is_finite() {
        return Err(CoreError::Degenerate {
            what: "cut line".to_owned(),
            problem: "its two ends give the same viewing ray (the camera is degenerate or the line too short)".to_owned(),
        });
    }
    Ok((a0, unit))
}

/// Combines cuts into a partition (Kho & Garland §4.2.1). With `base = None` the
/// automatic partition is overridden: the whole mesh is split by the cuts. With
/// `Some(base)` it is augmented: only `base.roi` is split, and `base.rigid` is kept.
///
/// The free (deformable) part is the connected piece, between the cuts' boundaries, that
/// holds the vertex nearest to `curve` (the reference curve, distance to its segments).
/// Every other piece becomes one rigid component. Vertices on a cut boundary join the free
/// part when they touch it, otherwise the first rigid piece they touch (a decision, so that
/// the free part keeps its whole boundary ring and rigid parts stay attached to it).
/// Vertices not referenced by any triangle stay static.
///
/// # Errors
/// [`CoreError::StrokeTooShort`] for an empty curve, [`CoreError::NotFinite`] for a bad curve
/// node, [`CoreError::Degenerate`] when `positions` does not match the topology,
/// [`CoreError::NoSuchVertex`] when `base` names a vertex that does not exist and
/// [`CoreError::Cut`] when the region to split is empty.
pub fn combine_cuts(
    positions: &[Vec3],
    topology: &Topology,
    base: Option<&Partition>,
    cuts: &[MeshCut],
    curve: &[Vec3],
) -> Result<Partition> {
    check_positions("combining cuts", positions, topology)?;
    let n = topology.vertex_count();
    if curve.is_empty() {
        return Err(CoreError::StrokeTooShort {
            what: "reference curve for combining cuts".to_owned(),
            found: 0,
            needed: 1,
        });
    }
    if let Some(i) = curve.iter().position(|p| !p.is_finite()) {
        return Err(CoreError::NotFinite {
            what: format!("reference curve node {i}"),
            value: format!("{}", curve[i]),
        });
    }
    let mut domain = vec![false; n];
    match base {
        Some(b) => {
            for &v in b.roi.iter().chain(b.rigid.iter().flatten()) {
                if v as usize >= n {
                    return Err(CoreError::NoSuchVertex {
                        what: "partition to refine".to_owned(),
                        index: v,
                        vertices: n,
                    });
                }
            }
            for &v in &b.roi {
                domain[v as usize] = true;
            }
        }
        None => {
            for t in &topology.triangles {
                for &v in t {
                    domain[v as usize] = true;
                }
            }
        }
    }
    let mut on_cut = vec![false; n];
    for c in cuts {
        for &v in &c.boundary {
            if (v as usize) < n {
                on_cut[v as usize] = true;
            }
        }
    }
    let distance_to_curve = |p: Vec3| -> f32 {
        if curve.len() == 1 {
            return p.distance(curve[0]);
        }
        curve
            .windows(2)
            .map(|w| {
                let d = w[1] - w[0];
                let l2 = d.length_squared();
                let s = if l2 > 0.0 {
                    ((p - w[0]).dot(d) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                p.distance(w[0] + d * s)
            })
            .fold(f32::INFINITY, f32::min)
    };
    let Some(seed) = (0..n)
        .filter(|&v| domain[v] && !on_cut[v])
        .map(|v| (v, distance_to_curve(positions[v])))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(v, _)| v as u32)
    else {
        return Err(CoreError::Cut {
            what: "combining cuts".to_owned(),
            problem: "no vertex is left to deform (the region is empty or lies entirely on cut boundaries)".to_owned(),
        });
    };
    let graph = VertexGraph::new(n, &topology.triangles);
    let mut labels = vec![u32::MAX; n];
    for v in 0..n {
        if !domain[v] || on_cut[v] {
            labels[v] = u32::MAX - 1;
        }
    }
    graph.flood([seed], &mut labels, 0, |_, _| false);
    let mut next = 1u32;
    for v in 0..n {
        if labels[v] == u32::MAX {
            graph.flood([v as u32], &mut labels, next, |_, _| false);
            next += 1;
        }
    }
    // Boundary vertices of the domain: free part first, else the first rigid piece.
    for v in 0..n {
        if domain[v] && on_cut[v] {
            let touching = graph
                .neighbours(v as u32)
                .iter()
                .map(|&w| labels[w as usize])
                .filter(|&l| l < u32::MAX - 1)
                .min();
            labels[v] = touching.unwrap_or(0);
        }
    }
    let mut roi = Vec::new();
    let mut pieces: Vec<Vec<u32>> = vec![Vec::new(); next as usize - 1];
    for v in 0..n {
        if !domain[v] {
            continue;
        }
        match labels[v] {
            0 => roi.push(v as u32),
            l if l < next => pieces[l as usize - 1].push(v as u32),
            _ => {}
        }
    }
    let mut rigid: Vec<Vec<u32>> = base.map(|b| b.rigid.clone()).unwrap_or_default();
    rigid.extend(pieces.into_iter().filter(|p| !p.is_empty()));
    Ok(Partition { roi, rigid })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sketch::camera::Projection;
    use crate::sketch::raycast::tests::cylinder;
    use crate::sketch::roi::tests::welded;

    fn front_camera(height: f32) -> Camera {
        Camera {
            eye: Vec3::new(0.0, 0.0, 10.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Orthographic { height },
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(400.0, 400.0),
        }
    }

    /// A grid over x ∈ [−1, 1] (step 0.02), y ∈ [−1, 1] (step 0.05) with a 90° ridge along
    /// the column x = `ridge`: z = −|x − ridge|.
    fn ridge(ridge_column: usize) -> (Vec<Vec3>, Topology, f32) {
        let (nx, ny) = (101usize, 41usize);
        let xs: Vec<f32> = (0..nx).map(|i| -1.0 + 0.02 * i as f32).collect();
        let r = xs[ridge_column];
        let mut p = Vec::new();
        for j in 0..ny {
            let y = -1.0 + 0.05 * j as f32;
            for &x in &xs {
                p.push(Vec3::new(x, y, -(x - r).abs()));
            }
        }
        let mut t = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let a = (j * nx + i) as u32;
                let (b, c, d) = (a + 1, a + 1 + nx as u32, a + nx as u32);
                t.push([a, b, c]);
                t.push([a, c, d]);
            }
        }
        let (pos, topo) = welded(p, &t);
        (pos, topo, r)
    }

    #[test]
    fn min_cut_follows_a_sharp_crease() {
        // 400 px for 4 world units: 100 px per unit. The ridge is at x = 0.04 (4 px right
        // of the screen centre); the line is slanted from x = −0.02 to x = +0.02.
        let (pos, topo, r) = ridge(52);
        assert!((r - 0.04).abs() < 1e-5);
        let cam = front_camera(4.0);
        let a = cam.project(Vec3::new(-0.02, -1.3, 0.0)).unwrap().0;
        let b = cam.project(Vec3::new(0.02, 1.3, 0.0)).unwrap().0;
        let cut = cut_with_line(&cam, [a, b], &pos, &topo).unwrap();
        assert!(!cut.boundary_edges.is_empty());
        for e in &cut.boundary_edges {
            for v in e {
                assert!((pos[*v as usize].x - r).abs() < 1e-5, "edge off the crease");
            }
        }
        // The boundary runs the full height: 41 vertices on the ridge column.
        assert_eq!(cut.boundary.len(), 41);
        // Line goes up the screen (pixel y decreasing): its right is +x.
        assert!(cut.positive.iter().all(|&v| pos[v as usize].x > r));
        assert!(cut.negative.iter().all(|&v| pos[v as usize].x < r));
        assert_eq!(
            cut.positive.len() + cut.negative.len() + cut.boundary.len(),
            pos.len()
        );
    }

    #[test]
    fn flat_sheet_is_cut_near_the_line_not_at_a_distant_column() {
        // Control for the crease test: without a ridge the cut stays a straight column
        // inside the fuzzy band (cost π per unit length), never at x = 0.04 + 0.04.
        let (mut pos, topo, _) = ridge(52);
        for p in &mut pos {
            p.z = 0.0;
        }
        let cam = front_camera(4.0);
        let a = cam.project(Vec3::new(-0.02, -1.3, 0.0)).unwrap().0;
        let b = cam.project(Vec3::new(0.02, 1.3, 0.0)).unwrap().0;
        let cut = cut_with_line(&cam, [a, b], &pos, &topo).unwrap();
        let xs: Vec<f32> = cut
            .boundary_edges
            .iter()
            .flatten()
            .map(|&v| pos[v as usize].x)
            .collect();
        let total: f32 = cut
            .boundary_edges
            .iter()
            .map(|e| pos[e[0] as usize].distance(pos[e[1] as usize]))
            .sum();
        // Shortest separating path on the grid: a straight column of length 2.
        assert!((total - 2.0).abs() < 1e-3, "{total}");
        assert!(xs.iter().all(|x| x.abs() <= 0.07));
    }

    #[test]
    fn cylinder_cut_splits_top_from_bottom_and_combines() {
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let mut cam = front_camera(6.0);
        cam.eye = Vec3::new(0.0, 2.0, 10.0);
        cam.target = Vec3::new(0.0, 2.0, 0.0);
        // Horizontal line at y = 1.1 across the cylinder, drawn left to right.
        let a = cam.project(Vec3::new(-1.0, 1.1, 0.0)).unwrap().0;
        let b = cam.project(Vec3::new(1.0, 1.1, 0.0)).unwrap().0;
        let cut = cut_with_line(&cam, [a, b], &pos, &topo).unwrap();
        // Right of a left-to-right line (pixel y down) is below: negative = above.
        assert!(cut.positive.iter().all(|&v| pos[v as usize].y < 1.2));
        assert!(cut.negative.iter().all(|&v| pos[v as usize].y > 1.0));
        assert!(
            cut.boundary
                .iter()
                .all(|&v| (pos[v as usize].y - 1.1).abs() < 0.2)
        );
        // The boundary is a ring around the cylinder.
        assert_eq!(cut.boundary.len(), 24);
        // Override: the curve is on the upper part, so the lower part becomes rigid.
        let curve = [Vec3::new(0.0, 2.0, 0.5), Vec3::new(0.0, 3.5, 0.5)];
        let part = combine_cuts(&pos, &topo, None, std::slice::from_ref(&cut), &curve).unwrap();
        assert_eq!(part.rigid.len(), 1);
        assert_eq!(part.rigid[0], cut.positive);
        let mut roi_expected: Vec<u32> =
            cut.negative.iter().chain(&cut.boundary).copied().collect();
        roi_expected.sort_unstable();
        assert_eq!(part.roi, roi_expected);
        // Augment: only the base region is split; the base rigid part is kept.
        let base = Partition {
            roi: (0..pos.len() as u32)
                .filter(|&v| pos[v as usize].y < 3.0)
                .collect(),
            rigid: vec![
                (0..pos.len() as u32)
                    .filter(|&v| pos[v as usize].y >= 3.0)
                    .collect(),
            ],
        };
        let curve = [Vec3::new(0.0, 2.0, 0.5), Vec3::new(0.0, 2.8, 0.5)];
        let part =
            combine_cuts(&pos, &topo, Some(&base), std::slice::from_ref(&cut), &curve).unwrap();
        assert_eq!(part.rigid.len(), 2);
        assert_eq!(part.rigid[0], base.rigid[0]);
        assert_eq!(part.rigid[1], cut.positive);
        assert!(part.roi.iter().all(|&v| {
            let y = pos[v as usize].y;
            // The boundary ring (at y = 1.0 or 1.25) joins the free part.
            y < 3.0 && y > 0.99
        }));
        assert!(part.roi.iter().any(|&v| pos[v as usize].y > 2.7));
    }

    #[test]
    fn perspective_cut_is_a_ring_around_the_cylinder() {
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let cam = Camera {
            eye: Vec3::new(0.0, 2.0, 6.0),
            target: Vec3::new(0.0, 2.0, 0.0),
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y: 0.9 },
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(400.0, 400.0),
        };
        // Right to left this time: the positive side (right of the direction) is above.
        let a = cam.project(Vec3::new(1.0, 2.6, 0.5)).unwrap().0;
        let b = cam.project(Vec3::new(-1.0, 2.6, 0.5)).unwrap().0;
        let cut = cut_with_line(&cam, [a, b], &pos, &topo).unwrap();
        assert_eq!(cut.boundary.len(), 24);
        let ring_y = pos[cut.boundary[0] as usize].y;
        assert!(cut.boundary.iter().all(|&v| pos[v as usize].y == ring_y));
        assert!((ring_y - 2.6).abs() < 0.3, "{ring_y}");
        assert!(cut.positive.iter().all(|&v| pos[v as usize].y > ring_y));
        assert!(cut.negative.iter().all(|&v| pos[v as usize].y < ring_y));
        // The plane contains the eye.
        assert!(cut.normal.dot(cam.eye - cut.point).abs() < 1e-3);
    }

    #[test]
    fn nearest_region_is_cut_when_the_plane_meets_two_parts() {
        // Two cylinders, one behind the other; the line crosses both on screen.
        let (mut p, mut t) = cylinder(24, 16, 0.5, 4.0);
        let (p2, t2) = cylinder(24, 16, 0.5, 4.0);
        let off = p.len() as u32;
        p.extend(p2.iter().map(|q| *q + Vec3::new(0.0, 0.0, -3.0)));
        t.extend(t2.iter().map(|tri| tri.map(|v| v + off)));
        let (pos, topo) = welded(p, &t);
        let mut cam = front_camera(6.0);
        cam.eye = Vec3::new(0.0, 2.0, 10.0);
        cam.target = Vec3::new(0.0, 2.0, 0.0);
        let a = cam.project(Vec3::new(-1.0, 1.1, 0.0)).unwrap().0;
        let b = cam.project(Vec3::new(1.0, 1.1, 0.0)).unwrap().0;
        let cut = cut_with_line(&cam, [a, b], &pos, &topo).unwrap();
        assert!(cut.boundary.iter().all(|&v| pos[v as usize].z > -1.0));
        // The back cylinder is on neither side.
        let back: Vec<u32> = (0..pos.len() as u32)
            .filter(|&v| pos[v as usize].z < -1.0)
            .collect();
        assert!(
            back.iter()
                .all(|v| !cut.positive.contains(v) && !cut.negative.contains(v))
        );
    }

    #[test]
    fn bad_lines_are_errors() {
        let (p, t) = cylinder(24, 16, 0.5, 4.0);
        let (pos, topo) = welded(p, &t);
        let cam = front_camera(6.0);
        let err = cut_with_line(&cam, [Vec2::ZERO, Vec2::new(0.5, 0.0)], &pos, &topo);
        assert!(matches!(err, Err(CoreError::OutOfRange { .. })));
        // A line that misses the mesh.
        let err = cut_with_line(
            &cam,
            [Vec2::new(0.0, 5.0), Vec2::new(10.0, 5.0)],
            &pos,
            &topo,
        );
        assert!(matches!(err, Err(CoreError::Cut { .. })), "{err:?}");
        // A torus cut through one side of its ring: the cut does not separate (handle).
        let (p, t) = crate::sketch::roi::tests::torus(32, 12, 2.0, 0.5);
        let (pos, topo) = welded(p, &t);
        let mut cam = front_camera(8.0);
        cam.eye = Vec3::new(0.0, 10.0, 0.0);
        cam.target = Vec3::ZERO;
        cam.up = -Vec3::Z;
        let a = cam.project(Vec3::new(1.0, 0.0, 2.6)).unwrap().0;
        let b = cam.project(Vec3::new(1.0, 0.0, 1.0)).unwrap().0;
        let err = cut_with_line(&cam, [a, b], &pos, &topo).unwrap_err();
        assert!(err.to_string().contains("does not separate"), "{err}");
    }
}
