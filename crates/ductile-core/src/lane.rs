//! Sixteen `f32` lanes whose operations the compiler vectorises for whatever target a kernel
//! is compiled for, so that one kernel runs 4 lanes a register on baseline x86-64 (SSE2) and
//! 8 where [`pulp`]'s runtime dispatch finds AVX2.
//!
//! Every operation is lane by lane and exactly rounded (IEEE sums, products, quotients and
//! square roots, comparisons, bit operations): no operation is fused, so a lane gets the
//! same bits whatever register width computes it. [`Lane::exp`] and [`Lane::ln`] are the
//! polynomial approximations of the `wide` crate (a few ulp) written in these operations;
//! they give the bits of `wide::f32x16`'s functions on a target without FMA, which the
//! tests check on millions of inputs. `wide` chooses its instructions when the crate is
//! compiled, so its code cannot use AVX2 in a binary built for every x86-64 CPU — hence this
//! type.
//!
//! Every function is `#[inline(always)]`: a kernel compiled for AVX2 (a function with
//! `#[target_feature]`, as [`pulp`] generates) vectorises only what is inlined into it.

use core::f32::consts::{LOG2_E, SQRT_2};
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::Vec3;

/// Lanes per group.
pub(crate) const LANES: usize = 16;

/// Sixteen `f32` values, operated on lane by lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Lane(pub(crate) [f32; LANES]);

/// A lane mask: all bits set where true.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(C, align(64))]
pub(crate) struct Mask([u32; LANES]);

/// `[e(0), …, e(15)]` for an expression `e` of the lane index, written as a loop the
/// compiler turns into vector code (a macro, not a closure: a closure is a function of its
/// own, compiled without the target features of the kernel that calls it).
macro_rules! each {
    (|$i:ident| $e:expr) => {{
        let mut out = [Default::default(); LANES];
        for ($i, o) in out.iter_mut().enumerate() {
            *o = $e;
        }
        out
    }};
}

/// All bits set when `b`.
#[inline(always)]
fn full(b: bool) -> u32 {
    if b { u32::MAX } else { 0 }
}

impl Lane {
    /// Every lane 0.
    pub(crate) const ZERO: Self = Self([0.0; LANES]);

    /// Every lane `v`.
    #[inline(always)]
    #[must_use]
    pub(crate) const fn splat(v: f32) -> Self {
        Self([v; LANES])
    }

    /// The lanes as an array.
    #[inline(always)]
    #[must_use]
    pub(crate) fn as_array(&self) -> &[f32; LANES] {
        &self.0
    }

    #[inline(always)]
    fn bits(self) -> [u32; LANES] {
        each!(|i| self.0[i].to_bits())
    }

    #[inline(always)]
    fn from_bits(b: [u32; LANES]) -> Self {
        Self(each!(|i| f32::from_bits(b[i])))
    }

    /// `self == o` (ordered: false where either is NaN).
    #[inline(always)]
    #[must_use]
    pub(crate) fn simd_eq(self, o: Self) -> Mask {
        Mask(each!(|i| full(self.0[i] == o.0[i])))
    }

