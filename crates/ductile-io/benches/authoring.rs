//! Criterion benchmark: the evaluation work behind the Studio's authoring (issue 13), what
//! the frame after a click or a drag runs — [`MeshEvaluator::update`] on the identikit head
//! scene (45 macro layers, all at 0, as the Studio opens it) with the head split 5×5
//! ([`ductile_core::primitives::subdivided_n`], 221,052 welded vertices, `head-221k`):
//!
//! * `add/<kind>/head-221k` — after Add ▸ `<kind>` (the very operation the Add menu applies:
//!   [`Operation::add_tool_layer`] with the tool [`create::tool`] places around the mesh, a new
//!   top layer); the add is undone (untimed) between iterations.
//! * `edit/<kind>/head-221k` — after the tool's moved state changes (what dragging one of
//!   its handles or an inspector field of a selected point does: γ of an FFSD point, a
//!   constraint's displacement, the last deformed axis or curve point, one lattice or
//!   shape-surface control point), alternating between two values; the layer keeps its
//!   binding.
//! * `rebind/<kind>/head-221k` — after a rest-state value changes (the tool's first
//!   parameter as [`tool_channels`] lists it: a point's position, a frame corner, the rest
//!   curve), which binds the layer again; the setup prints the parameter.
//! * `fs-edit/sketch-100k` — after one control value of a sketch tool's turning-angle F(s)
//!   changes, the region of interest being 100,000 vertices (the tube of the core `sketch`
//!   bench: 600 rings × 200 vertices, the middle 500 rings deformable, 100-node strokes).
//!
//! Targets (issue 13): ≤ 16 ms of evaluation per add or inspector change on the 221k head;
//! ≤ 50 ms per F(s) edit on the 100k sketch region.

use std::f32::consts::PI;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use ductile_anim::channel::{set_tool_channel, tool_channels};
use ductile_anim::value::Value;
use ductile_core::mesh::RestMesh;
use ductile_core::primitives::{self, subdivided_n};
use ductile_core::sketch::partition::Partition;
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool};
use ductile_core::spline::SplineControl;
use ductile_core::tool::Tool;
use ductile_history::operation::Operation;
use ductile_scene::create::{self, NewTool, Placement};
use ductile_scene::prelude::*;
use glam::{Quat, Vec3};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn big_head() -> RestMesh {
    let path = root().join("assets/meshes/lee-perry-smith-head.glb");
    let rest =
        ductile_io::load_rest_mesh(&ductile_io::MeshRef::parse(path.to_str().expect("path")))
            .expect("head mesh");
    RestMesh::new(subdivided_n(rest.mesh(), 5), "head split 5×5").expect("subdivided head")
}

/// `v` moved a little (a different value of the same kind; curves and axes translate).
fn nudged(v: &Value, flip: bool) -> Value {
    let k = if flip { 1.1 } else { 1.0 };
    let shift = Vec3::splat(if flip { 0.01 } else { 0.0 });
    match v {
        Value::Polyline(p) => Value::Polyline(p.iter().map(|q| *q + shift).collect()),
        Value::Axis(a) => Value::Axis(
            a.iter()
                .map(|q| ductile_core::axial::AxisPoint {
                    position: q.position + shift,
                    ..*q
                })
                .collect(),
        ),
        Value::Scalar(x) => Value::Scalar(x * k + if flip { 0.01 } else { 0.0 }),
        Value::Vector(p) => Value::Vector(*p * k + Vec3::splat(if flip { 0.01 } else { 0.0 })),
        Value::Rotation(q) => Value::Rotation(if flip {
            *q * Quat::from_rotation_y(0.05)
        } else {
            *q
        }),
        Value::Values(xs) => Value::Values(xs.iter().map(|x| x * k).collect()),
        other => other.clone(),
    }
}

fn add_tool(doc: &Document, kind: NewTool, place: &Placement) -> (Operation, String) {
    Operation::add_tool_layer(
        doc,
        "head",
        kind.stem(),
        create::tool(kind, place),
        Transform::IDENTITY,
    )
    .expect("add operation")
}

