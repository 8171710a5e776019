//! Studio projects (`ductile_io::project`): opening scenes and histories, saving a scene with
//! its history elsewhere and reopening it (mesh sources rewritten, undo still works), the
//! embedded default head, loading meshes from memory, and errors that name the file.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::path::{Path, PathBuf};

use ductile_history::operation::Operation;
use ductile_io::project::normalize;
use ductile_io::{
    IoError, MeshFormat, MeshRef, Project, ProjectWarning, embedded, load_mesh,
    load_mesh_from_bytes, load_rest_mesh_from_bytes,
};
use ductile_scene::document::{Document, NodeKind};
use ductile_scene::transform::Transform;
use glam::Vec3;

/// Two tetrahedra, objects `a` and `b`.
const PARTS_OBJ: &str = "o a
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
o b
v 3 0 0
v 4 0 0
v 3 1 0
v 3 0 1
f 5 7 6
f 5 6 8
f 5 8 7
f 6 7 8
";

/// One tetrahedron.
const TETRA_OBJ: &str = "o tetra
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 2
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
";

/// A scene whose mesh selects object `a` of `meshes/parts.obj`.
const SCENE: &str = r#"(
    version: 1,
    nodes: [
        (name: "body", kind: Mesh((source: "meshes/parts.obj#a", stack: [(tool: "pull")]))),
        (
            name: "pull",
            parent: Some("body"),
            kind: Tool(Ffsd((points: [(position: (0.0, 0.0, 1.5), gamma: 0.5, alpha: 2.0, epsilon: 0.5)]))),
        ),
    ],
)"#;

/// A temporary directory laid out as `src/scene.ron`, `src/meshes/parts.obj`,
/// `extra/tetra.obj`.
fn layout() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let root = normalize(dir.path());
    std::fs::create_dir_all(root.join("src/meshes")).unwrap();
    std::fs::create_dir_all(root.join("extra")).unwrap();
    std::fs::write(root.join("src/meshes/parts.obj"), PARTS_OBJ).unwrap();
    std::fs::write(root.join("extra/tetra.obj"), TETRA_OBJ).unwrap();
    std::fs::write(root.join("src/scene.ron"), SCENE).unwrap();
    (dir, root)
}

fn source(doc: &Document, node: &str) -> String {
    doc.mesh(node).unwrap().source.clone()
}

fn moved(doc: &Document, node: &str, by: f32) -> Operation {
    let t = Transform {
        translation: Vec3::new(by, 0.0, 0.0),
        ..Transform::default()
    };
    Operation::set_transform(doc, node, t).unwrap()
}

/// Opens `src/scene.ron` and records five steps (a move, two imports, removing the first
/// import, a layer weight), then undoes the last one (a redo tail of one step).
fn edited(root: &Path) -> Project {
    let (mut p, warnings) = Project::open(root.join("src/scene.ron")).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(p.history().len(), 0);
    let op = moved(p.document(), "pull", 0.1);
    p.push(op, "move", 1, None).unwrap();
    for _ in 0..2 {
        let imported = p.import_mesh(root.join("extra/tetra.obj")).unwrap();
        let op = Operation::add_node(p.document(), imported.node);
        p.push(op, "import", 2, None).unwrap();
    }
    assert_eq!(source(p.document(), "tetra"), "../extra/tetra.obj");
    assert_eq!(source(p.document(), "tetra-2"), "../extra/tetra.obj");
    let op = Operation::remove_node(p.document(), "tetra").unwrap();
    p.push(op, "remove", 3, None).unwrap();
    let op = Operation::set_layer_weight(p.document(), "body", 0, 0.5).unwrap();
    p.push(op, "weight", 4, None).unwrap();
    assert!(p.undo().unwrap());
    assert_eq!(p.history().cursor(), 4);
    p
}

