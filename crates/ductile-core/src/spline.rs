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
