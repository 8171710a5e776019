//! Sketch mode (Kho & Garland in the viewport): draw the reference stroke on the mesh, then
//! the target stroke (bend) or a stroke whose length sets the angle (twist); after the
//! reference, C draws a cut line that makes the parts beyond it rigid. While sketching the
//! mesh shows the region of interest with the paper's blue-to-red ramp of `s(v)` and rigid
//! parts in orange. Escape cancels; each completed sketch is one undo step (a new sketch tool
//! with its layer, or the redrawn tool's new strokes). The left mouse button draws; the middle
//! and right buttons and the wheel still move the camera.
//!
//! The logic (projection, partition, tools) is in `ductile_scene::sketching`; this module
//! turns pointer input into strokes and strokes into document operations.

use bevy::mesh::VertexAttributeValues;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use ductile_bevy::prelude::*;
use ductile_core::sketch::camera::{Camera as SketchCamera, Projection as SketchProjection};
use ductile_core::sketch::tool::{SketchMode, Stroke};
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::document::NodeKind;
use ductile_scene::sketching::{self, Preview, SketchKind};

use crate::camera::{KeyboardToViewport, PointerOverViewport};
use crate::ui::ViewportRect;

/// What the next stroke is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The reference stroke (along the part to deform).
    Reference,
    /// The target stroke (bend) or the twist stroke.
    Second,
    /// A cut line (press C after the reference).
    Cut,
}

/// A sketch in progress.
#[derive(Debug, Clone)]
pub struct Session {
    /// The mesh node sketched on.
    pub mesh: String,
    /// Bend or twist.
    pub kind: SketchKind,
    /// The sketch tool node whose strokes are redrawn, if any (else a new tool is made).
    pub redraw: Option<String>,
    /// What the next stroke is.
    pub stage: Stage,
    /// The reference stroke, once drawn (pixels relative to the viewport, and the camera).
    pub reference: Option<Stroke>,
    /// The preview of the reference (and the cuts).
    pub preview: Option<Preview>,
    /// The stroke being drawn (viewport pixels).
    pub drawing: Vec<Vec2>,
    /// The last problem (a stroke that missed the mesh…), shown to the user.
    pub problem: Option<String>,
}

/// Sketch mode's state: the session, if sketching.
#[derive(Resource, Debug, Default)]
pub struct SketchState {
    /// The sketch in progress.
    pub session: Option<Session>,
    /// Where Shift+A asked for the Add popup (window position), until the UI opens it.
    pub add_popup: Option<Vec2>,
    /// Colours were written on this mesh and must be taken off when the sketch ends.
    painted: Option<String>,
}

impl SketchState {
    /// Starts sketching on `mesh` (a new tool, or the strokes of tool `redraw` again).
    pub fn begin(&mut self, mesh: &str, kind: SketchKind, redraw: Option<String>) {
        self.session = Some(Session {
            mesh: mesh.to_owned(),
            kind,
            redraw,
            stage: Stage::Reference,
            reference: None,
            preview: None,
            drawing: Vec::new(),
            problem: None,
        });
    }

    /// True while a sketch is in progress (the left button draws instead of orbiting).
    #[must_use]
    pub fn active(&self) -> bool {
        self.session.is_some()
    }

    /// The hint shown over the viewport.
    #[must_use]
    pub fn hint(&self) -> Option<String> {
        let s = self.session.as_ref()?;
        let what = match s.kind {
            SketchKind::Bend => "bend",
            SketchKind::Twist => "twist",
        };
        let step = match (s.stage, s.kind) {
            (Stage::Reference, _) => "draw the reference stroke along the part to deform".to_owned(),
            (Stage::Second, SketchKind::Bend) => {
                "draw the target stroke (where the reference should go); C: cut line".to_owned()
            }
            (Stage::Second, SketchKind::Twist) => {
                "draw the twist stroke: its length sets the angle (as long as the reference: one turn); C: cut line".to_owned()
            }
            (Stage::Cut, _) => "draw a cut line across the part to keep rigid".to_owned(),
        };
        let problem = s
            .problem
            .as_ref()
            .map(|p| format!("  — {p}"))
            .unwrap_or_default();
        Some(format!("Sketch {what}: {step}; Esc cancels{problem}"))
    }

