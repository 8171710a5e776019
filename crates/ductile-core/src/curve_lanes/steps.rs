//! The Gauss–Newton steps of [`CurvePieces::closest_each`] in AVX2 registers: the same
//! operations as the lane form [`CurvePieces::closest_lanes`], on `registers.rs`'s two
//! registers of eight lanes per value (a lane group of 16) instead of `lane.rs`'s arrays.
//! On 200,000 points around a six-point curve (one thread) the steps took 31 ns per point
//! instead of 62 (Bézier) and 27 instead of 48 (cubic B-spline).
//!
//! Each lane does the lane form's operations in its order, so each answer has its bits (and
//! so [`CurvePieces::closest`]'s): the Horner sums `c·u + cᵢ` from zero, the step
//! `u − ((c − x)·c') / |c'|²` with glam's dot order, the piece a step lands in from `ceil` and
//! `floor` (`vroundps`, exact as `f32::ceil` and `f32::floor`) and the lane form's `min` and
//! clamps, and the same stopping rules. The coefficients are the lane form's table entries:
//! one broadcast when every lane is on one piece, a register permutation of a run of pieces
//! ([`CurvePieces::columns`]) when they lie within 16 of each other, else lane by lane.

use core::arch::x86_64::{__m256, __m256i};

use pulp::x86::V3;
use pulp::{f32x8, m32x8};

use super::Pieces;
use crate::curve_pieces::{CurvePieces, REFINE_STEPS};
use crate::lane::{LANES, Lane, Lanes3};
use crate::registers::{Block, Ops, Two, two};

/// A value of a lane group: two registers.
type R = Two<f32x8>;

/// A lane group's mask.
type M = Two<m32x8>;

#[inline(always)]
fn regs(l: Lane) -> R {
    bytemuck::cast(l.0)
}

#[inline(always)]
fn lane(r: R) -> Lane {
    Lane(bytemuck::cast(r))
}

#[inline(always)]
fn block(l: &Lanes3) -> Block<V3> {
    Block {
        x: regs(l.x),
        y: regs(l.y),
        z: regs(l.z),
    }
}

#[inline(always)]
fn lanes3(b: Block<V3>) -> Lanes3 {
    Lanes3 {
        x: lane(b.x),
        y: lane(b.y),
        z: lane(b.z),
    }
}

/// The least integer not below each lane, as `f32::ceil`.
#[inline(always)]
fn ceil(v3: V3, a: R) -> R {
    two!(|h| bytemuck::cast(v3.avx._mm256_ceil_ps(bytemuck::cast::<f32x8, __m256>(a[h]))))
}

/// The greatest integer not above each lane, as `f32::floor`.
#[inline(always)]
fn floor(v3: V3, a: R) -> R {
    two!(|h| bytemuck::cast(
        v3.avx
            ._mm256_floor_ps(bytemuck::cast::<f32x8, __m256>(a[h]))
    ))
}

/// `a` where `b` is NaN or `a < b`, else `b`: [`Lane::min`].
#[inline(always)]
fn min(o: Ops<V3>, a: R, b: R) -> R {
    let m = o.or(o.lt(a, b), o.not(o.eq(b, b)));
    o.select(m, a, b)
}

