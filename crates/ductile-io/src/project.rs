//! Studio projects: a scene file, its edit history beside it, and the rest meshes they use.
//!
//! A project saved as `X.ron` is two files in the same directory (see
//! `docs/scene-format.md`, "Projects: scene + history"):
//!
//! * `X.ron`, the scene file of the current document, readable by every tool on its own;
//! * `X.history.ron`, the history file with the base document **inline** and the cursor
//!   (the step the document is at), so that undo works across sessions.
//!
//! [`Project::open`] takes either file: a scene picks up its sibling history when the
//! history's replay at its saved cursor equals the scene's document (otherwise the project
//! starts a fresh history and says why in a [`ProjectWarning`]); a history file is replayed
//! to its saved cursor.
//!
//! **Mesh sources.** Mesh sources are relative to the project's directory. Saving into
//! another directory rewrites every source so that it still names the same file: relative
//! to the new directory, or absolute when the two share nothing but the file system root. A
//! mesh that only exists in memory (the embedded default head) is written next to the saved
//! scene. The rewrite is one map from old source text to new source text, applied to the
//! current document, the history's base and every node an `AddNode` or `RemoveNode` step
//! carries (inside groups too), so every step still applies and undoes exactly.

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

use ductile_core::mesh::{Deformed, RestMesh};
use ductile_history::error::HistoryError;
use ductile_history::history::{Entry, History};
use ductile_history::operation::Operation;
use ductile_scene::document::{Document, MeshNode, Node, NodeKind};
use thiserror::Error;

use crate::bake::{BakeOptions, BakeReport, export_animation, export_variant_morphs};
use crate::embedded;
use crate::error::{IoError, Result};
use crate::export::{ExportMesh, export_gltf};
use crate::history_file::{LoadedHistory, SaveBase, history_to_string, is_history_text};
use crate::history_file::{parse_history, read_history};
use crate::mesh::{MeshFormat, MeshRef, load_rest_mesh, load_rest_mesh_from_bytes};
use crate::scene::{LoadedMesh, LoadedScene, parse_scene, scene_dir, scene_to_string};
use crate::write_atomic;

/// The suffix of a project's history file: `X.ron` keeps its history in `X.history.ron`.
pub const HISTORY_SUFFIX: &str = ".history.ron";

/// The history file of the scene file `scene`: `X.ron` → `X.history.ron` (a name without
/// the `.ron` extension gets the suffix appended).
#[must_use]
pub fn history_path_for(scene: &Path) -> PathBuf {
    let name = scene
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let stem = name.strip_suffix(".ron").unwrap_or(&name);
    scene.with_file_name(format!("{stem}{HISTORY_SUFFIX}"))
}

/// The scene file of the history file `history` when it follows the project naming:
/// `X.history.ron` → `X.ron`; `None` for any other name.
#[must_use]
pub fn scene_path_for(history: &Path) -> Option<PathBuf> {
    let name = history.file_name()?.to_str()?;
    let stem = name.strip_suffix(HISTORY_SUFFIX)?;
    (!stem.is_empty()).then(|| history.with_file_name(format!("{stem}.ron")))
}

/// A mesh held in memory, served for a mesh source of a project that has no file on disk
/// (for example embedded in the program with `include_bytes!`).
#[derive(Clone)]
pub struct EmbeddedMesh {
    /// The mesh source exactly as the scene writes it (with its `#name` selection, if any).
    pub source: String,
    /// The file's bytes; the format comes from the source's extension.
    pub bytes: Cow<'static, [u8]>,
}

impl fmt::Debug for EmbeddedMesh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbeddedMesh")
            .field("source", &self.source)
            .field("bytes", &self.bytes.len())
            .finish()
    }
}

/// Why [`Project::open`] did not take the history beside a scene file. The project still
/// opens, with a fresh history starting at the scene's document.
#[derive(Debug, Error)]
pub enum ProjectWarning {
    /// The history file cannot be read, or its steps do not replay.
    #[error("{}: the history was not loaded, undo starts from the scene as saved: {source}", path.display())]
    HistoryUnreadable {
        /// The history file.
        path: PathBuf,
        /// Why it could not be used.
        source: Box<IoError>,
    },
    /// The history replays to a document other than the scene's (the scene was changed
    /// after the history was saved, by hand or by another program).
    #[error(
        "{}: the history ends at a different document than {} (the scene was changed after the history was saved); undo starts from the scene as saved",
        path.display(),
        scene.display()
    )]
    HistoryMismatch {
        /// The history file.
        path: PathBuf,
        /// The scene file.
        scene: PathBuf,
    },
}

