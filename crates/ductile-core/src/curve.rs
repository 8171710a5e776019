//! Curve deformation by De Casteljau (Bézier, global) and De Boor (B-spline, local), after
//! the generalised de Casteljau deformation of Chang & Rockwood (SIGGRAPH 1994) as described
//! in Bechmann's survey "Multidimensional free-form deformation tools" §4.2;
//! `docs/algorithms/curve-deformation.md` has the derivation and the decisions.
//!
//! The tool has a rest control polygon `P₀…Pₙ` and a deformed one `Q₀…Qₙ`. A vertex `x` is
//! attached at bind time to its closest rest-curve point: parameter `t`, offset
//! `o = x − C_P(t)`. The survey's two steps are:
//!
//! 1. *the object is mapped by an affine transformation onto each segment of the control
//!    polygon*: segment `i` carries the map `Gᵢ(t, o) = (1 − t) Qᵢ + t Qᵢ₊₁ + Rᵢ o`, where
//!    `Rᵢ` is the minimal rotation taking the rest segment direction `Pᵢ₊₁ − Pᵢ` to the
//!    deformed one `Qᵢ₊₁ − Qᵢ` (so the offset turns with its segment);
//! 2. *then De Casteljau* (Bézier) or *De Boor* (B-spline) blends the `n` mapped copies with
//!    the remaining levels of the recursion, i.e. with the degree-`(p−1)` basis `Mᵢ` over the
//!    segments: `D(x) = Σᵢ Mᵢ(t) Gᵢ(t, o) = C_Q(t) + (Σᵢ Mᵢ(t) Rᵢ) o`.
//!
//! The first level of the recursion applied to the points alone is exactly the first
//! De Casteljau / De Boor level, so points on the rest curve land on the deformed curve. The
//! tool evaluates the algebraically identical displacement form
//! `D(x) = x + Σⱼ Nⱼ(t)(Qⱼ − Pⱼ) + Σᵢ Mᵢ(t)(Rᵢ − I) o`, which is exactly `x` (bit for bit)
//! when `Q = P` and exactly `x` wherever no moved control point has a non-zero basis function.

use glam::{Affine3A, Mat3, Mat3A, Quat, Vec3, Vec3A};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::basis::{KnotVector, MAX_DEGREE, bernstein_all, bernstein_all_with_derivative};
use crate::chunks::{BIND_CHUNK, Fresh, Reuse, Slotted, bind_slots_in, recycled};
use crate::curve_lanes::BoundPoints;
use crate::curve_pieces::CurvePieces;
use crate::error::{CoreError, Result, check_finite_vec3};
use crate::frames::PolylineIndex;
use crate::tool::{BindInput, Deformer};

/// Largest number of control points a Bézier polygon may have (degree [`MAX_DEGREE`]).
pub const MAX_BEZIER_POINTS: usize = MAX_DEGREE + 1;

/// Samples per control point of the polyline drawn for a curve ([`CurveEvaluator::samples`]).
const SAMPLES_PER_POINT: usize = 16;

/// The polynomial basis of a control polygon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CurveBasis {
    /// One Bézier curve of degree `n` (n + 1 control points, at most [`MAX_BEZIER_POINTS`]):
    /// `C(t) = Σ Bᵢⁿ(t) Pᵢ`, `t ∈ [0, 1]`. Every point moves every part of the curve.
    Bezier,
    /// A clamped uniform B-spline of the given degree (1 ≤ degree ≤ [`MAX_DEGREE`], more
    /// control points than the degree): `C(t) = Σ Nᵢ,ₚ(t) Pᵢ`, `t ∈ [0, 1]`. Control point
    /// `i` moves only the part `t ∈ [u_i, u_{i+p+1})`.
    BSpline {
        /// The degree `p`.
        degree: usize,
    },
}

/// Evaluates a curve of a given basis and control-point count: the knot vectors are built
/// once. Weights are written to fixed buffers of `MAX_DEGREE + 1` entries.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveEvaluator {
    basis: CurveBasis,
    count: usize,
    /// Knots of the curve (B-spline).
    knots: Option<KnotVector>,
    /// Knots of the degree-`(p−1)` segment basis (B-spline with `p ≥ 2`).
    segment_knots: Option<KnotVector>,
}

/// Basis weights at one parameter: `values[..len]` belong to indices `first..first + len`.
#[derive(Debug, Clone, Copy)]
pub struct Weights {
    /// Index of the first non-zero function.
    pub first: usize,
    /// Number of non-zero functions.
    pub len: usize,
    /// Their values.
    pub values: [f32; MAX_DEGREE + 1],
}

/// The most control points of a B-spline curve (and of an axial tool's axis): far more than
/// a hand-placed curve needs, few enough that binding stays interactive (the closest-point
/// search samples 16 points per control point).
pub const MAX_CURVE_POINTS: usize = 4096;

