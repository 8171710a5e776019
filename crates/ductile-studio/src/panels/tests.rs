//! Headless tests of the panels with egui_kittest: each panel is drawn in a harness without a
//! window, driven by clicks and typing, and the operations it emits are checked — and, applied
//! to the document, what they do.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap (house rules).

use bevy::math::Vec3;
use bevy_egui::egui;
use ductile_bevy::prelude::*;
use ductile_core::ffsd::{ControlPoint, FfsdTool};
use ductile_core::influence::Shape;
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::create::{LatticeKind, NewTool, Placement};
use ductile_scene::document::{Document, LayerSpec, MeshNode, Node, NodeKind, VolumeNode};
use ductile_scene::prelude::Value;
use ductile_scene::transform::Transform;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

use super::add_menu::{AddRequest, add_menu_contents};
use super::history::HistoryPanel;
use super::inspector::Inspector;
use super::macros::{MacrosPanel, random_face};
use super::menu_bar::{MenuAction, MenuBar, ViewOptions};
use super::outliner::Outliner;
use super::stack::StackPanel;
use super::status_bar::{StatusBar, StatusInfo};
use super::timeline::TimelinePanel;
use super::variants::VariantsPanel;
use super::{Gestures, PanelContext, PanelRequest};

/// A mesh "m" with an FFSD tool "p" on its stack and a sphere volume "v".
fn document() -> Document {
    let node = |name: &str, parent: Option<&str>, kind| Node {
        name: name.into(),
        parent: parent.map(str::to_owned),
        transform: Transform::IDENTITY,
        kind,
    };
    Document {
        nodes: vec![
            node(
                "m",
                None,
                NodeKind::Mesh(MeshNode {
                    source: "m.obj".into(),
                    stack: vec![LayerSpec::new("p")],
                    areas: Default::default(),
                }),
            ),
            node(
                "p",
                Some("m"),
                NodeKind::Tool(Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
                    Vec3::ZERO,
                    0.5,
                    2.0,
                    0.1,
                )]))),
            ),
            node(
                "v",
                Some("m"),
                NodeKind::Volume(VolumeNode {
                    shape: Shape::Sphere { radius: 1.0 },
                }),
            ),
        ],
        ..Document::default()
    }
}

/// What a panel test keeps between frames: the document (with its history), the selection,
/// gestures, and everything the panel emitted.
struct State<P> {
    doc: SceneDocument,
    selection: Selection,
    gestures: Gestures,
    panel: P,
    commands: Vec<DocumentCommand>,
    requests: Vec<PanelRequest>,
    /// The rest meshes the panels see (none unless a test loads one).
    meshes: Vec<(String, std::sync::Arc<ductile_core::mesh::RestMesh>)>,
    /// The clock the panels read, in seconds (a test advances it).
    now: f64,
}

impl<P> State<P> {
    fn new(panel: P) -> Self {
        Self {
            doc: SceneDocument::new(document()),
            selection: Selection::default(),
            gestures: Gestures::default(),
            panel,
            commands: Vec::new(),
            requests: Vec::new(),
            meshes: Vec::new(),
            now: 0.0,
        }
    }

    /// The operations emitted (each an undo step).
    fn ops(&self) -> Vec<Operation> {
        self.commands
            .iter()
            .filter_map(|c| match c {
                DocumentCommand::Apply { op, .. } => Some((**op).clone()),
                _ => None,
            })
            .collect()
    }

    /// The tool the last emitted operation sets (it must be a `SetTool`).
    fn last_tool(&self) -> Tool {
        match self.ops().last() {
            Some(Operation::SetTool { new, .. }) => new.clone(),
            other => panic!("the last operation sets no tool: {other:?}"),
        }
    }

    /// Applies the emitted commands to the document, as the Studio does after its UI pass.
    fn apply_commands(&mut self) {
        for c in std::mem::take(&mut self.commands) {
            self.doc.run(c).unwrap();
        }
    }
}

/// Presses at `from`, moves to `to` over `steps` frames and releases there; with `apply`, the
/// emitted commands are applied after every frame, as the Studio does after its UI pass.
fn slow_drag<P>(
    h: &mut Harness<'_, State<P>>,
    from: egui::Pos2,
    to: egui::Pos2,
    steps: usize,
    apply: bool,
) {
    h.hover_at(from);
    h.run();
    h.drag_at(from);
    h.run();
    for k in 1..=steps {
        h.hover_at(from + (to - from) * (k as f32 / steps as f32));
        h.run();
        if apply {
            h.state_mut().apply_commands();
        }
    }
    h.drop_at(to);
    h.run();
    if apply {
        h.state_mut().apply_commands();
    }
}

/// A harness drawing `show` with a panel context built from the state each frame.
fn harness<'a, P: 'a>(
    state: State<P>,
    show: impl FnMut(&mut P, &mut egui::Ui, &mut PanelContext<'_>) + 'a,
) -> Harness<'a, State<P>> {
    harness_sized(state, egui::vec2(900.0, 900.0), show)
}

/// [`harness`] in a window of `size`.
fn harness_sized<'a, P: 'a>(
    state: State<P>,
    size: egui::Vec2,
    mut show: impl FnMut(&mut P, &mut egui::Ui, &mut PanelContext<'_>) + 'a,
) -> Harness<'a, State<P>> {
    Harness::builder().with_size(size).build_ui_state(
        move |ui, s: &mut State<P>| {
            let mut cx = PanelContext {
                doc: &s.doc,
                selection: &mut s.selection,
                commands: Vec::new(),
                requests: Vec::new(),
                gestures: &mut s.gestures,
                now: s.now,
                meshes: &s.meshes,
            };
            show(&mut s.panel, ui, &mut cx);
            let (commands, requests) = (cx.commands, cx.requests);
            s.commands.extend(commands);
            s.requests.extend(requests);
        },
        state,
    )
}

