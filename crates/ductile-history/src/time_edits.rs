//! Constructors of the time operations (keys, tracks, timeline, variants) that read the
//! `old` values from a document, like [`crate::edits`]: callers say only what they want.

use std::collections::BTreeMap;

use ductile_anim::key::{Interpolation, Key};
use ductile_scene::prelude::*;
use ductile_scene::symmetry::mirror_name;

use crate::check::node_index;
use crate::error::{HistoryError, Result};
use crate::operation::Operation;
use crate::time_ops::key_at;

impl Operation {
    /// Sets `key` on node `node`'s channel `param` (replacing a key at the same time).
    #[must_use]
    pub fn set_key(doc: &Document, node: &str, param: &str, key: Key) -> Self {
        Operation::SetKey {
            node: node.to_owned(),
            param: param.to_owned(),
            time: key.time,
            old: key_at(doc, node, param, key.time).cloned(),
            new: Some(key),
        }
    }

    /// Keys the current value of node `node`'s channel `param` at time `time` (keeping the
    /// interpolation of a key already there, else smooth).
    pub fn key_current(doc: &Document, node: &str, param: &str, time: f32) -> Result<Self> {
        let value = doc.channel(node, param)?;
        let interpolation =
            key_at(doc, node, param, time).map_or(Interpolation::default(), |k| k.interpolation);
        Ok(Self::set_key(
            doc,
            node,
            param,
            Key {
                time,
                value,
                interpolation,
            },
        ))
    }

    /// Keys every channel of node `node` at time `time` with its current value, as one step
    /// (the Studio's K on what the inspector shows).
    pub fn key_node(doc: &Document, node: &str, time: f32) -> Result<Self> {
        let ops = doc
            .channels(node)?
            .into_iter()
            .map(|(param, _)| Self::key_current(doc, node, &param, time))
            .collect::<Result<Vec<_>>>()?;
        Ok(Operation::Group {
            label: format!("key '{node}' at {time} s"),
            ops,
        })
    }

    /// Deletes the key at `time` of node `node`'s channel `param`.
    pub fn delete_key(doc: &Document, node: &str, param: &str, time: f32) -> Result<Self> {
        let old = key_at(doc, node, param, time)
            .cloned()
            .ok_or_else(|| no_key(node, param, time))?;
        Ok(Operation::SetKey {
            node: node.to_owned(),
            param: param.to_owned(),
            time,
            old: Some(old),
            new: None,
        })
    }

    /// Moves the key at `from` to `to`.
    #[must_use]
    pub fn move_key(node: &str, param: &str, from: f32, to: f32) -> Self {
        Operation::MoveKey {
            node: node.to_owned(),
            param: param.to_owned(),
            from,
            to,
        }
    }

    /// Sets how the track goes on from the key at `time`.
    pub fn set_interpolation(
        doc: &Document,
        node: &str,
        param: &str,
        time: f32,
        interpolation: Interpolation,
    ) -> Result<Self> {
        let old = key_at(doc, node, param, time)
            .cloned()
            .ok_or_else(|| no_key(node, param, time))?;
        let new = Key {
            interpolation,
            ..old.clone()
        };
        Ok(Operation::SetKey {
            node: node.to_owned(),
            param: param.to_owned(),
            time,
            old: Some(old),
            new: Some(new),
        })
    }

    /// Sets (or with `None` removes) the whole track of node `node`'s channel `param`.
    #[must_use]
    pub fn set_track(doc: &Document, node: &str, param: &str, keys: Option<Vec<Key>>) -> Self {
        Operation::SetTrack {
            node: node.to_owned(),
            param: param.to_owned(),
            old: doc.animation.track(node, param).map(<[Key]>::to_vec),
            new: keys,
        }
    }

    /// Sets the timeline's frame rate and range.
    #[must_use]
    pub fn set_timeline(doc: &Document, new: Timeline) -> Self {
        Operation::SetTimeline {
            old: doc.animation.timeline(),
            new,
        }
    }

