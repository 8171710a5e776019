//! The inspector's layer section: the selected layer's influence (which volumes, which named
//! area, the falloff — none, linear, smooth or a custom curve —, the inner plateau and
//! invert), and the volume section: a volume node's shape type and sizes.

use bevy_egui::egui;
use ductile_anim::channel::{set_shape_channel, shape_channels};
use ductile_core::influence::{Falloff, Shape};
use ductile_core::spline::SplineControl;
use ductile_history::operation::Operation;
use ductile_scene::document::{InfluenceSpec, NodeKind};

use super::PanelContext;
use super::curve_editor::{curve_editor, spline_structure};
use super::params::{REFUSED, Refusals, parameter_list};

/// The influence and volume sections' state.
#[derive(Debug, Default)]
pub struct InfluenceEditor {
    refusals: Refusals,
}

impl InfluenceEditor {
    /// Draws the influence of layer `index` of mesh `mesh`.
    pub fn show_layer(
        &mut self,
        ui: &mut egui::Ui,
        cx: &mut PanelContext<'_>,
        mesh: &str,
        index: usize,
    ) {
        let doc = cx.doc.shown();
        let Ok(m) = doc.mesh(mesh) else { return };
        let Some(layer) = m.stack.get(index) else {
            return;
        };
        self.refusals.for_node(&format!("{mesh}/{index}"));
        ui.label(
            egui::RichText::new(format!("Layer {index} of '{mesh}': '{}'", layer.tool)).strong(),
        );
        let old = layer.influence.clone();
        let mut inf = old.clone().unwrap_or_default();
        let mut response = None;
        let mut has = old.is_some();
        if ui
            .checkbox(&mut has, "influence (else every vertex, weight 1)")
            .changed()
        {
            let new = has.then(InfluenceSpec::default);
            if let Ok(op) = Operation::set_layer_influence(doc, mesh, index, new) {
                cx.apply(op);
            }
            return;
        }
        if !has {
            return;
        }
        // Volumes: every volume node of the scene, checked when it masks the layer.
        let volumes: Vec<&str> = doc
            .nodes
            .iter()
            .filter(|n| matches!(n.kind, NodeKind::Volume(_)))
            .map(|n| n.name.as_str())
            .collect();
        ui.horizontal_wrapped(|ui| {
            ui.label("volumes");
            if volumes.is_empty() {
                ui.weak("none in the scene (Add > volume)");
            }
            for v in &volumes {
                let mut on = inf.volumes.iter().any(|x| x == v);
                if ui.checkbox(&mut on, *v).changed() {
                    if on {
                        inf.volumes.push((*v).to_owned());
                    } else {
                        inf.volumes.retain(|x| x != v);
                    }
                }
            }
        });
        ui.horizontal(|ui| {
            ui.label("area");
            let current = inf.area.clone().unwrap_or_else(|| "(none)".to_owned());
            egui::ComboBox::from_id_salt("influence-area")
                .selected_text(current)
                .show_ui(ui, |ui| {
                    ui.selectable_value(&mut inf.area, None, "(none)");
                    for a in m.areas.keys() {
                        ui.selectable_value(&mut inf.area, Some(a.clone()), a);
                    }
                });
            ui.checkbox(&mut inf.invert, "invert")
                .on_hover_text("the area minus the volumes");
        });
        ui.horizontal(|ui| {
            ui.label("falloff");
            let current = match inf.falloff {
                Falloff::None => 0,
                Falloff::Linear => 1,
                Falloff::Smooth => 2,
                Falloff::Curve(_) => 3,
            };
            let mut k = current;
            egui::ComboBox::from_id_salt("influence-falloff")
                .selected_text(["none", "linear", "smooth", "curve"][current])
                .show_ui(ui, |ui| {
                    for (i, l) in ["none", "linear", "smooth", "curve"].iter().enumerate() {
                        ui.selectable_value(&mut k, i, *l);
                    }
                });
            if k != current {
                inf.falloff = match k {
                    0 => Falloff::None,
                    1 => Falloff::Linear,
                    2 => Falloff::Smooth,
                    _ => Falloff::Curve(SplineControl::identity(5, 3)),
                };
            }
            ui.label("inner");
            let r = ui
                .add(egui::DragValue::new(&mut inf.inner).speed(0.005))
                .on_hover_text("normalised distance of full weight, in [0, 1)");
            if r.changed() {
                response = Some(r);
            }
        });
        if let Falloff::Curve(f) = &mut inf.falloff {
            ui.label("weight F(s) from the boundary (s = 0) to the plateau (s = 1)");
            let mut values = f.values.clone();
            let r = curve_editor(
                ui,
                egui::Id::new(("falloff-curve", mesh, index)),
                &mut values,
                f.degree,
            );
            if r.changed() {
                f.values = values;
                response = Some(r);
            }
            spline_structure(ui, f, &mut response);
        }
        if let Some(reason) = self.refusals.reason("influence") {
            ui.colored_label(REFUSED, format!("refused: {reason}"));
        }
        let new = Some(inf);
        if new == old {
            return;
        }
        // The same rules as the operation: inner in [0, 1), a valid falloff curve.
        let problem = new.as_ref().and_then(|inf| {
            if !(inf.inner.is_finite() && (0.0..1.0).contains(&inf.inner)) {
                Some(format!("inner = {} must be in [0, 1)", inf.inner))
            } else {
                inf.falloff
                    .validate("influence")
                    .err()
                    .map(|e| e.to_string())
            }
        });
        if let Some(p) = problem {
            self.refusals.refuse("influence", p);
            return;
        }
        self.refusals.accept("influence");
        if let Ok(op) = Operation::set_layer_influence(doc, mesh, index, new) {
            match response {
                Some(r) => {
                    cx.apply_in_gesture(&r, op, format!("influence of layer {index} of '{mesh}'"))
                }
                None => cx.apply(op),
            }
        }
    }

