//! The FFSD deformation `P = V + limit(Σₖ dₖ(V))` and the search for each point's nearest
//! vertex `V_min`, on blocks of vertices, two SIMD registers per value, in [`pulp`]'s
//! explicit vector operations: 16 vertices where the CPU has AVX2. Two independent registers
//! per step keep the long chain of `exp` from stalling the core on each operation's latency.
//! Without AVX2, `pulp` dispatches to scalar code (one lane per register), and the callers
//! run the lanes' kernels there instead, which the compiler vectorises for SSE2; the generic
//! code here still runs at that width in the tests.
//!
//! The same kernels on [`crate::lane`]'s sixteen-float lanes (plain loops the compiler
//! vectorises) came out of the compiler partly lane by lane: it vectorised the three
//! coordinates of one vertex, with a shuffle per lane, instead of one coordinate of eight
//! vertices. On 1,600 vertices, one thread (2026-11-27): 6.6 → 5.3 ns per vertex for one
//! point, 4.8 → 3.4 ns per vertex and point for two, 4.0 → 2.5 ns for four. This code states
//! every register operation and takes the lanes' operations in the lanes' order (no fused
//! multiply–add), so every vertex gets the bits of [`super::FfsdTool::deform_lanes`], which
//! the tests check at the dispatched width and in scalar code.
//!
//! The blocks and the shared operations are [`crate::registers`]'.
//!
//! `exp` is the lanes' [`crate::lane::Lane::exp`] where every lane of the block is in
//! `[−87, 87]` (its range reduction and polynomial, `2ʳ` built in the exponent bits) or below
//! `−103.63` (0); any other block (subnormal `2ʳ`, overflow, NaN) is handed to the lanes'
//! `exp`, lane for lane the same function.

use glam::Vec3;
use pulp::Simd;

use super::{FfsdBind, FfsdTool, HeightLimit};
use crate::lane::{LANES, Lane};
use crate::registers::{Block, MAX_BLOCK, Ops, Two, load, store, two};

/// `ln 2` in two parts and `exp`'s polynomial, as [`crate::lane`] takes them.
use crate::lane::{EXP_P, LN2_HI, LN2_LO};

/// The FFSD kernels' own register operations.
impl<S: Simd> Ops<S> {
    /// Rounded to the nearest integer, ties to even: below `2²³` in magnitude, adding and
    /// taking away `±2²³` (the sign of the lane) rounds; above it every `f32` is an integer
    /// ([`crate::lane::Lane`]'s `round_ties_even`).
    #[inline(always)]
    fn round_ties_even(self, x: Two<S::f32s>) -> Two<S::f32s> {
        const TWO_23: f32 = 8_388_608.0;
        let s = self.0;
        let (sign, two_23) = (s.splat_u32s(0x8000_0000), s.splat_u32s(TWO_23.to_bits()));
        let c = two!(|i| s
            .transmute_f32s_u32s(s.or_u32s(s.and_u32s(s.transmute_u32s_f32s(x[i]), sign), two_23)));
        let rounded = self.sub(self.add(x, c), c);
        let small = self.lt(two!(|i| s.abs_f32s(x[i])), self.splat(TWO_23));
        self.select(small, rounded, x)
    }

    /// `eˣ` in each lane, the bits of [`Lane::exp`].
    #[inline(always)]
    fn exp(self, x: Two<S::f32s>) -> Two<S::f32s> {
        let s = self.0;
        let normal = self.and(self.ge(x, self.splat(-87.0)), self.le(x, self.splat(87.0)));
        let zero = self.lt(x, self.splat(-103.63));
        if !self.all(self.or(normal, zero)) {
            return exp_outside::<S>(x);
        }
        // `Lane::exp`'s common case: `r = round(x / ln 2)` in [−126, 126], so `2ʳ` is normal
        // (`wide`'s `vm_pow2n` without its subnormal branch).
        let r = self.round_ties_even(self.mul(x, self.splat(core::f32::consts::LOG2_E)));
        let t = self.sub(x, self.mul(r, self.splat(LN2_HI)));
        let t = self.sub(t, self.mul(r, self.splat(LN2_LO)));
        let t2 = self.mul(t, t);
        let t4 = self.mul(t2, t2);
        let p = [
            self.splat(EXP_P[0]),
            self.splat(EXP_P[1]),
            self.splat(EXP_P[2]),
            self.splat(EXP_P[3]),
            self.splat(EXP_P[4]),
            self.splat(EXP_P[5]),
        ];
        let z = self.add(
            self.mul(self.add(self.mul(p[3], t), p[2]), t2),
            self.add(
                self.mul(self.add(self.mul(p[5], t), p[4]), t4),
                self.add(self.mul(p[1], t), p[0]),
            ),
        );
        let z = self.add(self.mul(z, t2), t);
        let z = self.add(z, self.splat(1.0));
        let a = self.add(r, self.splat(127.0 + 8_388_608.0));
        let shift = s.splat_u32s(23);
        let pow2 =
            two!(|i| s
                .transmute_f32s_u32s(s.wrapping_dyn_shl_u32s(s.transmute_u32s_f32s(a[i]), shift)));
        self.select(zero, self.splat(0.0), self.mul(z, pow2))
    }

