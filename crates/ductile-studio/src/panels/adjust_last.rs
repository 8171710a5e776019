//! "Adjust last operation" (as in Blender) for a lattice just added: its resolution, basis
//! and degrees, chosen right after Add > Lattice in a small panel at the bottom left of the
//! 3-D view, for as long as the add is the last step. Every change is folded into that step
//! (the Studio adds nodes with a gesture id, and [`Operation::can_merge`] lets a tool edit of
//! the gesture join the step that added the tool), so one Ctrl+Z still removes the lattice
//! whatever resolution it was given.

use bevy_egui::egui;
use ductile_bevy::prelude::*;
use ductile_core::lattice::{LatticeBasis, LatticeTool};
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;

use super::PanelContext;
use super::tool_editor::lattice_structure;

/// The panel (no state of its own: it follows the history's last applied step).
#[derive(Debug, Default)]
pub struct AdjustLast;

/// The lattice the last applied step added, when that step carries a gesture (as the
/// Studio's Add menu makes it): its node name, its current state and the gesture.
#[must_use]
pub fn last_added_lattice(doc: &SceneDocument) -> Option<(String, LatticeTool, u64)> {
    let history = doc.history();
    let entry = history.entries().get(history.cursor().checked_sub(1)?)?;
    let gesture = entry.gesture?;
    let Operation::Group { ops, .. } = &entry.op else {
        return None;
    };
    let Some(Operation::AddNode { node, .. }) = ops.first() else {
        return None;
    };
    match &doc.shown().node(&node.name).ok()?.kind {
        NodeKind::Tool(Tool::Lattice(l)) => Some((node.name.clone(), l.clone(), gesture)),
        _ => None,
    }
}

/// The step's label: what was added, with its resolution.
fn label(name: &str, l: &LatticeTool) -> String {
    let (a, b, c) = l.counts;
    let basis = match l.basis {
        LatticeBasis::Bernstein => "Bernstein".to_owned(),
        LatticeBasis::BSpline { degree: (p, q, r) } => format!("B-spline of degrees {p}, {q}, {r}"),
    };
    format!("add lattice '{name}' ({a}×{b}×{c}, {basis})")
}

impl AdjustLast {
    /// Draws the panel at the bottom left of `view` (the 3-D view's rectangle) while the
    /// last step added a lattice; a change is emitted in the add's gesture.
    pub fn show(&mut self, ctx: &egui::Context, view: egui::Rect, cx: &mut PanelContext<'_>) {
        let Some((name, lattice, gesture)) = last_added_lattice(cx.doc) else {
            return;
        };
        egui::Area::new(egui::Id::new("adjust-last"))
            .order(egui::Order::Foreground)
            .pivot(egui::Align2::LEFT_BOTTOM)
            .fixed_pos(egui::pos2(view.left() + 10.0, view.bottom() - 10.0))
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    egui::CollapsingHeader::new(format!("Adjust last: add lattice '{name}'"))
                        .id_salt("adjust-last-header")
                        .default_open(true)
                        .show(ui, |ui| self.contents(ui, cx, &name, &lattice, gesture));
                });
            });
    }

    /// The panel's fields, for the lattice `lattice` of node `name` added in `gesture`.
    pub fn contents(
        &mut self,
        ui: &mut egui::Ui,
        cx: &mut PanelContext<'_>,
        name: &str,
        lattice: &LatticeTool,
        gesture: u64,
    ) {
        let mut l = lattice.clone();
        // The add's gesture holds every change, whichever field made it.
        if !lattice_structure(ui, &mut l, &mut None) || l == *lattice {
            return;
        }
        if let Err(e) = Tool::Lattice(l.clone()).validate(&format!("lattice '{name}'")) {
            cx.requests
                .push(super::PanelRequest::Problem(format!("refused: {e}")));
            return;
        }
        let label = label(name, &l);
        if let Ok(op) = Operation::set_tool(cx.doc.shown(), name, Tool::Lattice(l)) {
            cx.commands.push(DocumentCommand::Apply {
                op: Box::new(op),
                label,
                gesture: Some(gesture),
            });
        }
    }
}
