//! The identikit panel: one slider per macro tool, grouped by the macro's group; a filter,
//! "Reset all", a **Symmetric** toggle (a slider of a left/right pair moves its mirror too),
//! "Reset" in each slider's context menu, and a seeded **random face** within a fraction of
//! every slider's range (FaceGen's "random within limits").

use std::collections::BTreeMap;

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;

use super::{KeyState, PanelContext, PanelRequest, hover_channel};

/// The operation that sets every macro tool to a seeded random value within `limit` of its
/// range ([`ductile_scene::document::Document::random_macro_values`]), as one step.
///
/// # Errors
/// `limit` outside `[0, 1]`.
pub fn random_face(
    doc: &ductile_scene::document::Document,
    seed: u64,
    limit: f32,
    symmetric: bool,
) -> Result<Operation, String> {
    let values = doc
        .random_macro_values(seed, limit, symmetric)
        .map_err(|e| e.to_string())?;
    let ops = values
        .iter()
        .filter_map(|(n, v)| Operation::set_macro_value(doc, n, *v).ok())
        .collect();
    Ok(Operation::Group {
        label: format!("random face (seed {seed}, limit {limit})"),
        ops,
    })
}

/// The macros panel.
#[derive(Debug)]
pub struct MacrosPanel {
    filter: String,
    /// Left/right pairs move together.
    pub symmetric: bool,
    /// Seed of the next random face.
    pub seed: u64,
    /// How far into each slider's range a random face may go, in [0, 1].
    pub limit: f32,
}

impl Default for MacrosPanel {
    fn default() -> Self {
        Self {
            filter: String::new(),
            symmetric: false,
            seed: 1,
            limit: 0.5,
        }
    }
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
            ui.add(egui::TextEdit::singleline(&mut self.filter).desired_width(100.0));
            ui.checkbox(&mut self.symmetric, "Symmetric")
                .on_hover_text("A slider of a left/right pair moves its mirror too");
            ui.menu_button("Random face", |ui| {
                ui.horizontal(|ui| {
                    ui.label("seed");
                    ui.add(egui::DragValue::new(&mut self.seed).speed(1.0));
                    ui.label("limit");
                    ui.add(
                        egui::DragValue::new(&mut self.limit)
                            .range(0.0..=1.0)
                            .speed(0.01),
                    )
                    .on_hover_text("How far into each slider's range the face may go");
                });
                if ui.button("Draw").clicked() {
                    match random_face(doc, self.seed, self.limit, self.symmetric) {
                        Ok(op) => {
                            cx.apply(op);
                            self.seed += 1;
                        }
                        Err(e) => cx.requests.push(PanelRequest::Problem(e)),
                    }
                    ui.close();
                }
            });
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
                                if r.hovered() {
                                    hover_channel(ui.ctx(), node, "value");
                                }
                                if r.clicked() || r.drag_stopped() {
                                    cx.selection.node = Some((*node).to_owned());
                                }
                                let set = |v: f32| {
                                    if self.symmetric {
                                        Operation::set_macro_value_symmetric(doc, node, v)
                                    } else {
                                        Operation::set_macro_value(doc, node, v)
                                    }
                                };
                                if r.changed()
                                    && let Ok(op) = set(v)
                                {
                                    cx.apply_in_gesture(&r, op, format!("macro '{node}'"));
                                }
                                let mut reset = false;
                                r.context_menu(|ui| {
                                    if ui.button("Reset to 0").clicked() {
                                        reset = true;
                                        ui.close();
                                    }
                                });
                                if reset
                                    && *value != 0.0
                                    && let Ok(op) = set(0.0)
                                {
                                    cx.apply(op);
                                }
                            }
                        });
                }
            });
    }
}
