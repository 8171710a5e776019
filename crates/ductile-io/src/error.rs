//! The error type of `ductile-io`.
//!
//! Every variant names the file concerned (and, inside a scene, the node), and its message is
//! complete on one line: the typed cause is kept as [`std::error::Error::source`] for
//! programs, but the message already contains its text, so printing only the top error is
//! enough. [`report`] prints a chain without repeating what an outer message already says.

use std::path::PathBuf;

use ductile_core::error::CoreError;
use ductile_scene::error::SceneError;
use thiserror::Error;

/// Everything that can go wrong reading or writing Ductile files.
#[derive(Debug, Error)]
pub enum IoError {
    /// A file could not be read (missing, unreadable, not UTF-8, ...).
    #[error("{}: cannot read the file: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A file could not be written (or the temporary file could not be moved into place).
    #[error("{}: cannot write the file: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The RON text is malformed or does not match the scene format (unknown field, wrong
    /// type, missing field, ...). Line and column are 1-based.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Ron {
        /// The file.
        path: PathBuf,
        /// Line of the problem (1-based).
        line: usize,
        /// Column of the problem (1-based).
        column: usize,
        /// RON's description of the problem.
        message: String,
    },
    /// A scene file has no `version` field.
    #[error(
        "{}: the scene file has no `version` field (supported versions: {})",
        path.display(),
        list(SUPPORTED_VERSIONS)
    )]
    MissingVersion {
        /// The file.
        path: PathBuf,
    },
    /// A scene file has a version this build cannot read.
    #[error(
        "{}: scene format version {found} is not supported (supported versions: {})",
        path.display(),
        list(SUPPORTED_VERSIONS)
    )]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// The version found.
        found: u64,
    },
    /// A file extension this operation does not handle.
    #[error("{}: unsupported file extension '{extension}' (expected {expected})", path.display())]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
        /// The extension found (empty when there is none).
        extension: String,
        /// The extensions accepted, in words.
        expected: &'static str,
    },
    /// The glTF file could not be decoded.
    #[error("{}: invalid glTF: {}", path.display(), gltf_problem(source))]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        source: gltf::Error,
    },
    /// The glTF file is structurally invalid in a way the decoder does not check.
    #[error("{}: invalid glTF: {problem}", path.display())]
    GltfStructure {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// A glTF primitive lacks data the importer needs.
    #[error("{}: glTF mesh '{mesh}', primitive {primitive}: {problem}", path.display())]
    GltfPrimitive {
        /// The file.
        path: PathBuf,
        /// The glTF mesh (name or index).
        mesh: String,
        /// Primitive number in the mesh.
        primitive: usize,
        /// What is wrong.
        problem: String,
    },
    /// A line of an OBJ file that cannot be decoded: its number (from 1), its text and why.
    #[error("{}:{line}: invalid OBJ line `{text}`: {problem}", path.display())]
    ObjLine {
        /// The file.
        path: PathBuf,
        /// Line number, from 1.
        line: usize,
        /// The line (cut to 80 characters).
        text: String,
        /// What is wrong with it.
        problem: String,
    },
    /// The OBJ file could not be decoded (and no single line could be blamed).
    #[error("{}: invalid OBJ: {source}", path.display())]
    Obj {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        source: tobj::LoadError,
    },
    /// A `#name` selection names no object/group (OBJ) or mesh (glTF) of the file.
    #[error(
        "{}: there is no {kind} named '{name}' (available: {})",
        path.display(),
        if available.is_empty() { "none".to_owned() } else { available.join(", ") }
    )]
    NoSuchPart {
        /// The file.
        path: PathBuf,
        /// "OBJ object or group" or "glTF mesh".
        kind: &'static str,
        /// The name asked for.
        name: String,
        /// The names the file has.
        available: Vec<String>,
    },
    /// The file (or the selected part) contains no triangles.
    #[error("{}: the mesh is empty ({vertices} vertices, no triangles)", path.display())]
    EmptyMesh {
        /// The file.
        path: PathBuf,
        /// Vertices found.
        vertices: usize,
    },
    /// The imported mesh is not usable (indices out of range, non-finite positions, every
    /// triangle degenerate, ...). Core's message already starts with the file name.
    #[error("{source}")]
    InvalidMesh {
        /// The file.
        path: PathBuf,
        /// Core's validation error.
        source: CoreError,
    },
    /// A mesh node's source could not be loaded.
    #[error("{}: mesh node '{node}': cannot load '{}': {source}", scene.display(), mesh.display())]
    MeshNode {
        /// The scene file.
        scene: PathBuf,
        /// The mesh node.
        node: String,
        /// The resolved mesh path (with its `#name` selection, if any).
        mesh: PathBuf,
        /// Why loading failed.
        source: Box<IoError>,
    },
    /// The scene document has problems (every one found by `Document::problems`).
    #[error("{}: {}", path.display(), problems.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// Every problem found.
        problems: Vec<SceneError>,
    },
    /// One problem of a scene found while resolving or evaluating a mesh's stack.
    #[error("{}: {source}", path.display())]
    SceneProblem {
        /// The scene file.
        path: PathBuf,
        /// The problem.
        source: SceneError,
    },
    /// A mesh cannot be evaluated at a time of the animation.
    #[error("{}: mesh '{mesh}' at {time} s: {source}", path.display())]
    MeshAtTime {
        /// The scene file.
        path: PathBuf,
        /// The mesh node.
        mesh: String,
        /// The time (seconds).
        time: f32,
        /// The problem.
        source: Box<SceneError>,
    },
    /// An animation or variants cannot be baked or exported as asked (a range outside the
    /// timeline, too many morph targets, a refining layer, no variants, ...).
    #[error("{}: {problem}", path.display())]
    Bake {
        /// The scene file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// A mesh cannot be exported (non-finite positions, too large, ...).
    #[error("{}: cannot export mesh '{mesh}': {problem}", path.display())]
    Export {
        /// The output file.
        path: PathBuf,
        /// The mesh.
        mesh: String,
        /// What is wrong.
        problem: String,
    },
    /// A history file has no `version` field.
    #[error(
        "{}: the history file has no `version` field (supported versions: {})",
        path.display(),
        list(crate::history_file::SUPPORTED_HISTORY_VERSIONS)
    )]
    MissingHistoryVersion {
        /// The file.
        path: PathBuf,
    },
    /// A history file has a version this build cannot read.
    #[error(
        "{}: history format version {found} is not supported (supported versions: {})",
        path.display(),
        list(crate::history_file::SUPPORTED_HISTORY_VERSIONS)
    )]
    UnsupportedHistoryVersion {
        /// The file.
        path: PathBuf,
        /// The version found.
        found: u64,
    },
    /// A version 1 history file holds an operation that came with version 2 (keys, the
    /// timeline, variants): the file's version is wrong, or it was edited by hand.
    #[error(
        "{}: step {step} is a {operation} operation, which came with history version 2; \
         a version 1 file cannot hold it (set `version: 2` if the file is otherwise right)",
        path.display()
    )]
    OperationTooNew {
        /// The file.
        path: PathBuf,
        /// The step (1-based).
        step: usize,
        /// The operation's name as written in the file.
        operation: &'static str,
    },
    /// The scene a history file refers to as its base is not the one the history was
    /// recorded on (its document's hash differs).
    #[error(
        "{}: the base scene {} does not match this history (its document hash is {found}, the history was recorded on {expected}); the scene was changed after the history was saved",
        path.display(),
        scene.display()
    )]
    BaseMismatch {
        /// The history file.
        path: PathBuf,
        /// The referenced scene file.
        scene: PathBuf,
        /// The hash recorded in the history.
        expected: String,
        /// The hash of the scene's document now.
        found: String,
    },
    /// A step of a history cannot be applied (or a step asked for does not exist).
    #[error("{}: {source}", path.display())]
    History {
        /// The history file.
        path: PathBuf,
        /// The history's error (it names the step).
        source: ductile_history::error::HistoryError,
    },
    /// A project that has no scene file yet was asked to save in place (use "save as").
    #[error("{}: the project has no file yet: choose where to save it (save as)", name.display())]
    NoProjectFile {
        /// The name the project is known by.
        name: PathBuf,
    },
}

/// The scene format versions this build reads.
pub const SUPPORTED_VERSIONS: &[u64] = &[1, 2];

/// The decoder's message without its own "invalid glTF:" prefix (which its validation errors
/// carry and the others do not), so that the message says it once: each validation problem
/// as `path: problem`, separated by semicolons.
fn gltf_problem(error: &gltf::Error) -> String {
    match error {
        gltf::Error::Validation(problems) => problems
            .iter()
            .map(|(path, problem)| format!("{path}: {problem}"))
            .collect::<Vec<_>>()
            .join("; "),
        other => other.to_string(),
    }
}

fn list(versions: &[u64]) -> String {
    versions
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Shorthand for results in this crate.
pub type Result<T, E = IoError> = std::result::Result<T, E>;

/// The error and its causes on one line, separated by `": "`, leaving out any cause whose
/// text the message before it already contains.
#[must_use]
pub fn report(error: &(dyn std::error::Error + 'static)) -> String {
    let mut out = error.to_string();
    let mut last = out.clone();
    let mut cause = error.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !last.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        last = text;
        cause = c.source();
    }
    out
}
