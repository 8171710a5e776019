//! Skeleton-style coordinates of curves: a curve as its start, segment lengths and turning
//! angles, so that blending the coordinates keeps lengths and bends joints instead of moving
//! points on straight lines (Kho & Garland 2005, §6.1; `docs/algorithms/animation.md`).
//!
//! Coordinates are computed *jointly* for a set of curves (the keys around a time, or the
//! variants being blended): the curves share one frame, so that any affine combination of
//! their coordinate vectors (`Σ wᵢ cᵢ`, `Σ wᵢ = 1`) decodes to an in-between curve, and the
//! coordinates of curve `i` decode to curve `i` itself (up to rounding).
//!
//! * **Plane curves** (the sketch tool's bend target, normal `n`): both curves are
//!   resampled at the union of their nodes' normalised arc lengths `σ`; each segment `j` gets
//!   its in-plane length `lⱼ` and its accumulated, unwrapped angle `ψⱼ` about `n`, measured
//!   from one shared in-plane direction `e₀` (the base curve's first direction); each node its
//!   height `hᵢ = n·(pᵢ − p₀)` off the plane. A curve is rebuilt from its start:
//!   `pᵢ₊₁ = p₀ + Σ_{j≤i} lⱼ R(n, ψⱼ) e₀ + hᵢ₊₁ n`. Between two curves the total length
//!   is interpolated linearly and every angle by `α θⱼ` (the paper's construction).
//! * **3-D curves** (the curve deformation's control polygon, the axial axis) have no single
//!   plane: each segment gets its length and a frame `Qⱼ`, transported from segment to
//!   segment by the minimal rotation between their directions (a discrete rotation-minimising
//!   frame). The coordinates are the start point, the rotation vector of the first frame
//!   relative to the base curve's, the lengths, and the rotation vector of each relative
//!   rotation `rⱼ = Qⱼ₋₁⁻¹ Qⱼ` relative to the base curve's. Between two curves this is a slerp
//!   of the first frame and of every relative rotation, and a lerp of every length.

use ductile_core::sketch::bend::signed_angle;
use glam::{Quat, Vec3};

/// Segments shorter than this (relative to the curve's length) have no direction of their
/// own: they take the previous segment's.
const TINY: f32 = 1e-7;

/// The shared frame of plane-curve coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneFrame {
    /// Unit normal of the sketch plane.
    normal: Vec3,
    /// Unit in-plane direction all angles are measured from.
    e0: Vec3,
}

/// Normalised arc-length parameters of a polyline's nodes (`0` first, `1` last); `None` when
/// it has fewer than two nodes or no length.
fn arc_params(points: &[Vec3]) -> Option<Vec<f64>> {
    if points.len() < 2 {
        return None;
    }
    let mut acc = 0.0_f64;
    let mut s = Vec::with_capacity(points.len());
    s.push(0.0);
    for w in points.windows(2) {
        acc += f64::from(w[0].distance(w[1]));
        s.push(acc);
    }
    if !(acc > 0.0 && acc.is_finite()) {
        return None;
    }
    for x in &mut s {
        *x /= acc;
    }
    if let Some(last) = s.last_mut() {
        *last = 1.0;
    }
    Some(s)
}

/// The polyline `points` (node parameters `s`) at the parameters `at` (ascending, in
/// `[0, 1]`): nodes where a parameter equals a node's, linear in between.
fn resample(points: &[Vec3], s: &[f64], at: &[f64]) -> Vec<Vec3> {
    at.iter()
        .map(|&x| {
            let j = s.partition_point(|&v| v <= x).clamp(1, s.len() - 1);
            let (a, b) = (s[j - 1], s[j]);
            if x <= a {
                points[j - 1]
            } else if x >= b {
                points[j]
            } else {
                let u = ((x - a) / (b - a)) as f32;
                points[j - 1].lerp(points[j], u)
            }
        })
        .collect()
}

/// `a + 2πk` for the integer `k` that brings it closest to `near`.
fn unwrap_near(a: f32, near: f32) -> f32 {
    let tau = std::f32::consts::TAU;
    a + ((near - a) / tau).round() * tau
}