impl CurveEvaluator {
    /// The evaluator for `count` control points. Fails (naming `what`) when the count does
    /// not fit the basis: fewer than 2 points, more than [`MAX_BEZIER_POINTS`] for Bézier,
    /// or a B-spline degree outside `1..=MAX_DEGREE` or not below the count.
    pub fn new(basis: CurveBasis, count: usize, what: &str) -> Result<Self> {
        if count < 2 {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!("a curve needs at least 2 control points, found {count}"),
            });
        }
        match basis {
            CurveBasis::Bezier => {
                if count > MAX_BEZIER_POINTS {
                    return Err(CoreError::OutOfRange {
                        what: format!("{what}: number of Bézier control points"),
                        value: count as f64,
                        expected: "must be at most 16 (degree 15)",
                    });
                }
                Ok(Self {
                    basis,
                    count,
                    knots: None,
                    segment_knots: None,
                })
            }
            CurveBasis::BSpline { degree } => {
                if count > MAX_CURVE_POINTS {
                    return Err(CoreError::OutOfRange {
                        what: format!("{what}: number of B-spline control points"),
                        value: count as f64,
                        expected: "must be at most 4096",
                    });
                }
                if degree == 0 || degree > MAX_DEGREE || degree >= count {
                    return Err(CoreError::OutOfRange {
                        what: format!("{what}: B-spline degree"),
                        value: degree as f64,
                        expected: "must be in 1..=15 and less than the number of control points",
                    });
                }
                let knots = KnotVector::clamped_uniform(degree, count);
                let segment_knots = if degree >= 2 {
                    KnotVector::clamped_uniform(degree - 1, count - 1)
                } else {
                    None
                };
                Ok(Self {
                    basis,
                    count,
                    knots,
                    segment_knots,
                })
            }
        }
    }

    /// The basis.
    #[must_use]
    pub fn basis(&self) -> CurveBasis {
        self.basis
    }

    /// Number of control points.
    #[must_use]
    pub fn count(&self) -> usize {
        self.count
    }

    /// The degree `p` of the curve.
    #[must_use]
    pub fn degree(&self) -> usize {
        match self.basis {
            CurveBasis::Bezier => self.count - 1,
            CurveBasis::BSpline { degree } => degree,
        }
    }

    /// The non-zero basis functions of the control points at `t ∈ [0, 1]` (clamped):
    /// Bernstein `Bᵢⁿ(t)` or B-spline `Nᵢ,ₚ(t)`.
    #[must_use]
    pub fn point_weights(&self, t: f32) -> Weights {
        let t = t.clamp(0.0, 1.0);
        let mut w = Weights {
            first: 0,
            len: self.degree() + 1,
            values: [0.0; MAX_DEGREE + 1],
        };
        match &self.knots {
            None => bernstein_all(self.count - 1, t, &mut w.values),
            Some(k) => w.first = k.basis(t, &mut w.values) - k.degree(),
        }
        w
    }

    /// The non-zero degree-`(p−1)` basis functions over the `count − 1` polygon segments at
    /// `t`: the weights of the last `p − 1` levels of De Casteljau (`Bᵢⁿ⁻¹`) or De Boor
    /// (`Nᵢ,ₚ₋₁` on the knot vector without its end knots). For a linear B-spline it is the
    /// indicator of the segment containing `t`.
    #[must_use]
    pub fn segment_weights(&self, t: f32) -> Weights {
        let t = t.clamp(0.0, 1.0);
        let mut w = Weights {
            first: 0,
            len: self.degree(),
            values: [0.0; MAX_DEGREE + 1],
        };
        match (&self.knots, &self.segment_knots) {
            (None, _) => bernstein_all(self.count - 2, t, &mut w.values),
            (Some(k), None) => {
                // Degree 1: N_{s−1}, N_s are non-zero; segment s − 1 holds t.
                w.first = k.span(t) - 1;
                w.values[0] = 1.0;
            }
            (Some(_), Some(sk)) => w.first = sk.basis(t, &mut w.values) - sk.degree(),
        }
        w
    }

    /// `C(t) = Σ wᵢ Pᵢ`.
    #[must_use]
    pub fn point(&self, ctrl: &[Vec3], t: f32) -> Vec3 {
        let w = self.point_weights(t);
        (0..w.len).fold(Vec3::ZERO, |acc, k| acc + ctrl[w.first + k] * w.values[k])
    }

    /// `C(t)` and `C'(t)` (derivative with respect to `t`).
    #[must_use]
    pub fn point_and_derivative(&self, ctrl: &[Vec3], t: f32) -> (Vec3, Vec3) {
        let t = t.clamp(0.0, 1.0);
        let mut v = [0.0_f32; MAX_DEGREE + 1];
        let mut d = [0.0_f32; MAX_DEGREE + 1];
        let first = match &self.knots {
            None => {
                bernstein_all_with_derivative(self.count - 1, t, &mut v, &mut d);
                0
            }
            Some(k) => k.basis_with_derivative(t, &mut v, &mut d) - k.degree(),
        };
        (0..=self.degree()).fold((Vec3::ZERO, Vec3::ZERO), |(p, dp), k| {
            (p + ctrl[first + k] * v[k], dp + ctrl[first + k] * d[k])
        })
    }

    /// `C'(t)` from the hodograph: `C'(t) = Σᵢ Mᵢ(t) cᵢ (Pᵢ₊₁ − Pᵢ)` with the segment basis
    /// `Mᵢ` of [`CurveEvaluator::segment_weights`] and `cᵢ = n` (Bézier, degree `n`) or
    /// `cᵢ = p / (u_{i+p+1} − u_{i+1})` (B-spline, degree `p`). Same value as
    /// [`CurveEvaluator::point_and_derivative`], without allocating.
    #[must_use]
    pub fn derivative(&self, ctrl: &[Vec3], t: f32) -> Vec3 {
        let m = self.segment_weights(t);
        let p = self.degree();
        (0..m.len).fold(Vec3::ZERO, |acc, k| {
            let i = m.first + k;
            let c = match &self.knots {
                None => p as f32,
                Some(kv) => {
                    let span = kv.knots()[i + p + 1] - kv.knots()[i + 1];
                    if span > 0.0 { p as f32 / span } else { 0.0 }
                }
            };
            acc + (ctrl[i + 1] - ctrl[i]) * (c * m.values[k])
        })
    }

    /// The curve sampled at `t = k / m`, `k = 0..=m`, with `m = 16 · count`, indexed for
    /// closest-point queries.
    #[must_use]
    pub fn samples(&self, ctrl: &[Vec3]) -> PolylineIndex {
        let m = SAMPLES_PER_POINT * self.count;
        let points = (0..=m)
            .map(|k| self.point(ctrl, k as f32 / m as f32))
            .collect();
        // m ≥ 32, so the index always exists.
        PolylineIndex::new(points).unwrap_or_else(|| unreachable!("at least two samples"))
    }
}