    /// `self < o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn simd_lt(self, o: Self) -> Mask {
        Mask(each!(|i| full(self.0[i] < o.0[i])))
    }

    /// `self <= o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn simd_le(self, o: Self) -> Mask {
        Mask(each!(|i| full(self.0[i] <= o.0[i])))
    }

    /// `self > o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn simd_gt(self, o: Self) -> Mask {
        Mask(each!(|i| full(self.0[i] > o.0[i])))
    }

    /// `self >= o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn simd_ge(self, o: Self) -> Mask {
        Mask(each!(|i| full(self.0[i] >= o.0[i])))
    }

    /// `|x|`: the sign bit cleared, as `f32::abs`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn abs(self) -> Self {
        Self::from_bits(each!(|i| self.0[i].to_bits() & 0x7FFF_FFFF))
    }

    /// The greater lane, as glam's `max_element` compares: `self > o ? self : o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn greater(self, o: Self) -> Self {
        self.simd_gt(o).select(self, o)
    }

    /// The least integer not below each lane, as `f32::ceil`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn ceil(self) -> Self {
        Self(each!(|i| self.0[i].ceil()))
    }

    /// The greatest integer not above each lane, as `f32::floor`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn floor(self) -> Self {
        Self(each!(|i| self.0[i].floor()))
    }

    /// `√x`, exactly rounded.
    #[inline(always)]
    #[must_use]
    pub(crate) fn sqrt(self) -> Self {
        Self(each!(|i| self.0[i].sqrt()))
    }

    /// `f32::clamp(0, 1)` in each lane: 0 below, 1 above, NaN kept.
    #[inline(always)]
    #[must_use]
    pub(crate) fn clamp01(self) -> Self {
        let (zero, one) = (Self::ZERO, Self::splat(1.0));
        let q = self.simd_lt(zero).select(zero, self);
        q.simd_gt(one).select(one, q)
    }

    /// The lesser lane, as SSE's `minps` after a NaN test of `o` (the `wide` crate's
    /// `min`): `self` where `o` is NaN, else `self < o ? self : o`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn min(self, o: Self) -> Self {
        Self(each!(|i| {
            let (a, b) = (self.0[i], o.0[i]);
            if b.is_nan() || a < b { a } else { b }
        }))
    }

    #[inline(always)]
    fn is_nan(self) -> Mask {
        Mask(each!(|i| full(self.0[i].is_nan())))
    }

    /// Neither infinite nor NaN.
    #[inline(always)]
    pub(crate) fn is_finite(self) -> Mask {
        Mask(each!(|i| {
            full((self.0[i].to_bits() << 1) & 0xFF00_0000 != 0xFF00_0000)
        }))
    }

    #[inline(always)]
    fn is_sign_negative(self) -> Mask {
        Mask(each!(|i| full(self.0[i].to_bits() & 0x8000_0000 != 0)))
    }

    #[inline(always)]
    fn is_zero_or_subnormal(self) -> Mask {
        Mask(each!(|i| full(self.0[i].to_bits() & 0x7F80_0000 == 0)))
    }

    /// Rounded to the nearest integer, ties to even, as SSE2's `cvtps2dq` and back (`wide`
    /// without SSE4.1): the value itself beyond `2³¹` and for NaN, `+0` for a zero result.
    /// Below `2²³` in magnitude, adding and taking away `±2²³` rounds in the current
    /// (nearest-even) mode; above it every `f32` is an integer.
    #[inline(always)]
    fn round_ties_even(self) -> Self {
        const TWO_23: f32 = 8_388_608.0;
        Self(each!(|i| {
            let x = self.0[i];
            if x.abs() < TWO_23 {
                let c = f32::from_bits((x.to_bits() & 0x8000_0000) | TWO_23.to_bits());
                (x + c) - c
            } else {
                x
            }
        }))
    }

    /// `2ⁿ` for integral lanes `n` (`wide`'s `vm_pow2n`), subnormal from `n < −126` down to
    /// `−149`, 0 below.
    #[inline(always)]
    fn pow2n(self) -> Self {
        let a = self + Self::splat(127.0 + 8_388_608.0);
        let normal = Self::from_bits(each!(|i| a.0[i].to_bits() << 23));
        let is_sub = self.simd_lt(Self::splat(-126.0));
        if !is_sub.any() {
            return normal;
        }
        let valid = self.simd_ge(Self::splat(-149.0));
        let shift = self + Self::splat(149.0);
        let sub = Self::from_bits(each!(|i| {
            if valid.0[i] != 0 {
                1_u32.wrapping_shl(shift.0[i] as i32 as u32)
            } else {
                0
            }
        }));
        is_sub.select(sub, normal)
    }

    /// The binary exponent of normal lanes, as a float (`wide`'s `exponent`).
    #[inline(always)]
    fn exponent(self) -> Self {
        let b = Self::from_bits(each!(
            |i| (self.0[i].to_bits() >> 23) | 8_388_608.0_f32.to_bits()
        ));
        b - Self::splat(8_388_608.0 + 127.0)
    }

    /// The mantissa scaled into `[0.5, 1)` (`wide`'s `fraction_2`).
    #[inline(always)]
    fn fraction_2(self) -> Self {
        Self::from_bits(each!(|i| (self.0[i].to_bits() & 0x007F_FFFF) | 0x3F00_0000))
    }

    /// `eˣ`: `wide::f32x16::exp` (range reduction by `ln 2` in two parts, a degree-5
    /// polynomial), the same operations in the same order without fused multiply–adds.
    #[inline(always)]
    #[must_use]
    pub(crate) fn exp(self) -> Self {
        // The common case, every lane in [−103.63, 87]: finite, not below the underflow to
        // 0, and `2^r` at most 2^126, so each special case below would keep the polynomial's
        // value; the same operations without them.
        if (self.simd_ge(Self::splat(-103.63)) & self.simd_le(Self::splat(87.0))).all() {
            let r = (self * Self::splat(LOG2_E)).round_ties_even();
            return self.exp_reduced(r) * r.pow2n();
        }
        let finite = self.is_finite();
        let neg_underflow = self.simd_lt(Self::splat(-103.63)) & finite;
        if neg_underflow.all() {
            return Self::ZERO;
        }
        let max_r = Self::splat(127.0);
        let r = (self * Self::splat(LOG2_E)).round_ties_even();
        let big = r.simd_gt(max_r);
        let r_safe = big.select(max_r, r);
        // `2^(r − 127)` where `r` passes 127, else 1 (and a product by 1 changes no bits).
        let scaled = big.any();
        let excess = big.select(r - max_r, Self::ZERO);
        let z = self.exp_reduced(r);
        let z = if scaled { z * excess.pow2n() } else { z };
        let z = z * r_safe.pow2n();
        let nan = self.is_nan();
        let result = nan.select(NAN, z);
        let result = (self.simd_gt(Self::splat(88.723)) & finite).select(INFINITY, result);
        let result = neg_underflow.select(Self::ZERO, result);
        let negative = self.is_sign_negative();
        let result = (!finite & !negative & !nan).select(INFINITY, result);
        (!finite & negative & !nan).select(Self::ZERO, result)
    }

    /// `e^(x − r·ln 2)` for `x = self` and `r` the integer nearest `x / ln 2`: the range
    /// reduction by `ln 2` in two parts, then the degree-5 polynomial, of [`Lane::exp`].
    #[inline(always)]
    fn exp_reduced(self, r: Self) -> Self {
        let x = self - r * Self::splat(LN2_HI);
        let x = x - r * Self::splat(LN2_LO);
        let x2 = x * x;
        let x4 = x2 * x2;
        let z = (Self::splat(EXP_P[3]) * x + Self::splat(EXP_P[2])) * x2
            + ((Self::splat(EXP_P[5]) * x + Self::splat(EXP_P[4])) * x4
                + (Self::splat(EXP_P[1]) * x + Self::splat(EXP_P[0])));
        let z = z * x2 + x;
        z + Self::splat(1.0)
    }

    /// `ln x`: `wide::f32x16::ln` (mantissa in `[√½, √2)`, a degree-8 polynomial), the same
    /// operations in the same order without fused multiply–adds.
    #[inline(always)]
    #[must_use]
    pub(crate) fn ln(self) -> Self {
        let half = Self::splat(0.5);
        let one = Self::splat(1.0);
        let x = self.fraction_2();
        let e = self.exponent();
        let mask = x.simd_gt(Self::splat(SQRT_2) * half);
        let x = (!mask).select(x + x, x);
        let fe = mask.select(e + one, e);
        let x = x - one;
        let x2 = x * x;
        let x4 = x2 * x2;
        let x8 = x4 * x4;
        let res = x4
            * (x2 * (Self::splat(LN_P[7]) * x + Self::splat(LN_P[6]))
                + (x * Self::splat(LN_P[5]) + Self::splat(LN_P[4])))
            + (x8 * Self::splat(LN_P[8])
                + (x2 * (x * Self::splat(LN_P[3]) + Self::splat(LN_P[2]))
                    + (x * Self::splat(LN_P[1]) + Self::splat(LN_P[0]))));
        let res = x2 * x * res;
        let res = fe * Self::splat(LN2_LO) + res;
        let res = res + (x - x2 * half);
        let res = fe * Self::splat(LN2_HI) + res;
        let overflow = !self.is_finite();
        let underflow = self.simd_lt(Self::splat(f32::MIN_POSITIVE));
        if !(overflow | underflow).any() {
            return res;
        }
        let res = underflow.select(NAN, res);
        let res = self.is_zero_or_subnormal().select(-INFINITY, res);
        let res = overflow.select(self, res);
        (overflow & self.is_sign_negative()).select(NAN, res)
    }
}

