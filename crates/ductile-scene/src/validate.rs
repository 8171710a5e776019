//! Whole-document validation: every problem, not just the first.

use std::collections::HashSet;

use ductile_core::error::CoreError;

use crate::document::{Area, Document, NodeKind};
use crate::error::SceneError;

impl Document {
    /// Every problem of the document that can be found without loading meshes: names,
    /// parents and cycles, finite transforms, layer references (tools, volumes, areas),
    /// macro references, every tool, volume, influence and macro parameter, the timeline,
    /// every keyframe track and every variant.
    #[must_use]
    pub fn problems(&self) -> Vec<SceneError> {
        let mut out = Vec::new();
        let mut seen = HashSet::new();
        for (i, n) in self.nodes.iter().enumerate() {
            if n.name.is_empty() {
                out.push(SceneError::EmptyName { index: i });
            } else if let Some(problem) = name_problem(&n.name) {
                out.push(SceneError::BadName {
                    index: i,
                    name: n.name.clone(),
                    problem,
                });
            } else if !seen.insert(n.name.as_str()) {
                out.push(SceneError::DuplicateName {
                    name: n.name.clone(),
                });
            }
        }
        // Parents by index and the nodes on a parent cycle, in linear time (a chain of
        // 10,000 groups took minutes with a name lookup per step of every ancestor walk).
        let index = self.name_index();
        let parents: Vec<Option<usize>> = self
            .nodes
            .iter()
            .map(|n| n.parent.as_deref().and_then(|p| index.get(p).copied()))
            .collect();
        let on_cycle = on_parent_cycle(&parents);
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(p) = &n.parent {
                if parents[i].is_none() {
                    out.push(SceneError::UnknownParent {
                        node: n.name.clone(),
                        parent: p.clone(),
                    });
                } else if on_cycle[i] {
                    out.push(SceneError::Cycle {
                        node: n.name.clone(),
                    });
                }
            }
            if !n.transform.is_finite() {
                out.push(SceneError::NotFinite {
                    what: format!("node '{}': transform", n.name),
                    value: format!("{:?}", n.transform),
                });
            } else if let Some(problem) = n.transform.degeneracy() {
                out.push(SceneError::DegenerateTransform {
                    what: format!("node '{}'", n.name),
                    problem,
                });
            }
            match &n.kind {
                NodeKind::Tool(t) => push_core(&mut out, t.validate(&format!("tool '{}'", n.name))),
                NodeKind::Macro(m) => {
                    if !self.macros.contains_key(&m.name) {
                        out.push(SceneError::UnknownMacro {
                            node: n.name.clone(),
                            name: m.name.clone(),
                        });
                    }
                    if !m.value.is_finite() {
                        out.push(SceneError::NotFinite {
                            what: format!("macro tool '{}': value", n.name),
                            value: m.value.to_string(),
                        });
                    }
                }
                NodeKind::Volume(v) => {
                    push_core(&mut out, v.shape.validate(&format!("volume '{}'", n.name)))
                }
                NodeKind::Mesh(mesh) => self.mesh_problems(&n.name, mesh, &mut out),
                NodeKind::Group => {}
            }
        }
        for (name, m) in &self.macros {
            let tool = ductile_core::tool::Tool::Ffsd(m.tool(1.0));
            push_core(&mut out, tool.validate(&format!("macro '{name}'")));
            if !(m.range.0.is_finite() && m.range.1.is_finite() && m.range.0 < m.range.1) {
                out.push(SceneError::NotFinite {
                    what: format!("macro '{name}': range (must be finite, min < max)"),
                    value: format!("{:?}", m.range),
                });
            }
        }
        self.animation_problems(&mut out);
        self.variant_problems(&mut out);
        out
    }

    /// Macros whose own area is missing where they are used (see
    /// [`SceneError::UnknownMacroArea`]): a warning, not a problem — the scene evaluates as
    /// it is (layers name their areas themselves), but a new layer of such a macro (the
    /// Studio's "Add layer") would be refused.
    #[must_use]
    pub fn macro_area_warnings(&self) -> Vec<SceneError> {
        self.macros
            .iter()
            .filter_map(|(name, m)| {
                let area = m.area.as_ref()?;
                let meshes = self.macro_area_missing(name, area)?;
                Some(SceneError::UnknownMacroArea {
                    name: name.clone(),
                    area: area.clone(),
                    meshes,
                })
            })
            .collect()
    }

    /// Where macro `name`'s area `area` is missing, in words: the meshes whose stacks hold a
    /// layer of one of its macro tools and lack the area, or "any mesh" when no macro tool
    /// is on a stack and no mesh has the area; `None` when it is found.
    fn macro_area_missing(&self, name: &str, area: &str) -> Option<String> {
        let users: Vec<&str> = self
            .nodes
            .iter()
            .filter(|n| matches!(&n.kind, NodeKind::Macro(m) if m.name == name))
            .map(|n| n.name.as_str())
            .collect();
        let mut using = Vec::new();
        let (mut any, mut on_stacks) = (false, false);
        for n in &self.nodes {
            if let NodeKind::Mesh(mesh) = &n.kind {
                let has = mesh.areas.contains_key(area);
                let uses = mesh.stack.iter().any(|l| users.contains(&l.tool.as_str()));
                any |= has;
                on_stacks |= uses;
                if uses && !has {
                    using.push(format!("mesh '{}'", n.name));
                }
            }
        }
        if !using.is_empty() {
            Some(using.join(", "))
        } else if !on_stacks && !any {
            Some("any mesh".to_owned())
        } else {
            None
        }
    }

    fn mesh_problems(
        &self,
        name: &str,
        mesh: &crate::document::MeshNode,
        out: &mut Vec<SceneError>,
    ) {
        for (area_name, area) in &mesh.areas {
            if let Area::Region(shapes) = area {
                for (k, s) in shapes.iter().enumerate() {
                    let what = format!("mesh '{name}', area '{area_name}', shape {k}");
                    push_core(out, s.shape.validate(&what));
                    // A NaN placement would make the area silently empty.
                    if !s.transform.is_finite() {
                        out.push(SceneError::NotFinite {
                            what: format!("{what}: transform"),
                            value: format!("{:?}", s.transform),
                        });
                    } else if let Some(problem) = s.transform.degeneracy() {
                        out.push(SceneError::DegenerateTransform { what, problem });
                    }
                }
            }
        }
        for (i, layer) in mesh.stack.iter().enumerate() {
            let what = format!("mesh '{name}', layer {i} ('{}')", layer.tool);
            match self.node(&layer.tool) {
                Err(_) => out.push(SceneError::UnknownTool {
                    mesh: name.to_owned(),
                    layer: i,
                    tool: layer.tool.clone(),
                }),
                Ok(t) if !t.kind.is_tool() => out.push(SceneError::WrongKind {
                    node: layer.tool.clone(),
                    found: t.kind.name(),
                    expected: "tool",
                }),
                Ok(_) => {}
            }
            if !(layer.weight.is_finite() && (0.0..=1.0).contains(&layer.weight)) {
                out.push(SceneError::Core(CoreError::OutOfRange {
                    what: format!("{what}: weight"),
                    value: f64::from(layer.weight),
                    expected: "must be in [0, 1]",
                }));
            }
            if let Some(inf) = &layer.influence {
                for v in &inf.volumes {
                    match self.node(v) {
                        Err(_) => out.push(SceneError::UnknownVolume {
                            mesh: name.to_owned(),
                            layer: i,
                            volume: v.clone(),
                        }),
                        Ok(n) if !matches!(n.kind, NodeKind::Volume(_)) => {
                            out.push(SceneError::WrongKind {
                                node: v.clone(),
                                found: n.kind.name(),
                                expected: "volume",
                            })
                        }
                        Ok(_) => {}
                    }
                }
                if let Some(a) = &inf.area
                    && !mesh.areas.contains_key(a)
                {
                    out.push(SceneError::UnknownArea {
                        mesh: name.to_owned(),
                        layer: i,
                        area: a.clone(),
                    });
                }
                if !(inf.inner.is_finite() && (0.0..1.0).contains(&inf.inner)) {
                    out.push(SceneError::Core(CoreError::OutOfRange {
                        what: format!("{what}: influence inner"),
                        value: f64::from(inf.inner),
                        expected: "must be in [0, 1)",
                    }));
                }
            }
        }
    }

    /// `Ok` when [`Document::problems`] finds nothing, else the first problem.
    pub fn validate(&self) -> Result<(), SceneError> {
        match self.problems().into_iter().next() {
            None => Ok(()),
            Some(e) => Err(e),
        }
    }
}

