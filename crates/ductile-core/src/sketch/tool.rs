//! The sketch deformation tool (Kho & Garland 2005, §4.3–§5.5): plain serialisable state
//! (reference curve, bend target or twist, spline controls, partition, smoothing and
//! refinement options) and its bind / evaluation.
//!
//! * **bind** (depends on the layer input and the reference curve only): resolve the
//!   reference curve (project a recorded stroke), the sketch plane, the region of interest
//!   and the rigid components within the layer's active set, the skinning `s(v)` of every
//!   vertex of the region and of every rigid component's virtual vertex, and the sparse
//!   Cholesky factorisation of the smoothing system (Eq. 9).
//! * **evaluate** (every time the target, twist or a spline changes): the parameters
//!   `(s, θ)` per vertex (Eq. 5 / Eq. 7, with Eq. 8 and the speed control), their
//!   smoothing (two solves with the stored factor), the map of Eq. (6) / Eq. (7), the rigid
//!   components following their virtual vertex, and optionally the adaptive refinement
//!   (§5.5).
//!
//! Static vertices (neither region of interest nor rigid) keep their input bit for bit.

use glam::{Affine3A, Vec2, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_finite, check_finite_vec3};
use crate::refinement::{LayerRefinement, SplitMesh, WholeDeform};
use crate::sketch::bend::{Bend, TurningCurve, bend_point, rebuild};
use crate::sketch::camera::Camera;
use crate::sketch::partition::Partition;
use crate::sketch::raycast::Bvh;
use crate::sketch::refine::{RefineOptions, Vertices, refine};
use crate::sketch::roi::partition_from_curve;
use crate::sketch::skin::{Polyline, skin, virtual_vertex};
use crate::sketch::smooth::Smoother;
use crate::sketch::stroke::{filter_stroke, joint_curve, project_stroke, project_target_stroke};
use crate::sketch::twist::{Axis, twist_point};
pub use crate::spline::SplineControl;
use crate::tool::{BindInput, Deformer};

/// A stroke recorded in the image plane: pixel positions (origin top-left, y down) and the
/// camera it was drawn with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stroke {
    /// Stroke nodes in pixels, in drawing order.
    pub pixels: Vec<Vec2>,
    /// The camera (in the tool's space) the stroke was drawn with.
    pub camera: Camera,
}

/// A curve of the sketch tool, either given in 3-D or recorded as a stroke.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Curve {
    /// A polyline in the mesh's space.
    Points(Vec<Vec3>),
    /// A recorded stroke, projected (at bind time for the reference) onto the sketch plane:
    /// the view-parallel plane through the first hit of the reference stroke (§4.1).
    Stroke(Stroke),
    /// A recorded stroke turned into a joint curve inside the mesh: every node becomes the
    /// midpoint of the first front and back hits of its ray (§5.2). Reference only.
    Joints(Stroke),
}

impl Curve {
    fn validate(&self, what: &str) -> Result<()> {
        let (pixels, camera) = match self {
            Curve::Points(points) => {
                for (i, &p) in points.iter().enumerate() {
                    check_finite_vec3(|| format!("{what}: point {i}"), p)?;
                }
                return check_count(what, points.len());
            }
            Curve::Stroke(s) | Curve::Joints(s) => (&s.pixels, &s.camera),
        };
        for (i, p) in pixels.iter().enumerate() {
            check_finite(|| format!("{what}: pixel {i}"), p.x)?;
            check_finite(|| format!("{what}: pixel {i}"), p.y)?;
        }
        check_count(what, pixels.len())?;
        for (name, v) in [
            ("eye", camera.eye),
            ("target", camera.target),
            ("up", camera.up),
        ] {
            check_finite_vec3(|| format!("{what}: camera {name}"), v)?;
        }
        if camera.forward() == Vec3::ZERO || !(camera.viewport.x > 0.0 && camera.viewport.y > 0.0) {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: "the stroke's camera has no view direction or an empty viewport".into(),
            });
        }
        Ok(())
    }

    fn camera(&self) -> Option<&Camera> {
        match self {
            Curve::Points(_) => None,
            Curve::Stroke(s) | Curve::Joints(s) => Some(&s.camera),
        }
    }

    fn transformed(&self, m: &Affine3A) -> Self {
        let stroke = |s: &Stroke| Stroke {
            pixels: s.pixels.clone(),
            camera: transform_camera(&s.camera, m),
        };
        match self {
            Curve::Points(p) => Curve::Points(p.iter().map(|&q| m.transform_point3(q)).collect()),
            Curve::Stroke(s) => Curve::Stroke(stroke(s)),
            Curve::Joints(s) => Curve::Joints(stroke(s)),
        }
    }
}

fn check_count(what: &str, n: usize) -> Result<()> {
    if n < 2 {
        return Err(CoreError::Degenerate {
            what: what.to_owned(),
            problem: format!("a curve needs at least 2 points, found {n}"),
        });
    }
    Ok(())
}

fn transform_camera(c: &Camera, m: &Affine3A) -> Camera {
    Camera {
        eye: m.transform_point3(c.eye),
        target: m.transform_point3(c.target),
        up: m.transform_vector3(c.up),
        ..*c
    }
}

/// What the tool does with the reference curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SketchMode {
    /// Bend the region so that the reference curve follows the target curve (§5.1).
    Bend {
        /// The target curve (translated to start at the reference's start; strokes are
        /// projected onto the sketch plane).
        target: Curve,
        /// Turning-angle control `F(s)` of Eq. (8), `φ'ᵢ = φᵢ + F(sᵢ) − sᵢ` (radians);
        /// `None` is `F(s) = s`.
        #[serde(default)]
        turning: Option<SplineControl>,
    },
    /// Twist the region about the reference curve (the joint curve) (§5.2).
    Twist {
        /// `θ_max` (radians, right-handed about the curve's direction).
        angle: f32,
        /// Twist-speed control: `θ(v) = F(s(v)) θ_max`; `None` is `F(s) = s`.
        #[serde(default)]
        speed: Option<SplineControl>,
    },
}

