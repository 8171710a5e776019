//! The deformer abstraction and the [`Tool`] enum of every tool kind.
//!
//! Every tool follows the same two-step protocol:
//!
//! 1. **bind** — compute cached data from the layer's *input* (the positions coming out of the
//!    layer below, the welded topology, the active vertices of the layer's influence) and the
//!    tool's rest state. A bind is recomputed only when one of those inputs changes.
//! 2. **deform** — map each active vertex to its deformed position, using the bind. This is
//!    pure and per vertex, so the stack may split the active set into chunks and deform them
//!    in parallel.
//!
//! Tools are plain serialisable data, always given in the space of the mesh they deform.

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::axial::{AxialBind, AxialTool};
use crate::chunks::Reuse;
use crate::curve::{CurveBind, CurveSetup, CurveTool};
use crate::direct_ffd::{DirectFfdBind, DirectFfdTool};
use crate::dogme::{Anchor, DogmeBind, DogmeTool};
use crate::error::Result;
use crate::ffsd::{FfsdBind, FfsdTool};
use crate::lattice::{LatticeTool, PreparedLattice};
use crate::mesh::Topology;
use crate::refinement::WholeDeform;
use crate::sketch::tool::{SketchBind, SketchTool};
use crate::surface::{ShapeSurfaceTool, SurfaceBind, SurfaceSetup};

/// What a tool sees when it binds: the layer's input.
#[derive(Debug, Clone, Copy)]
pub struct BindInput<'a> {
    /// Welded positions entering the layer (mesh space).
    pub positions: &'a [Vec3],
    /// Welded topology of the mesh.
    pub topology: &'a Topology,
    /// Active (influenced) welded vertex indices, ascending and non-empty.
    pub active: &'a [u32],
}

/// A deformation tool: the bind / deform protocol described in the module documentation.
pub trait Deformer {
    /// Cached data computed by [`Deformer::bind`].
    type Bind: Send + Sync + std::fmt::Debug;

    /// Checks every parameter (finite, in its domain, not degenerate). `what` names the tool.
    fn validate(&self, what: &str) -> Result<()>;

    /// Computes the bind from the layer input. Called only on a validated tool.
    fn bind(&self, input: &BindInput<'_>) -> Result<Self::Bind>;

    /// Writes the deformed position of each vertex of `active` (a sub-slice of the bound
    /// active set) into `out` (same length). `positions` is the layer input the bind saw.
    fn deform(&self, bind: &Self::Bind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]);

    /// The same tool expressed in another space: `m` maps the tool's space to the target.
    #[must_use]
    fn transformed(&self, m: &Affine3A) -> Self;

    /// True when `other` has the same rest state, so that a bind made for `self` is valid for
    /// `other` too. The default compares nothing and always re-binds.
    fn same_rest_state(&self, _other: &Self) -> bool {
        false
    }
}

/// Every deformation tool Ductile has, as a stack layer's tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Tool {
    /// FFSD control points (Yoshizawa et al. 2002; Martínek & Kolingerová 2014).
    Ffsd(FfsdTool),
    /// Sketch-based bending and twisting (Kho & Garland 2005).
    Sketch(Box<SketchTool>),
    /// Axial deformation AxDf (Lazarus et al. 1994; Bechmann's survey §4.1).
    Axial(AxialTool),
    /// Curve deformation by De Casteljau / De Boor (Chang & Rockwood 1994; survey §4.2).
    Curve(CurveTool),
    /// Lattice FFD: Bernstein (Sederberg–Parry), B-spline and rational lattices.
    Lattice(LatticeTool),
    /// DOGME constraint points with B-spline extrusion functions.
    Dogme(DogmeTool),
    /// Direct FFD: point constraints solved on a lattice.
    DirectFfd(DirectFfdTool),
    /// Shape surface (Feng et al.): a B-spline surface and a height surface.
    ShapeSurface(ShapeSurfaceTool),
}

