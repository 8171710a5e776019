//! `ductile apply` end to end: scene in, glTF out, output loads back.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use common::{cli, data, ron_files, root};
use ductile_io::{MeshRef, load_mesh, load_scene};

/// Applies `scene` into a temporary `.glb` and checks the output against the scene's meshes:
/// same vertex count, indices and UVs, deformed positions equal to the stack's evaluation.
fn apply_and_reload(scene: &std::path::Path) -> Vec<(usize, bool)> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let (r, stdout) = cli(&[
        "apply",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r, Ok(0), "{}: {stdout}", scene.display());
    let loaded = load_scene(scene).unwrap();
    assert!(stdout.contains("wrote"), "{stdout}");
    let mut moved = Vec::new();
    for m in &loaded.meshes {
        assert!(stdout.contains(&format!("mesh '{}'", m.name)), "{stdout}");
        let back = load_mesh(&MeshRef {
            path: out.clone(),
            select: Some(m.name.clone()),
        })
        .unwrap();
        let rest = m.rest.mesh();
        let expected = loaded.evaluate(&m.name).unwrap();
        // The rest mesh's indices and UVs, or the refined ones when a layer refined it.
        assert_eq!(back.indices, expected.indices(&m.rest), "{}", m.name);
        assert_eq!(back.uvs.as_deref(), expected.uvs(&m.rest), "{}", m.name);
        if expected.refined.is_none() {
            assert_eq!(back.indices, rest.indices, "{}", m.name);
        }
        assert_eq!(back.positions, expected.positions, "{}", m.name);
        let normals = back.normals.expect("apply writes normals");
        assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
        moved.push((back.positions.len(), back.positions != rest.positions));
    }
    moved
}

#[test]
fn apply_tetra_moves_the_apex() {
    let moved = apply_and_reload(&data("tetra.ron"));
    assert_eq!(moved, vec![(6, true)]);
}

#[test]
fn apply_spot_scene_deforms_and_keeps_attributes() {
    let moved = apply_and_reload(&data("spot.ron"));
    assert_eq!(moved, vec![(3225, true)]);
}

#[test]
fn apply_every_shipped_scene() {
    // New demo scenes under scenes/ are covered automatically.
    for scene in ron_files(&root().join("scenes")) {
        let (r, out) = cli(&["check", scene.to_str().unwrap()]);
        assert_eq!(r, Ok(0), "{}: {out}", scene.display());
        apply_and_reload(&scene);
    }
}

#[test]
fn apply_writes_gltf_json_too() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tetra.gltf");
    let (r, _) = cli(&[
        "apply",
        data("tetra.ron").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r, Ok(0));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("data:application/octet-stream;base64,"));
    assert_eq!(
        load_mesh(&MeshRef::parse(out.to_str().unwrap()))
            .unwrap()
            .positions
            .len(),
        6
    );
}

#[test]
fn default_output_is_the_scene_stem_in_the_current_directory() {
    let p = ductile_cli::commands::apply::default_output(std::path::Path::new("a/b/face.ron"));
    assert_eq!(p, std::path::PathBuf::from("face.glb"));
}

#[test]
fn failed_apply_leaves_the_old_output_and_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    std::fs::write(&out, b"old").unwrap();
    // A scene that fails to load.
    let bad = data("malformed/unknown-tool.ron");
    let (r, _) = cli(&["apply", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let msg = r.unwrap_err();
    assert!(msg.contains("tool 'push' does not exist"), "{msg}");
    // Unsupported output extension: refused before anything is written.
    let txt = dir.path().join("out.txt");
    let (r, _) = cli(&[
        "apply",
        data("tetra.ron").to_str().unwrap(),
        "-o",
        txt.to_str().unwrap(),
    ]);
    assert!(r.unwrap_err().contains("unsupported file extension 'txt'"));
    // An export that fails half-way (non-finite data) writes nothing either.
    let nan = glam::Vec3::new(f32::NAN, 0.0, 0.0);
    let positions = [glam::Vec3::ZERO, glam::Vec3::X, nan];
    let mesh = ductile_io::ExportMesh {
        name: "bad",
        positions: &positions,
        normals: None,
        uvs: None,
        indices: std::borrow::Cow::Borrowed(&[0, 1, 2]),
    };
    let err = ductile_io::export_gltf(&out, &[mesh])
        .unwrap_err()
        .to_string();
    assert!(err.contains("not finite"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.glb")]);
}

#[test]
fn info_reports_counts_and_accepts_a_name_suffix() {
    let (r, out) = cli(&["info", data("tetra.obj").to_str().unwrap()]);
    assert_eq!(r, Ok(0));
    assert!(out.contains("stored vertices: 6"), "{out}");
    assert!(out.contains("welded vertices: 4"), "{out}");
    assert!(out.contains("triangles:       4"), "{out}");
    let spec = format!("{}#tetra", data("tetra.obj").display());
    assert_eq!(cli(&["info", &spec]).0, Ok(0));
    let spec = format!("{}#nothing", data("tetra.obj").display());
    let msg = cli(&["info", &spec]).0.unwrap_err();
    assert!(
        msg.contains("no OBJ object or group named 'nothing' (available: tetra)"),
        "{msg}"
    );
}

#[test]
fn apply_exports_a_refined_mesh() {
    // The sketch demo with adaptive refinement forced on: the output has the rest vertices
    // plus the split-edge vertices, and its own index buffer.
    let scene = data("sketch-refine.ron");
    let rest = load_scene(&scene).unwrap().meshes[0]
        .rest
        .mesh()
        .positions
        .len();
    let out = apply_and_reload(&scene);
    assert_eq!(out.len(), 1);
    assert!(
        out[0].0 > rest,
        "{} vertices after refinement, {rest} before",
        out[0].0
    );
    assert!(out[0].1);
}

#[test]
fn makehuman_body_is_selected_by_name() {
    let all = root().join("assets/meshes/makehuman-base.obj");
    if !all.exists() {
        return;
    }
    let body = load_mesh(&MeshRef::parse(&format!("{}#body", all.display()))).unwrap();
    let whole = load_mesh(&MeshRef::parse(all.to_str().unwrap())).unwrap();
    assert!(body.triangle_count() > 1000);
    assert!(body.triangle_count() < whole.triangle_count());
}

#[test]
fn bench_prints_min_median_max() {
    let (r, out) = cli(&[
        "bench",
        data("tetra.ron").to_str().unwrap(),
        "--iterations",
        "3",
        "--threads",
        "2",
    ]);
    assert_eq!(r, Ok(0));
    assert!(out.contains("3 iterations, 2 threads"), "{out}");
    assert!(
        out.contains("mesh 'tetra' (4 vertices, 1 layers): resolve "),
        "{out}"
    );
    assert!(out.contains("median"), "{out}");
    let (r, _) = cli(&[
        "bench",
        data("tetra.ron").to_str().unwrap(),
        "--iterations",
        "0",
    ]);
    assert!(r.is_err());
    // Issue 14: a thread count no machine has is refused, not attempted.
    for threads in ["4294967295", "1025", "0"] {
        let (r, _) = cli(&[
            "bench",
            data("tetra.ron").to_str().unwrap(),
            "--threads",
            threads,
        ]);
        assert!(r.is_err(), "--threads {threads} was accepted");
    }
}
