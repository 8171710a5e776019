//! Issue 14: every deformer maps finite input to finite output, or refuses its parameters at
//! the boundary.
//!
//! For every tool kind, random parameters are drawn: mostly ordinary values, but now and then
//! an extreme finite one (±1e30, ±1e-30, ±1e6, ±`f32::MAX`, 0, −0), coincident control points
//! or a degenerate frame. A tool may refuse them: [`Tool::validate`] or [`Tool::bind`]
//! returns an error, which the stack passes on to the user as it is. A tool that accepts them
//! must map every finite input point (a bumpy grid, points at ±1e6, tiny points, points
//! exactly on its own control points, a few random points) to a finite point.
//!
//! The stack's own check for non-finite output (the "non-finite position" error of
//! `LayerBinding`, and the sketch tool's "is not finite" error) is a last line of defence,
//! not a refusal: a case that reaches it fails the property, because it means the tool
//! accepted parameters it cannot evaluate.
//!
//! Each property also fails when too few of its cases were accepted (a quarter of a batch,
//! at most 16, within 32 batches; see `run_property`), since it would then check little or
//! nothing.

use std::cell::Cell;

use ductile_core::axial::{AxialTool, AxisPoint, AxisShape};
use ductile_core::curve::{CurveBasis, CurveTool};
use ductile_core::direct_ffd::{DirectConstraint, DirectFfdTool};
use ductile_core::dogme::{Anchor, Constraint, DogmeTool, Support};
use ductile_core::error::CoreError;
use ductile_core::ffsd::{ControlPoint, FfsdTool, HeightLimit, PointMode};
use ductile_core::influence::{Falloff, Influence, Shape, Volume};
use ductile_core::lattice::{ControlEdit, LatticeBasis, LatticeFrame, LatticeTool};
use ductile_core::mesh::{RestMesh, Topology};
use ductile_core::primitives;
use ductile_core::sketch::camera::{Camera, Projection};
use ductile_core::sketch::partition::Partition;
use ductile_core::sketch::refine::RefineOptions;
use ductile_core::sketch::tool::{Curve as SketchCurve, SketchMode, SketchTool, Stroke};
use ductile_core::spline::SplineControl;
use ductile_core::stack::{Layer, Stack};
use ductile_core::surface::{HeightEdit, ShapeSurfaceTool, SurfaceEdit, SurfaceFrame};
use ductile_core::tool::{BindInput, Deformer, Tool};
use glam::{Affine3A, Quat, Vec2, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestRunner};

/// Cases per tool kind: enough to meet each extreme value several times, few enough for a
/// run of a few seconds at `opt-level = 1`.
const CASES: u32 = 64;

/// Cases of the sketch tool, whose bind and evaluation (partition, smoothing, refinement)
/// cost more than a per-vertex tool's.
const SKETCH_CASES: u32 = 32;

/// Cases of the whole-stack property.
const STACK_CASES: u32 = 48;

/// Extreme finite parameter values.
const EXTREMES: [f32; 14] = [
    0.0,
    -0.0,
    1e-30,
    -1e-30,
    1e-6,
    -1e-6,
    1e6,
    -1e6,
    1e30,
    -1e30,
    f32::MAX,
    -f32::MAX,
    f32::MIN_POSITIVE,
    -f32::MIN_POSITIVE,
];

/// Extreme finite input coordinates (the issue asks for ±1e6 inputs; tiny ones test the
/// divisions by small distances).
const INPUT_EXTREMES: [f32; 7] = [0.0, -0.0, 1e-30, -1e-30, 1e-6, 1e6, -1e6];

// ---------------------------------------------------------------------------------------
// The harness.
// ---------------------------------------------------------------------------------------

/// What one case came to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    /// The tool refused its parameters (validation or bind failed): allowed.
    Refused,
    /// The tool accepted its parameters and every output was checked to be finite.
    Checked,
}

/// Batches of cases a property may run to reach its accepted cases (see [`run_property`]).
const MAX_BATCHES: u32 = 32;

/// Runs `check` on batches of `cases` values of `strategy` until a quarter of a batch's
/// count (at most 16) was accepted and checked. Fails with proptest's shrunk counterexample
/// on the first failing case (a non-finite output or a panic), and fails when
/// [`MAX_BATCHES`] batches did not reach that count.
///
/// The strategies are hostile on purpose, so most cases of some kinds are refused (about
/// 19 in 20 for Direct FFD, which refuses every bad lattice and its own bad constraints):
/// a single batch of 64 then accepted none about one run in 30, and the test failed by
/// chance. Such a property now runs about 5 batches; one that refuses everything runs all
/// 32 (2,048 cases) before it fails. Only the first batch replays the saved regressions
/// (the later ones would count them again), and each batch has its own seed, also under a
/// fixed `PROPTEST_RNG_SEED`.
fn run_property<S: Strategy>(
    name: &str,
    cases: u32,
    strategy: S,
    check: impl Fn(S::Value) -> Result<Outcome, TestCaseError>,
) {
    let wanted = cases.div_ceil(4).min(16);
    let checked = Cell::new(0_u32);
    let mut batches = 0;
    while checked.get() < wanted && batches < MAX_BATCHES {
        batches += 1;
        let mut config = ProptestConfig {
            cases,
            source_file: Some(file!()),
            ..ProptestConfig::default()
        };
        if batches > 1 {
            config.failure_persistence = None;
        }
        if let RngSeed::Fixed(seed) = config.rng_seed {
            config.rng_seed = RngSeed::Fixed(seed.wrapping_add(u64::from(batches)));
        }
        let result = TestRunner::new(config).run(&strategy, |value| {
            if check(value)? == Outcome::Checked {
                checked.set(checked.get() + 1);
            }
            Ok(())
        });
        if let Err(e) = result {
            panic!("{name}: {e}");
        }
    }
    assert!(
        checked.get() >= wanted,
        "{name}: {} cases were accepted in {batches} batches of {cases}, fewer than the \
         {wanted} the property needs",
        checked.get()
    );
}

