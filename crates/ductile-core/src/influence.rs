//! Influence: which vertices a layer may move, and how strongly.
//!
//! An [`Influence`] combines an optional named vertex area (resolved to welded vertex
//! indices) with optional influence volumes. Its per-vertex weight is
//!
//! `w(v) = a(v) · g(v)`, where `a(v) ∈ {0, 1}` is area membership (1 when there is no area)
//! and `g(v)` is the union (maximum) of the volumes' falloff weights (1 when there are no
//! volumes). With `invert`, `g` becomes `1 − g`: the area minus the volumes.
//!
//! Only vertices with `w(v) > 0` are handed to the tool at all (the FFSD paper's "area of
//! influence" speed-up); all others keep their input position bit for bit.

use std::borrow::Cow;

use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::chunks::{CHUNK, PARALLEL_THRESHOLD, strictly_ascending, zeroed};
use crate::error::{CoreError, Result, check_finite};
use crate::spline::SplineControl;
use crate::volume_lanes::{Ids, LaneInfluence};

/// The shape of an influence volume in its own local frame (centred at the origin).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// A ball of the given radius.
    Sphere {
        /// Radius (> 0).
        radius: f32,
    },
    /// An axis-aligned box (in the local frame) with the given half extents.
    Box {
        /// Half extents along local X, Y, Z (each > 0).
        half_extents: Vec3,
    },
    /// A capsule around the local Y axis from `−half_height` to `+half_height`.
    Capsule {
        /// Radius (> 0).
        radius: f32,
        /// Half the length of the axis segment (≥ 0).
        half_height: f32,
    },
    /// A generalised cylinder around a curve: the points within `radius(t)` of the polyline
    /// through `points`, the radius varying linearly along each segment from one point's
    /// `radii` to the next one's (the ends are rounded, as a capsule's).
    Tube {
        /// The curve, at least 2 points (local frame).
        points: Vec<Vec3>,
        /// The radius at each point (> 0; as many as points).
        radii: Vec<f32>,
    },
}

impl Shape {
    /// Normalised distance of a local point: 0 at the centre (or axis), 1 on the boundary,
    /// above 1 outside. For the box it is the largest of `|x|/hx, |y|/hy, |z|/hz`.
    #[must_use]
    pub fn normalized_distance(&self, local: Vec3) -> f32 {
        match self {
            Shape::Sphere { radius } => local.length() / radius,
            Shape::Box { half_extents } => (local.abs() / *half_extents).max_element(),
            Shape::Capsule {
                radius,
                half_height,
            } => {
                let axis = Vec3::new(0.0, local.y.clamp(-half_height, *half_height), 0.0);
                (local - axis).length() / radius
            }
            Shape::Tube { points, radii } => tube_distance(points, radii, local),
        }
    }

    /// The local axis-aligned box holding every point of normalised distance ≤ 1:
    /// `(min, max)`.
    #[must_use]
    pub fn local_bounds(&self) -> (Vec3, Vec3) {
        let half = match self {
            Shape::Sphere { radius } => Vec3::splat(*radius),
            Shape::Box { half_extents } => *half_extents,
            Shape::Capsule {
                radius,
                half_height,
            } => Vec3::new(*radius, half_height + radius, *radius),
            Shape::Tube { points, radii } => {
                let r = Vec3::splat(radii.iter().copied().fold(0.0, f32::max));
                let lo = points
                    .iter()
                    .fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
                let hi = points
                    .iter()
                    .fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
                return (lo - r, hi + r);
            }
        };
        (-half, half)
    }

    /// The axis-aligned box, in the space `placement` maps into, that holds every point of the
    /// shape (normalised distance ≤ 1), padded by `1e-4` of its size (and `1e-6`) so that
    /// rounding never leaves a point of the shape outside it.
    #[must_use]
    pub fn bounds_in(&self, placement: &Affine3A) -> (Vec3, Vec3) {
        let (lo, hi) = self.local_bounds();
        let mut min = Vec3::splat(f32::INFINITY);
        let mut max = Vec3::splat(f32::NEG_INFINITY);
        for k in 0..8 {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let p = placement.transform_point3(corner);
            min = min.min(p);
            max = max.max(p);
        }
        let pad = (max - min) * 1e-4 + Vec3::splat(1e-6);
        (min - pad, max + pad)
    }

    /// Checks the shape's sizes (finite and positive). `what` names the volume in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        let positive = |name: &str, v: f32| -> Result<()> {
            check_finite(|| format!("{what}: {name}"), v)?;
            if v <= 0.0 {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: {name}"),
                    value: f64::from(v),
                    expected: "must be > 0",
                });
            }
            Ok(())
        };
        match self {
            Shape::Sphere { radius } => positive("radius", *radius),
            Shape::Box { half_extents } => {
                positive("half_extents.x", half_extents.x)?;
                positive("half_extents.y", half_extents.y)?;
                positive("half_extents.z", half_extents.z)
            }
            Shape::Tube { points, radii } => {
                if points.len() < 2 || points.len() != radii.len() || points.len() > MAX_TUBE_POINTS
                {
                    return Err(CoreError::Degenerate {
                        what: what.to_owned(),
                        problem: format!(
                            "a tube needs 2 to {MAX_TUBE_POINTS} points and one radius per point, found {} points and {} radii",
                            points.len(),
                            radii.len()
                        ),
                    });
                }
                for (i, p) in points.iter().enumerate() {
                    crate::error::check_finite_vec3(|| format!("{what}: point {i}"), *p)?;
                }
                for (i, &r) in radii.iter().enumerate() {
                    positive(&format!("radius {i}"), r)?;
                }
                Ok(())
            }
            Shape::Capsule {
                radius,
                half_height,
            } => {
                let (radius, half_height) = (*radius, *half_height);
                positive("radius", radius)?;
                check_finite(|| format!("{what}: half_height"), half_height)?;
                if half_height < 0.0 {
                    return Err(CoreError::OutOfRange {
                        what: format!("{what}: half_height"),
                        value: f64::from(half_height),
                        expected: "must be >= 0",
                    });
                }
                Ok(())
            }
        }
    }
}

/// The most points a tube volume may have.
pub const MAX_TUBE_POINTS: usize = 1024;

/// Normalised distance of `p` from a tube: the smallest `|p − c| / r(c)` over the closest
/// point `c` of each segment, with the radius interpolated linearly along the segment.
fn tube_distance(points: &[Vec3], radii: &[f32], p: Vec3) -> f32 {
    let mut best = f32::INFINITY;
    for (w, r) in points.windows(2).zip(radii.windows(2)) {
        let (a, b) = (w[0], w[1]);
        let ab = b - a;
        let len2 = ab.length_squared();
        let t = if len2 > 0.0 {
            ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c = a + ab * t;
        let radius = r[0] + (r[1] - r[0]) * t;
        best = best.min(p.distance(c) / radius);
    }
    best
}

/// How the weight falls from 1 to 0 between the inner part of a volume and its boundary.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub enum Falloff {
    /// Weight 1 everywhere inside the volume, 0 outside.
    None,
    /// Weight falls linearly with normalised distance.
    Linear,
    /// Weight falls along the smoothstep `s²(3 − 2s)`: zero slope at both ends.
    #[default]
    Smooth,
    /// A custom curve: the weight is the spline control `F(s)` (clamped to `[0, 1]`) of the
    /// same `s` (0 on the boundary, 1 at the inner plateau), so `F(s) = s` is `Linear`.
    Curve(SplineControl),
}

