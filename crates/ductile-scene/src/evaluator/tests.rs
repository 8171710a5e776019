//! The evaluator against [`Document::evaluate`]: random sequences of edits, after each of
//! which the incremental result must equal a fresh evaluation bit for bit.

use std::collections::BTreeMap;

use ductile_core::ffsd::{ControlPoint, FfsdMacro, FfsdTool, PointMode};
use ductile_core::influence::{Falloff, Shape};
use ductile_core::mesh::{Deformed, Mesh, RestMesh};
use ductile_core::primitives::grid;
use ductile_core::stack::{LayerBinding, Stack};
use glam::{Quat, Vec3};
use proptest::prelude::*;

use super::*;
use crate::document::{
    InfluenceSpec, LayerSpec, MacroUse, MeshNode, Node, NodeKind, RegionShape, VolumeNode,
};
use crate::transform::Transform;

const ROWS: usize = 16;
const COLUMNS: usize = 24;

/// A tube of `ROWS × COLUMNS` welded vertices, stored with a seam: column `COLUMNS` is a
/// bit-equal copy of column 0.
fn tube() -> Mesh {
    grid(ROWS, COLUMNS + 1, false, |r, c| {
        let a = std::f32::consts::TAU * (c % COLUMNS) as f32 / COLUMNS as f32;
        Vec3::new(a.cos(), r as f32 * 0.2, a.sin())
    })
}

fn rest() -> RestMesh {
    RestMesh::new(tube(), "tube").unwrap()
}

fn node(name: &str, parent: Option<&str>, kind: NodeKind) -> Node {
    Node {
        name: name.to_owned(),
        parent: parent.map(str::to_owned),
        transform: Transform::IDENTITY,
        kind,
    }
}

fn with_area(tool: &str, area: &str) -> LayerSpec {
    LayerSpec {
        influence: Some(InfluenceSpec {
            area: Some(area.to_owned()),
            ..InfluenceSpec::default()
        }),
        ..LayerSpec::new(tool)
    }
}

fn ffsd(points: Vec<ControlPoint>) -> NodeKind {
    NodeKind::Tool(Tool::Ffsd(FfsdTool::new(points)))
}

/// Names of the tool nodes layers may use.
const TOOLS: [&str; 5] = ["mac", "mac2", "free", "dir", "wide"];

/// The test scene: mesh `m` with five layers (a macro in a region area, a free tool on the
/// whole mesh, a directional point in a vertex area and a volume, a wide point limited by
/// the volume only, a second macro in a box area), mesh `other`, an unrelated group.
fn scene() -> Document {
    let areas = BTreeMap::from([
        (
            "top".to_owned(),
            Area::Region(vec![RegionShape {
                shape: Shape::Sphere { radius: 0.6 },
                transform: Transform::from_translation(Vec3::new(0.0, 2.6, 1.0)),
            }]),
        ),
        (
            "front".to_owned(),
            Area::Vertices((0..(ROWS * (COLUMNS + 1)) as u32).step_by(3).collect()),
        ),
        (
            "band".to_owned(),
            Area::Region(vec![RegionShape {
                shape: Shape::Box {
                    half_extents: Vec3::new(2.0, 0.3, 2.0),
                },
                transform: Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            }]),
        ),
    ]);
    let stack = vec![
        with_area("mac", "top"),
        LayerSpec::new("free"),
        LayerSpec {
            influence: Some(InfluenceSpec {
                volumes: vec!["vol".to_owned()],
                area: Some("front".to_owned()),
                falloff: Falloff::Smooth,
                inner: 0.2,
                invert: false,
            }),
            ..LayerSpec::new("dir")
        },
        LayerSpec {
            influence: Some(InfluenceSpec {
                volumes: vec!["vol".to_owned()],
                ..InfluenceSpec::default()
            }),
            weight: 0.7,
            ..LayerSpec::new("wide")
        },
        with_area("mac2", "band"),
    ];
    let macros = BTreeMap::from([(
        "bump".to_owned(),
        FfsdMacro {
            label: "Bump".to_owned(),
            group: "Test".to_owned(),
            area: Some("top".to_owned()),
            points: vec![ControlPoint::basic(Vec3::new(0.0, 2.6, 1.3), 0.4, 2.0, 0.3)],
            height: None,
            range: (-1.0, 1.0),
        },
    )]);
    Document {
        nodes: vec![
            node(
                "m",
                None,
                NodeKind::Mesh(MeshNode {
                    source: "tube.obj".to_owned(),
                    stack,
                    areas,
                }),
            ),
            node("g", Some("m"), NodeKind::Group),
            node(
                "vol",
                Some("g"),
                NodeKind::Volume(VolumeNode {
                    shape: Shape::Sphere { radius: 0.9 },
                }),
            ),
            node(
                "mac",
                Some("m"),
                NodeKind::Macro(MacroUse {
                    name: "bump".to_owned(),
                    value: 0.5,
                }),
            ),
            node(
                "mac2",
                Some("m"),
                NodeKind::Macro(MacroUse {
                    name: "bump".to_owned(),
                    value: 0.0,
                }),
            ),
            node(
                "free",
                Some("g"),
                ffsd(vec![ControlPoint::basic(
                    Vec3::new(1.2, 0.5, 0.0),
                    0.2,
                    2.0,
                    0.5,
                )]),
            ),
            node(
                "dir",
                Some("m"),
                ffsd(vec![ControlPoint {
                    position: Vec3::new(0.0, 1.5, 1.4),
                    mode: PointMode::Directional {
                        reference: Vec3::new(0.0, 1.5, 0.9),
                    },
                    gamma: 0.3,
                    alpha: 2.0,
                    epsilon: 0.5,
                }]),
            ),
            node(
                "wide",
                Some("m"),
                ffsd(vec![ControlPoint::basic(
                    Vec3::new(0.0, 0.8, -1.4),
                    -0.3,
                    1.5,
                    0.6,
                )]),
            ),
            node(
                "other",
                None,
                NodeKind::Mesh(MeshNode {
                    source: "tube.obj".to_owned(),
                    stack: vec![LayerSpec::new("free2")],
                    areas: BTreeMap::new(),
                }),
            ),
            node(
                "free2",
                Some("other"),
                ffsd(vec![ControlPoint::basic(Vec3::ZERO, 0.1, 2.0, 0.5)]),
            ),
            node("unrelated", None, NodeKind::Group),
        ],
        macros,
        ..Document::default()
    }
}