/// The coefficients of `exp`'s polynomial (`1/k!` from `k = 2`).
pub(crate) const EXP_P: [f32; 6] = [
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
];

/// The coefficients of `ln`'s polynomial, as `wide` writes them.
#[allow(clippy::excessive_precision)]
const LN_P: [f32; 9] = [
    3.3333331174E-1,
    -2.4999993993E-1,
    2.0000714765E-1,
    -1.6668057665E-1,
    1.4249322787E-1,
    -1.2420140846E-1,
    1.1676998740E-1,
    -1.1514610310E-1,
    7.0376836292E-2,
];

/// `ln 2` in two parts (fdlibm's split, as `wide` writes it): `LN2_HI = 0.693359375` has few
/// mantissa bits, so `r · LN2_HI` is exact for the `r` of a range reduction.
pub(crate) const LN2_HI: f32 = 355.0 / 512.0;
/// `ln 2 − LN2_HI`, as `wide` writes it.
#[allow(clippy::excessive_precision)]
pub(crate) const LN2_LO: f32 = -2.12194440e-4;

/// The quiet NaN `wide` returns from `exp` and `ln`.
const NAN: Lane = Lane([f32::from_bits(0x7FC0_0101); LANES]);
const INFINITY: Lane = Lane::splat(f32::INFINITY);

