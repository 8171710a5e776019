//! Axial deformation (AxDf, Lazarus, Coquillart & Jancène 1994) as described in Bechmann's
//! survey "Multidimensional free-form deformation tools" §4.1;
//! `docs/algorithms/axial.md` has the decisions taken where the survey is loose.
//!
//! A point `U` is attached at bind time to its closest point `A_U` on the rest axis, with
//! the rotation-minimising frame `R₁` there ([`crate::frames`]), the twist `W₁` (rotation by
//! `q₁` about the tangent) and the scale `S₁` (factor `θ₁` on the two coordinates across the
//! axis). Its local coordinates are `l = (T₁ R₁ W₁ S₁)⁻¹ U`. The deformed point is
//!
//! `D(U) = T₂ R₂ W₂ S₂ l = A'_U + R₂ W₂ S₂ S₁⁻¹ W₁⁻¹ R₁ᵀ (U − A_U)`
//!
//! (the survey's `T₂S₂W₂R₂(T₁S₁W₁R₁)⁻¹U`, with `W` and `S` acting in the local frame, where
//! they commute). `A'_U` is the point with the same axis parameter on the deformed axis.
//! The zone of influence is the generalised cylinder of radius `r` around the rest axis:
//! with `d = |U − A_U|`, the point moves by `w · (D(U) − U)`, `w = falloff(d / r)`, and
//! keeps its position exactly where `d ≥ r`.

use glam::{Affine3A, Mat3, Quat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::axial_lanes::{AxisTable, BindArrays};
use crate::chunks::{BIND_CHUNK, Reuse, Slotted, bind_slots_in, recycled};
use crate::curve::{CurveBasis, CurveEvaluator, validate_polygon};
use crate::error::{CoreError, Result, check_finite};
use crate::frames::{Frame, PolylineIndex, double_reflection, polyline_tangents};
use crate::influence::Falloff;
use crate::slerp::SlerpArc;
use crate::tool::{BindInput, Deformer, uniform_scale};

/// Samples per control point of a spline axis.
const SAMPLES_PER_POINT: usize = 16;

/// How the axis runs through its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum AxisShape {
    /// Straight segments between the points.
    #[default]
    Polyline,
    /// A Bézier curve with the points as control polygon.
    Bezier,
    /// A clamped uniform B-spline of the given degree with the points as control polygon.
    BSpline {
        /// The degree `p` (1..=15, less than the number of points).
        degree: usize,
    },
}

/// One axis point of a state: position, twist `q` and scale `θ`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisPoint {
    /// Position (mesh space).
    pub position: Vec3,
    /// Twist angle `q` about the axis tangent, radians (right-hand rule), default 0.
    #[serde(default)]
    pub twist: f32,
    /// Scale `θ > 0` across the axis, default 1.
    #[serde(default = "one")]
    pub scale: f32,
}

fn one() -> f32 {
    1.0
}

impl AxisPoint {
    /// A point without twist and with unit scale.
    #[must_use]
    pub fn at(position: Vec3) -> Self {
        Self {
            position,
            twist: 0.0,
            scale: 1.0,
        }
    }
}

/// The AxDf tool: an axis with a rest and a deformed state and its zone of influence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxialTool {
    /// Polyline or spline through the points.
    #[serde(default)]
    pub shape: AxisShape,
    /// Rest state of the axis (at least 2 points, no two consecutive ones equal).
    pub rest: Vec<AxisPoint>,
    /// Deformed state, as many points as `rest`.
    pub deformed: Vec<AxisPoint>,
    /// Radius `r > 0` of the generalised cylinder around the rest axis (mesh units).
    pub radius: f32,
    /// Falloff of the weight from the axis to the cylinder's surface.
    #[serde(default)]
    pub falloff: Falloff,
    /// Normalised distance up to which the weight stays 1, in `[0, 1)`.
    #[serde(default)]
    pub inner: f32,
}

impl AxialTool {
    /// A polyline tool whose deformed state equals its rest state (the identity).
    #[must_use]
    pub fn new(rest: Vec<AxisPoint>, radius: f32) -> Self {
        Self {
            shape: AxisShape::Polyline,
            deformed: rest.clone(),
            rest,
            radius,
            falloff: Falloff::Smooth,
            inner: 0.0,
        }
    }
}

/// An axis sampled into a polyline with a frame, twist and scale per sample. Rest and
/// deformed states are sampled at the same curve parameters, so sample `k` of one
/// corresponds to sample `k` of the other.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledAxis {
    /// Sample positions.
    pub points: Vec<Vec3>,
    /// Rotation-minimising frame of each sample, as a rotation (local → world).
    pub rotations: Vec<Quat>,
    /// Twist `q` at each sample (radians).
    pub twist: Vec<f32>,
    /// Scale `θ` at each sample.
    pub scale: Vec<f32>,
    /// The slerp between the frames of each sample segment (one fewer than the samples).
    arcs: Vec<SlerpArc>,
    /// The start of the frame propagation: first unit tangent and the normal given to
    /// [`double_reflection`].
    start: Frame,
}

