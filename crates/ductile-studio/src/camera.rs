//! The viewport camera: orbit, pan and zoom around a focus point, with mouse and trackpad,
//! and frame-selected (F).
//!
//! Mouse: left-drag on empty space or middle-drag orbits, Shift + those (or right-drag) pans,
//! the wheel zooms. Trackpad: two-finger scroll orbits (Shift: pans), pinch zooms.

use bevy::input::gestures::PinchGesture;
use bevy::input::mouse::{MouseScrollUnit, MouseWheel};
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use ductile_bevy::prelude::*;

/// An orbiting camera: it looks at `focus` from `distance` away, at `yaw` around +Y and
/// `pitch` above the horizon (radians).
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// The point looked at (world).
    pub focus: Vec3,
    /// Rotation around the world Y axis.
    pub yaw: f32,
    /// Elevation above the XZ plane, kept inside (−π/2, π/2).
    pub pitch: f32,
    /// Distance from the focus.
    pub distance: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            focus: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            distance: 1.0,
        }
    }
}

impl OrbitCamera {
    /// The camera transform for this orbit.
    #[must_use]
    pub fn transform(&self) -> Transform {
        let rotation = Quat::from_euler(EulerRot::YXZ, self.yaw, -self.pitch, 0.0);
        let eye = self.focus + rotation * Vec3::Z * self.distance;
        Transform::from_translation(eye).looking_at(self.focus, Vec3::Y)
    }

    /// Frames a box: looks at its centre, keeping the direction, from just far enough that
    /// all eight corners are inside the view (vertical field of view `fov` in radians,
    /// `aspect` = width / height), with a 5% margin. A corner `p` (relative to the centre) at
    /// depth `d + p·f` is inside when `|p·r| ≤ (d + p·f)·tan(h/2)` and `|p·u| ≤ (d + p·f)·
    /// tan(v/2)`, with `tan(h/2) = tan(v/2)·aspect`; the distance is the largest `d` any
    /// corner asks for.
    pub fn frame(&mut self, min: Vec3, max: Vec3, fov: f32, aspect: f32) {
        self.focus = (min + max) * 0.5;
        let t = self.transform();
        let (right, up, forward) = (*t.right(), *t.up(), *t.forward());
        let tan_v = (fov * 0.5).tan() * 0.95;
        let tan_h = tan_v
            * if aspect.is_finite() && aspect > 0.0 {
                aspect
            } else {
                1.0
            };
        let mut distance = 1e-3_f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            );
            let p = corner - self.focus;
            let depth = p.dot(forward);
            distance = distance
                .max(p.dot(right).abs() / tan_h - depth)
                .max(p.dot(up).abs() / tan_v - depth)
                .max(1e-3 - depth);
        }
        self.distance = distance;
    }
}

/// Whether the pointer is over the 3-D viewport (not over a panel, menu or dialog); set at
/// the start of each frame from that frame's pointer position ([`crate::pointer`]).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct PointerOverViewport(pub bool);

/// Whether the keyboard belongs to the viewport (no text field has focus); set by the UI.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct KeyboardToViewport(pub bool);