/// The sketch deformation tool (Kho & Garland 2005).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SketchTool {
    /// Region of interest and rigid components (welded indices of the mesh the layer
    /// binds on); `None` computes them at bind time from the cutting planes at the ends of
    /// the reference curve (§4.2, `sketch::roi`).
    #[serde(default)]
    pub partition: Option<Partition>,
    /// The reference curve (a skeleton of the region).
    pub reference: Curve,
    /// Unit normal of the sketch plane, the bending axis; `None` takes the direction towards
    /// the eye of the reference stroke's camera. Required for a bend of a `Points` reference.
    #[serde(default)]
    pub normal: Option<Vec3>,
    /// Bend or twist.
    pub mode: SketchMode,
    /// Scale control of the offsets `v − v_r` (§5.3); `None` is `F(s) = 1`.
    #[serde(default)]
    pub scale: Option<SplineControl>,
    /// Smooth the deformation parameters (§5.4, Eq. 9).
    #[serde(default = "yes")]
    pub smooth: bool,
    /// Adaptive refinement (§5.5); `None` keeps the topology.
    #[serde(default)]
    pub refine: Option<RefineOptions>,
}

fn yes() -> bool {
    true
}

/// The role of a welded vertex in the bind.
const STATIC: u32 = u32::MAX;
const ROI: u32 = u32::MAX - 1;

/// One rigid component, bound.
#[derive(Debug, Clone)]
struct RigidPart {
    /// Its vertices within the active set, and their slots in the active list.
    vertices: Vec<u32>,
    slots: Vec<u32>,
    /// `s` of its virtual vertex.
    s: f32,
}

/// The bind of a [`SketchTool`].
#[derive(Debug)]
pub struct SketchBind {
    /// The 3-D reference curve.
    reference: Polyline,
    /// Reference curve with turning angles (bend only).
    turning: Option<TurningCurve>,
    /// Joint axis with tangents (twist only).
    axis: Option<Axis>,
    /// Sketch-plane normal (bend only).
    normal: Vec3,
    /// Region-of-interest vertices within the active set, their slots and `s(v)`.
    roi: Vec<u32>,
    roi_slots: Vec<u32>,
    roi_s: Vec<f32>,
    rigid: Vec<RigidPart>,
    /// Role of every welded vertex: `STATIC`, `ROI`, or the rigid component index.
    role: Vec<u32>,
    smoother: Option<Smoother>,
    /// Welded triangles, kept when refinement is on.
    triangles: Option<Vec<[u32; 3]>>,
    /// The active set the bind was made for (ascending).
    active: Vec<u32>,
}

impl SketchBind {
    /// The reference curve the bind uses (3-D, mesh space).
    #[must_use]
    pub fn reference(&self) -> &Polyline {
        &self.reference
    }

    /// The skinning `s(v)` of the region of interest: `(vertex, s)` pairs.
    pub fn skinning(&self) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.roi.iter().copied().zip(self.roi_s.iter().copied())
    }
}

/// Vertices per parallel task of the per-vertex parts of an evaluation.
const PAR_CHUNK: usize = 4096;

/// The per-evaluation deformation: the bend or twist with its controls.
enum Map<'a> {
    Bend {
        bend: Box<Bend>,
        scale: Option<&'a SplineControl>,
    },
    Twist {
        axis: &'a Axis,
        angle: f32,
        speed: Option<&'a SplineControl>,
        scale: Option<&'a SplineControl>,
    },
}

impl Map<'_> {
    /// The user's rotational angle `θ(s)` (Eq. 5 or Eq. 7).
    fn theta(&self, s: f32) -> f32 {
        match self {
            Map::Bend { bend, .. } => bend.theta(s),
            Map::Twist { angle, speed, .. } => speed.map_or(s, |f| f.eval(s)) * angle,
        }
    }

    /// The map of a point with parameters `(s, θ)`; `k` scales the offset.
    fn apply(&self, v: Vec3, s: f32, theta: f32, scaled: bool) -> Vec3 {
        match self {
            Map::Bend { bend, scale } => {
                let k = if scaled {
                    scale.map_or(1.0, |f| f.eval(s))
                } else {
                    1.0
                };
                bend_point(
                    v,
                    bend.reference.curve.point_at(s),
                    bend.target.curve.point_at(s),
                    bend.normal,
                    theta,
                    k,
                )
            }
            Map::Twist { axis, scale, .. } => {
                let k = if scaled {
                    scale.map_or(1.0, |f| f.eval(s))
                } else {
                    1.0
                };
                twist_point(v, axis.curve.point_at(s), axis.tangent_at(s), theta, k)
            }
        }
    }
}

impl SketchTool {
    fn bend_normal(&self, what: &str) -> Result<Vec3> {
        let n = match (self.normal, self.reference.camera()) {
            (Some(n), _) => n,
            (None, Some(c)) => -c.forward(),
            (None, None) => {
                return Err(CoreError::Degenerate {
                    what: what.to_owned(),
                    problem: "a bend of a 3-D reference curve needs the sketch-plane normal".into(),
                });
            }
        };
        n.try_normalize().ok_or_else(|| CoreError::Degenerate {
            what: what.to_owned(),
            problem: "the sketch-plane normal is zero".into(),
        })
    }

