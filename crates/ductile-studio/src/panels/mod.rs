//! The Studio's panels, one struct and file per panel (like egui_demo_lib). Panels read the
//! document and emit [`DocumentCommand`]s into [`PanelContext::commands`]; they never
//! mutate the document.

pub mod add_menu;
pub mod adjust_last;
pub mod curve_editor;
pub mod history;
pub mod influence;
pub mod inspector;
pub mod key_offer;
pub mod macros;
pub mod menu_bar;
pub mod outliner;
pub mod params;
pub mod stack;
pub mod status_bar;
pub mod timeline;
pub mod tool_editor;
pub mod variants;

#[cfg(test)]
mod tests;

use bevy_egui::egui;
use ductile_bevy::prelude::*;
use ductile_history::operation::Operation;

/// What a panel asks the Studio for besides document edits.
#[derive(Debug, Clone, PartialEq)]
pub enum PanelRequest {
    /// Redraw the strokes of this sketch tool node in sketch mode.
    RedrawSketch(String),
    /// Tell the user why an action could not be done (shown in the status bar).
    Problem(String),
    /// Show these copies side by side with the mesh in focus (none: no comparison).
    Compare(Vec<crate::compare::CompareEntry>),
}

/// Whether a channel is animated, and keyed at the current time (the colours of keyed
/// fields follow Blender: yellow on a key, green between keys, orange when changed and not
/// keyed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyState {
    /// The channel has no track.
    Static,
    /// The channel has a track without a key at the current time.
    Animated,
    /// The channel has a key at the current time.
    Keyed,
    /// The channel is animated and changed by an edit waiting to be keyed.
    Changed,
}

impl KeyState {
    /// The state of channel `path` of node `node` at the document's current time.
    #[must_use]
    pub fn of(doc: &SceneDocument, node: &str, path: &str) -> Self {
        let fps = doc.document().animation.fps;
        let frame = doc.frame();
        if doc
            .pending()
            .is_some_and(|p| p.channels().iter().any(|(n, c)| n == node && c == path))
        {
            return Self::Changed;
        }
        match doc.document().animation.track(node, path) {
            None => Self::Static,
            Some(keys) if keys.iter().any(|k| (k.time * fps).round() == frame) => Self::Keyed,
            Some(_) => Self::Animated,
        }
    }

    /// The colour a field's label takes, if any.
    #[must_use]
    pub fn color(self) -> Option<egui::Color32> {
        match self {
            Self::Static => None,
            Self::Animated => Some(egui::Color32::from_rgb(120, 200, 110)),
            Self::Keyed => Some(egui::Color32::from_rgb(235, 200, 70)),
            Self::Changed => Some(key_offer::UNKEYED),
        }
    }
}

/// Remembers that the pointer is over the field of channel `path` of node `node` this frame,
/// so that K keys that channel alone (read by the timeline the next frame; see
/// [`take_hovered_channel`]).
pub fn hover_channel(ctx: &egui::Context, node: &str, path: &str) {
    ctx.data_mut(|d| {
        d.insert_temp(
            egui::Id::new("hovered-channel"),
            (node.to_owned(), path.to_owned()),
        );
    });
}

/// The channel whose field the pointer was over in the last frame, if any (and forgets it).
pub fn take_hovered_channel(ctx: &egui::Context) -> Option<(String, String)> {
    ctx.data_mut(|d| d.remove_temp::<(String, String)>(egui::Id::new("hovered-channel")))
}

/// What every panel may read and the edits it may ask for.
pub struct PanelContext<'a> {
    /// The document (read only).
    pub doc: &'a SceneDocument,
    /// The selection (view state, edited directly).
    pub selection: &'a mut Selection,
    /// Edits requested this frame, applied after the UI pass.
    pub commands: Vec<DocumentCommand>,
    /// Other requests of this frame (adding nodes, sketch mode).
    pub requests: Vec<PanelRequest>,
    /// Source of gesture ids for sliders and drags.
    pub gestures: &'a mut Gestures,
    /// Seconds since the Studio started (for playback).
    pub now: f64,
    /// The rest meshes loaded, by mesh node name (a DOGME or Direct FFD constraint anchored
    /// at a vertex is checked against its mesh's vertex count).
    pub meshes: &'a [(String, std::sync::Arc<ductile_core::mesh::RestMesh>)],
}

impl PanelContext<'_> {
    /// Requests `op` as its own undo step.
    pub fn apply(&mut self, op: Operation) {
        self.commands.push(DocumentCommand::apply(op));
    }

    /// Requests `op` as part of the gesture of widget `id` (a slider being dragged): the
    /// gesture's edits become one undo step.
    pub fn apply_in_gesture(&mut self, response: &egui::Response, op: Operation, label: String) {
        let gesture = self.gestures.for_widget(response);
        self.commands.push(DocumentCommand::Apply {
            op: Box::new(op),
            label,
            gesture,
        });
    }
}

/// Gesture ids for widgets: a slider drag keeps one id from press to release, so its edits
/// merge into one undo step; a keyboard change is its own step.
#[derive(bevy::prelude::Resource, Debug)]
pub struct Gestures {
    next: u64,
    /// The widget of the current gesture, when its press started, and the gesture's id.
    current: Option<(egui::Id, Option<f64>, u64)>,
}

impl Default for Gestures {
    /// Ids counted from the milliseconds since the UNIX epoch when the session starts: a
    /// history saved by an earlier session keeps its steps' gesture ids, and a new gesture
    /// must not continue one of them (its edit would merge into the loaded step). A session
    /// takes an id per drag or added node, far fewer than the milliseconds that pass, so its
    /// ids stay below the clock and a later session starts above all of them.
    fn default() -> Self {
        let now_ms = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64);
        Self {
            next: now_ms,
            current: None,
        }
    }
}

impl Gestures {
    /// A gesture id of its own, for an edit that later edits may join (a node added from the
    /// Add menu, which the "Adjust last operation" panel edits within the same step).
    pub fn fresh(&mut self) -> u64 {
        self.next += 1;
        (1 << 48) + self.next
    }

    /// The gesture of the widget behind `response`: the current one while the same press
    /// drags the same widget, else a new one. A drag's first change may come frames after
    /// the press (an integer field moves after several points), so the press's start time
    /// tells two drags of one widget apart; on the release frame the press has ended and
    /// the widget's current gesture goes on.
    pub fn for_widget(&mut self, response: &egui::Response) -> Option<u64> {
        let dragging = response.dragged() || response.drag_stopped();
        if !dragging {
            self.current = None;
            return None;
        }
        let press = response.ctx.input(|i| i.pointer.press_start_time());
        match self.current {
            Some((id, started, g))
                if id == response.id
                    && !response.drag_started()
                    && (press.is_none() || press == started) =>
            {
                Some(g)
            }
            _ => {
                let g = self.fresh();
                self.current = Some((response.id, press, g));
                Some(g)
            }
        }
    }
}