impl Falloff {
    /// Weight at normalised distance `t`, with full weight up to `inner` (in `[0, 1)`):
    /// `s = (1 − t) / (1 − inner)` clamped to `[0, 1]`, then `None → [t ≤ 1]`, `Linear → s`,
    /// `Smooth → s²(3 − 2s)`, `Curve(F) → F(s)` clamped to `[0, 1]`.
    #[must_use]
    pub fn weight(&self, t: f32, inner: f32) -> f32 {
        if t > 1.0 {
            return 0.0;
        }
        if t <= inner {
            return 1.0;
        }
        let s = ((1.0 - t) / (1.0 - inner)).clamp(0.0, 1.0);
        match self {
            Falloff::None => 1.0,
            Falloff::Linear => s,
            Falloff::Smooth => s * s * (3.0 - 2.0 * s),
            Falloff::Curve(f) => f.eval(s).clamp(0.0, 1.0),
        }
    }

    /// The falloff's name for messages and menus.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Falloff::None => "none",
            Falloff::Linear => "linear",
            Falloff::Smooth => "smooth",
            Falloff::Curve(_) => "curve",
        }
    }

    /// Checks a custom curve's control (finite values, degree). `what` names the influence.
    pub fn validate(&self, what: &str) -> Result<()> {
        match self {
            Falloff::Curve(f) => f.validate(&format!("{what}: falloff curve")),
            _ => Ok(()),
        }
    }
}

/// An influence volume placed in mesh space.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    /// The volume's shape in its local frame.
    pub shape: Shape,
    /// Mesh space → the volume's local frame (the inverse of its placement).
    pub to_local: Affine3A,
}

impl Volume {
    /// A volume whose local frame is placed in mesh space by `placement`. Fails when the
    /// placement is singular or the shape invalid.
    pub fn new(shape: Shape, placement: Affine3A, what: &str) -> Result<Self> {
        shape.validate(what)?;
        let det = placement.matrix3.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!("its transform is singular (determinant {det})"),
            });
        }
        Ok(Self {
            shape,
            to_local: placement.inverse(),
        })
    }

    /// Normalised distance of a mesh-space point (see [`Shape::normalized_distance`]).
    #[must_use]
    pub fn normalized_distance(&self, p: Vec3) -> f32 {
        self.shape
            .normalized_distance(self.to_local.transform_point3(p))
    }

    /// A mesh-space box outside which [`Volume::normalized_distance`] is above 1: the shape's
    /// bounds placed in mesh space ([`Shape::bounds_in`]), padded by 0.1 % of their size and
    /// of their distance from the origin so that rounding in the transform to the local frame
    /// cannot bring a point outside the box to distance 1.
    #[must_use]
    pub fn cull_box(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.shape.bounds_in(&self.to_local.inverse());
        let pad = (hi - lo) * 1e-3 + (lo.abs().max(hi.abs())) * 1e-3 + Vec3::splat(1e-6);
        (lo - pad, hi + pad)
    }
}

/// The vertices `ids` (ascending, in range of `positions`) of positive `weight`, in order,
/// with their weights. Generic over the iterator, so the loop compiles without a call per
/// vertex. With `reuse` (an earlier mask of the same influence and its stale vertices, see
/// [`Influence::mask_reusing`]), a vertex that is not stale takes its earlier weight (0
/// where it was not in that mask) without reading its position; `start` is at most the
/// first id.
fn gather(
    ids: impl Iterator<Item = u32>,
    positions: &[Vec3],
    weight: &impl Fn(Vec3) -> f32,
    reuse: Option<(&Mask, &[bool])>,
    start: u32,
) -> Mask {
    let mut mask = Mask::default();
    let mut earlier = reuse.map(|(old, stale)| Earlier::new(old, stale, start));
    for i in ids {
        let w = match &mut earlier {
            Some(e) if !e.is_stale(i) => e.weight(i),
            _ => weight(positions[i as usize]),
        };
        if w > 0.0 {
            mask.indices.push(i);
            mask.weights.push(w);
        }
    }
    mask
}

/// The weights an earlier mask gave, looked up for ascending vertices (what a mask made from
/// an earlier one copies, [`Influence::mask_reusing`]).
pub(crate) struct Earlier<'a> {
    old: &'a Mask,
    stale: &'a [bool],
    /// The first entry of `old` not below the vertices looked up so far.
    next: usize,
}

impl<'a> Earlier<'a> {
    /// Lookups of `old` for the vertices from `start` on, with `stale` the vertices that
    /// moved since (a vertex past its end counts as stale).
    pub(crate) fn new(old: &'a Mask, stale: &'a [bool], start: u32) -> Self {
        Self {
            next: old.indices.partition_point(|&x| x < start),
            old,
            stale,
        }
    }

    /// Whether vertex `i` moved, so that its weight must be computed again.
    #[inline(always)]
    pub(crate) fn is_stale(&self, i: u32) -> bool {
        self.stale.get(i as usize).copied().unwrap_or(true)
    }

    /// Bit `j` set when vertex `ids[j]` is stale (at most 32 vertices).
    #[inline(always)]
    pub(crate) fn stale_lanes(&self, ids: &[u32]) -> u32 {
        ids.iter()
            .enumerate()
            .fold(0, |bits, (j, &i)| bits | (u32::from(self.is_stale(i)) << j))
    }

    /// [`Earlier::stale_lanes`] of consecutive vertices `ids`: their flags read as one
    /// 128-bit word when they are 16 and in range, so that a group where nothing or
    /// everything moved costs a load and a comparison.
    #[inline(always)]
    pub(crate) fn stale_run(&self, ids: &[u32]) -> u32 {
        const ALL: u128 = u128::from_le_bytes([1; 16]);
        let at = ids.first().map_or(0, |&i| i as usize);
        if ids.len() == 16
            && let Some(flags) = self.stale.get(at..at + 16)
            && let Ok(bytes) = <[u8; 16]>::try_from(bytemuck::cast_slice::<bool, u8>(flags))
        {
            match u128::from_le_bytes(bytes) {
                0 => return 0,
                ALL => return 0xffff,
                _ => {}
            }
        }
        self.stale_lanes(ids)
    }

    /// Appends `old`'s entries from vertex `first` to vertex `last` (both included) to
    /// `mask`: the mask of a run of vertices none of which is stale. Every entry of `old` in
    /// that span must be a vertex of the run (true when `old` was made from the same
    /// candidates: the same area, or every vertex), and its weight is positive, as in every
    /// mask. `first` must be at least every vertex looked up before.
    #[inline(always)]
    pub(crate) fn copy_run(&mut self, first: u32, last: u32, mask: &mut Mask) {
        let indices = &self.old.indices;
        while indices.get(self.next).is_some_and(|&x| x < first) {
            self.next += 1;
        }
        let start = self.next;
        while indices.get(self.next).is_some_and(|&x| x <= last) {
            self.next += 1;
        }
        mask.indices.extend_from_slice(&indices[start..self.next]);
        mask.weights
            .extend_from_slice(&self.old.weights[start..self.next]);
    }

    /// `old`'s weight of `i` (0 when `i` is not in it); `i` at least every earlier one.
    #[inline(always)]
    pub(crate) fn weight(&mut self, i: u32) -> f32 {
        let indices = &self.old.indices;
        while indices.get(self.next).is_some_and(|&x| x < i) {
            self.next += 1;
        }
        match indices.get(self.next) {
            Some(&x) if x == i => self.old.weights[self.next],
            _ => 0.0,
        }
    }
}

/// A layer's influence, resolved to mesh space and welded vertex indices.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Influence {
    /// Volumes (their union); empty means "no volume restriction".
    pub volumes: Vec<Volume>,
    /// Sorted welded vertex indices of the named area, if any (a mask sorts and makes unique
    /// a copy of one that is not).
    pub area: Option<Vec<u32>>,
    /// Falloff shape inside the volumes.
    pub falloff: Falloff,
    /// Normalised distance up to which the weight stays 1, in `[0, 1)`.
    pub inner: f32,
    /// Use `1 − g` for the volume part (the area minus the volumes).
    pub invert: bool,
}

