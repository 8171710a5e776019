//! The standard benchmark suite (`ductile bench --suite`): fixed cases built from the meshes
//! the program carries (the identikit head, subdivided to the sizes needed), so any two
//! commits or machines can be compared with one command. The criterion benchmark
//! `cargo bench -p ductile-cli --bench suite` times the same cases ([`Case::prepare`]).
//!
//! | case | what is timed |
//! |---|---|
//! | `identikit-30` | 30 FFSD macros on the head (8,844 welded vertices), full evaluation with normals, 1 thread |
//! | `mixed-1m/full` | the head split 11×11 (1.07 M welded vertices), 30 mixed layers, full evaluation with normals, 2 threads |
//! | `mixed-1m/full-1t` | the same on 1 thread, judged by the speed-up `full-1t / full` (at least [`SPEED_UP_TARGET`]), not by a time target |
//! | `mixed-1m/edit-top` | the same stack, the top layer's moved state changed, the incremental evaluator |
//! | `mixed-1m/edit-middle` | the same, the 16th of 30 layers changed: the 14 layers above it read what it moved |
//! | `lattice-1m` | a Bernstein 4×4×4 lattice on 1 M points, bind and deform, 2 threads |
//! | `batch-200` | the identikit demo applied to 200 head-sized meshes (load, evaluate, write `.glb`), 2 jobs |
//!
//! The mixed stack is what an artist builds: each layer is one of the Add menu's tools (FFSD
//! point, DOGME, Direct FFD, axial, Bézier and B-spline curves, shape surface, the three
//! lattices) placed around one region of the head and limited to it by an influence volume
//! (sphere, box, capsule, tube in turn); every tool has a moved state. See
//! `docs/performance.md`, "Standard suite".

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use ductile_core::chunks::CHUNK;
use ductile_core::lattice::{ControlEdit, LatticeFrame, LatticeTool};
use ductile_core::mesh::{RestMesh, Topology};
use ductile_core::primitives::subdivided_n;
use ductile_core::stack::Stack;
use ductile_core::tool::{BindInput, Tool};
use ductile_io::{MeshFormat, embedded};
use ductile_scene::create::{self, NewTool, NewVolume, Placement, SurfacePoint};
use ductile_scene::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use crate::batch;

/// Points of the lattice case, and the subdivision that takes the head to about a million
/// welded vertices (8,844 · 11² = 1.07 M).
const MILLION: usize = 1_000_000;
const SPLIT_1M: u32 = 11;
/// Layers of the mixed stack, and macros of the identikit case.
const MIXED_LAYERS: usize = 30;
const MACROS: usize = 30;
/// Meshes of the batch case.
const BATCH_MESHES: usize = 200;

/// One case of the suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// 30 identikit macros on the head, one thread.
    Identikit,
    /// 1 M vertices, 30 mixed layers, full evaluation, 2 threads.
    MixedFull,
    /// The same on one thread.
    MixedFullOneThread,
    /// The same stack, the top layer changed, incremental evaluator, 2 threads.
    MixedEditTop,
    /// The same stack, the middle layer changed, incremental evaluator, 2 threads.
    MixedEditMiddle,
    /// Bernstein 4×4×4 lattice on 1 M points, bind and deform, 2 threads.
    Lattice,
    /// The identikit demo on 200 head-sized meshes, 2 jobs.
    Batch,
}

/// A measured case.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The case's name.
    pub case: &'static str,
    /// Welded vertices (points for the lattice case; vertices of one mesh for the batch).
    pub vertices: usize,
    /// Layers of the stack.
    pub layers: usize,
    /// Worker threads (jobs for the batch).
    pub threads: usize,
    /// Median wall-clock time of one run, ms.
    pub median_ms: f64,
    /// 95th percentile (nearest rank), ms.
    pub p95_ms: f64,
    /// How many runs were timed.
    pub samples: usize,
    /// The time target on the project's 2-core machine, ms; `None` for the one-thread case,
    /// whose criterion is the speed-up ([`speed_up`]).
    pub target_ms: Option<f64>,
}