/// One edit of the scene.
#[derive(Debug, Clone)]
enum Edit {
    MacroValue(bool, f32),
    MovePoint(usize, Vec3),
    Weight(usize, f32),
    Toggle(usize),
    MoveVolume(Vec3),
    RotateGroup(f32),
    AreaRadius(f32),
    AreaVertices(u32),
    AddLayer(usize, usize, bool),
    RemoveLayer(usize),
    MoveLayer(usize, usize),
    OtherMesh(f32),
    Unrelated(f32),
}

impl Edit {
    /// True for edits that cannot change mesh `m`.
    fn is_unrelated(&self) -> bool {
        matches!(self, Edit::OtherMesh(_) | Edit::Unrelated(_))
    }

    fn apply(&self, doc: &mut Document) {
        let stack_len = doc.mesh("m").unwrap().stack.len();
        match *self {
            Edit::MacroValue(second, v) => {
                let name = if second { "mac2" } else { "mac" };
                if let NodeKind::Macro(m) = &mut doc.node_mut(name).unwrap().kind {
                    m.value = v;
                }
            }
            Edit::MovePoint(t, d) => {
                let name = ["free", "dir", "wide"][t % 3];
                if let NodeKind::Tool(Tool::Ffsd(f)) = &mut doc.node_mut(name).unwrap().kind {
                    f.points[0].position += d;
                }
            }
            Edit::Weight(l, w) if stack_len > 0 => {
                doc.mesh_mut("m").unwrap().stack[l % stack_len].weight = w;
            }
            Edit::Toggle(l) if stack_len > 0 => {
                let layer = &mut doc.mesh_mut("m").unwrap().stack[l % stack_len];
                layer.enabled = !layer.enabled;
            }
            Edit::MoveVolume(d) => doc.node_mut("vol").unwrap().transform.translation += d,
            Edit::RotateGroup(a) => {
                doc.node_mut("g").unwrap().transform.rotation = Quat::from_rotation_y(a);
            }
            Edit::AreaRadius(r) => {
                if let Some(Area::Region(shapes)) = doc.mesh_mut("m").unwrap().areas.get_mut("top")
                {
                    shapes[0].shape = Shape::Sphere { radius: r };
                }
            }
            Edit::AreaVertices(start) => {
                let count = (ROWS * (COLUMNS + 1)) as u32;
                doc.mesh_mut("m").unwrap().areas.insert(
                    "front".to_owned(),
                    Area::Vertices((start % 5..count).step_by(3).collect()),
                );
            }
            Edit::AddLayer(t, at, area) => {
                let tool = TOOLS[t % TOOLS.len()];
                let spec = if area {
                    with_area(tool, ["top", "front", "band"][t % 3])
                } else {
                    LayerSpec::new(tool)
                };
                doc.mesh_mut("m")
                    .unwrap()
                    .stack
                    .insert(at % (stack_len + 1), spec);
            }
            Edit::RemoveLayer(l) if stack_len > 0 => {
                doc.mesh_mut("m").unwrap().stack.remove(l % stack_len);
            }
            Edit::MoveLayer(from, to) if stack_len > 0 => {
                let stack = &mut doc.mesh_mut("m").unwrap().stack;
                let layer = stack.remove(from % stack_len);
                stack.insert(to % stack_len, layer);
            }
            Edit::OtherMesh(v) => {
                if let NodeKind::Tool(Tool::Ffsd(f)) = &mut doc.node_mut("free2").unwrap().kind {
                    f.points[0].gamma = v;
                }
            }
            Edit::Unrelated(x) => doc.node_mut("unrelated").unwrap().transform.translation.x = x,
            _ => {}
        }
    }
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (-0.3_f32..0.3, -0.3_f32..0.3, -0.3_f32..0.3).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => (any::<bool>(), prop_oneof![Just(0.0_f32), -1.0_f32..1.0])
            .prop_map(|(s, v)| Edit::MacroValue(s, v)),
        2 => (0..3_usize, vec3()).prop_map(|(t, d)| Edit::MovePoint(t, d)),
        1 => (0..8_usize, prop_oneof![Just(0.0_f32), Just(1.0_f32), 0.0_f32..1.0])
            .prop_map(|(l, w)| Edit::Weight(l, w)),
        1 => (0..8_usize).prop_map(Edit::Toggle),
        1 => vec3().prop_map(Edit::MoveVolume),
        1 => (-1.0_f32..1.0).prop_map(Edit::RotateGroup),
        1 => (0.2_f32..1.2).prop_map(Edit::AreaRadius),
        1 => (0..5_u32).prop_map(Edit::AreaVertices),
        1 => (0..5_usize, 0..8_usize, any::<bool>()).prop_map(|(t, a, b)| Edit::AddLayer(t, a, b)),
        1 => (0..8_usize).prop_map(Edit::RemoveLayer),
        1 => (0..8_usize, 0..8_usize).prop_map(|(a, b)| Edit::MoveLayer(a, b)),
        1 => (-1.0_f32..1.0).prop_map(Edit::OtherMesh),
        1 => (-1.0_f32..1.0).prop_map(Edit::Unrelated),
    ]
}

