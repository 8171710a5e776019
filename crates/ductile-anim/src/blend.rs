//! Values as coordinate vectors, so that every in-between is one rule: an affine combination
//! `Σ wᵢ cᵢ` of coordinates (`Σ wᵢ = 1`), decoded back to a value.
//!
//! * numbers, vectors and spline values are their own coordinates;
//! * a rotation is the rotation vector of `q_base⁻¹ qᵢ` (each quaternion's sign chosen
//!   nearest the previous one, so consecutive values are joined by the short path); between
//!   two rotations this is a slerp;
//! * curves use the skeleton coordinates of [`crate::skeleton`].
//!
//! Keyframe interpolation ([`crate::key`]) and variant blending both use it, so an
//! in-between of two keys and a 50/50 blend of two variants are the same thing.

use ductile_core::axial::AxisPoint;
use glam::{Quat, Vec3};

use crate::channel::same_direction;
use crate::skeleton::{
    PlaneFrame, SpaceFrame, plane_coords, plane_points, space_coords, space_len, space_points,
};
use crate::value::Value;

/// How coordinates decode back to a value.
#[derive(Debug, Clone, PartialEq)]
enum Frame {
    Scalar,
    Vector,
    Rotation(Quat),
    Values,
    /// The frame and the values' normal (as given, not normalised).
    Plane(PlaneFrame, Vec3),
    Space(SpaceFrame),
    Axis(SpaceFrame, usize),
}

/// Coordinates of a set of values of one kind, in one shared frame (see the module
/// documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Encoded {
    frame: Frame,
    coords: Vec<Vec<f32>>,
}

/// Encodes `values` jointly, the frame taken from `values[base]`. `None` when the values
/// cannot be interpolated: different kinds, different counts of spline values or 3-D curve
/// points, different sketch-plane normals, degenerate curves.
#[must_use]
pub fn encode(values: &[&Value], base: usize) -> Option<Encoded> {
    let first = *values.get(base)?;
    if values.iter().any(|v| v.kind() != first.kind()) {
        return None;
    }
    let (frame, coords) = match first {
        Value::Scalar(_) => (
            Frame::Scalar,
            values
                .iter()
                .map(|v| match v {
                    Value::Scalar(x) => vec![*x],
                    _ => Vec::new(),
                })
                .collect(),
        ),
        Value::Vector(_) => (
            Frame::Vector,
            values
                .iter()
                .map(|v| match v {
                    Value::Vector(x) => x.to_array().to_vec(),
                    _ => Vec::new(),
                })
                .collect(),
        ),
        Value::Rotation(_) => {
            let mut reps: Vec<Quat> = Vec::with_capacity(values.len());
            for v in values {
                let Value::Rotation(q) = v else { return None };
                let len = q.length();
                if !(len > 0.0 && len.is_finite()) {
                    return None;
                }
                let q = *q / len;
                let q = match reps.last() {
                    Some(p) if p.dot(q) < 0.0 => -q,
                    _ => q,
                };
                reps.push(q);
            }
            let b = reps[base];
            let coords = reps
                .iter()
                .map(|q| (b.inverse() * *q).to_scaled_axis().to_array().to_vec())
                .collect();
            (Frame::Rotation(b), coords)
        }
        Value::Values(first) => {
            let mut coords = Vec::with_capacity(values.len());
            for v in values {
                match v {
                    Value::Values(x) if x.len() == first.len() => coords.push(x.clone()),
                    _ => return None,
                }
            }
            (Frame::Values, coords)
        }
        Value::Polyline(_) => {
            let curves: Vec<&[Vec3]> = values
                .iter()
                .filter_map(|v| match v {
                    Value::Polyline(p) => Some(p.as_slice()),
                    _ => None,
                })
                .collect();
            let (frame, coords) = space_coords(&curves, base)?;
            (Frame::Space(frame), coords)
        }
        Value::Axis(first) => {
            let n = first.len();
            let mut positions: Vec<Vec<Vec3>> = Vec::with_capacity(values.len());
            for v in values {
                match v {
                    Value::Axis(a) if a.len() == n => {
                        positions.push(a.iter().map(|p| p.position).collect());
                    }
                    _ => return None,
                }
            }
            let curves: Vec<&[Vec3]> = positions.iter().map(Vec::as_slice).collect();
            let (frame, mut coords) = space_coords(&curves, base)?;
            for (c, v) in coords.iter_mut().zip(values) {
                if let Value::Axis(a) = v {
                    c.extend(a.iter().flat_map(|p| [p.twist, p.scale]));
                }
            }
            (Frame::Axis(frame, n), coords)
        }
        Value::PlaneCurve { normal, .. } => {
            let mut curves: Vec<&[Vec3]> = Vec::with_capacity(values.len());
            for v in values {
                match v {
                    Value::PlaneCurve { points, normal: n } if same_direction(*n, *normal) => {
                        curves.push(points);
                    }
                    _ => return None,
                }
            }
            let (frame, coords) = plane_coords(&curves, *normal, base)?;
            (Frame::Plane(frame, *normal), coords)
        }
    };
    Some(Encoded { frame, coords })
}