impl Outcome {
    /// The outcome as one JSON object (no line break).
    #[must_use]
    pub fn json(&self) -> String {
        let round = |x: f64| (x * 1000.0).round() / 1000.0;
        serde_json::json!({
            "case": self.case,
            "vertices": self.vertices,
            "layers": self.layers,
            "threads": self.threads,
            "median_ms": round(self.median_ms),
            "p95_ms": round(self.p95_ms),
            "samples": self.samples,
            "target_ms": self.target_ms,
        })
        .to_string()
    }
}

/// The least speed-up of `mixed-1m/full` from one thread to two that issue 15 asks for.
pub const SPEED_UP_TARGET: f64 = 1.8;

/// The speed-up of the full evaluation from one thread to two, `full-1t` over `full` (their
/// medians), when `outcomes` hold both.
#[must_use]
pub fn speed_up(outcomes: &[Outcome]) -> Option<f64> {
    let median = |case: Case| {
        outcomes
            .iter()
            .find(|o| o.case == case.name())
            .map(|o| o.median_ms)
    };
    Some(median(Case::MixedFullOneThread)? / median(Case::MixedFull)?)
}

/// A case ready to run: what it is, and one timed run.
pub struct Prepared {
    /// Welded vertices (or points).
    pub vertices: usize,
    /// Layers.
    pub layers: usize,
    /// Worker threads.
    pub threads: usize,
    /// The case's thread pool, which the timed runs are made from inside ([`Prepared::time`])
    /// so that a run is the work alone: entering a pool from another thread means waking a
    /// pool thread and being woken when it is done, 150–300 µs on this project's VM (timed
    /// with an empty job), a sixth of the identikit case. `None` for the batch, which starts
    /// its own threads.
    pub pool: Option<Arc<rayon::ThreadPool>>,
    /// One run of the timed work, in the case's thread pool.
    pub run: Box<dyn FnMut() -> anyhow::Result<()> + Send>,
}

impl Prepared {
    /// Makes `n` runs one after the other from inside the case's pool and returns the
    /// wall-clock time of each.
    ///
    /// # Errors
    /// The first run's error.
    pub fn time(&mut self, n: usize) -> anyhow::Result<Vec<Duration>> {
        let Self { pool, run, .. } = self;
        let mut runs = || -> anyhow::Result<Vec<Duration>> {
            (0..n)
                .map(|_| {
                    let t = Instant::now();
                    run()?;
                    Ok(t.elapsed())
                })
                .collect()
        };
        match pool {
            Some(pool) => pool.install(runs),
            None => runs(),
        }
    }
}

impl std::fmt::Debug for Prepared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Prepared")
            .field("vertices", &self.vertices)
            .field("layers", &self.layers)
            .field("threads", &self.threads)
            .finish_non_exhaustive()
    }
}

impl Case {
    /// Every case, in the order the suite runs them.
    pub const ALL: [Case; 7] = [
        Case::Identikit,
        Case::MixedFull,
        Case::MixedFullOneThread,
        Case::MixedEditTop,
        Case::MixedEditMiddle,
        Case::Lattice,
        Case::Batch,
    ];

