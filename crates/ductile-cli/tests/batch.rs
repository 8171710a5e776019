//! `ductile apply SCENE --input … --out-dir DIR`: the batch as a user runs it, through the
//! binary — outputs equal to a single `apply`, per-input failures, shards as separate
//! processes, a batch killed half-way and resumed.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// A flat `n × n` grid of quads in the unit square at height `z`, as OBJ text.
fn grid_obj(n: usize, z: f32) -> String {
    let mut s = String::from("o plate\n");
    for j in 0..n {
        for i in 0..n {
            let d = (n - 1) as f32;
            writeln!(s, "v {} {} {z}", i as f32 / d, j as f32 / d).unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n, a + n + 1);
            writeln!(s, "f {a} {b} {d}\nf {a} {d} {c}").unwrap();
        }
    }
    s
}

/// A scene whose one mesh, "plate", is pushed in its middle by an FFSD point limited to a
/// region area and a sphere volume; with `vertex_area`, also a layer limited to an area given
/// by vertex indices.
fn scene(dir: &Path, vertex_area: bool) -> PathBuf {
    std::fs::write(dir.join("plate.obj"), grid_obj(21, 0.0)).unwrap();
    let extra_layer = if vertex_area {
        r#", (tool: "corner", influence: Some((area: Some("corner"))))"#
    } else {
        ""
    };
    let text = format!(
        r#"(
    version: 1,
    nodes: [
        (name: "plate", kind: Mesh((
            source: "plate.obj",
            stack: [(tool: "pull", influence: Some((volumes: ["ball"], area: Some("middle"))))
                {extra_layer}],
            areas: {{
                "middle": Region([(shape: Sphere(radius: 0.4), transform: (translation: (0.5, 0.5, 0.0)))]),
                "corner": Vertices([0, 1, 21, 22]),
            }},
        ))),
        (name: "pull", parent: Some("plate"),
         kind: Tool(Ffsd((points: [(position: (0.5, 0.5, 0.3), gamma: 0.4, alpha: 2.0, epsilon: 0.5)])))),
        (name: "corner", parent: Some("plate"),
         kind: Tool(Ffsd((points: [(position: (0.0, 0.0, 0.2), gamma: 0.2, alpha: 2.0, epsilon: 0.5)])))),
        (name: "ball", parent: Some("plate"), transform: (translation: (0.5, 0.5, 0.0)),
         kind: Volume((shape: Sphere(radius: 0.45)))),
    ],
)"#
    );
    let path = dir.join(if vertex_area {
        "vertex.ron"
    } else {
        "region.ron"
    });
    std::fs::write(&path, text).unwrap();
    path
}

fn ductile(args: &[&str]) -> (i32, String, String) {
    ductile_env(args, &[])
}

