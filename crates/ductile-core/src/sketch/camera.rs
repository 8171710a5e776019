//! A camera model (view, projection, viewport) so that strokes in pixels can be handled
//! without an engine, and tested headless.
//!
//! Pixel coordinates have their origin at the top-left corner of the viewport, x to the
//! right and y down, in pixels; `(0.5, 0.5)` is the centre of the first pixel.

use glam::{Mat4, Vec2, Vec3, Vec4Swizzles};
use serde::{Deserialize, Serialize};

/// Perspective or orthographic projection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Projection {
    /// Perspective with the given vertical field of view in radians.
    Perspective {
        /// Vertical field of view (radians, in (0, π)).
        fov_y: f32,
    },
    /// Orthographic with the given visible height in world units.
    Orthographic {
        /// Visible height (world units, > 0).
        height: f32,
    },
}

/// A ray `origin + t·direction`, `t ≥ 0`, with a unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

/// A look-at camera with a projection and a viewport size in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position (world/mesh space).
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
    /// Near clipping distance (> 0).
    pub near: f32,
    /// Far clipping distance (> near).
    pub far: f32,
    /// Viewport size in pixels `(width, height)`.
    pub viewport: Vec2,
}

impl Camera {
    /// World → view matrix (right-handed, looking down −Z).
    #[must_use]
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye, self.target, self.up)
    }

    /// View → clip matrix (OpenGL-style depth in [−1, 1]).
    #[must_use]
    pub fn projection_matrix(&self) -> Mat4 {
        let aspect = self.viewport.x / self.viewport.y;
        match self.projection {
            Projection::Perspective { fov_y } => {
                Mat4::perspective_rh_gl(fov_y, aspect, self.near, self.far)
            }
            Projection::Orthographic { height } => {
                let h = 0.5 * height;
                let w = h * aspect;
                Mat4::orthographic_rh_gl(-w, w, -h, h, self.near, self.far)
            }
        }
    }

    /// Unit view direction (eye towards target).
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize_or_zero()
    }

    /// Projects a world point to pixel coordinates and its view depth (distance along the
    /// view direction). `None` when the point is behind the eye.
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let view = self.view() * p.extend(1.0);
        let depth = -view.z;
        if depth <= 0.0 && matches!(self.projection, Projection::Perspective { .. }) {
            return None;
        }
        let clip = self.projection_matrix() * view;
        let ndc = clip.xy() / clip.w;
        Some((
            Vec2::new(
                (ndc.x + 1.0) * 0.5 * self.viewport.x,
                (1.0 - ndc.y) * 0.5 * self.viewport.y,
            ),
            depth,
        ))
    }

    /// The ray through pixel `px` (from the eye for perspective, from the near plane's
    /// parallel through the pixel for orthographic).
    #[must_use]
    pub fn ray(&self, px: Vec2) -> Ray {
        let ndc = Vec2::new(
            2.0 * px.x / self.viewport.x - 1.0,
            1.0 - 2.0 * px.y / self.viewport.y,
        );
        let inv = (self.projection_matrix() * self.view()).inverse();
        let near = inv.project_point3(ndc.extend(-1.0));
        let far = inv.project_point3(ndc.extend(1.0));
        Ray {
            origin: near,
            direction: (far - near).normalize_or_zero(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(projection: Projection) -> Camera {
        Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection,
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(800.0, 600.0),
        }
    }

    #[test]
    fn centre_projects_to_viewport_centre_and_rays_round_trip() {
        for proj in [
            Projection::Perspective { fov_y: 0.8 },
            Projection::Orthographic { height: 4.0 },
        ] {
            let c = cam(proj);
            let (px, depth) = c.project(Vec3::ZERO).unwrap();
            assert!((px - Vec2::new(400.0, 300.0)).length() < 1e-3);
            assert!((depth - 5.0).abs() < 1e-4);
            let p = Vec3::new(0.7, -0.4, 1.0);
            let (px, _) = c.project(p).unwrap();
            let ray = c.ray(px);
            let t = (p - ray.origin).dot(ray.direction);
            assert!(
                (ray.origin + ray.direction * t - p).length() < 1e-3,
                "{proj:?}"
            );
            // y grows downwards in pixels.
            assert!(px.y > 300.0);
        }
    }
}
