//! The axial tool's per-vertex work — the frame at a vertex's axis parameter, its local
//! coordinates at bind time and its move at deform time — for a lane group of vertices at a
//! time, in `registers.rs`'s registers where [`pulp`]'s runtime dispatch finds AVX2.
//!
//! At fraction `f` of sample segment `j` the axis point is `A = P_j (1 − f) + P_{j+1} f`, the
//! frame `R` the segment's slerp ([`SlerpArc`]), the scale `s = θ_j (1 − f) + θ_{j+1} f` and
//! `M = R S` with `S = diag(1, s, s)`; the bind keeps `l = S⁻¹ Rᵀ (U − A)` and `A + M l`, the
//! deform moves a vertex by `w ((A' + M' l) − (A + M l))` (`axial.rs`). Every lane does the
//! scalar path's operations in their order (glam's `Vec3::lerp`, `Mat3::from_quat`, the
//! product with `Mat3::from_diagonal`, `Mat3 * Vec3`), so each vertex gets the bits of
//! `SampledAxis::at_with_parts` and the per-vertex code; a test compares them.
//!
//! The registers take a segment whose two ends have no twist, whatever its frames (equal, an
//! arc apart or nearly equal: [`SlerpArc`]'s three kinds). A group with a twisted segment
//! (whose rotation about the tangent uses the standard library's sine) or with a value that is
//! not finite (whose NaN could take another payload in a vector register) is left to the
//! per-vertex code, and so is everything on a CPU without AVX2 (where two registers do not
//! hold a lane group). The Add menu's axis is a polyline of four segments, so a group's
//! vertices mostly share one segment, whose values are then broadcast instead of gathered
//! lane by lane.

use glam::{Quat, Vec3};

use std::f32::consts::{FRAC_PI_2, PI};

use pulp::Simd;

use crate::lane::{LANES, Lane, Lanes3};
use crate::registers::{Block, Ops, Two, load, store};
use crate::slerp::{SIN, SlerpArc};

/// How a segment's frame is interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Equal frames, no twist: the start's frame.
    Same,
    /// Frames an arc apart, no twist: the arc's two sines.
    Arc,
    /// Frames nearly equal, no twist: the normalised linear interpolation.
    Lerp,
    /// Anything else: the scalar path.
    Scalar,
}

impl Kind {
    /// The kind's value in [`SegmentLanes::arc`].
    fn code(self) -> f32 {
        match self {
            Kind::Same | Kind::Scalar => 0.0,
            Kind::Arc => 1.0,
            Kind::Lerp => 2.0,
        }
    }
}

/// What a sample segment's frame needs, ready to broadcast or gather.
#[derive(Debug, Clone, Copy)]
struct Segment {
    kind: Kind,
    /// The sample points at both ends.
    p0: Vec3,
    p1: Vec3,
    /// The scales at both ends.
    s0: f32,
    s1: f32,
    /// The start frame and the arc's far end (the start again for [`Kind::Same`]).
    r: Quat,
    e: Quat,
    /// `θ` and `sin θ` of the arc (0 and 1 for the other kinds).
    theta: f32,
    sin_theta: f32,
}

/// A sampled axis's segments as the lanes read them.
#[derive(Debug, Clone)]
pub(crate) struct AxisTable {
    segments: Vec<Segment>,
}

impl AxisTable {
    /// The table of an axis with sample `points`, frames `rotations`, `twist`, `scale` and the
    /// slerp `arcs` between consecutive frames.
    #[must_use]
    pub(crate) fn new(
        points: &[Vec3],
        rotations: &[Quat],
        twist: &[f32],
        scale: &[f32],
        arcs: &[SlerpArc],
    ) -> Self {
        let segments = arcs
            .iter()
            .enumerate()
            .map(|(j, arc)| {
                let untwisted = twist[j] == 0.0 && twist[j + 1] == 0.0;
                let r = rotations[j];
                let (kind, e, theta, sin_theta) = match *arc {
                    SlerpArc::Same if untwisted => (Kind::Same, r, 0.0, 1.0),
                    SlerpArc::Arc {
                        end,
                        theta,
                        sin_theta,
                    } if untwisted => (Kind::Arc, end, theta, sin_theta),
                    SlerpArc::Lerp { end } if untwisted => (Kind::Lerp, end, 0.0, 1.0),
                    _ => (Kind::Scalar, r, 0.0, 1.0),
                };
                Segment {
                    kind,
                    p0: points[j],
                    p1: points[j + 1],
                    s0: scale[j],
                    s1: scale[j + 1],
                    r,
                    e,
                    theta,
                    sin_theta,
                }
            })
            .collect();
        Self { segments }
    }

