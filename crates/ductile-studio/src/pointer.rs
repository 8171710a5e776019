//! Whether the pointer is over the 3-D view, decided at the start of each frame.
//!
//! A press belongs to the view when the pointer was over the view *when it was pressed*. The
//! frame that handles a press is the first that knows where the pointer is, so the answer
//! cannot come from the UI pass of the frame before: under slow frames (a heavy scene, software
//! rendering), a hand that moves into the view and presses at once delivers both in one frame,
//! and the press would be judged at the pointer's old place, outside the view, and lost (the
//! start of a sketch stroke, of an orbit, of a box selection). So [`pointer_over_viewport`]
//! runs before anything reads input: it takes this frame's pointer position and the layout the
//! person saw when they pressed, the last frame's (the view's rectangle and egui's windows,
//! menus and popups on top of it).

use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy_egui::{EguiContexts, egui};

use crate::camera::PointerOverViewport;
use crate::ui::ViewportRect;

/// Sets [`PointerOverViewport`] from the window's pointer position of this frame and the last
/// frame's layout (runs in `PreUpdate`, after bevy_egui has read the window's input).
pub fn pointer_over_viewport(
    windows: Query<&Window, With<PrimaryWindow>>,
    rect: Res<ViewportRect>,
    mut contexts: EguiContexts,
    mut over: ResMut<PointerOverViewport>,
) {
    let cursor = windows.single().ok().and_then(Window::cursor_position);
    let Ok(ctx) = contexts.ctx_mut() else {
        return;
    };
    over.set_if_neq(PointerOverViewport(over_viewport(ctx, rect.0, cursor)));
}

/// Whether `cursor` (logical pixels, which are egui points here) lies in the view's
/// rectangle `rect` and no egui layer above the background (a window, menu or popup of the
/// last pass) covers it.
#[must_use]
fn over_viewport(ctx: &egui::Context, rect: Option<(Vec2, Vec2)>, cursor: Option<Vec2>) -> bool {
    let (Some((min, max)), Some(c)) = (rect, cursor) else {
        return false;
    };
    let inside = c.cmpge(min).all() && c.cmplt(max).all();
    inside
        && ctx
            .layer_id_at(egui::pos2(c.x, c.y))
            .is_none_or(|l| l.order == egui::Order::Background)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two egui passes (a new window is laid out invisibly in its first) with a window at
    /// (100, 100)–(300, 200).
    fn laid_out() -> egui::Context {
        let ctx = egui::Context::default();
        for _ in 0..2 {
            let input = egui::RawInput {
                screen_rect: Some(egui::Rect::from_min_size(
                    egui::Pos2::ZERO,
                    egui::vec2(800.0, 600.0),
                )),
                ..Default::default()
            };
            let mut output = ctx.run_ui(input, |ui| {
                egui::Window::new("dialog")
                    .fixed_pos(egui::pos2(100.0, 100.0))
                    .fixed_size(egui::vec2(200.0, 100.0))
                    .show(ui.ctx(), |ui| ui.label("on top of the view"));
            });
            // No renderer takes the font texture here.
            output.textures_delta.clear();
        }
        ctx
    }

    #[test]
    fn a_point_of_the_view_not_under_a_window_is_over_the_view() {
        let ctx = laid_out();
        let view = Some((Vec2::new(0.0, 30.0), Vec2::new(600.0, 600.0)));
        assert!(over_viewport(&ctx, view, Some(Vec2::new(400.0, 400.0))));
        assert!(over_viewport(&ctx, view, Some(Vec2::new(0.0, 30.0))));
    }

    #[test]
    fn a_window_a_panel_or_no_pointer_is_not_the_view() {
        let ctx = laid_out();
        let view = Some((Vec2::new(0.0, 30.0), Vec2::new(600.0, 600.0)));
        // Under the window.
        assert!(!over_viewport(&ctx, view, Some(Vec2::new(150.0, 150.0))));
        // Outside the view's rectangle (over a side panel, or above the view).
        assert!(!over_viewport(&ctx, view, Some(Vec2::new(700.0, 400.0))));
        assert!(!over_viewport(&ctx, view, Some(Vec2::new(400.0, 10.0))));
        assert!(!over_viewport(&ctx, view, Some(Vec2::new(600.0, 400.0))));
        // No pointer in the window, or no view.
        assert!(!over_viewport(&ctx, view, None));
        assert!(!over_viewport(&ctx, None, Some(Vec2::new(400.0, 400.0))));
    }
}