impl SampledAxis {
    /// Samples an axis state. Polyline: the points themselves, with vertex tangents from
    /// [`polyline_tangents`]. Spline: `16 · count + 1` points uniform in the curve parameter
    /// with analytic tangents; twist and scale blended with the same basis functions.
    /// Frames by double reflection from `first` (tangent, normal) — for the deformed state
    /// the rest state's first frame turned by the minimal rotation between the first
    /// tangents — or from [`Frame::from_tangent`].
    pub fn new(
        shape: AxisShape,
        pts: &[AxisPoint],
        first: Option<Frame>,
        what: &str,
    ) -> Result<Self> {
        let positions: Vec<Vec3> = pts.iter().map(|p| p.position).collect();
        let degenerate = |problem: &str| CoreError::Degenerate {
            what: what.to_owned(),
            problem: problem.to_owned(),
        };
        let (points, tangents, twist, scale) = match shape {
            AxisShape::Polyline => (
                positions.clone(),
                polyline_tangents(&positions)
                    .ok_or_else(|| degenerate("the axis has a zero-length segment"))?,
                pts.iter().map(|p| p.twist).collect(),
                pts.iter().map(|p| p.scale).collect(),
            ),
            AxisShape::Bezier | AxisShape::BSpline { .. } => {
                let basis = match shape {
                    AxisShape::BSpline { degree } => CurveBasis::BSpline { degree },
                    _ => CurveBasis::Bezier,
                };
                let ev = CurveEvaluator::new(basis, pts.len(), what)?;
                let m = SAMPLES_PER_POINT * pts.len();
                let mut points = Vec::with_capacity(m + 1);
                let mut tangents = Vec::with_capacity(m + 1);
                let mut twist = Vec::with_capacity(m + 1);
                let mut scale = Vec::with_capacity(m + 1);
                for k in 0..=m {
                    let t = k as f32 / m as f32;
                    let (p, d) = ev.point_and_derivative(&positions, t);
                    let w = ev.point_weights(t);
                    let (mut q, mut s) = (0.0, 0.0);
                    for j in 0..w.len {
                        q += pts[w.first + j].twist * w.values[j];
                        s += pts[w.first + j].scale * w.values[j];
                    }
                    points.push(p);
                    tangents.push(d);
                    twist.push(q);
                    scale.push(s);
                }
                // Where the derivative vanishes (a cusp of the control polygon), use the
                // chord to the neighbouring sample.
                for k in 0..=m {
                    if tangents[k].length_squared() <= 1e-12 * points[k].length_squared().max(1.0) {
                        let (a, b) = if k < m { (k, k + 1) } else { (k - 1, k) };
                        tangents[k] = points[b] - points[a];
                    }
                }
                (points, tangents, twist, scale)
            }
        };
        let t0 = tangents[0]
            .try_normalize()
            .ok_or_else(|| degenerate("the axis has no tangent at its start"))?;
        let n0 = match first {
            None => Frame::from_tangent(t0).map(|f| f.normal),
            Some(f) if f.tangent == t0 => Some(f.normal),
            Some(f) => Some(Quat::from_rotation_arc(f.tangent, t0) * f.normal),
        }
        .ok_or_else(|| degenerate("the axis has no tangent at its start"))?;
        let frames = double_reflection(&points, &tangents, n0).ok_or_else(|| {
            degenerate("the axis has a cusp (zero tangent) where frames are undefined")
        })?;
        let rotations: Vec<Quat> = frames.iter().map(Frame::rotation).collect();
        Ok(Self {
            points,
            arcs: rotations
                .windows(2)
                .map(|w| SlerpArc::new(w[0], w[1]))
                .collect(),
            rotations,
            twist,
            scale,
            start: Frame {
                tangent: t0,
                normal: n0,
                binormal: t0.cross(n0),
            },
        })
    }

    /// The start of the frame propagation (first unit tangent and first normal). Passing it
    /// to [`SampledAxis::new`] for an equal state reproduces the frames bit for bit.
    #[must_use]
    pub fn first_frame(&self) -> Frame {
        self.start
    }

    /// The segments as [`crate::axial_lanes`] reads them.
    fn table(&self) -> AxisTable {
        AxisTable::new(
            &self.points,
            &self.rotations,
            &self.twist,
            &self.scale,
            &self.arcs,
        )
    }

    /// Axis point `A` and local-to-world map `M = R W S` at fraction `f` of sample segment
    /// `j`: position and twist/scale interpolated linearly, frame by spherical
    /// interpolation.
    #[must_use]
    pub fn at(&self, j: usize, f: f32) -> (Vec3, Mat3) {
        let (a, m, _, _) = self.at_with_parts(j, f);
        (a, m)
    }

    /// [`SampledAxis::at`] with the parts of `M = (R W) S`: the rotation `R W` and the scale
    /// `s` of `S = diag(1, s, s)`, so that `M⁻¹ = S⁻¹ (R W)ᵀ` needs no general inverse.
    fn at_with_parts(&self, j: usize, f: f32) -> (Vec3, Mat3, Mat3, f32) {
        let a = self.points[j].lerp(self.points[j + 1], f);
        // Between equal frames (a straight stretch of axis) the frame itself; otherwise the
        // segment's slerp, whose arc cosine was taken once per segment.
        let r = self.arcs[j].at(self.rotations[j], f);
        let q = self.twist[j] + (self.twist[j + 1] - self.twist[j]) * f;
        // As a weighted sum, not `θ_j + (θ_{j+1} − θ_j) f`: both terms are non-negative, so
        // between two valid (positive) scales the result is positive, where the difference
        // form cancels to 0 at `f = 1` between 10⁶ and 10⁻⁶ and the bind then divides by it.
        let s = self.scale[j] * (1.0 - f) + self.scale[j + 1] * f;
        // No twist (the common case): `R W = R`, without the sine and cosine of 0.
        let rw = if q == 0.0 {
            Mat3::from_quat(r)
        } else {
            Mat3::from_quat(r * Quat::from_rotation_x(q))
        };
        let m = rw * Mat3::from_diagonal(Vec3::new(1.0, s, s));
        (a, m, rw, s)
    }
}

