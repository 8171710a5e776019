//! A Studio save killed at any moment (issue 14): the Studio saves through
//! [`Project::save`], which writes the scene and then its history, each atomically. A child
//! process (this test binary, run again with `DUCTILE_SAVE_LOOP` set) saves a growing history
//! over and over; it is killed with SIGKILL at moments spread over a second, and after each
//! kill the project must open: the scene whole (old or new), and the history either
//! replaying to it or, when the kill fell between the two writes, set aside with a warning
//! while the scene still opens.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use ductile_history::operation::Operation;
use ductile_io::Project;
use ductile_scene::document::NodeKind;

const LOOP_ENV: &str = "DUCTILE_SAVE_LOOP";

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name)
}

/// The child: opens the scene and saves it after every one of many edits, until killed.
fn save_loop(scene: &Path) {
    let (mut project, _) = Project::open(scene).unwrap();
    let tool = project
        .document()
        .nodes
        .iter()
        .find(|n| matches!(n.kind, NodeKind::Tool(_)))
        .unwrap()
        .name
        .clone();
    for k in 0..100_000_u32 {
        let mut t = project
            .document()
            .nodes
            .iter()
            .find(|n| n.name == tool)
            .unwrap()
            .transform;
        t.translation.x = (k % 100) as f32 * 0.001;
        if let Ok(op) = Operation::set_transform(project.document(), &tool, t) {
            let _ = project.push(op, format!("move {k}"), u64::from(k), None);
        }
        project.save().unwrap();
    }
}

#[test]
fn a_project_save_killed_at_any_moment_leaves_a_project_that_opens() {
    if let Some(scene) = std::env::var_os(LOOP_ENV) {
        save_loop(Path::new(&scene));
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("tetra.ron");
    std::fs::copy(data("tetra.obj"), dir.path().join("tetra.obj")).unwrap();
    std::fs::copy(data("tetra.ron"), &scene).unwrap();
    let mut set_aside = 0;
    for k in 0..16_u64 {
        let mut child = Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "a_project_save_killed_at_any_moment_leaves_a_project_that_opens",
                "--nocapture",
            ])
            .env(LOOP_ENV, &scene)
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(150 + 60 * k));
        child.kill().unwrap();
        child.wait().unwrap();
        let (project, warnings) = Project::open(&scene)
            .unwrap_or_else(|e| panic!("kill {k}: the project does not open: {e}"));
        assert!(
            warnings.is_empty() || project.history().is_empty(),
            "kill {k}: a warning, yet the history was kept: {warnings:?}"
        );
        set_aside += usize::from(!warnings.is_empty());
        // What a kill leaves besides the two files: at most the hidden temporary files of
        // the writes in flight.
        for entry in std::fs::read_dir(dir.path()).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            assert!(
                ["tetra.ron", "tetra.history.ron", "tetra.obj"].contains(&name.as_str())
                    || ductile_io::atomic_temporary_target(&name).is_some(),
                "kill {k}: unexpected file {name}"
            );
        }
    }
    // The saves ran (the history grew) before the kills.
    let (project, _) = Project::open(&scene).unwrap();
    assert!(
        !project.history().is_empty() || set_aside > 0,
        "no save happened before the kills"
    );
}
