//! Time to glTF: an animation baked as morph targets with a weights animation, one file per
//! frame, and variants as morph targets (see `docs/algorithms/animation.md`, "Export").
//!
//! **Baked animation.** The scene is sampled on its timeline: every frame from `from` to
//! `to` at the export rate, plus every key time in between (so keys are reproduced exactly,
//! even between frames). Each mesh is evaluated at each sample with one incremental
//! [`MeshEvaluator`] (a sketch bend whose target moves keeps its binding). A sample whose
//! deformed positions are within `tolerance × (the rest mesh's bounding-box diagonal)` of the
//! previous sample's target reuses that target, so holds cost nothing. Each target holds the
//! sample's position and normal deltas from the rest mesh; the weights animation is one-hot
//! per sample with linear interpolation, a crossfade between neighbouring baked frames. Any
//! glTF viewer plays it; in-betweens stay skeleton-style because every frame is baked.
//!
//! **Variants.** One target per variant (the variant's deformed mesh minus the rest mesh),
//! named after it, default weights 0: a viewer blends faces live. A morph blend is a linear
//! blend of vertex positions, not of parameters; [`morph_blend_error`] measures the
//! difference.

use std::path::{Path, PathBuf};

use ductile_core::mesh::{Deformed, RestMesh};
use ductile_scene::document::Document;
use ductile_scene::evaluator::MeshEvaluator;
use glam::Vec3;

use crate::error::{IoError, Result};
use crate::export::{ExportMesh, MorphTarget, Morphs, Sampling, WeightsAnimation, WeightsTrack};
use crate::scene::LoadedScene;

/// The most morph targets one mesh may get: bevy handles 256 morph weights, and three.js's
/// WebGL2 path keeps every target in one array texture of about that depth.
pub const MAX_TARGETS: usize = 256;

/// Default of [`BakeOptions::tolerance`].
pub const DEFAULT_TOLERANCE: f32 = 1e-5;

/// How an animation is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BakeOptions {
    /// Samples per second (finite, > 0).
    pub fps: f32,
    /// First frame, in the scene's timeline frames.
    pub from: i32,
    /// Last frame (≥ `from`).
    pub to: i32,
    /// Samples closer than this fraction of the rest mesh's bounding-box diagonal (largest
    /// vertex distance) share one morph target.
    pub tolerance: f32,
}

