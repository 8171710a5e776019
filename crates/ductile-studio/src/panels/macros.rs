//! The identikit panel: one slider per macro tool, grouped by the macro's group.

use std::collections::BTreeMap;

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;

use super::{KeyState, PanelContext};

/// The macros panel.
#[derive(Debug, Default)]
pub struct MacrosPanel {
    filter: String,
}

/// One slider: the macro node's name, the macro's label, its value and its range.
type MacroRow<'a> = (&'a str, &'a str, f32, (f32, f32));

impl MacrosPanel {
    /// Draws the sliders.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let mut groups: BTreeMap<&str, Vec<MacroRow<'_>>> = BTreeMap::new();
        for node in &doc.nodes {
            if let NodeKind::Macro(m) = &node.kind {
                let (label, group, range) = match doc.macros.get(&m.name) {
                    Some(def) => (def.label.as_str(), def.group.as_str(), def.range),
                    None => (m.name.as_str(), "Unknown macro", (-1.0, 1.0)),
                };
                groups
                    .entry(group)
                    .or_default()
                    .push((node.name.as_str(), label, m.value, range));
            }
        }
        if groups.is_empty() {
            ui.weak("No macro tools in this scene.");
            return;
        }
        ui.horizontal(|ui| {
            ui.label("Filter");
            ui.text_edit_singleline(&mut self.filter);
            if ui.button("Reset all").clicked() {
                let ops: Vec<Operation> = groups
                    .values()
                    .flatten()
                    .filter(|(_, _, v, _)| *v != 0.0)
                    .filter_map(|(n, _, _, _)| Operation::set_macro_value(doc, n, 0.0).ok())
                    .collect();
                if !ops.is_empty() {
                    cx.apply(Operation::Group {
                        label: "reset every macro".to_owned(),
                        ops,
                    });
                }
            }
        });
        let filter = self.filter.to_lowercase();
        egui::ScrollArea::vertical()
            .id_salt("macros")
            .show(ui, |ui| {
                for (group, items) in &groups {
                    let visible: Vec<_> = items
                        .iter()
                        .filter(|(n, l, _, _)| {
                            filter.is_empty()
                                || l.to_lowercase().contains(&filter)
                                || n.to_lowercase().contains(&filter)
                                || group.to_lowercase().contains(&filter)
                        })
                        .collect();
                    if visible.is_empty() {
                        continue;
                    }
                    egui::CollapsingHeader::new(if group.is_empty() { "Macros" } else { group })
                        .default_open(true)
                        .show(ui, |ui| {
                            for (node, label, value, range) in visible {
                                let mut v = *value;
                                let mut text = egui::RichText::new(*label);
                                if let Some(c) = KeyState::of(cx.doc, node, "value").color() {
                                    text = text.color(c);
                                }
                                let r = ui.add(
                                    egui::Slider::new(&mut v, range.0..=range.1)
                                        .text(text)
                                        .fixed_decimals(2),
                                );
                                // Selected on release, not on press: the inspector above
                                // grows when a macro is selected, and the slider must not
                                // move under the pointer while it is dragged.
                                if r.clicked() || r.drag_stopped() {
                                    cx.selection.node = Some((*node).to_owned());
                                }
                                if r.changed()
                                    && let Ok(op) = Operation::set_macro_value(doc, node, v)
                                {
                                    cx.apply_in_gesture(&r, op, format!("macro '{node}'"));
                                }
                            }
                        });
                }
            });
    }
}