    /// `limit` of a block of summed displacements `d` (`s = |d|`; a zero `d` unchanged): the
    /// operations of [`HeightLimit::limit_lanes`].
    #[inline(always)]
    fn limit(self, h: &HeightLimit, d: Block<S>, s_ref: f32) -> Block<S> {
        let len = self.sqrt(self.length_squared(d));
        let zero = self.eq(len, self.splat(0.0));
        let nothing = self.splat3(Vec3::ZERO);
        let limited = match *h {
            HeightLimit::Above { theta } => {
                let s_max = self.splat(theta * s_ref);
                let over = self.gt(len, s_max);
                self.select3(over, self.scale(d, self.div(s_max, len)), d)
            }
            HeightLimit::Below { theta } => {
                let s_min = self.splat(theta * s_ref);
                let under = self.le(len, s_min);
                let k = self.div(self.sub(len, s_min), len);
                self.select3(under, nothing, self.scale(d, k))
            }
            HeightLimit::Both { below, above } => {
                let (lo, hi) = (self.splat(below * s_ref), self.splat(above * s_ref));
                let under = self.le(len, lo);
                // `Lane::min`: `a` where `b` is NaN or `a < b`, else `b`.
                let (a, b) = (self.sub(len, lo), self.sub(hi, lo));
                let keep_a = self.or(self.lt(a, b), self.not(self.eq(b, b)));
                let k = self.div(self.select(keep_a, a, b), len);
                self.select3(under, nothing, self.scale(d, k))
            }
        };
        self.select3(zero, d, limited)
    }

    /// `P = V + limit(Σₖ dₖ(V))` for the block `v`: the operations of
    /// [`FfsdTool::deform_lanes`] (`D` summed in point order from zero). Every point's
    /// `α` is 2 or 1 (see [`supports`]).
    #[inline(always)]
    fn deform(self, tool: &FfsdTool, bind: &FfsdBind, v: Block<S>) -> Block<S> {
        let mut acc = self.splat3(Vec3::ZERO);
        for p in &bind.points {
            let d2 = self.length_squared(self.sub3(self.splat3(p.centre), v));
            let pow = if p.half_alpha == 1.0 {
                d2
            } else {
                self.sqrt(d2)
            };
            let e = self.mul(
                self.sub(pow, self.splat(p.anchor_pow)),
                self.splat(p.inv_two_eps2),
            );
            let w = self.exp(self.neg(e));
            let w = self.select(self.eq(w, w), w, self.splat(0.0));
            let g = self.mul(self.splat(p.gamma), w);
            let push = self.scale(self.sub3(v, self.splat3(p.target)), g);
            acc = self.add3(acc, push);
        }
        let d = match &tool.height {
            Some(h) => self.limit(h, acc, bind.s_ref),
            None => acc,
        };
        self.add3(v, d)
    }
}

/// [`Lane::exp`] on the lanes of `x`: the blocks outside `exp`'s common case (subnormal or
/// infinite `2ʳ`, NaN), lane for lane the same function.
#[inline(always)]
fn exp_outside<S: Simd>(x: Two<S::f32s>) -> Two<S::f32s> {
    let n = S::F32_LANES;
    let mut lanes = [0.0_f32; MAX_BLOCK];
    store::<S>(&mut lanes[..2 * n], x);
    exp_lanes(&mut lanes, (2 * n).div_ceil(LANES));
    load::<S>(&lanes[..2 * n])
}

/// [`Lane::exp`] in place on the first `groups` lane groups of `x`.
#[inline(never)]
fn exp_lanes(x: &mut [f32; MAX_BLOCK], groups: usize) {
    for part in x.as_chunks_mut::<LANES>().0.iter_mut().take(groups) {
        *part = Lane(*part).exp().0;
    }
}

/// Whether this kernel evaluates `bind`: every point's `α` is 2 or 1, whose `|X − V|^α` is
/// `d²` or `√d²` (another `α` takes `ln` and `exp` per lane: the lanes' kernel does those).
pub(super) fn supports(bind: &FfsdBind) -> bool {
    bind.points
        .iter()
        .all(|p| p.half_alpha == 1.0 || p.half_alpha == 0.5)
}