/// A mesh imported into a project ([`Project::import_mesh`]): the new mesh node, not yet in
/// the document (add it with `Operation::add_node`), and its rest mesh.
#[derive(Debug, Clone)]
pub struct ImportedMesh {
    /// The mesh node: a name unique in the document, made from the file stem, and the source
    /// relative to the project's directory (absolute when the project has none).
    pub node: Node,
    /// The validated, welded rest mesh.
    pub rest: Arc<RestMesh>,
}

/// A document being edited: the document, its undo history, where it lives on disk and the
/// rest meshes of its mesh sources.
///
/// The document and the history always agree: the document is the history's base with its
/// first `cursor` steps applied. Edits go through [`Project::push`], [`Project::undo`],
/// [`Project::redo`] and [`Project::jump`].
#[derive(Debug, Clone)]
pub struct Project {
    /// The scene file it is saved to; `None` until saved (new, embedded, or opened from a
    /// history file not named `X.history.ron`).
    path: Option<PathBuf>,
    /// The file errors name: the scene or history file opened, or a pseudo-name.
    origin: PathBuf,
    /// The directory relative mesh sources are relative to; `None` for a project that never
    /// had a file (relative sources then resolve against the current directory, after the
    /// embedded meshes).
    source_dir: Option<PathBuf>,
    document: Document,
    history: History,
    /// The document as last opened or saved.
    saved: Document,
    /// Meshes served from memory, by source text.
    embedded: BTreeMap<String, EmbeddedMesh>,
    /// Rest meshes loaded so far, by source text.
    cache: BTreeMap<String, Arc<RestMesh>>,
}

impl Project {
    /// An empty, unsaved project (the Studio's File → New).
    #[must_use]
    pub fn new_empty() -> Self {
        Self::unsaved(
            PathBuf::from("untitled.ron"),
            Document::default(),
            Vec::new(),
        )
    }

    fn unsaved(origin: PathBuf, document: Document, embedded: Vec<EmbeddedMesh>) -> Self {
        Self {
            path: None,
            origin,
            source_dir: None,
            history: History::new(document.clone()),
            saved: document.clone(),
            document,
            embedded: embedded
                .into_iter()
                .map(|m| (m.source.clone(), m))
                .collect(),
            cache: BTreeMap::new(),
        }
    }

    /// The identikit head scene embedded in the program ([`crate::embedded`]), with its
    /// mesh served from memory: it opens from any working directory. The scene's mesh source
    /// stays as written; [`Project::save_as`] writes the mesh next to the saved scene.
    pub fn embedded_default() -> Result<Self> {
        Self::from_memory(
            embedded::IDENTIKIT_HEAD_NAME,
            embedded::IDENTIKIT_HEAD_SCENE,
            vec![EmbeddedMesh {
                source: embedded::HEAD_SOURCE.to_owned(),
                bytes: Cow::Borrowed(embedded::HEAD_GLB),
            }],
        )
    }

    /// An unsaved project from scene text held in memory; `name` names it in errors. Mesh
    /// sources found in `meshes` are decoded from memory, the others are read from disk
    /// relative to the current directory. The document is checked and every mesh loaded.
    pub fn from_memory(name: &str, scene_text: &str, meshes: Vec<EmbeddedMesh>) -> Result<Self> {
        let origin = PathBuf::from(name);
        let document = parse_scene(scene_text, &origin)?;
        check_document(&origin, &document)?;
        let mut project = Self::unsaved(origin, document, meshes);
        project.load_meshes()?;
        Ok(project)
    }

