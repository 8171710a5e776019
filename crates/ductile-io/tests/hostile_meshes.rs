//! Hostile mesh files (issue 14): each was a crash, an abort, a silent wrong result or a read
//! of a file outside the glTF file's folder before the importer checked it. Each must now be
//! refused with an error naming the file and the problem.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use ductile_io::{MeshRef, load_mesh};

/// A triangle: 3 float VEC3 positions (36 bytes), 3 u16 indices (6 bytes) and a spare u16
/// (7) that a sparse accessor can point at.
fn triangle_bytes() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [[0.0_f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0_u16, 1, 2, 7] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

fn data_uri() -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(triangle_bytes())
    )
}

const POSITIONS: &str =
    r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#;

/// The triangle's glTF JSON with `uri` as its buffer.
fn triangle(uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"uri":"{uri}","byteLength":44}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36,"byteStride":12}},{{"buffer":0,"byteOffset":36,"byteLength":6}},{{"buffer":0,"byteOffset":42,"byteLength":2}}],
"accessors":[{POSITIONS},{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
    )
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn load(path: &Path) -> Result<usize, String> {
    load_mesh(&MeshRef::parse(path.to_str().unwrap()))
        .map(|m| m.positions.len())
        .map_err(|e| e.to_string())
}

/// Loads `text` written as `case.gltf` and expects an error naming the file and saying `what`.
fn refused(text: &str, what: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "case.gltf", text);
    let err = load(&path).expect_err("a hostile file was accepted");
    assert!(
        err.contains("case.gltf"),
        "the error does not name the file: {err}"
    );
    assert!(err.contains(what), "expected '{what}' in: {err}");
}

#[test]
fn the_untouched_triangle_loads() {
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(
        load(&write(dir.path(), "t.gltf", &triangle(&data_uri()))),
        Ok(3)
    );
}

#[test]
fn a_stride_smaller_than_the_element_is_refused_not_a_panic() {
    let text = triangle(&data_uri()).replace(r#""byteStride":12"#, r#""byteStride":4"#);
    refused(&text, "byteStride 4, smaller than one element (12 bytes)");
}

#[test]
fn a_node_listed_twice_is_refused_before_instances_multiply() {
    let text = triangle(&data_uri()).replace(
        r#""nodes":[{"mesh":0}]"#,
        r#""nodes":[{"children":[1,1]},{"children":[2,2]},{"children":[3,3]},{"mesh":0}]"#,
    );
    refused(&text, "is reached twice in the node hierarchy");
}

#[test]
fn a_cycle_is_refused() {
    let text = triangle(&data_uri()).replace(
        r#""nodes":[{"mesh":0}]"#,
        r#""nodes":[{"mesh":0,"children":[1]},{"children":[0]}]"#,
    );
    refused(&text, "reached twice");
}

#[test]
fn a_huge_sparse_accessor_is_refused_before_allocating() {
    let huge = r#"{"componentType":5126,"count":4000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,0],"sparse":{"count":1,"indices":{"bufferView":1,"componentType":5123},"values":{"bufferView":0}}}"#;
    let text = triangle(&data_uri()).replace(POSITIONS, huge);
    refused(&text, "more than the limit");
}

#[test]
fn a_sparse_index_beyond_the_count_is_refused() {
    let sparse = r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0],"sparse":{"count":1,"indices":{"bufferView":2,"componentType":5123},"values":{"bufferView":0}}}"#;
    let text = triangle(&data_uri()).replace(POSITIONS, sparse);
    refused(&text, "sparse index 0 is 7, not below the count 3");
}

#[test]
fn indices_that_do_not_fit_their_view_are_refused_not_ignored() {
    let text = triangle(&data_uri()).replace(
        r#""componentType":5123,"count":3,"type":"SCALAR""#,
        r#""componentType":5123,"count":30,"type":"SCALAR""#,
    );
    refused(&text, "does not fit in buffer view 1");
}

#[test]
fn a_view_beyond_its_buffer_is_refused() {
    let text = triangle(&data_uri()).replace(
        r#""byteOffset":36,"byteLength":6"#,
        r#""byteOffset":36,"byteLength":600"#,
    );
    refused(&text, "does not fit in buffer 0");
}

#[test]
fn external_buffers_are_read_only_inside_the_folder() {
    let outer = tempfile::tempdir().unwrap();
    let dir = outer.path().join("scene");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("tri.bin"), triangle_bytes()).unwrap();
    std::fs::write(outer.path().join("secret.bin"), triangle_bytes()).unwrap();
    assert_eq!(load(&write(&dir, "ok.gltf", &triangle("tri.bin"))), Ok(3));

    for (uri, what) in [
        ("../secret.bin", "contains '..'"),
        ("%2e%2e/secret.bin", "contains '..'"),
        ("/etc/passwd", "is an absolute path"),
        ("/proc/self/environ", "is an absolute path"),
        ("/dev/zero", "is an absolute path"),
        ("file:///etc/passwd", "has the scheme 'file:'"),
    ] {
        let err = load(&write(&dir, "bad.gltf", &triangle(uri))).expect_err(uri);
        assert!(
            err.contains("bad.gltf") && err.contains(what),
            "{uri}: {err}"
        );
    }
}

