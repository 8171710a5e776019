//! `docs/scene-format.md` cannot rot: its complete example is parsed, checked, loaded and
//! evaluated, and every tool kind of `ductile-core` has a section there.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use ductile_scene::document::NodeKind;

/// The fenced ```ron blocks of a markdown text.
fn ron_blocks(md: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in md.lines() {
        match &mut current {
            None if line.trim() == "```ron" => current = Some(String::new()),
            Some(block) if line.trim() == "```" => {
                out.push(std::mem::take(block));
                current = None;
            }
            Some(block) => {
                block.push_str(line);
                block.push('\n');
            }
            None => {}
        }
    }
    out
}

#[test]
fn the_complete_example_loads_and_evaluates() {
    let path = common::root().join("docs/scene-format.md");
    let md = std::fs::read_to_string(&path).unwrap();
    let blocks = ron_blocks(&md);
    assert_eq!(blocks.len(), 1, "expected one ```ron example block");
    let doc = ductile_io::parse_scene(&blocks[0], &path).unwrap();
    assert_eq!(doc.problems(), vec![]);
    // Every node kind appears in the example.
    for kind in ["mesh", "tool", "macro tool", "volume", "group"] {
        assert!(
            doc.nodes.iter().any(|n| n.kind.name() == kind),
            "the example has no {kind} node"
        );
    }
    let mut meshes = 0;
    for n in &doc.nodes {
        if let NodeKind::Mesh(m) = &n.kind {
            let loaded = ductile_io::scene::load_node_mesh(&path, &n.name, &m.source).unwrap();
            let out = doc.evaluate(&n.name, &loaded.rest).unwrap();
            assert_ne!(
                out.positions,
                loaded.rest.mesh().positions,
                "the example moves nothing"
            );
            meshes += 1;
        }
    }
    assert_eq!(meshes, 1);
    // Saving and re-reading the example gives the same document.
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("example.ron");
    ductile_io::save_scene(&saved, &doc).unwrap();
    assert_eq!(ductile_io::read_scene(&saved).unwrap(), doc);
}

#[test]
fn every_tool_kind_is_documented() {
    let root = common::root();
    let md = std::fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let src = std::fs::read_to_string(root.join("crates/ductile-core/src/tool.rs")).unwrap();
    let body = src
        .split("pub enum Tool {")
        .nth(1)
        .and_then(|s| s.split("\n}").next())
        .unwrap();
    let variants: Vec<&str> = body
        .lines()
        .map(str::trim)
        .filter(|l| !l.starts_with("//") && !l.starts_with('#'))
        .filter_map(|l| l.split_once('(').map(|(name, _)| name))
        .filter(|name| !name.is_empty() && name.chars().all(char::is_alphanumeric))
        .collect();
    assert!(variants.contains(&"Ffsd"), "{variants:?}");
    for v in variants {
        assert!(
            md.contains(&format!("### `{v}((...))`")),
            "docs/scene-format.md has no section `### \\`{v}((...))\\`` for the tool kind {v}"
        );
    }
}
