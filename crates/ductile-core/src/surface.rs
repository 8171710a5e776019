//! Shape surface (the survey's 2-D tool, Bechmann §3, after Feng, Ma & Peng):
//!
//! a B-spline tensor surface `S(u, v)`, at rest a planar grid, and a height surface `H` on
//! the same grid (at rest `H_z ≡ 1`). Binding projects every point `U` onto the rest
//! surface along its normal: `U = S(u₁, u₂) + u₃ N(u₁, u₂)`; the coordinates
//! `(u₁, u₂, u₃)` are kept, and the deformed point is (survey §3, last equation)
//!
//! `D(U) = S'(u₁, u₂) + H_z(u₁, u₂) · u₃ · N'(u₁, u₂)`
//!
//! with `S'` the moved surface and `N'` its unit normal. It is evaluated in the equivalent
//! displacement form `D(U) = U + (S' − S)(u₁, u₂) + u₃ (H_z N' − N)(u₁, u₂)`, which is the
//! identity bit for bit while nothing moves. Points that do not project onto the surface
//! along its normal (their closest point is on the border with a tangential residual) stay
//! where they are: the deformed area is "the space projecting on the shape surface".
//! `docs/algorithms/shape-surface.md` gives the details.

use std::sync::Arc;

use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::basis::{KnotVector, MAX_DEGREE};
use crate::chunks::{BIND_CHUNK, Reuse, Slotted, bind_slots_in, recycled, zeroed};
use crate::curve_pieces::BasisPieces;
use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::lane::copy_prefix;
use crate::surface_lanes::PlanarProjection;
use crate::tool::{BindInput, Deformer};

/// The rest plane of a shape surface: `origin + a·u_edge + b·v_edge`, `(a, b) ∈ [0, 1]²`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceFrame {
    /// The corner `S(0, 0)` at rest.
    pub origin: Vec3,
    /// The edge to `S(1, 0)`.
    pub u_edge: Vec3,
    /// The edge to `S(0, 1)`.
    pub v_edge: Vec3,
}

/// An offset of one control point `P_ij` of the shape surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceEdit {
    /// Control point index `(i, j)` along `u` and `v`.
    pub at: (u32, u32),
    /// Offset from the point's planar rest position (tool space).
    pub offset: Vec3,
}

/// A value of one control point of the height surface (`z` of `H`, 1 at rest).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeightEdit {
    /// Control point index `(i, j)`.
    pub at: (u32, u32),
    /// The height `h_ij` (1: unchanged thickness).
    pub height: f32,
}

/// A shape surface tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSurfaceTool {
    /// The planar rest grid.
    pub frame: SurfaceFrame,
    /// Control points along `u` and `v` (each > degree).
    pub counts: (u32, u32),
    /// B-spline degree along `u` and `v` (1 to 15; default cubic).
    #[serde(default = "cubic")]
    pub degree: (u32, u32),
    /// Optional offsets that make the *rest* surface non-planar (default: planar, as in the
    /// paper). Points are projected onto this rest surface.
    #[serde(default)]
    pub rest: Vec<SurfaceEdit>,
    /// Control point moves of the deformed surface `S'` (relative to the rest surface).
    #[serde(default)]
    pub moves: Vec<SurfaceEdit>,
    /// Height surface control values (all others 1).
    #[serde(default)]
    pub heights: Vec<HeightEdit>,
}

fn cubic() -> (u32, u32) {
    (3, 3)
}

impl ShapeSurfaceTool {
    /// A planar, unmoved cubic surface over `frame` with `counts` control points.
    #[must_use]
    pub fn planar(frame: SurfaceFrame, counts: (u32, u32)) -> Self {
        Self {
            frame,
            counts,
            degree: cubic(),
            rest: Vec::new(),
            moves: Vec::new(),
            heights: Vec::new(),
        }
    }

    /// The rest and moved control nets `P_ij` (rest Greville grid plus `rest` offsets, and
    /// that plus `moves`), dense with index `i + n_u j`; `None` when the counts or degrees
    /// are invalid.
    #[must_use]
    pub fn control_nets(&self) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
        let kv = self.knots()?;
        let (rest, moved, _) = self.nets(&kv);
        Some((rest, moved))
    }

    /// Points `S(u, v) = Σᵢⱼ Nᵢ(u) Nⱼ(v) P_ij` of the surface with control net `net` (dense,
    /// index `i + n_u j`, as from [`ShapeSurfaceTool::control_nets`]) at each parameter pair
    /// of `params` (clamped to `[0, 1]²`). `None` when the counts or degrees are invalid or
    /// `net` does not have `n_u · n_v` points.
    #[must_use]
    pub fn surface_points(&self, net: &[Vec3], params: &[(f32, f32)]) -> Option<Vec<Vec3>> {
        let kv = self.knots()?;
        let n_u = kv[0].count();
        if net.len() != n_u * kv[1].count() {
            return None;
        }
        let (pu, pv) = (kv[0].degree(), kv[1].degree());
        Some(
            params
                .iter()
                .map(|&(u, v)| {
                    let b = bases(&kv, u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
                    eval_net(net, n_u, pu, pv, &b)[0]
                })
                .collect(),
        )
    }

    fn knots(&self) -> Option<[KnotVector; 2]> {
        let (pu, pv) = (self.degree.0 as usize, self.degree.1 as usize);
        if pu > MAX_DEGREE || pv > MAX_DEGREE {
            return None;
        }
        Some([
            KnotVector::clamped_uniform(pu, self.counts.0 as usize)?,
            KnotVector::clamped_uniform(pv, self.counts.1 as usize)?,
        ])
    }

    /// The rest and moved control nets and the heights, dense (index `i + n_u j`).
    fn nets(&self, kv: &[KnotVector; 2]) -> (Vec<Vec3>, Vec<Vec3>, Vec<f32>) {
        let (nu, nv) = (self.counts.0 as usize, self.counts.1 as usize);
        let greville = |k: &KnotVector, i: usize| {
            let p = k.degree();
            k.knots()[i + 1..=i + p].iter().sum::<f32>() / p as f32
        };
        let mut rest = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                rest.push(
                    self.frame.origin
                        + self.frame.u_edge * greville(&kv[0], i)
                        + self.frame.v_edge * greville(&kv[1], j),
                );
            }
        }
        for e in &self.rest {
            rest[e.at.0 as usize + nu * e.at.1 as usize] += e.offset;
        }
        let mut moved = rest.clone();
        for e in &self.moves {
            moved[e.at.0 as usize + nu * e.at.1 as usize] += e.offset;
        }
        let mut heights = vec![1.0; nu * nv];
        for e in &self.heights {
            heights[e.at.0 as usize + nu * e.at.1 as usize] = e.height;
        }
        (rest, moved, heights)
    }
}

/// Basis values and first derivatives of both parameters at one `(u, v)`.
#[derive(Debug, Clone, Copy)]
struct Bases {
    nu: [f32; MAX_DEGREE + 1],
    du: [f32; MAX_DEGREE + 1],
    nv: [f32; MAX_DEGREE + 1],
    dv: [f32; MAX_DEGREE + 1],
    su: usize,
    sv: usize,
}

