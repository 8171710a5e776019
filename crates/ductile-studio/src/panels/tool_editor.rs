//! The inspector's tool section: for every tool kind its structure (modes, bases, counts,
//! adding and removing points) and every parameter (through [`super::params`]), and the
//! selected handles' values (a lattice control point's offset and weight, a shape surface
//! point's move and height). Every edit is checked by the tool's rules first; a refused one
//! shows its reason and changes nothing.

use bevy::math::Vec3;
use bevy_egui::egui;
use ductile_anim::channel::{set_tool_channel, tool_channels};
use ductile_anim::value::Value;
use ductile_core::axial::{AxialTool, AxisPoint, AxisShape};
use ductile_core::curve::{CurveBasis, CurveTool};
use ductile_core::direct_ffd::DirectConstraint;
use ductile_core::dogme::{Anchor, Constraint, DogmeTool, Support};
use ductile_core::ffsd::{ControlPoint, FfsdTool, HeightLimit, PointMode};
use ductile_core::influence::Falloff;
use ductile_core::lattice::{ControlEdit, LatticeBasis, LatticeTool};
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};
use ductile_core::spline::SplineControl;
use ductile_core::surface::{HeightEdit, ShapeSurfaceTool, SurfaceEdit};
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::create::resized_lattice;
use ductile_scene::handles::HandleId;

use super::curve_editor::{curve_editor, spline_structure};
use super::params::{REFUSED, Refusals, meta, parameter_list, value_widget};
use super::{PanelContext, PanelRequest};

/// The tool section's state: refused edits and their reasons.
#[derive(Debug, Default)]
pub struct ToolEditor {
    /// Reasons of refused edits, by parameter path (or "structure").
    pub refusals: Refusals,
}

/// A combo box of labelled choices; returns the index picked when it changed.
fn choice(
    ui: &mut egui::Ui,
    id: impl std::hash::Hash + std::fmt::Debug,
    current: usize,
    labels: &[&str],
) -> Option<usize> {
    let mut picked = current;
    egui::ComboBox::from_id_salt(id)
        .selected_text(labels.get(current).copied().unwrap_or("?"))
        .show_ui(ui, |ui| {
            for (i, l) in labels.iter().enumerate() {
                ui.selectable_value(&mut picked, i, *l);
            }
        });
    (picked != current).then_some(picked)
}

/// Adds `widget`; when it changed its value, keeps its response in `response` (so that a
/// drag of it is one undo step, [`PanelContext::apply_in_gesture`]) and returns true.
fn dragged(
    ui: &mut egui::Ui,
    widget: impl egui::Widget,
    response: &mut Option<egui::Response>,
) -> bool {
    let r = ui.add(widget);
    let changed = r.changed();
    if changed {
        *response = Some(r);
    }
    changed
}

/// A labelled count field in `range`; see [`dragged`].
fn count_edit(
    ui: &mut egui::Ui,
    label: &str,
    v: &mut u32,
    range: std::ops::RangeInclusive<u32>,
    response: &mut Option<egui::Response>,
) -> bool {
    ui.label(label);
    dragged(
        ui,
        egui::DragValue::new(v).range(range).speed(0.05),
        response,
    )
}

