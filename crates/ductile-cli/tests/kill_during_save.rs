//! A single-file command killed at any moment, in the middle of its write included, leaves
//! the file it writes either as it was or complete: never half written (issue 14). Every
//! output goes through `ductile_io::write_atomic` (a temporary file, flushed, renamed).

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use common::data;

fn apply(scene: &str, output: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ductile"));
    c.args(["apply", scene, "--output", output.to_str().unwrap()]);
    c
}

#[test]
fn apply_killed_at_any_moment_leaves_the_old_file_or_the_new_one() {
    let dir = tempfile::tempdir().unwrap();
    // The two versions of the output: the old one (the tetrahedron scene) and the new one
    // (Spot, about 3,000 vertices, so that the write itself takes a moment).
    let old_path = dir.path().join("old.glb");
    let new_path = dir.path().join("new.glb");
    assert!(
        apply(&data("tetra.ron"), &old_path)
            .status()
            .unwrap()
            .success()
    );
    let started = Instant::now();
    assert!(
        apply(&data("spot.ron"), &new_path)
            .status()
            .unwrap()
            .success()
    );
    let run = started.elapsed();
    let old = std::fs::read(&old_path).unwrap();
    let new = std::fs::read(&new_path).unwrap();
    assert_ne!(old, new);

    // Kill (SIGKILL: no chance to clean up) at moments spread over the whole run, the end
    // (the write) most densely.
    let out = dir.path().join("out.glb");
    let mut outcomes = [0_usize; 2];
    for k in 0..24_u32 {
        std::fs::write(&out, &old).unwrap();
        let at = run.mul_f64(if k < 12 {
            f64::from(k) / 12.0
        } else {
            0.75 + 0.5 * f64::from(k - 12) / 12.0
        });
        let mut child = apply(&data("spot.ron"), &out).spawn().unwrap();
        std::thread::sleep(at);
        let _ = child.kill();
        child.wait().unwrap();
        let now = std::fs::read(&out).unwrap();
        assert!(
            now == old || now == new,
            "killed after {at:?}: the output is neither the old file nor the new one ({} bytes)",
            now.len()
        );
        outcomes[usize::from(now == new)] += 1;
        // A write in flight leaves only its hidden temporary file beside the output.
        for entry in std::fs::read_dir(dir.path()).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            assert!(
                ["old.glb", "new.glb", "out.glb"].contains(&name.as_str())
                    || ductile_io::atomic_temporary_target(&name) == Some("out.glb"),
                "unexpected file {name}"
            );
        }
    }
    // The kills fell both before and after the write (else the test showed nothing).
    assert!(outcomes[0] > 0, "every kill came after the write");
}
