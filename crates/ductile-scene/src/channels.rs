//! The animatable parameters (channels) of a node: its transform
//! (`transform.translation`, `transform.rotation`, `transform.scale`), a macro tool's
//! `value`, a volume's shape parameters and a tool's parameters (paths as in
//! [`ductile_anim::channel`]).

use ductile_anim::channel::{set_shape_channel, set_tool_channel, shape_channels, tool_channels};
use ductile_anim::error::AnimError;
use ductile_anim::value::Value;

use crate::document::{Document, Node, NodeKind};
use crate::error::{Result, SceneError};
use crate::transform::Transform;

/// Path of the translation channel of every node.
pub const TRANSLATION: &str = "transform.translation";
/// Path of the rotation channel of every node.
pub const ROTATION: &str = "transform.rotation";
/// Path of the scale channel of every node.
pub const SCALE: &str = "transform.scale";
/// Path of a macro tool's value.
pub const MACRO_VALUE: &str = "value";

/// Every channel of `node` with its current value: the transform's three, then the kind's.
#[must_use]
pub fn node_channels(node: &Node) -> Vec<(String, Value)> {
    let t = &node.transform;
    let mut out = vec![
        (TRANSLATION.to_owned(), Value::Vector(t.translation)),
        (ROTATION.to_owned(), Value::Rotation(t.rotation)),
        (SCALE.to_owned(), Value::Vector(t.scale)),
    ];
    match &node.kind {
        NodeKind::Macro(m) => out.push((MACRO_VALUE.to_owned(), Value::Scalar(m.value))),
        NodeKind::Volume(v) => out.extend(shape_channels(&v.shape)),
        NodeKind::Tool(tool) => out.extend(tool_channels(tool)),
        NodeKind::Mesh(_) | NodeKind::Group => {}
    }
    out
}

fn set_transform(t: &mut Transform, path: &str, value: &Value) -> Option<Result<(), AnimError>> {
    let wrong = |expected: &'static str| AnimError::WrongValue {
        path: path.to_owned(),
        expected,
        found: value.shape(),
    };
    Some(match (path, value) {
        (TRANSLATION, Value::Vector(v)) => {
            t.translation = *v;
            Ok(())
        }
        (ROTATION, Value::Rotation(q)) => {
            t.rotation = *q;
            Ok(())
        }
        (SCALE, Value::Vector(v)) => {
            t.scale = *v;
            Ok(())
        }
        (TRANSLATION | SCALE, _) => Err(wrong("a vector")),
        (ROTATION, _) => Err(wrong("a rotation")),
        _ => return None,
    })
}

/// Writes `value` into channel `path` of `node`; the node is unchanged on error.
pub fn set_node_channel(node: &mut Node, path: &str, value: &Value) -> Result<(), AnimError> {
    if let Some(r) = set_transform(&mut node.transform, path, value) {
        return r;
    }
    let owner = node.kind.name();
    match &mut node.kind {
        NodeKind::Macro(m) if path == MACRO_VALUE => match value {
            Value::Scalar(x) => {
                m.value = *x;
                Ok(())
            }
            other => Err(AnimError::WrongValue {
                path: path.to_owned(),
                expected: "a number",
                found: other.shape(),
            }),
        },
        NodeKind::Volume(v) => set_shape_channel(&mut v.shape, path, value),
        NodeKind::Tool(tool) => set_tool_channel(tool, path, value),
        _ => Err(AnimError::NoSuchChannel {
            path: path.to_owned(),
            owner: owner.to_owned(),
        }),
    }
}

impl Document {
    /// Every channel of node `name` with its current value (see [`node_channels`]).
    pub fn channels(&self, name: &str) -> Result<Vec<(String, Value)>> {
        Ok(node_channels(self.node(name)?))
    }

    /// The current value of channel `path` of node `name`.
    pub fn channel(&self, name: &str, path: &str) -> Result<Value> {
        let node = self.node(name)?;
        node_channels(node)
            .into_iter()
            .find(|(p, _)| p == path)
            .map(|(_, v)| v)
            .ok_or_else(|| SceneError::Channel {
                node: name.to_owned(),
                source: AnimError::NoSuchChannel {
                    path: path.to_owned(),
                    owner: node.kind.name().to_owned(),
                },
            })
    }

    /// Writes `value` into channel `path` of node `name`. The value is not validated
    /// against the tool's rules (evaluation and [`Document::problems`] do that); the
    /// document is unchanged on error.
    pub fn set_channel(&mut self, name: &str, path: &str, value: &Value) -> Result<()> {
        let node = self.node_mut(name)?;
        set_node_channel(node, path, value).map_err(|source| SceneError::Channel {
            node: name.to_owned(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};

    use super::*;
    use crate::document::{MacroUse, VolumeNode};
    use ductile_core::influence::Shape;

    fn doc() -> Document {
        Document {
            nodes: vec![
                Node {
                    name: "m".into(),
                    parent: None,
                    transform: Transform::IDENTITY,
                    kind: NodeKind::Macro(MacroUse {
                        name: "nose".into(),
                        value: 0.25,
                    }),
                },
                Node {
                    name: "v".into(),
                    parent: None,
                    transform: Transform::IDENTITY,
                    kind: NodeKind::Volume(VolumeNode {
                        shape: Shape::Sphere { radius: 1.0 },
                    }),
                },
            ],
            ..Document::default()
        }
    }

    #[test]
    fn node_channels_are_the_transform_and_the_kind() {
        let d = doc();
        let paths: Vec<String> = d.channels("m").unwrap().into_iter().map(|c| c.0).collect();
        assert_eq!(paths, [TRANSLATION, ROTATION, SCALE, MACRO_VALUE]);
        assert_eq!(d.channel("v", "radius").unwrap(), Value::Scalar(1.0));
    }

    #[test]
    fn set_channel_writes_one_parameter() {
        let mut d = doc();
        d.set_channel("m", MACRO_VALUE, &Value::Scalar(0.5))
            .unwrap();
        d.set_channel("v", ROTATION, &Value::Rotation(Quat::from_rotation_z(1.0)))
            .unwrap();
        d.set_channel("v", "radius", &Value::Scalar(2.0)).unwrap();
        assert_eq!(d.channel("m", MACRO_VALUE).unwrap(), Value::Scalar(0.5));
        assert_eq!(d.channel("v", "radius").unwrap(), Value::Scalar(2.0));
        let before = d.clone();
        let e = d
            .set_channel("m", TRANSLATION, &Value::Scalar(1.0))
            .unwrap_err();
        assert!(
            e.to_string().contains("node 'm'") && e.to_string().contains("a vector"),
            "{e}"
        );
        assert!(d.set_channel("m", "gamma", &Value::Scalar(1.0)).is_err());
        assert!(
            d.set_channel("x", SCALE, &Value::Vector(Vec3::ONE))
                .is_err()
        );
        assert_eq!(d, before);
    }
}
