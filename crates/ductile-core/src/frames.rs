//! Rotation-minimising frames (RMF) along sampled curves by the double-reflection method of
//! Wang, Jüttler, Zheng & Liu, "Computation of Rotation Minimizing Frames", ACM TOG 27(1),
//! 2008, Algorithm 1; and the closest point on a polyline.
//!
//! Given sample points `xᵢ` with unit tangents `tᵢ` and a first normal `r₀ ⟂ t₀`, each step
//! reflects the frame twice:
//!
//! * `v₁ = xᵢ₊₁ − xᵢ`, `c₁ = v₁·v₁`, `rᴸ = rᵢ − (2/c₁)(v₁·rᵢ) v₁`, `tᴸ = tᵢ − (2/c₁)(v₁·tᵢ) v₁`;
//! * `v₂ = tᵢ₊₁ − tᴸ`, `c₂ = v₂·v₂`, `rᵢ₊₁ = rᴸ − (2/c₂)(v₂·rᴸ) v₂`, `sᵢ₊₁ = tᵢ₊₁ × rᵢ₊₁`.
//!
//! The first reflection maps `xᵢ` to `xᵢ₊₁`; the second brings the reflected tangent onto
//! `tᵢ₊₁`. The composition has fourth-order global accuracy in the step for the rotation
//! about the tangent, so frames neither flip nor spin along a bent or helical axis (unlike
//! Frenet frames, which are undefined where the curvature vanishes). A reflection whose
//! vector is (numerically) zero is skipped: coincident samples, or a tangent already
//! matching.

use glam::{Mat3, Quat, Vec3};

/// An orthonormal, right-handed frame along a curve: `tangent × normal = binormal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit tangent `t` (local x axis).
    pub tangent: Vec3,
    /// Unit normal `r` (local y axis), perpendicular to the tangent.
    pub normal: Vec3,
    /// Unit binormal `s = t × r` (local z axis).
    pub binormal: Vec3,
}

impl Frame {
    /// The frame with the given unit tangent and a normal made perpendicular to it
    /// (Gram–Schmidt). Returns `None` when `normal` is (nearly) parallel to `tangent` or
    /// either is not finite.
    #[must_use]
    pub fn new(tangent: Vec3, normal: Vec3) -> Option<Self> {
        let t = tangent.try_normalize()?;
        let r = (normal - t * normal.dot(t)).try_normalize()?;
        Some(Self {
            tangent: t,
            normal: r,
            binormal: t.cross(r),
        })
    }

    /// A frame with the given tangent and a deterministic normal: the world axis least
    /// aligned with the tangent, made perpendicular to it. `None` for a zero or non-finite
    /// tangent.
    #[must_use]
    pub fn from_tangent(tangent: Vec3) -> Option<Self> {
        let t = tangent.try_normalize()?;
        let a = t.abs();
        let axis = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        Self::new(t, axis)
    }

    /// The rotation matrix with columns `(t, r, s)`: local coordinates → world directions.
    #[must_use]
    pub fn matrix(&self) -> Mat3 {
        Mat3::from_cols(self.tangent, self.normal, self.binormal)
    }

    /// The frame as a unit quaternion (the rotation of [`Frame::matrix`]).
    #[must_use]
    pub fn rotation(&self) -> Quat {
        Quat::from_mat3(&self.matrix()).normalize()
    }
}

/// Rotation-minimising frames at `points` with unit `tangents` (same length), starting from
/// the normal `first_normal` (made perpendicular to `tangents[0]`), by double reflection
/// (Wang et al. 2008, Algorithm 1; formulas in the module documentation).
///
/// Returns `None` when the slices differ in length or are empty, or when `first_normal` is
/// parallel to the first tangent or a tangent is zero.
#[must_use]
pub fn double_reflection(
    points: &[Vec3],
    tangents: &[Vec3],
    first_normal: Vec3,
) -> Option<Vec<Frame>> {
    if points.len() != tangents.len() || points.is_empty() {
        return None;
    }
    let mut frames = Vec::with_capacity(points.len());
    let mut frame = Frame::new(tangents[0], first_normal)?;
    frames.push(frame);
    for i in 0..points.len() - 1 {
        let next_t = tangents[i + 1].try_normalize()?;
        let v1 = points[i + 1] - points[i];
        let c1 = v1.length_squared();
        let (r_l, t_l) = if c1 > f32::MIN_POSITIVE * 1e6 {
            (
                frame.normal - (2.0 / c1) * v1.dot(frame.normal) * v1,
                frame.tangent - (2.0 / c1) * v1.dot(frame.tangent) * v1,
            )
        } else {
            (frame.normal, frame.tangent)
        };
        let v2 = next_t - t_l;
        let c2 = v2.length_squared();
        let r = if c2 > 1e-12 {
            r_l - (2.0 / c2) * v2.dot(r_l) * v2
        } else {
            r_l
        };
        // Re-orthonormalise against rounding drift over long sample runs.
        frame = Frame::new(next_t, r)?;
        frames.push(frame);
    }
    Some(frames)
}