impl ToolEditor {
    /// Draws the tool section of node `name` holding `tool`.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>, name: &str, tool: &Tool) {
        self.refusals.for_node(name);
        ui.label(egui::RichText::new(tool.kind_name()).strong());
        // Structure.
        let mut structural: Option<(Tool, Option<egui::Response>)> = None;
        ui.push_id("structure", |ui| {
            structural = structure(ui, cx, name, tool);
        });
        if let Some(reason) = self.refusals.reason("structure") {
            ui.colored_label(REFUSED, format!("refused: {reason}"));
        }
        if let Some((new, response)) = structural {
            let problem = AnchorMesh::all(cx, name)
                .iter()
                .find_map(|m| m.problem(&new, tool));
            match problem {
                Some(reason) => self.refusals.refuse("structure", reason),
                None => self.apply(cx, name, tool, new, "structure", response),
            }
        }
        // The selected handles' own values.
        let selected: Vec<HandleId> = cx.selection.handles.iter().copied().collect();
        if let Some((new, response)) = selected_points(ui, tool, &selected) {
            self.apply(cx, name, tool, new, "selected point", Some(response));
        }
        if let Some(reason) = self.refusals.reason("selected point") {
            ui.colored_label(REFUSED, format!("refused: {reason}"));
        }
        ui.separator();
        // Every parameter.
        let channels = tool_channels(tool);
        if channels.is_empty() {
            ui.weak("No numeric parameter.");
        }
        let degree = |path: &str| spline_of(tool, path).map(|f| f.degree);
        if let Some(edit) = parameter_list(ui, cx.doc, name, &channels, &self.refusals, &degree) {
            let mut new = tool.clone();
            match set_tool_channel(&mut new, &edit.path, &edit.value) {
                Ok(()) => self.apply(cx, name, tool, new, &edit.path, Some(edit.response)),
                Err(e) => self.refusals.refuse(&edit.path, e.to_string()),
            }
        }
    }

    /// Applies `new` in place of `old` when it validates (a drag is one gesture), else
    /// records the reason under `what`.
    fn apply(
        &mut self,
        cx: &mut PanelContext<'_>,
        name: &str,
        old: &Tool,
        new: Tool,
        what: &str,
        response: Option<egui::Response>,
    ) {
        if &new == old {
            return;
        }
        if let Err(e) = new.validate(&format!("tool '{name}'")) {
            self.refusals.refuse(what, e.to_string());
            return;
        }
        self.refusals.accept(what);
        let doc = cx.doc.shown();
        let Ok(op) = Operation::set_tool(doc, name, new) else {
            return;
        };
        match response {
            Some(r) => cx.apply_in_gesture(&r, op, format!("edit '{name}'")),
            None => cx.apply(op),
        }
    }
}

/// The spline control `F(s)` whose values channel `path` of `tool` holds (a sketch tool's
/// turning, twist-speed or scale control).
fn spline_of<'a>(tool: &'a Tool, path: &str) -> Option<&'a SplineControl> {
    let Tool::Sketch(s) = tool else {
        return None;
    };
    match (path, &s.mode) {
        ("mode.turning.values", SketchMode::Bend { turning, .. }) => turning.as_ref(),
        ("mode.speed.values", SketchMode::Twist { speed, .. }) => speed.as_ref(),
        ("scale.values", _) => s.scale.as_ref(),
        _ => None,
    }
}

