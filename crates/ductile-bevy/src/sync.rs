//! Keeps one entity per document node: spawned when the node appears, updated when it
//! changes, despawned when it goes. Runs only when the document changed.

use std::collections::HashMap;

use bevy::prelude::*;
use ductile_scene::document::NodeKind;

use crate::components::{MeshNodeMarker, SceneNode};
use crate::document::SceneDocument;

/// The entity of every document node, by node name.
#[derive(Resource, Debug, Default, Clone)]
pub struct NodeEntities {
    by_name: HashMap<String, Entity>,
}

impl NodeEntities {
    /// The entity mirroring node `name`.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<Entity> {
        self.by_name.get(name).copied()
    }

    /// Number of mirrored nodes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.by_name.len()
    }

    /// True when no node is mirrored.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.by_name.is_empty()
    }
}

/// Converts a document affine (world transform) into a bevy [`Transform`].
#[must_use]
pub fn to_bevy_transform(affine: bevy::math::Affine3A) -> Transform {
    Transform::from_matrix(Mat4::from(affine))
}

/// Spawns, updates and despawns node entities so that they mirror the document. Components
/// are written only when their value changes, so change detection downstream sees real
/// edits only.
pub fn sync_document_entities(
    mut commands: Commands,
    doc: Res<SceneDocument>,
    mut entities: ResMut<NodeEntities>,
    mut nodes: Query<(&mut SceneNode, &mut Transform)>,
) {
    let document = doc.shown();
    let mut seen: HashMap<String, Entity> = HashMap::with_capacity(document.nodes.len());
    for node in &document.nodes {
        let transform = document
            .world_transform(&node.name)
            .map(to_bevy_transform)
            .unwrap_or_default();
        let wanted = SceneNode {
            name: node.name.clone(),
            node: node.clone(),
        };
        let mesh_source = match &node.kind {
            NodeKind::Mesh(m) => Some(m.source.clone()),
            _ => None,
        };
        match entities
            .by_name
            .get(&node.name)
            .and_then(|&e| nodes.get_mut(e).ok().map(|q| (e, q)))
        {
            Some((entity, (mut scene_node, mut t))) => {
                let kind_changed = std::mem::discriminant(&scene_node.node.kind)
                    != std::mem::discriminant(&node.kind);
                let source_changed = match (&scene_node.node.kind, &node.kind) {
                    (NodeKind::Mesh(a), NodeKind::Mesh(b)) => a.source != b.source,
                    _ => false,
                };
                if kind_changed || source_changed {
                    // A node that became something else starts over as a new entity.
                    commands.entity(entity).despawn();
                    seen.insert(
                        node.name.clone(),
                        spawn_node(&mut commands, wanted, transform, mesh_source),
                    );
                    continue;
                }
                scene_node.set_if_neq(wanted);
                t.set_if_neq(transform);
                seen.insert(node.name.clone(), entity);
            }
            None => {
                seen.insert(
                    node.name.clone(),
                    spawn_node(&mut commands, wanted, transform, mesh_source),
                );
            }
        }
    }
    for (name, entity) in &entities.by_name {
        if !seen.contains_key(name) {
            commands.entity(*entity).despawn();
        }
    }
    entities.by_name = seen;
}

fn spawn_node(
    commands: &mut Commands,
    node: SceneNode,
    transform: Transform,
    mesh_source: Option<String>,
) -> Entity {
    let name = Name::new(node.name.clone());
    let mut e = commands.spawn((node, name, transform, Visibility::default()));
    if let Some(source) = mesh_source {
        e.insert(MeshNodeMarker { source });
    }
    e.id()
}