fn bits(d: &Deformed) -> (Vec<[u32; 3]>, Vec<[u32; 3]>) {
    let b = |v: &Vec<Vec3>| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    (b(&d.positions), b(&d.normals))
}

/// The evaluator's output equals a fresh evaluation of `doc` bit for bit (or both fail).
fn check_against_fresh(
    ev: &MeshEvaluator,
    update: &Result<Update>,
    doc: &Document,
    rest: &RestMesh,
) {
    match doc.evaluate("m", rest) {
        Ok(expected) => {
            assert!(
                update.is_ok(),
                "fresh evaluation succeeded, update failed: {update:?}"
            );
            let got = ev.deformed().expect("an output after a successful update");
            assert!(
                bits(got) == bits(&expected),
                "output differs from Document::evaluate"
            );
            assert_eq!(got.refined, expected.refined);
        }
        Err(e) => assert!(
            update.is_err(),
            "fresh evaluation failed ({e}), update did not"
        ),
    }
}

/// Layer `k`'s heat maps against an oracle: its input is the stack below it evaluated
/// from scratch, its output the stack up to it.
fn check_heat_maps(ev: &MeshEvaluator, doc: &Document, rest: &RestMesh, k: usize) {
    let stack = doc.resolve_stack("m", rest).unwrap();
    let below = Stack {
        layers: stack.layers[..k].to_vec(),
    };
    let upto = Stack {
        layers: stack.layers[..=k].to_vec(),
    };
    let input = below.evaluate_welded(rest).unwrap();
    let output = upto.evaluate_welded(rest).unwrap();
    let layer = &stack.layers[k];
    let topo = rest.topology();
    let displacement: Vec<f32> = input
        .iter()
        .zip(&output)
        .map(|(a, b)| (*b - *a).length())
        .collect();
    assert_eq!(
        ev.layer_displacement(k).unwrap(),
        topo.scatter(&displacement)
    );
    let mut weights = vec![0.0_f32; input.len()];
    if layer.enabled && layer.weight != 0.0 {
        let mask = LayerBinding::bind(layer, &input, topo).unwrap().mask;
        for (&i, &w) in mask.indices.iter().zip(&mask.weights) {
            weights[i as usize] = w * layer.weight;
        }
    }
    assert_eq!(ev.layer_weights(k).unwrap(), topo.scatter(&weights));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_edits_match_a_fresh_evaluation(edits in prop::collection::vec(edit(), 1..12)) {
        let rest = rest();
        let mut doc = scene();
        let mut ev = MeshEvaluator::new("m", rest.clone());
        let first = ev.update(&doc);
        check_against_fresh(&ev, &first, &doc, &rest);
        for e in &edits {
            e.apply(&mut doc);
            let update = ev.update(&doc);
            check_against_fresh(&ev, &update, &doc, &rest);
            if e.is_unrelated() {
                let u = *update.as_ref().unwrap();
                prop_assert!(!u.changed && u.layers_evaluated == 0, "{e:?} gave {u:?}");
            }
            if let Ok(u) = &update {
                let len = doc.mesh("m").unwrap().stack.len();
                if len > 0 {
                    check_heat_maps(&ev, &doc, &rest, u.first_layer.min(len - 1));
                }
            }
        }
        // Nothing changed: no work.
        let again = ev.update(&doc);
        if let Ok(u) = again {
            prop_assert_eq!(u, Update { changed: false, first_layer: u.first_layer, layers_evaluated: 0 });
        }
    }
}

