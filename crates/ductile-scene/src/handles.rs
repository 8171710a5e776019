//! Handles: the draggable points of a node, and the edit that moves one.
//!
//! [`handles`] lists a node's handles with their positions; [`moved`] returns the
//! [`NodeEdit`] that puts one handle at a new position (the Studio turns it into a history
//! operation: `Operation::set_tool` or `Operation::set_transform`).
//!
//! **Frames.** Every handle's position is given in the frame [`moved`] expects it in:
//! tool handles in the node's *local* frame (the frame its tool is given in), the
//! [`HandleId::Origin`] handle in the *parent's* frame (it is the node's translation).
//! So `moved(doc, node, &h.id, h.position)` is always the identity edit.
//!
//! **Order.** Tool handles come first, those that deform (control points, targets) before
//! rest-state ones, and the origin last: when several handles lie under the cursor, pick
//! the first. `docs/algorithms/handles-and-gizmos.md` lists what each tool kind offers.

use std::fmt;

use ductile_core::dogme::{Anchor, Support};
use ductile_core::ffsd::{ControlPoint, PointMode};
use ductile_core::lattice::{LatticeTool, PreparedLattice};
use ductile_core::sketch::tool::{Curve, SketchMode};
use ductile_core::surface::{ShapeSurfaceTool, SurfaceEdit};
use ductile_core::tool::Tool;
use glam::Vec3;

use crate::document::{Document, NodeKind};
use crate::error::{Result, SceneError};
use crate::transform::Transform;

/// Identifies one handle of a node. Indices count from 0 in the tool's own lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum HandleId {
    /// The node's origin (its translation, in the parent's frame). Every node has it.
    Origin,
    /// FFSD control point `k` (its position `C`).
    Control(usize),
    /// The reference point `R` of FFSD control point `k` (directional mode only).
    Reference(usize),
    /// Point `k` of the rest polygon (axial, curve) or of the sketch reference curve.
    Rest(usize),
    /// Point `k` of the deformed polygon (axial, curve) or of the sketch bend target.
    Deformed(usize),
    /// Lattice control point `(i, j, k)` (lattice tools and Direct FFD's lattice).
    Lattice(u32, u32, u32),
    /// Control point `(i, j)` of a shape surface's rest net.
    SurfaceRest(u32, u32),
    /// Control point `(i, j)` of a shape surface's moved net.
    SurfaceMoved(u32, u32),
    /// The point of DOGME / Direct FFD constraint `k` (free-point anchors only).
    Source(usize),
    /// The target (point plus displacement) of DOGME / Direct FFD constraint `k`.
    Target(usize),
    /// Point `k` of a tube volume's curve.
    Spine(usize),
}

impl HandleId {
    /// True for the one handle whose position is in the parent's frame
    /// ([`HandleId::Origin`]); all others are in the node's local frame.
    #[must_use]
    pub fn in_parent_frame(&self) -> bool {
        matches!(self, HandleId::Origin)
    }
}

impl fmt::Display for HandleId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            HandleId::Origin => write!(f, "origin"),
            HandleId::Control(k) => write!(f, "control point {k}"),
            HandleId::Reference(k) => write!(f, "reference point of control point {k}"),
            HandleId::Rest(k) => write!(f, "rest point {k}"),
            HandleId::Deformed(k) => write!(f, "deformed point {k}"),
            HandleId::Lattice(i, j, k) => write!(f, "lattice point ({i}, {j}, {k})"),
            HandleId::SurfaceRest(i, j) => write!(f, "rest surface point ({i}, {j})"),
            HandleId::SurfaceMoved(i, j) => write!(f, "moved surface point ({i}, {j})"),
            HandleId::Source(k) => write!(f, "constraint point {k}"),
            HandleId::Target(k) => write!(f, "constraint target {k}"),
            HandleId::Spine(k) => write!(f, "tube point {k}"),
        }
    }
}

/// What a handle does, for its look.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HandleRole {
    /// Moves the whole node.
    Origin,
    /// Deforms: FFSD control point, deformed polygon point, lattice or moved surface point,
    /// sketch target point.
    Control,
    /// An FFSD directional reference point.
    Reference,
    /// Places the tool's rest state: rest polygon, rest surface or sketch reference point.
    Rest,
    /// A constraint point.
    Source,
    /// A constraint target.
    Target,
}

