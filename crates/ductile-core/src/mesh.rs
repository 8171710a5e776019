//! Indexed triangle meshes and their welded topology.
//!
//! File formats such as glTF store one copy of a vertex per distinct (position, normal, UV)
//! combination, so a vertex on a UV or normal seam appears several times. Deformers must move
//! those copies together or the surface tears. [`RestMesh`] therefore keeps the mesh *as
//! stored* (for output, in the original vertex order) next to its *welded* topology: one
//! topological vertex per distinct position. All deformation happens on welded vertices; the
//! result is scattered back to every stored copy.

use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

use glam::{Vec2, Vec3};

use crate::chunks::{PARALLEL_COPY_THRESHOLD, gather_at};
use crate::error::{CoreError, Result};
use crate::normals::{TriangleBlocks, smooth_normals};
use crate::refinement::RefinedMesh;

/// An indexed triangle mesh as stored in a file: positions, optional normals and UVs, and
/// triangle indices (three per triangle, counter-clockwise front faces).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Vertex positions in the mesh's own space.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, if the file had them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the file had them.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangle indices, three per triangle.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Checks that the mesh is usable: non-empty, indices in range and a multiple of three,
    /// attributes of the right length, all positions finite. `what` names the mesh in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        let n = self.positions.len();
        if n == 0 || self.indices.len() < 3 {
            return Err(CoreError::EmptyMesh {
                what: what.to_owned(),
                vertices: n,
                triangles: self.indices.len() / 3,
            });
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(CoreError::RaggedIndices {
                what: what.to_owned(),
                count: self.indices.len(),
            });
        }
        if let Some(i) = self.indices.iter().position(|&i| i as usize >= n) {
            return Err(CoreError::IndexOutOfRange {
                what: what.to_owned(),
                triangle: i / 3,
                index: self.indices[i],
                vertices: n,
            });
        }
        if let Some(normals) = &self.normals
            && normals.len() != n
        {
            return Err(CoreError::AttributeLength {
                what: what.to_owned(),
                attribute: "normals",
                found: normals.len(),
                expected: n,
            });
        }
        if let Some(uvs) = &self.uvs
            && uvs.len() != n
        {
            return Err(CoreError::AttributeLength {
                what: what.to_owned(),
                attribute: "uvs",
                found: uvs.len(),
                expected: n,
            });
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(CoreError::NotFinite {
                what: format!("{what}: position of vertex {i}"),
                value: format!("{}", self.positions[i]),
            });
        }
        // Texture coordinates pass through to exported files: a NaN there would reach them
        // silently. (Normals are recomputed from the positions.)
        if let Some(uvs) = &self.uvs
            && let Some(i) = uvs.iter().position(|p| !p.is_finite())
        {
            return Err(CoreError::NotFinite {
                what: format!("{what}: texture coordinate of vertex {i}"),
                value: format!("{}", uvs[i]),
            });
        }
        Ok(())
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Axis-aligned bounds `(min, max)` of the positions; `None` for an empty mesh.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds(&self.positions)
    }
}

/// Axis-aligned bounds `(min, max)` of a point set; `None` when it is empty.
#[must_use]
pub fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// The welded topology of a mesh: one vertex per distinct stored position.
///
/// Two stored vertices are welded when their positions are bit-for-bit equal (glTF and OBJ
/// exporters write seam copies with identical positions). Triangles that collapse after
/// welding (two equal corners) are kept out of [`Topology::triangles`].
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    /// For every stored vertex, its welded vertex.
    pub weld: Vec<u32>,
    /// For every welded vertex, the first stored vertex that maps to it.
    pub representative: Vec<u32>,
    /// Triangles over welded vertices.
    pub triangles: Vec<[u32; 3]>,
}

