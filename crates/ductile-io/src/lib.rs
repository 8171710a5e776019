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
//!   default scene ([`embedded`]);
//! * [`recovery`]: the Studio's autosave of unsaved work and its recovery after a crash.
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
pub mod recovery;
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
    MeshFormat, MeshPart, MeshRef, load_mesh, load_mesh_from_bytes, load_rest_mesh,
    load_rest_mesh_from_bytes, mesh_parts,
};
pub use project::{
    EmbeddedMesh, ImportedMesh, Project, ProjectWarning, history_path_for, scene_path_for,
};
pub use scene::{
    LoadedMesh, LoadedScene, check_history, check_scene, load_scene, parse_scene, read_scene,
    save_scene,
};

/// The most bytes Ductile reads from one scene, history or mesh file: 4 GiB, far above a
/// real file (a ten-million-vertex mesh with normals, UVs and indices takes about 0.5 GB).
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Reads the whole of the regular file `path`, refusing anything else before opening it: a
/// FIFO would block the open forever, a device such as `/dev/zero` would be read until
/// memory runs out, a folder cannot be read. A file larger than [`MAX_FILE_BYTES`] is
/// refused too. Scene, history and mesh files are all read through here, so a hostile
/// scene naming `/dev/zero` as its mesh or base gets an error, not a hang.
///
/// # Errors
/// The operating system's error, or [`std::io::ErrorKind::InvalidInput`] naming what the
/// path is when it is not a regular file or is too large.
pub fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    read_limited(path, MAX_FILE_BYTES)
}

/// The most bytes of one scene or history file: 512 MiB. Parsing RON text takes several
/// times its size in memory; real files are far smaller (the 45-macro identikit scene is
/// 46 KB, the character artist's six-step history with two sketch tools 15 KB).
pub const MAX_TEXT_BYTES: u64 = 512 << 20;

/// [`read_file`] as UTF-8 text (scene and history files), at most [`MAX_TEXT_BYTES`].
///
/// # Errors
/// As [`read_file`] (with the smaller limit), and [`std::io::ErrorKind::InvalidData`] when
/// the file is not UTF-8.
pub fn read_text_file(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read_limited(path, MAX_TEXT_BYTES)?).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "the file is not UTF-8 text (byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// [`read_file`] with the size limit `limit`, checked before reading (from the file's
/// metadata) and while reading (the file may grow).
fn read_limited(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        return Err(not_regular(kind));
    }
    let mut file = std::fs::File::open(path)?;
    // The path may have been swapped between the two calls: check the open file itself.
    let meta = file.metadata()?;
    if !meta.file_type().is_file() {
        return Err(not_regular(meta.file_type()));
    }
    let too_large = |size: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("the file holds {size} bytes, more than the limit of {limit}"),
        )
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::new();
    (&mut file).take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

fn not_regular(kind: std::fs::FileType) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("it is {}, not a regular file", file_kind(kind)),
    )
}

/// What a file that is not a regular file is, in words.
fn file_kind(kind: std::fs::FileType) -> &'static str {
    if kind.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if kind.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, flushed
/// to disk, then renamed over `path`, and the directory flushed so the rename survives a
/// crash. On any error the temporary file is removed and `path` is untouched.
///
/// Like a careful editor: an existing file keeps its permissions, a new one gets the
/// permissions any new file gets (read-write for all, less the umask) rather than the
/// temporary file's private 0600; a symbolic link at `path` stays a link and the file it
/// points to is replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let err = |source| IoError::Write {
        path: path.to_owned(),
        source,
    };
    // Write through a symbolic link (one that dangles names the file to create).
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            let link = std::fs::read_link(path).map_err(err)?;
            match path.parent() {
                Some(dir) if link.is_relative() => dir.join(link),
                _ => link,
            }
        }
        _ => path.to_owned(),
    };
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let existing = std::fs::metadata(&target).ok().map(|m| m.permissions());
    let file_name = target
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy());
    let mut tmp = temporary_in(dir, &file_name).map_err(err)?;
    if let Some(permissions) = existing {
        tmp.as_file().set_permissions(permissions).map_err(err)?;
    }
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(&target).map_err(|e| err(e.error))?;
    // The rename is durable only once the directory is flushed. Some file systems refuse to
    // open or sync a directory; the data itself is already on disk then.
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// The number of random characters in the name of [`write_atomic`]'s temporary file.
const TEMPORARY_RANDOM_CHARS: usize = 6;

/// A new temporary file in `dir` for the file called `file_name` there: `.NAME.XXXXXX.tmp`,
/// hidden and recognisable after a crash ([`atomic_temporary_target`]), created with the
/// permissions any new file gets (0666 less the umask) rather than 0600.
fn temporary_in(dir: &Path, file_name: &str) -> std::io::Result<tempfile::NamedTempFile> {
    let prefix = format!(".{file_name}.");
    let mut builder = tempfile::Builder::new();
    builder
        .prefix(&prefix)
        .suffix(".tmp")
        .rand_bytes(TEMPORARY_RANDOM_CHARS);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir)
}

/// The name of the file that a temporary file of [`write_atomic`] was to become, from the
/// temporary file's name (`.NAME.XXXXXX.tmp` → `NAME`), or `None` for any other name. A
/// process killed while writing leaves such a file beside the output; a later run may remove
/// it.
#[must_use]
pub fn atomic_temporary_target(name: &str) -> Option<&str> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (target, random) = inner.rsplit_once('.')?;
    (!target.is_empty()
        && random.len() == TEMPORARY_RANDOM_CHARS
        && random.chars().all(|c| c.is_ascii_alphanumeric()))
    .then_some(target)
}

#[cfg(all(test, unix))]
mod tests {
    use std::os::unix::fs::PermissionsExt as _;

    use super::{atomic_temporary_target, write_atomic};

    #[test]
    fn temporary_files_name_their_target() {
        assert_eq!(
            atomic_temporary_target(".head.glb.a1B2c3.tmp"),
            Some("head.glb")
        );
        assert_eq!(atomic_temporary_target(".a.b.c.x1y2z3.tmp"), Some("a.b.c"));
        for other in [
            "head.glb",
            ".head.glb.tmp",
            ".head.glb.abc.tmp",
            "..x1y2z3.tmp",
            ".h.x1y2z!.tmp",
        ] {
            assert_eq!(atomic_temporary_target(other), None, "{other}");
        }
        // What write_atomic leaves while it writes is recognised.
        let dir = tempfile::tempdir().unwrap();
        let tmp = super::temporary_in(dir.path(), "scene.ron").unwrap();
        let name = tmp.path().file_name().unwrap().to_str().unwrap().to_owned();
        assert_eq!(atomic_temporary_target(&name), Some("scene.ron"), "{name}");
    }

    fn mode(p: &std::path::Path) -> u32 {
        std::fs::metadata(p).unwrap().permissions().mode() & 0o7777
    }

    #[test]
    fn a_new_file_gets_the_permissions_of_any_new_file() {
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain");
        std::fs::write(&plain, b"x").unwrap();
        let ours = dir.path().join("ours.glb");
        write_atomic(&ours, b"data").unwrap();
        assert_eq!(
            mode(&ours),
            mode(&plain),
            "not the umask's mode (0600 before)"
        );
    }

    #[test]
    fn an_existing_file_keeps_its_permissions() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("shared.ron");
        std::fs::write(&p, b"old").unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(mode(&p), 0o640);
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
    }

    #[test]
    fn a_symbolic_link_stays_and_its_target_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.glb");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.glb");
        std::os::unix::fs::symlink("real.glb", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
    }
}