/// The structure controls of `tool`; returns the changed tool (and the widget, for drags).
fn structure(
    ui: &mut egui::Ui,
    cx: &mut PanelContext<'_>,
    name: &str,
    tool: &Tool,
) -> Option<(Tool, Option<egui::Response>)> {
    let mut t = tool.clone();
    let mut response = None;
    let changed = match &mut t {
        Tool::Ffsd(f) => ffsd(ui, f),
        Tool::Dogme(d) => dogme(ui, d, AnchorMesh::of(cx, name).as_ref(), &mut response),
        Tool::DirectFfd(d) => {
            let mesh = AnchorMesh::of(cx, name);
            let mut a = lattice_structure(ui, &mut d.lattice, &mut response);
            lattice_hint(ui, &d.lattice);
            for (i, c) in d.constraints.iter_mut().enumerate() {
                ui.horizontal(|ui| {
                    ui.label(format!("constraint {i}"));
                    a |= anchor_choice(
                        ui,
                        ("direct-anchor", i),
                        &mut c.at,
                        mesh.as_ref(),
                        &mut response,
                    );
                });
            }
            let b = ui
                .horizontal(|ui| {
                    ui.label(format!("{} constraints", d.constraints.len()));
                    let add = ui.button("+ constraint").clicked();
                    if add {
                        let at = d
                            .constraints
                            .last()
                            .map_or(Anchor::Point(d.lattice.frame.origin), |c| c.at);
                        d.constraints.push(DirectConstraint {
                            at,
                            displacement: Vec3::ZERO,
                        });
                    }
                    let remove = d.constraints.len() > 1 && ui.button("− last").clicked();
                    if remove {
                        d.constraints.pop();
                    }
                    add || remove
                })
                .inner;
            a || b
        }
        Tool::Lattice(l) => {
            let c = lattice_structure(ui, l, &mut response);
            lattice_hint(ui, l);
            c
        }
        Tool::Axial(a) => {
            let (c, r) = axial(ui, a);
            response = r;
            c
        }
        Tool::Curve(c) => curve(ui, c, &mut response),
        Tool::ShapeSurface(s) => surface(ui, s, &mut response),
        Tool::Sketch(s) => {
            if ui
                .button("Redraw strokes…")
                .on_hover_text("Sketch mode: draw this tool's strokes again (Esc cancels)")
                .clicked()
            {
                cx.requests
                    .push(PanelRequest::RedrawSketch(name.to_owned()));
            }
            let mut straightened = false;
            if let Some(straight) = ductile_scene::sketching::straight_target(s)
                && ui
                    .button("Straight target (no bend)")
                    .on_hover_text(
                        "Sets the target curve to the reference: the region rests undeformed \
                         (key it at the first frame, the bend at a later one)",
                    )
                    .clicked()
                && let SketchMode::Bend { target, .. } = &mut s.mode
            {
                *target = Curve::Points(straight);
                straightened = true;
            }
            let (c, r) = sketch(ui, s);
            response = r;
            c || straightened
        }
    };
    changed.then_some((t, response))
}

fn ffsd(ui: &mut egui::Ui, f: &mut FfsdTool) -> bool {
    let mut changed = false;
    let mut remove = None;
    for (i, p) in f.points.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("point {i}"));
            let current = match p.mode {
                PointMode::Basic => 0,
                PointMode::Virtual => 1,
                PointMode::Directional { .. } => 2,
            };
            if let Some(k) = choice(
                ui,
                ("mode", i),
                current,
                &["basic", "virtual", "directional"],
            ) {
                p.mode = match k {
                    0 => PointMode::Basic,
                    1 => PointMode::Virtual,
                    _ => PointMode::Directional {
                        // R below C by ε: the point pulls along that direction.
                        reference: p.position - Vec3::Z * p.epsilon,
                    },
                };
                changed = true;
            }
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove
        && f.points.len() > 1
    {
        f.points.remove(i);
        changed = true;
    }
    ui.horizontal(|ui| {
        if ui.button("+ point").clicked() {
            let mut p =
                f.points
                    .last()
                    .copied()
                    .unwrap_or(ControlPoint::basic(Vec3::ZERO, 0.5, 2.0, 0.1));
            p.position += Vec3::X * p.epsilon;
            if let PointMode::Directional { reference } = &mut p.mode {
                *reference += Vec3::X * p.epsilon;
            }
            f.points.push(p);
            changed = true;
        }
        ui.label("height limit");
        let current = match f.height {
            None => 0,
            Some(HeightLimit::Above { .. }) => 1,
            Some(HeightLimit::Below { .. }) => 2,
            Some(HeightLimit::Both { .. }) => 3,
        };
        if let Some(k) = choice(
            ui,
            "height",
            current,
            &["none", "from above", "from below", "both sides"],
        ) {
            f.height = match k {
                0 => None,
                1 => Some(HeightLimit::Above { theta: 0.8 }),
                2 => Some(HeightLimit::Below { theta: 0.8 }),
                _ => Some(HeightLimit::Both {
                    below: 0.2,
                    above: 0.8,
                }),
            };
            changed = true;
        }
    });
    changed
}