/// Bind of an [`AxialTool`]: the sampled rest axis; per bound (active) vertex, in the order of
/// the active list, its sample segment, fraction, local coordinates `l`, the rest-state image
/// `A_U + M₁ l` (≈ `U`) and the zone weight `w`; and per welded vertex its slot in those
/// arrays (a layer limited to a small volume keeps only what its vertices need).
#[derive(Debug, Clone)]
pub struct AxialBind {
    rest: SampledAxis,
    slot: Vec<u32>,
    segment: Vec<u32>,
    fraction: Vec<f32>,
    local: Vec<Vec3>,
    base: Vec<Vec3>,
    weight: Vec<f32>,
}

impl Slotted for AxialBind {
    fn slots(&self) -> &[u32] {
        &self.slot
    }
}

impl AxialBind {
    /// Zone weight of welded vertex `i` (0 outside the cylinder or when it was not active).
    #[must_use]
    pub fn weight(&self, i: u32) -> f32 {
        self.slot
            .get(i as usize)
            .and_then(|&s| self.weight.get(s as usize))
            .copied()
            .unwrap_or(0.0)
    }

    /// The sampled rest axis.
    #[must_use]
    pub fn rest_axis(&self) -> &SampledAxis {
        &self.rest
    }

    /// The per-vertex arrays, as the lanes read them.
    fn arrays(&self) -> BindArrays<'_> {
        BindArrays {
            slot: &self.slot,
            segment: &self.segment,
            fraction: &self.fraction,
            local: &self.local,
            base: &self.base,
            weight: &self.weight,
        }
    }
}

impl AxialTool {
    /// [`Deformer::bind`], copying the entry of every vertex that is not stale from
    /// `previous`, a bind of a tool with the same rest state (see [`Reuse`]): a vertex's
    /// segment, local coordinates and zone weight depend on its input alone. The same bits.
    pub fn bind_reusing(
        &self,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, AxialBind>>,
    ) -> Result<AxialBind> {
        self.bind_in(input, previous, None)
    }

    /// [`AxialTool::bind_reusing`] made in the buffers of `spare`, a bind this thread no
    /// longer needs (every value that is read is written again).
    pub(crate) fn bind_in(
        &self,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, AxialBind>>,
        spare: Option<AxialBind>,
    ) -> Result<AxialBind> {
        let rest = SampledAxis::new(self.shape, &self.rest, None, "axial tool: rest axis")?;
        let (slot, segment, fraction, local, base, weight) = spare
            .map_or_else(Default::default, |b| {
                (b.slot, b.segment, b.fraction, b.local, b.base, b.weight)
            });
        let (slot, active) = bind_slots_in(slot, input.positions.len(), input.active);
        let m = active.len();
        // A vertex outside the zone keeps the stale values of `spare` but weight 0, and
        // nothing reads its other values.
        let mut bind = AxialBind {
            slot,
            segment: recycled(segment, m),
            fraction: recycled(fraction, m),
            local: recycled(local, m),
            base: recycled(base, m),
            weight: recycled(weight, m),
            rest,
        };
        let index =
            PolylineIndex::new(bind.rest.points.clone()).ok_or_else(|| CoreError::Degenerate {
                what: "axial tool: rest axis".to_owned(),
                problem: "fewer than 2 samples".to_owned(),
            })?;
        let inv_r = 1.0 / self.radius;
        let table = bind.rest.table();
        // Every vertex on its own, in parallel chunks (the same bits as one by one): the
        // closest axis points of a chunk's vertices that are not reused, a lane group at a
        // time.
        let rest = &bind.rest;
        bind.segment
            .par_chunks_mut(BIND_CHUNK)
            .zip(bind.fraction.par_chunks_mut(BIND_CHUNK))
            .zip(bind.local.par_chunks_mut(BIND_CHUNK))
            .zip(bind.base.par_chunks_mut(BIND_CHUNK))
            .zip(bind.weight.par_chunks_mut(BIND_CHUNK))
            .zip(active.par_chunks(BIND_CHUNK))
            .for_each(|(((((segment, fraction), local), base), weight), ids)| {
                let (fresh, xs) =
                    Reuse::split_chunk(previous, ids, input.positions, |j, old, s| {
                        segment[j] = old.segment[s];
                        fraction[j] = old.fraction[s];
                        local[j] = old.local[s];
                        base[j] = old.base[s];
                        weight[j] = old.weight[s];
                    });
                let n = xs.len();
                let mut found = vec![(0, 0.0, 0.0); n];
                index.closest_each(&xs, &mut found);
                let ws: Vec<f32> = found
                    .iter()
                    .map(|&(_, _, d2)| self.falloff.weight(d2.sqrt() * inv_r, self.inner))
                    .collect();
                // Lane groups on the lanes; the groups they leave, vertex by vertex.
                let (mut ls, mut bs, mut done) =
                    (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![false; n]);
                table.bind_each(&found, &xs, &ws, &mut ls, &mut bs, &mut done);
                for (k, (u, (j, f, _))) in xs.into_iter().zip(found).enumerate() {
                    let v = fresh.slot(k);
                    let w = ws[k];
                    if w <= 0.0 {
                        weight[v] = 0.0;
                        continue;
                    }
                    let (l, b) = if done[k] {
                        (ls[k], bs[k])
                    } else {
                        bind_vertex(rest, u, j, f)
                    };
                    segment[v] = j as u32;
                    fraction[v] = f;
                    local[v] = l;
                    base[v] = b;
                    weight[v] = w;
                }
            });
        Ok(bind)
    }
}

