//! Gizmos for every tool and volume: the geometry comes from `ductile_scene::gizmo` (pure,
//! per node, in its local frame); this module places it in the world, picks colours by role
//! and selection, and draws it with bevy's immediate-mode gizmos, on top of the meshes.

use bevy::prelude::*;
use ductile_scene::document::{Document, NodeKind};
use ductile_scene::gizmo::{Gizmo, Role, gizmo, layer_falloff};

use crate::document::SceneDocument;
use crate::selection::Selection;

/// The gizmo group of tool and volume gizmos (drawn over the meshes).
#[derive(Default, Reflect, GizmoConfigGroup)]
pub struct ToolGizmos;

/// What to draw.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct GizmoSettings {
    /// Draw tool and volume gizmos at all.
    pub enabled: bool,
    /// Draw the gizmos of macro tools that are not selected (the identikit has dozens).
    pub unselected_macros: bool,
}

impl Default for GizmoSettings {
    fn default() -> Self {
        Self {
            enabled: true,
            unselected_macros: false,
        }
    }
}

/// The colour of a role (before dimming unselected nodes).
#[must_use]
pub fn role_color(role: Role) -> Color {
    match role {
        Role::ControlPoint => Color::srgb(1.0, 0.55, 0.1),
        Role::ReferencePoint => Color::srgb(0.3, 0.8, 1.0),
        Role::RestPoint | Role::RestCurve | Role::RestPolygon => Color::srgb(0.6, 0.6, 0.7),
        Role::ConstraintPoint => Color::srgb(0.95, 0.3, 0.8),
        Role::ConstraintTarget => Color::srgb(0.3, 1.0, 0.5),
        Role::Displacement => Color::srgb(1.0, 0.9, 0.3),
        Role::EpsilonRadius | Role::InfluenceRadius => Color::srgb(1.0, 0.7, 0.4),
        Role::Curve => Color::srgb(1.0, 0.85, 0.2),
        Role::ControlPolygon => Color::srgb(0.9, 0.6, 0.2),
        Role::FrameX => Color::srgb(0.95, 0.25, 0.25),
        Role::FrameY => Color::srgb(0.3, 0.9, 0.3),
        Role::FrameZ => Color::srgb(0.3, 0.45, 1.0),
        Role::LatticeEdge => Color::srgb(0.55, 0.75, 1.0),
        Role::LatticeFrame => Color::srgb(0.5, 0.5, 0.6),
        Role::SurfaceGrid => Color::srgb(0.4, 0.9, 0.9),
        Role::VolumeOutline => Color::srgb(0.75, 0.55, 1.0),
        Role::FalloffPlateau => Color::srgb(0.55, 0.35, 0.9),
        Role::Support => Color::srgb(0.7, 0.7, 0.7),
    }
}

/// What the cached gizmos were built from: document revision, selected node, selected layer
/// (mesh, index), hidden nodes and whether unselected macros are drawn.
type GizmoKey = (
    u64,
    Option<String>,
    Option<(String, usize)>,
    std::collections::BTreeSet<String>,
    bool,
);

/// World-space gizmos of the document, rebuilt when the document or selection changes.
#[derive(Default)]
pub struct GizmoCache {
    key: Option<GizmoKey>,
    items: Vec<(Gizmo, bool)>,
}

/// Every node's gizmo in world space, with whether it is drawn as selected.
#[must_use]
pub fn world_gizmos(
    doc: &Document,
    selection: &Selection,
    unselected_macros: bool,
) -> Vec<(Gizmo, bool)> {
    let mut out = Vec::new();
    for node in &doc.nodes {
        let selected = selection.is_selected(&node.name);
        if matches!(node.kind, NodeKind::Macro(_)) && !selected && !unselected_macros {
            continue;
        }
        if selection.is_hidden(&node.name) {
            continue;
        }
        let (Ok(g), Ok(world)) = (gizmo(doc, &node.name), doc.world_transform(&node.name)) else {
            continue;
        };
        if !g.is_empty() {
            out.push((g.transformed(&world), selected));
        }
    }
    // The selected layer's falloff plateaus, in each volume's frame.
    if let Some((mesh, layer)) = &selection.layer
        && let Ok(list) = layer_falloff(doc, mesh, *layer)
    {
        for (volume, g) in list {
            if let Ok(world) = doc.world_transform(&volume) {
                out.push((g.transformed(&world), true));
            }
        }
    }
    out
}

/// Draws the cached world gizmos; unselected nodes are dimmed.
pub fn draw_gizmos(
    doc: Res<SceneDocument>,
    selection: Res<Selection>,
    settings: Res<GizmoSettings>,
    cameras: Query<&GlobalTransform, With<Camera3d>>,
    mut cache: Local<GizmoCache>,
    mut gizmos: Gizmos<ToolGizmos>,
) {
    if !settings.enabled {
        return;
    }
    let key = (
        doc.revision(),
        selection.node.clone(),
        selection.layer.clone(),
        selection.hidden.clone(),
        settings.unselected_macros,
    );
    if cache.key.as_ref() != Some(&key) {
        cache.items = world_gizmos(doc.shown(), &selection, settings.unselected_macros);
        cache.key = Some(key);
    }
    let eye = cameras.iter().next().map(GlobalTransform::translation);
    for (g, selected) in &cache.items {
        let color = |role: Role| {
            let c = role_color(role);
            if *selected { c } else { c.with_alpha(0.35) }
        };
        for line in &g.lines {
            gizmos.linestrip(line.points.iter().copied(), color(line.role));
        }
        for c in &g.circles {
            let rotation = Quat::from_rotation_arc(Vec3::Z, c.normal.normalize_or(Vec3::Z));
            gizmos
                .circle(Isometry3d::new(c.center, rotation), c.radius, color(c.role))
                .resolution(48);
        }
        for p in &g.points {
            let size = eye.map_or(0.005, |e| e.distance(p.position) * 0.006);
            gizmos.cross(
                Isometry3d::from_translation(p.position),
                size,
                color(p.role),
            );
        }
    }
}