/// For each node, whether it lies on a cycle of `parents` (each node's parent index), in
/// linear time: every walk stops at a node an earlier walk finished.
fn on_parent_cycle(parents: &[Option<usize>]) -> Vec<bool> {
    const NEW: u8 = 0;
    const ON_PATH: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![NEW; parents.len()];
    let mut cyclic = vec![false; parents.len()];
    let mut path = Vec::new();
    for start in 0..parents.len() {
        let mut at = Some(start);
        while let Some(i) = at {
            match state[i] {
                NEW => {
                    state[i] = ON_PATH;
                    path.push(i);
                    at = parents[i];
                }
                ON_PATH => {
                    // The path from `i`'s first visit on is the cycle.
                    let from = path.iter().rposition(|&q| q == i).unwrap_or(0);
                    for &q in &path[from..] {
                        cyclic[q] = true;
                    }
                    at = None;
                }
                _ => at = None,
            }
        }
        for q in path.drain(..) {
            state[q] = DONE;
        }
    }
    cyclic
}

/// Why a non-empty node name is refused: only white space, or a control character (a
/// name must be visible in the outliner and safe to print in a terminal).
#[must_use]
pub fn name_problem(name: &str) -> Option<&'static str> {
    if name.trim().is_empty() {
        Some("is only white space")
    } else if name.chars().any(char::is_control) {
        Some("contains a control character")
    } else {
        None
    }
}