#[test]
fn a_slider_change_reevaluates_only_its_layer_and_those_it_touches() {
    let rest = rest();
    let mut doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    let u = ev.update(&doc).unwrap();
    // Layers 0..4 are live; `mac2` (value 0) is inert.
    assert_eq!(
        u,
        Update {
            changed: true,
            first_layer: 0,
            layers_evaluated: 4
        }
    );
    // The top macro: `free` (whole mesh) must follow, `dir` (front ∩ vol) and `wide` (vol)
    // read every vertex or not depending on their domain; the output must match.
    for (value, expect_change) in [(0.7, true), (0.7, false), (0.0, true)] {
        if let NodeKind::Macro(m) = &mut doc.node_mut("mac").unwrap().kind {
            m.value = value;
        }
        let u = ev.update(&doc).unwrap();
        assert_eq!(u.changed, expect_change, "value {value}: {u:?}");
        check_against_fresh(&ev, &Ok(u), &doc, &rest);
    }
    // The second macro, alone in its band area at the top of the stack: one layer.
    if let NodeKind::Macro(m) = &mut doc.node_mut("mac2").unwrap().kind {
        m.value = 0.8;
    }
    let u = ev.update(&doc).unwrap();
    assert_eq!(
        u,
        Update {
            changed: true,
            first_layer: 4,
            layers_evaluated: 1
        }
    );
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    // Moving the volume re-evaluates `dir` and `wide` but not the layers below.
    doc.node_mut("vol").unwrap().transform.translation.x += 0.1;
    let u = ev.update(&doc).unwrap();
    assert_eq!(u.first_layer, 2);
    assert!(u.layers_evaluated >= 2, "{u:?}");
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
}

#[test]
fn a_change_to_a_disjoint_area_keeps_the_bindings_above() {
    // Two macros in disjoint areas: changing the lower one must not rebind the upper one.
    let rest = rest();
    let mut doc = scene();
    let stack = &mut doc.mesh_mut("m").unwrap().stack;
    *stack = vec![with_area("mac2", "band"), with_area("mac", "top")];
    if let NodeKind::Macro(m) = &mut doc.node_mut("mac2").unwrap().kind {
        m.value = 0.5;
    }
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    if let NodeKind::Macro(m) = &mut doc.node_mut("mac2").unwrap().kind {
        m.value = -0.5;
    }
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    // The band (y in [0.7, 1.3]) and the top sphere (y around 2.6) share no vertex.
    assert_eq!(
        u,
        Update {
            changed: true,
            first_layer: 0,
            layers_evaluated: 1
        }
    );
}

#[test]
fn areas_are_resolved_once_until_their_definition_changes() {
    let rest = rest();
    let mut doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    // top, front, band.
    assert_eq!(ev.area_resolutions(), 3);
    for v in [0.1, 0.2, 0.3] {
        if let NodeKind::Macro(m) = &mut doc.node_mut("mac").unwrap().kind {
            m.value = v;
        }
        ev.update(&doc).unwrap();
    }
    assert_eq!(ev.area_resolutions(), 3);
    Edit::AreaRadius(0.8).apply(&mut doc);
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    assert_eq!(ev.area_resolutions(), 4);
    ev.update(&doc).unwrap();
    assert_eq!(ev.area_resolutions(), 4);
}

#[test]
fn errors_keep_the_last_result_and_recover() {
    let rest = rest();
    let mut doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    let good = ev.deformed().unwrap().clone();
    doc.mesh_mut("m").unwrap().stack[1].weight = f32::NAN;
    assert!(ev.update(&doc).is_err());
    assert_eq!(ev.deformed(), Some(&good));
    doc.mesh_mut("m").unwrap().stack[1].weight = 0.5;
    let u = ev.update(&doc).unwrap();
    assert!(u.changed);
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    // An unknown mesh is an error, not a panic.
    let mut missing = MeshEvaluator::new("nope", rest);
    assert!(missing.update(&doc).is_err());
    assert!(missing.deformed().is_none());
    assert!(missing.layer_weights(0).is_none());
}

#[test]
fn heat_maps_of_inert_layers_and_out_of_range() {
    let rest = rest();
    let doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    assert!(ev.layer_weights(0).is_none());
    ev.update(&doc).unwrap();
    // `mac2` at 0 (layer 4) is inert: no displacement, but its mask is shown.
    check_heat_maps(&ev, &doc, &rest, 4);
    assert!(ev.layer_weights(4).unwrap().iter().any(|&w| w > 0.0));
    assert!(ev.layer_displacement(4).unwrap().iter().all(|&d| d == 0.0));
    for k in 0..4 {
        check_heat_maps(&ev, &doc, &rest, k);
    }
    assert!(ev.layer_weights(5).is_none());
    assert!(ev.layer_displacement(5).is_none());
}

#[test]
fn evaluator_is_send() {
    fn send<T: Send>() {}
    send::<MeshEvaluator>();
}

#[test]
fn a_rebound_layer_with_the_same_bind_is_refreshed_exactly() {
    // The macro moves the top of the tube; `free` (whole mesh, anchor near y = 0.5) reads
    // those vertices, so it is bound again, but its anchor did not move: same bind, and
    // only the moved vertices are deformed again.
    let rest = rest();
    let mut doc = scene();
    let stack = &mut doc.mesh_mut("m").unwrap().stack;
    *stack = vec![with_area("mac", "top"), LayerSpec::new("free")];
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    for value in [-0.5, 0.9, 0.0, 0.3] {
        if let NodeKind::Macro(m) = &mut doc.node_mut("mac").unwrap().kind {
            m.value = value;
        }
        let before = ev.refreshed;
        let u = ev.update(&doc).unwrap();
        check_against_fresh(&ev, &Ok(u), &doc, &rest);
        // At 0 the macro is inert and `free` is the first layer that differs in the chain.
        if value != 0.0 {
            assert_eq!(u.layers_evaluated, 2, "{value}: {u:?}");
            assert_eq!(ev.refreshed, before + 1, "{value}");
        }
    }
}

