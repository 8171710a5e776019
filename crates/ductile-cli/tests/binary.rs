//! The `ductile` binary itself: exit statuses and `error:` lines on stderr.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use std::process::Command;

use common::data;

fn ductile(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ductile"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

#[test]
fn check_exits_0_on_a_good_scene_and_1_on_a_bad_one() {
    let (code, out, _) = ductile(&["check", &data("tetra.ron")]);
    assert_eq!((code, out.as_str()), (0, "ok\n"));
    let (code, out, _) = ductile(&["check", &data("malformed/theta-zero.ron")]);
    assert_eq!(code, 1);
    assert!(out.contains("theta = 0 is out of range"), "{out}");
}

#[test]
fn errors_go_to_stderr_with_an_error_prefix() {
    let (code, out, err) = ductile(&["apply", "no-such-scene.ron"]);
    assert_eq!(code, 1);
    assert!(out.is_empty());
    assert!(
        err.starts_with(
            "error: cannot load scene no-such-scene.ron: no-such-scene.ron: cannot read the file"
        ),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn usage_errors_exit_2_and_help_exits_0() {
    assert_eq!(ductile(&["frobnicate"]).0, 2);
    let (code, out, _) = ductile(&["--help"]);
    assert_eq!(code, 0);
    for sub in ["apply", "check", "info", "bench"] {
        assert!(out.contains(sub), "{out}");
    }
}
