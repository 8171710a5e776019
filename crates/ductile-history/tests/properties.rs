//! Property tests over random valid operation sequences: undo and redo of everything, jump
//! versus replay, save → load → replay with bit-identical meshes, exact inverses.

mod common;

use common::{evaluated_bits, grid, node, point, ron_text, scene};
use ductile_core::ffsd::{FfsdMacro, FfsdTool};
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_history::prelude::*;
use ductile_scene::prelude::*;
use glam::{Quat, Vec3};
use proptest::prelude::*;
use serde::{Deserialize, Serialize};

/// One random choice, turned into an operation against the current document by [`make`].
#[derive(Debug, Clone)]
struct Choice {
    kind: u8,
    a: usize,
    b: usize,
    x: f32,
    gesture: Option<u64>,
}

fn choice() -> impl Strategy<Value = Choice> {
    (
        0u8..18,
        any::<usize>(),
        any::<usize>(),
        -1.0f32..1.0,
        prop::option::of(0u64..2),
    )
        .prop_map(|(kind, a, b, x, gesture)| Choice {
            kind,
            a,
            b,
            x,
            gesture,
        })
}

fn names_where(doc: &Document, f: impl Fn(&NodeKind) -> bool) -> Vec<String> {
    doc.nodes
        .iter()
        .filter(|n| f(&n.kind))
        .map(|n| n.name.clone())
        .collect()
}

fn pick(v: &[String], k: usize) -> Option<&str> {
    (!v.is_empty()).then(|| v[k % v.len()].as_str())
}