/// A layer whose tool binds again (an FFSD point moved) while its influence and the input
/// its mask reads are unchanged keeps its mask (the same allocation: the volume weights are
/// not computed again), and the result is bit-identical to a fresh evaluation; a moved
/// volume makes a new mask.
#[test]
fn a_rebound_tool_keeps_its_mask() {
    let rest = rest();
    let mut doc = scene();
    // The volume on the tube's wall, so that both layers it limits hold vertices.
    doc.node_mut("vol").unwrap().transform.translation = Vec3::new(0.7, 1.2, 0.0);
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    let mask_of = |ev: &MeshEvaluator, layer: &str| {
        let stage = ev
            .stages
            .iter()
            .find(|s| s.resolved.layer.name == layer)
            .expect("the layer has a stage");
        Arc::clone(&stage.binding.mask)
    };
    for (step, layer) in ["wide", "dir", "wide"].into_iter().enumerate() {
        let before = mask_of(&ev, layer);
        assert!(!before.is_empty(), "{layer}: its volume holds vertices");
        if let NodeKind::Tool(Tool::Ffsd(f)) = &mut doc.node_mut(layer).unwrap().kind {
            f.points[0].position += Vec3::new(0.05, -0.03, 0.02) * (step + 1) as f32;
        }
        let binds = ev.binds();
        let u = ev.update(&doc);
        check_against_fresh(&ev, &u, &doc, &rest);
        assert!(ev.binds() > binds, "{layer}: a moved point binds again");
        assert!(
            Arc::ptr_eq(&before, &mask_of(&ev, layer)),
            "{layer}: the mask is kept"
        );
    }
    let before = mask_of(&ev, "wide");
    doc.node_mut("vol").unwrap().transform.translation += Vec3::new(0.2, 0.0, 0.0);
    let u = ev.update(&doc);
    check_against_fresh(&ev, &u, &doc, &rest);
    assert!(
        !Arc::ptr_eq(&before, &mask_of(&ev, "wide")),
        "a moved volume makes a new mask"
    );
}

/// A Bernstein 2×2×2 lattice over `x, z ∈ [−1.2, 1.2]`, `y ∈ [y0, y0 + height]`, its
/// control point (1, 1, 1) moved by `offset`.
fn band_lattice(y0: f32, height: f32, offset: Vec3) -> Tool {
    use ductile_core::lattice::{ControlEdit, LatticeBasis, LatticeFrame, LatticeTool};
    Tool::Lattice(LatticeTool {
        frame: LatticeFrame {
            origin: Vec3::new(-1.2, y0, -1.2),
            s: Vec3::new(2.4, 0.0, 0.0),
            t: Vec3::new(0.0, height, 0.0),
            u: Vec3::new(0.0, 0.0, 2.4),
        },
        counts: (2, 2, 2),
        basis: LatticeBasis::Bernstein,
        points: vec![ControlEdit {
            at: (1, 1, 1),
            offset,
            weight: 1.0,
        }],
        falloff: 0.0,
    })
}