    /// Saves the current state of every tool and macro tool as variant `name` (replacing a
    /// variant of that name).
    #[must_use]
    pub fn save_variant(doc: &Document, name: &str) -> Self {
        Self::put_variant(doc, name, Some(doc.snapshot()))
    }

    /// Saves `variant` (made by a blend or a random draw: it keeps its origin) as `name`, or
    /// deletes variant `name` with `None`.
    #[must_use]
    pub fn put_variant(doc: &Document, name: &str, variant: Option<Variant>) -> Self {
        Operation::SetVariant {
            name: name.to_owned(),
            old: doc.variants.get(name).cloned(),
            new: variant,
        }
    }

    /// Deletes variant `name`.
    pub fn delete_variant(doc: &Document, name: &str) -> Result<Self> {
        doc.variant(name)?;
        Ok(Self::put_variant(doc, name, None))
    }

    /// Renames variant `old` to `new`.
    #[must_use]
    pub fn rename_variant(old: &str, new: &str) -> Self {
        Operation::RenameVariant {
            old: old.to_owned(),
            new: new.to_owned(),
        }
    }

    /// Writes `states` into their nodes (transform, macro value, tool) as one step labelled
    /// `label`; nodes already in that state get no operation.
    pub fn apply_states(
        doc: &Document,
        states: &BTreeMap<String, NodeState>,
        label: &str,
    ) -> Result<Self> {
        let mut ops = Vec::new();
        for (name, s) in states {
            let node = &doc.nodes[node_index(doc, name)?];
            if node.transform != s.transform {
                ops.push(Operation::set_transform(doc, name, s.transform)?);
            }
            match (&node.kind, &s.state) {
                (NodeKind::Macro(m), State::Macro(v)) => {
                    if m.value != *v {
                        ops.push(Operation::set_macro_value(doc, name, *v)?);
                    }
                }
                (NodeKind::Tool(t), State::Tool(v)) => {
                    if t != v {
                        ops.push(Operation::set_tool(doc, name, v.clone())?);
                    }
                }
                (kind, state) => {
                    return Err(SceneError::WrongKind {
                        node: name.clone(),
                        found: kind.name(),
                        expected: match state {
                            State::Macro(_) => "macro tool",
                            State::Tool(_) => "tool",
                        },
                    }
                    .into());
                }
            }
        }
        Ok(Operation::Group {
            label: label.to_owned(),
            ops,
        })
    }

    /// Applies variant `name` to the scene (one step).
    pub fn apply_variant(doc: &Document, name: &str) -> Result<Self> {
        let v = doc.variant(name)?;
        Self::apply_states(doc, &v.states, &format!("apply variant '{name}'"))
    }

    /// Sets macro tool `node` to `value` and, when it has a left/right mirror
    /// ([`ductile_scene::symmetry`]), the mirror too, as one step.
    pub fn set_macro_value_symmetric(doc: &Document, node: &str, value: f32) -> Result<Self> {
        let mut ops = vec![Operation::set_macro_value(doc, node, value)?];
        if let Some(other) = doc.mirror_of(node) {
            ops.push(Operation::set_macro_value(doc, other, value)?);
        }
        Ok(Operation::Group {
            label: match mirror_name(node) {
                Some(other) if ops.len() == 2 => format!("set '{node}' and '{other}' to {value}"),
                _ => format!("set '{node}' to {value}"),
            },
            ops,
        })
    }
}

fn no_key(node: &str, param: &str, time: f32) -> HistoryError {
    SceneError::Track {
        node: node.to_owned(),
        param: param.to_owned(),
        problem: format!("there is no key at {time} s"),
    }
    .into()
}

#[cfg(test)]
mod tests {
    use ductile_anim::value::Value;

    use super::*;
    use crate::history::History;

