//! Runs of per-vertex layers evaluated a block of vertices at a time: the part of
//! [`Stack::evaluate`](crate::stack::Stack::evaluate) that takes most of a large mesh's time.
//!
//! A layer is *per-vertex* ([`is_per_vertex`]) when each active vertex's weight and
//! deformed position depend on that vertex's input position alone: its influence has no
//! named area (a volume weighs a vertex by its position), and its tool's bind either holds
//! data of each vertex's own input (a curve, an axial tool, a shape surface:
//! [`Tool::binds_per_vertex`](crate::tool::Tool::binds_per_vertex)) or reads no vertex at
//! all (a lattice; DOGME and Direct FFD with point anchors:
//! [`Tool::binds_without_vertices`](crate::tool::Tool::binds_without_vertices)). FFSD binds
//! to the vertex nearest each control point, and a sketch works on the layer as a whole.
//! Consecutive per-vertex layers form a *run*, and [`evaluate_run`] takes a block of
//! [`BLOCK`] consecutive vertices through every layer of the run before the next block, the
//! blocks in parallel (one after the other on a mesh below the parallel threshold): the
//! block's positions, masks and binds stay in the core's cache between layers instead of a
//! pass over the whole mesh per layer and phase, and the threads meet once per run instead
//! of several times per layer. A bind that reads no vertex is made once for the run and
//! serves every block, and so is what a curve's or a shape surface's bind computes from the
//! tool alone (their pieces, knots and nets). Each thread keeps the buffers of its last
//! block's binds and deformed positions, and makes its next block's in them ([`Spare`]).
//!
//! Each vertex goes through the very operations of the layer-by-layer evaluation, so it gets
//! the same bits. A block whose box no volume of a layer reaches takes that layer's weight of
//! no volume without reading its positions ([`Influence::mask_in_box`]). A block stops at its
//! first error; the run returns the error of the earliest layer and, within it, of the lowest
//! block — the error the layer-by-layer evaluation gives (a tool's bind errors do not depend
//! on the positions, a layer that weighs no vertex binds nothing, and a non-finite output
//! names the block's lowest such vertex).

use glam::Vec3;
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::Range;

use crate::chunks::{CHUNK, PARALLEL_THRESHOLD};
use crate::error::{CoreError, Result};
use crate::influence::{Influence, Mask, chunk_box};
use crate::mesh::Topology;
use crate::stack::{Layer, apply_per_vertex};
use crate::tool::{BindInput, BindSetup, SpareBinds, ToolBind};

/// The vertices a block holds: two chunks, small enough that a block's positions and a
/// layer's bind data for them stay in a core's cache, and below the threshold at which the
/// masks, binds and deformations split their own work over the threads.
pub(crate) const BLOCK: usize = 2 * CHUNK;

/// Whether `layer` can join a run ([module documentation](self)).
#[must_use]
pub(crate) fn is_per_vertex(layer: &Layer) -> bool {
    (layer.tool.binds_per_vertex() || layer.tool.binds_without_vertices())
        && !layer.tool.is_whole_layer()
        && layer
            .influence
            .as_ref()
            .is_none_or(|inf| inf.area.is_none())
}

