//! Keys and the value of a track of keys at a time.
//!
//! A key holds a time (seconds), a value and how the track goes on to the next key:
//!
//! * [`Interpolation::Step`] holds the key's value until the next key;
//! * [`Interpolation::Linear`] is the affine in-between `(1 − u) c_k + u c_{k+1}` of the two
//!   keys' coordinates ([`crate::blend`]): a lerp of numbers and vectors, a slerp of
//!   rotations, skeleton-style for curves;
//! * [`Interpolation::Smooth`] is a cubic Hermite per coordinate with monotone tangents
//!   (Fritsch–Carlson, in the weighted harmonic-mean form of Fritsch & Butland used by
//!   PCHIP): it never overshoots the two keys it joins, is flat between equal keys and at a
//!   local extreme, and the first and last keys of a track get flat tangents (Blender's
//!   "auto clamped", Maya's "auto").
//!
//! Before the first key a track holds the first value, after the last the last. At a key's
//! time the track's value is the key's value itself, bit for bit. Two keys whose values cannot
//! be interpolated (different kinds, different counts of points or spline values, another
//! sketch-plane normal) make the track step between them ([`structure_breaks`] lists where).

use serde::{Deserialize, Serialize};

use crate::blend::{Encoded, encode};
use crate::value::Value;

/// How a track goes from a key to the next one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Interpolation {
    /// Hold the value until the next key.
    Step,
    /// Straight (skeleton-style for curves, slerp for rotations).
    Linear,
    /// Monotone cubic (no overshoot), the default, as in Blender and Maya.
    #[default]
    Smooth,
}

impl Interpolation {
    /// The mode's name for messages and menus.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Step => "step",
            Interpolation::Linear => "linear",
            Interpolation::Smooth => "smooth",
        }
    }
}

/// One key of a track.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Key {
    /// Time in seconds (finite; keys of a track are strictly increasing in time).
    pub time: f32,
    /// The parameter's value at `time`.
    pub value: Value,
    /// How the track goes on to the next key (default [`Interpolation::Smooth`]).
    #[serde(default)]
    pub interpolation: Interpolation,
}

impl Key {
    /// A key with the default (smooth) interpolation.
    #[must_use]
    pub fn new(time: f32, value: Value) -> Self {
        Self {
            time,
            value,
            interpolation: Interpolation::default(),
        }
    }
}

/// The number of keys whose time is `≤ t`.
fn keys_at_or_before(keys: &[Key], t: f32) -> usize {
    keys.partition_point(|k| k.time <= t)
}

/// The value of the track `keys` (strictly increasing times) at time `t`; `None` when the
/// track has no key.
#[must_use]
pub fn sample(keys: &[Key], t: f32) -> Option<Value> {
    let n = keys_at_or_before(keys, t);
    if n == 0 {
        return keys.first().map(|k| k.value.clone());
    }
    let k = n - 1;
    if k + 1 == keys.len() || keys[k].time == t {
        return Some(keys[k].value.clone());
    }
    let (a, b) = (&keys[k], &keys[k + 1]);
    let u = (t - a.time) / (b.time - a.time);
    Some(match a.interpolation {
        Interpolation::Step => a.value.clone(),
        Interpolation::Linear => linear(a, b, u).unwrap_or_else(|| a.value.clone()),
        Interpolation::Smooth => smooth(keys, k, t).unwrap_or_else(|| a.value.clone()),
    })
}

fn linear(a: &Key, b: &Key, u: f32) -> Option<Value> {
    if let (Value::Rotation(p), Value::Rotation(q)) = (&a.value, &b.value) {
        // glam's slerp takes the short path.
        return Some(Value::Rotation(p.slerp(*q, u)));
    }
    let e = encode(&[&a.value, &b.value], 0)?;
    let c = e.coords();
    Some(e.decode(&lerp(&c[0], &c[1], u)))
}

fn lerp(a: &[f32], b: &[f32], u: f32) -> Vec<f32> {
    a.iter().zip(b).map(|(x, y)| x + (y - x) * u).collect()
}

