//! Variants: named snapshots of the tools' states (for the identikit, every macro value and
//! every free tool), blended two at a time with `t`, N at a time with weights, or at random.
//!
//! A blend combines every animatable parameter (see [`crate::channels`]) with the rule of
//! [`ductile_anim::blend`]: numbers as convex (or, outside `[0, 1]`, extrapolated)
//! combinations, rotations by slerp, curve tools skeleton-style. Tools whose structure
//! differs between the variants (another kind, another number of points, another mode) are
//! refused with a message naming the node.

use std::collections::BTreeMap;

use ductile_anim::blend::combine;
use ductile_anim::channel::{set_tool_channel, tool_channels};
use ductile_anim::check_weights;
use ductile_anim::random::random_weights;
use ductile_anim::value::Value;
use ductile_core::tool::Tool;
use serde::{Deserialize, Serialize};

use crate::document::{Document, NodeKind};
use crate::error::{Result, SceneError};
use crate::symmetry::mirror_pairs;
use crate::transform::Transform;

/// A named snapshot of tool states (the name is the key in [`Document::variants`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// The state of every tool and macro tool node, by node name.
    pub states: BTreeMap<String, NodeState>,
    /// How the variant was made, when it was generated rather than saved from the scene
    /// (a random variant keeps its seed and the weights it drew; replaying never draws
    /// again).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<Origin>,
}

/// The state of one node in a variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeState {
    /// The node's local transform (identity when left out).
    #[serde(default, skip_serializing_if = "is_identity")]
    pub transform: Transform,
    /// The tool state.
    pub state: State,
}

fn is_identity(t: &Transform) -> bool {
    *t == Transform::IDENTITY
}

/// What a variant keeps of a tool node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum State {
    /// A macro tool's value γ.
    Macro(f32),
    /// A free tool, complete.
    Tool(Tool),
}

/// How a generated variant was made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Origin {
    /// A blend of variants with these weights.
    Blend {
        /// `(variant, weight)` pairs.
        weights: Vec<(String, f32)>,
    },
    /// A seeded random blend (see [`RandomOptions`]).
    Random {
        /// The seed.
        seed: u64,
        /// The variants drawn from.
        sources: Vec<String>,
        /// The weights drawn (one per source).
        weights: Vec<f32>,
        /// The spread used.
        spread: f32,
        /// The asymmetry limit used, if any.
        #[serde(default)]
        asymmetry: Option<f32>,
    },
}

/// Options of a seeded random variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RandomOptions {
    /// The seed: the same seed and sources give the same face on every machine.
    pub seed: u64,
    /// Distance from the mean of the sources, in `[0, 1]`: 0 gives the mean face, 1 any
    /// convex combination (see [`ductile_anim::random::random_weights`]).
    pub spread: f32,
    /// Largest difference allowed between the values of a left/right pair of macro tools
    /// (see [`crate::symmetry`]); `None` leaves pairs as drawn.
    pub asymmetry: Option<f32>,
}

impl Default for RandomOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            spread: 1.0,
            asymmetry: None,
        }
    }
}

impl Document {
    /// The current state of every tool and macro tool node, as a variant.
    #[must_use]
    pub fn snapshot(&self) -> Variant {
        let states = self
            .nodes
            .iter()
            .filter_map(|n| {
                let state = match &n.kind {
                    NodeKind::Macro(m) => State::Macro(m.value),
                    NodeKind::Tool(t) => State::Tool(t.clone()),
                    _ => return None,
                };
                Some((
                    n.name.clone(),
                    NodeState {
                        transform: n.transform,
                        state,
                    },
                ))
            })
            .collect();
        Variant {
            states,
            origin: None,
        }
    }

    /// The variant called `name`.
    pub fn variant(&self, name: &str) -> Result<&Variant> {
        self.variants
            .get(name)
            .ok_or_else(|| SceneError::UnknownVariant {
                name: name.to_owned(),
                known: self.variants.keys().cloned().collect(),
            })
    }