fn ductile_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ductile"))
        .args(args)
        .envs(env.iter().copied())
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file of `dir` by name with its bytes.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().into_string().unwrap(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// `count` grids of different sizes and heights in `dir/in`, named `m00.obj`, `m01.obj`, ….
fn inputs(dir: &Path, count: usize, size: usize) -> Vec<PathBuf> {
    let folder = dir.join("in");
    std::fs::create_dir_all(&folder).unwrap();
    (0..count)
        .map(|k| {
            let p = folder.join(format!("m{k:02}.obj"));
            std::fs::write(&p, grid_obj(size + k % 3, 0.01 * k as f32)).unwrap();
            p
        })
        .collect()
}

#[test]
fn a_batch_writes_what_a_single_apply_writes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), false);
    let single = dir.path().join("single.glb");
    let (code, _, err) = ductile(&["apply", s(&scene), "-o", s(&single)]);
    assert_eq!(code, 0, "{err}");
    let ins = inputs(dir.path(), 3, 15);
    let out = dir.path().join("out");
    let glob = format!("{}/in/*.obj", dir.path().display());
    let (code, stdout, err) = ductile(&[
        "apply",
        s(&scene),
        "--input",
        s(&dir.path().join("plate.obj")),
        "--input",
        &glob,
        "--out-dir",
        s(&out),
        "--jobs",
        "2",
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(
        stdout.contains("batch: 4 done, 0 failed, 0 skipped"),
        "{stdout}"
    );
    let written = files(&out);
    assert_eq!(
        written.keys().collect::<Vec<_>>(),
        ["m00.glb", "m01.glb", "m02.glb", "plate.glb"]
    );
    // The scene's own mesh through the batch: the same bytes as `ductile apply`.
    assert_eq!(written["plate.glb"], std::fs::read(&single).unwrap());
    // Another mesh is deformed too (its region area and volume carried over): the vertices
    // of m00 (a 15 × 15 grid over the unit square) inside the area and the ball move, the
    // others stay.
    let load = |p: &Path| ductile_io::load_mesh(&ductile_io::MeshRef::parse(s(p))).unwrap();
    let (before, after) = (load(&ins[0]), load(&out.join("m00.glb")));
    assert_eq!(before.positions.len(), after.positions.len());
    let centre = glam::Vec3::new(0.5, 0.5, 0.0);
    let mut moved = 0;
    for (a, b) in before.positions.iter().zip(&after.positions) {
        if a.distance(centre) > 0.45 {
            assert_eq!(a, b, "outside the ball nothing moves");
        } else if (b.z - a.z).abs() > 1e-4 {
            moved += 1;
        }
    }
    assert!(moved > 10, "{moved} vertices of m00 moved");
    let (code, _, err) = ductile(&["apply", s(&scene), "--input", &glob, "--out-dir", s(&out)]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        files(&out),
        written,
        "the same batch again writes the same bytes"
    );
}

#[test]
fn an_input_that_cannot_take_the_stack_fails_alone() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), true);
    let ins = inputs(dir.path(), 2, 21);
    // m00 has the scene mesh's vertex count; m01 has 22 × 22; one input is missing.
    let out = dir.path().join("out");
    let report = dir.path().join("report.jsonl");
    let (code, stdout, err) = ductile(&[
        "apply",
        s(&scene),
        "--input",
        s(&ins[0]),
        "--input",
        s(&ins[1]),
        "--input",
        "nowhere/missing.obj",
        "--out-dir",
        s(&out),
        "--report",
        s(&report),
    ]);
    assert_eq!(code, 1, "{stdout}{err}");
    assert!(stdout.contains("batch: 1 done, 2 failed"), "{stdout}");
    assert!(
        stdout.contains("area 'corner', given by vertex indices of mesh 'plate' (441 vertices), but this mesh has 484 vertices"),
        "{stdout}"
    );
    assert!(stdout.contains("nowhere/missing.obj: error: "), "{stdout}");
    assert_eq!(files(&out).keys().collect::<Vec<_>>(), ["m00.glb"]);
    let report = std::fs::read_to_string(&report).unwrap();
    let lines: Vec<&str> = report.lines().collect();
    assert_eq!(lines.len(), 3, "{report}");
    for l in &lines {
        assert!(l.starts_with("{\"") && l.ends_with('}'), "{l}");
        for field in [
            "\"input\":",
            "\"output\":",
            "\"vertices\":",
            "\"ms\":",
            "\"error\":",
        ] {
            assert!(l.contains(field), "{l}");
        }
    }
    let done: Vec<&&str> = lines
        .iter()
        .filter(|l| l.contains("\"status\":\"done\""))
        .collect();
    assert_eq!(done.len(), 1, "{report}");
    assert!(
        done[0].contains("\"vertices\":441") && done[0].contains("\"error\":null"),
        "{report}"
    );
}

#[test]
fn shards_in_separate_processes_write_every_input_exactly_once() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), false);
    let ins = inputs(dir.path(), 11, 9);
    let list = dir.path().join("list.txt");
    let text: String = ins
        .iter()
        .rev()
        .map(|p| format!("{}\n", p.display()))
        .collect();
    std::fs::write(&list, text).unwrap();
    let out = dir.path().join("out");
    let count = 4;
    let children: Vec<_> = (0..count)
        .map(|i| {
            let report = dir.path().join(format!("report-{i}.jsonl"));
            let mut c = Command::new(env!("CARGO_BIN_EXE_ductile"));
            c.args([
                "apply",
                s(&scene),
                "--input-list",
                s(&list),
                "--out-dir",
                s(&out),
            ])
            .args(["--report", s(&report), "--jobs", "1"])
            .env_remove("JOB_COMPLETION_INDEX")
            .stdout(Stdio::null());
            if i == 0 {
                // The first as a Slurm array task (`--array=1-4`) reads its shard itself.
                c.args(["--shard", "auto"])
                    .env("SLURM_ARRAY_TASK_ID", "1")
                    .env("SLURM_ARRAY_TASK_MIN", "1")
                    .env("SLURM_ARRAY_TASK_COUNT", count.to_string());
            } else {
                c.args(["--shard", &format!("{i}/{count}")])
                    .env_remove("SLURM_ARRAY_TASK_ID");
            }
            (report, c.spawn().unwrap())
        })
        .collect();
    let mut written: Vec<String> = Vec::new();
    for (report, mut child) in children {
        assert!(child.wait().unwrap().success());
        for line in std::fs::read_to_string(report).unwrap().lines() {
            assert!(line.contains("\"status\":\"done\""), "{line}");
            let output = line
                .split("\"output\":\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            written.push(output.to_owned());
        }
    }
    written.sort();
    let expected: Vec<String> = (0..11)
        .map(|k| format!("{}/m{k:02}.glb", out.display()))
        .collect();
    assert_eq!(written, expected, "every input once, by exactly one shard");
    assert_eq!(files(&out).len(), 11);
}

