//! Versioned RON history files: a base scene (inline, or a reference to a scene file with
//! the hash of its document) and the recorded steps (see `docs/history-format.md`).
//!
//! Reading follows the scene files' three steps: a lenient probe of `version`, a strict
//! parse with the layout of that version (unknown fields denied), then migration to the
//! current types. A referenced base is read and its hash compared with the recorded one, so
//! that a history is never replayed on a scene it was not made on.

use std::path::{Path, PathBuf};

use ductile_history::history::{Entry, History, replay};
use ductile_scene::document::{Document, NodeKind};
use serde::{Deserialize, Serialize};

use crate::error::{IoError, Result};
use crate::scene::{LoadedScene, load_node_mesh, read_scene, scene_dir};
use crate::write_atomic;

/// The history format version [`save_history`] writes. Version 2 added the time
/// operations (keys, tracks, timeline, variants) and the animation and variants of an
/// inline base; a version 1 file is read with the same layout (it cannot hold them).
pub const HISTORY_VERSION: u64 = 2;

/// The history format versions this build reads.
pub const SUPPORTED_HISTORY_VERSIONS: &[u64] = &[1, 2];

/// Where a history's base document comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Base {
    /// The document, written in full in the history file (mesh sources are relative to the
    /// history file).
    Inline(Document),
    /// A scene file, relative to the history file, and the hash of its document
    /// ([`document_hash`]).
    Reference {
        /// Path of the scene file, relative to the history file's directory.
        path: String,
        /// BLAKE3 hash of the scene's document, 64 hex digits.
        hash: String,
    },
}

/// The on-disk layout of versions 1 and 2 (2 may hold the time operations; the layout is
/// the same).
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename = "History", deny_unknown_fields)]
struct HistoryV1 {
    version: u64,
    base: Base,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cursor: Option<usize>,
    entries: Vec<Entry>,
}

/// Reads only `version` and whether there is an `entries` field; everything else is
/// skipped.
#[derive(Deserialize)]
#[serde(rename = "History")]
struct Probe {
    #[serde(default, deserialize_with = "present_u64")]
    version: Option<u64>,
    #[serde(default, deserialize_with = "present_any")]
    entries: Option<()>,
}

fn present_u64<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    u64::deserialize(d).map(Some)
}

fn present_any<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<()>, D::Error> {
    serde::de::IgnoredAny::deserialize(d).map(|_| Some(()))
}

/// True when `text` is a history file rather than a scene file: its top-level structure has
/// an `entries` field. Text that is not RON at all gives `false`.
#[must_use]
pub fn is_history_text(text: &str) -> bool {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    ron::Options::default()
        .from_str::<Probe>(text)
        .is_ok_and(|p| p.entries.is_some())
}

/// True when the file at `path` is a history file ([`is_history_text`]); `false` when it
/// cannot be read.
#[must_use]
pub fn is_history_file(path: impl AsRef<Path>) -> bool {
    crate::read_text_file(path.as_ref()).is_ok_and(|t| is_history_text(&t))
}

/// The canonical hash of a document: BLAKE3 of its compact RON text (`ron::to_string`),
/// as 64 lowercase hex digits. Comments, layout and omitted default fields of a scene file
/// do not change it; any change of content does.
pub fn document_hash(doc: &Document) -> Result<String, ron::Error> {
    let text = ron::to_string(doc)?;
    Ok(blake3::hash(text.as_bytes()).to_hex().to_string())
}

/// A history file, read and with its base resolved (not replayed).
#[derive(Debug, Clone)]
pub struct LoadedHistory {
    /// The history file.
    pub path: PathBuf,
    /// How the file gives its base.
    pub base_source: Base,
    /// The file that the base's mesh sources are relative to: the referenced scene file, or
    /// the history file itself for an inline base.
    pub mesh_root: PathBuf,
    /// The history (base document and steps; its cursor is at the end).
    pub history: History,
    /// How many steps were applied when the file was saved.
    pub cursor: usize,
}

impl LoadedHistory {
    /// The document after step `to` (0 = the base), replayed with every step checked.
    pub fn replay(&self, to: usize) -> Result<Document> {
        replay(self.history.base(), self.history.entries(), to).map_err(|source| IoError::History {
            path: self.path.clone(),
            source,
        })
    }

    /// The scene of `document` (a replayed state of this history) with the rest mesh of
    /// every mesh node loaded relative to [`LoadedHistory::mesh_root`].
    pub fn scene(&self, document: Document) -> Result<LoadedScene> {
        let mut meshes = Vec::new();
        for node in &document.nodes {
            if let NodeKind::Mesh(m) = &node.kind {
                meshes.push(load_node_mesh(&self.mesh_root, &node.name, &m.source)?);
            }
        }
        Ok(LoadedScene {
            path: self.path.clone(),
            document,
            meshes,
        })
    }
}

fn ron_error(path: &Path, e: &ron::error::SpannedError) -> IoError {
    IoError::Ron {
        path: path.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    }
}