/// What a [`Tool`]'s bind computes from the tool alone ([`Tool::bind_setup`]): a curve's
/// pieces, a shape surface's knots, nets and basis pieces; the other kinds compute theirs in
/// each bind.
pub(crate) enum BindSetup {
    /// A curve's evaluator and rest pieces.
    Curve(Box<CurveSetup>),
    /// A shape surface's knots, rest net, search seeds and basis pieces.
    Surface(Box<SurfaceSetup>),
    /// Nothing made ahead.
    Nothing,
}

/// The bind of a [`Tool`].
#[derive(Debug)]
pub enum ToolBind {
    /// Bind of [`Tool::Ffsd`].
    Ffsd(FfsdBind),
    /// Bind of [`Tool::Sketch`].
    Sketch(Box<SketchBind>),
    /// Bind of [`Tool::Axial`].
    Axial(AxialBind),
    /// Bind of [`Tool::Curve`].
    Curve(CurveBind),
    /// Bind of [`Tool::Lattice`].
    Lattice(Box<PreparedLattice>),
    /// Bind of [`Tool::Dogme`].
    Dogme(DogmeBind),
    /// Bind of [`Tool::DirectFfd`].
    DirectFfd(Box<DirectFfdBind>),
    /// Bind of [`Tool::ShapeSurface`].
    ShapeSurface(Box<SurfaceBind>),
}

/// Binds that a thread made and no longer needs, one per kind whose bind holds per-vertex
/// arrays: [`Tool::bind_set_up`] makes the next bind of that kind in their buffers instead
/// of allocating and zeroing new ones. The blocks of a run of per-vertex layers
/// (`fused.rs`) keep them between blocks.
#[derive(Debug, Default)]
pub(crate) struct SpareBinds {
    curve: Option<CurveBind>,
    surface: Option<Box<SurfaceBind>>,
    axial: Option<AxialBind>,
}

impl SpareBinds {
    /// Keeps `bind`'s buffers for the next bind of its kind (a kind without per-vertex
    /// arrays is dropped).
    pub(crate) fn keep(&mut self, bind: ToolBind) {
        match bind {
            ToolBind::Curve(b) => self.curve = Some(b),
            ToolBind::ShapeSurface(b) => self.surface = Some(b),
            ToolBind::Axial(b) => self.axial = Some(b),
            _ => {}
        }
    }
}