/// Checks a control polygon: every point finite, no zero-length segment.
pub(crate) fn validate_polygon(points: &[Vec3], what: &str) -> Result<()> {
    for (i, p) in points.iter().enumerate() {
        check_finite_vec3(|| format!("{what}: point {i}"), *p)?;
    }
    for (i, w) in points.windows(2).enumerate() {
        if w[0] == w[1] {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "segment {i} has zero length (points {i} and {} coincide)",
                    i + 1
                ),
            });
        }
    }
    Ok(())
}

/// Curve deformation: a rest and a deformed control polygon of the same basis and size.
///
/// `D(x) = C_Q(t) + (Σᵢ Mᵢ(t) Rᵢ)(x − C_P(t))` with `t` the rest-curve parameter closest to
/// `x` (module documentation). Points beyond the curve ends attach to the end point and move
/// rigidly with the end segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveTool {
    /// Bézier (global, De Casteljau) or B-spline (local, De Boor).
    pub basis: CurveBasis,
    /// Rest control polygon `P₀…Pₙ` (mesh space).
    pub rest: Vec<Vec3>,
    /// Deformed control polygon `Q₀…Qₙ` (mesh space), as many points as `rest`.
    pub deformed: Vec<Vec3>,
}

impl CurveTool {
    /// A tool whose deformed polygon equals its rest polygon (the identity).
    #[must_use]
    pub fn new(basis: CurveBasis, rest: Vec<Vec3>) -> Self {
        Self {
            basis,
            deformed: rest.clone(),
            rest,
        }
    }

    /// The minimal rotations `Rᵢ` taking each rest segment direction to the deformed one
    /// (exactly the identity where they are equal).
    #[must_use]
    pub fn segment_rotations(&self) -> Vec<Mat3> {
        self.rest
            .windows(2)
            .zip(self.deformed.windows(2))
            .map(|(p, q)| {
                let (a, b) = ((p[1] - p[0]).normalize(), (q[1] - q[0]).normalize());
                if a == b {
                    Mat3::IDENTITY
                } else {
                    Mat3::from_quat(Quat::from_rotation_arc(a, b))
                }
            })
            .collect()
    }
}

/// Bind of a [`CurveTool`]: per bound (active) vertex, in the order of the active list, the
/// rest parameter `t`, the offset `o = x − C_P(t)` and the non-zero basis functions at `t`
/// (point basis, then segment basis: `2p + 1` values per vertex); and per welded vertex its
/// slot in those arrays. A layer limited to a small volume of a big mesh keeps only what its
/// vertices need (4 bytes per mesh vertex for the slots).
#[derive(Debug, Clone)]
pub struct CurveBind {
    evaluator: CurveEvaluator,
    slot: Vec<u32>,
    params: Vec<f32>,
    offsets: Vec<Vec3>,
    /// First point index (which is also the first segment index) of the non-zero functions.
    firsts: Vec<u32>,
    /// `degree + 1` point weights then `degree` segment weights per vertex.
    weights: Vec<f32>,
}

impl Slotted for CurveBind {
    fn slots(&self) -> &[u32] {
        &self.slot
    }
}

impl CurveBind {
    /// The bound rest parameter of welded vertex `i` (`None` when it was not active).
    #[must_use]
    pub fn parameter(&self, i: u32) -> Option<f32> {
        let s = *self.slot.get(i as usize)?;
        self.params.get(s as usize).copied()
    }
}

/// What a curve bind computes from the tool alone: the basis's evaluator and the rest
/// curve's power-form pieces with their seed polyline ([`CurveTool::bind_setup`]). Made once,
/// it serves the binds of many sets of vertices.
#[derive(Debug, Clone)]
pub(crate) struct CurveSetup {
    evaluator: CurveEvaluator,
    pieces: CurvePieces,
}

