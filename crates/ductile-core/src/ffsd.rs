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
//!
//! Vertices are deformed sixteen at a time (`crate::lane`'s lanes, with `wide`'s polynomial
//! `exp` and `ln`, accurate to a few ulp), in a kernel compiled for the widest registers the
//! CPU has ([`pulp`]'s runtime dispatch: AVX2 where present, SSE2 on any x86-64); no operation
//! is fused, so every register width gives the same bits. Every scalar value this module
//! computes (`S_ref`, [`HeightLimit::limit`], the anchors' `|X − V_min|^α`) goes through the
//! same lane arithmetic, so a vertex gets the same bits whichever vertices share its lanes.
//! Where the CPU has AVX2, tools whose every `α` is 2 or 1 (no `ln`: the identikit's
//! macros) and the search for `V_min` run the same operations in `simd`'s explicit register
//! code instead, which the compiler cannot rearrange lane by lane; the bits are the lanes'
//! (tested).

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::lane::{LANES, Lane, Lanes3};

use rayon::prelude::*;

use crate::chunks::{CHUNK, PARALLEL_THRESHOLD};
use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::tool::{BindInput, Deformer, uniform_scale};

mod simd;

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
            if v < crate::error::MIN_WIDTH {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: {name}"),
                    value: f64::from(v),
                    expected: "must be at least 1e-6 (a width in scene units)",
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
        self.limit_lanes(Lanes3::splat(d), s_ref).lane(0)
    }

    /// [`HeightLimit::limit`] on a lane group of displacements (`s = |d|`; a zero `d` is
    /// returned unchanged).
    #[inline(always)]
    fn limit_lanes(&self, d: Lanes3, s_ref: f32) -> Lanes3 {
        let s = d.length();
        let zero = s.simd_eq(Lane::ZERO);
        let limited = match *self {
            HeightLimit::Above { theta } => {
                let s_max = Lane::splat(theta * s_ref);
                let over = s.simd_gt(s_max);
                d.select(over, d.scale(s_max / s))
            }
            HeightLimit::Below { theta } => {
                let s_min = Lane::splat(theta * s_ref);
                let under = s.simd_le(s_min);
                d.scale((s - s_min) / s).select(under, Lanes3::ZERO)
            }
            HeightLimit::Both { below, above } => {
                let (lo, hi) = (Lane::splat(below * s_ref), Lane::splat(above * s_ref));
                let under = s.simd_le(lo);
                d.scale((s - lo).min(hi - lo) / s)
                    .select(under, Lanes3::ZERO)
            }
        };
        limited.select(zero, d)
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
    /// `γ · W/σ · (V − T)` in each lane.
    #[inline(always)]
    fn displacement(&self, v: &Lanes3) -> Lanes3 {
        let d2 = Lanes3::splat(self.centre).sub(*v).length_squared();
        let e = (pow_half(d2, self.half_alpha) - Lane::splat(self.anchor_pow))
            * Lane::splat(self.inv_two_eps2);
        let w = (-e).exp();
        // Far beyond the point's reach both powers can overflow (∞ − ∞ = NaN, for a large α
        // on a large mesh): the weight there is 0, as the Gaussian's limit is.
        let w = w.simd_eq(w).select(w, Lane::ZERO);
        v.sub(Lanes3::splat(self.target))
            .scale(Lane::splat(self.gamma) * w)
    }
}

