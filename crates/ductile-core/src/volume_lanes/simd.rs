//! Volume masks on blocks of two SIMD registers in [`pulp`]'s explicit vector operations
//! ([`crate::registers`]): 16 vertices a block where the CPU has AVX2 (8 with NEON). A fresh
//! mask (no earlier mask to reuse) of an influence whose falloff has a lane form runs here;
//! the kernel on the lanes keeps the masks made from an earlier one, and the CPUs where
//! `pulp` dispatches to scalar code (x86 without AVX2: the compiler vectorises the lanes for
//! SSE2).
//!
//! The lanes' kernel came out of the compiler with its comparisons packed into bytes and
//! unpacked again for every select, and a branch per lane to append the weights. Here the
//! comparisons stay in registers, and a block's positive lanes are packed without a branch.
//! Each step is the lanes' operation in the lanes' order, exactly rounded and never fused,
//! so every vertex gets the bits of [`crate::influence::Influence::volume_weight`] (tests
//! here, at the dispatched width and in scalar code, and in `influence.rs`).

use glam::Vec3;
use pulp::Simd;

use super::{Ids, LaneFalloff, LaneInfluence, LaneShape, LaneVolume};
use crate::influence::Mask;
use crate::lane::{LANES, Lanes3};
use crate::registers::{Block, MAX_BLOCK, Ops, Two, load, store};

/// The volume masks' own register operations.
impl<S: Simd> Ops<S> {
    /// `|x|`: the sign bit cleared, as `f32::abs`.
    #[inline(always)]
    fn abs(self, x: Two<S::f32s>) -> Two<S::f32s> {
        let s = self.0;
        let magnitude = s.splat_u32s(0x7FFF_FFFF);
        crate::registers::two!(
            |i| s.transmute_f32s_u32s(s.and_u32s(s.transmute_u32s_f32s(x[i]), magnitude))
        )
    }

    /// `a > b ? a : b`, as glam's `max_element` compares.
    #[inline(always)]
    fn greater(self, a: Two<S::f32s>, b: Two<S::f32s>) -> Two<S::f32s> {
        self.select(self.gt(a, b), a, b)
    }

    /// `|v|`: `√((x² + y²) + z²)`.
    #[inline(always)]
    fn length(self, v: Block<S>) -> Two<S::f32s> {
        self.sqrt(self.length_squared(v))
    }

    /// `((a·x + b·y) + c·z) + t` of the block `v`: one coordinate of glam's
    /// `Affine3A::transform_point3`.
    #[inline(always)]
    fn row(self, v: Block<S>, a: f32, b: f32, c: f32, t: f32) -> Two<S::f32s> {
        let (a, b, c, t) = (self.splat(a), self.splat(b), self.splat(c), self.splat(t));
        self.add(
            self.add(
                self.add(self.mul(a, v.x), self.mul(b, v.y)),
                self.mul(c, v.z),
            ),
            t,
        )
    }

    /// The volume's normalised distance in each lane: the operations of the lanes'
    /// `LaneVolume::distance`.
    #[inline(always)]
    fn distance(self, vol: &LaneVolume, v: Block<S>) -> Two<S::f32s> {
        let (a, b, c, t) = (vol.x_axis, vol.y_axis, vol.z_axis, vol.translation);
        let l = Block {
            x: self.row(v, a.x, b.x, c.x, t.x),
            y: self.row(v, a.y, b.y, c.y, t.y),
            z: self.row(v, a.z, b.z, c.z, t.z),
        };
        match &vol.shape {
            &LaneShape::Sphere { radius } => self.div(self.length(l), self.splat(radius)),
            &LaneShape::Box { half } => {
                let x = self.div(self.abs(l.x), self.splat(half.x));
                let y = self.div(self.abs(l.y), self.splat(half.y));
                let z = self.div(self.abs(l.z), self.splat(half.z));
                self.greater(x, self.greater(y, z))
            }
            &LaneShape::Capsule {
                radius,
                half_height,
            } => {
                let (lo, hi) = (self.splat(-half_height), self.splat(half_height));
                let y = self.select(self.lt(l.y, lo), lo, l.y);
                let y = self.select(self.gt(y, hi), hi, y);
                let zero = self.splat(0.0);
                let d = Block {
                    x: self.sub(l.x, zero),
                    y: self.sub(l.y, y),
                    z: self.sub(l.z, zero),
                };
                self.div(self.length(d), self.splat(radius))
            }
            LaneShape::Tube(segments) => {
                let mut best = self.splat(f32::INFINITY);
                for seg in segments {
                    let (a, ab) = (seg.a, seg.ab);
                    let t = if seg.len2 > 0.0 {
                        let d = self.sub3(l, self.splat3(a));
                        let dot = self.add(
                            self.add(
                                self.mul(d.x, self.splat(ab.x)),
                                self.mul(d.y, self.splat(ab.y)),
                            ),
                            self.mul(d.z, self.splat(ab.z)),
                        );
                        let t = self.div(dot, self.splat(seg.len2));
                        let t = self.select(self.lt(t, self.splat(0.0)), self.splat(0.0), t);
                        self.select(self.gt(t, self.splat(1.0)), self.splat(1.0), t)
                    } else {
                        self.splat(0.0)
                    };
                    let on = Block {
                        x: self.add(self.splat(a.x), self.mul(self.splat(ab.x), t)),
                        y: self.add(self.splat(a.y), self.mul(self.splat(ab.y), t)),
                        z: self.add(self.splat(a.z), self.mul(self.splat(ab.z), t)),
                    };
                    let radius = self.add(self.splat(seg.r0), self.mul(self.splat(seg.dr), t));
                    let q = self.div(self.length(self.sub3(l, on)), radius);
                    best = self.select(self.lt(q, best), q, best);
                }
                best
            }
        }
    }