/// Unit tangents of a polyline at its vertices: the normalised sum of the unit directions of
/// the two adjacent segments (the segment direction at the ends). Where the two directions
/// cancel (a 180° turn) the outgoing direction is used. Returns `None` when a segment has
/// zero length or the polyline has fewer than two points.
#[must_use]
pub fn polyline_tangents(points: &[Vec3]) -> Option<Vec<Vec3>> {
    if points.len() < 2 {
        return None;
    }
    let dirs: Vec<Vec3> = points
        .windows(2)
        .map(|w| (w[1] - w[0]).try_normalize())
        .collect::<Option<_>>()?;
    let n = points.len();
    Some(
        (0..n)
            .map(|i| {
                if i == 0 {
                    dirs[0]
                } else if i == n - 1 {
                    dirs[n - 2]
                } else {
                    (dirs[i - 1] + dirs[i]).try_normalize().unwrap_or(dirs[i])
                }
            })
            .collect(),
    )
}

/// The closest point to `x` on a polyline (at least two points): `(segment, fraction,
/// squared distance)` with the point `points[s] + f (points[s+1] − points[s])`, `f ∈ [0, 1]`.
/// Zero-length segments are treated as points. On ties the first segment wins.
///
/// # Panics
/// When `points` has fewer than two points.
#[must_use]
pub fn closest_on_polyline(points: &[Vec3], x: Vec3) -> (usize, f32, f32) {
    let mut best = (0, 0.0, f32::INFINITY);
    for (s, w) in points.windows(2).enumerate() {
        let d = w[1] - w[0];
        let (f, dist2) = project_on_segment(w[0], d, d.length_squared(), x);
        if dist2 < best.2 {
            best = (s, f, dist2);
        }
    }
    best
}