/// A tool whose deformed state changes (a sketch bend's target, a curve's deformed control
/// points, a lattice's control points) on an unchanged input keeps its binding — for the
/// sketch tool its region of interest, skinning and Eq. 9 factorisation — and the result is
/// still bit-identical to a fresh evaluation; a change of its rest state binds again.
#[test]
fn a_changed_deformed_state_keeps_the_binding() {
    use ductile_core::curve::{CurveBasis, CurveTool};
    use ductile_core::sketch::partition::Partition;
    use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};

    let rest = rest();
    let roi: Vec<u32> = (0..ROWS * COLUMNS)
        .filter(|&i| (4..12).contains(&(i / COLUMNS)))
        .map(|i| i as u32)
        .collect();
    let up = |x: f32| {
        vec![
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::new(x, 1.6, 0.0),
            Vec3::new(x, 2.4, 0.0),
        ]
    };
    let sketch = |x: f32| {
        Tool::Sketch(Box::new(SketchTool {
            partition: Some(Partition {
                roi: roi.clone(),
                rigid: Vec::new(),
            }),
            reference: Curve::Points(up(0.0)),
            normal: Some(Vec3::Z),
            mode: SketchMode::Bend {
                target: Curve::Points(up(x)),
                turning: None,
            },
            scale: None,
            smooth: true,
            refine: None,
        }))
    };
    let curve = |y: f32| {
        Tool::Curve(CurveTool {
            basis: CurveBasis::BSpline { degree: 2 },
            rest: vec![
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
            ],
            deformed: vec![
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, y, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
            ],
        })
    };
    let lattice = |dz: f32| band_lattice(2.0, 1.2, Vec3::new(0.0, 0.0, dz));
    let mut doc = scene();
    doc.mesh_mut("m").unwrap().stack = vec![
        LayerSpec::new("bend"),
        LayerSpec::new("crv"),
        LayerSpec::new("lat"),
    ];
    for (name, tool) in [
        ("bend", sketch(0.3)),
        ("crv", curve(0.2)),
        ("lat", lattice(0.1)),
    ] {
        doc.nodes.push(node(name, Some("m"), NodeKind::Tool(tool)));
    }
    let mut ev = MeshEvaluator::new("m", rest.clone());
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    let binds = ev.binds();
    assert_eq!(binds, 3);
    for (k, x) in [0.5_f32, -0.4, 0.1].into_iter().enumerate() {
        doc.node_mut("bend").unwrap().kind = NodeKind::Tool(sketch(x));
        if k == 1 {
            doc.node_mut("lat").unwrap().kind = NodeKind::Tool(lattice(x));
        }
        let u = ev.update(&doc).unwrap();
        check_against_fresh(&ev, &Ok(u), &doc, &rest);
        // The sketch layer kept its binding; the layers above read moved vertices, so they
        // bind again.
        assert_eq!(u.first_layer, 0);
        assert_eq!(ev.binds(), binds + 2 * (k + 1), "frame {k}");
    }
    // Only the top layer changes: only it is bound again (a lattice's bind is its prepared
    // control grid, made from the tool alone, so it is always made anew).
    let before = ev.binds();
    doc.node_mut("lat").unwrap().kind = NodeKind::Tool(lattice(0.35));
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    assert_eq!((u.layers_evaluated, ev.binds()), (1, before + 1));
    // The curve keeps its binding; the lattice above reads moved vertices.
    doc.node_mut("crv").unwrap().kind = NodeKind::Tool(curve(-0.3));
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    assert_eq!(ev.binds(), before + 2);
    // A new reference curve is a new rest state: bound again.
    let before = ev.binds();
    if let NodeKind::Tool(Tool::Sketch(t)) = &mut doc.node_mut("bend").unwrap().kind {
        t.reference = Curve::Points(up(0.05));
    }
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    assert!(ev.binds() > before);
}

/// A soloed layer evaluates alone: the same result as every other layer disabled.
#[test]
fn a_soloed_layer_evaluates_alone() {
    let rest = rest();
    let mut doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    doc.mesh_mut("m").unwrap().stack[1].solo = true;
    let u = ev.update(&doc).unwrap();
    check_against_fresh(&ev, &Ok(u), &doc, &rest);
    let mut alone = doc.clone();
    for (i, l) in alone.mesh_mut("m").unwrap().stack.iter_mut().enumerate() {
        l.solo = false;
        l.enabled = i == 1;
    }
    assert_eq!(
        bits(ev.deformed().unwrap()),
        bits(&alone.evaluate("m", &rest).unwrap())
    );
}

#[test]
fn kept_stages_follow_their_layers_when_inert_layers_move() {
    // Found by `random_edits_match_a_fresh_evaluation`: with `mac` inert (value 0), a layer
    // inserted at the bottom leaves the first non-inert layer unchanged, so its stage is
    // kept — but its stack index moved, and the heat maps of the next edit read the stage
    // of the wrong layer.
    let rest = rest();
    let mut doc = scene();
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    for e in [
        Edit::MacroValue(false, 0.0),
        Edit::AddLayer(2, 0, false),
        Edit::MacroValue(false, 0.4240849),
    ] {
        e.apply(&mut doc);
        let u = ev.update(&doc).unwrap();
        check_against_fresh(&ev, &Ok(u), &doc, &rest);
        let len = doc.mesh("m").unwrap().stack.len();
        for k in 0..len {
            check_heat_maps(&ev, &doc, &rest, k);
        }
    }
}

