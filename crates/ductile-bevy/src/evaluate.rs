//! Per-frame stack evaluation: each mesh node's [`MeshEvaluator`] runs when the document
//! changed, and the result is written in place into the mesh asset.
//!
//! Small meshes are evaluated inline (the result shows in the same frame). Meshes with more
//! welded vertices than [`EvaluationSettings::background_threshold`] are evaluated on bevy's
//! async compute pool so that a long evaluation never stalls the frame: while one runs, newer
//! edits wait, and the latest document is evaluated as soon as it finishes (intermediate
//! states are skipped, never queued).

use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::asset::RenderAssetUsages;
use bevy::camera::primitives::Aabb;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use ductile_core::mesh::RestMesh;
use ductile_scene::document::Document;
use ductile_scene::evaluator::{MeshEvaluator, Update};

use crate::components::{MeshNodeMarker, SceneNode};
use crate::document::SceneDocument;
use crate::heatmap::{HeatMap, heat_colors};
use crate::rest::RestMeshes;
use crate::selection::Selection;

/// How meshes are evaluated.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct EvaluationSettings {
    /// Meshes with more welded vertices than this are evaluated in the background.
    pub background_threshold: usize,
}

impl Default for EvaluationSettings {
    fn default() -> Self {
        Self {
            background_threshold: 60_000,
        }
    }
}

/// What the last evaluation of a mesh did.
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluationReport {
    /// The document revision it evaluated.
    pub revision: u64,
    /// Wall-clock time of the evaluation.
    pub duration: Duration,
    /// Index of the first re-evaluated layer.
    pub first_layer: usize,
    /// Number of layers evaluated.
    pub layers_evaluated: usize,
    /// Whether it ran in the background.
    pub background: bool,
}

/// Totals over every evaluation, for the status bar and tests.
#[derive(Resource, Debug, Default, Clone, PartialEq)]
pub struct EvaluationStats {
    /// How many evaluations changed a mesh since the app started.
    pub evaluations: u64,
    /// The most recent evaluation that changed a mesh: the mesh node and its report.
    pub last: Option<(String, EvaluationReport)>,
    /// Meshes whose stack failed to evaluate, with the error (their last good result stays
    /// on screen).
    pub errors: Vec<(String, String)>,
}

type TaskOutput = (MeshEvaluator, Result<Update, String>, Duration);

/// The evaluation state of a mesh node whose rest mesh is loaded: the evaluator (absent while
/// it runs in the background), the rendered mesh asset and the last report.
#[derive(Component)]
pub struct MeshEvaluation {
    rest: Arc<RestMesh>,
    evaluator: Option<MeshEvaluator>,
    task: Option<(u64, Task<TaskOutput>)>,
    seen_revision: Option<u64>,
    heat_key: Option<(HeatMap, usize)>,
    /// The mesh asset the node is drawn with.
    pub mesh: Handle<Mesh>,
    /// The last evaluation that changed the mesh.
    pub last: Option<EvaluationReport>,
    /// The error of the last evaluation, if it failed.
    pub error: Option<String>,
}

impl MeshEvaluation {
    /// The rest mesh.
    #[must_use]
    pub fn rest(&self) -> &Arc<RestMesh> {
        &self.rest
    }

    /// The evaluator, unless it is running in the background.
    #[must_use]
    pub fn evaluator(&self) -> Option<&MeshEvaluator> {
        self.evaluator.as_ref()
    }

    /// True while a background evaluation runs.
    #[must_use]
    pub fn is_running(&self) -> bool {
        self.task.is_some()
    }
}

/// The material meshes are drawn with (white, so that heat-map vertex colours show as they
/// are).
#[derive(Resource, Debug, Clone)]
pub struct MeshMaterial(pub Handle<StandardMaterial>);

/// Makes the render mesh of a rest mesh: positions, normals, UVs and indices, kept in the
/// main world too so that evaluation can write positions in place.
#[must_use]
pub fn render_mesh(rest: &RestMesh) -> Mesh {
    let m = rest.mesh();
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::MAIN_WORLD | RenderAssetUsages::RENDER_WORLD,
    );
    let positions: Vec<[f32; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
    mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    let normals = rest.output(rest.welded_positions()).normals;
    mesh.insert_attribute(
        Mesh::ATTRIBUTE_NORMAL,
        normals.iter().map(|n| n.to_array()).collect::<Vec<_>>(),
    );
    if let Some(uvs) = &m.uvs {
        mesh.insert_attribute(
            Mesh::ATTRIBUTE_UV_0,
            uvs.iter().map(|t| t.to_array()).collect::<Vec<_>>(),
        );
    }
    mesh.insert_indices(Indices::U32(m.indices.clone()));
    mesh
}

