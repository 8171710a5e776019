//! Adding nodes from the Add menu and Shift+A: the new tool or volume is placed around the
//! mesh in focus (its current deformed shape), or around the selected layer's area when a
//! layer acting on part of the mesh is selected (the surface point under the cursor for
//! Shift+A, else the mesh's front — `ductile_scene::create`), gets a unique name, is parented to the
//! mesh and gets a layer on top of its stack (a volume masks the selected layer instead), all
//! as one undo step.

use bevy::picking::mesh_picking::ray_cast::{MeshRayCast, MeshRayCastSettings, RayCastVisibility};
use bevy::prelude::*;
use ductile_bevy::prelude::*;
use ductile_history::operation::Operation;
use ductile_scene::create::{self, Placement, SurfacePoint, front_point_of};
use ductile_scene::document::Document;
use ductile_scene::sketching::SketchKind;

use crate::panels::add_menu::AddRequest;
use crate::sketch::SketchState;
use crate::studio::Notices;

/// A node to add: what, and where the cursor was (window position, logical pixels) when
/// Shift+A opened the menu.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct AddNode {
    /// What to add.
    pub request: AddRequest,
    /// The cursor, for placing on the surface under it.
    pub cursor: Option<Vec2>,
}

/// The current (deformed) stored positions of mesh entity `ev`, or its rest positions.
fn current_positions(ev: &MeshEvaluation) -> Vec<Vec3> {
    match ev.evaluator().and_then(|e| e.deformed()) {
        Some(d) if d.refined.is_none() => d.positions.clone(),
        _ => ev.rest().mesh().positions.clone(),
    }
}

/// The current positions of the stored vertices the selected layer acts on (weight above 0
/// on its input), when a layer of mesh `mesh` is selected and it acts on some but not all of
/// them: the "selected area" a new tool is placed around.
fn selected_area(
    selection: &Selection,
    mesh: &str,
    ev: &MeshEvaluation,
    positions: &[Vec3],
) -> Option<Vec<Vec3>> {
    let (m, k) = selection.layer.as_ref()?;
    if m != mesh {
        return None;
    }
    let weights = ev.evaluator()?.layer_weights(*k)?;
    let area: Vec<Vec3> = weights
        .iter()
        .zip(positions)
        .filter(|(w, _)| **w > 0.0)
        .map(|(_, p)| *p)
        .collect();
    (!area.is_empty() && area.len() < positions.len()).then_some(area)
}

/// A new node's step: the operation (one undo step), the node's name, and the layer that
/// should be selected after it (the new tool's, or the layer a new volume masks).
#[derive(Debug, Clone, PartialEq)]
pub struct Added {
    /// The step.
    pub op: Operation,
    /// The new node's name.
    pub name: String,
    /// The layer to select.
    pub layer: Option<(String, usize)>,
}

/// The step that adds a tool or a volume to mesh `mesh` placed by `place`; `None` for the
/// requests that are not a node on a mesh (a group, sketch mode).
pub fn add_operation(
    doc: &Document,
    selection: &Selection,
    mesh: &str,
    request: AddRequest,
    place: &Placement,
) -> ductile_history::error::Result<Option<Added>> {
    Ok(match request {
        AddRequest::Tool(kind) => {
            let tool = create::tool(kind, place);
            let index = doc.mesh(mesh).map_or(0, |m| m.stack.len());
            let (op, name) = Operation::add_tool_layer(
                doc,
                mesh,
                kind.stem(),
                tool,
                ductile_scene::transform::Transform::IDENTITY,
            )?;
            Some(Added {
                op,
                name,
                layer: Some((mesh.to_owned(), index)),
            })
        }
        AddRequest::Volume(kind) => {
            let (shape, transform) = create::volume(kind, place);
            let mask = selection.layer.clone().filter(|(m, _)| m == mesh);
            let (op, name) = Operation::add_volume(
                doc,
                Some(mesh),
                kind.stem(),
                shape,
                transform,
                mask.as_ref().map(|(m, i)| (m.as_str(), *i)),
            )?;
            Some(Added {
                op,
                name,
                layer: mask,
            })
        }
        AddRequest::Group | AddRequest::SketchBend | AddRequest::SketchTwist => None,
    })
}

