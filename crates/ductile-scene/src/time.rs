//! Time: the document's keyframe tracks and timeline, and the document at a time
//! ([`Document::at`]).
//!
//! A track animates one channel of one node (see [`crate::channels`]); it is addressed by the
//! node's name and the channel's path, and [`Document::rename`] moves a renamed node's
//! tracks with it. Times are in seconds; the timeline (`start`, `end`, in frames at `fps`)
//! is the range played and exported.

use std::collections::BTreeMap;

use ductile_anim::key::{Key, key_problem, sample, structure_breaks};
use ductile_anim::value::Value;
use serde::{Deserialize, Serialize};

use crate::channels::{node_channels, set_node_channel};
use crate::document::{Document, Node};
use crate::error::{Result, SceneError};

/// A node's tracks: keys by channel path.
pub type NodeTracks = BTreeMap<String, Vec<Key>>;

/// The timeline's settings: frame rate and frame range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Timeline {
    /// Frames per second (finite, > 0).
    pub fps: f32,
    /// First frame.
    pub start: i32,
    /// Last frame (≥ `start`).
    pub end: i32,
}

/// The keyframe tracks and the timeline of a document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Animation {
    /// Frames per second (finite, > 0; default 24).
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// First frame of the timeline (default 0).
    #[serde(default)]
    pub start: i32,
    /// Last frame of the timeline (≥ `start`; default 48).
    #[serde(default = "default_end")]
    pub end: i32,
    /// Tracks by node name, then by channel path; each a list of keys, strictly increasing
    /// in time.
    #[serde(default)]
    pub tracks: BTreeMap<String, NodeTracks>,
}

fn default_fps() -> f32 {
    24.0
}

fn default_end() -> i32 {
    48
}

impl Default for Animation {
    fn default() -> Self {
        Self {
            fps: default_fps(),
            start: 0,
            end: default_end(),
            tracks: BTreeMap::new(),
        }
    }
}

impl Animation {
    /// The timeline's settings.
    #[must_use]
    pub fn timeline(&self) -> Timeline {
        Timeline {
            fps: self.fps,
            start: self.start,
            end: self.end,
        }
    }

    /// Sets the timeline's settings (unchecked; see [`Timeline::problems`]).
    pub fn set_timeline(&mut self, t: Timeline) {
        self.fps = t.fps;
        self.start = t.start;
        self.end = t.end;
    }

    /// True when this is the default timeline without tracks (it is then not written to
    /// scene files).
    #[must_use]
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// True when no track has a key.
    #[must_use]
    pub fn is_static(&self) -> bool {
        self.tracks.values().all(|t| t.values().all(Vec::is_empty))
    }

    /// The time in seconds of frame `frame` at the timeline's rate.
    #[must_use]
    pub fn frame_time(&self, frame: f32) -> f32 {
        frame / self.fps
    }

    /// The keys of channel `path` of node `node`, if it has a track.
    #[must_use]
    pub fn track(&self, node: &str, path: &str) -> Option<&[Key]> {
        self.tracks.get(node)?.get(path).map(Vec::as_slice)
    }

    /// Every track as `(node, path, keys)`, in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &str, &[Key])> {
        self.tracks.iter().flat_map(|(node, t)| {
            t.iter()
                .map(move |(path, keys)| (node.as_str(), path.as_str(), keys.as_slice()))
        })
    }

    /// Every key time of every track, sorted, without duplicates.
    #[must_use]
    pub fn key_times(&self) -> Vec<f32> {
        let mut t: Vec<f32> = self
            .iter()
            .flat_map(|(_, _, k)| k.iter().map(|k| k.time))
            .collect();
        t.sort_by(f32::total_cmp);
        t.dedup();
        t
    }

    /// Checks that frame `frame` lies in the timeline `[start, end]`.
    pub fn check_frame(&self, frame: f32) -> Result<()> {
        if frame.is_finite() && frame >= self.start as f32 && frame <= self.end as f32 {
            Ok(())
        } else {
            Err(SceneError::Timeline {
                problem: format!(
                    "frame {frame} is outside the timeline (frames {} to {})",
                    self.start, self.end
                ),
            })
        }
    }
}

