//! The inspector: the selected node's name, parent and transform, then its kind's section —
//! every parameter of every tool kind ([`super::tool_editor`]), a volume's shape and sizes, a
//! macro tool's value — and, when a layer is selected, its influence
//! ([`super::influence`]).

use bevy::math::{EulerRot, Quat, Vec3};
use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;
use ductile_scene::transform::Transform;

use super::influence::InfluenceEditor;
use super::tool_editor::ToolEditor;
use super::{KeyState, PanelContext};
use ductile_bevy::prelude::SceneDocument;

/// The inspector panel.
#[derive(Debug, Default)]
pub struct Inspector {
    rename: Option<(String, String)>,
    tool: ToolEditor,
    influence: InfluenceEditor,
}

impl Inspector {
    /// Draws the selected node's properties.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        if let Some((mesh, index)) = cx.selection.layer.clone() {
            self.influence.show_layer(ui, cx, &mesh, index);
            ui.separator();
        }
        let Some(name) = cx.selection.node.clone() else {
            ui.weak("Select a node in the outliner, a handle in the viewport or a macro slider.");
            return;
        };
        let Ok(node) = doc.node(&name) else {
            cx.selection.select(None);
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
                cx.selection.select(Some(new));
            }
        });
        ui.label(format!("Kind: {}", node.kind.name()));
        animated_channels(ui, cx.doc, &name);
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
                self.tool.show(ui, cx, &name, tool);
                ui.weak("Drag the handles in the viewport (X/Y/Z constrain, Ctrl snaps, Shift-click selects several).");
            }
            NodeKind::Volume(v) => {
                self.influence.show_volume(ui, cx, &name, &v.shape);
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
        let doc = cx.doc.shown();
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

/// One line per animated channel of `node`, coloured by its [`KeyState`] at the current
/// frame: an edit of such a field keys it at this frame (see `docs/studio.md`, "Time").
fn animated_channels(ui: &mut egui::Ui, doc: &SceneDocument, node: &str) {
    let Some(tracks) = doc.document().animation.tracks.get(node) else {
        return;
    };
    ui.horizontal_wrapped(|ui| {
        ui.label("Animated:");
        for (path, keys) in tracks {
            let state = KeyState::of(doc, node, path);
            let text = match state {
                KeyState::Keyed => format!("{path} (key here)"),
                _ => format!("{path} ({} keys)", keys.len()),
            };
            let mut rich = egui::RichText::new(text);
            if let Some(c) = state.color() {
                rich = rich.color(c);
            }
            ui.label(rich).on_hover_text(
                "Editing this field sets a key at the current frame (K keys every field)",
            );
        }
    });
}