/// The box of each [`CHUNK`] of consecutive positions, kept beside positions that change a
/// layer at a time, so that a mask passes over the chunks that no volume's cull box reaches
/// without reading their positions ([`Influence::mask_bounded`]). Meshes keep neighbouring
/// vertices near each other in memory (on the suite's million-vertex head, half the chunks'
/// boxes hold less than 0.03 % of the mesh's box), and a stack's volumes are mostly small.
///
/// A box is the least and greatest of each coordinate over the chunk, NaN left out: every
/// position with no NaN lies in it, and a position with a NaN is in no cull box. After a
/// layer moves some vertices, [`ChunkBounds::mark`] flags their chunks and
/// [`ChunkBounds::refresh`] computes those boxes again.
#[derive(Debug, Clone)]
pub struct ChunkBounds {
    /// Per chunk, its least and greatest coordinates.
    boxes: Vec<(Vec3, Vec3)>,
    /// Per chunk, whether its positions changed since its box was computed.
    stale: Vec<bool>,
    /// The number of positions the boxes are for.
    len: usize,
}

impl ChunkBounds {
    /// The boxes of `positions`' chunks.
    #[must_use]
    pub fn new(positions: &[Vec3]) -> Self {
        Self {
            boxes: positions.par_chunks(CHUNK).map(chunk_box).collect(),
            stale: vec![false; positions.len().div_ceil(CHUNK)],
            len: positions.len(),
        }
    }

    /// Flags the chunks of the vertices `changed` (ascending, as a mask's indices always are)
    /// as stale: a binary search (about 20 reads) per flagged chunk finds the next vertex
    /// past it, instead of a read of every index (3 ms a stack evaluation on one thread, on
    /// the suite's million-vertex stack).
    pub fn mark(&mut self, changed: &[u32]) {
        debug_assert!(changed.is_sorted(), "a mask's indices ascend");
        let mut rest = changed;
        while let Some(&i) = rest.first() {
            let c = i as usize / CHUNK;
            let Some(stale) = self.stale.get_mut(c) else {
                // Ascending: every vertex left is past the last chunk too.
                break;
            };
            *stale = true;
            let end = (c + 1) * CHUNK;
            rest = &rest[rest.partition_point(|&j| (j as usize) < end)..];
        }
    }

    /// Flags the chunks that hold any of the vertices `span` as stale.
    pub fn mark_span(&mut self, span: std::ops::Range<usize>) {
        if span.is_empty() {
            return;
        }
        let end = span.end.div_ceil(CHUNK).min(self.stale.len());
        for stale in self.stale.iter_mut().take(end).skip(span.start / CHUNK) {
            *stale = true;
        }
    }

    /// Computes the boxes of the stale chunks again from `positions`, or every box when
    /// their number changed.
    pub fn refresh(&mut self, positions: &[Vec3]) {
        if positions.len() != self.len {
            *self = Self::new(positions);
            return;
        }
        let stale: Vec<usize> = (0..self.stale.len()).filter(|&c| self.stale[c]).collect();
        let boxes: Vec<(Vec3, Vec3)> = stale
            .par_iter()
            .map(|&c| chunk_box(&positions[c * CHUNK..((c + 1) * CHUNK).min(self.len)]))
            .collect();
        for (c, b) in stale.into_iter().zip(boxes) {
            self.boxes[c] = b;
            self.stale[c] = false;
        }
    }

    /// Whether the box of chunk `c` holds a point of the box `lo..=hi` (always, for a
    /// stale or unknown chunk).
    fn reaches(&self, c: usize, lo: Vec3, hi: Vec3) -> bool {
        match (self.boxes.get(c), self.stale.get(c)) {
            (Some(&(min, max)), Some(false)) => max.cmpge(lo).all() && min.cmple(hi).all(),
            _ => true,
        }
    }
}

/// The least and greatest of each coordinate of `points`, NaN left out; `+∞` and `−∞` for
/// no number. In [`pulp`]'s runtime dispatch (the same code at each width): `n` points (the
/// register's lanes) at a time, in two sets of three registers of running bounds, each set
/// taking every other group of `n` points. Read as floats, the points are `x, y, z, x, …`, so
/// lane `j` of register `r` holds coordinate `(r·n + j) mod 3` throughout. Which of `−0` and
/// `+0` a bound keeps may depend on the order; the boxes are only compared, where the two
/// are equal.
///
/// The running bounds are `min(x, lo)` and `max(x, hi)`: one instruction each, where the
/// kept-by-compare form (`x < lo`, a select) took a compare and a blend that waited on each
/// other; two independent sets let the processor overlap them. x86's `minps(x, lo)` is
/// `x < lo ? x : lo` (the second operand when either is NaN), the compare form's very result,
/// zeros included, so NaN stays out. An instruction set whose minimum returns NaN (NEON's
/// `fmin`) leaves a NaN in a register lane instead, which would hide every later point of that
/// lane from the bounds: a NaN in any lane sends the points to be read again by compare and
/// select (`docs/performance.md`, thirty-second session: the compare form took 4 % of a
/// two-thread evaluation's samples).
pub(crate) fn chunk_box(points: &[Vec3]) -> (Vec3, Vec3) {
    pulp::Arch::new().dispatch(ChunkBox(points))
}

/// [`chunk_box`] for one dispatched width.
struct ChunkBox<'a>(&'a [Vec3]);

impl pulp::WithSimd for ChunkBox<'_> {
    type Output = (Vec3, Vec3);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, s: S) -> (Vec3, Vec3) {
        let coords: &[f32] = bytemuck::cast_slice(self.0);
        match box_of::<S, false>(s, coords) {
            (bounds, false) => bounds,
            (_, true) => box_of::<S, true>(s, coords).0,
        }
    }
}

/// The bounds of [`chunk_box`] over `coords` (points as `x, y, z, x, …`): running bounds by
/// compare and select (`SELECT`: NaN always left out) or by minimum and maximum; with whether
/// a register lane ended NaN (then the bounds miss points: see [`chunk_box`]).
#[inline(always)]
fn box_of<S: pulp::Simd, const SELECT: bool>(s: S, coords: &[f32]) -> ((Vec3, Vec3), bool) {
    let n = S::F32_LANES;
    let mut lo = [[s.splat_f32s(f32::INFINITY); 3]; 2];
    let mut hi = [[s.splat_f32s(f32::NEG_INFINITY); 3]; 2];
    let mut pairs = coords.chunks_exact(6 * n);
    for pair in &mut pairs {
        for (set, g) in pair.chunks_exact(3 * n).enumerate() {
            for r in 0..3 {
                let x: S::f32s =
                    bytemuck::pod_read_unaligned(bytemuck::cast_slice(&g[r * n..(r + 1) * n]));
                let (l, h) = (lo[set][r], hi[set][r]);
                (lo[set][r], hi[set][r]) = if SELECT {
                    (
                        s.select_f32s(s.less_than_f32s(x, l), x, l),
                        s.select_f32s(s.greater_than_f32s(x, h), x, h),
                    )
                } else {
                    (s.min_f32s(x, l), s.max_f32s(x, h))
                };
            }
        }
    }
    // The registers' lanes in order (both sets), then the floats left over: float `f` of
    // either is coordinate `f mod 3`.
    let lo_lanes: &[f32] = bytemuck::cast_slice(&lo);
    let hi_lanes: &[f32] = bytemuck::cast_slice(&hi);
    let nan = lo_lanes.iter().chain(hi_lanes).any(|v| v.is_nan());
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let rest = pairs.remainder();
    for (f, (&l, &h)) in lo_lanes
        .iter()
        .zip(hi_lanes)
        .chain(rest.iter().zip(rest))
        .enumerate()
    {
        let k = f % 3;
        lo[k] = if l < lo[k] { l } else { lo[k] };
        hi[k] = if h > hi[k] { h } else { hi[k] };
    }
    ((Vec3::from_array(lo), Vec3::from_array(hi)), nan)
}

