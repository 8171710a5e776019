//! The outliner: every node as a tree by parent, with an icon per kind. Click selects;
//! double-click or F2 renames in place (Enter applies, Escape cancels); the eye hides a node
//! in the viewport; 🗑 deletes it with everything that refers to it; dragging a node onto
//! another makes it its child (onto "scene" makes it a root); a filter keeps the nodes whose
//! name contains the text (and their ancestors).

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, NodeKind};

use super::PanelContext;

/// The outliner panel.
#[derive(Debug, Default)]
pub struct Outliner {
    filter: String,
    /// The node being renamed and the text typed so far.
    renaming: Option<(String, String)>,
}

/// What a dragged outliner row carries: the node's name.
#[derive(Debug, Clone, PartialEq)]
struct DraggedNode(String);

/// The icon of a node kind (glyphs of egui's default proportional fonts only).
#[must_use]
pub fn icon(kind: &NodeKind) -> &'static str {
    match kind {
        NodeKind::Mesh(_) => "▣",
        NodeKind::Tool(t) => match t {
            ductile_core::tool::Tool::Ffsd(_) => "✚",
            ductile_core::tool::Tool::Sketch(_) => "✏",
            ductile_core::tool::Tool::Axial(_) => "➰",
            ductile_core::tool::Tool::Curve(_) => "〰",
            ductile_core::tool::Tool::Lattice(_) => "⊞",
            ductile_core::tool::Tool::DirectFfd(_) => "⛶",
            ductile_core::tool::Tool::Dogme(_) => "🔘",
            ductile_core::tool::Tool::ShapeSurface(_) => "◼",
        },
        NodeKind::Macro(_) => "♦",
        NodeKind::Volume(_) => "⚪",
        NodeKind::Group => "🗀",
    }
}

impl Outliner {
    /// True when `name` or one of its descendants matches the filter.
    fn visible(&self, doc: &Document, name: &str, depth: usize) -> bool {
        if self.filter.is_empty() {
            return true;
        }
        let needle = self.filter.to_lowercase();
        if name.to_lowercase().contains(&needle) {
            return true;
        }
        depth < 64
            && doc
                .children(name)
                .iter()
                .any(|c| self.visible(doc, &c.name, depth + 1))
    }

    /// Draws the tree.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.filter)
                    .hint_text("filter by name")
                    .desired_width(140.0),
            );
            if ui
                .button("+ group")
                .on_hover_text("A new empty group under the selected node")
                .clicked()
            {
                let parent = cx.selection.node.clone().filter(|n| doc.node(n).is_ok());
                if let Ok((op, name)) = Operation::add_group(doc, parent.as_deref(), "group") {
                    cx.apply(op);
                    cx.selection.select(Some(name));
                }
            }
        });
        // Dropping on the scene row makes a node a root; it says so while a node is dragged.
        let dragging = egui::DragAndDrop::has_payload_of_type::<DraggedNode>(ui.ctx());
        let (_, dropped) = ui.dnd_drop_zone::<DraggedNode, ()>(egui::Frame::default(), |ui| {
            ui.weak(if dragging {
                "scene (drop here to unparent)"
            } else {
                "scene"
            });
        });
        if let Some(d) = dropped
            && let Ok(op) = Operation::reparent(doc, &d.0, None)
        {
            cx.apply(op);
        }
        if ui.input(|i| i.key_pressed(egui::Key::F2))
            && !ui.ctx().text_edit_focused()
            && let Some(n) = &cx.selection.node
        {
            self.renaming = Some((n.clone(), n.clone()));
        }
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
        if !self.visible(doc, name, 0) {
            return;
        }
        // Macro nodes are many (the identikit has one per slider): the Identikit panel lists
        // them; here they show only as a count under their parent.
        let children = doc.children(name);
        let macros = children
            .iter()
            .filter(|c| matches!(c.kind, NodeKind::Macro(_)))
            .count();
        let frame = egui::Frame::default();
        let (_, dropped) = ui.dnd_drop_zone::<DraggedNode, ()>(frame, |ui| {
            ui.horizontal(|ui| {
                ui.add_space(depth as f32 * 12.0);
                let hidden = cx.selection.is_hidden(name);
                if ui
                    .selectable_label(!hidden, "👁")
                    .on_hover_text(if hidden {
                        "Show in the viewport"
                    } else {
                        "Hide in the viewport"
                    })
                    .clicked()
                {
                    if hidden {
                        cx.selection.hidden.remove(name);
                    } else {
                        cx.selection.hidden.insert(name.to_owned());
                    }
                }
                let renaming_this = self.renaming.as_ref().is_some_and(|(n, _)| n == name);
                if renaming_this {
                    let mut done = None;
                    if let Some((_, text)) = &mut self.renaming {
                        let r = ui.add(egui::TextEdit::singleline(text).desired_width(120.0));
                        r.request_focus();
                        if ui.input(|i| i.key_pressed(egui::Key::Escape)) {
                            done = Some(None);
                        } else if r.lost_focus() || ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                            done = Some(Some(text.trim().to_owned()));
                        }
                    }
                    if let Some(result) = done {
                        self.renaming = None;
                        if let Some(new) = result.filter(|n| !n.is_empty() && n != name) {
                            cx.apply(Operation::rename(name, &new));
                            if cx.selection.is_selected(name) {
                                cx.selection.select(Some(new));
                            }
                        }
                    }
                } else {
                    let selected = cx.selection.is_selected(name);
                    let text = format!("{} {name}", icon(&node.kind));
                    // One widget senses both: a click selects, a drag carries the node
                    // (a drag source laid over the label would swallow quick clicks).
                    let r = ui.add(
                        egui::Button::selectable(selected, text)
                            .sense(egui::Sense::click_and_drag()),
                    );
                    r.dnd_set_drag_payload(DraggedNode(name.to_owned()));
                    if r.dragged() {
                        egui::containers::Tooltip::for_widget(&r)
                            .at_pointer()
                            .show(|ui| ui.label(format!("{} {name}", icon(&node.kind))));
                    }
                    if r.clicked() {
                        cx.selection.select(Some(name.to_owned()));
                        if let NodeKind::Mesh(_) = node.kind {
                            cx.selection.layer = None;
                        }
                    }
                    if r.double_clicked() {
                        self.renaming = Some((name.to_owned(), name.to_owned()));
                    }
                }
                if macros > 0 {
                    ui.weak(format!("+{macros} macros"));
                }
                if ui
                    .small_button("🗑")
                    .on_hover_text("Delete (with its children, layers and references)")
                    .clicked()
                    && let Ok(op) = Operation::remove_node_and_references(doc, name)
                {
                    cx.apply(op);
                    if cx.selection.is_selected(name) {
                        cx.selection.select(None);
                        cx.selection.layer = None;
                    }
                }
            });
        });
        // A refused reparent (onto a descendant: a cycle) is reported in the status bar.
        if let Some(d) = dropped
            && d.0 != name
            && let Ok(op) = Operation::reparent(doc, &d.0, Some(name))
        {
            cx.apply(op);
        }
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
