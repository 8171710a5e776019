//! The error type of `ductile-scene`.

use ductile_anim::error::AnimError;
use ductile_core::error::CoreError;
use thiserror::Error;

/// A problem with a scene document. Each variant names the node, layer or area concerned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SceneError {
    /// Two nodes share a name (names identify nodes).
    #[error("node name '{name}' is used more than once")]
    DuplicateName {
        /// The name.
        name: String,
    },
    /// A node name is empty.
    #[error("node {index} has an empty name")]
    EmptyName {
        /// Position of the node in the document.
        index: usize,
    },
    /// No node has this name.
    #[error("there is no node named '{name}'")]
    NoSuchNode {
        /// The name looked up.
        name: String,
    },
    /// A node's parent does not exist.
    #[error("node '{node}' has parent '{parent}', which does not exist")]
    UnknownParent {
        /// The child.
        node: String,
        /// The missing parent.
        parent: String,
    },
    /// Following parents from a node comes back to it.
    #[error("node '{node}' is its own ancestor (cycle in the scene graph)")]
    Cycle {
        /// A node on the cycle.
        node: String,
    },
    /// A node is not of the kind an operation or reference needs.
    #[error("node '{node}' is a {found}, not a {expected}")]
    WrongKind {
        /// The node.
        node: String,
        /// Its kind.
        found: &'static str,
        /// The kind needed.
        expected: &'static str,
    },
    /// A layer names a tool that does not exist.
    #[error("mesh '{mesh}', layer {layer}: tool '{tool}' does not exist")]
    UnknownTool {
        /// The mesh.
        mesh: String,
        /// Layer index (0 = bottom).
        layer: usize,
        /// The missing tool name.
        tool: String,
    },
    /// A layer's influence names a volume that does not exist.
    #[error("mesh '{mesh}', layer {layer}: influence volume '{volume}' does not exist")]
    UnknownVolume {
        /// The mesh.
        mesh: String,
        /// Layer index.
        layer: usize,
        /// The missing volume name.
        volume: String,
    },
    /// A layer's influence or a macro names an area the mesh does not have.
    #[error("mesh '{mesh}', layer {layer}: area '{area}' is not defined on this mesh")]
    UnknownArea {
        /// The mesh.
        mesh: String,
        /// Layer index.
        layer: usize,
        /// The missing area.
        area: String,
    },
    /// A macro's own area (the area a new layer of it works in) is not an area of the mesh
    /// that uses it (or of any mesh, when no macro tool uses it yet).
    #[error("macro '{name}': its area '{area}' is not defined on {meshes}")]
    UnknownMacroArea {
        /// The macro.
        name: String,
        /// The missing area.
        area: String,
        /// Where it was looked for, as words ("mesh 'head'", "any mesh").
        meshes: String,
    },
    /// A macro node names a macro that is not in the document's library.
    #[error("macro node '{node}': there is no macro named '{name}'")]
    UnknownMacro {
        /// The node.
        node: String,
        /// The missing macro.
        name: String,
    },
    /// A transform cannot be inverted ([`crate::transform::Transform::degeneracy`]).
    #[error("{what}: the transform cannot be inverted: {problem}")]
    DegenerateTransform {
        /// Whose transform.
        what: String,
        /// What is wrong.
        problem: &'static str,
    },
    /// A node name that cannot be shown or typed: only spaces, or a control character.
    #[error("node {index} has the name {name:?}, which {problem}")]
    BadName {
        /// Position of the node in the document.
        index: usize,
        /// The name (printed with escapes).
        name: String,
        /// What is wrong.
        problem: &'static str,
    },
    /// A number is NaN or infinite.
    #[error("{what}: {value} is not a finite number")]
    NotFinite {
        /// Which value.
        what: String,
        /// The value as printed.
        value: String,
    },
    /// An index (layer, area vertex, position) is out of range.
    #[error("{what}: index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What was indexed.
        what: String,
        /// The index.
        index: usize,
        /// The length.
        len: usize,
    },
    /// A parameter is invalid according to `ductile-core`.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A node's animatable parameter cannot be read or written (no such parameter, a
    /// value of the wrong kind).
    #[error("node '{node}': {source}")]
    Channel {
        /// The node.
        node: String,
        /// What is wrong.
        source: AnimError,
    },
    /// A keyframe track is invalid.
    #[error("animation track '{node}' / '{param}': {problem}")]
    Track {
        /// The node the track animates.
        node: String,
        /// The parameter's path.
        param: String,
        /// What is wrong.
        problem: String,
    },
    /// The timeline (frame rate, frame range) is invalid, or a frame is outside it.
    #[error("timeline: {problem}")]
    Timeline {
        /// What is wrong.
        problem: String,
    },
    /// No variant has this name.
    #[error("there is no variant named '{name}'{}", known_variants(.known))]
    UnknownVariant {
        /// The name looked up.
        name: String,
        /// The variants there are.
        known: Vec<String>,
    },
    /// A variant is invalid, or variants cannot be blended.
    #[error("variant '{variant}': {problem}")]
    Variant {
        /// The variant (or the blended variants, joined by '+').
        variant: String,
        /// What is wrong, naming the node.
        problem: String,
    },
    /// Blending or random-variant settings are invalid.
    #[error("{0}")]
    Blend(#[from] AnimError),
    /// A node has no handle with this id (see `handles::handles`).
    #[error("node '{node}' has no handle {handle}")]
    NoSuchHandle {
        /// The node.
        node: String,
        /// The handle id as printed.
        handle: String,
    },
}

fn known_variants(known: &[String]) -> String {
    if known.is_empty() {
        " (the scene has no variants)".to_owned()
    } else {
        format!(" (variants: {})", known.join(", "))
    }
}

/// Shorthand for results in this crate.
pub type Result<T, E = SceneError> = std::result::Result<T, E>;