/// Orbits, pans and zooms from mouse buttons, wheel and trackpad gestures. Drags follow the
/// cursor's position in the window (not raw device motion, which absolute pointers such as
/// tablets, remote desktops and X test input do not always send).
#[allow(clippy::too_many_arguments)]
pub fn orbit_camera(
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    windows: Query<&Window, With<PrimaryWindow>>,
    mut last_cursor: Local<Option<Vec2>>,
    mut wheel: MessageReader<MouseWheel>,
    mut pinch: MessageReader<PinchGesture>,
    over: Res<PointerOverViewport>,
    drag: Res<DragState>,
    hover: Option<Res<bevy::picking::hover::HoverMap>>,
    handles: Query<(), With<HandleMarker>>,
    mut orbiting: Local<bool>,
    sketch: Res<crate::sketch::SketchState>,
    box_select: Res<crate::box_select::BoxSelect>,
    mut cameras: Query<(&mut OrbitCamera, &mut Transform, &Projection)>,
) {
    let Ok((mut orbit, mut transform, projection)) = cameras.single_mut() else {
        return;
    };
    let shift = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    // In sketch mode the left button draws: only the middle and right buttons move the view.
    let any_button: &[MouseButton] = if sketch.active() {
        &[MouseButton::Middle, MouseButton::Right]
    } else {
        &[MouseButton::Left, MouseButton::Middle, MouseButton::Right]
    };
    let any_button = any_button.iter().copied();
    // A gesture starts only over the viewport and not on a handle; it continues until the
    // buttons are released, wherever the pointer goes.
    if buttons.any_just_pressed(any_button.clone()) {
        let on_handle = hover.as_ref().is_some_and(|h| {
            h.values()
                .any(|hits| hits.keys().any(|e| handles.contains(*e)))
        });
        // A box selection owns the left button from B to its release (the middle and right
        // buttons still move the view).
        let boxing = (box_select.armed || box_select.corners.is_some())
            && buttons.just_pressed(MouseButton::Left);
        *orbiting = over.0 && drag.active.is_none() && !on_handle && !boxing;
    }
    if !buttons.any_pressed(any_button) {
        *orbiting = false;
    }
    let fov = vertical_fov(projection);
    let pan_scale = orbit.distance * (fov * 0.5).tan() * 2.0 / 800.0;
    let cursor = windows.single().ok().and_then(Window::cursor_position);
    let delta = match (*last_cursor, cursor) {
        (Some(a), Some(b)) => b - a,
        _ => Vec2::ZERO,
    };
    *last_cursor = cursor;
    if *orbiting && drag.active.is_none() && delta != Vec2::ZERO {
        let pan = buttons.pressed(MouseButton::Right)
            || (shift && buttons.any_pressed([MouseButton::Left, MouseButton::Middle]));
        if pan {
            let right = transform.right();
            let up = transform.up();
            orbit.focus += (-*right * delta.x + *up * delta.y) * pan_scale;
        } else {
            orbit.yaw -= delta.x * 0.008;
            orbit.pitch = (orbit.pitch + delta.y * 0.008).clamp(-1.55, 1.55);
        }
    }
    for w in wheel.read() {
        if !over.0 {
            continue;
        }
        match w.unit {
            MouseScrollUnit::Line => orbit.distance *= 0.9_f32.powf(w.y),
            MouseScrollUnit::Pixel => {
                // Trackpad two-finger scroll: orbit, or pan with Shift.
                if shift {
                    let right = transform.right();
                    let up = transform.up();
                    orbit.focus += (-*right * w.x + *up * w.y) * pan_scale;
                } else {
                    orbit.yaw += w.x * 0.005;
                    orbit.pitch = (orbit.pitch + w.y * 0.005).clamp(-1.55, 1.55);
                }
            }
        }
    }
    for p in pinch.read() {
        if over.0 {
            orbit.distance *= 1.0 - p.0.clamp(-0.5, 0.5);
        }
    }
    orbit.distance = orbit.distance.clamp(1e-3, 1e4);
    let wanted = orbit.transform();
    if *transform != wanted {
        *transform = wanted;
    }
}

/// The vertical field of view of a camera (radians); π/4 for a non-perspective one.
#[must_use]
pub fn vertical_fov(projection: &Projection) -> f32 {
    match projection {
        Projection::Perspective(p) => p.fov,
        _ => std::f32::consts::FRAC_PI_4,
    }
}

/// The width / height of the part of the window a camera draws in (its viewport, else the
/// projection's aspect; 1 when neither is known).
#[must_use]
pub fn view_aspect(projection: &Projection, camera: &Camera) -> f32 {
    let aspect = match (&camera.viewport, projection) {
        (Some(view), _) if view.physical_size.y > 0 => {
            view.physical_size.x as f32 / view.physical_size.y as f32
        }
        (_, Projection::Perspective(p)) => p.aspect_ratio,
        _ => 1.0,
    };
    if aspect.is_finite() && aspect > 0.0 {
        aspect
    } else {
        1.0
    }
}

/// A request from the View menu to frame the selection (as F does).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct FrameRequest(pub bool);