impl CurveTool {
    /// [`Deformer::bind`], copying the entry of every vertex that is not stale from
    /// `previous`, a bind of a tool with the same rest state (see [`Reuse`]): a vertex's
    /// parameter, offset and weights depend on its input alone. The same bits.
    pub fn bind_reusing(
        &self,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, CurveBind>>,
    ) -> Result<CurveBind> {
        self.bind_set_up(&self.bind_setup()?, input, previous, None)
    }

    /// What [`Deformer::deform`] sums: each control point's move `Qᵢ − Pᵢ` and each
    /// segment's turn `Rᵢ − I`, in SIMD vectors (`Vec3A`, `Mat3A`: the same component-wise
    /// products and sums as `Vec3` and `Mat3`, so the same bits, a vector operation for
    /// three).
    fn moves_and_turns(&self) -> (Vec<Vec3A>, Vec<Mat3A>) {
        let moves = self
            .deformed
            .iter()
            .zip(&self.rest)
            .map(|(q, p)| Vec3A::from(*q - *p))
            .collect();
        let turns = self
            .segment_rotations()
            .into_iter()
            .map(|r| Mat3A::from(r - Mat3::IDENTITY))
            .collect();
        (moves, turns)
    }

    /// The part of a bind that depends on the tool alone.
    pub(crate) fn bind_setup(&self) -> Result<CurveSetup> {
        let evaluator = CurveEvaluator::new(self.basis, self.rest.len(), "curve tool")?;
        let pieces = CurvePieces::new(&evaluator, &self.rest);
        Ok(CurveSetup { evaluator, pieces })
    }

    /// [`CurveTool::bind_reusing`] with `setup`, this tool's [`CurveTool::bind_setup`], made
    /// in the buffers of `spare`, a bind this thread no longer needs (every value is written
    /// again).
    pub(crate) fn bind_set_up(
        &self,
        setup: &CurveSetup,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, CurveBind>>,
        spare: Option<CurveBind>,
    ) -> Result<CurveBind> {
        let (evaluator, pieces) = (setup.evaluator.clone(), &setup.pieces);
        let (slot, params, offsets, firsts, weights) = spare.map_or_else(Default::default, |b| {
            (b.slot, b.params, b.offsets, b.firsts, b.weights)
        });
        let (slot, active) = bind_slots_in(slot, input.positions.len(), input.active);
        let m = active.len();
        let stride = 2 * evaluator.degree() + 1;
        // Every entry is written below: a bind's own vertex, or a reused one's copy.
        let mut params = recycled(params, m);
        let mut offsets = recycled(offsets, m);
        let mut firsts = recycled(firsts, m);
        let mut weights = recycled(weights, m * stride);
        let previous = previous.filter(|p| p.bind.evaluator.degree() == evaluator.degree());
        // Every vertex on its own, in parallel chunks (the same bits as one by one): the
        // closest points of a chunk's vertices that are not reused, a lane group at a time.
        params
            .par_chunks_mut(BIND_CHUNK)
            .zip(offsets.par_chunks_mut(BIND_CHUNK))
            .zip(firsts.par_chunks_mut(BIND_CHUNK))
            .zip(weights.par_chunks_mut(BIND_CHUNK * stride))
            .zip(active.par_chunks(BIND_CHUNK))
            .for_each(|((((params, offsets), firsts), weights), ids)| {
                let (fresh, xs) =
                    Reuse::split_chunk(previous, ids, input.positions, |j, old, s| {
                        params[j] = old.params[s];
                        offsets[j] = old.offsets[s];
                        firsts[j] = old.firsts[s];
                        weights[j * stride..(j + 1) * stride]
                            .copy_from_slice(&old.weights[s * stride..(s + 1) * stride]);
                    });
                match &fresh {
                    // Nothing reused in this chunk (a first bind, say): the answers go
                    // straight to it, in order.
                    Fresh::Every => {
                        debug_assert_eq!(xs.len(), params.len(), "every slot is a query");
                        pieces.bind_each(
                            &xs,
                            BoundPoints {
                                params,
                                offsets,
                                firsts,
                                weights,
                            },
                        );
                    }
                    Fresh::Listed(slots) => {
                        let n = xs.len();
                        let (mut p, mut o, mut f) = (vec![0.0; n], vec![Vec3::ZERO; n], vec![0; n]);
                        let mut w = vec![0.0; n * stride];
                        pieces.bind_each(
                            &xs,
                            BoundPoints {
                                params: &mut p,
                                offsets: &mut o,
                                firsts: &mut f,
                                weights: &mut w,
                            },
                        );
                        for (k, &j) in slots.iter().enumerate() {
                            (params[j], offsets[j], firsts[j]) = (p[k], o[k], f[k]);
                            weights[j * stride..(j + 1) * stride]
                                .copy_from_slice(&w[k * stride..(k + 1) * stride]);
                        }
                    }
                }
            });
        Ok(CurveBind {
            evaluator,
            slot,
            params,
            offsets,
            firsts,
            weights,
        })
    }
}

impl Deformer for CurveTool {
    type Bind = CurveBind;