#[cfg(unix)]
#[test]
fn links_out_of_the_folder_and_special_files_are_refused() {
    let outer = tempfile::tempdir().unwrap();
    let dir = outer.path().join("scene");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(outer.path().join("secret.bin"), triangle_bytes()).unwrap();
    std::os::unix::fs::symlink(outer.path().join("secret.bin"), dir.join("link.bin")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
    for uri in ["link.bin", "zero.bin"] {
        let err = load(&write(&dir, "bad.gltf", &triangle(uri))).expect_err(uri);
        assert!(err.contains("leads outside"), "{uri}: {err}");
    }
    // A FIFO would block a plain read forever.
    let fifo = dir.join("fifo.bin");
    if std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let err = load(&write(&dir, "bad.gltf", &triangle("fifo.bin"))).expect_err("fifo");
        assert!(err.contains("not a regular file"), "{err}");
    }
    std::fs::create_dir(dir.join("folder.bin")).unwrap();
    let err = load(&write(&dir, "bad.gltf", &triangle("folder.bin"))).expect_err("folder");
    assert!(err.contains("not a regular file"), "{err}");
}

#[test]
fn at_most_the_declared_length_is_read_and_a_short_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut long = triangle_bytes();
    long.extend(std::iter::repeat_n(0xAB, 1 << 20));
    std::fs::write(dir.path().join("long.bin"), long).unwrap();
    assert_eq!(
        load(&write(dir.path(), "a.gltf", &triangle("long.bin"))),
        Ok(3)
    );
    std::fs::write(dir.path().join("short.bin"), &triangle_bytes()[..20]).unwrap();
    let err = load(&write(dir.path(), "b.gltf", &triangle("short.bin"))).unwrap_err();
    assert!(
        err.contains("declares 44 bytes but its source holds only 20"),
        "{err}"
    );
}

#[test]
fn non_finite_texture_coordinates_are_refused() {
    // Issue 14: they passed `check` and reached the exported file.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nan.obj");
    std::fs::write(
        &p,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt nan 0\nvt 0 inf\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let err = ductile_io::load_rest_mesh(&MeshRef::parse(p.to_str().unwrap()))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("nan.obj") && err.contains("texture coordinate of vertex 1"),
        "{err}"
    );
}

#[test]
fn obj_errors_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    for (text, expected) in [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n",
            "bad.obj:3: invalid OBJ line `v 0 1 x`: 'x' is not a number",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 9\n",
            "bad.obj:5: invalid OBJ line `f 1 2 9`: '9': vertex index 9 is out of range (3 defined so far)",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            "bad.obj:5: invalid OBJ line `f 1/1 2/2 3/1`: '2/2': texture coordinate index 2 is out of range (1 defined so far)",
        ),
    ] {
        let path = write(dir.path(), "bad.obj", text);
        let e = load(&path).unwrap_err();
        assert!(e.ends_with(expected), "{e}");
    }
}

/// Runs `f` on another thread and fails the test when it takes more than ten seconds (a
/// read of a FIFO blocks forever, one of `/dev/zero` runs until memory is exhausted).
fn within_ten_seconds<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(10))
        .unwrap_or_else(|_| panic!("{what}: still reading after ten seconds"))
}

#[cfg(unix)]
#[test]
fn scenes_histories_and_meshes_naming_special_files_are_refused_not_read() {
    // A scene's mesh source, a history's base scene, or the file given on the command line
    // may name a device, a FIFO or a folder: the read used to hang (FIFO) or run until memory
    // ran out (/dev/zero).
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.obj");
    let have_fifo = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.obj")).unwrap();
    std::fs::create_dir(dir.path().join("folder.obj")).unwrap();
    let mut sources = vec![("zero.obj", "a device"), ("folder.obj", "a folder")];
    if have_fifo {
        sources.push(("pipe.obj", "a FIFO"));
    }
    for (source, what) in sources {
        // As a scene's mesh source.
        let scene = dir.path().join(format!("{source}.ron"));
        std::fs::write(
            &scene,
            format!("(version: 2, nodes: [(name: \"m\", kind: Mesh((source: \"{source}\")))])"),
        )
        .unwrap();
        let err = within_ten_seconds(source, move || {
            ductile_io::load_scene(&scene)
                .map(|_| ())
                .unwrap_err()
                .to_string()
        });
        assert!(
            err.contains(source) && err.contains(what),
            "{source}: {err}"
        );
        // As the scene, history or mesh file itself.
        let path = dir.path().join(source);
        let err = within_ten_seconds(source, move || {
            ductile_io::read_scene(&path)
                .map(|_| ())
                .unwrap_err()
                .to_string()
        });
        assert!(err.contains(what), "{source}: {err}");
        let path = dir.path().join(source);
        let err = within_ten_seconds(source, move || {
            ductile_io::read_history(&path)
                .map(|_| ())
                .unwrap_err()
                .to_string()
        });
        assert!(err.contains(what), "{source}: {err}");
    }
    // As a history's base scene.
    let history = dir.path().join("h.history.ron");
    std::fs::write(
        &history,
        "(version: 1, base: Reference(path: \"zero.obj\", hash: \"00\"), entries: [])",
    )
    .unwrap();
    let err = within_ten_seconds("base", move || {
        ductile_io::read_history(&history)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    });
    assert!(
        err.contains("zero.obj") && err.contains("a device"),
        "{err}"
    );
}

#[test]
fn a_scene_or_history_larger_than_the_text_limit_is_refused_before_it_is_read() {
    // A sparse file: 513 MiB long, no disk used. Read and parsed, it would take gigabytes.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.ron");
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(ductile_io::MAX_TEXT_BYTES + (1 << 20)).unwrap();
    drop(f);
    for err in [
        ductile_io::read_scene(&path)
            .map(|_| ())
            .unwrap_err()
            .to_string(),
        ductile_io::read_history(&path)
            .map(|_| ())
            .unwrap_err()
            .to_string(),
    ] {
        assert!(
            err.contains("huge.ron") && err.contains("more than the limit of 536870912"),
            "{err}"
        );
    }
}