/// The vertices a layer acts on and their weights in `(0, 1]`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mask {
    /// Welded vertex indices, ascending.
    pub indices: Vec<u32>,
    /// Weight of each vertex in `indices`.
    pub weights: Vec<f32>,
}

impl Mask {
    /// Every vertex with weight 1.
    #[must_use]
    pub fn all(count: usize) -> Self {
        Self {
            indices: (0..count as u32).collect(),
            weights: vec![1.0; count],
        }
    }

    /// Number of active vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when no vertex is active.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
}

impl Influence {
    /// Weight `g(v)` of the volume part at `p` (1 when there are no volumes), inverted when
    /// asked.
    #[must_use]
    pub fn volume_weight(&self, p: Vec3) -> f32 {
        if self.volumes.is_empty() {
            return 1.0;
        }
        let g = self
            .volumes
            .iter()
            .map(|v| self.falloff.weight(v.normalized_distance(p), self.inner))
            .fold(0.0_f32, f32::max);
        if self.invert { 1.0 - g } else { g }
    }

    /// The mask over `positions` (welded, the layer's input): every vertex with `w(v) > 0`.
    #[must_use]
    pub fn mask(&self, positions: &[Vec3]) -> Mask {
        self.mask_in(self.area.as_deref(), positions)
    }

    /// [`Influence::mask`], passing over the chunks of vertices whose box in `bounds` (of
    /// these `positions`, refreshed) no volume's cull box reaches: their weight is that of
    /// no volume (0, or 1 when inverted) without a position read. The same mask. The boxes
    /// serve the masks of volumes over every vertex of a mesh above the parallel threshold,
    /// with a falloff that has a lane form; other masks, and boxes of another vertex count,
    /// go as [`Influence::mask`] does.
    #[must_use]
    pub fn mask_bounded(&self, positions: &[Vec3], bounds: &ChunkBounds) -> Mask {
        self.mask_with(self.area.as_deref(), positions, None, Some(bounds))
    }

    /// [`Influence::mask`] of `positions` whose box, as [`ChunkBounds`] computes one (NaN
    /// left out), is `lo..=hi`: when no volume's cull box reaches that box and the falloff
    /// has a lane form, every vertex gets the weight of no volume (0, or 1 when inverted)
    /// without a position read. The same mask.
    #[must_use]
    pub fn mask_in_box(&self, positions: &[Vec3], (lo, hi): (Vec3, Vec3)) -> Mask {
        let culled = LaneInfluence::new(self)
            .filter(|_| self.area.is_none())
            .and_then(|lanes| lanes.culled(|l, h| hi.cmpge(l).all() && lo.cmple(h).all()));
        match culled {
            Some(w) if w > 0.0 => Mask {
                indices: (0..positions.len() as u32).collect(),
                weights: vec![w; positions.len()],
            },
            Some(_) => Mask::default(),
            None => self.mask(positions),
        }
    }

    /// Whether [`Influence::mask_bounded`] reads the chunk boxes on `n` positions: volumes
    /// over every vertex of a mesh above the parallel threshold, with a falloff that has a
    /// lane form (a caller builds the boxes only for such masks).
    #[must_use]
    pub fn reads_chunk_bounds(&self, n: usize) -> bool {
        self.area.is_none()
            && !self.volumes.is_empty()
            && !matches!(self.falloff, Falloff::Curve(_))
            && n >= PARALLEL_THRESHOLD
    }

    /// [`Influence::mask`] with `area` (sorted welded indices) in place of [`Influence::area`],
    /// for a caller that keeps the area's vertices elsewhere (shared between layers).
    #[must_use]
    pub fn mask_in(&self, area: Option<&[u32]>, positions: &[Vec3]) -> Mask {
        self.mask_with(area, positions, None, None)
    }

    /// [`Influence::mask_in`] on `positions`, given `old`, this influence's mask (with the
    /// same `area`) on earlier positions that differ from `positions` only at the `stale`
    /// vertices (`stale[v]`; a vertex past its end counts as stale). A vertex's weight is a
    /// function of its own position, so a vertex that is not stale keeps its old weight (or
    /// stays out): only the stale ones are weighed again. The same bits as
    /// [`Influence::mask_in`].
    #[must_use]
    pub fn mask_reusing(
        &self,
        area: Option<&[u32]>,
        positions: &[Vec3],
        old: &Mask,
        stale: &[bool],
    ) -> Mask {
        self.mask_with(area, positions, Some((old, stale)), None)
    }

    fn mask_with(
        &self,
        area: Option<&[u32]>,
        positions: &[Vec3],
        reuse: Option<(&Mask, &[bool])>,
        bounds: Option<&ChunkBounds>,
    ) -> Mask {
        let n = positions.len();
        let bounds = bounds.filter(|b| b.len == n);
        // A mask's indices ascend (`ChunkBounds::mark` and the reuse of an earlier mask read
        // them so): an area given out of order or with repeats (a resolved area never is)
        // is sorted and made unique first.
        let area: Option<Cow<'_, [u32]>> = area.map(|a| {
            if strictly_ascending(a) {
                Cow::Borrowed(a)
            } else {
                let mut copy = a.to_vec();
                copy.sort_unstable();
                copy.dedup();
                Cow::Owned(copy)
            }
        });
        let area = area.as_deref();
        if self.volumes.is_empty() {
            // `g(v) = 1` everywhere: the mask is the area (or every vertex), weight 1.
            let indices: Vec<u32> = match area {
                // Every index in range (the usual case): a plain copy.
                Some(area) if area.last().is_none_or(|&i| (i as usize) < n) => area.to_vec(),
                Some(area) => area.iter().copied().filter(|&i| (i as usize) < n).collect(),
                None => (0..n as u32).collect(),
            };
            let weights = vec![1.0; indices.len()];
            return Mask { indices, weights };
        }
        // Sixteen vertices at a time where the falloff has a lane form (the same bits; a
        // custom spline falloff goes vertex by vertex).
        let lanes = LaneInfluence::new(self)
            .filter(|_| area.is_none_or(|a| a.iter().all(|&i| (i as usize) < n)));
        if let Some(lanes) = &lanes {
            return gather_lanes(lanes, area, n, positions, reuse, bounds);
        }
        // Outside every volume's (padded) box the volume weight `g` is exactly 0, so such a
        // vertex is decided by a box test alone: weight 0, or 1 when inverted (`1 − 0`), the
        // very bits `volume_weight` gives it.
        let boxes: Vec<(Vec3, Vec3)> = self.volumes.iter().map(Volume::cull_box).collect();
        let outside = if self.invert { 1.0 } else { 0.0 };
        let weight = |p: Vec3| {
            if boxes
                .iter()
                .any(|(lo, hi)| p.cmpge(*lo).all() && p.cmple(*hi).all())
            {
                self.volume_weight(p)
            } else {
                outside
            }
        };
        let candidates = area.map_or(n, <[u32]>::len);
        if candidates < PARALLEL_THRESHOLD {
            return match area {
                Some(area) => gather(
                    area.iter().copied().filter(|&i| (i as usize) < n),
                    positions,
                    &weight,
                    reuse,
                    0,
                ),
                None => gather(0..n as u32, positions, &weight, reuse, 0),
            };
        }
        // Chunks in parallel, one task each (as in `gather_lanes`), each gathering its own
        // part in order, then copied in order into the mask (in parallel too).
        let parts: Vec<Mask> = match area {
            Some(area) => area
                .par_chunks(CHUNK)
                .with_max_len(1)
                .map(|c| {
                    gather(
                        c.iter().copied().filter(|&i| (i as usize) < n),
                        positions,
                        &weight,
                        reuse,
                        c[0],
                    )
                })
                .collect(),
            None => (0..n.div_ceil(CHUNK))
                .into_par_iter()
                .with_max_len(1)
                .map(|c| {
                    let end = ((c + 1) * CHUNK).min(n);
                    let start = (c * CHUNK) as u32;
                    gather(start..end as u32, positions, &weight, reuse, start)
                })
                .collect(),
        };
        join(&parts)
    }

    /// Checks `inner` and every volume. `what` names the layer in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        check_finite(|| format!("{what}: influence inner"), self.inner)?;
        if !(0.0..1.0).contains(&self.inner) {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: influence inner"),
                value: f64::from(self.inner),
                expected: "must be in [0, 1)",
            });
        }
        for (i, v) in self.volumes.iter().enumerate() {
            v.shape.validate(&format!("{what}: volume {i}"))?;
        }
        self.falloff.validate(what)
    }
}