#[test]
fn add_lattice_on_the_selected_mesh_is_one_group_adding_a_node_and_a_layer() {
    let mut h = Harness::new_ui_state(
        |ui, picked: &mut Option<AddRequest>| {
            if let Some(r) = add_menu_contents(ui, true) {
                *picked = Some(r);
            }
        },
        None,
    );
    h.get_by_label("Lattice (Bernstein)").click();
    h.run();
    let request = h.state().expect("an entry was picked");
    assert_eq!(
        request,
        AddRequest::Tool(NewTool::Lattice(LatticeKind::Bernstein))
    );
    // What the Studio makes of it, around a unit cube.
    let mut doc = SceneDocument::new(document());
    let place = Placement::around(&[Vec3::splat(-1.0), Vec3::ONE]).unwrap();
    let added = crate::authoring::add_operation(
        doc.document(),
        &Selection::default(),
        "m",
        request,
        &place,
    )
    .unwrap()
    .unwrap();
    let Operation::Group { ops, .. } = &added.op else {
        panic!("one group: {:?}", added.op)
    };
    assert!(matches!(
        ops[..],
        [Operation::AddNode { .. }, Operation::AddLayer { .. }]
    ));
    doc.apply(added.op, "", None).unwrap();
    assert_eq!(doc.history().len(), 1, "one undo step");
    assert_eq!(added.name, "lattice");
    assert_eq!(added.layer, Some(("m".to_owned(), 1)));
    assert_eq!(doc.document().mesh("m").unwrap().stack[1].tool, "lattice");
}

#[test]
fn a_new_volume_masks_the_selected_layer() {
    let selection = Selection {
        layer: Some(("m".to_owned(), 0)),
        ..Default::default()
    };
    let doc = document();
    let place = Placement::around(&[Vec3::splat(-1.0), Vec3::ONE]).unwrap();
    let added = crate::authoring::add_operation(
        &doc,
        &selection,
        "m",
        AddRequest::Volume(ductile_scene::create::NewVolume::Sphere),
        &place,
    )
    .unwrap()
    .unwrap();
    let mut d = doc.clone();
    added.op.apply(&mut d).unwrap();
    let inf = d.mesh("m").unwrap().stack[0].influence.clone().unwrap();
    assert_eq!(inf.volumes, vec![added.name]);
}

#[test]
fn the_stack_panel_solos_and_duplicates_layers() {
    let mut h = harness(State::new(StackPanel::default()), |p, ui, cx| {
        p.show(ui, cx)
    });
    h.run();
    h.get_by_label("S").click();
    h.run();
    let ops = h.state().ops();
    assert!(
        matches!(
            ops[..],
            [Operation::SetLayerSolo {
                index: 0,
                new: true,
                ..
            }]
        ),
        "{ops:?}"
    );
    h.state_mut().apply_commands();
    h.get_by_label("📋").click();
    h.run();
    let ops = h.state().ops();
    let Some(Operation::Group { ops: members, .. }) = ops.last() else {
        panic!("{ops:?}")
    };
    assert_eq!(members.len(), 2, "the copied node and its layer");
    h.state_mut().apply_commands();
    let stack = &h.state().doc.document().mesh("m").unwrap().stack;
    assert_eq!(stack.len(), 2);
    assert_eq!(stack[1].tool, "p-copy");
    assert!(stack[1].solo, "the copy keeps the layer's flags");
}

#[test]
fn the_outliner_adds_groups_renames_and_deletes() {
    let mut h = harness(State::new(Outliner::default()), |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label("+ group").click();
    h.run();
    assert!(matches!(h.state().ops()[..], [Operation::Group { .. }]));
    h.state_mut().apply_commands();
    assert!(h.state().doc.document().node("group").is_ok());
    // Double-click renames in place; Enter applies.
    h.get_by_label("⚪ v").click();
    h.run();
    assert!(h.state().selection.is_selected("v"), "a click selects");
    h.key_press(egui::Key::F2);
    h.run();
    h.get_all_by_value("v").next().unwrap().type_text("-ball");
    h.key_press(egui::Key::Enter);
    h.run();
    assert!(
        h.state()
            .ops()
            .iter()
            .any(|o| matches!(o, Operation::Rename { new, .. } if new == "v-ball")),
        "{:?}",
        h.state().ops()
    );
    h.state_mut().apply_commands();
    assert!(h.state().doc.document().node("v-ball").is_ok());
    // 🗑 deletes the tool with its layer, in one step.
    let before = h.state().doc.history().len();
    h.get_all_by_label("🗑").nth(1).unwrap().click();
    h.run();
    h.state_mut().apply_commands();
    assert_eq!(h.state().doc.history().len(), before + 1);
    assert!(h.state().doc.document().problems().is_empty());
}

#[test]
fn the_inspector_edits_a_tool_and_refuses_an_out_of_range_value() {
    let mut state = State::new(Inspector::default());
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // Structure: a second control point.
    h.get_by_label("+ point").click();
    h.run();
    let Tool::Ffsd(f) = h.state().last_tool() else {
        panic!("an FFSD tool")
    };
    assert_eq!(f.points.len(), 2);
    h.state_mut().commands.clear();
    // ε = −1 is refused at the widget, with the reason, and nothing is applied.
    let is_epsilon = |n: &egui_kittest::kittest::AccessKitNode<'_>| {
        n.role() == egui::accesskit::Role::SpinButton
            && n.numeric_value().is_some_and(|v| (v - 0.1).abs() < 1e-6)
    };
    // Drag the ε field 300 points to the left: at 0.001 per point it would reach −0.2.
    let at = h
        .get(egui_kittest::kittest::By::new().predicate(is_epsilon))
        .rect()
        .center();
    slow_drag(&mut h, at, at - egui::vec2(300.0, 0.0), 30, false);
    // Only the edits that kept ε > 0 were applied; the rest was refused with the reason.
    let last_epsilon = h.state().ops().iter().rev().find_map(|o| match o {
        Operation::SetTool {
            new: Tool::Ffsd(f), ..
        } => Some(f.points[0].epsilon),
        _ => None,
    });
    assert!(last_epsilon.is_none_or(|e| e > 0.0), "{last_epsilon:?}");
    h.get_by_label_contains("refused:");
    h.get_by_label_contains("must be at least 1e-6 (a width in scene units)");
    h.state_mut().commands.clear();
    assert!(h.state().ops().is_empty(), "{:?}", h.state().ops());
}

/// The history panel over a history of one layer-weight step per value of `weights`
/// (labelled "weight W"), back at the opened state.
fn history_of_weights(weights: &[f32]) -> State<HistoryPanel> {
    let mut state = State::new(HistoryPanel::default());
    for &w in weights {
        let op = Operation::set_layer_weight(state.doc.document(), "m", 0, w).unwrap();
        state.doc.apply(op, format!("weight {w}"), None).unwrap();
    }
    state.doc.jump(0).unwrap();
    state
}