impl Mask {
    /// No lane set.
    pub(crate) const NONE: Self = Self([0; LANES]);

    /// `a` where set, `b` elsewhere (a bitwise blend, as `wide`'s `select`).
    #[inline(always)]
    #[must_use]
    pub(crate) fn select(self, a: Lane, b: Lane) -> Lane {
        let (a, b) = (a.bits(), b.bits());
        Lane::from_bits(each!(|i| (self.0[i] & a[i]) | (!self.0[i] & b[i])))
    }

    /// Whether lane `j` is set.
    #[inline(always)]
    #[must_use]
    pub(crate) fn lane(self, j: usize) -> bool {
        self.0[j] != 0
    }

    /// Whether any lane is set.
    #[inline(always)]
    #[must_use]
    pub(crate) fn any(self) -> bool {
        self.0.iter().fold(0, |a, &m| a | m) != 0
    }

    /// Whether every lane is set.
    #[inline(always)]
    #[must_use]
    pub(crate) fn all(self) -> bool {
        self.0.iter().fold(u32::MAX, |a, &m| a & m) == u32::MAX
    }
}

macro_rules! lanewise {
    ($trait:ident, $f:ident, $ty:ty, $op:tt) => {
        impl $trait for $ty {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(each!(|i| self.0[i] $op o.0[i]))
            }
        }
    };
}
lanewise!(Add, add, Lane, +);
lanewise!(Sub, sub, Lane, -);
lanewise!(Mul, mul, Lane, *);
lanewise!(Div, div, Lane, /);
lanewise!(BitAnd, bitand, Mask, &);
lanewise!(BitOr, bitor, Mask, |);