fn bases(kv: &[KnotVector; 2], u: f32, v: f32) -> Bases {
    piece_bases(&[None, None], kv, u, v)
}

/// [`bases`] from power-form pieces of the two knot vectors (or the recurrence of a knot
/// vector too long for a piece table).
fn piece_bases(pieces: &[Option<BasisPieces>; 2], kv: &[KnotVector; 2], u: f32, v: f32) -> Bases {
    let mut b = Bases {
        nu: [0.0; MAX_DEGREE + 1],
        du: [0.0; MAX_DEGREE + 1],
        nv: [0.0; MAX_DEGREE + 1],
        dv: [0.0; MAX_DEGREE + 1],
        su: 0,
        sv: 0,
    };
    b.su = basis_1d(pieces[0].as_ref(), &kv[0], u, &mut b.nu, &mut b.du);
    b.sv = basis_1d(pieces[1].as_ref(), &kv[1], v, &mut b.nv, &mut b.dv);
    b
}

/// [`piece_bases`] written to `out` as a bind keeps them, `N_u`, `N_u'`, `N_v`, `N_v'`
/// (`p_u + 1`, `p_u + 1`, `p_v + 1`, `p_v + 1` values); returns the first non-zero function in
/// `u` and in `v`.
#[inline]
fn piece_bases_into(
    pieces: &[Option<BasisPieces>; 2],
    kv: &[KnotVector; 2],
    u: f32,
    v: f32,
    out: &mut [f32],
) -> (usize, usize) {
    let (pu, pv) = (kv[0].degree(), kv[1].degree());
    // Degrees up to 3: each direction's values and derivatives in two vectors, stored at once
    // (a planar bind measured 5-10 % faster than through `basis_1d`, 2026-11-27).
    if let [Some(a), Some(b)] = pieces
        && let (Some((first_u, nu, du)), Some((first_v, nv, dv))) =
            (a.values_and_derivatives4(u), b.values_and_derivatives4(v))
    {
        // Bicubic (the Add menu's; of degrees up to 3, the only one with 16 values): four
        // whole vectors.
        if let Ok(out) = <&mut [f32; 16]>::try_from(&mut *out) {
            for (o, x) in out.chunks_exact_mut(4).zip([nu, du, nv, dv]) {
                o.copy_from_slice(&x.to_array());
            }
            return (first_u, first_v);
        }
        let (out_nu, rest) = out.split_at_mut(pu + 1);
        let (out_du, rest) = rest.split_at_mut(pu + 1);
        let (out_nv, out_dv) = rest.split_at_mut(pv + 1);
        copy_prefix(out_nu, &nu.to_array());
        copy_prefix(out_du, &du.to_array());
        copy_prefix(out_nv, &nv.to_array());
        copy_prefix(&mut out_dv[..=pv], &dv.to_array());
        return (first_u, first_v);
    }
    let (nu, rest) = out.split_at_mut(pu + 1);
    let (du, rest) = rest.split_at_mut(pu + 1);
    let (nv, dv) = rest.split_at_mut(pv + 1);
    (
        basis_1d(pieces[0].as_ref(), &kv[0], u, nu, du),
        basis_1d(pieces[1].as_ref(), &kv[1], v, nv, &mut dv[..=pv]),
    )
}

/// The non-zero basis functions of one knot vector at `t` and their derivatives, from its
/// power-form pieces or (without them) the recurrence; returns the first one's index.
fn basis_1d(
    pieces: Option<&BasisPieces>,
    kv: &KnotVector,
    t: f32,
    values: &mut [f32],
    derivs: &mut [f32],
) -> usize {
    match pieces {
        Some(p) => p.values_and_derivatives(t, values, derivs),
        None => kv.basis_with_derivative(t, values, derivs) - kv.degree(),
    }
}

/// `(S, S_u, S_v)` of a control net at bases `b`.
fn eval_net(net: &[Vec3], n_u: usize, pu: usize, pv: usize, b: &Bases) -> [Vec3; 3] {
    eval_weights(net, n_u, b.weights(pu, pv))
}

/// The non-zero basis values and derivatives at one `(u, v)`, borrowed: from a [`Bases`] or
/// from those of a [`SurfaceBind`]'s bound point.
#[derive(Debug, Clone, Copy)]
struct Weights<'a> {
    nu: &'a [f32],
    du: &'a [f32],
    nv: &'a [f32],
    dv: &'a [f32],
    su: usize,
    sv: usize,
}

impl Bases {
    fn weights(&self, pu: usize, pv: usize) -> Weights<'_> {
        Weights {
            nu: &self.nu[..=pu],
            du: &self.du[..=pu],
            nv: &self.nv[..=pv],
            dv: &self.dv[..=pv],
            su: self.su,
            sv: self.sv,
        }
    }
}

/// `(S, S_u, S_v)` of a sparse net given as its non-zero entries `(i, j, P_ij)` in
/// increasing `i + n_u·j` order: the same sums as [`eval_weights`] over the full net, in
/// the same order, without the zero terms (so the same bits).
#[inline(always)]
fn eval_sparse(entries: &[(usize, usize, Vec3)], b: Weights<'_>) -> [Vec3; 3] {
    let mut r = [Vec3::ZERO; 3];
    for &(ci, cj, p) in entries {
        let (Some(i), Some(j)) = (ci.checked_sub(b.su), cj.checked_sub(b.sv)) else {
            continue;
        };
        if i < b.nu.len() && j < b.nv.len() {
            r[0] += p * (b.nu[i] * b.nv[j]);
            r[1] += p * (b.du[i] * b.nv[j]);
            r[2] += p * (b.nu[i] * b.dv[j]);
        }
    }
    r
}

/// `(S, S_u, S_v)` of a control net: `Σᵢⱼ P_ij (NᵢNⱼ, N'ᵢNⱼ, NᵢN'ⱼ)`.
#[inline(always)]
fn eval_weights(net: &[Vec3], n_u: usize, b: Weights<'_>) -> [Vec3; 3] {
    let mut r = [Vec3::ZERO; 3];
    for j in 0..b.nv.len() {
        for i in 0..b.nu.len() {
            let p = net[b.su + i + n_u * (b.sv + j)];
            r[0] += p * (b.nu[i] * b.nv[j]);
            r[1] += p * (b.du[i] * b.nv[j]);
            r[2] += p * (b.nu[i] * b.dv[j]);
        }
    }
    r
}