/// Joint plane-curve coordinates of `curves` about `normal` (see the module documentation),
/// with the angles measured from the first in-plane direction of `curves[base]`. `None` when
/// the normal is zero or a curve has fewer than two nodes, no length, or (the base) no extent
/// in the plane.
#[must_use]
pub fn plane_coords(
    curves: &[&[Vec3]],
    normal: Vec3,
    base: usize,
) -> Option<(PlaneFrame, Vec<Vec<f32>>)> {
    let n = normal.try_normalize()?;
    let params: Vec<Vec<f64>> = curves
        .iter()
        .map(|c| arc_params(c))
        .collect::<Option<_>>()?;
    let mut union: Vec<f64> = params.iter().flatten().copied().collect();
    union.sort_by(f64::total_cmp);
    union.dedup_by(|a, b| (*a - *b).abs() <= 1e-9);
    let curves: Vec<Vec<Vec3>> = curves
        .iter()
        .zip(&params)
        .map(|(c, s)| resample(c, s, &union))
        .collect();
    let in_plane = |e: Vec3| e - n * n.dot(e);
    let reference = curves.get(base)?;
    let scale = reference
        .windows(2)
        .map(|w| w[0].distance(w[1]))
        .sum::<f32>();
    let e0 = reference
        .windows(2)
        .map(|w| in_plane(w[1] - w[0]))
        .find(|e| e.length() > TINY * scale)?
        .normalize();
    let mut previous_start: Option<f32> = None;
    let coords = curves
        .iter()
        .map(|r| {
            let m = r.len() - 1;
            let length: f32 = r.windows(2).map(|w| w[0].distance(w[1])).sum();
            let mut c = Vec::with_capacity(3 + 3 * m);
            c.extend(r[0].to_array());
            let mut psi = Vec::with_capacity(m);
            let mut lengths = Vec::with_capacity(m);
            let mut d_prev = e0;
            for j in 0..m {
                let e = in_plane(r[j + 1] - r[j]);
                let l = e.length();
                let d = if l > TINY * length { e / l } else { d_prev };
                let turn = signed_angle(d_prev, d, n);
                let a = if j == 0 {
                    let a = previous_start.map_or(turn, |p| unwrap_near(turn, p));
                    previous_start = Some(a);
                    a
                } else {
                    psi[j - 1] + turn
                };
                psi.push(a);
                lengths.push(l);
                d_prev = d;
            }
            c.extend(psi);
            c.extend(lengths);
            c.extend((1..=m).map(|i| n.dot(r[i] - r[0])));
            c
        })
        .collect();
    Some((PlaneFrame { normal: n, e0 }, coords))
}

/// The plane curve of coordinates `c` (see [`plane_coords`]). Negative lengths (from an
/// extrapolation) are taken as 0.
#[must_use]
pub fn plane_points(frame: &PlaneFrame, c: &[f32]) -> Vec<Vec3> {
    let m = c.len().saturating_sub(3) / 3;
    let p0 = Vec3::new(c[0], c[1], c[2]);
    let (psi, rest) = c[3..].split_at(m);
    let (lengths, heights) = rest.split_at(m);
    let mut out = Vec::with_capacity(m + 1);
    out.push(p0);
    let mut w = Vec3::ZERO;
    for j in 0..m {
        w += Quat::from_axis_angle(frame.normal, psi[j]) * frame.e0 * lengths[j].max(0.0);
        out.push(p0 + w + frame.normal * heights[j]);
    }
    out
}

/// The shared frame of 3-D curve coordinates: the base curve's first frame and relative
/// rotations.
#[derive(Debug, Clone, PartialEq)]
pub struct SpaceFrame {
    first: Quat,
    relative: Vec<Quat>,
}

/// Unit segment directions of a polyline; a zero-length segment takes the previous
/// direction (the next one at the start). `None` when every segment has zero length.
fn directions(points: &[Vec3]) -> Option<Vec<Vec3>> {
    let length: f32 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
    let raw: Vec<Option<Vec3>> = points
        .windows(2)
        .map(|w| {
            let e = w[1] - w[0];
            let l = e.length();
            (l > TINY * length && l > 0.0).then(|| e / l)
        })
        .collect();
    let first = raw.iter().flatten().next().copied()?;
    let mut prev = first;
    Some(
        raw.iter()
            .map(|d| {
                let d = d.unwrap_or(prev);
                prev = d;
                d
            })
            .collect(),
    )
}

/// The rotation vector (axis × angle, angle in `[0, π]`) of a unit quaternion: its
/// logarithm on the short path.
#[must_use]
pub fn log(q: Quat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    q.to_scaled_axis()
}

