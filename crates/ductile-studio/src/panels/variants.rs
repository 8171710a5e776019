//! The variants panel: save the current face (every tool and macro tool state) as a named
//! variant, rename, apply and delete variants; an **A/B slider** that morphs live between two
//! variants and beyond them (caricature, `t` in [−1, 2]); N-way weights; and a seeded random
//! face drawn from the selected variants (FaceGen-style limits: spread and a left/right
//! asymmetry cap). Every action is one undo step; a slider drag is one step.

use std::collections::{BTreeMap, BTreeSet};

use bevy_egui::egui;
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, unique_among};
use ductile_scene::variant::{RandomOptions, Variant};

use super::{PanelContext, PanelRequest};
use crate::compare::CompareEntry;

/// The variants panel's state.
#[derive(Debug)]
pub struct VariantsPanel {
    /// Name for the next saved variant.
    pub new_name: String,
    /// The name is the suggested one (`variant`, `variant-2`, …), not one the user typed.
    auto_name: bool,
    /// The variant being renamed and the name typed so far.
    renaming: Option<(String, String)>,
    /// Variants ticked for the N-way blend and the random face.
    pub picked: BTreeSet<String>,
    /// N-way blend weights by variant.
    pub weights: BTreeMap<String, f32>,
    /// A and B of the morph slider.
    pub a: Option<String>,
    /// See `a`.
    pub b: Option<String>,
    /// The morph slider's position: 0 = A, 1 = B, beyond = caricature.
    pub t: f32,
    /// Seed of the next random face.
    pub seed: u64,
    /// Spread of the random face in [0, 1].
    pub spread: f32,
    /// Largest left/right difference of a random face's macro pairs (`None`: as drawn).
    pub asymmetry: Option<f32>,
    /// What is shown side by side with the current face.
    pub compare: Vec<CompareEntry>,
}

impl Default for VariantsPanel {
    fn default() -> Self {
        Self {
            new_name: String::new(),
            auto_name: true,
            renaming: None,
            picked: BTreeSet::new(),
            weights: BTreeMap::new(),
            a: None,
            b: None,
            t: 0.5,
            seed: 1,
            spread: 1.0,
            asymmetry: Some(0.1),
            compare: Vec::new(),
        }
    }
}

/// `stem`, or `stem-2`, `stem-3`, …: a name no variant of `doc` has.
fn unique_variant_name(doc: &Document, stem: &str) -> String {
    unique_among(stem, |n| doc.variants.contains_key(n))
}

/// The operation that writes `variant`'s states into the scene, labelled `label`.
fn apply_op(doc: &Document, variant: &Variant, label: &str) -> Result<Operation, String> {
    Operation::apply_states(doc, &variant.states, label).map_err(|e| e.to_string())
}