/// True for the errors that catch a non-finite output after the fact (the stack's and the
/// sketch tool's), as opposed to a refusal of the parameters.
fn is_output_guard(e: &CoreError) -> bool {
    match e {
        CoreError::Degenerate { problem, .. } => {
            problem.contains("non-finite position")
                || (problem.starts_with("the deformation of vertex")
                    && problem.ends_with("is not finite"))
        }
        _ => false,
    }
}

/// Fails unless every output point is finite, naming the first bad one and its input.
fn assert_all_finite(kind: &str, input: &[Vec3], output: &[Vec3]) -> Result<(), TestCaseError> {
    prop_assert_eq!(input.len(), output.len());
    for (k, (p, o)) in input.iter().zip(output).enumerate() {
        prop_assert!(
            o.is_finite(),
            "{}: input point {} = {} was mapped to {}",
            kind,
            k,
            p,
            o
        );
    }
    Ok(())
}

/// A topology without triangles, for the per-vertex tools (they do not read it).
fn no_topology() -> Topology {
    Topology {
        weld: Vec::new(),
        representative: Vec::new(),
        triangles: Vec::new(),
    }
}

/// Validates, binds (every point active) and deforms `positions` with `tool` through the
/// public [`Tool`] entry points the stack uses, and checks every output.
fn check_tool(
    tool: &Tool,
    positions: &[Vec3],
    topology: &Topology,
) -> Result<Outcome, TestCaseError> {
    let kind = tool.kind_name();
    if tool.validate("tool under test").is_err() {
        return Ok(Outcome::Refused);
    }
    let active: Vec<u32> = (0..positions.len() as u32).collect();
    let input = BindInput {
        positions,
        topology,
        active: &active,
    };
    // A bind error is a refusal too: the stack reports it and leaves the mesh alone.
    let Ok(bind) = tool.bind(&input) else {
        return Ok(Outcome::Refused);
    };
    if let Some(whole) = tool.deform_whole(&bind, positions, true) {
        let whole = match whole {
            Ok(w) => w,
            Err(e) => {
                prop_assert!(
                    !is_output_guard(&e),
                    "{}: accepted parameters gave a non-finite deformation: {}",
                    kind,
                    e
                );
                return Ok(Outcome::Refused);
            }
        };
        assert_all_finite(kind, positions, &whole.out)?;
        if let Some(refinement) = &whole.refinement {
            for (k, d) in refinement.deformed.iter().enumerate() {
                prop_assert!(
                    d.is_finite(),
                    "{}: refined vertex {} went to {}",
                    kind,
                    k,
                    d
                );
            }
        }
        return Ok(Outcome::Checked);
    }
    let mut out = vec![Vec3::ZERO; positions.len()];
    tool.deform(&bind, positions, &active, &mut out);
    assert_all_finite(kind, positions, &out)?;
    // The stack's one-pass path reads the inputs already gathered (FFSD has its own kernel
    // for it); it must be just as finite.
    let mut gathered = vec![Vec3::ZERO; positions.len()];
    tool.deform_gathered(&bind, positions, positions, &active, &mut gathered);
    assert_all_finite(kind, positions, &gathered)?;
    Ok(Outcome::Checked)
}

/// The finite points a per-vertex tool is run on: a bumpy grid over the region the ordinary
/// parameters cover, far and tiny points, the tool's own `probes` and a few `random` ones.
fn inputs(probes: &[Vec3], random: &[Vec3]) -> Vec<Vec3> {
    let mut p = Vec::new();
    for j in 0..7 {
        for i in 0..7 {
            let (x, y) = (i as f32 * 0.5 - 1.5, j as f32 * 0.5 - 1.5);
            p.push(Vec3::new(x, y, 0.2 * (2.0 * x).sin() * y.cos()));
        }
    }
    for s in [1e6_f32, -1e6] {
        p.extend([Vec3::X * s, Vec3::Y * s, Vec3::Z * s, Vec3::splat(s)]);
    }
    p.extend([Vec3::ZERO, Vec3::splat(1e-30), Vec3::new(1e6, -1e-30, 0.5)]);
    p.extend(probes.iter().copied().filter(|q| q.is_finite()));
    p.extend_from_slice(random);
    p
}