#[test]
fn the_history_panel_steps_and_jumps() {
    let state = history_of_weights(&[0.2, 0.4]);
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label("⏭").click();
    h.run();
    assert!(matches!(h.state().commands[..], [DocumentCommand::Jump(1)]));
    h.state_mut().apply_commands();
    h.get_by_label("weight 0.4").click();
    h.run();
    assert!(matches!(h.state().commands[..], [DocumentCommand::Jump(2)]));
}

#[test]
fn the_history_panel_plays_at_its_speed_and_pauses() {
    let state = history_of_weights(&[0.2, 0.4, 0.6, 0.8]);
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // At 2 steps per second (the default), a step every 0.5 s from the press of ▶. While it
    // plays the panel asks for a repaint every frame: one frame at a time.
    h.get_by_label("▶").click();
    h.step();
    let mut steps = Vec::new();
    for frame in 1..=6 {
        h.state_mut().now = 0.25 * f64::from(frame);
        h.step();
        if let [DocumentCommand::Jump(k)] = h.state().commands[..] {
            steps.push((h.state().now, k));
        }
        h.state_mut().apply_commands();
    }
    assert_eq!(steps, [(0.5, 1), (1.0, 2), (1.5, 3)]);
    // Faster: 4 steps per second, then ⏸ stops it where it is.
    h.state_mut().panel.speed = 4.0;
    h.state_mut().now = 1.75;
    h.step();
    assert!(matches!(h.state().commands[..], [DocumentCommand::Jump(4)]));
    h.state_mut().apply_commands();
    h.step();
    assert!(!h.state().panel.is_playing(), "it stops at the last step");
    h.state_mut().doc.jump(1).unwrap();
    h.step();
    h.get_by_label("▶").click();
    h.step();
    h.state_mut().now = 2.0;
    h.step();
    assert!(matches!(h.state().commands[..], [DocumentCommand::Jump(2)]));
    h.state_mut().apply_commands();
    h.get_by_label("⏸").click();
    h.step();
    h.state_mut().now = 10.0;
    h.step();
    assert!(h.state().commands.is_empty(), "paused");
    assert_eq!(h.state().doc.history().cursor(), 2);
}

#[test]
fn the_influence_editor_masks_a_layer_with_a_volume() {
    let mut state = State::new(Inspector::default());
    state.selection.layer = Some(("m".to_owned(), 0));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label("influence (else every vertex, weight 1)")
        .click();
    h.run();
    h.state_mut().apply_commands();
    h.run();
    h.get_by_label("v").click();
    h.run();
    let ops = h.state().ops();
    let Some(Operation::SetLayerInfluence { new: Some(inf), .. }) = ops.last() else {
        panic!("{ops:?}")
    };
    assert_eq!(inf.volumes, vec!["v".to_owned()]);
}

#[test]
fn a_sketch_tool_asks_for_its_strokes_to_be_redrawn() {
    let mut state = State::new(Inspector::default());
    let tool = ductile_scene::sketching::twist_tool(
        ductile_core::sketch::tool::Stroke {
            pixels: vec![bevy::math::Vec2::ZERO, bevy::math::Vec2::ONE * 50.0],
            camera: ductile_core::sketch::camera::Camera {
                eye: Vec3::Z * 5.0,
                target: Vec3::ZERO,
                up: Vec3::Y,
                projection: ductile_core::sketch::camera::Projection::Perspective { fov_y: 0.6 },
                near: 0.1,
                far: 100.0,
                viewport: bevy::math::Vec2::new(400.0, 300.0),
            },
        },
        1.0,
        None,
    );
    let op = Operation::set_tool(state.doc.document(), "p", tool).unwrap();
    state.doc.apply(op, "", None).unwrap();
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label("Redraw strokes…").click();
    h.run();
    assert_eq!(
        h.state().requests,
        vec![PanelRequest::RedrawSketch("p".to_owned())]
    );
}

