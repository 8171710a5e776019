//! Layers that change the topology: edge splits.
//!
//! A refining layer (today: the sketch tool with adaptive refinement, Kho & Garland §5.5)
//! returns a [`LayerRefinement`]: an ordered list of edge splits. Split `k` creates welded
//! vertex `n + k` (`n` the welded vertex count the layer was bound on) at
//! `(1 − t)·a + t·b` on the edge `{a, b}` of the triangle list *as it is after the earlier
//! splits*, and cuts every triangle incident to that edge in two. The result is a pure
//! function of the triangle list and the split list, so the tool that decides the splits
//! and the stack that replays them on the stored mesh share [`SplitMesh`] and always agree.
//!
//! Stored vertices (seams): a new welded vertex gets one stored copy per distinct stored
//! edge `{i, j}` the split cuts (one copy where the edge is not a seam, one per side where
//! it is), with UVs and normals interpolated along that stored edge. The copies of one new
//! vertex share their position and are welded together, so the seam stays a seam.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use crate::mesh::{Mesh, Topology};

/// A point on an edge: `(1 − t)·a + t·b`, with `a`, `b` vertex indices and `t ∈ [0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgePoint {
    /// First end.
    pub a: u32,
    /// Second end.
    pub b: u32,
    /// Parameter from `a` (0) to `b` (1).
    pub t: f32,
}

impl EdgePoint {
    /// Interpolates a per-vertex value of the two ends.
    #[must_use]
    pub fn lerp<T>(&self, values: &[T]) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        values[self.a as usize] * (1.0 - self.t) + values[self.b as usize] * self.t
    }
}

/// What a refining layer outputs besides the deformed positions of the existing vertices.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LayerRefinement {
    /// The splits, in order; split `k` creates welded vertex `n + k`.
    pub splits: Vec<EdgePoint>,
    /// Deformed position of each new vertex (the tool's output, before the layer's weight
    /// and influence blend).
    pub deformed: Vec<Vec3>,
}

/// The output of a tool evaluated as a whole layer (see `Tool::deform_whole`).
#[derive(Debug, Clone, PartialEq)]
pub struct WholeDeform {
    /// Deformed position of every active vertex (same order as the active list).
    pub out: Vec<Vec3>,
    /// The refinement, when asked for and something was split.
    pub refinement: Option<LayerRefinement>,
}

/// Stored-level data carried along the splits.
#[derive(Debug, Clone)]
struct Stored {
    /// Stored corners of every welded triangle (same order as the welded triangles).
    triangles: Vec<[u32; 3]>,
    /// Welded vertex of every stored vertex.
    weld: Vec<u32>,
    /// First stored copy of every welded vertex.
    representative: Vec<u32>,
    uvs: Option<Vec<Vec2>>,
    normals: Option<Vec<Vec3>>,
    /// Parent stored edge of every stored vertex beyond the original ones.
    parents: Vec<EdgePoint>,
    original: usize,
}

/// A triangle list under successive edge splits.
#[derive(Debug, Clone)]
pub struct SplitMesh {
    triangles: Vec<[u32; 3]>,
    vertex_count: u32,
    edges: HashMap<(u32, u32), Vec<u32>>,
    stored: Option<Stored>,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

impl SplitMesh {
    /// Starts from welded triangles over `vertex_count` vertices.
    #[must_use]
    pub fn new(triangles: &[[u32; 3]], vertex_count: usize) -> Self {
        let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(triangles.len() * 2);
        for (ti, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                edges
                    .entry(key(t[k], t[(k + 1) % 3]))
                    .or_default()
                    .push(ti as u32);
            }
        }
        Self {
            triangles: triangles.to_vec(),
            vertex_count: vertex_count as u32,
            edges,
            stored: None,
        }
    }

    /// Starts from a refined (or original) stored surface, tracking stored copies too.
    #[must_use]
    pub fn with_stored(surface: &RefinedMesh) -> Self {
        let topo = &surface.topology;
        let mut m = Self::new(&topo.triangles, topo.vertex_count());
        m.stored = Some(Stored {
            triangles: surface.stored_triangles.clone(),
            weld: topo.weld.clone(),
            representative: topo.representative.clone(),
            uvs: surface.uvs.clone(),
            normals: surface.normals.clone(),
            parents: surface.parents.clone(),
            original: surface.original_stored,
        });
        m
    }