#[test]
fn save_as_elsewhere_rewrites_sources_and_reopens_with_a_working_history() {
    let (_dir, root) = layout();
    let mut p = edited(&root);
    assert!(p.is_modified());
    let target = root.join("out/deep/copy.ron");
    std::fs::create_dir_all(target.parent().unwrap()).unwrap();
    p.save_as(&target).unwrap();
    assert!(!p.is_modified());
    assert_eq!(p.path(), Some(target.as_path()));

    // Every source names the same files from the new place, selection kept.
    let scene_text = std::fs::read_to_string(&target).unwrap();
    assert!(
        scene_text.contains(r#"source: "../../src/meshes/parts.obj#a""#),
        "{scene_text}"
    );
    assert!(
        scene_text.contains(r#"source: "../../extra/tetra.obj""#),
        "{scene_text}"
    );
    let history_path = root.join("out/deep/copy.history.ron");
    assert_eq!(p.history_path(), Some(history_path.clone()));
    let history_text = std::fs::read_to_string(&history_path).unwrap();
    let sources: Vec<&str> = history_text
        .split("source: \"")
        .skip(1)
        .map(|s| &s[..s.find('"').unwrap()])
        .collect();
    // The base, the two AddNode steps and the RemoveNode step.
    assert_eq!(sources.len(), 4, "{history_text}");
    assert!(
        sources.iter().all(|s| s.starts_with("../../")),
        "{sources:?}"
    );
    assert!(history_text.contains("cursor: Some(4)"), "{history_text}");

    // Reopen: equal document, equal history, same cursor.
    let (mut q, warnings) = Project::open(&target).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(q.document(), p.document());
    assert_eq!(q.history(), p.history());
    assert!(!q.is_modified());
    // Redo the tail, then undo everything: the base comes back, with its meshes.
    assert!(q.redo().unwrap());
    assert_eq!(q.document().mesh("body").unwrap().stack[0].weight, 0.5);
    q.jump(3).unwrap();
    assert_eq!(q.rest_mesh("tetra").unwrap().topology().vertex_count(), 4);
    while q.undo().unwrap() {}
    assert_eq!(q.document(), q.history().base());
    assert_eq!(source(q.document(), "body"), "../../src/meshes/parts.obj#a");
    let body = q.rest_mesh("body").unwrap();
    assert_eq!(body.topology().vertex_count(), 4, "object a only");
    while q.redo().unwrap() {}
    assert_eq!(q.history().cursor(), 5);
}

#[test]
fn saving_in_place_keeps_sources_and_the_history_follows_the_scene() {
    let (_dir, root) = layout();
    let mut p = edited(&root);
    p.save().unwrap();
    let text = std::fs::read_to_string(root.join("src/scene.ron")).unwrap();
    assert!(text.contains(r#"source: "meshes/parts.obj#a""#), "{text}");
    // Opening the history file itself gives the same project, saved to the scene beside it.
    let (q, _) = Project::open(root.join("src/scene.history.ron")).unwrap();
    assert_eq!(q.path(), Some(root.join("src/scene.ron").as_path()));
    assert_eq!(q.document(), p.document());
    assert_eq!(q.history().cursor(), 4);
    // A history under another name has no scene file: save asks for save as.
    std::fs::copy(
        root.join("src/scene.history.ron"),
        root.join("src/edits.ron"),
    )
    .unwrap();
    let (mut e, _) = Project::open(root.join("src/edits.ron")).unwrap();
    assert_eq!(e.path(), None);
    assert_eq!(e.document(), p.document());
    let err = e.save().unwrap_err();
    assert!(matches!(err, IoError::NoProjectFile { .. }), "{err}");
    assert!(err.to_string().contains("edits.ron"), "{err}");
}

#[test]
fn a_history_that_does_not_end_at_the_scene_is_dropped_with_a_warning() {
    let (_dir, root) = layout();
    let mut p = edited(&root);
    p.save().unwrap();
    let scene = root.join("src/scene.ron");
    // The scene changed by hand after saving.
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("gamma: 0.5", "gamma: 0.25")).unwrap();
    let (q, warnings) = Project::open(&scene).unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(
        matches!(warnings[0], ProjectWarning::HistoryMismatch { .. }),
        "{}",
        warnings[0]
    );
    assert!(warnings[0].to_string().contains("scene.history.ron"));
    assert_eq!(q.history().len(), 0);
    assert_eq!(q.history().base(), q.document());
    // A broken history file: also a warning, not an error.
    std::fs::write(
        root.join("src/scene.history.ron"),
        "(version: 1, entries: [",
    )
    .unwrap();
    let (_, warnings) = Project::open(&scene).unwrap();
    assert!(
        matches!(warnings[..], [ProjectWarning::HistoryUnreadable { .. }]),
        "{warnings:?}"
    );
    assert!(warnings[0].to_string().contains("scene.history.ron:"));
}

#[test]
fn the_embedded_head_opens_and_saves_its_mesh_beside_the_scene() {
    let mut p = Project::embedded_default().unwrap();
    assert_eq!(p.path(), None);
    assert_eq!(source(p.document(), "head"), embedded::HEAD_SOURCE);
    let rest = p.rest_mesh("head").unwrap();
    assert!(rest.topology().vertex_count() > 1000);
    let before = p.evaluate("head").unwrap();

    let dir = tempfile::tempdir().unwrap();
    let root = normalize(dir.path());
    // A different file of the same name is never overwritten.
    std::fs::create_dir_all(root.join("b")).unwrap();
    std::fs::write(root.join("b/lee-perry-smith-head.glb"), b"not a head").unwrap();
    p.save_as(root.join("b/face.ron")).unwrap();
    assert_eq!(source(p.document(), "head"), "lee-perry-smith-head-2.glb");
    assert_eq!(
        std::fs::read(root.join("b/lee-perry-smith-head.glb")).unwrap(),
        b"not a head"
    );
    assert_eq!(
        std::fs::read(root.join("b/lee-perry-smith-head-2.glb")).unwrap(),
        embedded::HEAD_GLB
    );
    // Reopened from disk it evaluates to the same mesh.
    let (mut q, warnings) = Project::open(root.join("b/face.ron")).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(q.evaluate("head").unwrap().positions, before.positions);

    // A second save elsewhere now rewrites the source like any other file.
    std::fs::create_dir_all(root.join("c")).unwrap();
    q.save_as(root.join("c/face.ron")).unwrap();
    assert_eq!(
        source(q.document(), "head"),
        "../b/lee-perry-smith-head-2.glb"
    );
    assert!(!root.join("c/lee-perry-smith-head.glb").exists());
}

#[test]
fn an_embedded_mesh_equal_to_an_existing_file_reuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = normalize(dir.path());
    std::fs::write(root.join("lee-perry-smith-head.glb"), embedded::HEAD_GLB).unwrap();
    let mut p = Project::embedded_default().unwrap();
    p.save_as(root.join("head.ron")).unwrap();
    assert_eq!(source(p.document(), "head"), "lee-perry-smith-head.glb");
    assert!(!root.join("lee-perry-smith-head-2.glb").exists());
}

#[test]
fn a_new_project_imports_absolute_sources_and_saves_them_relative() {
    let (_dir, root) = layout();
    let mut p = Project::new_empty();
    assert!(p.document().nodes.is_empty());
    let imported = p.import_mesh(root.join("src/meshes/parts.obj")).unwrap();
    let NodeKind::Mesh(m) = &imported.node.kind else {
        panic!("a mesh node")
    };
    assert_eq!(imported.node.name, "parts");
    assert!(Path::new(&m.source).is_absolute(), "{}", m.source);
    assert_eq!(imported.rest.topology().vertex_count(), 8);
    let op = Operation::add_node(p.document(), imported.node);
    p.push(op, "", 0, None).unwrap();
    assert_eq!(p.history().entries()[0].label, "add mesh 'parts'");
    p.save_as(root.join("new.ron")).unwrap();
    assert_eq!(source(p.document(), "parts"), "src/meshes/parts.obj");
    let (mut q, _) = Project::open(root.join("new.ron")).unwrap();
    assert!(q.undo().unwrap());
    assert!(q.document().nodes.is_empty());
    assert!(q.redo().unwrap());
    assert_eq!(q.load_meshes().unwrap().len(), 1);
}

#[test]
fn export_writes_every_deformed_mesh() {
    let (_dir, root) = layout();
    let (mut p, _) = Project::open(root.join("src/scene.ron")).unwrap();
    let out = root.join("out.glb");
    p.export_gltf(&out).unwrap();
    let g = gltf::Gltf::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(g.meshes().count(), 1);
    assert_eq!(g.meshes().next().unwrap().name(), Some("body"));
}

#[test]
fn errors_name_the_file() {
    let (_dir, root) = layout();
    let missing = root.join("nope.ron");
    let err = Project::open(&missing).unwrap_err().to_string();
    assert!(err.contains("nope.ron"), "{err}");

    std::fs::remove_file(root.join("src/meshes/parts.obj")).unwrap();
    let err = Project::open(root.join("src/scene.ron"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("scene.ron"), "{err}");
    assert!(err.contains("mesh node 'body'"), "{err}");
    assert!(err.contains("parts.obj#a"), "{err}");

    let mut p = Project::new_empty();
    let err = p.import_mesh(root.join("extra/nothing.obj")).unwrap_err();
    assert!(err.to_string().contains("nothing.obj"), "{err}");
    let err = p.import_mesh(root.join("src/scene.ron")).unwrap_err();
    assert!(matches!(err, IoError::UnsupportedExtension { .. }), "{err}");

    let err = Project::from_memory("memory.ron", "(version: 1, nodes: [", Vec::new())
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("memory.ron:"), "{err}");
}

#[test]
fn meshes_load_from_memory_like_from_files() {
    let (_dir, root) = layout();
    let file = root.join("src/meshes/parts.obj");
    let from_file = load_mesh(&MeshRef::parse(&format!("{}#b", file.display()))).unwrap();
    let from_bytes =
        load_mesh_from_bytes(PARTS_OBJ.as_bytes(), MeshFormat::Obj, "parts.obj#b").unwrap();
    assert_eq!(from_bytes, from_file);
    assert_eq!(from_bytes.positions[0], Vec3::new(3.0, 0.0, 0.0));

    let head = load_rest_mesh_from_bytes(embedded::HEAD_GLB, MeshFormat::Gltf, "head.glb").unwrap();
    let on_disk =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/lee-perry-smith-head.glb");
    let file_head = ductile_io::load_rest_mesh(&MeshRef::parse(on_disk.to_str().unwrap())).unwrap();
    assert_eq!(head.mesh(), file_head.mesh());

    let err = load_mesh_from_bytes(b"garbage", MeshFormat::Gltf, "in-memory.glb").unwrap_err();
    assert!(
        err.to_string().starts_with("in-memory.glb: invalid glTF"),
        "{err}"
    );
    let err = load_mesh_from_bytes(PARTS_OBJ.as_bytes(), MeshFormat::Obj, "p.obj#zz").unwrap_err();
    assert!(
        err.to_string().contains("p.obj: there is no OBJ object"),
        "{err}"
    );
    assert!(matches!(
        MeshFormat::from_path(Path::new("x.GLB")),
        Ok(MeshFormat::Gltf)
    ));
    assert!(MeshFormat::from_path(Path::new("x.stl")).is_err());
}

/// The exact text of a small saved history (`tests/data/small.history.ron`): the base
/// inline with every field written, the cursor of the undone step, both steps.
#[test]
fn a_small_saved_history_reads_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let root = normalize(dir.path());
    std::fs::write(root.join("tetra.obj"), TETRA_OBJ).unwrap();
    let scene = r#"(version: 1, nodes: [(name: "t", kind: Mesh((source: "tetra.obj", stack: [(tool: "p")]))), (name: "p", kind: Tool(Ffsd((points: [(position: (0.0, 0.0, 2.5), gamma: 0.5, alpha: 2.0, epsilon: 0.5)]))))])"#;
    std::fs::write(root.join("s.ron"), scene).unwrap();
    let (mut p, _) = Project::open(root.join("s.ron")).unwrap();
    let op = Operation::set_layer_weight(p.document(), "t", 0, 0.25).unwrap();
    p.push(op, "half", 1_763_700_000_000, Some(7)).unwrap();
    let op = Operation::set_layer_enabled(p.document(), "t", 0, false).unwrap();
    p.push(op, "off", 1_763_700_001_000, None).unwrap();
    p.undo().unwrap();
    p.save().unwrap();
    let text = std::fs::read_to_string(root.join("s.history.ron")).unwrap();
    assert_eq!(
        text,
        include_str!("data/small.history.ron"),
        "the saved history text changed; if on purpose, update tests/data/small.history.ron"
    );
    // The snapshot reopens at its cursor with the undone step still redoable.
    let (mut q, _) = Project::open(root.join("s.history.ron")).unwrap();
    assert_eq!(q.history().cursor(), 1);
    assert!(q.redo().unwrap());
    assert!(!q.document().mesh("t").unwrap().stack[0].enabled);
}

/// A history file of version 1 (before keys and variants existed) still opens, at its
/// cursor, with the same document as its version 2 twin.
#[test]
fn a_version_1_history_still_opens() {
    let dir = tempfile::tempdir().unwrap();
    let root = normalize(dir.path());
    std::fs::write(root.join("tetra.obj"), TETRA_OBJ).unwrap();
    for (name, text) in [
        ("v1.history.ron", include_str!("data/small-v1.history.ron")),
        ("v2.history.ron", include_str!("data/small.history.ron")),
    ] {
        std::fs::write(root.join(name), text).unwrap();
    }
    let (v1, _) = Project::open(root.join("v1.history.ron")).unwrap();
    let (v2, _) = Project::open(root.join("v2.history.ron")).unwrap();
    assert_eq!(v1.history().cursor(), 1);
    assert_eq!(v1.document(), v2.document());
}

#[test]
fn a_part_of_a_file_is_listed_imported_and_saved_with_its_selection() {
    let (_dir, root) = layout();
    let parts = ductile_io::mesh_parts(&root.join("src/meshes/parts.obj")).unwrap();
    let names: Vec<(&str, usize)> = parts
        .iter()
        .map(|p| (p.name.as_str(), p.vertices))
        .collect();
    assert_eq!(names, [("a", 4), ("b", 4)]);
    let head =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/lee-perry-smith-head.glb");
    let glb = ductile_io::mesh_parts(&head).unwrap();
    assert_eq!(glb.len(), 1, "{glb:?}");
    assert_eq!(glb[0].name, "LeePerrySmith");
    assert!(ductile_io::mesh_parts(&root.join("src/scene.ron")).is_err());

    let mut p = Project::new_empty();
    let imported = p
        .import_mesh_part(root.join("src/meshes/parts.obj"), Some("b"))
        .unwrap();
    assert_eq!(imported.node.name, "b", "named after the part");
    assert_eq!(imported.rest.topology().vertex_count(), 4, "part b only");
    let op = Operation::add_node(p.document(), imported.node);
    p.push(op, "", 0, None).unwrap();
    p.save_as(root.join("new.ron")).unwrap();
    assert_eq!(source(p.document(), "b"), "src/meshes/parts.obj#b");
    let (mut q, _) = Project::open(root.join("new.ron")).unwrap();
    assert_eq!(q.rest_mesh("b").unwrap().topology().vertex_count(), 4);
    let missing = p
        .import_mesh_part(root.join("src/meshes/parts.obj"), Some("c"))
        .unwrap_err();
    assert!(missing.to_string().contains("'c'"), "{missing}");
}
