//! The timeline: the current frame, the frame range and rate, play / pause / loop, jump to
//! the previous or next key, and the keys of the selected node as diamonds — a summary row
//! and one row per animated channel — that can be selected (click, Shift-click, box), moved
//! by dragging (one undo step per drag), given an interpolation or deleted from their
//! context menu. **K** keys what the inspector shows: an edit waiting to be keyed (see
//! [`super::key_offer`]), else the field under the pointer (an inspector field or an
//! identikit slider), else every channel of the selected node, or with nothing selected
//! every macro tool's value (the identikit face). **Auto-key** keys animated fields as they
//! are edited.
//!
//! Times are seconds in the document and whole frames here (`frame = time · fps`).

use std::collections::{BTreeMap, BTreeSet};

use bevy_egui::egui;
use ductile_anim::key::{Interpolation, Key};
use ductile_bevy::prelude::*;
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, NodeKind};
use ductile_scene::time::Timeline;

use super::{PanelContext, PanelRequest};

/// One key: node, channel path and time (seconds, as stored).
type KeyRef = (String, String, u32);

/// Height of a row of diamonds and of the frame ruler, in points.
const ROW: f32 = 18.0;
/// Half the size of a diamond, in points.
const DIAMOND: f32 = 5.0;

/// What a drag on the strip does, decided when it starts.
#[derive(Debug, Clone, PartialEq)]
enum Drag {
    /// Moving the current frame.
    Scrub,
    /// Moving the selected keys; the frames moved so far.
    Keys { moved: i32 },
    /// Selecting the keys in a rectangle from this corner.
    Box { from: egui::Pos2, add: bool },
}

/// The timeline panel's state.
#[derive(Debug)]
pub struct TimelinePanel {
    /// While playing: the Studio's clock and the document time when playback started.
    playing: Option<(f64, f32)>,
    /// Start again at the first frame after the last (else playback stops there).
    pub looping: bool,
    /// Show one row per animated channel under the summary row.
    pub expanded: bool,
    /// The selected keys.
    selected: BTreeSet<KeyRef>,
    drag: Option<Drag>,
    /// Where the last frame drew the keys: the keys' rectangle and the frame range.
    layout: Option<(egui::Rect, i32, i32)>,
}

impl Default for TimelinePanel {
    fn default() -> Self {
        Self {
            playing: None,
            looping: true,
            expanded: false,
            selected: BTreeSet::new(),
            drag: None,
            layout: None,
        }
    }
}

/// A row of the strip: its label and its keys.
struct Row {
    label: String,
    keys: Vec<KeyRef>,
}

fn bits(t: f32) -> u32 {
    t.to_bits()
}

