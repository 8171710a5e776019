//! Smooth vertex normals: the serial sum over the triangles, and the same sums a block of
//! vertices at a time in parallel ([`TriangleBlocks`]).

use glam::Vec3;
use rayon::prelude::*;

use crate::chunks::zeroed;

/// Area-weighted smooth vertex normals: each vertex normal is the normalised sum of the
/// un-normalised face normals `(b − a) × (c − a)` of its triangles, so every face contributes
/// in proportion to twice its area.
///
/// Area weighting is used (rather than angle weighting) because it needs no trigonometry, is
/// exact for the planar case, and on the dense scanned meshes Ductile deforms the two differ
/// by far less than what a viewer can see. A vertex with no non-degenerate triangle gets
/// `Vec3::ZERO`'s fallback `Vec3::Z`.
#[must_use]
pub fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let n = face_normal([a, b, c], positions);
        acc[a as usize] += n;
        acc[b as usize] += n;
        acc[c as usize] += n;
    }
    for n in &mut acc {
        *n = n.try_normalize().unwrap_or(Vec3::Z);
    }
    acc
}

/// The un-normalised face normal `(b − a) × (c − a)` of triangle `[a, b, c]` (twice its
/// area along its unit normal), as [`smooth_normals`] sums it.
#[must_use]
#[inline]
pub fn face_normal([a, b, c]: [u32; 3], positions: &[Vec3]) -> Vec3 {
    let (pa, pb, pc) = (
        positions[a as usize],
        positions[b as usize],
        positions[c as usize],
    );
    (pb - pa).cross(pc - pa)
}

/// The triangles of a mesh grouped by the blocks of consecutive vertices they touch, so
/// that [`smooth_normals`] can be summed a block at a time in parallel with the very same
/// additions: each block sums, for its own vertices, the face normals of its triangles in
/// ascending triangle order, as the serial loop does. A triangle whose corners lie in
/// several blocks is listed (and its face normal computed) in each of them.
///
/// Meshes keep the vertices of a face near each other in memory (subdivision and most
/// exporters order them face by face), so few triangles are listed twice; a vertex order
/// without that locality is refused ([`TriangleBlocks::new`] returns `None`), since every
/// block would then go over most triangles.
#[derive(Debug, Clone)]
pub struct TriangleBlocks {
    /// Vertices per block.
    block: usize,
    /// The number of vertices the blocks cover.
    vertices: usize,
    /// Where each block's triangles start in `triangles` (one more entry than blocks).
    starts: Vec<u32>,
    /// Per block, the triangles with a corner in it, in ascending order (their corners,
    /// copied: read in order, where indices into the mesh's triangles would be read all
    /// over it, a cache line per triangle).
    triangles: Vec<[u32; 3]>,
}

impl TriangleBlocks {
    /// The groups of `triangles` over `vertices` vertices in blocks of `block` (at least 1);
    /// `None` when a corner is out of range, when one and a half times the triangle count
    /// does not fit in `u32`, or when the groups would list more than one and a half times
    /// as many triangles as there are (a vertex order without locality).
    #[must_use]
    pub fn new(vertices: usize, triangles: &[[u32; 3]], block: usize) -> Option<Self> {
        let block = block.max(1);
        let count = vertices.div_ceil(block);
        let limit = triangles.len() + triangles.len() / 2;
        if u32::try_from(limit).is_err() {
            return None;
        }
        // The distinct blocks of a triangle's corners, in corner order.
        let blocks_of = |t: &[u32; 3]| -> Option<[Option<usize>; 3]> {
            let [a, b, c] = t.map(|v| v as usize);
            if a.max(b).max(c) >= vertices {
                return None;
            }
            let [a, b, c] = [a / block, b / block, c / block];
            Some([
                Some(a),
                (b != a).then_some(b),
                (c != a && c != b).then_some(c),
            ])
        };
        let mut starts = vec![0_u32; count + 1];
        let mut total = 0_usize;
        for t in triangles {
            for k in blocks_of(t)?.into_iter().flatten() {
                starts[k + 1] += 1;
                total += 1;
            }
            if total > limit {
                return None;
            }
        }
        for k in 0..count {
            starts[k + 1] += starts[k];
        }
        let mut next = starts.clone();
        let mut listed = vec![[0_u32; 3]; total];
        for t in triangles {
            for k in blocks_of(t)?.into_iter().flatten() {
                listed[next[k] as usize] = *t;
                next[k] += 1;
            }
        }
        Some(Self {
            block,
            vertices,
            starts,
            triangles: listed,
        })
    }

