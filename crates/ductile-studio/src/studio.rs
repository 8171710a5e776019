//! The Studio plugin: window contents (camera, lights, grid, wireframe), rest-mesh loading
//! through the project, keyboard shortcuts and the first framing of the scene.

use bevy::camera::Viewport;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::pbr::wireframe::{WireframeConfig, WireframePlugin};
use bevy::picking::mesh_picking::MeshPickingPlugin;
use bevy::prelude::*;
use bevy_egui::{EguiPlugin, EguiPrimaryContextPass};
use ductile_bevy::prelude::*;
use ductile_io::project::Project;

use crate::camera::{
    KeyboardToViewport, OrbitCamera, PointerOverViewport, frame_selected, orbit_camera,
    selection_bounds, vertical_fov, view_aspect,
};
use crate::files::{FileDialogs, StudioAction, run_actions};
use crate::panels::Gestures;
use crate::panels::menu_bar::ViewOptions;
use crate::ui::{PanelState, ViewportRect, studio_ui};

/// The Studio around the [`DuctilePlugin`].
pub struct StudioPlugin {
    /// The project to open.
    pub project: Project,
    /// Warnings from opening it (shown in the status bar).
    pub warnings: Vec<String>,
    /// A node to select at start.
    pub select: Option<String>,
    /// Autosave and the recovery of an earlier session's unsaved work.
    pub recovery: RecoveryOptions,
}

/// How the Studio autosaves, and what it found from an earlier session.
#[derive(Debug, Clone)]
pub struct RecoveryOptions {
    /// Write the recovery file at least this often while there are unsaved edits.
    pub every: std::time::Duration,
    /// And after this many steps.
    pub every_steps: u32,
    /// A recovery file an earlier session left for this project.
    pub found: Option<ductile_io::recovery::FoundRecovery>,
    /// Restore it at start without asking (`--recover`).
    pub recover_now: bool,
}

/// The open project: where it is saved, its mesh sources (the live document and history are
/// in [`SceneDocument`]; the project receives them when saving).
#[derive(Resource)]
pub struct OpenProject(pub Project);

/// Messages for the user (errors of file operations, warnings), newest last.
#[derive(Resource, Debug, Default, Clone)]
pub struct Notices(pub Vec<String>);

impl Notices {
    /// Logs `result` (info or error) and shows its text in the status bar.
    pub fn push_result(&mut self, result: Result<String, String>) {
        match &result {
            Ok(text) => info!("{text}"),
            Err(text) => error!("{text}"),
        }
        self.0.push(result.unwrap_or_else(|e| e));
    }
}

/// Frame every mesh once its evaluation exists (after opening a project).
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct FramePending(pub bool);

impl Plugin for StudioPlugin {
    fn build(&self, app: &mut App) {
        if self.recovery.recover_now {
            app.add_systems(Startup, crate::autosave::recover_at_start);
        }
        let project = self.project.clone();
        let doc =
            SceneDocument::with_history(project.history().clone(), project.document().clone());
        app.add_plugins((
            EguiPlugin::default(),
            MeshPickingPlugin,
            WireframePlugin::default(),
            DuctilePlugin,
        ))
        .insert_resource(doc)
        .insert_resource(OpenProject(project))
        .insert_resource(Notices(self.warnings.clone()))
        .insert_resource(FramePending(true))
        .insert_resource(ClearColor(Color::srgb(0.16, 0.17, 0.19)))
        .insert_resource(Selection {
            node: self.select.clone(),
            ..Selection::default()
        })
        .init_resource::<ViewOptions>()
        .init_resource::<PointerOverViewport>()
        .init_resource::<KeyboardToViewport>()
        .init_resource::<ViewportRect>()
        .init_resource::<PanelState>()
        .init_resource::<Gestures>()
        .init_resource::<FileDialogs>()
        .init_resource::<crate::camera::FrameRequest>()
        .init_resource::<crate::sketch::SketchState>()
        .init_resource::<crate::box_select::BoxSelect>()
        .init_resource::<crate::compare::Compare>()
        .init_resource::<crate::files::ExportJob>()
        .insert_resource(crate::autosave::Autosave::new(
            self.recovery.every,
            self.recovery.every_steps,
            self.recovery.found.clone(),
        ))
        .add_message::<StudioAction>()
        .add_message::<crate::authoring::AddNode>()
        .add_systems(Startup, setup)
        .add_systems(
            EguiPrimaryContextPass,
            (studio_ui, crate::autosave::recovery_offer).chain(),
        )
        .add_systems(Last, crate::autosave::autosave_at_exit)
        .add_systems(
            PreUpdate,
            (
                crate::ctrl_text::strip_ctrl_text,
                crate::pointer::pointer_over_viewport,
            )
                .after(bevy_egui::EguiInputSet::WriteEguiEvents)
                .before(bevy_egui::EguiPreUpdateSet::BeginPass),
        )
        .add_systems(
            Update,
            (
                (
                    viewport_shortcuts,
                    shortcuts,
                    crate::box_select::box_select,
                    run_actions,
                    crate::authoring::add_nodes,
                    crate::sketch::sketch_input,
                )
                    .chain()
                    .before(DuctileSystems::Input),
                crate::files::poll_export,
                crate::autosave::autosave.after(DuctileSystems::Evaluate),
                load_rest_meshes
                    .before(DuctileSystems::Evaluate)
                    .after(DuctileSystems::Sync),
                (
                    orbit_camera,
                    frame_selected,
                    frame_on_open,
                    crate::compare::update_compare,
                )
                    .chain()
                    .after(DuctileSystems::Evaluate),
                (apply_viewport, draw_grid, apply_wireframe, window_title),
            ),
        );
    }
}

