//! Gizmo geometry: what to draw for a node, as plain data in the node's local frame.
//!
//! A [`Gizmo`] is a list of polylines, circles and points, each tagged with a [`Role`] so
//! that a renderer (the Studio's bevy systems) picks colours and sizes; there are no colours
//! here. [`gizmo`] builds the geometry of any node of a [`Document`]: a tool's control
//! points, curves with their rotation-minimising frames, lattices, surface grids, constraint
//! points, a macro tool's FFSD points at its current value, a volume's outline.
//! [`volume_outline`] and [`falloff_plateau`] draw influence volumes and the part of them
//! where a layer's weight stays 1; [`layer_falloff`] does that for every volume of a layer.
//! `docs/algorithms/handles-and-gizmos.md` lists what each kind shows and why.

mod outline;
mod tools;

use glam::{Affine3A, Vec3};

use crate::document::{Document, NodeKind, wrong_kind};
use crate::error::{Result, SceneError};
use ductile_core::tool::uniform_scale;

pub use outline::{falloff_plateau, volume_outline};
pub use tools::tool_gizmo;

/// What a piece of gizmo geometry stands for; the renderer maps roles to colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// A point the user drags to deform: an FFSD control point, a deformed polygon point, a
    /// lattice or moved surface control point, a sketch target curve point.
    ControlPoint,
    /// An FFSD directional reference point `R`.
    ReferencePoint,
    /// A rest-state point: a rest polygon point, a rest surface net point, a sketch
    /// reference curve point.
    RestPoint,
    /// A DOGME or Direct FFD constraint point (where the constraint grabs).
    ConstraintPoint,
    /// Where a constraint point must go (constraint point plus displacement).
    ConstraintTarget,
    /// A line from a point to where it pushes or is pushed: FFSD reference → control point,
    /// constraint point → target.
    Displacement,
    /// The ε radius of an FFSD point (three great circles).
    EpsilonRadius,
    /// A deformed (current) curve: axial deformed axis, deformed curve, sketch target.
    Curve,
    /// A rest curve: axial rest axis, rest curve, sketch reference.
    RestCurve,
    /// A deformed control polygon or control net.
    ControlPolygon,
    /// A rest control polygon or control net.
    RestPolygon,
    /// A frame's first axis (the curve tangent).
    FrameX,
    /// A frame's second axis (the normal).
    FrameY,
    /// A frame's third axis (the binormal).
    FrameZ,
    /// A circle of the axial tool's zone of influence (radius `r` around the rest axis).
    InfluenceRadius,
    /// An edge between neighbouring lattice control points.
    LatticeEdge,
    /// The rest parallelepiped of a lattice.
    LatticeFrame,
    /// An iso-parameter line of a (moved) shape surface.
    SurfaceGrid,
    /// The outline of an influence volume (its boundary, normalised distance 1).
    VolumeOutline,
    /// The boundary of the part of a volume where a layer's falloff weight is 1.
    FalloffPlateau,
    /// The support of a DOGME constraint (its deformed area).
    Support,
}

/// A polyline: consecutive points are joined (two points make a segment).
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// The vertices, in order (at least two).
    pub points: Vec<Vec3>,
    /// What it stands for.
    pub role: Role,
}

/// A circle of the given radius around `center` in the plane perpendicular to `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre.
    pub center: Vec3,
    /// Unit normal of the circle's plane.
    pub normal: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// What it stands for.
    pub role: Role,
}

/// A marked point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Position.
    pub position: Vec3,
    /// What it stands for.
    pub role: Role,
}

/// The geometry to draw for a node, in one frame (the node's local frame unless said
/// otherwise).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Gizmo {
    /// Polylines.
    pub lines: Vec<Line>,
    /// Circles.
    pub circles: Vec<Circle>,
    /// Points.
    pub points: Vec<Point>,
}

impl Gizmo {
    /// Adds a polyline (ignored when it has fewer than two points).
    pub fn line(&mut self, points: Vec<Vec3>, role: Role) {
        if points.len() >= 2 {
            self.lines.push(Line { points, role });
        }
    }

    /// Adds a segment from `a` to `b`.
    pub fn segment(&mut self, a: Vec3, b: Vec3, role: Role) {
        self.lines.push(Line {
            points: vec![a, b],
            role,
        });
    }

    /// Adds a circle.
    pub fn circle(&mut self, center: Vec3, normal: Vec3, radius: f32, role: Role) {
        self.circles.push(Circle {
            center,
            normal,
            radius,
            role,
        });
    }