impl CurvePieces {
    /// [`CurvePieces::closest_lanes`] in registers: each lane's piece, local parameter,
    /// point and squared distance, the same bits. `p` is the degree.
    #[inline(always)]
    pub(super) fn closest_registers(
        &self,
        v3: V3,
        p: usize,
        x: &Lanes3,
        seg: Lane,
        frac: Lane,
    ) -> (Lane, Lane, Lanes3, Lane) {
        let o = Ops(v3);
        let x = block(x);
        let (zero, one) = (o.splat(0.0), o.splat(1.0));
        let infinity = o.splat(f32::INFINITY);
        let last = o.splat((self.count - 1) as f32);
        let (mut k, mut u) = self.settled_registers(o, regs(seg), regs(frac));
        let (mut c, mut dc) = self.point_and_tangent_registers(o, p, k, u);
        let mut best = o.length_squared(o.sub3(c, x));
        let mut going: M = o.eq(zero, zero);
        for _ in 0..REFINE_STEPS {
            let l2 = o.length_squared(dc);
            // `l2 > 0` and finite.
            going = o.and(going, o.and(o.gt(l2, zero), o.lt(l2, infinity)));
            if !o.any(going) {
                break;
            }
            let next = o.sub(u, o.div(o.dot(o.sub3(c, x), dc), l2));
            going = o.and(going, o.eq(next, next));
            let back = min(o, ceil(v3, o.neg(next)), k);
            let ahead = min(o, floor(v3, next), o.sub(last, k));
            let below = o.lt(next, zero);
            let above = o.gt(next, one);
            let kn = o.select(below, o.sub(k, back), o.select(above, o.add(k, ahead), k));
            let un = o.select(
                below,
                o.clamp01(o.add(next, back)),
                o.select(above, o.clamp01(o.sub(next, ahead)), next),
            );
            let (kn, un) = self.settled_registers(o, kn, un);
            let (cn, dn) = self.point_and_tangent_registers(o, p, kn, un);
            let d = o.length_squared(o.sub3(cn, x));
            going = o.and(going, o.lt(d, best));
            best = o.select(going, d, best);
            k = o.select(going, kn, k);
            u = o.select(going, un, u);
            c = o.select3(going, cn, c);
            dc = o.select3(going, dn, dc);
        }
        (lane(k), lane(u), lanes3(c), lane(best))
    }

    /// [`CurvePieces::settled_lanes`] in registers.
    #[inline(always)]
    fn settled_registers(&self, o: Ops<V3>, k: R, u: R) -> (R, R) {
        let one = o.splat(1.0);
        let next = o.add(k, one);
        let m = o.and(o.ge(u, one), o.lt(next, o.splat(self.count as f32)));
        (o.select(m, next, k), o.select(m, o.splat(0.0), u))
    }

    /// [`CurvePieces::point_and_tangent_lanes`] in registers, for degree `p`.
    #[inline(always)]
    fn point_and_tangent_registers(
        &self,
        o: Ops<V3>,
        p: usize,
        k: R,
        u: R,
    ) -> (Block<V3>, Block<V3>) {
        debug_assert_eq!(p, self.degree);
        let q = p.max(1);
        let pieces = Pieces::from_registers(o.0, k, self.count);
        let zero = o.splat3(glam::Vec3::ZERO);
        let (mut c, mut d) = (zero, zero);
        // Three Horner loops, one per way of taking the coefficients, on purpose: one loop
        // taking them from a closure ran the closest-point bench 5.4 times slower (closures
        // do not inherit the caller's target features, so their intrinsics became calls).
        if pieces.same {
            let (curve, tangent) = (
                &self.curve[pieces.first * (p + 1)..],
                &self.tangent[pieces.first * q..],
            );
            for i in (0..=p).rev() {
                c = o.add3(o.scale(c, u), o.splat3(curve[i]));
            }
            for i in (0..q).rev() {
                d = o.add3(o.scale(d, u), o.splat3(tangent[i]));
            }
        } else if let Some((v3, rel, wide)) = pieces.window {
            for i in (0..=p).rev() {
                let ci = self.window_column(v3, i, pieces.first, rel, wide);
                c = o.add3(o.scale(c, u), ci);
            }
            for i in (0..q).rev() {
                let di = self.window_column(v3, p + 1 + i, pieces.first, rel, wide);
                d = o.add3(o.scale(d, u), di);
            }
        } else {
            for i in (0..=p).rev() {
                c = o.add3(o.scale(c, u), block(&pieces.gather(&self.curve, p + 1, i)));
            }
            for i in (0..q).rev() {
                d = o.add3(o.scale(d, u), block(&pieces.gather(&self.tangent, q, i)));
            }
        }
        (c, d)
    }

    /// Coefficient `column` of each lane's piece `first + rel[j]`: the run of pieces loaded,
    /// each lane's own picked by `vpermps`.
    #[inline(always)]
    fn window_column(
        &self,
        v3: V3,
        column: usize,
        first: usize,
        rel: [__m256i; 2],
        wide: bool,
    ) -> Block<V3> {
        Block {
            x: bytemuck::cast(permuted(v3, self.column_run(column, 0, first), rel, wide)),
            y: bytemuck::cast(permuted(v3, self.column_run(column, 1, first), rel, wide)),
            z: bytemuck::cast(permuted(v3, self.column_run(column, 2, first), rel, wide)),
        }
    }
}

