//! glTF 2.0 export: binary `.glb`, or `.gltf` JSON with the buffer embedded as base64.
//!
//! Each exported mesh becomes one glTF mesh (one triangle primitive) and one root node of the
//! same name, in the order given. A primitive has `POSITION` (float VEC3 with the `min`/`max`
//! bounds the specification requires), `NORMAL` (float VEC3) when given, `TEXCOORD_0` (float
//! VEC2) when given, and `u32` indices. All data lives in one buffer, one buffer view per
//! attribute. The file is written atomically.
//!
//! [`export_gltf_with`] adds morph targets ([`Morphs`]: position and normal deltas, sparse
//! where that is smaller, names in `mesh.extras.targetNames`, default weights in
//! `mesh.weights`) and animations of the targets' weights ([`WeightsAnimation`]). Views of
//! animation and sparse data carry no buffer-view target, as the specification requires.

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

/// One morph target of an exported mesh: per-vertex deltas from the base mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct MorphTarget {
    /// The target's name (written to `mesh.extras.targetNames`).
    pub name: String,
    /// Position deltas, one per vertex of the base mesh.
    pub positions: Vec<Vec3>,
    /// Normal deltas (same count), if any.
    pub normals: Option<Vec<Vec3>>,
}

/// How a weights animation goes between its keys (glTF's sampler interpolation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// Hold each key's weights.
    Step,
    /// Linear crossfade between keys.
    Linear,
}

/// One animated mesh of a [`WeightsAnimation`].
#[derive(Debug, Clone, PartialEq)]
pub struct WeightsTrack {
    /// Index of the mesh in the exported list (its node is animated).
    pub mesh: usize,
    /// Key times in seconds, strictly increasing, ≥ 0.
    pub times: Vec<f32>,
    /// The mesh's target weights at each key, back to back (`times.len() × targets`).
    pub weights: Vec<f32>,
    /// Interpolation between keys.
    pub sampling: Sampling,
}

/// A glTF animation of morph-target weights.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightsAnimation {
    /// The animation's name.
    pub name: String,
    /// One track per animated mesh.
    pub tracks: Vec<WeightsTrack>,
}

