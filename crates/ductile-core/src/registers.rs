//! Blocks of two SIMD registers in [`pulp`]'s explicit vector operations, for the kernels
//! that [`crate::lane`]'s sixteen-float lanes compiled badly: 16 `f32` a block where the CPU
//! has AVX2 (x86), 8 with NEON (aarch64), 2 where `pulp` dispatches to scalar code (x86
//! without AVX2; the callers run the lanes' kernels there, which the compiler vectorises for
//! SSE2).
//!
//! Two independent registers per value let the core overlap one register's chain of
//! dependent operations with the other's. The operations here are exactly rounded and never
//! fused, so a kernel that takes the lanes' operations in the lanes' order gets their bits.
//! Users: `ffsd/simd.rs` (FFSD deformation and nearest vertices), `volume_lanes/simd.rs`
//! (volume masks), `axial_lanes.rs` (the axial tool's frames, whose callers take the
//! per-vertex code where there is no AVX2) and `curve_lanes/steps.rs` (the curve closest
//! points' Gauss–Newton steps, on the lanes where there is no AVX2).

use glam::Vec3;
use pulp::Simd;

use crate::lane::LANES;

/// Two registers, operated on together (`two!`'s expression for register 0, then 1).
pub(crate) type Two<T> = [T; 2];

/// `[e(0), e(1)]` for an expression `e` of the register index (a macro, not a closure: a
/// closure is compiled without the kernel's target features).
macro_rules! two {
    (|$i:ident| $e:expr) => {
        [
            {
                let $i = 0;
                $e
            },
            {
                let $i = 1;
                $e
            },
        ]
    };
}
pub(crate) use two;