    /// The segments of `js` (gathered into `scratch` when they differ), or `None` when one of
    /// them is not for the registers.
    #[inline(always)]
    fn lanes<'a>(
        &'a self,
        js: &[u32; LANES],
        scratch: &'a mut SegmentLanes,
    ) -> Option<Segments<'a>> {
        let first = self.segments.get(js[0] as usize)?;
        if first.kind == Kind::Scalar {
            return None;
        }
        if js.iter().all(|&j| j == js[0]) {
            return Some(Segments::One(first));
        }
        scratch.has_arc = false;
        scratch.has_lerp = false;
        for (i, &j) in js.iter().enumerate() {
            let g = self.segments.get(j as usize)?;
            if g.kind == Kind::Scalar {
                return None;
            }
            scratch.set(i, g);
        }
        Some(Segments::Each(scratch))
    }
}

#[cfg(test)]
impl AxisTable {
    /// The kinds of the segments: "same", "arc", "lerp" and "scalar" where every segment is
    /// of that kind, "mixed" otherwise.
    #[must_use]
    pub(crate) fn kinds(&self) -> &'static str {
        let name = |k: Kind| match k {
            Kind::Same => "same",
            Kind::Arc => "arc",
            Kind::Lerp => "lerp",
            Kind::Scalar => "scalar",
        };
        let first = self.segments[0].kind;
        if self.segments.iter().all(|g| g.kind == first) {
            name(first)
        } else {
            "mixed"
        }
    }
}

/// A lane group's segments: one for every lane (the usual case on a mesh, whose neighbouring
/// vertices share a segment), broadcast into registers, or one per lane.
enum Segments<'a> {
    One(&'a Segment),
    Each(&'a SegmentLanes),
}

impl Segments<'_> {
    /// The frames at fractions `f`.
    #[inline(always)]
    fn at<S: Simd>(&self, o: Ops<S>, f: R<S>) -> Frame<S> {
        match self {
            Segments::One(g) => frame_at(o, *g, f),
            Segments::Each(g) => frame_at(o, *g, f),
        }
    }
}

/// A lane group's segments: each field of [`Segment`] in lanes; `arc` is 1 where the segment
/// is an arc, 2 where it is a linear interpolation, 0 where its frames are equal.
#[derive(Debug, Clone, Copy)]
struct SegmentLanes {
    arc: Lane,
    p0: Lanes3,
    p1: Lanes3,
    s0: Lane,
    s1: Lane,
    r: [Lane; 4],
    e: [Lane; 4],
    theta: Lane,
    sin_theta: Lane,
    /// Whether a lane is an arc, a linear interpolation.
    has_arc: bool,
    has_lerp: bool,
}

impl SegmentLanes {
    /// Every value 0: a kernel's scratch for groups on several segments.
    const ZERO: Self = Self {
        arc: Lane::ZERO,
        p0: Lanes3::ZERO,
        p1: Lanes3::ZERO,
        s0: Lane::ZERO,
        s1: Lane::ZERO,
        r: [Lane::ZERO; 4],
        e: [Lane::ZERO; 4],
        theta: Lane::ZERO,
        sin_theta: Lane::ZERO,
        has_arc: false,
        has_lerp: false,
    };

    #[inline(always)]
    fn set(&mut self, i: usize, g: &Segment) {
        self.arc.0[i] = g.kind.code();
        self.p0.set(i, g.p0);
        self.p1.set(i, g.p1);
        self.s0.0[i] = g.s0;
        self.s1.0[i] = g.s1;
        for (c, (r, e)) in g.r.to_array().into_iter().zip(g.e.to_array()).enumerate() {
            self.r[c].0[i] = r;
            self.e[c].0[i] = e;
        }
        self.theta.0[i] = g.theta;
        self.sin_theta.0[i] = g.sin_theta;
        self.has_arc |= g.kind == Kind::Arc;
        self.has_lerp |= g.kind == Kind::Lerp;
    }
}