/// One draggable point of a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handle {
    /// Which handle.
    pub id: HandleId,
    /// Position: node-local frame, or the parent's frame for the origin
    /// ([`HandleId::in_parent_frame`]).
    pub position: Vec3,
    /// What it does.
    pub role: HandleRole,
    /// A radius to show around it, in the same frame: an FFSD point's ε radius
    /// ([`epsilon_radius`]) on the point its weight is centred on, a DOGME sphere support's
    /// radius on the constraint point.
    pub radius: Option<f32>,
}

/// The edit that moves a handle, to be turned into a history operation.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeEdit {
    /// The node's new tool (`Operation::set_tool`).
    Tool(Tool),
    /// The node's new local transform (`Operation::set_transform`).
    Transform(Transform),
    /// The volume node's new shape (`Operation::set_volume`).
    Volume(ductile_core::influence::Shape),
}

/// The handles of node `node`: its tool's handles ([`tool_handles`], tool nodes only), then
/// its [`HandleId::Origin`]. Macro tools, volumes, meshes and groups have only the origin
/// (a macro's points belong to the library, not to the node). Fails when the node does not
/// exist or its tool is invalid.
pub fn handles(doc: &Document, node: &str) -> Result<Vec<Handle>> {
    let n = doc.node(node)?;
    let mut out = match &n.kind {
        NodeKind::Tool(t) => tool_handles(t, node)?,
        NodeKind::Volume(v) => match &v.shape {
            ductile_core::influence::Shape::Tube { points, .. } => points
                .iter()
                .enumerate()
                .map(|(k, &position)| Handle {
                    id: HandleId::Spine(k),
                    position,
                    role: HandleRole::Control,
                    radius: None,
                })
                .collect(),
            _ => Vec::new(),
        },
        _ => Vec::new(),
    };
    out.push(Handle {
        id: HandleId::Origin,
        position: n.transform.translation,
        role: HandleRole::Origin,
        radius: None,
    });
    Ok(out)
}

/// The edit that puts handle `id` of node `node` at `position` (node-local frame; for
/// [`HandleId::Origin`] the parent's frame, i.e. the node's new translation). Moving a
/// handle to where it is returns the unchanged tool or transform.
///
/// What a move changes: a point's position; a lattice or surface point's offset (by the
/// move); a constraint point's anchor with its displacement kept (the target follows); a
/// constraint target's displacement; the origin's translation (rotation and scale kept).
///
/// Fails when `position` is not finite, the node does not exist, it has no handle `id`
/// ([`SceneError::NoSuchHandle`] names both), or the moved tool does not validate.
pub fn moved(doc: &Document, node: &str, id: &HandleId, position: Vec3) -> Result<NodeEdit> {
    if !position.is_finite() {
        return Err(SceneError::NotFinite {
            what: format!("node '{node}': new position of handle {id}"),
            value: format!("{position}"),
        });
    }
    let n = doc.node(node)?;
    let no_handle = || SceneError::NoSuchHandle {
        node: node.to_owned(),
        handle: id.to_string(),
    };
    if *id == HandleId::Origin {
        return Ok(NodeEdit::Transform(Transform {
            translation: position,
            ..n.transform
        }));
    }
    if let (HandleId::Spine(k), NodeKind::Volume(v)) = (id, &n.kind) {
        let mut shape = v.shape.clone();
        let ductile_core::influence::Shape::Tube { points, .. } = &mut shape else {
            return Err(no_handle());
        };
        *points.get_mut(*k).ok_or_else(no_handle)? = position;
        shape.validate(node)?;
        return Ok(NodeEdit::Volume(shape));
    }
    let NodeKind::Tool(tool) = &n.kind else {
        return Err(no_handle());
    };
    let current = tool_handles(tool, node)?
        .into_iter()
        .find(|h| h.id == *id)
        .ok_or_else(no_handle)?;
    if current.position == position {
        return Ok(NodeEdit::Tool(tool.clone()));
    }
    let new = moved_tool(tool, id, position - current.position, position).ok_or_else(no_handle)?;
    new.validate(node)?;
    Ok(NodeEdit::Tool(new))
}

