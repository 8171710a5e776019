//! Draggable handles: one small pickable sphere per editable point of the selected node (and
//! the origins of the other tools and volumes, to pick them), and the drag that turns pointer
//! motion into history operations.
//!
//! A drag edits the document live (every frame of the drag pushes an operation with the
//! drag's gesture id) and the history merges the whole drag into one step, so a release
//! leaves exactly one undo step.

use std::collections::HashMap;

use bevy::picking::events::{Drag, DragEnd, DragStart, Pointer, Press};
use bevy::picking::pointer::PointerButton;
use bevy::prelude::*;
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, NodeKind};
use ductile_scene::handles::{HandleId, HandleRole, NodeEdit, handles, moved};

use crate::components::HandleMarker;
use crate::document::{DocumentCommand, SceneDocument};
use crate::drag::{AxisConstraint, drag_target};
use crate::error::{DuctileBevyError, Result};
use crate::selection::Selection;

/// Meshes and materials of handles (present when the app renders).
#[derive(Resource, Debug, Clone)]
pub struct HandleAssets {
    /// A unit sphere.
    pub sphere: Handle<Mesh>,
    /// Material of a selected node's handles.
    pub selected: Handle<StandardMaterial>,
    /// Material of other nodes' handles.
    pub unselected: Handle<StandardMaterial>,
    /// Material of the handle being dragged.
    pub active: Handle<StandardMaterial>,
}

/// How handles look and snap.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct HandleSettings {
    /// Handle radius as a fraction of the distance to the camera (constant on screen).
    pub screen_radius: f32,
    /// Snapping increment in world units (used while a snap modifier is held).
    pub snap_step: f32,
}

impl Default for HandleSettings {
    fn default() -> Self {
        Self {
            screen_radius: 0.008,
            snap_step: 0.005,
        }
    }
}

/// The drag in progress, if any, and the axis constraint (X/Y/Z keys).
#[derive(Resource, Debug, Default, Clone, PartialEq)]
pub struct DragState {
    /// The handle being dragged.
    pub active: Option<ActiveDrag>,
    /// The axis constraint; reset when a drag ends.
    pub constraint: AxisConstraint,
    /// Set by the application while the primary button belongs to another gesture (a box
    /// selection): a press on a handle then neither selects it nor starts a drag.
    pub blocked: bool,
}

/// A handle drag in progress.
#[derive(Debug, Clone, PartialEq)]
pub struct ActiveDrag {
    /// The node whose handle it is.
    pub node: String,
    /// The handle.
    pub id: HandleId,
    /// The handle's world position when the drag started.
    pub start: Vec3,
    /// The gesture id all the drag's edits share (one undo step).
    pub gesture: u64,
    /// The other selected handles of the node moved along (by the same world offset), with
    /// their world positions when the drag started.
    pub with: Vec<(HandleId, Vec3)>,
}

/// True for the nodes whose origin handle shows even when they are not selected (so they
/// can be picked in the viewport): tools and volumes. Macro tools and meshes are picked in
/// the panels (the identikit has dozens of macros on one head).
fn shows_unselected_origin(kind: &NodeKind) -> bool {
    matches!(kind, NodeKind::Tool(_) | NodeKind::Volume(_))
}

/// Every handle that should exist now, with its world position.
fn wanted_handles(doc: &Document, selection: &Selection) -> Vec<(String, HandleId, Vec3, bool)> {
    let mut out = Vec::new();
    for node in &doc.nodes {
        let selected = selection.is_selected(&node.name);
        if !selected && !shows_unselected_origin(&node.kind) || selection.is_hidden(&node.name) {
            continue;
        }
        let Ok(world) = doc.world_transform(&node.name) else {
            continue;
        };
        let parent_world = match &node.parent {
            Some(p) => doc.world_transform(p).unwrap_or_default(),
            None => bevy::math::Affine3A::IDENTITY,
        };
        let Ok(list) = handles(doc, &node.name) else {
            continue;
        };
        for h in list {
            let is_origin = matches!(h.role, HandleRole::Origin);
            if !selected && !is_origin {
                continue;
            }
            let p = if is_origin {
                parent_world.transform_point3(h.position)
            } else {
                world.transform_point3(h.position)
            };
            if p.is_finite() {
                out.push((node.name.clone(), h.id, p, selected));
            }
        }
    }
    out
}