    /// The case's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Case::Identikit => "identikit-30",
            Case::MixedFull => "mixed-1m/full",
            Case::MixedFullOneThread => "mixed-1m/full-1t",
            Case::MixedEditTop => "mixed-1m/edit-top",
            Case::MixedEditMiddle => "mixed-1m/edit-middle",
            Case::Lattice => "lattice-1m",
            Case::Batch => "batch-200",
        }
    }

    /// The time target on the project's 2-core machine, ms (issue 15). The one-thread case
    /// has none: issue 15 asks of it a speed-up ([`SPEED_UP_TARGET`], [`speed_up`]).
    #[must_use]
    pub fn target_ms(self) -> Option<f64> {
        match self {
            Case::Identikit => Some(1.0),
            Case::MixedFull => Some(150.0),
            Case::MixedFullOneThread => None,
            Case::MixedEditTop | Case::MixedEditMiddle => Some(16.0),
            Case::Lattice => Some(8.0),
            Case::Batch => Some(10_000.0),
        }
    }

    /// Timed runs of the case in the suite (the expensive cases fewer).
    #[must_use]
    pub fn samples(self) -> usize {
        match self {
            Case::Identikit => 200,
            Case::MixedFull | Case::MixedFullOneThread => 10,
            Case::MixedEditTop => 40,
            Case::MixedEditMiddle => 10,
            Case::Lattice => 40,
            Case::Batch => 3,
        }
    }

    fn threads(self) -> usize {
        match self {
            Case::Identikit | Case::MixedFullOneThread => 1,
            _ => 2,
        }
    }

    /// Builds the case's meshes and stack (untimed) and returns its timed run. `fixtures`
    /// caches what several cases share (the million-vertex head and its stack).
    pub fn prepare(self, fixtures: &mut Fixtures) -> anyhow::Result<Prepared> {
        let threads = self.threads();
        let pool = Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .context("cannot start the thread pool")?,
        );
        match self {
            Case::Identikit => {
                let (doc, rest) = identikit_30()?;
                full_evaluation(&doc, "head", rest, pool)
            }
            Case::MixedFull | Case::MixedFullOneThread => {
                let (doc, rest) = fixtures.mixed()?;
                full_evaluation(&doc, MIXED_NODE, rest, pool)
            }
            Case::MixedEditTop | Case::MixedEditMiddle => {
                let (mut doc, rest) = fixtures.mixed()?;
                let vertices = rest.welded_positions().len();
                let layers = doc.mesh(MIXED_NODE)?.stack.len();
                let mut ev = MeshEvaluator::new(MIXED_NODE, rest);
                pool.install(|| ev.update(&doc))?;
                // A layer's moved state, alternating between two values: the top layer (the
                // one being worked on), or the middle one, so that the layers above it that
                // read what it moved are redone too.
                let edited = if self == Case::MixedEditTop {
                    layers - 1
                } else {
                    layers / 2
                };
                let name = doc.mesh(MIXED_NODE)?.stack[edited].tool.clone();
                let mut flip = false;
                Ok(Prepared {
                    vertices,
                    layers,
                    threads,
                    pool: Some(Arc::clone(&pool)),
                    run: Box::new(move || {
                        flip = !flip;
                        if let NodeKind::Tool(t) = &mut doc.node_mut(&name)?.kind {
                            move_state(t, if flip { 0.7 } else { 1.0 });
                        }
                        let u = pool.install(|| ev.update(&doc))?;
                        anyhow::ensure!(u.changed, "the edit changed nothing");
                        Ok(())
                    }),
                })
            }
            Case::Lattice => {
                let points = cube_points(MILLION);
                let tool = lattice_4x4x4();
                let active: Vec<u32> = (0..MILLION as u32).collect();
                let topology = Topology {
                    weld: Vec::new(),
                    representative: Vec::new(),
                    triangles: Vec::new(),
                };
                let mut out = vec![Vec3::ZERO; MILLION];
                Ok(Prepared {
                    vertices: MILLION,
                    layers: 1,
                    threads,
                    pool: Some(Arc::clone(&pool)),
                    run: Box::new(move || {
                        pool.install(|| -> anyhow::Result<()> {
                            let bind = tool.bind(&BindInput {
                                positions: &points,
                                topology: &topology,
                                active: &active,
                            })?;
                            // In chunks over the pool, as the stack deforms a layer.
                            out.par_chunks_mut(CHUNK)
                                .zip(active.par_chunks(CHUNK))
                                .for_each(|(o, a)| tool.deform(&bind, &points, a, o));
                            std::hint::black_box(&out);
                            Ok(())
                        })
                    }),
                })
            }
            Case::Batch => {
                let dir = tempfile::tempdir().context("cannot make a temporary folder")?;
                let (doc, rest) = identikit_30()?;
                let inputs = write_heads(dir.path(), &rest, BATCH_MESHES)?;
                let jobs = batch::plan(&inputs, &dir.path().join("out"), batch::Shard::ALL)?;
                std::fs::create_dir_all(dir.path().join("out"))?;
                let vertices = rest.welded_positions().len();
                let layers = doc.mesh("head")?.stack.len();
                Ok(Prepared {
                    vertices,
                    layers,
                    threads,
                    pool: None,
                    run: Box::new(move || {
                        let template = batch::Template::new(&doc, "head", &rest)?;
                        let records = batch::run(&template, &jobs, threads, false, |_| {});
                        if let Some(r) = records.iter().find(|r| r.error.is_some()) {
                            anyhow::bail!("{}: {}", r.input, r.error.as_deref().unwrap_or(""));
                        }
                        // Keep the folder alive as long as the case.
                        let _ = dir.path();
                        Ok(())
                    }),
                })
            }
        }
    }

    /// Prepares the case, runs it once untimed, then `samples` timed runs.
    pub fn measure(self, fixtures: &mut Fixtures, samples: usize) -> anyhow::Result<Outcome> {
        let mut p = self
            .prepare(fixtures)
            .with_context(|| format!("case {}", self.name()))?;
        p.time(1).with_context(|| format!("case {}", self.name()))?;
        let mut times = p
            .time(samples.max(1))
            .with_context(|| format!("case {}", self.name()))?;
        let (median, p95) = median_p95(&mut times);
        Ok(Outcome {
            case: self.name(),
            vertices: p.vertices,
            layers: p.layers,
            threads: p.threads,
            median_ms: crate::commands::ms(median),
            p95_ms: crate::commands::ms(p95),
            samples: times.len(),
            target_ms: self.target_ms(),
        })
    }
}

