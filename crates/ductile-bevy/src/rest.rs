//! Rest meshes, keyed by the mesh source they were loaded from.
//!
//! File I/O stays out of this crate: the application (the Studio, a test) loads each mesh
//! node's source with `ductile-io` and inserts it here; [`RestMeshes::missing`] says which
//! sources the document needs that are neither loaded nor failed.

use std::collections::BTreeMap;
use std::sync::Arc;

use bevy::prelude::*;
use ductile_core::mesh::RestMesh;
use ductile_scene::document::{Document, NodeKind};

/// The loaded rest meshes, by mesh source, and the sources that could not be loaded.
#[derive(Resource, Debug, Default, Clone)]
pub struct RestMeshes {
    loaded: BTreeMap<String, Arc<RestMesh>>,
    failed: BTreeMap<String, String>,
}

impl RestMeshes {
    /// Adds (or replaces) the rest mesh of `source`.
    pub fn insert(&mut self, source: impl Into<String>, rest: RestMesh) {
        let source = source.into();
        self.failed.remove(&source);
        self.loaded.insert(source, Arc::new(rest));
    }

    /// Records that `source` could not be loaded, and why (shown to the user; the source is
    /// not tried again until [`RestMeshes::clear`]).
    pub fn insert_failure(&mut self, source: impl Into<String>, error: impl Into<String>) {
        let source = source.into();
        self.loaded.remove(&source);
        self.failed.insert(source, error.into());
    }

    /// The rest mesh of `source`, if loaded.
    #[must_use]
    pub fn get(&self, source: &str) -> Option<&Arc<RestMesh>> {
        self.loaded.get(source)
    }

    /// Why `source` could not be loaded, if it failed.
    #[must_use]
    pub fn failure(&self, source: &str) -> Option<&str> {
        self.failed.get(source).map(String::as_str)
    }

    /// Every failed source with its error.
    pub fn failures(&self) -> impl Iterator<Item = (&str, &str)> {
        self.failed.iter().map(|(s, e)| (s.as_str(), e.as_str()))
    }

    /// Forgets every mesh (a new document was opened).
    pub fn clear(&mut self) {
        self.loaded.clear();
        self.failed.clear();
    }

    /// The sources of `doc`'s mesh nodes that are neither loaded nor failed, in document
    /// order, without repeats.
    #[must_use]
    pub fn missing(&self, doc: &Document) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for node in &doc.nodes {
            if let NodeKind::Mesh(m) = &node.kind
                && !self.loaded.contains_key(&m.source)
                && !self.failed.contains_key(&m.source)
                && !out.contains(&m.source)
            {
                out.push(m.source.clone());
            }
        }
        out
    }
}
