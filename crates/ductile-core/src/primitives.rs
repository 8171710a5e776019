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
}