    fn validate(&self, what: &str) -> Result<()> {
        if self.rest.len() != self.deformed.len() {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!(
                    "the rest polygon has {} points but the deformed one has {}",
                    self.rest.len(),
                    self.deformed.len()
                ),
            });
        }
        CurveEvaluator::new(self.basis, self.rest.len(), what)?;
        validate_polygon(&self.rest, &format!("{what}: rest polygon"))?;
        validate_polygon(&self.deformed, &format!("{what}: deformed polygon"))
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<CurveBind> {
        self.bind_reusing(input, None)
    }

    fn deform(&self, bind: &CurveBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        let p = bind.evaluator.degree();
        let (moves, turns) = self.moves_and_turns();
        // The common degrees with the loops' counts known, so that they unroll and their
        // bounds checks go (the Add menu's Bézier curve has degree 4, its B-spline 3).
        let (m, t) = (&moves[..], &turns[..]);
        match p {
            1 => deform_each(1, bind, m, t, positions, active, out),
            2 => deform_each(2, bind, m, t, positions, active, out),
            3 => deform_each(3, bind, m, t, positions, active, out),
            4 => deform_each(4, bind, m, t, positions, active, out),
            5 => deform_each(5, bind, m, t, positions, active, out),
            _ => deform_each(p, bind, m, t, positions, active, out),
        }
    }

    /// Control points map as points. Exact for rigid motions and uniform scalings (the
    /// rotations `Rᵢ` are conjugated by the rotation part); under shear or non-uniform scale
    /// the segment rotations of the mapped polygons are recomputed there, which is the tool
    /// defined in the target space.
    fn transformed(&self, m: &Affine3A) -> Self {
        Self {
            basis: self.basis,
            rest: self.rest.iter().map(|p| m.transform_point3(*p)).collect(),
            deformed: self
                .deformed
                .iter()
                .map(|p| m.transform_point3(*p))
                .collect(),
        }
    }

    fn same_rest_state(&self, other: &Self) -> bool {
        self.basis == other.basis && self.rest == other.rest
    }
}

