//! Polynomial bases shared by the lattice, surface, curve and DOGME tools: Bernstein
//! polynomials and B-spline basis functions over clamped uniform knot vectors (Piegl &
//! Tiller, *The NURBS Book*, algorithms A2.1–A2.3).

use std::ops::{Add, Div, Mul, Sub};

/// `f32` or `f64`: the recurrences below run in either (the tools evaluate in `f32`; the
/// power-form pieces of [`crate::curve_pieces`] build their coefficients in `f64`).
pub trait Real:
    Copy
    + PartialOrd
    + From<u8>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
{
}

impl<T> Real for T where
    T: Copy
        + PartialOrd
        + From<u8>
        + Add<Output = T>
        + Sub<Output = T>
        + Mul<Output = T>
        + Div<Output = T>
{
}

/// All Bernstein polynomials of degree `n` at `t`: `B_i^n(t) = C(n, i) tⁱ (1 − t)ⁿ⁻ⁱ`,
/// `i = 0..=n`, written to `out[..=n]`. Computed by the de Casteljau recurrence
/// `B_i^n = (1 − t) B_i^{n−1} + t B_{i−1}^{n−1}`, which is stable for `t ∈ [0, 1]`.
///
/// # Panics
/// When `out.len() <= n`.
pub fn bernstein_all<T: Real>(n: usize, t: T, out: &mut [T]) {
    let s = T::from(1) - t;
    out[0] = T::from(1);
    for j in 1..=n {
        let mut saved = T::from(0);
        for k in 0..j {
            let tmp = out[k];
            out[k] = saved + s * tmp;
            saved = t * tmp;
        }
        out[j] = saved;
    }
}

/// All Bernstein polynomials of degree `n` at `t` and their derivatives with respect to `t`:
/// `d/dt B_i^n = n (B_{i−1}^{n−1} − B_i^{n−1})`.
///
/// # Panics
/// When `values.len() <= n` or `derivs.len() <= n`.
pub fn bernstein_all_with_derivative(n: usize, t: f32, values: &mut [f32], derivs: &mut [f32]) {
    if n == 0 {
        values[0] = 1.0;
        derivs[0] = 0.0;
        return;
    }
    bernstein_all(n - 1, t, derivs);
    let nf = n as f32;
    let mut prev = 0.0;
    for i in 0..=n {
        let cur = if i < n { derivs[i] } else { 0.0 };
        values[i] = cur; // temporarily keep B^{n−1}_i
        derivs[i] = nf * (prev - cur);
        prev = cur;
    }
    bernstein_all(n, t, values);
}

/// A clamped, uniform knot vector for `count` control points of the given `degree`:
/// `degree + 1` zeros, uniformly spaced interior knots, `degree + 1` ones, so the curve
/// interpolates its end control points and the parameter domain is `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotVector {
    degree: usize,
    knots: Vec<f32>,
}

impl KnotVector {
    /// The clamped uniform knot vector. Needs `count > degree ≥ 1`; returns `None` otherwise.
    #[must_use]
    pub fn clamped_uniform(degree: usize, count: usize) -> Option<Self> {
        if degree == 0 || count <= degree {
            return None;
        }
        let interior = count - degree - 1;
        let mut knots = vec![0.0; degree + 1];
        for j in 1..=interior {
            knots.push(j as f32 / (interior + 1) as f32);
        }
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Some(Self { degree, knots })
    }