/// The fraction `f ∈ [0, 1]` of the point of segment `p + f·d` nearest to `x` (`l2 = |d|²`;
/// 0 for a zero-length segment) and its squared distance to `x`.
#[inline]
fn project_on_segment(p: Vec3, d: Vec3, l2: f32, x: Vec3) -> (f32, f32) {
    let f = if l2 > 0.0 {
        ((x - p).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (f, (p + d * f).distance_squared(x))
}

/// Segments per block of a [`PolylineIndex`].
pub(crate) const BLOCK: usize = 8;

/// Blocks whose bounds a query computes at a time on the stack.
pub(crate) const BOUND_BATCH: usize = 64;

/// The segments of one block as structure of arrays, one lane per segment: start points,
/// directions `p[s+1] − p[s]` and their squared lengths (lanes past the polyline's end
/// repeat its last segment and are never chosen).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BlockLanes {
    pub(crate) p: [[f32; BLOCK]; 3],
    pub(crate) d: [[f32; BLOCK]; 3],
    pub(crate) l2: [f32; BLOCK],
}

/// A polyline with bounding boxes over blocks of consecutive segments, for fast repeated
/// closest-point queries (the same answer as [`closest_on_polyline`]).
///
/// A query computes the bounds of all boxes, then projects onto the segments of the blocks
/// that may hold a nearer point than the best so far. Both loops run over arrays of plain
/// values (boxes and segments as structures of arrays) that the compiler turns into SIMD
/// code on any target; each lane does exactly the operations of
/// [`closest_on_polyline`], in the same order, so the answer has the same bits.
#[derive(Debug, Clone, PartialEq)]
pub struct PolylineIndex {
    points: Vec<Vec3>,
    /// Number of segments.
    pub(crate) segments: usize,
    /// The segments, [`BLOCK`] per block.
    pub(crate) lanes: Vec<BlockLanes>,
    /// The corners of each block's box, padded so that a segment point as rounded
    /// (`p + d·f`) never lies outside: `lo.x, lo.y, lo.z, hi.x, hi.y, hi.z` per block.
    pub(crate) boxes: [Vec<f32>; 6],
}

impl PolylineIndex {
    /// Indexes a polyline of at least two points. Returns `None` for fewer points.
    #[must_use]
    pub fn new(points: Vec<Vec3>) -> Option<Self> {
        if points.len() < 2 {
            return None;
        }
        let segments = points.len() - 1;
        let mut boxes: [Vec<f32>; 6] = Default::default();
        let mut lanes = Vec::with_capacity(segments.div_ceil(BLOCK));
        for first in (0..segments).step_by(BLOCK) {
            let end = (first + BLOCK).min(segments);
            let span = &points[first..=end];
            let (lo, hi) = span
                .iter()
                .fold((span[0], span[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let pad = (hi - lo).max_element() * 1e-4 + lo.abs().max(hi.abs()).max_element() * 1e-5;
            let (lo, hi) = (lo - Vec3::splat(pad), hi + Vec3::splat(pad));
            for (b, v) in boxes.iter_mut().zip([lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]) {
                b.push(v);
            }
            let mut block = BlockLanes {
                p: [[0.0; BLOCK]; 3],
                d: [[0.0; BLOCK]; 3],
                l2: [0.0; BLOCK],
            };
            for i in 0..BLOCK {
                let s = (first + i).min(segments - 1);
                let (a, d) = (points[s], points[s + 1] - points[s]);
                for c in 0..3 {
                    block.p[c][i] = a[c];
                    block.d[c][i] = d[c];
                }
                block.l2[i] = d.length_squared();
            }
            lanes.push(block);
        }
        Some(Self {
            points,
            segments,
            lanes,
            boxes,
        })
    }

    /// The indexed points.
    #[must_use]
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Like [`closest_on_polyline`]: `(segment, fraction, squared distance)`, the same
    /// bits. Blocks whose bounding box is farther than the best distance found so far are
    /// skipped, starting from the block nearest to `x`.
    #[must_use]
    pub fn closest(&self, x: Vec3) -> (usize, f32, f32) {
        // The answer is the least squared distance and, among equal ones, the earliest
        // segment, whatever the order in which blocks are searched: start with the first
        // block of least bound, then search every block that may hold a nearer point.
        let blocks = self.lanes.len();
        let mut bounds = [0.0_f32; BOUND_BATCH];
        let mut start = (0, f32::INFINITY);
        for from in (0..blocks).step_by(BOUND_BATCH) {
            let len = self.bounds(x, from, &mut bounds);
            for (k, &d) in bounds[..len].iter().enumerate() {
                if d < start.1 {
                    start = (from + k, d);
                }
            }
        }
        let mut best = self.search(start.0, x);
        for from in (0..blocks).step_by(BOUND_BATCH) {
            // One batch's bounds are still on the stack when there is only one batch.
            let len = if blocks <= BOUND_BATCH {
                blocks
            } else {
                self.bounds(x, from, &mut bounds)
            };
            for (k, &d) in bounds[..len].iter().enumerate() {
                let b = from + k;
                if b != start.0 && d <= best.2 {
                    let c = self.search(b, x);
                    // Ties go to the earlier segment, as in `closest_on_polyline`.
                    if c.2 < best.2 || (c.2 == best.2 && c.0 < best.0) {
                        best = c;
                    }
                }
            }
        }
        best
    }

    /// The squared distances from `x` to the boxes of blocks `from..` (at most
    /// [`BOUND_BATCH`]), written to `out`; returns how many. No point of a block is nearer.
    #[inline]
    fn bounds(&self, x: Vec3, from: usize, out: &mut [f32; BOUND_BATCH]) -> usize {
        let len = (self.lanes.len() - from).min(BOUND_BATCH);
        let [lx, ly, lz, hx, hy, hz] = &self.boxes;
        let (lx, ly, lz) = (
            &lx[from..from + len],
            &ly[from..from + len],
            &lz[from..from + len],
        );
        let (hx, hy, hz) = (
            &hx[from..from + len],
            &hy[from..from + len],
            &hz[from..from + len],
        );
        for k in 0..len {
            let ex = (lx[k] - x.x).max(x.x - hx[k]).max(0.0);
            let ey = (ly[k] - x.y).max(x.y - hy[k]).max(0.0);
            let ez = (lz[k] - x.z).max(x.z - hz[k]).max(0.0);
            out[k] = ex * ex + ey * ey + ez * ez;
        }
        len
    }

    /// [`closest_on_polyline`] over the segments of block `b`: every lane projected (the
    /// operations of [`project_on_segment`]), then the first least distance.
    fn search(&self, b: usize, x: Vec3) -> (usize, f32, f32) {
        let block = &self.lanes[b];
        let mut f = [0.0_f32; BLOCK];
        let mut d2 = [0.0_f32; BLOCK];
        for i in 0..BLOCK {
            let (px, py, pz) = (block.p[0][i], block.p[1][i], block.p[2][i]);
            let (dx, dy, dz) = (block.d[0][i], block.d[1][i], block.d[2][i]);
            let l2 = block.l2[i];
            let dot = (x.x - px) * dx + (x.y - py) * dy + (x.z - pz) * dz;
            let q = dot / l2;
            let fi = if l2 > 0.0 { q.clamp(0.0, 1.0) } else { 0.0 };
            let (ex, ey, ez) = (
                (px + dx * fi) - x.x,
                (py + dy * fi) - x.y,
                (pz + dz * fi) - x.z,
            );
            f[i] = fi;
            d2[i] = ex * ex + ey * ey + ez * ez;
        }
        let first = b * BLOCK;
        let len = (self.segments - first).min(BLOCK);
        let mut best = (first, 0.0, f32::INFINITY);
        for i in 0..len {
            if d2[i] < best.2 {
                best = (first + i, f[i], d2[i]);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{PI, TAU};

    /// Helix `(a cos s, a sin s, c s)`, its unit tangent and Frenet normal.
    fn helix(a: f32, c: f32, s: f32) -> (Vec3, Vec3, Vec3) {
        let p = Vec3::new(a * s.cos(), a * s.sin(), c * s);
        let t = Vec3::new(-a * s.sin(), a * s.cos(), c).normalize();
        let n = Vec3::new(-s.cos(), -s.sin(), 0.0);
        (p, t, n)
    }

    #[test]
    fn helix_frame_follows_minus_torsion_and_never_flips() {
        // Along a helix the RMF normal turns against the Frenet normal at the rate −τ per
        // unit arc length (r' ∥ t ⇒ φ' = −τ), τ = c / (a² + c²), arc length = s √(a² + c²).
        let (a, c) = (1.0_f32, 0.4_f32);
        let steps = 400;
        let s_max = 2.0 * TAU;
        let samples: Vec<(Vec3, Vec3, Vec3)> = (0..=steps)
            .map(|k| helix(a, c, s_max * k as f32 / steps as f32))
            .collect();
        let points: Vec<Vec3> = samples.iter().map(|x| x.0).collect();
        let tangents: Vec<Vec3> = samples.iter().map(|x| x.1).collect();
        let frames = double_reflection(&points, &tangents, samples[0].2).unwrap();
        let speed = (a * a + c * c).sqrt();
        let tau = c / (a * a + c * c);
        let mut prev = frames[0].normal;
        for (k, (f, (_, t, n))) in frames.iter().zip(&samples).enumerate() {
            let s = s_max * k as f32 / steps as f32;
            // Orthonormal and right-handed.
            assert!((f.tangent - *t).length() < 1e-5);
            assert!(f.normal.dot(f.tangent).abs() < 1e-5);
            assert!((f.normal.length() - 1.0).abs() < 1e-5);
            assert!((f.tangent.cross(f.normal) - f.binormal).length() < 1e-5);
            // Signed angle from the Frenet normal to the RMF normal, about the tangent.
            let b = t.cross(*n);
            let phi = f.normal.dot(b).atan2(f.normal.dot(*n));
            let expected = -tau * speed * s;
            let diff = (phi - expected + PI).rem_euclid(TAU) - PI;
            assert!(
                diff.abs() < 2e-3,
                "step {k}: φ = {phi}, expected {expected}"
            );
            // No flip: consecutive normals stay close (the step turns the tangent by
            // κ·Δl ≈ 0.06 rad here).
            assert!(f.normal.dot(prev) > 0.99, "flip at step {k}");
            prev = f.normal;
        }
    }

    #[test]
    fn straight_line_keeps_its_frame() {
        let points: Vec<Vec3> = (0..10).map(|i| Vec3::new(0.0, 0.0, i as f32)).collect();
        let tangents = vec![Vec3::Z; 10];
        let frames = double_reflection(&points, &tangents, Vec3::X).unwrap();
        for f in frames {
            assert!((f.normal - Vec3::X).length() < 1e-6);
            assert!((f.binormal - Vec3::Y).length() < 1e-6);
        }
    }

    #[test]
    fn planar_curve_keeps_the_plane_normal_as_binormal() {
        // Quarter circle in the xy-plane: the RMF of a planar curve is its Frenet frame up to
        // a constant rotation; starting with normal = inward normal keeps binormal = z.
        let n = 32;
        let (points, tangents): (Vec<Vec3>, Vec<Vec3>) = (0..=n)
            .map(|k| {
                let a = 0.5 * PI * k as f32 / n as f32;
                (
                    Vec3::new(a.sin(), 1.0 - a.cos(), 0.0),
                    Vec3::new(a.cos(), a.sin(), 0.0),
                )
            })
            .unzip();
        let frames = double_reflection(&points, &tangents, Vec3::Y).unwrap();
        for (k, f) in frames.iter().enumerate() {
            let a = 0.5 * PI * k as f32 / n as f32;
            assert!((f.binormal - Vec3::Z).length() < 1e-5);
            assert!((f.normal - Vec3::new(-a.sin(), a.cos(), 0.0)).length() < 1e-5);
        }
    }

    #[test]
    fn degenerate_inputs_give_none() {
        assert!(double_reflection(&[Vec3::ZERO], &[Vec3::Z], Vec3::Z).is_none());
        assert!(double_reflection(&[], &[], Vec3::X).is_none());
        assert!(polyline_tangents(&[Vec3::ZERO, Vec3::ZERO]).is_none());
        assert!(polyline_tangents(&[Vec3::ZERO]).is_none());
        assert!(Frame::from_tangent(Vec3::ZERO).is_none());
        assert!(Frame::from_tangent(Vec3::NAN).is_none());
    }

    #[test]
    fn index_agrees_with_brute_force() {
        let pl: Vec<Vec3> = (0..70)
            .map(|k| {
                let s = k as f32 * 0.2;
                Vec3::new(s.cos(), s.sin(), 0.1 * s)
            })
            .collect();
        let index = PolylineIndex::new(pl.clone()).unwrap();
        for i in 0..300 {
            let x = Vec3::new(
                (i as f32 * 0.37).sin() * 2.0,
                (i as f32 * 0.71).cos() * 2.0,
                i as f32 * 0.005,
            );
            let (s, f, d2) = closest_on_polyline(&pl, x);
            let (si, fi, d2i) = index.closest(x);
            assert_eq!(d2, d2i, "{x}");
            assert!(s == si && f == fi || d2 == d2i);
        }
    }

    #[test]
    fn index_gives_the_brute_force_bits_on_short_and_long_polylines() {
        // 40 blocks and 600 blocks.
        for n in [321, 4801] {
            let pl: Vec<Vec3> = (0..n)
                .map(|k| {
                    let s = k as f32 * 0.013;
                    Vec3::new(s.cos() * (1.0 + 0.1 * s), s.sin(), 0.05 * s)
                })
                .collect();
            let index = PolylineIndex::new(pl.clone()).unwrap();
            for i in 0..2000 {
                let x = Vec3::new(
                    (i as f32 * 0.37).sin() * 3.0,
                    (i as f32 * 0.71).cos() * 3.0,
                    (i as f32 * 0.13).sin() * 2.0,
                );
                let brute = closest_on_polyline(&pl, x);
                let indexed = index.closest(x);
                assert_eq!(
                    (brute.0, brute.1.to_bits(), brute.2.to_bits()),
                    (indexed.0, indexed.1.to_bits(), indexed.2.to_bits()),
                    "n = {n}, x = {x}"
                );
            }
        }
    }

    #[test]
    fn closest_point_on_polyline() {
        let pl = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
        let (s, f, d2) = closest_on_polyline(&pl, Vec3::new(0.25, -0.5, 0.0));
        assert_eq!(s, 0);
        assert!((f - 0.25).abs() < 1e-6 && (d2 - 0.25).abs() < 1e-6);
        let (s, f, d2) = closest_on_polyline(&pl, Vec3::new(2.0, 0.75, 0.0));
        assert_eq!(s, 1);
        assert!((f - 0.75).abs() < 1e-6 && (d2 - 1.0).abs() < 1e-6);
    }
}
