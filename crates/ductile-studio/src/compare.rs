//! Side by side: copies of the mesh in focus placed next to it, each showing a saved variant
//! (or the undeformed rest mesh), so that a witness compares faces at a glance. The copies
//! are view state, not scene nodes: they are not saved, exported or edited, and they follow
//! the document (a variant's states written into the current document, evaluated with their
//! own incremental evaluator).

use std::sync::Arc;

use bevy::mesh::VertexAttributeValues;
use bevy::prelude::*;
use ductile_bevy::evaluate::{MeshMaterial, render_mesh};
use ductile_bevy::prelude::*;
use ductile_core::mesh::RestMesh;
use ductile_scene::evaluator::MeshEvaluator;

use crate::camera::{OrbitCamera, vertical_fov, view_aspect};

/// What one copy shows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CompareEntry {
    /// The rest mesh, no deformation.
    Rest,
    /// The saved variant of this name.
    Variant(String),
}

impl CompareEntry {
    /// The label drawn over the copy.
    #[must_use]
    pub fn label(&self) -> &str {
        match self {
            Self::Rest => "rest",
            Self::Variant(v) => v,
        }
    }
}

/// The copies wanted (in order, from the mesh towards +x), and where their labels go.
#[derive(Resource, Debug, Default, Clone, PartialEq)]
pub struct Compare {
    /// The entries shown next to the mesh in focus.
    pub entries: Vec<CompareEntry>,
    /// Screen positions (logical pixels) of the labels, with their text: the current face's
    /// and each copy's, above their bounds.
    pub labels: Vec<(String, Vec2)>,
}

/// A copy: its entry, the mesh node it copies and its own evaluator.
#[derive(Component)]
pub struct CompareCopy {
    entry: CompareEntry,
    source: String,
    rest: Arc<RestMesh>,
    evaluator: MeshEvaluator,
    seen: Option<u64>,
    mesh: Handle<Mesh>,
}

/// Keeps one copy per entry next to the first mesh node with a loaded rest mesh, brings each
/// up to date with the document, frames everything when the entries change, and places the
/// labels.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn update_compare(
    mut commands: Commands,
    mut compare: ResMut<Compare>,
    doc: Res<SceneDocument>,
    material: Option<Res<MeshMaterial>>,
    mut meshes: ResMut<Assets<Mesh>>,
    sources: Query<(&SceneNode, &MeshEvaluation, &GlobalTransform)>,
    mut copies: Query<(Entity, &mut CompareCopy, &mut Transform)>,
    mut cameras: Query<(&mut OrbitCamera, &Projection, &Camera, &GlobalTransform)>,
) {
    // Idle (the common case): no copy wanted and none left to remove.
    if compare.entries.is_empty() && copies.is_empty() {
        if !compare.labels.is_empty() {
            compare.labels.clear();
        }
        return;
    }
    let Some((node, source, at)) = sources.iter().next() else {
        return;
    };
    let rest = source.rest();
    let Some((min, max)) = ductile_core::mesh::bounds(rest.welded_positions()) else {
        return;
    };
    let step = Vec3::X * (max.x - min.x) * 1.15;
    // Drop copies no longer wanted (or of another mesh).
    let mut have = Vec::new();
    for (e, copy, _) in &copies {
        if copy.source != node.name || !compare.entries.contains(&copy.entry) {
            commands.entity(e).despawn();
        } else {
            have.push(copy.entry.clone());
        }
    }
    let mut changed = false;
    for entry in &compare.entries {
        if have.contains(entry) {
            continue;
        }
        changed = true;
        let mesh = meshes.add(render_mesh(rest));
        let mut e = commands.spawn((
            CompareCopy {
                entry: entry.clone(),
                source: node.name.clone(),
                rest: Arc::clone(rest),
                evaluator: MeshEvaluator::new(&node.name, (**rest).clone()),
                seen: None,
                mesh: mesh.clone(),
            },
            Mesh3d(mesh),
            Transform::default(),
        ));
        if let Some(m) = &material {
            e.insert(MeshMaterial3d(m.0.clone()));
        }
    }
    // Place and evaluate the copies.
    let document = doc.shown();
    for (_, mut copy, mut transform) in &mut copies {
        let Some(k) = compare.entries.iter().position(|e| *e == copy.entry) else {
            continue;
        };
        let placed = Transform::from_matrix(at.to_matrix())
            .with_translation(at.translation() + step * (k + 1) as f32);
        if *transform != placed {
            *transform = placed;
        }
        if copy.seen == Some(doc.revision()) {
            continue;
        }
        copy.seen = Some(doc.revision());
        let CompareEntry::Variant(name) = &copy.entry else {
            continue; // the rest mesh as loaded
        };
        let Ok(variant) = document.variant(name) else {
            continue;
        };
        let Ok(posed) = document.with_states(&variant.states) else {
            continue;
        };
        let copy = &mut *copy;
        if copy.evaluator.update(&posed).is_ok()
            && let Some(d) = copy.evaluator.deformed()
            && let Some(mut mesh) = meshes.get_mut(&copy.mesh)
            && d.positions.len() == copy.rest.mesh().positions.len()
        {
            if let Some(VertexAttributeValues::Float32x3(v)) =
                mesh.attribute_mut(Mesh::ATTRIBUTE_POSITION)
            {
                for (dst, p) in v.iter_mut().zip(&d.positions) {
                    *dst = p.to_array();
                }
            }
            if let Some(VertexAttributeValues::Float32x3(v)) =
                mesh.attribute_mut(Mesh::ATTRIBUTE_NORMAL)
            {
                for (dst, n) in v.iter_mut().zip(&d.normals) {
                    *dst = n.to_array();
                }
            }
        }
    }
    let Ok((mut orbit, projection, camera, eye)) = cameras.single_mut() else {
        return;
    };
    let n = compare.entries.len() as f32;
    if changed {
        let (lo, hi) = (at.transform_point(min), at.transform_point(max) + step * n);
        orbit.frame(
            lo.min(hi),
            lo.max(hi),
            vertical_fov(projection),
            view_aspect(projection, camera),
        );
    }
    // Labels above each face: the current one, then the copies.
    let top = at.transform_point(Vec3::new(
        (min.x + max.x) * 0.5,
        max.y,
        (min.z + max.z) * 0.5,
    ));
    let mut labels = Vec::new();
    if !compare.entries.is_empty() {
        let names = std::iter::once("current".to_owned())
            .chain(compare.entries.iter().map(|e| e.label().to_owned()));
        for (k, name) in names.enumerate() {
            if let Ok(p) = camera.world_to_viewport(eye, top + step * k as f32) {
                labels.push((name, p));
            }
        }
    }
    if compare.labels != labels {
        compare.labels = labels;
    }
}