/// Points on and around a lattice: its rest control points (at the Bernstein Greville
/// abscissae `i/n`), points just inside and outside it and far along its diagonal.
fn lattice_probes(l: &LatticeTool) -> Vec<Vec3> {
    let f = l.frame;
    let [nx, ny, nz] = l.count_array().map(|n| n.min(8));
    let step = |n: usize| 1.0 / (n.max(2) - 1) as f32;
    let mut p = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                p.push(f.point(Vec3::new(
                    i as f32 * step(nx),
                    j as f32 * step(ny),
                    k as f32 * step(nz),
                )));
            }
        }
    }
    for c in [-0.5, -1e-6, 0.5, 1.0, 1.0 + 1e-6, 1.5, 1e6] {
        p.push(f.point(Vec3::splat(c)));
    }
    p
}

/// Points exactly on (and next to) each tool's control points.
fn probes(tool: &Tool) -> Vec<Vec3> {
    let mut p = Vec::new();
    match tool {
        Tool::Ffsd(t) => {
            for c in &t.points {
                p.extend([c.position, c.centre(), c.position + Vec3::X * c.epsilon]);
            }
        }
        Tool::Lattice(t) => p.extend(lattice_probes(t)),
        Tool::DirectFfd(t) => {
            p.extend(lattice_probes(&t.lattice));
            for c in &t.constraints {
                if let Anchor::Point(x) = c.at {
                    p.extend([x, x + c.displacement]);
                }
            }
        }
        Tool::Dogme(t) => {
            for c in &t.constraints {
                if let Anchor::Point(x) = c.at {
                    let reach = match c.support {
                        Support::Sphere { radius } => Vec3::splat(radius),
                        Support::Box { half_extents, .. } => half_extents,
                    };
                    p.extend([x, x + reach * 0.5, x + reach]);
                }
            }
        }
        Tool::Axial(t) => {
            for a in &t.rest {
                p.extend([
                    a.position,
                    a.position + Vec3::Y * (0.5 * t.radius),
                    a.position + Vec3::Y * t.radius,
                ]);
            }
        }
        Tool::Curve(t) => {
            p.extend(&t.rest);
            p.extend(&t.deformed);
            p.extend(t.rest.windows(2).map(|w| (w[0] + w[1]) * 0.5));
            p.extend(t.rest.iter().map(|&q| q + Vec3::Z * 1e6));
        }
        Tool::ShapeSurface(t) => {
            let f = t.frame;
            let (nu, nv) = ((t.counts.0 as usize).min(8), (t.counts.1 as usize).min(8));
            let step = |n: usize| 1.0 / (n.max(2) - 1) as f32;
            for j in 0..nv {
                for i in 0..nu {
                    p.push(
                        f.origin
                            + f.u_edge * (i as f32 * step(nu))
                            + f.v_edge * (j as f32 * step(nv)),
                    );
                }
            }
            let centre = f.origin + (f.u_edge + f.v_edge) * 0.5;
            let n = f.u_edge.cross(f.v_edge).normalize_or_zero();
            for h in [0.0, 1e-30, 0.5, 1e6, -1e6] {
                p.push(centre + n * h);
            }
        }
        Tool::Sketch(_) => {}
    }
    p
}

/// The property for one per-vertex tool kind: finite output on [`inputs`] or a refusal.
fn per_vertex_property(name: &str, tools: BoxedStrategy<Tool>) {
    let topology = no_topology();
    run_property(name, CASES, (tools, random_inputs()), |(tool, random)| {
        let positions = inputs(&probes(&tool), &random);
        check_tool(&tool, &positions, &topology)
    });
}

// ---------------------------------------------------------------------------------------
// Value strategies.
// ---------------------------------------------------------------------------------------

fn extreme() -> impl Strategy<Value = f32> {
    prop::sample::select(EXTREMES.to_vec())
}

/// A signed parameter: ordinary, or now and then extreme.
fn scalar() -> impl Strategy<Value = f32> {
    prop_oneof![10 => -2.0_f32..2.0, 1 => extreme()]
}

/// A size that should be positive: ordinary and positive, or now and then extreme (zero and
/// negative included).
fn size() -> impl Strategy<Value = f32> {
    prop_oneof![10 => 0.05_f32..2.0, 1 => extreme()]
}