/// The full evaluation of mesh node `node`'s stack (resolved once, untimed): bind every
/// layer, deform, normals, in `pool`.
fn full_evaluation(
    doc: &Document,
    node: &str,
    rest: RestMesh,
    pool: Arc<rayon::ThreadPool>,
) -> anyhow::Result<Prepared> {
    let stack: Stack = doc.resolve_stack(node, &rest)?;
    Ok(Prepared {
        vertices: rest.welded_positions().len(),
        layers: stack.layers.len(),
        threads: pool.current_num_threads(),
        pool: Some(Arc::clone(&pool)),
        run: Box::new(move || {
            pool.install(|| std::hint::black_box(stack.evaluate(&rest)))?;
            Ok(())
        }),
    })
}

/// The peak resident memory of this process (`VmHWM` of `/proc/self/status`, Linux), in
/// bytes; `None` where it cannot be read.
#[must_use]
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The median and the 95th percentile (nearest rank) of a non-empty sample.
#[must_use]
pub fn median_p95(times: &mut [Duration]) -> (Duration, Duration) {
    times.sort_unstable();
    let n = times.len();
    if n == 0 {
        return (Duration::ZERO, Duration::ZERO);
    }
    let median = if n % 2 == 1 {
        times[n / 2]
    } else {
        (times[n / 2 - 1] + times[n / 2]) / 2
    };
    let rank = (0.95 * n as f64).ceil() as usize;
    (median, times[rank.clamp(1, n) - 1])
}

/// What several cases share, built once per suite run.
#[derive(Debug, Default)]
pub struct Fixtures {
    mixed: Option<(Document, RestMesh)>,
}

impl Fixtures {
    /// The million-vertex head with its 30 mixed layers.
    pub fn mixed(&mut self) -> anyhow::Result<(Document, RestMesh)> {
        if self.mixed.is_none() {
            let head = head()?;
            let rest = RestMesh::new(subdivided_n(head.mesh(), SPLIT_1M), "head split 11×11")?;
            let doc = mixed_stack(&rest, MIXED_LAYERS);
            self.mixed = Some((doc, rest));
        }
        self.mixed.clone().context("mixed fixture")
    }
}

/// The name of the mesh node of the mixed stack.
pub const MIXED_NODE: &str = "mesh";

/// The identikit head the program carries.
pub fn head() -> anyhow::Result<RestMesh> {
    Ok(ductile_io::load_rest_mesh_from_bytes(
        embedded::HEAD_GLB,
        MeshFormat::Gltf,
        embedded::HEAD_SOURCE,
    )?)
}

