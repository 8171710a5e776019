//! Channels: the animatable (numeric) parameters of every tool kind and volume shape, each
//! addressed by a *path* that follows the scene format's field names.
//!
//! The path rule: field names joined by `.`, list items as `[i]`; enum variant names and
//! `Some(…)` are transparent. So `points[2].gamma` is the γ of an FFSD tool's third point,
//! `height.theta` its height limit, `mode.target` a sketch bend's target curve,
//! `constraints[0].support.radius` a DOGME support sphere. Only parameters that exist in the
//! tool's current structure are channels (a `Box` support has `half_extents` and `rotation`,
//! a `Sphere` one has `radius`); counts, degrees, bases, modes and the sketch tool's
//! reference curve, partition and normal are structure, not channels.
//!
//! [`visit_tool`] walks every channel of a tool with a mutable [`Slot`], which reads
//! ([`Slot::get`]) and writes ([`Slot::set`]) it; [`tool_channels`], [`tool_channel`] and
//! [`set_tool_channel`] are built on it.

use ductile_core::axial::{AxialTool, AxisPoint};
use ductile_core::curve::CurveTool;
use ductile_core::direct_ffd::DirectFfdTool;
use ductile_core::dogme::{Anchor, DogmeTool, Support};
use ductile_core::ffsd::{FfsdTool, HeightLimit, PointMode};
use ductile_core::influence::Shape;
use ductile_core::lattice::LatticeTool;
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};
use ductile_core::surface::ShapeSurfaceTool;
use ductile_core::tool::Tool;
use glam::{Quat, Vec3};

use crate::error::{AnimError, Result};
use crate::value::{Value, ValueKind};