/// An operation for choice `c` at step `step` (used for fresh names), or `None` when the
/// document has nothing to apply it to. Some operations are invalid (cycles, removal of
/// referenced nodes, radius ≤ 0): they must be refused cleanly.
fn make(doc: &Document, c: &Choice, step: usize) -> Option<Operation> {
    let all = names_where(doc, |_| true);
    let meshes = names_where(doc, |k| matches!(k, NodeKind::Mesh(_)));
    let tools = names_where(doc, NodeKind::is_tool);
    let ffsd = names_where(doc, |k| matches!(k, NodeKind::Tool(_)));
    let macro_nodes = names_where(doc, |k| matches!(k, NodeKind::Macro(_)));
    let volumes = names_where(doc, |k| matches!(k, NodeKind::Volume(_)));
    let mesh = pick(&meshes, c.a);
    let stack_len = mesh.map_or(0, |m| doc.mesh(m).map_or(0, |m| m.stack.len()));
    let layer = (stack_len > 0).then(|| c.b % stack_len);
    let x = c.x;
    Some(match c.kind {
        0 => {
            let t = Transform {
                translation: Vec3::new(x, (c.b % 7) as f32 * 0.1, 0.0),
                rotation: Quat::from_rotation_z(x),
                scale: Vec3::splat(1.0 + 0.5 * x * x),
            };
            Operation::set_transform(doc, pick(&all, c.a)?, t).ok()?
        }
        1 => Operation::set_macro_value(doc, pick(&macro_nodes, c.a)?, x).ok()?,
        2 => {
            let l = layer?;
            let old = doc.mesh(mesh?).ok()?.stack[l].enabled;
            Operation::set_layer_enabled(doc, mesh?, l, !old).ok()?
        }
        3 => Operation::set_layer_weight(doc, mesh?, layer?, x.abs()).ok()?,
        4 => Operation::move_layer(mesh?, c.a % stack_len.max(1), layer?),
        5 => Operation::add_node(
            doc,
            Node {
                name: format!("t{step}"),
                parent: pick(&all, c.b).map(str::to_owned),
                transform: Transform::from_translation(Vec3::new(0.0, 0.0, x)),
                kind: NodeKind::Tool(Tool::Ffsd(FfsdTool::new(vec![point(x, -x, 0.5 * x)]))),
            },
        ),
        6 => Operation::add_layer(
            mesh?,
            c.b % (stack_len + 1),
            LayerSpec {
                weight: x.abs(),
                ..LayerSpec::new(pick(&tools, c.a)?)
            },
        ),
        7 => Operation::remove_layer(doc, mesh?, layer?).ok()?,
        8 => Operation::remove_node(doc, pick(&all, c.a)?).ok()?,
        9 => Operation::remove_node_and_references(doc, pick(&all, c.a)?).ok()?,
        10 => Operation::rename(pick(&all, c.a)?, &format!("r{step}")),
        11 => Operation::reparent(
            doc,
            pick(&all, c.a)?,
            if c.b.is_multiple_of(4) {
                None
            } else {
                pick(&all, c.b)
            },
        )
        .ok()?,
        12 => {
            let name = pick(&ffsd, c.a)?;
            let points = (0..=c.b % 3)
                .map(|k| point(x, k as f32 * 0.2, 0.3))
                .collect();
            Operation::set_tool(doc, name, Tool::Ffsd(FfsdTool::new(points))).ok()?
        }
        13 => Operation::set_volume(doc, pick(&volumes, c.a)?, Shape::Sphere { radius: x + 0.5 })
            .ok()?,
        14 => {
            let m = doc.mesh(mesh?).ok()?;
            let inf = (!c.b.is_multiple_of(3)).then(|| InfluenceSpec {
                volumes: pick(&volumes, c.b).map(str::to_owned).into_iter().collect(),
                area: m
                    .areas
                    .keys()
                    .next()
                    .filter(|_| c.b.is_multiple_of(2))
                    .cloned(),
                inner: x.abs() * 0.9,
                invert: c.b.is_multiple_of(5),
                ..InfluenceSpec::default()
            });
            Operation::set_layer_influence(doc, mesh?, layer?, inf).ok()?
        }
        15 => {
            let area = (!c.b.is_multiple_of(3)).then(|| {
                Area::Region(vec![RegionShape {
                    shape: Shape::Box {
                        half_extents: Vec3::splat(x.abs() + 0.2),
                    },
                    transform: Transform::IDENTITY,
                }])
            });
            Operation::define_area(doc, mesh?, &format!("a{}", c.a % 3), area).ok()?
        }
        16 => {
            let name = ["bump", "dent"][c.a % 2];
            let def = (!c.b.is_multiple_of(4)).then(|| FfsdMacro {
                label: name.to_owned(),
                group: String::new(),
                area: None,
                points: vec![point(0.0, x, 0.2 + x.abs())],
                height: None,
                range: (-1.0, 1.0),
            });
            Operation::set_macro_definition(doc, name, def)
        }
        _ => {
            let first = Operation::set_transform(
                doc,
                pick(&all, c.a)?,
                Transform::from_translation(Vec3::splat(x)),
            )
            .ok()?;
            let second = match pick(&macro_nodes, c.b) {
                Some(m) => Operation::set_macro_value(doc, m, -x).ok()?,
                None => Operation::add_node(doc, node(&format!("g{step}"), None, NodeKind::Group)),
            };
            Operation::Group {
                label: "pair".to_owned(),
                ops: vec![first, second],
            }
        }
    })
}

/// The history file layout of the tests (the real one lives in `ductile-io`).
#[derive(Serialize, Deserialize)]
struct Saved {
    base: Document,
    entries: Vec<Entry>,
}

