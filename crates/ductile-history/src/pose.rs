//! Edits made on the document at a time: the Studio shows and edits the **pose**
//! `base.at(t)` ([`Document::at`]), but the history records edits of the **base** document
//! (tracks, rest values, structure). [`Operation::onto_base`] turns an edit built against the
//! pose into the edit of the base that has the same effect at time `t`:
//!
//! * a changed channel that has a track becomes a key at `t` (the auto-key of Blender and
//!   Maya for animated properties: without it the edit would be undone by the track at the
//!   next frame, and the artist's work lost);
//! * a changed channel without a track changes the base value, as without animation;
//! * animated channels the edit did not change keep their base values (the pose's values are
//!   not written into the base);
//! * every other operation (structure, layers, keys, variants) is kept, except that a
//!   removed node is recorded as it is in the base, so that undo restores it exactly.
//!
//! A document without tracks is its own pose, and every operation comes back unchanged.

use ductile_anim::key::Key;
use ductile_anim::value::Value;
use ductile_scene::channels::{node_channels, set_node_channel};
use ductile_scene::prelude::*;

use crate::check::node_index;
use crate::error::Result;
use crate::operation::Operation;
use crate::time_ops::key_at;

impl Operation {
    /// The edit of `base` that has the effect of `self` (built against `posed`, which is
    /// `base.at(t)`) at time `t` seconds. See the [module documentation](self).
    ///
    /// # Errors
    /// `self` does not apply to `posed` (its recorded values are not the pose's), or names a
    /// node that does not exist.
    pub fn onto_base(self, base: &Document, posed: &Document, t: f32) -> Result<Self> {
        if base.animation.is_static() {
            return Ok(self);
        }
        let label = self.describe();
        let mut out = Vec::new();
        let mut base = base.clone();
        let mut posed = posed.clone();
        rebase(self, &mut base, &mut posed, t, &mut out)?;
        Ok(match out.len() {
            1 if !matches!(out[0], Operation::SetKey { .. }) => out.remove(0),
            _ => Operation::Group { label, ops: out },
        })
    }
}

/// Rebases `op` onto `base`, appending the base's operations to `out` and applying them to
/// `base` (and `op` to `posed`) so that the next operation of a group sees their effect.
fn rebase(
    op: Operation,
    base: &mut Document,
    posed: &mut Document,
    t: f32,
    out: &mut Vec<Operation>,
) -> Result<()> {
    use Operation as O;
    match op {
        O::Group { ops, .. } => {
            for op in ops {
                rebase(op, base, posed, t, out)?;
            }
            return Ok(());
        }
        O::SetTransform { ref node, .. }
        | O::SetTool { ref node, .. }
        | O::SetVolume { ref node, .. }
        | O::SetMacroValue { ref node, .. }
            if base.animation.tracks.contains_key(node) =>
        {
            let node = node.clone();
            let before = posed.node(&node)?.clone();
            op.apply(posed)?;
            let after = posed.node(&node)?.clone();
            let ops = channel_edit(base, &node, &before, &after, t)?;
            for op in ops {
                op.apply(base)?;
                out.push(op);
            }
            return Ok(());
        }
        _ => {}
    }
    op.apply(posed)?;
    let op = match op {
        O::RemoveNode { index, .. } if index < base.nodes.len() => O::RemoveNode {
            index,
            node: base.nodes[index].clone(),
        },
        other => other,
    };
    op.apply(base)?;
    out.push(op);
    Ok(())
}

