//! Volume masks a lane group at a time: [`Influence::mask`]'s per-vertex weight `w(v)`
//! computed for sixteen vertices at once on [`crate::lane`]'s lanes, compiled per register
//! width and picked at run time by [`pulp`] (8 lanes a register where the CPU has AVX2).
//!
//! Every lane performs the scalar path's operations in the same order — glam's
//! `Affine3A::transform_point3` into the volume's frame (`((X·x + Y·y) + Z·z) + T`), the
//! shape's normalised distance (`Vec3::length`, `max_element`, `f32::clamp` written as the
//! same comparisons), the falloff (`s = (1 − t)/(1 − inner)` clamped, `s²(3 − 2s)`), the
//! union as `f32::max` and `1 − g` when inverted — with exactly rounded operations and no
//! fused multiply–add, so a vertex gets the bits of [`Influence::volume_weight`] whatever
//! the register width (tests in `influence.rs`). A custom spline falloff has no lane form
//! and stays on the scalar path. Where the CPU has AVX2, a fresh mask (nothing to reuse)
//! runs the same operations in explicit registers instead (`volume_lanes/simd.rs`).

mod simd;

use glam::Vec3;

use crate::influence::{Earlier, Falloff, Influence, Mask, Shape};
use crate::lane::{LANES, Lane, Lanes3, Mask as LaneMask};

/// The vertices a kernel weighs.
#[derive(Clone, Copy)]
pub(crate) enum Ids<'a> {
    /// `start..end`.
    Range(u32, u32),
    /// These indices, ascending and in range.
    List(&'a [u32]),
}

impl Ids<'_> {
    /// How many vertices.
    fn len(self) -> usize {
        match self {
            Ids::Range(start, end) => (end - start) as usize,
            Ids::List(ids) => ids.len(),
        }
    }
}

/// A volume's shape in its local frame, in a form the lanes evaluate.
#[derive(Debug, Clone)]
enum LaneShape {
    Sphere { radius: f32 },
    Box { half: Vec3 },
    Capsule { radius: f32, half_height: f32 },
    Tube(Vec<TubeSegment>),
}

/// One segment of a tube, with what `tube_distance` computes of it before it reads the
/// point: `b − a`, `|b − a|²` and the radius step `r₁ − r₀`.
#[derive(Debug, Clone, Copy)]
struct TubeSegment {
    a: Vec3,
    ab: Vec3,
    len2: f32,
    r0: f32,
    dr: f32,
}

/// One volume: its mesh-to-local transform by columns, its shape and its cull box.
#[derive(Debug, Clone)]
struct LaneVolume {
    x_axis: Vec3,
    y_axis: Vec3,
    z_axis: Vec3,
    translation: Vec3,
    shape: LaneShape,
    lo: Vec3,
    hi: Vec3,
}

/// The falloffs the lanes evaluate.
#[derive(Debug, Clone, Copy)]
enum LaneFalloff {
    None,
    Linear,
    Smooth,
}

/// An [`Influence`]'s volume weight in lanes.
#[derive(Debug, Clone)]
pub(crate) struct LaneInfluence {
    volumes: Vec<LaneVolume>,
    falloff: LaneFalloff,
    inner: f32,
    invert: bool,
}

