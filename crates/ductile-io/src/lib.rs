//! `ductile-io`: everything Ductile reads from and writes to disk.
//!
//! * [`scene`]: versioned RON scene files ([`load_scene`], [`save_scene`], [`check_scene`])
//!   with a migration step for old versions;
//! * [`mesh`]: mesh import from glTF (`.glb`, `.gltf`) and OBJ, with an optional `#name`
//!   selection of one part ([`load_mesh`], [`MeshRef`]);
//! * [`export`]: glTF 2.0 export ([`export_gltf`]).
//!
//! Every error is an [`IoError`] naming the file (and the scene node). Every file is written
//! atomically ([`write_atomic`]): a failed write never leaves a half-written file.

pub mod error;
pub mod export;
pub mod mesh;
pub mod scene;

use std::io::Write as _;
use std::path::Path;

pub use error::{IoError, Result, report};
pub use export::{ExportMesh, export_gltf};
pub use mesh::{MeshRef, load_mesh, load_rest_mesh};
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
