//! Left/right pairs for symmetric editing (the identikit's `left-brow-height` and
//! `right-brow-height`): two nodes form a pair when one name becomes the other by swapping
//! a `left`/`right` word (separated by `-`, `_`, `.` or a space, any case: `left-ear`,
//! `ear_Left`, `Right.brow`) or a Blender-style side suffix (`.L`/`.R`, `_L`/`_R`).

use crate::document::{Document, NodeKind};

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
}