impl LaneInfluence {
    /// The lane form of `influence`'s volumes (with their cull boxes), or `None` when it has
    /// no volume or its falloff has no lane form.
    pub(crate) fn new(influence: &Influence) -> Option<Self> {
        let falloff = match influence.falloff {
            Falloff::None => LaneFalloff::None,
            Falloff::Linear => LaneFalloff::Linear,
            Falloff::Smooth => LaneFalloff::Smooth,
            Falloff::Curve(_) => return None,
        };
        if influence.volumes.is_empty() {
            return None;
        }
        let volumes = influence
            .volumes
            .iter()
            .map(|v| {
                let (lo, hi) = v.cull_box();
                let shape = match &v.shape {
                    &Shape::Sphere { radius } => LaneShape::Sphere { radius },
                    &Shape::Box { half_extents } => LaneShape::Box { half: half_extents },
                    &Shape::Capsule {
                        radius,
                        half_height,
                    } => LaneShape::Capsule {
                        radius,
                        half_height,
                    },
                    Shape::Tube { points, radii } => LaneShape::Tube(
                        points
                            .windows(2)
                            .zip(radii.windows(2))
                            .map(|(w, r)| {
                                let ab = w[1] - w[0];
                                TubeSegment {
                                    a: w[0],
                                    ab,
                                    len2: ab.length_squared(),
                                    r0: r[0],
                                    dr: r[1] - r[0],
                                }
                            })
                            .collect(),
                    ),
                };
                let m = v.to_local;
                Some(LaneVolume {
                    x_axis: m.matrix3.x_axis.into(),
                    y_axis: m.matrix3.y_axis.into(),
                    z_axis: m.matrix3.z_axis.into(),
                    translation: m.translation.into(),
                    shape,
                    lo,
                    hi,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Self {
            volumes,
            falloff,
            inner: influence.inner,
            invert: influence.invert,
        })
    }

    /// The vertices of `ids` of positive weight, in order, with their weights: the
    /// lane form of `influence.rs`'s scalar gather. With `reuse` (an earlier mask of the
    /// same influence and the stale vertices, see `Influence::mask_reusing`), a vertex that
    /// is not stale keeps its earlier weight (0 where it was not in that mask), and a lane
    /// group without a stale vertex reads no position.
    pub(crate) fn gather(
        &self,
        ids: Ids<'_>,
        positions: &[Vec3],
        reuse: Option<(&Mask, &[bool])>,
    ) -> Mask {
        pulp::Arch::new().dispatch(Gather {
            influence: self,
            ids,
            positions,
            reuse,
        })
    }

    /// The weight of every vertex of a region that no cull box reaches, by `reaches(lo, hi)`
    /// (whether the region holds a point of the box `lo..=hi`): 0, or 1 when inverted;
    /// `None` when some cull box may reach it.
    pub(crate) fn culled(&self, reaches: impl Fn(Vec3, Vec3) -> bool) -> Option<f32> {
        if self.volumes.iter().any(|v| reaches(v.lo, v.hi)) {
            return None;
        }
        Some(if self.invert { 1.0 } else { 0.0 })
    }

    /// `w(v)` in each lane: outside every cull box the weight is 0 (1 when inverted) from the
    /// box test alone, as the scalar path decides it; inside one, `g` (or `1 − g`).
    #[inline(always)]
    fn weights(&self, v: &Lanes3) -> Lane {
        let outside = Lane::splat(if self.invert { 1.0 } else { 0.0 });
        let mut inside = LaneMask::NONE;
        for vol in &self.volumes {
            inside = inside
                | (v.x.simd_ge(Lane::splat(vol.lo.x))
                    & v.y.simd_ge(Lane::splat(vol.lo.y))
                    & v.z.simd_ge(Lane::splat(vol.lo.z))
                    & v.x.simd_le(Lane::splat(vol.hi.x))
                    & v.y.simd_le(Lane::splat(vol.hi.y))
                    & v.z.simd_le(Lane::splat(vol.hi.z)));
        }
        if !inside.any() {
            return outside;
        }
        // `fold(0, f32::max)`: a weight is never NaN or −0 for a point inside a box, and a
        // NaN would keep the union, as `f32::max` does.
        let mut g = Lane::ZERO;
        for vol in &self.volumes {
            let w = self.falloff(vol.distance(v));
            g = w.simd_gt(g).select(w, g);
        }
        let w = if self.invert { Lane::splat(1.0) - g } else { g };
        inside.select(w, outside)
    }

    /// [`Falloff::weight`] in each lane.
    #[inline(always)]
    fn falloff(&self, t: Lane) -> Lane {
        let one = Lane::splat(1.0);
        let s = ((one - t) / Lane::splat(1.0 - self.inner)).clamp01();
        let f = match self.falloff {
            LaneFalloff::None => one,
            LaneFalloff::Linear => s,
            LaneFalloff::Smooth => s * s * (Lane::splat(3.0) - Lane::splat(2.0) * s),
        };
        let w = t.simd_le(Lane::splat(self.inner)).select(one, f);
        t.simd_gt(one).select(Lane::ZERO, w)
    }
}

impl LaneVolume {
    /// [`crate::influence::Volume::normalized_distance`] in each lane.
    #[inline(always)]
    fn distance(&self, v: &Lanes3) -> Lane {
        let s = Lane::splat;
        let (a, b, c, t) = (self.x_axis, self.y_axis, self.z_axis, self.translation);
        let l = Lanes3 {
            x: s(a.x) * v.x + s(b.x) * v.y + s(c.x) * v.z + s(t.x),
            y: s(a.y) * v.x + s(b.y) * v.y + s(c.y) * v.z + s(t.y),
            z: s(a.z) * v.x + s(b.z) * v.y + s(c.z) * v.z + s(t.z),
        };
        match &self.shape {
            &LaneShape::Sphere { radius } => l.length() / s(radius),
            &LaneShape::Box { half } => {
                let (x, y, z) = (
                    l.x.abs() / s(half.x),
                    l.y.abs() / s(half.y),
                    l.z.abs() / s(half.z),
                );
                x.greater(y.greater(z))
            }
            &LaneShape::Capsule {
                radius,
                half_height,
            } => {
                // `local.y.clamp(−h, h)`, then `local − (0, y, 0)`.
                let y = l.y;
                let y = y.simd_lt(s(-half_height)).select(s(-half_height), y);
                let y = y.simd_gt(s(half_height)).select(s(half_height), y);
                let d = Lanes3 {
                    x: l.x - Lane::ZERO,
                    y: l.y - y,
                    z: l.z - Lane::ZERO,
                };
                d.length() / s(radius)
            }
            LaneShape::Tube(segments) => {
                // `tube_distance`: per segment `t = clamp((p − a)·ab / |ab|², 0, 1)` (0 for a
                // point-like segment), `c = a + ab t`, `|p − c| / (r₀ + (r₁ − r₀) t)`, and
                // the least of them as `f32::min` keeps it.
                let mut best = s(f32::INFINITY);
                for seg in segments {
                    let (a, ab) = (seg.a, seg.ab);
                    let t = if seg.len2 > 0.0 {
                        let d = Lanes3 {
                            x: l.x - s(a.x),
                            y: l.y - s(a.y),
                            z: l.z - s(a.z),
                        };
                        let t = (d.x * s(ab.x) + d.y * s(ab.y) + d.z * s(ab.z)) / s(seg.len2);
                        let t = t.simd_lt(Lane::ZERO).select(Lane::ZERO, t);
                        t.simd_gt(s(1.0)).select(s(1.0), t)
                    } else {
                        Lane::ZERO
                    };
                    let c = Lanes3 {
                        x: l.x - (s(a.x) + s(ab.x) * t),
                        y: l.y - (s(a.y) + s(ab.y) * t),
                        z: l.z - (s(a.z) + s(ab.z) * t),
                    };
                    let q = c.length() / (s(seg.r0) + s(seg.dr) * t);
                    best = q.simd_lt(best).select(q, best);
                }
                best
            }
        }
    }
}

/// [`LaneInfluence::gather`]'s kernel.
struct Gather<'a> {
    influence: &'a LaneInfluence,
    ids: Ids<'a>,
    positions: &'a [Vec3],
    reuse: Option<(&'a Mask, &'a [bool])>,
}

/// Where a lane group's positions come from.
#[derive(Clone, Copy)]
enum Source<'a> {
    /// These consecutive positions.
    Load(&'a [Vec3]),
    /// The positions of these vertices.
    Gather(&'a [Vec3], &'a [u32]),
}

impl Source<'_> {
    #[inline(always)]
    fn lanes(self) -> Lanes3 {
        match self {
            Source::Load(points) => Lanes3::load(points),
            Source::Gather(positions, ids) => Lanes3::gather(positions, ids),
        }
    }
}

impl pulp::WithSimd for Gather<'_> {
    type Output = Mask;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, s: S) -> Mask {
        if S::F32_LANES > 1 && self.reuse.is_none() {
            return simd::mask(s, self.influence, self.ids, self.positions);
        }
        let mut mask = Mask::default();
        let start = match self.ids {
            Ids::Range(start, _) => start,
            Ids::List(ids) => ids.first().copied().unwrap_or(0),
        };
        let mut earlier = self
            .reuse
            .map(|(old, stale)| Earlier::new(old, stale, start));
        let influence = self.influence;
        // The first and last vertex of the lane groups without a stale vertex met since the
        // last group with one: their earlier entries are copied at once.
        let mut clean: Option<(u32, u32)> = None;
        match self.ids {
            Ids::Range(start, end) => {
                let points = &self.positions[start as usize..end as usize];
                for (g, chunk) in points.chunks(LANES).enumerate() {
                    let first = start + (g * LANES) as u32;
                    let mut ids = [0; LANES];
                    for (j, id) in ids.iter_mut().enumerate() {
                        *id = first + j as u32;
                    }
                    let ids = &ids[..chunk.len()];
                    let reuse = earlier.as_mut().map(|e| {
                        let stale = e.stale_run(ids);
                        (e, stale)
                    });
                    let source = Source::Load(chunk);
                    weigh_group(influence, reuse, &mut clean, ids, source, &mut mask);
                }
            }
            Ids::List(ids) => {
                for chunk in ids.chunks(LANES) {
                    let reuse = earlier.as_mut().map(|e| {
                        let stale = e.stale_lanes(chunk);
                        (e, stale)
                    });
                    let source = Source::Gather(self.positions, chunk);
                    weigh_group(influence, reuse, &mut clean, chunk, source, &mut mask);
                }
            }
        }
        if let (Some(e), Some((first, last))) = (&mut earlier, clean) {
            e.copy_run(first, last, &mut mask);
        }
        mask
    }
}

