//! The menu bar: File, Edit and View menus with their shortcuts shown.

use bevy_egui::egui;

use ductile_bevy::prelude::*;

use super::add_menu::{AddRequest, add_menu_contents};

/// What the user picked in the menu bar (carried out by the Studio after the UI pass).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MenuAction {
    /// Add ▸ something (also Shift+A in the viewport).
    Add(AddRequest),
    /// File ▸ New.
    New,
    /// File ▸ Open…
    Open,
    /// File ▸ Save.
    Save,
    /// File ▸ Save As…
    SaveAs,
    /// File ▸ Import mesh…
    ImportMesh,
    /// File ▸ Export glTF…
    ExportGltf,
    /// File ▸ Export animation…
    ExportAnimation,
    /// File ▸ Export variants as morph targets…
    ExportMorphs,
    /// File ▸ Quit.
    Quit,
    /// Edit ▸ Undo.
    Undo,
    /// Edit ▸ Redo.
    Redo,
    /// Edit ▸ Delete.
    Delete,
    /// View ▸ Frame selected.
    FrameSelected,
}

/// View toggles owned by the menu bar.
#[derive(bevy::prelude::Resource, Debug, Clone, Copy, PartialEq)]
pub struct ViewOptions {
    /// Draw the ground grid.
    pub grid: bool,
    /// Draw meshes as wireframe over the shading.
    pub wireframe: bool,
    /// Draw tool and volume gizmos.
    pub gizmos: bool,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            grid: true,
            wireframe: false,
            gizmos: true,
        }
    }
}

/// The menu bar panel.
#[derive(Debug, Default)]
pub struct MenuBar;

impl MenuBar {
    /// Draws the menus; returns the action picked, if any.
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        doc: &SceneDocument,
        has_selection: bool,
        has_mesh: bool,
        view: &mut ViewOptions,
        heat: &mut HeatMapSettings,
    ) -> Option<MenuAction> {
        let mut action = None;
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                let mut item = |ui: &mut egui::Ui, label: &str, shortcut: &str, a: MenuAction| {
                    if ui
                        .add(egui::Button::new(label).shortcut_text(shortcut))
                        .clicked()
                    {
                        action = Some(a);
                        ui.close();
                    }
                };
                item(ui, "New", "Ctrl+N", MenuAction::New);
                item(ui, "Open…", "Ctrl+O", MenuAction::Open);
                item(ui, "Save", "Ctrl+S", MenuAction::Save);
                item(ui, "Save As…", "Ctrl+Shift+S", MenuAction::SaveAs);
                ui.separator();
                item(ui, "Import mesh…", "Ctrl+I", MenuAction::ImportMesh);
                item(ui, "Export glTF…", "Ctrl+E", MenuAction::ExportGltf);
                item(ui, "Export animation…", "", MenuAction::ExportAnimation);
                item(
                    ui,
                    "Export variants as morph targets…",
                    "",
                    MenuAction::ExportMorphs,
                );
                ui.separator();
                item(ui, "Quit", "Ctrl+Q", MenuAction::Quit);
            });
            ui.menu_button("Edit", |ui| {
                let history = doc.history();
                let undo_label = match history.cursor().checked_sub(1) {
                    Some(i) => format!("Undo {}", history.entries()[i].label),
                    None => "Undo".to_owned(),
                };
                if ui
                    .add_enabled(
                        history.can_undo(),
                        egui::Button::new(undo_label).shortcut_text("Ctrl+Z"),
                    )
                    .clicked()
                {
                    action = Some(MenuAction::Undo);
                    ui.close();
                }
                let redo_label = match history.entries().get(history.cursor()) {
                    Some(e) => format!("Redo {}", e.label),
                    None => "Redo".to_owned(),
                };
                if ui
                    .add_enabled(
                        history.can_redo(),
                        egui::Button::new(redo_label).shortcut_text("Ctrl+Shift+Z / Ctrl+Y"),
                    )
                    .clicked()
                {
                    action = Some(MenuAction::Redo);
                    ui.close();
                }
                ui.separator();
                if ui
                    .add_enabled(
                        has_selection,
                        egui::Button::new("Delete").shortcut_text("Delete"),
                    )
                    .clicked()
                {
                    action = Some(MenuAction::Delete);
                    ui.close();
                }
            });
            ui.menu_button("Add", |ui| {
                if let Some(r) = add_menu_contents(ui, has_mesh) {
                    action = Some(MenuAction::Add(r));
                }
                ui.separator();
                ui.weak("Shift+A in the viewport: at the cursor");
            });
            ui.menu_button("View", |ui| {
                ui.checkbox(&mut view.grid, "Grid");
                ui.checkbox(&mut view.wireframe, "Wireframe");
                ui.checkbox(&mut view.gizmos, "Gizmos and handles (Alt+Shift+Z)");
                ui.separator();
                ui.label("Heat-map of the selected layer");
                ui.radio_value(&mut heat.mode, None, "Off (shaded)");
                ui.radio_value(&mut heat.mode, Some(HeatMap::Weight), "Weight");
                ui.radio_value(&mut heat.mode, Some(HeatMap::Displacement), "Displacement");
                ui.separator();
                if ui
                    .add(egui::Button::new("Frame selected").shortcut_text("F"))
                    .clicked()
                {
                    action = Some(MenuAction::FrameSelected);
                    ui.close();
                }
            });
        });
        action
    }
}
