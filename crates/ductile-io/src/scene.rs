//! Versioned RON scene files.
//!
//! A scene file is the [`Document`] with a `version` field in front (see
//! `docs/scene-format.md`). Reading happens in three steps:
//!
//! 1. a lenient probe reads only `version` (every other field is skipped), so an unknown
//!    version is reported as such and not as a confusing field error;
//! 2. the text is parsed with the struct of *that* version, with unknown fields denied;
//! 3. [`migrate`] lifts an old version's struct to the current [`Document`] one step at a
//!    time (version 1 → 2 adds an empty timeline and no variants).
//!
//! Writing always produces the current version, pretty-printed, atomically.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ductile_core::ffsd::FfsdMacro;
use ductile_core::mesh::{Deformed, RestMesh};
use ductile_scene::document::{Document, Node, NodeKind, unique_keys};
use ductile_scene::time::Animation;
use ductile_scene::variant::Variant;
use serde::{Deserialize, Serialize};

use crate::error::{IoError, Result};
use crate::mesh::{MeshRef, load_rest_mesh};
use crate::write_atomic;

/// The version [`save_scene`] writes. Version 2 added `animation` (keyframe tracks and the
/// timeline) and `variants`; a version 1 reader would refuse those fields.
pub const CURRENT_VERSION: u64 = 2;

/// Reads only the `version` field; everything else is skipped. (Named `Scene` in parse
/// errors: "expected opening `(` for struct `Scene`".)
#[derive(Deserialize)]
#[serde(rename = "Scene")]
struct VersionProbe {
    #[serde(default, deserialize_with = "present")]
    version: Option<u64>,
}

/// `version: 1` (not `Some(1)`) marks the field as present.
fn present<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    u64::deserialize(d).map(Some)
}

/// The on-disk layout of version 1: the document's fields plus `version`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
struct SceneV1 {
    #[allow(dead_code)]
    version: u64,
    #[serde(default)]
    nodes: Vec<Node>,
    #[serde(default, deserialize_with = "unique_keys")]
    macros: BTreeMap<String, FfsdMacro>,
}

/// The on-disk layout of version 2: version 1 plus the animation and the variants.
#[derive(Debug, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
struct SceneV2 {
    #[allow(dead_code)]
    version: u64,
    #[serde(default)]
    nodes: Vec<Node>,
    #[serde(default, deserialize_with = "unique_keys")]
    macros: BTreeMap<String, FfsdMacro>,
    #[serde(default)]
    animation: Animation,
    #[serde(default, deserialize_with = "unique_keys")]
    variants: BTreeMap<String, Variant>,
}

/// What [`save_scene`] writes (borrowing the document).
#[derive(Serialize)]
struct SceneOut<'a> {
    version: u64,
    nodes: &'a [Node],
    macros: &'a BTreeMap<String, FfsdMacro>,
    #[serde(skip_serializing_if = "Animation::is_default")]
    animation: &'a Animation,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    variants: &'a BTreeMap<String, Variant>,
}

/// The parts of a version 1 scene.
#[derive(Debug)]
pub struct SceneV1Parts {
    /// The nodes.
    pub nodes: Vec<Node>,
    /// The macro library.
    pub macros: BTreeMap<String, FfsdMacro>,
}

/// A scene file parsed in the layout of its own version, before migration.
#[derive(Debug)]
pub enum VersionedScene {
    /// Version 1: nodes and macros.
    V1(SceneV1Parts),
    /// Version 2: the current document.
    V2(Document),
}