/// The Fritsch–Butland monotone slope at an interior key with the intervals `h0`, `h1` and
/// secants `d0`, `d1` on either side: 0 at a local extreme or a flat side, else the weighted
/// harmonic mean `3(h0 + h1) / ((2h1 + h0)/d0 + (h1 + 2h0)/d1)`, which keeps the cubic
/// monotone between the keys.
#[must_use]
pub fn monotone_slope(h0: f32, d0: f32, h1: f32, d1: f32) -> f32 {
    if d0 * d1 <= 0.0 {
        return 0.0;
    }
    let w1 = 2.0 * h1 + h0;
    let w2 = h1 + 2.0 * h0;
    (w1 + w2) / (w1 / d0 + w2 / d1)
}

/// The cubic Hermite on `[0, 1]` from `p0` (slope `m0 · h`) to `p1` (slope `m1 · h`), where
/// `h` is the interval's length and `m` slopes per unit time.
#[must_use]
pub fn hermite(p0: f32, m0: f32, p1: f32, m1: f32, h: f32, u: f32) -> f32 {
    let u2 = u * u;
    let u3 = u2 * u;
    let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
    let h10 = u3 - 2.0 * u2 + u;
    let h01 = -2.0 * u3 + 3.0 * u2;
    let h11 = u3 - u2;
    h00 * p0 + h10 * h * m0 + h01 * p1 + h11 * h * m1
}

/// The smooth in-between on the interval from key `k` to key `k + 1` at time `t`. The keys
/// around it (`k − 1`, `k + 2`) give the slopes where their values can be encoded with the
/// interval's; a missing or incompatible neighbour gives a flat slope.
fn smooth(keys: &[Key], k: usize, t: f32) -> Option<Value> {
    let before = k.checked_sub(1);
    let after = (k + 2 < keys.len()).then_some(k + 2);
    // The widest compatible set of keys around the interval.
    let candidates = [(before, after), (None, after), (before, None), (None, None)];
    let (set, e): (Vec<usize>, Encoded) = candidates.iter().find_map(|&(b, a)| {
        let set: Vec<usize> = b.into_iter().chain([k, k + 1]).chain(a).collect();
        let values: Vec<&Value> = set.iter().map(|&i| &keys[i].value).collect();
        let base = usize::from(b.is_some());
        encode(&values, base).map(|e| (set, e))
    })?;
    let at = |i: usize| set.iter().position(|&j| j == i);
    let (ia, ib) = (at(k)?, at(k + 1)?);
    let c = e.coords();
    let time = |i: usize| keys[set[i]].time;
    let h = time(ib) - time(ia);
    let u = (t - time(ia)) / h;
    let out: Vec<f32> = (0..c[ia].len())
        .map(|x| {
            let secant = |i: usize, j: usize| (c[j][x] - c[i][x]) / (time(j) - time(i));
            let d = secant(ia, ib);
            let m0 = match ia.checked_sub(1) {
                Some(p) => monotone_slope(time(ia) - time(p), secant(p, ia), h, d),
                None => 0.0,
            };
            let m1 = match (ib + 1 < c.len()).then_some(ib + 1) {
                Some(q) => monotone_slope(h, d, time(q) - time(ib), secant(ib, q)),
                None => 0.0,
            };
            hermite(c[ia][x], m0, c[ib][x], m1, h, u)
        })
        .collect();
    Some(e.decode(&out))
}

/// Indices `k` of the intervals (key `k` to key `k + 1`) that should interpolate but step,
/// because the two keys' values cannot be interpolated.
#[must_use]
pub fn structure_breaks(keys: &[Key]) -> Vec<usize> {
    keys.windows(2)
        .enumerate()
        .filter(|(_, w)| {
            w[0].interpolation != Interpolation::Step
                && encode(&[&w[0].value, &w[1].value], 0).is_none()
        })
        .map(|(k, _)| k)
        .collect()
}