impl Timeline {
    /// The problems of the settings: the frame rate must be finite and > 0, the range not
    /// reversed.
    #[must_use]
    pub fn problems(&self) -> Vec<SceneError> {
        let mut out = Vec::new();
        if !(self.fps.is_finite() && self.fps > 0.0) {
            out.push(SceneError::Timeline {
                problem: format!("fps = {} must be a finite number > 0", self.fps),
            });
        }
        if self.start > self.end {
            out.push(SceneError::Timeline {
                problem: format!("start frame {} is after end frame {}", self.start, self.end),
            });
        }
        out
    }
}

impl Document {
    /// The document at time `t` (seconds): every animated channel set to its track's value
    /// at `t`. A pure function of the document and `t`; a document without tracks comes
    /// back unchanged, so it evaluates exactly as before.
    ///
    /// # Errors
    /// A track naming a node or channel that does not exist, or holding values of another
    /// kind than its channel ([`Document::problems`] reports these too).
    pub fn at(&self, t: f32) -> Result<Document> {
        let mut doc = self.clone();
        doc.pose_at(self, t)?;
        Ok(doc)
    }

    /// Sets every animated channel of `self` to the value of `source`'s tracks at time `t`
    /// (seconds), leaving every other part of `self` as it is: what [`Document::at`] does
    /// without copying the document (playback writes into one working copy).
    pub fn pose_at(&mut self, source: &Document, t: f32) -> Result<()> {
        for (node, path, keys) in source.animation.iter() {
            let Some(value) = sample(keys, t) else {
                continue;
            };
            self.set_channel(node, path, &value)
                .map_err(|e| track_error(node, path, e))?;
        }
        Ok(())
    }

    /// The problems of the timeline and of every track: unknown nodes and channels, key
    /// values of another kind than their channel, bad key times and values.
    pub(crate) fn animation_problems(&self, out: &mut Vec<SceneError>) {
        out.extend(self.animation.timeline().problems());
        for (node, path, keys) in self.animation.iter() {
            let problem = |p: String| SceneError::Track {
                node: node.to_owned(),
                param: path.to_owned(),
                problem: p,
            };
            let Ok(n) = self.node(node) else {
                out.push(problem("there is no such node".to_owned()));
                continue;
            };
            if let Some(p) = track_problem(n, path, keys) {
                out.push(problem(p));
            }
        }
    }

    /// Warnings that do not stop evaluation: macros whose own area is missing where they are
    /// used ([`Document::macro_area_warnings`]), and intervals of a track that should
    /// interpolate but step because their two keys' values cannot be interpolated (another
    /// number of points or spline values, another kind).
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .macro_area_warnings()
            .iter()
            .map(ToString::to_string)
            .collect();
        for (node, path, keys) in self.animation.iter() {
            for k in structure_breaks(keys) {
                out.push(format!(
                    "animation track '{node}' / '{path}': keys {k} (at {} s, {}) and {} (at {} s, {}) cannot be interpolated; the track steps there",
                    keys[k].time,
                    keys[k].value.shape(),
                    k + 1,
                    keys[k + 1].time,
                    keys[k + 1].value.shape(),
                ));
            }
        }
        out
    }

    /// The value of node `node`'s channel `path` at time `t`: its track's if it has one,
    /// else its current value.
    pub fn channel_at(&self, node: &str, path: &str, t: f32) -> Result<Value> {
        match self.animation.track(node, path).and_then(|k| sample(k, t)) {
            Some(v) => Ok(v),
            None => self.channel(node, path),
        }
    }
}