/// Gives every mesh node whose rest mesh is loaded its render mesh, material and
/// evaluation state (and takes them away again when the node's source is gone).
pub fn attach_mesh_evaluation(
    mut commands: Commands,
    rests: Res<RestMeshes>,
    material: Option<Res<MeshMaterial>>,
    mut meshes: ResMut<Assets<Mesh>>,
    nodes: Query<(Entity, &SceneNode, &MeshNodeMarker), Without<MeshEvaluation>>,
) {
    for (entity, node, marker) in &nodes {
        let Some(rest) = rests.get(&marker.source) else {
            continue;
        };
        let handle = meshes.add(render_mesh(rest));
        let evaluation = MeshEvaluation {
            rest: Arc::clone(rest),
            evaluator: Some(MeshEvaluator::new(&node.name, (**rest).clone())),
            task: None,
            seen_revision: None,
            heat_key: None,
            mesh: handle.clone(),
            last: None,
            error: None,
        };
        let aabb = ductile_core::mesh::bounds(rest.welded_positions())
            .map_or_else(Aabb::default, |(min, max)| Aabb::from_min_max(min, max));
        let mut e = commands.entity(entity);
        e.insert((evaluation, Mesh3d(handle), aabb));
        if let Some(material) = &material {
            e.insert(MeshMaterial3d(material.0.clone()));
        }
    }
}