    /// The document with the states of `states` written into their nodes (transforms,
    /// macro values, tools). Errors name a node that does not exist or is of another kind.
    pub fn with_states(&self, states: &BTreeMap<String, NodeState>) -> Result<Document> {
        let mut doc = self.clone();
        doc.set_states(states)?;
        Ok(doc)
    }

    /// Writes `states` into their nodes in place (what [`Document::with_states`] does
    /// without copying the document: an A/B slider writes each blend into one working
    /// copy). Checks every state first: on error the document is unchanged.
    pub fn set_states(&mut self, states: &BTreeMap<String, NodeState>) -> Result<()> {
        let mut at = Vec::with_capacity(states.len());
        for (name, s) in states {
            let i = self
                .index_of(name)
                .ok_or_else(|| SceneError::NoSuchNode { name: name.clone() })?;
            let fits = matches!(
                (&self.nodes[i].kind, &s.state),
                (NodeKind::Macro(_), State::Macro(_)) | (NodeKind::Tool(_), State::Tool(_))
            );
            if !fits {
                return Err(SceneError::WrongKind {
                    node: name.clone(),
                    found: self.nodes[i].kind.name(),
                    expected: match s.state {
                        State::Macro(_) => "macro tool",
                        State::Tool(_) => "tool",
                    },
                });
            }
            at.push(i);
        }
        for (i, s) in at.into_iter().zip(states.values()) {
            let node = &mut self.nodes[i];
            node.transform = s.transform;
            match (&mut node.kind, &s.state) {
                (NodeKind::Macro(m), State::Macro(v)) => m.value = *v,
                (NodeKind::Tool(t), State::Tool(v)) => t.clone_from(v),
                _ => {}
            }
        }
        Ok(())
    }

    /// The blend `Σ wᵢ Vᵢ` of the named variants (`(name, weight)` pairs; the weights must
    /// sum to 1, and may lie outside `[0, 1]` to extrapolate, as for a caricature). Every
    /// variant must hold the same nodes (else the error names the node and the variant
    /// missing it).
    pub fn blend_variants(&self, weights: &[(&str, f32)]) -> Result<Variant> {
        let w: Vec<f32> = weights.iter().map(|(_, w)| *w).collect();
        check_weights(&w)?;
        let variants: Vec<&Variant> = weights
            .iter()
            .map(|(name, _)| self.variant(name))
            .collect::<Result<_>>()?;
        let label = weights
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join("+");
        let first = variants[0];
        for (v, (name, _)) in variants.iter().zip(weights) {
            for node in first.states.keys() {
                if !v.states.contains_key(node) {
                    return Err(SceneError::Variant {
                        variant: (*name).to_owned(),
                        problem: format!(
                            "has no state for node '{node}', which variant '{}' has",
                            weights[0].0
                        ),
                    });
                }
            }
            if let Some(extra) = v.states.keys().find(|k| !first.states.contains_key(*k)) {
                return Err(SceneError::Variant {
                    variant: weights[0].0.to_owned(),
                    problem: format!("has no state for node '{extra}', which variant '{name}' has"),
                });
            }
        }
        let mut states = BTreeMap::new();
        for node in first.states.keys() {
            let sources: Vec<&NodeState> = variants.iter().map(|v| &v.states[node]).collect();
            let state = blend_states(&sources, &w).map_err(|problem| SceneError::Variant {
                variant: label.clone(),
                problem: format!("node '{node}': {problem}"),
            })?;
            states.insert(node.clone(), state);
        }
        Ok(Variant {
            states,
            origin: Some(Origin::Blend {
                weights: weights.iter().map(|(n, w)| ((*n).to_owned(), *w)).collect(),
            }),
        })
    }

