//! The default Studio scene, embedded in the program: the identikit head
//! (`scenes/identikit-head.ron`) and its mesh (`assets/meshes/lee-perry-smith-head.glb`),
//! so that the Studio opens it from any working directory ([`crate::Project::embedded_default`]).

/// The text of `scenes/identikit-head.ron`, as shipped.
pub const IDENTIKIT_HEAD_SCENE: &str = include_str!("../../../scenes/identikit-head.ron");

/// The file name the embedded scene is known by (in errors, and as the default name when it
/// is saved).
pub const IDENTIKIT_HEAD_NAME: &str = "identikit-head.ron";

/// The mesh source the embedded scene's `head` node names, exactly as written in the scene
/// (relative to `scenes/`).
pub const HEAD_SOURCE: &str = "../assets/meshes/lee-perry-smith-head.glb";

/// The bytes of `assets/meshes/lee-perry-smith-head.glb` (binary glTF; the Lee Perry-Smith
/// head scan, CC BY 3.0, see `assets/LICENSES.md`).
pub const HEAD_GLB: &[u8] = include_bytes!("../../../assets/meshes/lee-perry-smith-head.glb");
