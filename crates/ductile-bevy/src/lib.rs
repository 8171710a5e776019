//! Ductile's bevy plugin: the ECS mirror of a scene document, per-frame re-evaluation of
//! every mesh's non-destructive deformation stack, gizmos for every tool and volume, and
//! handle picking and dragging.
//!
//! The document ([`SceneDocument`]) is the single source of truth and is edited only
//! through [`DocumentCommand`] messages that become history operations. The plugin's
//! systems run in [`DuctileSystems`] sets, in this order each frame:
//! [`DuctileSystems::Input`] (handle drags) → [`DuctileSystems::Edit`] (apply commands) →
//! [`DuctileSystems::Sync`] (document → entities) → [`DuctileSystems::Evaluate`] (stacks →
//! mesh assets) → [`DuctileSystems::Gizmos`].
//!
//! The plugin works with `MinimalPlugins` (plus `AssetPlugin` and the `Mesh` asset) for
//! headless tests; rendering, gizmos and picking systems are added only when their plugins
//! are present.
#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod components;
pub mod document;
pub mod drag;
pub mod error;
pub mod evaluate;
pub mod gizmos;
pub mod handles;
pub mod heatmap;
pub mod rest;
pub mod selection;
pub mod sync;
pub mod undo_selection;

use bevy::picking::events::{DragStart, Pointer};
use bevy::prelude::*;

use crate::document::{
    DocumentChange, DocumentCommand, EditStatus, SceneDocument, apply_document_commands,
};
use crate::evaluate::{
    EvaluationSettings, EvaluationStats, HeatMapSettings, MeshMaterial, attach_mesh_evaluation,
    evaluate_meshes,
};
use crate::handles::{
    DragState, HandleAssets, HandleSettings, axis_keys, drag_handles, scale_handles,
    select_on_press, sync_handles,
};
use crate::rest::RestMeshes;
use crate::selection::Selection;
use crate::sync::{NodeEntities, sync_document_entities};

/// The commonly used types.
pub mod prelude {
    pub use crate::DuctilePlugin;
    pub use crate::DuctileSystems;
    pub use crate::components::{HandleMarker, MeshNodeMarker, SceneNode};
    pub use crate::document::{
        DocumentChange, DocumentCommand, EditStatus, PendingEdit, SceneDocument,
    };
    pub use crate::drag::AxisConstraint;
    pub use crate::error::DuctileBevyError;
    pub use crate::evaluate::{
        EvaluationReport, EvaluationSettings, EvaluationStats, HeatMapSettings, MeshEvaluation,
    };
    pub use crate::gizmos::GizmoSettings;
    pub use crate::handles::{DragState, HandleSettings};
    pub use crate::heatmap::HeatMap;
    pub use crate::rest::RestMeshes;
    pub use crate::selection::Selection;
    pub use crate::sync::NodeEntities;
}

/// The system sets of the plugin, chained in declaration order in `Update`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DuctileSystems {
    /// Pointer and keyboard input on handles (drags emit document commands).
    Input,
    /// Applies document commands (edits, undo, redo).
    Edit,
    /// Mirrors the document as entities and handles.
    Sync,
    /// Evaluates changed stacks and writes positions and normals into mesh assets.
    Evaluate,
    /// Draws tool and volume gizmos.
    Gizmos,
}

/// Adds the document, the ECS mirror, evaluation, gizmos and handle dragging.
#[derive(Debug, Default, Clone, Copy)]
pub struct DuctilePlugin;

impl Plugin for DuctilePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SceneDocument>()
            .init_resource::<EditStatus>()
            .init_resource::<RestMeshes>()
            .init_resource::<NodeEntities>()
            .init_resource::<Selection>()
            .init_resource::<EvaluationSettings>()
            .init_resource::<EvaluationStats>()
            .init_resource::<HeatMapSettings>()
            .init_resource::<HandleSettings>()
            .init_resource::<DragState>()
            .init_resource::<gizmos::GizmoSettings>()
            .init_resource::<undo_selection::SelectionMemory>()
            .add_message::<DocumentCommand>()
            .add_message::<DocumentChange>()
            .add_systems(First, undo_selection::remember_frame_selection)
            .configure_sets(
                Update,
                (
                    DuctileSystems::Input,
                    DuctileSystems::Edit,
                    DuctileSystems::Sync,
                    DuctileSystems::Evaluate,
                    DuctileSystems::Gizmos,
                )
                    .chain(),
            )
            .add_systems(
                Update,
                (
                    (
                        apply_document_commands,
                        undo_selection::restore_selection_on_undo,
                    )
                        .chain()
                        .in_set(DuctileSystems::Edit),
                    (
                        sync_document_entities.run_if(resource_changed::<SceneDocument>),
                        sync_handles,
                        crate::selection::apply_hidden,
                    )
                        .chain()
                        .in_set(DuctileSystems::Sync),
                    (attach_mesh_evaluation, ApplyDeferred, evaluate_meshes)
                        .chain()
                        .in_set(DuctileSystems::Evaluate),
                ),
            );
    }

    fn finish(&self, app: &mut App) {
        let world = app.world_mut();
        if let (true, true) = (
            world.contains_resource::<Assets<Mesh>>(),
            world.contains_resource::<Assets<StandardMaterial>>(),
        ) {
            let sphere = world.resource_mut::<Assets<Mesh>>().add(
                Sphere::new(1.0)
                    .mesh()
                    .ico(2)
                    .unwrap_or_else(|_| Sphere::new(1.0).mesh().uv(16, 8)),
            );
            let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
            let unlit = |c: Color| StandardMaterial {
                base_color: c,
                unlit: true,
                ..default()
            };
            let assets = HandleAssets {
                sphere,
                selected: materials.add(unlit(Color::srgb(1.0, 0.55, 0.1))),
                unselected: materials.add(unlit(Color::srgb(0.55, 0.6, 0.7))),
                active: materials.add(unlit(Color::srgb(1.0, 0.95, 0.3))),
            };
            let mesh_material = materials.add(StandardMaterial {
                base_color: Color::srgb(0.86, 0.84, 0.82),
                perceptual_roughness: 0.6,
                ..default()
            });
            world.insert_resource(assets);
            world.insert_resource(MeshMaterial(mesh_material));
        }
        if world.contains_resource::<Messages<Pointer<DragStart>>>() {
            app.add_systems(
                Update,
                ((select_on_press, axis_keys, drag_handles)
                    .chain()
                    .in_set(DuctileSystems::Input),),
            );
        }
        if app.world().contains_resource::<GizmoConfigStore>() {
            app.init_gizmo_group::<gizmos::ToolGizmos>();
            let (config, _) = app
                .world_mut()
                .resource_mut::<GizmoConfigStore>()
                .into_inner()
                .config_mut::<gizmos::ToolGizmos>();
            config.depth_bias = -1.0;
            config.line.width = 2.0;
            app.add_systems(
                Update,
                (
                    gizmos::draw_gizmos.in_set(DuctileSystems::Gizmos),
                    scale_handles,
                ),
            );
        }
    }
}