/// Evaluates the per-vertex layers `run` ([`is_per_vertex`], none inert) on `positions` in
/// place, a [`BLOCK`] at a time, and returns the spans of the blocks that some layer moved.
/// `topology` is the mesh's (per-vertex tools do not read it).
pub(crate) fn evaluate_run(
    run: &[&Layer],
    positions: &mut [Vec3],
    topology: &Topology,
) -> Result<Vec<Range<usize>>> {
    debug_assert!(run.iter().all(|l| is_per_vertex(l) && !l.is_inert()));
    // What each layer's binds need from the tool alone, made once: the whole bind of a tool
    // that reads no vertex, or its setup. A block that weighs no vertex of the layer does not
    // use it, and its error counts only where a block does.
    let mut made: Vec<Result<Made>> = run
        .iter()
        .map(|l| {
            if l.tool.binds_without_vertices() {
                let input = BindInput {
                    positions: &[],
                    topology,
                    active: &[],
                };
                l.tool.bind(&input).map(|b| Made::Bind(Box::new(b)))
            } else {
                l.tool.bind_setup().map(Made::Setup)
            }
        })
        .collect();
    let binds: Vec<Shared<'_>> = made
        .iter()
        .map(|m| match m {
            Ok(Made::Bind(b)) => Shared::Bind(b.as_ref()),
            Ok(Made::Setup(s)) => Shared::Setup(s),
            Err(_) => Shared::Failed,
        })
        .collect();
    let work = |(b, block): (usize, &mut [Vec3])| {
        let start = b * BLOCK;
        // The buffers this thread's block before left; taken, so that a block this thread
        // starts while it waits inside this one (a bind's parallel chunks) finds none and
        // makes its own.
        let mut spare = SPARE.take();
        let moved = evaluate_block(run, &binds, block, start, topology, &mut spare);
        SPARE.set(spare);
        Ok(moved?.then_some(start..start + block.len()))
    };
    // A mesh below the parallel threshold makes no parallel call of its own, as a layer's
    // passes over it make none.
    let outcomes: Vec<std::result::Result<Option<Range<usize>>, Failure>> =
        if positions.len() < PARALLEL_THRESHOLD {
            positions.chunks_mut(BLOCK).enumerate().map(work).collect()
        } else {
            // One task per block: blocks differ in cost (a tool's region covers some of
            // them), and on two threads rayon's default split makes quarters of the blocks
            // and splits further only a part that the other thread steals, so a thread could
            // be left alone with a costly quarter while the other waited (20 ms of a 56 ms
            // run of the suite's million-vertex stack, measured).
            positions
                .par_chunks_mut(BLOCK)
                .with_max_len(1)
                .enumerate()
                .map(work)
                .collect()
        };
    let mut moved = Vec::new();
    let mut first: Option<Failure> = None;
    for outcome in outcomes {
        match outcome {
            Ok(span) => moved.extend(span),
            // Blocks ascend, so the first failure of the least layer is the lowest block's.
            Err(f) if first.as_ref().is_none_or(|g| f.layer < g.layer) => first = Some(f),
            Err(_) => {}
        }
    }
    match first {
        Some(Failure {
            error: Some(error), ..
        }) => Err(error),
        Some(Failure { layer, error: None }) => {
            match std::mem::replace(&mut made[layer], Ok(Made::Setup(BindSetup::Nothing))) {
                Err(error) => Err(error),
                Ok(_) => unreachable!("only a failed shared part has no error of its own"),
            }
        }
        None => Ok(moved),
    }
}

/// What a run makes once for a layer: the bind itself, or the bind's setup.
enum Made {
    Bind(Box<ToolBind>),
    Setup(BindSetup),
}