/// A fraction that should lie in `[0, 1]` or `(0, 1]`, or now and then an extreme value.
fn unit() -> impl Strategy<Value = f32> {
    prop_oneof![10 => 0.0_f32..=1.0, 1 => extreme()]
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (scalar(), scalar(), scalar()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn input_point() -> impl Strategy<Value = Vec3> {
    let coord =
        || prop_oneof![10 => -2.0_f32..2.0, 1 => prop::sample::select(INPUT_EXTREMES.to_vec())];
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn random_inputs() -> impl Strategy<Value = Vec<Vec3>> {
    prop::collection::vec(input_point(), 0..6)
}

/// A spline control: mostly 2 to 4 values of degree 1 to 3, sometimes too few values or a
/// degree out of range.
fn spline_control() -> impl Strategy<Value = SplineControl> {
    (
        prop_oneof![
            6 => prop::collection::vec(scalar(), 2..5),
            1 => prop::collection::vec(scalar(), 0..2),
        ],
        prop_oneof![6 => 1_usize..4, 1 => Just(0_usize), 1 => 14_usize..18],
    )
        .prop_map(|(values, degree)| SplineControl { values, degree })
}

fn falloff() -> impl Strategy<Value = Falloff> {
    prop_oneof![
        Just(Falloff::None),
        Just(Falloff::Linear),
        Just(Falloff::Smooth),
        spline_control().prop_map(Falloff::Curve),
    ]
}

/// A control point count per axis: mostly 2 to 5, sometimes too few.
fn count() -> impl Strategy<Value = u32> {
    prop_oneof![8 => 2_u32..6, 1 => 0_u32..2]
}

/// A B-spline degree: mostly 1 to 3, sometimes 0 or above the maximum of 15.
fn degree() -> impl Strategy<Value = u32> {
    prop_oneof![8 => 1_u32..4, 1 => Just(0_u32), 1 => 15_u32..18]
}

// ---------------------------------------------------------------------------------------
// Tool strategies, one per kind.
// ---------------------------------------------------------------------------------------

fn ffsd_point() -> impl Strategy<Value = ControlPoint> {
    (vec3(), 0..3_u8, vec3(), scalar(), size(), size()).prop_map(
        |(position, mode, reference, gamma, alpha, epsilon)| ControlPoint {
            position,
            mode: match mode {
                0 => PointMode::Basic,
                1 => PointMode::Virtual,
                _ => PointMode::Directional { reference },
            },
            gamma,
            alpha,
            epsilon,
        },
    )
}

fn height_limit() -> impl Strategy<Value = Option<HeightLimit>> {
    prop::option::of(
        (0..3_u8, unit(), unit()).prop_map(|(kind, a, b)| match kind {
            0 => HeightLimit::Above { theta: a },
            1 => HeightLimit::Below { theta: a },
            _ => HeightLimit::Both {
                below: a.min(b),
                above: a.max(b),
            },
        }),
    )
}

fn ffsd() -> BoxedStrategy<FfsdTool> {
    (
        prop::collection::vec(ffsd_point(), 0..5),
        any::<bool>(),
        height_limit(),
        prop_oneof![4 => Just(1.0_f32), 4 => -2.0_f32..2.0, 1 => extreme()],
    )
        .prop_map(|(mut points, coincident, height, gain)| {
            // Two control points at the same place (with their own parameters).
            if coincident && points.len() > 1 {
                points[1].position = points[0].position;
            }
            FfsdTool {
                points,
                height,
                gain,
            }
        })
        .boxed()
}

/// A lattice frame: mostly a box around the input grid, sometimes arbitrary edges, and
/// sometimes degenerate (coplanar edges, a zero edge).
fn lattice_frame() -> impl Strategy<Value = LatticeFrame> {
    (vec3(), vec3(), vec3(), vec3(), 0..8_u8).prop_map(|(o, a, b, c, kind)| match kind {
        0..=3 => {
            let min = Vec3::new(-1.6, -1.6, -0.6) + o * 0.1;
            LatticeFrame::from_box(min, min + Vec3::new(3.2, 3.2, 1.2) * a.abs())
        }
        4 | 5 => LatticeFrame {
            origin: o,
            s: a,
            t: b,
            u: c,
        },
        6 => LatticeFrame {
            origin: o,
            s: a,
            t: b,
            u: a + b,
        },
        _ => LatticeFrame {
            origin: o,
            s: a,
            t: Vec3::ZERO,
            u: c,
        },
    })
}

fn lattice_basis() -> impl Strategy<Value = LatticeBasis> {
    prop_oneof![
        Just(LatticeBasis::Bernstein),
        (degree(), degree(), degree()).prop_map(|degree| LatticeBasis::BSpline { degree }),
    ]
}

fn lattice() -> BoxedStrategy<LatticeTool> {
    (
        lattice_frame(),
        (count(), count(), count()),
        lattice_basis(),
        prop::collection::vec(
            (
                (0_u32..3, 0_u32..3, 0_u32..3),
                vec3(),
                prop_oneof![6 => Just(1.0_f32), 3 => 0.1_f32..3.0, 1 => extreme()],
            ),
            0..5,
        ),
        prop_oneof![4 => Just(0.0_f32), 4 => 0.0_f32..1.0, 1 => extreme()],
    )
        .prop_map(|(frame, counts, basis, edits, falloff)| LatticeTool {
            frame,
            counts,
            basis,
            points: edits
                .into_iter()
                .map(|(at, offset, weight)| ControlEdit { at, offset, weight })
                .collect(),
            falloff,
        })
        .boxed()
}

/// A DOGME / Direct FFD anchor: mostly a free point, sometimes a vertex (which may not
/// exist).
fn anchor() -> impl Strategy<Value = Anchor> {
    prop_oneof![3 => vec3().prop_map(Anchor::Point), 1 => (0_u32..90).prop_map(Anchor::Vertex)]
}

fn direct_ffd() -> BoxedStrategy<DirectFfdTool> {
    (
        lattice(),
        prop::collection::vec(
            (
                0..3_u8,
                (0.0_f32..=1.0, 0.0_f32..=1.0, 0.0_f32..=1.0),
                anchor(),
                vec3(),
            ),
            0..4,
        ),
        any::<bool>(),
    )
        .prop_map(|(lattice, raw, coincident)| {
            let frame = lattice.frame;
            let mut constraints: Vec<DirectConstraint> = raw
                .into_iter()
                .map(|(kind, (a, b, c), at, displacement)| DirectConstraint {
                    // Mostly a point inside the lattice (the only points it can move).
                    at: if kind < 2 {
                        Anchor::Point(frame.point(Vec3::new(a, b, c)))
                    } else {
                        at
                    },
                    displacement,
                })
                .collect();
            // Two opposite constraints on one point: the least-squares case.
            if coincident && constraints.len() > 1 {
                constraints[1].at = constraints[0].at;
                constraints[1].displacement = -constraints[0].displacement;
            }
            DirectFfdTool {
                lattice,
                constraints,
            }
        })
        .boxed()
}

fn support() -> impl Strategy<Value = Support> {
    prop_oneof![
        size().prop_map(|radius| Support::Sphere { radius }),
        (
            (size(), size(), size()),
            prop_oneof![
                3 => Just(Quat::IDENTITY),
                1 => (scalar(), scalar(), scalar(), scalar())
                    .prop_map(|(x, y, z, w)| Quat::from_xyzw(x, y, z, w)),
            ],
        )
            .prop_map(|((x, y, z), rotation)| Support::Box {
                half_extents: Vec3::new(x, y, z),
                rotation,
            }),
    ]
}

fn dogme() -> BoxedStrategy<DogmeTool> {
    (
        prop::collection::vec((anchor(), vec3(), support()), 0..5),
        prop_oneof![6 => 2_u32..6, 1 => 0_u32..20],
        any::<bool>(),
    )
        .prop_map(|(raw, degree, coincident)| {
            let mut constraints: Vec<Constraint> = raw
                .into_iter()
                .map(|(at, displacement, support)| Constraint {
                    at,
                    displacement,
                    support,
                })
                .collect();
            // Two opposite constraints on one point: the survey's "best approximation" case.
            if coincident && constraints.len() > 1 {
                constraints[1].at = constraints[0].at;
                constraints[1].displacement = -constraints[0].displacement;
            }
            DogmeTool {
                constraints,
                degree,
            }
        })
        .boxed()
}

fn axis_shape() -> impl Strategy<Value = AxisShape> {
    prop_oneof![
        Just(AxisShape::Polyline),
        Just(AxisShape::Bezier),
        prop_oneof![6 => 1_usize..4, 1 => Just(0_usize), 1 => 15_usize..18]
            .prop_map(|degree| AxisShape::BSpline { degree }),
    ]
}

fn axial() -> BoxedStrategy<AxialTool> {
    (
        axis_shape(),
        prop::collection::vec((vec3(), scalar(), size(), vec3(), scalar(), size()), 2..6),
        size(),
        falloff(),
        prop_oneof![4 => Just(0.0_f32), 4 => unit()],
        0..4_u8,
    )
        .prop_map(|(shape, raw, radius, falloff, inner, coincident)| {
            let mut rest: Vec<AxisPoint> = raw
                .iter()
                .map(|&(position, twist, scale, ..)| AxisPoint {
                    position,
                    twist,
                    scale,
                })
                .collect();
            let mut deformed: Vec<AxisPoint> = raw
                .iter()
                .map(|&(position, _, _, offset, twist, scale)| AxisPoint {
                    position: position + offset * 0.5,
                    twist,
                    scale,
                })
                .collect();
            match coincident {
                // Consecutive equal points: a zero-length segment.
                1 => rest[1].position = rest[0].position,
                // A closed axis: the third point back on the first (not consecutive).
                2 if rest.len() > 2 => rest[2].position = rest[0].position,
                // The deformed axis collapses a segment.
                3 => deformed[1].position = deformed[0].position,
                _ => {}
            }
            AxialTool {
                shape,
                rest,
                deformed,
                radius,
                falloff,
                inner,
            }
        })
        .boxed()
}

fn curve_basis() -> impl Strategy<Value = CurveBasis> {
    prop_oneof![
        Just(CurveBasis::Bezier),
        prop_oneof![6 => 1_usize..5, 1 => Just(0_usize), 1 => 15_usize..20]
            .prop_map(|degree| CurveBasis::BSpline { degree }),
    ]
}

fn curve() -> BoxedStrategy<CurveTool> {
    (
        curve_basis(),
        prop::collection::vec((vec3(), vec3()), 2..8),
        0..4_u8,
    )
        .prop_map(|(basis, raw, coincident)| {
            let mut rest: Vec<Vec3> = raw.iter().map(|r| r.0).collect();
            let mut deformed: Vec<Vec3> = raw.iter().map(|r| r.0 + r.1 * 0.5).collect();
            match coincident {
                1 => rest[1] = rest[0],
                2 => deformed[1] = deformed[0],
                3 if rest.len() > 2 => rest[2] = rest[0],
                _ => {}
            }
            CurveTool {
                basis,
                rest,
                deformed,
            }
        })
        .boxed()
}

/// A shape-surface frame: mostly a plane over the input grid, sometimes arbitrary edges, and
/// sometimes degenerate (parallel edges, a zero edge).
fn surface_frame() -> impl Strategy<Value = SurfaceFrame> {
    (vec3(), vec3(), vec3(), 0..6_u8).prop_map(|(o, a, b, kind)| match kind {
        0..=2 => SurfaceFrame {
            origin: Vec3::new(-1.6, -1.6, 0.0) + o * 0.1,
            u_edge: Vec3::X * 3.2 + a * 0.1,
            v_edge: Vec3::Y * 3.2 + b * 0.1,
        },
        3 => SurfaceFrame {
            origin: o,
            u_edge: a,
            v_edge: b,
        },
        4 => SurfaceFrame {
            origin: o,
            u_edge: a,
            v_edge: a * 2.0,
        },
        _ => SurfaceFrame {
            origin: o,
            u_edge: Vec3::ZERO,
            v_edge: b,
        },
    })
}

fn surface() -> BoxedStrategy<ShapeSurfaceTool> {
    let at = || (0_u32..6, 0_u32..6);
    (
        surface_frame(),
        (
            prop_oneof![8 => 2_u32..7, 1 => 0_u32..2],
            prop_oneof![8 => 2_u32..7, 1 => 0_u32..2],
        ),
        (degree(), degree()),
        prop::collection::vec((at(), vec3()), 0..2),
        prop::collection::vec((at(), vec3()), 0..4),
        prop::collection::vec((at(), scalar()), 0..3),
    )
        .prop_map(|(frame, counts, degree, rest, moves, heights)| {
            let edits = |list: Vec<((u32, u32), Vec3)>| -> Vec<SurfaceEdit> {
                list.into_iter()
                    .map(|(at, offset)| SurfaceEdit { at, offset })
                    .collect()
            };
            ShapeSurfaceTool {
                frame,
                counts,
                degree,
                rest: edits(rest),
                moves: edits(moves),
                heights: heights
                    .into_iter()
                    .map(|(at, height)| HeightEdit { at, height })
                    .collect(),
            }
        })
        .boxed()
}

// ---------------------------------------------------------------------------------------
// The sketch tool, on a cylinder.
// ---------------------------------------------------------------------------------------

/// A uniform scale of the mesh (and of the sketch tool with it): mostly 1, sometimes tiny
/// or huge.
fn mesh_scale() -> impl Strategy<Value = f32> {
    prop_oneof![4 => Just(1.0_f32), 1 => prop::sample::select(vec![1e-30_f32, 1e-3, 1e3, 1e6])]
}

/// An open cylinder along +x from 0 to 4, radius 0.25, 8 segments, a ring every 0.25;
/// everything times `scale`.
fn cylinder(scale: f32) -> Result<RestMesh, TestCaseError> {
    let mesh = primitives::grid(17, 8, true, |r, c| {
        let a = std::f32::consts::TAU * c as f32 / 8.0;
        Vec3::new(0.25 * r as f32, 0.25 * a.cos(), 0.25 * a.sin()) * scale
    });
    RestMesh::new(mesh, "cylinder").map_err(|e| TestCaseError::fail(format!("cylinder: {e}")))
}

/// The camera strokes are drawn with: looking down −z at the middle of the unit cylinder,
/// mostly with a sensible projection, sometimes with extreme or inconsistent settings
/// (negative field of view, near beyond far, an empty viewport).
fn camera() -> impl Strategy<Value = Camera> {
    (
        prop_oneof![
            3 => prop_oneof![4 => 1.0_f32..8.0, 1 => extreme()]
                .prop_map(|height| Projection::Orthographic { height }),
            1 => scalar().prop_map(|fov_y| Projection::Perspective { fov_y }),
        ],
        prop_oneof![4 => Just((0.1_f32, 100.0_f32)), 1 => (scalar(), scalar())],
        prop_oneof![
            4 => Just(Vec2::new(800.0, 600.0)),
            1 => (scalar(), scalar()).prop_map(|(x, y)| Vec2::new(x, y)),
        ],
    )
        .prop_map(|(projection, (near, far), viewport)| Camera {
            eye: Vec3::new(2.0, 0.0, 10.0),
            target: Vec3::new(2.0, 0.0, 0.0),
            up: Vec3::Y,
            projection,
            near,
            far,
            viewport,
        })
}

/// A stroke: mostly pixels across the cylinder's image, sometimes extreme pixels.
fn stroke() -> impl Strategy<Value = Stroke> {
    let pixel = (
        prop_oneof![10 => 150.0_f32..650.0, 1 => extreme()],
        prop_oneof![10 => 270.0_f32..330.0, 1 => extreme()],
    )
        .prop_map(|(x, y)| Vec2::new(x, y));
    (prop::collection::vec(pixel, 1..6), camera())
        .prop_map(|(pixels, camera)| Stroke { pixels, camera })
}

fn sketch_reference() -> impl Strategy<Value = SketchCurve> {
    prop_oneof![
        // The cylinder's axis over [a, b].
        4 => (0.0_f32..1.5, 2.5_f32..4.0).prop_map(|(a, b)| {
            SketchCurve::Points(vec![Vec3::new(a, 0.0, 0.0), Vec3::new(b, 0.0, 0.0)])
        }),
        1 => prop::collection::vec(vec3(), 1..5).prop_map(SketchCurve::Points),
        2 => stroke().prop_map(SketchCurve::Stroke),
        1 => stroke().prop_map(SketchCurve::Joints),
    ]
}

fn sketch_mode() -> impl Strategy<Value = SketchMode> {
    prop_oneof![
        (
            prop_oneof![
                4 => prop::collection::vec(vec3(), 2..6).prop_map(SketchCurve::Points),
                // Every target point in one place.
                1 => vec3().prop_map(|p| SketchCurve::Points(vec![p, p])),
                1 => stroke().prop_map(SketchCurve::Stroke),
            ],
            prop::option::weighted(0.3, spline_control()),
        )
            .prop_map(|(target, turning)| SketchMode::Bend { target, turning }),
        (scalar(), prop::option::weighted(0.3, spline_control()))
            .prop_map(|(angle, speed)| SketchMode::Twist { angle, speed }),
    ]
}

fn sketch() -> BoxedStrategy<SketchTool> {
    (
        sketch_reference(),
        prop_oneof![
            3 => Just(Some(Vec3::Z)),
            1 => Just(None::<Vec3>),
            1 => vec3().prop_map(Some),
        ],
        sketch_mode(),
        prop::option::weighted(0.3, spline_control()),
        any::<bool>(),
        prop::option::weighted(
            0.3,
            (
                prop_oneof![4 => 1.0_f32..3.0, 1 => extreme()],
                prop_oneof![4 => 2.5_f32..3.1, 1 => extreme()],
                0..4_u8,
            )
                .prop_map(|(stretch, angle, max_levels)| RefineOptions {
                    stretch,
                    angle,
                    max_levels,
                }),
        ),
    )
        .prop_map(
            |(reference, normal, mode, scale, smooth, refine)| SketchTool {
                partition: None,
                reference,
                normal,
                mode,
                scale,
                smooth,
                refine,
            },
        )
        .boxed()
}

/// A partition by x: the region of interest between the reference curve's smallest and
/// largest x (or `[scale, 3·scale]` for a stroke), one rigid component beyond it.
fn partition_along_x(reference: &SketchCurve, positions: &[Vec3], scale: f32) -> Partition {
    let (lo, hi) = match reference {
        SketchCurve::Points(p) => p
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q.x), hi.max(q.x))
            }),
        SketchCurve::Stroke(_) | SketchCurve::Joints(_) => (scale, 3.0 * scale),
    };
    let pick = |keep: &dyn Fn(f32) -> bool| -> Vec<u32> {
        positions
            .iter()
            .enumerate()
            .filter(|(_, p)| keep(p.x))
            .map(|(i, _)| i as u32)
            .collect()
    };
    let roi = pick(&|x: f32| (lo..=hi).contains(&x));
    let rigid = pick(&|x: f32| x > hi);
    Partition {
        roi,
        rigid: if rigid.is_empty() {
            Vec::new()
        } else {
            vec![rigid]
        },
    }
}