    /// Opens a scene file or a history file ([`is_history_text`] tells them apart) and
    /// loads every mesh of the document.
    ///
    /// * A scene `X.ron` takes its sibling history `X.history.ron` when that replays, at its
    ///   saved cursor, to exactly the scene's document; otherwise the history starts fresh at
    ///   the scene and a [`ProjectWarning`] says why.
    /// * A history file is replayed to its saved cursor (every step checked). The project is
    ///   saved to `X.ron` when the history is `X.history.ron`; any other name leaves the
    ///   project without a scene file ([`Project::save`] then asks for
    ///   [`Project::save_as`]), so that a scene the history refers to is never overwritten.
    ///
    /// Errors (unreadable or malformed file, document problems, a mesh that cannot be
    /// loaded) name the file.
    pub fn open(path: impl AsRef<Path>) -> Result<(Self, Vec<ProjectWarning>)> {
        let path = path.as_ref();
        let text = crate::read_text_file(path).map_err(|source| IoError::Read {
            path: path.to_owned(),
            source,
        })?;
        let (mut project, warnings) = if is_history_text(&text) {
            (Self::open_history(path, &text)?, Vec::new())
        } else {
            Self::open_scene(path, &text)?
        };
        project.load_meshes()?;
        Ok((project, warnings))
    }

    fn open_scene(path: &Path, text: &str) -> Result<(Self, Vec<ProjectWarning>)> {
        let document = parse_scene(text, path)?;
        check_document(path, &document)?;
        let history_path = history_path_for(path);
        let mut warnings = Vec::new();
        let history = if history_path.is_file() {
            match sibling_history(&history_path, path, &document) {
                Ok(h) => h,
                Err(w) => {
                    warnings.push(w);
                    History::new(document.clone())
                }
            }
        } else {
            History::new(document.clone())
        };
        let project = Self {
            path: Some(path.to_owned()),
            origin: path.to_owned(),
            source_dir: Some(scene_dir(path).to_owned()),
            saved: document.clone(),
            document,
            history,
            embedded: BTreeMap::new(),
            cache: BTreeMap::new(),
        };
        Ok((project, warnings))
    }

    fn open_history(path: &Path, text: &str) -> Result<Self> {
        let loaded = parse_history(text, path)?;
        let source_dir = scene_dir(&loaded.mesh_root).to_owned();
        let (history, document) = restore(loaded)?;
        check_document(path, &document)?;
        Ok(Self {
            path: scene_path_for(path),
            origin: path.to_owned(),
            source_dir: Some(source_dir),
            saved: document.clone(),
            document,
            history,
            embedded: BTreeMap::new(),
            cache: BTreeMap::new(),
        })
    }

    /// The file the project was opened from or last saved to (for an unsaved project, the
    /// name it was created under): what names it in errors, and its recovery file
    /// ([`crate::recovery::recovery_path`]).
    #[must_use]
    pub fn origin(&self) -> &Path {
        &self.origin
    }

    /// The scene file the project is saved to, if any.
    #[must_use]
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The history file beside the scene file ([`history_path_for`]), if the project has one.
    #[must_use]
    pub fn history_path(&self) -> Option<PathBuf> {
        self.path.as_deref().map(history_path_for)
    }

    /// The name shown for the project: the scene file's name, or the name it was opened or
    /// created under.
    #[must_use]
    pub fn display_name(&self) -> String {
        let p = self.path.as_deref().unwrap_or(&self.origin);
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    }

    /// The current document.
    #[must_use]
    pub fn document(&self) -> &Document {
        &self.document
    }

    /// The undo history; its cursor is the step [`Project::document`] is at.
    #[must_use]
    pub fn history(&self) -> &History {
        &self.history
    }

    /// Replaces the document and its history with ones edited elsewhere (the Studio keeps the
    /// live document in its own resource and hands it over before saving or exporting). The
    /// caller guarantees that `document` is `history`'s base with its first `cursor` steps
    /// applied.
    pub fn set_state(&mut self, document: Document, history: History) {
        self.document = document;
        self.history = history;
    }

    /// True when the document differs from the one last opened or saved.
    #[must_use]
    pub fn is_modified(&self) -> bool {
        self.document != self.saved
    }

    /// Applies `op` and records it ([`History::push`]: a continued gesture merges into one
    /// step). On error nothing changes.
    pub fn push(
        &mut self,
        op: Operation,
        label: impl Into<String>,
        time_ms: u64,
        gesture: Option<u64>,
    ) -> std::result::Result<(), HistoryError> {
        self.history
            .push(&mut self.document, op, label, time_ms, gesture)
    }

    /// Undoes one step; `false` at the start of the history.
    pub fn undo(&mut self) -> std::result::Result<bool, HistoryError> {
        self.history.undo(&mut self.document)
    }