/// [`Influence::mask_in`] on the lanes: the candidates (`area`, all in range, or every
/// vertex) in parallel chunks above [`PARALLEL_THRESHOLD`], joined in order.
fn gather_lanes(
    lanes: &LaneInfluence,
    area: Option<&[u32]>,
    n: usize,
    positions: &[Vec3],
    reuse: Option<(&Mask, &[bool])>,
    bounds: Option<&ChunkBounds>,
) -> Mask {
    let gather = |ids| lanes.gather(ids, positions, reuse);
    // In parallel, one task per chunk (`with_max_len(1)`): chunks that no cull box reaches
    // cost nothing, so equal splits of the chunks are not equal work, and rayon's default
    // split could leave a thread alone with a costly part (see `fused.rs`).
    match area {
        Some(area) if area.len() < PARALLEL_THRESHOLD => gather(Ids::List(area)),
        None if n < PARALLEL_THRESHOLD => gather(Ids::Range(0, n as u32)),
        Some(area) => join(
            &area
                .par_chunks(CHUNK)
                .with_max_len(1)
                .map(|c| gather(Ids::List(c)))
                .collect::<Vec<_>>(),
        ),
        None => join(
            &(0..n.div_ceil(CHUNK))
                .into_par_iter()
                .with_max_len(1)
                .map(|c| {
                    let (start, end) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                    // A chunk no cull box reaches: every vertex has the weight of no volume.
                    let culled = bounds.and_then(|b| lanes.culled(|lo, hi| b.reaches(c, lo, hi)));
                    match culled {
                        Some(w) if w > 0.0 => Mask {
                            indices: (start as u32..end as u32).collect(),
                            weights: vec![w; end - start],
                        },
                        Some(_) => Mask::default(),
                        None => gather(Ids::Range(start as u32, end as u32)),
                    }
                })
                .collect::<Vec<_>>(),
        ),
    }
}