impl VariantsPanel {
    /// Draws the panel.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let names: Vec<String> = doc.variants.keys().cloned().collect();
        self.picked.retain(|n| doc.variants.contains_key(n));
        ui.horizontal(|ui| {
            if self.auto_name {
                self.new_name = unique_variant_name(doc, "variant");
            }
            if ui
                .add(
                    egui::TextEdit::singleline(&mut self.new_name)
                        .desired_width(140.0)
                        .hint_text("name"),
                )
                .changed()
            {
                self.auto_name = self.new_name.trim().is_empty();
            }
            let name = self.new_name.trim().to_owned();
            let exists = doc.variants.contains_key(&name);
            if !name.is_empty()
                && ui
                    .button(if exists { "Replace" } else { "Save face" })
                    .on_hover_text("Save the current state of every tool and macro as a variant")
                    .clicked()
            {
                cx.apply(Operation::save_variant(doc, &name));
                self.auto_name = true;
            }
        });
        if names.is_empty() {
            ui.weak("No variants yet: set the sliders, then Save face.");
            return;
        }
        egui::Grid::new("variants-grid")
            .num_columns(4)
            .striped(true)
            .show(ui, |ui| {
                for name in &names {
                    let mut picked = self.picked.contains(name);
                    if ui
                        .checkbox(&mut picked, "")
                        .on_hover_text("Use in the N-way blend and the random face")
                        .changed()
                    {
                        if picked {
                            self.picked.insert(name.clone());
                        } else {
                            self.picked.remove(name);
                        }
                    }
                    match &mut self.renaming {
                        Some((old, typed)) if old == name => {
                            let r = ui.text_edit_singleline(typed);
                            if r.lost_focus() {
                                let new = typed.trim().to_owned();
                                if ui.input(|i| i.key_pressed(egui::Key::Enter))
                                    && !new.is_empty()
                                    && new != *old
                                {
                                    cx.apply(Operation::rename_variant(old, &new));
                                }
                                self.renaming = None;
                            } else {
                                r.request_focus();
                            }
                        }
                        _ => {
                            let r = ui.label(name).on_hover_text("Double-click or F2 to rename");
                            if r.double_clicked() {
                                self.renaming = Some((name.clone(), name.clone()));
                            }
                        }
                    }
                    let mut w = self.weights.get(name).copied().unwrap_or(0.0);
                    if ui
                        .add(egui::DragValue::new(&mut w).speed(0.01).range(-1.0..=2.0))
                        .on_hover_text("Weight in the N-way blend")
                        .changed()
                    {
                        self.weights.insert(name.clone(), w);
                    }
                    ui.horizontal(|ui| {
                        if ui.small_button("Apply").clicked()
                            && let Ok(v) = doc.variant(name)
                        {
                            match apply_op(doc, v, &format!("apply variant '{name}'")) {
                                Ok(op) => cx.apply(op),
                                Err(e) => cx.requests.push(PanelRequest::Problem(e)),
                            }
                        }
                        if ui.small_button("✏").on_hover_text("Rename").clicked() {
                            self.renaming = Some((name.clone(), name.clone()));
                        }
                        if ui.small_button("🗑").on_hover_text("Delete").clicked()
                            && let Ok(op) = Operation::delete_variant(doc, name)
                        {
                            cx.apply(op);
                        }
                    });
                    ui.end_row();
                }
            });
        self.morph(ui, cx, &names);
        self.blend(ui, cx);
        self.random(ui, cx);
        self.side_by_side(ui, cx, &names);
    }

    /// Which faces are shown next to the current one (view state, asked of the Studio).
    fn side_by_side(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>, names: &[String]) {
        let before = self.compare.clone();
        self.compare.retain(|e| match e {
            CompareEntry::Rest => true,
            CompareEntry::Variant(v) => names.contains(v),
        });
        ui.horizontal_wrapped(|ui| {
            ui.label("Side by side:");
            let entries = std::iter::once(CompareEntry::Rest)
                .chain(names.iter().cloned().map(CompareEntry::Variant));
            for entry in entries {
                let mut on = self.compare.contains(&entry);
                if ui.checkbox(&mut on, entry.label()).changed() {
                    if on {
                        self.compare.push(entry);
                    } else {
                        self.compare.retain(|e| *e != entry);
                    }
                }
            }
        });
        if self.compare != before {
            cx.requests
                .push(PanelRequest::Compare(self.compare.clone()));
        }
    }

    /// The A/B morph slider.
    fn morph(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>, names: &[String]) {
        let doc = cx.doc.shown();
        if self
            .a
            .as_ref()
            .is_none_or(|a| !doc.variants.contains_key(a))
        {
            self.a = names.first().cloned();
        }
        // B defaults to another variant than A as soon as there are two.
        if self
            .b
            .as_ref()
            .is_none_or(|b| !doc.variants.contains_key(b))
            || (self.b == self.a && names.len() >= 2)
        {
            self.b = names
                .iter()
                .find(|n| Some(*n) != self.a.as_ref())
                .or(names.first())
                .cloned();
        }
        ui.horizontal(|ui| {
            ui.label("Morph");
            for (id, slot) in [("variant-a", &mut self.a), ("variant-b", &mut self.b)] {
                egui::ComboBox::from_id_salt(id)
                    .width(90.0)
                    .selected_text(slot.clone().unwrap_or_default())
                    .show_ui(ui, |ui| {
                        for n in names {
                            ui.selectable_value(slot, Some(n.clone()), n);
                        }
                    });
            }
        });
        let (Some(a), Some(b)) = (self.a.clone(), self.b.clone()) else {
            return;
        };
        let r = ui
            .add(
                egui::Slider::new(&mut self.t, -1.0..=2.0)
                    .text("A to B")
                    .fixed_decimals(2),
            )
            .on_hover_text("0 is A, 1 is B; beyond them exaggerates the difference (caricature)");
        if r.changed() {
            match doc
                .blend_two(&a, &b, self.t)
                .map_err(|e| e.to_string())
                .and_then(|v| apply_op(doc, &v, &format!("morph '{a}' to '{b}'")))
            {
                Ok(op) => {
                    cx.apply_in_gesture(&r, op, format!("morph '{a}' to '{b}' at {:.2}", self.t))
                }
                Err(e) => cx.requests.push(PanelRequest::Problem(e)),
            }
        }
    }

    /// The N-way blend of the weights column.
    fn blend(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let weights: Vec<(&str, f32)> = self
            .weights
            .iter()
            .filter(|(n, w)| **w != 0.0 && doc.variants.contains_key(*n))
            .map(|(n, w)| (n.as_str(), *w))
            .collect();
        ui.horizontal(|ui| {
            let sum: f32 = weights.iter().map(|(_, w)| w).sum();
            if ui
                .add_enabled(!weights.is_empty(), egui::Button::new("Apply weights"))
                .on_hover_text("The blend of the variants with the weights column")
                .clicked()
            {
                match doc
                    .blend_variants(&weights)
                    .map_err(|e| e.to_string())
                    .and_then(|v| apply_op(doc, &v, "blend variants"))
                {
                    Ok(op) => cx.apply(op),
                    Err(e) => cx.requests.push(PanelRequest::Problem(e)),
                }
            }
            ui.weak(format!("Σ weights = {sum:.2}"));
        });
    }

    /// The seeded random face from the picked variants.
    fn random(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        ui.horizontal(|ui| {
            ui.label("Seed");
            ui.add(egui::DragValue::new(&mut self.seed).speed(1.0));
            ui.label("spread");
            ui.add(
                egui::DragValue::new(&mut self.spread)
                    .range(0.0..=1.0)
                    .speed(0.01),
            );
            let mut limit = self.asymmetry.is_some();
            ui.checkbox(&mut limit, "asym ≤");
            let mut a = self.asymmetry.unwrap_or(0.1);
            ui.add_enabled(
                limit,
                egui::DragValue::new(&mut a).range(0.0..=2.0).speed(0.01),
            );
            self.asymmetry = limit.then_some(a);
        });
        let sources: Vec<&str> = self.picked.iter().map(String::as_str).collect();
        if ui
            .add_enabled(
                sources.len() >= 2,
                egui::Button::new("Random face from the ticked variants"),
            )
            .on_hover_text(
                "Saves a seeded random blend as a variant and applies it (tick two or more)",
            )
            .clicked()
        {
            let options = RandomOptions {
                seed: self.seed,
                spread: self.spread,
                asymmetry: self.asymmetry,
            };
            let name = unique_variant_name(doc, &format!("random-{}", self.seed));
            let result = doc
                .random_variant(&sources, &options)
                .map_err(|e| e.to_string())
                .and_then(|v| {
                    let apply = apply_op(doc, &v, "apply")?;
                    Ok(Operation::Group {
                        label: format!("random face '{name}' (seed {})", self.seed),
                        ops: vec![Operation::put_variant(doc, &name, Some(v)), apply],
                    })
                });
            match result {
                Ok(op) => {
                    cx.apply(op);
                    self.seed += 1;
                }
                Err(e) => cx.requests.push(PanelRequest::Problem(e)),
            }
        }
    }
}
