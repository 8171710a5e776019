//! [`PolylineIndex::closest`] for a lane group of points at a time: the seeds of the curve
//! and axial binds, on `lane.rs`'s lanes in [`pulp`]'s runtime dispatch.
//!
//! A lane group computes the squared distances from its points to every block's box, then
//! projects all its points onto the segments of each block that may hold a point nearer
//! than some lane's best so far (one segment broadcast to every lane at a time). Each lane
//! keeps the least squared distance and, among equal ones, the earliest segment — the
//! answer of [`closest_on_polyline`](crate::frames::closest_on_polyline) and of the scalar
//! index, whatever the order blocks are searched in — and computes every projection with
//! the scalar operations in their order, so the answer has the same bits. A lane whose
//! answer is not finite (a point at `±∞` or NaN, or a squared distance past `f32::MAX`) is
//! answered again by the scalar query, whose ties between infinities are its own.

use glam::Vec3;

use crate::frames::{BLOCK, BOUND_BATCH, PolylineIndex};
use crate::lane::{LANES, Lane, Lanes3, Mask};

/// A lane group's answers: segment index (an `f32` integer), fraction and squared distance.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Seeds {
    /// The segment of each lane's closest point, exact as `f32` (below `2²⁴` segments).
    pub(crate) segment: Lane,
    /// The fraction `f ∈ [0, 1]` along the segment.
    pub(crate) fraction: Lane,
    /// The squared distance.
    pub(crate) d2: Lane,
}

/// Scratch space for a lane group's squared distances to a batch of block boxes.
pub(crate) type Bounds = [Lane; BOUND_BATCH];

/// The most segments whose indices the lanes hold exactly as `f32`.
const EXACT_SEGMENTS: usize = 1 << 24;

impl PolylineIndex {
    /// [`PolylineIndex::closest`] of every point of `xs`, written to `out` (as long as `xs`):
    /// the same bits, a lane group at a time.
    ///
    /// # Panics
    /// When `out` and `xs` differ in length.
    pub fn closest_each(&self, xs: &[Vec3], out: &mut [(usize, f32, f32)]) {
        assert_eq!(xs.len(), out.len(), "one answer per point");
        pulp::Arch::new().dispatch(ClosestEach {
            index: self,
            xs,
            out,
        });
    }

    /// Whether the lane path answers queries on this polyline (segment indices exact).
    #[inline(always)]
    pub(crate) fn has_lanes(&self) -> bool {
        self.segments < EXACT_SEGMENTS
    }

    /// The closest points of a lane group (module documentation). Lanes whose `d2` is not
    /// finite must be answered again by [`PolylineIndex::closest`]. `bounds` is scratch
    /// space, kept by the caller across lane groups (zeroing its 4 KiB per group cost a curve
    /// bind about 14 % more instructions, by callgrind).
    #[inline(always)]
    pub(crate) fn closest_lanes(&self, x: &Lanes3, bounds: &mut Bounds) -> Seeds {
        let blocks = self.lanes.len();
        // The first search: lane 0's first block of least bound (the lanes of a group are
        // usually near each other).
        let mut start = (0, f32::INFINITY);
        for from in (0..blocks).step_by(BOUND_BATCH) {
            let len = self.bound_lanes(x, from, bounds);
            for (k, d) in bounds[..len].iter().enumerate() {
                let d = d.as_array()[0];
                if d < start.1 {
                    start = (from + k, d);
                }
            }
        }
        let mut best = Seeds {
            segment: Lane::splat(f32::INFINITY),
            fraction: Lane::ZERO,
            d2: Lane::splat(f32::INFINITY),
        };
        self.search_lanes(start.0, x, &mut best);
        for from in (0..blocks).step_by(BOUND_BATCH) {
            let len = if blocks <= BOUND_BATCH {
                blocks
            } else {
                self.bound_lanes(x, from, bounds)
            };
            for (k, d) in bounds[..len].iter().enumerate() {
                let b = from + k;
                if b != start.0 && d.simd_le(best.d2).any() {
                    self.search_lanes(b, x, &mut best);
                }
            }
        }
        best
    }

    /// The squared distances from each lane's point to the boxes of blocks `from..` (at
    /// most [`BOUND_BATCH`]), as [`PolylineIndex::closest`]'s scalar bounds; returns how many.
    #[inline(always)]
    fn bound_lanes(&self, x: &Lanes3, from: usize, out: &mut Bounds) -> usize {
        let len = (self.lanes.len() - from).min(BOUND_BATCH);
        let [lx, ly, lz, hx, hy, hz] = &self.boxes;
        let zero = Lane::ZERO;
        for (k, o) in out[..len].iter_mut().enumerate() {
            let b = from + k;
            let ex = (Lane::splat(lx[b]) - x.x).greater(x.x - Lane::splat(hx[b]));
            let ey = (Lane::splat(ly[b]) - x.y).greater(x.y - Lane::splat(hy[b]));
            let ez = (Lane::splat(lz[b]) - x.z).greater(x.z - Lane::splat(hz[b]));
            let (ex, ey, ez) = (ex.greater(zero), ey.greater(zero), ez.greater(zero));
            *o = ex * ex + ey * ey + ez * ez;
        }
        len
    }