/// `(d²)^(α/2) = |d|^α` in each lane, with fast paths for α = 2 and α = 1.
#[inline(always)]
fn pow_half(d2: Lane, half_alpha: f32) -> Lane {
    if half_alpha == 1.0 {
        d2
    } else if half_alpha == 0.5 {
        d2.sqrt()
    } else {
        let p = (Lane::splat(half_alpha) * d2.ln()).exp();
        d2.simd_eq(Lane::ZERO).select(Lane::ZERO, p)
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

    /// `S_ref = maxₖ |D(V_min,k)|`, the displacement the height parameter is relative to;
    /// 0 for a tool without a height limit (nothing reads it then, so the bind skips it).
    #[must_use]
    pub fn reference_size(&self) -> f32 {
        self.s_ref
    }

    /// True when both binds hold bit-identical values (anchors, prepared points and
    /// `S_ref`): [`FfsdTool::deform`] then gives the same bits with either, vertex by vertex.
    #[must_use]
    pub fn same_bits(&self, other: &Self) -> bool {
        let v = |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
        let f = |a: f32, b: f32| a.to_bits() == b.to_bits();
        self.points.len() == other.points.len()
            && f(self.s_ref, other.s_ref)
            && self.points.iter().zip(&other.points).all(|(a, b)| {
                a.anchor == b.anchor
                    && v(a.centre, b.centre)
                    && v(a.target, b.target)
                    && f(a.gamma, b.gamma)
                    && f(a.half_alpha, b.half_alpha)
                    && f(a.inv_two_eps2, b.inv_two_eps2)
                    && f(a.anchor_pow, b.anchor_pow)
            })
    }

    /// `D(V) = Σₖ dₖ(V)` in each lane (Eq. 3), summed in point order from zero.
    #[inline(always)]
    fn sum(&self, v: &Lanes3) -> Lanes3 {
        let mut acc = Lanes3::ZERO;
        for p in &self.points {
            acc = acc.add(p.displacement(v));
        }
        acc
    }
}

/// The most control points of one FFSD tool: far more than a macro set or a hand-made tool
/// needs, few enough that the bind (nearest vertex of every point, and `S_ref`, quadratic in
/// the points, when a height limit is set) stays interactive.
pub const MAX_FFSD_POINTS: usize = 4096;

impl Deformer for FfsdTool {
    type Bind = FfsdBind;

    fn validate(&self, what: &str) -> Result<()> {
        check_finite(|| format!("{what}: gain"), self.gain)?;
        if self.points.len() > MAX_FFSD_POINTS {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: number of control points"),
                value: self.points.len() as f64,
                expected: "must be at most 4096",
            });
        }
        for (k, p) in self.points.iter().enumerate() {
            p.validate(&format!("{what}: control point {k}"))?;
        }
        if let Some(h) = &self.height {
            h.validate(&format!("{what}: height"))?;
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<FfsdBind> {
        let centres: Vec<Vec3> = self.points.iter().map(ControlPoint::centre).collect();
        let anchors = closest(input.positions, input.active, &centres);
        let points: Vec<PreparedPoint> = self
            .points
            .iter()
            .zip(anchors)
            .map(|(p, anchor)| {
                let centre = p.centre();
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
                    anchor_pow: pow_half(
                        Lanes3::splat(centre)
                            .sub(Lanes3::splat(v_min))
                            .length_squared(),
                        half_alpha,
                    )
                    .as_array()[0],
                    anchor,
                }
            })
            .collect();
        let mut bind = FfsdBind { points, s_ref: 0.0 };
        // `S_ref` sums every point at every anchor (quadratic in the points); only the
        // height limit reads it.
        if self.height.is_none() {
            return Ok(bind);
        }
        bind.s_ref = bind
            .points
            .iter()
            .map(|p| {
                bind.sum(&Lanes3::splat(input.positions[p.anchor as usize]))
                    .lane(0)
                    .length()
            })
            .fold(0.0, f32::max);
        Ok(bind)
    }

    /// `P = V + D(V)` (with the height limit), a lane group at a time, compiled for the
    /// widest registers the CPU has.
    fn deform(&self, bind: &FfsdBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        pulp::Arch::new().dispatch(Deform {
            tool: self,
            bind,
            positions,
            vertices: Vertices::Active(active),
            out,
        });
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

impl FfsdTool {
    /// [`Deformer::deform`] on input positions already gathered: `out[j]` is the deformed
    /// `inputs[j]` (same bits as `deform` gives that vertex).
    pub fn deform_inputs(&self, bind: &FfsdBind, inputs: &[Vec3], out: &mut [Vec3]) {
        pulp::Arch::new().dispatch(Deform {
            tool: self,
            bind,
            positions: inputs,
            vertices: Vertices::All,
            out,
        });
    }

    /// `P = V + D(V)`, limited, for one lane group; writes `out.len()` lanes.
    #[inline(always)]
    fn deform_lanes(&self, bind: &FfsdBind, v: Lanes3, out: &mut [Vec3]) {
        let d = bind.sum(&v);
        let d = match &self.height {
            Some(h) => h.limit_lanes(d, bind.s_ref),
            None => d,
        };
        v.add(d).write(out);
    }
}

/// Which vertices a [`Deform`] reads.
enum Vertices<'a> {
    /// `positions[active[j]]` for output `j`.
    Active(&'a [u32]),
    /// `positions[j]` for output `j`.
    All,
}

/// [`FfsdTool::deform_lanes`] over a slice, as a kernel that [`pulp`] compiles for each
/// register width (its lanes are [`Lane`]s: the same bits at every width).
struct Deform<'a> {
    tool: &'a FfsdTool,
    bind: &'a FfsdBind,
    positions: &'a [Vec3],
    vertices: Vertices<'a>,
    out: &'a mut [Vec3],
}

impl pulp::WithSimd for Deform<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, s: S) {
        let (tool, bind, positions) = (self.tool, self.bind, self.positions);
        // With one lane per register (`pulp`'s scalar code), the lanes below vectorise
        // better (SSE2, four to a register).
        if S::F32_LANES > 1 && simd::supports(bind) {
            let ids = match self.vertices {
                Vertices::Active(active) => Some(active),
                Vertices::All => None,
            };
            simd::deform(s, tool, bind, positions, ids, self.out);
            return;
        }
        match self.vertices {
            Vertices::Active(active) => {
                for (o, a) in self.out.chunks_mut(LANES).zip(active.chunks(LANES)) {
                    tool.deform_lanes(bind, Lanes3::gather(positions, a), o);
                }
            }
            Vertices::All => {
                for (o, v) in self.out.chunks_mut(LANES).zip(positions.chunks(LANES)) {
                    tool.deform_lanes(bind, Lanes3::load(v), o);
                }
            }
        }
    }
}

