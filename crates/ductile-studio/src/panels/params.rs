//! Every animatable parameter of a tool or a volume, edited generically: the channels of
//! `ductile_anim::channel` (paths such as `points[0].gamma`) each get a widget for their value
//! kind, with a unit, and an edit is checked by the tool's own rules before it is applied —
//! a value out of range is refused at the widget, with the reason shown, never applied.

use std::collections::BTreeMap;

use bevy::math::{EulerRot, Quat, Vec3};
use bevy_egui::egui;
use ductile_anim::value::Value;

use super::curve_editor::curve_editor;

/// The unit and feel of a parameter, from the last part of its path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Meta {
    /// Unit shown after the value ("" for pure numbers).
    pub unit: &'static str,
    /// Shown (and dragged) in degrees, stored in radians.
    pub angle: bool,
    /// What the value is, for the tooltip.
    pub hint: &'static str,
    /// For the values of a spline control `F(s)`, its degree: they are drawn with the F(s)
    /// curve editor ([`curve_editor`]). `None` for other lists of values (a tube's radii).
    pub spline: Option<usize>,
}

/// The [`Meta`] of a parameter path.
#[must_use]
pub fn meta(path: &str) -> Meta {
    let leaf = path.rsplit('.').next().unwrap_or(path);
    let m = |unit, angle, hint| Meta {
        unit,
        angle,
        hint,
        spline: None,
    };
    match leaf {
        "gamma" => m(
            "",
            false,
            "strength γ: the displacement at the closest vertex is γ·|V − C|; the sign sets the direction",
        ),
        "alpha" => m(
            "",
            false,
            "sharpness α (> 0): the exponent of the distance in the weight",
        ),
        "epsilon" => m(
            "units",
            false,
            "size ε (> 0, mesh units): the width of the weight",
        ),
        "gain" => m("", false, "gain: multiplies every point's γ"),
        "theta" | "below" | "above" => m(
            "",
            false,
            "height limit ϑ in (0, 1]: the share of the largest displacement kept",
        ),
        "radius" | "half_height" => m("units", false, "size in mesh units (> 0)"),
        "half_extents" => m("units", false, "half sizes in mesh units (each > 0)"),
        "inner" => m("", false, "normalised distance of full weight, in [0, 1)"),
        "falloff" => m(
            "units",
            false,
            "distance over which the deformation fades outside the lattice (≥ 0; 0: none)",
        ),
        "weight" => m("", false, "rational weight of the control point (> 0)"),
        "angle" => m("°", true, "angle"),
        "stretch" => m(
            "",
            false,
            "refinement: split edges stretched more than this ratio (> 0)",
        ),
        "twist" => m("°", true, "twist about the axis"),
        "rotation" => m("°", true, "rotation"),
        "displacement" => m("units", false, "displacement in mesh units"),
        "offset" => m(
            "units",
            false,
            "offset of the control point from its rest place",
        ),
        "height" => m(
            "",
            false,
            "height of the point above the surface (times u3)",
        ),
        "values" => m("", false, "control values of F(s) over s ∈ [0, 1]"),
        "radii" => m("units", false, "radius at each point of the tube (> 0)"),
        _ => m("units", false, "position in mesh units"),
    }
}

/// How far a drag moves a value per pixel: 1 % of its size, at least 0.001.
fn speed(x: f32) -> f64 {
    f64::from((x.abs() * 0.01).max(0.001))
}