/// Evaluates every mesh whose document revision is not the one it last evaluated, inline
/// or in the background, and collects finished background evaluations.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_meshes(
    doc: Res<SceneDocument>,
    settings: Res<EvaluationSettings>,
    selection: Res<Selection>,
    heat: Res<HeatMapSettings>,
    mut stats: ResMut<EvaluationStats>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut evaluations: Query<(&SceneNode, &mut MeshEvaluation, &mut Aabb)>,
    mut shared: Local<Option<(u64, Arc<Document>)>>,
) {
    for (node, mut ev, mut aabb) in &mut evaluations {
        let ev = &mut *ev;
        // Collect a finished background run.
        if let Some((revision, task)) = &mut ev.task
            && let Some((evaluator, result, duration)) = check_ready(task)
        {
            let revision = *revision;
            ev.task = None;
            ev.evaluator = Some(evaluator);
            finish(
                &node.name,
                ev,
                result,
                duration,
                revision,
                true,
                &mut stats,
                &mut meshes,
                &mut aabb,
                &selection,
                &heat,
            );
        }
        let wanted_heat = heat_key(&node.name, &selection, &heat);
        if ev.seen_revision == Some(doc.revision()) && ev.heat_key == wanted_heat {
            continue;
        }
        let Some(mut evaluator) = ev.evaluator.take() else {
            continue; // running; the newest revision is evaluated when it finishes
        };
        let revision = doc.revision();
        if ev.seen_revision == Some(revision) {
            // Only the heat-map changed.
            ev.evaluator = Some(evaluator);
            write_colors(&node.name, ev, &mut meshes, &selection, &heat);
            continue;
        }
        if ev.rest.topology().vertex_count() > settings.background_threshold {
            let document = match &*shared {
                Some((r, d)) if *r == revision => Arc::clone(d),
                _ => {
                    let d = Arc::new(doc.shown().clone());
                    *shared = Some((revision, Arc::clone(&d)));
                    d
                }
            };
            let task = AsyncComputeTaskPool::get().spawn(async move {
                let start = Instant::now();
                let result = evaluator.update(&document).map_err(|e| e.to_string());
                (evaluator, result, start.elapsed())
            });
            ev.task = Some((revision, task));
            ev.seen_revision = Some(revision);
        } else {
            let start = Instant::now();
            let result = evaluator.update(doc.shown()).map_err(|e| e.to_string());
            let duration = start.elapsed();
            ev.evaluator = Some(evaluator);
            finish(
                &node.name,
                ev,
                result,
                duration,
                revision,
                false,
                &mut stats,
                &mut meshes,
                &mut aabb,
                &selection,
                &heat,
            );
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn finish(
    name: &str,
    ev: &mut MeshEvaluation,
    result: Result<Update, String>,
    duration: Duration,
    revision: u64,
    background: bool,
    stats: &mut EvaluationStats,
    meshes: &mut Assets<Mesh>,
    aabb: &mut Aabb,
    selection: &Selection,
    heat: &HeatMapSettings,
) {
    ev.seen_revision = Some(revision);
    stats.errors.retain(|(m, _)| m != name);
    match result {
        Ok(update) => {
            ev.error = None;
            let report = EvaluationReport {
                revision,
                duration,
                first_layer: update.first_layer,
                layers_evaluated: update.layers_evaluated,
                background,
            };
            if update.changed {
                ev.last = Some(report.clone());
                write_positions(ev, meshes, aabb);
                stats.evaluations += 1;
                stats.last = Some((name.to_owned(), report));
            }
            ev.heat_key = None; // colours follow the new positions
            write_colors(name, ev, meshes, selection, heat);
        }
        Err(e) => {
            warn!("mesh '{name}': {e}");
            ev.error = Some(e.clone());
            stats.errors.push((name.to_owned(), e));
        }
    }
}

/// Writes the evaluator's deformed positions and normals into the mesh asset in place (or
/// replaces the buffers when a refining layer changed the vertex count).
fn write_positions(ev: &MeshEvaluation, meshes: &mut Assets<Mesh>, aabb: &mut Aabb) {
    let Some(deformed) = ev.evaluator.as_ref().and_then(MeshEvaluator::deformed) else {
        return;
    };
    let Some(mut mesh) = meshes.get_mut(&ev.mesh) else {
        return;
    };
    let n = deformed.positions.len();
    let same_count = matches!(
        mesh.attribute(Mesh::ATTRIBUTE_POSITION),
        Some(VertexAttributeValues::Float32x3(v)) if v.len() == n
    );
    if same_count {
        if let Some(VertexAttributeValues::Float32x3(v)) =
            mesh.attribute_mut(Mesh::ATTRIBUTE_POSITION)
        {
            for (dst, p) in v.iter_mut().zip(&deformed.positions) {
                *dst = p.to_array();
            }
        }
        if let Some(VertexAttributeValues::Float32x3(v)) =
            mesh.attribute_mut(Mesh::ATTRIBUTE_NORMAL)
        {
            for (dst, p) in v.iter_mut().zip(&deformed.normals) {
                *dst = p.to_array();
            }
        }
    } else {
        mesh.insert_attribute(
            Mesh::ATTRIBUTE_POSITION,
            deformed
                .positions
                .iter()
                .map(|p| p.to_array())
                .collect::<Vec<_>>(),
        );
        mesh.insert_attribute(
            Mesh::ATTRIBUTE_NORMAL,
            deformed
                .normals
                .iter()
                .map(|p| p.to_array())
                .collect::<Vec<_>>(),
        );
        match deformed.uvs(&ev.rest) {
            Some(uvs) => mesh.insert_attribute(
                Mesh::ATTRIBUTE_UV_0,
                uvs.iter().map(|t| t.to_array()).collect::<Vec<_>>(),
            ),
            None => {
                mesh.remove_attribute(Mesh::ATTRIBUTE_UV_0);
            }
        }
        mesh.remove_attribute(Mesh::ATTRIBUTE_COLOR);
        mesh.insert_indices(Indices::U32(deformed.indices(&ev.rest)));
    }
    if let Some((min, max)) = ductile_core::mesh::bounds(&deformed.positions) {
        *aabb = Aabb::from_min_max(min, max);
    }
}

/// Which heat-map the user wants on a mesh, by layer index.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct HeatMapSettings {
    /// The mode, or `None` for the shaded mesh.
    pub mode: Option<HeatMap>,
}

fn heat_key(mesh: &str, selection: &Selection, heat: &HeatMapSettings) -> Option<(HeatMap, usize)> {
    let mode = heat.mode?;
    let (m, layer) = selection.layer.as_ref()?;
    (m == mesh).then_some((mode, *layer))
}

fn write_colors(
    name: &str,
    ev: &mut MeshEvaluation,
    meshes: &mut Assets<Mesh>,
    selection: &Selection,
    heat: &HeatMapSettings,
) {
    let wanted = heat_key(name, selection, heat);
    if ev.heat_key == wanted && wanted.is_some() {
        return;
    }
    let values = wanted.and_then(|(mode, layer)| {
        let evaluator = ev.evaluator.as_ref()?;
        match mode {
            HeatMap::Weight => evaluator.layer_weights(layer),
            HeatMap::Displacement => evaluator.layer_displacement(layer),
        }
    });
    let Some(mut mesh) = meshes.get_mut(&ev.mesh) else {
        return;
    };
    let count = mesh
        .attribute(Mesh::ATTRIBUTE_POSITION)
        .map_or(0, VertexAttributeValues::len);
    match values.filter(|v| v.len() == count) {
        Some(values) => {
            let mode = wanted.map_or(HeatMap::Weight, |(m, _)| m);
            mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, heat_colors(mode, &values));
        }
        None => {
            if mesh.attribute(Mesh::ATTRIBUTE_COLOR).is_some() {
                mesh.remove_attribute(Mesh::ATTRIBUTE_COLOR);
            }
        }
    }
    ev.heat_key = wanted;
}