    /// Redoes one step; `false` at the end of the history.
    pub fn redo(&mut self) -> std::result::Result<bool, HistoryError> {
        self.history.redo(&mut self.document)
    }

    /// Moves to step `n` (0 = the base) ([`History::jump`]).
    pub fn jump(&mut self, n: usize) -> std::result::Result<(), HistoryError> {
        self.history.jump(&mut self.document, n)
    }

    /// The rest mesh of mesh node `node`, loaded on first use and cached by source (undoing
    /// and redoing an import does not read the file again). Errors name the project file
    /// and the node.
    pub fn rest_mesh(&mut self, node: &str) -> Result<Arc<RestMesh>> {
        let source = match self.document.mesh(node) {
            Ok(m) => m.source.clone(),
            Err(source) => {
                return Err(IoError::SceneProblem {
                    path: self.origin.clone(),
                    source,
                });
            }
        };
        if let Some(rest) = self.cache.get(&source) {
            return Ok(Arc::clone(rest));
        }
        let rest = Arc::new(self.load_source(node, &source)?);
        self.cache.insert(source, Arc::clone(&rest));
        Ok(rest)
    }

    /// The rest mesh of every mesh node, in document order (see [`Project::rest_mesh`]).
    pub fn load_meshes(&mut self) -> Result<Vec<(String, Arc<RestMesh>)>> {
        let names: Vec<String> = self
            .document
            .mesh_names()
            .into_iter()
            .map(ToOwned::to_owned)
            .collect();
        names
            .into_iter()
            .map(|n| {
                let rest = self.rest_mesh(&n)?;
                Ok((n, rest))
            })
            .collect()
    }

    fn load_source(&self, node: &str, source: &str) -> Result<RestMesh> {
        let wrap = |mesh: PathBuf, e: IoError| IoError::MeshNode {
            scene: self.origin.clone(),
            node: node.to_owned(),
            mesh,
            source: Box::new(e),
        };
        if let Some(m) = self.embedded.get(source) {
            let r = MeshRef::parse(source);
            let format = MeshFormat::from_path(&r.path).map_err(|e| wrap(r.display_path(), e))?;
            return load_rest_mesh_from_bytes(&m.bytes, format, source)
                .map_err(|e| wrap(r.display_path(), e));
        }
        let r =
            MeshRef::parse(source).resolved(self.source_dir.as_deref().unwrap_or(Path::new("")));
        load_rest_mesh(&r).map_err(|e| wrap(r.display_path(), e))
    }

    /// Evaluates the stack of mesh node `node` (positions and recomputed normals in the
    /// stored vertex order).
    pub fn evaluate(&mut self, node: &str) -> Result<Deformed> {
        let rest = self.rest_mesh(node)?;
        self.document
            .evaluate(node, &rest)
            .map_err(|source| IoError::SceneProblem {
                path: self.origin.clone(),
                source,
            })
    }

    /// Evaluates every mesh node and writes the deformed meshes to `path` (`.glb` or
    /// `.gltf`, [`export_gltf`]), one glTF mesh per mesh node, in document order.
    pub fn export_gltf(&mut self, path: impl AsRef<Path>) -> Result<()> {
        let meshes = self.load_meshes()?;
        let mut deformed = Vec::with_capacity(meshes.len());
        for (name, _) in &meshes {
            deformed.push(self.evaluate(name)?);
        }
        let exports: Vec<ExportMesh<'_>> = meshes
            .iter()
            .zip(&deformed)
            .map(|((name, rest), d)| ExportMesh::deformed(name, rest, d))
            .collect();
        export_gltf(path, &exports)
    }