    /// The falloff's weight of normalised distance `t` in each lane (the lanes'
    /// `LaneInfluence::falloff`).
    #[inline(always)]
    fn falloff(self, influence: &LaneInfluence, t: Two<S::f32s>) -> Two<S::f32s> {
        let (zero, one) = (self.splat(0.0), self.splat(1.0));
        let s = self.div(self.sub(one, t), self.splat(1.0 - influence.inner));
        // `clamp(0, 1)`, NaN kept.
        let s = self.select(self.lt(s, zero), zero, s);
        let s = self.select(self.gt(s, one), one, s);
        let f = match influence.falloff {
            LaneFalloff::None => one,
            LaneFalloff::Linear => s,
            LaneFalloff::Smooth => self.mul(
                self.mul(s, s),
                self.sub(self.splat(3.0), self.mul(self.splat(2.0), s)),
            ),
        };
        let w = self.select(self.le(t, self.splat(influence.inner)), one, f);
        self.select(self.gt(t, one), zero, w)
    }

    /// `w(v)` of the block `v` (the lanes' `LaneInfluence::weights`), or `None` when no lane
    /// has a positive weight.
    #[inline(always)]
    fn weights(self, influence: &LaneInfluence, v: Block<S>) -> Option<Two<S::f32s>> {
        let outside = self.splat(if influence.invert { 1.0 } else { 0.0 });
        // No lane set (`0 < 0`), then the union of the volumes' boxes.
        let mut inside = self.lt(self.splat(0.0), self.splat(0.0));
        for vol in &influence.volumes {
            let (lo, hi) = (vol.lo, vol.hi);
            let in_box = self.and(
                self.and(
                    self.and(
                        self.ge(v.x, self.splat(lo.x)),
                        self.ge(v.y, self.splat(lo.y)),
                    ),
                    self.and(
                        self.ge(v.z, self.splat(lo.z)),
                        self.le(v.x, self.splat(hi.x)),
                    ),
                ),
                self.and(
                    self.le(v.y, self.splat(hi.y)),
                    self.le(v.z, self.splat(hi.z)),
                ),
            );
            inside = self.or(inside, in_box);
        }
        if !self.any(inside) {
            return influence.invert.then_some(outside);
        }
        let mut g = self.splat(0.0);
        for vol in &influence.volumes {
            let w = self.falloff(influence, self.distance(vol, v));
            g = self.select(self.gt(w, g), w, g);
        }
        let w = if influence.invert {
            self.sub(self.splat(1.0), g)
        } else {
            g
        };
        let w = self.select(inside, w, outside);
        self.any(self.gt(w, self.splat(0.0))).then_some(w)
    }
}

