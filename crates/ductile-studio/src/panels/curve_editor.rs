//! The F(s) curve editor: a spline control `F(s)` over `s ∈ [0, 1]` (the sketch tool's
//! turning, scale and twist-speed controls, a custom falloff) drawn as a curve with its control
//! values as handles at their Greville abscissae; dragging a handle up or down changes its
//! value (one gesture while the button is held).

use bevy_egui::egui;
use ductile_core::spline::SplineControl;

/// Width and height of the plot in points.
const SIZE: egui::Vec2 = egui::vec2(250.0, 110.0);

/// The s of control value `i` of `n` (degree `p`): the average of the knots it spans, where
/// the value has most influence (exactly where `F(s) = s` puts value `s`).
fn greville(i: usize, n: usize, p: usize) -> f32 {
    let knot = |k: usize| -> f32 {
        // Clamped uniform knots: p + 1 zeros, then n − p − 1 interior, then p + 1 ones.
        if k <= p {
            0.0
        } else if k >= n {
            1.0
        } else {
            (k - p) as f32 / (n - p) as f32
        }
    };
    (1..=p).map(|j| knot(i + j)).sum::<f32>() / p as f32
}

/// Draws the editor for `values` (degree `degree`); `response.changed()` when a value moved.
pub fn curve_editor(
    ui: &mut egui::Ui,
    id: egui::Id,
    values: &mut [f32],
    degree: usize,
) -> egui::Response {
    let (rect, mut response) = ui.allocate_exact_size(SIZE, egui::Sense::hover());
    let n = values.len();
    if n < 2 {
        return response;
    }
    let p = degree.clamp(1, n - 1);
    // The vertical range: the values' range and [0, 1], padded; fixed during a drag so the
    // plot does not rescale under the pointer.
    let range_id = id.with("range");
    let dragging = ui
        .ctx()
        .dragged_id()
        .is_some_and(|d| (0..n).any(|i| id.with(i) == d));
    let (lo, hi) = match ui.ctx().data(|d| d.get_temp::<(f32, f32)>(range_id)) {
        Some(r) if dragging => r,
        _ => {
            let lo = values.iter().copied().fold(0.0_f32, f32::min);
            let hi = values.iter().copied().fold(1.0_f32, f32::max);
            let pad = 0.15 * (hi - lo).max(1e-3);
            (lo - pad, hi + pad)
        }
    };
    ui.ctx().data_mut(|d| d.insert_temp(range_id, (lo, hi)));
    let to_screen = |s: f32, v: f32| {
        egui::pos2(
            rect.left() + s * rect.width(),
            rect.bottom() - (v - lo) / (hi - lo) * rect.height(),
        )
    };
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    for v in [0.0, 1.0] {
        if v > lo && v < hi {
            painter.line_segment(
                [to_screen(0.0, v), to_screen(1.0, v)],
                egui::Stroke::new(0.5, ui.visuals().weak_text_color()),
            );
        }
    }
    let control = SplineControl {
        values: values.to_vec(),
        degree: p,
    };
    let curve: Vec<egui::Pos2> = (0..=64)
        .map(|k| {
            let s = k as f32 / 64.0;
            to_screen(s, control.eval(s))
        })
        .collect();
    painter.add(egui::Shape::line(
        curve,
        egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 200, 60)),
    ));
    for (i, v) in values.iter_mut().enumerate() {
        let s = greville(i, n, p);
        let at = to_screen(s, *v);
        let handle_id = id.with(i);
        let r = ui.interact(
            egui::Rect::from_center_size(at, egui::vec2(12.0, 12.0)),
            handle_id,
            egui::Sense::drag(),
        );
        if r.dragged() {
            let dy = r.drag_delta().y;
            if dy != 0.0 {
                *v -= dy / rect.height() * (hi - lo);
                response.mark_changed();
            }
            response = response.union(r.clone());
        }
        if r.drag_started() || r.drag_stopped() {
            response = response.union(r.clone());
        }
        let color = if r.hovered() || r.dragged() {
            egui::Color32::WHITE
        } else {
            egui::Color32::from_rgb(255, 140, 40)
        };
        painter.circle_filled(at, 4.0, color);
        r.on_hover_text(format!("c{i} = {v:.3} at s = {s:.2}"));
    }
    response
}

/// The most control values a spline control gets from the Studio.
pub const MAX_VALUES: usize = 32;

/// The structure of spline control `f` beside its editor: how many control values (− / +)
/// and the degree. A change resamples `F(s)` at the new control values' abscissae
/// ([`SplineControl::resampled`]): a linear `F` is kept exactly, another keeps its shape.
/// Returns true when `f` changed; `drag` gets the degree field's response when a drag of
/// it changed `f` (a drag is one undo step).
pub fn spline_structure(
    ui: &mut egui::Ui,
    f: &mut SplineControl,
    drag: &mut Option<egui::Response>,
) -> bool {
    let n = f.values.len();
    let mut count = n;
    let shown = f.degree.clamp(1, n.saturating_sub(1).max(1));
    let mut degree = shown;
    ui.horizontal(|ui| {
        ui.label(format!("{n} values"));
        if ui
            .add_enabled(n > 2, egui::Button::new("−").small())
            .on_hover_text("one control value less (F(s) resampled)")
            .clicked()
        {
            count = n - 1;
        }
        if ui
            .add_enabled(n < MAX_VALUES, egui::Button::new("+").small())
            .on_hover_text("one control value more (F(s) resampled)")
            .clicked()
        {
            count = n + 1;
        }
        let r = ui
            .add(
                egui::DragValue::new(&mut degree)
                    .range(1..=n.saturating_sub(1).clamp(1, 15))
                    .speed(0.05)
                    .prefix("degree "),
            )
            .on_hover_text("the degree of F(s): 1 (piecewise linear) to values − 1");
        if degree != shown {
            *drag = Some(r);
        }
    });
    if count == n && degree == shown {
        return false;
    }
    *f = f.resampled(count, degree);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greville_abscissae_reproduce_the_identity() {
        // Values at the Greville abscissae make F(s) = s (what SplineControl::identity does).
        let id = SplineControl::identity(6, 3);
        for (i, &v) in id.values.iter().enumerate() {
            assert!((greville(i, 6, 3) - v).abs() < 1e-6, "{i}");
        }
        assert_eq!(greville(0, 2, 1), 0.0);
        assert_eq!(greville(1, 2, 1), 1.0);
    }
}
