//! Mesh import rules on a hand-written glTF (`tests/data/transformed.gltf`): node world
//! transforms, mirrored winding, non-indexed primitives, `#name` selection.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use common::data;
use ductile_io::{IoError, MeshRef, load_mesh};
use glam::Vec3;

fn load(spec: &str) -> Result<ductile_core::mesh::Mesh, IoError> {
    load_mesh(&MeshRef::parse(&format!(
        "{}{spec}",
        data("transformed.gltf").display()
    )))
}

#[test]
fn instances_are_merged_with_world_transforms() {
    let m = load("").unwrap();
    // `child` = translate (1, 2, 3) · scale 2; `mirror` = translate (1, 2, 3) · scale (−1, 1, 1).
    let expected = [
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(3.0, 2.0, 3.0),
        Vec3::new(1.0, 4.0, 3.0),
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(0.0, 2.0, 3.0),
        Vec3::new(1.0, 3.0, 3.0),
    ];
    assert_eq!(m.positions, expected);
    // Non-indexed primitives get sequential indices; the mirrored copy has its winding
    // flipped so that it still faces outwards.
    assert_eq!(m.indices, vec![0, 1, 2, 3, 5, 4]);
    assert_eq!(m.normals, None);
    assert_eq!(m.uvs, None);
}

#[test]
fn a_name_selects_one_gltf_mesh() {
    assert_eq!(load("#tri").unwrap().positions.len(), 6);
    // `quad` is in the file but in no scene node: taken once, untransformed.
    let quad = load("#quad").unwrap();
    assert_eq!(quad.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(quad.indices, vec![0, 1, 2, 0, 2, 3]);
    let err = load("#nope").unwrap_err().to_string();
    assert!(
        err.contains("there is no glTF mesh named 'nope' (available: tri, quad)"),
        "{err}"
    );
}

#[test]
fn unsupported_extensions_and_missing_files_are_named() {
    let err = load_mesh(&MeshRef::parse("mesh.stl"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "mesh.stl: unsupported file extension 'stl' (expected .glb, .gltf or .obj)"
    );
    let err = load_mesh(&MeshRef::parse("nowhere/mesh.glb"))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("nowhere/mesh.glb: cannot read the file"),
        "{err}"
    );
}

/// Loads a corrupted copy of `transformed.gltf` (`from` replaced by `to`).
fn load_corrupted(from: &str, to: &str, select: &str) -> String {
    let text = std::fs::read_to_string(data("transformed.gltf")).unwrap();
    assert!(text.contains(from), "{from}");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.gltf");
    std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
    load_mesh(&MeshRef::parse(&format!("{}{select}", p.display())))
        .unwrap_err()
        .to_string()
}

#[test]
fn corrupt_gltf_files_are_errors_not_panics() {
    let e = load_corrupted(
        "\"name\": \"child\",",
        "\"name\": \"child\", \"children\": [0],",
        "",
    );
    assert!(
        e.contains("is reached twice in the node hierarchy (a cycle"),
        "{e}"
    );
    let e = load_corrupted("\"indices\": 2", "\"indices\": 1", "#quad");
    assert!(
        e.contains("glTF mesh 'quad', primitive 0: indices have an invalid accessor type"),
        "{e}"
    );
    let e = load_corrupted("\"count\": 3,", "\"count\": 300,", "");
    assert!(
        e.contains(
            "glTF mesh 'tri', primitive 0: attribute Positions: accessor 0 (300 elements of 12 \
             bytes from offset 0) does not fit in buffer view 0 (36 bytes)"
        ),
        "{e}"
    );
    let e = load_corrupted("\"version\": \"2.0\"", "\"version\": 2", "");
    assert!(e.contains("invalid glTF"), "{e}");
    // A problem the decoder's validation finds is named once, with its JSON path.
    let e = load_corrupted("\"componentType\": 5126", "\"componentType\": 7", "");
    assert_eq!(e.matches("invalid glTF").count(), 1, "{e}");
    assert!(
        e.contains("invalid glTF: accessors[0].componentType: Invalid value"),
        "{e}"
    );
}

#[test]
fn truncated_binary_gltf_is_an_error() {
    let head = common::root().join("assets/meshes/lee-perry-smith-head.glb");
    let bytes = std::fs::read(head).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for len in [0, 11, 20, 5000, bytes.len() - 1] {
        let p = dir.path().join("cut.glb");
        std::fs::write(&p, &bytes[..len]).unwrap();
        let e = load_mesh(&MeshRef::parse(p.to_str().unwrap()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cut.glb: invalid glTF"), "{len}: {e}");
    }
}