    /// The degree `p`.
    #[must_use]
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Number of control points `n + 1`.
    #[must_use]
    pub fn count(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The knots.
    #[must_use]
    pub fn knots(&self) -> &[f32] {
        &self.knots
    }

    /// The knot span index `s` with `u_s ≤ t < u_{s+1}` (A2.1), clamping `t` to `[0, 1]`;
    /// `t = 1` belongs to the last non-empty span. The non-zero basis functions at `t` are
    /// `N_{s−p}, …, N_s`.
    #[must_use]
    pub fn span(&self, t: f32) -> usize {
        let n = self.count() - 1;
        let t = t.clamp(0.0, 1.0);
        if t >= self.knots[n + 1] {
            return n;
        }
        // Binary search in [p, n].
        let (mut lo, mut hi) = (self.degree, n + 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if t < self.knots[mid] {
                hi = mid
            } else {
                lo = mid
            }
        }
        lo
    }

    /// The `p + 1` non-zero basis functions `N_{s−p..=s, p}(t)` (A2.2), with `s` the span;
    /// written to `out[..=p]`. Returns `s`.
    ///
    /// # Panics
    /// When `out.len() <= p`.
    pub fn basis(&self, t: f32, out: &mut [f32]) -> usize {
        let p = self.degree;
        let s = self.span(t);
        let t = t.clamp(0.0, 1.0);
        let mut left = [0.0_f32; 16];
        let mut right = [0.0_f32; 16];
        out[0] = 1.0;
        for j in 1..=p {
            left[j] = t - self.knots[s + 1 - j];
            right[j] = self.knots[s + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                let tmp = out[r] / (right[r + 1] + left[j - r]);
                out[r] = saved + right[r + 1] * tmp;
                saved = left[j - r] * tmp;
            }
            out[j] = saved;
        }
        s
    }

    /// The non-zero basis functions and their first derivatives at `t` (A2.3 with one
    /// derivative): `N'_{i,p} = p/(u_{i+p} − u_i) N_{i,p−1} − p/(u_{i+p+1} − u_{i+1}) N_{i+1,p−1}`.
    /// Returns the span `s`.
    ///
    /// # Panics
    /// When the slices are shorter than `p + 1`.
    pub fn basis_with_derivative(&self, t: f32, values: &mut [f32], derivs: &mut [f32]) -> usize {
        let p = self.degree;
        let s = self.span(t);
        // Degree p−1 functions N_{s−p+1..=s, p−1} live in lower[1..=p].
        let mut lower = [0.0_f32; 17];
        if p >= 1 {
            // The degree p−1 vector is this one without its end knots; its span s−1 reads
            // exactly the knots `knots[s+1−j]`, `knots[s+j]` that span s reads here, so the
            // recurrence runs on these knots with no copy.
            let mut tmp = [0.0_f32; 16];
            basis_at_span(&self.knots, p - 1, t, s, &mut tmp);
            lower[1..=p].copy_from_slice(&tmp[..p]);
        }
        if p == 0 {
            values[0] = 1.0;
            derivs[0] = 0.0;
            return s;
        }
        // One more step of the recurrence gives the values from the same degree p−1
        // functions: N_{i,p} = (t − u_i)/(u_{i+p} − u_i) N_{i,p−1}
        //                   + (u_{i+p+1} − t)/(u_{i+p+1} − u_{i+1}) N_{i+1,p−1}.
        let t = t.clamp(0.0, 1.0);
        let pf = p as f32;
        for j in 0..=p {
            let i = s - p + j;
            let (mut value, mut deriv) = (0.0, 0.0);
            let d = self.knots[i + p] - self.knots[i];
            if d > 0.0 {
                value += (t - self.knots[i]) / d * lower[j];
                deriv += pf / d * lower[j];
            }
            let d = self.knots[i + p + 1] - self.knots[i + 1];
            if d > 0.0 {
                value += (self.knots[i + p + 1] - t) / d * lower[j + 1];
                deriv -= pf / d * lower[j + 1];
            }
            values[j] = value;
            derivs[j] = deriv;
        }
        s
    }
}

/// The Cox–de Boor recurrence (Piegl & Tiller A2.2) for degree `p` at span `s` of `knots`
/// (`t` clamped to `[0, 1]`): writes `N_{s−p..=s, p}(t)` to `out[..=p]`.
pub(crate) fn basis_at_span<T: Real>(knots: &[T], p: usize, t: T, s: usize, out: &mut [T]) {
    let (zero, one) = (T::from(0), T::from(1));
    // `f32::clamp`'s comparisons: a NaN stays NaN.
    let t = if t < zero {
        zero
    } else if t > one {
        one
    } else {
        t
    };
    let mut left = [zero; 16];
    let mut right = [zero; 16];
    out[0] = one;
    for j in 1..=p {
        left[j] = t - knots[s + 1 - j];
        right[j] = knots[s + j] - t;
        let mut saved = zero;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let tmp = if denom != zero { out[r] / denom } else { zero };
            out[r] = saved + right[r + 1] * tmp;
            saved = left[j - r] * tmp;
        }
        out[j] = saved;
    }
}

/// Largest degree the fixed-size scratch buffers of this module support.
pub const MAX_DEGREE: usize = 15;

#[cfg(test)]
mod tests {
    use super::*;