/// The moved net's offsets from the rest net that deform sums: the non-zero entries (a drag
/// moves few control points) or the whole net with its row length `n_u`.
#[derive(Debug, Clone, Copy)]
enum Sums<'a> {
    Sparse(&'a [(usize, usize, Vec3)]),
    Dense(&'a [Vec3], usize),
}

/// The deformed position of bound point `b` at `x`, with its rest frame and its bases `bs`:
/// `x + D + (H_z N′ − N) u₃` (`S′ − S`'s value and derivatives from `sums`, the height
/// surface from `heights` and its row length where a height is edited).
#[inline(always)]
fn deformed_point(
    x: Vec3,
    b: &Bound,
    frame: &RestFrame,
    bs: Weights<'_>,
    sums: Sums<'_>,
    heights: Option<(&[f32], usize)>,
) -> Vec3 {
    let d = match sums {
        Sums::Sparse(entries) => eval_sparse(entries, bs),
        Sums::Dense(delta, n_u) => eval_weights(delta, n_u, bs),
    };
    // The rest unit normal `S_u × S_v / |S_u × S_v|`, computed once at bind.
    let n_rest = frame.normal;
    // A collapsed moved surface keeps the rest normal there.
    let n_new = (frame.du + d[1])
        .cross(frame.dv + d[2])
        .normalize_or(n_rest);
    // H_z = 1 + Σ (h_ij − 1) Nᵢ Nⱼ (partition of unity), exactly 1 at rest.
    // (Skipped when no height is edited: every term is then 0.)
    let mut h = 1.0;
    if let Some((heights, n_u)) = heights {
        for (j, &nv) in bs.nv.iter().enumerate() {
            for (k, &nu) in bs.nu.iter().enumerate() {
                h += (heights[bs.su + k + n_u * (bs.sv + j)] - 1.0) * nu * nv;
            }
        }
    }
    x + d[0] + (n_new * h - n_rest) * b.u3
}

/// One bound point: its surface coordinates and the first non-zero basis functions there
/// (its rest frame is in [`RestFrames`]).
#[derive(Debug, Clone, Copy, bytemuck::Zeroable)]
struct Bound {
    uv: (f32, f32),
    u3: f32,
    /// The first non-zero basis function in u and v (the knot spans minus the degrees).
    span: (u32, u32),
}

/// The bound point at `(u, v, u₃)`, its basis values written to `weights` (`2(p_u + 1) +
/// 2(p_v + 1)` values, or none where deform `evaluated` them from `pieces`). A function the
/// compiler must inline: as a closure it stayed a call for each of a bind's points, and a
/// planar bind took 8 % more instructions (`docs/performance.md`, thirty-first session).
#[inline(always)]
fn bound(
    pieces: &[Option<BasisPieces>; 2],
    knots: &[KnotVector; 2],
    evaluated: bool,
    (u, v, u3): (f32, f32, f32),
    weights: &mut [f32],
) -> Bound {
    let (first_u, first_v) = match pieces {
        [Some(a), Some(b)] if evaluated => (a.first_at(u), b.first_at(v)),
        _ => piece_bases_into(pieces, knots, u, v, weights),
    };
    Bound {
        uv: (u, v),
        u3,
        span: (first_u as u32, first_v as u32),
    }
}

/// The rest surface's frame at a bound point.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Zeroable)]
struct RestFrame {
    /// Rest unit normal `N(u₁, u₂)`.
    normal: Vec3,
    /// The rest surface's partial derivatives `S_u`, `S_v` at `(u₁, u₂)`: deform adds the
    /// moved net's derivatives to them.
    du: Vec3,
    dv: Vec3,
}

/// The rest frames of a bind's points: one for all of them where the rest surface is its
/// frame's plane (normal `U × V / |U × V|`, derivatives `U` and `V` everywhere), else one
/// per point. The plane's frame, kept once instead of in every point, takes 36 bytes per
/// bound point (of 56 with evaluated bases) off a bind of the Add menu's surfaces, planar at
/// rest, that the bind writes and deform reads.
#[derive(Debug, Clone)]
enum RestFrames {
    /// Every point's frame.
    Plane(RestFrame),
    /// Per bound point, in the order of `SurfaceBind::points`; empty for a plane without a
    /// normal, where no point projects and no frame is read.
    PerPoint(Vec<RestFrame>),
}

/// Where a [`SurfaceBind`]'s points get their basis values and derivatives at `(u₁, u₂)`:
/// `Nᵤ, N'ᵤ` (`p_u + 1` each) then `Nᵥ, N'ᵥ` (`p_v + 1` each), as [`piece_bases_into`]
/// writes them.
#[derive(Debug, Clone)]
enum BoundBases {
    /// Evaluated again per point by deform, from the power-form pieces of both directions
    /// (degrees up to 3, the Add menu's bicubic surfaces): one vector's Horner steps per
    /// direction, the same call as the bind's and so the same bits. Reading them from memory
    /// instead (64 bytes per bicubic point) cost more than this (2026-11-29).
    Pieces(Arc<[Option<BasisPieces>; 2]>),
    /// Kept per bound point, `2(p_u + 1) + 2(p_v + 1)` values each: degrees above 3 (Horner's
    /// rule per function, not in one vector), or a knot vector too long for a piece table
    /// (the recurrence, with divisions).
    Kept(Vec<f32>),
}

/// Slot of an active vertex that does not project onto the surface (it stays where it is).
const UNPROJECTED: u32 = u32::MAX - 1;

/// Bind of a [`ShapeSurfaceTool`]: `(u₁, u₂, u₃)` per active vertex, in the order of the
/// active list, and per welded vertex its slot (`u32::MAX` where it was not active,
/// `u32::MAX - 1` where it does not project).
#[derive(Debug, Clone)]
pub struct SurfaceBind {
    knots: [KnotVector; 2],
    /// Slot of each welded vertex in `points` (`u32::MAX`: not active; [`UNPROJECTED`]).
    slot: Vec<u32>,
    points: Vec<Bound>,
    /// The rest frame of each bound point.
    frames: RestFrames,
    /// Where deform gets each bound point's basis values and derivatives.
    bases: BoundBases,
    /// The rest net the bind was made on.
    rest: Vec<Vec3>,
}

impl Slotted for SurfaceBind {
    fn slots(&self) -> &[u32] {
        &self.slot
    }
}

/// The basis values and derivatives of one bound point, borrowed from `w` (laid out as
/// [`piece_bases_into`] writes them), with its first non-zero functions `span`.
fn weights_in(w: &[f32], (pu, pv): (usize, usize), span: (u32, u32)) -> Weights<'_> {
    let (nu, w) = w.split_at(pu + 1);
    let (du, w) = w.split_at(pu + 1);
    let (nv, dv) = w.split_at(pv + 1);
    Weights {
        nu,
        du,
        nv,
        dv: &dv[..=pv],
        su: span.0 as usize,
        sv: span.1 as usize,
    }
}

impl SurfaceBind {
    /// The basis values and derivatives of bound point `k`, `b`: read from the bind, or
    /// evaluated into `scratch` (at least `2(p_u + 1) + 2(p_v + 1)` long).
    fn weights_of<'a>(&'a self, k: usize, b: &Bound, scratch: &'a mut [f32]) -> Weights<'a> {
        let degrees = (self.knots[0].degree(), self.knots[1].degree());
        let stride = 2 * (degrees.0 + 1) + 2 * (degrees.1 + 1);
        match &self.bases {
            BoundBases::Pieces(pieces) => {
                let out = &mut scratch[..stride];
                piece_bases_into(pieces, &self.knots, b.uv.0, b.uv.1, out);
                weights_in(out, degrees, b.span)
            }
            BoundBases::Kept(w) => weights_in(&w[k * stride..(k + 1) * stride], degrees, b.span),
        }
    }
}