    /// The strokes to draw over the viewport (viewport pixels) and their colours.
    #[must_use]
    pub fn strokes(&self) -> Vec<(Vec<Vec2>, [u8; 3])> {
        let Some(s) = &self.session else {
            return Vec::new();
        };
        let mut out = Vec::new();
        if let Some(r) = &s.reference {
            out.push((r.pixels.clone(), [90, 170, 255]));
        }
        if !s.drawing.is_empty() {
            let color = match s.stage {
                Stage::Reference => [90, 170, 255],
                Stage::Second => [255, 120, 60],
                Stage::Cut => [255, 240, 80],
            };
            out.push((s.drawing.clone(), color));
        }
        out
    }
}

/// The sketch camera of the 3-D view, in the mesh's frame: eye, target and up of the bevy
/// camera mapped by the inverse of the mesh's world transform; the viewport is the 3-D view's
/// rectangle in logical pixels.
fn sketch_camera(
    camera: &GlobalTransform,
    projection: &Projection,
    mesh_world: &GlobalTransform,
    size: Vec2,
) -> SketchCamera {
    let to_mesh = mesh_world.affine().inverse();
    let eye = camera.translation();
    let (fov_y, near, far) = match projection {
        Projection::Perspective(p) => (p.fov, p.near, p.far),
        _ => (std::f32::consts::FRAC_PI_4, 0.01, 1000.0),
    };
    SketchCamera {
        eye: to_mesh.transform_point3(eye),
        target: to_mesh.transform_point3(eye + *camera.forward()),
        up: to_mesh.transform_vector3(*camera.up()),
        projection: SketchProjection::Perspective { fov_y },
        near,
        far,
        viewport: size,
    }
}

/// The welded positions the new layer will see (the mesh's current output) and its
/// topology.
fn layer_input(ev: &MeshEvaluation) -> Vec<Vec3> {
    let topology = ev.rest().topology();
    match ev.evaluator().and_then(|e| e.deformed()) {
        Some(d) if d.refined.is_none() => topology
            .representative
            .iter()
            .map(|&s| d.positions[s as usize])
            .collect(),
        _ => ev.rest().welded_positions().to_vec(),
    }
}

/// Paints (or, with `None`, unpaints) the preview colours on the mesh asset.
fn paint(meshes: &mut Assets<Mesh>, ev: &MeshEvaluation, preview: Option<&Preview>) {
    let Some(mut mesh) = meshes.get_mut(&ev.mesh.clone()) else {
        return;
    };
    match preview {
        Some(p) => {
            let topology = ev.rest().topology();
            let welded = p.colors(topology.vertex_count());
            let count = mesh
                .attribute(Mesh::ATTRIBUTE_POSITION)
                .map_or(0, VertexAttributeValues::len);
            if topology.weld.len() == count {
                let colors: Vec<[f32; 4]> =
                    topology.weld.iter().map(|&w| welded[w as usize]).collect();
                mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, colors);
            }
        }
        None => {
            mesh.remove_attribute(Mesh::ATTRIBUTE_COLOR);
        }
    }
}