/// Layers above a changed layer whose tools bind per vertex (curve, axis, shape surface,
/// lattice), limited by a volume the changed layer moves vertices into and out of, are
/// refreshed: only the moved vertices are weighed, bound and deformed again, and the result
/// is bit-identical to a fresh evaluation.
#[test]
fn layers_above_a_change_are_refreshed_on_the_moved_vertices() {
    use ductile_core::axial::{AxialTool, AxisPoint};
    use ductile_core::curve::{CurveBasis, CurveTool};
    use ductile_core::lattice::{ControlEdit, LatticeFrame, LatticeTool};
    use ductile_core::surface::{ShapeSurfaceTool, SurfaceEdit, SurfaceFrame};

    let rest = rest();
    let mut doc = scene();
    let axis: Vec<AxisPoint> = [2.0, 2.6, 3.2]
        .map(|y| AxisPoint {
            position: Vec3::new(0.0, y, 1.0),
            twist: 0.0,
            scale: 1.0,
        })
        .to_vec();
    let mut axial = AxialTool::new(axis, 0.8);
    axial.deformed[1].position += Vec3::new(0.1, 0.0, 0.1);
    let curve_rest = vec![
        Vec3::new(-1.0, 2.6, 1.0),
        Vec3::new(0.0, 2.6, 1.2),
        Vec3::new(1.0, 2.6, 1.0),
    ];
    let mut curve = CurveTool::new(CurveBasis::Bezier, curve_rest);
    curve.deformed[1] += Vec3::new(0.0, 0.2, 0.1);
    let mut surface = ShapeSurfaceTool::planar(
        SurfaceFrame {
            origin: Vec3::new(-1.0, 2.0, 1.0),
            u_edge: Vec3::new(2.0, 0.0, 0.0),
            v_edge: Vec3::new(0.0, 1.2, 0.0),
        },
        (4, 4),
    );
    surface.moves.push(SurfaceEdit {
        at: (1, 1),
        offset: Vec3::new(0.0, 0.0, 0.3),
    });
    let mut lattice = LatticeTool::bernstein(
        LatticeFrame {
            origin: Vec3::new(-1.2, 1.8, -0.2),
            s: Vec3::new(2.4, 0.0, 0.0),
            t: Vec3::new(0.0, 1.4, 0.0),
            u: Vec3::new(0.0, 0.0, 1.6),
        },
        (3, 3, 3),
    );
    lattice.points.push(ControlEdit {
        at: (1, 2, 1),
        offset: Vec3::new(0.1, 0.2, 0.0),
        weight: 1.0,
    });
    let above = ["crv", "ax", "srf", "lat"];
    for (name, tool) in above.into_iter().zip([
        Tool::Curve(curve),
        Tool::Axial(axial),
        Tool::ShapeSurface(surface),
        Tool::Lattice(lattice),
    ]) {
        doc.nodes.push(node(name, Some("m"), NodeKind::Tool(tool)));
    }
    let mut vol = node(
        "vol2",
        Some("m"),
        NodeKind::Volume(VolumeNode {
            shape: Shape::Sphere { radius: 1.2 },
        }),
    );
    vol.transform.translation = Vec3::new(0.0, 1.6, 1.0);
    doc.nodes.push(vol);
    let mut stack = vec![with_area("mac", "top")];
    stack.extend(above.map(|name| LayerSpec {
        influence: Some(InfluenceSpec {
            volumes: vec!["vol2".to_owned()],
            falloff: Falloff::Smooth,
            inner: 0.2,
            ..InfluenceSpec::default()
        }),
        ..LayerSpec::new(name)
    }));
    doc.mesh_mut("m").unwrap().stack = stack;
    let mut ev = MeshEvaluator::new("m", rest.clone());
    ev.update(&doc).unwrap();
    let mask_len = |ev: &MeshEvaluator| {
        ev.stages
            .iter()
            .find(|s| s.resolved.layer.name == "crv")
            .map_or(0, |s| s.indices().len())
    };
    let mut lens = vec![mask_len(&ev)];
    for value in [-0.9, 0.9, 0.3, 0.0, 0.6] {
        if let NodeKind::Macro(m) = &mut doc.node_mut("mac").unwrap().kind {
            m.value = value;
        }
        let before = ev.refreshed;
        let u = ev.update(&doc);
        check_against_fresh(&ev, &u, &doc, &rest);
        assert_eq!(ev.refreshed, before + above.len(), "{value}: {u:?}");
        lens.push(mask_len(&ev));
    }
    assert!(
        lens.windows(2).any(|w| w[0] != w[1]),
        "vertices enter and leave the volume: {lens:?}"
    );
}

/// On a mesh above the parallel threshold, an edit that moves more than half of the vertices
/// recomputes every normal, one with more than 1/32 of them as candidates takes the block
/// sweeps of the output patch, and a smaller one follows each moved vertex. All three, one
/// after the other, must give a fresh evaluation's bits. The lattices move 61 %, 23 % and
/// 1.5 % of the vertices; the first edit of the widest follows the full evaluation (no face
/// cache yet), its later ones take the dense path. The mesh has a seam (stored copies) and a
/// vertex in no triangle inside the lattice, whose block holds nothing else that moves.
#[test]
fn large_edits_patch_the_output_in_blocks_exactly() {
    const ROWS: usize = 130;
    const COLUMNS: usize = 160;
    let mut mesh = grid(ROWS, COLUMNS + 1, false, |r, c| {
        let a = std::f32::consts::TAU * (c % COLUMNS) as f32 / COLUMNS as f32;
        Vec3::new(a.cos(), r as f32 * 0.1, a.sin())
    });
    mesh.normals = None;
    mesh.uvs = None;
    mesh.positions.push(Vec3::new(0.0, 5.0, 0.0));
    let rest = RestMesh::new(mesh, "big tube").unwrap();
    assert!(rest.welded_positions().len() >= PARALLEL_THRESHOLD);
    let lattice = |y0: f32, height: f32, dz: f32| band_lattice(y0, height, Vec3::new(0.1, 0.0, dz));
    let mut doc = scene();
    doc.mesh_mut("m").unwrap().stack = vec![
        LayerSpec::new("wide"),
        LayerSpec::new("middle"),
        LayerSpec::new("narrow"),
    ];
    doc.nodes.push(node(
        "wide",
        Some("m"),
        NodeKind::Tool(lattice(1.0, 8.0, 0.1)),
    ));
    doc.nodes.push(node(
        "middle",
        Some("m"),
        NodeKind::Tool(lattice(4.05, 3.0, 0.1)),
    ));
    doc.nodes.push(node(
        "narrow",
        Some("m"),
        NodeKind::Tool(lattice(11.55, 0.2, 0.1)),
    ));
    let mut ev = MeshEvaluator::new("m", rest.clone());
    let u = ev.update(&doc);
    check_against_fresh(&ev, &u, &doc, &rest);
    for (k, dz) in [0.3_f32, -0.2, 0.25, 0.05, -0.4, 0.2, 0.12, -0.3, 0.07]
        .into_iter()
        .enumerate()
    {
        let (name, y0, height) = match k % 3 {
            0 => ("wide", 1.0, 8.0),
            1 => ("middle", 4.05, 3.0),
            _ => ("narrow", 11.55, 0.2),
        };
        doc.node_mut(name).unwrap().kind = NodeKind::Tool(lattice(y0, height, dz));
        let u = ev.update(&doc);
        assert!(u.as_ref().is_ok_and(|u| u.changed), "edit {k}: {u:?}");
        check_against_fresh(&ev, &u, &doc, &rest);
    }
    // More sweeps than the sweep stamps have values (255): they wrap and start again.
    for k in 0..300 {
        let dz = if k % 2 == 0 { 0.15 } else { -0.1 };
        doc.node_mut("middle").unwrap().kind = NodeKind::Tool(lattice(4.05, 3.0, dz));
        let u = ev.update(&doc);
        if k % 37 == 0 || k >= 250 && k % 5 == 0 {
            check_against_fresh(&ev, &u, &doc, &rest);
        }
    }
}