/// [`CurveTool::deform`] of the `active` vertices at degree `p`, given each control point's
/// move `moves` (`Qᵢ − Pᵢ`) and each segment's turn `turns` (`Rᵢ − I`):
/// `x + Σₖ wₖ (Q − P)_{f+k} + (Σₖ w_{p+1+k} (R − I)_{f+k}) o` with the vertex's first index
/// `f`, weights `w` and offset `o`. Inlined into each degree's call so that the loops'
/// counts are constants.
#[inline(always)]
fn deform_each(
    p: usize,
    bind: &CurveBind,
    moves: &[Vec3A],
    turns: &[Mat3A],
    positions: &[Vec3],
    active: &[u32],
    out: &mut [Vec3],
) {
    let stride = 2 * p + 1;
    for (o, &i) in out.iter_mut().zip(active) {
        let Some(&v) = bind.slot.get(i as usize).filter(|&&s| s != u32::MAX) else {
            // Not bound (not active when the layer bound): it stays.
            *o = positions[i as usize];
            continue;
        };
        let v = v as usize;
        let f = bind.firsts[v] as usize;
        let w = &bind.weights[v * stride..(v + 1) * stride];
        let (moves, turns) = (&moves[f..=f + p], &turns[f..f + p]);
        let mut d = Vec3A::ZERO;
        for k in 0..=p {
            d += moves[k] * w[k];
        }
        let mut turn = Mat3A::ZERO;
        for k in 0..p {
            turn += turns[k] * w[p + 1 + k];
        }
        let x = Vec3A::from(positions[i as usize]);
        *o = Vec3::from(x + d + turn * Vec3A::from(bind.offsets[v]));
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::Topology;
    use proptest::prelude::*;

    /// Validates, binds on `pts` (all active, no topology) and deforms them.
    pub(crate) fn run<T: Deformer>(tool: &T, pts: &[Vec3]) -> Vec<Vec3> {
        tool.validate("t").unwrap();
        deform_all(tool, &bind_all(tool, pts), pts)
    }

    /// `tool`'s bind on `pts`, all active, without topology.
    fn bind_all<T: Deformer>(tool: &T, pts: &[Vec3]) -> T::Bind {
        let topo = Topology {
            weld: vec![],
            representative: vec![],
            triangles: vec![],
        };
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        tool.bind(&BindInput {
            positions: pts,
            topology: &topo,
            active: &active,
        })
        .unwrap()
    }

    /// Every point of `pts` deformed by `tool` with `bind` (a [`bind_all`] on them).
    fn deform_all<T: Deformer>(tool: &T, bind: &T::Bind, pts: &[Vec3]) -> Vec<Vec3> {
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let mut out = vec![Vec3::ZERO; pts.len()];
        tool.deform(bind, pts, &active, &mut out);
        out
    }

    fn straight(count: usize, len: f32) -> Vec<Vec3> {
        (0..count)
            .map(|i| Vec3::new(len * i as f32 / (count - 1) as f32, 0.0, 0.0))
            .collect()
    }

    fn cloud() -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..=20 {
            for j in -2..=2 {
                for k in -2..=2 {
                    v.push(Vec3::new(
                        i as f32 * 0.2 - 0.5,
                        j as f32 * 0.15,
                        k as f32 * 0.15,
                    ));
                }
            }
        }
        v
    }

    /// The degrees whose loops `deform` unrolls (1 to 5) give the bits of the general loop
    /// (the degree hidden from the compiler), and so does a degree past them.
    #[test]
    fn unrolled_degrees_give_the_general_loops_bits() {
        let pts = cloud();
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let bases = [1, 2, 3, 4, 5, 6]
            .map(|degree| CurveBasis::BSpline { degree })
            .into_iter()
            .chain([CurveBasis::Bezier]);
        for basis in bases {
            let rest = straight(8, 1.0);
            let deformed: Vec<Vec3> = rest
                .iter()
                .enumerate()
                .map(|(i, p)| *p + Vec3::new(0.0, 0.1 * (i as f32).sin(), 0.07 * i as f32))
                .collect();
            let tool = CurveTool {
                basis,
                rest,
                deformed,
            };
            let bind = bind_all(&tool, &pts);
            let unrolled = deform_all(&tool, &bind, &pts);
            let (moves, turns) = tool.moves_and_turns();
            let mut general = vec![Vec3::ZERO; pts.len()];
            let p = std::hint::black_box(bind.evaluator.degree());
            deform_each(p, &bind, &moves, &turns, &pts, &active, &mut general);
            let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|x| x.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&unrolled), bits(&general), "{basis:?}");
            assert!(
                unrolled.iter().zip(&pts).any(|(a, b)| a != b),
                "{basis:?} moves"
            );
        }
    }

    #[test]
    fn segment_basis_is_the_derivative_basis() {
        // C'(t) = Σ Mᵢ(t) · p/(u_{i+p+1} − u_{i+1}) (P_{i+1} − P_i) for B-splines and
        // n Σ Bᵢⁿ⁻¹ (P_{i+1} − P_i) for Bézier: checks that the segment weights are the
        // degree-(p−1) basis on the right knots.
        let ctrl = vec![
            Vec3::ZERO,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(2.0, -1.0, 1.0),
            Vec3::new(3.0, 0.5, 2.0),
            Vec3::new(4.0, 1.0, -1.0),
            Vec3::new(5.0, 0.0, 0.0),
        ];
        for basis in [
            CurveBasis::Bezier,
            CurveBasis::BSpline { degree: 2 },
            CurveBasis::BSpline { degree: 3 },
        ] {
            let ev = CurveEvaluator::new(basis, ctrl.len(), "t").unwrap();
            let p = ev.degree() as f32;
            for k in 0..=20 {
                let t = k as f32 / 20.0;
                let (_, dc) = ev.point_and_derivative(&ctrl, t);
                let m = ev.segment_weights(t);
                let mut d = Vec3::ZERO;
                for j in 0..m.len {
                    let i = m.first + j;
                    let scale = match &ev.knots {
                        None => p,
                        Some(kv) => p / (kv.knots()[i + ev.degree() + 1] - kv.knots()[i + 1]),
                    };
                    d += (ctrl[i + 1] - ctrl[i]) * (scale * m.values[j]);
                }
                assert!(
                    (d - dc).length() < 1e-3 * dc.length().max(1.0),
                    "{basis:?} t={t}"
                );
                let e = ev.derivative(&ctrl, t);
                assert!(
                    (e - dc).length() < 1e-3 * dc.length().max(1.0),
                    "{basis:?} t={t}"
                );
            }
        }
    }

    #[test]
    fn unmoved_polygon_is_exactly_the_identity() {
        let pts = cloud();
        let mut rest = straight(5, 3.0);
        rest[2].y = 0.4;
        for basis in [CurveBasis::Bezier, CurveBasis::BSpline { degree: 3 }] {
            let out = run(&CurveTool::new(basis, rest.clone()), &pts);
            assert_eq!(out, pts);
        }
    }

    #[test]
    fn points_on_the_rest_curve_land_on_the_deformed_curve() {
        let rest = straight(4, 3.0);
        let deformed = vec![
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(2.0, -1.0, 0.5),
            Vec3::new(3.0, 0.0, 0.0),
        ];
        for basis in [CurveBasis::Bezier, CurveBasis::BSpline { degree: 2 }] {
            let tool = CurveTool {
                basis,
                rest: rest.clone(),
                deformed: deformed.clone(),
            };
            let ev = CurveEvaluator::new(basis, 4, "t").unwrap();
            let ts: Vec<f32> = (0..=10).map(|k| k as f32 / 10.0).collect();
            let pts: Vec<Vec3> = ts.iter().map(|&t| ev.point(&rest, t)).collect();
            let out = run(&tool, &pts);
            for (t, o) in ts.iter().zip(&out) {
                assert!((*o - ev.point(&deformed, *t)).length() < 1e-4, "t = {t}");
            }
        }
    }

    #[test]
    fn straight_bezier_matches_generalised_de_casteljau() {
        // For a straight, evenly spaced rest polygon C_P(t) = P₀ + t (Pₙ − P₀), so the
        // offset o is the point's (y, z) and D must equal the explicit recursion: level 1
        // maps the point affinely onto each segment, (1 − t) Qᵢ + t Qᵢ₊₁ + Rᵢ o, and the
        // remaining levels interpolate linearly with t.
        let rest = straight(4, 3.0);
        let deformed = vec![
            Vec3::ZERO,
            Vec3::new(1.0, 0.8, 0.0),
            Vec3::new(2.2, 1.0, 0.3),
            Vec3::new(2.5, 2.5, 0.0),
        ];
        let tool = CurveTool {
            basis: CurveBasis::Bezier,
            rest: rest.clone(),
            deformed: deformed.clone(),
        };
        let rots = tool.segment_rotations();
        let pts = vec![
            Vec3::new(0.9, 0.2, -0.1),
            Vec3::new(2.1, -0.3, 0.2),
            Vec3::new(1.5, 0.0, 0.25),
        ];
        let out = run(&tool, &pts);
        for (x, o) in pts.iter().zip(&out) {
            let t = x.x / 3.0;
            let off = Vec3::new(0.0, x.y, x.z);
            let mut level: Vec<Vec3> = (0..3)
                .map(|i| deformed[i] * (1.0 - t) + deformed[i + 1] * t + rots[i] * off)
                .collect();
            while level.len() > 1 {
                level = level
                    .windows(2)
                    .map(|w| w[0] * (1.0 - t) + w[1] * t)
                    .collect();
            }
            assert!((level[0] - *o).length() < 1e-4, "{x}: {} vs {o}", level[0]);
        }
    }

    /// The deform in SIMD vectors (`Vec3A`, `Mat3A`) gives the bits of the same sums in
    /// `Vec3` and `Mat3`, for a global and a local curve.
    #[test]
    fn simd_deform_has_the_bits_of_the_plain_vector_sums() {
        let pts = cloud();
        let topo = Topology {
            weld: vec![],
            representative: vec![],
            triangles: vec![],
        };
        let every: Vec<u32> = (0..pts.len() as u32).collect();
        for basis in [CurveBasis::Bezier, CurveBasis::BSpline { degree: 3 }] {
            let mut tool = CurveTool::new(basis, straight(6, 3.0));
            tool.deformed[3] += Vec3::new(0.1, 0.8, -0.3);
            tool.deformed[5] += Vec3::new(-0.4, 0.2, 0.5);
            let bind = tool
                .bind(&BindInput {
                    positions: &pts,
                    topology: &topo,
                    active: &every,
                })
                .unwrap();
            let mut out = vec![Vec3::ZERO; pts.len()];
            tool.deform(&bind, &pts, &every, &mut out);
            let p = bind.evaluator.degree();
            let moves: Vec<Vec3> = tool
                .deformed
                .iter()
                .zip(&tool.rest)
                .map(|(q, r)| *q - *r)
                .collect();
            let turns: Vec<Mat3> = tool
                .segment_rotations()
                .into_iter()
                .map(|r| r - Mat3::IDENTITY)
                .collect();
            for (v, (x, o)) in pts.iter().zip(&out).enumerate() {
                let (f, w) = (bind.firsts[v] as usize, &bind.weights[v * (2 * p + 1)..]);
                let mut d = Vec3::ZERO;
                for k in 0..=p {
                    d += moves[f + k] * w[k];
                }
                let mut turn = Mat3::ZERO;
                for k in 0..p {
                    turn += turns[f + k] * w[p + 1 + k];
                }
                let expected = *x + d + turn * bind.offsets[v];
                assert_eq!(
                    o.to_array().map(f32::to_bits),
                    expected.to_array().map(f32::to_bits),
                    "{basis:?}, vertex {v}"
                );
            }
        }
    }

    #[test]
    fn vertices_not_active_at_bind_stay_and_have_no_parameter() {
        let pts = cloud();
        let mut tool = CurveTool::new(CurveBasis::BSpline { degree: 3 }, straight(6, 3.0));
        tool.deformed[3] += Vec3::new(0.0, 0.8, 0.0);
        let topo = Topology {
            weld: vec![],
            representative: vec![],
            triangles: vec![],
        };
        let every: Vec<u32> = (0..pts.len() as u32).collect();
        let even: Vec<u32> = every.iter().copied().filter(|i| i % 2 == 0).collect();
        let bind = |active: &[u32]| {
            tool.bind(&BindInput {
                positions: &pts,
                topology: &topo,
                active,
            })
            .unwrap()
        };
        let (all, half) = (bind(&every), bind(&even));
        let (mut a, mut h) = (vec![Vec3::ZERO; pts.len()], vec![Vec3::ZERO; pts.len()]);
        tool.deform(&all, &pts, &every, &mut a);
        tool.deform(&half, &pts, &every, &mut h);
        let mut moved = 0;
        for (k, ((x, a), h)) in pts.iter().zip(&a).zip(&h).enumerate() {
            if k % 2 == 0 {
                // A compact bind gives a bound vertex the bits of a bind of every vertex.
                assert_eq!(a, h);
                assert_eq!(half.parameter(k as u32), all.parameter(k as u32));
                moved += usize::from(a != x);
            } else {
                assert_eq!(h, x);
                assert_eq!(half.parameter(k as u32), None);
            }
        }
        assert!(moved > 20, "{moved}");
    }

    #[test]
    fn bspline_is_local_and_bezier_is_global() {
        let pts = cloud();
        let rest = straight(8, 3.0);
        let moved = 2;
        let mut deformed = rest.clone();
        deformed[moved] += Vec3::new(0.0, 0.5, 0.2);
        // B-spline degree 3: Nⱼ is non-zero on [u_j, u_{j+4}); the segment functions of the
        // segments touching point j are non-zero inside the same interval.
        let tool = CurveTool {
            basis: CurveBasis::BSpline { degree: 3 },
            rest: rest.clone(),
            deformed,
        };
        let kv = KnotVector::clamped_uniform(3, 8).unwrap();
        let (lo, hi) = (kv.knots()[moved], kv.knots()[moved + 4]);
        let bind = bind_all(&tool, &pts);
        let out = deform_all(&tool, &bind, &pts);
        let (mut inside_moved, mut outside) = (0, 0);
        for (k, (x, o)) in pts.iter().zip(&out).enumerate() {
            let t = bind.parameter(k as u32).unwrap();
            if t <= lo || t >= hi {
                assert_eq!(x, o, "t = {t} is outside [{lo}, {hi}) but moved");
                outside += 1;
            } else if x != o {
                inside_moved += 1;
            }
        }
        assert!(
            outside > 50 && inside_moved > 50,
            "{outside} {inside_moved}"
        );

        let mut deformed = rest.clone();
        deformed[moved] += Vec3::new(0.0, 0.5, 0.2);
        let bez = CurveTool {
            basis: CurveBasis::Bezier,
            rest,
            deformed,
        };
        let out = run(&bez, &pts);
        for (x, o) in pts.iter().zip(&out) {
            // Global: every point strictly inside the curve's parameter range moves.
            if x.x > 0.01 && x.x < 2.99 {
                assert!(x.distance(*o) > 0.0, "{x} did not move");
            }
        }
    }

    #[test]
    fn quarter_bend_turns_offsets_with_the_curve() {
        // Linear B-spline (a polyline): a point at the middle of a segment with offset y
        // follows the segment rotated by 90°.
        let rest = vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)];
        let deformed = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
        let tool = CurveTool {
            basis: CurveBasis::BSpline { degree: 1 },
            rest,
            deformed,
        };
        let out = run(&tool, &[Vec3::new(1.5, 0.2, 0.1), Vec3::new(0.5, 0.2, 0.0)]);
        assert!(
            (out[0] - Vec3::new(0.8, 0.5, 0.1)).length() < 1e-5,
            "{}",
            out[0]
        );
        assert!((out[1] - Vec3::new(0.5, 0.2, 0.0)).length() < 1e-6);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let ok = straight(4, 1.0);
        let mut t = CurveTool::new(CurveBasis::BSpline { degree: 3 }, ok.clone());
        assert!(t.validate("t").is_ok());
        t.deformed.pop();
        assert!(t.validate("t").is_err());
        let mut t = CurveTool::new(CurveBasis::BSpline { degree: 4 }, ok.clone());
        assert!(t.validate("t").is_err());
        t.basis = CurveBasis::BSpline { degree: 0 };
        assert!(t.validate("t").is_err());
        let mut t = CurveTool::new(CurveBasis::Bezier, ok.clone());
        t.deformed[1] = t.deformed[2];
        assert!(matches!(t.validate("t"), Err(CoreError::Degenerate { .. })));
        t.deformed[1] = Vec3::NAN;
        assert!(matches!(t.validate("t"), Err(CoreError::NotFinite { .. })));
        let t = CurveTool::new(CurveBasis::Bezier, vec![Vec3::ZERO]);
        assert!(t.validate("t").is_err());
        let t = CurveTool::new(CurveBasis::Bezier, straight(17, 1.0));
        assert!(t.validate("t").is_err());
    }

    #[test]
    fn transformed_commutes_with_rigid_motions() {
        let pts = cloud();
        let rest = straight(5, 3.0);
        let mut deformed = rest.clone();
        deformed[3] += Vec3::new(0.0, 0.6, 0.0);
        deformed[4] += Vec3::new(-0.5, 1.0, 0.3);
        let tool = CurveTool {
            basis: CurveBasis::BSpline { degree: 3 },
            rest,
            deformed,
        };
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_rotation_y(0.7),
            Vec3::new(1.0, -2.0, 0.5),
        );
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

    #[test]
    fn ron_round_trip() {
        let text = "(basis: BSpline(degree: 2), rest: [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0)], \
                    deformed: [(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (2.0, 0.0, 0.0)])";
        let tool: CurveTool = ron::from_str(text).unwrap();
        assert_eq!(tool.basis, CurveBasis::BSpline { degree: 2 });
        assert_eq!(tool.deformed[1], Vec3::new(1.0, 1.0, 0.0));
        let back: CurveTool = ron::from_str(&ron::to_string(&tool).unwrap()).unwrap();
        assert_eq!(back, tool);
    }

    proptest! {
        #[test]
        fn any_unmoved_bspline_is_the_identity(
            ys in proptest::collection::vec(-1.0f32..1.0, 6),
            px in -1.0f32..4.0, py in -1.0f32..1.0, pz in -1.0f32..1.0,
        ) {
            let rest: Vec<Vec3> = ys.iter().enumerate()
                .map(|(i, &y)| Vec3::new(i as f32 * 0.6, y, 0.3 * y * y)).collect();
            let tool = CurveTool::new(CurveBasis::BSpline { degree: 3 }, rest);
            let p = [Vec3::new(px, py, pz)];
            prop_assert_eq!(run(&tool, &p)[0], p[0]);
        }
    }
}