impl Encoded {
    /// The coordinate vector of each encoded value, in the order given.
    #[must_use]
    pub fn coords(&self) -> &[Vec<f32>] {
        &self.coords
    }

    /// The value whose coordinates are `c` (a combination of [`Encoded::coords`]).
    #[must_use]
    pub fn decode(&self, c: &[f32]) -> Value {
        match &self.frame {
            Frame::Scalar => Value::Scalar(c[0]),
            Frame::Vector => Value::Vector(Vec3::new(c[0], c[1], c[2])),
            Frame::Rotation(b) => Value::Rotation(
                (*b * Quat::from_scaled_axis(Vec3::new(c[0], c[1], c[2]))).normalize(),
            ),
            Frame::Values => Value::Values(c.to_vec()),
            Frame::Plane(frame, normal) => Value::PlaneCurve {
                points: plane_points(frame, c),
                normal: *normal,
            },
            Frame::Space(frame) => Value::Polyline(space_points(frame, c)),
            Frame::Axis(frame, n) => {
                let split = space_len(*n);
                let positions = space_points(frame, &c[..split]);
                Value::Axis(
                    positions
                        .into_iter()
                        .zip(c[split..].chunks_exact(2))
                        .map(|(position, ts)| AxisPoint {
                            position,
                            twist: ts[0],
                            scale: ts[1],
                        })
                        .collect(),
                )
            }
        }
    }
}

/// The affine combination `Σ wᵢ vᵢ` of `values` in their coordinates (see the module
/// documentation); the weights should sum to 1 (outside `[0, 1]` they extrapolate). A
/// value whose weight is exactly 1 while every other weight is 0 is returned as it is, bit
/// for bit. `None` when the values cannot be interpolated ([`encode`]) or the lengths of
/// `values` and `weights` differ.
#[must_use]
pub fn combine(values: &[&Value], weights: &[f32]) -> Option<Value> {
    if values.is_empty() || values.len() != weights.len() {
        return None;
    }
    if let Some(k) = weights.iter().position(|&w| w == 1.0)
        && weights.iter().enumerate().all(|(i, &w)| i == k || w == 0.0)
    {
        return values
            .iter()
            .all(|v| v.kind() == values[k].kind())
            .then(|| values[k].clone());
    }
    let encoded = encode(values, 0)?;
    let len = encoded.coords[0].len();
    if encoded.coords.iter().any(|c| c.len() != len) {
        return None;
    }
    let mut out = vec![0.0_f32; len];
    for (c, &w) in encoded.coords.iter().zip(weights) {
        for (o, x) in out.iter_mut().zip(c) {
            *o += w * x;
        }
    }
    Some(encoded.decode(&out))
}

#[cfg(test)]
mod tests {
    use std::f32::consts::FRAC_PI_2;

    use super::*;

    #[test]
    fn numbers_blend_as_affine_combinations() {
        let a = Value::Scalar(1.0);
        let b = Value::Scalar(3.0);
        assert_eq!(combine(&[&a, &b], &[0.75, 0.25]), Some(Value::Scalar(1.5)));
        // Extrapolation: t = 1.5.
        assert_eq!(combine(&[&a, &b], &[-0.5, 1.5]), Some(Value::Scalar(4.0)));
    }