/// Lane `j` of the result is `run[rel[j]]` (`rel[j] < 16`, below 8 unless `wide`): the run
/// loaded in one or two registers, each lane's value picked by `vpermps` (which reads the
/// low three bits of the index) and, where `wide`, the register chosen by `rel[j] ≥ 8`.
#[inline(always)]
fn permuted(v3: V3, run: &[f32], rel: [__m256i; 2], wide: bool) -> [__m256; 2] {
    let low: __m256 = bytemuck::pod_read_unaligned(bytemuck::cast_slice(&run[..8]));
    let mut out = [
        v3.avx2._mm256_permutevar8x32_ps(low, rel[0]),
        v3.avx2._mm256_permutevar8x32_ps(low, rel[1]),
    ];
    if wide {
        let high: __m256 = bytemuck::pod_read_unaligned(bytemuck::cast_slice(&run[8..16]));
        let seven = v3.avx._mm256_set1_epi32(7);
        for (o, r) in out.iter_mut().zip(rel) {
            let upper = v3
                .avx
                ._mm256_castsi256_ps(v3.avx2._mm256_cmpgt_epi32(r, seven));
            let picked = v3.avx2._mm256_permutevar8x32_ps(high, r);
            *o = v3.avx._mm256_blendv_ps(*o, picked, upper);
        }
    }
    out
}

impl Pieces {
    /// [`Pieces::new`] of the lanes' pieces `k` in registers, with the register permutation:
    /// the same fields, from vector operations. The pieces are clamped as `indices` clamps
    /// them (`(k as usize).min(count − 1)`: `vmaxps` gives its second operand, 0, for a NaN,
    /// and every value left is an exact integer below `2²⁴`), their least and greatest taken
    /// across the registers, and each lane's place in the window is a vector difference.
    /// The pieces one by one, read back from memory, are only written out where the lanes
    /// are gathered one by one (neither one piece nor a window of 16): `Pieces::new` wrote
    /// them, and the window, a lane at a time, and the window's registers then waited for
    /// those sixteen stores.
    #[inline(always)]
    fn from_registers(v3: V3, k: R, count: usize) -> Self {
        let (avx, avx2) = (v3.avx, v3.avx2);
        let zero = avx._mm256_setzero_ps();
        let top = avx._mm256_set1_ps((count - 1) as f32);
        let pieces: [__m256i; 2] = two!(|h| {
            let kh: __m256 = bytemuck::cast(k[h]);
            avx._mm256_cvttps_epi32(avx._mm256_min_ps(avx._mm256_max_ps(kh, zero), top))
        });
        let least = avx2._mm256_min_epi32(pieces[0], pieces[1]);
        let least = avx2._mm256_min_epi32(least, avx2._mm256_permute2x128_si256::<1>(least, least));
        let least = avx2._mm256_min_epi32(least, avx2._mm256_shuffle_epi32::<0b0100_1110>(least));
        let least = avx2._mm256_min_epi32(least, avx2._mm256_shuffle_epi32::<0b1011_0001>(least));
        let most = avx2._mm256_max_epi32(pieces[0], pieces[1]);
        let most = avx2._mm256_max_epi32(most, avx2._mm256_permute2x128_si256::<1>(most, most));
        let most = avx2._mm256_max_epi32(most, avx2._mm256_shuffle_epi32::<0b0100_1110>(most));
        let most = avx2._mm256_max_epi32(most, avx2._mm256_shuffle_epi32::<0b1011_0001>(most));
        // Both in `0..count`, so the casts are exact.
        let (first, last) = (
            avx2._mm256_cvtsi256_si32(least) as usize,
            avx2._mm256_cvtsi256_si32(most) as usize,
        );
        let same = first == last;
        let window = (last - first < 16).then(|| {
            let rel = two!(|h| avx2._mm256_sub_epi32(pieces[h], least));
            (v3, rel, last - first >= 8)
        });
        let mut k = [0; LANES];
        if !same && window.is_none() {
            let each: [i32; LANES] = bytemuck::cast(pieces);
            for (o, &kj) in k.iter_mut().zip(&each) {
                *o = kj as usize;
            }
        }
        Self {
            k,
            first,
            same,
            window,
        }
    }
}
