//! The Studio's egui pass: menu bar, left panel (outliner, stack, history), right panel
//! (inspector, identikit macros), status bar, dialogs; then the free rectangle left for the
//! 3-D viewport.

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_egui::{EguiContexts, egui};
use ductile_bevy::prelude::*;
use ductile_scene::document::NodeKind;

use crate::authoring::AddNode;
use crate::camera::KeyboardToViewport;
use crate::files::{FileDialogs, StudioAction};
use crate::panels::add_menu::AddPopup;
use crate::panels::history::HistoryPanel;
use crate::panels::inspector::Inspector;
use crate::panels::macros::MacrosPanel;
use crate::panels::menu_bar::{MenuAction, MenuBar, ViewOptions};
use crate::panels::outliner::Outliner;
use crate::panels::stack::StackPanel;
use crate::panels::status_bar::{StatusBar, StatusInfo};
use crate::panels::timeline::TimelinePanel;
use crate::panels::variants::VariantsPanel;
use crate::panels::{Gestures, PanelContext, PanelRequest};
use crate::sketch::SketchState;
use crate::studio::{Notices, OpenProject};

/// The panels' own state.
#[derive(Resource, Default)]
pub struct PanelState {
    menu: MenuBar,
    outliner: Outliner,
    stack: StackPanel,
    history: HistoryPanel,
    inspector: Inspector,
    macros: MacrosPanel,
    status: StatusBar,
    add_popup: AddPopup,
    timeline: TimelinePanel,
    key_offer: crate::panels::key_offer::KeyOffer,
    adjust_last: crate::panels::adjust_last::AdjustLast,
    variants: VariantsPanel,
    frame_ms: Option<f64>,
}

/// The window rectangle (logical pixels) not covered by panels: where the 3-D view draws.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq)]
pub struct ViewportRect(pub Option<(Vec2, Vec2)>);

/// Read-only resources the UI shows.
#[derive(SystemParam)]
pub struct UiInputs<'w, 's> {
    doc: Res<'w, SceneDocument>,
    stats: Res<'w, EvaluationStats>,
    edit: Res<'w, EditStatus>,
    drag: Res<'w, DragState>,
    project: Res<'w, OpenProject>,
    time: Res<'w, Time>,
    notices: ResMut<'w, Notices>,
    box_select: Res<'w, crate::box_select::BoxSelect>,
    export: Res<'w, crate::files::ExportJob>,
    /// Every mesh node's evaluation.
    meshes: Query<'w, 's, (&'static SceneNode, &'static MeshEvaluation)>,
}

/// What the UI writes besides its own state.
#[derive(SystemParam)]
pub struct UiOutputs<'w> {
    edits: MessageWriter<'w, DocumentCommand>,
    actions: MessageWriter<'w, StudioAction>,
    adds: MessageWriter<'w, AddNode>,
    sketch: ResMut<'w, SketchState>,
    compare: ResMut<'w, crate::compare::Compare>,
}

/// The left panel's width at start (outliner, stack, history), in logical pixels.
pub const LEFT_WIDTH: f32 = 360.0;
/// The right panel's width at start (inspector, identikit), in logical pixels.
pub const RIGHT_WIDTH: f32 = 440.0;
/// The timeline's height at start, in logical pixels.
pub const TIMELINE_HEIGHT: f32 = 120.0;

/// A resizable side panel that keeps the width the user gives it (`width` at start):
/// content wider than that scrolls sideways instead of widening the panel, so the viewport
/// does not jump when a long name appears.
fn side_panel(
    panel: egui::Panel,
    width: f32,
    root: &mut egui::Ui,
    contents: impl FnOnce(&mut egui::Ui),
) -> egui::InnerResponse<()> {
    panel.resizable(true).default_size(width).show(root, |ui| {
        egui::ScrollArea::horizontal()
            .auto_shrink([false, false])
            .show(ui, contents);
    })
}

/// A mode's hint (sketch mode, box select) in a dark box at the top left of the 3-D view.
fn paint_hint(painter: &egui::Painter, view: egui::Rect, hint: String) {
    let at = view.left_top() + egui::vec2(10.0, 10.0);
    let galley = painter.layout(
        hint,
        egui::FontId::proportional(14.0),
        egui::Color32::WHITE,
        view.width() - 20.0,
    );
    painter.rect_filled(
        egui::Rect::from_min_size(at, galley.size()).expand(5.0),
        4.0,
        egui::Color32::from_black_alpha(170),
    );
    painter.galley(at, galley, egui::Color32::WHITE);
}