/// The masks of consecutive chunks, copied in order into one (in parallel).
fn join(parts: &[Mask]) -> Mask {
    let len = parts.iter().map(Mask::len).sum();
    let mut mask = Mask {
        indices: zeroed(len),
        weights: zeroed(len),
    };
    let mut jobs = Vec::with_capacity(parts.len());
    let (mut indices, mut weights) = (&mut mask.indices[..], &mut mask.weights[..]);
    for p in parts {
        let (i, rest_i) = std::mem::take(&mut indices).split_at_mut(p.len());
        let (w, rest_w) = std::mem::take(&mut weights).split_at_mut(p.len());
        jobs.push((i, w, p));
        (indices, weights) = (rest_i, rest_w);
    }
    jobs.into_par_iter().for_each(|(i, w, p)| {
        i.copy_from_slice(&p.indices);
        w.copy_from_slice(&p.weights);
    });
    mask
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn bounds_hold_every_point_of_a_placed_shape() {
        let placement = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.5, 0.4, 2.0),
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            Vec3::new(-3.0, 0.5, 7.0),
        );
        let shapes = [
            Shape::Sphere { radius: 0.7 },
            Shape::Box {
                half_extents: Vec3::new(0.2, 1.0, 0.5),
            },
            Shape::Capsule {
                radius: 0.3,
                half_height: 0.8,
            },
        ];
        for shape in shapes {
            let (lo, hi) = shape.bounds_in(&placement);
            let volume = Volume::new(shape.clone(), placement, "v").unwrap();
            let (a, b) = shape.local_bounds();
            // A grid over the local bounds: every point of the shape lies in the box.
            for i in 0..=20 {
                for j in 0..=20 {
                    for k in 0..=20 {
                        let f = Vec3::new(i as f32, j as f32, k as f32) / 20.0;
                        let p = placement.transform_point3(a + (b - a) * f);
                        if volume.normalized_distance(p) <= 1.0 {
                            assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "{shape:?} {p}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_tube_measures_distance_to_its_curve_in_its_varying_radius() {
        let tube = Shape::Tube {
            points: vec![
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 2.0, 0.0),
            ],
            radii: vec![0.5, 1.0, 0.5],
        };
        tube.validate("t").unwrap();
        // On the curve: 0. Halfway along the first segment the radius is 0.75.
        assert_eq!(tube.normalized_distance(Vec3::new(1.0, 0.0, 0.0)), 0.0);
        assert!((tube.normalized_distance(Vec3::new(1.0, 0.0, 0.75)) - 1.0).abs() < 1e-6);
        // Past the ends the tube is rounded: distance to the end point over its radius.
        assert!((tube.normalized_distance(Vec3::new(-0.25, 0.0, 0.0)) - 0.5).abs() < 1e-6);
        // The second segment is nearer for a point beside it.
        assert!((tube.normalized_distance(Vec3::new(2.5, 1.0, 0.0)) - 0.5 / 0.75).abs() < 1e-6);
        let (lo, hi) = tube.local_bounds();
        assert_eq!(
            (lo, hi),
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(3.0, 3.0, 1.0))
        );
        for bad in [
            Shape::Tube {
                points: vec![Vec3::ZERO],
                radii: vec![1.0],
            },
            Shape::Tube {
                points: vec![Vec3::ZERO, Vec3::X],
                radii: vec![1.0],
            },
            Shape::Tube {
                points: vec![Vec3::ZERO, Vec3::X],
                radii: vec![1.0, 0.0],
            },
        ] {
            assert!(bad.validate("t").is_err(), "{bad:?}");
        }
    }

    #[test]
    fn a_curve_falloff_follows_its_spline() {
        let linear = Falloff::Curve(SplineControl::identity(4, 3));
        for k in 0..=10 {
            let t = k as f32 / 10.0;
            let a = linear.weight(t, 0.2);
            let b = Falloff::Linear.weight(t, 0.2);
            assert!((a - b).abs() < 1e-5, "{t}: {a} vs {b}");
        }
        // Values outside [0, 1] are clamped; a bad control is refused.
        let over = Falloff::Curve(SplineControl::constant(1.5));
        assert_eq!(over.weight(0.5, 0.0), 1.0);
        let bad = Falloff::Curve(SplineControl {
            values: vec![f32::NAN, 1.0],
            degree: 1,
        });
        assert!(bad.validate("layer").is_err());
    }

    #[test]
    fn falloff_shapes() {
        assert_eq!(Falloff::None.weight(0.99, 0.0), 1.0);
        assert_eq!(Falloff::None.weight(1.01, 0.0), 0.0);
        assert!((Falloff::Linear.weight(0.75, 0.5) - 0.5).abs() < 1e-6);
        assert!((Falloff::Smooth.weight(0.5, 0.0) - 0.5).abs() < 1e-6);
        assert_eq!(Falloff::Smooth.weight(0.2, 0.3), 1.0);
    }

    #[test]
    fn shapes_measure_normalised_distance() {
        let s = Shape::Sphere { radius: 2.0 };
        assert!((s.normalized_distance(Vec3::new(0.0, 1.0, 0.0)) - 0.5).abs() < 1e-6);
        let b = Shape::Box {
            half_extents: Vec3::new(1.0, 2.0, 4.0),
        };
        assert!((b.normalized_distance(Vec3::new(0.5, 1.8, 1.0)) - 0.9).abs() < 1e-6);
        let c = Shape::Capsule {
            radius: 1.0,
            half_height: 2.0,
        };
        assert!((c.normalized_distance(Vec3::new(0.5, 1.5, 0.0)) - 0.5).abs() < 1e-6);
        assert!((c.normalized_distance(Vec3::new(0.0, 3.0, 0.0)) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn area_times_inverted_volume() {
        let positions: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let vol = Volume::new(Shape::Sphere { radius: 1.5 }, Affine3A::IDENTITY, "v").unwrap();
        let inf = Influence {
            volumes: vec![vol],
            area: Some(vec![0, 1, 2, 3]),
            falloff: Falloff::None,
            inner: 0.0,
            invert: true,
        };
        let m = inf.mask(&positions);
        assert_eq!(m.indices, vec![2, 3]);
        assert_eq!(m.weights, vec![1.0, 1.0]);
    }

    #[test]
    fn singular_volume_is_refused() {
        let e = Volume::new(
            Shape::Sphere { radius: 1.0 },
            Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)),
            "v",
        );
        assert!(matches!(e, Err(CoreError::Degenerate { .. })));
        assert!(Shape::Sphere { radius: -1.0 }.validate("s").is_err());
    }

    #[test]
    fn an_area_without_volumes_is_its_vertices_in_range_at_weight_one() {
        let positions = vec![Vec3::ZERO; 10];
        let inf = |area: Vec<u32>| Influence {
            area: Some(area),
            ..Influence::default()
        };
        let m = inf(vec![1, 4, 9]).mask(&positions);
        assert_eq!((m.indices, m.weights), (vec![1, 4, 9], vec![1.0; 3]));
        // Indices past the mesh (an area of a re-imported, smaller mesh) are left out.
        let m = inf(vec![1, 12, 4, 10, 9]).mask(&positions);
        assert_eq!((m.indices, m.weights), (vec![1, 4, 9], vec![1.0; 3]));
        assert!(inf(vec![]).mask(&positions).is_empty());
    }

    #[test]
    fn long_masks_match_the_per_vertex_weights() {
        let n = PARALLEL_THRESHOLD + 1000;
        let positions: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i % 200) as f32 * 0.01, (i / 200) as f32 * 0.01, 0.0))
            .collect();
        let vol = Volume::new(
            Shape::Sphere { radius: 0.5 },
            Affine3A::from_translation(Vec3::new(1.0, 0.4, 0.0)),
            "v",
        )
        .unwrap();
        for (area, volumes) in [
            (None, vec![vol.clone()]),
            (
                Some((0..n as u32).step_by(1).collect::<Vec<_>>()),
                vec![vol.clone()],
            ),
            (Some((0..n as u32 + 5).step_by(2).collect()), vec![]),
            (None, vec![]),
        ] {
            let inf = Influence {
                volumes,
                area,
                falloff: Falloff::Smooth,
                inner: 0.2,
                invert: false,
            };
            let m = inf.mask(&positions);
            let candidates: Vec<u32> = match &inf.area {
                Some(a) => a.iter().copied().filter(|&i| (i as usize) < n).collect(),
                None => (0..n as u32).collect(),
            };
            let expected: Vec<(u32, f32)> = candidates
                .into_iter()
                .map(|i| (i, inf.volume_weight(positions[i as usize])))
                .filter(|&(_, w)| w > 0.0)
                .collect();
            assert!(!expected.is_empty());
            let got: Vec<(u32, f32)> = m.indices.into_iter().zip(m.weights).collect();
            assert_eq!(got, expected);
        }
    }

    /// A mask made from the mask on earlier positions weighs only the stale vertices again
    /// and gives the bits of a fresh mask (vertices entering and leaving the volume
    /// included), on both the one-thread and the parallel path; a moved vertex wrongly left
    /// out of the stale set keeps its earlier weight.
    #[test]
    fn masks_reusing_an_earlier_mask_match_a_fresh_one() {
        let vol = Volume::new(
            Shape::Sphere { radius: 0.5 },
            Affine3A::from_translation(Vec3::new(1.0, 0.4, 0.0)),
            "v",
        )
        .unwrap();
        for n in [3000, PARALLEL_THRESHOLD + 5000] {
            let before: Vec<Vec3> = (0..n)
                .map(|i| Vec3::new((i % 200) as f32 * 0.01, (i / 200) as f32 * 0.01, 0.0))
                .collect();
            let moved = |v: usize| v.is_multiple_of(7);
            let after: Vec<Vec3> = (0..n)
                .map(|v| {
                    before[v]
                        + if moved(v) {
                            Vec3::new(0.13, -0.02, 0.05)
                        } else {
                            Vec3::ZERO
                        }
                })
                .collect();
            let stale: Vec<bool> = (0..n).map(moved).collect();
            // A smooth falloff takes the lanes; a custom curve the vertex-by-vertex path.
            let curve = Falloff::Curve(SplineControl {
                values: vec![0.0, 0.3, 1.0],
                degree: 2,
            });
            for (area, invert, falloff) in [
                (None, false, Falloff::Smooth),
                (None, true, Falloff::Smooth),
                (
                    Some((0..n as u32).filter(|v| v % 3 != 0).collect::<Vec<_>>()),
                    false,
                    Falloff::Smooth,
                ),
                (None, false, curve.clone()),
                (None, true, curve.clone()),
                (
                    Some((0..n as u32).filter(|v| v % 3 != 0).collect::<Vec<_>>()),
                    false,
                    curve.clone(),
                ),
            ] {
                let inf = Influence {
                    volumes: vec![vol.clone()],
                    area,
                    falloff,
                    inner: 0.2,
                    invert,
                };
                let area = inf.area.as_deref();
                let old = inf.mask_in(area, &before);
                let fresh = inf.mask_in(area, &after);
                assert_ne!(old, fresh);
                assert_eq!(inf.mask_reusing(area, &after, &old, &stale), fresh, "{n}");
                let lying = vec![false; n];
                assert_eq!(inf.mask_reusing(area, &after, &old, &lying), old, "{n}");
            }
        }
    }

    #[test]
    fn culled_masks_match_the_per_vertex_weights_bit_for_bit() {
        // A grid through and around rotated, scaled volumes of every shape, above and below
        // the parallel threshold; every falloff (a curve with F(0) = 1 weighs points at
        // distance exactly 1), inverted or not.
        let grid = |k: usize| -> Vec<Vec3> {
            let mut v = Vec::new();
            for i in 0..k {
                for j in 0..k {
                    for l in 0..k {
                        let t = |a: usize| -1.5 + 3.0 * a as f32 / (k - 1) as f32;
                        v.push(Vec3::new(t(i), t(j), t(l)));
                    }
                }
            }
            v
        };
        let placement = placement();
        let shapes = every_shape(
            vec![
                Vec3::new(-0.5, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::new(0.4, 0.5, 0.1),
            ],
            vec![0.2, 0.4, 0.3],
        );
        let falloffs = [
            Falloff::None,
            Falloff::Linear,
            Falloff::Smooth,
            Falloff::Curve(SplineControl::constant(1.0)),
        ];
        for positions in [grid(12), grid(27)] {
            for shape in &shapes {
                let volume = Volume::new(shape.clone(), placement, "v").unwrap();
                for falloff in &falloffs {
                    for invert in [false, true] {
                        let inf = Influence {
                            volumes: vec![volume.clone()],
                            area: None,
                            falloff: falloff.clone(),
                            inner: 0.3,
                            invert,
                        };
                        let expected = weighed_bits(&inf, &positions);
                        assert!(!expected.is_empty() && expected.len() < positions.len());
                        let got = mask_bits(&inf.mask(&positions));
                        assert_eq!(got, expected, "{shape:?} {falloff:?} invert {invert}");
                    }
                }
            }
        }
    }

    /// Masks over chunk boxes are the plain masks: on a walk whose chunks lie apart (so
    /// most are passed over), with NaN positions, for every shape, inverted or not; and
    /// after vertices move into the volume, once their chunks are marked and refreshed.
    #[test]
    fn bounded_masks_are_the_plain_masks() {
        let n = 3 * PARALLEL_THRESHOLD + 123;
        let mut positions: Vec<Vec3> = (0..n)
            .map(|i| {
                let t = i as f32 / n as f32;
                Vec3::new(
                    8.0 * t - 4.0,
                    (i as f32 * 0.37).sin(),
                    (i as f32 * 0.11).cos(),
                )
            })
            .collect();
        positions[5] = Vec3::new(f32::NAN, 0.0, 0.0);
        positions[CHUNK + 7] = Vec3::splat(f32::NAN);
        let shapes = every_shape(
            vec![Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.4, 0.5, 0.1)],
            vec![0.2, 0.4],
        );
        let placement = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(0.4),
            Vec3::new(1.0, 0.0, 0.5),
        );
        for shape in shapes {
            for invert in [false, true] {
                let inf = Influence {
                    volumes: vec![Volume::new(shape.clone(), placement, "v").unwrap()],
                    area: None,
                    falloff: Falloff::Smooth,
                    inner: 0.2,
                    invert,
                };
                let mut positions = positions.clone();
                let mut bounds = ChunkBounds::new(&positions);
                let (lo, hi) = inf.volumes[0].cull_box();
                let chunks = n.div_ceil(CHUNK);
                assert!((0..chunks).any(|c| !bounds.reaches(c, lo, hi)), "{shape:?}");
                assert!((0..chunks).any(|c| bounds.reaches(c, lo, hi)), "{shape:?}");
                let before = inf.mask(&positions);
                assert_eq!(inf.mask_bounded(&positions, &bounds), before, "{shape:?}");
                // Vertices of far chunks moved onto the volume's centre.
                let moved: Vec<u32> = (0..n as u32).filter(|i| i % 997 == 3).collect();
                for &i in &moved {
                    positions[i as usize] = placement.translation.into();
                }
                let after = inf.mask(&positions);
                assert_ne!(after, before, "{shape:?}");
                bounds.mark(&moved);
                bounds.refresh(&positions);
                assert_eq!(inf.mask_bounded(&positions, &bounds), after, "{shape:?}");
                // More vertices than the boxes were for: all of them again.
                positions.extend_from_slice(&[placement.translation.into(); 5]);
                bounds.refresh(&positions);
                assert_eq!(inf.mask_bounded(&positions, &bounds), inf.mask(&positions));
            }
        }
    }

    #[test]
    fn a_chunk_box_holds_the_least_and_greatest_coordinates_without_nan() {
        use pulp::WithSimd;
        // Every length from none to past four groups of the widest registers (16 points),
        // with infinite coordinates at one point, a NaN in one coordinate here and there, or
        // NaN in every point's z (`usize::MAX`).
        let points: Vec<Vec3> = (0..70)
            .map(|k| {
                let t = k as f32;
                if k == 41 {
                    return Vec3::new(f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY);
                }
                Vec3::new(
                    (t * 1.3).sin() * 5.0,
                    (t * 0.7).cos() - t,
                    t * t * 0.1 - 3.0,
                )
            })
            .collect();
        for n in 0..=points.len() {
            for nan in [
                None,
                Some(0),
                Some(n / 2),
                Some(n.saturating_sub(1)),
                Some(usize::MAX),
            ] {
                let mut p = points[..n].to_vec();
                if let Some(k) = nan.filter(|&k| k < n) {
                    p[k][k % 3] = f32::NAN;
                }
                if nan == Some(usize::MAX) {
                    for q in &mut p {
                        q.z = f32::NAN;
                    }
                }
                let mut lo = Vec3::INFINITY;
                let mut hi = Vec3::NEG_INFINITY;
                for q in &p {
                    lo = Vec3::from_array(std::array::from_fn(|i| lo[i].min(q[i])));
                    hi = Vec3::from_array(std::array::from_fn(|i| hi[i].max(q[i])));
                }
                assert_eq!(chunk_box(&p), (lo, hi), "{n} points, NaN at {nan:?}");
                // Every register width, whatever this CPU dispatches to: 1, 4, 8, 16 lanes.
                let widths = [
                    ChunkBox(&p).with_simd(pulp::Scalar::new()),
                    ChunkBox(&p).with_simd(pulp::Scalar128b),
                    ChunkBox(&p).with_simd(pulp::Scalar256b),
                    ChunkBox(&p).with_simd(pulp::Scalar512b),
                ];
                for (w, b) in widths.into_iter().enumerate() {
                    assert_eq!(b, (lo, hi), "{n} points, NaN at {nan:?}, width {w}");
                }
                // The compare-and-select form that a NaN lane falls back to (no CPU this
                // test runs on leaves one), at every width; and the lanes of the min form
                // never hold a NaN here.
                let select = [
                    box_of::<_, true>(pulp::Scalar::new(), bytemuck::cast_slice(&p)),
                    box_of::<_, true>(pulp::Scalar128b, bytemuck::cast_slice(&p)),
                    box_of::<_, true>(pulp::Scalar256b, bytemuck::cast_slice(&p)),
                    box_of::<_, true>(pulp::Scalar512b, bytemuck::cast_slice(&p)),
                ];
                for (w, (b, lane_nan)) in select.into_iter().enumerate() {
                    assert_eq!(b, (lo, hi), "{n} points, NaN at {nan:?}, width {w}, select");
                    assert!(!lane_nan, "the select form keeps NaN out of its lanes");
                }
                let min = box_of::<_, false>(pulp::Scalar256b, bytemuck::cast_slice(&p));
                assert_eq!(min, ((lo, hi), false), "{n} points, NaN at {nan:?}, min");
            }
        }
    }

    /// An area out of order and with repeats gives the mask of its sorted, unique vertices
    /// (ascending, as marking the chunk boxes reads it), with and without volumes, on the
    /// serial and the parallel paths.
    #[test]
    fn an_unsorted_area_gives_an_ascending_mask() {
        let positions: Vec<Vec3> = (0..40_000)
            .map(|k| {
                let t = k as f32 * 0.001;
                Vec3::new(t.sin(), t.cos(), (t * 3.0).sin() * 0.5)
            })
            .collect();
        let sphere = Volume::new(Shape::Sphere { radius: 1.2 }, placement(), "v").unwrap();
        for volumes in [vec![], vec![sphere]] {
            for len in [100_u32, 30_000] {
                let mut sorted: Vec<u32> = (0..len).map(|k| k * 13 % 40_000).collect();
                sorted.sort_unstable();
                sorted.dedup();
                let mut shuffled: Vec<u32> = sorted.iter().rev().copied().collect();
                shuffled.extend_from_slice(&sorted[..10]);
                let inf = |area: Vec<u32>| Influence {
                    volumes: volumes.clone(),
                    area: Some(area),
                    falloff: Falloff::Smooth,
                    inner: 0.0,
                    invert: false,
                };
                let expected = inf(sorted.clone()).mask(&positions);
                let got = inf(shuffled).mask(&positions);
                assert!(got.indices.windows(2).all(|w| w[0] < w[1]));
                assert!(!got.is_empty());
                assert_eq!(got, expected, "{} volumes, {len}", volumes.len());
            }
        }
    }

    /// Marking flags the chunks that hold one of the changed vertices, and no other.
    #[test]
    fn marking_flags_exactly_the_chunks_of_the_changed_vertices() {
        let n = 40 * CHUNK + 17;
        let positions = vec![Vec3::ZERO; n];
        // Dense in chunks 3..12, one vertex in chunk 20, the very last vertex; none elsewhere.
        let mut changed: Vec<u32> = (3 * CHUNK as u32..12 * CHUNK as u32).step_by(2).collect();
        changed.extend([20 * CHUNK as u32 + 5, n as u32 - 1]);
        let expected: Vec<bool> = (0..n.div_ceil(CHUNK))
            .map(|c| changed.iter().any(|&i| i as usize / CHUNK == c))
            .collect();
        let mut bounds = ChunkBounds::new(&positions);
        bounds.mark(&changed);
        assert_eq!(bounds.stale, expected);
        // Vertices past the end (a refined mesh's) flag nothing more.
        let mut bounds = ChunkBounds::new(&positions);
        changed.extend([n as u32 + 3, 50 * CHUNK as u32]);
        bounds.mark(&changed);
        assert_eq!(bounds.stale, expected);
    }

    /// The placement the shape tests put their volumes at: scaled, rotated and moved.
    pub(crate) fn placement() -> Affine3A {
        Affine3A::from_scale_rotation_translation(
            Vec3::new(1.2, 0.7, 0.9),
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 1.1),
            Vec3::new(0.1, -0.2, 0.3),
        )
    }

    /// A sphere, a box, a capsule and a tube through `points` with `radii`.
    pub(crate) fn every_shape(points: Vec<Vec3>, radii: Vec<f32>) -> [Shape; 4] {
        [
            Shape::Sphere { radius: 0.8 },
            Shape::Box {
                half_extents: Vec3::new(0.5, 0.3, 0.75),
            },
            Shape::Capsule {
                radius: 0.3,
                half_height: 0.5,
            },
            Shape::Tube { points, radii },
        ]
    }

    /// A mask's vertices with the bits of their weights.
    fn mask_bits(m: &Mask) -> Vec<(u32, u32)> {
        m.indices
            .iter()
            .zip(&m.weights)
            .map(|(&i, w)| (i, w.to_bits()))
            .collect()
    }

    /// What [`mask_bits`] of `inf`'s mask on `positions` must be: its area's vertices (or
    /// every vertex; the area in range) of positive `volume_weight`, weighed one by one.
    fn weighed_bits(inf: &Influence, positions: &[Vec3]) -> Vec<(u32, u32)> {
        let candidates: Vec<u32> = match &inf.area {
            Some(a) => a.clone(),
            None => (0..positions.len() as u32).collect(),
        };
        candidates
            .into_iter()
            .map(|i| (i, inf.volume_weight(positions[i as usize])))
            .filter(|&(_, w)| w > 0.0)
            .map(|(i, w)| (i, w.to_bits()))
            .collect()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// The lane masks give every vertex the bits of `volume_weight`, for unions of up to
        /// three placed spheres, boxes, capsules and tubes, every lane falloff, any inner plateau,
        /// inverted or not, over a vertex list or every vertex, short or parallel.
        #[test]
        fn lane_masks_have_the_bits_of_the_per_vertex_weights(
            seed in 0_u64..1_000_000,
            count in 1_usize..4,
            falloff in 0_usize..3,
            inner in 0.0_f32..0.95,
            invert: bool,
            with_area: bool,
            long: bool,
        ) {
            let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let mut r = move || {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                ((state >> 40) as f32) / (1u64 << 24) as f32
            };
            let volumes: Vec<Volume> = (0..count)
                .map(|k| {
                    let shape = match (seed as usize + k) % 4 {
                        0 => Shape::Sphere { radius: 0.2 + r() },
                        1 => Shape::Box {
                            half_extents: Vec3::new(0.1 + r(), 0.1 + r(), 0.1 + r()),
                        },
                        2 => Shape::Capsule {
                            radius: 0.1 + 0.5 * r(),
                            half_height: if r() < 0.2 { 0.0 } else { r() },
                        },
                        _ => {
                            // A repeated point makes a segment of length 0.
                            let mut points: Vec<Vec3> = (0..2 + (seed as usize % 4))
                                .map(|_| Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5))
                                .collect();
                            points.push(*points.last().unwrap());
                            let radii = points.iter().map(|_| 0.05 + 0.4 * r()).collect();
                            Shape::Tube { points, radii }
                        }
                    };
                    let placement = Affine3A::from_scale_rotation_translation(
                        Vec3::new(0.3 + 2.0 * r(), 0.3 + 2.0 * r(), 0.3 + 2.0 * r()),
                        glam::Quat::from_euler(glam::EulerRot::XYZ, 6.0 * r(), 6.0 * r(), 6.0 * r()),
                        Vec3::new(2.0 * r() - 1.0, 2.0 * r() - 1.0, 2.0 * r() - 1.0),
                    );
                    Volume::new(shape, placement, "v").unwrap()
                })
                .collect();
            // Long enough that the area (two thirds of the vertices) goes parallel too.
            let n = if long { 2 * PARALLEL_THRESHOLD + 3001 } else { 997 };
            let positions: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(4.0 * r() - 2.0, 4.0 * r() - 2.0, 4.0 * r() - 2.0))
                .collect();
            let inf = Influence {
                volumes,
                area: with_area.then(|| (0..n as u32).filter(|i| i % 3 != 1).collect()),
                falloff: [Falloff::None, Falloff::Linear, Falloff::Smooth][falloff].clone(),
                inner,
                invert,
            };
            let m = inf.mask(&positions);
            proptest::prop_assert_eq!(mask_bits(&m), weighed_bits(&inf, &positions));
            // Made from this mask after a few runs of vertices moved, it is the fresh mask
            // there: short runs (lane groups without a stale vertex, and partly stale ones)
            // and long runs (wholly stale groups too).
            let patterns: [fn(usize) -> bool; 2] = [
                |v| (v / 5) % 7 == 3 || v % 31 == 0,
                |v| (v / 40) % 3 == 1 || v % 97 == 0,
            ];
            for pattern in patterns {
                let stale: Vec<bool> = (0..n).map(pattern).collect();
                let after: Vec<Vec3> = positions
                    .iter()
                    .zip(&stale)
                    .map(|(&p, &s)| if s { p * 0.8 + Vec3::new(0.1, -0.2, 0.05) } else { p })
                    .collect();
                let area = inf.area.as_deref();
                let reused = inf.mask_reusing(area, &after, &m, &stale);
                proptest::prop_assert_eq!(mask_bits(&reused), weighed_bits(&inf, &after));
            }
        }
    }
}