    /// Evaluates the tool on its bind: deformed positions of every vertex of the bound
    /// active set (in its order) and, when `refine_mesh` is true and the tool has
    /// refinement options, the refinement. `positions` is the layer input the bind saw.
    pub fn evaluate(
        &self,
        bind: &SketchBind,
        positions: &[Vec3],
        refine_mesh: bool,
    ) -> Result<WholeDeform> {
        let what = "sketch tool";
        let active = &bind.active;
        let map = match &self.mode {
            SketchMode::Bend { target, turning } => {
                let reference = bind.turning.clone().ok_or_else(|| CoreError::Degenerate {
                    what: what.to_owned(),
                    problem: "the bind was made for a twist, not a bend".into(),
                })?;
                let start = bind.reference.points()[0];
                let points = match target {
                    Curve::Points(p) => p.clone(),
                    Curve::Stroke(s) => project_target_stroke(
                        &s.camera,
                        &filter_stroke(&s.pixels)?,
                        bind.reference.points(),
                    )?,
                    Curve::Joints(_) => {
                        return Err(CoreError::Degenerate {
                            what: what.to_owned(),
                            problem: "a bend target cannot be a joint curve".into(),
                        });
                    }
                };
                let raw = Polyline::new(&points, "target curve")?;
                let raw = raw.translated(start - raw.points()[0]);
                let target = match turning {
                    None => TurningCurve::new(raw, bind.normal),
                    Some(f) => {
                        let base = TurningCurve::new(raw, bind.normal);
                        // Eq. (8): φ'ᵢ = φᵢ + F(sᵢ) − sᵢ at every node of the target.
                        let phi: Vec<f32> = base
                            .phi
                            .iter()
                            .zip(base.curve.node_s())
                            .map(|(&p, &s)| p + f.eval(s) - s)
                            .collect();
                        let pts = rebuild(&base.curve, &phi, bind.normal);
                        let curve = Polyline::new(&pts, "adjusted target curve")?;
                        TurningCurve::from_angles(curve, phi)
                    }
                };
                Map::Bend {
                    bend: Box::new(Bend::new(reference, target, bind.normal)),
                    scale: self.scale.as_ref(),
                }
            }
            SketchMode::Twist { angle, speed } => Map::Twist {
                axis: bind.axis.as_ref().ok_or_else(|| CoreError::Degenerate {
                    what: what.to_owned(),
                    problem: "the bind was made for a bend, not a twist".into(),
                })?,
                angle: *angle,
                speed: speed.as_ref(),
                scale: self.scale.as_ref(),
            },
        };
        let is_bend = matches!(map, Map::Bend { .. });

        // Parameters of the region of interest and of the rigid parts' virtual vertices.
        let mut s_roi = bind.roi_s.clone();
        let mut theta_roi: Vec<f32> = s_roi
            .par_iter()
            .with_min_len(PAR_CHUNK)
            .map(|&s| map.theta(s))
            .collect();
        let rigid_params: Vec<[f32; 2]> =
            bind.rigid.iter().map(|r| [r.s, map.theta(r.s)]).collect();
        let outside = |v: u32| -> [f32; 2] {
            match bind.role.get(v as usize).copied() {
                Some(k) if (k as usize) < rigid_params.len() => rigid_params[k as usize],
                _ => [0.0, 0.0],
            }
        };
        if let Some(sm) = &bind.smoother {
            if is_bend {
                let u: Vec<[f64; 2]> = s_roi
                    .iter()
                    .zip(&theta_roi)
                    .map(|(&s, &t)| [f64::from(s), f64::from(t)])
                    .collect();
                let out = sm.solve(&u, |v| outside(v).map(f64::from));
                for (k, u) in out.iter().enumerate() {
                    s_roi[k] = (u[0] as f32).clamp(0.0, 1.0);
                    theta_roi[k] = u[1] as f32;
                }
            } else {
                let u: Vec<[f64; 1]> = theta_roi.iter().map(|&t| [f64::from(t)]).collect();
                let out = sm.solve(&u, |v| [f64::from(outside(v)[1])]);
                for (k, u) in out.iter().enumerate() {
                    theta_roi[k] = u[0] as f32;
                }
            }
        }

        let mut out: Vec<Vec3> = active.iter().map(|&i| positions[i as usize]).collect();
        let mapped: Vec<Vec3> = (0..bind.roi.len())
            .into_par_iter()
            .with_min_len(PAR_CHUNK)
            .map(|k| {
                map.apply(
                    positions[bind.roi[k] as usize],
                    s_roi[k],
                    theta_roi[k],
                    true,
                )
            })
            .collect();
        for (&slot, p) in bind.roi_slots.iter().zip(mapped) {
            out[slot as usize] = p;
        }
        for (r, p) in bind.rigid.iter().zip(&rigid_params) {
            for (&v, &slot) in r.vertices.iter().zip(&r.slots) {
                out[slot as usize] = map.apply(positions[v as usize], p[0], p[1], false);
            }
        }
        if let Some(k) = out.iter().position(|p| !p.is_finite()) {
            return Err(CoreError::Degenerate {
                what: what.to_owned(),
                problem: format!("the deformation of vertex {} is not finite", active[k]),
            });
        }

        let refinement = match (&self.refine, &bind.triangles, refine_mesh) {
            (Some(options), Some(triangles), true) => {
                let n = positions.len();
                let mut vertices = Vertices {
                    input: positions.to_vec(),
                    deformed: positions.to_vec(),
                    params: vec![[0.0, 0.0]; n],
                    free: vec![false; n],
                    level: vec![0; n],
                };
                for (&i, &d) in active.iter().zip(&out) {
                    vertices.deformed[i as usize] = d;
                }
                for (k, &v) in bind.roi.iter().enumerate() {
                    vertices.params[v as usize] = [s_roi[k], theta_roi[k]];
                    vertices.free[v as usize] = true;
                }
                for (r, p) in bind.rigid.iter().zip(&rigid_params) {
                    for &v in &r.vertices {
                        vertices.params[v as usize] = *p;
                    }
                }
                let mut mesh = SplitMesh::new(triangles, n);
                let splits = refine(&mut mesh, &mut vertices, options, |p, u| {
                    map.apply(p, u[0], u[1], true)
                });
                (!splits.is_empty()).then(|| LayerRefinement {
                    deformed: vertices.deformed[n..].to_vec(),
                    splits,
                })
            }
            _ => None,
        };
        Ok(WholeDeform { out, refinement })
    }
}

impl Deformer for SketchTool {
    type Bind = SketchBind;