/// The identikit head scene with its first 30 macros at ±0.5 (alternately) and the others at
/// 0 (skipped by the evaluation), and the head.
pub fn identikit_30() -> anyhow::Result<(Document, RestMesh)> {
    let mut doc = ductile_io::parse_scene(
        embedded::IDENTIKIT_HEAD_SCENE,
        Path::new(embedded::IDENTIKIT_HEAD_NAME),
    )?;
    let used: Vec<String> = doc
        .mesh("head")?
        .stack
        .iter()
        .map(|l| l.tool.clone())
        .collect();
    for (k, name) in used.iter().enumerate() {
        if let NodeKind::Macro(m) = &mut doc.node_mut(name)?.kind {
            m.value = match k {
                k if k >= MACROS => 0.0,
                k if k % 2 == 0 => 0.5,
                _ => -0.5,
            };
        }
    }
    Ok((doc, head()?))
}

/// A document whose mesh node [`MIXED_NODE`] (on `rest`) has `layers` layers cycling through
/// the Add menu's tool kinds, each placed around its own region of the mesh (a box of half the
/// mesh's size around a vertex, spread over the mesh) and limited to it by a volume of the
/// Add menu's shapes in turn, every tool with a moved state.
#[must_use]
pub fn mixed_stack(rest: &RestMesh, layers: usize) -> Document {
    let positions = rest.welded_positions();
    let (lo, hi) = ductile_core::mesh::bounds(positions).unwrap_or((Vec3::ZERO, Vec3::ONE));
    let half = 0.25 * (hi - lo);
    let normals = ductile_core::normals::smooth_normals(positions, &rest.topology().triangles);
    let mut nodes = vec![Node {
        name: MIXED_NODE.into(),
        parent: None,
        transform: Transform::IDENTITY,
        kind: NodeKind::Mesh(MeshNode {
            source: "head split 11×11".into(),
            stack: Vec::new(),
            areas: Default::default(),
        }),
    }];
    let mut stack = Vec::with_capacity(layers);
    for k in 0..layers {
        // Vertices spread over the mesh by a stride coprime with typical counts.
        let v = (k * 7_919 * 131 + 17) % positions.len();
        let centre = positions[v];
        let place = Placement {
            min: centre - half,
            max: centre + half,
            surface: Some(SurfacePoint {
                position: centre,
                normal: normals[v].try_normalize().unwrap_or(Vec3::Z),
            }),
        };
        let kind = NewTool::ALL[k % NewTool::ALL.len()];
        let mut tool = create::tool(kind, &place);
        move_state(&mut tool, 1.0);
        let (shape, transform) = create::volume(NewVolume::ALL[k % NewVolume::ALL.len()], &place);
        let (tool_name, volume_name) = (format!("{}-{k}", kind.stem()), format!("volume-{k}"));
        nodes.push(Node {
            name: tool_name.clone(),
            parent: Some(MIXED_NODE.into()),
            transform: Transform::IDENTITY,
            kind: NodeKind::Tool(tool),
        });
        nodes.push(Node {
            name: volume_name.clone(),
            parent: Some(MIXED_NODE.into()),
            transform,
            kind: NodeKind::Volume(VolumeNode { shape }),
        });
        stack.push(LayerSpec {
            influence: Some(InfluenceSpec {
                volumes: vec![volume_name],
                ..InfluenceSpec::default()
            }),
            ..LayerSpec::new(tool_name)
        });
    }
    if let NodeKind::Mesh(m) = &mut nodes[0].kind {
        m.stack = stack;
    }
    Document {
        nodes,
        ..Document::default()
    }
}