/// The mesh whose welded vertices a tool's vertex anchors index: the first loaded mesh whose
/// stack uses the tool, with the tool-to-mesh transform and the rest positions.
struct AnchorMesh {
    name: String,
    to_mesh: bevy::math::Affine3A,
    rest: std::sync::Arc<ductile_core::mesh::RestMesh>,
}

impl AnchorMesh {
    /// Every loaded mesh whose stack uses `tool`, by name.
    fn all(cx: &PanelContext<'_>, tool: &str) -> Vec<Self> {
        let doc = cx.doc.shown();
        let mut all: Vec<Self> = cx
            .meshes
            .iter()
            .filter_map(|(mesh, rest)| {
                let uses = doc
                    .mesh(mesh)
                    .is_ok_and(|m| m.stack.iter().any(|l| l.tool == tool));
                let to_mesh = doc.to_mesh_space(tool, mesh).ok()?;
                uses.then(|| Self {
                    name: mesh.clone(),
                    to_mesh,
                    rest: rest.clone(),
                })
            })
            .collect();
        all.sort_by(|a, b| a.name.cmp(&b.name));
        all
    }

    /// The first of [`AnchorMesh::all`] by name: where a switched anchor is placed.
    fn of(cx: &PanelContext<'_>, tool: &str) -> Option<Self> {
        Self::all(cx, tool).into_iter().next()
    }

    fn vertices(&self) -> usize {
        self.rest.welded_positions().len()
    }

    /// Why a vertex anchor of `new` that differs from `old`'s (an edit) does not fit this
    /// mesh, if one does not. Anchors the edit left alone are not judged: a tool whose other
    /// anchors no longer fit (its mesh re-imported smaller) can still be repaired one by one.
    fn problem(&self, new: &Tool, old: &Tool) -> Option<String> {
        let anchors = |t: &Tool| -> Vec<Anchor> {
            match t {
                Tool::Dogme(d) => d.constraints.iter().map(|c| c.at).collect(),
                Tool::DirectFfd(d) => d.constraints.iter().map(|c| c.at).collect(),
                _ => Vec::new(),
            }
        };
        let (new, old) = (anchors(new), anchors(old));
        let n = self.vertices();
        new.iter().enumerate().find_map(|(k, a)| match a {
            Anchor::Vertex(v) if *v as usize >= n && old.get(k) != Some(a) => Some(format!(
                "constraint {k}: vertex {v} does not exist (mesh '{}' has {n} welded vertices, 0 to {})",
                self.name,
                n.saturating_sub(1)
            )),
            _ => None,
        })
    }
}

/// A constraint's anchor: a free point or a mesh vertex (its index). Switching keeps the
/// place: a point becomes the closest rest vertex of the mesh, a vertex the point at its rest
/// position. Returns true when the anchor changed.
fn anchor_choice(
    ui: &mut egui::Ui,
    id: impl std::hash::Hash + std::fmt::Debug,
    at: &mut Anchor,
    mesh: Option<&AnchorMesh>,
    drag: &mut Option<egui::Response>,
) -> bool {
    let mut changed = false;
    let current = usize::from(matches!(at, Anchor::Vertex(_)));
    if let Some(k) = choice(ui, id, current, &["free point", "mesh vertex"]) {
        *at = match (*at, k, mesh) {
            (Anchor::Point(p), 1, Some(m)) => {
                let q = m.to_mesh.transform_point3(p);
                let closest = m
                    .rest
                    .welded_positions()
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.distance_squared(q).total_cmp(&b.1.distance_squared(q)))
                    .map_or(0, |(i, _)| i as u32);
                Anchor::Vertex(closest)
            }
            (Anchor::Vertex(v), 0, Some(m)) => Anchor::Point(
                m.rest
                    .welded_positions()
                    .get(v as usize)
                    .map_or(Vec3::ZERO, |&q| m.to_mesh.inverse().transform_point3(q)),
            ),
            (_, 0, _) => Anchor::Point(Vec3::ZERO),
            _ => Anchor::Vertex(0),
        };
        changed = true;
    }
    if let Anchor::Vertex(v) = at {
        let r = ui.add(egui::DragValue::new(v).prefix("vertex ").speed(1.0));
        let r = match mesh {
            Some(m) => r.on_hover_text(format!(
                "welded vertex of mesh '{}', 0 to {}",
                m.name,
                m.vertices().saturating_sub(1)
            )),
            None => r,
        };
        if r.changed() {
            changed = true;
            *drag = Some(r);
        }
    }
    changed
}