impl Topology {
    /// Welds a mesh by exact position equality.
    #[must_use]
    pub fn weld(mesh: &Mesh) -> Self {
        let mut map: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
        let mut weld = Vec::with_capacity(mesh.positions.len());
        let mut representative = Vec::new();
        for (i, p) in mesh.positions.iter().enumerate() {
            // +0.0 and -0.0 are the same position.
            let key = [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() });
            let next = representative.len() as u32;
            let w = *map.entry(key).or_insert_with(|| {
                representative.push(i as u32);
                next
            });
            weld.push(w);
        }
        let triangles = mesh
            .indices
            .chunks_exact(3)
            .map(|t| {
                [
                    weld[t[0] as usize],
                    weld[t[1] as usize],
                    weld[t[2] as usize],
                ]
            })
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        Self {
            weld,
            representative,
            triangles,
        }
    }

    /// Number of welded vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.representative.len()
    }

    /// Number of stored vertices.
    #[must_use]
    pub fn stored_count(&self) -> usize {
        self.weld.len()
    }

    /// Gathers welded positions from stored positions (the representative copy of each).
    #[must_use]
    pub fn gather(&self, stored: &[Vec3]) -> Vec<Vec3> {
        self.representative
            .iter()
            .map(|&i| stored[i as usize])
            .collect()
    }

    /// Scatters welded values back to every stored copy, in the original vertex order: each
    /// stored vertex gathers its welded value ([`gather_at`], in parallel chunks for large
    /// meshes).
    #[must_use]
    pub fn scatter<T: Copy + Send + Sync>(&self, welded: &[T]) -> Vec<T> {
        gather_at(welded, &self.weld)
    }

    /// Vertex-to-vertex adjacency (each welded vertex's neighbours over triangle edges),
    /// sorted and without duplicates.
    #[must_use]
    pub fn adjacency(&self) -> Vec<Vec<u32>> {
        let mut adj = vec![Vec::new(); self.vertex_count()];
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                adj[a as usize].push(b);
                adj[b as usize].push(a);
            }
        }
        for list in &mut adj {
            list.sort_unstable();
            list.dedup();
        }
        adj
    }
}

/// Vertices per block of the parallel smooth normals ([`RestMesh::smooth_normals`]) on a mesh
/// of `vertices` welded vertices, for a pool of `threads`: two blocks per thread (so that a
/// thread that falls behind hands one over), of at least 16,384 vertices. Bigger blocks list
/// fewer triangles twice: on the suite's million-vertex head at two threads, blocks of
/// 16,384 take 8.6–8.7 ms (median of 31), 267,471 (four blocks) 7.6, 534,942 (two) 7.1
/// (`docs/performance.md`, twentieth session).
fn normal_block(vertices: usize, threads: usize) -> usize {
    vertices.div_ceil(2 * threads.max(1)).max(16_384)
}

/// A validated mesh ready for deformation: the stored mesh, its welded topology and the
/// welded rest positions. Cheap to clone (shared).
#[derive(Debug, Clone)]
pub struct RestMesh {
    inner: Arc<RestMeshInner>,
}

#[derive(Debug)]
struct RestMeshInner {
    mesh: Mesh,
    topology: Topology,
    welded: Vec<Vec3>,
    /// The welded triangles grouped by vertex blocks, for smooth normals in parallel; made
    /// at the first output on more than one thread of a mesh of [`PARALLEL_COPY_THRESHOLD`]
    /// welded vertices or more (`None` inside: the vertex order has no locality, or the mesh
    /// is too big to list, and the normals are summed in order).
    normal_blocks: OnceLock<Option<TriangleBlocks>>,
}

impl RestMesh {
    /// Validates and welds `mesh`. `what` names the mesh in errors (usually its file name).
    pub fn new(mesh: Mesh, what: &str) -> Result<Self> {
        mesh.validate(what)?;
        let topology = Topology::weld(&mesh);
        if topology.triangles.is_empty() {
            return Err(CoreError::EmptyMesh {
                what: format!("{what} (after welding, every triangle is degenerate)"),
                vertices: topology.vertex_count(),
                triangles: 0,
            });
        }
        let welded = topology.gather(&mesh.positions);
        Ok(Self {
            inner: Arc::new(RestMeshInner {
                mesh,
                topology,
                welded,
                normal_blocks: OnceLock::new(),
            }),
        })
    }