/// Sets a new tool's moved state to `k` times a small move (what dragging one of its handles
/// does): γ of the FFSD point, the displacement of a DOGME or Direct FFD constraint, the last
/// deformed axis or curve point, a lattice control point, a shape-surface point.
pub fn move_state(t: &mut Tool, k: f32) {
    match t {
        Tool::Ffsd(f) => f.points[0].gamma = k,
        Tool::Dogme(d) => {
            let c = &mut d.constraints[0];
            c.displacement = c.displacement.normalize_or_zero() * 0.02 * k;
        }
        Tool::DirectFfd(d) => {
            let c = &mut d.constraints[0];
            c.displacement = c.displacement.normalize_or_zero() * 0.02 * k;
        }
        Tool::Axial(a) => {
            let last = a.rest.len() - 1;
            a.deformed[last].position = a.rest[last].position + Vec3::Y * 0.05 * k;
            a.deformed[last].twist = 0.2 * k;
        }
        Tool::Curve(c) => {
            let last = c.rest.len() - 1;
            c.deformed[last] = c.rest[last] + Vec3::Y * 0.05 * k;
        }
        Tool::Lattice(l) => {
            l.points = vec![ControlEdit {
                at: (l.counts.0 / 2, l.counts.1 / 2, l.counts.2 - 1),
                offset: Vec3::Z * 0.05 * k,
                weight: 1.0,
            }];
        }
        Tool::ShapeSurface(s) => {
            s.moves = vec![ductile_core::surface::SurfaceEdit {
                at: (1, 1),
                offset: Vec3::Z * 0.03 * k,
            }];
        }
        Tool::Sketch(_) => {}
    }
}

/// `n` deterministic points filling the unit cube (a 64-bit LCG), as the core lattice
/// benchmark uses.
#[must_use]
pub fn cube_points(n: usize) -> Vec<Vec3> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n).map(|_| Vec3::new(next(), next(), next())).collect()
}

/// A Bernstein 4×4×4 (degree 3) lattice over the unit cube with every control point moved a
/// little (the core lattice benchmark's).
#[must_use]
pub fn lattice_4x4x4() -> Tool {
    let mut t = LatticeTool::bernstein(LatticeFrame::from_box(Vec3::ZERO, Vec3::ONE), (4, 4, 4));
    for k in 0..4 {
        for j in 0..4 {
            for i in 0..4 {
                let h = (i * 7 + j * 13 + k * 29) % 11;
                t.set_offset(
                    (i, j, k),
                    Vec3::new(0.01 * h as f32, -0.005 * h as f32, 0.02),
                );
            }
        }
    }
    Tool::Lattice(t)
}