    fn validate(&self, what: &str) -> Result<()> {
        self.reference
            .validate(&format!("{what}: reference curve"))?;
        match &self.mode {
            SketchMode::Bend { target, turning } => {
                target.validate(&format!("{what}: target curve"))?;
                if matches!(target, Curve::Joints(_)) {
                    return Err(CoreError::Degenerate {
                        what: format!("{what}: target curve"),
                        problem: "a bend target cannot be a joint curve".into(),
                    });
                }
                if let Some(f) = turning {
                    f.validate(&format!("{what}: turning-angle control"))?;
                }
                self.bend_normal(what)?;
            }
            SketchMode::Twist { angle, speed } => {
                check_finite(|| format!("{what}: twist angle"), *angle)?;
                if let Some(f) = speed {
                    f.validate(&format!("{what}: twist-speed control"))?;
                }
            }
        }
        if let Some(n) = self.normal {
            check_finite_vec3(|| format!("{what}: normal"), n)?;
        }
        if let Some(f) = &self.scale {
            f.validate(&format!("{what}: scale control"))?;
        }
        if let Some(r) = &self.refine {
            check_finite(|| format!("{what}: refine stretch"), r.stretch)?;
            check_finite(|| format!("{what}: refine angle"), r.angle)?;
            if r.stretch.is_nan() || r.stretch <= 0.0 {
                return Err(CoreError::OutOfRange {
                    what: format!("{what}: refine stretch"),
                    value: f64::from(r.stretch),
                    expected: "must be > 0",
                });
            }
        }
        Ok(())
    }

    fn bind(&self, input: &BindInput<'_>) -> Result<SketchBind> {
        let what = "sketch tool";
        let positions = input.positions;
        let n = positions.len();
        let topology = input.topology;
        let reference_points = match &self.reference {
            Curve::Points(p) => p.clone(),
            Curve::Stroke(s) => {
                let bvh = Bvh::build(positions, &topology.triangles)?;
                project_stroke(
                    &s.camera,
                    &filter_stroke(&s.pixels)?,
                    positions,
                    topology,
                    &bvh,
                )?
            }
            Curve::Joints(s) => {
                let bvh = Bvh::build(positions, &topology.triangles)?;
                joint_curve(&s.camera, &filter_stroke(&s.pixels)?, &bvh)?
            }
        };
        let reference = Polyline::new(&reference_points, "reference curve")?;
        let computed;
        let partition = match &self.partition {
            Some(p) => p,
            None => {
                computed = partition_from_curve(positions, topology, reference.points())?;
                &computed
            }
        };

        // Roles, restricted to the active set.
        let mut role = vec![STATIC; n];
        let mut slot_of = vec![u32::MAX; n];
        for (k, &i) in input.active.iter().enumerate() {
            slot_of[i as usize] = k as u32;
        }
        let check = |v: u32, part: &str| -> Result<()> {
            if (v as usize) < n {
                Ok(())
            } else {
                Err(CoreError::NoSuchVertex {
                    what: format!("{what}: {part}"),
                    index: v,
                    vertices: n,
                })
            }
        };
        let mut roi = Vec::new();
        for &v in &partition.roi {
            check(v, "region of interest")?;
            if slot_of[v as usize] != u32::MAX && role[v as usize] == STATIC {
                role[v as usize] = ROI;
                roi.push(v);
            }
        }
        let mut rigid = Vec::new();
        for (c, comp) in partition.rigid.iter().enumerate() {
            let mut vertices = Vec::new();
            for &v in comp {
                check(v, &format!("rigid component {c}"))?;
                if slot_of[v as usize] != u32::MAX && role[v as usize] == STATIC {
                    role[v as usize] = rigid.len() as u32;
                    vertices.push(v);
                }
            }
            if !vertices.is_empty() {
                let slots = vertices.iter().map(|&v| slot_of[v as usize]).collect();
                rigid.push((vertices, slots));
            }
        }
        let roi_slots = roi.iter().map(|&v| slot_of[v as usize]).collect();
        let roi_s = skin(&reference, positions, &roi);

        let needs_adjacency = self.smooth || !rigid.is_empty();
        let adjacency = if needs_adjacency {
            input.topology.adjacency()
        } else {
            Vec::new()
        };
        let in_roi: Vec<bool> = role.iter().map(|&r| r == ROI).collect();
        let rigid = rigid
            .into_iter()
            .map(|(vertices, slots)| {
                let centre = virtual_vertex(&vertices, positions, &adjacency, &in_roi);
                RigidPart {
                    s: reference.closest_s(centre),
                    vertices,
                    slots,
                }
            })
            .collect();
        let smoother = if self.smooth && !roi.is_empty() {
            Some(Smoother::new(&roi, positions, &adjacency, what)?)
        } else {
            None
        };
        let (turning, axis, normal) = match self.mode {
            SketchMode::Bend { .. } => {
                let normal = self.bend_normal(what)?;
                (
                    Some(TurningCurve::new(reference.clone(), normal)),
                    None,
                    normal,
                )
            }
            SketchMode::Twist { .. } => (None, Some(Axis::new(reference.clone())), Vec3::Z),
        };
        Ok(SketchBind {
            reference,
            turning,
            axis,
            normal,
            roi,
            roi_slots,
            roi_s,
            rigid,
            role,
            smoother,
            triangles: self
                .refine
                .is_some()
                .then(|| input.topology.triangles.clone()),
            active: input.active.to_vec(),
        })
    }

    fn deform(&self, bind: &SketchBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        // The stack evaluates this tool as a whole (see `Tool::deform_whole`); this
        // per-vertex entry point evaluates it whole as well and picks the asked vertices.
        match self.evaluate(bind, positions, false) {
            Ok(r) => {
                for (o, &i) in out.iter_mut().zip(active) {
                    *o = match bind.active.binary_search(&i) {
                        Ok(k) => r.out[k],
                        Err(_) => positions[i as usize],
                    };
                }
            }
            Err(_) => {
                for (o, &i) in out.iter_mut().zip(active) {
                    *o = positions[i as usize];
                }
            }
        }
    }

