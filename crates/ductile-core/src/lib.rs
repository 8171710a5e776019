//! `ductile-core`: meshes, influence, deformation tools and the non-destructive deformation
//! stack of Ductile.
//!
//! The crate is pure computation: no engine, no UI, no file I/O (see
//! `docs/ARCHITECTURE.md`). A [`RestMesh`](mesh::RestMesh) holds a validated mesh and its
//! welded topology; a [`Stack`](stack::Stack) of [`Layer`](stack::Layer)s, each with a
//! [`Tool`](tool::Tool) and an optional [`Influence`](influence::Influence), maps it to
//! [`Deformed`](mesh::Deformed) positions and normals.

#![warn(clippy::unwrap_used, clippy::expect_used)]

pub mod axial;
mod axial_lanes;
pub mod basis;
pub mod chunks;
pub mod curve;
mod curve_lanes;
pub mod curve_pieces;
pub mod direct_ffd;
pub mod dogme;
pub mod error;
pub mod ffsd;
pub mod frames;
mod fused;
pub mod influence;
mod lane;
pub mod lattice;
pub mod mesh;
pub mod normals;
mod polyline_lanes;
pub mod primitives;
pub mod refinement;
mod registers;
pub mod sketch;
pub mod slerp;
pub mod spline;
pub mod stack;
pub mod surface;
mod surface_lanes;
pub mod tool;
mod volume_lanes;

/// The types most users need.
pub mod prelude {
    pub use crate::axial::{AxialTool, AxisPoint, AxisShape};
    pub use crate::curve::{CurveBasis, CurveTool};
    pub use crate::error::{CoreError, Result};
    pub use crate::ffsd::{ControlPoint, FfsdMacro, FfsdTool, HeightLimit, PointMode};
    pub use crate::influence::{Falloff, Influence, Mask, Shape, Volume};
    pub use crate::mesh::{Deformed, Mesh, RestMesh, Topology};
    pub use crate::stack::{Layer, LayerBinding, Stack};
    pub use crate::tool::{BindInput, Deformer, Tool, ToolBind};
}
