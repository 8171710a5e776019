//! FFSD control points: Free-Form Shape Deformation (Yoshizawa et al. 2002) with the
//! identikit improvements of Martínek & Kolingerová (GRAPP 2014, "Deformation Method for 3D
//! Identikit Creation"). Equation numbers refer to that paper; `docs/algorithms/ffsd.md`
//! lists every decision taken where the paper is ambiguous.
//!
//! For one control point with centre `X` (the control point `C`, or the reference point `R`
//! in directional mode), target `T` and parameters `γ, α, ε`, a vertex `V` moves by
//!
//! `d(V) = γ · W(X, V) / σ · (V − T)`, `W(X, V) = exp(−|X − V|^α / (2ε²))`, `σ = W(X, V_min)`
//!
//! where `V_min` is the active vertex closest to `X` and
//!
//! * basic mode (Eq. 1): `X = C`, `T = C`;
//! * virtual control point (Eq. 2): `X = C`, `T = V_cp = 2·V_min − C` (the paper prints
//!   `V_min − C`, a vector; we reflect `C` about `V_min`, as Eq. 4 reflects it about `R`);
//! * directional (Eq. 4): `X = R`, `T = V_cp = 2R − C`, and `σ = W(R, V_min)` with `V_min`
//!   closest to `R`.
//!
//! Several points add up (Eq. 3): `D(V) = Σₖ dₖ(V)`, `P = V + D(V)`. The height parameter
//! `ϑ` (Eq. 5–6) limits `|D|` relative to `S_ref = maxₖ |D(V_min,k)|`.
//!
//! `W/σ` is evaluated as `exp(−(|X − V|^α − |X − V_min|^α) / (2ε²))`, which is the same
//! number but never divides by an underflowed `σ`.

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::tool::{BindInput, Deformer, uniform_scale};

/// How a control point pushes the surface.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum PointMode {
    /// Eq. (1): displacement along `V − C`; round-repelling for γ > 0, sharp-attracting for
    /// γ < 0.
    #[default]
    Basic,
    /// Eq. (2) with the virtual control point `2·V_min − C`: the opposite shapes
    /// (round-attracting, sharp-repelling).
    Virtual,
    /// Eq. (4): displacement along `C − R` around the user's reference point `R`.
    Directional {
        /// The reference point `R` (mesh space).
        reference: Vec3,
    },
}

/// One FFSD control point and its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlPoint {
    /// The control point `C` (mesh space).
    pub position: Vec3,
    /// Basic, virtual or directional.
    #[serde(default)]
    pub mode: PointMode,
    /// γ: strength and sign of the pull (typically in [−1, 1]).
    pub gamma: f32,
    /// α > 0: sharpness (exponent of the distance).
    pub alpha: f32,
    /// ε > 0: size of the influenced region (mesh units).
    pub epsilon: f32,
}

impl ControlPoint {
    /// A basic-mode point.
    #[must_use]
    pub fn basic(position: Vec3, gamma: f32, alpha: f32, epsilon: f32) -> Self {
        Self {
            position,
            mode: PointMode::Basic,
            gamma,
            alpha,
            epsilon,
        }
    }

    /// The point `X` whose weight `W(X, V)` drives this point: `R` in directional mode,
    /// `C` otherwise.
    #[must_use]
    pub fn centre(&self) -> Vec3 {
        match self.mode {
            PointMode::Directional { reference } => reference,
            _ => self.position,
        }
    }

    fn validate(&self, what: &str) -> Result<()> {
        check_finite_vec3(|| format!("{what}: position"), self.position)?;
        if let PointMode::Directional { reference } = self.mode {
            check_finite_vec3(|| format!("{what}: reference"), reference)?;
        }
        check_finite(|| format!("{what}: gamma"), self.gamma)?;
        for (name, v) in [("alpha", self.alpha), ("epsilon", self.epsilon)] {
            check_finite(|| format!("{what}: {name}"), v)?;
            if v <= 0.0 {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: {name}"),
                    value: f64::from(v),
                    expected: "must be > 0",
                });
            }
        }
        Ok(())
    }
}