    fn transformed(&self, m: &Affine3A) -> Self {
        let mode = match &self.mode {
            SketchMode::Bend { target, turning } => SketchMode::Bend {
                target: target.transformed(m),
                turning: turning.clone(),
            },
            SketchMode::Twist { angle, speed } => SketchMode::Twist {
                angle: *angle,
                speed: speed.clone(),
            },
        };
        let normal_matrix = m.matrix3.inverse().transpose();
        Self {
            partition: self.partition.clone(),
            reference: self.reference.transformed(m),
            normal: self.normal.map(|n| {
                (normal_matrix * glam::Vec3A::from(n))
                    .normalize_or_zero()
                    .into()
            }),
            mode,
            scale: self.scale.clone(),
            smooth: self.smooth,
            refine: self.refine,
        }
    }

    fn same_rest_state(&self, other: &Self) -> bool {
        self.partition == other.partition
            && self.reference == other.reference
            && self.normal == other.normal
            && self.smooth == other.smooth
            && self.refine == other.refine
            && std::mem::discriminant(&self.mode) == std::mem::discriminant(&other.mode)
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, PI};

    use glam::Vec2;

    use glam::Quat;

    use super::*;
    use crate::mesh::{Mesh, RestMesh};
    use crate::sketch::camera::Projection;
    use crate::stack::{Layer, Stack};
    use crate::tool::Tool;

    const RADIUS: f32 = 0.25;
    const SEGMENTS: u32 = 16;
    const STEP: f32 = 0.125;
    const LENGTH: f32 = 12.0;
    const ROI: (f32, f32) = (2.0, 10.0);

    /// An open cylinder along +x from 0 to `LENGTH`, rings every `STEP`, with UVs and a
    /// UV seam (the first column of every ring is stored twice).
    fn cylinder() -> Mesh {
        cylinder_every(STEP)
    }

    /// [`cylinder`] with rings every `step`.
    fn cylinder_every(step: f32) -> Mesh {
        let rings = (LENGTH / step).round() as u32 + 1;
        let cols = SEGMENTS + 1;
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        for r in 0..rings {
            let x = r as f32 * step;
            for c in 0..cols {
                let a = 2.0 * PI * (c % SEGMENTS) as f32 / SEGMENTS as f32;
                positions.push(Vec3::new(x, RADIUS * a.cos(), RADIUS * a.sin()));
                uvs.push(Vec2::new(c as f32 / SEGMENTS as f32, x / LENGTH));
            }
        }
        let mut indices = Vec::new();
        for r in 0..rings - 1 {
            for c in 0..SEGMENTS {
                let (a, b) = (r * cols + c, r * cols + c + 1);
                let (d, e) = (a + cols, b + cols);
                // Outward-facing (counter-clockwise seen from outside).
                indices.extend([a, b, e, a, e, d]);
            }
        }
        Mesh {
            positions,
            normals: None,
            uvs: Some(uvs),
            indices,
        }
    }

    fn partition(rest: &RestMesh) -> Partition {
        let p = rest.welded_positions();
        let mut roi = Vec::new();
        let mut rigid = Vec::new();
        for (i, v) in p.iter().enumerate() {
            if v.x >= ROI.0 && v.x <= ROI.1 {
                roi.push(i as u32);
            } else if v.x > ROI.1 {
                rigid.push(i as u32);
            }
        }
        Partition {
            roi,
            rigid: vec![rigid],
        }
    }

    /// A U of the same length as the region (8): 2 along +x, a half circle turning left
    /// (counter-clockwise seen from +z), 2 back along −x.
    fn u_target(z: f32) -> Vec<Vec3> {
        let r = 4.0 / PI;
        let mut pts = vec![Vec3::new(2.0, 0.0, z), Vec3::new(4.0, 0.0, z)];
        for k in 1..=64 {
            let a = PI * k as f32 / 64.0;
            pts.push(Vec3::new(4.0 + r * a.sin(), r * (1.0 - a.cos()), z));
        }
        pts.push(Vec3::new(2.0, 2.0 * r, z));
        pts
    }

    fn axis_reference() -> Curve {
        Curve::Points(vec![Vec3::new(ROI.0, 0.0, 0.0), Vec3::new(ROI.1, 0.0, 0.0)])
    }

    fn bend_tool(rest: &RestMesh, smooth: bool) -> SketchTool {
        SketchTool {
            partition: Some(partition(rest)),
            reference: axis_reference(),
            normal: Some(Vec3::Z),
            mode: SketchMode::Bend {
                target: Curve::Points(u_target(0.0)),
                turning: None,
            },
            scale: None,
            smooth,
            refine: None,
        }
    }

    fn run(rest: &RestMesh, tool: SketchTool) -> Vec<Vec3> {
        Stack {
            layers: vec![Layer::new("sketch", Tool::Sketch(Box::new(tool)))],
        }
        .evaluate_welded(rest)
        .unwrap()
    }

    /// Centroids of the deformed rings of the region of interest, in x order.
    fn ring_centres(rest: &RestMesh, out: &[Vec3]) -> Vec<Vec3> {
        let mut rings: std::collections::BTreeMap<i32, (Vec3, f32)> = Default::default();
        for (p, q) in rest.welded_positions().iter().zip(out) {
            if p.x >= ROI.0 && p.x <= ROI.1 {
                let e = rings.entry((p.x / STEP).round() as i32).or_default();
                e.0 += *q;
                e.1 += 1.0;
            }
        }
        rings.values().map(|(s, n)| *s / *n).collect()
    }

    fn polyline_length(p: &[Vec3]) -> f32 {
        p.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    fn check_u(rest: &RestMesh, out: &[Vec3]) {
        let rest_p = rest.welded_positions();
        let part = partition(rest);
        // Static part: bit for bit.
        for (i, p) in rest_p.iter().enumerate() {
            if p.x < ROI.0 {
                assert_eq!(
                    p.to_array().map(f32::to_bits),
                    out[i].to_array().map(f32::to_bits)
                );
            }
        }
        // Rigid part: every pairwise distance kept.
        let rigid = &part.rigid[0];
        for (k, &a) in rigid.iter().enumerate().step_by(7) {
            for &b in &rigid[k + 1..] {
                let (a, b) = (a as usize, b as usize);
                let d0 = rest_p[a].distance(rest_p[b]);
                let d1 = out[a].distance(out[b]);
                assert!((d0 - d1).abs() < 1e-5, "rigid distance {d0} became {d1}");
            }
        }
        // The rigid end now points back along −x: a U.
        let tip = out[rigid[rigid.len() - 1] as usize];
        assert!(tip.x < 1.0 && tip.y > 2.0, "tip {tip}");
        // Arc length along the axis.
        let centres = ring_centres(rest, out);
        let len = polyline_length(&centres);
        let rest_len = ROI.1 - ROI.0;
        assert!(
            (len - rest_len).abs() < 0.01 * rest_len,
            "axis length {len}, rest {rest_len}"
        );
    }

    #[test]
    fn cylinder_bends_into_a_u_without_smoothing() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let out = run(&rest, bend_tool(&rest, false));
        check_u(&rest, &out);
    }