    /// The two-variant blend `(1 − t) A + t B`; `t` outside `[0, 1]` extrapolates. At
    /// `t = 0` and `t = 1` the states are `A`'s and `B`'s, bit for bit.
    pub fn blend_two(&self, a: &str, b: &str, t: f32) -> Result<Variant> {
        if !t.is_finite() {
            return Err(SceneError::NotFinite {
                what: "blend t".to_owned(),
                value: t.to_string(),
            });
        }
        self.blend_variants(&[(a, 1.0 - t), (b, t)])
    }

    /// A seeded random variant: a random convex combination of `sources` (weights uniform on
    /// the simplex, pulled towards the mean by `options.spread`), then every left/right pair
    /// of macro tools brought within `options.asymmetry` of each other (both move towards
    /// their mean). The result records the seed and the weights drawn.
    pub fn random_variant(&self, sources: &[&str], options: &RandomOptions) -> Result<Variant> {
        let weights = random_weights(sources.len(), options.seed, options.spread)?;
        let pairs: Vec<(&str, f32)> = sources
            .iter()
            .copied()
            .zip(weights.iter().copied())
            .collect();
        let mut v = self.blend_variants(&pairs)?;
        if let Some(limit) = options.asymmetry {
            if !(limit.is_finite() && limit >= 0.0) {
                return Err(SceneError::NotFinite {
                    what: "asymmetry limit (must be a finite number ≥ 0)".to_owned(),
                    value: limit.to_string(),
                });
            }
            for (left, right) in mirror_pairs(self) {
                let value = |v: &Variant, n: &str| match v.states.get(n).map(|s| &s.state) {
                    Some(State::Macro(x)) => Some(*x),
                    _ => None,
                };
                let (Some(l), Some(r)) = (value(&v, &left), value(&v, &right)) else {
                    continue;
                };
                if (l - r).abs() > limit {
                    let mean = 0.5 * (l + r);
                    let half = 0.5 * limit * (l - r).signum();
                    for (n, x) in [(&left, mean + half), (&right, mean - half)] {
                        if let Some(s) = v.states.get_mut(n) {
                            s.state = State::Macro(x);
                        }
                    }
                }
            }
        }
        v.origin = Some(Origin::Random {
            seed: options.seed,
            sources: sources.iter().map(|s| (*s).to_owned()).collect(),
            weights,
            spread: options.spread,
            asymmetry: options.asymmetry,
        });
        Ok(v)
    }

    /// The problems of every variant (see [`Document::variant_problems_of`]).
    pub(crate) fn variant_problems(&self, out: &mut Vec<SceneError>) {
        for (name, v) in &self.variants {
            out.extend(self.variant_problems_of(name, v));
        }
    }

    /// The problems of variant `v` called `name` against this document: an empty name or
    /// one with control characters, states of nodes that do not exist or are of another
    /// kind, invalid tools, non-finite values.
    #[must_use]
    pub fn variant_problems_of(&self, name: &str, v: &Variant) -> Vec<SceneError> {
        let mut out = Vec::new();
        let problem = |p: String| SceneError::Variant {
            variant: name.to_owned(),
            problem: p,
        };
        if name.trim().is_empty() || name.chars().any(char::is_control) {
            out.push(problem(
                "a variant name must not be empty or contain control characters".to_owned(),
            ));
        }
        for (node, s) in &v.states {
            let Ok(n) = self.node(node) else {
                out.push(problem(format!("node '{node}' does not exist")));
                continue;
            };
            if !s.transform.is_finite() {
                out.push(problem(format!(
                    "node '{node}': the transform is not finite"
                )));
            }
            match (&n.kind, &s.state) {
                (NodeKind::Macro(_), State::Macro(x)) => {
                    if !x.is_finite() {
                        out.push(problem(format!("node '{node}': value {x} is not finite")));
                    }
                }
                (NodeKind::Tool(current), State::Tool(t)) => {
                    if std::mem::discriminant(current) != std::mem::discriminant(t) {
                        out.push(problem(format!(
                            "node '{node}' is a {} but the variant holds a {}",
                            current.kind_name(),
                            t.kind_name()
                        )));
                    } else if let Err(e) = t.validate(&format!("node '{node}'")) {
                        out.push(problem(e.to_string()));
                    }
                }
                (kind, State::Macro(_)) => out.push(problem(format!(
                    "node '{node}' is a {}, not a macro tool",
                    kind.name()
                ))),
                (kind, State::Tool(_)) => out.push(problem(format!(
                    "node '{node}' is a {}, not a tool",
                    kind.name()
                ))),
            }
        }
        out
    }
}

