//! Procedural meshes: a grid of vertices laid on a parametric surface, and midpoint
//! subdivision of a stored mesh, for tests, benchmarks and demos.

use std::collections::HashMap;

use glam::Vec3;

use crate::mesh::Mesh;

/// A `rows × columns` grid mesh: vertex `(r, c)` is stored at index `r · columns + c` at
/// `position(r, c)`. Each quad `(r, c)–(r + 1, c + 1)` becomes the triangles `[a, b, d]` and
/// `[a, d, c']` with `a = (r, c)`, `b = (r, c + 1)`, `c' = (r + 1, c)`, `d = (r + 1, c + 1)`
/// (counter-clockwise when rows grow along +v and columns along +u). With `wrap_columns`,
/// column `columns − 1` joins column 0 (a tube or a sphere's rings).
///
/// Returns a mesh without normals or UVs; an empty index list when `rows < 2` or
/// `columns < 2`.
#[must_use]
pub fn grid(
    rows: usize,
    columns: usize,
    wrap_columns: bool,
    mut position: impl FnMut(usize, usize) -> Vec3,
) -> Mesh {
    let mut positions = Vec::with_capacity(rows * columns);
    for r in 0..rows {
        for c in 0..columns {
            positions.push(position(r, c));
        }
    }
    let mut indices = Vec::new();
    if rows >= 2 && columns >= 2 {
        let quads_per_row = if wrap_columns { columns } else { columns - 1 };
        let at = |r: usize, c: usize| (r * columns + c % columns) as u32;
        for r in 0..rows - 1 {
            for c in 0..quads_per_row {
                let (a, b, c2, d) = (at(r, c), at(r, c + 1), at(r + 1, c), at(r + 1, c + 1));
                indices.extend([a, b, d, a, d, c2]);
            }
        }
    }
    Mesh {
        positions,
        normals: None,
        uvs: None,
        indices,
    }
}

/// Midpoint subdivision, `levels` times: every triangle `(a, b, c)` becomes four,
/// `(a, ab, ca)`, `(ab, b, bc)`, `(ca, bc, c)` and `(ab, bc, ca)` (counter-clockwise like
/// the parent), with one new stored vertex per stored edge at its midpoint
/// `(p_a + p_b) · 0.5`, UV `(uv_a + uv_b) · 0.5` and normal `normalize(n_a + n_b)` (`n_a` when
/// the sum is zero). Stored vertices keep their indices; the new ones follow, in order of
/// first use.
///
/// The midpoint of two seam copies' edge is computed from the same position bits in either
/// order (addition is commutative), so welding still joins the new copies. Each level
/// multiplies the triangle count by 4; a closed mesh's vertex count grows about as fast.
/// Indices must be in range (see [`Mesh::validate`]); triangles with an index out of range
/// are dropped.
#[must_use]
pub fn subdivided(mesh: &Mesh, levels: u32) -> Mesh {
    let mut out = mesh.clone();
    for _ in 0..levels {
        out = subdivide_once(&out);
    }
    out
}