impl Tool {
    /// A short name of the tool kind, for messages and UI.
    #[must_use]
    pub fn kind_name(&self) -> &'static str {
        match self {
            Tool::Ffsd(_) => "FFSD control points",
            Tool::Sketch(_) => "sketch deformation",
            Tool::Axial(_) => "axial deformation",
            Tool::Curve(_) => "curve deformation",
            Tool::Lattice(_) => "lattice FFD",
            Tool::Dogme(_) => "DOGME constraint points",
            Tool::DirectFfd(_) => "Direct FFD",
            Tool::ShapeSurface(_) => "shape surface",
        }
    }

    /// True when the tool is exactly the identity map whatever the mesh, bit for bit, so the
    /// stack may skip it (and need not bind it): an FFSD tool whose every effective γ is 0
    /// (a macro at value 0); a non-rational lattice with no moved control point
    /// (`x + Σ B·0`); a curve or an axis whose deformed state equals its rest state (their
    /// displacement forms give exactly 0 there); a shape surface with no move and every
    /// height 1 (its displacement form is exactly 0 too). A tool just added in the Studio is
    /// in one of these states, so adding it costs no evaluation. Other tools are never
    /// skipped (their identity would hold only up to rounding).
    #[must_use]
    pub fn is_identity(&self) -> bool {
        match self {
            Tool::Ffsd(t) => t.gain == 0.0 || t.points.iter().all(|p| p.gamma == 0.0),
            Tool::Lattice(t) => t
                .points
                .iter()
                .all(|e| e.offset == Vec3::ZERO && e.weight == 1.0),
            Tool::Curve(t) => t.rest == t.deformed,
            Tool::Axial(t) => t.rest == t.deformed,
            Tool::ShapeSurface(t) => {
                t.moves.iter().all(|e| e.offset == Vec3::ZERO)
                    && t.heights.iter().all(|h| h.height == 1.0)
            }
            Tool::Sketch(_) | Tool::Dogme(_) | Tool::DirectFfd(_) => false,
        }
    }

    /// See [`Deformer::validate`].
    pub fn validate(&self, what: &str) -> Result<()> {
        match self {
            Tool::Ffsd(t) => t.validate(what),
            Tool::Sketch(t) => t.validate(what),
            Tool::Axial(t) => t.validate(what),
            Tool::Curve(t) => t.validate(what),
            Tool::Lattice(t) => t.validate(what),
            Tool::Dogme(t) => t.validate(what),
            Tool::DirectFfd(t) => t.validate(what),
            Tool::ShapeSurface(t) => t.validate(what),
        }
    }

    /// See [`Deformer::bind`].
    pub fn bind(&self, input: &BindInput<'_>) -> Result<ToolBind> {
        Ok(match self {
            Tool::Ffsd(t) => ToolBind::Ffsd(t.bind(input)?),
            Tool::Sketch(t) => ToolBind::Sketch(Box::new(t.bind(input)?)),
            Tool::Axial(t) => ToolBind::Axial(t.bind(input)?),
            Tool::Curve(t) => ToolBind::Curve(t.bind(input)?),
            Tool::Lattice(t) => ToolBind::Lattice(Box::new(t.bind(input)?)),
            Tool::Dogme(t) => ToolBind::Dogme(t.bind(input)?),
            Tool::DirectFfd(t) => ToolBind::DirectFfd(Box::new(t.bind(input)?)),
            Tool::ShapeSurface(t) => ToolBind::ShapeSurface(Box::new(t.bind(input)?)),
        })
    }

    /// [`Tool::bind`], copying from `previous` (a bind of a tool with the same rest state)
    /// the per-vertex data of every vertex that is not stale, where the tool's per-vertex
    /// data depends on that vertex's input alone (curves, axes, shape surfaces; see
    /// [`Reuse`]). The same bits as [`Tool::bind`]; the other kinds bind in full.
    pub fn bind_reusing(
        &self,
        input: &BindInput<'_>,
        previous: Option<Reuse<'_, ToolBind>>,
    ) -> Result<ToolBind> {
        Ok(match (self, previous.map(|p| (p, p.bind))) {
            (Tool::Curve(t), Some((p, ToolBind::Curve(b)))) => {
                ToolBind::Curve(t.bind_reusing(input, Some(p.with(b)))?)
            }
            (Tool::Axial(t), Some((p, ToolBind::Axial(b)))) => {
                ToolBind::Axial(t.bind_reusing(input, Some(p.with(b)))?)
            }
            (Tool::ShapeSurface(t), Some((p, ToolBind::ShapeSurface(b)))) => {
                ToolBind::ShapeSurface(Box::new(t.bind_reusing(input, Some(p.with(b.as_ref())))?))
            }
            _ => self.bind(input)?,
        })
    }

    /// True when the tool's bind depends on the positions of no vertex (a lattice), or
    /// holds per active vertex data that depends on that vertex's input alone (curves,
    /// axes, shape surfaces): two binds of the same tool then agree on every vertex whose
    /// input is the same, and so does the deformation of such a vertex.
    #[must_use]
    pub fn binds_per_vertex(&self) -> bool {
        matches!(
            self,
            Tool::Lattice(_) | Tool::Curve(_) | Tool::Axial(_) | Tool::ShapeSurface(_)
        )
    }

    /// What the tool's bind computes from the tool alone, made once for the binds of many
    /// sets of vertices ([`Tool::bind_set_up`]).
    pub(crate) fn bind_setup(&self) -> Result<BindSetup> {
        Ok(match self {
            Tool::Curve(t) => BindSetup::Curve(Box::new(t.bind_setup()?)),
            Tool::ShapeSurface(t) => BindSetup::Surface(Box::new(t.bind_setup()?)),
            _ => BindSetup::Nothing,
        })
    }

    /// [`Tool::bind`] with `setup`, this tool's [`Tool::bind_setup`], made in the buffers of
    /// the bind of its kind that `spare` keeps, if any. The same bits.
    pub(crate) fn bind_set_up(
        &self,
        setup: &BindSetup,
        input: &BindInput<'_>,
        spare: &mut SpareBinds,
    ) -> Result<ToolBind> {
        match (self, setup) {
            (Tool::Curve(t), BindSetup::Curve(s)) => Ok(ToolBind::Curve(t.bind_set_up(
                s,
                input,
                None,
                spare.curve.take(),
            )?)),
            (Tool::ShapeSurface(t), BindSetup::Surface(s)) => {
                let old = spare.surface.take().map(|b| *b);
                Ok(ToolBind::ShapeSurface(Box::new(
                    t.bind_set_up(s, input, None, old)?,
                )))
            }
            (Tool::Axial(t), _) => Ok(ToolBind::Axial(t.bind_in(
                input,
                None,
                spare.axial.take(),
            )?)),
            _ => self.bind(input),
        }
    }

    /// True when the tool's bind reads neither the input positions nor the active vertices
    /// (a lattice; DOGME and Direct FFD when every anchor is a point, not a vertex): one
    /// bind, made on no vertex, deforms any vertex as a bind on it would.
    #[must_use]
    pub fn binds_without_vertices(&self) -> bool {
        let point = |a: &Anchor| matches!(a, Anchor::Point(_));
        match self {
            Tool::Lattice(_) => true,
            Tool::Dogme(t) => t.constraints.iter().all(|c| point(&c.at)),
            Tool::DirectFfd(t) => t.constraints.iter().all(|c| point(&c.at)),
            _ => false,
        }
    }

    /// [`Tool::deform`] with the active vertices' input positions already gathered
    /// (`inputs[j]` is `positions[active[j]]`): FFSD reads them in order, the other tools
    /// read `positions` as usual. Same bits as [`Tool::deform`].
    pub fn deform_gathered(
        &self,
        bind: &ToolBind,
        positions: &[Vec3],
        inputs: &[Vec3],
        active: &[u32],
        out: &mut [Vec3],
    ) {
        match (self, bind) {
            (Tool::Ffsd(t), ToolBind::Ffsd(b)) => t.deform_inputs(b, inputs, out),
            _ => self.deform(bind, positions, active, out),
        }
    }

    /// See [`Deformer::deform`]. A bind of another kind deforms nothing (`out` keeps the
    /// input positions); the stack never pairs them that way.
    pub fn deform(&self, bind: &ToolBind, positions: &[Vec3], active: &[u32], out: &mut [Vec3]) {
        match (self, bind) {
            (Tool::Ffsd(t), ToolBind::Ffsd(b)) => t.deform(b, positions, active, out),
            (Tool::Sketch(t), ToolBind::Sketch(b)) => t.deform(b, positions, active, out),
            (Tool::Axial(t), ToolBind::Axial(b)) => t.deform(b, positions, active, out),
            (Tool::Curve(t), ToolBind::Curve(b)) => t.deform(b, positions, active, out),
            (Tool::Lattice(t), ToolBind::Lattice(b)) => t.deform(b, positions, active, out),
            (Tool::Dogme(t), ToolBind::Dogme(b)) => t.deform(b, positions, active, out),
            (Tool::DirectFfd(t), ToolBind::DirectFfd(b)) => t.deform(b, positions, active, out),
            (Tool::ShapeSurface(t), ToolBind::ShapeSurface(b)) => {
                t.deform(b, positions, active, out)
            }
            #[allow(unreachable_patterns)]
            _ => {
                for (o, &i) in out.iter_mut().zip(active) {
                    *o = positions[i as usize];
                }
            }
        }
    }

    /// Evaluates a tool that works on the layer as a whole (a linear solve, a topology
    /// change) rather than vertex by vertex: the deformed position of every vertex of the
    /// active set the bind was made for (in its order) and, when `refine` is true, the
    /// tool's refinement.
    /// `None` for per-vertex tools, which the stack deforms in chunks with
    /// [`Tool::deform`].
    pub fn deform_whole(
        &self,
        bind: &ToolBind,
        positions: &[Vec3],
        refine: bool,
    ) -> Option<Result<WholeDeform>> {
        match (self, bind) {
            (Tool::Sketch(t), ToolBind::Sketch(b)) => Some(t.evaluate(b, positions, refine)),
            _ => None,
        }
    }

    /// True for the tools [`Tool::deform_whole`] evaluates as a whole (their output for a
    /// vertex may depend on other vertices); false for per-vertex tools.
    #[must_use]
    pub fn is_whole_layer(&self) -> bool {
        matches!(self, Tool::Sketch(_))
    }

    /// See [`Deformer::transformed`].
    #[must_use]
    pub fn transformed(&self, m: &Affine3A) -> Self {
        match self {
            Tool::Ffsd(t) => Tool::Ffsd(t.transformed(m)),
            Tool::Sketch(t) => Tool::Sketch(Box::new(t.transformed(m))),
            Tool::Axial(t) => Tool::Axial(t.transformed(m)),
            Tool::Curve(t) => Tool::Curve(t.transformed(m)),
            Tool::Lattice(t) => Tool::Lattice(t.transformed(m)),
            Tool::Dogme(t) => Tool::Dogme(t.transformed(m)),
            Tool::DirectFfd(t) => Tool::DirectFfd(t.transformed(m)),
            Tool::ShapeSurface(t) => Tool::ShapeSurface(t.transformed(m)),
        }
    }

    /// See [`Deformer::same_rest_state`].
    #[must_use]
    pub fn same_rest_state(&self, other: &Self) -> bool {
        match (self, other) {
            (Tool::Ffsd(a), Tool::Ffsd(b)) => a.same_rest_state(b),
            (Tool::Sketch(a), Tool::Sketch(b)) => a.same_rest_state(b),
            (Tool::Axial(a), Tool::Axial(b)) => a.same_rest_state(b),
            (Tool::Curve(a), Tool::Curve(b)) => a.same_rest_state(b),
            (Tool::Lattice(a), Tool::Lattice(b)) => a.same_rest_state(b),
            (Tool::Dogme(a), Tool::Dogme(b)) => a.same_rest_state(b),
            (Tool::DirectFfd(a), Tool::DirectFfd(b)) => a.same_rest_state(b),
            (Tool::ShapeSurface(a), Tool::ShapeSurface(b)) => a.same_rest_state(b),
            #[allow(unreachable_patterns)]
            _ => false,
        }
    }
}

