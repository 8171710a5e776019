//! Crash recovery: the Studio's autosave of the live history, and what the next start finds.
//!
//! While a project has unsaved edits, the Studio writes its whole history (base document
//! inline, every step, the cursor) to a recovery file, a history file like any other
//! (`docs/history-format.md`), atomically ([`crate::write_atomic`]): a crash or a kill
//! during the write leaves the previous recovery file whole. Saving the project, or
//! closing the Studio normally, removes the file. A recovery file that is still there at the
//! next start is what an unclean exit left; the Studio offers to restore it.
//!
//! Recovery files live in one folder ([`recovery_dir`]), one per project, named after the
//! project and a hash of the path it was opened from ([`recovery_path`]), so that two
//! projects never share one. Mesh sources stay as the project wrote them: a recovered
//! history is handed back to the project it came from, which resolves them as before.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use ductile_history::history::History;
use ductile_scene::document::Document;

use crate::history_file::{SaveBase, read_history, save_history};
use crate::project::{Project, restore};
use crate::{IoError, Result};

/// The environment variable that overrides the recovery folder (tests use it).
pub const RECOVERY_DIR_ENV: &str = "DUCTILE_RECOVERY_DIR";

/// The folder recovery files are written to: `$DUCTILE_RECOVERY_DIR`, else
/// `$XDG_STATE_HOME/ductile/recovery`, else `~/.local/state/ductile/recovery` (the XDG base
/// directory rule for state that should survive a restart), else the system's temporary
/// folder.
#[must_use]
pub fn recovery_dir() -> PathBuf {
    let env = |name: &str| {
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    if let Some(dir) = env(RECOVERY_DIR_ENV) {
        return dir;
    }
    if let Some(state) = env("XDG_STATE_HOME") {
        return state.join("ductile/recovery");
    }
    if let Some(home) = env("HOME") {
        return home.join(".local/state/ductile/recovery");
    }
    std::env::temp_dir().join("ductile-recovery")
}

/// The recovery file of `project` in [`recovery_dir`]: the project's name, then the first
/// 16 hex digits of the BLAKE3 hash of the absolute path it was opened from (or of its name,
/// for a project never saved), then `.recovery.history.ron`.
#[must_use]
pub fn recovery_path(project: &Project) -> PathBuf {
    let origin = project.origin();
    let absolute = std::path::absolute(origin).unwrap_or_else(|_| origin.to_owned());
    let hash = blake3::hash(absolute.to_string_lossy().as_bytes()).to_hex();
    let stem = project.display_name();
    let stem = stem.strip_suffix(".ron").unwrap_or(&stem);
    let stem: String = stem
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    recovery_dir().join(format!("{stem}-{}.recovery.history.ron", &hash[..16]))
}

/// Writes `history` (its base inline, its cursor kept) to the recovery file `path`,
/// atomically, creating the folder if needed.
///
/// # Errors
/// The folder cannot be created or the file cannot be written.
pub fn write_recovery(path: &Path, history: &History) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| IoError::Write {
            path: dir.to_owned(),
            source,
        })?;
    }
    save_history(path, history, SaveBase::Inline)
}

/// A recovery file left by a session that did not close normally.
#[derive(Debug, Clone, PartialEq)]
pub struct FoundRecovery {
    /// The file.
    pub path: PathBuf,
    /// When it was last written.
    pub written: SystemTime,
    /// The steps of its history.
    pub steps: usize,
}

/// The recovery file at `path`, if there is one that reads as a history.
#[must_use]
pub fn find_recovery(path: &Path) -> Option<FoundRecovery> {
    let written = std::fs::metadata(path).ok()?.modified().ok()?;
    let loaded = read_history(path).ok()?;
    Some(FoundRecovery {
        path: path.to_owned(),
        written,
        steps: loaded.history.len(),
    })
}

/// Reads the recovery file `path`: the history (cursor as saved) and the document at its
/// cursor, every step replayed and checked.
///
/// # Errors
/// The file cannot be read, is not a history, or a step does not replay.
pub fn read_recovery(path: &Path) -> Result<(History, Document)> {
    restore(read_history(path)?)
}

/// Removes the recovery file `path` (after a save or a normal exit); nothing to do when
/// there is none.
///
/// # Errors
/// The file exists and cannot be removed.
pub fn discard_recovery(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(IoError::Write {
            path: path.to_owned(),
            source: e,
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_history_written_for_recovery_reads_back_at_its_cursor() {
        let dir = tempfile::tempdir().unwrap();
        let mut project = Project::embedded_default().unwrap();
        let doc = project.document().clone();
        let name = doc
            .nodes
            .iter()
            .find(|n| matches!(n.kind, ductile_scene::document::NodeKind::Macro(_)))
            .unwrap()
            .name
            .clone();
        for v in [0.3, 0.6, 0.9] {
            let op = ductile_history::operation::Operation::set_macro_value(
                project.document(),
                &name,
                v,
            )
            .unwrap();
            project.push(op, format!("set {v}"), 0, None).unwrap();
        }
        project.undo().unwrap();
        let path = dir.path().join("r/head.recovery.history.ron");
        write_recovery(&path, project.history()).unwrap();
        let found = find_recovery(&path).unwrap();
        assert_eq!(found.steps, 3);
        let (history, document) = read_recovery(&path).unwrap();
        assert_eq!(&history, project.history());
        assert_eq!(&document, project.document());
        discard_recovery(&path).unwrap();
        assert!(find_recovery(&path).is_none());
        discard_recovery(&path).unwrap();
    }

    #[test]
    fn projects_from_different_files_get_different_recovery_files() {
        let a = Project::embedded_default().unwrap();
        let b = Project::new_empty();
        assert_ne!(recovery_path(&a), recovery_path(&b));
        assert!(
            recovery_path(&a)
                .file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("identikit-head-")
        );
    }
}