fn dogme(
    ui: &mut egui::Ui,
    d: &mut DogmeTool,
    mesh: Option<&AnchorMesh>,
    drag: &mut Option<egui::Response>,
) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("degree");
        changed |= dragged(ui, egui::DragValue::new(&mut d.degree).speed(0.05), drag);
    });
    let mut remove = None;
    for (i, c) in d.constraints.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("constraint {i}"));
            changed |= anchor_choice(ui, ("anchor", i), &mut c.at, mesh, drag);
            let support = usize::from(matches!(c.support, Support::Box { .. }));
            if let Some(k) = choice(
                ui,
                ("support", i),
                support,
                &["sphere support", "box support"],
            ) {
                let size = match c.support {
                    Support::Sphere { radius } => radius,
                    Support::Box { half_extents, .. } => half_extents.max_element(),
                };
                c.support = if k == 0 {
                    Support::Sphere { radius: size }
                } else {
                    Support::Box {
                        half_extents: Vec3::splat(size),
                        rotation: bevy::math::Quat::IDENTITY,
                    }
                };
                changed = true;
            }
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove
        && d.constraints.len() > 1
    {
        d.constraints.remove(i);
        changed = true;
    }
    if ui.button("+ constraint").clicked()
        && let Some(c) = d.constraints.last().copied()
    {
        d.constraints.push(Constraint {
            at: match c.at {
                Anchor::Point(p) => Anchor::Point(p + Vec3::X * 0.1),
                other => other,
            },
            ..c
        });
        changed = true;
    }
    changed
}

/// The lattice's structure: control point counts (a resize keeps the moved points where it
/// can, [`resized_lattice`]), basis and degrees. Returns true when it changed; a changed
/// field's response goes to `response` (see [`dragged`]).
pub fn lattice_structure(
    ui: &mut egui::Ui,
    l: &mut LatticeTool,
    response: &mut Option<egui::Response>,
) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let mut counts = l.counts;
        let mut any = false;
        any |= count_edit(ui, "points", &mut counts.0, 2..=16, response);
        any |= count_edit(ui, "×", &mut counts.1, 2..=16, response);
        any |= count_edit(ui, "×", &mut counts.2, 2..=16, response);
        if any && counts != l.counts {
            *l = resized_lattice(l, counts);
            changed = true;
        }
    });
    ui.horizontal(|ui| {
        ui.label("basis");
        let current = usize::from(matches!(l.basis, LatticeBasis::BSpline { .. }));
        if let Some(k) = choice(ui, "lattice-basis", current, &["Bernstein", "B-spline"]) {
            l.basis = if k == 0 {
                LatticeBasis::Bernstein
            } else {
                let d = |n: u32| n.saturating_sub(1).clamp(1, 3);
                LatticeBasis::BSpline {
                    degree: (d(l.counts.0), d(l.counts.1), d(l.counts.2)),
                }
            };
            changed = true;
        }
        if let LatticeBasis::BSpline { degree } = &mut l.basis {
            ui.label("degrees");
            for d in [&mut degree.0, &mut degree.1, &mut degree.2] {
                changed |= dragged(ui, egui::DragValue::new(d).speed(0.05), response);
            }
        }
    });
    changed
}

/// What to do with a lattice's control points, under its structure.
fn lattice_hint(ui: &mut egui::Ui, l: &LatticeTool) {
    ui.weak(format!(
        "{} moved control points; click one in the viewport to edit it (Shift: several)",
        l.points.len()
    ));
}