/// For each of `xs`, the active vertex closest to it (the first one on ties). Long lists
/// are searched in one parallel pass over chunks whose winners are combined in order with
/// the same strict comparison, so the result is the serial one.
fn closest(positions: &[Vec3], active: &[u32], xs: &[Vec3]) -> Vec<u32> {
    // One sweep over the chunk for all points, a block of vertices at a time (see
    // `simd::nearest`).
    let search = |chunk: &[u32]| -> Vec<(u32, f32)> {
        pulp::Arch::new().dispatch(Nearest {
            positions,
            chunk,
            centres: xs,
        })
    };
    if active.len() < PARALLEL_THRESHOLD {
        return search(active).into_iter().map(|b| b.0).collect();
    }
    let winners: Vec<Vec<(u32, f32)>> = active.par_chunks(CHUNK).map(search).collect();
    let mut best = vec![(active[0], f32::INFINITY); xs.len()];
    for chunk in winners {
        for (b, w) in best.iter_mut().zip(chunk) {
            if w.1 < b.1 {
                *b = w;
            }
        }
    }
    best.into_iter().map(|b| b.0).collect()
}

/// The kernel of [`closest`] over one chunk of active vertices: for each centre, the
/// nearest vertex and its squared distance.
struct Nearest<'a> {
    positions: &'a [Vec3],
    chunk: &'a [u32],
    centres: &'a [Vec3],
}

impl pulp::WithSimd for Nearest<'_> {
    type Output = Vec<(u32, f32)>;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, s: S) -> Self::Output {
        if S::F32_LANES > 1 {
            return simd::nearest(s, self.positions, self.chunk, self.centres);
        }
        // One lane per register (`pulp`'s scalar code): the lanes vectorise better (SSE2).
        // The distances `|V − X|²` of a lane group, and only when one beats the best so
        // far, the group's lanes in order with the same strict test.
        let centres: Vec<Lanes3> = self.centres.iter().map(|&x| Lanes3::splat(x)).collect();
        let mut best = vec![(self.chunk[0], f32::INFINITY); centres.len()];
        for group in self.chunk.chunks(LANES) {
            let v = Lanes3::gather(self.positions, group);
            for (b, c) in best.iter_mut().zip(&centres) {
                let d = v.sub(*c).length_squared();
                if d.simd_lt(Lane::splat(b.1)).any() {
                    for (&i, &d) in group.iter().zip(d.as_array()) {
                        if d < b.1 {
                            *b = (i, d);
                        }
                    }
                }
            }
        }
        best
    }
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