/// Pushes the operations made from `choices`, checking that refused ones change nothing.
/// Returns the live document, the history, and the document after each step (`[0]` is
/// the base).
fn build(choices: &[Choice]) -> (Document, History, Vec<Document>) {
    let base = scene();
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    let mut states = vec![base];
    for (step, c) in choices.iter().enumerate() {
        let Some(op) = make(&doc, c, step) else {
            continue;
        };
        let before = doc.clone();
        let len = history.len();
        match history.push(&mut doc, op, "", step as u64, c.gesture) {
            Ok(()) => {
                if history.len() == len {
                    *states.last_mut().unwrap() = doc.clone();
                } else {
                    states.push(doc.clone());
                }
                assert!(
                    doc.problems().is_empty(),
                    "an accepted operation made the document invalid: {:?}",
                    doc.problems()
                );
            }
            Err(_) => {
                assert_eq!(doc, before);
                assert_eq!(history.len(), len);
            }
        }
        assert_eq!(history.cursor(), history.len());
        assert_eq!(states.len(), history.len() + 1);
    }
    (doc, history, states)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn undo_all_then_redo_all(choices in prop::collection::vec(choice(), 1..40)) {
        let (mut doc, mut history, states) = build(&choices);
        let end = doc.clone();
        while history.undo(&mut doc).unwrap() {
            prop_assert_eq!(&doc, &states[history.cursor()]);
        }
        prop_assert_eq!(history.cursor(), 0);
        prop_assert_eq!(ron_text(&doc), ron_text(&states[0]));
        while history.redo(&mut doc).unwrap() {
            prop_assert_eq!(&doc, &states[history.cursor()]);
        }
        prop_assert_eq!(history.cursor(), history.len());
        prop_assert_eq!(ron_text(&doc), ron_text(&end));
    }

    #[test]
    fn jump_equals_replay(
        choices in prop::collection::vec(choice(), 1..40),
        jumps in prop::collection::vec(any::<usize>(), 1..6),
    ) {
        let (mut doc, mut history, states) = build(&choices);
        for j in jumps {
            let n = j % (history.len() + 1);
            history.jump(&mut doc, n).unwrap();
            prop_assert_eq!(history.cursor(), n);
            let replayed = replay(history.base(), history.entries(), n).unwrap();
            prop_assert_eq!(ron_text(&doc), ron_text(&replayed));
            prop_assert_eq!(&doc, &states[n]);
        }
        let len = history.len();
        prop_assert!(
            matches!(history.jump(&mut doc, len + 1), Err(HistoryError::NoSuchStep { .. })),
            "jump past the end must be refused"
        );
    }

    #[test]
    fn inverse_is_revert(choices in prop::collection::vec(choice(), 1..30)) {
        let (_, history, states) = build(&choices);
        for (k, entry) in history.entries().iter().enumerate() {
            let mut d = states[k + 1].clone();
            entry.op.inverse().apply(&mut d).unwrap();
            prop_assert_eq!(ron_text(&d), ron_text(&states[k]));
            prop_assert_eq!(entry.op.inverse().inverse(), entry.op.clone());
        }
    }

    #[test]
    fn save_load_replay_is_bit_identical(choices in prop::collection::vec(choice(), 1..40)) {
        let (doc, history, _) = build(&choices);
        let text = ron::ser::to_string_pretty(
            &Saved { base: history.base().clone(), entries: history.entries().to_vec() },
            ron::ser::PrettyConfig::default(),
        ).unwrap();
        let loaded: Saved = ron::from_str(&text).unwrap();
        prop_assert_eq!(&loaded.entries, &history.entries().to_vec());
        let replayed = replay(&loaded.base, &loaded.entries, loaded.entries.len()).unwrap();
        prop_assert_eq!(&replayed, &doc);
        prop_assert_eq!(ron_text(&replayed), ron_text(&doc));
        let rest = grid(6);
        prop_assert_eq!(evaluated_bits(&replayed, &rest), evaluated_bits(&doc, &rest));
    }
}