/// The base operations for a node whose pose went from `before` to `after`: keys at `t` for
/// its changed animated channels, and the edit of its base state for the rest.
fn channel_edit(
    base: &Document,
    name: &str,
    before: &Node,
    after: &Node,
    t: f32,
) -> Result<Vec<Operation>> {
    let tracks = base.animation.tracks.get(name);
    let animated = |path: &str| tracks.is_some_and(|m| m.get(path).is_some_and(|k| !k.is_empty()));
    let old: Vec<(String, Value)> = node_channels(before);
    let mut ops = Vec::new();
    let current = &base.nodes[node_index(base, name)?];
    let mut merged = after.clone();
    for (path, new_value) in node_channels(after) {
        if !animated(&path) {
            continue;
        }
        let changed = old
            .iter()
            .find(|(p, _)| *p == path)
            .is_none_or(|(_, v)| *v != new_value);
        if changed {
            let interpolation = key_at(base, name, &path, t)
                .map_or_else(ductile_anim::key::Interpolation::default, |k| {
                    k.interpolation
                });
            ops.push(Operation::set_key(
                base,
                name,
                &path,
                Key {
                    time: t,
                    value: new_value,
                    interpolation,
                },
            ));
        }
        // The base keeps its own value of an animated channel (the track decides the pose).
        if let Ok(v) = base.channel(name, &path) {
            let _ = set_node_channel(&mut merged, &path, &v);
        }
    }
    if merged.transform != current.transform {
        ops.push(Operation::set_transform(base, name, merged.transform)?);
    }
    match (&current.kind, merged.kind) {
        (NodeKind::Tool(a), NodeKind::Tool(b)) if *a != b => {
            ops.push(Operation::set_tool(base, name, b)?);
        }
        (NodeKind::Volume(a), NodeKind::Volume(b)) if a.shape != b.shape => {
            ops.push(Operation::set_volume(base, name, b.shape)?);
        }
        (NodeKind::Macro(a), NodeKind::Macro(b)) if a.value != b.value => {
            ops.push(Operation::set_macro_value(base, name, b.value)?);
        }
        _ => {}
    }
    Ok(ops)
}

#[cfg(test)]
mod tests {
    use ductile_anim::key::Interpolation;
    use ductile_core::influence::Shape;
    use glam::Vec3;

    use super::*;
    use crate::history::History;

    fn node(name: &str, kind: NodeKind) -> Node {
        Node {
            name: name.into(),
            parent: None,
            transform: Transform::IDENTITY,
            kind,
        }
    }