/// Mutable access to one channel of a tool or shape.
#[derive(Debug)]
pub enum Slot<'a> {
    /// A number.
    Scalar(&'a mut f32),
    /// A vector or point.
    Vector(&'a mut Vec3),
    /// A rotation.
    Rotation(&'a mut Quat),
    /// Spline control values.
    Values(&'a mut Vec<f32>),
    /// A 3-D curve's points.
    Polyline(&'a mut Vec<Vec3>),
    /// An axis.
    Axis(&'a mut Vec<AxisPoint>),
    /// A plane curve's points and the plane's normal (structure, not written).
    PlaneCurve(&'a mut Vec<Vec3>, Vec3),
}

impl Slot<'_> {
    /// The kind of value the channel holds.
    #[must_use]
    pub fn kind(&self) -> ValueKind {
        match self {
            Slot::Scalar(_) => ValueKind::Scalar,
            Slot::Vector(_) => ValueKind::Vector,
            Slot::Rotation(_) => ValueKind::Rotation,
            Slot::Values(_) => ValueKind::Values,
            Slot::Polyline(_) => ValueKind::Polyline,
            Slot::Axis(_) => ValueKind::Axis,
            Slot::PlaneCurve(..) => ValueKind::PlaneCurve,
        }
    }

    /// The channel's current value.
    #[must_use]
    pub fn get(&self) -> Value {
        match self {
            Slot::Scalar(x) => Value::Scalar(**x),
            Slot::Vector(v) => Value::Vector(**v),
            Slot::Rotation(q) => Value::Rotation(**q),
            Slot::Values(v) => Value::Values((*v).clone()),
            Slot::Polyline(p) => Value::Polyline((*p).clone()),
            Slot::Axis(a) => Value::Axis((*a).clone()),
            Slot::PlaneCurve(p, n) => Value::PlaneCurve {
                points: (*p).clone(),
                normal: *n,
            },
        }
    }

    /// Writes `value` into the channel. Errors (writing nothing) when the value is of
    /// another kind, or a plane curve of another plane.
    pub fn set(self, path: &str, value: &Value) -> Result<()> {
        let wrong = |expected: ValueKind| AnimError::WrongValue {
            path: path.to_owned(),
            expected: expected.name(),
            found: value.shape(),
        };
        match (self, value) {
            (Slot::Scalar(x), Value::Scalar(v)) => *x = *v,
            (Slot::Vector(x), Value::Vector(v)) => *x = *v,
            (Slot::Rotation(x), Value::Rotation(v)) => *x = *v,
            (Slot::Values(x), Value::Values(v)) => x.clone_from(v),
            (Slot::Polyline(x), Value::Polyline(v)) => x.clone_from(v),
            (Slot::Axis(x), Value::Axis(v)) => x.clone_from(v),
            (Slot::PlaneCurve(x, n), Value::PlaneCurve { points, normal }) => {
                if !same_direction(*normal, n) {
                    return Err(AnimError::OtherPlane {
                        path: path.to_owned(),
                        normal: n,
                        found: *normal,
                    });
                }
                x.clone_from(points);
            }
            (slot, _) => return Err(wrong(slot.kind())),
        }
        Ok(())
    }
}

/// True when `a` and `b` point the same way (within 1e-6 of the cosine): plane normals
/// written by hand need not be unit vectors to the last bit.
#[must_use]
pub fn same_direction(a: Vec3, b: Vec3) -> bool {
    match (a.try_normalize(), b.try_normalize()) {
        (Some(a), Some(b)) => a.dot(b) >= 1.0 - 1e-6,
        _ => false,
    }
}

/// Walks channels, keeping the current path, and hands each to `f`. With a `target`, only
/// the channel of that path is handed over (subtrees whose prefix cannot lead to it are
/// skipped).
struct Walker<'f> {
    path: String,
    target: Option<&'f str>,
    f: &'f mut dyn FnMut(&str, Slot<'_>),
}

impl Walker<'_> {
    fn wanted(&self) -> bool {
        self.target.is_none_or(|t| t.starts_with(&self.path))
    }

    fn push(&mut self, name: &str) -> usize {
        let len = self.path.len();
        if !self.path.is_empty() {
            self.path.push('.');
        }
        self.path.push_str(name);
        len
    }

    fn slot(&mut self, name: &str, slot: Slot<'_>) {
        let len = self.push(name);
        if self.target.is_none_or(|t| t == self.path) {
            (self.f)(&self.path, slot);
        }
        self.path.truncate(len);
    }

    fn scalar(&mut self, name: &str, x: &mut f32) {
        self.slot(name, Slot::Scalar(x));
    }

    fn vector(&mut self, name: &str, v: &mut Vec3) {
        self.slot(name, Slot::Vector(v));
    }

    fn scope(&mut self, name: &str, body: impl FnOnce(&mut Self)) {
        let len = self.push(name);
        if self.wanted() {
            body(self);
        }
        self.path.truncate(len);
    }

    fn items<T>(&mut self, name: &str, items: &mut [T], mut body: impl FnMut(&mut Self, &mut T)) {
        let len = self.push(name);
        if self.wanted() {
            for (i, item) in items.iter_mut().enumerate() {
                let inner = self.path.len();
                self.path.push_str(&format!("[{i}]"));
                if self.wanted() {
                    body(self, item);
                }
                self.path.truncate(inner);
            }
        }
        self.path.truncate(len);
    }
}

fn ffsd(w: &mut Walker<'_>, t: &mut FfsdTool) {
    w.items("points", &mut t.points, |w, p| {
        w.vector("position", &mut p.position);
        if let PointMode::Directional { reference } = &mut p.mode {
            w.scope("mode", |w| w.vector("reference", reference));
        }
        w.scalar("gamma", &mut p.gamma);
        w.scalar("alpha", &mut p.alpha);
        w.scalar("epsilon", &mut p.epsilon);
    });
    if let Some(h) = &mut t.height {
        w.scope("height", |w| match h {
            HeightLimit::Above { theta } | HeightLimit::Below { theta } => w.scalar("theta", theta),
            HeightLimit::Both { below, above } => {
                w.scalar("below", below);
                w.scalar("above", above);
            }
        });
    }
    w.scalar("gain", &mut t.gain);
}

fn axial(w: &mut Walker<'_>, t: &mut AxialTool) {
    w.slot("rest", Slot::Axis(&mut t.rest));
    w.slot("deformed", Slot::Axis(&mut t.deformed));
    w.scalar("radius", &mut t.radius);
    w.scalar("inner", &mut t.inner);
}

fn curve(w: &mut Walker<'_>, t: &mut CurveTool) {
    w.slot("rest", Slot::Polyline(&mut t.rest));
    w.slot("deformed", Slot::Polyline(&mut t.deformed));
}

fn lattice(w: &mut Walker<'_>, t: &mut LatticeTool) {
    w.scope("frame", |w| {
        w.vector("origin", &mut t.frame.origin);
        w.vector("s", &mut t.frame.s);
        w.vector("t", &mut t.frame.t);
        w.vector("u", &mut t.frame.u);
    });
    w.items("points", &mut t.points, |w, p| {
        w.vector("offset", &mut p.offset);
        w.scalar("weight", &mut p.weight);
    });
    w.scalar("falloff", &mut t.falloff);
}

fn anchor(w: &mut Walker<'_>, at: &mut Anchor) {
    if let Anchor::Point(p) = at {
        w.vector("at", p);
    }
}

fn dogme(w: &mut Walker<'_>, t: &mut DogmeTool) {
    w.items("constraints", &mut t.constraints, |w, c| {
        anchor(w, &mut c.at);
        w.vector("displacement", &mut c.displacement);
        w.scope("support", |w| match &mut c.support {
            Support::Sphere { radius } => w.scalar("radius", radius),
            Support::Box {
                half_extents,
                rotation,
            } => {
                w.vector("half_extents", half_extents);
                w.slot("rotation", Slot::Rotation(rotation));
            }
        });
    });
}

fn direct_ffd(w: &mut Walker<'_>, t: &mut DirectFfdTool) {
    w.scope("lattice", |w| lattice(w, &mut t.lattice));
    w.items("constraints", &mut t.constraints, |w, c| {
        anchor(w, &mut c.at);
        w.vector("displacement", &mut c.displacement);
    });
}

fn surface(w: &mut Walker<'_>, t: &mut ShapeSurfaceTool) {
    w.scope("frame", |w| {
        w.vector("origin", &mut t.frame.origin);
        w.vector("u_edge", &mut t.frame.u_edge);
        w.vector("v_edge", &mut t.frame.v_edge);
    });
    w.items("rest", &mut t.rest, |w, e| {
        w.vector("offset", &mut e.offset)
    });
    w.items("moves", &mut t.moves, |w, e| {
        w.vector("offset", &mut e.offset)
    });
    w.items("heights", &mut t.heights, |w, e| {
        w.scalar("height", &mut e.height)
    });
}

/// The unit normal of a sketch tool's plane: the given normal, else the direction towards
/// the eye of the reference stroke's camera; `None` when neither gives one.
#[must_use]
pub fn sketch_normal(t: &SketchTool) -> Option<Vec3> {
    let n = match (&t.normal, &t.reference) {
        (Some(n), _) => *n,
        (None, Curve::Stroke(s) | Curve::Joints(s)) => -s.camera.forward(),
        (None, Curve::Points(_)) => return None,
    };
    n.try_normalize()
}

fn sketch(w: &mut Walker<'_>, t: &mut SketchTool) {
    let normal = sketch_normal(t);
    w.scope("mode", |w| match &mut t.mode {
        SketchMode::Bend { target, turning } => {
            if let (Curve::Points(points), Some(n)) = (target, normal) {
                w.slot("target", Slot::PlaneCurve(points, n));
            }
            if let Some(f) = turning {
                w.scope("turning", |w| w.slot("values", Slot::Values(&mut f.values)));
            }
        }
        SketchMode::Twist { angle, speed } => {
            w.scalar("angle", angle);
            if let Some(f) = speed {
                w.scope("speed", |w| w.slot("values", Slot::Values(&mut f.values)));
            }
        }
    });
    if let Some(f) = &mut t.scale {
        w.scope("scale", |w| w.slot("values", Slot::Values(&mut f.values)));
    }
    if let Some(r) = &mut t.refine {
        w.scope("refine", |w| {
            w.scalar("stretch", &mut r.stretch);
            w.scalar("angle", &mut r.angle);
        });
    }
}

fn tool(w: &mut Walker<'_>, t: &mut Tool) {
    match t {
        Tool::Ffsd(t) => ffsd(w, t),
        Tool::Sketch(t) => sketch(w, t),
        Tool::Axial(t) => axial(w, t),
        Tool::Curve(t) => curve(w, t),
        Tool::Lattice(t) => lattice(w, t),
        Tool::Dogme(t) => dogme(w, t),
        Tool::DirectFfd(t) => direct_ffd(w, t),
        Tool::ShapeSurface(t) => surface(w, t),
    }
}

fn shape(w: &mut Walker<'_>, s: &mut Shape) {
    match s {
        Shape::Sphere { radius } => w.scalar("radius", radius),
        Shape::Box { half_extents } => w.vector("half_extents", half_extents),
        Shape::Capsule {
            radius,
            half_height,
        } => {
            w.scalar("radius", radius);
            w.scalar("half_height", half_height);
        }
        Shape::Tube { points, radii } => {
            w.slot("points", Slot::Polyline(points));
            w.slot("radii", Slot::Values(radii));
        }
    }
}

/// Calls `f` with the path and a [`Slot`] of every channel of `t`, in the order of the
/// scene format's fields.
pub fn visit_tool(t: &mut Tool, f: &mut dyn FnMut(&str, Slot<'_>)) {
    tool(
        &mut Walker {
            path: String::new(),
            target: None,
            f,
        },
        t,
    );
}

/// Calls `f` with the path and a [`Slot`] of every channel of a volume shape.
pub fn visit_shape(s: &mut Shape, f: &mut dyn FnMut(&str, Slot<'_>)) {
    shape(
        &mut Walker {
            path: String::new(),
            target: None,
            f,
        },
        s,
    );
}

fn with_slot<T, R>(
    item: &mut T,
    walk: fn(&mut Walker<'_>, &mut T),
    path: &str,
    g: impl FnOnce(&str, Slot<'_>) -> R,
) -> Option<R> {
    let mut g = Some(g);
    let mut out = None;
    let mut f = |p: &str, s: Slot<'_>| {
        if let Some(g) = g.take() {
            out = Some(g(p, s));
        }
    };
    walk(
        &mut Walker {
            path: String::new(),
            target: Some(path),
            f: &mut f,
        },
        item,
    );
    out
}

/// Every channel of `t` with its current value, in order.
#[must_use]
pub fn tool_channels(t: &Tool) -> Vec<(String, Value)> {
    let mut copy = t.clone();
    let mut out = Vec::new();
    visit_tool(&mut copy, &mut |p, s| out.push((p.to_owned(), s.get())));
    out
}

/// The value of channel `path` of `t`.
pub fn tool_channel(t: &Tool, path: &str) -> Result<Value> {
    let mut copy = t.clone();
    with_slot(&mut copy, tool, path, |_, s| s.get()).ok_or_else(|| no_channel(path, t))
}

/// Writes `value` into channel `path` of `t`. Errors when `t` has no such channel or the
/// value is of another kind; `t` is then unchanged.
pub fn set_tool_channel(t: &mut Tool, path: &str, value: &Value) -> Result<()> {
    let kind = t.kind_name();
    with_slot(t, tool, path, |p, s| s.set(p, value)).unwrap_or_else(|| {
        Err(AnimError::NoSuchChannel {
            path: path.to_owned(),
            owner: kind.to_owned(),
        })
    })
}

/// Every channel of a volume shape with its current value, in order.
#[must_use]
pub fn shape_channels(s: &Shape) -> Vec<(String, Value)> {
    let mut copy = s.clone();
    let mut out = Vec::new();
    visit_shape(&mut copy, &mut |p, slot| {
        out.push((p.to_owned(), slot.get()))
    });
    out
}

/// Writes `value` into channel `path` of a volume shape.
pub fn set_shape_channel(s: &mut Shape, path: &str, value: &Value) -> Result<()> {
    with_slot(s, shape, path, |p, slot| slot.set(p, value)).unwrap_or_else(|| {
        Err(AnimError::NoSuchChannel {
            path: path.to_owned(),
            owner: "volume shape".to_owned(),
        })
    })
}

fn no_channel(path: &str, t: &Tool) -> AnimError {
    AnimError::NoSuchChannel {
        path: path.to_owned(),
        owner: t.kind_name().to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use ductile_core::curve::CurveBasis;
    use ductile_core::ffsd::ControlPoint;
    use ductile_core::sketch::tool::SplineControl;

    use super::*;

    fn ffsd_tool() -> Tool {
        let point = |x: f32, mode| ControlPoint {
            position: Vec3::new(x, 0.0, 0.0),
            mode,
            gamma: 0.5,
            alpha: 2.0,
            epsilon: 0.1,
        };
        Tool::Ffsd(FfsdTool {
            points: vec![
                point(0.0, PointMode::Basic),
                point(1.0, PointMode::Directional { reference: Vec3::Y }),
            ],
            height: Some(HeightLimit::Both {
                below: 0.1,
                above: 0.2,
            }),
            gain: 1.0,
        })
    }

    #[test]
    fn ffsd_channels_follow_the_format() {
        let paths: Vec<String> = tool_channels(&ffsd_tool())
            .into_iter()
            .map(|c| c.0)
            .collect();
        assert_eq!(
            paths,
            [
                "points[0].position",
                "points[0].gamma",
                "points[0].alpha",
                "points[0].epsilon",
                "points[1].position",
                "points[1].mode.reference",
                "points[1].gamma",
                "points[1].alpha",
                "points[1].epsilon",
                "height.below",
                "height.above",
                "gain",
            ]
        );
    }

    #[test]
    fn channels_read_and_write_by_path() {
        let mut t = ffsd_tool();
        assert_eq!(
            tool_channel(&t, "points[1].gamma").unwrap(),
            Value::Scalar(0.5)
        );
        set_tool_channel(&mut t, "points[1].gamma", &Value::Scalar(-0.25)).unwrap();
        set_tool_channel(&mut t, "points[0].position", &Value::Vector(Vec3::ONE)).unwrap();
        let Tool::Ffsd(f) = &t else { panic!() };
        assert_eq!(f.points[1].gamma, -0.25);
        assert_eq!(f.points[0].position, Vec3::ONE);
        // Unknown paths and wrong kinds are refused and change nothing.
        let before = t.clone();
        let e = set_tool_channel(&mut t, "points[7].gamma", &Value::Scalar(1.0)).unwrap_err();
        assert!(e.to_string().contains("points[7].gamma"), "{e}");
        let e = set_tool_channel(&mut t, "gain", &Value::Vector(Vec3::X)).unwrap_err();
        assert!(e.to_string().contains("a number"), "{e}");
        assert!(tool_channel(&t, "points[0]").is_err());
        assert_eq!(t, before);
    }

    #[test]
    fn a_path_prefix_is_not_a_channel() {
        // "points[1]" must not match "points[10].gamma" and friends.
        let mut t = ffsd_tool();
        if let Tool::Ffsd(f) = &mut t {
            let p = f.points[0];
            f.points.resize(12, p);
        }
        set_tool_channel(&mut t, "points[10].gamma", &Value::Scalar(9.0)).unwrap();
        let Tool::Ffsd(f) = &t else { panic!() };
        assert_eq!(f.points[1].gamma, 0.5);
        assert_eq!(f.points[10].gamma, 9.0);
    }

    #[test]
    fn sketch_channels_include_the_target_as_a_plane_curve() {
        let t = Tool::Sketch(Box::new(SketchTool {
            partition: None,
            reference: Curve::Points(vec![Vec3::ZERO, Vec3::X]),
            normal: Some(Vec3::new(0.0, 0.0, 2.0)),
            mode: SketchMode::Bend {
                target: Curve::Points(vec![Vec3::ZERO, Vec3::Y]),
                turning: Some(SplineControl::identity(4, 3)),
            },
            scale: Some(SplineControl::constant(1.0)),
            smooth: true,
            refine: None,
        }));
        let channels = tool_channels(&t);
        let paths: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(
            paths,
            ["mode.target", "mode.turning.values", "scale.values"]
        );
        assert_eq!(
            channels[0].1,
            Value::PlaneCurve {
                points: vec![Vec3::ZERO, Vec3::Y],
                normal: Vec3::Z
            }
        );
    }

    #[test]
    fn curve_and_shape_channels() {
        let c = Tool::Curve(CurveTool {
            basis: CurveBasis::Bezier,
            rest: vec![Vec3::ZERO, Vec3::X],
            deformed: vec![Vec3::ZERO, Vec3::Y],
        });
        assert_eq!(
            tool_channel(&c, "deformed").unwrap(),
            Value::Polyline(vec![Vec3::ZERO, Vec3::Y])
        );
        let mut s = Shape::Capsule {
            radius: 1.0,
            half_height: 2.0,
        };
        let paths: Vec<String> = shape_channels(&s).into_iter().map(|c| c.0).collect();
        assert_eq!(paths, ["radius", "half_height"]);
        set_shape_channel(&mut s, "half_height", &Value::Scalar(3.0)).unwrap();
        assert_eq!(
            s,
            Shape::Capsule {
                radius: 1.0,
                half_height: 3.0
            }
        );
        assert!(set_shape_channel(&mut s, "half_extents", &Value::Vector(Vec3::ONE)).is_err());
    }
}