    /// The mesh as stored.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.inner.mesh
    }

    /// The welded topology.
    #[must_use]
    pub fn topology(&self) -> &Topology {
        &self.inner.topology
    }

    /// Welded rest positions (one per topological vertex).
    #[must_use]
    pub fn welded_positions(&self) -> &[Vec3] {
        &self.inner.welded
    }

    /// Builds the stored-order output for welded `positions`: positions scattered to every
    /// copy and smooth normals recomputed (see [`smooth_normals`]).
    #[must_use]
    pub fn output(&self, welded_positions: &[Vec3]) -> Deformed {
        let topo = self.topology();
        let normals = self.smooth_normals(welded_positions);
        Deformed {
            positions: topo.scatter(welded_positions),
            normals: topo.scatter(&normals),
            refined: None,
        }
    }

    /// [`smooth_normals`] of welded `positions` over the welded triangles: on a mesh of
    /// [`PARALLEL_COPY_THRESHOLD`] welded vertices or more and more than one thread, summed a
    /// block of vertices at a time in parallel ([`TriangleBlocks`], two blocks per thread of
    /// the pool that first asks, made once per mesh), the same bits on any number of threads.
    /// On one thread the serial loop is the faster (the blocks list a few triangles twice and
    /// add a pass of zeros: 14–16 ms against 12.5 on the suite's million-vertex head, 7.6 on
    /// two threads).
    ///
    /// # Panics
    /// When a triangle's corner is past the end of `positions`.
    #[must_use]
    pub fn smooth_normals(&self, positions: &[Vec3]) -> Vec<Vec3> {
        let topo = self.topology();
        let n = topo.vertex_count();
        let parallel = n >= PARALLEL_COPY_THRESHOLD
            && positions.len() == n
            && rayon::current_num_threads() > 1;
        let blocks = parallel
            .then(|| {
                self.inner
                    .normal_blocks
                    .get_or_init(|| {
                        let block = normal_block(n, rayon::current_num_threads());
                        TriangleBlocks::new(n, &topo.triangles, block)
                    })
                    .as_ref()
            })
            .flatten();
        match blocks {
            Some(b) => b.smooth_normals(positions),
            None => smooth_normals(positions, &topo.triangles),
        }
    }

    /// Builds the stored-order output of a refined surface: `welded_positions` covers the
    /// refined welded vertices; positions and recomputed normals are scattered to every
    /// stored vertex of `refined` (the rest mesh's first, then the new ones).
    #[must_use]
    pub fn output_refined(&self, welded_positions: &[Vec3], refined: RefinedMesh) -> Deformed {
        let topo = &refined.topology;
        let normals = smooth_normals(welded_positions, &topo.triangles);
        Deformed {
            positions: topo.scatter(welded_positions),
            normals: topo.scatter(&normals),
            refined: Some(Box::new(refined)),
        }
    }
}

/// Deformed vertex data in the stored vertex order of the rest mesh (same length, same
/// indices and UVs apply) — unless a layer refined the mesh: then `refined` holds the new
/// surface, and `positions` / `normals` cover its stored vertices (the rest mesh's first,
/// in their order, then the new ones; see [`crate::refinement`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Deformed {
    /// Deformed positions.
    pub positions: Vec<Vec3>,
    /// Recomputed smooth unit normals.
    pub normals: Vec<Vec3>,
    /// The refined surface (new triangle list, UVs and stored normals of every stored
    /// vertex, parent edges of the new ones); `None` when the topology is the rest mesh's.
    pub refined: Option<Box<RefinedMesh>>,
}

impl Deformed {
    /// The index buffer to draw or export the output with: the rest mesh's, or the refined
    /// one.
    #[must_use]
    pub fn indices(&self, rest: &RestMesh) -> Vec<u32> {
        match &self.refined {
            Some(r) => r.indices(),
            None => rest.mesh().indices.clone(),
        }
    }

    /// The UVs of every output vertex (the rest mesh's, or interpolated for refined ones).
    #[must_use]
    pub fn uvs<'a>(&'a self, rest: &'a RestMesh) -> Option<&'a [Vec2]> {
        match &self.refined {
            Some(r) => r.uvs.as_deref(),
            None => rest.mesh().uvs.as_deref(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chunks::PARALLEL_COPY_THRESHOLD;

    /// Two triangles forming a quad, with the shared edge stored twice (a UV seam).
    fn seam_quad() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::X, // copy of 1
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::Y, // copy of 2
            ],
            normals: None,
            uvs: None,
            indices: vec![0, 1, 2, 3, 4, 5],
        }
    }

    #[test]
    fn weld_merges_seam_copies_and_keeps_order() {
        let topo = Topology::weld(&seam_quad());
        assert_eq!(topo.vertex_count(), 4);
        assert_eq!(topo.weld, vec![0, 1, 2, 1, 3, 2]);
        assert_eq!(topo.triangles, vec![[0, 1, 2], [1, 3, 2]]);
        let stored = topo.scatter(&[10, 11, 12, 13]);
        assert_eq!(stored, vec![10, 11, 12, 11, 13, 12]);
    }