/// Draws every panel and forwards what they asked for.
#[allow(clippy::too_many_arguments)]
pub fn studio_ui(
    mut contexts: EguiContexts,
    mut inputs: UiInputs,
    mut panels: ResMut<PanelState>,
    mut selection: ResMut<Selection>,
    mut gestures: ResMut<Gestures>,
    mut view: ResMut<ViewOptions>,
    mut heat: ResMut<HeatMapSettings>,
    mut dialogs: ResMut<FileDialogs>,
    mut viewport: ResMut<ViewportRect>,
    mut keyboard: ResMut<KeyboardToViewport>,
    outputs: UiOutputs,
) -> Result {
    let UiOutputs {
        mut edits,
        mut actions,
        mut adds,
        mut sketch,
        mut compare,
    } = outputs;
    let ctx = contexts.ctx_mut()?.clone();
    let panels = &mut *panels;
    let dt = f64::from(inputs.time.delta_secs()) * 1000.0;
    if dt > 0.0 {
        panels.frame_ms = Some(panels.frame_ms.map_or(dt, |f| f * 0.9 + dt * 0.1));
    }
    let mut root = egui::Ui::new(
        ctx.clone(),
        "studio-root".into(),
        egui::UiBuilder::new()
            .layer_id(egui::LayerId::background())
            .max_rect(ctx.viewport_rect()),
    );
    let meshes: Vec<_> = inputs
        .meshes
        .iter()
        .map(|(node, ev)| (node.name.clone(), ev.rest().clone()))
        .collect();
    let mut cx = PanelContext {
        doc: &inputs.doc,
        selection: &mut selection,
        commands: Vec::new(),
        requests: Vec::new(),
        gestures: &mut gestures,
        now: inputs.time.elapsed_secs_f64(),
        meshes: &meshes,
    };
    let has_selection = cx.selection.node.is_some();
    let has_mesh = !inputs.doc.shown().mesh_names().is_empty();

    let mut menu_action = None;
    let top = egui::Panel::top("menu-bar").show(&mut root, |ui| {
        menu_action = panels.menu.show(
            ui,
            &inputs.doc,
            has_selection,
            has_mesh,
            &mut view,
            &mut heat,
        );
    });

    let info = status_info(&inputs, panels.frame_ms);
    let bottom = egui::Panel::bottom("status-bar").show(&mut root, |ui| {
        panels.status.show(ui, &info);
    });
    let timeline = egui::Panel::bottom("timeline")
        .resizable(true)
        .default_size(TIMELINE_HEIGHT)
        .show(&mut root, |ui| {
            panels.timeline.show(ui, &mut cx);
        });

    let left = side_panel(
        egui::Panel::left("left-panel"),
        LEFT_WIDTH,
        &mut root,
        |ui| {
            ui.heading("Scene");
            panels.outliner.show(ui, &mut cx);
            ui.separator();
            ui.heading("Stack");
            panels.stack.show(ui, &mut cx);
            ui.separator();
            ui.heading("History");
            panels.history.show(ui, &mut cx);
        },
    );

    let right = side_panel(
        egui::Panel::right("right-panel"),
        RIGHT_WIDTH,
        &mut root,
        |ui| {
            ui.heading("Inspector");
            // Without macro tools the identikit section is one line: the inspector takes the
            // height it would have used.
            let has_macros = cx
                .doc
                .shown()
                .nodes
                .iter()
                .any(|n| matches!(n.kind, ductile_scene::document::NodeKind::Macro(_)));
            let total = ui.available_height();
            let height = if has_macros {
                total * 0.45
            } else {
                (total * 0.7).max(120.0)
            };
            egui::ScrollArea::vertical()
                .id_salt("inspector")
                .max_height(height)
                .show(ui, |ui| panels.inspector.show(ui, &mut cx));
            ui.separator();
            // Every section scrolls within its share, so the panel never grows over the
            // timeline.
            egui::CollapsingHeader::new(egui::RichText::new("Variants").heading())
                .default_open(true)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical()
                        .id_salt("variants")
                        .max_height(total * 0.35)
                        .show(ui, |ui| panels.variants.show(ui, &mut cx));
                });
            ui.separator();
            ui.heading("Identikit");
            panels.macros.show(ui, &mut cx);
        },
    );

    // The free rectangle between the panels.
    let screen = ctx.viewport_rect();
    let min = egui::pos2(left.response.rect.right(), top.response.rect.bottom());
    let max = egui::pos2(
        right.response.rect.left(),
        bottom.response.rect.top().min(timeline.response.rect.top()),
    );
    let free = egui::Rect::from_min_max(min, max).intersect(screen);
    // The offer to key an edit of animated fields, over the bottom of the view.
    panels.key_offer.show(&ctx, free, &mut cx);
    // The resolution of a lattice just added ("Adjust last operation"), at its bottom left.
    panels.adjust_last.show(&ctx, free, &mut cx);

    if let Some(a) = dialogs.show(&ctx) {
        actions.write(a);
    }

    // The Add popup at the cursor (Shift+A over the viewport, as in Blender; the shortcut is
    // read by the Studio's `shortcuts`, which sees a Shift released in the same frame).
    if let Some(at) = sketch_popup_request(&mut sketch) {
        panels.add_popup.open_at = Some(egui::pos2(at.x, at.y));
    }
    let popup_at = panels.add_popup.open_at;
    if let Some(request) = panels.add_popup.show(&ctx, has_mesh) {
        adds.write(AddNode {
            request,
            cursor: popup_at.map(|p| Vec2::new(p.x, p.y)),
        });
    }

    let commands = std::mem::take(&mut cx.commands);
    for c in commands {
        edits.write(c);
    }
    for r in std::mem::take(&mut cx.requests) {
        match r {
            PanelRequest::RedrawSketch(node) => {
                let doc = inputs.doc.shown();
                let mesh = cx.selection.mesh_in_focus(doc);
                let kind = match doc.node(&node).map(|n| &n.kind) {
                    Ok(ductile_scene::document::NodeKind::Tool(
                        ductile_core::tool::Tool::Sketch(t),
                    )) if matches!(
                        t.mode,
                        ductile_core::sketch::tool::SketchMode::Twist { .. }
                    ) =>
                    {
                        ductile_scene::sketching::SketchKind::Twist
                    }
                    _ => ductile_scene::sketching::SketchKind::Bend,
                };
                if let Some(mesh) = mesh {
                    sketch.begin(&mesh, kind, Some(node));
                }
            }
            PanelRequest::Compare(entries) => compare.entries = entries,
            PanelRequest::Problem(text) => {
                warn!("{text}");
                inputs.notices.0.push(text);
            }
        }
    }
    if let Some(MenuAction::Add(request)) = menu_action {
        adds.write(AddNode {
            request,
            cursor: None,
        });
    } else if let Some(a) = menu_action {
        actions.write(match a {
            MenuAction::New => StudioAction::New,
            MenuAction::Open => StudioAction::Open,
            MenuAction::Save => StudioAction::Save,
            MenuAction::SaveAs => StudioAction::SaveAs,
            MenuAction::ImportMesh => StudioAction::ImportMesh,
            MenuAction::ExportGltf => StudioAction::ExportGltf,
            MenuAction::ExportAnimation => StudioAction::ExportAnimation,
            MenuAction::ExportMorphs => StudioAction::ExportMorphs,
            MenuAction::Quit => StudioAction::Quit,
            MenuAction::Undo => StudioAction::Undo,
            MenuAction::Redo => StudioAction::Redo,
            MenuAction::Delete => StudioAction::Delete,
            MenuAction::FrameSelected => StudioAction::FrameSelected,
            MenuAction::Add(_) => unreachable!("handled above"),
        });
    }

    let wanted = (free.width() > 8.0 && free.height() > 8.0).then(|| {
        (
            Vec2::new(free.min.x, free.min.y),
            Vec2::new(free.max.x, free.max.y),
        )
    });
    if viewport.0 != wanted {
        viewport.0 = wanted;
    }
    // Side by side: a label over each face.
    if !compare.labels.is_empty() {
        let painter = ctx
            .layer_painter(egui::LayerId::new(
                egui::Order::Foreground,
                egui::Id::new("compare-labels"),
            ))
            .with_clip_rect(free);
        for (text, at) in &compare.labels {
            painter.text(
                egui::pos2(at.x, at.y - 8.0),
                egui::Align2::CENTER_BOTTOM,
                text,
                egui::FontId::proportional(15.0),
                egui::Color32::WHITE,
            );
        }
    }
    // Sketch mode: the strokes and the hint over the 3-D view.
    if sketch.active() {
        let painter = ctx.layer_painter(egui::LayerId::new(
            egui::Order::Foreground,
            egui::Id::new("sketch-overlay"),
        ));
        let painter = painter.with_clip_rect(free);
        for (points, [r, g, b]) in sketch.strokes() {
            let line: Vec<egui::Pos2> = points
                .iter()
                .map(|p| egui::pos2(free.min.x + p.x, free.min.y + p.y))
                .collect();
            painter.add(egui::Shape::line(
                line,
                egui::Stroke::new(2.5, egui::Color32::from_rgb(r, g, b)),
            ));
        }
        if let Some(hint) = sketch.hint() {
            paint_hint(&painter, free, hint);
        }
    }
    // Box select: the hint and the rectangle being drawn.
    if inputs.box_select.armed || inputs.box_select.corners.is_some() {
        let painter = ctx
            .layer_painter(egui::LayerId::new(
                egui::Order::Foreground,
                egui::Id::new("box-select-overlay"),
            ))
            .with_clip_rect(free);
        if let Some(r) = inputs.box_select.rect() {
            let rect = egui::Rect::from_min_max(
                egui::pos2(r.min.x, r.min.y),
                egui::pos2(r.max.x, r.max.y),
            );
            painter.rect_filled(rect, 0.0, egui::Color32::from_white_alpha(18));
            painter.rect_stroke(
                rect,
                0.0,
                egui::Stroke::new(1.0, egui::Color32::WHITE),
                egui::StrokeKind::Inside,
            );
        }
        if let Some(hint) = inputs.box_select.hint() {
            paint_hint(&painter, free, hint.to_owned());
        }
    }
    // Only a text field keeps the shortcuts from the viewport: a slider keeps the keyboard
    // focus after it is dragged, and Ctrl+Z must still undo that drag.
    let keys_free = !ctx.text_edit_focused();
    if keyboard.0 != keys_free {
        keyboard.0 = keys_free;
    }
    Ok(())
}