/// Uniform subdivision of every triangle into `n²`: every stored edge is split into `n`
/// equal segments and every triangle `(a, b, c)` into the `n²` triangles of its barycentric
/// grid — grid point `(i, j)` (`i` steps from `a` towards `b`, `j` towards `c`, `i + j ≤ n`)
/// sits at `(p_a · (n − i − j) + p_b · i + p_c · j) / n`, and the triangles
/// `((i, j), (i + 1, j), (i, j + 1))` and `((i + 1, j), (i + 1, j + 1), (i, j + 1))` keep the
/// parent's orientation. UVs are interpolated the same way; normals are the normalised
/// interpolation (the first corner's normal when it is zero).
///
/// Stored vertices keep their indices; then come the `n − 1` points of each stored edge (in
/// order of first use) and the interior points of each triangle. A point on an edge `(u, v)`
/// is computed from the two end positions taken in a canonical order (by their bits, `±0`
/// alike, as [`crate::mesh::Topology::weld`] compares them), `(p_lo · (n − s) + p_hi · s) / n`
/// with `s` steps from `lo`: the seam copies of an edge get bit-identical points, so welding
/// still joins them. A closed mesh with `V` vertices, `E` edges and `F` triangles becomes one
/// with `V + (n − 1)·E + (n − 1)(n − 2)/2 · F` vertices and `n²·F` triangles.
/// `subdivided_n(mesh, 2)` has the vertex and triangle counts of `subdivided(mesh, 1)`;
/// `n = 0` or `1` returns a copy. Triangles with an index out of range are dropped.
#[must_use]
pub fn subdivided_n(mesh: &Mesh, n: u32) -> Mesh {
    if n <= 1 {
        return mesh.clone();
    }
    let count = mesh.positions.len();
    let nf = n as f32;
    let mut out = Mesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        uvs: mesh.uvs.clone(),
        indices: Vec::with_capacity(mesh.indices.len() * (n * n) as usize),
    };
    // One weighted point: `Σ p_k · w_k / n` over the (index, weight) pairs, in the order
    // given; normals and UVs interpolated over the same pairs.
    let push = |out: &mut Mesh, corners: &[(usize, f32)]| -> u32 {
        let index = out.positions.len() as u32;
        let mix3 = |v: &[Vec3]| {
            corners
                .iter()
                .fold(Vec3::ZERO, |acc, &(i, w)| acc + v[i] * w)
        };
        out.positions.push(mix3(&mesh.positions) / nf);
        if let (Some(dst), Some(src)) = (&mut out.normals, &mesh.normals) {
            dst.push(mix3(src).try_normalize().unwrap_or(src[corners[0].0]));
        }
        if let (Some(dst), Some(src)) = (&mut out.uvs, &mesh.uvs) {
            let uv = corners
                .iter()
                .fold(glam::Vec2::ZERO, |acc, &(i, w)| acc + src[i] * w);
            dst.push(uv / nf);
        }
        index
    };
    let key = |i: usize| {
        let p = mesh.positions[i];
        [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() })
    };
    // Stored edge (min, max) → index of its first new point (the one next to `min`).
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.indices.len());
    let mut edge_point = |out: &mut Mesh, u: u32, v: u32, s: u32| -> u32 {
        let (m, big) = (u.min(v), u.max(v));
        let base = *edges.entry((m, big)).or_insert_with(|| {
            let (m, big) = (m as usize, big as usize);
            let (lo, hi, flip) = if key(m) <= key(big) {
                (m, big, false)
            } else {
                (big, m, true)
            };
            let first = out.positions.len() as u32;
            for k in 1..n {
                let s_lo = if flip { n - k } else { k };
                push(out, &[(lo, (n - s_lo) as f32), (hi, s_lo as f32)]);
            }
            first
        });
        // Steps from `m`.
        let k = if u == m { s } else { n - s };
        base + k - 1
    };
    let mut grid_index = vec![0_u32; ((n + 1) * (n + 2) / 2) as usize];
    let at = |i: u32, j: u32| (j * (n + 1) - j * j.saturating_sub(1) / 2 + i) as usize;
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]];
        if [a, b, c].iter().any(|&i| i as usize >= count) {
            continue;
        }
        for j in 0..=n {
            for i in 0..=n - j {
                let index = match (i, j) {
                    (0, 0) => a,
                    (i, 0) if i == n => b,
                    (0, j) if j == n => c,
                    (i, 0) => edge_point(&mut out, a, b, i),
                    (i, j) if i + j == n => edge_point(&mut out, b, c, j),
                    (0, j) => edge_point(&mut out, a, c, j),
                    (i, j) => push(
                        &mut out,
                        &[
                            (a as usize, (n - i - j) as f32),
                            (b as usize, i as f32),
                            (c as usize, j as f32),
                        ],
                    ),
                };
                grid_index[at(i, j)] = index;
            }
        }
        for j in 0..n {
            for i in 0..n - j {
                let (p, q, r) = (
                    grid_index[at(i, j)],
                    grid_index[at(i + 1, j)],
                    grid_index[at(i, j + 1)],
                );
                out.indices.extend([p, q, r]);
                if i + j + 2 <= n {
                    let d = grid_index[at(i + 1, j + 1)];
                    out.indices.extend([q, d, r]);
                }
            }
        }
    }
    out
}