impl Neg for Lane {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(each!(|i| -self.0[i]))
    }
}

impl Not for Mask {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(each!(|i| !self.0[i]))
    }
}

/// The first `out.len()` values of `a` into `out`, as one fixed-size copy for every length up
/// to 16 (a copy of a run-time length calls `memcpy`, which costs more than the few values).
///
/// # Panics
/// When `out` is longer than `a`.
#[inline(always)]
pub(crate) fn copy_prefix<const N: usize>(out: &mut [f32], a: &[f32; N]) {
    macro_rules! fixed {
        ($($n:literal)*) => {
            match out.len() {
                $($n if $n <= N => out.copy_from_slice(&a[..$n]),)*
                n => out.copy_from_slice(&a[..n]),
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
}

/// A lane group of points in structure-of-arrays form: the lanes of the FFSD and
/// volume-mask kernels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lanes3 {
    pub(crate) x: Lane,
    pub(crate) y: Lane,
    pub(crate) z: Lane,
}

impl Lanes3 {
    pub(crate) const ZERO: Self = Self {
        x: Lane::ZERO,
        y: Lane::ZERO,
        z: Lane::ZERO,
    };

    /// `v` in every lane.
    #[inline(always)]
    pub(crate) fn splat(v: Vec3) -> Self {
        Self {
            x: Lane::splat(v.x),
            y: Lane::splat(v.y),
            z: Lane::splat(v.z),
        }
    }

    /// The positions of `active` (up to a lane group; the last one repeated to fill the lanes).
    #[inline(always)]
    pub(crate) fn gather(positions: &[Vec3], active: &[u32]) -> Self {
        // A whole group: its points gathered in order, then split as `load` splits them.
        if let Ok(active) = <&[u32; LANES]>::try_from(active) {
            let points: [Vec3; LANES] = each!(|j| positions[active[j] as usize]);
            return Self::load(&points);
        }
        let mut lanes = Self::ZERO;
        let last = active.len() - 1;
        for j in 0..LANES {
            lanes.set(j, positions[active[j.min(last)] as usize]);
        }
        lanes
    }

    /// Up to a lane group of points (the last one repeated to fill the lanes).
    #[inline(always)]
    pub(crate) fn load(points: &[Vec3]) -> Self {
        // A whole group: the coordinates are every third float of 48 consecutive ones, a
        // fixed pattern the compiler turns into vector shuffles (the loop below goes through
        // memory one float at a time).
        if let Ok(points) = <&[Vec3; LANES]>::try_from(points) {
            let f: &[f32; 3 * LANES] = bytemuck::cast_ref(points);
            return Self {
                x: Lane(each!(|j| f[3 * j])),
                y: Lane(each!(|j| f[3 * j + 1])),
                z: Lane(each!(|j| f[3 * j + 2])),
            };
        }
        let mut lanes = Self::ZERO;
        let last = points.len() - 1;
        for j in 0..LANES {
            lanes.set(j, points[j.min(last)]);
        }
        lanes
    }

    /// Lane `j` set to `v`.
    #[inline(always)]
    pub(crate) fn set(&mut self, j: usize, v: Vec3) {
        (self.x.0[j], self.y.0[j], self.z.0[j]) = (v.x, v.y, v.z);
    }

    /// Lane `j` as a vector.
    #[inline(always)]
    pub(crate) fn lane(&self, j: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array()[j],
            self.y.as_array()[j],
            self.z.as_array()[j],
        )
    }

    /// Writes the first `out.len()` lanes to `out`.
    #[inline(always)]
    pub(crate) fn write(&self, out: &mut [Vec3]) {
        let (x, y, z) = (self.x.as_array(), self.y.as_array(), self.z.as_array());
        for (j, o) in out.iter_mut().enumerate() {
            *o = Vec3::new(x[j], y[j], z[j]);
        }
    }

    #[inline(always)]
    pub(crate) fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    #[inline(always)]
    pub(crate) fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    #[inline(always)]
    pub(crate) fn scale(self, k: Lane) -> Self {
        Self {
            x: self.x * k,
            y: self.y * k,
            z: self.z * k,
        }
    }

    /// `x² + y² + z²`, summed in that order (as glam's `dot`).
    #[inline(always)]
    pub(crate) fn length_squared(&self) -> Lane {
        self.x * self.x + self.y * self.y + self.z * self.z
    }

    #[inline(always)]
    pub(crate) fn length(&self) -> Lane {
        self.length_squared().sqrt()
    }

    /// `other` in the lanes where `mask` is set, `self` elsewhere.
    #[inline(always)]
    pub(crate) fn select(self, mask: Mask, other: Self) -> Self {
        Self {
            x: mask.select(other.x, self.x),
            y: mask.select(other.y, self.y),
            z: mask.select(other.z, self.z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x16;

    #[test]
    fn copy_prefix_copies_every_length_and_nothing_more() {
        let a: [f32; 16] = core::array::from_fn(|i| i as f32 + 1.0);
        for n in 0..=16 {
            let mut out = [-1.0_f32; 17];
            copy_prefix(&mut out[..n], &a);
            assert_eq!(&out[..n], &a[..n], "length {n}");
            assert!(out[n..].iter().all(|&v| v == -1.0), "length {n}");
        }
        let mut four = [0.0; 3];
        copy_prefix(&mut four, &[5.0, 6.0, 7.0, 8.0]);
        assert_eq!(four, [5.0, 6.0, 7.0]);
    }

    #[test]
    #[should_panic]
    fn copy_prefix_refuses_a_destination_longer_than_the_source() {
        let mut out = [0.0; 5];
        copy_prefix(&mut out, &[1.0, 2.0, 3.0, 4.0]);
    }

    /// `clamp01` is `f32::clamp(0, 1)` lane by lane: NaN stays NaN, −0.0 keeps its sign and
    /// the infinities go to the ends.
    #[test]
    fn clamp01_is_f32_clamp_in_every_lane() {
        let xs = [
            f32::NAN,
            -0.0,
            0.0,
            -1e-30,
            0.5,
            1.0,
            1.0 + f32::EPSILON,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -3.0,
            7.0,
            1e-40,
            0.999_999_9,
            -f32::NAN,
            2.0,
            0.25,
        ];
        let got = Lane(xs).clamp01();
        for (x, y) in xs.iter().zip(got.0) {
            assert_eq!(y.to_bits(), x.clamp(0.0, 1.0).to_bits(), "{x}");
        }
    }

    /// Loading and gathering whole and partial groups put point `j` in lane `j` (the last
    /// point repeated in the lanes past a partial group's end).
    #[test]
    fn loaded_and_gathered_lanes_hold_their_points() {
        let points: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(i as f32, -(i as f32) * 0.5, 1e3 + i as f32))
            .collect();
        let ids: Vec<u32> = (0..40).map(|i| (i * 7 % 40) as u32).collect();
        for len in [1, 5, LANES - 1, LANES] {
            for start in [0, 3, 24] {
                let part = &points[start..start + len];
                let group = &ids[start..start + len];
                let (loaded, gathered) = (Lanes3::load(part), Lanes3::gather(&points, group));
                for j in 0..LANES {
                    let k = j.min(len - 1);
                    assert_eq!(
                        loaded.lane(j),
                        part[k],
                        "load, {len} from {start}, lane {j}"
                    );
                    assert_eq!(
                        gathered.lane(j),
                        points[group[k] as usize],
                        "gather, {len} from {start}, lane {j}"
                    );
                }
            }
        }
    }

    /// Our lanes and `wide`'s on the same inputs: the same bits, NaN payloads included.
    fn same(inputs: &[f32], ours: impl Fn(Lane) -> Lane, theirs: impl Fn(f32x16) -> f32x16) {
        for group in inputs.chunks(LANES) {
            let mut a = [1.0_f32; LANES];
            a[..group.len()].copy_from_slice(group);
            let o = ours(Lane(a)).0;
            let t = theirs(f32x16::new(a)).to_array();
            for i in 0..LANES {
                assert_eq!(
                    o[i].to_bits(),
                    t[i].to_bits(),
                    "input {:e} ({:#x}): {:e} vs wide's {:e}",
                    a[i],
                    a[i].to_bits(),
                    o[i],
                    t[i]
                );
            }
        }
    }

    /// Every 97th bit pattern (a few tens of millions of floats of every sign, exponent,
    /// subnormal, infinity and NaN), then the special values and the edges of the ranges.
    fn inputs() -> Vec<f32> {
        let mut v: Vec<f32> = (0..=u32::MAX).step_by(97).map(f32::from_bits).collect();
        v.extend([
            0.0,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            88.72,
            88.723,
            88.73,
            -87.3,
            -103.6,
            -103.63,
            -103.7,
            86.99,
            87.0,
            87.01,
            -103.62,
            0.5,
            -0.5,
            1.5,
            2.5,
            8_388_607.5,
            -8_388_607.5,
            4_194_304.5,
        ]);
        v
    }

    #[test]
    fn exp_has_the_bits_of_wide_without_fma() {
        same(&inputs(), Lane::exp, f32x16::exp);
    }

    /// Whole lane groups at the ends of `exp`'s common-case range and just past them, where
    /// it takes its short path or the full one.
    #[test]
    fn exp_of_whole_groups_at_the_short_path_ends_has_the_bits_of_wide() {
        for x in [
            -103.63_f32,
            -103.62,
            -103.64,
            86.99,
            87.0,
            87.01,
            88.72,
            -87.3,
            0.0,
            -0.0,
        ] {
            same(&[x; LANES], Lane::exp, f32x16::exp);
        }
    }

    #[test]
    fn ln_has_the_bits_of_wide_without_fma() {
        same(&inputs(), Lane::ln, f32x16::ln);
    }

    #[test]
    fn arithmetic_and_selection_have_the_bits_of_wide() {
        let v = inputs();
        let shifted: Vec<f32> = v.iter().map(|x| x * 0.75 - 1.0).collect();
        for (a, b) in v.chunks(LANES).zip(shifted.chunks(LANES)) {
            if a.len() < LANES {
                break;
            }
            let (ours, theirs) = (
                (Lane(a.try_into().unwrap()), Lane(b.try_into().unwrap())),
                (
                    f32x16::new(a.try_into().unwrap()),
                    f32x16::new(b.try_into().unwrap()),
                ),
            );
            let check = |o: Lane, t: f32x16| {
                let t = t.to_array();
                for i in 0..LANES {
                    assert_eq!(o.0[i].to_bits(), t[i].to_bits(), "{} {}", a[i], b[i]);
                }
            };
            check(ours.0.min(ours.1), theirs.0.min(theirs.1));
            check(ours.0.sqrt(), theirs.0.sqrt());
            check(ours.0 / ours.1, theirs.0 / theirs.1);
            check(-ours.0, -theirs.0);
            check(
                ours.0.simd_lt(ours.1).select(ours.0, ours.1),
                theirs.0.simd_lt(theirs.1).select(theirs.0, theirs.1),
            );
            check(
                ours.0.simd_le(ours.1).select(ours.0 * ours.1, ours.1),
                theirs
                    .0
                    .simd_le(theirs.1)
                    .select(theirs.0 * theirs.1, theirs.1),
            );
        }
    }

    #[test]
    fn rounding_is_to_the_nearest_even_integer() {
        let r = Lane(each!(|i| i as f32 * 0.5 - 4.0)).round_ties_even().0;
        let expected = [
            -4.0, -4.0, -3.0, -2.0, -2.0, -2.0, -1.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 3.0, 4.0,
        ];
        assert_eq!(r, expected);
        assert_eq!(Lane::splat(-0.3).round_ties_even().0[0].to_bits(), 0);
    }
}
