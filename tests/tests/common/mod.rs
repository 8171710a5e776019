//! Helpers shared by the integration tests.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_owned()
}

/// A file under `tests/data/`.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(name)
}

/// Runs the CLI in-process; returns (exit status or error message, stdout).
pub fn cli(args: &[&str]) -> (Result<u8, String>, String) {
    let mut out = Vec::new();
    let argv = std::iter::once("ductile").chain(args.iter().copied());
    let r = ductile_cli::run(argv, &mut out).map_err(|e| ductile_cli::error_message(&e));
    (r, String::from_utf8(out).expect("utf-8 output"))
}

/// The `.ron` files of a directory, sorted (empty when it does not exist).
pub fn ron_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}