    /// Draws volume node `name`'s shape: its type and every size, a drag being one undo step.
    pub fn show_volume(
        &mut self,
        ui: &mut egui::Ui,
        cx: &mut PanelContext<'_>,
        name: &str,
        shape: &Shape,
    ) {
        self.refusals.for_node(name);
        let doc = cx.doc.shown();
        let kinds = ["sphere", "box", "capsule", "tube"];
        let current = match shape {
            Shape::Sphere { .. } => 0,
            Shape::Box { .. } => 1,
            Shape::Capsule { .. } => 2,
            Shape::Tube { .. } => 3,
        };
        let size = shape.local_bounds().1.max_element();
        let mut k = current;
        ui.horizontal(|ui| {
            ui.label("shape");
            egui::ComboBox::from_id_salt("volume-shape")
                .selected_text(kinds[current])
                .show_ui(ui, |ui| {
                    for (i, l) in kinds.iter().enumerate() {
                        ui.selectable_value(&mut k, i, *l);
                    }
                });
        });
        if k != current {
            let new = match k {
                0 => Shape::Sphere { radius: size },
                1 => Shape::Box {
                    half_extents: bevy::math::Vec3::splat(size),
                },
                2 => Shape::Capsule {
                    radius: size * 0.5,
                    half_height: size * 0.5,
                },
                _ => Shape::Tube {
                    points: vec![bevy::math::Vec3::NEG_Y * size, bevy::math::Vec3::Y * size],
                    radii: vec![size * 0.5; 2],
                },
            };
            if let Ok(op) = Operation::set_volume(doc, name, new) {
                cx.apply(op);
            }
            return;
        }
        let channels = shape_channels(shape);
        if let Some(edit) = parameter_list(ui, cx.doc, name, &channels, &self.refusals, &|_| None) {
            let mut new = shape.clone();
            let result = set_shape_channel(&mut new, &edit.path, &edit.value)
                .map_err(|e| e.to_string())
                .and_then(|()| {
                    new.validate(&format!("volume '{name}'"))
                        .map_err(|e| e.to_string())
                });
            match result {
                Err(reason) => self.refusals.refuse(&edit.path, reason),
                Ok(()) => {
                    self.refusals.accept(&edit.path);
                    if let Ok(op) = Operation::set_volume(doc, name, new) {
                        cx.apply_in_gesture(&edit.response, op, format!("resize '{name}'"));
                    }
                }
            }
        }
        if let Shape::Tube { points, radii } = shape {
            ui.horizontal(|ui| {
                if ui.button("+ point").clicked() && points.len() >= 2 {
                    let n = points.len();
                    let mut s = shape.clone();
                    if let Shape::Tube {
                        points: p,
                        radii: r,
                    } = &mut s
                    {
                        p.push(points[n - 1] + (points[n - 1] - points[n - 2]));
                        r.push(radii[n - 1]);
                    }
                    if let Ok(op) = Operation::set_volume(doc, name, s) {
                        cx.apply(op);
                    }
                }
                if points.len() > 2 && ui.button("− last").clicked() {
                    let mut s = shape.clone();
                    if let Shape::Tube {
                        points: p,
                        radii: r,
                    } = &mut s
                    {
                        p.pop();
                        r.pop();
                    }
                    if let Ok(op) = Operation::set_volume(doc, name, s) {
                        cx.apply(op);
                    }
                }
            });
        }
    }
}