/// The vertices of `ids` of positive weight, in order, with their weights: a block of two
/// registers at a time, the positive lanes of each block packed after the earlier ones in
/// the thread's scratch buffers, then copied out at their length. Where a block is a lane
/// group (AVX2), its positions come through [`Lanes3`]'s loads, which the compiler turns
/// into vector shuffles; other blocks (scalar code, the last partial block) are copied
/// coordinate by coordinate.
///
/// The scratch holds as many entries as the most candidates a thread weighed at once (at
/// most [`crate::chunks::CHUNK`] in a parallel mask's chunk, fewer than
/// [`crate::chunks::PARALLEL_THRESHOLD`] in a serial mask: under 128 KiB a thread). It
/// replaced a mask grown by pushes, copied at each doubling of its capacity and appended to
/// by two copies of variable length per block: the suite's million-vertex stack's masks went
/// from 34.7–36.5 to 32.4–32.9 ms at two threads, 61.5–62.3 to 55.8–57.5 at one
/// (`layer_profile`, alternating).
#[inline(always)]
pub(super) fn mask<S: Simd>(
    simd: S,
    influence: &LaneInfluence,
    ids: Ids<'_>,
    positions: &[Vec3],
) -> Mask {
    debug_assert!(2 * S::F32_LANES <= MAX_BLOCK);
    let total = ids.len();
    // Taken out of the thread's slot and put back, not borrowed in a closure: a closure is
    // compiled without the dispatched target features, and the kernel inlined into one ran
    // ten times slower.
    let mut scratch = SCRATCH.take();
    // Room for every candidate. The buffers keep their contents between masks, so they are
    // zeroed only where they grow.
    if scratch.indices.len() < total {
        scratch.indices.resize(total, 0);
        scratch.weights.resize(total, 0.0);
    }
    let count = weigh(Ops(simd), influence, ids, positions, &mut scratch);
    let mask = Mask {
        indices: scratch.indices[..count].to_vec(),
        weights: scratch.weights[..count].to_vec(),
    };
    SCRATCH.set(scratch);
    mask
}

std::thread_local! {
    /// Where [`mask`] packs a mask before copying it out at its length (see there why).
    static SCRATCH: std::cell::RefCell<Mask> = std::cell::RefCell::new(Mask::default());
}