/// Joint 3-D curve coordinates of `curves` (all with the same number of points, at least
/// two), relative to `curves[base]` (see the module documentation). `None` when the counts
/// differ or a curve has no length.
#[must_use]
pub fn space_coords(curves: &[&[Vec3]], base: usize) -> Option<(SpaceFrame, Vec<Vec<f32>>)> {
    let count = curves.get(base)?.len();
    if count < 2 || curves.iter().any(|c| c.len() != count) {
        return None;
    }
    let dirs: Vec<Vec<Vec3>> = curves
        .iter()
        .map(|c| directions(c))
        .collect::<Option<_>>()?;
    // First frames, transported from curve to curve by the minimal rotation between their
    // first directions; relative rotations along each curve.
    let mut firsts: Vec<Quat> = Vec::with_capacity(curves.len());
    let mut relatives: Vec<Vec<Quat>> = Vec::with_capacity(curves.len());
    for (c, d) in dirs.iter().enumerate() {
        let first = match c {
            0 => Quat::from_rotation_arc(Vec3::X, d[0]),
            _ => (Quat::from_rotation_arc(dirs[c - 1][0], d[0]) * firsts[c - 1]).normalize(),
        };
        let mut q = first;
        let mut rel = Vec::with_capacity(d.len().saturating_sub(1));
        for j in 1..d.len() {
            let next = (Quat::from_rotation_arc(d[j - 1], d[j]) * q).normalize();
            rel.push((q.inverse() * next).normalize());
            q = next;
        }
        firsts.push(first);
        relatives.push(rel);
    }
    let frame = SpaceFrame {
        first: firsts[base],
        relative: relatives[base].clone(),
    };
    let coords = curves
        .iter()
        .enumerate()
        .map(|(c, points)| {
            let m = count - 1;
            let mut v = Vec::with_capacity(6 + m + 3 * (m - 1));
            v.extend(points[0].to_array());
            v.extend(log(frame.first.inverse() * firsts[c]).to_array());
            v.extend(points.windows(2).map(|w| w[0].distance(w[1])));
            for (b, r) in frame.relative.iter().zip(&relatives[c]) {
                v.extend(log(b.inverse() * *r).to_array());
            }
            v
        })
        .collect();
    Some((frame, coords))
}

/// Number of coordinates [`space_coords`] gives a curve of `points` points.
#[must_use]
pub fn space_len(points: usize) -> usize {
    let m = points.saturating_sub(1);
    6 + m + 3 * m.saturating_sub(1)
}