    /// Current welded triangles.
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Current welded vertex count.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.vertex_count as usize
    }

    /// True when `{a, b}` is an edge of the current triangles.
    #[must_use]
    pub fn has_edge(&self, a: u32, b: u32) -> bool {
        self.edges.contains_key(&key(a, b))
    }

    /// The current edges `{a, b}` (`a < b`), sorted.
    #[must_use]
    pub fn sorted_edges(&self) -> Vec<(u32, u32)> {
        let mut e: Vec<_> = self.edges.keys().copied().collect();
        e.sort_unstable();
        e
    }

    /// The third corners of the triangles on edge `{a, b}`.
    #[must_use]
    pub fn opposite(&self, a: u32, b: u32) -> Vec<u32> {
        self.edges
            .get(&key(a, b))
            .map(|ts| {
                ts.iter()
                    .map(|&ti| {
                        let t = self.triangles[ti as usize];
                        t.into_iter().find(|&c| c != a && c != b).unwrap_or(a)
                    })
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Splits the edge `{e.a, e.b}` at `e.t` and returns the new welded vertex. Does
    /// nothing but allocate the vertex when the edge does not exist.
    pub fn split(&mut self, e: EdgePoint) -> u32 {
        let m = self.vertex_count;
        self.vertex_count += 1;
        let tris = self.edges.remove(&key(e.a, e.b)).unwrap_or_default();
        let mut copies: Vec<((u32, u32), u32)> = Vec::new();
        if let Some(st) = &mut self.stored {
            st.representative.push(u32::MAX);
        }
        for ti in tris {
            let t = self.triangles[ti as usize];
            let Some(k) = (0..3).find(|&k| key(t[k], t[(k + 1) % 3]) == key(e.a, e.b)) else {
                continue;
            };
            let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let tj = self.triangles.len() as u32;
            self.triangles[ti as usize] = [x, m, z];
            self.triangles.push([m, y, z]);
            if let Some(list) = self.edges.get_mut(&key(y, z)) {
                for entry in list.iter_mut().filter(|v| **v == ti) {
                    *entry = tj;
                }
            }
            self.edges.entry(key(x, m)).or_default().push(ti);
            self.edges.entry(key(m, y)).or_default().push(tj);
            let mz = self.edges.entry(key(m, z)).or_default();
            mz.push(ti);
            mz.push(tj);
            if let Some(st) = &mut self.stored {
                let s = st.triangles[ti as usize];
                let (ix, iy, iz) = (s[k], s[(k + 1) % 3], s[(k + 2) % 3]);
                let sk = key(ix, iy);
                let im = if let Some(&(_, im)) = copies.iter().find(|(kk, _)| *kk == sk) {
                    im
                } else {
                    let im = st.weld.len() as u32;
                    // Parameter along the stored edge (ix → iy); x is a or b.
                    let t_xy = if x == e.a { e.t } else { 1.0 - e.t };
                    let p = EdgePoint {
                        a: ix,
                        b: iy,
                        t: t_xy,
                    };
                    if let Some(uvs) = &mut st.uvs {
                        let uv = p.lerp(uvs);
                        uvs.push(uv);
                    }
                    if let Some(normals) = &mut st.normals {
                        let n = p.lerp(normals).normalize_or_zero();
                        normals.push(n);
                    }
                    st.weld.push(m);
                    st.parents.push(p);
                    if st.representative[m as usize] == u32::MAX {
                        st.representative[m as usize] = im;
                    }
                    copies.push((sk, im));
                    im
                };
                st.triangles[ti as usize] = [ix, im, iz];
                st.triangles.push([im, iy, iz]);
            }
        }
        if let Some(st) = &mut self.stored
            && st.representative[m as usize] == u32::MAX
        {
            // The edge did not exist: give the vertex a stored copy anyway so that every
            // welded vertex has one.
            let ia = st.representative[e.a as usize];
            let ib = st.representative[e.b as usize];
            let p = EdgePoint {
                a: ia,
                b: ib,
                t: e.t,
            };
            if let Some(uvs) = &mut st.uvs {
                let uv = p.lerp(uvs);
                uvs.push(uv);
            }
            if let Some(normals) = &mut st.normals {
                let n = p.lerp(normals).normalize_or_zero();
                normals.push(n);
            }
            st.representative[m as usize] = st.weld.len() as u32;
            st.weld.push(m);
            st.parents.push(p);
        }
        m
    }

    /// The stored surface after the splits (`None` when built without stored data).
    #[must_use]
    pub fn into_refined(self) -> Option<RefinedMesh> {
        let st = self.stored?;
        Some(RefinedMesh {
            topology: Topology {
                weld: st.weld,
                representative: st.representative,
                triangles: self.triangles,
            },
            stored_triangles: st.triangles,
            uvs: st.uvs,
            normals: st.normals,
            parents: st.parents,
            original_stored: st.original,
        })
    }
}

/// The current surface of a stack whose layers refined the mesh: its welded topology and
/// its stored vertices (the rest mesh's stored vertices first, in their order, then one
/// stored vertex per new (welded vertex, stored parent edge) pair).
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedMesh {
    /// Welded topology of the refined surface: `weld` and `representative` cover the
    /// original and the new stored vertices.
    pub topology: Topology,
    /// Stored corners of every triangle of `topology.triangles` (same order).
    pub stored_triangles: Vec<[u32; 3]>,
    /// UVs of every stored vertex (interpolated along the parent edge for new ones).
    pub uvs: Option<Vec<Vec2>>,
    /// Stored normals of every stored vertex (interpolated and normalised for new ones).
    pub normals: Option<Vec<Vec3>>,
    /// Parent stored edge of each new stored vertex (stored vertex `original_stored + k`).
    pub parents: Vec<EdgePoint>,
    /// Number of stored vertices of the rest mesh.
    pub original_stored: usize,
}

impl RefinedMesh {
    /// The unrefined surface of a stored mesh and its welded topology: the triangles that
    /// survive welding (see [`Topology::weld`]), with their stored corners.
    #[must_use]
    pub fn unrefined(mesh: &Mesh, topology: &Topology) -> Self {
        let stored_triangles = mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .filter(|t| {
                let w = t.map(|i| topology.weld[i as usize]);
                w[0] != w[1] && w[1] != w[2] && w[0] != w[2]
            })
            .collect();
        Self {
            topology: topology.clone(),
            stored_triangles,
            uvs: mesh.uvs.clone(),
            normals: mesh.normals.clone(),
            parents: Vec::new(),
            original_stored: mesh.positions.len(),
        }
    }

    /// The stored index buffer (three per triangle).
    #[must_use]
    pub fn indices(&self) -> Vec<u32> {
        self.stored_triangles.iter().flatten().copied().collect()
    }

    /// Applies a layer's splits.
    #[must_use]
    pub fn split(&self, splits: &[EdgePoint]) -> Self {
        let mut m = SplitMesh::with_stored(self);
        for &e in splits {
            m.split(e);
        }
        m.into_refined().unwrap_or_else(|| self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quad (0,0) (1,0) (1,1) (0,1) as two triangles with the diagonal 1–3 stored twice
    /// (a UV seam): stored 0..4 for the first triangle's side, 4, 5 copies of 1 and 3.
    fn seam_quad() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::X,
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::Y,
            ],
            normals: None,
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
                Vec2::new(5.0, 0.0),
                Vec2::new(6.0, 1.0),
                Vec2::new(4.0, 1.0),
            ]),
            indices: vec![0, 1, 2, 3, 4, 5],
        }
    }

    #[test]
    fn splitting_a_seam_edge_makes_two_stored_copies() {
        let mesh = seam_quad();
        let topo = Topology::weld(&mesh);
        let base = RefinedMesh::unrefined(&mesh, &topo);
        // Welded: 0, 1 (X), 2 (Y), 3 (1,1). Split the diagonal {1, 2} at t = 0.25 from 1.
        let r = base.split(&[EdgePoint {
            a: 1,
            b: 2,
            t: 0.25,
        }]);
        assert_eq!(r.topology.vertex_count(), 5);
        assert_eq!(r.topology.triangles.len(), 4);
        // Two stored copies of welded vertex 4, with UVs along their own stored edges.
        assert_eq!(r.topology.weld.len(), 8);
        assert_eq!(&r.topology.weld[6..], &[4, 4]);
        let uvs = r.uvs.as_ref().unwrap();
        assert!((uvs[6] - Vec2::new(0.75, 0.25)).length() < 1e-6, "{uvs:?}");
        assert!((uvs[7] - Vec2::new(4.75, 0.25)).length() < 1e-6, "{uvs:?}");
        // Orientation is kept: every triangle still faces +z.
        let p = |w: u32| match w {
            4 => Vec3::new(0.75, 0.25, 0.0),
            w => mesh.positions[topo.representative[w as usize] as usize],
        };
        for t in &r.topology.triangles {
            let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            assert!(n.z > 0.0, "{t:?}");
        }
        // Stored triangles weld to the welded ones.
        for (s, w) in r.stored_triangles.iter().zip(&r.topology.triangles) {
            assert_eq!(s.map(|i| r.topology.weld[i as usize]), *w);
        }
    }

    #[test]
    fn interior_edge_split_makes_one_copy_and_replays_identically() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            normals: None,
            uvs: None,
            indices: vec![0, 1, 2, 1, 3, 2],
        };
        let topo = Topology::weld(&mesh);
        let splits = [
            EdgePoint { a: 1, b: 2, t: 0.5 },
            EdgePoint { a: 0, b: 4, t: 0.5 },
        ];
        let r = RefinedMesh::unrefined(&mesh, &topo).split(&splits);
        assert_eq!(r.topology.weld.len(), 6);
        assert_eq!(r.topology.triangles.len(), 6);
        let mut welded_only = SplitMesh::new(&topo.triangles, 4);
        for &e in &splits {
            welded_only.split(e);
        }
        assert_eq!(welded_only.triangles(), &r.topology.triangles[..]);
    }
}