impl SurfaceBind {
    /// The cached `(u₁, u₂, u₃)` of welded vertex `i`, if it projects onto the surface.
    #[must_use]
    pub fn coordinates(&self, i: u32) -> Option<Vec3> {
        let s = *self.slot.get(i as usize)?;
        let b = self.points.get(s as usize)?;
        Some(Vec3::new(b.uv.0, b.uv.1, b.u3))
    }
}

/// Closest point of the surface `net` to `x`: seeded at the nearest of the `samples`, then
/// Gauss–Newton on `(S − x)·S_u = (S − x)·S_v = 0`, clamped to `[0, 1]²`.
fn closest_point(
    kv: &[KnotVector; 2],
    net: &[Vec3],
    samples: &[(f32, f32, Vec3)],
    x: Vec3,
) -> (f32, f32, [Vec3; 3]) {
    let n_u = kv[0].count();
    let (pu, pv) = (kv[0].degree(), kv[1].degree());
    let (mut u, mut v, _) = samples
        .iter()
        .map(|&(u, v, p)| (u, v, p.distance_squared(x)))
        .fold((0.5, 0.5, f32::INFINITY), |best, s| {
            if s.2 < best.2 { s } else { best }
        });
    let mut s = eval_net(net, n_u, pu, pv, &bases(kv, u, v));
    for _ in 0..32 {
        let r = s[0] - x;
        let (a, b, c) = (s[1].dot(s[1]), s[1].dot(s[2]), s[2].dot(s[2]));
        let (g1, g2) = (r.dot(s[1]), r.dot(s[2]));
        let det = a * c - b * b;
        if det.is_nan() || det.abs() <= 1e-20 {
            break;
        }
        let du = (c * g1 - b * g2) / det;
        let dv = (a * g2 - b * g1) / det;
        let (nu, nv) = ((u - du).clamp(0.0, 1.0), (v - dv).clamp(0.0, 1.0));
        let step = (nu - u).abs() + (nv - v).abs();
        (u, v) = (nu, nv);
        s = eval_net(net, n_u, pu, pv, &bases(kv, u, v));
        if step < 1e-7 {
            break;
        }
    }
    (u, v, s)
}

/// What a shape-surface bind computes from the tool alone ([`ShapeSurfaceTool::bind_setup`]):
/// the knots, the rest net, the seeds of the closest-point search on a curved rest surface,
/// the plane's projection, and the basis pieces. Made once, it serves the binds of many sets
/// of vertices.
#[derive(Debug, Clone)]
pub(crate) struct SurfaceSetup {
    knots: [KnotVector; 2],
    rest: Vec<Vec3>,
    samples: Vec<(f32, f32, Vec3)>,
    plane: Option<PlanarProjection>,
    pieces: Arc<[Option<BasisPieces>; 2]>,
}

impl ShapeSurfaceTool {
    /// [`Deformer::bind`], copying the entry of every vertex that is not stale from
    /// `previous`, a bind of a tool with the same rest state (see [`Reuse`]): a vertex's
    /// `(u₁, u₂, u₃)`, frame and basis values, or that it does not project, depend on its
    /// input alone. The same bits.
    pub fn bind_reusing(
        &self,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, SurfaceBind>>,
    ) -> Result<SurfaceBind> {
        self.bind_set_up(&self.bind_setup()?, input, previous, None)
    }

    /// The part of a bind that depends on the tool alone.
    pub(crate) fn bind_setup(&self) -> Result<SurfaceSetup> {
        let knots = self.knots().ok_or_else(|| CoreError::OutOfRange {
            what: "shape surface: counts / degree".into(),
            value: f64::from(self.counts.0.min(self.counts.1)),
            expected: "each degree must be in [1, 15] and each count greater than its degree",
        })?;
        let (rest, _, _) = self.nets(&knots);
        let n_u = self.counts.0 as usize;
        let (pu, pv) = (knots[0].degree(), knots[1].degree());
        let planar = self.rest.is_empty();
        // Seeds of the search on a curved rest surface: a grid of surface samples, four per
        // knot span.
        let gu = (4 * (knots[0].count() - pu) + 1).min(129);
        let gv = (4 * (knots[1].count() - pv) + 1).min(129);
        let mut samples = Vec::with_capacity(if planar { 0 } else { gu * gv });
        for j in 0..if planar { 0 } else { gv } {
            for i in 0..gu {
                let (u, v) = (i as f32 / (gu - 1) as f32, j as f32 / (gv - 1) as f32);
                samples.push((u, v, eval_net(&rest, n_u, pu, pv, &bases(&knots, u, v))[0]));
            }
        }
        // A rest surface without rest edits is the frame's plane, `S(u, v) = O + u·U + v·V`
        // exactly (B-splines reproduce linear functions from the Greville abscissae): its
        // closest point solves the 2×2 normal equations directly instead of a search, a lane
        // group at a time (`surface_lanes.rs`), and its derivatives there are `U` and `V`.
        let plane = if planar {
            PlanarProjection::new(&self.frame)
        } else {
            None
        };
        // The bases at each bound point, from power-form pieces (no knot search or
        // division): evaluated again by deform for degrees up to 3, else kept per point.
        let pieces = Arc::new([BasisPieces::new(&knots[0]), BasisPieces::new(&knots[1])]);
        Ok(SurfaceSetup {
            knots,
            rest,
            samples,
            plane,
            pieces,
        })
    }