#[test]
fn a_killed_batch_leaves_only_whole_files_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), false);
    inputs(dir.path(), 24, 120);
    let glob = format!("{}/in/*.obj", dir.path().display());
    // The reference: the whole batch in one go.
    let reference = dir.path().join("reference");
    let (code, _, err) = ductile(&[
        "apply",
        s(&scene),
        "--input",
        &glob,
        "--out-dir",
        s(&reference),
    ]);
    assert_eq!(code, 0, "{err}");
    let reference = files(&reference);
    assert_eq!(reference.len(), 24);

    // The same batch, killed (SIGKILL: no chance to clean up) after its third output.
    let out = dir.path().join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_ductile"))
        .args([
            "apply",
            s(&scene),
            "--input",
            &glob,
            "--out-dir",
            s(&out),
            "--jobs",
            "2",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let mut done = 0;
    while done < 3 {
        let line = lines.next().unwrap().unwrap();
        done += usize::from(line.starts_with('['));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = files(&out);
    assert!(partial.len() < 24, "the batch was killed before its end");
    for (name, bytes) in &partial {
        assert!(
            !name.ends_with(".glb") || reference[name] == *bytes,
            "{name} is whole"
        );
    }
    // What a kill in the middle of a write leaves: a hidden temporary file.
    std::fs::write(out.join(".m23.glb.Ab12Cd.tmp"), b"half a file").unwrap();
    let kept = partial.keys().filter(|n| n.ends_with(".glb")).count();
    // The kill itself may have caught a write in flight and left its temporary file too.
    let temporaries = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            let name = e.as_ref().unwrap().file_name();
            ductile_io::atomic_temporary_target(&name.to_string_lossy()).is_some()
        })
        .count();

    let report = dir.path().join("resume.jsonl");
    let (code, stdout, err) = ductile(&[
        "apply",
        s(&scene),
        "--input",
        &glob,
        "--out-dir",
        s(&out),
        "--skip-existing",
        "--report",
        s(&report),
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(
        stdout.contains(&format!("removed {temporaries} temporary files")),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!("{} done, 0 failed, {kept} skipped", 24 - kept)),
        "{stdout}"
    );
    assert_eq!(
        files(&out),
        reference,
        "resumed: every output whole, nothing else left"
    );
}

#[test]
fn bad_batches_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), false);
    let ins = inputs(dir.path(), 1, 5);
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::copy(&ins[0], other.join("m00.obj")).unwrap();
    let out = dir.path().join("out");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "--input".into(),
                s(&ins[0]).into(),
                "--input".into(),
                s(&other.join("m00.obj")).into(),
            ],
            "would both be written to",
        ),
        (
            vec!["--input".into(), format!("{}/*.stl", dir.path().display())],
            "matches no file",
        ),
        (
            vec![
                "--input".into(),
                s(&ins[0]).into(),
                "--shard".into(),
                "4/4".into(),
            ],
            "must be below the number of shards",
        ),
        (
            vec![
                "--input".into(),
                s(&ins[0]).into(),
                "--shard".into(),
                "auto".into(),
            ],
            "neither JOB_COMPLETION_INDEX",
        ),
        (
            vec![
                "--input".into(),
                s(&ins[0]).into(),
                "--mesh".into(),
                "pull".into(),
            ],
            "is not a mesh node of the scene (its meshes: plate)",
        ),
    ];
    for (extra, expected) in cases {
        let mut args = vec![
            "apply".to_owned(),
            s(&scene).to_owned(),
            "--out-dir".into(),
            s(&out).into(),
        ];
        args.extend(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = ductile(&args);
        assert_eq!(code, 1, "{args:?}");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    // Without --out-dir, or with -o, the arguments themselves are refused.
    assert_eq!(ductile(&["apply", s(&scene), "--input", s(&ins[0])]).0, 1);
    assert_eq!(
        ductile(&["apply", s(&scene), "--input", s(&ins[0]), "-o", "x.glb"]).0,
        2
    );
}