/// The height parameter ϑ of Eq. (5)–(6) and the direction it limits from.
///
/// With `D = Σₖ dₖ(V)`, `s = |D|` and `S_ref = maxₖ |D(V_min,k)|`:
/// * `Above { theta }`: `S_max = ϑ·S_ref`; where `s > S_max`, `D ← D · S_max / s` (Eq. 5 with
///   `L = S_max / S`, applied only where Eq. 6 holds). Flattens peaks, keeps detail.
/// * `Below { theta }`: `S_min = ϑ·S_ref`; where `s ≤ S_min`, `D ← 0`, else
///   `D ← D · (s − S_min) / s`: a smaller mound, cut off sharply at its base, continuous.
/// * `Both { below, above }`: first the cut from below at `below·S_ref`, then the clamp from
///   above at `above·S_ref`: only the centre of the region moves, by at most
///   `(above − below)·S_ref`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum HeightLimit {
    /// Limit from above (the paper's case).
    Above {
        /// ϑ in (0, 1].
        theta: f32,
    },
    /// Limit from below.
    Below {
        /// ϑ in (0, 1].
        theta: f32,
    },
    /// Limit from both sides.
    Both {
        /// Lower ϑ in (0, 1), less than `above`.
        below: f32,
        /// Upper ϑ in (0, 1].
        above: f32,
    },
}

impl HeightLimit {
    fn validate(&self, what: &str) -> Result<()> {
        let in_unit = |name: &str, v: f32| -> Result<()> {
            check_finite(|| format!("{what}: {name}"), v)?;
            if !(v > 0.0 && v <= 1.0) {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: {name}"),
                    value: f64::from(v),
                    expected: "must be in (0, 1]",
                });
            }
            Ok(())
        };
        match *self {
            HeightLimit::Above { theta } | HeightLimit::Below { theta } => in_unit("theta", theta),
            HeightLimit::Both { below, above } => {
                in_unit("below", below)?;
                in_unit("above", above)?;
                if below >= above {
                    return Err(CoreError::OutOfRange {
                        what: format!("{what}: below"),
                        value: f64::from(below),
                        expected: "must be less than above",
                    });
                }
                Ok(())
            }
        }
    }

    /// Applies the limit to a summed displacement `d` given the reference size `s_ref`.
    #[must_use]
    pub fn limit(&self, d: Vec3, s_ref: f32) -> Vec3 {
        let s = d.length();
        if s == 0.0 {
            return d;
        }
        match *self {
            HeightLimit::Above { theta } => {
                let s_max = theta * s_ref;
                if s > s_max { d * (s_max / s) } else { d }
            }
            HeightLimit::Below { theta } => {
                let s_min = theta * s_ref;
                if s <= s_min {
                    Vec3::ZERO
                } else {
                    d * ((s - s_min) / s)
                }
            }
            HeightLimit::Both { below, above } => {
                let (lo, hi) = (below * s_ref, above * s_ref);
                if s <= lo {
                    Vec3::ZERO
                } else {
                    d * ((s - lo).min(hi - lo) / s)
                }
            }
        }
    }
}

/// An FFSD tool: control points summed (Eq. 3), an optional height limit, and a gain that
/// multiplies every γ (a macro's slider).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FfsdTool {
    /// The control points.
    pub points: Vec<ControlPoint>,
    /// Optional height parameter ϑ and its mode.
    #[serde(default)]
    pub height: Option<HeightLimit>,
    /// Multiplies every γ (1 for a free tool; the slider value for a macro).
    #[serde(default = "one")]
    pub gain: f32,
}

fn one() -> f32 {
    1.0
}

impl FfsdTool {
    /// A tool of the given points, no height limit, gain 1.
    #[must_use]
    pub fn new(points: Vec<ControlPoint>) -> Self {
        Self {
            points,
            height: None,
            gain: 1.0,
        }
    }
}

/// One point, prepared for evaluation.
#[derive(Debug, Clone, Copy)]
struct PreparedPoint {
    centre: Vec3,
    target: Vec3,
    gamma: f32,
    half_alpha: f32,
    inv_two_eps2: f32,
    /// `|X − V_min|^α`.
    anchor_pow: f32,
    /// Index of `V_min`.
    anchor: u32,
}

impl PreparedPoint {
    #[inline]
    fn displacement(&self, v: Vec3) -> Vec3 {
        let e = (pow_half(self.centre.distance_squared(v), self.half_alpha) - self.anchor_pow)
            * self.inv_two_eps2;
        (v - self.target) * (self.gamma * (-e).exp())
    }
}

/// `(d²)^(α/2) = |d|^α`, with fast paths for α = 2 and α = 1.
#[inline]
fn pow_half(d2: f32, half_alpha: f32) -> f32 {
    if half_alpha == 1.0 {
        d2
    } else if half_alpha == 0.5 {
        d2.sqrt()
    } else if d2 == 0.0 {
        0.0
    } else {
        (half_alpha * d2.ln()).exp()
    }
}

/// Bind of an [`FfsdTool`]: the prepared points (with `V_min` found among the active
/// vertices of the layer input) and `S_ref`.
#[derive(Debug, Clone)]
pub struct FfsdBind {
    points: Vec<PreparedPoint>,
    s_ref: f32,
}