/// Takes the position where Shift+A asked for the Add popup, if it did.
fn sketch_popup_request(sketch: &mut SketchState) -> Option<Vec2> {
    sketch.add_popup.take()
}

fn status_info(inputs: &UiInputs, frame_ms: Option<f64>) -> StatusInfo {
    let mut vertices = 0;
    let mut triangles = 0;
    let mut evaluating = false;
    for (_, ev) in &inputs.meshes {
        let mesh = ev.rest().mesh();
        match ev.evaluator().and_then(|e| e.deformed()) {
            Some(d) => {
                vertices += d.positions.len();
                triangles += d
                    .refined
                    .as_ref()
                    .map_or(mesh.triangle_count(), |r| r.stored_triangles.len());
            }
            None => {
                vertices += mesh.positions.len();
                triangles += mesh.triangle_count();
            }
        }
        evaluating |= ev.is_running();
    }
    let error = inputs
        .edit
        .last_error
        .clone()
        .or_else(|| inputs.doc.pose_error().map(|e| format!("animation: {e}")))
        .or_else(|| {
            inputs
                .stats
                .errors
                .first()
                .map(|(m, e)| format!("mesh '{m}': {e}"))
        })
        .or_else(|| inputs.notices.0.last().cloned());
    StatusInfo {
        vertices,
        triangles,
        // The last evaluation, while its mesh is still in the scene (File > New or Open
        // replace the meshes; the next evaluation of a new one takes the place).
        evaluation: inputs
            .stats
            .last
            .as_ref()
            .filter(|(m, _)| {
                inputs
                    .doc
                    .shown()
                    .node(m)
                    .is_ok_and(|n| matches!(n.kind, NodeKind::Mesh(_)))
            })
            .map(|(m, r)| {
                (
                    m.clone(),
                    r.duration.as_secs_f64() * 1000.0,
                    r.layers_evaluated,
                    r.background,
                )
            }),
        frame_ms,
        drag: inputs
            .drag
            .active
            .as_ref()
            .map(|_| inputs.drag.constraint.label()),
        evaluating,
        error,
        file: inputs.project.0.display_name(),
        modified: inputs.doc.is_modified(),
        export: inputs
            .export
            .0
            .as_ref()
            .map(|j| (j.what.clone(), j.fraction())),
    }
}
