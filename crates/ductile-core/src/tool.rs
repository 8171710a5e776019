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
use crate::curve::{CurveBind, CurveTool};
use crate::direct_ffd::{DirectFfdBind, DirectFfdTool};
use crate::dogme::{DogmeBind, DogmeTool};
use crate::error::Result;
use crate::ffsd::{FfsdBind, FfsdTool};
use crate::lattice::{LatticeTool, PreparedLattice};
use crate::mesh::Topology;
use crate::refinement::WholeDeform;
use crate::sketch::tool::{SketchBind, SketchTool};
use crate::surface::{ShapeSurfaceTool, SurfaceBind};

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

    /// True when the tool is exactly the identity map whatever the mesh (an FFSD tool whose
    /// every effective γ is 0, such as a macro at value 0), so the stack may skip it.
    #[must_use]
    pub fn is_identity(&self) -> bool {
        match self {
            Tool::Ffsd(t) => t.gain == 0.0 || t.points.iter().all(|p| p.gamma == 0.0),
            #[allow(unreachable_patterns)]
            _ => false,
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