fn axial(ui: &mut egui::Ui, a: &mut AxialTool) -> (bool, Option<egui::Response>) {
    let mut changed = false;
    let mut response = None;
    ui.horizontal(|ui| {
        ui.label("axis");
        let current = match a.shape {
            AxisShape::Polyline => 0,
            AxisShape::Bezier => 1,
            AxisShape::BSpline { .. } => 2,
        };
        if let Some(k) = choice(
            ui,
            "axis-shape",
            current,
            &["polyline", "Bézier", "B-spline"],
        ) {
            a.shape = match k {
                0 => AxisShape::Polyline,
                1 => AxisShape::Bezier,
                _ => AxisShape::BSpline {
                    degree: 3.min(a.rest.len().saturating_sub(1)).max(1),
                },
            };
            changed = true;
        }
        if let AxisShape::BSpline { degree } = &mut a.shape {
            let field = egui::DragValue::new(degree).prefix("degree ").speed(0.05);
            changed |= dragged(ui, field, &mut response);
        }
        ui.label("falloff");
        changed |= falloff_choice(ui, "axial-falloff", &mut a.falloff);
    });
    if let Falloff::Curve(f) = &mut a.falloff {
        ui.label("weight F(s) from the radius (s = 0) to the inner radius (s = 1)");
        let mut values = f.values.clone();
        let r = curve_editor(
            ui,
            egui::Id::new("axial-falloff-curve"),
            &mut values,
            f.degree,
        );
        if r.changed() {
            f.values = values;
            response = Some(r);
            changed = true;
        }
        changed |= spline_structure(ui, f, &mut response);
    }
    ui.horizontal(|ui| {
        ui.label(format!("{} axis points", a.rest.len()));
        if ui.button("+ point").clicked() {
            extend_axis(&mut a.rest);
            extend_axis(&mut a.deformed);
            changed = true;
        }
        if a.rest.len() > 2 && ui.button("− last").clicked() {
            a.rest.pop();
            a.deformed.pop();
            changed = true;
        }
    });
    (changed, response)
}

fn extend_axis(points: &mut Vec<AxisPoint>) {
    let n = points.len();
    if n >= 2 {
        let (a, b) = (points[n - 2], points[n - 1]);
        points.push(AxisPoint {
            position: b.position + (b.position - a.position),
            ..b
        });
    }
}

fn curve(ui: &mut egui::Ui, c: &mut CurveTool, response: &mut Option<egui::Response>) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("basis");
        let current = usize::from(matches!(c.basis, CurveBasis::BSpline { .. }));
        if let Some(k) = choice(
            ui,
            "curve-basis",
            current,
            &["Bézier (De Casteljau)", "B-spline (De Boor)"],
        ) {
            c.basis = if k == 0 {
                CurveBasis::Bezier
            } else {
                CurveBasis::BSpline {
                    degree: 3.min(c.rest.len().saturating_sub(1)).max(1),
                }
            };
            changed = true;
        }
        if let CurveBasis::BSpline { degree } = &mut c.basis {
            let field = egui::DragValue::new(degree).prefix("degree ").speed(0.05);
            changed |= dragged(ui, field, response);
        }
    });
    ui.horizontal(|ui| {
        ui.label(format!("{} control points", c.rest.len()));
        if ui.button("+ point").clicked() {
            for p in [&mut c.rest, &mut c.deformed] {
                let n = p.len();
                if n >= 2 {
                    let next = p[n - 1] + (p[n - 1] - p[n - 2]);
                    p.push(next);
                }
            }
            changed = true;
        }
        if c.rest.len() > 2 && ui.button("− last").clicked() {
            c.rest.pop();
            c.deformed.pop();
            changed = true;
        }
    });
    changed
}