/// Morph targets and weight animations exported with the meshes ([`export_gltf_with`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Morphs {
    /// Per exported mesh (in order; missing entries have none), its morph targets.
    pub targets: Vec<Vec<MorphTarget>>,
    /// Per exported mesh, the default weights (`mesh.weights`; zeros when missing).
    pub weights: Vec<Vec<f32>>,
    /// Animations of the weights.
    pub animations: Vec<WeightsAnimation>,
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
        target: impl Into<Option<json::buffer::Target>>,
    ) -> json::Index<json::buffer::View> {
        let target = target.into();
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
            target: target.map(Checked::Valid),
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
        target: impl Into<Option<json::buffer::Target>>,
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

impl Builder {
    /// A float VEC3 accessor of deltas: dense, or sparse over zeros (indices of the non-zero
    /// deltas, strictly increasing) when that takes fewer bytes. `bounds` adds `min`/`max`
    /// (required for position targets).
    fn deltas(&mut self, deltas: &[Vec3], bounds: bool) -> json::Index<json::Accessor> {
        use json::accessor::{ComponentType, Type};
        let n = deltas.len();
        let moved: Vec<u32> = (0..n as u32)
            .filter(|&i| deltas[i as usize] != Vec3::ZERO)
            .collect();
        let wide = n > usize::from(u16::MAX);
        let index_size = if wide { 4 } else { 2 };
        let bounds = bounds.then(|| {
            let (lo, hi) = ductile_core::mesh::bounds(deltas).unwrap_or_default();
            (lo.to_array().to_vec(), hi.to_array().to_vec())
        });
        if moved.len() * (index_size + 12) >= n * 12 {
            return self.accessor(
                &f32_bytes(deltas.iter().flat_map(|d| d.to_array())),
                n,
                ComponentType::F32,
                Type::Vec3,
                json::buffer::Target::ArrayBuffer,
                bounds,
            );
        }
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(json::Value::from(lo)), Some(json::Value::from(hi))),
            None => (None, None),
        };
        let sparse = if moved.is_empty() {
            None
        } else {
            let index_bytes: Vec<u8> = if wide {
                moved.iter().flat_map(|i| i.to_le_bytes()).collect()
            } else {
                moved
                    .iter()
                    .flat_map(|&i| (i as u16).to_le_bytes())
                    .collect()
            };
            let indices = self.view(&index_bytes, None);
            let values = self.view(
                &f32_bytes(moved.iter().flat_map(|&i| deltas[i as usize].to_array())),
                None,
            );
            Some(json::accessor::sparse::Sparse {
                count: USize64::from(moved.len()),
                indices: json::accessor::sparse::Indices {
                    buffer_view: indices,
                    byte_offset: USize64(0),
                    component_type: Checked::Valid(json::accessor::IndexComponentType(if wide {
                        ComponentType::U32
                    } else {
                        ComponentType::U16
                    })),
                    extensions: None,
                    extras: Default::default(),
                },
                values: json::accessor::sparse::Values {
                    buffer_view: values,
                    byte_offset: USize64(0),
                    extensions: None,
                    extras: Default::default(),
                },
                extensions: None,
                extras: Default::default(),
            })
        };
        self.root.push(json::Accessor {
            buffer_view: None,
            byte_offset: None,
            count: USize64::from(n),
            component_type: Checked::Valid(json::accessor::GenericComponentType(
                ComponentType::F32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Checked::Valid(Type::Vec3),
            min,
            max,
            name: None,
            normalized: false,
            sparse,
        })
    }

    /// A float SCALAR accessor for animation data (no buffer-view target); `bounds` adds
    /// `min`/`max` (required for sampler inputs).
    fn scalars(&mut self, values: &[f32], bounds: bool) -> json::Index<json::Accessor> {
        use json::accessor::{ComponentType, Type};
        let bounds = bounds.then(|| {
            let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (vec![lo], vec![hi])
        });
        self.accessor(
            &f32_bytes(values.iter().copied()),
            values.len(),
            ComponentType::F32,
            Type::Scalar,
            None,
            bounds,
        )
    }
}

/// The JSON `{"targetNames": [...]}` for a mesh's extras.
fn target_names(targets: &[MorphTarget]) -> Result<Option<Box<json::extras::RawValue>>> {
    let names: Vec<json::Value> = targets
        .iter()
        .map(|t| json::Value::from(t.name.clone()))
        .collect();
    let text = format!("{{\"targetNames\":{}}}", json::Value::Array(names));
    json::extras::RawValue::from_string(text)
        .map(Some)
        .map_err(|e| IoError::Write {
            path: "extras".into(),
            source: std::io::Error::other(e),
        })
}

fn check_morphs(path: &Path, meshes: &[ExportMesh<'_>], morphs: &Morphs) -> Result<()> {
    let err = |mesh: &str, problem: String| IoError::Export {
        path: path.to_owned(),
        mesh: mesh.to_owned(),
        problem,
    };
    for (i, targets) in morphs.targets.iter().enumerate() {
        let Some(m) = meshes.get(i) else {
            return Err(err(
                "?",
                format!("morph targets for mesh {i}, which is not exported"),
            ));
        };
        let n = m.positions.len();
        for t in targets {
            let bad = t.positions.len() != n
                || t.normals.as_ref().is_some_and(|v| v.len() != n)
                || t.positions.iter().any(|p| !p.is_finite())
                || t.normals.iter().flatten().any(|p| !p.is_finite());
            if bad {
                return Err(err(
                    m.name,
                    format!(
                        "morph target '{}' does not match the mesh or is not finite",
                        t.name
                    ),
                ));
            }
        }
        if let Some(w) = morphs.weights.get(i)
            && w.len() != targets.len()
        {
            return Err(err(
                m.name,
                format!("{} default weights for {} targets", w.len(), targets.len()),
            ));
        }
    }
    for a in &morphs.animations {
        for t in &a.tracks {
            let name = meshes.get(t.mesh).map_or("?", |m| m.name);
            let count = morphs.targets.get(t.mesh).map_or(0, Vec::len);
            let increasing = t.times.windows(2).all(|w| w[0] < w[1]);
            if count == 0
                || t.times.is_empty()
                || !increasing
                || t.times.iter().any(|x| !(x.is_finite() && *x >= 0.0))
                || t.weights.len() != t.times.len() * count
                || t.weights.iter().any(|w| !w.is_finite())
            {
                return Err(err(
                    name,
                    format!(
                        "animation '{}': times must be finite, ≥ 0 and strictly increasing, with {count} weights per time",
                        a.name
                    ),
                ));
            }
        }
    }
    Ok(())
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
fn build(path: &Path, meshes: &[ExportMesh<'_>], morphs: &Morphs) -> Result<(json::Root, Vec<u8>)> {
    check_morphs(path, meshes, morphs)?;
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
    for (i, m) in meshes.iter().enumerate() {
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
        let targets = morphs.targets.get(i).filter(|t| !t.is_empty());
        let (json_targets, extras, weights) = match targets {
            None => (None, Default::default(), None),
            Some(targets) => {
                let json_targets = targets
                    .iter()
                    .map(|t| json::mesh::MorphTarget {
                        positions: Some(b.deltas(&t.positions, true)),
                        normals: t.normals.as_ref().map(|n| b.deltas(n, false)),
                        tangents: None,
                    })
                    .collect();
                let weights = morphs
                    .weights
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| vec![0.0; targets.len()]);
                (Some(json_targets), target_names(targets)?, Some(weights))
            }
        };
        let mesh = b.root.push(json::Mesh {
            extensions: None,
            extras,
            name: Some(m.name.to_owned()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: None,
                mode: Checked::Valid(json::mesh::Mode::Triangles),
                targets: json_targets,
            }],
            weights,
        });
        nodes.push(b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(m.name.to_owned()),
            ..Default::default()
        }));
    }
    for a in &morphs.animations {
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for t in &a.tracks {
            let input = b.scalars(&t.times, true);
            let output = b.scalars(&t.weights, false);
            channels.push(json::animation::Channel {
                sampler: json::Index::new(samplers.len() as u32),
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node: nodes[t.mesh],
                    path: Checked::Valid(json::animation::Property::MorphTargetWeights),
                },
                extensions: None,
                extras: Default::default(),
            });
            samplers.push(json::animation::Sampler {
                extensions: None,
                extras: Default::default(),
                input,
                interpolation: Checked::Valid(match t.sampling {
                    Sampling::Step => json::animation::Interpolation::Step,
                    Sampling::Linear => json::animation::Interpolation::Linear,
                }),
                output,
            });
        }
        b.root.push(json::Animation {
            extensions: None,
            extras: Default::default(),
            channels,
            name: Some(a.name.clone()),
            samplers,
        });
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
    export_gltf_with(path, meshes, &Morphs::default())
}

/// [`export_gltf`] with morph targets and weight animations (see [`Morphs`]).
pub fn export_gltf_with(
    path: impl AsRef<Path>,
    meshes: &[ExportMesh<'_>],
    morphs: &Morphs,
) -> Result<()> {
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
    let (mut root, bin) = build(path, meshes, morphs)?;
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
        let (root, bin) = build(
            Path::new("x.glb"),
            &[ExportMesh::from_mesh("m", &mesh)],
            &Morphs::default(),
        )
        .unwrap();
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