/// The last part of a path, for a row label.
#[must_use]
pub fn leaf(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

/// The group of a path: everything before its last part ("" for top-level parameters).
#[must_use]
pub fn group(path: &str) -> &str {
    path.rsplit_once('.').map_or("", |(g, _)| g)
}

fn scalar(ui: &mut egui::Ui, x: &mut f32, meta: Meta) -> egui::Response {
    if meta.angle {
        let mut deg = x.to_degrees();
        let r = ui.add(egui::DragValue::new(&mut deg).speed(0.5).suffix("°"));
        if r.changed() {
            *x = deg.to_radians();
        }
        r
    } else {
        let s = speed(*x);
        let mut d = egui::DragValue::new(x).speed(s).max_decimals(5);
        if !meta.unit.is_empty() {
            d = d.suffix(format!(" {}", meta.unit));
        }
        ui.add(d)
    }
}

fn vector(ui: &mut egui::Ui, v: &mut Vec3) -> Option<egui::Response> {
    let mut changed = None;
    let s = speed(v.abs().max_element());
    for (c, axis) in [(&mut v.x, "x "), (&mut v.y, "y "), (&mut v.z, "z ")] {
        let r = ui.add(
            egui::DragValue::new(c)
                .speed(s)
                .prefix(axis)
                .max_decimals(5),
        );
        if r.changed() {
            changed = Some(r);
        }
    }
    changed
}

/// A widget for `value`; returns the new value and the response of the widget that changed
/// it (for gestures), or `None` when nothing changed.
pub fn value_widget(
    ui: &mut egui::Ui,
    id: egui::Id,
    value: &Value,
    meta: Meta,
) -> Option<(Value, egui::Response)> {
    match value {
        Value::Scalar(x) => {
            let mut x = *x;
            let r = scalar(ui, &mut x, meta);
            r.changed().then_some((Value::Scalar(x), r))
        }
        Value::Vector(v) => {
            let mut v = *v;
            ui.horizontal(|ui| vector(ui, &mut v))
                .inner
                .map(|r| (Value::Vector(v), r))
        }
        Value::Rotation(q) => {
            let (mut y, mut x, mut z) = q.to_euler(EulerRot::YXZ);
            let mut changed = None;
            ui.horizontal(|ui| {
                for (a, axis) in [(&mut x, "x "), (&mut y, "y "), (&mut z, "z ")] {
                    let mut deg = a.to_degrees() + 0.0;
                    let r = ui.add(
                        egui::DragValue::new(&mut deg)
                            .speed(0.5)
                            .prefix(axis)
                            .suffix("°"),
                    );
                    if r.changed() {
                        *a = deg.to_radians();
                        changed = Some(r);
                    }
                }
            });
            changed.map(|r| (Value::Rotation(Quat::from_euler(EulerRot::YXZ, y, x, z)), r))
        }
        Value::Values(values) => {
            let mut v = values.clone();
            let mut changed = None;
            if let Some(degree) = meta.spline {
                let r = curve_editor(ui, id, &mut v, degree);
                changed = r.changed().then_some(r);
            }
            ui.horizontal_wrapped(|ui| {
                for (i, x) in v.iter_mut().enumerate() {
                    let r = ui
                        .add(egui::DragValue::new(x).speed(0.01).max_decimals(4))
                        .on_hover_text(format!("c{i}"));
                    if r.changed() {
                        changed = Some(r);
                    }
                }
            });
            changed.map(|r| (Value::Values(v), r))
        }
        Value::Polyline(points) => {
            let mut p = points.clone();
            points_rows(ui, &mut p).map(|r| (Value::Polyline(p), r))
        }
        Value::PlaneCurve { points, normal } => {
            let mut p = points.clone();
            points_rows(ui, &mut p).map(|r| {
                (
                    Value::PlaneCurve {
                        points: p,
                        normal: *normal,
                    },
                    r,
                )
            })
        }
        Value::Axis(axis) => {
            let mut a = axis.clone();
            let mut changed = None;
            for (i, point) in a.iter_mut().enumerate() {
                ui.horizontal(|ui| {
                    ui.label(format!("{i}"));
                    if let Some(r) = vector(ui, &mut point.position) {
                        changed = Some(r);
                    }
                    let r = scalar(ui, &mut point.twist, meta_of("twist"));
                    if r.changed() {
                        changed = Some(r);
                    }
                    let r = ui.add(
                        egui::DragValue::new(&mut point.scale)
                            .speed(0.005)
                            .prefix("scale "),
                    );
                    if r.changed() {
                        changed = Some(r);
                    }
                });
            }
            changed.map(|r| (Value::Axis(a), r))
        }
    }
}

fn meta_of(leaf: &str) -> Meta {
    meta(leaf)
}

fn points_rows(ui: &mut egui::Ui, points: &mut [Vec3]) -> Option<egui::Response> {
    let mut changed = None;
    for (i, p) in points.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("{i}"));
            if let Some(r) = vector(ui, p) {
                changed = Some(r);
            }
        });
    }
    changed
}

/// What the parameter list asks for: a new value of one parameter, with the widget response
/// (a drag is one gesture, one undo step).
pub struct ParamEdit {
    /// The parameter's path.
    pub path: String,
    /// Its new value.
    pub value: Value,
    /// The widget that changed it.
    pub response: egui::Response,
}

/// The reasons of refused edits, by parameter path (shown under the field until a valid
/// edit of that parameter, or another node).
#[derive(Debug, Default)]
pub struct Refusals {
    node: String,
    reasons: BTreeMap<String, String>,
}

impl Refusals {
    /// Forgets the reasons when another node is shown.
    pub fn for_node(&mut self, node: &str) {
        if self.node != node {
            self.node = node.to_owned();
            self.reasons.clear();
        }
    }