/// The local coordinates `l = S⁻¹ (R W)ᵀ (U − A)` and the rest image `A + M l` of `u`, whose
/// closest point on the rest axis is at fraction `f` of segment `j`: one vertex of
/// [`AxialTool::bind_reusing`] (whose lane groups have these bits).
fn bind_vertex(rest: &SampledAxis, u: Vec3, j: usize, f: f32) -> (Vec3, Vec3) {
    let (a, m, rw, s) = rest.at_with_parts(j, f);
    // M = R W S is a rotation times diag(1, s, s) with s > 0: M⁻¹ = S⁻¹ (R W)ᵀ.
    let l = rw.transpose() * (u - a);
    let l = Vec3::new(l.x, l.y / s, l.z / s);
    (l, a + m * l)
}

/// The deformed position of welded vertex `i` at input position `u`: one vertex of
/// [`Deformer::deform`] for [`AxialTool`] (whose lane groups have these bits).
fn deform_vertex(deformed: &SampledAxis, bind: &AxialBind, u: Vec3, i: u32) -> Vec3 {
    // A vertex that was not active when the layer bound stays.
    let Some(&k) = bind.slot.get(i as usize).filter(|&&s| s != u32::MAX) else {
        return u;
    };
    let k = k as usize;
    let w = bind.weight[k];
    if w <= 0.0 {
        return u;
    }
    let (j, f, l) = (bind.segment[k] as usize, bind.fraction[k], bind.local[k]);
    let (a2, m2) = deformed.at(j, f);
    // D(U) − U = (A' + M₂ l) − (A + M₁ l): the second term was computed at bind time by the
    // same operations, so the difference is exactly 0 for an unmoved axis.
    let d = (a2 + m2 * l) - bind.base[k];
    if w == 1.0 { u + d } else { u + d * w }
}

impl Deformer for AxialTool {
    type Bind = AxialBind;