/// A lane group's segments as registers: one segment broadcast, or one per lane loaded.
trait Source {
    fn p0<S: Simd>(&self, o: Ops<S>) -> Block<S>;
    fn p1<S: Simd>(&self, o: Ops<S>) -> Block<S>;
    fn s0<S: Simd>(&self, o: Ops<S>) -> R<S>;
    fn s1<S: Simd>(&self, o: Ops<S>) -> R<S>;
    fn r<S: Simd>(&self, o: Ops<S>, c: usize) -> R<S>;
    fn e<S: Simd>(&self, o: Ops<S>, c: usize) -> R<S>;
    fn theta<S: Simd>(&self, o: Ops<S>) -> R<S>;
    fn sin_theta<S: Simd>(&self, o: Ops<S>) -> R<S>;
    /// [`Kind::code`] of each lane.
    fn code<S: Simd>(&self, o: Ops<S>) -> R<S>;
    fn has_arc(&self) -> bool;
    fn has_lerp(&self) -> bool;
}

impl Source for Segment {
    #[inline(always)]
    fn p0<S: Simd>(&self, o: Ops<S>) -> Block<S> {
        o.splat3(self.p0)
    }
    #[inline(always)]
    fn p1<S: Simd>(&self, o: Ops<S>) -> Block<S> {
        o.splat3(self.p1)
    }
    #[inline(always)]
    fn s0<S: Simd>(&self, o: Ops<S>) -> R<S> {
        o.splat(self.s0)
    }
    #[inline(always)]
    fn s1<S: Simd>(&self, o: Ops<S>) -> R<S> {
        o.splat(self.s1)
    }
    #[inline(always)]
    fn r<S: Simd>(&self, o: Ops<S>, c: usize) -> R<S> {
        o.splat(self.r.to_array()[c])
    }
    #[inline(always)]
    fn e<S: Simd>(&self, o: Ops<S>, c: usize) -> R<S> {
        o.splat(self.e.to_array()[c])
    }
    #[inline(always)]
    fn theta<S: Simd>(&self, o: Ops<S>) -> R<S> {
        o.splat(self.theta)
    }
    #[inline(always)]
    fn sin_theta<S: Simd>(&self, o: Ops<S>) -> R<S> {
        o.splat(self.sin_theta)
    }
    #[inline(always)]
    fn code<S: Simd>(&self, o: Ops<S>) -> R<S> {
        o.splat(self.kind.code())
    }
    #[inline(always)]
    fn has_arc(&self) -> bool {
        self.kind == Kind::Arc
    }
    #[inline(always)]
    fn has_lerp(&self) -> bool {
        self.kind == Kind::Lerp
    }
}

impl Source for SegmentLanes {
    #[inline(always)]
    fn p0<S: Simd>(&self, _: Ops<S>) -> Block<S> {
        regs3::<S>(&self.p0)
    }
    #[inline(always)]
    fn p1<S: Simd>(&self, _: Ops<S>) -> Block<S> {
        regs3::<S>(&self.p1)
    }
    #[inline(always)]
    fn s0<S: Simd>(&self, _: Ops<S>) -> R<S> {
        regs::<S>(&self.s0)
    }
    #[inline(always)]
    fn s1<S: Simd>(&self, _: Ops<S>) -> R<S> {
        regs::<S>(&self.s1)
    }
    #[inline(always)]
    fn r<S: Simd>(&self, _: Ops<S>, c: usize) -> R<S> {
        regs::<S>(&self.r[c])
    }
    #[inline(always)]
    fn e<S: Simd>(&self, _: Ops<S>, c: usize) -> R<S> {
        regs::<S>(&self.e[c])
    }
    #[inline(always)]
    fn theta<S: Simd>(&self, _: Ops<S>) -> R<S> {
        regs::<S>(&self.theta)
    }
    #[inline(always)]
    fn sin_theta<S: Simd>(&self, _: Ops<S>) -> R<S> {
        regs::<S>(&self.sin_theta)
    }
    #[inline(always)]
    fn code<S: Simd>(&self, _: Ops<S>) -> R<S> {
        regs::<S>(&self.arc)
    }
    #[inline(always)]
    fn has_arc(&self) -> bool {
        self.has_arc
    }
    #[inline(always)]
    fn has_lerp(&self) -> bool {
        self.has_lerp
    }
}