#[test]
fn gesture_merges_into_one_step_and_undo_restores_the_start() {
    let base = scene();
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    for k in 1..=10 {
        let t = Transform::from_translation(Vec3::new(0.1 * k as f32, 0.0, 0.0));
        let op = Operation::set_transform(&doc, "vol", t).unwrap();
        history
            .push(&mut doc, op, format!("drag to {k}"), k, Some(7))
            .unwrap();
    }
    assert_eq!(history.len(), 1);
    assert_eq!(
        history.entries()[0].time_ms,
        1,
        "the time of the first edit"
    );
    assert_eq!(
        history.entries()[0].label,
        "drag to 10",
        "the label of the last edit (where the gesture ended)"
    );
    assert_eq!(
        doc.node("vol").unwrap().transform.translation,
        Vec3::new(1.0, 0.0, 0.0)
    );
    // Another target in the same gesture is a new step; another gesture too.
    let op = Operation::set_macro_value(&doc, "mac", 0.9).unwrap();
    history.push(&mut doc, op, "", 11, Some(7)).unwrap();
    let op = Operation::set_macro_value(&doc, "mac", 0.1).unwrap();
    history.push(&mut doc, op, "", 12, Some(8)).unwrap();
    assert_eq!(history.len(), 3);
    assert_eq!(history.entries()[1].label, "set 'mac' to 0.9");
    history.jump(&mut doc, 0).unwrap();
    assert_eq!(doc, base);
}

#[test]
fn new_step_after_undo_drops_the_redo_tail() {
    let base = scene();
    let mut doc = base.clone();
    let mut history = History::new(base);
    for (k, v) in [0.1, 0.2, 0.3].into_iter().enumerate() {
        let op = Operation::set_macro_value(&doc, "mac", v).unwrap();
        history
            .push(&mut doc, op, format!("v{k}"), 0, None)
            .unwrap();
    }
    assert!(history.undo(&mut doc).unwrap());
    assert!(history.undo(&mut doc).unwrap());
    assert!(history.can_redo());
    let op = Operation::set_layer_weight(&doc, "grid", 0, 0.25).unwrap();
    history.push(&mut doc, op, "w", 0, None).unwrap();
    assert_eq!(history.len(), 2);
    assert!(!history.can_redo());
    assert!(!history.redo(&mut doc).unwrap());
    let labels: Vec<&str> = history.entries().iter().map(|e| e.label.as_str()).collect();
    assert_eq!(labels, ["v0", "w"]);
    assert_eq!(replay(history.base(), history.entries(), 2).unwrap(), doc);
}

#[test]
fn undo_at_the_start_does_nothing() {
    let base = scene();
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    assert!(!history.undo(&mut doc).unwrap());
    assert_eq!(doc, base);
}

#[test]
fn remove_node_and_references_is_one_undoable_step() {
    let base = scene();
    let mut doc = base.clone();
    let mut history = History::new(base.clone());
    // Removing "grid" takes its four children, and so both layers, with it.
    let op = Operation::remove_node_and_references(&doc, "grid").unwrap();
    history.push(&mut doc, op, "", 0, None).unwrap();
    assert_eq!(doc.nodes.len(), 1);
    assert!(doc.problems().is_empty());
    history.undo(&mut doc).unwrap();
    assert_eq!(ron_text(&doc), ron_text(&base));
    // Removing the volume only edits the influences that name it.
    let mut with_vol = base.clone();
    let inf = InfluenceSpec {
        volumes: vec!["vol".into()],
        ..InfluenceSpec::default()
    };
    Operation::set_layer_influence(&with_vol, "grid", 0, Some(inf))
        .unwrap()
        .apply(&mut with_vol)
        .unwrap();
    let op = Operation::remove_node_and_references(&with_vol, "vol").unwrap();
    let before = with_vol.clone();
    op.apply(&mut with_vol).unwrap();
    assert_eq!(with_vol.mesh("grid").unwrap().stack.len(), 2);
    assert!(with_vol.index_of("vol").is_none());
    op.revert(&mut with_vol).unwrap();
    assert_eq!(with_vol, before);
}

#[test]
fn negative_zero_survives_a_round_trip() {
    // Bit-exact restoration relies on RON keeping the sign of zero.
    let op = Operation::SetMacroValue {
        node: "mac".into(),
        old: -0.0,
        new: 0.0,
    };
    let back: Operation = ron::from_str(&ron_text(&op)).unwrap();
    let Operation::SetMacroValue { old, .. } = back else {
        panic!("wrong variant")
    };
    assert_eq!(old.to_bits(), (-0.0f32).to_bits());
}