/// Turns pointer input into strokes and strokes into operations (see the module docs).
#[allow(clippy::too_many_arguments)]
pub fn sketch_input(
    mut state: ResMut<SketchState>,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    keyboard: Res<KeyboardToViewport>,
    over: Res<PointerOverViewport>,
    rect: Res<ViewportRect>,
    windows: Query<&Window, With<PrimaryWindow>>,
    cameras: Query<(&GlobalTransform, &Projection), With<Camera3d>>,
    doc: Res<SceneDocument>,
    evaluations: Query<(&SceneNode, &MeshEvaluation, &GlobalTransform)>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut edits: MessageWriter<DocumentCommand>,
    mut selection: ResMut<Selection>,
) {
    let state = &mut *state;
    let Some(session) = &mut state.session else {
        if let Some(mesh) = state.painted.take()
            && let Some((_, ev, _)) = evaluations.iter().find(|(n, _, _)| n.name == mesh)
        {
            paint(&mut meshes, ev, None);
        }
        return;
    };
    let Some((_, ev, mesh_at)) = evaluations.iter().find(|(n, _, _)| n.name == session.mesh) else {
        state.session = None;
        return;
    };
    if keyboard.0 && keys.just_pressed(KeyCode::Escape) {
        state.session = None;
        return;
    }
    if keyboard.0 && keys.just_pressed(KeyCode::KeyC) && session.preview.is_some() {
        session.stage = Stage::Cut;
        session.drawing.clear();
    }
    let Some((min, max)) = rect.0 else { return };
    let cursor = windows
        .single()
        .ok()
        .and_then(Window::cursor_position)
        .map(|c| c - min);
    if buttons.just_pressed(MouseButton::Left) && over.0 {
        session.drawing.clear();
        if let Some(c) = cursor {
            session.drawing.push(c);
        }
    } else if buttons.pressed(MouseButton::Left)
        && !session.drawing.is_empty()
        && let Some(c) = cursor
        && session.drawing.last().is_none_or(|l| l.distance(c) >= 1.0)
    {
        session.drawing.push(c);
    }
    if !buttons.just_released(MouseButton::Left) || session.drawing.is_empty() {
        return;
    }
    let pixels = std::mem::take(&mut session.drawing);
    let Ok((camera_at, projection)) = cameras.single() else {
        return;
    };
    let camera = sketch_camera(camera_at, projection, mesh_at, max - min);
    let stroke = Stroke { pixels, camera };
    let topology = ev.rest().topology();
    let input = layer_input(ev);
    match session.stage {
        Stage::Reference => match sketching::preview(session.kind, &stroke, &input, topology) {
            Ok(p) => {
                paint(&mut meshes, ev, Some(&p));
                state.painted = Some(session.mesh.clone());
                session.preview = Some(p);
                session.reference = Some(stroke);
                session.stage = Stage::Second;
                session.problem = None;
            }
            Err(e) => session.problem = Some(format!("{e}; draw it again, on the mesh")),
        },
        Stage::Cut => {
            let (Some(p), Some(first), Some(last)) = (
                &session.preview,
                stroke.pixels.first().copied(),
                stroke.pixels.last().copied(),
            ) else {
                return;
            };
            match sketching::cut(p, &stroke.camera, [first, last], &input, topology) {
                Ok(p) => {
                    paint(&mut meshes, ev, Some(&p));
                    session.preview = Some(p);
                    session.problem = None;
                }
                Err(e) => session.problem = Some(e.to_string()),
            }
            session.stage = Stage::Second;
        }
        Stage::Second => {
            let Some(reference) = session.reference.clone() else {
                return;
            };
            // A cut partition is kept; else the tool computes its own when it binds.
            let cut = session
                .preview
                .as_ref()
                .filter(|p| p.partition.rigid.len() > 1)
                .map(|p| p.partition.clone());
            let tool = match (session.kind, &session.preview) {
                // On the previewed reference curve: the target becomes a keyable channel.
                (SketchKind::Bend, Some(p)) => {
                    match sketching::bend_tool_on(&p.curve, &reference, &stroke, cut) {
                        Ok(t) => t,
                        Err(e) => {
                            session.problem = Some(e.to_string());
                            return;
                        }
                    }
                }
                (SketchKind::Bend, None) => sketching::bend_tool(reference, stroke, cut),
                (SketchKind::Twist, _) => {
                    let angle = sketching::twist_angle(&reference.pixels, &stroke.pixels);
                    sketching::twist_tool(reference, angle, cut)
                }
            };
            if let Err(e) = tool.validate("sketch tool") {
                session.problem = Some(e.to_string());
                return;
            }
            let document = doc.shown();
            let op = match &session.redraw {
                Some(node) => Operation::set_tool(document, node, redrawn(document, node, tool))
                    .map(|op| (op, node.clone())),
                None => Operation::add_tool_layer(
                    document,
                    &session.mesh,
                    match session.kind {
                        SketchKind::Bend => "bend",
                        SketchKind::Twist => "twist",
                    },
                    tool,
                    ductile_scene::transform::Transform::IDENTITY,
                ),
            };
            match op {
                Ok((op, name)) => {
                    edits.write(DocumentCommand::apply(op));
                    selection.select(Some(name));
                    state.session = None;
                }
                Err(e) => session.problem = Some(e.to_string()),
            }
        }
    }
}

/// The redrawn tool: the new strokes with the old tool's other settings (spline controls,
/// smoothing, refinement, normal).
fn redrawn(doc: &ductile_scene::document::Document, node: &str, new: Tool) -> Tool {
    let (Ok(NodeKind::Tool(Tool::Sketch(old))), Tool::Sketch(mut s)) =
        (doc.node(node).map(|n| &n.kind), new.clone())
    else {
        return new;
    };
    s.scale = old.scale.clone();
    s.smooth = old.smooth;
    s.refine = old.refine;
    s.normal = old.normal;
    match (&mut s.mode, &old.mode) {
        (SketchMode::Bend { turning, .. }, SketchMode::Bend { turning: t, .. }) => {
            turning.clone_from(t);
        }
        (SketchMode::Twist { speed, .. }, SketchMode::Twist { speed: v, .. }) => {
            speed.clone_from(v);
        }
        _ => {}
    }
    Tool::Sketch(s)
}