// ---------------------------------------------------------------------------------------
// Influence and the stack.
// ---------------------------------------------------------------------------------------

fn volume_shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        size().prop_map(|radius| Shape::Sphere { radius }),
        (size(), size(), size()).prop_map(|(x, y, z)| Shape::Box {
            half_extents: Vec3::new(x, y, z)
        }),
        (size(), scalar()).prop_map(|(radius, half_height)| Shape::Capsule {
            radius,
            half_height
        }),
        prop::collection::vec((vec3(), size()), 1..4).prop_map(|nodes| {
            let (points, radii): (Vec<Vec3>, Vec<f32>) = nodes.into_iter().unzip();
            Shape::Tube { points, radii }
        }),
    ]
}

fn placement() -> impl Strategy<Value = Affine3A> {
    (
        prop_oneof![4 => Just(Vec3::ONE), 1 => vec3()],
        scalar(),
        scalar(),
        vec3(),
    )
        .prop_map(|(scale, a, b, translation)| {
            Affine3A::from_scale_rotation_translation(
                scale,
                Quat::from_rotation_y(a) * Quat::from_rotation_x(b),
                translation,
            )
        })
}

/// An influence: the volumes [`Volume::new`] accepts (a refused volume is left out: it was
/// refused at the boundary), a falloff, an inner plateau, maybe an area and an inversion.
fn influence() -> BoxedStrategy<Influence> {
    (
        prop::collection::vec((volume_shape(), placement()), 0..3),
        falloff(),
        prop_oneof![4 => Just(0.0_f32), 4 => unit()],
        prop_oneof![4 => Just(false), 1 => Just(true)],
        prop::option::weighted(0.3, prop::collection::vec(0_u32..90, 0..12)),
    )
        .prop_map(|(volumes, falloff, inner, invert, area)| Influence {
            volumes: volumes
                .into_iter()
                .filter_map(|(shape, placement)| Volume::new(shape, placement, "volume").ok())
                .collect(),
            area: area.map(|mut a| {
                a.sort_unstable();
                a.dedup();
                a
            }),
            falloff,
            inner,
            invert,
        })
        .boxed()
}