/// A layer's part made once, as the blocks read it (or that making it failed).
#[derive(Clone, Copy)]
enum Shared<'a> {
    Bind(&'a ToolBind),
    Setup(&'a BindSetup),
    Failed,
}

/// A block's first error, at the layer of the run at position `layer`: its own, or `None`
/// for the error of making the layer's shared part.
struct Failure {
    layer: usize,
    error: Option<CoreError>,
}

thread_local! {
    /// The buffers of the last block a thread evaluated, for its next block.
    static SPARE: RefCell<Spare> = RefCell::default();
}

/// Buffers a block evaluation no longer needs, kept for the next block on the same thread:
/// made again for each block, they took a bind's allocation and zeros per layer and block
/// (`docs/performance.md`, thirty-second session).
#[derive(Default)]
struct Spare {
    /// The binds of the kinds that hold per-vertex arrays.
    binds: SpareBinds,
    /// The deformed positions of a layer's active vertices.
    deformed: Vec<Vec3>,
}

/// Takes the block of vertices `start..` through every layer of `run` (with `binds`, one per
/// layer), in the buffers of `spare`; returns whether a layer moved any of them.
fn evaluate_block(
    run: &[&Layer],
    binds: &[Shared<'_>],
    block: &mut [Vec3],
    start: usize,
    topology: &Topology,
    spare: &mut Spare,
) -> std::result::Result<bool, Failure> {
    // The block's box, computed when a mask needs it and dropped when a layer moves a vertex.
    let mut bounds: Option<(Vec3, Vec3)> = None;
    let mut moved = false;
    for (k, (layer, shared)) in run.iter().zip(binds).enumerate() {
        let fail = |error| Failure {
            layer: k,
            error: Some(error),
        };
        let mask = match &layer.influence {
            Some(inf) => mask(inf, block, &mut bounds),
            None => Mask::all(block.len()),
        };
        if mask.is_empty() {
            continue;
        }
        let offset = start as u32;
        match *shared {
            Shared::Failed => {
                return Err(Failure {
                    layer: k,
                    error: None,
                });
            }
            Shared::Bind(bind) => {
                apply_per_vertex(layer, bind, &mask, block, offset, &mut spare.deformed)
                    .map_err(fail)?;
            }
            Shared::Setup(setup) => {
                let input = BindInput {
                    positions: block,
                    topology,
                    active: &mask.indices,
                };
                let own = layer.tool.bind_set_up(setup, &input, &mut spare.binds);
                let own = own.map_err(fail)?;
                let applied =
                    apply_per_vertex(layer, &own, &mask, block, offset, &mut spare.deformed);
                // Its buffers serve the next bind of its kind, whether or not it applied.
                spare.binds.keep(own);
                applied.map_err(fail)?;
            }
        }
        bounds = None;
        moved = true;
    }
    Ok(moved)
}

/// `inf`'s mask of `block`, culled by the block's box (computed into `bounds` when unknown).
fn mask(inf: &Influence, block: &[Vec3], bounds: &mut Option<(Vec3, Vec3)>) -> Mask {
    if inf.volumes.is_empty() {
        return inf.mask(block);
    }
    let b = *bounds.get_or_insert_with(|| chunk_box(block));
    inf.mask_in_box(block, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axial::{AxialTool, AxisPoint};
    use crate::curve::{CurveBasis, CurveTool};
    use crate::direct_ffd::{DirectConstraint, DirectFfdTool};
    use crate::dogme::{Anchor, Constraint, DogmeTool, Support};
    use crate::ffsd::{ControlPoint, FfsdTool};
    use crate::influence::{Falloff, Shape, Volume};
    use crate::lattice::{LatticeFrame, LatticeTool};
    use crate::mesh::RestMesh;
    use crate::stack::{LayerBinding, Stack};
    use crate::surface::{ShapeSurfaceTool, SurfaceEdit, SurfaceFrame};
    use crate::tool::Tool;
    use glam::Affine3A;

    /// A wavy `n × n` sheet over `[0, 2.29]²`: 230 × 230 makes 52,900 vertices in seven
    /// blocks (in parallel), 100 × 100 makes 10,000 in two (below the parallel threshold).
    fn sheet(n: usize) -> RestMesh {
        let step = 2.29 / (n - 1) as f32;
        let mesh = crate::primitives::grid(n, n, false, |r, c| {
            let (x, y) = (c as f32 * step, r as f32 * step);
            Vec3::new(x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos())
        });
        RestMesh::new(mesh, "sheet").unwrap()
    }

    /// An influence of one volume (a sphere or an axis-aligned box) around `centre`.
    fn around(centre: Vec3, shape: Shape, invert: bool) -> Option<Influence> {
        let placement = Affine3A::from_translation(centre);
        Some(Influence {
            volumes: vec![Volume::new(shape, placement, "v").unwrap()],
            falloff: Falloff::Smooth,
            invert,
            ..Influence::default()
        })
    }

    fn layer(name: &str, tool: Tool, influence: Option<Influence>) -> Layer {
        Layer {
            influence,
            ..Layer::new(name, tool)
        }
    }

    /// A curve along `x` at height `y`, bent upwards in the middle.
    fn bent_curve(basis: CurveBasis, y: f32) -> Tool {
        let rest: Vec<Vec3> = (0..5).map(|k| Vec3::new(0.5 * k as f32, y, 0.0)).collect();
        let mut tool = CurveTool::new(basis, rest);
        tool.deformed[2].z += 0.3;
        tool.deformed[3].y -= 0.2;
        Tool::Curve(tool)
    }

    fn lattice(min: Vec3, max: Vec3, offset: Vec3) -> LatticeTool {
        let mut tool = LatticeTool::bernstein(LatticeFrame::from_box(min, max), (3, 3, 3));
        tool.set_offset((1, 1, 1), offset);
        tool
    }

    fn dogme(at: Anchor) -> Tool {
        Tool::Dogme(DogmeTool {
            constraints: vec![Constraint {
                at,
                displacement: Vec3::new(0.0, 0.1, 0.2),
                support: Support::Sphere { radius: 0.6 },
            }],
            degree: 3,
        })
    }

    /// A bicubic shape surface over the sheet with a control point raised; `curved` gives
    /// it a rest edit (a search for each closest point instead of the plane's projection).
    fn surface(curved: bool) -> Tool {
        let frame = SurfaceFrame {
            origin: Vec3::new(0.1, 0.1, 0.0),
            u_edge: Vec3::new(2.1, 0.0, 0.0),
            v_edge: Vec3::new(0.0, 2.1, 0.0),
        };
        let mut tool = ShapeSurfaceTool::planar(frame, (5, 5));
        tool.moves.push(SurfaceEdit {
            at: (2, 2),
            offset: Vec3::new(0.0, 0.1, 0.25),
        });
        if curved {
            tool.rest.push(SurfaceEdit {
                at: (3, 1),
                offset: Vec3::new(0.0, 0.0, 0.15),
            });
        }
        Tool::ShapeSurface(tool)
    }

    /// [`surface`] of degree 4 in both directions: its bind keeps each point's bases
    /// instead of deform evaluating them again.
    fn quartic_surface(curved: bool) -> Tool {
        let mut tool = surface(curved);
        if let Tool::ShapeSurface(s) = &mut tool {
            s.degree = (4, 4);
        }
        tool
    }

    /// A twisted and bent axial tool along `x`.
    fn axial() -> Tool {
        let point = |x: f32| AxisPoint {
            position: Vec3::new(x, 0.4, 0.0),
            twist: 0.0,
            scale: 1.0,
        };
        let mut tool = AxialTool::new(vec![point(0.4), point(1.2), point(2.0)], 0.4);
        tool.deformed[2].position.y += 0.2;
        tool.deformed[2].twist = 0.5;
        Tool::Axial(tool)
    }

    /// Every kind of layer a run takes, and the kinds that end one: per-vertex layers with
    /// their own binds and with one shared bind, volumes that reach some blocks, every block
    /// (inverted, so that culled blocks take weight 1) or none, no influence, and between
    /// them an FFSD point, a named area and a vertex anchor.
    fn mixed() -> Stack {
        let sphere = |radius| Shape::Sphere { radius };
        let cube = |h| Shape::Box {
            half_extents: Vec3::splat(h),
        };
        let mut direct = DirectFfdTool {
            lattice: lattice(
                Vec3::new(0.2, 0.2, -0.5),
                Vec3::new(2.0, 2.0, 0.5),
                Vec3::ZERO,
            ),
            constraints: Vec::new(),
        };
        direct.constraints.push(DirectConstraint {
            at: Anchor::Point(Vec3::new(1.0, 1.2, 0.0)),
            displacement: Vec3::new(0.05, 0.0, 0.1),
        });
        let layers = vec![
            layer(
                "lattice",
                Tool::Lattice(lattice(
                    Vec3::new(0.3, 0.1, -0.4),
                    Vec3::new(1.6, 0.9, 0.4),
                    Vec3::new(0.1, -0.2, 0.3),
                )),
                around(Vec3::new(0.9, 0.5, 0.0), sphere(0.5), false),
            ),
            layer(
                "curve",
                bent_curve(CurveBasis::BSpline { degree: 3 }, 1.1),
                around(Vec3::new(1.0, 1.1, 0.0), cube(0.25), true),
            ),
            layer(
                "dogme",
                dogme(Anchor::Point(Vec3::new(1.5, 1.5, 0.0))),
                None,
            ),
            layer(
                "surface",
                surface(false),
                around(Vec3::new(0.6, 1.6, 0.0), sphere(0.5), false),
            ),
            layer(
                "curved surface",
                surface(true),
                around(Vec3::new(1.6, 0.6, 0.0), cube(0.45), false),
            ),
            // Two binds that keep their bases one after the other: the second is made in
            // the first's buffers.
            layer(
                "quartic surface",
                quartic_surface(false),
                around(Vec3::new(1.0, 0.8, 0.0), sphere(0.6), false),
            ),
            layer(
                "curved quartic surface",
                quartic_surface(true),
                around(Vec3::new(1.3, 1.0, 0.0), cube(0.5), false),
            ),
            layer(
                "axial",
                axial(),
                around(Vec3::new(1.2, 0.4, 0.0), sphere(0.5), false),
            ),
            layer(
                "nowhere",
                Tool::Lattice(lattice(Vec3::splat(5.0), Vec3::splat(6.0), Vec3::ONE)),
                around(Vec3::splat(5.5), sphere(0.4), false),
            ),
            layer(
                "ffsd",
                Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
                    Vec3::new(1.0, 1.0, 0.3),
                    0.4,
                    2.0,
                    0.3,
                )])),
                around(Vec3::new(1.0, 1.0, 0.0), sphere(0.7), false),
            ),
            layer("direct", Tool::DirectFfd(direct), None),
            layer(
                "area curve",
                bent_curve(CurveBasis::Bezier, 0.6),
                Some(Influence {
                    area: Some((0..52_900).step_by(3).collect()),
                    ..Influence::default()
                }),
            ),
            layer(
                "vertex dogme",
                dogme(Anchor::Vertex(5_000)),
                around(Vec3::new(1.2, 1.3, 0.0), sphere(0.8), false),
            ),
            layer(
                "top curve",
                bent_curve(CurveBasis::Bezier, 1.9),
                around(Vec3::new(1.1, 1.9, 0.0), sphere(0.6), false),
            ),
        ];
        Stack { layers }
    }

    /// The layers one at a time over every vertex (the evaluation before runs).
    fn layer_by_layer(stack: &Stack, rest: &RestMesh) -> Result<Vec<Vec3>> {
        stack.validate()?;
        let mut positions = rest.welded_positions().to_vec();
        for l in stack.layers.iter().filter(|l| !l.is_inert()) {
            LayerBinding::bind(l, &positions, rest.topology())?.apply(l, &mut positions)?;
        }
        Ok(positions)
    }

    fn bits(p: &[Vec3]) -> Vec<[u32; 3]> {
        p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
    }

    fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(f)
    }

    #[test]
    fn runs_give_the_layer_by_layer_bits() {
        let stack = mixed();
        let runs: Vec<bool> = stack.layers.iter().map(is_per_vertex).collect();
        assert_eq!(
            runs,
            [
                true, true, true, true, true, true, true, true, true, false, true, false, false,
                true
            ],
            "which layers a run takes"
        );
        for n in [230, 100] {
            let rest = sheet(n);
            let want = layer_by_layer(&stack, &rest).unwrap();
            let moved = want
                .iter()
                .zip(rest.welded_positions())
                .filter(|(a, b)| a != b)
                .count();
            assert!(moved > want.len() / 4, "the stack moves much of the sheet");
            for threads in [1, 2, 3] {
                let got = on_threads(threads, || stack.evaluate_welded(&rest)).unwrap();
                assert_eq!(bits(&got), bits(&want), "{n}² vertices, {threads} threads");
            }
        }
    }

    /// A layer that lifts the middle of the sheet by about 1 and one whose volume lies where
    /// it lifts them, which no vertex reaches at rest: the second layer must cull the blocks
    /// the first moved by their new boxes, not by their boxes at rest.
    #[test]
    fn a_volume_weighs_the_vertices_an_earlier_layer_of_the_run_moved_into_it() {
        let centre = Vec3::new(1.1, 1.1, 0.0);
        let lift = Tool::Dogme(DogmeTool {
            constraints: vec![Constraint {
                at: Anchor::Point(centre),
                displacement: Vec3::Z,
                support: Support::Sphere { radius: 0.5 },
            }],
            degree: 3,
        });
        let push = lattice(
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(1.7, 1.7, 1.5),
            Vec3::new(0.3, 0.0, 0.0),
        );
        let stack = Stack {
            layers: vec![
                layer(
                    "lift",
                    lift,
                    around(centre, Shape::Sphere { radius: 0.6 }, false),
                ),
                layer(
                    "push",
                    Tool::Lattice(push),
                    around(centre + Vec3::Z, Shape::Sphere { radius: 0.3 }, false),
                ),
            ],
        };
        let rest = sheet(230);
        assert!(
            rest.welded_positions().iter().all(|p| p.z < 0.5),
            "at rest no vertex is in the second volume"
        );
        let lifted = layer_by_layer(
            &Stack {
                layers: stack.layers[..1].to_vec(),
            },
            &rest,
        )
        .unwrap();
        let want = layer_by_layer(&stack, &rest).unwrap();
        let pushed = want.iter().zip(&lifted).filter(|(a, b)| a != b).count();
        assert!(
            pushed > 200,
            "the second layer moves {pushed} lifted vertices"
        );
        for threads in [1, 2] {
            let got = on_threads(threads, || stack.evaluate_welded(&rest)).unwrap();
            assert_eq!(bits(&got), bits(&want), "{threads} threads");
        }
    }

    #[test]
    fn a_run_reports_moved_blocks_only() {
        let rest = sheet(230);
        let stack = mixed();
        let mut positions = rest.welded_positions().to_vec();
        let run: Vec<&Layer> = stack.layers[..1].iter().collect();
        let moved = evaluate_run(&run, &mut positions, rest.topology()).unwrap();
        assert!(!moved.is_empty());
        for (b, (now, was)) in positions
            .chunks(BLOCK)
            .zip(rest.welded_positions().chunks(BLOCK))
            .enumerate()
        {
            let span = b * BLOCK..b * BLOCK + now.len();
            assert_eq!(moved.contains(&span), now != was, "block {b}");
        }
    }

    /// A Direct FFD layer whose constraint point `at` lies outside its lattice, so that its
    /// bind (made once for a run) fails, weighing the vertices near `centre`.
    fn unbindable(name: &str, at: Vec3, centre: Vec3) -> Layer {
        let mut tool = DirectFfdTool {
            lattice: lattice(Vec3::ZERO, Vec3::ONE, Vec3::ZERO),
            constraints: Vec::new(),
        };
        tool.constraints.push(DirectConstraint {
            at: Anchor::Point(at),
            displacement: Vec3::X,
        });
        let l = layer(
            name,
            Tool::DirectFfd(tool),
            around(centre, Shape::Sphere { radius: 0.3 }, false),
        );
        assert!(is_per_vertex(&l) && !l.is_inert());
        l
    }

    #[test]
    fn a_run_reports_the_earliest_failing_layer() {
        let rest = sheet(230);
        // The first failing layer weighs vertices of late blocks only; the second fails in
        // an early block, which a block-by-block run meets first.
        let stack = Stack {
            layers: vec![
                layer("curve", bent_curve(CurveBasis::Bezier, 1.0), None),
                unbindable("late", Vec3::splat(3.0), Vec3::new(1.5, 2.0, 0.0)),
                unbindable("early", Vec3::splat(4.0), Vec3::new(0.5, 0.3, 0.0)),
            ],
        };
        let want = layer_by_layer(&stack, &rest).unwrap_err().to_string();
        assert!(want.contains("[3, 3, 3]"), "{want}");
        for threads in [1, 2] {
            let got = on_threads(threads, || stack.evaluate_welded(&rest)).unwrap_err();
            assert_eq!(got.to_string(), want, "{threads} threads");
        }
    }

    #[test]
    fn a_block_names_a_non_finite_vertex_by_its_index_in_the_mesh() {
        // A lattice leaves a point outside it as it is, NaN included.
        let l = layer(
            "lattice",
            Tool::Lattice(lattice(Vec3::ZERO, Vec3::ONE, Vec3::Z)),
            None,
        );
        let bind = l.tool.bind(&BindInput {
            positions: &[],
            topology: sheet(2).topology(),
            active: &[],
        });
        let mut block = vec![Vec3::splat(0.5); 100];
        block[37].y = f32::NAN;
        block[61].x = f32::INFINITY;
        let err = apply_per_vertex(
            &l,
            &bind.unwrap(),
            &Mask::all(100),
            &mut block,
            (3 * BLOCK) as u32,
            &mut Vec::new(),
        )
        .unwrap_err();
        let vertex = 3 * BLOCK + 37;
        assert!(
            err.to_string()
                .ends_with(&format!("non-finite position for vertex {vertex}")),
            "{err}"
        );
    }

    #[test]
    fn a_shared_bind_fails_only_where_its_layer_weighs_a_vertex() {
        let rest = sheet(230);
        let direct = |centre| Stack {
            layers: vec![
                layer("curve", bent_curve(CurveBasis::Bezier, 1.0), None),
                unbindable("direct", Vec3::splat(3.0), centre),
            ],
        };
        // Its volume weighs no vertex: no bind, no error, as layer by layer.
        let idle = direct(Vec3::splat(9.0));
        let want = layer_by_layer(&idle, &rest).unwrap();
        assert_eq!(bits(&idle.evaluate_welded(&rest).unwrap()), bits(&want));
        // It weighs some: the bind's error.
        let failing = direct(Vec3::new(1.0, 1.0, 0.0));
        let want = layer_by_layer(&failing, &rest).unwrap_err().to_string();
        assert!(want.contains("outside the lattice"), "{want}");
        assert_eq!(
            failing.evaluate_welded(&rest).unwrap_err().to_string(),
            want
        );
    }
}