    #[test]
    fn cylinder_bends_into_a_u_with_smoothing_and_no_triangle_flips() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let out = run(&rest, bend_tool(&rest, true));
        check_u(&rest, &out);
        // Every triangle still faces away from the deformed axis.
        let mut axis = vec![out[0]];
        axis.extend(ring_centres(&rest, &out));
        let axis = Polyline::new(&axis, "axis").unwrap();
        let mut flipped = 0;
        for t in &rest.topology().triangles {
            let [a, b, c] = t.map(|i| out[i as usize]);
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0;
            let on_axis = axis.point_at(axis.closest_s(centre));
            if n.dot(centre - on_axis) <= 0.0 {
                flipped += 1;
            }
        }
        assert_eq!(flipped, 0);
        // Smoothing changes something (it is not a no-op) but keeps the region close.
        let plain = run(&rest, bend_tool(&rest, false));
        let max_diff = out
            .iter()
            .zip(&plain)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        assert!(max_diff > 1e-4 && max_diff < 0.5, "{max_diff}");
    }

    #[test]
    fn twist_rotates_each_vertex_by_s_times_theta_max() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let theta_max = 0.8 * PI;
        let tool = SketchTool {
            mode: SketchMode::Twist {
                angle: theta_max,
                speed: None,
            },
            normal: None,
            smooth: false,
            ..bend_tool(&rest, false)
        };
        let out = run(&rest, tool);
        for (p, q) in rest.welded_positions().iter().zip(&out) {
            if p.x < ROI.0 || p.x > ROI.1 {
                continue;
            }
            let s = (p.x - ROI.0) / (ROI.1 - ROI.0);
            assert!((q.x - p.x).abs() < 1e-5, "twist moved along the axis");
            let a0 = p.z.atan2(p.y);
            let a1 = q.z.atan2(q.y);
            let mut d = a1 - a0;
            while d < -PI {
                d += 2.0 * PI;
            }
            while d > PI {
                d -= 2.0 * PI;
            }
            assert!(
                (d - s * theta_max).abs() < 1e-4,
                "x {}: rotated {d}, expected {}",
                p.x,
                s * theta_max
            );
            assert!((Vec2::new(q.y, q.z).length() - RADIUS).abs() < 1e-5);
        }
    }

    #[test]
    fn twist_speed_and_scale_controls() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let tool = SketchTool {
            mode: SketchMode::Twist {
                angle: FRAC_PI_2,
                // F(s) = 1 − s (linear): the twist is strongest at the start.
                speed: Some(SplineControl {
                    values: vec![1.0, 0.0],
                    degree: 1,
                }),
            },
            scale: Some(SplineControl::constant(2.0)),
            normal: None,
            smooth: false,
            ..bend_tool(&rest, false)
        };
        let out = run(&rest, tool);
        for (p, q) in rest.welded_positions().iter().zip(&out) {
            if p.x < ROI.0 || p.x > ROI.1 {
                continue;
            }
            let s = (p.x - ROI.0) / (ROI.1 - ROI.0);
            let expect =
                Quat::from_rotation_x((1.0 - s) * FRAC_PI_2) * (Vec3::new(0.0, p.y, p.z) * 2.0);
            assert!(
                (Vec3::new(0.0, q.y, q.z) - expect).length() < 1e-5,
                "{p} -> {q}"
            );
        }
    }

    #[test]
    fn identity_spline_reproduces_s_and_leaves_the_bend_unchanged() {
        let f = SplineControl::identity(6, 3);
        for k in 0..=20 {
            let s = k as f32 / 20.0;
            assert!((f.eval(s) - s).abs() < 1e-6, "F({s}) = {}", f.eval(s));
        }
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let plain = run(&rest, bend_tool(&rest, false));
        let mut tool = bend_tool(&rest, false);
        if let SketchMode::Bend { turning, .. } = &mut tool.mode {
            *turning = Some(f);
        }
        let adjusted = run(&rest, tool);
        for (a, b) in plain.iter().zip(&adjusted) {
            assert!(a.distance(*b) < 1e-3);
        }
    }

    #[test]
    fn turning_control_straightens_the_u() {
        // φ'ᵢ = φᵢ + F(sᵢ) − sᵢ with F(s) = s + π/64 on the 64 turning nodes of the half
        // circle (each turns −π/64, clockwise positive) cancels the turn: straight again.
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let mut tool = bend_tool(&rest, false);
        let mut f = SplineControl::identity(4, 3);
        for v in &mut f.values {
            *v += PI / 64.0;
        }
        if let SketchMode::Bend { turning, .. } = &mut tool.mode {
            *turning = Some(f);
        }
        // Node 0 and the last node also receive the offset; node 1 (s = 0.25) has φ = 0
        // and turns by π/64 too, so the result is only nearly straight: check the tip
        // went from pointing back (−x) to far along +x.
        let out = run(&rest, tool);
        let tip = out[*partition(&rest).rigid[0].last().unwrap() as usize];
        assert!(tip.x > 8.0, "{tip}");
    }

    #[test]
    fn strokes_give_the_same_bend_as_the_curves_they_draw() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let camera = Camera {
            eye: Vec3::new(6.0, 1.0, 20.0),
            target: Vec3::new(6.0, 1.0, 0.0),
            up: Vec3::Y,
            projection: Projection::Orthographic { height: 14.0 },
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(1000.0, 1000.0),
        };
        let px = |p: Vec3| camera.project(p).unwrap().0;
        let stroke = |pts: &[Vec3]| Stroke {
            pixels: pts.iter().map(|&p| px(p)).collect(),
            camera,
        };
        // The reference stroke's first ray hits the top of the cylinder at z = RADIUS, so
        // the sketch plane is z = RADIUS.
        let ref_pts = [Vec3::new(ROI.0, 0.0, RADIUS), Vec3::new(ROI.1, 0.0, RADIUS)];
        let tool = SketchTool {
            reference: Curve::Stroke(stroke(&ref_pts)),
            normal: None,
            mode: SketchMode::Bend {
                target: Curve::Stroke(stroke(&u_target(RADIUS))),
                turning: None,
            },
            ..bend_tool(&rest, false)
        };
        let from_strokes = run(&rest, tool.clone());
        // Without a stored partition the region comes from the cutting planes at the
        // reference's ends (§4.2): the same U, static part untouched.
        let auto = run(
            &rest,
            SketchTool {
                partition: None,
                ..tool
            },
        );
        for (i, p) in rest.welded_positions().iter().enumerate() {
            if p.x < ROI.0 - 1e-3 {
                assert_eq!(*p, auto[i]);
            } else if p.x > ROI.1 + STEP {
                assert!(
                    auto[i].distance(from_strokes[i]) < 0.05,
                    "{p}: {} vs {}",
                    auto[i],
                    from_strokes[i]
                );
            }
        }
        // The tool filters recorded strokes (§4.1); with an orthographic camera filtering
        // pixels is filtering the plane points they come from.
        let filtered =
            crate::sketch::stroke::filter_stroke(&stroke(&u_target(RADIUS)).pixels).unwrap();
        let target: Vec<Vec3> = filtered
            .iter()
            .map(|&p| {
                let ray = camera.ray(p);
                ray.origin + ray.direction * ((RADIUS - ray.origin.z) / ray.direction.z)
            })
            .collect();
        let tool = SketchTool {
            reference: Curve::Points(ref_pts.to_vec()),
            mode: SketchMode::Bend {
                target: Curve::Points(target),
                turning: None,
            },
            ..bend_tool(&rest, false)
        };
        let from_points = run(&rest, tool);
        for (a, b) in from_strokes.iter().zip(&from_points) {
            assert!(a.distance(*b) < 2e-3, "{a} vs {b}");
        }
    }

    #[test]
    fn refinement_adds_vertices_on_the_bend_and_keeps_the_rest() {
        let mut mesh = cylinder();
        // A coarse cylinder (rings every 1.0) so that the U stretches and bends edges.
        let keep: Vec<bool> = mesh
            .positions
            .iter()
            .map(|p| (p.x.fract()).abs() < 1e-6)
            .collect();
        let mut map = vec![u32::MAX; mesh.positions.len()];
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        for (i, k) in keep.iter().enumerate() {
            if *k {
                map[i] = positions.len() as u32;
                positions.push(mesh.positions[i]);
                uvs.push(mesh.uvs.as_ref().unwrap()[i]);
            }
        }
        let cols = SEGMENTS + 1;
        let rings = positions.len() as u32 / cols;
        let mut indices = Vec::new();
        for r in 0..rings - 1 {
            for c in 0..SEGMENTS {
                let (a, b) = (r * cols + c, r * cols + c + 1);
                indices.extend([a, b, b + cols, a, b + cols, a + cols]);
            }
        }
        mesh = Mesh {
            positions,
            normals: None,
            uvs: Some(uvs),
            indices,
        };
        let rest = RestMesh::new(mesh, "coarse").unwrap();
        // A tighter U (half circle of radius 1) so edges on the outside stretch > 1.5×.
        let mut target = vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0)];
        for k in 1..=32 {
            let a = PI * k as f32 / 32.0;
            target.push(Vec3::new(6.0 + 0.3 * a.sin(), 0.3 * (1.0 - a.cos()), 0.0));
        }
        target.push(Vec3::new(2.0, 0.6, 0.0));
        let tool = SketchTool {
            mode: SketchMode::Bend {
                target: Curve::Points(target),
                turning: None,
            },
            scale: Some(SplineControl::constant(3.0)),
            refine: Some(RefineOptions::default()),
            ..bend_tool(&rest, false)
        };
        let plain = Stack {
            layers: vec![Layer::new(
                "s",
                Tool::Sketch(Box::new(SketchTool {
                    refine: None,
                    ..tool.clone()
                })),
            )],
        }
        .evaluate(&rest)
        .unwrap();
        let stack = Stack {
            layers: vec![Layer::new("s", Tool::Sketch(Box::new(tool)))],
        };
        let out = stack.evaluate(&rest).unwrap();
        let refined = out
            .refined
            .as_ref()
            .expect("the bend refines the coarse mesh");
        let n = rest.mesh().positions.len();
        assert!(out.positions.len() > n);
        assert_eq!(out.positions.len(), refined.topology.weld.len());
        // Original stored vertices: same output as without refinement.
        for (a, b) in out.positions[..n].iter().zip(&plain.positions) {
            assert_eq!(a, b);
        }
        // Indices are valid and UVs cover every output vertex.
        let indices = out.indices(&rest);
        assert!(indices.iter().all(|&i| (i as usize) < out.positions.len()));
        assert_eq!(out.uvs(&rest).unwrap().len(), out.positions.len());
        // New vertices sit in the region of interest (never in the static part).
        for p in &refined.parents {
            let (a, b) = (
                rest.mesh().positions.get(p.a as usize),
                rest.mesh().positions.get(p.b as usize),
            );
            if let (Some(a), Some(b)) = (a, b) {
                assert!(a.x >= ROI.0 || b.x >= ROI.0);
            }
        }
        assert!(out.normals.iter().all(|n| n.is_finite()));
    }

    /// On a mesh big enough for the stack's chunk boxes (24,592 welded vertices), a volume
    /// layer after the bend weighs the vertices the bend moved into its sphere, where no
    /// vertex lay at rest: the boxes of the chunks the bend moved are refreshed (or all built
    /// again after a refining bend) before the mask reads them. The stack gives the bits of
    /// the same layers bound one after the other with plain masks.
    #[test]
    fn a_volume_after_a_bend_weighs_the_vertices_moved_into_it_on_a_big_mesh() {
        use crate::ffsd::{ControlPoint, FfsdTool};
        use crate::influence::{Falloff, Influence, Shape, Volume};
        use crate::refinement::RefinedMesh;
        use crate::stack::LayerBinding;
        let rest = RestMesh::new(cylinder_every(STEP / 16.0), "fine").unwrap();
        assert!(rest.welded_positions().len() >= crate::chunks::PARALLEL_THRESHOLD);
        let bump = |at: Vec3, radius: f32| {
            let mut layer = Layer::new(
                "bump",
                Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
                    at + Vec3::Z * 0.2,
                    0.3,
                    2.0,
                    0.3,
                )])),
            );
            let placement = glam::Affine3A::from_translation(at);
            layer.influence = Some(Influence {
                volumes: vec![Volume::new(Shape::Sphere { radius }, placement, "v").unwrap()],
                falloff: Falloff::Smooth,
                ..Influence::default()
            });
            layer
        };
        // The U's way back passes over x ∈ [2, 4] at y ≈ 2.55; the cylinder lies at y ≈ 0.
        let over_the_way_back = Vec3::new(3.0, 8.0 / PI, 0.0);
        let bits = |p: &[Vec3]| -> Vec<[u32; 3]> {
            p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
        };
        // The U stretches its outside 1.2× and hardly bends an edge of this fine mesh: a
        // refinement that splits every edge stretched by more than 1.1×.
        let every_stretched = RefineOptions {
            stretch: 1.1,
            angle: 4.0,
            max_levels: 1,
        };
        for refine in [None, Some(every_stretched)] {
            let bend = SketchTool {
                refine,
                ..bend_tool(&rest, false)
            };
            let stack = Stack {
                layers: vec![
                    bump(Vec3::new(1.0, 0.0, 0.0), 0.6),
                    Layer::new("bend", Tool::Sketch(Box::new(bend))),
                    bump(over_the_way_back, 0.8),
                ],
            };
            let out = stack.evaluate_surface(&rest).unwrap();
            // The layers one after the other, each mask from every position.
            let mut positions = rest.welded_positions().to_vec();
            let mut refined: Option<RefinedMesh> = None;
            let mut moved = 0;
            for layer in &stack.layers {
                let topology = refined.as_ref().map_or(rest.topology(), |r| &r.topology);
                let binding = LayerBinding::bind(layer, &positions, topology).unwrap();
                let before = positions.clone();
                if let Some(splits) = binding.apply_refining(layer, &mut positions).unwrap() {
                    let base = refined
                        .take()
                        .unwrap_or_else(|| RefinedMesh::unrefined(rest.mesh(), rest.topology()));
                    refined = Some(base.split(&splits));
                }
                moved = before
                    .iter()
                    .zip(&positions)
                    .filter(|(a, b)| a != b)
                    .count();
            }
            assert!(moved > 50, "the last volume holds {moved} moved vertices");
            let (a, b) = (bits(&out.positions), bits(&positions));
            assert_eq!(a.len(), b.len(), "refine: {refine:?}");
            let differ = a.iter().zip(&b).filter(|(a, b)| a != b).count();
            assert_eq!(differ, 0, "positions differing, refine: {refine:?}");
            assert_eq!(out.refined.is_some(), refine.is_some());
        }
    }

    #[test]
    fn state_round_trips_through_ron() {
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y: 0.8 },
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(800.0, 600.0),
        };
        let tool = Tool::Sketch(Box::new(SketchTool {
            partition: Some(Partition {
                roi: vec![1, 2, 3],
                rigid: vec![vec![4, 5]],
            }),
            reference: Curve::Stroke(Stroke {
                pixels: vec![Vec2::new(10.0, 20.0), Vec2::new(30.0, 40.0)],
                camera,
            }),
            normal: None,
            mode: SketchMode::Bend {
                target: Curve::Points(vec![Vec3::ZERO, Vec3::X]),
                turning: Some(SplineControl::identity(4, 3)),
            },
            scale: None,
            smooth: true,
            refine: Some(RefineOptions::default()),
        }));
        let text = ron::to_string(&tool).unwrap();
        let back: Tool = ron::from_str(&text).unwrap();
        assert_eq!(back, tool);
        // Defaults: smoothing on, no refinement, no controls.
        let short: SketchTool = ron::from_str(
            "(partition: Some((roi: [0], rigid: [])), reference: Points([(0,0,0),(1,0,0)]), normal: Some((0,0,1)), mode: Twist(angle: 1.0))",
        )
        .unwrap();
        assert!(short.smooth && short.refine.is_none() && short.scale.is_none());
    }

    #[test]
    fn bad_input_gives_errors_not_panics() {
        let rest = RestMesh::new(cylinder(), "cylinder").unwrap();
        let mut t = bend_tool(&rest, true);
        t.normal = None;
        assert!(t.validate("t").is_err(), "3-D reference without a normal");
        let mut t = bend_tool(&rest, true);
        t.partition.as_mut().unwrap().roi.push(1_000_000);
        let err = Stack {
            layers: vec![Layer::new("s", Tool::Sketch(Box::new(t)))],
        }
        .evaluate(&rest)
        .unwrap_err();
        assert!(
            matches!(
                err,
                CoreError::NoSuchVertex {
                    index: 1_000_000,
                    ..
                }
            ),
            "{err}"
        );
        let mut t = bend_tool(&rest, true);
        t.reference = Curve::Points(vec![Vec3::ONE, Vec3::ONE]);
        assert!(
            Stack {
                layers: vec![Layer::new("s", Tool::Sketch(Box::new(t)))]
            }
            .evaluate(&rest)
            .is_err()
        );
        let mut t = bend_tool(&rest, true);
        t.mode = SketchMode::Twist {
            angle: f32::NAN,
            speed: None,
        };
        assert!(t.validate("t").is_err());
    }
}
