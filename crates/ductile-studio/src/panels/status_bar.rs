//! The status bar: vertices, triangles, last evaluation time, frame time, drag constraint
//! and the last error.

use bevy_egui::egui;

/// What the status bar shows, gathered by the UI system.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct StatusInfo {
    /// Vertices drawn (stored vertices of every mesh).
    pub vertices: usize,
    /// Triangles drawn.
    pub triangles: usize,
    /// The last stack evaluation: mesh, milliseconds, layers evaluated, background.
    pub evaluation: Option<(String, f64, usize, bool)>,
    /// Smoothed frame time in milliseconds.
    pub frame_ms: Option<f64>,
    /// The drag's axis constraint, while dragging.
    pub drag: Option<&'static str>,
    /// True while a background evaluation runs.
    pub evaluating: bool,
    /// The last error to show.
    pub error: Option<String>,
    /// The file shown in the title.
    pub file: String,
    /// Unsaved changes.
    pub modified: bool,
    /// A background export: what it writes and the fraction done.
    pub export: Option<(String, f32)>,
}

/// The status bar panel.
#[derive(Debug, Default)]
pub struct StatusBar;

impl StatusBar {
    /// Draws the bar.
    pub fn show(&mut self, ui: &mut egui::Ui, info: &StatusInfo) {
        ui.horizontal(|ui| {
            ui.label(format!(
                "{}{}",
                info.file,
                if info.modified { " •" } else { "" }
            ));
            ui.separator();
            ui.label(format!("{} vertices", info.vertices));
            ui.separator();
            ui.label(format!("{} triangles", info.triangles));
            ui.separator();
            match &info.evaluation {
                Some((mesh, ms, layers, background)) => ui.label(format!(
                    "eval '{mesh}': {ms:.2} ms ({layers} layers{})",
                    if *background { ", background" } else { "" }
                )),
                None => ui.label("eval: –"),
            };
            if info.evaluating {
                ui.spinner();
            }
            ui.separator();
            match info.frame_ms {
                Some(ms) => ui.label(format!("frame {ms:.1} ms")),
                None => ui.label("frame –"),
            };
            if let Some(axis) = info.drag {
                ui.separator();
                ui.label(format!("drag: {axis} (X/Y/Z constrain, Ctrl snaps)"));
            }
            if let Some((what, done)) = &info.export {
                ui.separator();
                ui.add(
                    egui::ProgressBar::new(*done)
                        .desired_width(160.0)
                        .show_percentage()
                        .text(what.as_str()),
                );
            }
            if let Some(e) = &info.error {
                ui.separator();
                ui.colored_label(egui::Color32::from_rgb(230, 90, 70), e);
            }
        });
    }
}