    /// A macro tool "nose" keyed 0 → 1 over one second, an unanimated macro tool "chin" and
    /// a sphere volume whose radius is keyed.
    fn doc() -> Document {
        let macro_node = |name: &str| {
            node(
                name,
                NodeKind::Macro(MacroUse {
                    name: "m".into(),
                    value: 0.0,
                }),
            )
        };
        let mut d = Document {
            nodes: vec![
                macro_node("nose"),
                macro_node("chin"),
                node(
                    "ball",
                    NodeKind::Volume(VolumeNode {
                        shape: Shape::Sphere { radius: 1.0 },
                    }),
                ),
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
                    Vec3::ZERO,
                    0.1,
                    2.0,
                    0.1,
                )],
                height: None,
                range: (-1.0, 1.0),
            },
        );
        let keys = |a: f32, b: f32| {
            vec![
                Key::new(0.0, Value::Scalar(a)),
                Key::new(1.0, Value::Scalar(b)),
            ]
        };
        d.animation
            .tracks
            .entry("nose".into())
            .or_default()
            .insert("value".into(), keys(0.0, 1.0));
        d
    }

    fn push(base: &mut Document, h: &mut History, op: Operation, t: f32) {
        let posed = base.at(t).unwrap();
        let op = op.onto_base(base, &posed, t).unwrap();
        h.push(base, op, "", 0, None).unwrap();
    }

    #[test]
    fn a_static_document_keeps_every_operation() {
        let mut d = doc();
        d.animation.tracks.clear();
        let op = Operation::set_macro_value(&d, "nose", 0.3).unwrap();
        assert_eq!(op.clone().onto_base(&d, &d, 0.5).unwrap(), op);
    }

    #[test]
    fn editing_an_animated_channel_keys_it_at_the_time() {
        let mut d = doc();
        let mut h = History::new(d.clone());
        let posed = d.at(0.5).unwrap();
        let op = Operation::set_macro_value(&posed, "nose", 0.9).unwrap();
        push(&mut d, &mut h, op, 0.5);
        assert_eq!(d.animation.track("nose", "value").unwrap().len(), 3);
        assert_eq!(
            d.at(0.5).unwrap().channel("nose", "value").unwrap(),
            Value::Scalar(0.9)
        );
        // The base value of the animated channel is untouched.
        assert_eq!(d.channel("nose", "value").unwrap(), Value::Scalar(0.0));
        // The new key keeps the default interpolation; a second edit replaces it.
        let posed = d.at(0.5).unwrap();
        let op = Operation::set_macro_value(&posed, "nose", 0.7).unwrap();
        push(&mut d, &mut h, op, 0.5);
        let keys = d.animation.track("nose", "value").unwrap();
        assert_eq!(keys.len(), 3);
        assert_eq!(keys[1].value, Value::Scalar(0.7));
        assert_eq!(keys[1].interpolation, Interpolation::default());
        // Undo twice restores the document exactly.
        h.undo(&mut d).unwrap();
        h.undo(&mut d).unwrap();
        assert_eq!(d, doc());
    }

    #[test]
    fn an_unanimated_channel_edits_the_base() {
        let mut d = doc();
        let mut h = History::new(d.clone());
        let posed = d.at(0.5).unwrap();
        let op = Operation::set_macro_value(&posed, "chin", 0.4).unwrap();
        let rebased = op.clone().onto_base(&d, &posed, 0.5).unwrap();
        assert_eq!(rebased, op, "no track on 'chin': the same edit");
        push(&mut d, &mut h, op, 0.5);
        assert_eq!(d.channel("chin", "value").unwrap(), Value::Scalar(0.4));
    }

    #[test]
    fn a_whole_node_edit_keys_only_what_changed() {
        let mut d = doc();
        // Animate the sphere's radius and edit its transform (not animated) in the pose.
        let radius = d.channels("ball").unwrap().last().unwrap().0.clone();
        d.animation.tracks.entry("ball".into()).or_default().insert(
            radius.clone(),
            vec![
                Key::new(0.0, Value::Scalar(1.0)),
                Key::new(1.0, Value::Scalar(3.0)),
            ],
        );
        let posed = d.at(0.5).unwrap();
        let mut t = Transform::IDENTITY;
        t.translation = Vec3::X;
        let op = Operation::set_transform(&posed, "ball", t).unwrap();
        let rebased = op.onto_base(&d, &posed, 0.5).unwrap();
        let mut after = d.clone();
        rebased.apply(&mut after).unwrap();
        assert_eq!(after.node("ball").unwrap().transform, t);
        assert_eq!(
            after.animation, d.animation,
            "no key: the radius did not change"
        );
        assert_eq!(
            after.node("ball").unwrap().kind,
            d.node("ball").unwrap().kind,
            "the base radius is not overwritten by the pose's"
        );
        // Now change the radius in the pose: a key, and the base shape stays.
        let shape = Shape::Sphere { radius: 5.0 };
        let op = Operation::set_volume(&posed, "ball", shape).unwrap();
        let rebased = op.onto_base(&d, &posed, 0.5).unwrap();
        let mut after = d.clone();
        rebased.apply(&mut after).unwrap();
        assert_eq!(after.animation.track("ball", &radius).unwrap().len(), 3);
        assert_eq!(
            after.node("ball").unwrap().kind,
            d.node("ball").unwrap().kind
        );
        assert_eq!(
            after.at(0.5).unwrap().channel("ball", &radius).unwrap(),
            Value::Scalar(5.0)
        );
    }

    #[test]
    fn removing_a_posed_node_records_the_base_node() {
        let mut d = doc();
        d.animation.tracks.clear();
        d.animation
            .tracks
            .entry("chin".into())
            .or_default()
            .insert("value".into(), vec![Key::new(0.0, Value::Scalar(0.5))]);
        let posed = d.at(0.0).unwrap();
        let op = Operation::remove_node_and_references(&posed, "chin").unwrap();
        let Operation::Group { ops, .. } = op.clone().onto_base(&d, &posed, 0.0).unwrap() else {
            panic!("a group");
        };
        assert_eq!(
            ops.last(),
            Some(&Operation::RemoveNode {
                index: 1,
                node: d.nodes[1].clone()
            })
        );
        assert_ne!(
            posed.nodes[1], d.nodes[1],
            "the pose's node differs from the base's"
        );
        let mut after = d.clone();
        let mut h = History::new(d.clone());
        push(&mut after, &mut h, op, 0.0);
        assert!(after.node("chin").is_err());
        h.undo(&mut after).unwrap();
        assert_eq!(after, d, "undo restores the base node and its track");
    }

    #[test]
    fn an_edit_that_does_not_fit_the_pose_is_refused() {
        let d = doc();
        let posed = d.at(0.5).unwrap();
        // Built against the base (value 0), not the pose (value 0.5).
        let op = Operation::set_macro_value(&d, "nose", 0.9).unwrap();
        assert!(op.onto_base(&d, &posed, 0.5).is_err());
    }
}