/// Lifts a scene of any supported version to the current [`Document`].
///
/// Each arm converts one version to the next and falls through to the following step, so a
/// new version `N + 1` adds one variant and one conversion `N → N + 1`; nothing else changes.
#[must_use]
pub fn migrate(scene: VersionedScene) -> Document {
    match scene {
        VersionedScene::V1(v1) => migrate(VersionedScene::V2(Document {
            nodes: v1.nodes,
            macros: v1.macros,
            animation: Animation::default(),
            variants: BTreeMap::new(),
        })),
        VersionedScene::V2(doc) => doc,
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

fn ron_options() -> ron::Options {
    ron::Options::default()
}

/// The text of a RON file without its UTF-8 byte-order mark (editors on Windows add one),
/// or an error naming the file when it holds nothing but white space; `expected` says what
/// it should hold.
pub(crate) fn file_body<'a>(text: &'a str, path: &Path, expected: &str) -> Result<&'a str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(IoError::Ron {
            path: path.to_owned(),
            line: 1,
            column: 1,
            message: format!("the file is empty (expected {expected})"),
        });
    }
    Ok(text)
}

/// Parses scene text; `path` names the file in errors.
pub fn parse_scene(text: &str, path: &Path) -> Result<Document> {
    let text = file_body(text, path, "a scene: `(version: 2, nodes: [...])`")?;
    let opts = ron_options();
    let probe: VersionProbe = opts.from_str(text).map_err(|e| ron_error(path, &e))?;
    let version = probe.version.ok_or_else(|| IoError::MissingVersion {
        path: path.to_owned(),
    })?;
    let scene = match version {
        1 => {
            let v1: SceneV1 = opts.from_str(text).map_err(|e| ron_error(path, &e))?;
            VersionedScene::V1(SceneV1Parts {
                nodes: v1.nodes,
                macros: v1.macros,
            })
        }
        2 => {
            let v2: SceneV2 = opts.from_str(text).map_err(|e| ron_error(path, &e))?;
            VersionedScene::V2(Document {
                nodes: v2.nodes,
                macros: v2.macros,
                animation: v2.animation,
                variants: v2.variants,
            })
        }
        found => {
            return Err(IoError::UnsupportedVersion {
                path: path.to_owned(),
                found,
            });
        }
    };
    Ok(migrate(scene))
}

/// Reads and parses a scene file without checking the document or loading meshes.
pub fn read_scene(path: impl AsRef<Path>) -> Result<Document> {
    let path = path.as_ref();
    let text = crate::read_text_file(path).map_err(|source| IoError::Read {
        path: path.to_owned(),
        source,
    })?;
    parse_scene(&text, path)
}

/// The document as pretty RON text of the current version.
pub fn scene_to_string(doc: &Document) -> Result<String, ron::Error> {
    let out = SceneOut {
        version: CURRENT_VERSION,
        nodes: &doc.nodes,
        macros: &doc.macros,
        animation: &doc.animation,
        variants: &doc.variants,
    };
    let pretty = ron::ser::PrettyConfig::default();
    ron_options().to_string_pretty(&out, pretty)
}