/// `A`, the columns of `R` and `s` at fractions `f` (`SampledAxis::at_with_parts`).
#[inline(always)]
fn frame_at<S: Simd, G: Source>(o: Ops<S>, seg: &G, f: R<S>) -> Frame<S> {
    let g = o.sub(o.splat(1.0), f);
    // Vec3::lerp: `self * (1 − s) + rhs * s`.
    let (p0, p1) = (seg.p0(o), seg.p1(o));
    let a = Block {
        x: o.add(o.mul(p0.x, g), o.mul(p1.x, f)),
        y: o.add(o.mul(p0.y, g), o.mul(p1.y, f)),
        z: o.add(o.mul(p0.z, g), o.mul(p1.z, f)),
    };
    let r: [R<S>; 4] = [seg.r(o, 0), seg.r(o, 1), seg.r(o, 2), seg.r(o, 3)];
    let mut q = r;
    if seg.has_arc() || seg.has_lerp() {
        let e: [R<S>; 4] = [seg.e(o, 0), seg.e(o, 1), seg.e(o, 2), seg.e(o, 3)];
        let code = seg.code(o);
        // SlerpArc::at: `(start · sin((1 − s) θ) + end · sin(s θ)) / sin θ` on an arc.
        if seg.has_arc() {
            let is_arc = o.eq(code, o.splat(1.0));
            let theta = seg.theta(o);
            let sin_theta = seg.sin_theta(o);
            let k1 = sin_poly(o, o.mul(theta, g));
            let k2 = sin_poly(o, o.mul(theta, f));
            for c in 0..4 {
                let slerped = o.div(o.add(o.mul(r[c], k1), o.mul(e[c], k2)), sin_theta);
                q[c] = o.select(is_arc, slerped, q[c]);
            }
        }
        // `(start (1 − s) + end s).normalize()` between nearly equal frames, the length
        // from glam's SSE2 dot product `(x² + z²) + (y² + w²)`.
        if seg.has_lerp() {
            let is_lerp = o.eq(code, o.splat(2.0));
            let mut p = r;
            for c in 0..4 {
                p[c] = o.add(o.mul(r[c], g), o.mul(e[c], f));
            }
            let xz = o.add(o.mul(p[0], p[0]), o.mul(p[2], p[2]));
            let yw = o.add(o.mul(p[1], p[1]), o.mul(p[3], p[3]));
            let len = o.sqrt(o.add(xz, yw));
            for c in 0..4 {
                q[c] = o.select(is_lerp, o.div(p[c], len), q[c]);
            }
        }
    }
    let s = o.add(o.mul(seg.s0(o), g), o.mul(seg.s1(o), f));
    Frame {
        a,
        r: from_quat(o, q),
        s,
    }
}

/// Two registers of `f32`: a lane group where the CPU has AVX2.
type R<S> = Two<<S as Simd>::f32s>;

/// A lane in registers.
#[inline(always)]
fn regs<S: Simd>(l: &Lane) -> R<S> {
    load::<S>(&l.0)
}

/// Lanes of points in registers.
#[inline(always)]
fn regs3<S: Simd>(l: &Lanes3) -> Block<S> {
    Block {
        x: regs::<S>(&l.x),
        y: regs::<S>(&l.y),
        z: regs::<S>(&l.z),
    }
}

/// Registers back into lanes of points.
#[inline(always)]
fn lanes3<S: Simd>(b: &Block<S>) -> Lanes3 {
    let mut l = Lanes3::ZERO;
    store::<S>(&mut l.x.0, b.x);
    store::<S>(&mut l.y.0, b.y);
    store::<S>(&mut l.z.0, b.z);
    l
}

/// [`crate::slerp`]'s sine polynomial in registers (the operations of `sin_poly_lanes`).
#[inline(always)]
fn sin_poly<S: Simd>(o: Ops<S>, x: R<S>) -> R<S> {
    let x = o.select(o.le(x, o.splat(FRAC_PI_2)), x, o.sub(o.splat(PI), x));
    let x2 = o.mul(x, x);
    let mut r = o.add(o.mul(o.splat(SIN[0]), x2), o.splat(SIN[1]));
    for &c in &SIN[2..] {
        r = o.add(o.mul(r, x2), o.splat(c));
    }
    o.mul(r, x)
}