fn authoring(c: &mut Criterion) {
    let rest = big_head();
    let place = Placement::on_mesh(&rest).expect("placement");
    let base = ductile_io::read_scene(root().join("scenes/identikit-head.ron")).expect("scene");
    eprintln!(
        "head split 5×5: {} welded vertices",
        rest.welded_positions().len()
    );
    let mut group = c.benchmark_group("add");
    for kind in NewTool::ALL {
        let mut ev = MeshEvaluator::new("head", rest.clone());
        ev.update(&base).expect("first update");
        let (op, name) = add_tool(&base, kind, &place);
        let mut with = base.clone();
        op.apply(&mut with).expect("apply");
        let u = ev.update(&with).expect("update");
        eprintln!("add {} ('{name}'): {u:?}", kind.label());
        ev.update(&base).expect("back");
        group.bench_function(format!("{}/head-221k", kind.stem_label()), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let t = Instant::now();
                    black_box(ev.update(black_box(&with)).expect("update"));
                    total += t.elapsed();
                    ev.update(&base).expect("undo");
                }
                total
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("edit");
    for kind in NewTool::ALL {
        let (op, name) = add_tool(&base, kind, &place);
        let mut doc = base.clone();
        op.apply(&mut doc).expect("apply");
        // What dragging a handle or an inspector field of the tool's moved state does.
        let edit = |doc: &mut Document, flip: bool| {
            if let NodeKind::Tool(t) = &mut doc.node_mut(&name).expect("node").kind {
                move_state(t, if flip { 1.0 } else { 0.5 });
            }
        };
        edit(&mut doc, false);
        bench_edit(&mut group, kind, "", &rest, doc, edit);
    }
    group.finish();

    let mut group = c.benchmark_group("rebind");
    for kind in NewTool::ALL {
        let (op, name) = add_tool(&base, kind, &place);
        let mut doc = base.clone();
        op.apply(&mut doc).expect("apply");
        if let NodeKind::Tool(t) = &mut doc.node_mut(&name).expect("node").kind {
            move_state(t, 0.5);
        }
        let tool = match &doc.node(&name).expect("node").kind {
            NodeKind::Tool(t) => t.clone(),
            _ => unreachable!("a tool node"),
        };
        // Its first parameter is a rest-state one (a position, a frame, a rest curve).
        let (path, value) = tool_channels(&tool)
            .into_iter()
            .next()
            .expect("a parameter");
        let edit = |doc: &mut Document, flip: bool| {
            if let NodeKind::Tool(t) = &mut doc.node_mut(&name).expect("node").kind {
                set_tool_channel(t, &path, &nudged(&value, flip)).expect("set");
            }
        };
        bench_edit(&mut group, kind, &path, &rest, doc, edit);
    }
    group.finish();

    fs_edit(c);
}

/// Times `update` after `edit(doc, flip)` with `flip` alternating; prints whether the
/// edit binds the layer again.
fn bench_edit(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    kind: NewTool,
    what: &str,
    rest: &RestMesh,
    mut doc: Document,
    edit: impl Fn(&mut Document, bool),
) {
    let mut ev = MeshEvaluator::new("head", rest.clone());
    ev.update(&doc).expect("first update");
    let binds = ev.binds();
    let mut flip = false;
    for _ in 0..2 {
        flip = !flip;
        edit(&mut doc, flip);
        ev.update(&doc).expect("update");
    }
    eprintln!(
        "{} {}: binds again: {}",
        kind.label(),
        what,
        ev.binds() > binds
    );
    group.bench_function(format!("{}/head-221k", kind.stem_label()), |b| {
        b.iter(|| {
            flip = !flip;
            edit(&mut doc, flip);
            black_box(ev.update(black_box(&doc)).expect("update"))
        })
    });
}

/// Sets the tool's moved state to `k` times a small move of its last control point (a
/// control value the user drags): γ for FFSD points, the displacement for DOGME and Direct
/// FFD constraints, the last deformed axis or curve point, one lattice control point and
/// one shape-surface point.
fn move_state(t: &mut Tool, k: f32) {
    match t {
        Tool::Ffsd(f) => f.points[0].gamma = k,
        Tool::Dogme(d) => {
            let c = &mut d.constraints[0];
            c.displacement = c.displacement.normalize_or_zero() * 0.2 * k;
        }
        Tool::DirectFfd(d) => {
            let c = &mut d.constraints[0];
            c.displacement = c.displacement.normalize_or_zero() * 0.2 * k;
        }
        Tool::Axial(a) => {
            let last = a.rest.len() - 1;
            a.deformed[last].position = a.rest[last].position + Vec3::Y * 0.5 * k;
        }
        Tool::Curve(c) => {
            let last = c.rest.len() - 1;
            c.deformed[last] = c.rest[last] + Vec3::Y * 0.5 * k;
        }
        Tool::Lattice(l) => {
            l.points = vec![ductile_core::lattice::ControlEdit {
                at: (l.counts.0 - 1, l.counts.1 - 1, l.counts.2 - 1),
                offset: Vec3::Y * 0.5 * k,
                weight: 1.0,
            }];
        }
        Tool::ShapeSurface(s) => {
            s.moves = vec![ductile_core::surface::SurfaceEdit {
                at: (1, 1),
                offset: Vec3::Z * 0.3 * k,
            }];
        }
        Tool::Sketch(_) => {}
    }
}

/// A short name for a tool kind in benchmark ids.
trait StemLabel {
    fn stem_label(self) -> String;
}

impl StemLabel for NewTool {
    fn stem_label(self) -> String {
        match self {
            NewTool::BezierCurve => "bezier-curve".to_owned(),
            NewTool::BSplineCurve => "bspline-curve".to_owned(),
            NewTool::Lattice(k) => format!("lattice-{k:?}").to_lowercase(),
            other => other.stem().to_owned(),
        }
    }
}

const RINGS: usize = 600;
const SEGMENTS: usize = 200;
const STEP: f32 = 0.02;

/// The sketch scene: the tube with a bend tool whose region of interest is its middle 500
/// rings (100,000 vertices), a straight reference and a U-shaped target, and a turning-angle
/// F(s) with 6 control values.
fn sketch_scene() -> (Document, RestMesh) {
    let mesh = primitives::grid(RINGS, SEGMENTS, true, |r, s| {
        let a = 2.0 * PI * s as f32 / SEGMENTS as f32;
        Vec3::new(r as f32 * STEP, 0.3 * a.cos(), 0.3 * a.sin())
    });
    let rest = RestMesh::new(mesh, "tube").expect("tube");
    let (x0, x1) = (50.0 * STEP, 549.0 * STEP);
    let (mut roi, mut rigid) = (Vec::new(), Vec::new());
    for (i, p) in rest.welded_positions().iter().enumerate() {
        if p.x >= x0 - 1e-4 && p.x <= x1 + 1e-4 {
            roi.push(i as u32);
        } else if p.x > x1 {
            rigid.push(i as u32);
        }
    }
    assert_eq!(roi.len(), 100_000);
    let line = |k: usize| Vec3::new(x0 + (x1 - x0) * k as f32 / 99.0, 0.0, 0.0);
    let reference: Vec<Vec3> = (0..100).map(line).collect();
    let len = x1 - x0;
    let target: Vec<Vec3> = (0..100)
        .map(|k| {
            let a = PI * k as f32 / 99.0;
            let r = len / PI;
            Vec3::new(x0 + r * a.sin(), r - r * a.cos(), 0.0)
        })
        .collect();
    let tool = Tool::Sketch(Box::new(SketchTool {
        partition: Some(Partition {
            roi,
            rigid: vec![rigid],
        }),
        reference: Curve::Points(reference),
        normal: Some(Vec3::Z),
        mode: SketchMode::Bend {
            target: Curve::Points(target),
            turning: Some(SplineControl::identity(6, 3)),
        },
        scale: None,
        smooth: true,
        refine: None,
    }));
    let doc = Document {
        nodes: vec![
            Node {
                name: "tube".to_owned(),
                parent: None,
                transform: Transform::IDENTITY,
                kind: NodeKind::Mesh(MeshNode {
                    source: "tube.obj".to_owned(),
                    stack: vec![LayerSpec::new("bend")],
                    areas: Default::default(),
                }),
            },
            Node {
                name: "bend".to_owned(),
                parent: Some("tube".to_owned()),
                transform: Transform::IDENTITY,
                kind: NodeKind::Tool(tool),
            },
        ],
        ..Document::default()
    };
    (doc, rest)
}

fn fs_edit(c: &mut Criterion) {
    let (mut doc, rest) = sketch_scene();
    let mut ev = MeshEvaluator::new("tube", rest);
    ev.update(&doc).expect("first update");
    let identity = SplineControl::identity(6, 3).values;
    let mut flip = false;
    let edit = |doc: &mut Document, flip: bool| {
        if let NodeKind::Tool(Tool::Sketch(s)) = &mut doc.node_mut("bend").expect("bend").kind
            && let SketchMode::Bend {
                turning: Some(f), ..
            } = &mut s.mode
        {
            // The F(s) editor drags one control value: the third, up by 0.1 or back.
            f.values.clone_from(&identity);
            if flip {
                f.values[2] += 0.1;
            }
        }
    };
    let binds = ev.binds();
    for _ in 0..2 {
        flip = !flip;
        edit(&mut doc, flip);
        eprintln!("fs-edit: {:?}", ev.update(&doc).expect("update"));
    }
    eprintln!("fs-edit: binds again: {}", ev.binds() > binds);
    let mut group = c.benchmark_group("fs-edit");
    group.sample_size(10);
    group.bench_function("sketch-100k", |b| {
        b.iter(|| {
            flip = !flip;
            edit(&mut doc, flip);
            black_box(ev.update(black_box(&doc)).expect("update"))
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = authoring
}
criterion_main!(benches);
