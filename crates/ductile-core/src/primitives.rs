//! Procedural meshes: a grid of vertices laid on a parametric surface, for tests, benchmarks
//! and demos.

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