impl FfsdBind {
    /// Index of `V_min` for each control point (welded vertex index).
    #[must_use]
    pub fn anchors(&self) -> Vec<u32> {
        self.points.iter().map(|p| p.anchor).collect()
    }

    /// `S_ref = maxₖ |D(V_min,k)|`, the displacement the height parameter is relative to.
    #[must_use]
    pub fn reference_size(&self) -> f32 {
        self.s_ref
    }

    fn sum(&self, v: Vec3) -> Vec3 {
        self.points
            .iter()
            .fold(Vec3::ZERO, |acc, p| acc + p.displacement(v))
    }
}

impl Deformer for FfsdTool {
    type Bind = FfsdBind;

    fn validate(&self, what: &str) -> Result<()> {
        check_finite(|| format!("{what}: gain"), self.gain)?;
        for (k, p) in self.points.iter().enumerate() {
            p.validate(&format!("{what}: control point {k}"))?;
        }
        if let Some(h) = &self.height {
            h.validate(&format!("{what}: height"))?;
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<FfsdBind> {
        let points: Vec<PreparedPoint> = self
            .points
            .iter()
            .map(|p| {
                let centre = p.centre();
                let anchor = closest(input.positions, input.active, centre);
                let v_min = input.positions[anchor as usize];
                let target = match p.mode {
                    PointMode::Basic => p.position,
                    PointMode::Virtual => 2.0 * v_min - p.position,
                    PointMode::Directional { reference } => 2.0 * reference - p.position,
                };
                let half_alpha = 0.5 * p.alpha;
                PreparedPoint {
                    centre,
                    target,
                    gamma: p.gamma * self.gain,
                    half_alpha,
                    inv_two_eps2: 1.0 / (2.0 * p.epsilon * p.epsilon),
                    anchor_pow: pow_half(centre.distance_squared(v_min), half_alpha),
                    anchor,
                }
            })
            .collect();
        let mut bind = FfsdBind { points, s_ref: 0.0 };
        bind.s_ref = bind
            .points
            .iter()
            .map(|p| bind.sum(input.positions[p.anchor as usize]).length())
            .fold(0.0, f32::max);
        Ok(bind)
    }

    fn deform(&self, bind: &FfsdBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        for (o, &i) in out.iter_mut().zip(active) {
            let v = positions[i as usize];
            let d = bind.sum(v);
            let d = match &self.height {
                Some(h) => h.limit(d, bind.s_ref),
                None => d,
            };
            *o = v + d;
        }
    }

    /// Points and references map as points; `ε` becomes `ε · s^(α/2)` with `s` the uniform
    /// scale of `m`, so that `W` keeps its shape exactly under similarity transforms.
    fn transformed(&self, m: &Affine3A) -> Self {
        let s = uniform_scale(m);
        let points = self
            .points
            .iter()
            .map(|p| ControlPoint {
                position: m.transform_point3(p.position),
                mode: match p.mode {
                    PointMode::Directional { reference } => PointMode::Directional {
                        reference: m.transform_point3(reference),
                    },
                    other => other,
                },
                epsilon: p.epsilon * s.powf(0.5 * p.alpha),
                ..*p
            })
            .collect();
        Self {
            points,
            ..self.clone()
        }
    }

    fn same_rest_state(&self, other: &Self) -> bool {
        self == other
    }
}

/// The active vertex closest to `x` (first one on ties).
fn closest(positions: &[Vec3], active: &[u32], x: Vec3) -> u32 {
    let mut best = (active[0], f32::INFINITY);
    for &i in active {
        let d = positions[i as usize].distance_squared(x);
        if d < best.1 {
            best = (i, d);
        }
    }
    best.0
}

/// A macro: a named, predefined set of control points with base parameters, driven by one
/// user value γ that multiplies every point's γ (the paper's §5: "the only exception is the
/// parameter γ by which the user controls the size of the required deformation").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FfsdMacro {
    /// Text shown to the user.
    pub label: String,
    /// Group in the identikit panel (for example "Nose").
    #[serde(default)]
    pub group: String,
    /// The named vertex area the macro works in (the paper's area of influence).
    #[serde(default)]
    pub area: Option<String>,
    /// The control points with their base parameters.
    pub points: Vec<ControlPoint>,
    /// Height limit.
    #[serde(default)]
    pub height: Option<HeightLimit>,
    /// Slider range `(min, max)` for the user value.
    #[serde(default = "default_range")]
    pub range: (f32, f32),
}

fn default_range() -> (f32, f32) {
    (-1.0, 1.0)
}

impl FfsdMacro {
    /// The FFSD tool for user value `value` (the gain).
    #[must_use]
    pub fn tool(&self, value: f32) -> FfsdTool {
        FfsdTool {
            points: self.points.clone(),
            height: self.height,
            gain: value,
        }
    }
}
