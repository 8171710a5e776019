//! The stack panel: the layers of the mesh in focus, bottom first — enable, solo, weight,
//! drag a layer onto another to reorder, duplicate, remove; clicking a layer selects it (the
//! inspector then shows its influence) and its tool.

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::{InfluenceSpec, LayerSpec, NodeKind};

use super::PanelContext;

/// The stack panel.
#[derive(Debug, Default)]
pub struct StackPanel {
    add_tool: String,
}

/// What a dragged layer carries: its mesh and index.
#[derive(Debug, Clone, PartialEq)]
struct DraggedLayer(String, usize);

/// What a layer's row shows: its mesh, its index and spec, and the stack's length (which the
/// move buttons check).
#[derive(Clone, Copy)]
struct Row<'a> {
    mesh: &'a str,
    i: usize,
    layer: &'a LayerSpec,
    count: usize,
}

/// A short description of a layer's influence.
fn influence_summary(inf: Option<&InfluenceSpec>) -> String {
    let Some(inf) = inf else {
        return "all vertices".to_owned();
    };
    let mut parts = Vec::new();
    if let Some(a) = &inf.area {
        parts.push(format!("area {a}"));
    }
    if !inf.volumes.is_empty() {
        parts.push(format!(
            "{} {}",
            if inf.invert { "minus" } else { "in" },
            inf.volumes.join(", ")
        ));
    }
    if parts.is_empty() {
        "all vertices".to_owned()
    } else {
        parts.join(", ")
    }
}