/// Carries out [`AddNode`] requests.
#[allow(clippy::too_many_arguments)]
pub fn add_nodes(
    mut requests: MessageReader<AddNode>,
    doc: Res<SceneDocument>,
    mut selection: ResMut<Selection>,
    mut sketch: ResMut<SketchState>,
    mut edits: MessageWriter<DocumentCommand>,
    mut notices: ResMut<Notices>,
    mut gestures: ResMut<crate::panels::Gestures>,
    mut ray_cast: MeshRayCast,
    cameras: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    meshes: Query<(Entity, &SceneNode, &MeshEvaluation, &GlobalTransform)>,
) {
    for request in requests.read() {
        let document = doc.shown();
        if request.request == AddRequest::Group {
            let parent = selection.node.clone().filter(|n| document.node(n).is_ok());
            if let Ok((op, name)) = Operation::add_group(document, parent.as_deref(), "group") {
                edits.write(DocumentCommand::apply(op));
                selection.select(Some(name));
            }
            continue;
        }
        let Some(mesh) = selection.mesh_in_focus(document) else {
            notices
                .0
                .push("Add: the scene has no mesh (File > Import mesh…)".to_owned());
            continue;
        };
        match request.request {
            AddRequest::SketchBend => {
                sketch.begin(&mesh, SketchKind::Bend, None);
                continue;
            }
            AddRequest::SketchTwist => {
                sketch.begin(&mesh, SketchKind::Twist, None);
                continue;
            }
            _ => {}
        }
        let Some((entity, _, ev, at)) = meshes.iter().find(|(_, n, _, _)| n.name == mesh) else {
            notices
                .0
                .push(format!("Add: mesh '{mesh}' is not loaded yet"));
            continue;
        };
        let positions = current_positions(ev);
        // The selected layer's area on this mesh (the vertices it acts on), when it is not
        // the whole mesh: the new node fits it instead of the mesh's bounds.
        let area = selected_area(&selection, &mesh, ev, &positions);
        let Some(mut place) = Placement::around(area.as_deref().unwrap_or(&positions)) else {
            continue;
        };
        if area.is_some()
            && let Some((_, k)) = &selection.layer
        {
            notices.0.push(format!(
                "Add: placed around the area of layer {k} (select no layer to use the whole mesh)"
            ));
        }
        // The surface point: under the cursor (Shift+A), else the mesh's front.
        let to_local = at.affine().inverse();
        let under_cursor = request.cursor.and_then(|cursor| {
            let (camera, camera_at) = cameras.iter().find(|(c, _)| c.is_active)?;
            let ray = camera.viewport_to_world(camera_at, cursor).ok()?;
            let filter = |e: Entity| e == entity;
            let settings = MeshRayCastSettings::default()
                .with_filter(&filter)
                .with_visibility(RayCastVisibility::Any);
            let (_, hit) = ray_cast.cast_ray(ray, &settings).first()?.clone();
            let normal = to_local.transform_vector3(hit.normal).try_normalize()?;
            Some(SurfacePoint {
                position: to_local.transform_point3(hit.point),
                normal,
            })
        });
        place.surface = under_cursor.or_else(|| {
            let indices = &ev.rest().mesh().indices;
            let triangles: Vec<[u32; 3]> = indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect();
            front_point_of(&positions, &triangles)
        });
        match add_operation(document, &selection, &mesh, request.request, &place) {
            Ok(Some(added)) => {
                // In a gesture of its own, which the "Adjust last operation" panel continues
                // (a lattice's resolution chosen right after adding it, in the same step).
                edits.write(DocumentCommand::Apply {
                    op: Box::new(added.op),
                    label: String::new(),
                    gesture: Some(gestures.fresh()),
                });
                selection.select(Some(added.name));
                selection.layer = added.layer;
            }
            Ok(None) => {}
            Err(e) => notices.0.push(format!("Add: {e}")),
        }
    }
}
