//! What the `ductile` binary's tests share.

use std::path::Path;

/// The path of `tests/data/NAME` of the workspace, as text for a command line.
pub fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name)
        .display()
        .to_string()
}