/// The axis point, the frame's columns and the scale of a lane group.
#[derive(Clone, Copy)]
struct Frame<S: Simd> {
    a: Block<S>,
    r: [Block<S>; 3],
    s: R<S>,
}

/// `Mat3::from_quat(q)`'s columns.
#[inline(always)]
fn from_quat<S: Simd>(o: Ops<S>, [x, y, z, w]: [R<S>; 4]) -> [Block<S>; 3] {
    let (x2, y2, z2) = (o.add(x, x), o.add(y, y), o.add(z, z));
    let (xx, xy, xz) = (o.mul(x, x2), o.mul(x, y2), o.mul(x, z2));
    let (yy, yz, zz) = (o.mul(y, y2), o.mul(y, z2), o.mul(z, z2));
    let (wx, wy, wz) = (o.mul(w, x2), o.mul(w, y2), o.mul(w, z2));
    let one = o.splat(1.0);
    [
        Block {
            x: o.sub(one, o.add(yy, zz)),
            y: o.add(xy, wz),
            z: o.sub(xz, wy),
        },
        Block {
            x: o.sub(xy, wz),
            y: o.sub(one, o.add(xx, zz)),
            z: o.add(yz, wx),
        },
        Block {
            x: o.add(xz, wy),
            y: o.sub(yz, wx),
            z: o.sub(one, o.add(xx, yy)),
        },
    ]
}

/// `Mat3 * Vec3`: `(c₀ v.x + c₁ v.y) + c₂ v.z`.
#[inline(always)]
fn mul<S: Simd>(o: Ops<S>, m: &[Block<S>; 3], v: &Block<S>) -> Block<S> {
    o.add3(
        o.add3(o.scale(m[0], v.x), o.scale(m[1], v.y)),
        o.scale(m[2], v.z),
    )
}

impl<S: Simd> Frame<S> {
    /// `M = R · Mat3::from_diagonal((1, s, s))`, column by column as glam multiplies.
    #[inline(always)]
    fn m(&self, o: Ops<S>) -> [Block<S>; 3] {
        let (one, zero, s) = (o.splat(1.0), o.splat(0.0), self.s);
        [
            mul(
                o,
                &self.r,
                &Block {
                    x: one,
                    y: zero,
                    z: zero,
                },
            ),
            mul(
                o,
                &self.r,
                &Block {
                    x: zero,
                    y: s,
                    z: zero,
                },
            ),
            mul(
                o,
                &self.r,
                &Block {
                    x: zero,
                    y: zero,
                    z: s,
                },
            ),
        ]
    }
}

/// `c · v`, summed in the order x, y, z.
#[inline(always)]
fn dot<S: Simd>(o: Ops<S>, c: &Block<S>, v: &Block<S>) -> R<S> {
    o.add(o.add(o.mul(c.x, v.x), o.mul(c.y, v.y)), o.mul(c.z, v.z))
}

/// Whether every lane of every coordinate of `vs` is finite (`x − x` is 0 exactly for a
/// finite `x` and NaN otherwise).
#[inline(always)]
fn finite<S: Simd>(o: Ops<S>, vs: &[&Block<S>]) -> bool {
    let zero = o.splat(0.0);
    let mut ok = true;
    for v in vs {
        for c in [v.x, v.y, v.z] {
            ok &= o.all(o.eq(o.sub(c, c), zero));
        }
    }
    ok
}

impl AxisTable {
    /// The local coordinates `l` and rest images `A + M l` of points `xs` whose closest axis
    /// points are `found` (segment, fraction, squared distance), written to `local` and
    /// `base` where the weight `ws` is positive. `done[k]` is true when point `k` needs no
    /// per-vertex work: its values were written, or its weight is 0 or less (the bind keeps
    /// nothing for it); false leaves it to the per-vertex code (every slice as long as `xs`).
    /// Written values have the bits of the per-vertex bind.
    pub(crate) fn bind_each(
        &self,
        found: &[(usize, f32, f32)],
        xs: &[Vec3],
        ws: &[f32],
        local: &mut [Vec3],
        base: &mut [Vec3],
        done: &mut [bool],
    ) {
        let n = xs.len();
        assert!(
            found.len() == n
                && ws.len() == n
                && local.len() == n
                && base.len() == n
                && done.len() == n,
            "one entry per point"
        );
        pulp::Arch::new().dispatch(BindEach {
            table: self,
            found,
            xs,
            ws,
            local,
            base,
            done,
        });
    }