/// Spawns, moves and despawns handle entities to match the document and the selection.
pub fn sync_handles(
    mut commands: Commands,
    doc: Res<SceneDocument>,
    selection: Res<Selection>,
    drag: Res<DragState>,
    gizmos: Res<crate::gizmos::GizmoSettings>,
    assets: Option<Res<HandleAssets>>,
    mut existing: Query<(
        Entity,
        &HandleMarker,
        &mut Transform,
        Option<&mut MeshMaterial3d<StandardMaterial>>,
    )>,
) {
    if !(doc.is_changed() || selection.is_changed() || drag.is_changed() || gizmos.is_changed()) {
        return;
    }
    // With the overlays off (no gizmos), there are no handles either.
    let mut wanted: HashMap<(String, HandleId), (Vec3, bool)> = if gizmos.enabled {
        wanted_handles(doc.shown(), &selection)
            .into_iter()
            .map(|(n, id, p, s)| ((n, id), (p, s)))
            .collect()
    } else {
        HashMap::new()
    };
    let material_for = |node: &str, id: &HandleId, selected: bool| {
        assets.as_ref().map(|a| {
            let active = drag
                .active
                .as_ref()
                .is_some_and(|d| d.node == node && &d.id == id)
                || (selected && selection.handles.contains(id));
            if active {
                a.active.clone()
            } else if selected {
                a.selected.clone()
            } else {
                a.unselected.clone()
            }
        })
    };
    for (entity, marker, mut transform, material) in &mut existing {
        match wanted.remove(&(marker.node.clone(), marker.id)) {
            Some((p, selected)) => {
                if transform.translation != p {
                    transform.translation = p;
                }
                if let (Some(mut m), Some(want)) =
                    (material, material_for(&marker.node, &marker.id, selected))
                    && m.0 != want
                {
                    m.0 = want;
                }
            }
            None => commands.entity(entity).despawn(),
        }
    }
    for ((node, id), (p, selected)) in wanted {
        let material = material_for(&node, &id, selected);
        let mut e = commands.spawn((
            HandleMarker { node, id },
            Transform::from_translation(p),
            Visibility::default(),
        ));
        if let (Some(a), Some(m)) = (&assets, material) {
            e.insert((Mesh3d(a.sphere.clone()), MeshMaterial3d(m)));
        }
    }
}

/// Keeps handles the same size on screen: radius = distance to the camera ×
/// [`HandleSettings::screen_radius`].
pub fn scale_handles(
    settings: Res<HandleSettings>,
    cameras: Query<&GlobalTransform, With<Camera3d>>,
    mut handles: Query<&mut Transform, With<HandleMarker>>,
) {
    let Some(camera) = cameras.iter().next() else {
        return;
    };
    let eye = camera.translation();
    for mut t in &mut handles {
        let s = Vec3::splat((t.translation.distance(eye) * settings.screen_radius).max(1e-5));
        if t.scale != s {
            t.scale = s;
        }
    }
}

/// The operation that puts handle `id` of `node` at world point `world` (converted to the
/// node's frame, or its parent's for the origin).
pub fn handle_operation(
    doc: &Document,
    node: &str,
    id: &HandleId,
    world: Vec3,
) -> Result<Operation> {
    let n = doc.node(node)?;
    let frame = if matches!(id, HandleId::Origin) {
        match &n.parent {
            Some(p) => doc.world_transform(p)?,
            None => bevy::math::Affine3A::IDENTITY,
        }
    } else {
        doc.world_transform(node)?
    };
    if frame.matrix3.determinant().abs() < 1e-12 {
        return Err(DuctileBevyError::DegenerateFrame {
            node: node.to_owned(),
        });
    }
    let local = frame.inverse().transform_point3(world);
    Ok(match moved(doc, node, id, local)? {
        NodeEdit::Tool(tool) => Operation::set_tool(doc, node, tool)?,
        NodeEdit::Transform(t) => Operation::set_transform(doc, node, t)?,
        NodeEdit::Volume(shape) => Operation::set_volume(doc, node, shape)?,
    })
}

/// Toggles the drag's axis constraint with the X, Y and Z keys.
pub fn axis_keys(keys: Option<Res<ButtonInput<KeyCode>>>, mut drag: ResMut<DragState>) {
    let Some(keys) = keys else { return };
    if drag.active.is_none() {
        return;
    }
    for (key, axis) in [
        (KeyCode::KeyX, AxisConstraint::X),
        (KeyCode::KeyY, AxisConstraint::Y),
        (KeyCode::KeyZ, AxisConstraint::Z),
    ] {
        if keys.just_pressed(key) {
            let c = drag.constraint.toggled(axis);
            drag.constraint = c;
        }
    }
}

/// A primary press on a handle selects its node and the handle (with Shift: adds the handle
/// to the selected ones of that node, or removes it); on a mesh, the mesh. Nothing while
/// [`DragState::blocked`].
pub fn select_on_press(
    mut presses: MessageReader<Pointer<Press>>,
    keys: Option<Res<ButtonInput<KeyCode>>>,
    mut selection: ResMut<Selection>,
    drag: Res<DragState>,
    handles: Query<&HandleMarker>,
    nodes: Query<&crate::components::SceneNode, With<crate::components::MeshNodeMarker>>,
) {
    let shift = keys
        .as_ref()
        .is_some_and(|k| k.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]));
    let blocked = drag.blocked;
    for press in presses.read() {
        if press.event.button != PointerButton::Primary || blocked {
            continue;
        }
        match (handles.get(press.entity), nodes.get(press.entity)) {
            (Ok(h), _) => selection.press_handle(&h.node, h.id, shift),
            (_, Ok(n)) if !selection.is_selected(&n.name) => {
                selection.select(Some(n.name.clone()));
            }
            _ => {}
        }
    }
}

