//! Every fixture under `tests/data/malformed/` is rejected by `ductile check` (exit status 1)
//! and by `load_scene`, with the message fragments its `// expect:` lines name.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

mod common;

use common::{cli, data, ron_files};

fn expectations(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|l| l.strip_prefix("// expect: "))
        .collect()
}

#[test]
fn every_malformed_fixture_is_reported_with_its_message() {
    let files = ron_files(&data("malformed"));
    assert!(files.len() >= 14, "fixtures missing: {files:?}");
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        let expected = expectations(&text);
        assert!(
            !expected.is_empty(),
            "{}: no `// expect:` line",
            f.display()
        );
        let (r, out) = cli(&["check", f.to_str().unwrap()]);
        assert_eq!(r, Ok(1), "{}: {out}", f.display());
        for e in &expected {
            assert!(
                out.contains(e),
                "{}: expected '{e}' in:\n{out}",
                f.display()
            );
        }
        assert!(ductile_io::load_scene(&f).is_err(), "{}", f.display());
    }
}

#[test]
fn a_good_scene_checks_ok() {
    let (r, out) = cli(&["check", data("tetra.ron").to_str().unwrap()]);
    assert_eq!((r, out.as_str()), (Ok(0), "ok\n"));
}

#[test]
fn errors_name_the_file_and_never_panic_on_odd_input() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("empty.ron", &b""[..]),
        ("binary.ron", &[0xff, 0xfe, 0x00, 0x01][..]),
        ("number.ron", &b"42"[..]),
        ("deep.ron", "(".repeat(10_000).as_bytes()),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let (r, out) = cli(&["check", p.to_str().unwrap()]);
        assert_eq!(r, Ok(1), "{name}");
        assert!(out.contains(name), "{name}: {out}");
    }
    let missing = dir.path().join("nope.ron");
    let (r, out) = cli(&["check", missing.to_str().unwrap()]);
    assert_eq!(r, Ok(1));
    assert!(out.contains("nope.ron: cannot read the file"), "{out}");
}

#[test]
fn check_reports_bad_areas_no_layer_uses_yet() {
    // Issue 14: `check` missed out-of-range vertex indices of areas no layer used.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("areas.ron");
    let mesh = data("tetra.obj");
    std::fs::write(
        &scene,
        format!(
            "(version: 1, nodes: [(name: \"tetra\", kind: Mesh((source: {:?}, \
             areas: {{\"fine\": Vertices([0, 1]), \"unused\": Vertices([0, 99])}})))])",
            mesh.to_str().unwrap()
        ),
    )
    .unwrap();
    let (r, out) = cli(&["check", scene.to_str().unwrap()]);
    assert_eq!(r, Ok(1), "{out}");
    assert!(
        out.contains("area 'unused'") && out.contains("99") && !out.contains("'fine'"),
        "{out}"
    );
}

#[test]
fn a_bad_transform_is_reported_once_on_its_node_not_again_through_the_tools_beneath() {
    // Issue 14: a zero scale on a group was reported on the group, then a second time as a
    // zero epsilon of the tool beneath it (a value derived in mesh space, never written);
    // a translation of 1e38 was reported only as a tool's control point out of range.
    let dir = tempfile::tempdir().unwrap();
    let mesh = data("tetra.obj");
    for (transform, expected) in [
        ("scale: (0.0, 1.0, 1.0)", "a scale component is zero"),
        (
            "translation: (1e38, 0.0, 0.0)",
            "a translation component lies beyond ±1e9",
        ),
        (
            "scale: (1e-20, 1.0, 1.0)",
            "a scale component is smaller than 1e-9",
        ),
    ] {
        let scene = dir.path().join("bad-group.ron");
        std::fs::write(
            &scene,
            format!(
                "(version: 2, nodes: [\
                 (name: \"tetra\", kind: Mesh((source: {:?}, stack: [(tool: \"pull\")]))),\
                 (name: \"g\", parent: Some(\"tetra\"), transform: ({transform}), kind: Group),\
                 (name: \"pull\", parent: Some(\"g\"), kind: Tool(Ffsd((points: [\
                 (position: (0.0, 0.0, 0.0), gamma: 0.5, alpha: 2.0, epsilon: 0.5)])))),\
                 ])",
                mesh.to_str().unwrap()
            ),
        )
        .unwrap();
        let (r, out) = cli(&["check", scene.to_str().unwrap()]);
        assert_eq!(r, Ok(1), "{out}");
        assert!(
            out.contains("node 'g'") && out.contains(expected),
            "{transform}: {out}"
        );
        assert!(out.contains("1 problem\n"), "{transform}: {out}");
        assert!(!out.contains("tool 'pull'"), "{transform}: {out}");
    }
}
