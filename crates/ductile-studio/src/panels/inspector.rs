//! The inspector: the selected node's name, transform and kind-specific values.

use bevy::math::{EulerRot, Quat, Vec3};
use bevy_egui::egui;
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;
use ductile_scene::transform::Transform;

use super::PanelContext;

/// The inspector panel.
#[derive(Debug, Default)]
pub struct Inspector {
    rename: Option<(String, String)>,
}

fn tool_summary(tool: &Tool) -> String {
    let json = format!("{tool:?}");
    let kind = json.split('(').next().unwrap_or("tool").to_owned();
    match tool {
        Tool::Ffsd(t) => format!("FFSD, {} control points, gain {}", t.points.len(), t.gain),
        _ => kind,
    }
}

impl Inspector {
    /// Draws the selected node's properties.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.document();
        let Some(name) = cx.selection.node.clone() else {
            ui.weak("Select a node in the outliner, a handle in the viewport or a macro slider.");
            return;
        };
        let Ok(node) = doc.node(&name) else {
            cx.selection.node = None;
            return;
        };
        // Name (rename on Enter or focus loss).
        let (editing_for, text) = self
            .rename
            .get_or_insert_with(|| (name.clone(), name.clone()));
        if *editing_for != name {
            *editing_for = name.clone();
            *text = name.clone();
        }
        ui.horizontal(|ui| {
            ui.label("Name");
            let r = ui.text_edit_singleline(text);
            if r.lost_focus() && *text != name && !text.trim().is_empty() {
                let new = text.trim().to_owned();
                cx.apply(Operation::rename(&name, &new));
                cx.selection.node = Some(new);
            }
        });
        ui.label(format!("Kind: {}", node.kind.name()));
        if let Some(parent) = &node.parent {
            ui.label(format!("Parent: {parent}"));
        }
        ui.separator();
        self.transform(ui, cx, &name, node.transform);
        ui.separator();
        match &node.kind {
            NodeKind::Macro(m) => {
                let (label, range) = doc
                    .macros
                    .get(&m.name)
                    .map_or((m.name.as_str(), (-1.0, 1.0)), |d| {
                        (d.label.as_str(), d.range)
                    });
                ui.label(format!("Macro '{}' ({label})", m.name));
                let mut v = m.value;
                let r = ui.add(egui::Slider::new(&mut v, range.0..=range.1).text("value"));
                if r.changed()
                    && let Ok(op) = Operation::set_macro_value(doc, &name, v)
                {
                    cx.apply_in_gesture(&r, op, format!("macro '{name}'"));
                }
            }
            NodeKind::Tool(tool) => {
                ui.label(tool_summary(tool));
                if let Tool::Ffsd(f) = tool {
                    for (i, p) in f.points.iter().enumerate() {
                        ui.horizontal(|ui| {
                            ui.label(format!("point {i}"));
                            let mut q = *p;
                            let a = ui
                                .add(egui::DragValue::new(&mut q.gamma).speed(0.005).prefix("γ "));
                            let b = ui.add(
                                egui::DragValue::new(&mut q.alpha)
                                    .range(0.05..=8.0)
                                    .speed(0.01)
                                    .prefix("α "),
                            );
                            let c = ui.add(
                                egui::DragValue::new(&mut q.epsilon)
                                    .range(1e-4..=100.0)
                                    .speed(0.001)
                                    .prefix("ε "),
                            );
                            for r in [a, b, c] {
                                if r.changed() {
                                    let mut t = f.clone();
                                    t.points[i] = q;
                                    if let Ok(op) = Operation::set_tool(doc, &name, Tool::Ffsd(t)) {
                                        cx.apply_in_gesture(&r, op, format!("edit '{name}'"));
                                    }
                                }
                            }
                        });
                    }
                }
                ui.weak("Drag the handles in the viewport (X/Y/Z constrain, Ctrl snaps).");
            }
            NodeKind::Volume(v) => {
                let mut shape = v.shape;
                let changed = match &mut shape {
                    Shape::Sphere { radius } => ui
                        .add(
                            egui::DragValue::new(radius)
                                .range(1e-4..=1e4)
                                .speed(0.001)
                                .prefix("radius "),
                        )
                        .changed(),
                    Shape::Box { half_extents } => vec3_edit(ui, half_extents, "half "),
                    Shape::Capsule {
                        half_height,
                        radius,
                    } => {
                        let a = ui
                            .add(
                                egui::DragValue::new(half_height)
                                    .range(0.0..=1e4)
                                    .speed(0.001)
                                    .prefix("half length "),
                            )
                            .changed();
                        let b = ui
                            .add(
                                egui::DragValue::new(radius)
                                    .range(1e-4..=1e4)
                                    .speed(0.001)
                                    .prefix("radius "),
                            )
                            .changed();
                        a || b
                    }
                };
                if changed && let Ok(op) = Operation::set_volume(doc, &name, shape) {
                    cx.apply(op);
                }
            }
            NodeKind::Mesh(m) => {
                ui.label(format!("Source: {}", m.source));
                ui.label(format!("{} layers, {} areas", m.stack.len(), m.areas.len()));
            }
            NodeKind::Group => {
                ui.label("A group: its transform places its children.");
            }
        }
    }

    fn transform(
        &mut self,
        ui: &mut egui::Ui,
        cx: &mut PanelContext<'_>,
        name: &str,
        t: Transform,
    ) {
        let doc = cx.doc.document();
        let mut new = t;
        let mut responses = Vec::new();
        ui.label("Transform (parent frame)");
        ui.horizontal(|ui| {
            ui.label("Move");
            for (v, axis) in [
                (&mut new.translation.x, "x "),
                (&mut new.translation.y, "y "),
                (&mut new.translation.z, "z "),
            ] {
                responses.push(ui.add(egui::DragValue::new(v).speed(0.001).prefix(axis)));
            }
        });
        let (mut ry, mut rx, mut rz) = t.rotation.to_euler(EulerRot::YXZ);
        ui.horizontal(|ui| {
            ui.label("Turn°");
            for (v, axis) in [(&mut rx, "x "), (&mut ry, "y "), (&mut rz, "z ")] {
                let mut deg = v.to_degrees() + 0.0; // + 0.0 shows -0 as 0.
                let r = ui.add(egui::DragValue::new(&mut deg).speed(0.5).prefix(axis));
                *v = deg.to_radians();
                responses.push(r);
            }
        });
        let mut uniform = (t.scale.x + t.scale.y + t.scale.z) / 3.0;
        ui.horizontal(|ui| {
            ui.label("Scale");
            let r = ui.add(
                egui::DragValue::new(&mut uniform)
                    .range(1e-3..=1e3)
                    .speed(0.005),
            );
            if r.changed() {
                new.scale = Vec3::splat(uniform);
            }
            responses.push(r);
        });
        new.rotation = Quat::from_euler(EulerRot::YXZ, ry, rx, rz);
        if let Some(r) = responses.iter().find(|r| r.changed())
            && new != t
            && let Ok(op) = Operation::set_transform(doc, name, new)
        {
            cx.apply_in_gesture(r, op, format!("move '{name}'"));
        }
    }
}

fn vec3_edit(ui: &mut egui::Ui, v: &mut Vec3, prefix: &str) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        for (c, axis) in [(&mut v.x, "x"), (&mut v.y, "y"), (&mut v.z, "z")] {
            changed |= ui
                .add(
                    egui::DragValue::new(c)
                        .range(1e-4..=1e4)
                        .speed(0.001)
                        .prefix(format!("{prefix}{axis} ")),
                )
                .changed();
        }
    });
    changed
}