/// Writes `count` head-sized meshes into `dir` (`head-000.glb`, …): the head, each copy
/// scaled a little differently, as scans of several people would differ. Returns their paths.
pub fn write_heads(dir: &Path, rest: &RestMesh, count: usize) -> anyhow::Result<Vec<String>> {
    let mut paths = Vec::with_capacity(count);
    for k in 0..count {
        let mut mesh = rest.mesh().clone();
        let s = 1.0 + 0.002 * (k % 25) as f32;
        for p in &mut mesh.positions {
            *p *= Vec3::new(s, 1.0, 2.0 - s);
        }
        let name = format!("head-{k:03}");
        let path = dir.join(format!("{name}.glb"));
        ductile_io::export_gltf(&path, &[ductile_io::ExportMesh::from_mesh(&name, &mesh)])?;
        paths.push(path.to_string_lossy().into_owned());
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_take_the_nearest_rank() {
        let ms = |v: u64| Duration::from_millis(v);
        let mut t: Vec<Duration> = (1..=20).rev().map(ms).collect();
        assert_eq!(median_p95(&mut t), (Duration::from_micros(10_500), ms(19)));
        assert_eq!(median_p95(&mut [ms(3)]), (ms(3), ms(3)));
    }

    /// The one-thread case is judged by the speed-up (issue 15: 1 thread vs 2 threads,
    /// at least 1.8×), not by a time of its own; its JSON line says so with a null target.
    #[test]
    fn the_speed_up_is_the_one_thread_median_over_the_two_thread_one() {
        let outcome = |case: Case, median_ms: f64| Outcome {
            case: case.name(),
            vertices: 1,
            layers: 1,
            threads: 1,
            median_ms,
            p95_ms: median_ms,
            samples: 1,
            target_ms: case.target_ms(),
        };
        let full = outcome(Case::MixedFull, 160.0);
        let one = outcome(Case::MixedFullOneThread, 320.0);
        assert_eq!(speed_up(&[one.clone(), full.clone()]), Some(2.0));
        assert_eq!(speed_up(std::slice::from_ref(&full)), None);
        assert_eq!(speed_up(std::slice::from_ref(&one)), None);
        let slow = outcome(Case::MixedFullOneThread, 240.0);
        assert!(speed_up(&[full.clone(), slow]).unwrap() < SPEED_UP_TARGET);
        assert_eq!(Case::MixedFullOneThread.target_ms(), None);
        assert_eq!(Case::MixedFull.target_ms(), Some(150.0));
        let json: serde_json::Value = serde_json::from_str(&one.json()).unwrap();
        assert!(json["target_ms"].is_null(), "{json}");
        let json: serde_json::Value = serde_json::from_str(&full.json()).unwrap();
        assert_eq!(json["target_ms"], 150.0);
    }

    #[test]
    fn the_mixed_stack_has_every_kind_limited_to_a_region() {
        let rest = head().unwrap();
        let doc = mixed_stack(&rest, 30);
        assert!(doc.problems().is_empty(), "{:?}", doc.problems());
        let stack = doc.resolve_stack(MIXED_NODE, &rest).unwrap();
        assert_eq!(stack.layers.len(), 30);
        assert!(
            stack.layers.iter().all(|l| !l.is_inert()),
            "every layer moves something"
        );
        let d = doc.evaluate(MIXED_NODE, &rest).unwrap();
        let moved = d
            .positions
            .iter()
            .zip(&rest.mesh().positions)
            .filter(|(a, b)| a != b)
            .count();
        // Local edits: much of the head moves, not all of it.
        let n = rest.mesh().positions.len();
        assert!(moved > n / 10 && moved < n, "{moved} of {n}");
    }

    #[test]
    fn the_identikit_case_sets_thirty_macros() {
        let (doc, rest) = identikit_30().unwrap();
        let stack = doc.resolve_stack("head", &rest).unwrap();
        let active = stack.layers.iter().filter(|l| !l.is_inert()).count();
        assert_eq!(active, 30);
    }

    /// Positions and normals as bits, for exact comparisons.
    fn bits(d: &ductile_core::mesh::Deformed) -> Vec<[u32; 6]> {
        d.positions
            .iter()
            .zip(&d.normals)
            .map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z].map(f32::to_bits))
            .collect()
    }

    #[test]
    fn evaluation_is_bit_identical_on_any_thread_count_and_incrementally() {
        // The head split 2×2 (35k vertices): above the parallel threshold, so the chunked
        // parallel paths run.
        let head = head().unwrap();
        let rest = RestMesh::new(subdivided_n(head.mesh(), 2), "head split 2×2").unwrap();
        assert!(rest.welded_positions().len() > ductile_core::chunks::PARALLEL_THRESHOLD);
        let mut doc = mixed_stack(&rest, MIXED_LAYERS);
        let run = |threads: usize, doc: &Document| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| doc.evaluate(MIXED_NODE, &rest).unwrap())
        };
        let one = bits(&run(1, &doc));
        assert_eq!(bits(&run(2, &doc)), one, "2 threads");
        assert_eq!(bits(&run(8, &doc)), one, "8 threads");

        // The incremental evaluator after edits of the middle and the top layer gives what
        // a full evaluation of the edited document gives.
        let mut ev = MeshEvaluator::new(MIXED_NODE, rest.clone());
        ev.update(&doc).unwrap();
        assert_eq!(bits(ev.deformed().unwrap()), one);
        let names: Vec<String> = doc
            .mesh(MIXED_NODE)
            .unwrap()
            .stack
            .iter()
            .map(|l| l.tool.clone())
            .collect();
        for name in [&names[15], &names[29], &names[3]] {
            if let NodeKind::Tool(t) = &mut doc.node_mut(name).unwrap().kind {
                move_state(t, 0.6);
            }
            let u = ev.update(&doc).unwrap();
            assert!(u.changed, "{name}");
            assert_eq!(
                bits(ev.deformed().unwrap()),
                bits(&run(2, &doc)),
                "after editing {name}"
            );
        }
    }
}