    /// [`ShapeSurfaceTool::bind_reusing`] with `setup`, this tool's
    /// [`ShapeSurfaceTool::bind_setup`], made in the buffers of `spare`, a bind this thread
    /// no longer needs (every value that is read is written again).
    pub(crate) fn bind_set_up(
        &self,
        setup: &SurfaceSetup,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, SurfaceBind>>,
        spare: Option<SurfaceBind>,
    ) -> Result<SurfaceBind> {
        let SurfaceSetup {
            knots,
            rest,
            samples,
            plane,
            pieces,
        } = setup;
        let (knots, plane) = (knots.clone(), *plane);
        let (pu, pv) = (knots[0].degree(), knots[1].degree());
        let size = self.frame.u_edge.length() + self.frame.v_edge.length();
        let evaluated = pu <= 3 && pv <= 3 && pieces.iter().all(Option::is_some);
        // The values kept per bound point (none where deform evaluates them).
        let stride = if evaluated {
            0
        } else {
            2 * (pu + 1) + 2 * (pv + 1)
        };
        // The bound point of `x` found by search (a curved rest surface, or a plane whose
        // edges give no positive determinant) with its rest frame, its basis values written
        // to `weights`; `None` (and `weights` untouched) where it does not project.
        let project = |x: Vec3, weights: &mut [f32]| -> Option<(Bound, RestFrame)> {
            let (u, v, s) = closest_point(&knots, rest, samples, x);
            let n = s[1].cross(s[2]);
            if n.length_squared().is_nan() || n.length_squared() <= 0.0 {
                return None;
            }
            let n = n.normalize();
            let r = x - s[0];
            let u3 = r.dot(n);
            // Projects along the normal: the residual is (nearly) normal to the surface.
            if (r - n * u3).length() > 1e-4 * size {
                return None;
            }
            let frame = RestFrame {
                normal: n,
                du: s[1],
                dv: s[2],
            };
            Some((bound(pieces, &knots, evaluated, (u, v, u3), weights), frame))
        };
        // Every active vertex on its own, in parallel chunks, into its slot; a vertex that
        // does not project keeps an unused slot and is marked unbound after.
        let (slot, points, frames, weights) = spare.map_or_else(Default::default, |b| {
            let frames = match b.frames {
                RestFrames::PerPoint(f) => f,
                RestFrames::Plane(_) => Vec::new(),
            };
            let weights = match b.bases {
                BoundBases::Kept(w) => w,
                BoundBases::Pieces(_) => Vec::new(),
            };
            (b.slot, b.points, frames, weights)
        });
        let (mut slot, active) = bind_slots_in(slot, input.positions.len(), input.active);
        let m = active.len();
        // The plane's one frame (a plane without a normal has none, and no point projects),
        // or a frame per point on a curved rest surface.
        let shared = plane.as_ref().and_then(|p| {
            p.normal.map(|normal| RestFrame {
                normal,
                du: p.u_edge,
                dv: p.v_edge,
            })
        });
        let per_point = plane.is_none();
        // The values of a point that does not project are not read (its slot says so).
        let mut points: Vec<Bound> = recycled(points, m);
        let mut frames: Vec<RestFrame> = if per_point {
            recycled(frames, m)
        } else {
            Vec::new()
        };
        let mut weights: Vec<f32> = recycled(weights, m * stride);
        let mut projects = zeroed(m);
        // The same knots and the same kind of frames (the plane's, the same one), as a bind
        // of the same rest state has.
        let previous = previous.filter(|p| {
            p.bind.knots == knots
                && match &p.bind.frames {
                    RestFrames::Plane(f) => shared == Some(*f),
                    RestFrames::PerPoint(_) => per_point,
                }
        });
        // Per chunk, its part of `frames` (none on a plane, where `frames` is empty).
        let frame_parts: Vec<Option<&mut [RestFrame]>> = if per_point {
            frames.chunks_mut(BIND_CHUNK).map(Some).collect()
        } else {
            (0..m.div_ceil(BIND_CHUNK)).map(|_| None).collect()
        };
        // Per chunk, its part of `weights` (empty where deform evaluates them).
        let weight_parts: Vec<&mut [f32]> = if evaluated {
            (0..m.div_ceil(BIND_CHUNK)).map(|_| &mut [][..]).collect()
        } else {
            weights.chunks_mut(BIND_CHUNK * stride).collect()
        };
        points
            .par_chunks_mut(BIND_CHUNK)
            .zip(weight_parts)
            .zip(projects.par_chunks_mut(BIND_CHUNK))
            .zip(frame_parts)
            .zip(active.par_chunks(BIND_CHUNK))
            .for_each(|((((points, weights), projects), mut frames), ids)| {
                let (fresh, xs) =
                    Reuse::split_chunk(previous, ids, input.positions, |j, old, s| {
                        if s != UNPROJECTED as usize {
                            points[j] = old.points[s];
                            projects[j] = true;
                            if let BoundBases::Kept(old) = &old.bases {
                                weights[j * stride..(j + 1) * stride]
                                    .copy_from_slice(&old[s * stride..(s + 1) * stride]);
                            }
                            if let (Some(f), RestFrames::PerPoint(old)) =
                                (frames.as_deref_mut(), &old.frames)
                            {
                                f[j] = old[s];
                            }
                        }
                    });
                if let Some(plane) = &plane {
                    // Without a normal no point of the plane projects.
                    if plane.normal.is_none() {
                        return;
                    }
                    let mut found = vec![None; xs.len()];
                    plane.project_each(&xs, &mut found);
                    for (k, p) in found.into_iter().enumerate() {
                        if let Some(p) = p {
                            let j = fresh.slot(k);
                            let w = &mut weights[j * stride..(j + 1) * stride];
                            points[j] = bound(pieces, &knots, evaluated, p, w);
                            projects[j] = true;
                        }
                    }
                    return;
                }
                for (k, x) in xs.into_iter().enumerate() {
                    let j = fresh.slot(k);
                    if let Some((b, f)) = project(x, &mut weights[j * stride..(j + 1) * stride]) {
                        points[j] = b;
                        projects[j] = true;
                        if let Some(frames) = frames.as_deref_mut() {
                            frames[j] = f;
                        }
                    }
                }
            });
        for (&i, _) in active.iter().zip(&projects).filter(|(_, p)| !**p) {
            slot[i as usize] = UNPROJECTED;
        }
        // A plane without a normal keeps no frame (`frames` is empty): no point projects,
        // and none is read.
        let frames = match shared {
            Some(f) => RestFrames::Plane(f),
            None => RestFrames::PerPoint(frames),
        };
        let bases = if evaluated {
            BoundBases::Pieces(Arc::clone(pieces))
        } else {
            BoundBases::Kept(weights)
        };
        Ok(SurfaceBind {
            knots,
            slot,
            points,
            frames,
            bases,
            rest: rest.clone(),
        })
    }
}

impl Deformer for ShapeSurfaceTool {
    type Bind = SurfaceBind;