/// The first problem of a track's keys, if any: times not finite or not strictly
/// increasing, values not finite, or values of different kinds.
#[must_use]
pub fn key_problem(keys: &[Key]) -> Option<String> {
    for (i, k) in keys.iter().enumerate() {
        if !k.time.is_finite() {
            return Some(format!("key {i}: time {} is not finite", k.time));
        }
        if !k.value.is_finite() {
            return Some(format!("key {i} (at {} s): value is not finite", k.time));
        }
    }
    for (i, w) in keys.windows(2).enumerate() {
        if w[1].time <= w[0].time {
            return Some(format!(
                "key {} (at {} s) does not come after key {i} (at {} s): key times must be strictly increasing",
                i + 1,
                w[1].time,
                w[0].time
            ));
        }
        if w[1].value.kind() != w[0].value.kind() {
            return Some(format!(
                "key {} is {} but key {i} is {}",
                i + 1,
                w[1].value.kind().name(),
                w[0].value.kind().name()
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};
    use proptest::prelude::*;

    use super::*;

    fn scalar(v: &Value) -> f32 {
        match v {
            Value::Scalar(x) => *x,
            other => panic!("not a number: {other:?}"),
        }
    }

    fn track(points: &[(f32, f32)], interpolation: Interpolation) -> Vec<Key> {
        points
            .iter()
            .map(|&(time, x)| Key {
                time,
                value: Value::Scalar(x),
                interpolation,
            })
            .collect()
    }

    fn at(keys: &[Key], t: f32) -> f32 {
        scalar(&sample(keys, t).unwrap())
    }

    #[test]
    fn keys_are_hit_exactly_and_held_outside() {
        let keys = track(
            &[(0.0, 0.1), (0.5, 0.7), (1.25, -0.3)],
            Interpolation::Smooth,
        );
        for k in &keys {
            assert_eq!(sample(&keys, k.time).unwrap(), k.value);
        }
        assert_eq!(at(&keys, -3.0), 0.1);
        assert_eq!(at(&keys, 9.0), -0.3);
        assert!(sample(&[], 0.0).is_none());
    }

    #[test]
    fn step_holds_and_linear_is_straight() {
        let step = track(&[(0.0, 1.0), (2.0, 3.0)], Interpolation::Step);
        assert_eq!(at(&step, 1.999), 1.0);
        let lin = track(&[(0.0, 1.0), (2.0, 3.0)], Interpolation::Linear);
        assert!((at(&lin, 0.5) - 1.5).abs() < 1e-6);
        assert!((at(&lin, 1.5) - 2.5).abs() < 1e-6);
    }

    #[test]
    fn smooth_between_two_keys_is_the_smoothstep() {
        // Flat end slopes: p(u) = a + (b − a)(3u² − 2u³).
        let keys = track(&[(1.0, 2.0), (3.0, 6.0)], Interpolation::Smooth);
        for i in 1..10 {
            let u = i as f32 / 10.0;
            let expect = 2.0 + 4.0 * (3.0 * u * u - 2.0 * u * u * u);
            assert!((at(&keys, 1.0 + 2.0 * u) - expect).abs() < 1e-5);
        }
    }

    #[test]
    fn smooth_interior_slope_is_the_fritsch_butland_mean() {
        // Keys (0,0), (1,1), (3,2): secants 1 and 0.5, h = 1 and 2; slope at key 1 is
        // 3·3 / (5/1 + 4/0.5) = 9/13. On [0, 1]: m0 = 0, m1 = 9/13.
        let keys = track(&[(0.0, 0.0), (1.0, 1.0), (3.0, 2.0)], Interpolation::Smooth);
        let m1 = 9.0 / 13.0;
        assert!((monotone_slope(1.0, 1.0, 2.0, 0.5) - m1).abs() < 1e-7);
        let u = 0.4_f32;
        let expect = hermite(0.0, 0.0, 1.0, m1, 1.0, u);
        assert!((at(&keys, u) - expect).abs() < 1e-6);
        let by_hand = (-2.0 * u.powi(3) + 3.0 * u * u) + (u.powi(3) - u * u) * m1;
        assert!((expect - by_hand).abs() < 1e-6);
    }

    #[test]
    fn smooth_is_flat_between_equal_keys_and_at_an_extreme() {
        let keys = track(
            &[(0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, 0.0)],
            Interpolation::Smooth,
        );
        for i in 0..=20 {
            let t = 1.0 + i as f32 / 20.0;
            assert_eq!(at(&keys, t), 1.0, "at {t}");
        }
        // A peak: nothing above it on either side.
        let peak = track(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.2)], Interpolation::Smooth);
        for i in 0..=200 {
            assert!(at(&peak, i as f32 / 100.0) <= 1.0);
        }
    }

    #[test]
    fn mixed_interpolations_follow_the_key_that_starts_the_interval() {
        let mut keys = track(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)], Interpolation::Linear);
        keys[1].interpolation = Interpolation::Step;
        assert!((at(&keys, 0.5) - 0.5).abs() < 1e-6);
        assert_eq!(at(&keys, 1.5), 1.0);
    }

    #[test]
    fn linear_rotations_slerp_on_the_short_path() {
        let a = Quat::from_rotation_y(0.2);
        let b = -Quat::from_rotation_y(1.2);
        let keys = vec![
            Key {
                time: 0.0,
                value: Value::Rotation(a),
                interpolation: Interpolation::Linear,
            },
            Key::new(1.0, Value::Rotation(b)),
        ];
        let Some(Value::Rotation(q)) = sample(&keys, 0.5) else {
            panic!()
        };
        assert!(q.angle_between(Quat::from_rotation_y(0.7)) < 1e-5);
    }

    #[test]
    fn smooth_rotations_do_not_overshoot() {
        let keys: Vec<Key> = [0.0_f32, 0.5, 1.5]
            .iter()
            .enumerate()
            .map(|(i, &a)| Key::new(i as f32, Value::Rotation(Quat::from_rotation_x(a))))
            .collect();
        for i in 0..=40 {
            let Some(Value::Rotation(q)) = sample(&keys, i as f32 / 20.0) else {
                panic!()
            };
            let (axis, angle) = q.to_axis_angle();
            let signed = angle * axis.dot(Vec3::X).signum();
            assert!((-1e-5..=1.5 + 1e-5).contains(&signed), "{signed}");
        }
    }

    #[test]
    fn different_structures_step_and_are_reported() {
        let keys = vec![
            Key::new(0.0, Value::Values(vec![0.0, 1.0])),
            Key::new(1.0, Value::Values(vec![0.0, 0.5, 1.0])),
        ];
        assert_eq!(sample(&keys, 0.5), Some(keys[0].value.clone()));
        assert_eq!(structure_breaks(&keys), vec![0]);
        let mut stepped = keys.clone();
        stepped[0].interpolation = Interpolation::Step;
        assert!(structure_breaks(&stepped).is_empty());
    }

    #[test]
    fn key_problems_are_named() {
        let bad = track(&[(0.0, 0.0), (0.0, 1.0)], Interpolation::Smooth);
        assert!(key_problem(&bad).unwrap().contains("strictly increasing"));
        let nan = track(&[(0.0, f32::NAN)], Interpolation::Smooth);
        assert!(key_problem(&nan).unwrap().contains("not finite"));
        let kinds = vec![
            Key::new(0.0, Value::Scalar(0.0)),
            Key::new(1.0, Value::Vector(Vec3::X)),
        ];
        assert!(key_problem(&kinds).unwrap().contains("a vector"));
        assert!(key_problem(&track(&[(0.0, 1.0), (1.0, 2.0)], Interpolation::Step)).is_none());
    }

    proptest! {
        /// Smooth never leaves the range of the two keys of its interval.
        #[test]
        fn smooth_never_overshoots(
            values in proptest::collection::vec(-10.0_f32..10.0, 2..7),
            gaps in proptest::collection::vec(0.05_f32..3.0, 6),
            u in 0.0_f32..1.0,
        ) {
            let mut t = 0.0;
            let mut pts = Vec::new();
            for (i, &v) in values.iter().enumerate() {
                pts.push((t, v));
                t += gaps[i];
            }
            let keys = track(&pts, Interpolation::Smooth);
            for w in pts.windows(2) {
                let x = at(&keys, w[0].0 + u * (w[1].0 - w[0].0));
                let (lo, hi) = (w[0].1.min(w[1].1), w[0].1.max(w[1].1));
                prop_assert!(x >= lo - 1e-4 && x <= hi + 1e-4, "{x} not in [{lo}, {hi}]");
            }
        }
    }
}