/// Any per-vertex tool (the sketch tool needs its own mesh and is covered on its own).
fn any_tool() -> BoxedStrategy<Tool> {
    prop_oneof![
        ffsd().prop_map(Tool::Ffsd),
        lattice().prop_map(Tool::Lattice),
        direct_ffd().prop_map(Tool::DirectFfd),
        dogme().prop_map(Tool::Dogme),
        axial().prop_map(Tool::Axial),
        curve().prop_map(Tool::Curve),
        surface().prop_map(Tool::ShapeSurface),
    ]
    .boxed()
}

/// A bumpy 9 × 9 sheet over `[−1.5, 1.5]²`, times `scale`.
fn sheet(scale: f32) -> Result<RestMesh, TestCaseError> {
    let mesh = primitives::grid(9, 9, false, |j, i| {
        let (x, y) = (i as f32 * 0.375 - 1.5, j as f32 * 0.375 - 1.5);
        Vec3::new(x, y, 0.2 * (2.0 * x).sin() * y.cos()) * scale
    });
    RestMesh::new(mesh, "sheet").map_err(|e| TestCaseError::fail(format!("sheet: {e}")))
}

// ---------------------------------------------------------------------------------------
// The properties.
// ---------------------------------------------------------------------------------------

#[test]
fn ffsd_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("FFSD", ffsd().prop_map(Tool::Ffsd).boxed());
}