impl BakeOptions {
    /// The scene's whole timeline at its own rate.
    #[must_use]
    pub fn timeline(doc: &Document) -> Self {
        Self {
            fps: doc.animation.fps,
            from: doc.animation.start,
            to: doc.animation.end,
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

/// One sample of a baked animation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time in the scene (seconds).
    pub time: f32,
    /// True when a key lies at this time.
    pub key: bool,
}

/// The sample times of `options` on `doc`'s timeline: every frame from `from` to `to` at
/// `fps` (frame `f` of the timeline is at `f / doc fps` seconds) and every key time in
/// between, sorted, without duplicates. Errors when the range leaves the timeline or the
/// rate is not positive.
pub fn sample_times(doc: &Document, path: &Path, options: &BakeOptions) -> Result<Vec<Sample>> {
    let bad = |problem: String| IoError::Bake {
        path: path.to_owned(),
        problem,
    };
    let anim = &doc.animation;
    if !(options.fps.is_finite() && options.fps > 0.0) {
        return Err(bad(format!("--fps {} must be a number > 0", options.fps)));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(bad(format!(
            "tolerance {} must be a number ≥ 0",
            options.tolerance
        )));
    }
    if options.from > options.to {
        return Err(bad(format!(
            "--from {} is after --to {}",
            options.from, options.to
        )));
    }
    for f in [options.from, options.to] {
        anim.check_frame(f as f32).map_err(|e| bad(e.to_string()))?;
    }
    let t0 = anim.frame_time(options.from as f32);
    let t1 = anim.frame_time(options.to as f32);
    let steps = ((t1 - t0) * options.fps).round() as i64;
    if steps > 100_000 {
        return Err(bad(format!(
            "{steps} samples are too many (at most 100000)"
        )));
    }
    let mut times: Vec<Sample> = (0..=steps)
        .map(|k| t0 + k as f32 / options.fps)
        .filter(|&t| t <= t1)
        .chain([t1])
        .map(|time| Sample { time, key: false })
        .collect();
    for t in anim.key_times() {
        if t >= t0 && t <= t1 {
            times.push(Sample { time: t, key: true });
        }
    }
    times.sort_by(|a, b| a.time.total_cmp(&b.time).then(b.key.cmp(&a.key)));
    times.dedup_by(|b, a| {
        if a.time == b.time {
            a.key |= b.key;
            true
        } else {
            false
        }
    });
    Ok(times)
}

/// The largest distance between two position lists of the same length.
fn max_distance(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f32::max)
}

fn diagonal(rest: &RestMesh) -> f32 {
    ductile_core::mesh::bounds(&rest.mesh().positions).map_or(0.0, |(lo, hi)| lo.distance(hi))
}

/// The undeformed rest mesh as an output (positions and recomputed normals).
fn rest_output(rest: &RestMesh) -> Deformed {
    rest.output(rest.welded_positions())
}

/// A target: `deformed − base`.
fn target(name: String, base: &Deformed, deformed: &Deformed) -> MorphTarget {
    MorphTarget {
        name,
        positions: deformed
            .positions
            .iter()
            .zip(&base.positions)
            .map(|(d, b)| *d - *b)
            .collect(),
        normals: Some(
            deformed
                .normals
                .iter()
                .zip(&base.normals)
                .map(|(d, b)| *d - *b)
                .collect(),
        ),
    }
}

/// What a bake produced, for reports.
#[derive(Debug, Clone, PartialEq)]
pub struct BakeReport {
    /// The samples taken.
    pub samples: Vec<Sample>,
    /// Per mesh (in scene order): its name and number of morph targets.
    pub targets: Vec<(String, usize)>,
}

/// The scene's meshes at every sample: the rest mesh as base, one morph target per distinct
/// sample, and the weights animation. `progress(done, total)` is called after each sample.
pub fn bake_animation(
    scene: &LoadedScene,
    options: &BakeOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Vec<Deformed>, Morphs, BakeReport)> {
    let doc = &scene.document;
    let path = &scene.path;
    let samples = sample_times(doc, path, options)?;
    let t0 = samples.first().map_or(0.0, |s| s.time);
    let scene_err = |source| IoError::SceneProblem {
        path: path.clone(),
        source,
    };
    let mut evaluators: Vec<MeshEvaluator> = scene
        .meshes
        .iter()
        .map(|m| MeshEvaluator::new(&m.name, m.rest.clone()))
        .collect();
    let bases: Vec<Deformed> = scene.meshes.iter().map(|m| rest_output(&m.rest)).collect();
    let limits: Vec<f32> = scene
        .meshes
        .iter()
        .map(|m| options.tolerance * diagonal(&m.rest))
        .collect();
    let mut targets: Vec<Vec<MorphTarget>> = vec![Vec::new(); scene.meshes.len()];
    let mut last: Vec<Option<Vec<Vec3>>> = vec![None; scene.meshes.len()];
    // Per mesh, the target index of each sample.
    let mut chosen: Vec<Vec<usize>> = vec![Vec::with_capacity(samples.len()); scene.meshes.len()];
    let mut posed = doc.clone();
    for (k, s) in samples.iter().enumerate() {
        posed.pose_at(doc, s.time).map_err(scene_err)?;
        for (i, m) in scene.meshes.iter().enumerate() {
            evaluators[i]
                .update(&posed)
                .map_err(|source| IoError::MeshAtTime {
                    path: path.clone(),
                    mesh: m.name.clone(),
                    time: s.time,
                    source: Box::new(source),
                })?;
            let Some(d) = evaluators[i].deformed() else {
                continue;
            };
            if d.refined.is_some() {
                return Err(IoError::Bake {
                    path: path.clone(),
                    problem: format!(
                        "mesh '{}': a sketch layer refines the mesh, so its topology changes from frame to frame and cannot be a morph target; export one file per frame (--frames DIR)",
                        m.name
                    ),
                });
            }
            let reuse = last[i]
                .as_ref()
                .is_some_and(|p| max_distance(p, &d.positions) <= limits[i]);
            if !reuse {
                if targets[i].len() == MAX_TARGETS {
                    return Err(IoError::Bake {
                        path: path.clone(),
                        problem: format!(
                            "mesh '{}' needs more than {MAX_TARGETS} morph targets; export fewer frames (--from, --to, a lower --fps) or one file per frame (--frames DIR)",
                            m.name
                        ),
                    });
                }
                let frame = s.time * doc.animation.fps;
                targets[i].push(target(format!("frame {frame:.2}"), &bases[i], d));
                last[i] = Some(d.positions.clone());
            }
            chosen[i].push(targets[i].len() - 1);
        }
        progress(k + 1, samples.len());
    }
    let times: Vec<f32> = samples.iter().map(|s| s.time - t0).collect();
    let mut tracks = Vec::new();
    let mut weights = Vec::new();
    for (i, t) in targets.iter().enumerate() {
        let n = t.len();
        let mut w = vec![0.0_f32; times.len() * n];
        for (k, &c) in chosen[i].iter().enumerate() {
            w[k * n + c] = 1.0;
        }
        weights.push(w[..n].to_vec());
        // One sample only: a constant track still needs two distinct times in some viewers,
        // but glTF allows one; keep it.
        tracks.push(WeightsTrack {
            mesh: i,
            times: times.clone(),
            weights: w,
            sampling: Sampling::Linear,
        });
    }
    let report = BakeReport {
        samples: samples.clone(),
        targets: scene
            .meshes
            .iter()
            .zip(&targets)
            .map(|(m, t)| (m.name.clone(), t.len()))
            .collect(),
    };
    let morphs = Morphs {
        targets,
        weights,
        animations: vec![WeightsAnimation {
            name: "ductile".to_owned(),
            tracks,
        }],
    };
    Ok((bases, morphs, report))
}

/// Bakes the animation ([`bake_animation`]) and writes it to `out` (`.glb` or `.gltf`).
pub fn export_animation(
    scene: &LoadedScene,
    out: &Path,
    options: &BakeOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<BakeReport> {
    let (bases, morphs, report) = bake_animation(scene, options, progress)?;
    let meshes: Vec<ExportMesh<'_>> = scene
        .meshes
        .iter()
        .zip(&bases)
        .map(|(m, d)| ExportMesh::deformed(&m.name, &m.rest, d))
        .collect();
    crate::export::export_gltf_with(out, &meshes, &morphs)?;
    Ok(report)
}

/// Writes one `.glb` per sample into `dir` (created if needed): `frame-0000.glb`, … named by
/// the sample's index. Returns the files written.
pub fn export_frames(
    scene: &LoadedScene,
    dir: &Path,
    options: &BakeOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<PathBuf>> {
    let doc = &scene.document;
    let samples = sample_times(doc, &scene.path, options)?;
    std::fs::create_dir_all(dir).map_err(|source| IoError::Write {
        path: dir.to_owned(),
        source,
    })?;
    let mut evaluators: Vec<MeshEvaluator> = scene
        .meshes
        .iter()
        .map(|m| MeshEvaluator::new(&m.name, m.rest.clone()))
        .collect();
    let mut posed = doc.clone();
    let mut files = Vec::with_capacity(samples.len());
    for (k, s) in samples.iter().enumerate() {
        posed
            .pose_at(doc, s.time)
            .map_err(|source| IoError::SceneProblem {
                path: scene.path.clone(),
                source,
            })?;
        for (ev, m) in evaluators.iter_mut().zip(&scene.meshes) {
            ev.update(&posed).map_err(|source| IoError::MeshAtTime {
                path: scene.path.clone(),
                mesh: m.name.clone(),
                time: s.time,
                source: Box::new(source),
            })?;
        }
        let meshes: Vec<ExportMesh<'_>> = evaluators
            .iter()
            .zip(&scene.meshes)
            .filter_map(|(ev, m)| Some(ExportMesh::deformed(&m.name, &m.rest, ev.deformed()?)))
            .collect();
        let file = dir.join(format!("frame-{k:04}.glb"));
        crate::export::export_gltf(&file, &meshes)?;
        files.push(file);
        progress(k + 1, samples.len());
    }
    Ok(files)
}

/// Evaluates every mesh of `doc` (a document of `scene`, such as a variant applied).
fn evaluate_all(scene: &LoadedScene, doc: &Document) -> Result<Vec<Deformed>> {
    scene
        .meshes
        .iter()
        .map(|m| {
            doc.evaluate(&m.name, &m.rest)
                .map_err(|source| IoError::SceneProblem {
                    path: scene.path.clone(),
                    source,
                })
        })
        .collect()
}

/// The rest meshes as base and one morph target per variant (named after it, in name
/// order, default weight 0), ready for [`crate::export::export_gltf_with`]. `progress` is
/// told the variants evaluated and their count, after each.
pub fn variant_morphs(
    scene: &LoadedScene,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Vec<Deformed>, Morphs)> {
    let doc = &scene.document;
    if doc.variants.is_empty() {
        return Err(IoError::Bake {
            path: scene.path.clone(),
            problem: "the scene has no variants".to_owned(),
        });
    }
    if doc.variants.len() > MAX_TARGETS {
        return Err(IoError::Bake {
            path: scene.path.clone(),
            problem: format!(
                "{} variants are more than the {MAX_TARGETS} morph targets a mesh may have",
                doc.variants.len()
            ),
        });
    }
    let bases: Vec<Deformed> = scene.meshes.iter().map(|m| rest_output(&m.rest)).collect();
    let mut targets: Vec<Vec<MorphTarget>> = vec![Vec::new(); scene.meshes.len()];
    let total = doc.variants.len();
    progress(0, total);
    for (done, (name, v)) in doc.variants.iter().enumerate() {
        let applied = doc
            .with_states(&v.states)
            .map_err(|source| IoError::SceneProblem {
                path: scene.path.clone(),
                source,
            })?;
        for (i, d) in evaluate_all(scene, &applied)?.iter().enumerate() {
            if d.refined.is_some() {
                return Err(IoError::Bake {
                    path: scene.path.clone(),
                    problem: format!(
                        "mesh '{}': variant '{name}' refines the mesh, so it cannot be a morph target",
                        scene.meshes[i].name
                    ),
                });
            }
            targets[i].push(target(name.clone(), &bases[i], d));
        }
        progress(done + 1, total);
    }
    let weights = targets.iter().map(|t| vec![0.0; t.len()]).collect();
    Ok((
        bases,
        Morphs {
            targets,
            weights,
            animations: Vec::new(),
        },
    ))
}

/// Writes the rest meshes with one morph target per variant to `out` (`progress` as for
/// [`variant_morphs`]).
pub fn export_variant_morphs(
    scene: &LoadedScene,
    out: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<String>> {
    let (bases, morphs) = variant_morphs(scene, progress)?;
    let meshes: Vec<ExportMesh<'_>> = scene
        .meshes
        .iter()
        .zip(&bases)
        .map(|(m, d)| ExportMesh::deformed(&m.name, &m.rest, d))
        .collect();
    crate::export::export_gltf_with(out, &meshes, &morphs)?;
    Ok(scene.document.variants.keys().cloned().collect())
}

/// How far a morph-target blend is from the parameter blend it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct BlendError {
    /// The two variants.
    pub pair: (String, String),
    /// The blend factor `t`.
    pub t: f32,
    /// Largest vertex distance between `(1 − t)·V_A + t·V_B` (morph targets) and the mesh of
    /// the blended parameters, over every mesh.
    pub max: f32,
    /// Root mean square of that distance over every stored vertex.
    pub rms: f32,
    /// The same largest distance as a fraction of the rest mesh's bounding-box diagonal.
    pub relative: f32,
}

/// The error of blending variants `a` and `b` by morph targets at `t` instead of by
/// parameters (see the module documentation).
pub fn morph_blend_error(scene: &LoadedScene, a: &str, b: &str, t: f32) -> Result<BlendError> {
    let doc = &scene.document;
    let err = |source| IoError::SceneProblem {
        path: scene.path.clone(),
        source,
    };
    let va = evaluate_all(
        scene,
        &doc.with_states(&doc.variant(a).map_err(err)?.states)
            .map_err(err)?,
    )?;
    let vb = evaluate_all(
        scene,
        &doc.with_states(&doc.variant(b).map_err(err)?.states)
            .map_err(err)?,
    )?;
    let blended = doc.blend_two(a, b, t).map_err(err)?;
    let vp = evaluate_all(scene, &doc.with_states(&blended.states).map_err(err)?)?;
    let (mut max, mut sum, mut count, mut diag) = (0.0_f32, 0.0_f64, 0_usize, 0.0_f32);
    for (((pa, pb), pp), m) in va.iter().zip(&vb).zip(&vp).zip(&scene.meshes) {
        diag = diag.max(diagonal(&m.rest));
        for ((x, y), z) in pa.positions.iter().zip(&pb.positions).zip(&pp.positions) {
            let morph = *x * (1.0 - t) + *y * t;
            let d = morph.distance(*z);
            max = max.max(d);
            sum += f64::from(d * d);
            count += 1;
        }
    }
    Ok(BlendError {
        pair: (a.to_owned(), b.to_owned()),
        t,
        max,
        rms: (sum / count.max(1) as f64).sqrt() as f32,
        relative: if diag > 0.0 { max / diag } else { 0.0 },
    })
}