/// Writes the document as pretty RON (current version), atomically: the text goes to a
/// temporary file in the same directory, which is then renamed over `path`.
pub fn save_scene(path: impl AsRef<Path>, doc: &Document) -> Result<()> {
    let path = path.as_ref();
    let text = scene_to_string(doc).map_err(|e| IoError::Write {
        path: path.to_owned(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(path, text.as_bytes())
}

/// One mesh node of a loaded scene with its rest mesh.
#[derive(Debug, Clone)]
pub struct LoadedMesh {
    /// The mesh node's name.
    pub name: String,
    /// The mesh source, resolved against the scene file's directory.
    pub source: MeshRef,
    /// The validated, welded rest mesh.
    pub rest: RestMesh,
}

/// A scene file with its document checked and every mesh node's rest mesh loaded.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The scene file.
    pub path: PathBuf,
    /// The document.
    pub document: Document,
    /// The mesh nodes in document order.
    pub meshes: Vec<LoadedMesh>,
}

impl LoadedScene {
    /// The loaded mesh node called `name`.
    #[must_use]
    pub fn mesh(&self, name: &str) -> Option<&LoadedMesh> {
        self.meshes.iter().find(|m| m.name == name)
    }

    /// Evaluates the stack of mesh `name` (positions and recomputed normals in the stored
    /// vertex order). Errors name the scene file.
    pub fn evaluate(&self, name: &str) -> Result<Deformed> {
        let scene_err = |source| IoError::SceneProblem {
            path: self.path.clone(),
            source,
        };
        let mesh = self.mesh(name).ok_or_else(|| {
            scene_err(ductile_scene::error::SceneError::NoSuchNode {
                name: name.to_owned(),
            })
        })?;
        self.document.evaluate(name, &mesh.rest).map_err(scene_err)
    }
}

/// The directory relative paths in the file at `path` are resolved against: its parent
/// (empty for a bare file name, so that joined paths stay as the user wrote them).
#[must_use]
pub fn scene_dir(path: &Path) -> &Path {
    path.parent().unwrap_or(Path::new(""))
}

/// Loads the rest mesh of mesh node `node` (source `source`) of the scene at `scene_path`.
pub fn load_node_mesh(scene_path: &Path, node: &str, source: &str) -> Result<LoadedMesh> {
    let mesh_ref = MeshRef::parse(source).resolved(scene_dir(scene_path));
    let rest = load_rest_mesh(&mesh_ref).map_err(|e| IoError::MeshNode {
        scene: scene_path.to_owned(),
        node: node.to_owned(),
        mesh: mesh_ref.display_path(),
        source: Box::new(e),
    })?;
    Ok(LoadedMesh {
        name: node.to_owned(),
        source: mesh_ref,
        rest,
    })
}

/// Reads a scene file, checks the document (every problem of `Document::problems`, reported
/// together) and loads every mesh node's rest mesh, relative to the scene file's directory.
pub fn load_scene(path: impl AsRef<Path>) -> Result<LoadedScene> {
    let path = path.as_ref();
    let document = read_scene(path)?;
    let problems = document.problems();
    if !problems.is_empty() {
        return Err(IoError::Scene {
            path: path.to_owned(),
            problems,
        });
    }
    let mut meshes = Vec::new();
    for node in &document.nodes {
        if let NodeKind::Mesh(m) = &node.kind {
            meshes.push(load_node_mesh(path, &node.name, &m.source)?);
        }
    }
    Ok(LoadedScene {
        path: path.to_owned(),
        document,
        meshes,
    })
}

/// Every problem of a scene file, not just the first: a read or parse error (alone, since
/// nothing else can be checked then), or every document problem, every mesh that cannot be
/// loaded, and every error resolving or evaluating a mesh's stack (without repeating a
/// problem already reported). Empty when the file is fine.
#[must_use]
pub fn check_scene(path: impl AsRef<Path>) -> Vec<IoError> {
    let path = path.as_ref();
    match read_scene(path) {
        Ok(d) => check_document(path, path, &d),
        Err(e) => vec![e],
    }
}

/// Every problem of a history file: a read or parse error or a bad base (alone), the first
/// step that does not replay (naming it), or else every problem of the document the whole
/// history replays to, as [`check_scene`] finds them (meshes relative to the history's mesh
/// root). Empty when the file is fine.
#[must_use]
pub fn check_history(path: impl AsRef<Path>) -> Vec<IoError> {
    let path = path.as_ref();
    let loaded = match crate::history_file::read_history(path) {
        Ok(l) => l,
        Err(e) => return vec![e],
    };
    match loaded.replay(loaded.history.len()) {
        Ok(document) => check_document(path, &loaded.mesh_root, &document),
        Err(e) => vec![e],
    }
}

/// The problems of `document`, read from `path`, whose mesh sources are relative to
/// `mesh_root` (see [`check_scene`]).
fn check_document(path: &Path, mesh_root: &Path, document: &Document) -> Vec<IoError> {
    let mut out: Vec<IoError> = document
        .problems()
        .into_iter()
        .map(|source| IoError::SceneProblem {
            path: path.to_owned(),
            source,
        })
        .collect();
    let bad_transform = document
        .nodes
        .iter()
        .any(|n| !n.transform.is_finite() || n.transform.degeneracy().is_some());
    for node in &document.nodes {
        let NodeKind::Mesh(m) = &node.kind else {
            continue;
        };
        match load_node_mesh(mesh_root, &node.name, &m.source) {
            Err(e) => out.push(e),
            Ok(loaded) => {
                let mut report = |source: ductile_scene::error::SceneError| {
                    let text = source.to_string();
                    if !out.iter().any(|e| e.to_string().contains(&text)) {
                        out.push(IoError::SceneProblem {
                            path: path.to_owned(),
                            source,
                        });
                    }
                };
                // Through a node whose transform was refused above, the tools' parameters in
                // mesh space are derived values the user never wrote: evaluating would report
                // the same bad value a second time, disguised.
                if !bad_transform && let Err(source) = document.evaluate(&node.name, &loaded.rest) {
                    report(source);
                }
                // Every area, used by a layer yet or not: a bad one would fail only when a
                // layer (or a macro) starts using it.
                for (area, def) in &m.areas {
                    let what = format!("mesh '{}', area '{area}'", node.name);
                    if let Err(source) =
                        ductile_scene::resolve::resolve_area(def, &loaded.rest, &what)
                    {
                        report(source);
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::parse_scene;
    use crate::history_file::{is_history_text, parse_history};

    #[test]
    fn a_byte_order_mark_is_skipped_and_an_empty_file_is_named_as_such() {
        // Issue 14: both gave an error about an internal type (`VersionProbe`).
        let p = Path::new("face.ron");
        let doc = parse_scene("\u{feff}(version: 1, nodes: [])", p).unwrap();
        assert!(doc.nodes.is_empty());
        for empty in ["", "  \n\t", "\u{feff}"] {
            let e = parse_scene(empty, p).unwrap_err().to_string();
            assert_eq!(
                e,
                "face.ron:1:1: the file is empty (expected a scene: `(version: 2, nodes: [...])`)"
            );
        }
        let e = parse_scene("[1, 2]", p).unwrap_err().to_string();
        assert!(e.contains("struct `Scene`") && !e.contains("Probe"), "{e}");

        let h = Path::new("face.history.ron");
        let text = "\u{feff}(version: 1, base: Inline((nodes: [])), entries: [])";
        assert!(is_history_text(text));
        if let Err(e) = parse_history(text, h) {
            panic!("{e}");
        }
        let e = parse_history("", h).unwrap_err().to_string();
        assert!(
            e.contains("face.history.ron:1:1: the file is empty (expected a history"),
            "{e}"
        );
    }

    #[test]
    fn a_name_twice_in_a_map_is_refused_not_the_last_kept() {
        // Issue 14: duplicate keys in `areas` / `macros` maps: the last silently won.
        let p = Path::new("twice.ron");
        let areas = "(version: 2, nodes: [(name: \"m\", kind: Mesh((source: \"a.obj\", \
                     areas: {\"top\": Vertices([0]), \"top\": Vertices([1])})))])";
        let e = parse_scene(areas, p).unwrap_err().to_string();
        assert!(
            e.starts_with("twice.ron:") && e.contains("\"top\" appears twice"),
            "{e}"
        );
        let macros = "(version: 1, macros: {\"nose\": (label: \"a\", points: []), \
                      \"nose\": (label: \"b\", points: [])})";
        let e = parse_scene(macros, p).unwrap_err().to_string();
        assert!(e.contains("\"nose\" appears twice"), "{e}");
        let once = "(version: 1, macros: {\"nose\": (label: \"a\", points: [])})";
        assert_eq!(parse_scene(once, p).unwrap().macros.len(), 1);
    }
}
