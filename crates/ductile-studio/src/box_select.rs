//! Box select (B over the viewport, as in Blender): the next left-button drag draws a
//! rectangle, and on release the handles of the selected node inside it become the selected
//! handles (with Shift held at the release, they are added to the selection). Escape or B
//! again cancels. Selected handles move together when one of them is dragged, as one undo
//! step, so a box followed by a drag is a group edit.

use std::collections::BTreeSet;

use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use ductile_bevy::prelude::*;
use ductile_scene::handles::HandleId;

use crate::camera::{KeyboardToViewport, OrbitCamera, PointerOverViewport};

/// The box selection in progress.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq)]
pub struct BoxSelect {
    /// B was pressed: the next left-button drag over the viewport draws the box.
    pub armed: bool,
    /// The corner where the drag started and the pointer's position now (window pixels).
    pub corners: Option<(Vec2, Vec2)>,
}

impl BoxSelect {
    /// The rectangle drawn so far (window pixels, top-left origin), if a drag is under way.
    #[must_use]
    pub fn rect(&self) -> Option<Rect> {
        self.corners.map(|(a, b)| Rect::from_corners(a, b))
    }

    /// The hint shown over the viewport while armed.
    #[must_use]
    pub fn hint(&self) -> Option<&'static str> {
        self.armed.then_some(
            "Box select: drag a rectangle over the handles (Shift at release adds); Esc cancels",
        )
    }
}

/// The handles whose screen positions lie in `rect` (edges included).
#[must_use]
pub fn handles_in_rect(
    handles: impl IntoIterator<Item = (HandleId, Vec2)>,
    rect: Rect,
) -> BTreeSet<HandleId> {
    handles
        .into_iter()
        .filter(|(_, p)| rect.contains(*p))
        .map(|(id, _)| id)
        .collect()
}

/// Arms, draws and applies the box (see the module documentation). Runs after the
/// shortcuts, so the Escape that cancels a box does not also clear the selection.
#[allow(clippy::too_many_arguments)]
pub fn box_select(
    keys: Res<ButtonInput<KeyCode>>,
    buttons: Res<ButtonInput<MouseButton>>,
    keyboard: Res<KeyboardToViewport>,
    over: Res<PointerOverViewport>,
    sketch: Res<crate::sketch::SketchState>,
    windows: Query<&Window, With<PrimaryWindow>>,
    cameras: Query<(&Camera, &GlobalTransform), With<OrbitCamera>>,
    handles: Query<(&HandleMarker, &GlobalTransform)>,
    mut drag: ResMut<DragState>,
    mut selection: ResMut<Selection>,
    mut state: ResMut<BoxSelect>,
) {
    let cursor = windows.single().ok().and_then(Window::cursor_position);
    if keyboard.0 && drag.active.is_none() && state.corners.is_none() {
        if keys.just_pressed(KeyCode::KeyB) && over.0 && !sketch.active() {
            state.armed = !state.armed;
        } else if keys.just_pressed(KeyCode::Escape) {
            state.armed = false;
        }
    }
    if sketch.active() {
        *state = BoxSelect::default();
    }
    if state.armed
        && state.corners.is_none()
        && buttons.just_pressed(MouseButton::Left)
        && over.0
        && let Some(at) = cursor
    {
        state.corners = Some((at, at));
    }
    if let (Some((from, _)), Some(at)) = (state.corners, cursor) {
        state.corners = Some((from, at));
    }
    if state.corners.is_some() && !buttons.pressed(MouseButton::Left) {
        let rect = state.rect();
        *state = BoxSelect::default();
        if let (Some(rect), Some(node), Ok((camera, at))) =
            (rect, selection.node.clone(), cameras.single())
        {
            let inside = handles_in_rect(
                handles
                    .iter()
                    .filter(|(m, _)| m.node == node)
                    .filter_map(|(m, t)| {
                        let p = camera.world_to_viewport(at, t.translation()).ok()?;
                        Some((m.id, p))
                    }),
                rect,
            );
            let shift = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight])
                || keys.any_just_released([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
            if !shift {
                selection.handles.clear();
            }
            selection.handles.extend(inside);
        }
    }
    let blocked = state.armed || state.corners.is_some();
    if drag.blocked != blocked {
        drag.blocked = blocked;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_handles_inside_the_box_are_picked() {
        let points = [
            (HandleId::Origin, Vec2::new(5.0, 5.0)),
            (HandleId::Lattice(0, 0, 0), Vec2::new(10.0, 10.0)),
            (HandleId::Lattice(1, 0, 0), Vec2::new(20.0, 30.0)),
            (HandleId::Lattice(2, 0, 0), Vec2::new(40.0, 15.0)),
        ];
        // Dragged from bottom right to top left: the corners' order does not matter.
        let rect = Rect::from_corners(Vec2::new(25.0, 31.0), Vec2::new(10.0, 8.0));
        let picked = handles_in_rect(points, rect);
        assert_eq!(
            picked,
            BTreeSet::from([HandleId::Lattice(0, 0, 0), HandleId::Lattice(1, 0, 0)])
        );
        assert!(handles_in_rect(points, Rect::from_corners(Vec2::ZERO, Vec2::ONE)).is_empty());
    }

    #[test]
    fn the_hint_shows_only_while_armed() {
        let mut b = BoxSelect::default();
        assert!(b.hint().is_none() && b.rect().is_none());
        b.armed = true;
        b.corners = Some((Vec2::new(3.0, 9.0), Vec2::new(1.0, 2.0)));
        assert!(b.hint().is_some());
        assert_eq!(
            b.rect(),
            Some(Rect::new(1.0, 2.0, 3.0, 9.0)),
            "a box from any corner is the same rectangle"
        );
    }
}