#[test]
fn lattice_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("lattice FFD", lattice().prop_map(Tool::Lattice).boxed());
}

#[test]
fn direct_ffd_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("Direct FFD", direct_ffd().prop_map(Tool::DirectFfd).boxed());
}

#[test]
fn dogme_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("DOGME", dogme().prop_map(Tool::Dogme).boxed());
}

#[test]
fn axial_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("axial deformation", axial().prop_map(Tool::Axial).boxed());
}

#[test]
fn curve_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property("curve deformation", curve().prop_map(Tool::Curve).boxed());
}

#[test]
fn shape_surface_output_is_finite_or_the_parameters_are_refused() {
    per_vertex_property(
        "shape surface",
        surface().prop_map(Tool::ShapeSurface).boxed(),
    );
}

/// The sketch tool is evaluated as a whole layer (with its refinement) on a cylinder, the
/// tool scaled with the mesh; half the cases give the partition, half let the bind find it.
#[test]
fn sketch_output_is_finite_or_the_parameters_are_refused() {
    run_property(
        "sketch deformation",
        SKETCH_CASES,
        (sketch(), any::<bool>(), mesh_scale()),
        |(tool, explicit_partition, scale)| {
            let rest = cylinder(scale)?;
            // A uniform scale keeps the sketch-plane normal; `transformed` would carry it
            // through the inverse matrix, which underflows at the tiniest scale.
            let normal = tool.normal;
            let mut tool = tool.transformed(&Affine3A::from_scale(Vec3::splat(scale)));
            tool.normal = normal;
            if explicit_partition {
                tool.partition = Some(partition_along_x(
                    &tool.reference,
                    rest.welded_positions(),
                    scale,
                ));
            }
            check_tool(
                &Tool::Sketch(Box::new(tool)),
                rest.welded_positions(),
                rest.topology(),
            )
        },
    );
}

