//! Every file of the fuzzers' saved corpus (`fuzz/corpus/TARGET/`) and every input a fuzzer
//! once found failing (`fuzz/regressions/TARGET/`, kept after the fix) runs through its
//! target (`ductile_tests::fuzz`), without the instrumentation: whatever the fuzzers found
//! stays fixed on every CI run. `tools/fuzz/run` does the fuzzing itself.

use std::path::{Path, PathBuf};

use ductile_history::prelude::Operation;
use ductile_scene::document::NodeKind;
use ductile_tests::fuzz;

/// A fuzz target: bytes in, a panic when a bug is found.
type Target = fn(&[u8]);

const TARGETS: [(&str, Target); 5] = [
    ("scene", fuzz::scene),
    ("history", fuzz::history),
    ("operations", fuzz::operations),
    ("gltf", fuzz::gltf),
    ("obj", fuzz::obj),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    files.sort();
    files
}

#[test]
fn the_saved_corpus_and_the_regressions_run_clean() {
    let mut total = 0;
    for (name, target) in TARGETS {
        let corpus = files(&root().join("fuzz/corpus").join(name));
        assert!(
            !corpus.is_empty(),
            "fuzz/corpus/{name} is empty: run tools/fuzz/run and tools/fuzz/run merge"
        );
        let regressions = files(&root().join("fuzz/regressions").join(name));
        for file in corpus.iter().chain(&regressions) {
            let data = std::fs::read(file).unwrap();
            // A panic names the file, so that it can be run again alone.
            let outcome = std::panic::catch_unwind(|| target(&data));
            assert!(outcome.is_ok(), "{name}: {} panicked", file.display());
            total += 1;
        }
    }
    assert!(total > 100, "only {total} corpus files");
}

/// Writes seed inputs for the operations target: for each shipped base, lists of the edits
/// the Studio makes (move, rename, reparent, re-weight, reorder, remove, key), so that the
/// fuzzer starts from operations that name real nodes. Run once with `--ignored` after the
/// bases change; the files are committed under `fuzz/corpus/operations`.
#[test]
#[ignore = "writes the operations target's seed corpus"]
fn write_operation_seeds() {
    let out = root().join("fuzz/corpus/operations");
    std::fs::create_dir_all(&out).unwrap();
    let scenes = [
        "identikit-demo.ron",
        "lattice-demo.ron",
        "volume-demo.ron",
        "sketch-demo.ron",
        "animation-demo.ron",
        "identikit-variants.ron",
    ];
    for (pick, scene) in scenes.iter().enumerate() {
        let text = std::fs::read_to_string(root().join("scenes").join(scene)).unwrap();
        let doc = ductile_io::parse_scene(&text, Path::new(scene)).unwrap();
        let mut ops: Vec<Operation> = Vec::new();
        for node in doc.nodes.iter().take(12) {
            let mut t = node.transform;
            t.translation.y += 0.01;
            t.scale *= 1.1;
            ops.extend(Operation::set_transform(&doc, &node.name, t).ok());
            ops.push(Operation::rename(
                &node.name,
                &format!("{}-renamed", node.name),
            ));
            ops.push(Operation::rename(
                &format!("{}-renamed", node.name),
                &node.name,
            ));
            if let NodeKind::Mesh(m) = &node.kind {
                for i in 0..m.stack.len().min(4) {
                    ops.extend(Operation::set_layer_weight(&doc, &node.name, i, 0.5).ok());
                    ops.extend(Operation::set_layer_enabled(&doc, &node.name, i, false).ok());
                }
                if m.stack.len() > 1 {
                    ops.push(Operation::move_layer(&node.name, 0, m.stack.len() - 1));
                }
            }
            if let NodeKind::Macro(_) = &node.kind {
                ops.extend(Operation::set_macro_value(&doc, &node.name, 0.7).ok());
            }
            if node.kind.is_tool() {
                ops.extend(Operation::key_node(&doc, &node.name, 0.5).ok());
            }
        }
        for (i, chunk) in ops.chunks(6).enumerate() {
            let mut bytes = vec![u8::try_from(pick).unwrap()];
            bytes.extend(ron::to_string(&chunk.to_vec()).unwrap().as_bytes());
            std::fs::write(out.join(format!("seed-{pick}-{i}")), bytes).unwrap();
        }
        // The removal of each node, alone (its references must go first or it is refused).
        for (i, node) in doc.nodes.iter().enumerate().take(8) {
            if let Ok(op) = Operation::remove_node_and_references(&doc, &node.name) {
                let mut bytes = vec![u8::try_from(pick).unwrap()];
                bytes.extend(ron::to_string(&vec![op]).unwrap().as_bytes());
                std::fs::write(out.join(format!("seed-{pick}-remove-{i}")), bytes).unwrap();
            }
        }
    }
}
