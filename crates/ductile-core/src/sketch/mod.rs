//! Sketch-based mesh deformation after Kho & Garland, "Sketching Mesh Deformations"
//! (I3D 2005): strokes drawn in the image plane bend and twist a region of the mesh.

pub mod bend;
pub mod camera;
pub mod cut;
pub mod partition;
pub mod raycast;
pub mod refine;
pub mod roi;
pub mod skin;
pub mod smooth;
pub mod stroke;
pub mod tool;
pub mod twist;
