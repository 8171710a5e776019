//! Round trips: RON save → load, glTF export → import.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use common::data;
use ductile_io::{ExportMesh, MeshRef, export_gltf, load_mesh, read_scene, save_scene};

#[test]
fn ron_save_then_load_gives_an_equal_document() {
    let dir = tempfile::tempdir().unwrap();
    for scene in ["spot.ron", "tetra.ron"] {
        let doc = read_scene(data(scene)).unwrap();
        let out = dir.path().join(scene);
        save_scene(&out, &doc).unwrap();
        let back = read_scene(&out).unwrap();
        assert_eq!(back, doc, "{scene}");
        // Saving is deterministic.
        let out2 = dir.path().join(format!("again-{scene}"));
        save_scene(&out2, &back).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&out2).unwrap());
    }
}

#[test]
fn saved_scene_keeps_awkward_floats_exactly() {
    let mut doc = read_scene(data("tetra.ron")).unwrap();
    let ductile_scene::document::NodeKind::Tool(ductile_core::tool::Tool::Ffsd(t)) =
        &mut doc.node_mut("pull").unwrap().kind
    else {
        panic!("pull is an FFSD tool");
    };
    t.points[0].gamma = 0.1 + 0.2;
    t.points[0].epsilon = f32::MIN_POSITIVE;
    t.points[0].position.x = -1.0e-30;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.ron");
    save_scene(&out, &doc).unwrap();
    assert_eq!(read_scene(&out).unwrap(), doc);
}

fn export_import(src: &str, ext: &str) {
    let mesh = load_mesh(&MeshRef::parse(data(src).to_str().unwrap()))
        .or_else(|_| load_mesh(&MeshRef::parse(common::root().join(src).to_str().unwrap())))
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(format!("m.{ext}"));
    export_gltf(&out, &[ExportMesh::from_mesh("m", &mesh)]).unwrap();
    let back = load_mesh(&MeshRef::parse(out.to_str().unwrap())).unwrap();
    assert_eq!(back.positions, mesh.positions, "{src} as {ext}");
    assert_eq!(back.indices, mesh.indices, "{src} as {ext}");
    assert_eq!(back.uvs, mesh.uvs, "{src} as {ext}");
    // The file is valid for the gltf crate's validator.
    let bytes = std::fs::read(&out).unwrap();
    gltf::Gltf::from_slice(&bytes).unwrap();
}

#[test]
fn gltf_export_then_import_gives_the_same_mesh() {
    for ext in ["glb", "gltf"] {
        export_import("tetra.obj", ext);
        export_import("assets/meshes/spot.obj", ext);
    }
}

#[test]
fn several_meshes_export_as_separate_named_meshes() {
    let tetra = load_mesh(&MeshRef::parse(data("tetra.obj").to_str().unwrap())).unwrap();
    let mut moved = tetra.clone();
    moved.positions.iter_mut().for_each(|p| p.x += 5.0);
    moved.uvs = None;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("two.glb");
    export_gltf(
        &out,
        &[
            ExportMesh::from_mesh("a", &tetra),
            ExportMesh::from_mesh("b", &moved),
        ],
    )
    .unwrap();
    let all = load_mesh(&MeshRef::parse(out.to_str().unwrap())).unwrap();
    assert_eq!(all.positions.len(), 12);
    // Only some parts have UVs: the merge drops them.
    assert_eq!(all.uvs, None);
    assert_eq!(&all.indices[12..15], &[6, 7, 8]);
    let b = load_mesh(&MeshRef::parse(&format!("{}#b", out.display()))).unwrap();
    assert_eq!(b.positions, moved.positions);
}
