//! The error type of `ductile-core`.

use thiserror::Error;

/// Everything that can go wrong when building meshes, binding tools or evaluating a stack.
///
/// Every variant carries the place (`what`: a human-readable path such as
/// `"control point 2 of tool 'nose'"`) and the problem, so callers can show it as it is.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CoreError {
    /// A mesh has no vertices or no triangles.
    #[error("{what}: the mesh is empty ({vertices} vertices, {triangles} triangles)")]
    EmptyMesh {
        /// Which mesh.
        what: String,
        /// Vertex count found.
        vertices: usize,
        /// Triangle count found.
        triangles: usize,
    },
    /// The index buffer length is not a multiple of three.
    #[error("{what}: index count {count} is not a multiple of 3")]
    RaggedIndices {
        /// Which mesh.
        what: String,
        /// Index count found.
        count: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{what}: triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices"
    )]
    IndexOutOfRange {
        /// Which mesh.
        what: String,
        /// Triangle number (0-based).
        triangle: usize,
        /// The offending index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A per-vertex attribute has the wrong length.
    #[error("{what}: {attribute} has {found} entries but the mesh has {expected} vertices")]
    AttributeLength {
        /// Which mesh.
        what: String,
        /// Attribute name (`normals`, `uvs`).
        attribute: &'static str,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
    },
    /// A number is NaN or infinite.
    #[error("{what}: {value} is not a finite number")]
    NotFinite {
        /// Which parameter.
        what: String,
        /// The value, as printed.
        value: String,
    },
    /// A parameter is outside its domain.
    #[error("{what} = {value} is out of range: {expected}")]
    OutOfRange {
        /// Which parameter.
        what: String,
        /// The value found.
        value: f64,
        /// The allowed domain, in words (for example "must be > 0").
        expected: &'static str,
    },
    /// A tool or volume is geometrically degenerate (zero-volume frame, zero-size support, ...).
    #[error("{what}: {problem}")]
    Degenerate {
        /// Which tool or volume.
        what: String,
        /// What is degenerate.
        problem: String,
    },
    /// A vertex index given by the user (an area, a constraint) does not exist.
    #[error("{what}: vertex {index} does not exist (the mesh has {vertices} vertices)")]
    NoSuchVertex {
        /// Which area or constraint.
        what: String,
        /// The index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A sketch stroke has too few usable points (after filtering and merging short segments).
    #[error("{what}: the stroke has {found} usable points, at least {needed} are needed")]
    StrokeTooShort {
        /// Which stroke.
        what: String,
        /// Points left.
        found: usize,
        /// Points needed.
        needed: usize,
    },
    /// No point of a sketch stroke hits the mesh, so the stroke cannot be placed in 3-D.
    #[error("{what}: none of the {points} stroke points hits the mesh")]
    StrokeMissesMesh {
        /// Which stroke.
        what: String,
        /// Number of stroke points tried.
        points: usize,
    },
    /// A stroke point cannot be projected (its ray is parallel to the sketch plane or the
    /// plane is behind the eye).
    #[error("{what}: stroke point {index} cannot be projected onto the sketch plane: {problem}")]
    StrokeProjection {
        /// Which stroke.
        what: String,
        /// Stroke point index (0-based).
        index: usize,
        /// What went wrong.
        problem: String,
    },
    /// Twisting needs a front and a back hit for every node of the reference curve
    /// (Kho & Garland §5.2); the ray through this node hits the mesh only once (or never).
    #[error(
        "{what}: the ray through curve node {node} hits the mesh {hits} time(s); twisting needs a front and a back hit"
    )]
    SingleHit {
        /// Which curve.
        what: String,
        /// Curve node index (0-based).
        node: usize,
        /// Number of distinct hits found.
        hits: usize,
    },
    /// The region of interest of a sketch deformation could not be recognised.
    #[error("{what}: {problem}")]
    RegionOfInterest {
        /// Which curve or cutting plane.
        what: String,
        /// What went wrong.
        problem: String,
    },
    /// An interactive cut (Kho & Garland §4.2.1) failed.
    #[error("{what}: {problem}")]
    Cut {
        /// Which cut.
        what: String,
        /// What went wrong.
        problem: String,
    },
}

/// Shorthand for results in this crate.
pub type Result<T, E = CoreError> = std::result::Result<T, E>;

/// The largest magnitude of a tool parameter or a mesh coordinate, in scene units: ±10⁹
/// (a billion metres when the unit is the metre), far beyond any model, so that squared
/// distances (≤ 10¹⁸·3) and the products the deformers form stay finite in `f32`, whose
/// range ends at 3.4·10³⁸. Values beyond it are refused where they are read (issue 14: every
/// deformer maps finite input to finite output or refuses its parameters).
pub const MAX_MAGNITUDE: f32 = 1e9;

/// The smallest width a deformer accepts (FFSD's α and ε, in scene units): 10⁻⁶, a
/// micrometre when the unit is the metre. Narrower Gaussians overflow `f32` in
/// `1 / (2ε²)` and turn into NaN at their centre.
pub const MIN_WIDTH: f32 = 1e-6;

/// Returns an error naming `what` when `value` is NaN or infinite, or its magnitude exceeds
/// [`MAX_MAGNITUDE`].
pub fn check_finite(what: impl FnOnce() -> String, value: f32) -> Result<()> {
    if !value.is_finite() {
        Err(CoreError::NotFinite {
            what: what(),
            value: value.to_string(),
        })
    } else if value.abs() > MAX_MAGNITUDE {
        Err(beyond_range(what(), value.to_string()))
    } else {
        Ok(())
    }
}

fn beyond_range(what: String, value: String) -> CoreError {
    CoreError::Degenerate {
        what,
        problem: format!("{value} lies beyond ±1e9, the range Ductile computes in"),
    }
}

/// Returns an error naming `what` when any component of `v` is NaN or infinite, or its
/// magnitude exceeds [`MAX_MAGNITUDE`].
pub fn check_finite_vec3(what: impl FnOnce() -> String, v: glam::Vec3) -> Result<()> {
    if !v.is_finite() {
        Err(CoreError::NotFinite {
            what: what(),
            value: format!("{v}"),
        })
    } else if v.abs().max_element() > MAX_MAGNITUDE {
        Err(beyond_range(what(), format!("{v}")))
    } else {
        Ok(())
    }
}
