//! glTF 2.0 export: binary `.glb`, or `.gltf` JSON with the buffer embedded as base64.
//!
//! Each exported mesh becomes one glTF mesh (one triangle primitive) and one root node of the
//! same name, in the order given. A primitive has `POSITION` (float VEC3 with the `min`/`max`
//! bounds the specification requires), `NORMAL` (float VEC3) when given, `TEXCOORD_0` (float
//! VEC2) when given, and `u32` indices. All data lives in one buffer, one buffer view per
//! attribute. The file is written atomically.

use std::borrow::Cow;
use std::path::Path;

use base64::Engine as _;
use ductile_core::mesh::{Deformed, Mesh, RestMesh};
use glam::{Vec2, Vec3};
use gltf::json;
use gltf::json::validation::{Checked, USize64};

use crate::error::{IoError, Result};
use crate::mesh::extension;
use crate::write_atomic;

/// One mesh to export, borrowing its data.
#[derive(Debug, Clone)]
pub struct ExportMesh<'a> {
    /// Name of the glTF mesh and node.
    pub name: &'a str,
    /// Positions.
    pub positions: &'a [Vec3],
    /// Normals (same length as positions), if any.
    pub normals: Option<&'a [Vec3]>,
    /// Texture coordinates (same length as positions), if any.
    pub uvs: Option<&'a [Vec2]>,
    /// Triangle indices, three per triangle (owned when a layer refined the mesh).
    pub indices: Cow<'a, [u32]>,
}

impl<'a> ExportMesh<'a> {
    /// A stored mesh as it is.
    #[must_use]
    pub fn from_mesh(name: &'a str, mesh: &'a Mesh) -> Self {
        Self {
            name,
            positions: &mesh.positions,
            normals: mesh.normals.as_deref(),
            uvs: mesh.uvs.as_deref(),
            indices: Cow::Borrowed(&mesh.indices),
        }
    }

    /// A deformed mesh: deformed positions and recomputed normals with the rest mesh's UVs
    /// and indices, or the refined ones when a layer refined the mesh.
    #[must_use]
    pub fn deformed(name: &'a str, rest: &'a RestMesh, deformed: &'a Deformed) -> Self {
        Self {
            name,
            positions: &deformed.positions,
            normals: Some(&deformed.normals),
            uvs: deformed.uvs(rest),
            indices: match &deformed.refined {
                Some(refined) => Cow::Owned(refined.indices()),
                None => Cow::Borrowed(&rest.mesh().indices),
            },
        }
    }
}

/// Builds the glTF document and its single binary buffer.
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
}

impl Builder {
    fn view(
        &mut self,
        bytes: &[u8],
        target: json::buffer::Target,
    ) -> json::Index<json::buffer::View> {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        // Every element is 4-byte aligned already (f32 or u32); keep it so if that changes.
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Checked::Valid(target)),
            extensions: None,
            extras: Default::default(),
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        kind: json::accessor::Type,
        target: json::buffer::Target,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(json::Value::from(lo)), Some(json::Value::from(hi))),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Checked::Valid(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }
}

fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

fn check(path: &Path, m: &ExportMesh<'_>) -> Result<()> {
    let err = |problem: String| IoError::Export {
        path: path.to_owned(),
        mesh: m.name.to_owned(),
        problem,
    };
    let n = m.positions.len();
    if n == 0 || m.indices.is_empty() {
        return Err(err("the mesh is empty".to_owned()));
    }
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Err(err(format!("position of vertex {i} is not finite")));
    }
    if m.normals.is_some_and(|v| v.len() != n) || m.uvs.is_some_and(|v| v.len() != n) {
        return Err(err(
            "normals or UVs do not match the vertex count".to_owned()
        ));
    }
    if !m.indices.len().is_multiple_of(3) {
        return Err(err("index count is not a multiple of 3".to_owned()));
    }
    if let Some(i) = m.indices.iter().find(|&&i| i as usize >= n) {
        return Err(err(format!("index {i} is out of range ({n} vertices)")));
    }
    Ok(())
}