    /// [`smooth_normals`] of `positions` (as many as the blocks cover) over the triangles the
    /// blocks were made of, the same bits, the blocks in parallel.
    ///
    /// # Panics
    /// When `positions` is not as long as the blocks' vertex count.
    #[must_use]
    pub fn smooth_normals(&self, positions: &[Vec3]) -> Vec<Vec3> {
        assert_eq!(positions.len(), self.vertices, "one position per vertex");
        let mut acc: Vec<Vec3> = zeroed(positions.len());
        acc.par_chunks_mut(self.block)
            .enumerate()
            .for_each(|(k, acc)| {
                let first = k * self.block;
                let listed = &self.triangles[self.starts[k] as usize..self.starts[k + 1] as usize];
                for &[a, b, c] in listed {
                    let n = face_normal([a, b, c], positions);
                    let local = [a, b, c].map(|v| (v as usize).wrapping_sub(first));
                    if local.iter().all(|&j| j < acc.len()) {
                        // The usual triangle, all in this block: the serial loop's adds.
                        acc[local[0]] += n;
                        acc[local[1]] += n;
                        acc[local[2]] += n;
                    } else {
                        for j in local {
                            if let Some(x) = acc.get_mut(j) {
                                *x += n;
                            }
                        }
                    }
                }
                for n in acc.iter_mut() {
                    *n = n.try_normalize().unwrap_or(Vec3::Z);
                }
            });
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    }

    /// A strip of `n` vertices zig-zagging over a wavy sheet, triangles in vertex order.
    fn strip(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions = (0..n)
            .map(|i| {
                let x = (i / 2) as f32 * 0.37;
                let y = (i % 2) as f32;
                Vec3::new(x, y, (x * 1.7).sin() * 0.3 + y * 0.1)
            })
            .collect();
        let triangles = (0..n - 2)
            .map(|i| {
                if i % 2 == 0 {
                    [i, i + 1, i + 2]
                } else {
                    [i + 1, i, i + 2]
                }
            })
            .collect();
        (positions, triangles)
    }

    #[test]
    fn blocks_give_the_serial_bits_with_triangles_across_blocks_and_repeated_corners() {
        let (positions, mut triangles) = strip(200);
        // A triangle with a repeated corner (adds its normal twice to that vertex) and one
        // whose corners lie in three blocks.
        triangles.push([5, 5, 9]);
        triangles.push([3, 60, 121]);
        for block in [7, 64, 200, 500] {
            let blocks = TriangleBlocks::new(positions.len(), &triangles, block).expect("blocks");
            assert_eq!(
                bits(&blocks.smooth_normals(&positions)),
                bits(&smooth_normals(&positions, &triangles)),
                "blocks of {block}"
            );
        }
    }

    #[test]
    fn a_vertex_order_without_locality_or_a_corner_out_of_range_has_no_blocks() {
        // Every triangle across three far-apart blocks.
        let triangles: Vec<[u32; 3]> = (0..100).map(|i| [i, i + 100, i + 200]).collect();
        assert!(TriangleBlocks::new(300, &triangles, 10).is_none());
        assert!(TriangleBlocks::new(300, &triangles, 300).is_some());
        assert!(TriangleBlocks::new(299, &triangles, 300).is_none());
    }

    proptest! {
        #[test]
        fn block_sums_are_the_serial_sums(
            points in prop::collection::vec(prop::array::uniform3(-3.0f32..3.0), 3..120),
            picks in prop::collection::vec((0usize..1000, 0usize..1000, 0usize..1000), 1..200),
            spread in 1usize..12,
            block in 1usize..40,
        ) {
            let positions: Vec<Vec3> = points.into_iter().map(Vec3::from).collect();
            let n = positions.len();
            // Triangles over nearby vertices (at most `spread` apart), in random order.
            let triangles: Vec<[u32; 3]> = picks
                .into_iter()
                .map(|(a, b, c)| {
                    let a = a % n;
                    let near = |x: usize| ((a + x % spread).min(n - 1)) as u32;
                    [a as u32, near(b), near(c)]
                })
                .collect();
            match TriangleBlocks::new(n, &triangles, block) {
                Some(blocks) => prop_assert_eq!(
                    bits(&blocks.smooth_normals(&positions)),
                    bits(&smooth_normals(&positions, &triangles))
                ),
                // Refused only when the lists would be too long.
                None => {
                    let listed: usize = triangles
                        .iter()
                        .map(|t| {
                            let mut b = t.map(|v| v as usize / block);
                            b.sort_unstable();
                            1 + usize::from(b[1] != b[0]) + usize::from(b[2] != b[1])
                        })
                        .sum();
                    prop_assert!(2 * listed > 3 * triangles.len(), "{listed} listed");
                }
            }
        }
    }
}