#[test]
fn the_timeline_keys_the_selection_and_a_drag_moves_keys_in_one_step() {
    let mut panel = TimelinePanel::default();
    panel.expanded = true;
    let mut state = State::new(panel);
    state.selection.select(Some("v".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // K keys every channel of the selected node at the current frame (0), as one step.
    h.get_by_label("Key 'v' (K)").click();
    h.run();
    let ops = h.state().ops();
    let Some(Operation::Group { ops: keys, .. }) = ops.last() else {
        panic!("{ops:?}")
    };
    let channels = h.state().doc.document().channels("v").unwrap().len();
    assert_eq!(keys.len(), channels, "one key per channel");
    h.state_mut().apply_commands();
    assert_eq!(h.state().doc.history().len(), 1);
    // Go to frame 12 and edit the radius in the pose: auto-key is off, so the edit is
    // offered to be keyed, not recorded; K keys it there, as one step.
    h.state_mut().doc.set_time(0.5);
    let posed = h.state().doc.shown().clone();
    let op = Operation::set_volume(&posed, "v", Shape::Sphere { radius: 2.0 }).unwrap();
    h.state_mut().doc.apply(op, "", None).unwrap();
    assert!(h.state().doc.pending().is_some(), "the edit is offered");
    assert_eq!(h.state().doc.history().len(), 1, "and not recorded yet");
    h.run();
    h.key_press(egui::Key::K);
    h.run();
    assert!(
        matches!(h.state().commands[..], [DocumentCommand::KeyPending]),
        "K keys the offered edit: {:?}",
        h.state().commands
    );
    h.state_mut().apply_commands();
    assert_eq!(h.state().doc.history().len(), 2);
    let doc = h.state().doc.document().clone();
    assert_eq!(
        doc.node("v").unwrap().kind,
        document().node("v").unwrap().kind,
        "the base shape is unchanged"
    );
    let (path, _) = doc.channels("v").unwrap().last().unwrap().clone();
    let track = doc.animation.track("v", &path).unwrap();
    assert_eq!(track.len(), 2, "keys at frames 0 and 12: {track:?}");
    // Drag the summary diamond of frame 12 to frame 20 (slowly, over several frames): one
    // undo step moving every key of that frame.
    h.run();
    let from = h.state().panel.key_position(12.0, 0).unwrap();
    let to = h.state().panel.key_position(20.0, 0).unwrap();
    slow_drag(&mut h, from, to, 8, true);
    assert_eq!(
        h.state().doc.history().len(),
        3,
        "the drag is one step: {:#?}",
        h.state().doc.history().entries()
    );
    let doc = h.state().doc.document();
    let times: Vec<f32> = doc
        .animation
        .track("v", &path)
        .unwrap()
        .iter()
        .map(|k| k.time)
        .collect();
    assert_eq!(times, vec![0.0, 20.0 / 24.0]);
    assert_eq!(
        h.state().panel.selected_keys().len(),
        1,
        "the moved key stays selected"
    );
    // Undo puts the key back at frame 12.
    h.state_mut().doc.undo().unwrap();
    let t = h
        .state()
        .doc
        .document()
        .animation
        .track("v", &path)
        .unwrap()[1]
        .time;
    assert_eq!(t, 0.5);
}

#[test]
fn the_timeline_with_nothing_selected_keys_nothing_without_macros() {
    let mut h = harness(State::new(TimelinePanel::default()), |p, ui, cx| {
        p.show(ui, cx)
    });
    h.run();
    h.get_by_label("Key every macro (K)").click();
    h.run();
    assert!(h.state().ops().is_empty());
    assert!(
        matches!(&h.state().requests[..], [PanelRequest::Problem(p)] if p.contains("select a node")),
        "{:?}",
        h.state().requests
    );
}

#[test]
fn the_variants_panel_saves_applies_and_deletes_variants() {
    let mut h = harness(State::new(VariantsPanel::default()), |p, ui, cx| {
        p.show(ui, cx)
    });
    h.run();
    h.get_by_label("Save face").click();
    h.run();
    assert!(matches!(
        h.state().ops()[..],
        [Operation::SetVariant { .. }]
    ));
    h.state_mut().apply_commands();
    assert!(h.state().doc.document().variants.contains_key("variant"));
    // Move the FFSD point, save a second face, then apply the first: the point goes back.
    let moved = |d: &Document| {
        let Ok(NodeKind::Tool(Tool::Ffsd(f))) = d.node("p").map(|n| &n.kind) else {
            panic!()
        };
        let mut f = f.clone();
        f.points[0].gamma = 0.9;
        Operation::set_tool(d, "p", Tool::Ffsd(f)).unwrap()
    };
    let op = moved(h.state().doc.shown());
    h.state_mut().doc.apply(op, "", None).unwrap();
    h.run();
    h.get_by_label("Save face").click();
    h.run();
    h.state_mut().apply_commands();
    assert_eq!(h.state().doc.document().variants.len(), 2);
    h.get_all_by_label("Apply").next().unwrap().click();
    h.run();
    h.state_mut().apply_commands();
    assert_eq!(
        h.state().doc.document().node("p").unwrap().kind,
        document().node("p").unwrap().kind,
        "variant 'variant' restores the first face"
    );
    // The morph slider's blend halfway is a step too, and undo restores the face.
    let doc = h.state().doc.document().clone();
    let half = doc.blend_two("variant", "variant-2", 0.5).unwrap();
    let op = Operation::apply_states(&doc, &half.states, "morph").unwrap();
    h.state_mut().doc.apply(op, "", None).unwrap();
    h.state_mut().doc.undo().unwrap();
    assert_eq!(h.state().doc.document(), &doc);
    // 🗑 deletes a variant in one step.
    let before = h.state().doc.history().cursor();
    h.get_all_by_label("🗑").next().unwrap().click();
    h.run();
    h.state_mut().apply_commands();
    assert_eq!(h.state().doc.history().cursor(), before + 1);
    assert_eq!(h.state().doc.document().variants.len(), 1);
}

/// Two macro tools "left-ear" and "right-ear" of one macro with range [−1, 1].
fn ears() -> Document {
    let node = |name: &str| Node {
        name: name.into(),
        parent: None,
        transform: Transform::IDENTITY,
        kind: NodeKind::Macro(ductile_scene::document::MacroUse {
            name: "ear".into(),
            value: 0.0,
        }),
    };
    let mut d = Document {
        nodes: vec![node("left-ear"), node("right-ear")],
        ..Document::default()
    };
    d.macros.insert(
        "ear".into(),
        ductile_core::ffsd::FfsdMacro {
            label: "Ear".into(),
            group: "Ears".into(),
            area: None,
            points: vec![ControlPoint::basic(Vec3::ZERO, 0.1, 2.0, 0.1)],
            height: None,
            range: (-1.0, 1.0),
        },
    );
    d
}

#[test]
fn the_identikit_moves_both_sides_when_symmetric_and_draws_seeded_faces() {
    let mut state = State::new(MacrosPanel::default());
    state.doc = SceneDocument::new(ears());
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label("Symmetric").click();
    h.run();
    assert!(h.state().panel.symmetric);
    // Drag the first slider's value field to the right: both ears move, in one step.
    let at = h
        .get_all(egui_kittest::kittest::By::new().role(egui::accesskit::Role::SpinButton))
        .next()
        .unwrap()
        .rect()
        .center();
    slow_drag(&mut h, at, at + egui::vec2(40.0, 0.0), 10, true);
    assert_eq!(h.state().doc.history().len(), 1, "one step");
    let Some(Operation::Group { ops: pair, .. }) = h
        .state()
        .doc
        .history()
        .entries()
        .first()
        .map(|e| e.op.clone())
    else {
        panic!("{:?}", h.state().doc.history().entries())
    };
    assert_eq!(pair.len(), 2, "both sides");
    let doc = h.state().doc.document().clone();
    let left = doc.channel("left-ear", "value").unwrap();
    assert_ne!(left, Value::Scalar(0.0));
    assert_eq!(doc.channel("right-ear", "value").unwrap(), left);
    // A random face is one step, seeded, and keeps pairs equal when symmetric.
    let doc = ears();
    let a = random_face(&doc, 3, 0.8, true).unwrap();
    assert_eq!(a, random_face(&doc, 3, 0.8, true).unwrap());
    let mut face = doc.clone();
    a.apply(&mut face).unwrap();
    assert_eq!(
        face.channel("left-ear", "value").unwrap(),
        face.channel("right-ear", "value").unwrap()
    );
    assert_ne!(
        face.channel("left-ear", "value").unwrap(),
        Value::Scalar(0.0)
    );
}

#[test]
fn k_over_a_field_keys_that_channel_alone() {
    let mut state = State::new(TimelinePanel::default());
    state.selection.select(Some("v".to_owned()));
    let path = document().channels("v").unwrap().last().unwrap().0.clone();
    let hovered = path.clone();
    // The inspector marks the field under the pointer every frame; the timeline reads it.
    let mut h = harness(state, move |p, ui, cx| {
        super::hover_channel(ui.ctx(), "v", &hovered);
        p.show(ui, cx);
    });
    h.run();
    h.key_press(egui::Key::K);
    h.run();
    let ops = h.state().ops();
    assert!(
        matches!(&ops[..], [Operation::SetKey { node, param, .. }] if node == "v" && *param == path),
        "{ops:?}"
    );
}

#[test]
fn the_key_offer_keys_or_reverts_an_edit_of_an_animated_field() {
    // The sphere's radius keyed 1 at frame 0 and 3 at frame 24; at frame 12 the radius
    // typed as 5 is held and offered.
    let mut doc = document();
    let path = doc.channels("v").unwrap().last().unwrap().0.clone();
    doc.animation.tracks.entry("v".into()).or_default().insert(
        path.clone(),
        vec![
            ductile_scene::prelude::Key::new(0.0, Value::Scalar(1.0)),
            ductile_scene::prelude::Key::new(1.0, Value::Scalar(3.0)),
        ],
    );
    let mut state = State::new(super::key_offer::KeyOffer);
    state.doc = SceneDocument::new(doc);
    state.doc.set_time(0.5);
    let edit = |state: &mut State<super::key_offer::KeyOffer>| {
        let posed = state.doc.shown().clone();
        let op = Operation::set_volume(&posed, "v", Shape::Sphere { radius: 5.0 }).unwrap();
        state.doc.apply(op, "radius", None).unwrap();
    };
    edit(&mut state);
    let mut h = harness(state, |p, ui, cx| {
        p.show(&ui.ctx().clone(), ui.max_rect(), cx);
    });
    h.run();
    let text = format!("Not keyed: {path} of 'v' at frame 12");
    h.get_by_label(&text);
    assert_eq!(
        super::KeyState::of(&h.state().doc, "v", &path),
        super::KeyState::Changed,
        "the field is marked as changed, not keyed"
    );
    // Revert drops it: nothing recorded, the pose as before.
    h.get_by_label("Revert").click();
    h.run();
    assert!(matches!(
        h.state().commands[..],
        [DocumentCommand::RevertPending]
    ));
    h.state_mut().apply_commands();
    assert!(h.state().doc.pending().is_none());
    assert!(h.state().doc.history().is_empty());
    h.run();
    assert!(h.query_by_label(&text).is_none(), "the offer is gone");
    // Again, and Key: one step, a key at frame 12 with the edited value.
    edit(h.state_mut());
    h.run();
    h.get_by_label("Key (K)").click();
    h.run();
    assert!(matches!(
        h.state().commands[..],
        [DocumentCommand::KeyPending]
    ));
    h.state_mut().apply_commands();
    let d = h.state().doc.document();
    assert_eq!(h.state().doc.history().len(), 1);
    let track = d.animation.track("v", &path).unwrap();
    assert_eq!(track.len(), 3, "{track:?}");
    assert_eq!(track[1].time, 0.5);
    assert_eq!(track[1].value, Value::Scalar(5.0));
    assert_eq!(
        super::KeyState::of(&h.state().doc, "v", &path),
        super::KeyState::Keyed
    );
}

/// A spin button (a `DragValue`) showing `value`.
fn spin_button(value: f64) -> egui_kittest::kittest::By<'static> {
    egui_kittest::kittest::By::new().predicate(move |n| {
        n.role() == egui::accesskit::Role::SpinButton
            && n.numeric_value().is_some_and(|v| (v - value).abs() < 1e-6)
    })
}

#[test]
fn a_new_lattice_s_resolution_is_adjusted_within_its_add_step() {
    use super::adjust_last::{AdjustLast, last_added_lattice};
    let mut state = State::new(AdjustLast);
    let place = Placement::around(&[Vec3::splat(-1.0), Vec3::ONE]).unwrap();
    let added = crate::authoring::add_operation(
        state.doc.document(),
        &Selection::default(),
        "m",
        AddRequest::Tool(NewTool::Lattice(LatticeKind::Bernstein)),
        &place,
    )
    .unwrap()
    .unwrap();
    // As the Studio adds it: in a gesture of its own.
    let gesture = state.gestures.fresh();
    state.doc.apply(added.op, "", Some(gesture)).unwrap();
    let mut h = harness(state, |p, ui, cx| {
        let view = ui.max_rect();
        p.show(&ui.ctx().clone(), view, cx);
    });
    h.run();
    h.get_by_label_contains("Adjust last: add lattice 'lattice'");
    // Drag the first count (3) to the right: 0.05 per point, so 60 points make it 6.
    let at = h.get_all(spin_button(3.0)).next().unwrap().rect().center();
    slow_drag(&mut h, at, at + egui::vec2(60.0, 0.0), 12, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 1, "the resize joined the add step");
    let (_, l, _) = last_added_lattice(doc).unwrap();
    assert!(l.counts.0 > 3 && l.counts.1 == 3, "{:?}", l.counts);
    assert!(
        doc.history().entries()[0]
            .label
            .starts_with("add lattice 'lattice' ("),
        "{}",
        doc.history().entries()[0].label
    );
    // One Ctrl+Z removes the lattice, whatever its resolution.
    h.state_mut().doc.undo().unwrap();
    let doc = h.state().doc.document();
    assert!(doc.node("lattice").is_err());
    assert!(doc.problems().is_empty());
    // Another step after the add closes the panel.
    h.state_mut().doc.redo().unwrap();
    let op = Operation::set_layer_weight(h.state().doc.document(), "m", 0, 0.5).unwrap();
    h.state_mut().doc.apply(op, "", None).unwrap();
    assert!(last_added_lattice(&h.state().doc).is_none());
}

#[test]
fn a_volume_size_drag_is_one_undo_step() {
    let mut state = State::new(Inspector::default());
    let op =
        Operation::set_volume(state.doc.document(), "v", Shape::Sphere { radius: 0.7 }).unwrap();
    state.doc.apply(op, "", None).unwrap();
    let start = state.doc.document().clone();
    state.selection.select(Some("v".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // The radius (0.7) dragged 40 points over 20 frames, each frame's edit applied.
    let at = h.get(spin_button(0.7)).rect().center();
    slow_drag(&mut h, at, at + egui::vec2(40.0, 0.0), 20, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 2, "{:?}", doc.history().entries());
    let NodeKind::Volume(v) = &doc.document().node("v").unwrap().kind else {
        panic!("a volume")
    };
    let Shape::Sphere { radius } = v.shape else {
        panic!("a sphere")
    };
    assert!(radius > 0.7, "{radius}");
    h.state_mut().doc.undo().unwrap();
    assert_eq!(h.state().doc.document(), &start);
}

#[test]
fn an_inspector_field_drag_is_one_undo_step() {
    let mut state = State::new(Inspector::default());
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // γ (0.5) dragged to the right over 20 frames.
    let at = h.get(spin_button(0.5)).rect().center();
    slow_drag(&mut h, at, at + egui::vec2(60.0, 0.0), 20, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 1, "{:?}", doc.history().entries());
    let NodeKind::Tool(Tool::Ffsd(f)) = &doc.document().node("p").unwrap().kind else {
        panic!("the FFSD tool")
    };
    assert!(f.points[0].gamma > 0.5, "{}", f.points[0].gamma);
}

#[test]
fn each_drag_of_a_lattice_count_field_is_one_undo_step() {
    let mut state = State::new(Inspector::default());
    let place = Placement::around(&[Vec3::splat(-1.0), Vec3::ONE]).unwrap();
    let added = crate::authoring::add_operation(
        state.doc.document(),
        &Selection::default(),
        "m",
        AddRequest::Tool(NewTool::Lattice(LatticeKind::Bernstein)),
        &place,
    )
    .unwrap()
    .unwrap();
    state.doc.apply(added.op, "", None).unwrap();
    let added = state.doc.document().clone();
    state.selection.select(Some("lattice".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // The first count (3) dragged 60 points to the right over 12 frames: several integer
    // changes, each applied as the Studio does, and one undo step.
    let at = h.get_all(spin_button(3.0)).next().unwrap().rect().center();
    slow_drag(&mut h, at, at + egui::vec2(60.0, 0.0), 12, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 2, "{:#?}", doc.history().entries());
    let NodeKind::Tool(Tool::Lattice(l)) = &doc.document().node("lattice").unwrap().kind else {
        panic!("the lattice")
    };
    assert!(l.counts.0 > 4 && l.counts.1 == 3, "{:?}", l.counts);
    let first = l.counts;
    // A second drag of the same field is a step of its own: undo takes back only it.
    let at = h
        .get_all(spin_button(f64::from(first.0)))
        .next()
        .unwrap()
        .rect()
        .center();
    slow_drag(&mut h, at, at + egui::vec2(40.0, 0.0), 8, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 3, "{:#?}", doc.history().entries());
    h.state_mut().doc.undo().unwrap();
    let NodeKind::Tool(Tool::Lattice(l)) = &h.state().doc.document().node("lattice").unwrap().kind
    else {
        panic!("the lattice")
    };
    assert_eq!(l.counts, first);
    h.state_mut().doc.undo().unwrap();
    assert_eq!(h.state().doc.document(), &added);
}

/// The sketch tool of [`a_sketch_tool_asks_for_its_strokes_to_be_redrawn`] in bend mode
/// with a turning control `turning`.
fn sketch_with_turning(turning: ductile_core::spline::SplineControl) -> Tool {
    use ductile_core::sketch::tool::{Curve, SketchMode};
    let camera = ductile_core::sketch::camera::Camera {
        eye: Vec3::Z * 5.0,
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: ductile_core::sketch::camera::Projection::Perspective { fov_y: 0.6 },
        near: 0.1,
        far: 100.0,
        viewport: bevy::math::Vec2::new(400.0, 300.0),
    };
    let stroke = ductile_core::sketch::tool::Stroke {
        pixels: vec![bevy::math::Vec2::ZERO, bevy::math::Vec2::ONE * 50.0],
        camera,
    };
    let mut tool = ductile_scene::sketching::twist_tool(stroke.clone(), 1.0, None);
    if let Tool::Sketch(s) = &mut tool {
        s.mode = SketchMode::Bend {
            target: Curve::Stroke(stroke),
            turning: Some(turning),
        };
    }
    tool
}

#[test]
fn a_spline_control_keeps_its_degree_and_gains_a_value_resampled() {
    use ductile_core::sketch::tool::SketchMode;
    use ductile_core::spline::SplineControl;
    let turning = SplineControl {
        values: vec![0.0, 0.8, 1.0],
        degree: 1,
    };
    let mut state = State::new(Inspector::default());
    let op = Operation::set_tool(
        state.doc.document(),
        "p",
        sketch_with_turning(turning.clone()),
    )
    .unwrap();
    state.doc.apply(op, "", None).unwrap();
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    h.get_by_label_contains("3 values");
    h.get_by_label("+").click();
    h.run();
    let Tool::Sketch(s) = h.state().last_tool() else {
        panic!("a sketch tool")
    };
    let SketchMode::Bend {
        turning: Some(f), ..
    } = &s.mode
    else {
        panic!("{:?}", s.mode)
    };
    assert_eq!((f.values.len(), f.degree), (4, 1));
    // The piecewise-linear F is sampled at the new abscissae 0, 1/3, 2/3, 1.
    for (v, s) in f.values.iter().zip([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]) {
        assert!((v - turning.eval(s)).abs() < 1e-6, "{:?}", f.values);
    }
}

#[test]
fn dragging_an_f_s_handle_changes_its_value_in_one_undo_step() {
    use ductile_core::sketch::tool::SketchMode;
    use ductile_core::spline::SplineControl;
    let turning = SplineControl {
        values: vec![0.0, 0.8, 1.0],
        degree: 1,
    };
    let mut state = State::new(Inspector::default());
    let op = Operation::set_tool(state.doc.document(), "p", sketch_with_turning(turning)).unwrap();
    state.doc.apply(op, "", None).unwrap();
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // The editor (250 × 110 points) sits right above the values' fields, its left edge at
    // theirs. Its vertical range is [0, 1] padded by 15 %: [−0.15, 1.15]. The handle of
    // c1 = 0.8 is at s = 0.5 (its Greville abscissa for degree 1).
    let c1 = h.get(spin_button(0.8)).rect();
    let c0 = h
        .get_all(spin_button(0.0))
        .map(|n| n.rect())
        .find(|r| (r.top() - c1.top()).abs() < 1.0 && r.left() < c1.left())
        .unwrap();
    let spacing = egui::Style::default().spacing.item_spacing.y;
    let plot = egui::Rect::from_min_size(
        egui::pos2(c0.left(), c1.top() - spacing - 110.0),
        egui::vec2(250.0, 110.0),
    );
    let handle = egui::pos2(
        plot.left() + 0.5 * plot.width(),
        plot.bottom() - (0.8 + 0.15) / 1.3 * plot.height(),
    );
    // 22 points up over 11 frames, each frame's edit applied: + 22/110 · 1.3 = 0.26.
    slow_drag(&mut h, handle, handle - egui::vec2(0.0, 22.0), 11, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 2, "{:#?}", doc.history().entries());
    let NodeKind::Tool(Tool::Sketch(s)) = &doc.document().node("p").unwrap().kind else {
        panic!("the sketch tool")
    };
    let SketchMode::Bend {
        turning: Some(f), ..
    } = &s.mode
    else {
        panic!("{:?}", s.mode)
    };
    assert!((f.values[1] - 1.06).abs() < 0.02, "{:?}", f.values);
    assert_eq!((f.values[0], f.values[2]), (0.0, 1.0));
    h.state_mut().doc.undo().unwrap();
    let NodeKind::Tool(Tool::Sketch(s)) = &h.state().doc.document().node("p").unwrap().kind else {
        panic!("the sketch tool")
    };
    let SketchMode::Bend {
        turning: Some(f), ..
    } = &s.mode
    else {
        panic!("{:?}", s.mode)
    };
    assert_eq!(
        f.values,
        [0.0, 0.8, 1.0],
        "one Ctrl+Z undoes the whole drag"
    );
}

#[test]
fn a_constraint_on_a_vertex_the_mesh_lacks_is_refused_with_the_reason() {
    use ductile_core::dogme::{Anchor, Constraint, DogmeTool, Support};
    let mut state = State::new(Inspector::default());
    let tool = Tool::Dogme(DogmeTool {
        constraints: vec![Constraint {
            at: Anchor::Point(Vec3::new(0.1, 0.9, 0.0)),
            displacement: Vec3::Z * 0.1,
            support: Support::Sphere { radius: 0.5 },
        }],
        degree: 3,
    });
    let op = Operation::set_tool(state.doc.document(), "p", tool).unwrap();
    state.doc.apply(op, "", None).unwrap();
    // The mesh "m": one triangle, so vertices 0 to 2.
    let mesh = ductile_core::mesh::Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        indices: vec![0, 1, 2],
        ..Default::default()
    };
    let rest = ductile_core::mesh::RestMesh::new(mesh, "m").unwrap();
    state.meshes = vec![("m".to_owned(), std::sync::Arc::new(rest))];
    state.selection.select(Some("p".to_owned()));
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // "free point" → "mesh vertex": the closest vertex to (0.1, 0.9, 0) is vertex 2.
    h.get_by_value("free point").click();
    h.run();
    h.get_by_label("mesh vertex").click();
    h.run();
    let Tool::Dogme(d) = h.state().last_tool() else {
        panic!("a DOGME tool")
    };
    assert_eq!(d.constraints[0].at, Anchor::Vertex(2));
    h.state_mut().apply_commands();
    h.run();
    // Vertex 7 is refused at the widget, with the reason, and not applied.
    let field = h.get(spin_button(2.0));
    field.click();
    h.run();
    // The field is in text mode with its text selected: typing replaces it.
    h.event(egui::Event::Text("7".to_owned()));
    h.run();
    h.key_press(egui::Key::Enter);
    h.run();
    h.run();
    assert!(h.state().commands.is_empty(), "{:?}", h.state().ops());
    h.get_by_label_contains("vertex 7 does not exist (mesh 'm' has 3 welded vertices, 0 to 2)");
    // A tool whose anchor no longer fits (its mesh re-imported smaller) can still be repaired:
    // only the anchors an edit changes are judged.
    let mut broken = d.clone();
    broken.constraints[0].at = Anchor::Vertex(9);
    broken.degree = 4;
    let op = Operation::set_tool(h.state().doc.document(), "p", Tool::Dogme(broken)).unwrap();
    h.state_mut().doc.apply(op, "", None).unwrap();
    h.run();
    h.run();
    h.get_by_value("mesh vertex").click();
    h.run();
    h.get_by_label("free point").click();
    h.run();
    let Tool::Dogme(d) = h.state().last_tool() else {
        panic!("the repair is applied to the DOGME tool")
    };
    assert!(matches!(d.constraints[0].at, Anchor::Point(_)));
}

#[test]
fn the_stack_panel_enables_weighs_and_reorders_by_dragging() {
    let mut state = State::new(StackPanel::default());
    let (op, _) = Operation::duplicate_layer(state.doc.document(), "m", 0).unwrap();
    state.doc.apply(op, "", None).unwrap();
    let mut h = harness(state, |p, ui, cx| p.show(ui, cx));
    h.run();
    // The enabled box of the lower layer.
    h.get_all_by_role(egui::accesskit::Role::CheckBox)
        .next()
        .unwrap()
        .click();
    h.run();
    assert!(
        matches!(
            h.state().ops()[..],
            [Operation::SetLayerEnabled {
                index: 0,
                new: false,
                ..
            }]
        ),
        "{:?}",
        h.state().ops()
    );
    h.state_mut().commands.clear();
    // The weight of the lower layer dragged over 20 frames: one undo step.
    let at = h.get_all(spin_button(1.0)).next().unwrap().rect().center();
    slow_drag(&mut h, at, at - egui::vec2(60.0, 0.0), 20, true);
    let doc = &h.state().doc;
    assert_eq!(doc.history().len(), 2, "{:?}", doc.history().entries());
    let weight = doc.document().mesh("m").unwrap().stack[0].weight;
    assert!(weight < 1.0 && weight > 0.0, "{weight}");
    // The ☰ of the lower layer dropped on the upper one moves it there.
    let handles: Vec<egui::Pos2> = h.get_all_by_label("☰").map(|n| n.rect().center()).collect();
    assert_eq!(handles.len(), 2);
    slow_drag(&mut h, handles[0], handles[1], 10, false);
    let ops = h.state().ops();
    assert!(
        matches!(
            ops.last(),
            Some(Operation::MoveLayer { from: 0, to: 1, .. })
        ),
        "{ops:?}"
    );
}

/// A layer whose name is wider than the panel: its controls stay in the panel, at the
/// places the other rows have them, and its name is cut short; clicking it selects it.
#[test]
fn a_long_layer_name_is_cut_short_and_leaves_the_controls_in_the_panel() {
    let mut state = State::new(StackPanel::default());
    let (op, _) = Operation::duplicate_layer(state.doc.document(), "m", 0).unwrap();
    state.doc.apply(op, "", None).unwrap();
    let long = "the-left-eyebrow-ridge-prominence-and-the-brow-height-together";
    state
        .doc
        .apply(Operation::rename("p", long), "", None)
        .unwrap();
    let width = 320.0;
    let mut h = harness_sized(state, egui::vec2(width, 400.0), |p, ui, cx| p.show(ui, cx));
    h.run();
    let bins: Vec<egui::Rect> = h.get_all_by_label("🗑").map(|n| n.rect()).collect();
    assert_eq!(bins.len(), 2);
    for b in &bins {
        assert!(
            b.right() <= width,
            "a remove button ends at {} of {width}",
            b.right()
        );
    }
    assert_eq!(bins[0].left(), bins[1].left(), "the rows' controls line up");
    let name = h.get_by_label(long).rect();
    let weight = h.get_all(spin_button(1.0)).next().unwrap().rect();
    assert!(
        name.right() <= weight.left(),
        "{name:?} runs under {weight:?}"
    );
    h.get_by_label(long).click();
    h.run();
    assert_eq!(h.state().selection.layer, Some(("m".to_owned(), 0)));
}

#[test]
fn the_outliner_filters_hides_and_reparents_by_dragging() {
    let mut h = harness(State::new(Outliner::default()), |p, ui, cx| p.show(ui, cx));
    h.run();
    assert_eq!(h.get_all_by_label("🗑").count(), 3, "m, p and v");
    // The eye of the volume hides it (view state, no undo step).
    h.get_all_by_label("👁").nth(2).unwrap().click();
    h.run();
    assert!(h.state().selection.is_hidden("v"));
    assert!(h.state().ops().is_empty());
    // Dragging the volume onto the tool makes it the tool's child.
    let from = h.get_by_label("⚪ v").rect().center();
    let to = h.get_by_label_contains(" p").rect().center();
    slow_drag(&mut h, from, to, 10, false);
    let ops = h.state().ops();
    assert!(
        ops.iter().any(|o| matches!(o,
            Operation::Reparent { node, new: Some(p), .. } if node == "v" && p == "p")),
        "{ops:?}"
    );
    h.state_mut().commands.clear();
    // The filter keeps the matching nodes and their ancestors.
    h.get_all_by_role(egui::accesskit::Role::TextInput)
        .next()
        .unwrap()
        .click();
    h.run();
    h.event(egui::Event::Text("v".to_owned()));
    h.run();
    h.run();
    assert_eq!(h.get_all_by_label("🗑").count(), 2, "m and v");
}

/// What a menu bar test keeps between frames: the document, the view toggles and the
/// actions picked.
struct MenuState {
    doc: SceneDocument,
    view: ViewOptions,
    heat: HeatMapSettings,
    actions: Vec<MenuAction>,
}

#[test]
fn the_menu_bar_undoes_the_named_step_adds_a_tool_and_toggles_the_view() {
    let mut doc = SceneDocument::new(document());
    let op = Operation::set_volume(doc.document(), "v", Shape::Sphere { radius: 2.0 }).unwrap();
    doc.apply(op, "resize v", None).unwrap();
    let state = MenuState {
        doc,
        view: ViewOptions::default(),
        heat: HeatMapSettings::default(),
        actions: Vec::new(),
    };
    let mut h = Harness::builder()
        .with_size(egui::vec2(900.0, 700.0))
        .build_ui_state(
            |ui, s: &mut MenuState| {
                let picked = MenuBar.show(ui, &s.doc, false, true, &mut s.view, &mut s.heat);
                s.actions.extend(picked);
            },
            state,
        );
    // Edit: Undo names the step it undoes.
    h.get_by_label("Edit").click();
    h.run();
    h.get_by_label_contains("Undo ").click();
    h.run();
    assert_eq!(h.state().actions, [MenuAction::Undo]);
    // Add ▸ a lattice: the request the Studio turns into one undo step.
    h.get_by_label("Add").click();
    h.run();
    h.get_by_label("Lattice (Bernstein)").click();
    h.run();
    assert_eq!(
        h.state().actions[1..],
        [MenuAction::Add(AddRequest::Tool(NewTool::Lattice(
            LatticeKind::Bernstein
        )))]
    );
    // View: a toggle changes the view options, not the document.
    h.get_by_label("View").click();
    h.run();
    h.get_by_label("Wireframe").click();
    h.run();
    assert!(h.state().view.wireframe);
    assert_eq!(h.state().actions.len(), 2);
    assert_eq!(h.state().doc.history().len(), 1);
}

#[test]
fn the_status_bar_shows_the_file_counts_evaluation_drag_and_error() {
    let info = StatusInfo {
        vertices: 8844,
        triangles: 17_684,
        evaluation: Some(("head".to_owned(), 1.25, 3, true)),
        frame_ms: Some(16.7),
        drag: Some("X"),
        evaluating: false,
        error: Some("scene.ron: line 3: expected a number".to_owned()),
        file: "scene.ron".to_owned(),
        modified: true,
        export: None,
    };
    let h = Harness::new_ui_state(|ui, info: &mut StatusInfo| StatusBar.show(ui, info), info);
    for label in [
        "scene.ron •",
        "8844 vertices",
        "17684 triangles",
        "eval 'head': 1.25 ms (3 layers, background)",
        "frame 16.7 ms",
        "drag: X (X/Y/Z constrain, Ctrl snaps)",
        "scene.ron: line 3: expected a number",
    ] {
        h.get_by_label(label);
    }
}