fn surface(
    ui: &mut egui::Ui,
    s: &mut ShapeSurfaceTool,
    response: &mut Option<egui::Response>,
) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let mut counts = s.counts;
        let mut any = count_edit(ui, "points", &mut counts.0, 2..=32, response);
        any |= count_edit(ui, "×", &mut counts.1, 2..=32, response);
        if any && counts != s.counts {
            s.counts = counts;
            let (u, v) = counts;
            s.rest.retain(|e| e.at.0 < u && e.at.1 < v);
            s.moves.retain(|e| e.at.0 < u && e.at.1 < v);
            s.heights.retain(|e| e.at.0 < u && e.at.1 < v);
            changed = true;
        }
        ui.label("degrees");
        changed |= dragged(
            ui,
            egui::DragValue::new(&mut s.degree.0).speed(0.05),
            response,
        );
        changed |= dragged(
            ui,
            egui::DragValue::new(&mut s.degree.1).speed(0.05),
            response,
        );
    });
    changed
}

fn falloff_choice(ui: &mut egui::Ui, id: &str, f: &mut Falloff) -> bool {
    let current = match f {
        Falloff::None => 0,
        Falloff::Linear => 1,
        Falloff::Smooth => 2,
        Falloff::Curve(_) => 3,
    };
    match choice(ui, id, current, &["none", "linear", "smooth", "curve"]) {
        Some(k) => {
            *f = match k {
                0 => Falloff::None,
                1 => Falloff::Linear,
                2 => Falloff::Smooth,
                _ => Falloff::Curve(SplineControl::identity(4, 3)),
            };
            true
        }
        None => false,
    }
}

fn sketch(ui: &mut egui::Ui, s: &mut SketchTool) -> (bool, Option<egui::Response>) {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("mode");
        let current = usize::from(matches!(s.mode, SketchMode::Twist { .. }));
        if let Some(k) = choice(ui, "sketch-mode", current, &["bend", "twist"]) {
            s.mode = if k == 0 {
                let target = match &s.reference {
                    Curve::Joints(stroke) => Curve::Stroke(stroke.clone()),
                    other => other.clone(),
                };
                SketchMode::Bend {
                    target,
                    turning: None,
                }
            } else {
                SketchMode::Twist {
                    angle: 0.0,
                    speed: None,
                }
            };
            changed = true;
        }
        changed |= ui.checkbox(&mut s.smooth, "smooth (Eq. 9)").changed();
        let mut refine = s.refine.is_some();
        if ui.checkbox(&mut refine, "refine").changed() {
            s.refine = refine.then(Default::default);
            changed = true;
        }
    });
    let mut response = None;
    ui.horizontal(|ui| {
        let mut given = s.normal.is_some();
        if ui
            .checkbox(&mut given, "normal")
            .on_hover_text(
                "The sketch plane's normal; off: towards the eye of the reference stroke",
            )
            .changed()
        {
            s.normal = given.then_some(Vec3::Z);
            changed = true;
        }
        if let Some(n) = &mut s.normal
            && let Some((Value::Vector(v), r)) = value_widget(
                ui,
                egui::Id::new("sketch-normal"),
                &Value::Vector(*n),
                meta("normal"),
            )
        {
            *n = v;
            response = Some(r);
            changed = true;
        }
    });
    // The spline controls: on or off (F(s) = s, or 1 for the scale).
    ui.horizontal(|ui| {
        let mut toggle = |ui: &mut egui::Ui,
                          label: &str,
                          f: &mut Option<SplineControl>,
                          start: SplineControl| {
            let mut on = f.is_some();
            if ui.checkbox(&mut on, label).changed() {
                *f = on.then_some(start);
                changed = true;
            }
        };
        match &mut s.mode {
            SketchMode::Bend { turning, .. } => {
                toggle(ui, "turning F(s)", turning, SplineControl::identity(5, 3));
            }
            SketchMode::Twist { speed, .. } => {
                toggle(ui, "twist speed F(s)", speed, SplineControl::identity(5, 3));
            }
        }
        toggle(
            ui,
            "scale F(s)",
            &mut s.scale,
            SplineControl {
                values: vec![1.0; 5],
                degree: 3,
            },
        );
    });
    // Their number of values and degree (the values are drawn as F(s) curves below).
    let controls = match &mut s.mode {
        SketchMode::Bend { turning, .. } => [("turning", turning), ("scale", &mut s.scale)],
        SketchMode::Twist { speed, .. } => [("twist speed", speed), ("scale", &mut s.scale)],
    };
    for (label, f) in controls {
        if let Some(f) = f {
            ui.push_id(label, |ui| {
                ui.horizontal(|ui| {
                    ui.label(format!("{label} F(s):"));
                    changed |= spline_structure(ui, f, &mut response);
                });
            });
        }
    }
    (changed, response)
}