    fn doc() -> Document {
        let node = |name: &str, value: f32| Node {
            name: name.into(),
            parent: None,
            transform: Transform::IDENTITY,
            kind: NodeKind::Macro(MacroUse {
                name: "m".into(),
                value,
            }),
        };
        let mut d = Document {
            nodes: vec![
                node("left-ear", 0.0),
                node("right-ear", 0.0),
                node("nose", 0.2),
            ],
            ..Document::default()
        };
        d.macros.insert(
            "m".into(),
            ductile_core::ffsd::FfsdMacro {
                label: "m".into(),
                group: String::new(),
                area: None,
                points: vec![ductile_core::ffsd::ControlPoint::basic(
                    glam::Vec3::ZERO,
                    0.1,
                    2.0,
                    0.1,
                )],
                height: None,
                range: (-1.0, 1.0),
            },
        );
        d
    }

    fn apply(d: &mut Document, h: &mut History, op: Operation) {
        let label = op.describe();
        h.push(d, op, label, 0, None).unwrap();
    }

    #[test]
    fn keys_set_move_and_delete_with_exact_undo() {
        let mut d = doc();
        let before = d.clone();
        let mut h = History::new(d.clone());
        {
            let op = Operation::key_current(&d, "nose", "value", 0.0).unwrap();
            apply(&mut d, &mut h, op)
        }
        {
            let op = Operation::set_key(&d, "nose", "value", Key::new(1.0, Value::Scalar(0.8)));
            apply(&mut d, &mut h, op);
        }
        assert_eq!(
            d.at(0.5).unwrap().channel("nose", "value").unwrap(),
            Value::Scalar(0.5)
        );
        {
            let op = Operation::set_interpolation(&d, "nose", "value", 0.0, Interpolation::Step)
                .unwrap();
            apply(&mut d, &mut h, op);
        }
        assert_eq!(
            d.at(0.5).unwrap().channel("nose", "value").unwrap(),
            Value::Scalar(0.2)
        );
        {
            let op = Operation::move_key("nose", "value", 1.0, 2.0);
            apply(&mut d, &mut h, op)
        }
        assert_eq!(d.animation.track("nose", "value").unwrap()[1].time, 2.0);
        {
            let op = Operation::delete_key(&d, "nose", "value", 0.0).unwrap();
            apply(&mut d, &mut h, op)
        }
        {
            let op = Operation::delete_key(&d, "nose", "value", 2.0).unwrap();
            apply(&mut d, &mut h, op)
        }
        // The last key gone, the track is gone.
        assert!(d.animation.tracks.is_empty());
        while h.undo(&mut d).unwrap() {}
        assert_eq!(d, before);
    }

    #[test]
    fn bad_keys_are_refused() {
        let d = doc();
        let e = Operation::set_key(
            &d,
            "nose",
            "value",
            Key::new(0.0, Value::Vector(glam::Vec3::X)),
        )
        .apply(&mut d.clone())
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("'nose' / 'value'") && e.contains("a number"),
            "{e}"
        );
        let e = Operation::set_key(&d, "nose", "gamma", Key::new(0.0, Value::Scalar(1.0)))
            .apply(&mut d.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no animatable parameter 'gamma'"), "{e}");
        let e = Operation::set_key(&d, "nose", "value", Key::new(f32::NAN, Value::Scalar(1.0)))
            .apply(&mut d.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("key time: NaN is not a finite number"), "{e}");
        let mut d2 = d.clone();
        Operation::set_key(&d, "nose", "value", Key::new(0.0, Value::Scalar(1.0)))
            .apply(&mut d2)
            .unwrap();
        Operation::set_key(&d2, "nose", "value", Key::new(1.0, Value::Scalar(1.0)))
            .apply(&mut d2)
            .unwrap();
        assert!(
            Operation::move_key("nose", "value", 0.0, 1.0)
                .apply(&mut d2)
                .is_err()
        );
        let e = Operation::set_timeline(
            &d,
            Timeline {
                fps: 0.0,
                start: 0,
                end: 1,
            },
        )
        .apply(&mut d.clone())
        .unwrap_err()
        .to_string();
        assert!(e.contains("fps"), "{e}");
    }

