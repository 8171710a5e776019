//! The history panel: every step, the current one highlighted; click to jump.

use bevy_egui::egui;
use ductile_bevy::prelude::*;

use super::PanelContext;

/// The history panel.
#[derive(Debug, Default)]
pub struct HistoryPanel;

impl HistoryPanel {
    /// Draws the steps.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let history = cx.doc.history();
        let cursor = history.cursor();
        egui::ScrollArea::vertical()
            .id_salt("history")
            .stick_to_bottom(true)
            .show(ui, |ui| {
                if ui.selectable_label(cursor == 0, "(opened)").clicked() && cursor != 0 {
                    cx.commands.push(DocumentCommand::Jump(0));
                }
                for (i, entry) in history.entries().iter().enumerate() {
                    let step = i + 1;
                    let text = if step > cursor {
                        egui::RichText::new(&entry.label).weak()
                    } else {
                        egui::RichText::new(&entry.label)
                    };
                    if ui.selectable_label(step == cursor, text).clicked() && step != cursor {
                        cx.commands.push(DocumentCommand::Jump(step));
                    }
                }
            });
    }
}