/// One lane group of the kernel: weighs `ids` (the positions from `source`, read only when
/// some vertex needs a fresh weight) and appends those of positive weight to `mask`. With an
/// earlier mask, `reuse` holds it and `stale`, bit `j` set when lane `j`'s vertex is
/// stale; a group without a
/// stale vertex only extends the run `clean`, whose earlier entries are appended when a
/// group with one comes (or by the caller at the end). A function, not a closure, so that
/// it is compiled with the kernel's target features.
#[inline(always)]
fn weigh_group(
    influence: &LaneInfluence,
    reuse: Option<(&mut Earlier<'_>, u32)>,
    clean: &mut Option<(u32, u32)>,
    ids: &[u32],
    source: Source<'_>,
    mask: &mut Mask,
) {
    let w = match reuse {
        Some((_, 0)) => {
            // Nothing moved: the group's earlier entries stay as they are.
            let first = clean.map_or(ids[0], |(f, _)| f);
            *clean = Some((first, ids[ids.len() - 1]));
            return;
        }
        Some((e, stale)) => {
            if let Some((f, l)) = clean.take() {
                e.copy_run(f, l, mask);
            }
            let mut w = influence.weights(&source.lanes());
            // The lanes that did not move keep their earlier weights (the earlier entries
            // of those that moved are passed over by the next lookup).
            for (j, &i) in ids.iter().enumerate() {
                if stale & (1 << j) == 0 {
                    w.0[j] = e.weight(i);
                }
            }
            w
        }
        None => influence.weights(&source.lanes()),
    };
    // Most groups of a small volume's mask are outside it: a group of no positive weight
    // appends nothing, and the lane loop is skipped.
    if w.simd_gt(Lane::ZERO).any() {
        push_positive(ids, &w, mask);
    }
}

/// Appends the vertices of `ids` whose weight in `w` (lane by lane) is positive to `mask`.
#[inline(always)]
fn push_positive(ids: &[u32], w: &Lane, mask: &mut Mask) {
    for (&i, &w) in ids.iter().zip(w.as_array()) {
        if w > 0.0 {
            mask.indices.push(i);
            mask.weights.push(w);
        }
    }
}