    fn validate(&self, what: &str) -> Result<()> {
        if self.rest.len() != self.deformed.len() {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "the rest axis has {} points but the deformed one has {}",
                    self.rest.len(),
                    self.deformed.len()
                ),
            });
        }
        if self.rest.len() < 2 {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "an axis needs at least 2 distinct points, found {}",
                    self.rest.len()
                ),
            });
        }
        if self.rest.len() > crate::curve::MAX_CURVE_POINTS {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: number of axis points"),
                value: self.rest.len() as f64,
                expected: "must be at most 4096",
            });
        }
        check_finite(|| format!("{what}: radius"), self.radius)?;
        if self.radius <= 0.0 {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: radius"),
                value: f64::from(self.radius),
                expected: "must be > 0",
            });
        }
        check_finite(|| format!("{what}: inner"), self.inner)?;
        if !(0.0..1.0).contains(&self.inner) {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: inner"),
                value: f64::from(self.inner),
                expected: "must be in [0, 1)",
            });
        }
        for (state, pts) in [("rest", &self.rest), ("deformed", &self.deformed)] {
            let w = format!("{what}: {state} axis");
            let positions: Vec<Vec3> = pts.iter().map(|p| p.position).collect();
            validate_polygon(&positions, &w)?;
            for (i, p) in pts.iter().enumerate() {
                check_finite(|| format!("{w}: point {i}: twist"), p.twist)?;
                check_finite(|| format!("{w}: point {i}: scale"), p.scale)?;
                // A ratio: the deformed over the rest scale multiplies offsets from the
                // axis, so both stay within six orders of magnitude of 1.
                if !(1e-6..=1e6).contains(&p.scale) {
                    return Err(CoreError::OutOfRange {
                        what: format!("{w}: point {i}: scale"),
                        value: f64::from(p.scale),
                        expected: "must be in [1e-6, 1e6]",
                    });
                }
            }
        }
        let rest = SampledAxis::new(self.shape, &self.rest, None, &format!("{what}: rest axis"))?;
        SampledAxis::new(
            self.shape,
            &self.deformed,
            Some(rest.first_frame()),
            &format!("{what}: deformed axis"),
        )?;
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<AxialBind> {
        self.bind_reusing(input, None)
    }

    fn deform(&self, bind: &AxialBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        let deformed = SampledAxis::new(
            self.shape,
            &self.deformed,
            Some(bind.rest.first_frame()),
            "",
        );
        let Ok(deformed) = deformed else {
            // Unreachable for a validated tool; never produce garbage.
            for (o, &i) in out.iter_mut().zip(active) {
                *o = positions[i as usize];
            }
            return;
        };
        // Lane groups on the lanes; the groups they leave, vertex by vertex.
        let mut done = vec![false; active.len()];
        deformed
            .table()
            .deform_each(bind.arrays(), positions, active, out, &mut done);
        for ((o, &i), done) in out.iter_mut().zip(active).zip(done) {
            if !done {
                *o = deform_vertex(&deformed, bind, positions[i as usize], i);
            }
        }
    }

    /// Positions map as points; the radius scales by the uniform scale of `m`; twist angles
    /// change sign when `m` mirrors (the frames stay right-handed); scale factors are ratios
    /// and stay. Exact for similarity transforms (the first frame's choice cancels out).
    fn transformed(&self, m: &Affine3A) -> Self {
        let mirror = m.matrix3.determinant() < 0.0;
        let map = |pts: &[AxisPoint]| -> Vec<AxisPoint> {
            pts.iter()
                .map(|p| AxisPoint {
                    position: m.transform_point3(p.position),
                    twist: if mirror { -p.twist } else { p.twist },
                    scale: p.scale,
                })
                .collect()
        };
        Self {
            rest: map(&self.rest),
            deformed: map(&self.deformed),
            radius: self.radius * uniform_scale(m),
            ..self.clone()
        }
    }

    fn same_rest_state(&self, other: &Self) -> bool {
        self.shape == other.shape
            && self.rest == other.rest
            && self.radius == other.radius
            && self.falloff == other.falloff
            && self.inner == other.inner
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::tests::run;
    use proptest::prelude::*;
    use std::f32::consts::{FRAC_PI_2, PI};

    fn line(count: usize, from: Vec3, to: Vec3) -> Vec<AxisPoint> {
        (0..count)
            .map(|i| AxisPoint::at(from.lerp(to, i as f32 / (count - 1) as f32)))
            .collect()
    }

    fn cloud(len: f32) -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..=16 {
            for j in -2..=2 {
                for k in -2..=2 {
                    v.push(Vec3::new(
                        len * i as f32 / 16.0,
                        j as f32 * 0.1,
                        k as f32 * 0.1,
                    ));
                }
            }
        }
        v
    }

    #[test]
    fn unmoved_axis_without_twist_is_exactly_the_identity() {
        let pts = cloud(2.0);
        let mut rest = line(5, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        rest[2].position.y = 0.3;
        rest[3].position.z = -0.2;
        for shape in [
            AxisShape::Polyline,
            AxisShape::Bezier,
            AxisShape::BSpline { degree: 3 },
        ] {
            let tool = AxialTool {
                shape,
                ..AxialTool::new(rest.clone(), 1.0)
            };
            assert_eq!(run(&tool, &pts), pts, "{shape:?}");
        }
    }

    #[test]
    fn straight_axis_bent_into_a_quarter_circle() {
        // Axis along x of length L = 2 with N = 8 segments; deformed vertices on the quarter
        // circle of radius ρ = 2L/π centred at (0, ρ): vertex k at angle φₖ = (π/2) k/N.
        // The polyline vertex tangents are the circle tangents (by symmetry) and the RMF of
        // a planar curve keeps the binormal, so at vertex k a point (xₖ, y, z) maps to
        // (ρ sin φₖ − y sin ψₖ, ρ − ρ cos φₖ + y cos ψₖ, z) with the tangent angle ψₖ = φₖ
        // inside; at the two ends the polyline tangent is the chord: ψ₀ = φ₁/2,
        // ψ_N = π/2 − φ₁/2.
        let (len, n) = (2.0_f32, 8);
        let rho = 2.0 * len / PI;
        let rest = line(n + 1, Vec3::ZERO, Vec3::new(len, 0.0, 0.0));
        let deformed: Vec<AxisPoint> = (0..=n)
            .map(|k| {
                let phi = FRAC_PI_2 * k as f32 / n as f32;
                AxisPoint::at(Vec3::new(rho * phi.sin(), rho * (1.0 - phi.cos()), 0.0))
            })
            .collect();
        let tool = AxialTool {
            deformed,
            falloff: Falloff::None,
            ..AxialTool::new(rest, 1.0)
        };
        let mut pts = Vec::new();
        let mut expected = Vec::new();
        for k in 0..=n {
            let phi = FRAC_PI_2 * k as f32 / n as f32;
            let half_step = FRAC_PI_2 / n as f32 / 2.0;
            let psi = match k {
                0 => half_step,
                k if k == n => FRAC_PI_2 - half_step,
                _ => phi,
            };
            for (y, z) in [(0.2, 0.0), (-0.3, 0.1), (0.0, -0.25)] {
                pts.push(Vec3::new(len * k as f32 / n as f32, y, z));
                expected.push(Vec3::new(
                    rho * phi.sin() - y * psi.sin(),
                    rho * (1.0 - phi.cos()) + y * psi.cos(),
                    z,
                ));
            }
        }
        for (o, e) in run(&tool, &pts).iter().zip(&expected) {
            assert!(o.distance(*e) < 1e-4, "{o} vs {e}");
        }
    }

    #[test]
    fn analytic_twist() {
        // Straight axis along z, deformed twist rising linearly from 0 to Θ: a point
        // (ρ cos α, ρ sin α, z) goes to (ρ cos(α + Θz/L), ρ sin(α + Θz/L), z).
        let (len, theta) = (2.0_f32, 1.3_f32);
        let rest = line(2, Vec3::ZERO, Vec3::new(0.0, 0.0, len));
        let mut deformed = rest.clone();
        deformed[1].twist = theta;
        let tool = AxialTool {
            deformed,
            falloff: Falloff::None,
            ..AxialTool::new(rest, 1.0)
        };
        let mut pts = Vec::new();
        for i in 0..=10 {
            for a in 0..6 {
                let (rho, alpha, z) = (0.3 + 0.05 * a as f32, a as f32, len * i as f32 / 10.0);
                pts.push(Vec3::new(rho * alpha.cos(), rho * alpha.sin(), z));
            }
        }
        for (p, o) in pts.iter().zip(run(&tool, &pts)) {
            let rho = p.truncate().length();
            let alpha = p.y.atan2(p.x) + theta * p.z / len;
            let e = Vec3::new(rho * alpha.cos(), rho * alpha.sin(), p.z);
            assert!(o.distance(e) < 1e-5, "{p}: {o} vs {e}");
        }
    }

    #[test]
    fn rest_twist_and_scale_cancel_matching_deformed_values() {
        // W₂ = W₁ and S₂ = S₁ on an unmoved axis: D = identity up to rounding.
        let pts = cloud(2.0);
        let mut rest = line(3, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        rest[1].twist = 0.7;
        rest[2].scale = 1.5;
        let tool = AxialTool::new(rest, 1.0);
        for (p, o) in pts.iter().zip(run(&tool, &pts)) {
            assert!(p.distance(o) < 1e-5);
        }
    }

    /// A tool on the unmoved axis `rest` of radius `radius`, every deformed point's scale
    /// `scale`, without falloff.
    fn scaled(rest: Vec<AxisPoint>, scale: f32, radius: f32) -> AxialTool {
        let mut deformed = rest.clone();
        for p in &mut deformed {
            p.scale = scale;
        }
        AxialTool {
            deformed,
            falloff: Falloff::None,
            ..AxialTool::new(rest, radius)
        }
    }

    /// The extreme valid scales at the two ends of a segment: the interpolated scale at the
    /// far end is that end's 10⁻⁶, not a cancellation to 0, so the points on the axis there
    /// stay finite (found by the finite-output property test).
    #[test]
    fn extreme_end_scales_keep_the_axis_end_finite() {
        let mut rest = line(2, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.762_016));
        rest[0].scale = 1e6;
        rest[1].scale = 1e-6;
        let tool = scaled(rest.clone(), 0.05, 0.05);
        let pts = [rest[1].position, rest[0].position, Vec3::new(0.0, 0.0, 0.9)];
        for (p, o) in pts.iter().zip(run(&tool, &pts)) {
            assert!(o.is_finite(), "{p} went to {o}");
        }
    }

    #[test]
    fn scale_scales_across_the_axis_only() {
        let tool = scaled(line(2, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)), 2.0, 1.0);
        let pts = [Vec3::new(0.1, 0.2, 0.5), Vec3::new(-0.3, 0.0, 0.25)];
        let out = run(&tool, &pts);
        assert!(out[0].distance(Vec3::new(0.2, 0.4, 0.5)) < 1e-6);
        assert!(out[1].distance(Vec3::new(-0.6, 0.0, 0.25)) < 1e-6);
    }

    #[test]
    fn outside_the_cylinder_nothing_moves_and_the_falloff_is_monotone() {
        let rest = line(3, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        let mut deformed = rest.clone();
        deformed[2].position = Vec3::new(1.0, 1.0, 0.0);
        let tool = AxialTool {
            deformed,
            ..AxialTool::new(rest, 0.5)
        };
        let pts: Vec<Vec3> = (0..20)
            .map(|i| Vec3::new(1.6, 0.05 * i as f32, 0.0))
            .collect();
        let out = run(&tool, &pts);
        let mut last = f32::INFINITY;
        for (p, o) in pts.iter().zip(&out) {
            let moved = p.distance(*o);
            if p.y >= 0.5 {
                assert_eq!(p, o);
            }
            assert!(moved <= last + 1e-6, "{p}");
            last = moved;
        }
        assert!(p_moved(&pts, &out) > 0.3);
    }

    fn p_moved(a: &[Vec3], b: &[Vec3]) -> f32 {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.distance(*y))
            .fold(0.0, f32::max)
    }

    #[test]
    fn helix_axis_frames_do_not_flip() {
        // A point bound to a helical B-spline axis: consecutive sample frames turn little
        // about the tangent (the RMF's rotation about the tangent stays bounded by the
        // torsion times the step), never by a flip.
        let pts: Vec<AxisPoint> = (0..24)
            .map(|k| {
                let s = k as f32 * 0.5;
                AxisPoint::at(Vec3::new(s.cos(), s.sin(), 0.3 * s))
            })
            .collect();
        let axis = SampledAxis::new(AxisShape::BSpline { degree: 3 }, &pts, None, "t").unwrap();
        for w in axis.rotations.windows(2) {
            let (a, b) = (Mat3::from_quat(w[0]), Mat3::from_quat(w[1]));
            // Twist of frame b relative to a, about b's tangent: angle between a's normal
            // projected into b's normal plane and b's normal.
            let n = a.y_axis - b.x_axis * a.y_axis.dot(b.x_axis);
            let twist = n.dot(b.z_axis).atan2(n.dot(b.y_axis));
            assert!(twist.abs() < 0.02, "twist step {twist}");
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        let ok = AxialTool::new(line(3, Vec3::ZERO, Vec3::X), 0.5);
        assert!(ok.validate("t").is_ok());
        let mut t = ok.clone();
        t.radius = 0.0;
        assert!(t.validate("t").is_err());
        t.radius = f32::NAN;
        assert!(matches!(t.validate("t"), Err(CoreError::NotFinite { .. })));
        let mut t = ok.clone();
        t.deformed[1].position = t.deformed[0].position;
        assert!(matches!(t.validate("t"), Err(CoreError::Degenerate { .. })));
        let mut t = ok.clone();
        t.rest.truncate(1);
        t.deformed.truncate(1);
        assert!(t.validate("t").is_err());
        let mut t = ok.clone();
        t.deformed[2].scale = 0.0;
        assert!(t.validate("t").is_err());
        let mut t = ok.clone();
        t.deformed[2].twist = f32::INFINITY;
        assert!(t.validate("t").is_err());
        let mut t = ok.clone();
        t.deformed.pop();
        assert!(t.validate("t").is_err());
        let mut t = ok;
        t.shape = AxisShape::BSpline { degree: 3 };
        assert!(t.validate("t").is_err());
    }

    #[test]
    fn transformed_commutes_with_similarities() {
        let pts = cloud(2.0);
        let rest = line(4, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        let mut deformed = rest.clone();
        deformed[2].position += Vec3::new(0.0, 0.4, 0.1);
        deformed[3].position += Vec3::new(-0.3, 0.8, 0.0);
        deformed[3].twist = 0.8;
        deformed[1].scale = 1.3;
        let tool = AxialTool {
            deformed,
            ..AxialTool::new(rest, 0.4)
        };
        for m in [
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(1.5),
                Quat::from_rotation_z(0.9),
                Vec3::new(1.0, 2.0, -1.0),
            ),
            Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
        ] {
            let a: Vec<Vec3> = run(&tool, &pts)
                .iter()
                .map(|p| m.transform_point3(*p))
                .collect();
            let moved: Vec<Vec3> = pts.iter().map(|p| m.transform_point3(*p)).collect();
            let b = run(&tool.transformed(&m), &moved);
            for (x, y) in a.iter().zip(&b) {
                assert!(x.distance(*y) < 1e-4, "{x} vs {y}");
            }
        }
    }

    #[test]
    fn ron_defaults_and_round_trip() {
        let text = "(rest: [(position: (0.0, 0.0, 0.0)), (position: (1.0, 0.0, 0.0))], \
                    deformed: [(position: (0.0, 0.0, 0.0)), (position: (1.0, 0.5, 0.0), twist: 0.3, scale: 2.0)], \
                    radius: 0.5)";
        let tool: AxialTool = ron::from_str(text).unwrap();
        assert_eq!(tool.shape, AxisShape::Polyline);
        assert_eq!(tool.falloff, Falloff::Smooth);
        assert_eq!(tool.inner, 0.0);
        assert_eq!((tool.rest[1].twist, tool.rest[1].scale), (0.0, 1.0));
        assert_eq!((tool.deformed[1].twist, tool.deformed[1].scale), (0.3, 2.0));
        let back: AxialTool = ron::from_str(&ron::to_string(&tool).unwrap()).unwrap();
        assert_eq!(back, tool);
        assert!(
            ron::from_str::<AxialTool>("(rest: [], deformed: [], radius: 1.0, bogus: 1)").is_err()
        );
    }

    /// A spread of points around `axis`'s bounds (a deterministic generator), with a few that
    /// are not finite.
    fn spread(count: usize, seed: u32) -> Vec<Vec3> {
        let mut seed = seed.max(1);
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let mut pts: Vec<Vec3> = (0..count)
            .map(|_| Vec3::new(2.4 * next() - 0.2, next() - 0.5, next() - 0.5))
            .collect();
        for (k, bad) in [Vec3::NAN, Vec3::INFINITY, Vec3::new(1e30, 0.0, -1e30)]
            .into_iter()
            .enumerate()
        {
            pts[count / 3 + 37 * k] = bad;
        }
        pts
    }

    /// Binds `tool` on every other point of `pts` and deforms all of them; every bound entry
    /// and moved position must have the bits of the per-vertex code. Returns how many points
    /// of positive weight the registers bound, and how many such vertices they moved (the
    /// rest were left to the per-vertex code).
    fn lanes_match_the_vertex_code(tool: &AxialTool, pts: &[Vec3]) -> (usize, usize) {
        tool.validate("t").unwrap();
        let topo = crate::mesh::Topology {
            weld: vec![],
            representative: vec![],
            triangles: vec![],
        };
        let bound: Vec<u32> = (0..pts.len() as u32).step_by(2).collect();
        let input = BindInput {
            positions: pts,
            topology: &topo,
            active: &bound,
        };
        let bind = tool.bind(&input).unwrap();
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for &i in &bound {
            let k = bind.slot[i as usize] as usize;
            if bind.weight[k] <= 0.0 {
                continue;
            }
            let (j, f) = (bind.segment[k] as usize, bind.fraction[k]);
            let (l, b) = bind_vertex(&bind.rest, pts[i as usize], j, f);
            assert_eq!(bits(bind.local[k]), bits(l), "local of {i}");
            assert_eq!(bits(bind.base[k]), bits(b), "base of {i}");
        }
        let every: Vec<u32> = (0..pts.len() as u32).collect();
        let mut out = vec![Vec3::ZERO; pts.len()];
        tool.deform(&bind, pts, &every, &mut out);
        let deformed = SampledAxis::new(
            tool.shape,
            &tool.deformed,
            Some(bind.rest.first_frame()),
            "",
        )
        .unwrap();
        for (&i, o) in every.iter().zip(&out) {
            let want = deform_vertex(&deformed, &bind, pts[i as usize], i);
            assert_eq!(bits(*o), bits(want), "vertex {i}");
        }
        // How many points of positive weight the registers bound and moved.
        let index = PolylineIndex::new(bind.rest.points.clone()).unwrap();
        let xs: Vec<Vec3> = bound.iter().map(|&i| pts[i as usize]).collect();
        let mut found = vec![(0, 0.0, 0.0); xs.len()];
        index.closest_each(&xs, &mut found);
        let inv_r = 1.0 / tool.radius;
        let ws: Vec<f32> = found
            .iter()
            .map(|&(_, _, d2)| tool.falloff.weight(d2.sqrt() * inv_r, tool.inner))
            .collect();
        let n = xs.len();
        let (mut ls, mut bs, mut done) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![false; n]);
        bind.rest
            .table()
            .bind_each(&found, &xs, &ws, &mut ls, &mut bs, &mut done);
        let bound_on_registers = (0..n).filter(|&k| done[k] && ws[k] > 0.0).count();
        let mut done = vec![false; every.len()];
        deformed
            .table()
            .deform_each(bind.arrays(), pts, &every, &mut out, &mut done);
        let moved_on_registers = every
            .iter()
            .filter(|&&i| done[i as usize] && bind.weight(i) > 0.0)
            .count();
        (bound_on_registers, moved_on_registers)
    }

    /// At least `floor` where the CPU runs the register kernels, none elsewhere.
    fn check_count(count: usize, floor: usize, what: &str) {
        if crate::axial_lanes::registers_run() {
            assert!(count > floor, "{what}: {count} on registers");
        } else {
            assert_eq!(count, 0, "{what}: without AVX2");
        }
    }

    #[test]
    fn lane_groups_have_the_bits_of_the_vertex_code() {
        // Points in random order (groups on several segments) and sorted along the axis
        // (groups on one segment, broadcast).
        let random = spread(3001, 7);
        let mut sorted = random.clone();
        sorted.sort_by(|a, b| a.x.total_cmp(&b.x));
        let mut rest = line(5, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        rest[1].position.y = 0.05;
        rest[2].position.z = -0.1;
        rest[3].position.y = -0.05;
        let mut deformed = rest.clone();
        deformed[3].position += Vec3::new(0.1, 0.3, -0.2);
        deformed[4].position += Vec3::new(-0.2, 0.6, 0.1);
        deformed[4].scale = 1.7;
        deformed[1].scale = 0.6;
        for (pts, in_order) in [(&random, false), (&sorted, true)] {
            for shape in [
                AxisShape::Polyline,
                AxisShape::Bezier,
                AxisShape::BSpline { degree: 3 },
            ] {
                for twist in [false, true] {
                    let mut tool = AxialTool {
                        shape,
                        deformed: deformed.clone(),
                        ..AxialTool::new(rest.clone(), 0.45)
                    };
                    tool.rest[0].scale = 1.2;
                    if twist {
                        // A twist on one point of each state: the segments it reaches (all
                        // of a spline's) take the per-vertex code.
                        tool.deformed[2].twist = 0.7;
                        tool.rest[3].twist = -0.2;
                    }
                    let (bound, moved) = lanes_match_the_vertex_code(&tool, pts);
                    // Most points go through the registers (so the comparison above tests
                    // them); with twists, only the groups of sorted points on the polyline's
                    // untwisted segments, and none of the splines'.
                    let what = format!("{shape:?}, twist {twist}, in order {in_order}");
                    if !twist || (shape == AxisShape::Polyline && in_order) {
                        check_count(bound, 300, &format!("bind, {what}"));
                        check_count(moved, 300, &format!("deform, {what}"));
                    } else if shape != AxisShape::Polyline {
                        assert_eq!((bound, moved), (0, 0), "{what}");
                    }
                }
            }
        }
        // A straight axis along a coordinate axis (equal frames with zeros, whose signs the
        // products keep) and one in general position (frames equal but for rounding: the
        // normalised lerp).
        for (from, to, kinds) in [
            (Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), "same"),
            (Vec3::new(0.1, -0.3, 0.2), Vec3::new(1.9, 0.4, -0.1), "lerp"),
        ] {
            let rest = line(5, from, to);
            let table = SampledAxis::new(AxisShape::Polyline, &rest, None, "")
                .unwrap()
                .table();
            assert_eq!(table.kinds(), kinds, "from {from} to {to}");
            let mut deformed = rest.clone();
            deformed[4].position.y += 0.5;
            let tool = AxialTool {
                deformed,
                ..AxialTool::new(rest, 0.5)
            };
            for pts in [&random, &sorted] {
                let (bound, moved) = lanes_match_the_vertex_code(&tool, pts);
                check_count(bound, 300, &format!("bind from {from} to {to}"));
                check_count(moved, 300, &format!("deform from {from} to {to}"));
            }
        }
    }

    proptest! {
        #[test]
        fn lanes_match_the_vertex_code_on_any_axis(
            shape in 0usize..3,
            rest in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 3..7),
            moves in prop::collection::vec(prop::array::uniform3(-0.5f32..0.5), 7),
            scales in prop::collection::vec(0.3f32..3.0, 7),
            radius in 0.2f32..2.0,
            seed in 1u32..1000,
        ) {
            let shape = [AxisShape::Polyline, AxisShape::Bezier, AxisShape::BSpline { degree: 2 }][shape];
            let rest: Vec<AxisPoint> = rest
                .iter()
                .enumerate()
                .map(|(k, p)| AxisPoint::at(Vec3::from(*p) + Vec3::X * k as f32))
                .collect();
            let deformed: Vec<AxisPoint> = rest
                .iter()
                .zip(&moves)
                .zip(&scales)
                .map(|((p, m), &s)| AxisPoint { position: p.position + Vec3::from(*m), twist: 0.0, scale: s })
                .collect();
            let tool = AxialTool { shape, deformed, ..AxialTool::new(rest, radius) };
            if tool.validate("t").is_ok() {
                let pts: Vec<Vec3> = spread(600, seed).iter().map(|p| *p * 3.0).collect();
                lanes_match_the_vertex_code(&tool, &pts);
            }
        }
    }

    proptest! {
        #[test]
        fn rigid_motion_of_the_axis_moves_points_rigidly(
            angle in -3.0f32..3.0, tx in -1.0f32..1.0, ty in -1.0f32..1.0,
            px in 0.0f32..2.0, py in -0.3f32..0.3, pz in -0.3f32..0.3,
        ) {
            // Deformed axis = rigid motion of the rest axis, zone covering the point fully:
            // every point inside follows the same rigid motion.
            let rest = line(4, Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
            let m = Affine3A::from_rotation_translation(Quat::from_rotation_y(angle), Vec3::new(tx, ty, 0.0));
            let deformed = rest.iter().map(|p| AxisPoint::at(m.transform_point3(p.position))).collect();
            let tool = AxialTool { deformed, falloff: Falloff::None, ..AxialTool::new(rest, 5.0) };
            let p = Vec3::new(px, py, pz);
            let o = run(&tool, &[p])[0];
            prop_assert!(o.distance(m.transform_point3(p)) < 1e-4);
        }
    }
}