/// The handles of a tool in the tool's own space, in picking order (see the module
/// documentation). The tool is validated first (`what` names it in errors), so every
/// position is finite.
pub fn tool_handles(tool: &Tool, what: &str) -> Result<Vec<Handle>> {
    tool.validate(what)?;
    let mut out = Vec::new();
    let mut push = |id: HandleId, position: Vec3, role: HandleRole, radius: Option<f32>| {
        out.push(Handle {
            id,
            position,
            role,
            radius,
        });
    };
    match tool {
        Tool::Ffsd(t) => {
            for (k, p) in t.points.iter().enumerate() {
                let r = epsilon_radius(p);
                match p.mode {
                    PointMode::Directional { reference } => {
                        push(HandleId::Control(k), p.position, HandleRole::Control, None);
                        push(HandleId::Reference(k), reference, HandleRole::Reference, r);
                    }
                    PointMode::Basic | PointMode::Virtual => {
                        push(HandleId::Control(k), p.position, HandleRole::Control, r);
                    }
                }
            }
        }
        Tool::Axial(t) => {
            for (k, p) in t.deformed.iter().enumerate() {
                push(HandleId::Deformed(k), p.position, HandleRole::Control, None);
            }
            for (k, p) in t.rest.iter().enumerate() {
                push(HandleId::Rest(k), p.position, HandleRole::Rest, None);
            }
        }
        Tool::Curve(t) => {
            for (k, &p) in t.deformed.iter().enumerate() {
                push(HandleId::Deformed(k), p, HandleRole::Control, None);
            }
            for (k, &p) in t.rest.iter().enumerate() {
                push(HandleId::Rest(k), p, HandleRole::Rest, None);
            }
        }
        Tool::Lattice(t) => lattice_handles(t, what, &mut push)?,
        Tool::ShapeSurface(t) => {
            let (rest, moved) = surface_nets(t, what)?;
            let nu = t.counts.0 as usize;
            let at = |idx: usize| ((idx % nu) as u32, (idx / nu) as u32);
            for (idx, &p) in moved.iter().enumerate() {
                let (i, j) = at(idx);
                push(HandleId::SurfaceMoved(i, j), p, HandleRole::Control, None);
            }
            for (idx, &p) in rest.iter().enumerate() {
                let (i, j) = at(idx);
                push(HandleId::SurfaceRest(i, j), p, HandleRole::Rest, None);
            }
        }
        Tool::Dogme(t) => {
            for (k, c) in t.constraints.iter().enumerate() {
                if let Anchor::Point(p) = c.at {
                    let r = match c.support {
                        Support::Sphere { radius } => Some(radius),
                        Support::Box { .. } => None,
                    };
                    push(
                        HandleId::Target(k),
                        p + c.displacement,
                        HandleRole::Target,
                        None,
                    );
                    push(HandleId::Source(k), p, HandleRole::Source, r);
                }
            }
        }
        Tool::DirectFfd(t) => {
            for (k, c) in t.constraints.iter().enumerate() {
                if let Anchor::Point(p) = c.at {
                    push(
                        HandleId::Target(k),
                        p + c.displacement,
                        HandleRole::Target,
                        None,
                    );
                    push(HandleId::Source(k), p, HandleRole::Source, None);
                }
            }
            lattice_handles(&t.lattice, &format!("{what}: lattice"), &mut push)?;
        }
        Tool::Sketch(t) => {
            if let SketchMode::Bend {
                target: Curve::Points(pts),
                ..
            } = &t.mode
            {
                for (k, &p) in pts.iter().enumerate() {
                    push(HandleId::Deformed(k), p, HandleRole::Control, None);
                }
            }
            if let Curve::Points(pts) = &t.reference {
                for (k, &p) in pts.iter().enumerate() {
                    push(HandleId::Rest(k), p, HandleRole::Rest, None);
                }
            }
        }
    }
    Ok(out)
}

fn lattice_handles(
    t: &LatticeTool,
    what: &str,
    push: &mut impl FnMut(HandleId, Vec3, HandleRole, Option<f32>),
) -> Result<()> {
    let pts = lattice_points(t, what)?;
    let [l, m, _] = t.count_array();
    for (idx, &p) in pts.iter().enumerate() {
        let id = HandleId::Lattice(
            (idx % l) as u32,
            ((idx / l) % m) as u32,
            (idx / (l * m)) as u32,
        );
        push(id, p, HandleRole::Control, None);
    }
    Ok(())
}

