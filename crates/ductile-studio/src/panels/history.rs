//! The history panel: every step (a row-virtualised list, so 10,000-step histories scroll
//! smoothly), the current one highlighted, click to jump; and playback — play, pause and
//! step through the history at a chosen speed, as a reviewer replays a colleague's edits.

use bevy_egui::egui;
use ductile_bevy::prelude::*;

use super::PanelContext;

/// The history panel.
#[derive(Debug)]
pub struct HistoryPanel {
    /// Steps per second while playing.
    pub speed: f64,
    /// When playing: the time of the last step taken.
    playing_since: Option<f64>,
}

impl Default for HistoryPanel {
    fn default() -> Self {
        Self {
            speed: 2.0,
            playing_since: None,
        }
    }
}

impl HistoryPanel {
    /// True while the history plays.
    #[must_use]
    pub fn is_playing(&self) -> bool {
        self.playing_since.is_some()
    }

    /// Draws the controls and the steps.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let history = cx.doc.history();
        let cursor = history.cursor();
        let len = history.len();
        ui.horizontal(|ui| {
            if ui
                .add_enabled(cursor > 0, egui::Button::new("⏮").small())
                .on_hover_text("Back to the opened state")
                .clicked()
            {
                cx.commands.push(DocumentCommand::Jump(0));
                self.playing_since = None;
            }
            if ui
                .add_enabled(cursor > 0, egui::Button::new("◀").small())
                .on_hover_text("One step back")
                .clicked()
            {
                cx.commands.push(DocumentCommand::Jump(cursor - 1));
            }
            let playing = self.is_playing();
            if ui
                .add_enabled(
                    playing || cursor < len,
                    egui::Button::new(if playing { "⏸" } else { "▶" }).small(),
                )
                .on_hover_text(if playing {
                    "Pause"
                } else {
                    "Play the steps from here"
                })
                .clicked()
            {
                self.playing_since = if playing { None } else { Some(cx.now) };
            }
            if ui
                .add_enabled(cursor < len, egui::Button::new("⏭").small())
                .on_hover_text("One step forward")
                .clicked()
            {
                cx.commands.push(DocumentCommand::Jump(cursor + 1));
            }
            ui.add(
                egui::DragValue::new(&mut self.speed)
                    .range(0.25..=60.0)
                    .speed(0.05)
                    .suffix(" steps/s"),
            );
            ui.weak(format!("{cursor}/{len}"));
        });
        // Playback: one step every 1/speed seconds until the end.
        if let Some(since) = self.playing_since {
            if cursor >= len {
                self.playing_since = None;
            } else if cx.now - since >= 1.0 / self.speed {
                cx.commands.push(DocumentCommand::Jump(cursor + 1));
                self.playing_since = Some(cx.now);
            }
            ui.ctx().request_repaint();
        }
        let total = len + 1;
        let row = ui.spacing().interact_size.y;
        egui::ScrollArea::vertical()
            .id_salt("history")
            .auto_shrink([false, true])
            .max_height(ui.available_height().max(row * 4.0))
            .show_rows(ui, row, total, |ui, rows| {
                for row in rows {
                    let (text, step) = if row == 0 {
                        (egui::RichText::new("(opened)"), 0)
                    } else {
                        let entry = &history.entries()[row - 1];
                        let t = if row > cursor {
                            egui::RichText::new(&entry.label).weak()
                        } else {
                            egui::RichText::new(&entry.label)
                        };
                        (t, row)
                    };
                    if ui.selectable_label(step == cursor, text).clicked() && step != cursor {
                        cx.commands.push(DocumentCommand::Jump(step));
                        self.playing_since = None;
                    }
                }
            });
    }
}