    /// The document with the rest mesh of every mesh node loaded, as the bake and morph
    /// exports ([`crate::bake`]) take a scene file.
    pub fn loaded_scene(&mut self) -> Result<LoadedScene> {
        let meshes = self.load_meshes()?;
        let dir = self.source_dir.clone().unwrap_or_default();
        let meshes = meshes
            .into_iter()
            .map(|(name, rest)| {
                let source = self
                    .document
                    .mesh(&name)
                    .map(|m| MeshRef::parse(&m.source).resolved(&dir))
                    .map_err(|source| IoError::SceneProblem {
                        path: self.origin.clone(),
                        source,
                    })?;
                Ok(LoadedMesh {
                    name,
                    source,
                    rest: (*rest).clone(),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(LoadedScene {
            path: self.origin.clone(),
            document: self.document.clone(),
            meshes,
        })
    }

    /// Bakes the timeline and writes it to `path` as morph targets and a weights animation
    /// ([`crate::bake::export_animation`], what `ductile export-anim` does).
    pub fn export_animation(
        &mut self,
        path: impl AsRef<Path>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<BakeReport> {
        let scene = self.loaded_scene()?;
        let options = BakeOptions::timeline(&scene.document);
        export_animation(&scene, path.as_ref(), &options, progress)
    }

    /// Writes the rest meshes with one morph target per variant to `path`
    /// ([`crate::bake::export_variant_morphs`], what `ductile export-morphs` does); returns
    /// the targets' names.
    pub fn export_variant_morphs(&mut self, path: impl AsRef<Path>) -> Result<Vec<String>> {
        let scene = self.loaded_scene()?;
        export_variant_morphs(&scene, path.as_ref(), &mut |_, _| {})
    }

    /// Loads the mesh file at `path` (glTF or OBJ) and makes a mesh node for it, without
    /// adding it to the document: the caller adds `node` with an `AddNode` operation (one
    /// undo step). The node's name is the file stem, made unique in the document (`head`,
    /// `head-2`, ...); its source is relative to the project's directory, or absolute when
    /// the project has none yet. Errors name the mesh file.
    pub fn import_mesh(&mut self, path: impl AsRef<Path>) -> Result<ImportedMesh> {
        self.import_mesh_part(path, None)
    }

    /// [`Project::import_mesh`] of one part of the file (an OBJ object or group, a named
    /// glTF mesh; see [`crate::mesh::mesh_parts`]), or of the whole file with `None`. The
    /// source is `path#part` and the node is named after the part.
    pub fn import_mesh_part(
        &mut self,
        path: impl AsRef<Path>,
        part: Option<&str>,
    ) -> Result<ImportedMesh> {
        let path = path.as_ref();
        let rest = Arc::new(load_rest_mesh(&MeshRef {
            path: path.to_owned(),
            select: part.map(ToOwned::to_owned),
        })?);
        let mut source = match &self.source_dir {
            Some(dir) => relative_path(path, dir),
            None => slashes(&normalize(path)),
        };
        if let Some(part) = part {
            source = format!("{source}#{part}");
        }
        let stem = part
            .map(ToOwned::to_owned)
            .or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()))
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "mesh".to_owned());
        let node = Node {
            name: self.document.unique_name(&stem),
            parent: None,
            transform: Default::default(),
            kind: NodeKind::Mesh(MeshNode {
                source: source.clone(),
                stack: Vec::new(),
                areas: BTreeMap::new(),
            }),
        };
        self.cache.insert(source, Arc::clone(&rest));
        Ok(ImportedMesh { node, rest })
    }

    /// Saves to the project's scene file and its history file ([`Project::save_as`] with
    /// [`Project::path`]). A project without a scene file gives [`IoError::NoProjectFile`].
    pub fn save(&mut self) -> Result<()> {
        match self.path.clone() {
            Some(p) => self.save_as(p),
            None => Err(IoError::NoProjectFile {
                name: self.origin.clone(),
            }),
        }
    }

    /// Writes the current document to the scene file `path` and the history (base inline,
    /// with the cursor) to its history file ([`history_path_for`]), each atomically, and
    /// makes `path` the project's file.
    ///
    /// When `path` is in another directory than the project's, every mesh source is
    /// rewritten relative to it (see the module documentation), consistently in the
    /// document, the history's base and its steps. A mesh held only in memory is written
    /// next to `path` under its file name (`lee-perry-smith-head.glb`; an existing file
    /// with other content is never overwritten: `-2`, `-3`, ... is appended to the stem)
    /// and its source names that file. On error the project is unchanged (mesh files
    /// already written stay).
    pub fn save_as(&mut self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let dir = scene_dir(path);
        let history_path = history_path_for(path);
        let same_dir = self
            .source_dir
            .as_deref()
            .is_some_and(|d| normalize(d) == normalize(dir));

        let mut document = self.document.clone();
        let (mut base, mut entries, cursor) = self.history.clone().into_parts();
        let mut sources = BTreeSet::new();
        {
            let mut collect = |s: &mut String| {
                sources.insert(s.clone());
            };
            document_sources(&mut document, &mut collect);
            document_sources(&mut base, &mut collect);
            entries
                .iter_mut()
                .for_each(|e| op_sources(&mut e.op, &mut collect));
        }
        let mut map = BTreeMap::new();
        for source in sources {
            if let Some(m) = self.embedded.get(&source) {
                map.insert(source, materialize(dir, m)?);
            } else if !same_dir {
                let new = rebase_source(&source, self.source_dir.as_deref(), dir);
                map.insert(source, new);
            }
        }
        let mut rewrite = |s: &mut String| {
            if let Some(new) = map.get(s.as_str()) {
                s.clone_from(new);
            }
        };
        document_sources(&mut document, &mut rewrite);
        document_sources(&mut base, &mut rewrite);
        entries
            .iter_mut()
            .for_each(|e| op_sources(&mut e.op, &mut rewrite));
        let history =
            history_at(base, entries, cursor, &document).map_err(|source| IoError::History {
                path: history_path.clone(),
                source,
            })?;

        let write_err = |p: &Path| {
            let p = p.to_owned();
            move |e: ron::Error| IoError::Write {
                path: p,
                source: std::io::Error::other(e),
            }
        };
        let history_text = history_to_string(&history, SaveBase::Inline, &history_path)
            .map_err(write_err(&history_path))?;
        let scene_text = scene_to_string(&document).map_err(write_err(path))?;
        write_atomic(&history_path, history_text.as_bytes())?;
        write_atomic(path, scene_text.as_bytes())?;

        self.cache = std::mem::take(&mut self.cache)
            .into_iter()
            .map(|(k, v)| (map.get(&k).cloned().unwrap_or(k), v))
            .collect();
        self.embedded.clear();
        self.path = Some(path.to_owned());
        self.origin = path.to_owned();
        self.source_dir = Some(dir.to_owned());
        self.saved = document.clone();
        self.document = document;
        self.history = history;
        Ok(())
    }
}

/// Checks a document with every rule of `Document::problems`, reported together.
fn check_document(path: &Path, document: &Document) -> Result<()> {
    let problems = document.problems();
    if problems.is_empty() {
        Ok(())
    } else {
        Err(IoError::Scene {
            path: path.to_owned(),
            problems,
        })
    }
}

/// The history beside a scene, at its saved cursor, when it ends at the scene's document.
fn sibling_history(
    history_path: &Path,
    scene_path: &Path,
    document: &Document,
) -> std::result::Result<History, ProjectWarning> {
    let unreadable = |source| ProjectWarning::HistoryUnreadable {
        path: history_path.to_owned(),
        source: Box::new(source),
    };
    let loaded = read_history(history_path).map_err(unreadable)?;
    let (history, end) = restore(loaded).map_err(unreadable)?;
    if end == *document {
        Ok(history)
    } else {
        Err(ProjectWarning::HistoryMismatch {
            path: history_path.to_owned(),
            scene: scene_path.to_owned(),
        })
    }
}

/// The loaded history at its saved cursor, with the document there. Every step is replayed
/// and checked (the redo tail too), then the tail is undone.
pub(crate) fn restore(loaded: LoadedHistory) -> Result<(History, Document)> {
    let LoadedHistory {
        path,
        history,
        cursor,
        ..
    } = loaded;
    let err = |source| IoError::History {
        path: path.clone(),
        source,
    };
    let mut document = history.document_at(history.len()).map_err(err)?;
    let mut history = history;
    history.jump(&mut document, cursor).map_err(err)?;
    Ok((history, document))
}

/// The history of `base` and `entries` with its cursor at `cursor`, where `at_cursor` is
/// the document after the first `cursor` steps: the redo tail is applied to a copy and
/// undone again, so the result's cursor is `cursor`.
fn history_at(
    base: Document,
    entries: Vec<Entry>,
    cursor: usize,
    at_cursor: &Document,
) -> std::result::Result<History, HistoryError> {
    let mut end = at_cursor.clone();
    for e in entries.iter().skip(cursor) {
        e.op.apply(&mut end)?;
    }
    let mut history = History::from_entries(base, entries);
    history.jump(&mut end, cursor)?;
    Ok(history)
}

/// Calls `f` on the source of every mesh node of `doc`.
fn document_sources(doc: &mut Document, f: &mut impl FnMut(&mut String)) {
    doc.nodes.iter_mut().for_each(|n| node_source(n, f));
}

fn node_source(node: &mut Node, f: &mut impl FnMut(&mut String)) {
    if let NodeKind::Mesh(m) = &mut node.kind {
        f(&mut m.source);
    }
}

/// Calls `f` on the source of every mesh node an operation carries. The match lists every
/// operation so that a new one carrying nodes cannot be forgotten here.
fn op_sources(op: &mut Operation, f: &mut impl FnMut(&mut String)) {
    match op {
        Operation::AddNode { node, .. } | Operation::RemoveNode { node, .. } => {
            node_source(node, f);
        }
        Operation::Group { ops, .. } => ops.iter_mut().for_each(|o| op_sources(o, f)),
        Operation::Rename { .. }
        | Operation::Reparent { .. }
        | Operation::SetTransform { .. }
        | Operation::SetTool { .. }
        | Operation::SetVolume { .. }
        | Operation::SetMacroValue { .. }
        | Operation::AddLayer { .. }
        | Operation::RemoveLayer { .. }
        | Operation::MoveLayer { .. }
        | Operation::SetLayerEnabled { .. }
        | Operation::SetLayerWeight { .. }
        | Operation::SetLayerSolo { .. }
        | Operation::SetLayerInfluence { .. }
        | Operation::DefineArea { .. }
        | Operation::SetMacroDefinition { .. }
        | Operation::SetKey { .. }
        | Operation::MoveKey { .. }
        | Operation::SetTrack { .. }
        | Operation::SetTimeline { .. }
        | Operation::SetVariant { .. }
        | Operation::RenameVariant { .. } => {}
    }
}

/// How many numbered names [`materialize`] tries before giving up.
const MAX_COPIES: usize = 1000;

/// Writes an in-memory mesh into `dir` under its file name (or the first `stem-k.ext` that
/// is free or already holds the same bytes) and returns its new source (the file name, with
/// the `#name` selection kept).
fn materialize(dir: &Path, mesh: &EmbeddedMesh) -> Result<String> {
    let r = MeshRef::parse(&mesh.source);
    let name = r.path.file_name().map_or_else(
        || "mesh.glb".to_owned(),
        |n| n.to_string_lossy().into_owned(),
    );
    let (stem, ext) = match name.rsplit_once('.') {
        Some((s, e)) if !s.is_empty() => (s.to_owned(), format!(".{e}")),
        _ => (name.clone(), String::new()),
    };
    for k in 1..=MAX_COPIES {
        let file = if k == 1 {
            name.clone()
        } else {
            format!("{stem}-{k}{ext}")
        };
        let target = dir.join(&file);
        let existing = match std::fs::read(&target) {
            Ok(bytes) => Some(bytes),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(IoError::Read {
                    path: target,
                    source,
                });
            }
        };
        match existing {
            Some(bytes) if bytes[..] != mesh.bytes[..] => continue,
            Some(_) => {}
            None => write_atomic(&target, &mesh.bytes)?,
        }
        return Ok(match &r.select {
            Some(s) => format!("{file}#{s}"),
            None => file,
        });
    }
    Err(IoError::Write {
        path: dir.join(&name),
        source: std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("{MAX_COPIES} files of this name with other contents exist already"),
        ),
    })
}