    fn binom(n: usize, k: usize) -> f32 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f32 / (i + 1) as f32)
    }

    #[test]
    fn bernstein_matches_closed_form_and_sums_to_one() {
        let mut b = [0.0; 9];
        for n in 0..=8 {
            for &t in &[0.0, 0.13, 0.5, 0.77, 1.0] {
                bernstein_all(n, t, &mut b);
                let sum: f32 = b[..=n].iter().sum();
                assert!((sum - 1.0).abs() < 1e-6);
                for i in 0..=n {
                    let exact = binom(n, i) * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32);
                    assert!((b[i] - exact).abs() < 1e-6, "n={n} i={i} t={t}");
                }
            }
        }
    }

    #[test]
    fn bernstein_derivative_matches_finite_difference() {
        let (mut v, mut d, mut vp, mut vm) = ([0.0; 9], [0.0; 9], [0.0; 9], [0.0; 9]);
        let h = 1e-3;
        for n in 1..=6 {
            let t = 0.37;
            bernstein_all_with_derivative(n, t, &mut v, &mut d);
            bernstein_all(n, t + h, &mut vp);
            bernstein_all(n, t - h, &mut vm);
            for i in 0..=n {
                let fd = (vp[i] - vm[i]) / (2.0 * h);
                assert!((d[i] - fd).abs() < 2e-2, "n={n} i={i}: {} vs {fd}", d[i]);
            }
        }
    }

    #[test]
    fn bspline_basis_partition_of_unity_and_locality() {
        let kv = KnotVector::clamped_uniform(3, 7).unwrap();
        assert_eq!(
            kv.knots(),
            &[0.0, 0.0, 0.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.0, 1.0, 1.0]
        );
        let mut b = [0.0; 4];
        for k in 0..=100 {
            let t = k as f32 / 100.0;
            let s = kv.basis(t, &mut b);
            assert!((3..=6).contains(&s));
            assert!((b.iter().sum::<f32>() - 1.0).abs() < 1e-6, "t={t}");
            assert!(b.iter().all(|&x| x >= -1e-7));
        }
        kv.basis(0.0, &mut b);
        assert_eq!(b[0], 1.0);
        let s = kv.basis(1.0, &mut b);
        assert_eq!((s, b[3]), (6, 1.0));
    }

    #[test]
    fn bspline_degree_equal_count_minus_one_is_bernstein() {
        let kv = KnotVector::clamped_uniform(3, 4).unwrap();
        let (mut b, mut e) = ([0.0; 4], [0.0; 4]);
        for &t in &[0.1, 0.4, 0.9] {
            kv.basis(t, &mut b);
            bernstein_all(3, t, &mut e);
            for i in 0..4 {
                assert!((b[i] - e[i]).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn bspline_derivative_matches_finite_difference() {
        let kv = KnotVector::clamped_uniform(3, 8).unwrap();
        let (mut v, mut d, mut vp, mut vm) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
        let h = 1e-3;
        for &t in &[0.05, 0.31, 0.62, 0.93] {
            let s = kv.basis_with_derivative(t, &mut v, &mut d);
            assert_eq!(kv.basis(t + h, &mut vp), s);
            assert_eq!(kv.basis(t - h, &mut vm), s);
            for j in 0..4 {
                let fd = (vp[j] - vm[j]) / (2.0 * h);
                assert!(
                    (d[j] - fd).abs() < 5e-2 * (1.0 + fd.abs()),
                    "t={t} j={j}: {} vs {fd}",
                    d[j]
                );
            }
        }
    }

    #[test]
    fn values_with_the_derivative_are_the_basis() {
        for (p, n) in [
            (1, 2),
            (1, 5),
            (2, 3),
            (2, 7),
            (3, 4),
            (3, 9),
            (5, 6),
            (5, 12),
        ] {
            let kv = KnotVector::clamped_uniform(p, n).unwrap();
            let (mut v, mut d, mut b) = ([0.0; 16], [0.0; 16], [0.0; 16]);
            for k in 0..=200 {
                let t = k as f32 / 200.0;
                let s = kv.basis_with_derivative(t, &mut v, &mut d);
                assert_eq!(kv.basis(t, &mut b), s);
                for j in 0..=p {
                    assert!((v[j] - b[j]).abs() < 1e-6, "p={p} n={n} t={t} j={j}");
                }
                let sum: f32 = v[..=p].iter().sum();
                assert!((sum - 1.0).abs() < 1e-5);
                let dsum: f32 = d[..=p].iter().sum();
                assert!(
                    dsum.abs() < 1e-3 * (n as f32),
                    "derivatives of a partition of unity sum to 0"
                );
            }
        }
    }
}
