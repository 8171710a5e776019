//! The Studio's incremental evaluator on the shipped identikit demo (the real head): after
//! slider changes, a dragged point, a toggled layer and a moved layer, its output equals a
//! fresh `Document::evaluate` bit for bit, and a slider re-evaluates far fewer layers than
//! the stack has.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::path::{Path, PathBuf};

use ductile_core::mesh::{Deformed, RestMesh};
use ductile_scene::prelude::*;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bits(d: &Deformed) -> Vec<u32> {
    d.positions
        .iter()
        .chain(&d.normals)
        .flat_map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn set_macro(doc: &mut Document, node: &str, value: f32) {
    if let NodeKind::Macro(m) = &mut doc.node_mut(node).unwrap().kind {
        m.value = value;
    }
}

/// The shipped identikit demo and its head.
fn demo_and_head() -> (Document, RestMesh) {
    let doc = ductile_io::read_scene(root().join("scenes/identikit-demo.ron")).unwrap();
    let path = root().join("assets/meshes/lee-perry-smith-head.glb");
    let head =
        ductile_io::load_rest_mesh(&ductile_io::MeshRef::parse(path.to_str().unwrap())).unwrap();
    (doc, head)
}

#[test]
fn identikit_demo_edits_match_a_fresh_evaluation() {
    let (mut doc, rest) = demo_and_head();
    let mut ev = MeshEvaluator::new("head", rest.clone());
    let first = ev.update(&doc).unwrap();
    assert!(first.changed);
    let layers = doc.mesh("head").unwrap().stack.len();
    let resolutions = ev.area_resolutions();
    let check = |ev: &MeshEvaluator, doc: &Document| {
        let expected = doc.evaluate("head", &rest).unwrap();
        assert!(bits(ev.deformed().unwrap()) == bits(&expected));
    };
    check(&ev, &doc);
    for (node, value) in [
        ("nose-length", 0.2),
        ("nose-length", 0.9),
        ("chin-cleft", 0.4),
        ("ear-protrusion", 0.0),
        ("smile", 0.3),
    ] {
        set_macro(&mut doc, node, value);
        let u = ev.update(&doc).unwrap();
        assert!(u.changed, "{node} = {value}: {u:?}");
        assert!(u.layers_evaluated < layers / 2, "{node} = {value}: {u:?}");
        check(&ev, &doc);
    }
    doc.mesh_mut("head").unwrap().stack[20].enabled = false;
    ev.update(&doc).unwrap();
    check(&ev, &doc);
    let stack = &mut doc.mesh_mut("head").unwrap().stack;
    let moved = stack.remove(3);
    stack.insert(30, moved);
    ev.update(&doc).unwrap();
    check(&ev, &doc);
    assert_eq!(ev.area_resolutions(), resolutions);
}

/// The same on the head split 3×3 (about 80k welded vertices), where areas are large enough
/// for the parallel paths (mask, bind, the one-pass application, the output patch) to run.
#[test]
fn split_head_edits_match_a_fresh_evaluation() {
    let (mut doc, head) = demo_and_head();
    let rest = RestMesh::new(
        ductile_core::primitives::subdivided_n(head.mesh(), 3),
        "head split 3×3",
    )
    .unwrap();
    let mut ev = MeshEvaluator::new("head", rest.clone());
    ev.update(&doc).unwrap();
    let check = |ev: &MeshEvaluator, doc: &Document| {
        let expected = doc.evaluate("head", &rest).unwrap();
        assert!(bits(ev.deformed().unwrap()) == bits(&expected));
    };
    for (node, value) in [("nose-length", 0.2), ("chin-cleft", 0.4), ("smile", 0.3)] {
        set_macro(&mut doc, node, value);
        let u = ev.update(&doc).unwrap();
        assert!(u.changed, "{node} = {value}: {u:?}");
        check(&ev, &doc);
    }
}