    #[test]
    fn a_drag_on_a_keyed_value_merges_into_one_step() {
        let d = doc();
        let mut a = Operation::set_key(&d, "nose", "value", Key::new(0.0, Value::Scalar(0.3)));
        let mut d2 = d.clone();
        a.apply(&mut d2).unwrap();
        let b = Operation::set_key(&d2, "nose", "value", Key::new(0.0, Value::Scalar(0.4)));
        assert!(a.merge(&b));
        let mut d3 = d.clone();
        a.apply(&mut d3).unwrap();
        assert_eq!(
            d3.channel_at("nose", "value", 0.0).unwrap(),
            Value::Scalar(0.4)
        );
    }

    #[test]
    fn variants_save_apply_rename_delete() {
        let mut d = doc();
        let start = d.clone();
        let mut h = History::new(d.clone());
        {
            let op = Operation::save_variant(&d, "A");
            apply(&mut d, &mut h, op)
        }
        {
            let op = Operation::set_macro_value_symmetric(&d, "left-ear", 0.7).unwrap();
            apply(&mut d, &mut h, op)
        }
        assert_eq!(d.channel("right-ear", "value").unwrap(), Value::Scalar(0.7));
        {
            let op = Operation::save_variant(&d, "B");
            apply(&mut d, &mut h, op)
        }
        {
            let op = Operation::apply_variant(&d, "A").unwrap();
            apply(&mut d, &mut h, op)
        }
        assert_eq!(d.channel("left-ear", "value").unwrap(), Value::Scalar(0.0));
        {
            let op = Operation::rename_variant("A", "suspect A");
            apply(&mut d, &mut h, op)
        }
        assert!(
            Operation::rename_variant("B", "suspect A")
                .apply(&mut d.clone())
                .is_err()
        );
        assert!(
            Operation::rename_variant("B", "")
                .apply(&mut d.clone())
                .is_err()
        );
        {
            let op = Operation::delete_variant(&d, "B").unwrap();
            apply(&mut d, &mut h, op)
        }
        assert_eq!(d.variants.keys().collect::<Vec<_>>(), ["suspect A"]);
        while h.undo(&mut d).unwrap() {}
        assert_eq!(d, start);
    }

    #[test]
    fn removing_an_animated_node_takes_its_tracks_and_variant_states() {
        let mut d = doc();
        Operation::key_current(&d, "nose", "value", 0.0)
            .unwrap()
            .apply(&mut d)
            .unwrap();
        Operation::save_variant(&d, "A").apply(&mut d).unwrap();
        let e = Operation::remove_node(&d, "nose")
            .unwrap()
            .apply(&mut d.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("animation track 'nose'"), "{e}");
        let before = d.clone();
        let op = Operation::remove_node_and_references(&d, "nose").unwrap();
        op.apply(&mut d).unwrap();
        assert!(d.animation.tracks.is_empty());
        assert!(!d.variants["A"].states.contains_key("nose"));
        assert!(d.problems().is_empty());
        op.revert(&mut d).unwrap();
        assert_eq!(d, before);
    }

    #[test]
    fn rename_keeps_tracks_and_variants() {
        let mut d = doc();
        Operation::key_current(&d, "nose", "value", 0.0)
            .unwrap()
            .apply(&mut d)
            .unwrap();
        Operation::save_variant(&d, "A").apply(&mut d).unwrap();
        Operation::rename("nose", "snout").apply(&mut d).unwrap();
        assert!(d.animation.track("snout", "value").is_some());
        assert!(d.variants["A"].states.contains_key("snout"));
        assert!(d.problems().is_empty());
    }
}
