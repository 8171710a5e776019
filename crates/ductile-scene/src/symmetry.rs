//! Left/right pairs for symmetric editing (the identikit's `left-brow-height` and
//! `right-brow-height`): two nodes form a pair when one name becomes the other by swapping
//! a `left`/`right` word (separated by `-`, `_`, `.` or a space, any case: `left-ear`,
//! `ear_Left`, `Right.brow`) or a Blender-style side suffix (`.L`/`.R`, `_L`/`_R`).

use crate::document::{Document, MacroUse, NodeKind};
use crate::error::{Result, SceneError};

/// The name of the other side of `name`, or `None` when the name names no side.
#[must_use]
pub fn mirror_name(name: &str) -> Option<String> {
    for (a, b) in [(".L", ".R"), ("_L", "_R"), (".l", ".r"), ("_l", "_r")] {
        if let Some(stem) = name.strip_suffix(a) {
            return Some(format!("{stem}{b}"));
        }
        if let Some(stem) = name.strip_suffix(b) {
            return Some(format!("{stem}{a}"));
        }
    }
    let mut out = String::with_capacity(name.len() + 1);
    let mut swapped = false;
    // Byte position in `name` of the current word.
    let mut at = 0;
    for (i, word) in name.split(['-', '_', '.', ' ']).enumerate() {
        if i > 0 {
            // The separator that ended the previous word (one ASCII byte).
            out.push(char::from(name.as_bytes()[at - 1]));
        }
        at += word.len() + 1;
        let other = match word.to_ascii_lowercase().as_str() {
            "left" => Some("right"),
            "right" => Some("left"),
            _ => None,
        };
        match other {
            Some(o) if !swapped => {
                swapped = true;
                out.push_str(&match_case(word, o));
            }
            _ => out.push_str(word),
        }
    }
    swapped.then_some(out)
}

/// `word` (a side, in any case) spelled in `like`'s case pattern: `Left` → `Right`,
/// `LEFT` → `RIGHT`, `left` → `right`.
fn match_case(like: &str, word: &str) -> String {
    if like.chars().all(|c| c.is_ascii_uppercase()) {
        word.to_ascii_uppercase()
    } else if like.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
        let mut w = word.to_owned();
        w[..1].make_ascii_uppercase();
        w
    } else {
        word.to_owned()
    }
}

impl Document {
    /// The node on the other side of `name`: a node of the same kind whose name is
    /// [`mirror_name`] of `name` (for macro tools, any macro tool).
    #[must_use]
    pub fn mirror_of(&self, name: &str) -> Option<&str> {
        let node = self.node(name).ok()?;
        let other = self.node(&mirror_name(name)?).ok()?;
        (std::mem::discriminant(&node.kind) == std::mem::discriminant(&other.kind))
            .then_some(other.name.as_str())
    }
}

/// Every left/right pair of macro tool nodes of `doc`, each once, left name first (the one
/// that comes first in the document).
#[must_use]
pub fn mirror_pairs(doc: &Document) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (i, n) in doc.nodes.iter().enumerate() {
        if !matches!(n.kind, NodeKind::Macro(_)) {
            continue;
        }
        if let Some(other) = doc.mirror_of(&n.name)
            && doc.index_of(other).is_some_and(|j| j > i)
        {
            out.push((n.name.clone(), other.to_owned()));
        }
    }
    out
}

impl Document {
    /// A seeded random face (FaceGen's "random within limits"): every macro tool gets a
    /// value drawn uniformly within `limit ∈ [0, 1]` of its slider range on each side of 0
    /// (`u · limit · max` for `u ≥ 0`, `−u · limit · min` otherwise); with `symmetric`, the
    /// second of a left/right pair takes the first one's value. Macro tools whose macro is
    /// missing keep their value. Returns the new value of every macro tool, in document order.
    ///
    /// # Errors
    /// `limit` outside `[0, 1]`.
    pub fn random_macro_values(
        &self,
        seed: u64,
        limit: f32,
        symmetric: bool,
    ) -> Result<Vec<(String, f32)>> {
        if !(0.0..=1.0).contains(&limit) {
            return Err(SceneError::NotFinite {
                what: "random face limit (must lie in [0, 1])".to_owned(),
                value: limit.to_string(),
            });
        }
        let macros: Vec<(&str, &MacroUse)> = self
            .nodes
            .iter()
            .filter_map(|n| match &n.kind {
                NodeKind::Macro(m) => Some((n.name.as_str(), m)),
                _ => None,
            })
            .collect();
        let u = ductile_anim::random::random_unit_values(macros.len(), seed);
        let mut out: Vec<(String, f32)> = Vec::with_capacity(macros.len());
        for ((name, m), u) in macros.iter().zip(u) {
            let value = match self.macros.get(&m.name) {
                Some(def) if u >= 0.0 => u * limit * def.range.1.max(0.0),
                Some(def) => -u * limit * def.range.0.min(0.0),
                None => m.value,
            };
            out.push(((*name).to_owned(), value));
        }
        if symmetric {
            let mut seen = std::collections::BTreeMap::new();
            for (name, value) in &mut out {
                match self.mirror_of(name).and_then(|m| seen.get(m)) {
                    Some(v) => *value = *v,
                    None => {
                        seen.insert(name.clone(), *value);
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_swap_in_names() {
        assert_eq!(
            mirror_name("left-brow-height").as_deref(),
            Some("right-brow-height")
        );
        assert_eq!(
            mirror_name("right-ear-protrusion").as_deref(),
            Some("left-ear-protrusion")
        );
        assert_eq!(mirror_name("ear_Left").as_deref(), Some("ear_Right"));
        assert_eq!(mirror_name("BROW.RIGHT").as_deref(), Some("BROW.LEFT"));
        assert_eq!(mirror_name("hand.L").as_deref(), Some("hand.R"));
        assert_eq!(mirror_name("eye_R").as_deref(), Some("eye_L"));
        assert_eq!(mirror_name("nose-length"), None);
        // Only whole words count.
        assert_eq!(mirror_name("leftover"), None);
    }

    #[test]
    fn a_random_face_is_seeded_within_its_limits_and_symmetric_on_request() {
        use crate::document::Node;
        use crate::transform::Transform;
        let node = |name: &str| Node {
            name: name.into(),
            parent: None,
            transform: Transform::IDENTITY,
            kind: NodeKind::Macro(MacroUse {
                name: "m".into(),
                value: 0.0,
            }),
        };
        let mut d = Document {
            nodes: ["left-ear", "right-ear", "nose", "chin", "jaw", "brow"]
                .into_iter()
                .map(node)
                .collect(),
            ..Document::default()
        };
        d.macros.insert(
            "m".into(),
            ductile_core::ffsd::FfsdMacro {
                label: "m".into(),
                group: String::new(),
                area: None,
                points: Vec::new(),
                height: None,
                range: (-2.0, 1.0),
            },
        );
        let a = d.random_macro_values(5, 0.5, false).unwrap();
        assert_eq!(a, d.random_macro_values(5, 0.5, false).unwrap(), "seeded");
        assert_ne!(a, d.random_macro_values(6, 0.5, false).unwrap());
        assert!(a.iter().all(|(_, v)| (-1.0..=0.5).contains(v)), "{a:?}");
        assert_ne!(a[0].1, a[1].1);
        let s = d.random_macro_values(5, 0.5, true).unwrap();
        assert_eq!(s[0].1, s[1].1, "the right ear takes the left one's value");
        assert_eq!(s[2..], a[2..], "unpaired sliders are as drawn");
        assert!(d.random_macro_values(5, 1.5, false).is_err());
    }
}