    /// Projects every lane's point onto the segments of block `b` (the operations of
    /// `project_on_segment`), keeping in `best` each lane's least squared distance and,
    /// among equal ones, the earliest segment.
    #[inline(always)]
    fn search_lanes(&self, b: usize, x: &Lanes3, best: &mut Seeds) {
        let block = &self.lanes[b];
        let first = b * BLOCK;
        let len = (self.segments - first).min(BLOCK);
        let zero = Lane::ZERO;
        for i in 0..len {
            let (px, py, pz) = (
                Lane::splat(block.p[0][i]),
                Lane::splat(block.p[1][i]),
                Lane::splat(block.p[2][i]),
            );
            let (dx, dy, dz) = (
                Lane::splat(block.d[0][i]),
                Lane::splat(block.d[1][i]),
                Lane::splat(block.d[2][i]),
            );
            let l2 = block.l2[i];
            let f = if l2 > 0.0 {
                let dot = (x.x - px) * dx + (x.y - py) * dy + (x.z - pz) * dz;
                // `f32::clamp(0, 1)`, NaN kept.
                (dot / Lane::splat(l2)).clamp01()
            } else {
                zero
            };
            let (ex, ey, ez) = (
                (px + dx * f) - x.x,
                (py + dy * f) - x.y,
                (pz + dz * f) - x.z,
            );
            let d2 = ex * ex + ey * ey + ez * ez;
            let segment = Lane::splat((first + i) as f32);
            let better: Mask =
                d2.simd_lt(best.d2) | (d2.simd_eq(best.d2) & segment.simd_lt(best.segment));
            best.segment = better.select(segment, best.segment);
            best.fraction = better.select(f, best.fraction);
            best.d2 = better.select(d2, best.d2);
        }
    }
}

/// [`PolylineIndex::closest_each`]'s kernel.
struct ClosestEach<'a> {
    index: &'a PolylineIndex,
    xs: &'a [Vec3],
    out: &'a mut [(usize, f32, f32)],
}

impl pulp::WithSimd for ClosestEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let index = self.index;
        if !index.has_lanes() {
            for (o, &x) in self.out.iter_mut().zip(self.xs) {
                *o = index.closest(x);
            }
            return;
        }
        let mut bounds = [Lane::ZERO; BOUND_BATCH];
        for (xs, out) in self.xs.chunks(LANES).zip(self.out.chunks_mut(LANES)) {
            let seeds = index.closest_lanes(&Lanes3::load(xs), &mut bounds);
            let finite = seeds.d2.is_finite();
            for (j, o) in out.iter_mut().enumerate() {
                *o = if finite.lane(j) {
                    (
                        seeds.segment.as_array()[j] as usize,
                        seeds.fraction.as_array()[j],
                        seeds.d2.as_array()[j],
                    )
                } else {
                    index.closest(xs[j])
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::closest_on_polyline;
    use proptest::prelude::*;

    fn bits(a: (usize, f32, f32)) -> (usize, u32, u32) {
        (a.0, a.1.to_bits(), a.2.to_bits())
    }

    /// A wound spiral of `n` points, with repeated points (zero-length segments).
    fn spiral(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|k| {
                let s = (k - k % 7 / 6) as f32 * 0.013;
                Vec3::new(s.cos() * (1.0 + 0.1 * s), s.sin(), 0.05 * s)
            })
            .collect()
    }

    #[test]
    fn lanes_give_the_scalar_bits_on_short_and_long_polylines() {
        // 1 block, 40 blocks and 600 blocks (several bound batches).
        for n in [5, 321, 4801] {
            let pl = spiral(n);
            let index = PolylineIndex::new(pl.clone()).unwrap();
            let xs: Vec<Vec3> = (0..2003)
                .map(|i| {
                    Vec3::new(
                        (i as f32 * 0.37).sin() * 3.0,
                        (i as f32 * 0.71).cos() * 3.0,
                        (i as f32 * 0.13).sin() * 2.0,
                    )
                })
                .collect();
            let mut out = vec![(0, 0.0, 0.0); xs.len()];
            index.closest_each(&xs, &mut out);
            for (x, o) in xs.iter().zip(&out) {
                assert_eq!(bits(*o), bits(index.closest(*x)), "n = {n}, x = {x}");
                assert_eq!(bits(*o), bits(closest_on_polyline(&pl, *x)), "n = {n}");
            }
        }
    }

    #[test]
    fn equal_distances_go_to_the_earliest_segment_and_odd_points_to_the_scalar_query() {
        // A square traversed twice: every point is equally near two segments.
        let sq = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::ZERO,
        ];
        let pl: Vec<Vec3> = sq.iter().chain(&sq[1..]).chain(&sq[1..]).copied().collect();
        let index = PolylineIndex::new(pl.clone()).unwrap();
        let mut xs: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(0.1 * i as f32 - 1.0, 0.5, 0.3))
            .collect();
        xs.extend([
            Vec3::splat(f32::NAN),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(3e19, -3e19, 0.0),
            Vec3::new(0.5, 0.0, 0.0),
        ]);
        let mut out = vec![(0, 0.0, 0.0); xs.len()];
        index.closest_each(&xs, &mut out);
        for (x, o) in xs.iter().zip(&out) {
            assert_eq!(bits(*o), bits(index.closest(*x)), "x = {x}");
        }
        assert_eq!(out[43].0, 0);
    }

    proptest! {
        #[test]
        fn lanes_match_the_scalar_query(
            pts in prop::collection::vec(prop::array::uniform3(-10.0f32..10.0), 2..120),
            xs in prop::collection::vec(prop::array::uniform3(-20.0f32..20.0), 1..70),
        ) {
            let pl: Vec<Vec3> = pts.into_iter().map(Vec3::from).collect();
            let xs: Vec<Vec3> = xs.into_iter().map(Vec3::from).collect();
            let index = PolylineIndex::new(pl).unwrap();
            let mut out = vec![(0, 0.0, 0.0); xs.len()];
            index.closest_each(&xs, &mut out);
            for (x, o) in xs.iter().zip(&out) {
                prop_assert_eq!(bits(*o), bits(index.closest(*x)));
            }
        }
    }
}