/// The blend of one node's states (see [`Document::blend_variants`]); the error says why
/// they cannot be blended.
pub fn blend_states(sources: &[&NodeState], weights: &[f32]) -> Result<NodeState, String> {
    if let Some(k) = weights.iter().position(|&w| w == 1.0)
        && weights.iter().enumerate().all(|(i, &w)| i == k || w == 0.0)
        && same_kinds(sources)
    {
        return Ok(sources[k].clone());
    }
    // Equal sources blend to themselves, bit for bit, whatever the weights (a weighted sum
    // of equal values rounds differently when the weights are not 0 and 1), provided the
    // weights are an affine combination.
    if sources.windows(2).all(|w| w[0] == w[1]) && (weights.iter().sum::<f32>() - 1.0).abs() < 1e-6
    {
        return Ok(sources[0].clone());
    }
    let transform = blend_transforms(sources, weights)?;
    let state = match sources[0].state {
        State::Macro(_) => {
            let values: Vec<f32> = sources
                .iter()
                .map(|s| match s.state {
                    State::Macro(x) => Ok(x),
                    State::Tool(_) => Err(kinds_differ()),
                })
                .collect::<Result<_, String>>()?;
            State::Macro(values.iter().zip(weights).map(|(x, w)| x * w).sum())
        }
        State::Tool(_) => {
            let tools: Vec<&Tool> = sources
                .iter()
                .map(|s| match &s.state {
                    State::Tool(t) => Ok(t),
                    State::Macro(_) => Err(kinds_differ()),
                })
                .collect::<Result<_, String>>()?;
            State::Tool(blend_tools(&tools, weights)?)
        }
    };
    Ok(NodeState { transform, state })
}

fn same_kinds(sources: &[&NodeState]) -> bool {
    sources.iter().all(|s| {
        std::mem::discriminant(&s.state) == std::mem::discriminant(&sources[0].state)
            && match (&s.state, &sources[0].state) {
                (State::Tool(a), State::Tool(b)) => {
                    std::mem::discriminant(a) == std::mem::discriminant(b)
                }
                _ => true,
            }
    })
}

fn kinds_differ() -> String {
    "the variants hold a macro value in one and a tool in another".to_owned()
}

fn blend_value(values: &[Value], weights: &[f32], what: &str) -> Result<Value, String> {
    let refs: Vec<&Value> = values.iter().collect();
    combine(&refs, weights).ok_or_else(|| {
        let shapes: Vec<String> = values.iter().map(Value::shape).collect();
        format!("'{what}' cannot be blended ({})", shapes.join(" / "))
    })
}

fn blend_transforms(sources: &[&NodeState], weights: &[f32]) -> Result<Transform, String> {
    let pick = |f: fn(&Transform) -> Value| -> Vec<Value> {
        sources.iter().map(|s| f(&s.transform)).collect()
    };
    let translation = blend_value(
        &pick(|t| Value::Vector(t.translation)),
        weights,
        "translation",
    )?;
    let rotation = blend_value(&pick(|t| Value::Rotation(t.rotation)), weights, "rotation")?;
    let scale = blend_value(&pick(|t| Value::Vector(t.scale)), weights, "scale")?;
    match (translation, rotation, scale) {
        (Value::Vector(translation), Value::Rotation(rotation), Value::Vector(scale)) => {
            Ok(Transform {
                translation,
                rotation,
                scale,
            })
        }
        _ => Err("the transforms cannot be blended".to_owned()),
    }
}