/// Influence weights scale every layer's displacement, so they must be finite and in
/// `(0, 1]` for every vertex of the mask, whatever the volumes.
#[test]
fn influence_weights_are_finite_or_the_parameters_are_refused() {
    run_property(
        "influence",
        CASES,
        (influence(), random_inputs()),
        |(influence, random)| {
            if influence.validate("influence").is_err() {
                return Ok(Outcome::Refused);
            }
            let positions = inputs(&[], &random);
            let mask = influence.mask(&positions);
            prop_assert_eq!(mask.indices.len(), mask.weights.len());
            prop_assert!(
                mask.indices.windows(2).all(|w| w[0] < w[1]),
                "mask indices not ascending"
            );
            for (&i, &w) in mask.indices.iter().zip(&mask.weights) {
                prop_assert!(
                    (i as usize) < positions.len(),
                    "vertex {} does not exist",
                    i
                );
                prop_assert!(
                    w.is_finite() && w > 0.0 && w <= 1.0,
                    "vertex {} at {} has weight {}",
                    i,
                    positions[i as usize],
                    w
                );
            }
            Ok(Outcome::Checked)
        },
    );
}

/// The full evaluation path: a rest mesh and one to three layers of any per-vertex tool,
/// with random weights, influences and enabled flags. Either the stack refuses (validation
/// or a bind error) or every output position and normal is finite; its non-finite-output
/// guard must never be what stops it.
#[test]
fn stack_output_is_finite_or_the_parameters_are_refused() {
    let layer = (
        any_tool(),
        prop_oneof![4 => Just(1.0_f32), 3 => 0.0_f32..=1.0, 1 => extreme()],
        prop::option::weighted(0.4, influence()),
        prop_oneof![5 => Just(true), 1 => Just(false)],
    );
    run_property(
        "stack",
        STACK_CASES,
        (prop::collection::vec(layer, 1..4), mesh_scale()),
        |(layers, scale)| {
            let rest = sheet(scale)?;
            let layers = layers
                .into_iter()
                .enumerate()
                .map(|(k, (tool, weight, influence, enabled))| Layer {
                    name: format!("layer {k}"),
                    tool,
                    influence,
                    weight,
                    enabled,
                })
                .collect();
            match (Stack { layers }).evaluate(&rest) {
                Ok(out) => {
                    for (k, (p, n)) in out.positions.iter().zip(&out.normals).enumerate() {
                        prop_assert!(
                            p.is_finite() && n.is_finite(),
                            "stack: vertex {} has position {} and normal {}",
                            k,
                            p,
                            n
                        );
                    }
                    Ok(Outcome::Checked)
                }
                Err(e) => {
                    prop_assert!(
                        !is_output_guard(&e),
                        "stack: accepted parameters gave a non-finite deformation: {}",
                        e
                    );
                    Ok(Outcome::Refused)
                }
            }
        },
    );
}