    /// The moved positions of the vertices `active` of a bind (`slot`, `segment`, `fraction`,
    /// `local`, `base`, `weight`: `AxialBind`'s arrays) on this (deformed) axis, written to
    /// `out` for every lane group the lanes can do; `done[k]` tells whether `out[k]` was
    /// written (`out` and `done` as long as `active`). Written values have the bits of the
    /// per-vertex deform: the input position where the vertex is not bound or has no weight,
    /// `U + D` where the weight is 1 and `U + D w` elsewhere.
    pub(crate) fn deform_each(
        &self,
        bind: BindArrays<'_>,
        positions: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
        done: &mut [bool],
    ) {
        assert!(
            out.len() == active.len() && done.len() == active.len(),
            "one entry per vertex"
        );
        pulp::Arch::new().dispatch(DeformEach {
            table: self,
            bind,
            positions,
            active,
            out,
            done,
        });
    }
}

/// An axial bind's per-vertex arrays, as [`AxisTable::deform_each`] reads them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BindArrays<'a> {
    pub(crate) slot: &'a [u32],
    pub(crate) segment: &'a [u32],
    pub(crate) fraction: &'a [f32],
    pub(crate) local: &'a [Vec3],
    pub(crate) base: &'a [Vec3],
    pub(crate) weight: &'a [f32],
}

/// [`AxisTable::bind_each`]'s kernel.
struct BindEach<'a> {
    table: &'a AxisTable,
    found: &'a [(usize, f32, f32)],
    xs: &'a [Vec3],
    ws: &'a [f32],
    local: &'a mut [Vec3],
    base: &'a mut [Vec3],
    done: &'a mut [bool],
}

impl pulp::WithSimd for BindEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        if !holds_group::<S>() {
            self.done.fill(false);
            return;
        }
        let o = Ops(simd);
        let groups = self
            .xs
            .chunks(LANES)
            .zip(self.found.chunks(LANES))
            .zip(self.ws.chunks(LANES))
            .zip(self.local.chunks_mut(LANES))
            .zip(self.base.chunks_mut(LANES))
            .zip(self.done.chunks_mut(LANES));
        let mut scratch = SegmentLanes::ZERO;
        for (((((xs, found), ws), local), base), done) in groups {
            // A NaN weight is kept by the bind: scalar path. Of the others, the lanes of
            // positive weight are bound; the rest (whose values the bind does not keep)
            // compute with the first of them.
            if ws.iter().any(|w| w.is_nan()) {
                done.fill(false);
                continue;
            }
            let Some(first) = ws.iter().position(|&w| w > 0.0) else {
                done.fill(true);
                continue;
            };
            let n = xs.len();
            let mut js = [0u32; LANES];
            let mut f = Lane::ZERO;
            let mut points = [Vec3::ZERO; LANES];
            for i in 0..LANES {
                let k = if i < n && ws[i] > 0.0 { i } else { first };
                let (j, fi, _) = found[k];
                js[i] = u32::try_from(j).unwrap_or(u32::MAX);
                f.0[i] = fi;
                points[i] = xs[k];
            }
            let Some(segments) = self.table.lanes(&js, &mut scratch) else {
                done.fill(false);
                continue;
            };
            let (u, f) = (regs3::<S>(&Lanes3::load(&points)), regs::<S>(&f));
            let frame = segments.at(o, f);
            // `l = S⁻¹ (R W)ᵀ (U − A)`: row `k` of the transpose is column `k` of `R`.
            let v = o.sub3(u, frame.a);
            let l = Block {
                x: dot(o, &frame.r[0], &v),
                y: o.div(dot(o, &frame.r[1], &v), frame.s),
                z: o.div(dot(o, &frame.r[2], &v), frame.s),
            };
            let b = o.add3(frame.a, mul(o, &frame.m(o), &l));
            // A value that is not finite (from a point or fraction that is not) could take
            // another NaN payload in registers: such a group takes the scalar path.
            let ok = finite(o, &[&u, &l, &b]);
            if ok {
                lanes3(&l).write(local);
                lanes3(&b).write(base);
            }
            done.fill(ok);
        }
    }
}

