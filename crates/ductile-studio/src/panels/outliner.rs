//! The outliner: every node as a tree by parent, click to select.

use bevy_egui::egui;
use ductile_scene::document::{Document, NodeKind};

use super::PanelContext;

/// The outliner panel.
#[derive(Debug, Default)]
pub struct Outliner;

fn icon(kind: &NodeKind) -> &'static str {
    match kind {
        NodeKind::Mesh(_) => "▣",
        NodeKind::Tool(_) => "✚",
        NodeKind::Macro(_) => "◆",
        NodeKind::Volume(_) => "◯",
        NodeKind::Group => "▤",
    }
}

impl Outliner {
    /// Draws the tree.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.document();
        egui::ScrollArea::vertical()
            .id_salt("outliner")
            .max_height(ui.available_height() * 0.45)
            .show(ui, |ui| {
                for node in doc.nodes.iter().filter(|n| n.parent.is_none()) {
                    self.node(ui, doc, &node.name, cx, 0);
                }
            });
    }

    fn node(
        &mut self,
        ui: &mut egui::Ui,
        doc: &Document,
        name: &str,
        cx: &mut PanelContext<'_>,
        depth: usize,
    ) {
        let Ok(node) = doc.node(name) else { return };
        // Macro nodes are many (the identikit has one per slider): the Macros panel lists
        // them; here they show only as a count under their parent.
        let children = doc.children(name);
        let macros = children
            .iter()
            .filter(|c| matches!(c.kind, NodeKind::Macro(_)))
            .count();
        ui.horizontal(|ui| {
            ui.add_space(depth as f32 * 12.0);
            let selected = cx.selection.is_selected(name);
            let text = format!("{} {name}", icon(&node.kind));
            if ui.selectable_label(selected, text).clicked() {
                cx.selection.node = Some(name.to_owned());
                if let NodeKind::Mesh(_) = node.kind {
                    cx.selection.layer = None;
                }
            }
            if macros > 0 {
                ui.weak(format!("+{macros} macros"));
            }
        });
        if depth > 32 {
            return; // a cycle; the document check reports it
        }
        for child in children {
            if !matches!(child.kind, NodeKind::Macro(_)) || cx.selection.is_selected(&child.name) {
                let child_name = child.name.clone();
                self.node(ui, doc, &child_name, cx, depth + 1);
            }
        }
    }
}