#[cfg(test)]
mod tests {
    //! Oracle tests: every expected value below was worked out by hand from the paper's
    //! formulas (Eq. 1–6) on the triangle `V0 = (0,0,0)`, `V1 = (1,0,0)`, `V2 = (0,2,0)`,
    //! with `e^{−1/2} = 0.60653066`, `e^{−2} = 0.13533528`, `e^{−5/2} = 0.08208500`.

    use super::*;
    use crate::mesh::{Mesh, RestMesh};
    use crate::stack::{Layer, Stack};
    use crate::tool::Tool;

    fn triangle() -> RestMesh {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)],
            normals: None,
            uvs: None,
            indices: vec![0, 1, 2],
        };
        RestMesh::new(mesh, "triangle").unwrap()
    }

    fn deformed(tool: FfsdTool) -> Vec<Vec3> {
        let stack = Stack {
            layers: vec![Layer::new("t", Tool::Ffsd(tool))],
        };
        stack.evaluate_welded(&triangle()).unwrap()
    }

    /// `tool` bound on `positions` (any topology: an FFSD bind reads none), `active` active.
    fn bound(tool: &FfsdTool, positions: &[Vec3], active: &[u32]) -> FfsdBind {
        tool.bind(&BindInput {
            positions,
            topology: triangle().topology(),
            active,
        })
        .unwrap()
    }

    fn assert_close(got: &[Vec3], expected: &[[f32; 3]]) {
        for (i, (g, e)) in got.iter().zip(expected).enumerate() {
            let e = Vec3::from_array(*e);
            assert!(
                (*g - e).length() < 1e-6,
                "vertex {i}: got {g}, expected {e}"
            );
        }
    }

    const C: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    #[test]
    fn eq1_basic_deformation() {
        // V_min = V0, σ = W(C, V0); d = γ W/σ (V − C) with γ = 0.5, α = 2, ε = 1.
        let got = deformed(FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 2.0, 1.0)]));
        assert_close(
            &got,
            &[
                [0.0, 0.0, -0.5],
                [1.303_265_3, 0.0, -0.303_265_33],
                [0.0, 2.135_335_3, -0.067_667_64],
            ],
        );
    }

    #[test]
    fn eq1_with_fractional_alpha() {
        // α = 0.5: W/σ at V1 = exp(−(2^{1/4} − 1)/2) = 0.90973352, at V2 = exp(−(5^{1/4} − 1)/2)
        // = 0.78061408.
        let got = deformed(FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 0.5, 1.0)]));
        assert_close(
            &got,
            &[
                [0.0, 0.0, -0.5],
                [1.454_866_8, 0.0, -0.454_866_76],
                [0.0, 2.780_614, -0.390_307_04],
            ],
        );
    }

    #[test]
    fn eq2_virtual_control_point() {
        // V_cp = 2·V_min − C = (0, 0, −1): the surface is pulled towards C instead.
        let mut p = ControlPoint::basic(C, 0.5, 2.0, 1.0);
        p.mode = PointMode::Virtual;
        let got = deformed(FfsdTool::new(vec![p]));
        assert_close(
            &got,
            &[
                [0.0, 0.0, 0.5],
                [1.303_265_3, 0.0, 0.303_265_33],
                [0.0, 2.135_335_3, 0.067_667_64],
            ],
        );
    }

    #[test]
    fn eq4_directional_deformation() {
        // R = V1, C = (1, 0, 1): V_cp = 2R − C = (1, 0, −1), weights W(R, V), σ = W(R, V1).
        let p = ControlPoint {
            position: Vec3::new(1.0, 0.0, 1.0),
            mode: PointMode::Directional { reference: Vec3::X },
            gamma: 0.5,
            alpha: 2.0,
            epsilon: 1.0,
        };
        let got = deformed(FfsdTool::new(vec![p]));
        assert_close(
            &got,
            &[
                [-0.303_265_33, 0.0, 0.303_265_33],
                [1.0, 0.0, 0.5],
                [-0.041_042_5, 2.082_085, 0.041_042_5],
            ],
        );
    }

    #[test]
    fn eq3_several_points_add_up() {
        // Second point C2 = (0, 2, 1), γ = −0.5, V_min = V2.
        let got = deformed(FfsdTool::new(vec![
            ControlPoint::basic(C, 0.5, 2.0, 1.0),
            ControlPoint::basic(Vec3::new(0.0, 2.0, 1.0), -0.5, 2.0, 1.0),
        ]));
        assert_close(
            &got,
            &[
                [0.0, 0.135_335_28, -0.432_332_36],
                [1.262_222_8, 0.082_085, -0.262_222_83],
                [0.0, 2.135_335_3, 0.432_332_36],
            ],
        );
    }

    #[test]
    fn eq5_eq6_height_from_above() {
        // S_ref = |d(V0)| = 0.5, ϑ = 0.5 → S_max = 0.25. V0 (|d| = 0.5) and V1 (|d| = 0.4289)
        // are scaled to length 0.25; V2 (|d| = 0.1513) is below S_max and unchanged.
        let mut tool = FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 2.0, 1.0)]);
        tool.height = Some(HeightLimit::Above { theta: 0.5 });
        let got = deformed(tool);
        assert_close(
            &got,
            &[
                [0.0, 0.0, -0.25],
                [1.176_776_7, 0.0, -0.176_776_7],
                [0.0, 2.135_335_3, -0.067_667_64],
            ],
        );
    }

    #[test]
    fn height_from_below_and_both_sides() {
        // S_min = 0.5 · 0.5 = 0.25: below it nothing moves, above it the excess remains.
        let below = HeightLimit::Below { theta: 0.5 };
        assert_eq!(below.limit(Vec3::new(0.0, 0.0, 0.2), 0.5), Vec3::ZERO);
        assert!(
            (below.limit(Vec3::new(0.0, 0.0, 0.4), 0.5) - Vec3::new(0.0, 0.0, 0.15)).length()
                < 1e-7
        );
        let both = HeightLimit::Both {
            below: 0.2,
            above: 0.6,
        };
        assert_eq!(both.limit(Vec3::new(0.1, 0.0, 0.0), 1.0), Vec3::ZERO);
        assert!(
            (both.limit(Vec3::new(0.5, 0.0, 0.0), 1.0) - Vec3::new(0.3, 0.0, 0.0)).length() < 1e-7
        );
        assert!(
            (both.limit(Vec3::new(0.9, 0.0, 0.0), 1.0) - Vec3::new(0.4, 0.0, 0.0)).length() < 1e-7
        );
    }

    #[test]
    fn gain_scales_gamma_like_a_macro_slider() {
        let m = FfsdMacro {
            label: "m".into(),
            group: String::new(),
            area: None,
            points: vec![ControlPoint::basic(C, 1.0, 2.0, 1.0)],
            height: None,
            range: (-1.0, 1.0),
        };
        let got = deformed(m.tool(0.5));
        assert!((got[0] - Vec3::new(0.0, 0.0, -0.5)).length() < 1e-6);
        assert_eq!(deformed(m.tool(0.0)), triangle().welded_positions());
    }

    #[test]
    fn tiny_epsilon_does_not_divide_by_an_underflowed_sigma() {
        // W(C, V_min) = exp(−1/(2·1e-4)) underflows f32; the ratio form stays finite.
        let got = deformed(FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 2.0, 0.01)]));
        assert!(got.iter().all(|p| p.is_finite()));
        assert!((got[0] - Vec3::new(0.0, 0.0, -0.5)).length() < 1e-6);
        assert_eq!(got[1], Vec3::X);
    }

    #[test]
    fn invalid_parameters_are_named() {
        let bad = |p: ControlPoint| {
            FfsdTool::new(vec![p])
                .validate("tool 'x'")
                .unwrap_err()
                .to_string()
        };
        assert!(bad(ControlPoint::basic(C, 0.5, 0.0, 1.0)).contains("alpha"));
        assert!(bad(ControlPoint::basic(C, 0.5, 1.0, -1.0)).contains("epsilon"));
        assert!(bad(ControlPoint::basic(C, f32::NAN, 1.0, 1.0)).contains("gamma"));
        let mut t = FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 1.0, 1.0)]);
        t.height = Some(HeightLimit::Above { theta: 1.5 });
        assert!(
            t.validate("tool 'x'")
                .unwrap_err()
                .to_string()
                .contains("theta")
        );
        t.height = Some(HeightLimit::Above { theta: 0.0 });
        assert!(t.validate("tool 'x'").is_err());
        t.height = Some(HeightLimit::Both {
            below: 0.6,
            above: 0.5,
        });
        assert!(t.validate("tool 'x'").is_err());
    }

    #[test]
    fn transformed_keeps_the_shape_under_similarity() {
        let tool = FfsdTool::new(vec![ControlPoint::basic(C, 0.5, 0.7, 0.8)]);
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.5),
            glam::Quat::from_rotation_z(0.3),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let rest = triangle();
        let moved_mesh = Mesh {
            positions: rest
                .welded_positions()
                .iter()
                .map(|&p| m.transform_point3(p))
                .collect(),
            normals: None,
            uvs: None,
            indices: vec![0, 1, 2],
        };
        let moved = RestMesh::new(moved_mesh, "moved").unwrap();
        let a = Stack {
            layers: vec![Layer::new("t", Tool::Ffsd(tool.clone()))],
        }
        .evaluate_welded(&rest)
        .unwrap();
        let b = Stack {
            layers: vec![Layer::new("t", Tool::Ffsd(tool.transformed(&m)))],
        }
        .evaluate_welded(&moved)
        .unwrap();
        for (p, q) in a.iter().zip(&b) {
            assert!((m.transform_point3(*p) - *q).length() < 1e-4, "{p} → {q}");
        }
    }

    /// A vertex gets the same bits whichever vertices share its lanes: all 37 vertices at
    /// once (two full lane groups and a padded one), from gathered inputs, and each one
    /// alone agree, and the scalar height limit agrees with the lanes'.
    #[test]
    fn every_register_width_gives_the_same_bits() {
        // The kernel as dispatched (AVX2 on a CPU that has it) and compiled without target
        // features (SSE2 on x86-64): α of 0.8 and 1.3 take `ln` and `exp` in every lane.
        let positions: Vec<Vec3> = (0..203)
            .map(|i| {
                let t = i as f32 * 0.031;
                Vec3::new(t.sin(), (t * 1.7).cos() * 0.8, t * 0.2 - 0.5)
            })
            .collect();
        let active: Vec<u32> = (0..203).filter(|i| i % 7 != 3).collect();
        let mut a = ControlPoint::basic(Vec3::new(0.4, 0.2, 0.1), 0.35, 0.8, 0.3);
        a.mode = PointMode::Virtual;
        let b = ControlPoint::basic(Vec3::new(-0.3, 0.5, -0.2), -0.2, 1.3, 0.25);
        let mut tool = FfsdTool::new(vec![a, b]);
        tool.height = Some(HeightLimit::Below { theta: 0.2 });
        let bind = bound(&tool, &positions, &active);
        let mut dispatched = vec![Vec3::ZERO; active.len()];
        tool.deform(&bind, &positions, &active, &mut dispatched);
        let mut baseline = vec![Vec3::ZERO; active.len()];
        pulp::WithSimd::with_simd(
            Deform {
                tool: &tool,
                bind: &bind,
                positions: &positions,
                vertices: Vertices::Active(&active),
                out: &mut baseline,
            },
            pulp::Scalar::new(),
        );
        let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
            v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
        };
        assert_eq!(bits(&dispatched), bits(&baseline));
        assert!(
            dispatched
                .iter()
                .zip(&active)
                .any(|(d, &i)| *d != positions[i as usize])
        );
    }

    /// The register kernel (`α` of 2 or 1) gives every vertex the bits of the sixteen-float
    /// lanes' `deform_lanes`, dispatched (AVX2 here) and at one lane per register, for every
    /// height limit: on 623 active vertices of 701 (several stages, a partial block) spread
    /// so that `exp` meets its common case, its underflow to 0 and the subnormal band
    /// between, which the register kernel hands to the lanes' `exp`; and for a point so weak
    /// that its displacements are non-zero but their squared length underflows to 0 (the
    /// height limit then keeps them unchanged).
    #[test]
    fn the_register_kernel_gives_the_lanes_bits() {
        let positions: Vec<Vec3> = (0..701)
            .map(|i| {
                let t = i as f32 * 0.013;
                Vec3::new(3.0 * t.sin().abs(), (t * 2.3).cos() + 1.0, t * 0.4)
            })
            .collect();
        let active: Vec<u32> = (0..701).filter(|i| i % 9 != 4).collect();
        // The first vertex whose bits differ, if any.
        let differ = |a: &[Vec3], b: &[Vec3]| {
            a.iter()
                .zip(b)
                .position(|(p, q)| p.to_array().map(f32::to_bits) != q.to_array().map(f32::to_bits))
        };
        let heights = [
            None,
            Some(HeightLimit::Above { theta: 0.4 }),
            Some(HeightLimit::Below { theta: 0.3 }),
            Some(HeightLimit::Both {
                below: 0.2,
                above: 0.6,
            }),
        ];
        let mut bands = [false; 3];
        let mut tiny_seen = false;
        for alpha in [2.0, 1.0] {
            let mut a = ControlPoint::basic(Vec3::new(0.5, 1.2, 0.3), 0.4, alpha, 0.15);
            a.mode = PointMode::Virtual;
            let b = ControlPoint::basic(Vec3::new(2.5, 0.2, 2.0), -0.3, alpha, 0.25);
            let mut c = ControlPoint::basic(Vec3::new(1.5, 1.0, 1.0), 0.2, alpha, 0.5);
            c.mode = PointMode::Directional {
                reference: Vec3::new(1.4, 1.1, 0.8),
            };
            let weak = ControlPoint::basic(Vec3::new(1.0, 1.0, 1.0), 1e-24, alpha, 0.5);
            for (points, height) in heights
                .iter()
                .flat_map(|&h| [(vec![a, b, c], h), (vec![weak], h)])
            {
                let mut tool = FfsdTool::new(points);
                tool.height = height;
                let bind = bound(&tool, &positions, &active);
                assert!(simd::supports(&bind));
                for p in &bind.points {
                    for &i in &active {
                        let d2 = (p.centre - positions[i as usize]).length_squared();
                        let pow = if p.half_alpha == 1.0 { d2 } else { d2.sqrt() };
                        let x = -(pow - p.anchor_pow) * p.inv_two_eps2;
                        bands[usize::from(x < -87.0) + usize::from(x < -103.63)] = true;
                    }
                }
                let mut lanes = vec![Vec3::ZERO; active.len()];
                for (o, group) in lanes.chunks_mut(LANES).zip(active.chunks(LANES)) {
                    tool.deform_lanes(&bind, Lanes3::gather(&positions, group), o);
                }
                let mut dispatched = vec![Vec3::ZERO; active.len()];
                tool.deform(&bind, &positions, &active, &mut dispatched);
                let mut scalar = vec![Vec3::ZERO; active.len()];
                simd::deform(
                    pulp::Scalar::new(),
                    &tool,
                    &bind,
                    &positions,
                    Some(&active),
                    &mut scalar,
                );
                tiny_seen |= lanes.iter().zip(&active).any(|(o, &i)| {
                    let d = *o - positions[i as usize];
                    d != Vec3::ZERO && d.length_squared() == 0.0
                });
                assert_eq!(differ(&dispatched, &lanes), None, "α {alpha}, {height:?}");
                assert_eq!(differ(&scalar, &lanes), None, "α {alpha}, {height:?}");
                let gathered: Vec<Vec3> = active.iter().map(|&i| positions[i as usize]).collect();
                let mut inputs = vec![Vec3::ZERO; active.len()];
                tool.deform_inputs(&bind, &gathered, &mut inputs);
                assert_eq!(differ(&inputs, &lanes), None, "α {alpha}, {height:?}");
            }
        }
        assert_eq!(bands, [true; 3], "exp's three cases met");
        assert!(tiny_seen, "a displacement whose squared length underflows");
    }

    #[test]
    fn lanes_give_each_vertex_the_same_bits_in_any_group() {
        let positions: Vec<Vec3> = (0..37)
            .map(|i| Vec3::new(i as f32 * 0.1, (i % 5) as f32 * 0.2, 0.05 * (i % 3) as f32))
            .collect();
        let active: Vec<u32> = (0..37).collect();
        let mut p = ControlPoint::basic(Vec3::new(1.0, 0.4, 0.6), 0.5, 0.7, 0.5);
        p.mode = PointMode::Virtual;
        let mut tool = FfsdTool::new(vec![p, ControlPoint::basic(Vec3::Y, -0.3, 2.0, 0.4)]);
        tool.height = Some(HeightLimit::Both {
            below: 0.1,
            above: 0.7,
        });
        let bind = bound(&tool, &positions, &active);
        let mut all = vec![Vec3::ZERO; 37];
        tool.deform(&bind, &positions, &active, &mut all);
        let mut gathered = vec![Vec3::ZERO; 37];
        tool.deform_inputs(&bind, &positions, &mut gathered);
        assert_eq!(gathered, all);
        for i in 0..37 {
            let mut one = [Vec3::ZERO];
            tool.deform(&bind, &positions, &[i], &mut one);
            assert_eq!(
                one[0].to_array().map(f32::to_bits),
                all[i as usize].to_array().map(f32::to_bits)
            );
        }
        let d = Vec3::new(0.3, -0.2, 0.1);
        let h = HeightLimit::Above { theta: 0.5 };
        let lanes = h.limit_lanes(Lanes3::splat(d), 0.6);
        assert_eq!(h.limit(d, 0.6), lanes.lane(7));
        assert!((h.limit(d, 0.6).length() - 0.3).abs() < 1e-6);
    }

    /// The nearest active vertex of each centre is the first of the least
    /// `distance_squared`, as a plain loop finds it, on lists of every length around the
    /// register blocks and stages, dispatched and at one lane per register (both the
    /// register code and the lanes that run there); every vertex appears four times, so
    /// that the ties are exact.
    #[test]
    fn closest_is_the_first_nearest_of_a_plain_loop() {
        let positions: Vec<Vec3> = (0..600)
            .map(|i| {
                let t = (i % 150) as f32 * 0.05;
                Vec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        let xs = [
            Vec3::new(0.2, 0.9, 0.0),
            Vec3::new(-1.0, 0.05, 0.02),
            Vec3::ZERO,
            Vec3::new(3.0, -2.0, 1.0),
        ];
        for len in [1, 7, 15, 16, 17, 31, 33, 255, 256, 257, 511, 600] {
            let active: Vec<u32> = (0..600).rev().take(len).rev().collect();
            let plain: Vec<u32> = xs
                .iter()
                .map(|x| {
                    let mut best = (active[0], f32::INFINITY);
                    for &i in &active {
                        let d = positions[i as usize].distance_squared(*x);
                        if d < best.1 {
                            best = (i, d);
                        }
                    }
                    best.0
                })
                .collect();
            assert_eq!(closest(&positions, &active, &xs), plain, "{len} vertices");
            let first = |b: Vec<(u32, f32)>| b.into_iter().map(|b| b.0).collect::<Vec<_>>();
            let nearest = Nearest {
                positions: &positions,
                chunk: &active,
                centres: &xs,
            };
            let lanes = pulp::WithSimd::with_simd(nearest, pulp::Scalar::new());
            assert_eq!(first(lanes), plain, "{len} vertices, lanes");
            let one = simd::nearest(pulp::Scalar::new(), &positions, &active, &xs);
            assert_eq!(first(one), plain, "{len} vertices, one lane per register");
        }
    }

    #[test]
    fn parallel_closest_keeps_the_first_of_equal_distances() {
        let n = PARALLEL_THRESHOLD * 2 + 5;
        // Points on a line; the two closest to x = 30_000.5 are at equal distance: the
        // first (lower index) must win, also across a chunk boundary.
        let positions: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let active: Vec<u32> = (0..n as u32).collect();
        let x = Vec3::new(CHUNK as f32 * 7.0 - 0.5, 0.0, 0.0);
        let far = Vec3::new(-1.0, 0.0, 0.0);
        assert_eq!(
            closest(&positions, &active, &[x, far]),
            vec![CHUNK as u32 * 7 - 1, 0]
        );
        let x = Vec3::new(30_000.25, 1.0, 0.0);
        assert_eq!(closest(&positions, &active, &[x]), vec![30_000]);
        // The serial search over a short list agrees.
        let short: Vec<u32> = (29_990..30_010).collect();
        assert_eq!(closest(&positions, &short, &[x]), vec![30_000]);
    }
}