/// The operation that moves handles `ids` of `node` to the world points `targets`, as one
/// edit of the node (its tool or volume and, when the origin is among them, its transform):
/// the handles are moved one after the other on a copy of the document, the origin last.
pub fn handles_operation(
    doc: &Document,
    node: &str,
    moves: &[(HandleId, Vec3)],
) -> Result<Operation> {
    let mut ordered: Vec<&(HandleId, Vec3)> = moves.iter().collect();
    ordered.sort_by_key(|(id, _)| matches!(id, HandleId::Origin));
    let mut scratch = doc.clone();
    for (id, target) in ordered {
        handle_operation(&scratch, node, id, *target)?.apply(&mut scratch)?;
    }
    let before = doc.node(node)?;
    let after = scratch.node(node)?;
    let mut ops = Vec::new();
    if before.transform != after.transform {
        ops.push(Operation::set_transform(doc, node, after.transform)?);
    }
    match &after.kind {
        NodeKind::Tool(t) => ops.push(Operation::set_tool(doc, node, t.clone())?),
        NodeKind::Volume(v) => ops.push(Operation::set_volume(doc, node, v.shape.clone())?),
        _ => {}
    }
    Ok(Operation::Group {
        label: format!("move {} handles of '{node}'", moves.len()),
        ops,
    })
}

/// Starts, continues and ends handle drags from bevy's picking messages. The snap modifier
/// is Ctrl (either side).
#[allow(clippy::too_many_arguments)]
pub fn drag_handles(
    mut starts: MessageReader<Pointer<DragStart>>,
    mut drags: MessageReader<Pointer<Drag>>,
    mut ends: MessageReader<Pointer<DragEnd>>,
    keys: Option<Res<ButtonInput<KeyCode>>>,
    settings: Res<HandleSettings>,
    mut doc: ResMut<SceneDocument>,
    mut state: ResMut<DragState>,
    mut selection: ResMut<Selection>,
    mut edits: MessageWriter<DocumentCommand>,
    markers: Query<(&HandleMarker, &GlobalTransform)>,
    cameras: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
) {
    for start in starts.read() {
        if start.event.button != PointerButton::Primary || state.blocked {
            continue;
        }
        let Ok((marker, at)) = markers.get(start.entity) else {
            continue;
        };
        if !selection.is_selected(&marker.node) {
            selection.select(Some(marker.node.clone()));
        }
        // The other selected handles of the node come along.
        let with: Vec<(HandleId, Vec3)> = if selection.handles.contains(&marker.id) {
            markers
                .iter()
                .filter(|(m, _)| {
                    m.node == marker.node && m.id != marker.id && selection.handles.contains(&m.id)
                })
                .map(|(m, t)| (m.id, t.translation()))
                .collect()
        } else {
            Vec::new()
        };
        let gesture = doc.bypass_change_detection().new_gesture();
        state.active = Some(ActiveDrag {
            node: marker.node.clone(),
            id: marker.id,
            start: at.translation(),
            gesture,
            with,
        });
    }
    let last = drags
        .read()
        .filter(|d| d.event.button == PointerButton::Primary)
        .last()
        .cloned();
    if let (Some(drag), Some(active)) = (last, state.active.clone())
        && let Some((camera, camera_at)) = cameras.iter().find(|(c, _)| c.is_active)
        && let Ok(ray) = camera.viewport_to_world(camera_at, drag.pointer_location.position)
    {
        let snap = keys
            .as_ref()
            .is_some_and(|k| k.any_pressed([KeyCode::ControlLeft, KeyCode::ControlRight]))
            .then_some(settings.snap_step);
        if let Some(target) = drag_target(
            ray,
            active.start,
            camera_at.forward(),
            state.constraint,
            snap,
        ) {
            let op = if active.with.is_empty() {
                handle_operation(doc.shown(), &active.node, &active.id, target)
            } else {
                let delta = target - active.start;
                let moves: Vec<(HandleId, Vec3)> = std::iter::once((active.id, target))
                    .chain(active.with.iter().map(|(id, p)| (*id, *p + delta)))
                    .collect();
                handles_operation(doc.shown(), &active.node, &moves)
            };
            match op {
                Ok(op) => {
                    edits.write(DocumentCommand::Apply {
                        op: Box::new(op),
                        label: format!("drag '{}'", active.node),
                        gesture: Some(active.gesture),
                    });
                }
                Err(e) => warn!("drag of '{}': {e}", active.node),
            }
        }
    }
    if ends
        .read()
        .any(|e| e.event.button == PointerButton::Primary)
    {
        state.active = None;
        state.constraint = AxisConstraint::Free;
    }
}