impl StackPanel {
    /// Draws the stack of the mesh in focus.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let Some(mesh_name) = cx.selection.mesh_in_focus(doc) else {
            ui.weak("No mesh in the scene. File > Import mesh… adds one.");
            return;
        };
        let Ok(mesh) = doc.mesh(&mesh_name) else {
            return;
        };
        let soloed = mesh.stack.iter().any(|l| l.solo);
        ui.label(format!(
            "Stack of '{mesh_name}' ({} layers, top last{})",
            mesh.stack.len(),
            if soloed { ", soloed layers only" } else { "" }
        ));
        let count = mesh.stack.len();
        let mut moved: Option<(usize, usize)> = None;
        egui::ScrollArea::vertical()
            .id_salt("stack")
            .max_height(220.0)
            .show(ui, |ui| {
                for (i, layer) in mesh.stack.iter().enumerate() {
                    let frame = egui::Frame::default().inner_margin(1.0);
                    let (_, dropped) = ui.dnd_drop_zone::<DraggedLayer, ()>(frame, |ui| {
                        ui.horizontal(|ui| {
                            let row = Row {
                                mesh: &mesh_name,
                                i,
                                layer,
                                count,
                            };
                            Self::row(ui, cx, row);
                        });
                    });
                    if let Some(d) = dropped
                        && d.0 == mesh_name
                        && d.1 != i
                    {
                        moved = Some((d.1, i));
                    }
                }
            });
        if let Some((from, to)) = moved {
            cx.apply(Operation::move_layer(&mesh_name, from, to));
            if let Some((_, k)) = &mut cx.selection.layer
                && *k == from
            {
                *k = to;
            }
        }
        self.add_layer_row(ui, cx, &mesh_name, count);
    }

    /// One layer's row: drag handle, enabled, solo, name and controls.
    fn row(ui: &mut egui::Ui, cx: &mut PanelContext<'_>, row: Row<'_>) {
        let Row {
            mesh: mesh_name,
            i,
            layer,
            ..
        } = row;
        let doc = cx.doc.shown();
        ui.dnd_drag_source(
            egui::Id::new(("layer-drag", mesh_name, i)),
            DraggedLayer(mesh_name.to_owned(), i),
            |ui| {
                ui.label("☰")
                    .on_hover_text("Drag onto another layer to move it there");
            },
        );
        let mut enabled = layer.enabled;
        if ui
            .checkbox(&mut enabled, "")
            .on_hover_text("Enabled")
            .changed()
            && let Ok(op) = Operation::set_layer_enabled(doc, mesh_name, i, enabled)
        {
            cx.apply(op);
        }
        let solo_text = egui::RichText::new("S").strong();
        if ui
            .selectable_label(layer.solo, solo_text)
            .on_hover_text("Solo: when a layer is soloed, only soloed layers evaluate")
            .clicked()
            && let Ok(op) = Operation::set_layer_solo(doc, mesh_name, i, !layer.solo)
        {
            cx.apply(op);
        }
        // The controls sit at the row's right end, in the same place on every row; the
        // name takes the space between them and the solo button.
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            Self::controls(ui, cx, row);
            ui.with_layout(egui::Layout::left_to_right(egui::Align::Center), |ui| {
                Self::name(ui, cx, row);
            });
        });
    }

    /// A row's weight, duplicate, move and remove controls, added right to left.
    fn controls(ui: &mut egui::Ui, cx: &mut PanelContext<'_>, row: Row<'_>) {
        let Row {
            mesh: mesh_name,
            i,
            layer,
            count,
        } = row;
        let doc = cx.doc.shown();
        if ui
            .small_button("🗑")
            .on_hover_text("Remove the layer (the tool node stays)")
            .clicked()
            && let Ok(op) = Operation::remove_layer(doc, mesh_name, i)
        {
            cx.apply(op);
            if cx.selection.layer == Some((mesh_name.to_owned(), i)) {
                cx.selection.layer = None;
            }
        }
        if ui
            .add_enabled(i + 1 < count, egui::Button::new("⏶").small())
            .on_hover_text("Move up")
            .clicked()
        {
            cx.apply(Operation::move_layer(mesh_name, i, i + 1));
        }
        if ui
            .add_enabled(i > 0, egui::Button::new("⏷").small())
            .on_hover_text("Move down")
            .clicked()
        {
            cx.apply(Operation::move_layer(mesh_name, i, i - 1));
        }
        if ui
            .small_button("📋")
            .on_hover_text("Duplicate the layer and its tool")
            .clicked()
            && let Ok((op, copy)) = Operation::duplicate_layer(doc, mesh_name, i)
        {
            cx.apply(op);
            cx.selection.layer = Some((mesh_name.to_owned(), i + 1));
            cx.selection.select(Some(copy));
        }
        let mut weight = layer.weight;
        let r = ui.add(
            egui::DragValue::new(&mut weight)
                .range(0.0..=1.0)
                .speed(0.005)
                .prefix("w "),
        );
        if r.changed()
            && let Ok(op) = Operation::set_layer_weight(doc, mesh_name, i, weight)
        {
            let label = format!("weight of layer {i} of '{mesh_name}'");
            cx.apply_in_gesture(&r, op, label);
        }
    }

    /// A row's layer name, selecting the layer and its tool when clicked.
    fn name(ui: &mut egui::Ui, cx: &mut PanelContext<'_>, row: Row<'_>) {
        let Row {
            mesh: mesh_name,
            i,
            layer,
            ..
        } = row;
        let selected = cx.selection.layer == Some((mesh_name.to_owned(), i));
        // The name fills what the controls leave, cut short with "…" when it does
        // not fit (the full name and the influence on hover).
        let label = ui
            .add(egui::Button::selectable(selected, &layer.tool).truncate())
            .on_hover_text(format!(
                "{}: {}",
                layer.tool,
                influence_summary(layer.influence.as_ref())
            ));
        if label.clicked() {
            cx.selection.layer = Some((mesh_name.to_owned(), i));
            cx.selection.select(Some(layer.tool.clone()));
        }
    }

    /// Adds a layer for any tool node.
    fn add_layer_row(
        &mut self,
        ui: &mut egui::Ui,
        cx: &mut PanelContext<'_>,
        mesh_name: &str,
        count: usize,
    ) {
        let doc = cx.doc.shown();
        let Ok(mesh) = doc.mesh(mesh_name) else {
            return;
        };
        let tools: Vec<&str> = doc
            .nodes
            .iter()
            .filter(|n| n.kind.is_tool())
            .map(|n| n.name.as_str())
            .collect();
        if tools.is_empty() {
            return;
        }
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
                    spec.influence = Some(InfluenceSpec {
                        area: Some(area.clone()),
                        ..Default::default()
                    });
                }
                cx.apply(Operation::add_layer(mesh_name, count, spec));
            }
        });
    }
}
