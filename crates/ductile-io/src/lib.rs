//! `ductile-io`: everything Ductile reads from and writes to disk.
//!
//! * [`scene`]: versioned RON scene files ([`load_scene`], [`save_scene`], [`check_scene`])
//!   with a migration step for old versions;
//! * [`mesh`]: mesh import from glTF (`.glb`, `.gltf`) and OBJ, with an optional `#name`
//!   selection of one part ([`load_mesh`], [`MeshRef`]);
//! * [`export`]: glTF 2.0 export ([`export_gltf`], with morph targets and weight
//!   animations [`export_gltf_with`]);
//! * [`bake`]: an animation baked as morph targets or one file per frame, variants as
//!   morph targets;
//! * [`history_file`]: versioned RON edit histories with an inline or hashed base scene
//!   ([`read_history`], [`save_history`]);
//! * [`project`]: Studio projects, a scene file with its history beside it ([`Project`]:
//!   open, save, save as with mesh sources rewritten, import, export), and the embedded
//!   default scene ([`embedded`]).
//!
//! Meshes can also be decoded from memory ([`load_rest_mesh_from_bytes`]).
//!
//! Every error is an [`IoError`] naming the file (and the scene node). Every file is written
//! atomically ([`write_atomic`]): a failed write never leaves a half-written file.

pub mod bake;
pub mod embedded;
pub mod error;
pub mod export;
pub mod gltf_buffers;
pub mod history_file;
pub mod mesh;
pub mod project;
pub mod scene;

use std::io::Write as _;
use std::path::Path;

pub use error::{IoError, Result, report};
pub use export::{
    ExportMesh, MorphTarget, Morphs, Sampling, WeightsAnimation, WeightsTrack, export_gltf,
    export_gltf_with,
};
pub use history_file::{
    Base, LoadedHistory, SaveBase, document_hash, is_history_file, is_history_text, read_history,
    save_history,
};
pub use mesh::{
    MeshFormat, MeshRef, load_mesh, load_mesh_from_bytes, load_rest_mesh, load_rest_mesh_from_bytes,
};
pub use project::{
    EmbeddedMesh, ImportedMesh, Project, ProjectWarning, history_path_for, scene_path_for,
};
pub use scene::{
    LoadedMesh, LoadedScene, check_scene, load_scene, parse_scene, read_scene, save_scene,
};

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, flushed
/// to disk, then renamed over `path`. On any error the temporary file is removed and `path`
/// is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let err = |source| IoError::Write {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}