/// A mesh source relative to `old_dir` (the current directory when `None`) rewritten to
/// name the same file relative to `new_dir` (see [`relative_path`]); the `#name` selection
/// is kept.
#[must_use]
pub fn rebase_source(source: &str, old_dir: Option<&Path>, new_dir: &Path) -> String {
    let r = MeshRef::parse(source);
    let file = if r.path.is_absolute() {
        r.path.clone()
    } else {
        old_dir.unwrap_or(Path::new("")).join(&r.path)
    };
    let path = relative_path(&file, new_dir);
    match r.select {
        Some(s) => format!("{path}#{s}"),
        None => path,
    }
}

/// `target` as seen from the directory `dir`: a relative path with `/` separators and `..`
/// where needed, or `target` made absolute when the two share nothing but the file system
/// root (or not even that: another drive). Both are made absolute against the current
/// directory and resolved ([`normalize`]) first.
#[must_use]
pub fn relative_path(target: &Path, dir: &Path) -> String {
    let (target, dir) = (normalize(target), normalize(dir));
    let t: Vec<Component<'_>> = target.components().collect();
    let d: Vec<Component<'_>> = dir.components().collect();
    let roots = t
        .iter()
        .take_while(|c| matches!(c, Component::Prefix(_) | Component::RootDir))
        .count();
    let common = t.iter().zip(&d).take_while(|(a, b)| a == b).count();
    if common <= roots {
        return slashes(&target);
    }
    let mut parts: Vec<String> = vec!["..".to_owned(); d.len() - common];
    parts.extend(
        t[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    if parts.is_empty() {
        ".".to_owned()
    } else {
        parts.join("/")
    }
}

/// A path as text with `/` separators.
fn slashes(p: &Path) -> String {
    p.to_string_lossy().replace('\\', "/")
}

/// `p` absolute and resolved: canonical (symbolic links resolved) when it exists, else its
/// parent's canonical form joined with its name, else made absolute with `.` and `..`
/// removed textually. An empty path is the current directory.
#[must_use]
pub fn normalize(p: &Path) -> PathBuf {
    let p = if p.as_os_str().is_empty() {
        Path::new(".")
    } else {
        p
    };
    if let Ok(c) = std::fs::canonicalize(p) {
        return c;
    }
    if let (Some(parent), Some(name)) = (p.parent(), p.file_name())
        && let Ok(c) = std::fs::canonicalize(if parent.as_os_str().is_empty() {
            Path::new(".")
        } else {
            parent
        })
    {
        return c.join(name);
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_owned());
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push(c);
                }
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_and_scene_names_pair_up() {
        assert_eq!(
            history_path_for(Path::new("dir/face.ron")),
            PathBuf::from("dir/face.history.ron")
        );
        assert_eq!(
            history_path_for(Path::new("face")),
            PathBuf::from("face.history.ron")
        );
        assert_eq!(
            scene_path_for(Path::new("dir/face.history.ron")),
            Some(PathBuf::from("dir/face.ron"))
        );
        assert_eq!(scene_path_for(Path::new("dir/edits.ron")), None);
        assert_eq!(scene_path_for(Path::new(".history.ron")), None);
    }

    #[test]
    fn relative_paths_climb_and_fall_back_to_absolute() {
        let dir = tempfile::tempdir().unwrap();
        let root = normalize(dir.path());
        std::fs::create_dir_all(root.join("a/b")).unwrap();
        std::fs::create_dir_all(root.join("c")).unwrap();
        assert_eq!(
            relative_path(&root.join("c/m.obj"), &root.join("a/b")),
            "../../c/m.obj"
        );
        assert_eq!(
            relative_path(&root.join("a/b/m.obj"), &root.join("a/b")),
            "m.obj"
        );
        // A textual `..` is resolved before comparing.
        assert_eq!(
            relative_path(&root.join("a/b/../../c/m.obj"), &root.join("c")),
            "m.obj"
        );
        // Nothing but the root in common: absolute.
        let far = Path::new("/nonexistent-ductile-dir/x.glb");
        assert_eq!(relative_path(far, &root), "/nonexistent-ductile-dir/x.glb");
    }

    #[test]
    fn rebasing_keeps_the_selection() {
        let dir = tempfile::tempdir().unwrap();
        let root = normalize(dir.path());
        std::fs::create_dir_all(root.join("scenes")).unwrap();
        std::fs::create_dir_all(root.join("out/deep")).unwrap();
        let s = rebase_source(
            "../assets/m.obj#body",
            Some(&root.join("scenes")),
            &root.join("out/deep"),
        );
        assert_eq!(s, "../../assets/m.obj#body");
    }

    #[test]
    fn unique_names_count_up() {
        let mut doc = Document::default();
        assert_eq!(doc.unique_name("head"), "head");
        for name in ["head", "head-2"] {
            doc.nodes.push(Node {
                name: name.to_owned(),
                parent: None,
                transform: Default::default(),
                kind: NodeKind::Group,
            });
        }
        assert_eq!(doc.unique_name("head"), "head-3");
    }
}