    #[test]
    fn scatter_in_parallel_chunks_gives_every_stored_copy_its_value() {
        let welded: Vec<u32> = (0..50_000).map(|i| i * 3 + 1).collect();
        let n = PARALLEL_COPY_THRESHOLD + 4_097;
        let topo = Topology {
            weld: (0..n).map(|s| (s * 7_919 % 50_000) as u32).collect(),
            representative: Vec::new(),
            triangles: Vec::new(),
        };
        let stored = topo.scatter(&welded);
        assert_eq!(stored.len(), n);
        for (s, v) in stored.iter().enumerate() {
            assert_eq!(*v, welded[s * 7_919 % 50_000], "stored vertex {s}");
        }
    }

    #[test]
    fn validation_names_the_problem() {
        let mut m = seam_quad();
        m.indices.push(9);
        assert!(matches!(
            m.validate("q"),
            Err(CoreError::RaggedIndices { .. })
        ));
        m.indices.extend([1, 2]);
        assert!(matches!(
            m.validate("q"),
            Err(CoreError::IndexOutOfRange {
                index: 9,
                triangle: 2,
                ..
            })
        ));
        let empty = Mesh::default();
        assert!(matches!(
            empty.validate("e"),
            Err(CoreError::EmptyMesh { .. })
        ));
        let mut nan = seam_quad();
        nan.positions[2].x = f32::NAN;
        let err = nan.validate("n").unwrap_err().to_string();
        assert!(err.contains("vertex 2"), "{err}");
    }

    #[test]
    fn output_scatters_and_normals_face_plus_z() {
        let rest = RestMesh::new(seam_quad(), "q").unwrap();
        let out = rest.output(rest.welded_positions());
        assert_eq!(out.positions, rest.mesh().positions);
        for n in out.normals {
            assert!((n - Vec3::Z).length() < 1e-6);
        }
    }

    /// At most two blocks per thread, none below 16,384 vertices.
    #[test]
    fn normal_blocks_are_two_per_thread() {
        assert_eq!(normal_block(1_069_884, 2), 267_471);
        assert_eq!(normal_block(1_069_884, 16), 33_434);
        assert_eq!(normal_block(1_069_884, 64), 16_384);
        assert_eq!(normal_block(200_000, 0), 100_000);
        for (n, t) in [(131_072, 2), (1_000_001, 3), (999_999, 8)] {
            let b = normal_block(n, t);
            assert!(
                n.div_ceil(b) <= 2 * t && n.div_ceil(b) * b >= n,
                "{n} on {t}"
            );
        }
    }

    #[test]
    fn normals_of_a_big_mesh_on_two_threads_are_the_serial_bits() {
        // A wavy 400 × 400 grid (160,000 vertices, above the parallel threshold).
        let side = 400_u32;
        let positions = (0..side * side)
            .map(|k| {
                let (x, y) = ((k % side) as f32 * 0.01, (k / side) as f32 * 0.01);
                Vec3::new(x, y, (3.0 * x).sin() * (2.0 * y).cos() * 0.2)
            })
            .collect();
        let mut indices = Vec::new();
        for j in 0..side - 1 {
            for i in 0..side - 1 {
                let k = j * side + i;
                indices.extend([k, k + 1, k + side, k + 1, k + side + 1, k + side]);
            }
        }
        let mesh = Mesh {
            positions,
            indices,
            ..Mesh::default()
        };
        let rest = RestMesh::new(mesh, "grid").unwrap();
        let mut moved = rest.welded_positions().to_vec();
        for (k, p) in moved.iter_mut().enumerate() {
            p.z += (k as f32 * 0.37).sin() * 0.01;
        }
        let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
            v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
        };
        let serial = smooth_normals(&moved, &rest.topology().triangles);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let parallel = pool.install(|| rest.smooth_normals(&moved));
        // The blocks were made and used (not the serial loop).
        assert!(rest.inner.normal_blocks.get().is_some_and(Option::is_some));
        assert_eq!(bits(&parallel), bits(&serial));
        let out = pool.install(|| rest.output(&moved));
        assert_eq!(bits(&out.normals), bits(&rest.topology().scatter(&serial)));
    }
}