/// The 3-D curve of coordinates `c` (see [`space_coords`]). Negative lengths (from an
/// extrapolation) are taken as 0.
#[must_use]
pub fn space_points(frame: &SpaceFrame, c: &[f32]) -> Vec<Vec3> {
    let m = frame.relative.len() + 1;
    let v3 = |k: usize| Vec3::new(c[k], c[k + 1], c[k + 2]);
    let mut out: Vec<Vec3> = Vec::with_capacity(m + 1);
    out.push(v3(0));
    let mut q = (frame.first * Quat::from_scaled_axis(v3(3))).normalize();
    for j in 0..m {
        if j > 0 {
            let r = frame.relative[j - 1] * Quat::from_scaled_axis(v3(6 + m + 3 * (j - 1)));
            q = (q * r).normalize();
        }
        let next = out[j] + q * Vec3::X * c[6 + j].max(0.0);
        out.push(next);
    }
    out
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, PI};

    use super::*;

    fn length(p: &[Vec3]) -> f32 {
        p.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    fn close(a: &[Vec3], b: &[Vec3], eps: f32) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.distance(*y) < eps)
    }

    fn lerp(a: &[f32], b: &[f32], t: f32) -> Vec<f32> {
        a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect()
    }

    /// A straight limb along +x and the same limb bent 90° (left, about +z) at its middle.
    fn limb() -> (Vec<Vec3>, Vec<Vec3>) {
        let straight = vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)];
        let bent = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
        (straight, bent)
    }

    #[test]
    fn plane_coordinates_decode_to_their_curves() {
        let (a, b) = limb();
        let (frame, c) = plane_coords(&[&a, &b], Vec3::Z, 0).unwrap();
        assert!(close(&plane_points(&frame, &c[0]), &a, 1e-6));
        assert!(close(&plane_points(&frame, &c[1]), &b, 1e-6));
    }

    #[test]
    fn plane_in_between_keeps_length_and_halves_the_bend() {
        let (a, b) = limb();
        let (frame, c) = plane_coords(&[&a, &b], Vec3::Z, 0).unwrap();
        let mid = plane_points(&frame, &lerp(&c[0], &c[1], 0.5));
        assert!((length(&mid) - 2.0).abs() < 1e-6);
        // The second segment turned by 45°.
        let d = (mid[2] - mid[1]).normalize();
        assert!((d.angle_between(Vec3::X) - PI / 4.0).abs() < 1e-6, "{d}");
        // A lerp of the points would have shortened it to 1 + √2/2.
        let lerped: Vec<Vec3> = a.iter().zip(&b).map(|(p, q)| p.lerp(*q, 0.5)).collect();
        assert!((length(&lerped) - (1.0 + 0.5_f32.sqrt())).abs() < 1e-6);
    }

    #[test]
    fn plane_curves_with_different_nodes_share_the_union_of_parameters() {
        // Three nodes against five: the union has the nodes of both.
        let a = vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
        ];
        let b: Vec<Vec3> = (0..5)
            .map(|i| {
                let t = i as f32 / 4.0 * FRAC_PI_2;
                Vec3::new(t.sin(), 1.0 - t.cos(), 0.0) * (8.0 / PI)
            })
            .collect();
        let (frame, c) = plane_coords(&[&a, &b], Vec3::Z, 0).unwrap();
        assert_eq!(c[0].len(), c[1].len());
        let back_b = plane_points(&frame, &c[1]);
        // Every node of b is a node of the decoded curve.
        for p in &b {
            assert!(back_b.iter().any(|q| q.distance(*p) < 1e-5), "{p}");
        }
        let mid = plane_points(&frame, &lerp(&c[0], &c[1], 0.5));
        assert!((length(&mid) - 0.5 * (length(&a) + length(&b))).abs() < 1e-5);
    }

    #[test]
    fn plane_start_angles_unwrap_across_a_half_turn() {
        // The second curve starts just above −x: ψ₀ ≈ π − 0.01, and a third just below −x:
        // its start angle must continue past π, not jump to −π.
        let a = vec![Vec3::ZERO, Vec3::X];
        let b = vec![Vec3::ZERO, Vec3::new(-1.0, 0.01, 0.0)];
        let c = vec![Vec3::ZERO, Vec3::new(-1.0, -0.01, 0.0)];
        let (_, k) = plane_coords(&[&a, &b, &c], Vec3::Z, 0).unwrap();
        assert!((k[1][3] - (PI - 0.01)).abs() < 1e-4, "{}", k[1][3]);
        assert!((k[2][3] - (PI + 0.01)).abs() < 1e-4, "{}", k[2][3]);
    }

    #[test]
    fn plane_heights_off_the_plane_interpolate_linearly() {
        let a = vec![Vec3::ZERO, Vec3::X];
        let b = vec![Vec3::ZERO, Vec3::new(1.0, 0.0, 0.4)];
        let (frame, c) = plane_coords(&[&a, &b], Vec3::Z, 0).unwrap();
        let mid = plane_points(&frame, &lerp(&c[0], &c[1], 0.5));
        assert!((mid[1].z - 0.2).abs() < 1e-6);
    }

    #[test]
    fn space_coordinates_decode_to_their_curves() {
        let a = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 2.0),
        ];
        let b = vec![
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.1, 0.0, 1.5),
            Vec3::new(-1.0, 0.3, 1.5),
            Vec3::new(-1.0, 2.0, 1.0),
        ];
        let (frame, c) = space_coords(&[&a, &b], 0).unwrap();
        assert_eq!(c[0].len(), space_len(4));
        assert!(close(&space_points(&frame, &c[0]), &a, 1e-5));
        assert!(close(&space_points(&frame, &c[1]), &b, 1e-5));
        let (frame, c) = space_coords(&[&a, &b], 1).unwrap();
        assert!(close(&space_points(&frame, &c[0]), &a, 1e-5));
        assert!(close(&space_points(&frame, &c[1]), &b, 1e-5));
    }

    #[test]
    fn space_in_between_of_a_bent_limb_keeps_every_length() {
        let (a, b) = limb();
        let (frame, c) = space_coords(&[&a, &b], 0).unwrap();
        for k in 1..10 {
            let t = k as f32 / 10.0;
            let p = space_points(&frame, &lerp(&c[0], &c[1], t));
            assert!((p[0].distance(p[1]) - 1.0).abs() < 1e-6);
            assert!((p[1].distance(p[2]) - 1.0).abs() < 1e-6);
            // The bend stays in the plane of both keys and is t · 90°.
            assert!(p[2].z.abs() < 1e-6);
            let angle = (p[2] - p[1]).angle_between(Vec3::X);
            assert!((angle - t * FRAC_PI_2).abs() < 1e-5);
        }
    }

    #[test]
    fn space_counts_must_match_and_curves_need_length() {
        let (a, _) = limb();
        assert!(space_coords(&[&a, &a[..2]], 0).is_none());
        let point = vec![Vec3::ONE; 3];
        assert!(space_coords(&[&a, &point], 0).is_none());
        assert!(plane_coords(&[&a, &point], Vec3::Z, 0).is_none());
    }

    #[test]
    fn zero_length_segments_take_the_previous_direction() {
        let a = vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::new(2.0, 0.0, 0.0)];
        let (frame, c) = space_coords(&[&a], 0).unwrap();
        assert!(close(&space_points(&frame, &c[0]), &a, 1e-6));
    }
}