/// The tool with handle `id` moved by `delta` to `position`; `None` when the tool has no
/// such handle.
fn moved_tool(tool: &Tool, id: &HandleId, delta: Vec3, position: Vec3) -> Option<Tool> {
    let mut tool = tool.clone();
    match (&mut tool, *id) {
        (Tool::Ffsd(t), HandleId::Control(k)) => t.points.get_mut(k)?.position = position,
        (Tool::Ffsd(t), HandleId::Reference(k)) => match &mut t.points.get_mut(k)?.mode {
            PointMode::Directional { reference } => *reference = position,
            _ => return None,
        },
        (Tool::Axial(t), HandleId::Rest(k)) => t.rest.get_mut(k)?.position = position,
        (Tool::Axial(t), HandleId::Deformed(k)) => t.deformed.get_mut(k)?.position = position,
        (Tool::Curve(t), HandleId::Rest(k)) => *t.rest.get_mut(k)? = position,
        (Tool::Curve(t), HandleId::Deformed(k)) => *t.deformed.get_mut(k)? = position,
        (Tool::Lattice(t), HandleId::Lattice(i, j, k)) => move_lattice(t, (i, j, k), delta),
        (Tool::ShapeSurface(t), HandleId::SurfaceRest(i, j)) => {
            add_offset(&mut t.rest, (i, j), delta);
        }
        (Tool::ShapeSurface(t), HandleId::SurfaceMoved(i, j)) => {
            add_offset(&mut t.moves, (i, j), delta);
        }
        (Tool::Dogme(t), HandleId::Source(k)) => {
            move_source(&mut t.constraints.get_mut(k)?.at, position)
        }
        (Tool::Dogme(t), HandleId::Target(k)) => {
            let c = t.constraints.get_mut(k)?;
            c.displacement += delta;
        }
        (Tool::DirectFfd(t), HandleId::Lattice(i, j, k)) => {
            move_lattice(&mut t.lattice, (i, j, k), delta);
        }
        (Tool::DirectFfd(t), HandleId::Source(k)) => {
            move_source(&mut t.constraints.get_mut(k)?.at, position);
        }
        (Tool::DirectFfd(t), HandleId::Target(k)) => {
            t.constraints.get_mut(k)?.displacement += delta;
        }
        (Tool::Sketch(t), HandleId::Rest(k)) => match &mut t.reference {
            Curve::Points(p) => *p.get_mut(k)? = position,
            _ => return None,
        },
        (Tool::Sketch(t), HandleId::Deformed(k)) => match &mut t.mode {
            SketchMode::Bend {
                target: Curve::Points(p),
                ..
            } => *p.get_mut(k)? = position,
            _ => return None,
        },
        _ => return None,
    }
    Some(tool)
}

/// Moves a free-point anchor (vertex anchors have no handle, so this never sees one).
fn move_source(at: &mut Anchor, position: Vec3) {
    if let Anchor::Point(p) = at {
        *p = position;
    }
}

fn move_lattice(t: &mut LatticeTool, at: (u32, u32, u32), delta: Vec3) {
    let old = t
        .points
        .iter()
        .find(|e| e.at == at)
        .map_or(Vec3::ZERO, |e| e.offset);
    t.set_offset(at, old + delta);
}

fn add_offset(edits: &mut Vec<SurfaceEdit>, at: (u32, u32), delta: Vec3) {
    match edits.iter_mut().find(|e| e.at == at) {
        Some(e) => e.offset += delta,
        None => edits.push(SurfaceEdit { at, offset: delta }),
    }
}

/// The radius shown for an FFSD control point: the distance `ε^(2/α)` from the point's
/// centre `X` at which its weight `W = exp(−|X − V|^α / (2ε²))` (Martínek & Kolingerová
/// 2014, Eq. 1) has fallen to `e^(−1/2)`. For the usual α = 2 it is ε itself (the Gaussian's
/// standard deviation); for other α it is the length ε stands for (it scales with the tool
/// the way `FfsdTool::transformed` scales ε). `None` when it is not a positive finite
/// number (an extreme α).
#[must_use]
pub fn epsilon_radius(p: &ControlPoint) -> Option<f32> {
    let r = p.epsilon.powf(2.0 / p.alpha);
    (r.is_finite() && r > 0.0).then_some(r)
}

/// The control points of a lattice, rest position (Greville abscissae) plus offset, dense
/// with index `i + l(j + m k)`.
pub(crate) fn lattice_points(t: &LatticeTool, what: &str) -> Result<Vec<Vec3>> {
    let prepared: PreparedLattice = t.prepare(what)?;
    let [l, m, _] = prepared.counts();
    Ok(prepared
        .offsets()
        .iter()
        .enumerate()
        .map(|(idx, &d)| prepared.rest_control_point(idx % l, (idx / l) % m, idx / (l * m)) + d)
        .collect())
}

/// The rest and moved control nets of a shape surface (dense, index `i + n_u j`).
pub(crate) fn surface_nets(t: &ShapeSurfaceTool, what: &str) -> Result<(Vec<Vec3>, Vec<Vec3>)> {
    use ductile_core::tool::Deformer;
    t.validate(what)?;
    t.control_nets().ok_or_else(|| {
        SceneError::Core(ductile_core::error::CoreError::Degenerate {
            what: what.to_owned(),
            problem: "the counts or degrees do not make a surface".to_owned(),
        })
    })
}

#[cfg(test)]
mod tests;