/// The first problem of the keys `keys` on channel `path` of `node`: no key, bad times or
/// values, no such channel, a value that does not fit the channel (kind, or the plane of a
/// sketch curve).
#[must_use]
pub fn track_problem(node: &Node, path: &str, keys: &[Key]) -> Option<String> {
    if keys.is_empty() {
        return Some("the track has no key".to_owned());
    }
    if let Some(p) = key_problem(keys) {
        return Some(p);
    }
    if !node_channels(node).iter().any(|(p, _)| p == path) {
        return Some(format!(
            "the {} has no animatable parameter '{path}'",
            node.kind.name()
        ));
    }
    let mut probe = node.clone();
    for (i, k) in keys.iter().enumerate() {
        if let Err(e) = set_node_channel(&mut probe, path, &k.value) {
            return Some(format!("key {i} (at {} s): {e}", k.time));
        }
    }
    None
}

fn track_error(node: &str, path: &str, e: SceneError) -> SceneError {
    let problem = match e {
        SceneError::Channel { source, .. } => source.to_string(),
        other => other.to_string(),
    };
    SceneError::Track {
        node: node.to_owned(),
        param: path.to_owned(),
        problem,
    }
}

#[cfg(test)]
mod tests {
    use ductile_anim::key::Interpolation;

    use super::*;
    use crate::document::{MacroUse, NodeKind};
    use crate::transform::Transform;

    fn doc() -> Document {
        let mut d = Document {
            nodes: vec![Node {
                name: "nose".into(),
                parent: None,
                transform: Transform::IDENTITY,
                kind: NodeKind::Macro(MacroUse {
                    name: "nose".into(),
                    value: 0.0,
                }),
            }],
            ..Document::default()
        };
        d.animation.tracks.entry("nose".into()).or_default().insert(
            "value".into(),
            vec![
                Key {
                    time: 0.0,
                    value: Value::Scalar(0.0),
                    interpolation: Interpolation::Linear,
                },
                Key::new(2.0, Value::Scalar(1.0)),
            ],
        );
        d
    }

    #[test]
    fn the_document_at_a_time_takes_the_tracks_values() {
        let d = doc();
        let mid = d.at(0.5).unwrap();
        assert_eq!(mid.channel("nose", "value").unwrap(), Value::Scalar(0.25));
        assert_eq!(
            d.channel_at("nose", "value", 2.0).unwrap(),
            Value::Scalar(1.0)
        );
        // The original is untouched; without tracks nothing changes.
        assert_eq!(d.channel("nose", "value").unwrap(), Value::Scalar(0.0));
        let mut still = d.clone();
        still.animation.tracks.clear();
        assert_eq!(still.at(1.0).unwrap(), still);
    }

    #[test]
    fn bad_tracks_are_problems() {
        let mut d = doc();
        d.animation
            .tracks
            .entry("ghost".into())
            .or_default()
            .insert("value".into(), vec![Key::new(0.0, Value::Scalar(0.0))]);
        d.animation
            .tracks
            .get_mut("nose")
            .unwrap()
            .insert("gamma".into(), vec![Key::new(0.0, Value::Scalar(0.0))]);
        d.animation.tracks.get_mut("nose").unwrap().insert(
            "transform.scale".into(),
            vec![Key::new(0.0, Value::Scalar(2.0))],
        );
        d.animation.fps = 0.0;
        let text: Vec<String> = d.problems().iter().map(ToString::to_string).collect();
        let all = text.join("\n");
        assert!(all.contains("fps = 0"), "{all}");
        assert!(
            all.contains("'ghost' / 'value': there is no such node"),
            "{all}"
        );
        assert!(all.contains("no animatable parameter 'gamma'"), "{all}");
        assert!(all.contains("'transform.scale': key 0"), "{all}");
        assert!(d.at(0.0).is_err());
    }

    #[test]
    fn frames_outside_the_timeline_are_refused() {
        let a = Animation::default();
        assert!(a.check_frame(0.0).is_ok() && a.check_frame(48.0).is_ok());
        let e = a.check_frame(49.0).unwrap_err().to_string();
        assert!(
            e.contains("frame 49 is outside the timeline (frames 0 to 48)"),
            "{e}"
        );
    }
}