/// Methods of [`Ops`] that apply one `pulp` operation to each register of their operands
/// (`name(operands) -> result = pulp_operation`).
macro_rules! pairwise {
    ($($(#[$doc:meta])* $name:ident($($arg:ident: $ty:ident),*) -> $out:ident = $op:ident;)*) => {
        $(
            $(#[$doc])*
            #[inline(always)]
            pub(crate) fn $name(self, $($arg: Two<S::$ty>),*) -> Two<S::$out> {
                two!(|i| self.0.$op($($arg[i]),*))
            }
        )*
    };
}

/// A block of vertices: their coordinates.
#[derive(Clone, Copy)]
pub(crate) struct Block<S: Simd> {
    pub(crate) x: Two<S::f32s>,
    pub(crate) y: Two<S::f32s>,
    pub(crate) z: Two<S::f32s>,
}

/// Register operations on a [`pulp::Simd`] implementation, two registers at a time.
#[derive(Clone, Copy)]
pub(crate) struct Ops<S: Simd>(pub(crate) S);

impl<S: Simd> Ops<S> {
    #[inline(always)]
    pub(crate) fn splat(self, v: f32) -> Two<S::f32s> {
        let r = self.0.splat_f32s(v);
        [r, r]
    }

    pairwise! {
        add(a: f32s, b: f32s) -> f32s = add_f32s;
        sub(a: f32s, b: f32s) -> f32s = sub_f32s;
        mul(a: f32s, b: f32s) -> f32s = mul_f32s;
        div(a: f32s, b: f32s) -> f32s = div_f32s;
        sqrt(a: f32s) -> f32s = sqrt_f32s;
        lt(a: f32s, b: f32s) -> m32s = less_than_f32s;
        le(a: f32s, b: f32s) -> m32s = less_than_or_equal_f32s;
        ge(a: f32s, b: f32s) -> m32s = greater_than_or_equal_f32s;
        gt(a: f32s, b: f32s) -> m32s = greater_than_f32s;
        eq(a: f32s, b: f32s) -> m32s = equal_f32s;
        and(a: m32s, b: m32s) -> m32s = and_m32s;
        or(a: m32s, b: m32s) -> m32s = or_m32s;
        not(a: m32s) -> m32s = not_m32s;
        /// `a` where `m`, else `b`.
        select(m: m32s, a: f32s, b: f32s) -> f32s = select_f32s;
    }

    /// `-a`: the sign bit flipped, as `f32`'s negation.
    #[inline(always)]
    pub(crate) fn neg(self, a: Two<S::f32s>) -> Two<S::f32s> {
        let sign = self.0.splat_f32s(-0.0);
        two!(|i| self.0.xor_f32s(a[i], sign))
    }

    /// Whether every lane of `m` is set.
    #[inline(always)]
    pub(crate) fn all(self, m: Two<S::m32s>) -> bool {
        let m = self.0.and_m32s(m[0], m[1]);
        self.0.first_true_m32s(self.0.not_m32s(m)) == S::F32_LANES
    }

    /// Whether any lane of `m` is set.
    #[inline(always)]
    pub(crate) fn any(self, m: Two<S::m32s>) -> bool {
        self.0.first_true_m32s(self.0.or_m32s(m[0], m[1])) < S::F32_LANES
    }

    /// Each lane clamped to `[0, 1]` by two selects, NaN kept (as `f32::clamp(0, 1)` and
    /// [`crate::lane::Lane::clamp01`]).
    #[inline(always)]
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // The curve steps' (x86-64).
    pub(crate) fn clamp01(self, a: Two<S::f32s>) -> Two<S::f32s> {
        let (zero, one) = (self.splat(0.0), self.splat(1.0));
        let q = self.select(self.lt(a, zero), zero, a);
        self.select(self.gt(q, one), one, q)
    }

    /// `a·b` in glam's order: `(ax bx + ay by) + az bz`.
    #[inline(always)]
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // The curve steps' (x86-64).
    pub(crate) fn dot(self, a: Block<S>, b: Block<S>) -> Two<S::f32s> {
        self.add(
            self.add(self.mul(a.x, b.x), self.mul(a.y, b.y)),
            self.mul(a.z, b.z),
        )
    }

    /// `v` in every lane.
    #[inline(always)]
    pub(crate) fn splat3(self, v: Vec3) -> Block<S> {
        Block {
            x: self.splat(v.x),
            y: self.splat(v.y),
            z: self.splat(v.z),
        }
    }

    #[inline(always)]
    pub(crate) fn add3(self, a: Block<S>, b: Block<S>) -> Block<S> {
        Block {
            x: self.add(a.x, b.x),
            y: self.add(a.y, b.y),
            z: self.add(a.z, b.z),
        }
    }

    #[inline(always)]
    pub(crate) fn sub3(self, a: Block<S>, b: Block<S>) -> Block<S> {
        Block {
            x: self.sub(a.x, b.x),
            y: self.sub(a.y, b.y),
            z: self.sub(a.z, b.z),
        }
    }

    /// `x² + y² + z²`, summed in that order (as [`crate::lane::Lanes3::length_squared`]).
    #[inline(always)]
    pub(crate) fn length_squared(self, b: Block<S>) -> Two<S::f32s> {
        self.add(
            self.add(self.mul(b.x, b.x), self.mul(b.y, b.y)),
            self.mul(b.z, b.z),
        )
    }

    #[inline(always)]
    pub(crate) fn scale(self, b: Block<S>, k: Two<S::f32s>) -> Block<S> {
        Block {
            x: self.mul(b.x, k),
            y: self.mul(b.y, k),
            z: self.mul(b.z, k),
        }
    }

    #[inline(always)]
    pub(crate) fn select3(self, m: Two<S::m32s>, a: Block<S>, b: Block<S>) -> Block<S> {
        Block {
            x: self.select(m, a.x, b.x),
            y: self.select(m, a.y, b.y),
            z: self.select(m, a.z, b.z),
        }
    }
}

/// The most lanes of a block: two registers of AVX-512's 16 `f32`.
pub(crate) const MAX_BLOCK: usize = 2 * LANES;

/// Two registers' worth of `f32` from `a` (whose length is their lanes), unaligned.
#[inline(always)]
pub(crate) fn load<S: Simd>(a: &[f32]) -> Two<S::f32s> {
    let n = S::F32_LANES;
    [
        bytemuck::pod_read_unaligned(bytemuck::cast_slice(&a[..n])),
        bytemuck::pod_read_unaligned(bytemuck::cast_slice(&a[n..2 * n])),
    ]
}

/// Two registers into `a` (whose length is their lanes).
#[inline(always)]
pub(crate) fn store<S: Simd>(a: &mut [f32], v: Two<S::f32s>) {
    let n = S::F32_LANES;
    bytemuck::cast_slice_mut::<f32, u8>(&mut a[..n]).copy_from_slice(bytemuck::bytes_of(&v[0]));
    bytemuck::cast_slice_mut::<f32, u8>(&mut a[n..2 * n])
        .copy_from_slice(bytemuck::bytes_of(&v[1]));
}