/// The rows shown: the selected node's channels, or with no node selected one row per
/// animated node.
fn rows(doc: &Document, node: Option<&str>) -> Vec<Row> {
    let tracks = &doc.animation.tracks;
    match node {
        Some(n) => tracks
            .get(n)
            .into_iter()
            .flatten()
            .map(|(path, keys)| Row {
                label: path.clone(),
                keys: keys
                    .iter()
                    .map(|k| (n.to_owned(), path.clone(), bits(k.time)))
                    .collect(),
            })
            .collect(),
        None => tracks
            .iter()
            .map(|(n, channels)| Row {
                label: n.clone(),
                keys: channels
                    .iter()
                    .flat_map(|(path, keys)| {
                        keys.iter()
                            .map(move |k| (n.clone(), path.clone(), bits(k.time)))
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// The operation that keys what the inspector shows at time `t`: every channel of `node`,
/// or every macro tool's value when no node is selected.
///
/// # Errors
/// The node does not exist, or there is nothing to key.
pub fn key_operation(doc: &Document, node: Option<&str>, t: f32) -> Result<Operation, String> {
    match node {
        Some(n) => Operation::key_node(doc, n, t).map_err(|e| e.to_string()),
        None => {
            let ops = doc
                .nodes
                .iter()
                .filter(|n| matches!(n.kind, NodeKind::Macro(_)))
                .map(|n| Operation::key_current(doc, &n.name, "value", t))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| e.to_string())?;
            if ops.is_empty() {
                return Err("select a node to key (the scene has no macro tools)".to_owned());
            }
            Ok(Operation::Group {
                label: format!("key every macro at {t} s"),
                ops,
            })
        }
    }
}

/// The operation that moves the keys `keys` by `frames` frames (one `SetTrack` per track,
/// so that a drag merges into one step), or why it cannot (a key would land on another).
fn move_operation(
    doc: &Document,
    keys: &BTreeSet<KeyRef>,
    frames: i32,
) -> Result<Operation, String> {
    let fps = doc.animation.fps;
    let mut by_track: BTreeMap<(&str, &str), BTreeSet<u32>> = BTreeMap::new();
    for (n, p, t) in keys {
        by_track.entry((n, p)).or_default().insert(*t);
    }
    let mut ops = Vec::new();
    for ((n, p), times) in by_track {
        let Some(track) = doc.animation.track(n, p) else {
            continue;
        };
        let mut moved: Vec<Key> = track
            .iter()
            .map(|k| {
                let mut k = k.clone();
                if times.contains(&bits(k.time)) {
                    k.time = ((k.time * fps).round() + frames as f32) / fps;
                }
                k
            })
            .collect();
        moved.sort_by(|a, b| a.time.total_cmp(&b.time));
        if moved.windows(2).any(|w| w[0].time == w[1].time) {
            return Err(format!("a key of '{n}' / '{p}' would land on another"));
        }
        ops.push(Operation::set_track(doc, n, p, Some(moved)));
    }
    if ops.is_empty() {
        return Err("no key to move".to_owned());
    }
    Ok(Operation::Group {
        label: format!("move {} key(s) by {frames} frame(s)", keys.len()),
        ops,
    })
}

/// The keys `keys` moved by `frames` frames.
fn shifted(keys: &BTreeSet<KeyRef>, frames: i32, fps: f32) -> BTreeSet<KeyRef> {
    keys.iter()
        .map(|(n, p, t)| {
            let t = f32::from_bits(*t);
            let moved = ((t * fps).round() + frames as f32) / fps;
            (n.clone(), p.clone(), bits(moved))
        })
        .collect()
}

impl TimelinePanel {
    /// True while the timeline plays.
    #[must_use]
    pub fn is_playing(&self) -> bool {
        self.playing.is_some()
    }

    /// The selected keys, as (node, channel, time in seconds).
    #[cfg(test)]
    #[must_use]
    pub fn selected_keys(&self) -> Vec<(String, String, f32)> {
        self.selected
            .iter()
            .map(|(n, p, t)| (n.clone(), p.clone(), f32::from_bits(*t)))
            .collect()
    }

    /// Where the diamond of frame `frame` on row `row` (0 = the summary) was drawn in the
    /// last frame, in screen points.
    #[cfg(test)]
    #[must_use]
    pub fn key_position(&self, frame: f32, row: usize) -> Option<egui::Pos2> {
        let (r, start, end) = self.layout?;
        let span = (end - start).max(1) as f32;
        Some(egui::pos2(
            r.left() + (frame - start as f32) / span * r.width(),
            r.top() + ROW * (row as f32 + 1.5),
        ))
    }

    /// Starts or stops playback.
    pub fn toggle_play(&mut self, cx: &PanelContext<'_>) {
        self.playing = match self.playing {
            Some(_) => None,
            None => Some((cx.now, cx.doc.time())),
        };
    }

    /// Draws the timeline and handles its shortcuts (K keys, Space plays) unless a text
    /// field has the keyboard.
    pub fn show(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let anim = &doc.animation;
        let fps = anim.fps;
        let time = cx.doc.time();
        let frame = cx.doc.frame();
        let node = cx.selection.node.clone().filter(|n| doc.node(n).is_ok());
        // Forget selected keys that no longer exist (undo, another file); not during a drag,
        // whose moves the document shows only after this pass.
        if self.drag.is_none() {
            self.selected.retain(|(n, p, t)| {
                anim.track(n, p)
                    .is_some_and(|k| k.iter().any(|k| bits(k.time) == *t))
            });
        }
        self.playback(ui, cx);
        let key_times = anim.key_times();
        let set_frame = |cx: &mut PanelContext<'_>, f: f32| {
            cx.commands.push(DocumentCommand::SetTime(f / fps));
        };
        ui.horizontal(|ui| {
            if ui.small_button("⏮").on_hover_text("First frame").clicked() {
                set_frame(cx, anim.start as f32);
            }
            let prev = key_times.iter().rev().find(|t| **t < time - 1e-6);
            if ui
                .add_enabled(prev.is_some(), egui::Button::new("◀ key").small())
                .on_hover_text("Previous key")
                .clicked()
                && let Some(t) = prev
            {
                cx.commands.push(DocumentCommand::SetTime(*t));
            }
            let playing = self.is_playing();
            if ui
                .small_button(if playing { "⏸" } else { "▶" })
                .on_hover_text(if playing {
                    "Pause (Space)"
                } else {
                    "Play (Space)"
                })
                .clicked()
            {
                self.toggle_play(cx);
            }
            let next = key_times.iter().find(|t| **t > time + 1e-6);
            if ui
                .add_enabled(next.is_some(), egui::Button::new("key ▶").small())
                .on_hover_text("Next key")
                .clicked()
                && let Some(t) = next
            {
                cx.commands.push(DocumentCommand::SetTime(*t));
            }
            if ui.small_button("⏭").on_hover_text("Last frame").clicked() {
                set_frame(cx, anim.end as f32);
            }
            ui.checkbox(&mut self.looping, "Loop");
            ui.separator();
            ui.label("Frame");
            let mut f = frame;
            if ui
                .add(egui::DragValue::new(&mut f).speed(0.2).max_decimals(0))
                .changed()
            {
                set_frame(cx, f.round());
            }
            ui.label("Range");
            self.timeline_fields(ui, cx, doc);
            ui.separator();
            let key_label = match &node {
                Some(n) => format!("Key '{n}' (K)"),
                None => "Key every macro (K)".to_owned(),
            };
            if ui
                .button(key_label)
                .on_hover_text("Key every channel of the selection at this frame (K)")
                .clicked()
            {
                self.key(cx, node.as_deref(), time);
            }
            if ui
                .add_enabled(!self.selected.is_empty(), egui::Button::new("Delete keys"))
                .on_hover_text("Delete the selected keys")
                .clicked()
            {
                self.delete_selected(cx);
            }
            ui.checkbox(&mut self.expanded, "Channels");
            let mut auto = cx.doc.auto_key();
            if ui
                .toggle_value(&mut auto, "Auto-key")
                .on_hover_text(
                    "Key animated fields as you edit them (off: an edit at a frame without \
                     a key is offered to be keyed)",
                )
                .changed()
            {
                cx.commands.push(DocumentCommand::SetAutoKey(auto));
            }
        });
        // Shortcuts over the whole window, unless a text field is being typed in. K over a
        // field (inspector, identikit slider) keys that channel alone.
        let hovered = super::take_hovered_channel(ui.ctx());
        if !ui.ctx().egui_wants_keyboard_input() {
            if ui.input(|i| i.key_pressed(egui::Key::K) && i.modifiers.is_none()) {
                match hovered {
                    // An edit waiting to be keyed is what K keys first.
                    _ if cx.doc.pending().is_some() => {
                        cx.commands.push(DocumentCommand::KeyPending);
                    }
                    Some((n, path)) => match Operation::key_current(doc, &n, &path, time) {
                        Ok(op) => cx.apply(op),
                        Err(e) => cx.requests.push(PanelRequest::Problem(e.to_string())),
                    },
                    None => self.key(cx, node.as_deref(), time),
                }
            }
            if ui.input(|i| i.key_pressed(egui::Key::Space) && i.modifiers.is_none()) {
                // Space plays everywhere (as in Blender): a button focused with Tab (drawn
                // after the timeline) must not also take it as a click.
                ui.memory_mut(|m| {
                    if let Some(id) = m.focused() {
                        m.surrender_focus(id);
                    }
                });
                self.toggle_play(cx);
            }
        }
        self.strip(ui, cx, node.as_deref());
    }

    fn timeline_fields(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>, doc: &Document) {
        let t = doc.animation.timeline();
        let (mut start, mut end, mut fps) = (t.start, t.end, t.fps);
        let r1 = ui.add(egui::DragValue::new(&mut start).speed(0.2));
        let r2 = ui.add(egui::DragValue::new(&mut end).speed(0.2));
        ui.label("fps");
        let r3 = ui.add(
            egui::DragValue::new(&mut fps)
                .range(1.0..=240.0)
                .speed(0.1)
                .max_decimals(3),
        );
        let new = Timeline {
            fps,
            start: start.min(t.end),
            end: end.max(t.start),
        };
        for r in [r1, r2, r3] {
            if r.changed() && new != t {
                let op = Operation::set_timeline(doc, new);
                cx.apply_in_gesture(&r, op, "set the timeline".to_owned());
            }
        }
    }

    /// Advances the current time while playing (at the timeline's rate, looping or
    /// stopping at the last frame).
    fn playback(&mut self, ui: &egui::Ui, cx: &mut PanelContext<'_>) {
        let Some((since, from)) = self.playing else {
            return;
        };
        let a = &cx.doc.document().animation;
        let (start, end) = (a.start as f32 / a.fps, a.end as f32 / a.fps);
        let mut t = from + (cx.now - since) as f32;
        if t > end {
            if self.looping && end > start {
                t = start + (t - start) % (end - start);
            } else {
                t = end;
                self.playing = None;
            }
        }
        // Whole frames, as a player steps.
        let t = (t * a.fps).floor() / a.fps;
        if t != cx.doc.time() {
            cx.commands.push(DocumentCommand::SetTime(t));
        }
        ui.ctx().request_repaint();
    }

    fn key(&mut self, cx: &mut PanelContext<'_>, node: Option<&str>, t: f32) {
        match key_operation(cx.doc.shown(), node, t) {
            Ok(op) => cx.apply(op),
            Err(e) => cx.requests.push(PanelRequest::Problem(e)),
        }
    }

    fn delete_selected(&mut self, cx: &mut PanelContext<'_>) {
        let doc = cx.doc.shown();
        let ops: Vec<Operation> = self
            .selected
            .iter()
            .filter_map(|(n, p, t)| Operation::delete_key(doc, n, p, f32::from_bits(*t)).ok())
            .collect();
        if !ops.is_empty() {
            cx.apply(Operation::Group {
                label: format!("delete {} key(s)", ops.len()),
                ops,
            });
        }
        self.selected.clear();
    }

    fn set_interpolation(&mut self, cx: &mut PanelContext<'_>, interpolation: Interpolation) {
        let doc = cx.doc.shown();
        let ops: Vec<Operation> = self
            .selected
            .iter()
            .filter_map(|(n, p, t)| {
                Operation::set_interpolation(doc, n, p, f32::from_bits(*t), interpolation).ok()
            })
            .collect();
        if !ops.is_empty() {
            cx.apply(Operation::Group {
                label: format!("set {} key(s) to {interpolation:?}", ops.len()),
                ops,
            });
        }
    }

    /// The frame ruler and the rows of diamonds, with scrubbing, selection, moving and the
    /// keys' context menu.
    fn strip(&mut self, ui: &mut egui::Ui, cx: &mut PanelContext<'_>, node: Option<&str>) {
        let doc = cx.doc.shown();
        let anim = &doc.animation;
        let fps = anim.fps;
        let mut rows = rows(doc, node);
        let summary: Vec<KeyRef> = rows.iter().flat_map(|r| r.keys.iter().cloned()).collect();
        if !self.expanded {
            rows.clear();
        }
        let label_w = 150.0;
        // The summary row alone unless the channels are shown (at most eight rows): keying
        // never changes the layout by itself.
        let height = ROW * (2 + rows.len().min(8)) as f32;
        let (rect, response) = ui.allocate_exact_size(
            egui::vec2(ui.available_width(), height),
            egui::Sense::click_and_drag(),
        );
        let painter = ui.painter_at(rect);
        let visuals = ui.visuals();
        painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
        let track_rect = egui::Rect::from_min_max(
            egui::pos2(rect.left() + label_w, rect.top()),
            egui::pos2(rect.right() - 20.0, rect.bottom()),
        );
        self.layout = Some((track_rect, anim.start, anim.end));
        let span = (anim.end - anim.start).max(1) as f32;
        let x_of = |frame: f32| {
            track_rect.left() + (frame - anim.start as f32) / span * track_rect.width()
        };
        let frame_of = |x: f32| {
            (anim.start as f32 + (x - track_rect.left()) / track_rect.width() * span).round()
        };
        // Ruler: a tick per frame when there is room, numbers every `step` frames.
        let px = track_rect.width() / span;
        let step = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000]
            .into_iter()
            .find(|s| *s as f32 * px >= 40.0)
            .unwrap_or(1000);
        let text = visuals.text_color();
        let weak = visuals.weak_text_color();
        for f in anim.start..=anim.end {
            let x = x_of(f as f32);
            if f % step == 0 {
                painter.line_segment(
                    [
                        egui::pos2(x, rect.top() + ROW * 0.6),
                        egui::pos2(x, rect.bottom()),
                    ],
                    egui::Stroke::new(1.0, weak.gamma_multiply(0.3)),
                );
                painter.text(
                    egui::pos2(x + 2.0, rect.top() + 1.0),
                    egui::Align2::LEFT_TOP,
                    f.to_string(),
                    egui::FontId::monospace(10.0),
                    weak,
                );
            } else if px >= 4.0 {
                painter.line_segment(
                    [
                        egui::pos2(x, rect.top() + ROW * 0.75),
                        egui::pos2(x, rect.top() + ROW),
                    ],
                    egui::Stroke::new(1.0, weak.gamma_multiply(0.5)),
                );
            }
        }
        // Rows: the summary, then one per channel.
        let mut diamonds: Vec<(egui::Pos2, Vec<KeyRef>)> = Vec::new();
        let summary_label = match node {
            Some(n) => format!("{n} (all)"),
            None => "all keys".to_owned(),
        };
        let all_rows = std::iter::once((summary_label, summary))
            .chain(rows.into_iter().map(|r| (r.label, r.keys)));
        for (i, (label, keys)) in all_rows.enumerate() {
            let y = rect.top() + ROW * (i as f32 + 1.5);
            if y > rect.bottom() {
                break;
            }
            painter.text(
                egui::pos2(rect.left() + 4.0, y),
                egui::Align2::LEFT_CENTER,
                elide(&label, 22),
                egui::FontId::proportional(11.0),
                if i == 0 { text } else { weak },
            );
            // Keys at the same frame share one diamond.
            let mut at: BTreeMap<i64, Vec<KeyRef>> = BTreeMap::new();
            for k in keys {
                let f = (f32::from_bits(k.2) * fps).round() as i64;
                at.entry(f).or_default().push(k);
            }
            for (f, keys) in at {
                let p = egui::pos2(x_of(f as f32), y);
                if !track_rect.expand(DIAMOND).contains(p) {
                    continue;
                }
                let selected = keys.iter().all(|k| self.selected.contains(k));
                let fill = if selected {
                    egui::Color32::from_rgb(255, 200, 60)
                } else {
                    egui::Color32::from_gray(215)
                };
                painter.add(egui::Shape::convex_polygon(
                    vec![
                        p + egui::vec2(0.0, -DIAMOND),
                        p + egui::vec2(DIAMOND, 0.0),
                        p + egui::vec2(0.0, DIAMOND),
                        p + egui::vec2(-DIAMOND, 0.0),
                    ],
                    fill,
                    egui::Stroke::new(1.0, egui::Color32::BLACK),
                ));
                diamonds.push((p, keys));
            }
        }
        // The current frame.
        let x = x_of(cx.doc.frame());
        painter.line_segment(
            [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
            egui::Stroke::new(2.0, egui::Color32::from_rgb(80, 160, 255)),
        );
        let hit = |pos: egui::Pos2| {
            diamonds
                .iter()
                .find(|(p, _)| {
                    (p.x - pos.x).abs() <= DIAMOND + 2.0 && (p.y - pos.y).abs() <= DIAMOND + 2.0
                })
                .map(|(_, k)| k.clone())
        };
        let in_ruler =
            |pos: egui::Pos2| pos.y < rect.top() + ROW && pos.x >= track_rect.left() - 4.0;
        let shift = ui.input(|i| i.modifiers.shift);
        // Press: decide what the drag does.
        if response.drag_started()
            && let Some(pos) = ui
                .input(|i| i.pointer.press_origin())
                .or(response.interact_pointer_pos())
        {
            self.drag = Some(if in_ruler(pos) {
                Drag::Scrub
            } else if let Some(keys) = hit(pos) {
                if !keys.iter().all(|k| self.selected.contains(k)) {
                    if !shift {
                        self.selected.clear();
                    }
                    self.selected.extend(keys);
                }
                Drag::Keys { moved: 0 }
            } else {
                Drag::Box {
                    from: pos,
                    add: shift,
                }
            });
        }
        let pointer = response.interact_pointer_pos();
        match (&mut self.drag, pointer) {
            (Some(Drag::Scrub), Some(pos)) if response.dragged() => {
                let f = frame_of(pos.x).clamp(anim.start as f32, anim.end as f32);
                cx.commands.push(DocumentCommand::SetTime(f / fps));
            }
            (Some(Drag::Keys { moved }), Some(pos)) if response.dragged() => {
                let origin = ui.input(|i| i.pointer.press_origin()).unwrap_or(pos);
                let wanted = ((pos.x - origin.x) / px).round() as i32;
                if wanted != *moved {
                    let delta = wanted - *moved;
                    // Blocked by another key: the keys stay where they are.
                    if let Ok(op) = move_operation(doc, &self.selected, delta) {
                        cx.apply_in_gesture(&response, op, "move keys".to_owned());
                        self.selected = shifted(&self.selected, delta, fps);
                        *moved = wanted;
                    }
                }
            }
            (Some(Drag::Box { from, .. }), Some(pos)) if response.dragged() => {
                let r = egui::Rect::from_two_pos(*from, pos);
                painter.rect_stroke(
                    r,
                    0.0,
                    egui::Stroke::new(1.0, egui::Color32::from_rgb(255, 200, 60)),
                    egui::StrokeKind::Inside,
                );
            }
            _ => {}
        }
        if response.drag_stopped() {
            if let (Some(Drag::Box { from, add }), Some(pos)) = (&self.drag, pointer) {
                let r = egui::Rect::from_two_pos(*from, pos);
                if !add {
                    self.selected.clear();
                }
                for (p, keys) in &diamonds {
                    if r.contains(*p) {
                        self.selected.extend(keys.iter().cloned());
                    }
                }
            }
            self.drag = None;
        }
        // Clicks: the ruler sets the frame, a diamond selects its keys, empty space clears.
        if (response.clicked() || response.secondary_clicked())
            && let Some(pos) = pointer
        {
            if in_ruler(pos) && response.clicked() {
                let f = frame_of(pos.x).clamp(anim.start as f32, anim.end as f32);
                cx.commands.push(DocumentCommand::SetTime(f / fps));
            } else if let Some(keys) = hit(pos) {
                let all = keys.iter().all(|k| self.selected.contains(k));
                if shift && all && response.clicked() {
                    for k in &keys {
                        self.selected.remove(k);
                    }
                } else if !all {
                    if !shift {
                        self.selected.clear();
                    }
                    self.selected.extend(keys);
                }
            } else if response.clicked() && !shift {
                self.selected.clear();
            }
        }
        let has_keys = !self.selected.is_empty();
        response.context_menu(|ui| {
            if !has_keys {
                ui.weak("Select keys first (click a diamond).");
                return;
            }
            ui.label("Interpolation");
            for (label, i) in [
                ("Step", Interpolation::Step),
                ("Linear", Interpolation::Linear),
                ("Smooth", Interpolation::Smooth),
            ] {
                if ui.button(label).clicked() {
                    self.set_interpolation(cx, i);
                    ui.close();
                }
            }
            ui.separator();
            if ui.button("Delete keys").clicked() {
                self.delete_selected(cx);
                ui.close();
            }
        });
    }
}

/// `s` cut to `n` characters with an ellipsis.
fn elide(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_owned()
    } else {
        let mut out: String = s.chars().take(n - 1).collect();
        out.push('…');
        out
    }
}