/// The merged settle of two stages with different active vertices leaves the set exactly
/// as the three passes it replaces (advance the old stage, advance the new, settle the
/// common vertices): the same flags, count and members, on a mesh long enough that the
/// merge runs in several parallel chunks, and with vertices of the old stage below the
/// new stage's first and above its last; then on one chunk, empty stages and a vertex past
/// the flags.
#[test]
fn a_merged_settle_is_the_three_passes() {
    let n = 5 * ductile_core::chunks::CHUNK + 777;
    let mut state = 0x9e37_79b9_u32;
    let mut r = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    let stage = |indices: Vec<u32>, r: &mut dyn FnMut() -> u32| {
        // Inputs and outputs of three kinds: moved, kept, and (for the common vertices)
        // the same output as the other stage.
        let saved: Vec<Vec3> = indices.iter().map(|&v| Vec3::splat(v as f32)).collect();
        let written = indices
            .iter()
            .map(|&v| match r() % 3 {
                0 => Vec3::splat(v as f32),
                1 => Vec3::new(v as f32, 1.0, 0.0),
                _ => Vec3::new(v as f32, 0.0, (r() % 2) as f32),
            })
            .collect();
        Stage {
            index: 0,
            resolved: Resolved {
                layer: Layer::new("l", Tool::Ffsd(FfsdTool::new(Vec::new()))),
                area: None,
            },
            binding: LayerBinding {
                mask: Arc::new(Mask {
                    weights: vec![1.0; indices.len()],
                    indices,
                }),
                bind: None,
            },
            saved,
            written,
        }
    };
    let mut cases: Vec<(Vec<u32>, Vec<u32>)> = (0..4)
        .map(|_| {
            let old: Vec<u32> = (0..n as u32).filter(|&v| v < 300 || r() % 4 != 0).collect();
            let new: Vec<u32> = (300..n as u32 - 200).filter(|_| r() % 3 != 0).collect();
            (old, new)
        })
        .collect();
    let every: Vec<u32> = (0..n as u32).collect();
    // One chunk of the new stage (run in place) against an old stage over the whole mesh.
    cases.push((every.clone(), (1000..1100).collect()));
    // An empty new stage, then an empty old one.
    cases.push((every.clone(), Vec::new()));
    cases.push((Vec::new(), every.clone()));
    // A vertex past the flags: the three passes themselves run (they ignore it), so this
    // compares them with themselves; it fails if the guard goes, when the in-place merge
    // would index the flags past their end.
    cases.push((every.clone(), (0..n as u32 + 3).step_by(2).collect()));
    for (round, (old_idx, new_idx)) in cases.into_iter().enumerate() {
        let old = stage(old_idx, &mut r);
        let new = stage(new_idx, &mut r);
        let mut reference = Dirty::default();
        reference.reset(n);
        for v in 0..n as u32 {
            if r() % 5 == round as u32 % 5 {
                reference.insert(v);
            }
        }
        let mut merged = Dirty {
            flag: reference.flag.clone(),
            list: reference.list.clone(),
            count: reference.count,
        };
        reference.advance_old(&old);
        reference.advance_new(&new);
        reference.settle_common(&old, &new);
        merged.settle_merged(&old, &new);
        assert_eq!(merged.flag, reference.flag, "round {round}");
        assert_eq!(merged.count, reference.count, "round {round}");
        let members = |d: &mut Dirty| {
            let mut m = d.drain();
            m.sort_unstable();
            m
        };
        assert_eq!(
            members(&mut merged),
            members(&mut reference),
            "round {round}"
        );
    }
}