fn setup(mut commands: Commands, mut egui_settings: ResMut<bevy_egui::EguiGlobalSettings>) {
    // The UI gets its own camera over the whole window: the 3-D camera's viewport is only the
    // part the panels leave free, and the UI must not be confined to it.
    egui_settings.auto_create_primary_context = false;
    commands.spawn((
        bevy_egui::PrimaryEguiContext,
        Camera2d,
        bevy::camera::visibility::RenderLayers::none(),
        Camera {
            order: 1,
            clear_color: ClearColorConfig::None,
            ..default()
        },
    ));
    let orbit = OrbitCamera {
        focus: Vec3::ZERO,
        yaw: 0.35,
        pitch: 0.15,
        distance: 1.0,
    };
    commands.spawn((
        Camera3d::default(),
        Tonemapping::None,
        orbit,
        orbit.transform(),
        Projection::Perspective(PerspectiveProjection {
            fov: 35_f32.to_radians(),
            near: 0.001,
            ..default()
        }),
    ));
    commands.insert_resource(GlobalAmbientLight {
        color: Color::WHITE,
        brightness: 250.0,
        ..default()
    });
    // A key light over the viewer's shoulder and a dimmer fill light from the other side.
    commands.spawn((
        DirectionalLight {
            illuminance: 6_000.0,
            ..default()
        },
        Transform::from_xyz(1.0, 2.0, 2.5).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 1_800.0,
            ..default()
        },
        Transform::from_xyz(-2.0, 0.5, -1.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

/// Loads the rest mesh of every mesh source the document needs, through the project
/// (files relative to the project, or the embedded head).
fn load_rest_meshes(
    doc: Res<SceneDocument>,
    mut project: ResMut<OpenProject>,
    mut rests: ResMut<RestMeshes>,
    mut notices: ResMut<Notices>,
) {
    if !doc.is_changed() && !rests.is_changed() {
        return;
    }
    let missing = rests.missing(doc.document());
    for source in missing {
        let node = doc.document().nodes.iter().find(
            |n| matches!(&n.kind, ductile_scene::document::NodeKind::Mesh(m) if m.source == source),
        );
        let Some(node) = node else { continue };
        match project.0.rest_mesh(&node.name) {
            Ok(rest) => rests.insert(source, (*rest).clone()),
            Err(e) => {
                let text = ductile_io::report(&e);
                notices.0.push(text.clone());
                rests.insert_failure(source, text);
            }
        }
    }
}

/// Viewport shortcuts (ignored while a text field has the keyboard): Alt+Shift+Z toggles
/// the overlays (gizmos and handles) and Shift+A over the viewport opens the Add menu at the
/// cursor, as in Blender.
fn viewport_shortcuts(
    keys: Res<ButtonInput<KeyCode>>,
    keyboard: Res<KeyboardToViewport>,
    mut sketch: ResMut<crate::sketch::SketchState>,
    mut view: ResMut<ViewOptions>,
    over: Res<PointerOverViewport>,
    windows: Query<&Window, With<bevy::window::PrimaryWindow>>,
) {
    if !keyboard.0 {
        return;
    }
    let alt = keys.any_pressed([KeyCode::AltLeft, KeyCode::AltRight])
        || keys.any_just_released([KeyCode::AltLeft, KeyCode::AltRight]);
    let shift_held = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight])
        || keys.any_just_released([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    if alt && shift_held && keys.just_pressed(KeyCode::KeyZ) {
        view.gizmos = !view.gizmos;
    } else if shift_held
        && !alt
        && keys.just_pressed(KeyCode::KeyA)
        && over.0
        && !sketch.active()
        && let Some(at) = windows.single().ok().and_then(Window::cursor_position)
    {
        sketch.add_popup = Some(at);
    }
}

/// Keyboard shortcuts (ignored while a text field has the keyboard). Escape clears the
/// selection, node and layer (unless it cancels a sketch or a box selection).
fn shortcuts(
    keys: Res<ButtonInput<KeyCode>>,
    keyboard: Res<KeyboardToViewport>,
    drag: Res<DragState>,
    mut selection: ResMut<Selection>,
    sketch: Res<crate::sketch::SketchState>,
    box_select: Res<crate::box_select::BoxSelect>,
    mut actions: MessageWriter<StudioAction>,
) {
    if !keyboard.0 {
        return;
    }
    if keys.just_pressed(KeyCode::Escape)
        && drag.active.is_none()
        && !sketch.active()
        && !box_select.armed
        && (selection.node.is_some() || selection.layer.is_some())
    {
        selection.select(None);
        selection.layer = None;
    }
    // A modifier released in the same frame as the key still counts: at low frame rates
    // (software rendering) a quick Ctrl+Z arrives as press and release of both in one frame.
    let held = |k: [KeyCode; 2]| keys.any_pressed(k) || keys.any_just_released(k);
    let ctrl = held([KeyCode::ControlLeft, KeyCode::ControlRight])
        || held([KeyCode::SuperLeft, KeyCode::SuperRight]);
    let shift = held([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    let pressed = |k| keys.just_pressed(k);
    let action = if ctrl && pressed(KeyCode::KeyZ) && shift || ctrl && pressed(KeyCode::KeyY) {
        Some(StudioAction::Redo)
    } else if ctrl && pressed(KeyCode::KeyZ) {
        Some(StudioAction::Undo)
    } else if ctrl && shift && pressed(KeyCode::KeyS) {
        Some(StudioAction::SaveAs)
    } else if ctrl && pressed(KeyCode::KeyS) {
        Some(StudioAction::Save)
    } else if ctrl && pressed(KeyCode::KeyO) {
        Some(StudioAction::Open)
    } else if ctrl && pressed(KeyCode::KeyN) {
        Some(StudioAction::New)
    } else if ctrl && pressed(KeyCode::KeyI) {
        Some(StudioAction::ImportMesh)
    } else if ctrl && pressed(KeyCode::KeyE) {
        Some(StudioAction::ExportGltf)
    } else if ctrl && pressed(KeyCode::KeyQ) {
        Some(StudioAction::Quit)
    } else if (pressed(KeyCode::Delete) || pressed(KeyCode::Backspace)) && drag.active.is_none() {
        Some(StudioAction::Delete)
    } else {
        None
    };
    if let Some(a) = action {
        actions.write(a);
    }
}

/// Frames every mesh once, after a project opened and its meshes evaluated.
#[allow(clippy::type_complexity)]
fn frame_on_open(
    mut pending: ResMut<FramePending>,
    entities: Res<NodeEntities>,
    meshes: Query<(&bevy::camera::primitives::Aabb, &GlobalTransform), With<MeshEvaluation>>,
    handles: Query<(&HandleMarker, &GlobalTransform)>,
    mut cameras: Query<(&mut OrbitCamera, &Projection, &Camera)>,
) {
    if !pending.0 || meshes.is_empty() {
        return;
    }
    // Wait for the viewport between the panels: the framing depends on its shape.
    let Ok((mut orbit, projection, camera)) = cameras.single_mut() else {
        return;
    };
    if camera.viewport.is_none() {
        return;
    }
    let fov = vertical_fov(projection);
    let everything = Selection::default();
    if let Some((min, max)) = selection_bounds(&everything, &entities, &meshes, &handles) {
        orbit.frame(min, max, fov, view_aspect(projection, camera));
        pending.0 = false;
    }
}

/// Renders the 3-D view only in the part of the window the panels leave free.
fn apply_viewport(
    rect: Res<ViewportRect>,
    windows: Query<&Window, With<bevy::window::PrimaryWindow>>,
    mut cameras: Query<&mut Camera, With<Camera3d>>,
) {
    let (Ok(window), Ok(mut camera)) = (windows.single(), cameras.single_mut()) else {
        return;
    };
    let Some((min, max)) = rect.0 else { return };
    let scale = window.scale_factor();
    let size = UVec2::new(window.physical_width(), window.physical_height());
    let pos = (min * scale)
        .as_uvec2()
        .min(size.saturating_sub(UVec2::ONE));
    let end = (max * scale).as_uvec2().min(size);
    let wanted = Viewport {
        physical_position: pos,
        physical_size: end.saturating_sub(pos).max(UVec2::ONE),
        ..default()
    };
    let same = camera.viewport.as_ref().is_some_and(|v| {
        v.physical_position == wanted.physical_position && v.physical_size == wanted.physical_size
    });
    if !same {
        camera.viewport = Some(wanted);
    }
}

/// The ground grid, under the meshes at their lowest point, centred on them and three times as
/// wide as they are, with cells of a round size (a power of ten) about a tenth of their width.
fn draw_grid(
    view: Res<ViewOptions>,
    meshes: Query<(&bevy::camera::primitives::Aabb, &GlobalTransform), With<MeshEvaluation>>,
    mut gizmos: Gizmos,
) {
    if !view.grid {
        return;
    }
    let mut low = Vec3::splat(f32::INFINITY);
    let mut high = Vec3::splat(f32::NEG_INFINITY);
    for (aabb, at) in &meshes {
        let (min, max) = (
            Vec3::from(aabb.center - aabb.half_extents),
            Vec3::from(aabb.center + aabb.half_extents),
        );
        for corner in 0..8 {
            let local = Vec3::new(
                if corner & 1 == 0 { min.x } else { max.x },
                if corner & 2 == 0 { min.y } else { max.y },
                if corner & 4 == 0 { min.z } else { max.z },
            );
            let world = at.transform_point(local);
            low = low.min(world);
            high = high.max(world);
        }
    }
    let (grid_at, cells, cell) = ground_grid(low, high);
    let rotation = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    gizmos.grid(
        Isometry3d::new(grid_at, rotation),
        UVec2::splat(cells),
        Vec2::splat(cell),
        Color::srgba(0.6, 0.6, 0.65, 0.35),
    );
}

/// Where the ground grid lies for meshes whose world bounds are `low..high`: its centre, its
/// number of cells per side and its cell size. With no meshes (infinite bounds) it is 20 cells of
/// 10 cm around the origin.
#[must_use]
fn ground_grid(low: Vec3, high: Vec3) -> (Vec3, u32, f32) {
    if !(low.is_finite() && high.is_finite()) {
        return (Vec3::ZERO, 20, 0.1);
    }
    let width = (high.x - low.x).max(high.z - low.z).max(1e-3);
    let cell = 10f32.powf((width / 10.0).log10().round());
    let cells = ((3.0 * width / cell - 1e-3).ceil() as u32).clamp(4, 200);
    let cells = cells + cells % 2;
    let centre = Vec3::new(
        ((low.x + high.x) * 0.5 / cell).round() * cell,
        low.y,
        ((low.z + high.z) * 0.5 / cell).round() * cell,
    );
    (centre, cells, cell)
}

fn apply_wireframe(
    view: Res<ViewOptions>,
    config: Option<ResMut<WireframeConfig>>,
    mut gizmo_settings: ResMut<GizmoSettings>,
) {
    if gizmo_settings.enabled != view.gizmos {
        gizmo_settings.enabled = view.gizmos;
    }
    if let Some(mut config) = config
        && config.global != view.wireframe
    {
        config.global = view.wireframe;
    }
}

fn window_title(
    doc: Res<SceneDocument>,
    project: Res<OpenProject>,
    mut windows: Query<&mut Window, With<bevy::window::PrimaryWindow>>,
) {
    if !doc.is_changed() && !project.is_changed() {
        return;
    }
    if let Ok(mut window) = windows.single_mut() {
        let title = format!(
            "Ductile Studio — {}{}",
            project.0.display_name(),
            if doc.is_modified() { " •" } else { "" }
        );
        if window.title != title {
            window.title = title;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_grid_is_under_the_meshes_and_three_times_as_wide() {
        // A head 0.2 m wide standing on y = -0.1: cells of 10^round(log10(0.02)) = 1 cm,
        // ceil(0.6 / 0.01) = 60 cells, centred on the rounded middle at the lowest point.
        let (centre, cells, cell) =
            ground_grid(Vec3::new(-0.1, -0.1, -0.05), Vec3::new(0.1, 0.15, 0.07));
        assert!((cell - 0.01).abs() < 1e-6, "cell {cell}");
        assert_eq!(cells, 60);
        assert!(
            (centre - Vec3::new(0.0, -0.1, 0.01)).length() < 1e-6,
            "{centre}"
        );
    }

    #[test]
    fn ground_grid_without_meshes_is_around_the_origin() {
        let (centre, cells, cell) =
            ground_grid(Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        assert_eq!((centre, cells, cell), (Vec3::ZERO, 20, 0.1));
    }
}