/// Blends tools of the same structure channel by channel. The structure is the same when
/// every tool has the same channels and, with its channels copied into the first tool, equals
/// it (so counts, modes, bases, degrees and everything else that is not a channel agree).
fn blend_tools(tools: &[&Tool], weights: &[f32]) -> Result<Tool, String> {
    let base = tools[0];
    let channels: Vec<Vec<(String, Value)>> = tools.iter().map(|t| tool_channels(t)).collect();
    for (t, c) in tools.iter().zip(&channels).skip(1) {
        let differs = || {
            format!(
                "the tool's structure differs between the variants ({} / {}): only its parameters can be blended",
                describe(base),
                describe(t)
            )
        };
        if c.len() != channels[0].len() || c.iter().zip(&channels[0]).any(|(a, b)| a.0 != b.0) {
            return Err(differs());
        }
        let mut copy = base.clone();
        for (path, value) in c {
            set_tool_channel(&mut copy, path, value).map_err(|_| differs())?;
        }
        if copy != **t {
            return Err(differs());
        }
    }
    let mut out = base.clone();
    for (j, (path, _)) in channels[0].iter().enumerate() {
        let values: Vec<Value> = channels.iter().map(|c| c[j].1.clone()).collect();
        let v = blend_value(&values, weights, path)?;
        set_tool_channel(&mut out, path, &v).map_err(|e| e.to_string())?;
    }
    Ok(out)
}

fn describe(t: &Tool) -> String {
    let n = tool_channels(t).len();
    format!("{} with {n} parameters", t.kind_name())
}

#[cfg(test)]
mod tests {
    use ductile_core::curve::{CurveBasis, CurveTool};
    use glam::Vec3;

    use super::*;
    use crate::document::{MacroUse, Node};

