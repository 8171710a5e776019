//! Where a dragged handle goes: the pointer ray against a plane facing the camera, or
//! against one world axis through the handle's start, with optional increment snapping.
//!
//! Pure functions of the ray and the drag's start, tested without a window.

use bevy::math::{Dir3, Ray3d, Vec3};

/// The axis constraint of a drag (toggled with the X, Y and Z keys during the drag).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AxisConstraint {
    /// Move in the plane through the start point facing the camera.
    #[default]
    Free,
    /// Move along the world X axis through the start point.
    X,
    /// Move along the world Y axis through the start point.
    Y,
    /// Move along the world Z axis through the start point.
    Z,
}

impl AxisConstraint {
    /// The world axis, if constrained.
    #[must_use]
    pub fn axis(self) -> Option<Vec3> {
        match self {
            AxisConstraint::Free => None,
            AxisConstraint::X => Some(Vec3::X),
            AxisConstraint::Y => Some(Vec3::Y),
            AxisConstraint::Z => Some(Vec3::Z),
        }
    }

    /// Pressing the key of `axis` again frees the drag; another axis key switches to it.
    #[must_use]
    pub fn toggled(self, axis: AxisConstraint) -> AxisConstraint {
        if self == axis {
            AxisConstraint::Free
        } else {
            axis
        }
    }

    /// Name for the status bar.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            AxisConstraint::Free => "free",
            AxisConstraint::X => "X",
            AxisConstraint::Y => "Y",
            AxisConstraint::Z => "Z",
        }
    }
}

/// The dragged point for pointer ray `ray`, for a drag that started at world point `start`
/// with the camera looking along `view` (its forward direction).
///
/// - Free: the ray's intersection with the plane through `start` with normal `view`.
/// - Axis: the point of the line `start + s·axis` closest to the ray (the usual
///   closest-points-of-two-lines solution; `None` when the ray is nearly parallel to the
///   axis, where the closest point is ill-defined).
///
/// With `snap = Some(step)` (`step` > 0, world units) the displacement from `start` is
/// rounded to whole increments of `step` per world axis; snapping is by increments rather
/// than to an absolute grid so that a point of an organic mesh keeps its offset. Returns
/// `None` when the ray misses the plane (parallel, or the plane is behind the camera).
#[must_use]
pub fn drag_target(
    ray: Ray3d,
    start: Vec3,
    view: Dir3,
    constraint: AxisConstraint,
    snap: Option<f32>,
) -> Option<Vec3> {
    let target = match constraint.axis() {
        None => {
            let denom = ray.direction.dot(*view);
            if denom.abs() < 1e-6 {
                return None;
            }
            let t = (start - ray.origin).dot(*view) / denom;
            if t < 0.0 {
                return None;
            }
            ray.origin + *ray.direction * t
        }
        Some(axis) => {
            // Lines p = start + s·a and q = o + t·d; minimise |p − q|².
            let d = *ray.direction;
            let w = start - ray.origin;
            let b = axis.dot(d);
            let denom = 1.0 - b * b;
            if denom < 1e-4 {
                return None;
            }
            let s = (b * w.dot(d) - w.dot(axis)) / denom;
            start + axis * s
        }
    };
    if !target.is_finite() {
        return None;
    }
    Some(match snap {
        Some(step) if step > 0.0 && step.is_finite() => {
            start + ((target - start) / step).round() * step
        }
        _ => target,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(origin: Vec3, towards: Vec3) -> Ray3d {
        Ray3d::new(origin, Dir3::new(towards - origin).unwrap())
    }

    #[test]
    fn free_drag_stays_in_the_view_plane() {
        // Camera on +Z looking at −Z; start at the origin: the plane is z = 0.
        let r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 2.0, 0.0));
        let p = drag_target(r, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::Free, None).unwrap();
        assert!((p - Vec3::new(1.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn axis_drag_moves_only_along_the_axis() {
        let r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 2.0, 0.0));
        // Closest points of the X axis and the ray o = (0,0,5), d = (1,2,−5)/√30:
        // b = a·d = 1/√30, w = −o, w·d = 25/√30, w·a = 0, s = b(w·d)/(1 − b²) = 25/29.
        let p = drag_target(r, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::X, None).unwrap();
        assert!(
            (p - Vec3::new(25.0 / 29.0, 0.0, 0.0)).length() < 1e-5,
            "{p}"
        );
        // Y axis: b = 2/√30, s = (50/30)/(26/30) = 25/13.
        let p = drag_target(r, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::Y, None).unwrap();
        assert!(
            (p - Vec3::new(0.0, 25.0 / 13.0, 0.0)).length() < 1e-5,
            "{p}"
        );
        // A ray along the Z axis: no well-defined point.
        let down = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
        assert!(drag_target(down, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::Z, None).is_none());
    }

    #[test]
    fn snapping_rounds_the_displacement_to_increments() {
        let start = Vec3::new(0.013, 0.0, 0.0);
        let r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.26, 0.11, 0.0));
        let p = drag_target(r, start, Dir3::NEG_Z, AxisConstraint::Free, Some(0.1)).unwrap();
        assert!((p - Vec3::new(0.213, 0.1, 0.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn plane_behind_the_camera_or_parallel_gives_none() {
        let r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 10.0));
        assert!(drag_target(r, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::Free, None).is_none());
        let r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 0.0, 5.0));
        assert!(drag_target(r, Vec3::ZERO, Dir3::NEG_Z, AxisConstraint::Free, None).is_none());
    }

    #[test]
    fn toggling_an_axis_twice_frees_the_drag() {
        let c = AxisConstraint::Free.toggled(AxisConstraint::X);
        assert_eq!(c, AxisConstraint::X);
        assert_eq!(c.toggled(AxisConstraint::Y), AxisConstraint::Y);
        assert_eq!(c.toggled(AxisConstraint::X), AxisConstraint::Free);
    }
}