    /// Adds a point.
    pub fn point(&mut self, position: Vec3, role: Role) {
        self.points.push(Point { position, role });
    }

    /// Appends everything of `other`.
    pub fn extend(&mut self, other: Gizmo) {
        self.lines.extend(other.lines);
        self.circles.extend(other.circles);
        self.points.extend(other.points);
    }

    /// The same geometry with every item's role set to `role`.
    #[must_use]
    pub fn with_role(mut self, role: Role) -> Self {
        self.lines.iter_mut().for_each(|l| l.role = role);
        self.circles.iter_mut().for_each(|c| c.role = role);
        self.points.iter_mut().for_each(|p| p.role = role);
        self
    }

    /// The geometry mapped by `m`: points as points, circle normals by the inverse
    /// transpose, radii by the uniform scale `|det|^(1/3)` (so circles are exact for
    /// similarity transforms, the only ones that keep circles circular).
    #[must_use]
    pub fn transformed(&self, m: &Affine3A) -> Self {
        let s = uniform_scale(m);
        let normal_map = m.matrix3.inverse().transpose();
        Self {
            lines: self
                .lines
                .iter()
                .map(|l| Line {
                    points: l.points.iter().map(|&p| m.transform_point3(p)).collect(),
                    role: l.role,
                })
                .collect(),
            circles: self
                .circles
                .iter()
                .map(|c| Circle {
                    center: m.transform_point3(c.center),
                    normal: (normal_map * glam::Vec3A::from(c.normal))
                        .normalize_or_zero()
                        .into(),
                    radius: c.radius * s,
                    role: c.role,
                })
                .collect(),
            points: self
                .points
                .iter()
                .map(|p| Point {
                    position: m.transform_point3(p.position),
                    role: p.role,
                })
                .collect(),
        }
    }

    /// True when every coordinate and radius is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.lines
            .iter()
            .all(|l| l.points.iter().all(|p| p.is_finite()))
            && self
                .circles
                .iter()
                .all(|c| c.center.is_finite() && c.normal.is_finite() && c.radius.is_finite())
            && self.points.iter().all(|p| p.position.is_finite())
    }

    /// True when there is nothing to draw.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty() && self.circles.is_empty() && self.points.is_empty()
    }
}

/// The gizmo of node `node`, in the node's local frame:
///
/// * tool nodes: [`tool_gizmo`] of the tool;
/// * macro tool nodes: the FFSD geometry of the macro at the node's value
///   ([`Document::tool`]);
/// * volume nodes: the shape's outline ([`volume_outline`] at scale 1);
/// * meshes and groups: nothing (their handle is the origin, see `handles`).
///
/// Fails when the node does not exist, a macro is missing or the tool is invalid.
pub fn gizmo(doc: &Document, node: &str) -> Result<Gizmo> {
    let n = doc.node(node)?;
    match &n.kind {
        NodeKind::Tool(_) | NodeKind::Macro(_) => tool_gizmo(&doc.tool(node)?, node),
        NodeKind::Volume(v) => {
            v.shape.validate(node)?;
            Ok(volume_outline(&v.shape, 1.0))
        }
        NodeKind::Mesh(_) | NodeKind::Group => Ok(Gizmo::default()),
    }
}

/// The falloff plateaus of layer `layer` (0 = bottom) of mesh `mesh`: for every volume its
/// influence names, the volume's name and [`falloff_plateau`] of its shape with the layer's
/// falloff and `inner`, in the *volume's* local frame. Empty when the layer has no
/// influence or no volumes.
pub fn layer_falloff(doc: &Document, mesh: &str, layer: usize) -> Result<Vec<(String, Gizmo)>> {
    let m = doc.mesh(mesh)?;
    let spec = m
        .stack
        .get(layer)
        .ok_or_else(|| SceneError::IndexOutOfRange {
            what: format!("mesh '{mesh}': layer"),
            index: layer,
            len: m.stack.len(),
        })?;
    let Some(inf) = &spec.influence else {
        return Ok(Vec::new());
    };
    inf.volumes
        .iter()
        .map(|name| {
            let node = doc.node(name).map_err(|_| SceneError::UnknownVolume {
                mesh: mesh.to_owned(),
                layer,
                volume: name.clone(),
            })?;
            match &node.kind {
                NodeKind::Volume(v) => {
                    v.shape.validate(name)?;
                    Ok((
                        name.clone(),
                        falloff_plateau(&v.shape, &inf.falloff, inf.inner),
                    ))
                }
                other => Err(wrong_kind(name, other, "volume")),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