fn push_core(out: &mut Vec<SceneError>, r: Result<(), CoreError>) {
    if let Err(e) = r {
        out.push(SceneError::Core(e));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::document::{Node, NodeKind};
    use crate::transform::Transform;
    use glam::{Quat, Vec3};

    fn group(name: &str, transform: Transform) -> Node {
        Node {
            name: name.to_owned(),
            parent: None,
            transform,
            kind: NodeKind::Group,
        }
    }

    fn problems_of(nodes: Vec<Node>) -> Vec<String> {
        let doc = Document {
            nodes,
            ..Document::default()
        };
        doc.problems().iter().map(ToString::to_string).collect()
    }

    #[test]
    fn cycles_are_found_in_linear_time() {
        // 0 → 1 → 2 → 0 is a cycle; 3 hangs below it; 4 → 5 is a plain chain; 6 is its own
        // parent.
        let parents = [Some(1), Some(2), Some(0), Some(0), Some(5), None, Some(6)];
        assert_eq!(
            on_parent_cycle(&parents),
            vec![true, true, true, false, false, false, true]
        );
    }

    #[test]
    fn a_deep_chain_of_groups_is_checked_quickly() {
        // Issue 14: 10,000 nested groups took minutes (name lookups in every ancestor walk).
        let n = 10_000;
        let nodes = (0..n)
            .map(|i| Node {
                name: format!("g{i}"),
                parent: (i > 0).then(|| format!("g{}", i - 1)),
                transform: Transform::IDENTITY,
                kind: NodeKind::Group,
            })
            .collect();
        let doc = Document {
            nodes,
            ..Document::default()
        };
        // Before, this took minutes; now it takes milliseconds (not timed here: speed is for
        // benchmarks, but a regression would stall the test suite visibly).
        assert!(doc.problems().is_empty());
        assert!(doc.world_transform("g9999").is_ok());
    }

    #[test]
    fn degenerate_transforms_are_problems_as_in_the_history() {
        let zero_rotation = Transform {
            rotation: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            ..Transform::IDENTITY
        };
        let zero_scale = Transform {
            scale: Vec3::new(1.0, 0.0, 1.0),
            ..Transform::IDENTITY
        };
        let p = problems_of(vec![group("a", zero_rotation), group("b", zero_scale)]);
        assert_eq!(
            p,
            vec![
                "node 'a': the transform cannot be inverted: the rotation quaternion is zero",
                "node 'b': the transform cannot be inverted: a scale component is zero",
            ]
        );
    }

    #[test]
    fn blank_and_control_character_names_are_problems() {
        let p = problems_of(vec![
            group("  ", Transform::IDENTITY),
            group("a\u{1b}[31m", Transform::IDENTITY),
            group("fine name", Transform::IDENTITY),
        ]);
        assert_eq!(p.len(), 2, "{p:?}");
        assert!(p[0].contains("is only white space"), "{p:?}");
        assert!(
            p[1].contains(r"\u{1b}") && p[1].contains("control character"),
            "{p:?}"
        );
    }
}
