//! Spline controls: a function `F(s)` over `s ∈ [0, 1]` given by a few control values,
//! used by the sketch tool (turning angle, scale and twist speed along the curve, Kho &
//! Garland §5.3) and by the custom falloff of influence volumes.

use serde::{Deserialize, Serialize};

use crate::basis::KnotVector;
use crate::error::{CoreError, Result, check_finite};

/// A spline control `F(s) = Σᵢ N_{i,p}(s) cᵢ` over `s ∈ [0, 1]` (§5.3): a clamped uniform
/// B-spline function of the given degree with one value per control point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplineControl {
    /// Control values `cᵢ` (at least 2).
    pub values: Vec<f32>,
    /// Degree `p` (≥ 1, less than the number of values; default 3, lowered to
    /// `values.len() − 1` when there are fewer values).
    #[serde(default = "default_degree")]
    pub degree: usize,
}

fn default_degree() -> usize {
    3
}

impl SplineControl {
    /// The control that reproduces `F(s) = s` exactly (control values at the Greville
    /// abscissae), the paper's initial state for the turning-angle and twist-speed controls.
    #[must_use]
    pub fn identity(count: usize, degree: usize) -> Self {
        let degree = degree.clamp(1, count.saturating_sub(1).max(1));
        let values = match KnotVector::clamped_uniform(degree, count.max(2)) {
            Some(k) => (0..k.count())
                .map(|i| k.knots()[i + 1..=i + degree].iter().sum::<f32>() / degree as f32)
                .collect(),
            None => vec![0.0, 1.0],
        };
        Self { values, degree }
    }

    /// The constant control `F(s) = c`.
    #[must_use]
    pub fn constant(c: f32) -> Self {
        Self {
            values: vec![c, c],
            degree: 1,
        }
    }

    /// The control of `count` values (at least 2) and degree `degree` (clamped to
    /// `1..=count − 1`) whose values are this control's `F` at the new control's Greville
    /// abscissae `sᵢ = (t_{i+1} + … + t_{i+p}) / p`: how the Studio adds or removes a value
    /// or changes the degree. A linear `F` (the identity, a constant) is kept exactly (a
    /// B-spline with its values at the Greville abscissae reproduces linear functions); any
    /// other `F` is approximated by one through its samples, so its shape is kept.
    #[must_use]
    pub fn resampled(&self, count: usize, degree: usize) -> Self {
        let mut out = Self::identity(count.max(2), degree);
        for v in &mut out.values {
            *v = self.eval(*v);
        }
        out
    }

    fn knots(&self) -> Option<KnotVector> {
        let degree = self.degree.min(self.values.len().saturating_sub(1)).max(1);
        KnotVector::clamped_uniform(degree, self.values.len())
    }

    /// Checks the values (finite, at least 2) and the degree (1 to 15). `what` names the
    /// control in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        for (i, &v) in self.values.iter().enumerate() {
            check_finite(|| format!("{what}: value {i}"), v)?;
        }
        if self.values.len() < 2 || self.degree == 0 || self.degree > 15 {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "a spline control needs at least 2 values and a degree in 1..=15, found {} values of degree {}",
                    self.values.len(),
                    self.degree
                ),
            });
        }
        Ok(())
    }

    /// `F(s)` at `s` (clamped to `[0, 1]`).
    #[must_use]
    pub fn eval(&self, s: f32) -> f32 {
        let Some(k) = self.knots() else {
            return self.values.first().copied().unwrap_or(0.0);
        };
        let mut basis = [0.0_f32; 16];
        let span = k.basis(s.clamp(0.0, 1.0), &mut basis);
        let p = k.degree();
        (0..=p).map(|r| basis[r] * self.values[span - p + r]).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_linear_functions_and_the_shape_of_others() {
        let max_gap = |a: &SplineControl, b: &SplineControl| {
            (0..=100)
                .map(|k| (a.eval(k as f32 / 100.0) - b.eval(k as f32 / 100.0)).abs())
                .fold(0.0_f32, f32::max)
        };
        let identity = SplineControl::identity(5, 3);
        for (count, degree) in [(2, 1), (3, 2), (6, 3), (9, 2), (4, 7)] {
            let r = identity.resampled(count, degree);
            assert_eq!(r.values.len(), count);
            assert_eq!(r.degree, degree.min(count - 1));
            assert!(max_gap(&identity, &r) < 1e-5, "{count} {degree}");
            let c = SplineControl::constant(0.7).resampled(count, degree);
            assert!(c.values.iter().all(|&v| (v - 0.7).abs() < 1e-6), "{c:?}");
        }
        // A bump keeps its shape when a value is added (not exactly: within a few percent
        // of its height), and its peak stays in the middle.
        let bump = SplineControl {
            values: vec![0.0, 0.0, 1.0, 0.0, 0.0],
            degree: 3,
        };
        let more = bump.resampled(6, 3);
        assert!(max_gap(&bump, &more) < 0.15, "{more:?}");
        let at = |f: &SplineControl, s: f32| f.eval(s);
        assert!(at(&more, 0.5) > at(&more, 0.2) && at(&more, 0.5) > at(&more, 0.8));
        // One value is refused by `validate`, never produced.
        assert_eq!(bump.resampled(1, 3).values.len(), 2);
    }
}