/// One level of [`subdivided`].
fn subdivide_once(mesh: &Mesh) -> Mesh {
    let n = mesh.positions.len();
    let mut out = Mesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        uvs: mesh.uvs.clone(),
        indices: Vec::with_capacity(mesh.indices.len() * 4),
    };
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.indices.len());
    let mut midpoint = |out: &mut Mesh, a: u32, b: u32| -> u32 {
        let key = (a.min(b), a.max(b));
        *midpoints.entry(key).or_insert_with(|| {
            let (i, j) = (a as usize, b as usize);
            let index = out.positions.len() as u32;
            out.positions
                .push((mesh.positions[i] + mesh.positions[j]) * 0.5);
            if let (Some(dst), Some(src)) = (&mut out.normals, &mesh.normals) {
                let (na, nb) = (src[i], src[j]);
                dst.push((na + nb).try_normalize().unwrap_or(na));
            }
            if let (Some(dst), Some(src)) = (&mut out.uvs, &mesh.uvs) {
                dst.push((src[i] + src[j]) * 0.5);
            }
            index
        })
    };
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]];
        if [a, b, c].iter().any(|&i| i as usize >= n) {
            continue;
        }
        let ab = midpoint(&mut out, a, b);
        let bc = midpoint(&mut out, b, c);
        let ca = midpoint(&mut out, c, a);
        out.indices
            .extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn open_and_wrapped_grids() {
        let open = grid(3, 4, false, |r, c| Vec3::new(c as f32, r as f32, 0.0));
        assert_eq!(open.positions.len(), 12);
        assert_eq!(open.triangle_count(), 2 * 2 * 3);
        assert_eq!(&open.indices[..6], &[0, 1, 5, 0, 5, 4]);
        let tube = grid(2, 4, true, |r, c| Vec3::new(c as f32, r as f32, 0.0));
        assert_eq!(tube.triangle_count(), 2 * 4);
        assert_eq!(&tube.indices[18..], &[3, 0, 4, 3, 4, 7]);
        assert!(grid(1, 4, false, |_, _| Vec3::ZERO).indices.is_empty());
    }

    /// Two triangles forming a quad, the shared edge stored twice (a UV seam).
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
            normals: Some(vec![Vec3::Z, Vec3::Z, Vec3::Z, Vec3::X, Vec3::X, Vec3::X]),
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
                Vec2::new(0.5, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 0.5),
            ]),
            indices: vec![0, 1, 2, 3, 4, 5],
        }
    }

    #[test]
    fn one_level_splits_each_triangle_in_four_at_edge_midpoints() {
        let m = seam_quad();
        let s = subdivided(&m, 1);
        // 6 stored vertices + 3 new per triangle (no stored edge is shared).
        assert_eq!(s.positions.len(), 12);
        assert_eq!(s.triangle_count(), 8);
        assert!(s.validate("s").is_ok());
        // First triangle (0, 1, 2): ab = 6 at (0.5, 0, 0), bc = 7 at (0.5, 0.5, 0),
        // ca = 8 at (0, 0.5, 0).
        assert_eq!(&s.indices[..12], &[0, 6, 8, 6, 1, 7, 8, 7, 2, 6, 7, 8]);
        assert_eq!(s.positions[6], Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(s.positions[7], Vec3::new(0.5, 0.5, 0.0));
        assert_eq!(s.positions[8], Vec3::new(0.0, 0.5, 0.0));
        let uvs = s.uvs.as_ref().unwrap();
        assert_eq!(uvs[7], Vec2::new(0.5, 0.5));
        // Second triangle's seam edge (5, 3) is vertex 11: UV (0.25, 0.25), normal X.
        assert_eq!(s.positions[11], Vec3::new(0.5, 0.5, 0.0));
        assert_eq!(uvs[11], Vec2::new(0.25, 0.25));
        assert_eq!(s.normals.as_ref().unwrap()[11], Vec3::X);
        // The two copies of the seam midpoint weld: 4 + 5 welded vertices.
        let topo = crate::mesh::Topology::weld(&s);
        assert_eq!(topo.vertex_count(), 9);
        assert_eq!(topo.weld[7], topo.weld[11]);
        assert_eq!(topo.triangles.len(), 8);
    }

    #[test]
    fn shared_edges_get_one_midpoint_and_counts_grow_by_four() {
        let g = grid(3, 3, false, |r, c| Vec3::new(c as f32, r as f32, 0.0));
        // 9 vertices, 16 edges, 8 triangles.
        let s = subdivided(&g, 1);
        assert_eq!(s.positions.len(), 9 + 16);
        assert_eq!(s.triangle_count(), 32);
        let s2 = subdivided(&g, 2);
        // A 5×5 grid subdivided once more: 25 + 56 edges.
        assert_eq!(s2.positions.len(), 25 + 56);
        assert_eq!(s2.triangle_count(), 128);
        assert_eq!(subdivided(&g, 0), g);
        // Every position of the twice-subdivided grid lies on the quarter lattice.
        for p in &s2.positions {
            assert_eq!((p.x * 4.0).fract(), 0.0);
            assert_eq!((p.y * 4.0).fract(), 0.0);
        }
    }

    /// An octahedron with vertex 0 stored twice (a seam: the copy, 6, is used by the last
    /// two triangles, written in another rotation so their edges are walked the other way).
    fn seam_octahedron() -> Mesh {
        let positions = vec![
            Vec3::X,
            Vec3::Y,
            -Vec3::X,
            -Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
        ];
        let indices = vec![
            0, 1, 4, 1, 2, 4, 2, 3, 4, 4, 3, 6, // upper half; the last starts at the top
            1, 0, 5, 2, 1, 5, 3, 2, 5, 5, 6, 3, // lower half
        ];
        Mesh {
            positions,
            normals: None,
            uvs: None,
            indices,
        }
    }

    #[test]
    fn n_split_counts_follow_euler() {
        let m = seam_octahedron();
        // Welded: V = 6, E = 12, F = 8 (closed, χ = 2); stored: 7 vertices, 14 stored edges
        // (the two edges at the seam copy are stored twice).
        for n in 2..=5_u32 {
            let s = subdivided_n(&m, n);
            assert!(s.validate("s").is_ok());
            assert_eq!(s.triangle_count(), 8 * (n * n) as usize);
            let interior = ((n - 1) * (n - 2) / 2) as usize;
            assert_eq!(s.positions.len(), 7 + 14 * (n as usize - 1) + 8 * interior);
            let topo = crate::mesh::Topology::weld(&s);
            let v = topo.vertex_count();
            assert_eq!(v, 6 + 12 * (n as usize - 1) + 8 * interior, "n = {n}");
            // Euler on the welded result: V − E + F = 2, with E = 3F / 2 on a closed mesh.
            let f = topo.triangles.len();
            assert_eq!(f, 8 * (n * n) as usize);
            assert_eq!(v as i64 - (3 * f / 2) as i64 + f as i64, 2);
            let adjacency = topo.adjacency();
            let edges: usize = adjacency.iter().map(Vec::len).sum::<usize>() / 2;
            assert_eq!(edges, 3 * f / 2);
        }
        assert_eq!(subdivided_n(&m, 1), m);
        // n = 2 has the counts of one midpoint level.
        let (a, b) = (subdivided_n(&m, 2), subdivided(&m, 1));
        assert_eq!(
            (a.positions.len(), a.triangle_count()),
            (b.positions.len(), b.triangle_count())
        );
    }

    #[test]
    fn n_split_points_lie_on_their_triangles_and_seams_weld() {
        let m = seam_octahedron();
        let s = subdivided_n(&m, 5);
        // Every face of the octahedron lies on |x| + |y| + |z| = 1.
        for p in &s.positions {
            assert!((p.abs().element_sum() - 1.0).abs() < 1e-6, "{p}");
        }
        // Each small triangle lies on its parent face (all coordinates' signs agree) and
        // keeps its orientation (outward normal).
        for t in s.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| s.positions[t[k] as usize]);
            let normal = (b - a).cross(c - a);
            assert!(normal.dot(a + b + c) > 0.0);
        }
        // The seam copy's edges got bit-identical points: the weld joins them, and every
        // welded position appears once.
        let topo = crate::mesh::Topology::weld(&s);
        let mut welded: Vec<[u32; 3]> = topo
            .gather(&s.positions)
            .iter()
            .map(|p| [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() }))
            .collect();
        welded.sort_unstable();
        welded.dedup();
        assert_eq!(welded.len(), topo.vertex_count());
        let stored_copies = s.positions.len() - topo.vertex_count();
        // Vertex 0 and its copy, plus the 4 points of each of the two stored-twice edges.
        assert_eq!(stored_copies, 1 + 2 * 4);
    }

    #[test]
    fn n_split_of_one_triangle_is_the_barycentric_lattice() {
        let n = 5_u32;
        let k = n as f32;
        let m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::new(k, 0.0, 0.0), Vec3::new(0.0, k, 0.0)],
            normals: Some(vec![Vec3::Z; 3]),
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y]),
            indices: vec![0, 1, 2],
        };
        let s = subdivided_n(&m, n);
        assert_eq!(s.positions.len(), 21);
        assert_eq!(s.triangle_count(), 25);
        let mut lattice: Vec<(i32, i32)> = s
            .positions
            .iter()
            .map(|p| {
                assert_eq!(p.z, 0.0);
                assert_eq!(p.x.fract(), 0.0);
                assert_eq!(p.y.fract(), 0.0);
                (p.x as i32, p.y as i32)
            })
            .collect();
        lattice.sort_unstable();
        let mut expected: Vec<(i32, i32)> = (0..=5)
            .flat_map(|i| (0..=5 - i).map(move |j| (i, j)))
            .collect();
        expected.sort_unstable();
        assert_eq!(lattice, expected);
        // UVs follow positions (u = x / 5, v = y / 5); normals stay +Z.
        for (p, uv) in s.positions.iter().zip(s.uvs.as_ref().unwrap()) {
            assert!((uv.x - p.x / k).abs() < 1e-6 && (uv.y - p.y / k).abs() < 1e-6);
        }
        assert!(s.normals.as_ref().unwrap().iter().all(|&v| v == Vec3::Z));
        // Every small triangle has area 1/2 and is counter-clockwise like the parent.
        for t in s.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|q| s.positions[t[q] as usize]);
            assert_eq!((b - a).cross(c - a), Vec3::new(0.0, 0.0, 1.0));
        }
    }
}
