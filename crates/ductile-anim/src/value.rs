//! The value of one animatable parameter: what a key stores and what a variant blends.

use ductile_core::axial::AxisPoint;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// The value of an animatable parameter (a *channel*, see [`crate::channel`]).
///
/// Scalars, vectors and points animate as a whole value; rotations by shortest-path slerp;
/// curve-like values skeleton-style (segment lengths and turning angles, see
/// [`crate::skeleton`]), never by moving their points on straight lines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Value {
    /// A number (γ, a radius, a macro value, an angle in radians, …).
    Scalar(f32),
    /// A vector or a point, interpolated as a whole.
    Vector(Vec3),
    /// A rotation (unit quaternion `(x, y, z, w)`), interpolated by shortest-path slerp.
    Rotation(Quat),
    /// The control values of a spline control `F(s)` (sketch tool), interpolated value by
    /// value.
    Values(Vec<f32>),
    /// A 3-D control polygon (curve deformation), interpolated skeleton-style in 3-D:
    /// segment lengths and relative segment rotations in rotation-minimising frames.
    Polyline(Vec<Vec3>),
    /// An axis of the axial deformation: its points skeleton-style in 3-D, twist and scale
    /// per point as numbers.
    Axis(Vec<AxisPoint>),
    /// A curve in a sketch plane (the sketch tool's bend target), interpolated by its total
    /// length and the turning angles of its segments about `normal` (Kho & Garland §6.1).
    PlaneCurve {
        /// The curve's nodes.
        points: Vec<Vec3>,
        /// Unit normal of the sketch plane, the rotation axis of the turning angles.
        normal: Vec3,
    },
}

/// The kinds of [`Value`], for messages and for checking that a key fits its parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueKind {
    /// [`Value::Scalar`].
    Scalar,
    /// [`Value::Vector`].
    Vector,
    /// [`Value::Rotation`].
    Rotation,
    /// [`Value::Values`].
    Values,
    /// [`Value::Polyline`].
    Polyline,
    /// [`Value::Axis`].
    Axis,
    /// [`Value::PlaneCurve`].
    PlaneCurve,
}

impl ValueKind {
    /// The kind's name for messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ValueKind::Scalar => "a number",
            ValueKind::Vector => "a vector",
            ValueKind::Rotation => "a rotation",
            ValueKind::Values => "a list of spline values",
            ValueKind::Polyline => "a 3-D curve",
            ValueKind::Axis => "an axis",
            ValueKind::PlaneCurve => "a plane curve",
        }
    }
}

impl Value {
    /// The value's kind.
    #[must_use]
    pub fn kind(&self) -> ValueKind {
        match self {
            Value::Scalar(_) => ValueKind::Scalar,
            Value::Vector(_) => ValueKind::Vector,
            Value::Rotation(_) => ValueKind::Rotation,
            Value::Values(_) => ValueKind::Values,
            Value::Polyline(_) => ValueKind::Polyline,
            Value::Axis(_) => ValueKind::Axis,
            Value::PlaneCurve { .. } => ValueKind::PlaneCurve,
        }
    }

    /// True when every number of the value is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        match self {
            Value::Scalar(x) => x.is_finite(),
            Value::Vector(v) => v.is_finite(),
            Value::Rotation(q) => q.is_finite(),
            Value::Values(v) => v.iter().all(|x| x.is_finite()),
            Value::Polyline(p) => p.iter().all(|v| v.is_finite()),
            Value::Axis(a) => a
                .iter()
                .all(|p| p.position.is_finite() && p.twist.is_finite() && p.scale.is_finite()),
            Value::PlaneCurve { points, normal } => {
                normal.is_finite() && points.iter().all(|v| v.is_finite())
            }
        }
    }

    /// A short description of the value's shape, for messages: the kind, and the number of
    /// points or values of a list.
    #[must_use]
    pub fn shape(&self) -> String {
        let count = match self {
            Value::Values(v) => Some(v.len()),
            Value::Polyline(p) | Value::PlaneCurve { points: p, .. } => Some(p.len()),
            Value::Axis(a) => Some(a.len()),
            Value::Scalar(_) | Value::Vector(_) | Value::Rotation(_) => None,
        };
        match count {
            Some(n) => format!("{} of {n}", self.kind().name()),
            None => self.kind().name().to_owned(),
        }
    }
}