/// The values of the selected handles that are not parameters yet: a lattice point with no
/// move so far, a shape surface point's move and height. Returns the edited tool.
fn selected_points(
    ui: &mut egui::Ui,
    tool: &Tool,
    selected: &[HandleId],
) -> Option<(Tool, egui::Response)> {
    let mut out = None;
    for id in selected {
        match (tool, id) {
            (Tool::Lattice(l), HandleId::Lattice(i, j, k)) => {
                let at = (*i, *j, *k);
                let edit = l
                    .points
                    .iter()
                    .find(|e| e.at == at)
                    .copied()
                    .unwrap_or(ControlEdit {
                        at,
                        offset: Vec3::ZERO,
                        weight: 1.0,
                    });
                ui.label(format!("control point ({i}, {j}, {k})"));
                ui.horizontal(|ui| {
                    ui.label("offset");
                    let r = value_widget(
                        ui,
                        egui::Id::new(("lp", at)),
                        &Value::Vector(edit.offset),
                        meta("offset"),
                    );
                    ui.label("weight");
                    let w = value_widget(
                        ui,
                        egui::Id::new(("lw", at)),
                        &Value::Scalar(edit.weight),
                        meta("weight"),
                    );
                    let mut e = edit;
                    let response = match (r, w) {
                        (Some((Value::Vector(v), r)), _) => {
                            e.offset = v;
                            Some(r)
                        }
                        (_, Some((Value::Scalar(x), r))) => {
                            e.weight = x;
                            Some(r)
                        }
                        _ => None,
                    };
                    if let Some(r) = response {
                        let mut l = l.clone();
                        l.points.retain(|p| p.at != at);
                        l.points.push(e);
                        out = Some((Tool::Lattice(l), r));
                    }
                });
            }
            (Tool::ShapeSurface(s), HandleId::SurfaceMoved(i, j)) => {
                let at = (*i, *j);
                let offset = s
                    .moves
                    .iter()
                    .find(|e| e.at == at)
                    .map_or(Vec3::ZERO, |e| e.offset);
                let height = s
                    .heights
                    .iter()
                    .find(|e| e.at == at)
                    .map_or(0.0, |e| e.height);
                ui.label(format!("surface point ({i}, {j})"));
                ui.horizontal(|ui| {
                    ui.label("move");
                    if let Some((Value::Vector(v), r)) = value_widget(
                        ui,
                        egui::Id::new(("sm", at)),
                        &Value::Vector(offset),
                        meta("offset"),
                    ) {
                        let mut s = s.clone();
                        s.moves.retain(|e| e.at != at);
                        s.moves.push(SurfaceEdit { at, offset: v });
                        out = Some((Tool::ShapeSurface(s), r));
                    }
                    ui.label("height");
                    if let Some((Value::Scalar(h), r)) = value_widget(
                        ui,
                        egui::Id::new(("sh", at)),
                        &Value::Scalar(height),
                        meta("height"),
                    ) {
                        let mut s = s.clone();
                        s.heights.retain(|e| e.at != at);
                        s.heights.push(HeightEdit { at, height: h });
                        out = Some((Tool::ShapeSurface(s), r));
                    }
                });
            }
            _ => {}
        }
    }
    out
}