/// Parses history text; `path` names the file and anchors a referenced base.
pub fn parse_history(text: &str, path: &Path) -> Result<LoadedHistory> {
    let text = crate::scene::file_body(
        text,
        path,
        "a history: `(version: 1, base: ..., entries: [...])`",
    )?;
    let opts = ron::Options::default();
    let probe: Probe = opts.from_str(text).map_err(|e| ron_error(path, &e))?;
    let version = probe
        .version
        .ok_or_else(|| IoError::MissingHistoryVersion {
            path: path.to_owned(),
        })?;
    let file: HistoryV1 = match version {
        1 | 2 => opts.from_str(text).map_err(|e| ron_error(path, &e))?,
        found => {
            return Err(IoError::UnsupportedHistoryVersion {
                path: path.to_owned(),
                found,
            });
        }
    };
    if version == 1 {
        for (k, entry) in file.entries.iter().enumerate() {
            if let Some(operation) = version_2_operation(&entry.op) {
                return Err(IoError::OperationTooNew {
                    path: path.to_owned(),
                    step: k + 1,
                    operation,
                });
            }
        }
    }
    let (base, mesh_root) = match &file.base {
        Base::Inline(doc) => (doc.clone(), path.to_owned()),
        Base::Reference { path: rel, hash } => {
            let scene_path = scene_dir(path).join(rel);
            let doc = read_scene(&scene_path)?;
            let found = document_hash(&doc).map_err(|e| IoError::Write {
                path: scene_path.clone(),
                source: std::io::Error::other(e),
            })?;
            if !found.eq_ignore_ascii_case(hash) {
                return Err(IoError::BaseMismatch {
                    path: path.to_owned(),
                    scene: scene_path,
                    expected: hash.clone(),
                    found,
                });
            }
            (doc, scene_path)
        }
    };
    // The base gets the checks a scene file gets (`load_scene`, `check`, `apply`): replay and
    // history must not accept a base (duplicate names, cycles, NaN, missing tools) that
    // apply would refuse.
    let problems = base.problems();
    if !problems.is_empty() {
        return Err(IoError::Scene {
            path: mesh_root.clone(),
            problems,
        });
    }
    let len = file.entries.len();
    let cursor = file.cursor.unwrap_or(len);
    if cursor > len {
        return Err(IoError::History {
            path: path.to_owned(),
            source: ductile_history::error::HistoryError::NoSuchStep { step: cursor, len },
        });
    }
    Ok(LoadedHistory {
        path: path.to_owned(),
        base_source: file.base,
        mesh_root,
        history: History::from_entries(base, file.entries),
        cursor,
    })
}

/// The name of `op`'s kind when it (or a member of its group) came with history version 2.
fn version_2_operation(op: &ductile_history::operation::Operation) -> Option<&'static str> {
    use ductile_history::operation::Operation as O;
    match op {
        O::SetKey { .. } => Some("SetKey"),
        O::MoveKey { .. } => Some("MoveKey"),
        O::SetTrack { .. } => Some("SetTrack"),
        O::SetTimeline { .. } => Some("SetTimeline"),
        O::SetVariant { .. } => Some("SetVariant"),
        O::RenameVariant { .. } => Some("RenameVariant"),
        O::Group { ops, .. } => ops.iter().find_map(version_2_operation),
        _ => None,
    }
}

/// Reads a history file and resolves its base (without replaying it).
pub fn read_history(path: impl AsRef<Path>) -> Result<LoadedHistory> {
    let path = path.as_ref();
    let text = crate::read_text_file(path).map_err(|source| IoError::Read {
        path: path.to_owned(),
        source,
    })?;
    parse_history(&text, path)
}

/// How [`save_history`] writes the base.
#[derive(Debug, Clone, Copy)]
pub enum SaveBase<'a> {
    /// Write the base document in full.
    Inline,
    /// Refer to this scene file (written as a path relative to the history file's
    /// directory when possible) and record the base document's hash. The scene file must
    /// hold the history's base document.
    Reference(&'a Path),
}

/// The history as RON text of the current version. `reference` is the path to write for a
/// referenced base.
pub fn history_to_string(
    history: &History,
    base: SaveBase<'_>,
    history_path: &Path,
) -> Result<String, ron::Error> {
    let base = match base {
        SaveBase::Inline => Base::Inline(history.base().clone()),
        SaveBase::Reference(scene) => Base::Reference {
            path: crate::project::relative_path(scene, scene_dir(history_path)),
            hash: document_hash(history.base())?,
        },
    };
    let file = HistoryV1 {
        version: HISTORY_VERSION,
        base,
        cursor: (history.cursor() != history.len()).then_some(history.cursor()),
        entries: history.entries().to_vec(),
    };
    ron::Options::default().to_string_pretty(&file, ron::ser::PrettyConfig::default())
}

/// Writes the history to `path` atomically (see [`history_to_string`]).
pub fn save_history(path: impl AsRef<Path>, history: &History, base: SaveBase<'_>) -> Result<()> {
    let path = path.as_ref();
    let text = history_to_string(history, base, path).map_err(|e| IoError::Write {
        path: path.to_owned(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod history_base_tests {
    use std::path::Path;

    use super::parse_history;

    #[test]
    fn an_inline_base_gets_the_checks_of_a_scene() {
        // Issue 14: `replay` and `history` accepted bases that `apply` refused.
        let h = Path::new("bad.history.ron");
        for (base, what) in [
            (
                "(nodes: [(name: \"a\", kind: Group), (name: \"a\", kind: Group)])",
                "node name 'a' is used more than once",
            ),
            (
                "(nodes: [(name: \"a\", parent: Some(\"b\"), kind: Group), (name: \"b\", parent: Some(\"a\"), kind: Group)])",
                "cycle",
            ),
            (
                "(nodes: [(name: \"a\", transform: (translation: (NaN, 0.0, 0.0)), kind: Group)])",
                "not a finite number",
            ),
        ] {
            let text = format!("(version: 1, base: Inline({base}), entries: [])");
            let e = parse_history(&text, h).unwrap_err().to_string();
            assert!(e.contains("bad.history.ron") && e.contains(what), "{e}");
        }
    }
}