/// [`AxisTable::deform_each`]'s kernel.
struct DeformEach<'a> {
    table: &'a AxisTable,
    bind: BindArrays<'a>,
    positions: &'a [Vec3],
    active: &'a [u32],
    out: &'a mut [Vec3],
    done: &'a mut [bool],
}

impl pulp::WithSimd for DeformEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        if !holds_group::<S>() {
            self.done.fill(false);
            return;
        }
        let o = Ops(simd);
        let b = self.bind;
        let mut scratch = SegmentLanes::ZERO;
        for ((ids, out), done) in self
            .active
            .chunks(LANES)
            .zip(self.out.chunks_mut(LANES))
            .zip(self.done.chunks_mut(LANES))
        {
            let n = ids.len();
            let u = Lanes3::gather(self.positions, ids);
            // Each lane's entry in the bind, and whether it moves (bound, positive weight).
            let mut ks = [0u32; LANES];
            let mut moves = Lane::ZERO;
            let mut first = None;
            let mut nan = false;
            for i in 0..LANES {
                let slot = b.slot.get(ids[i.min(n - 1)] as usize).copied();
                if let Some(k) = slot.filter(|&k| k != u32::MAX) {
                    let w = b.weight[k as usize];
                    nan |= w.is_nan();
                    if w > 0.0 {
                        ks[i] = k;
                        moves.0[i] = 1.0;
                        first.get_or_insert(k);
                    }
                }
            }
            if nan {
                done.fill(false);
                continue;
            }
            let Some(first) = first else {
                u.write(out);
                done.fill(true);
                continue;
            };
            // The lanes that do not move compute with the first that does, and keep `U`.
            let (mut js, mut f, mut w) = ([0u32; LANES], Lane::ZERO, Lane::ZERO);
            for i in 0..LANES {
                if moves.0[i] == 0.0 {
                    ks[i] = first;
                }
                let k = ks[i] as usize;
                (js[i], f.0[i], w.0[i]) = (b.segment[k], b.fraction[k], b.weight[k]);
            }
            let Some(segments) = self.table.lanes(&js, &mut scratch) else {
                done.fill(false);
                continue;
            };
            let l = regs3::<S>(&Lanes3::gather(b.local, &ks));
            let base = regs3::<S>(&Lanes3::gather(b.base, &ks));
            let u = regs3::<S>(&u);
            let frame = segments.at(o, regs::<S>(&f));
            // D(U) − U = (A' + M₂ l) − (A + M₁ l).
            let d = o.sub3(o.add3(frame.a, mul(o, &frame.m(o), &l)), base);
            if !finite(o, &[&d, &u]) {
                done.fill(false);
                continue;
            }
            // `U + D w`, which is `U + D` exactly where `w = 1` (the scalar path's branch).
            let moved = o.add3(u, o.scale(d, regs::<S>(&w)));
            let moves = o.gt(regs::<S>(&moves), o.splat(0.0));
            lanes3(&o.select3(moves, moved, u)).write(out);
            done.fill(true);
        }
    }
}

/// Whether two registers of `S` hold a lane group (AVX2): the kernels run only then, and
/// leave every point to the per-vertex code elsewhere.
#[inline(always)]
const fn holds_group<S: Simd>() -> bool {
    2 * S::F32_LANES == LANES
}

/// Whether this CPU runs the register kernels (two registers hold a lane group: AVX2);
/// elsewhere every vertex takes the per-vertex code.
#[cfg(test)]
#[must_use]
pub(crate) fn registers_run() -> bool {
    struct Probe;
    impl pulp::WithSimd for Probe {
        type Output = bool;
        #[inline(always)]
        fn with_simd<S: Simd>(self, _: S) -> bool {
            holds_group::<S>()
        }
    }
    pulp::Arch::new().dispatch(Probe)
}