/// Vertices gathered into coordinate arrays at once, before any is loaded into registers:
/// a register loaded right after the scalar stores that wrote it waits for them (the
/// store buffer cannot forward several stores to one load).
const STAGE: usize = 256;

/// A stage of vertices: their x, y and z coordinates.
type Stage = [[f32; STAGE]; 3];

/// Gathers `len` vertices into `c` (`positions[ids[k]]`, or `positions[k]` without `ids`),
/// the last one repeated up to `padded` lanes (their results are dropped). The vertices
/// stay where `c` is, to be loaded a block at a time after all of them are written.
#[inline(always)]
fn gather(c: &mut Stage, positions: &[Vec3], ids: Option<&[u32]>, len: usize, padded: usize) {
    for l in 0..padded {
        let k = l.min(len - 1);
        let v = match ids {
            Some(ids) => positions[ids[k] as usize],
            None => positions[k],
        };
        (c[0][l], c[1][l], c[2][l]) = (v.x, v.y, v.z);
    }
}

/// The block of the stage's lanes `b..b + n`.
#[inline(always)]
fn load_block<S: Simd>(c: &Stage, b: usize) -> Block<S> {
    let n = 2 * S::F32_LANES;
    Block {
        x: load::<S>(&c[0][b..b + n]),
        y: load::<S>(&c[1][b..b + n]),
        z: load::<S>(&c[2][b..b + n]),
    }
}

/// Deforms the vertices `ids` of `positions` (or, with `ids` `None`, every position in
/// order) into `out`: [`STAGE`] vertices gathered into coordinate arrays, then deformed a
/// block of two registers at a time, then written out.
#[inline(always)]
pub(super) fn deform<S: Simd>(
    simd: S,
    tool: &FfsdTool,
    bind: &FfsdBind,
    positions: &[Vec3],
    ids: Option<&[u32]>,
    out: &mut [Vec3],
) {
    let ops = Ops(simd);
    let n = 2 * S::F32_LANES;
    debug_assert!(n <= MAX_BLOCK && STAGE.is_multiple_of(n));
    let mut c: Stage = [[0.0; STAGE]; 3];
    for (start, out) in (0..).step_by(STAGE).zip(out.chunks_mut(STAGE)) {
        let len = out.len();
        let padded = len.div_ceil(n) * n;
        match ids {
            Some(ids) => gather(&mut c, positions, Some(&ids[start..]), len, padded),
            None => gather(&mut c, &positions[start..], None, len, padded),
        }
        for b in (0..padded).step_by(n) {
            let r = ops.deform(tool, bind, load_block::<S>(&c, b));
            store::<S>(&mut c[0][b..b + n], r.x);
            store::<S>(&mut c[1][b..b + n], r.y);
            store::<S>(&mut c[2][b..b + n], r.z);
        }
        for (l, o) in out.iter_mut().enumerate() {
            *o = Vec3::new(c[0][l], c[1][l], c[2][l]);
        }
    }
}

/// For each of `centres`, the vertex of `chunk` nearest to it and its squared distance
/// `|V − X|²` (glam's `distance_squared` arithmetic: `(V − X)`, then `x² + y² + z²`), the
/// first one on ties: blocks of two registers in order, and only where a lane beats the best
/// so far, the block's lanes in order with the same strict test.
#[inline(always)]
pub(super) fn nearest<S: Simd>(
    simd: S,
    positions: &[Vec3],
    chunk: &[u32],
    centres: &[Vec3],
) -> Vec<(u32, f32)> {
    let ops = Ops(simd);
    let n = 2 * S::F32_LANES;
    debug_assert!(n <= MAX_BLOCK && STAGE.is_multiple_of(n));
    let mut best = vec![(chunk[0], f32::INFINITY); centres.len()];
    let mut c: Stage = [[0.0; STAGE]; 3];
    let mut d = [0.0_f32; MAX_BLOCK];
    for part in chunk.chunks(STAGE) {
        let len = part.len();
        let padded = len.div_ceil(n) * n;
        gather(&mut c, positions, Some(part), len, padded);
        for b in (0..padded).step_by(n) {
            let v = load_block::<S>(&c, b);
            let lanes = n.min(len - b);
            for (best, &x) in best.iter_mut().zip(centres) {
                let dist = ops.length_squared(ops.sub3(v, ops.splat3(x)));
                if !ops.any(ops.lt(dist, ops.splat(best.1))) {
                    continue;
                }
                store::<S>(&mut d[..n], dist);
                for (l, &dl) in d[..lanes].iter().enumerate() {
                    if dl < best.1 {
                        *best = (part[b + l], dl);
                    }
                }
            }
        }
    }
    best
}