/// F frames the selected node (a mesh's deformed bounds, a tool's or volume's handles), or
/// every mesh when nothing is selected.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn frame_selected(
    keys: Res<ButtonInput<KeyCode>>,
    keyboard: Res<KeyboardToViewport>,
    mut request: ResMut<FrameRequest>,
    selection: Res<Selection>,
    entities: Res<NodeEntities>,
    meshes: Query<(&bevy::camera::primitives::Aabb, &GlobalTransform), With<MeshEvaluation>>,
    handles: Query<(&HandleMarker, &GlobalTransform)>,
    mut cameras: Query<(&mut OrbitCamera, &Projection, &Camera)>,
) {
    let asked = std::mem::take(&mut request.0);
    if !(asked || keyboard.0 && keys.just_pressed(KeyCode::KeyF)) {
        return;
    }
    let Ok((mut orbit, projection, camera)) = cameras.single_mut() else {
        return;
    };
    let fov = vertical_fov(projection);
    if let Some((min, max)) = selection_bounds(&selection, &entities, &meshes, &handles) {
        orbit.frame(min, max, fov, view_aspect(projection, camera));
    }
}

/// The world bounds of what F frames.
#[allow(clippy::type_complexity)]
pub fn selection_bounds(
    selection: &Selection,
    entities: &NodeEntities,
    meshes: &Query<(&bevy::camera::primitives::Aabb, &GlobalTransform), With<MeshEvaluation>>,
    handles: &Query<(&HandleMarker, &GlobalTransform)>,
) -> Option<(Vec3, Vec3)> {
    let mut points: Vec<Vec3> = Vec::new();
    let mut add_mesh = |aabb: &bevy::camera::primitives::Aabb, at: &GlobalTransform| {
        let (c, h) = (Vec3::from(aabb.center), Vec3::from(aabb.half_extents));
        for s in [-1.0, 1.0] {
            for t in [-1.0, 1.0] {
                for u in [-1.0, 1.0] {
                    points.push(at.transform_point(c + h * Vec3::new(s, t, u)));
                }
            }
        }
    };
    match &selection.node {
        Some(name) => {
            if let Some(e) = entities.get(name)
                && let Ok((aabb, at)) = meshes.get(e)
            {
                add_mesh(aabb, at);
            }
            for (marker, at) in handles {
                if &marker.node == name {
                    points.push(at.translation());
                }
            }
        }
        None => {
            for (aabb, at) in meshes {
                add_mesh(aabb, at);
            }
        }
    }
    let first = *points.first()?;
    let (mut min, mut max) = (first, first);
    for p in &points {
        min = min.min(*p);
        max = max.max(*p);
    }
    if min == max {
        // A single point: frame a small box around it.
        min -= Vec3::splat(0.05);
        max += Vec3::splat(0.05);
    }
    Some((min, max))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Framing keeps every corner inside both fields of view and one at the margin.
    #[test]
    fn framing_fits_the_box_in_a_narrow_view() {
        let (min, max) = (Vec3::new(-2.0, -0.5, -1.0), Vec3::new(2.0, 0.5, 1.0));
        for (yaw, pitch, aspect) in [(0.0, 0.0, 0.5), (0.7, 0.3, 1.6), (2.0, -0.4, 1.0)] {
            let mut orbit = OrbitCamera {
                yaw,
                pitch,
                ..OrbitCamera::default()
            };
            let fov = std::f32::consts::FRAC_PI_4;
            orbit.frame(min, max, fov, aspect);
            let t = orbit.transform();
            let (tan_v, mut widest) = ((fov * 0.5).tan(), 0.0_f32);
            for i in 0..8 {
                let c = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let local = t.compute_affine().inverse().transform_point3(c);
                let depth = -local.z;
                assert!(depth > 0.0);
                let x = (local.x / depth) / (tan_v * aspect);
                let y = (local.y / depth) / tan_v;
                assert!(x.abs() <= 0.951 && y.abs() <= 0.951, "{x} {y}");
                widest = widest.max(x.abs()).max(y.abs());
            }
            assert!(widest > 0.94, "tight: {widest}");
        }
    }
}