/// [`mask`]'s kernel: packs the vertices of `ids` of positive weight and their weights at the
/// start of `scratch` (with room for every candidate) and returns how many there are. A
/// block writes all its lanes after the positive vertices before it, which are at most as
/// many as the candidates before it, so the writes stay within the candidates' room.
#[inline(always)]
fn weigh<S: Simd>(
    ops: Ops<S>,
    influence: &LaneInfluence,
    ids: Ids<'_>,
    positions: &[Vec3],
    scratch: &mut Mask,
) -> usize {
    let n = 2 * S::F32_LANES;
    let first = match ids {
        Ids::Range(start, _) => start as usize,
        Ids::List(_) => 0,
    };
    let total = ids.len();
    let mut count = 0;
    let mut w = [0.0_f32; MAX_BLOCK];
    for b in (0..total).step_by(n) {
        let len = n.min(total - b);
        let v = if n == LANES && len == LANES {
            let lanes = match ids {
                Ids::Range(..) => Lanes3::load(&positions[first + b..first + b + LANES]),
                Ids::List(ids) => Lanes3::gather(positions, &ids[b..b + LANES]),
            };
            Block {
                x: load::<S>(&lanes.x.0),
                y: load::<S>(&lanes.y.0),
                z: load::<S>(&lanes.z.0),
            }
        } else {
            let mut c = [[0.0_f32; MAX_BLOCK]; 3];
            for l in 0..n {
                let k = b + l.min(len - 1);
                let p = match ids {
                    Ids::Range(..) => positions[first + k],
                    Ids::List(ids) => positions[ids[k] as usize],
                };
                (c[0][l], c[1][l], c[2][l]) = (p.x, p.y, p.z);
            }
            Block {
                x: load::<S>(&c[0][..n]),
                y: load::<S>(&c[1][..n]),
                z: load::<S>(&c[2][..n]),
            }
        };
        let Some(weights) = ops.weights(influence, v) else {
            continue;
        };
        if len == n && ops.all(ops.gt(weights, ops.splat(0.0))) {
            // Every lane positive (a block inside a volume, or outside an inverted one):
            // the block is appended whole.
            store::<S>(&mut scratch.weights[count..count + n], weights);
            let indices = &mut scratch.indices[count..count + n];
            match ids {
                Ids::Range(..) => {
                    for (l, i) in indices.iter_mut().enumerate() {
                        *i = (first + b + l) as u32;
                    }
                }
                Ids::List(ids) => indices.copy_from_slice(&ids[b..b + n]),
            }
            count += n;
            continue;
        }
        store::<S>(&mut w[..n], weights);
        // The positive lanes, packed after those before without a branch per lane: every
        // lane is written at the end, and the end moves past the positive ones.
        let (indices, kept) = (
            &mut scratch.indices[count..count + len],
            &mut scratch.weights[count..count + len],
        );
        let mut c = 0;
        for (l, &wl) in w[..len].iter().enumerate() {
            let k = b + l;
            indices[c] = match ids {
                Ids::Range(..) => (first + k) as u32,
                Ids::List(ids) => ids[k],
            };
            kept[c] = wl;
            c += usize::from(wl > 0.0);
        }
        count += c;
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::influence::tests::{every_shape, placement};
    use crate::influence::{Falloff, Influence, Volume};

    /// Every shape, placed and rotated, each falloff with and without an inner plateau,
    /// inverted or not, one volume or a union: the kernel at the dispatched width and in
    /// scalar code gives the vertices of positive weight with the bits of the scalar path
    /// (`volume_weight` inside a cull box), on points around the volumes, on their axes and
    /// centres, and at NaN and the infinities, over ranges and lists of every length around
    /// the block size.
    #[test]
    fn the_register_kernel_gives_the_per_vertex_weights_bits() {
        let placement = placement();
        // The tube has a segment of length 0.
        let shapes = every_shape(
            vec![
                Vec3::new(-0.5, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::new(0.4, 0.5, 0.1),
            ],
            vec![0.2, 0.4, 0.4, 0.3],
        );
        let volumes: Vec<Volume> = shapes
            .iter()
            .map(|s| Volume::new(s.clone(), placement, "v").unwrap())
            .collect();
        let mut positions: Vec<Vec3> = (0..2_000)
            .map(|i| {
                let t = i as f32 * 0.37;
                Vec3::new(t.sin() * 1.4, (t * 1.3).cos() * 1.2, (t * 0.7).sin() * 1.3)
            })
            .collect();
        let specials = [
            Vec3::splat(f32::NAN),
            Vec3::new(0.1, f32::NAN, 0.3),
            Vec3::splat(f32::INFINITY),
            Vec3::new(f32::NEG_INFINITY, 0.0, 0.0),
            placement.transform_point3(Vec3::ZERO),
            placement.transform_point3(Vec3::new(0.0, 0.5, 0.0)),
            placement.transform_point3(Vec3::new(0.0, 0.5, 0.3)),
        ];
        for (k, s) in specials.iter().enumerate() {
            positions[37 * k + 5] = *s;
            positions[300 + 41 * k] = *s;
        }
        let list: Vec<u32> = (0..positions.len() as u32).filter(|i| i % 3 != 1).collect();
        let unions: Vec<Vec<Volume>> = volumes
            .iter()
            .map(|v| vec![v.clone()])
            .chain([volumes.clone()])
            .collect();
        for vols in unions {
            for falloff in [Falloff::None, Falloff::Linear, Falloff::Smooth] {
                for (inner, invert) in [(0.0, false), (0.3, false), (0.0, true), (0.3, true)] {
                    let inf = Influence {
                        volumes: vols.clone(),
                        area: None,
                        falloff: falloff.clone(),
                        inner,
                        invert,
                    };
                    let lanes = LaneInfluence::new(&inf).unwrap();
                    // The scalar path of `Influence::mask`: outside every cull box the
                    // weight is that of no volume (NaN coordinates are in no box).
                    let weighed = |i: u32| {
                        let p = positions[i as usize];
                        let boxed = vols.iter().any(|v| {
                            let (lo, hi) = v.cull_box();
                            p.cmpge(lo).all() && p.cmple(hi).all()
                        });
                        let w = match (boxed, invert) {
                            (true, _) => inf.volume_weight(p),
                            (false, false) => 0.0,
                            (false, true) => 1.0,
                        };
                        (w > 0.0).then_some((i, w.to_bits()))
                    };
                    let bits = |m: Mask| -> Vec<(u32, u32)> {
                        m.indices
                            .into_iter()
                            .zip(m.weights.into_iter().map(f32::to_bits))
                            .collect()
                    };
                    let what = format!(
                        "{} volumes, {falloff:?}, inner {inner}, invert {invert}",
                        vols.len()
                    );
                    let cases = [1, 15, 16, 17, 255, 256, 257, 1_999]
                        .into_iter()
                        .flat_map(|len| {
                            [(Ids::Range(0, len), false), (Ids::Range(1, len + 1), false)]
                                .into_iter()
                                .chain([(Ids::List(&list[..(len as usize).min(list.len())]), true)])
                        });
                    for (ids, listed) in cases {
                        let expected: Vec<(u32, u32)> = match ids {
                            Ids::Range(a, b) => (a..b).filter_map(weighed).collect(),
                            Ids::List(l) => l.iter().copied().filter_map(weighed).collect(),
                        };
                        let dispatched = bits(lanes.gather(ids, &positions, None));
                        let scalar = bits(mask(pulp::Scalar::new(), &lanes, ids, &positions));
                        assert_eq!(dispatched, expected, "{what}, listed {listed}");
                        assert_eq!(scalar, expected, "{what}, listed {listed}");
                    }
                }
            }
        }
    }
}
