//! The Add menu (menu bar, and Shift+A at the cursor, as in Blender): every tool kind, the
//! sketch tool (which starts sketch mode), every volume shape and a group. Picking an entry
//! returns an [`AddRequest`]; the Studio places the new node around the selected mesh
//! (`crate::authoring`) and applies it as one undo step.

use bevy_egui::egui;
use ductile_scene::create::{NewTool, NewVolume};

/// What to add.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AddRequest {
    /// A tool with its layer on the mesh in focus.
    Tool(NewTool),
    /// A sketch tool: enters sketch mode (bend: reference then target stroke).
    SketchBend,
    /// A sketch twist: reference stroke, then a stroke whose length sets the angle.
    SketchTwist,
    /// A volume under the mesh in focus (masking the selected layer, if any).
    Volume(NewVolume),
    /// An empty group (under the selected node, if any).
    Group,
}

impl AddRequest {
    /// Every entry, in menu order, with its label (separators between the sections are
    /// drawn by [`add_menu_contents`]).
    #[must_use]
    pub fn all() -> Vec<(AddRequest, &'static str)> {
        let mut v: Vec<(AddRequest, &'static str)> = NewTool::ALL
            .iter()
            .map(|&t| (AddRequest::Tool(t), t.label()))
            .collect();
        v.push((AddRequest::SketchBend, "Sketch bend (draw strokes)"));
        v.push((AddRequest::SketchTwist, "Sketch twist (draw strokes)"));
        v.extend(
            NewVolume::ALL
                .iter()
                .map(|&k| (AddRequest::Volume(k), k.label())),
        );
        v.push((AddRequest::Group, "Group"));
        v
    }
}

/// The entries of the Add menu, for the menu bar and the Shift+A popup. Returns the entry
/// picked. Tool entries need a mesh (`has_mesh`).
pub fn add_menu_contents(ui: &mut egui::Ui, has_mesh: bool) -> Option<AddRequest> {
    let mut picked = None;
    ui.label(egui::RichText::new("Tools").strong());
    for (i, (request, label)) in AddRequest::all().into_iter().enumerate() {
        let section_starts = matches!(
            request,
            AddRequest::SketchBend | AddRequest::Volume(NewVolume::Sphere) | AddRequest::Group
        );
        if section_starts && i > 0 {
            ui.separator();
            if let AddRequest::Volume(_) = request {
                ui.label(egui::RichText::new("Influence volumes").strong());
            }
        }
        let needs_mesh = !matches!(request, AddRequest::Group);
        if ui
            .add_enabled(has_mesh || !needs_mesh, egui::Button::new(label))
            .on_disabled_hover_text("Import or open a mesh first")
            .clicked()
        {
            picked = Some(request);
            ui.close();
        }
    }
    picked
}

/// The Shift+A popup: the Add menu in a small window at `at` (screen position) until an
/// entry is picked, Escape is pressed or the user clicks elsewhere.
#[derive(Debug, Default)]
pub struct AddPopup {
    /// Where the popup is open, if it is.
    pub open_at: Option<egui::Pos2>,
}

impl AddPopup {
    /// Draws the popup when open; returns the entry picked.
    pub fn show(&mut self, ctx: &egui::Context, has_mesh: bool) -> Option<AddRequest> {
        let at = self.open_at?;
        let mut picked = None;
        let area = egui::Area::new(egui::Id::new("add-popup"))
            .order(egui::Order::Foreground)
            .fixed_pos(at)
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.set_min_width(220.0);
                    ui.label(egui::RichText::new("Add").heading());
                    picked = add_menu_contents(ui, has_mesh);
                });
            });
        let clicked_elsewhere = ctx.input(|i| i.pointer.any_pressed())
            && ctx
                .pointer_interact_pos()
                .is_some_and(|p| !area.response.rect.contains(p));
        if picked.is_some() || clicked_elsewhere || ctx.input(|i| i.key_pressed(egui::Key::Escape))
        {
            self.open_at = None;
        }
        picked
    }
}