/// Builds the glTF JSON document and the binary buffer for `meshes`.
fn build(path: &Path, meshes: &[ExportMesh<'_>]) -> Result<(json::Root, Vec<u8>)> {
    use json::accessor::{ComponentType, Type};
    use json::buffer::Target;
    let mut b = Builder {
        root: json::Root {
            asset: json::Asset {
                generator: Some(format!("ductile-io {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        },
        bin: Vec::new(),
    };
    let mut nodes = Vec::with_capacity(meshes.len());
    for m in meshes {
        check(path, m)?;
        let (lo, hi) = ductile_core::mesh::bounds(m.positions).unwrap_or_default();
        let pos = b.accessor(
            &f32_bytes(m.positions.iter().flat_map(|p| p.to_array())),
            m.positions.len(),
            ComponentType::F32,
            Type::Vec3,
            Target::ArrayBuffer,
            Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
        );
        let mut attributes = std::collections::BTreeMap::new();
        attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
        if let Some(normals) = m.normals {
            // A zero normal (isolated vertex) is not a unit vector; the spec wants unit
            // normals, so such vertices get +Z.
            let unit = normals
                .iter()
                .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
                .flat_map(|n| n.to_array());
            let acc = b.accessor(
                &f32_bytes(unit),
                normals.len(),
                ComponentType::F32,
                Type::Vec3,
                Target::ArrayBuffer,
                None,
            );
            attributes.insert(Checked::Valid(json::mesh::Semantic::Normals), acc);
        }
        if let Some(uvs) = m.uvs {
            let acc = b.accessor(
                &f32_bytes(uvs.iter().flat_map(|t| t.to_array())),
                uvs.len(),
                ComponentType::F32,
                Type::Vec2,
                Target::ArrayBuffer,
                None,
            );
            attributes.insert(Checked::Valid(json::mesh::Semantic::TexCoords(0)), acc);
        }
        let indices = b.accessor(
            &m.indices
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect::<Vec<_>>(),
            m.indices.len(),
            ComponentType::U32,
            Type::Scalar,
            Target::ElementArrayBuffer,
            None,
        );
        let mesh = b.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(m.name.to_owned()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: None,
                mode: Checked::Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        nodes.push(b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(m.name.to_owned()),
            ..Default::default()
        }));
    }
    // glTF wants a scene's node list non-empty: a file without meshes has no scene.
    if !nodes.is_empty() {
        let scene = b.root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes,
        });
        b.root.scene = Some(scene);
    }
    Ok((b.root, b.bin))
}

/// Writes `meshes` to `path` as glTF 2.0: binary when the extension is `.glb`, JSON with an
/// embedded base64 buffer when it is `.gltf`. Atomic: on error nothing is left at `path`
/// (an existing file stays untouched).
pub fn export_gltf(path: impl AsRef<Path>, meshes: &[ExportMesh<'_>]) -> Result<()> {
    let path = path.as_ref();
    let binary = match extension(path).as_str() {
        "glb" => true,
        "gltf" => false,
        other => {
            return Err(IoError::UnsupportedExtension {
                path: path.to_owned(),
                extension: other.to_owned(),
                expected: ".glb or .gltf",
            });
        }
    };
    let (mut root, bin) = build(path, meshes)?;
    let json_err = |e: json::Error| IoError::Write {
        path: path.to_owned(),
        source: std::io::Error::other(e),
    };
    // A scene without meshes has no data: glTF forbids an empty buffer, so there is none.
    let has_data = !bin.is_empty();
    let bytes = if binary {
        if has_data {
            root.buffers.push(json::Buffer {
                byte_length: USize64::from(bin.len()),
                name: None,
                uri: None,
                extensions: None,
                extras: Default::default(),
            });
        }
        let json_bytes = json::serialize::to_vec(&root).map_err(json_err)?;
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                // Recomputed by `to_vec`.
                length: 0,
            },
            json: json_bytes.into(),
            bin: has_data.then(|| bin.into()),
        };
        glb.to_vec().map_err(|e| IoError::Write {
            path: path.to_owned(),
            source: std::io::Error::other(e),
        })?
    } else {
        if has_data {
            let uri = format!(
                "data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&bin)
            );
            root.buffers.push(json::Buffer {
                byte_length: USize64::from(bin.len()),
                name: None,
                uri: Some(uri),
                extensions: None,
                extras: Default::default(),
            });
        }
        json::serialize::to_vec_pretty(&root).map_err(json_err)?
    };
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_scene_exports_a_valid_file_without_buffer() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["e.glb", "e.gltf"] {
            let p = dir.path().join(name);
            export_gltf(&p, &[]).unwrap();
            let g = gltf::Gltf::from_slice(&std::fs::read(&p).unwrap()).unwrap();
            assert_eq!(g.buffers().count(), 0);
            assert_eq!(g.meshes().count(), 0);
        }
    }

    #[test]
    fn bounds_and_zero_normals_follow_the_spec() {
        let mesh = Mesh {
            positions: vec![
                Vec3::new(-1.0, 2.0, 0.5),
                Vec3::X,
                Vec3::new(0.0, 3.0, -2.0),
            ],
            normals: Some(vec![Vec3::ZERO, Vec3::Y * 2.0, Vec3::Z]),
            uvs: None,
            indices: vec![0, 1, 2],
        };
        let (root, bin) = build(Path::new("x.glb"), &[ExportMesh::from_mesh("m", &mesh)]).unwrap();
        let pos = &root.accessors[0];
        assert_eq!(pos.min, Some(json::Value::from(vec![-1.0f32, 0.0, -2.0])));
        assert_eq!(pos.max, Some(json::Value::from(vec![1.0f32, 3.0, 0.5])));
        // Normals are the second view: unit length, +Z for a zero normal.
        let off = 36;
        let n: Vec<f32> = bin[off..off + 36]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(n, vec![0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    }
}