    #[test]
    fn a_full_weight_returns_the_value_bit_for_bit() {
        let a = Value::PlaneCurve {
            points: vec![
                Vec3::ZERO,
                Vec3::new(0.3, 0.1, 0.0),
                Vec3::new(0.7, 0.2, 0.0),
            ],
            normal: Vec3::Z,
        };
        let b = Value::PlaneCurve {
            points: vec![Vec3::ZERO, Vec3::new(0.1, 0.6, 0.0)],
            normal: Vec3::Z,
        };
        assert_eq!(combine(&[&a, &b], &[1.0, 0.0]), Some(a.clone()));
        assert_eq!(combine(&[&a, &b], &[0.0, 1.0]), Some(b));
    }

    #[test]
    fn rotations_blend_by_slerp_on_the_short_path() {
        let a = Quat::from_rotation_z(0.1);
        // −q is the same rotation: the blend must not go the long way round.
        let b = -Quat::from_rotation_z(0.1 + FRAC_PI_2);
        let Some(Value::Rotation(m)) =
            combine(&[&Value::Rotation(a), &Value::Rotation(b)], &[0.5, 0.5])
        else {
            panic!("a rotation")
        };
        let expect = a.slerp(b, 0.5);
        assert!(m.angle_between(expect) < 1e-5, "{m} vs {expect}");
        assert!((m.angle_between(a) - FRAC_PI_2 / 2.0).abs() < 1e-5);
    }

    #[test]
    fn different_structures_do_not_blend() {
        let a = Value::Values(vec![0.0, 1.0]);
        let b = Value::Values(vec![0.0, 0.5, 1.0]);
        assert!(combine(&[&a, &b], &[0.5, 0.5]).is_none());
        assert!(combine(&[&a, &Value::Scalar(1.0)], &[0.5, 0.5]).is_none());
        let p = |n: Vec3| Value::PlaneCurve {
            points: vec![Vec3::ZERO, Vec3::X],
            normal: n,
        };
        assert!(combine(&[&p(Vec3::Z), &p(Vec3::Y)], &[0.5, 0.5]).is_none());
    }

    #[test]
    fn axes_blend_positions_skeleton_style_and_twist_linearly() {
        let point = |position: Vec3, twist: f32, scale: f32| AxisPoint {
            position,
            twist,
            scale,
        };
        let a = Value::Axis(vec![
            point(Vec3::ZERO, 0.0, 1.0),
            point(Vec3::X, 0.0, 1.0),
            point(Vec3::new(2.0, 0.0, 0.0), 0.0, 1.0),
        ]);
        let b = Value::Axis(vec![
            point(Vec3::ZERO, 0.0, 1.0),
            point(Vec3::X, 0.5, 2.0),
            point(Vec3::new(1.0, 1.0, 0.0), 1.0, 1.0),
        ]);
        let Some(Value::Axis(m)) = combine(&[&a, &b], &[0.5, 0.5]) else {
            panic!("an axis")
        };
        assert!((m[1].position.distance(m[2].position) - 1.0).abs() < 1e-6);
        assert!((m[1].twist - 0.25).abs() < 1e-6 && (m[1].scale - 1.5).abs() < 1e-6);
        assert!((m[2].twist - 0.5).abs() < 1e-6);
    }

    #[test]
    fn plane_curves_keep_their_normal() {
        let a = Value::PlaneCurve {
            points: vec![Vec3::ZERO, Vec3::X],
            normal: Vec3::new(0.0, 0.0, 2.0),
        };
        let b = Value::PlaneCurve {
            points: vec![Vec3::ZERO, Vec3::Y],
            normal: Vec3::new(0.0, 0.0, 2.0),
        };
        let Some(Value::PlaneCurve { normal, points }) = combine(&[&a, &b], &[0.5, 0.5]) else {
            panic!("a plane curve")
        };
        // The stored normal is the values', not the normalised one.
        assert_eq!(normal, Vec3::new(0.0, 0.0, 2.0));
        assert!((points[1].length() - 1.0).abs() < 1e-6);
    }
}