    fn doc() -> Document {
        let macro_node = |name: &str, value: f32| Node {
            name: name.into(),
            parent: None,
            transform: Transform::IDENTITY,
            kind: NodeKind::Macro(MacroUse {
                name: name.into(),
                value,
            }),
        };
        let curve = |y: f32| {
            Tool::Curve(CurveTool {
                basis: CurveBasis::BSpline { degree: 2 },
                rest: vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
                deformed: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0 + (1.0 - y), y, 0.0)],
            })
        };
        let mut d = Document {
            nodes: vec![
                macro_node("left-ear", 0.0),
                macro_node("right-ear", 0.0),
                Node {
                    name: "arm".into(),
                    parent: None,
                    transform: Transform::IDENTITY,
                    kind: NodeKind::Tool(curve(0.0)),
                },
            ],
            ..Document::default()
        };
        let mut a = d.snapshot();
        d.nodes[0].kind = NodeKind::Macro(MacroUse {
            name: "left-ear".into(),
            value: 1.0,
        });
        d.nodes[2].kind = NodeKind::Tool(curve(1.0));
        let b = d.snapshot();
        a.states.get_mut("right-ear").unwrap().state = State::Macro(0.5);
        d.variants.insert("A".into(), a);
        d.variants.insert("B".into(), b);
        d
    }

    #[test]
    fn blends_hit_the_variants_exactly_at_0_and_1() {
        let d = doc();
        assert_eq!(
            d.blend_two("A", "B", 0.0).unwrap().states,
            d.variants["A"].states
        );
        assert_eq!(
            d.blend_two("A", "B", 1.0).unwrap().states,
            d.variants["B"].states
        );
    }

    #[test]
    fn nodes_equal_in_both_variants_keep_their_state_bit_for_bit() {
        let mut d = doc();
        // The arm's curve is the same in A and B; an A/B slider must not touch it (its
        // edits would otherwise differ from frame to frame and split a drag into steps).
        let arm = d.variants["A"].states["arm"].clone();
        d.variants
            .get_mut("B")
            .unwrap()
            .states
            .insert("arm".into(), arm.clone());
        for v in ["A", "B"] {
            d.variants
                .get_mut(v)
                .unwrap()
                .states
                .get_mut("right-ear")
                .unwrap()
                .state = State::Macro(0.3);
        }
        for t in [0.1_f32, 0.37, 0.7, 1.05, -0.4, 1.9] {
            let blend = d.blend_two("A", "B", t).unwrap();
            assert_eq!(blend.states["arm"], arm, "t = {t}");
            assert_eq!(
                blend.states["right-ear"].state,
                State::Macro(0.3),
                "t = {t}"
            );
        }
    }

    #[test]
    fn macro_values_blend_linearly_and_extrapolate() {
        let d = doc();
        let v = d.blend_two("A", "B", 0.25).unwrap();
        assert_eq!(v.states["left-ear"].state, State::Macro(0.25));
        let v = d.blend_two("A", "B", 2.0).unwrap();
        assert_eq!(v.states["left-ear"].state, State::Macro(2.0));
        assert_eq!(v.states["right-ear"].state, State::Macro(-0.5));
    }

    #[test]
    fn curve_tools_blend_skeleton_style() {
        let d = doc();
        let v = d.blend_two("A", "B", 0.5).unwrap();
        let State::Tool(Tool::Curve(c)) = &v.states["arm"].state else {
            panic!()
        };
        // Both segments keep length 1; a lerp of the points would give 1 + √2/2 in all.
        let len: f32 = c.deformed.windows(2).map(|w| w[0].distance(w[1])).sum();
        assert!((len - 2.0).abs() < 1e-5, "{len}");
    }

    #[test]
    fn weights_must_sum_to_one_and_names_must_exist() {
        let d = doc();
        let e = d.blend_variants(&[("A", 0.5), ("B", 0.6)]).unwrap_err();
        assert!(e.to_string().contains("sum to 1"), "{e}");
        let e = d.blend_two("A", "C", 0.5).unwrap_err().to_string();
        assert!(
            e.contains("no variant named 'C'") && e.contains("A, B"),
            "{e}"
        );
    }

    #[test]
    fn different_structures_are_refused_naming_the_node() {
        let mut d = doc();
        if let Some(State::Tool(Tool::Curve(c))) = d
            .variants
            .get_mut("B")
            .map(|v| &mut v.states.get_mut("arm").unwrap().state)
        {
            c.basis = CurveBasis::Bezier;
        }
        let e = d.blend_two("A", "B", 0.5).unwrap_err().to_string();
        assert!(
            e.contains("node 'arm'") && e.contains("structure differs"),
            "{e}"
        );
    }

    #[test]
    fn random_variants_are_seeded_and_limit_asymmetry() {
        let d = doc();
        let opts = RandomOptions {
            seed: 7,
            spread: 1.0,
            asymmetry: Some(0.1),
        };
        let a = d.random_variant(&["A", "B"], &opts).unwrap();
        assert_eq!(a, d.random_variant(&["A", "B"], &opts).unwrap());
        let value = |n: &str| match a.states[n].state {
            State::Macro(x) => x,
            State::Tool(_) => panic!(),
        };
        assert!((value("left-ear") - value("right-ear")).abs() <= 0.1 + 1e-6);
        let Some(Origin::Random { seed, weights, .. }) = &a.origin else {
            panic!()
        };
        assert_eq!(*seed, 7);
        assert_eq!(weights.len(), 2);
    }

    #[test]
    fn states_are_written_into_their_nodes() {
        let d = doc();
        let b = d.with_states(&d.variants["B"].states).unwrap();
        assert_eq!(b.channel("left-ear", "value").unwrap(), Value::Scalar(1.0));
        let mut wrong = d.variants["A"].states.clone();
        wrong.get_mut("arm").unwrap().state = State::Macro(1.0);
        assert!(d.with_states(&wrong).is_err());
    }
}