/// The uniform scale factor of an affine map (cube root of `|det|`), used to carry lengths
/// such as radii into another space.
#[must_use]
pub fn uniform_scale(m: &Affine3A) -> f32 {
    m.matrix3.determinant().abs().cbrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axial::{AxialTool, AxisPoint, AxisShape};
    use crate::curve::{CurveBasis, CurveTool};
    use crate::lattice::{LatticeBasis, LatticeFrame, LatticeTool};
    use crate::mesh::RestMesh;
    use crate::surface::{ShapeSurfaceTool, SurfaceFrame};

    /// A bumpy sheet crossing the region of each tool of [`tools_at_rest`].
    fn sheet() -> RestMesh {
        let mesh = crate::primitives::grid(40, 40, false, |r, c| {
            let (x, y) = (r as f32 / 13.0 - 1.5, c as f32 / 11.0 - 1.8);
            Vec3::new(x, y, 0.3 * (x * 3.1).sin() * (y * 2.3).cos() + 0.05)
        });
        RestMesh::new(mesh, "sheet").unwrap()
    }

    /// Lattices, curves, axes and a shape surface around [`sheet`], at rest.
    fn tools_at_rest() -> Vec<Tool> {
        let axis = |n: usize| -> Vec<Vec3> {
            (0..n)
                .map(|i| Vec3::new(-1.2 + 2.4 * i as f32 / (n - 1) as f32, 0.1 * i as f32, 0.05))
                .collect()
        };
        let points: Vec<AxisPoint> = axis(5)
            .into_iter()
            .map(|position| AxisPoint {
                position,
                twist: 0.0,
                scale: 1.0,
            })
            .collect();
        let frame = LatticeFrame {
            origin: Vec3::new(-1.0, -1.0, -0.5),
            s: Vec3::new(2.0, 0.2, 0.0),
            t: Vec3::new(-0.1, 2.0, 0.0),
            u: Vec3::new(0.0, 0.0, 1.0),
        };
        let mut bspline = LatticeTool::bernstein(frame, (4, 5, 4));
        bspline.basis = LatticeBasis::BSpline { degree: (2, 2, 2) };
        bspline.falloff = 0.3;
        let mut axial_spline = AxialTool::new(points.clone(), 0.8);
        axial_spline.shape = AxisShape::BSpline { degree: 3 };
        let surface = ShapeSurfaceTool::planar(
            SurfaceFrame {
                origin: Vec3::new(-1.0, -1.0, 0.0),
                u_edge: Vec3::new(2.0, 0.0, 0.1),
                v_edge: Vec3::new(0.0, 2.0, 0.0),
            },
            (5, 4),
        );
        vec![
            Tool::Lattice(LatticeTool::bernstein(frame, (3, 3, 3))),
            Tool::Lattice(bspline),
            Tool::Curve(CurveTool {
                basis: CurveBasis::Bezier,
                rest: axis(5),
                deformed: axis(5),
            }),
            Tool::Curve(CurveTool {
                basis: CurveBasis::BSpline { degree: 3 },
                rest: axis(6),
                deformed: axis(6),
            }),
            Tool::Axial(AxialTool::new(points, 0.8)),
            Tool::Axial(axial_spline),
            Tool::ShapeSurface(surface),
        ]
    }

    /// The tools `is_identity` skips really are the identity, bit for bit, when bound and
    /// deformed anyway (a bumpy sheet crossing each tool's region).
    #[test]
    fn tools_at_rest_deform_nothing_bit_for_bit() {
        let rest = sheet();
        let positions = rest.welded_positions();
        let active: Vec<u32> = (0..positions.len() as u32).collect();
        let tools = tools_at_rest();
        for tool in tools {
            assert!(tool.is_identity(), "{}", tool.kind_name());
            tool.validate("t").unwrap();
            let bind = tool
                .bind(&BindInput {
                    positions,
                    topology: rest.topology(),
                    active: &active,
                })
                .unwrap();
            let mut out = vec![Vec3::ZERO; active.len()];
            tool.deform(&bind, positions, &active, &mut out);
            for (k, (o, p)) in out.iter().zip(positions).enumerate() {
                assert_eq!(
                    o.to_array().map(f32::to_bits),
                    p.to_array().map(f32::to_bits),
                    "{}: vertex {k}",
                    tool.kind_name()
                );
            }
        }
    }

    /// A bind made from an earlier one, on an input that moved at some vertices, deforms
    /// like a fresh bind, bit for bit (the moved vertices are bound again, the others
    /// copied, and the active set changed only at moved vertices); and it does copy: moved
    /// vertices wrongly left out of the stale set keep their earlier entries.
    #[test]
    fn binds_reusing_an_earlier_bind_match_a_fresh_one() {
        let rest = sheet();
        let before = rest.welded_positions().to_vec();
        let n = before.len() as u32;
        let moved = |v: u32| v.is_multiple_of(7);
        let after: Vec<Vec3> = (0..n)
            .map(|v| {
                before[v as usize]
                    + if moved(v) {
                        Vec3::new(0.03, -0.02, 0.05)
                    } else {
                        Vec3::ZERO
                    }
            })
            .collect();
        let stale: Vec<bool> = (0..n).map(moved).collect();
        let old_active: Vec<u32> = (0..n).filter(|v| v % 5 != 1).collect();
        let active: Vec<u32> = (0..n).filter(|&v| v % 5 != 1 || moved(v)).collect();
        let input = |positions, active| BindInput {
            positions,
            topology: rest.topology(),
            active,
        };
        let deform = |tool: &Tool, bind: &ToolBind, at: &[u32]| {
            let mut out = vec![Vec3::ZERO; at.len()];
            tool.deform(bind, &after, at, &mut out);
            out.iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        // The shape surface at rest is its frame's plane (one rest frame for every point);
        // a rest edit curves it (a rest frame per point).
        let curved = tools_at_rest().into_iter().find_map(|t| match t {
            Tool::ShapeSurface(mut t) => {
                t.rest.push(crate::surface::SurfaceEdit {
                    at: (2, 2),
                    offset: Vec3::new(0.05, 0.0, 0.3),
                });
                Some(Tool::ShapeSurface(t))
            }
            _ => None,
        });
        let tools = tools_at_rest().into_iter().chain(curved);
        for tool in tools.filter(Tool::binds_per_vertex) {
            let tool = match tool {
                Tool::Curve(mut t) => {
                    t.deformed[2] += Vec3::new(0.0, 0.2, 0.3);
                    Tool::Curve(t)
                }
                Tool::Axial(mut t) => {
                    t.deformed[2].position += Vec3::new(0.0, 0.2, 0.3);
                    t.deformed[3].twist = 0.5;
                    Tool::Axial(t)
                }
                Tool::ShapeSurface(mut t) => {
                    t.moves.push(crate::surface::SurfaceEdit {
                        at: (2, 1),
                        offset: Vec3::new(0.0, 0.1, 0.4),
                    });
                    Tool::ShapeSurface(t)
                }
                other => other,
            };
            let name = tool.kind_name();
            let old = tool.bind(&input(&before, &old_active)).unwrap();
            let fresh = tool.bind(&input(&after, &active)).unwrap();
            let reuse = |stale| Some(Reuse { bind: &old, stale });
            let reused = tool
                .bind_reusing(&input(&after, &active), reuse(&stale))
                .unwrap();
            assert_eq!(
                deform(&tool, &reused, &active),
                deform(&tool, &fresh, &active),
                "{name}"
            );
            if matches!(tool, Tool::Lattice(_)) {
                continue;
            }
            // Every moved vertex active in both, claimed unchanged.
            let lied: Vec<u32> = old_active.iter().copied().filter(|&v| moved(v)).collect();
            let lying = vec![false; n as usize];
            let copied = tool
                .bind_reusing(&input(&after, &active), reuse(&lying))
                .unwrap();
            let got = deform(&tool, &copied, &lied);
            assert_eq!(got, deform(&tool, &old, &lied), "{name}");
            assert_ne!(got, deform(&tool, &fresh, &lied), "{name}");
        }
    }

    #[test]
    fn tools_with_too_many_points_are_refused_not_left_to_run_for_minutes() {
        // Issue 14: 20,000 FFSD points bound in O(points²); a 100,000-point B-spline took
        // seconds to bind. Each kind refuses more than its documented limit.
        use crate::ffsd::{ControlPoint, FfsdTool, MAX_FFSD_POINTS};
        let n = MAX_FFSD_POINTS + 1;
        let points = (0..n)
            .map(|i| ControlPoint::basic(Vec3::new(i as f32, 0.0, 0.0), 0.1, 2.0, 0.5))
            .collect();
        let e = Tool::Ffsd(FfsdTool::new(points))
            .validate("tool 'many'")
            .unwrap_err();
        assert!(e.to_string().contains("number of control points"), "{e}");
        let polygon: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let curve = CurveTool::new(CurveBasis::BSpline { degree: 3 }, polygon.clone());
        let e = Tool::Curve(curve).validate("tool 'long'").unwrap_err();
        assert!(
            e.to_string().contains("number of B-spline control points"),
            "{e}"
        );
        let axis = AxialTool::new(polygon.into_iter().map(AxisPoint::at).collect(), 0.5);
        let e = Tool::Axial(axis).validate("tool 'long'").unwrap_err();
        assert!(e.to_string().contains("number of axis points"), "{e}");
    }
}
