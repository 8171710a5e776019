//! The `ductile-studio` binary's command line: help, and bad input refused with a clear
//! error that names the file or argument, before any window opens (so these run without a
//! display).

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap (house rules).

use std::process::{Command, Output};

fn studio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ductile-studio"))
        .args(args)
        // No display: a run that got past the checks would fail to open a window instead.
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}

/// Runs the Studio with `args`, checks that it refuses them, and returns what it printed on
/// stderr.
fn refused(args: &[&str]) -> String {
    let out = studio(args);
    assert!(!out.status.success(), "{args:?} was accepted");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn help_lists_the_options_and_credits_the_head() {
    let out = studio(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for option in ["--scene", "--screenshot", "--frames", "--size", "--select"] {
        assert!(text.contains(option), "--help lacks {option}:\n{text}");
    }
    assert!(
        text.contains("Lee Perry-Smith") && text.contains("CC BY 3.0"),
        "{text}"
    );
}

#[test]
fn a_missing_scene_is_refused_with_its_path() {
    let err = refused(&["--scene", "no/such/scene.ron"]);
    assert!(err.contains("no/such/scene.ron"), "{err}");
}

#[test]
fn a_malformed_scene_is_refused_with_its_path_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.ron");
    std::fs::write(&path, "(\n    version: 1,\n    nodes: [ (name: 3) ],\n)\n").unwrap();
    let err = refused(&["--scene", path.to_str().unwrap()]);
    assert!(
        err.contains("broken.ron:3:"),
        "the error names the file and line: {err}"
    );
}

#[test]
fn a_bad_window_size_is_refused() {
    let err = refused(&["--size", "10x10"]);
    assert!(err.contains("10x10") && err.contains("200..=8192"), "{err}");
}

#[test]
fn a_screenshot_into_a_missing_directory_is_refused_before_the_window() {
    let err = refused(&["--screenshot", "/no/such/dir/out.png"]);
    assert!(err.contains("/no/such/dir"), "{err}");
}

#[test]
fn a_screenshot_must_be_a_png() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.jpg");
    let err = refused(&["--screenshot", path.to_str().unwrap()]);
    assert!(err.contains(".png"), "{err}");
}
