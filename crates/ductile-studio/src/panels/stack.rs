//! The stack panel: the layers of the selected mesh (or of the mesh whose layer is
//! selected), bottom first, with enable, weight, order and removal.

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::{LayerSpec, NodeKind};

use super::PanelContext;

/// The stack panel.
#[derive(Debug, Default)]
pub struct StackPanel {
    add_tool: String,
}

impl StackPanel {
    /// Draws the stack of the mesh in focus.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.document();
        let mesh_name = match (&cx.selection.layer, &cx.selection.node) {
            (Some((m, _)), _) => Some(m.clone()),
            (None, Some(n)) if matches!(doc.node(n).map(|n| &n.kind), Ok(NodeKind::Mesh(_))) => {
                Some(n.clone())
            }
            _ => doc.mesh_names().first().map(|s| (*s).to_owned()),
        };
        let Some(mesh_name) = mesh_name else {
            ui.weak("No mesh in the scene. File ▸ Import mesh… adds one.");
            return;
        };
        let Ok(mesh) = doc.mesh(&mesh_name) else {
            return;
        };
        ui.label(format!(
            "Stack of '{mesh_name}' ({} layers, top last)",
            mesh.stack.len()
        ));
        let count = mesh.stack.len();
        egui::ScrollArea::vertical()
            .id_salt("stack")
            .max_height(220.0)
            .show(ui, |ui| {
                for (i, layer) in mesh.stack.iter().enumerate() {
                    ui.horizontal(|ui| {
                        let mut enabled = layer.enabled;
                        if ui
                            .checkbox(&mut enabled, "")
                            .on_hover_text("Enabled")
                            .changed()
                            && let Ok(op) =
                                Operation::set_layer_enabled(doc, &mesh_name, i, enabled)
                        {
                            cx.apply(op);
                        }
                        let selected = cx.selection.layer == Some((mesh_name.clone(), i));
                        if ui.selectable_label(selected, &layer.tool).clicked() {
                            cx.selection.layer = Some((mesh_name.clone(), i));
                            cx.selection.node = Some(layer.tool.clone());
                        }
                        let mut weight = layer.weight;
                        let r = ui.add(
                            egui::DragValue::new(&mut weight)
                                .range(0.0..=1.0)
                                .speed(0.005)
                                .prefix("w "),
                        );
                        if r.changed()
                            && let Ok(op) = Operation::set_layer_weight(doc, &mesh_name, i, weight)
                        {
                            let label = format!("weight of layer {i} of '{mesh_name}'");
                            cx.apply_in_gesture(&r, op, label);
                        }
                        if ui.add_enabled(i > 0, egui::Button::new("down")).clicked() {
                            cx.apply(Operation::move_layer(&mesh_name, i, i - 1));
                        }
                        if ui
                            .add_enabled(i + 1 < count, egui::Button::new("up"))
                            .clicked()
                        {
                            cx.apply(Operation::move_layer(&mesh_name, i, i + 1));
                        }
                        if ui
                            .button("remove")
                            .on_hover_text("Remove the layer")
                            .clicked()
                            && let Ok(op) = Operation::remove_layer(doc, &mesh_name, i)
                        {
                            cx.apply(op);
                            if cx.selection.layer == Some((mesh_name.clone(), i)) {
                                cx.selection.layer = None;
                            }
                        }
                    });
                }
            });
        // Add a layer for any tool node.
        let tools: Vec<&str> = doc
            .nodes
            .iter()
            .filter(|n| n.kind.is_tool())
            .map(|n| n.name.as_str())
            .collect();
        if !tools.is_empty() {
            ui.horizontal(|ui| {
                if !tools.contains(&self.add_tool.as_str()) {
                    self.add_tool = tools[0].to_owned();
                }
                egui::ComboBox::from_id_salt("add-layer-tool")
                    .selected_text(self.add_tool.clone())
                    .show_ui(ui, |ui| {
                        for t in &tools {
                            ui.selectable_value(&mut self.add_tool, (*t).to_owned(), *t);
                        }
                    });
                if ui.button("Add layer").clicked() {
                    let mut spec = LayerSpec::new(self.add_tool.clone());
                    // A macro works in its own area (the paper's area of influence).
                    if let Ok(NodeKind::Macro(m)) = doc.node(&self.add_tool).map(|n| &n.kind)
                        && let Some(def) = doc.macros.get(&m.name)
                        && let Some(area) = &def.area
                        && mesh.areas.contains_key(area)
                    {
                        spec.influence = Some(ductile_scene::document::InfluenceSpec {
                            area: Some(area.clone()),
                            ..Default::default()
                        });
                    }
                    cx.apply(Operation::add_layer(&mesh_name, count, spec));
                }
            });
        }
    }
}