    /// Records that an edit of `path` was refused.
    pub fn refuse(&mut self, path: &str, reason: String) {
        self.reasons.insert(path.to_owned(), reason);
    }

    /// Clears `path`'s reason (its last edit was applied).
    pub fn accept(&mut self, path: &str) {
        self.reasons.remove(path);
    }

    /// The reason `path`'s last edit was refused.
    #[must_use]
    pub fn reason(&self, path: &str) -> Option<&str> {
        self.reasons.get(path).map(String::as_str)
    }
}

/// The colour of refusal messages.
pub const REFUSED: egui::Color32 = egui::Color32::from_rgb(240, 110, 90);

/// `channels` grouped by their path's prefix ([`group`]), one group per prefix in the order
/// of first appearance (a point's `mode.reference` sits between its position and γ, and must
/// not split the point in two: two groups of one name would also clash in egui's ids).
#[must_use]
pub fn grouped(channels: &[(String, Value)]) -> Vec<(&str, Vec<&(String, Value)>)> {
    let mut groups: Vec<(&str, Vec<&(String, Value)>)> = Vec::new();
    for c in channels {
        let g = group(&c.0);
        match groups.iter_mut().find(|(name, _)| *name == g) {
            Some((_, items)) => items.push(c),
            None => groups.push((g, vec![c])),
        }
    }
    groups
}

/// Lists `channels` (path, value) of node `node` grouped by their path's prefix, one row
/// each, animated ones coloured by their [`super::KeyState`] in `doc`; the row under the
/// pointer is remembered for K ([`super::hover_channel`]). `spline_degree` gives the degree
/// of the spline control whose values a path holds (drawn as an F(s) curve). Returns the
/// edit made this frame, if any.
pub fn parameter_list(
    ui: &mut egui::Ui,
    doc: &ductile_bevy::prelude::SceneDocument,
    node: &str,
    channels: &[(String, Value)],
    refusals: &Refusals,
    spline_degree: &dyn Fn(&str) -> Option<usize>,
) -> Option<ParamEdit> {
    let id = format!("params-{node}");
    let id = id.as_str();
    let mut edit = None;
    let groups = grouped(channels);
    let many = groups.len() > 6;
    for (g, items) in groups {
        let rows = |ui: &mut egui::Ui| {
            egui::Grid::new((id, g))
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    for (path, value) in items {
                        let m = Meta {
                            spline: spline_degree(path),
                            ..meta(path)
                        };
                        // Animated fields are coloured as in Blender (yellow on a key,
                        // green between keys, orange when changed and not keyed).
                        let state = super::KeyState::of(doc, node, path);
                        let mut label = egui::RichText::new(leaf(path));
                        if let Some(c) = state.color() {
                            label = label.color(c);
                        }
                        let r = ui.label(label).on_hover_text(m.hint);
                        let mut over = r.hovered();
                        match state {
                            super::KeyState::Static => {}
                            super::KeyState::Changed => {
                                r.on_hover_text("animated, changed and not keyed: K keys it");
                            }
                            _ if doc.auto_key() => {
                                r.on_hover_text("animated: an edit sets a key at this frame");
                            }
                            _ => {
                                r.on_hover_text(
                                    "animated: an edit is offered to be keyed (K keys it)",
                                );
                            }
                        }
                        let inner = ui.vertical(|ui| {
                            let wid = egui::Id::new((id, path));
                            if let Some((value, response)) = value_widget(ui, wid, value, m) {
                                edit = Some(ParamEdit {
                                    path: path.clone(),
                                    value,
                                    response,
                                });
                            }
                            if let Some(reason) = refusals.reason(path) {
                                ui.colored_label(REFUSED, format!("refused: {reason}"));
                            }
                        });
                        over |= inner.response.contains_pointer();
                        if over {
                            super::hover_channel(ui.ctx(), node, path);
                        }
                        ui.end_row();
                    }
                });
        };
        if g.is_empty() {
            rows(ui);
        } else {
            egui::CollapsingHeader::new(g)
                .id_salt((id, g))
                .default_open(!many)
                .show(ui, rows);
        }
    }
    edit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_is_one_group_even_around_its_mode() {
        let c = |p: &str| (p.to_owned(), Value::Scalar(0.0));
        let channels = [
            c("points[0].position"),
            c("points[0].mode.reference"),
            c("points[0].gamma"),
            c("points[1].position"),
            c("gain"),
        ];
        let names: Vec<&str> = grouped(&channels).iter().map(|(g, _)| *g).collect();
        assert_eq!(names, ["points[0]", "points[0].mode", "points[1]", ""]);
        assert_eq!(grouped(&channels)[0].1.len(), 2);
    }
}