    fn validate(&self, what: &str) -> Result<()> {
        check_finite_vec3(|| format!("{what}: origin"), self.frame.origin)?;
        check_finite_vec3(|| format!("{what}: u_edge"), self.frame.u_edge)?;
        check_finite_vec3(|| format!("{what}: v_edge"), self.frame.v_edge)?;
        let n = self.frame.u_edge.cross(self.frame.v_edge);
        let scale = self.frame.u_edge.length() * self.frame.v_edge.length();
        if n.length().is_nan() || n.length() <= 1e-6 * scale {
            return Err(CoreError::Degenerate {
                what: what.to_string(),
                problem: "the surface frame is degenerate: u_edge and v_edge must be non-zero \
                          and not parallel"
                    .into(),
            });
        }
        if self.knots().is_none() {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: counts / degree"),
                value: f64::from(self.counts.0.min(self.counts.1)),
                expected: "each degree must be in [1, 15] and each count greater than its degree",
            });
        }
        let total = self.counts.0 as usize * self.counts.1 as usize;
        if total > 1 << 16 {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: number of control points"),
                value: total as f64,
                expected: "must be at most 65536",
            });
        }
        let in_range = |at: (u32, u32)| at.0 < self.counts.0 && at.1 < self.counts.1;
        for (list, name) in [(&self.rest, "rest"), (&self.moves, "moves")] {
            let mut seen = std::collections::HashSet::new();
            for (k, e) in list.iter().enumerate() {
                let w = format!("{what}: {name} {k} at {:?}", e.at);
                if !in_range(e.at) || !seen.insert(e.at) {
                    return Err(CoreError::Degenerate {
                        what: w,
                        problem: "the index is outside the grid or edited twice".into(),
                    });
                }
                check_finite_vec3(|| format!("{w}: offset"), e.offset)?;
            }
        }
        let mut seen = std::collections::HashSet::new();
        for (k, e) in self.heights.iter().enumerate() {
            let w = format!("{what}: heights {k} at {:?}", e.at);
            if !in_range(e.at) || !seen.insert(e.at) {
                return Err(CoreError::Degenerate {
                    what: w,
                    problem: "the index is outside the grid or edited twice".into(),
                });
            }
            check_finite(|| format!("{w}: height"), e.height)?;
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<SurfaceBind> {
        self.bind_reusing(input, None)
    }

    fn deform(&self, bind: &SurfaceBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        let (_, moved, heights) = self.nets(&bind.knots);
        let n_u = bind.knots[0].count();
        let (pu, pv) = (bind.knots[0].degree(), bind.knots[1].degree());
        let delta: Vec<Vec3> = moved.iter().zip(&bind.rest).map(|(m, r)| *m - *r).collect();
        // A drag moves a few control points: sum only those when they are fewer than half
        // of the (p_u + 1)(p_v + 1) a point depends on.
        let moved_entries: Vec<(usize, usize, Vec3)> = delta
            .iter()
            .enumerate()
            .filter(|(_, d)| **d != Vec3::ZERO)
            .map(|(k, d)| (k % n_u, k / n_u, *d))
            .collect();
        let sums = if 2 * moved_entries.len() < (pu + 1) * (pv + 1) {
            Sums::Sparse(&moved_entries)
        } else {
            Sums::Dense(&delta, n_u)
        };
        let heights = (!self.heights.is_empty()).then_some((&heights[..], n_u));
        // Bicubic bases from power-form pieces (the Add menu's surfaces): the four vectors
        // of `piece_bases_into` kept in registers, so that every sum below has a length
        // known to the compiler (same operations, same bits).
        let bicubic = if (pu, pv) == (3, 3)
            && let BoundBases::Pieces(pieces) = &bind.bases
            && let [Some(a), Some(b)] = &**pieces
        {
            Some((a, b))
        } else {
            None
        };
        let mut scratch = [0.0; 4 * (MAX_DEGREE + 1)];
        for (o, &i) in out.iter_mut().zip(active) {
            let x = positions[i as usize];
            let Some((k, b)) = bind
                .slot
                .get(i as usize)
                .and_then(|&s| bind.points.get(s as usize).map(|b| (s as usize, b)))
            else {
                *o = x;
                continue;
            };
            let frame = match &bind.frames {
                RestFrames::Plane(f) => f,
                RestFrames::PerPoint(f) => &f[k],
            };
            let four = bicubic.and_then(|(a, c)| {
                Some((
                    a.values_and_derivatives4(b.uv.0)?,
                    c.values_and_derivatives4(b.uv.1)?,
                ))
            });
            *o = match four {
                Some(((_, nu, du), (_, nv, dv))) => {
                    let [nu, du, nv, dv] = [nu, du, nv, dv].map(|v| v.to_array());
                    let bs = Weights {
                        nu: &nu,
                        du: &du,
                        nv: &nv,
                        dv: &dv,
                        su: b.span.0 as usize,
                        sv: b.span.1 as usize,
                    };
                    deformed_point(x, b, frame, bs, sums, heights)
                }
                None => deformed_point(
                    x,
                    b,
                    frame,
                    bind.weights_of(k, b, &mut scratch),
                    sums,
                    heights,
                ),
            };
        }
    }

    /// The frame and all offsets map affinely (points as points, offsets by the linear
    /// part); heights are relative and do not change. Exact for similarity transforms; under
    /// a non-uniform scale `u₃` is measured in the mapped space, as a distance must be.
    fn transformed(&self, m: &Affine3A) -> Self {
        let map = |e: &SurfaceEdit| SurfaceEdit {
            at: e.at,
            offset: m.transform_vector3(e.offset),
        };
        Self {
            frame: SurfaceFrame {
                origin: m.transform_point3(self.frame.origin),
                u_edge: m.transform_vector3(self.frame.u_edge),
                v_edge: m.transform_vector3(self.frame.v_edge),
            },
            rest: self.rest.iter().map(map).collect(),
            moves: self.moves.iter().map(map).collect(),
            ..self.clone()
        }
    }

    /// The bind depends on the rest surface only: moves and heights reuse it.
    fn same_rest_state(&self, other: &Self) -> bool {
        self.frame == other.frame
            && self.counts == other.counts
            && self.degree == other.degree
            && self.rest == other.rest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;
    use glam::Quat;

    fn frame() -> SurfaceFrame {
        SurfaceFrame {
            origin: Vec3::new(-1.0, -1.0, 0.0),
            u_edge: Vec3::new(2.0, 0.0, 0.0),
            v_edge: Vec3::new(0.0, 2.0, 0.0),
        }
    }

    #[test]
    fn nets_and_surface_points() {
        let mut t = ShapeSurfaceTool::planar(frame(), (4, 5));
        t.moves.push(SurfaceEdit {
            at: (3, 4),
            offset: Vec3::new(0.0, 0.0, 0.5),
        });
        let (rest, moved) = t.control_nets().unwrap();
        assert_eq!((rest.len(), moved.len()), (20, 20));
        // Clamped ends: the corners of the surface are the corner control points.
        let p = t.surface_points(&moved, &[(0.0, 0.0), (1.0, 1.0)]).unwrap();
        assert_eq!(p[0], Vec3::new(-1.0, -1.0, 0.0));
        assert!(
            (p[1] - Vec3::new(1.0, 1.0, 0.5)).length() < 1e-6,
            "{}",
            p[1]
        );
        // Linear precision of the planar rest net: S(u, v) = O + u·U + v·V.
        let q = t.surface_points(&rest, &[(0.3, 0.6)]).unwrap()[0];
        assert!((q - Vec3::new(-0.4, 0.2, 0.0)).length() < 1e-6, "{q}");
        assert!(t.surface_points(&rest[1..], &[(0.5, 0.5)]).is_none());
        t.degree = (4, 3);
        assert!(t.control_nets().is_none());
    }

    fn slab() -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..21 {
            for j in 0..5 {
                for k in 0..3 {
                    v.push(Vec3::new(
                        i as f32 * 0.09 - 0.9,
                        j as f32 * 0.2 - 0.4,
                        0.05 + k as f32 * 0.05,
                    ));
                }
            }
        }
        v
    }

    /// `tool` bound on every point of `pts` (no topology), reusing `previous` where given.
    fn bind_all(
        tool: &ShapeSurfaceTool,
        pts: &[Vec3],
        previous: Option<Reuse<'_, SurfaceBind>>,
    ) -> SurfaceBind {
        let topology = Topology {
            weld: Vec::new(),
            representative: Vec::new(),
            triangles: Vec::new(),
        };
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let input = BindInput {
            positions: pts,
            topology: &topology,
            active: &active,
        };
        tool.bind_reusing(&input, previous).unwrap()
    }

    /// Every point of `pts` deformed by `tool` through `bind`.
    fn deform_all(tool: &ShapeSurfaceTool, bind: &SurfaceBind, pts: &[Vec3]) -> Vec<Vec3> {
        let active: Vec<u32> = (0..pts.len() as u32).collect();
        let mut out = vec![Vec3::ZERO; pts.len()];
        tool.deform(bind, pts, &active, &mut out);
        out
    }

    /// The bits of every coordinate, for comparisons where `-0 != 0` and NaN equals itself.
    fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    }

    fn apply(tool: &ShapeSurfaceTool, pts: &[Vec3]) -> (Vec<Vec3>, SurfaceBind) {
        tool.validate("t").unwrap();
        let bind = bind_all(tool, pts, None);
        (deform_all(tool, &bind, pts), bind)
    }

    #[test]
    fn planar_unmoved_surface_is_identity_and_coordinates_are_right() {
        let tool = ShapeSurfaceTool::planar(frame(), (6, 5));
        let pts = slab();
        let (out, bind) = apply(&tool, &pts);
        assert!(out == pts, "the planar unmoved surface is the identity");
        // (u₁, u₂, u₃) of (x, y, z) on the plane [−1, 1]² at z = 0: ((x+1)/2, (y+1)/2, z).
        for (k, p) in pts.iter().enumerate() {
            let c = bind.coordinates(k as u32).unwrap();
            let e = Vec3::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0, p.z);
            assert!((c - e).length() < 1e-5, "{p}: {c} vs {e}");
        }
    }

    #[test]
    fn translating_the_surface_translates_and_heights_scale_thickness() {
        let mut tool = ShapeSurfaceTool::planar(frame(), (4, 4));
        for i in 0..4 {
            for j in 0..4 {
                tool.moves.push(SurfaceEdit {
                    at: (i, j),
                    offset: Vec3::new(0.1, 0.0, 0.3),
                });
                tool.heights.push(HeightEdit {
                    at: (i, j),
                    height: 2.0,
                });
            }
        }
        let pts = slab();
        let (out, _) = apply(&tool, &pts);
        for (p, q) in pts.iter().zip(&out) {
            // D = S' + 2·u₃·N: x, y shift by (0.1, 0), z = 0.3 + 2 z.
            let e = Vec3::new(p.x + 0.1, p.y, 0.3 + 2.0 * p.z);
            assert!((*q - e).length() < 1e-5, "{p}: {q} vs {e}");
        }
    }

    /// `bind` with every point's basis values kept, as a bind of a higher degree keeps them.
    fn with_kept_bases(bind: &SurfaceBind) -> SurfaceBind {
        let BoundBases::Pieces(pieces) = &bind.bases else {
            panic!("a bind of degrees up to 3 evaluates its bases");
        };
        let (pu, pv) = (bind.knots[0].degree(), bind.knots[1].degree());
        let stride = 2 * (pu + 1) + 2 * (pv + 1);
        let mut kept = vec![0.0; bind.points.len() * stride];
        for (b, w) in bind.points.iter().zip(kept.chunks_exact_mut(stride)) {
            let (su, sv) = piece_bases_into(pieces, &bind.knots, b.uv.0, b.uv.1, w);
            assert_eq!((su as u32, sv as u32), b.span);
        }
        SurfaceBind {
            bases: BoundBases::Kept(kept),
            ..bind.clone()
        }
    }

    #[test]
    fn evaluated_bases_deform_as_kept_ones() {
        // Degrees up to 3 evaluate each point's bases in deform instead of keeping them: the
        // same bits as the kept values, for every degree pair and for planar and curved rest
        // surfaces, dense and sparse moves, with and without heights; and a rebind that
        // copies every entry of an earlier bind that kept them evaluates them again.
        let pts = slab();
        for degree in [(1, 1), (2, 3), (3, 1), (3, 3)] {
            for (curved, dense) in [(false, false), (false, true), (true, false), (true, true)] {
                let mut tool = ShapeSurfaceTool {
                    degree,
                    ..ShapeSurfaceTool::planar(frame(), (6, 5))
                };
                if curved {
                    tool.rest.push(SurfaceEdit {
                        at: (2, 2),
                        offset: Vec3::new(0.0, 0.0, 0.15),
                    });
                }
                let moved: &[(u32, u32)] = if dense {
                    &[
                        (0, 0),
                        (1, 1),
                        (2, 1),
                        (3, 2),
                        (4, 3),
                        (5, 4),
                        (2, 3),
                        (1, 4),
                    ]
                } else {
                    &[(3, 2)]
                };
                for (k, &at) in moved.iter().enumerate() {
                    tool.moves.push(SurfaceEdit {
                        at,
                        offset: Vec3::new(0.05 * k as f32, -0.1, 0.3),
                    });
                }
                if dense {
                    tool.heights.push(HeightEdit {
                        at: (2, 2),
                        height: 1.7,
                    });
                }
                let (out, bind) = apply(&tool, &pts);
                let kept = with_kept_bases(&bind);
                let out_kept = deform_all(&tool, &kept, &pts);
                assert_eq!(
                    bits(&out),
                    bits(&out_kept),
                    "{degree:?} curved {curved} dense {dense}"
                );
                assert!(out != pts, "the moves move the slab");
                let stale = vec![false; pts.len()];
                let previous = Reuse {
                    bind: &kept,
                    stale: &stale,
                };
                let reused = bind_all(&tool, &pts, Some(previous));
                assert!(matches!(reused.bases, BoundBases::Pieces(_)));
                assert_eq!(
                    bits(&out),
                    bits(&deform_all(&tool, &reused, &pts)),
                    "{degree:?} curved {curved} dense {dense}"
                );
            }
        }
    }

    #[test]
    fn higher_degrees_keep_their_bases_and_reuse_them() {
        // Degrees (4, 2): the bind keeps every point's basis values. Moving every control
        // point by one offset translates the slab by it (the values sum to 1 and the
        // derivatives to 0, so the normal stays), and a rebind that copies the entries of the
        // vertices that did not move from the earlier bind deforms with the fresh bind's bits.
        let mut tool = ShapeSurfaceTool {
            degree: (4, 2),
            ..ShapeSurfaceTool::planar(frame(), (6, 5))
        };
        tool.rest.push(SurfaceEdit {
            at: (2, 2),
            offset: Vec3::new(0.0, 0.0, 0.1),
        });
        for i in 0..6 {
            for j in 0..5 {
                tool.moves.push(SurfaceEdit {
                    at: (i, j),
                    offset: Vec3::new(0.1, -0.05, 0.2),
                });
            }
        }
        let mut pts = slab();
        let (out, bind) = apply(&tool, &pts);
        assert!(matches!(bind.bases, BoundBases::Kept(_)));
        let mut bound = 0;
        for (p, q) in pts.iter().zip(&out) {
            if q != p {
                bound += 1;
                let e = *p + Vec3::new(0.1, -0.05, 0.2);
                assert!((*q - e).length() < 1e-5, "{p}: {q} vs {e}");
            }
        }
        assert!(
            bound > pts.len() / 2,
            "{bound} of {} points move",
            pts.len()
        );
        // Move every third point a little and bind again, reusing the rest.
        let mut stale = vec![false; pts.len()];
        for (k, p) in pts.iter_mut().enumerate().step_by(3) {
            p.z += 0.01;
            stale[k] = true;
        }
        let previous = Reuse {
            bind: &bind,
            stale: &stale,
        };
        let fresh = bind_all(&tool, &pts, None);
        let reused = bind_all(&tool, &pts, Some(previous));
        assert_eq!(
            bits(&deform_all(&tool, &fresh, &pts)),
            bits(&deform_all(&tool, &reused, &pts))
        );
    }

    #[test]
    fn sparse_sums_are_the_dense_sums_bit_for_bit() {
        // Two moved control points of a 6×5 net, degrees (3, 2): at every parameter the
        // sparse sum over the moved points equals the full sum over the net, bit for bit.
        let tool = ShapeSurfaceTool {
            degree: (3, 2),
            ..ShapeSurfaceTool::planar(frame(), (6, 5))
        };
        let knots = tool.knots().unwrap();
        let mut net = vec![Vec3::ZERO; 30];
        net[8] = Vec3::new(0.1, -0.3, 0.7); // (2, 1)
        net[29] = Vec3::new(-0.2, 0.05, 1.1); // (5, 4)
        let entries = [(2, 1, net[8]), (5, 4, net[29])];
        for a in 0..=20 {
            for c in 0..=20 {
                let b = bases(&knots, a as f32 / 20.0, c as f32 / 20.0);
                let dense = eval_weights(&net, 6, b.weights(3, 2));
                let sparse = eval_sparse(&entries, b.weights(3, 2));
                for k in 0..3 {
                    assert_eq!(
                        dense[k].to_array().map(f32::to_bits),
                        sparse[k].to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }

    #[test]
    fn bending_the_surface_bends_a_slab_along_its_normal() {
        // Lift the middle rows: the slab bends; each point stays at distance u₃ from S'
        // along N', so the thickness of the slab is kept (the survey's D with H = 1).
        let mut tool = ShapeSurfaceTool::planar(frame(), (5, 3));
        tool.degree = (3, 2);
        for j in 0..3 {
            tool.moves.push(SurfaceEdit {
                at: (2, j),
                offset: Vec3::new(0.0, 0.0, 0.5),
            });
        }
        let pts = slab();
        let (out, bind) = apply(&tool, &pts);
        let centre = out
            .iter()
            .zip(&pts)
            .filter(|(_, p)| p.x.abs() < 1e-3)
            .map(|(q, p)| q.z - p.z)
            .fold(f32::INFINITY, f32::min);
        assert!(centre > 0.2, "the middle rises: {centre}");
        let knots = tool.knots().unwrap();
        let (_, moved, _) = tool.nets(&knots);
        for (k, q) in out.iter().enumerate() {
            let c = bind.coordinates(k as u32).unwrap();
            let s = eval_net(&moved, 5, 3, 2, &bases(&knots, c.x, c.y));
            let n = s[1].cross(s[2]).normalize();
            assert!((*q - (s[0] + n * c.z)).length() < 1e-4, "point {k}");
        }
    }

    #[test]
    fn newton_projects_onto_a_curved_rest_surface() {
        // A bumped rest surface: the projection must satisfy (x − S)·S_u = (x − S)·S_v = 0.
        let mut tool = ShapeSurfaceTool::planar(frame(), (5, 5));
        tool.rest.push(SurfaceEdit {
            at: (2, 2),
            offset: Vec3::new(0.0, 0.0, 0.6),
        });
        let pts = slab();
        let (out, bind) = apply(&tool, &pts);
        assert!(out == pts, "unmoved: identity");
        let knots = tool.knots().unwrap();
        let (rest, _, _) = tool.nets(&knots);
        let mut checked = 0;
        for (k, p) in pts.iter().enumerate() {
            let Some(c) = bind.coordinates(k as u32) else {
                continue;
            };
            let s = eval_net(&rest, 5, 3, 3, &bases(&knots, c.x, c.y));
            let r = *p - s[0];
            assert!(r.dot(s[1].normalize()).abs() < 1e-4);
            assert!(r.dot(s[2].normalize()).abs() < 1e-4);
            checked += 1;
        }
        assert!(checked > pts.len() / 2);
    }

    #[test]
    fn points_not_projecting_stay_and_bad_parameters_are_errors() {
        let mut tool = ShapeSurfaceTool::planar(frame(), (4, 4));
        tool.moves.push(SurfaceEdit {
            at: (3, 3),
            offset: Vec3::new(0.0, 0.0, 1.0),
        });
        let far = Vec3::new(3.0, 0.0, 0.1);
        let (out, _) = apply(&tool, &[far]);
        assert_eq!(out[0], far);
        let flat = SurfaceFrame {
            v_edge: Vec3::new(4.0, 0.0, 0.0),
            ..frame()
        };
        assert!(
            ShapeSurfaceTool::planar(flat, (4, 4))
                .validate("t")
                .is_err()
        );
        assert!(
            ShapeSurfaceTool::planar(frame(), (3, 4))
                .validate("t")
                .is_err()
        );
        let mut t = ShapeSurfaceTool::planar(frame(), (4, 4));
        t.heights.push(HeightEdit {
            at: (0, 0),
            height: f32::NAN,
        });
        assert!(matches!(t.validate("t"), Err(CoreError::NotFinite { .. })));
        let mut t = ShapeSurfaceTool::planar(frame(), (4, 4));
        t.moves.push(SurfaceEdit {
            at: (4, 0),
            offset: Vec3::X,
        });
        assert!(t.validate("t").is_err());
    }

    #[test]
    fn transformed_commutes() {
        let mut tool = ShapeSurfaceTool::planar(frame(), (5, 4));
        tool.moves.push(SurfaceEdit {
            at: (2, 1),
            offset: Vec3::new(0.1, 0.2, 0.4),
        });
        tool.heights.push(HeightEdit {
            at: (1, 2),
            height: 1.5,
        });
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.7),
            Quat::from_axis_angle(Vec3::new(0.2, 1.0, 0.5).normalize(), 0.9),
            Vec3::new(0.3, -2.0, 1.0),
        );
        let pts = slab();
        let a: Vec<Vec3> = apply(&tool, &pts)
            .0
            .iter()
            .map(|p| m.transform_point3(*p))
            .collect();
        let mp: Vec<Vec3> = pts.iter().map(|p| m.transform_point3(*p)).collect();
        let b = apply(&tool.transformed(&m), &mp).0;
        for (x, y) in a.iter().zip(&b) {
            assert!((*x - *y).length() < 1e-4, "{x} vs {y}");
        }
    }
}
