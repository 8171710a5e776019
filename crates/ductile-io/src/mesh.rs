//! Mesh import: glTF (`.glb`, `.gltf`) and Wavefront OBJ (`.obj`).
//!
//! A mesh reference is a path with an optional `#name` suffix selecting one part of the
//! file. The merge rule:
//!
//! * **glTF**: every mesh instance of the default scene (or of the first scene when there is
//!   no default, or every mesh once with the identity when the file has no scene) is taken
//!   with its node's world transform applied to positions (and the inverse transpose to
//!   normals, renormalised; winding flipped under a mirroring transform). All triangle
//!   primitives (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; points and lines are skipped)
//!   are appended in scene order. `#name` keeps only the instances of the glTF mesh with that
//!   name (or that mesh once, untransformed, when the scene does not use it).
//! * **OBJ**: every object/group (`o`/`g`) is appended in file order; `#name` keeps only the
//!   objects/groups with that name. Faces are triangulated and each distinct
//!   (position, texcoord, normal) triple is one stored vertex (seam copies stay separate, as
//!   in glTF; the welded topology of `ductile-core` joins them).
//!
//! Normals (UVs) are kept only when every merged primitive has them. Materials, textures,
//! skins and morph targets are ignored.

use std::fmt;
use std::path::{Path, PathBuf};

use ductile_core::mesh::{Mesh, RestMesh};
use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::{IoError, Result};

/// A mesh file path with an optional `#name` selection of one object/group (OBJ) or mesh
/// (glTF).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshRef {
    /// The file.
    pub path: PathBuf,
    /// The selected part, if any.
    pub select: Option<String>,
}

impl MeshRef {
    /// Splits `spec` at its last `#` when what follows is a non-empty name without a path
    /// separator (`makehuman-base.obj#body`); otherwise the whole text is the path.
    #[must_use]
    pub fn parse(spec: &str) -> Self {
        match spec.rsplit_once('#') {
            Some((path, name))
                if !path.is_empty() && !name.is_empty() && !name.contains(['/', '\\']) =>
            {
                Self {
                    path: PathBuf::from(path),
                    select: Some(name.to_owned()),
                }
            }
            _ => Self {
                path: PathBuf::from(spec),
                select: None,
            },
        }
    }

    /// The same reference with a relative path joined to `base`.
    #[must_use]
    pub fn resolved(mut self, base: &Path) -> Self {
        if self.path.is_relative() {
            self.path = base.join(&self.path);
        }
        self
    }

    /// The path with the `#name` suffix, for messages.
    #[must_use]
    pub fn display_path(&self) -> PathBuf {
        match &self.select {
            None => self.path.clone(),
            Some(s) => PathBuf::from(format!("{}#{s}", self.path.display())),
        }
    }
}

impl fmt::Display for MeshRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.display_path().display())
    }
}

/// The lower-case extension of a path ("" when there is none).
#[must_use]
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// The mesh file formats the importer reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// glTF 2.0, binary (`.glb`) or JSON (`.gltf`); the decoder tells them apart by content.
    Gltf,
    /// Wavefront OBJ (`.obj`).
    Obj,
}

impl MeshFormat {
    /// The format of a file from its extension (case-insensitive): `.glb` and `.gltf` are
    /// [`MeshFormat::Gltf`], `.obj` is [`MeshFormat::Obj`]; anything else is an
    /// [`IoError::UnsupportedExtension`] naming the file.
    pub fn from_path(path: &Path) -> Result<Self> {
        match extension(path).as_str() {
            "glb" | "gltf" => Ok(Self::Gltf),
            "obj" => Ok(Self::Obj),
            other => Err(IoError::UnsupportedExtension {
                path: path.to_owned(),
                extension: other.to_owned(),
                expected: ".glb, .gltf or .obj",
            }),
        }
    }
}

/// Loads the mesh `r` refers to, as stored (not yet validated or welded).
pub fn load_mesh(r: &MeshRef) -> Result<Mesh> {
    let format = MeshFormat::from_path(&r.path)?;
    let bytes = crate::read_file(&r.path).map_err(|source| IoError::Read {
        path: r.path.clone(),
        source,
    })?;
    let base = crate::scene::scene_dir(&r.path);
    decode(&bytes, format, r, Some(base))
}

/// Loads, validates and welds the mesh `r` refers to.
pub fn load_rest_mesh(r: &MeshRef) -> Result<RestMesh> {
    weld(load_mesh(r)?, r)
}

/// Decodes a mesh held in memory (for example embedded in a program with `include_bytes!`),
/// as stored (not yet validated or welded). `name` is the source as a scene would write it,
/// with an optional `#name` selection of one part ([`MeshRef::parse`]); it names the mesh in
/// errors exactly like a file path does. A glTF file in memory cannot refer to external
/// buffer files (only to the binary chunk or to `data:` URIs).
pub fn load_mesh_from_bytes(bytes: &[u8], format: MeshFormat, name: &str) -> Result<Mesh> {
    decode(bytes, format, &MeshRef::parse(name), None)
}

/// [`load_mesh_from_bytes`], then validated and welded like [`load_rest_mesh`].
pub fn load_rest_mesh_from_bytes(bytes: &[u8], format: MeshFormat, name: &str) -> Result<RestMesh> {
    let r = MeshRef::parse(name);
    weld(decode(bytes, format, &r, None)?, &r)
}

/// Decodes `bytes` in `format`; `r` names the source and selects the part, `base` is the
/// directory external glTF buffers are resolved against (`None`: none may be used).
fn decode(bytes: &[u8], format: MeshFormat, r: &MeshRef, base: Option<&Path>) -> Result<Mesh> {
    let mesh = match format {
        MeshFormat::Gltf => load_gltf(bytes, &r.path, base, r.select.as_deref())?,
        MeshFormat::Obj => load_obj(bytes, &r.path, r.select.as_deref())?,
    };
    if mesh.indices.is_empty() {
        return Err(IoError::EmptyMesh {
            path: r.display_path(),
            vertices: mesh.positions.len(),
        });
    }
    Ok(mesh)
}

/// Validates and welds a loaded mesh; errors name `r`.
fn weld(mesh: Mesh, r: &MeshRef) -> Result<RestMesh> {
    let name = r.display_path();
    RestMesh::new(mesh, &name.display().to_string())
        .map_err(|source| IoError::InvalidMesh { path: name, source })
}

/// Appends mesh parts while tracking whether every part had normals and UVs.
#[derive(Default)]
struct Merger {
    mesh: Mesh,
    all_normals: bool,
    all_uvs: bool,
    parts: usize,
}

impl Merger {
    fn push(
        &mut self,
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        indices: impl IntoIterator<Item = u32>,
    ) {
        let base = self.mesh.positions.len() as u32;
        if self.parts == 0 {
            self.all_normals = true;
            self.all_uvs = true;
        }
        self.parts += 1;
        let n = positions.len();
        self.all_normals &= normals.as_ref().is_some_and(|v| v.len() == n);
        self.all_uvs &= uvs.as_ref().is_some_and(|v| v.len() == n);
        let m = &mut self.mesh;
        m.positions.extend(positions);
        if self.all_normals {
            m.normals
                .get_or_insert_with(Vec::new)
                .extend(normals.unwrap_or_default());
        }
        if self.all_uvs {
            m.uvs
                .get_or_insert_with(Vec::new)
                .extend(uvs.unwrap_or_default());
        }
        m.indices.extend(indices.into_iter().map(|i| i + base));
    }

    fn finish(mut self) -> Mesh {
        if !self.all_normals {
            self.mesh.normals = None;
        }
        if !self.all_uvs {
            self.mesh.uvs = None;
        }
        self.mesh
    }
}

/// The first line of an OBJ file that the decoder would refuse, for an error that names it:
/// its number (from 1), its text and the problem — a vertex, texture or normal coordinate
/// that is not a number (or missing), a face with fewer than three vertices, or a face index
/// that is zero, not a number or beyond the elements defined so far (negative indices count
/// back from the last one, as the format says).
fn obj_bad_line(bytes: &[u8]) -> Option<(usize, String, String)> {
    let text = String::from_utf8_lossy(bytes);
    let mut counts = [0_i64; 3]; // v, vt, vn
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(kind) = words.next() else {
            continue;
        };
        let rest: Vec<&str> = words.collect();
        let bad = |problem: String| {
            let shown: String = raw.trim().chars().take(80).collect();
            Some((k + 1, shown, problem))
        };
        let numbers = |need: usize, what: &str| -> Option<String> {
            if rest.len() < need {
                return Some(format!("{what} needs {need} numbers, found {}", rest.len()));
            }
            rest.iter()
                .find(|w| w.parse::<f64>().is_err())
                .map(|w| format!("'{w}' is not a number"))
        };
        match kind {
            "v" => {
                if let Some(p) = numbers(3, "a vertex") {
                    return bad(p);
                }
                counts[0] += 1;
            }
            "vt" => {
                if let Some(p) = numbers(1, "a texture coordinate") {
                    return bad(p);
                }
                counts[1] += 1;
            }
            "vn" => {
                if let Some(p) = numbers(3, "a normal") {
                    return bad(p);
                }
                counts[2] += 1;
            }
            "f" => {
                if rest.len() < 3 {
                    return bad(format!(
                        "a face needs at least 3 vertices, found {}",
                        rest.len()
                    ));
                }
                for corner in &rest {
                    for (slot, index) in corner.split('/').enumerate().take(3) {
                        if index.is_empty() && slot > 0 {
                            continue; // `1//3`: no texture coordinate
                        }
                        let names = ["vertex", "texture coordinate", "normal"];
                        let Ok(i) = index.parse::<i64>() else {
                            return bad(format!("'{corner}': '{index}' is not an index"));
                        };
                        let n = counts[slot];
                        if i == 0 || i > n || i < -n {
                            return bad(format!(
                                "'{corner}': {} index {i} is out of range ({n} defined so far)",
                                names[slot]
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// One part of a mesh file that a `#name` selection can pick ([`MeshRef`]): an OBJ object
/// or group, or a named glTF mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshPart {
    /// The part's name, as `#name` selects it.
    pub name: String,
    /// Its vertices as stored (before welding; every instance of a glTF mesh counted once).
    pub vertices: usize,
}

/// The parts of the mesh file `path` that can be selected by name, in file order (an OBJ
/// group named twice is one part). The file is read and parsed but no mesh is built, so
/// the Studio can ask which part to import before loading it.
///
/// # Errors
/// The file cannot be read, has an unsupported extension, or does not parse.
pub fn mesh_parts(path: &Path) -> Result<Vec<MeshPart>> {
    let format = MeshFormat::from_path(path)?;
    let bytes = crate::read_file(path).map_err(|source| IoError::Read {
        path: path.to_owned(),
        source,
    })?;
    let mut parts: Vec<MeshPart> = Vec::new();
    let mut add = |name: &str, vertices: usize| match parts.iter_mut().find(|p| p.name == name) {
        Some(p) => p.vertices += vertices,
        None => parts.push(MeshPart {
            name: name.to_owned(),
            vertices,
        }),
    };
    match format {
        MeshFormat::Obj => {
            for m in parse_obj(&bytes, path)? {
                add(&m.name, m.mesh.positions.len() / 3);
            }
        }
        MeshFormat::Gltf => {
            let (document, _) = parse_gltf(&bytes, path)?;
            for m in document.meshes() {
                let Some(name) = m.name() else {
                    continue;
                };
                let vertices = m
                    .primitives()
                    .filter_map(|p| p.get(&gltf::Semantic::Positions))
                    .map(|a| a.count())
                    .sum();
                add(name, vertices);
            }
        }
    }
    Ok(parts)
}

/// Checks every line of an OBJ file and parses it with tobj (triangulated, one index per
/// vertex, materials never opened).
fn parse_obj(bytes: &[u8], path: &Path) -> Result<Vec<tobj::Model>> {
    let mut reader = bytes;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Every line is checked before tobj reads the file: tobj 4.0.5 turns a face index 0
    // into an index before the first vertex and panics on it (found by the obj fuzzer).
    if let Some((line, text, problem)) = obj_bad_line(bytes) {
        return Err(IoError::ObjLine {
            path: path.to_owned(),
            line,
            text,
            problem,
        });
    }
    // Materials are not needed: never open .mtl files.
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|source| IoError::Obj {
        path: path.to_owned(),
        source,
    })?;
    Ok(models)
}

fn load_obj(bytes: &[u8], path: &Path, select: Option<&str>) -> Result<Mesh> {
    let models = parse_obj(bytes, path)?;
    if let Some(name) = select
        && !models.iter().any(|m| m.name == name)
    {
        let mut available: Vec<String> = models.iter().map(|m| m.name.clone()).collect();
        available.dedup();
        return Err(IoError::NoSuchPart {
            path: path.to_owned(),
            kind: "OBJ object or group",
            name: name.to_owned(),
            available,
        });
    }
    let mut merger = Merger::default();
    for model in models
        .into_iter()
        .filter(|m| select.is_none_or(|s| m.name == s))
    {
        let m = model.mesh;
        let positions: Vec<Vec3> = m
            .positions
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let normals = (!m.normals.is_empty()).then(|| {
            m.normals
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect()
        });
        let uvs = (!m.texcoords.is_empty()).then(|| {
            m.texcoords
                .chunks_exact(2)
                .map(|c| Vec2::new(c[0], c[1]))
                .collect()
        });
        merger.push(positions, normals, uvs, m.indices);
    }
    Ok(merger.finish())
}

fn gltf_error(path: &Path) -> impl FnOnce(gltf::Error) -> IoError + '_ {
    move |source| IoError::Gltf {
        path: path.to_owned(),
        source,
    }
}

/// Refuses a primitive whose attributes (or morph targets) name an accessor the file does not
/// have, before the gltf crate's validation reads it.
fn check_attribute_accessors(root: &gltf::json::Root, path: &Path) -> Result<()> {
    let count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive
                .targets
                .iter()
                .flatten()
                .flat_map(|t| [t.positions, t.normals, t.tangents].into_iter().flatten());
            let bad = primitive
                .attributes
                .values()
                .copied()
                .chain(primitive.indices)
                .chain(targets)
                .find(|a| a.value() >= count);
            if let Some(a) = bad {
                return Err(IoError::GltfStructure {
                    path: path.to_owned(),
                    problem: format!(
                        "mesh {m}, primitive {p} refers to accessor {}, but the file has {count} \
                         accessors",
                        a.value()
                    ),
                });
            }
        }
    }
    Ok(())
}

/// Parses a glTF file's structure (JSON and, for GLB, the binary chunk), checked where the
/// gltf crate would panic; buffers are not loaded.
fn parse_gltf(bytes: &[u8], path: &Path) -> Result<(gltf::Document, Option<Vec<u8>>)> {
    // gltf 1.4.1 subtracts the header's size from the declared length unchecked
    // (binary.rs:252): a length below 12 overflowed (a panic where overflow is checked).
    if let Some(header) = bytes.strip_prefix(b"glTF")
        && let Some(length) = header.get(4..8)
    {
        let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
        if length < 12 {
            return Err(IoError::GltfStructure {
                path: path.to_owned(),
                problem: format!(
                    "the GLB header declares a total length of {length} bytes, less than the \
                     12-byte header itself"
                ),
            });
        }
    }
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(gltf_error(path))?;
    // The gltf crate's own validation indexes the POSITION accessor without a bounds check
    // (gltf-json 1.4.1, mesh.rs:151): a file naming a missing accessor made it panic.
    check_attribute_accessors(raw.document.as_json(), path)?;
    let blob = raw.blob;
    let document = gltf::Document::from_json(raw.document.into_json()).map_err(gltf_error(path))?;
    Ok((document, blob))
}

fn load_gltf(bytes: &[u8], path: &Path, base: Option<&Path>, select: Option<&str>) -> Result<Mesh> {
    let (document, blob) = parse_gltf(bytes, path)?;
    let buffers = crate::gltf_buffers::load_buffers(&document, base, blob, path)?;

    // Mesh instances with their world transforms.
    let mut instances: Vec<(gltf::Mesh<'_>, Mat4)> = Vec::new();
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => {
            let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
                scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
            stack.reverse();
            // Depth-first, children in order. The gltf crate checks node indices but not
            // the shape of the hierarchy: glTF requires disjoint trees (2.0 §3.5.3), so a
            // node reached twice — a cycle, or a node listed twice, whose instances would
            // multiply at every level — is refused.
            let mut seen = vec![false; document.nodes().count()];
            while let Some((node, parent)) = stack.pop() {
                if std::mem::replace(&mut seen[node.index()], true) {
                    return Err(IoError::GltfStructure {
                        path: path.to_owned(),
                        problem: format!(
                            "node {} is reached twice in the node hierarchy (a cycle, or a \
                             node with two parents or listed twice); glTF requires trees",
                            node.index()
                        ),
                    });
                }
                let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
                if let Some(mesh) = node.mesh() {
                    instances.push((mesh, world));
                }
                let mut children: Vec<_> = node.children().map(|c| (c, world)).collect();
                children.reverse();
                stack.extend(children);
            }
        }
        None => instances.extend(document.meshes().map(|m| (m, Mat4::IDENTITY))),
    }
    if let Some(name) = select {
        instances.retain(|(m, _)| m.name() == Some(name));
        if instances.is_empty() {
            match document.meshes().find(|m| m.name() == Some(name)) {
                Some(m) => instances.push((m, Mat4::IDENTITY)),
                None => {
                    return Err(IoError::NoSuchPart {
                        path: path.to_owned(),
                        kind: "glTF mesh",
                        name: name.to_owned(),
                        available: document
                            .meshes()
                            .map(|m| {
                                m.name()
                                    .map_or_else(|| format!("#{}", m.index()), ToOwned::to_owned)
                            })
                            .collect(),
                    });
                }
            }
        }
    }

    let mut merger = Merger::default();
    for (mesh, world) in instances {
        let mesh_name = mesh
            .name()
            .map_or_else(|| mesh.index().to_string(), ToOwned::to_owned);
        for (k, prim) in mesh.primitives().enumerate() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                continue;
            }
            let bad = |problem: &str| IoError::GltfPrimitive {
                path: path.to_owned(),
                mesh: mesh_name.clone(),
                primitive: k,
                problem: problem.to_owned(),
            };
            check_accessors(&prim, &buffers).map_err(|p| bad(&p))?;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| {
                    bad("POSITION cannot be read (missing, or its accessor does not fit its buffer)")
                })?
                .map(Vec3::from)
                .collect();
            let normals: Option<Vec<Vec3>> =
                reader.read_normals().map(|it| it.map(Vec3::from).collect());
            let uvs: Option<Vec<Vec2>> = reader
                .read_tex_coords(0)
                .map(|tc| tc.into_f32().map(Vec2::from).collect());
            let raw: Vec<u32> = match (prim.indices(), reader.read_indices()) {
                (_, Some(ix)) => ix.into_u32().collect(),
                (None, None) => (0..positions.len() as u32).collect(),
                (Some(_), None) => return Err(bad("the indices cannot be read")),
            };
            let mut tris = triangle_list(mode, &raw);
            let (positions, normals) = apply_transform(&world, positions, normals);
            if world.determinant() < 0.0 {
                for t in tris.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            merger.push(positions, normals, uvs, tris);
        }
    }
    Ok(merger.finish())
}

/// The most elements an accessor may have (2²⁷, about 134 million): far above a real
/// mesh's vertex or index count, far below what would exhaust memory.
pub const MAX_ACCESSOR_ELEMENTS: usize = 1 << 27;

/// Checks that an accessor's data lies where it says, before the gltf crate's reader (which
/// panics on a stride smaller than the element, and allocates `count` elements for a sparse
/// accessor) touches it: count within [`MAX_ACCESSOR_ELEMENTS`]; a stride at least the
/// element size; the accessor inside its view and the view inside its buffer; a sparse
/// part inside its views, with indices below `count`.
fn check_layout(a: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> std::result::Result<(), String> {
    let what = format!("accessor {}", a.index());
    let count = a.count();
    // The gltf crate's reader computes `count - 1` unchecked (found by the gltf fuzzer), and
    // glTF 2.0 requires at least one element (accessor.count ≥ 1).
    if count == 0 {
        return Err(format!("{what} has 0 elements; glTF requires at least 1"));
    }
    if count > MAX_ACCESSOR_ELEMENTS {
        return Err(format!(
            "{what} has {count} elements, more than the limit of {MAX_ACCESSOR_ELEMENTS}"
        ));
    }
    let view_bytes = |v: &gltf::buffer::View<'_>| -> std::result::Result<usize, String> {
        let available = buffers.get(v.buffer().index()).map_or(0, Vec::len);
        match v.offset().checked_add(v.length()) {
            Some(end) if end <= available => Ok(v.length()),
            _ => Err(format!(
                "buffer view {} (offset {}, {} bytes) does not fit in buffer {} ({available} \
                 bytes)",
                v.index(),
                v.offset(),
                v.length(),
                v.buffer().index()
            )),
        }
    };
    let elem = a.size();
    if let Some(view) = a.view() {
        let length = view_bytes(&view)?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(format!(
                "{what}: buffer view {} has byteStride {stride}, smaller than one element \
                 ({elem} bytes)",
                view.index()
            ));
        }
        let need = match count.checked_sub(1) {
            None => Some(0),
            Some(last) => stride
                .checked_mul(last)
                .and_then(|n| n.checked_add(elem))
                .and_then(|n| n.checked_add(a.offset())),
        };
        if need.is_none_or(|n| n > length) {
            return Err(format!(
                "{what} ({count} elements of {elem} bytes from offset {}) does not fit in \
                 buffer view {} ({length} bytes)",
                a.offset(),
                view.index()
            ));
        }
    }
    if let Some(sparse) = a.sparse() {
        let n = sparse.count();
        // As for `count`: the reader computes `n - 1` unchecked; glTF requires n ≥ 1.
        if n == 0 {
            return Err(format!(
                "{what} has a sparse part of 0 values; glTF requires at least 1"
            ));
        }
        if n > count {
            return Err(format!(
                "{what} has {n} sparse values but only {count} elements"
            ));
        }
        let indices = sparse.indices();
        let size = indices.index_type().size();
        let view = indices.view();
        let length = view_bytes(&view)?;
        if indices
            .offset()
            .checked_add(n * size)
            .is_none_or(|e| e > length)
        {
            return Err(format!(
                "{what}: the sparse indices do not fit in their buffer view"
            ));
        }
        let values = sparse.values();
        let vview = values.view();
        let vlength = view_bytes(&vview)?;
        if values
            .offset()
            .checked_add(n * elem)
            .is_none_or(|e| e > vlength)
        {
            return Err(format!(
                "{what}: the sparse values do not fit in their buffer view"
            ));
        }
        let start = view.offset() + indices.offset();
        let data = &buffers[view.buffer().index()][start..start + n * size];
        for (k, chunk) in data.chunks_exact(size).enumerate() {
            let index = chunk
                .iter()
                .rev()
                .fold(0_usize, |acc, &b| (acc << 8) | usize::from(b));
            if index >= count {
                return Err(format!(
                    "{what}: sparse index {k} is {index}, not below the count {count}"
                ));
            }
        }
    }
    Ok(())
}

/// Checks the types of the accessors the importer reads (the gltf crate's reader assumes
/// them and would panic on others): `POSITION` and `NORMAL` float VEC3, `TEXCOORD_0` VEC2 of
/// float or normalised unsigned byte/short, indices unsigned SCALAR; and their layout
/// ([`check_layout`]).
fn check_accessors(
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
) -> std::result::Result<(), String> {
    use gltf::accessor::{DataType, Dimensions};
    use gltf::mesh::Semantic;
    let describe = |a: &gltf::Accessor<'_>| format!("{:?} {:?}", a.data_type(), a.dimensions());
    for (semantic, a) in prim.attributes() {
        let ok = match semantic {
            Semantic::Positions | Semantic::Normals => {
                a.data_type() == DataType::F32 && a.dimensions() == Dimensions::Vec3
            }
            Semantic::TexCoords(0) => {
                a.dimensions() == Dimensions::Vec2
                    && matches!(a.data_type(), DataType::F32 | DataType::U8 | DataType::U16)
            }
            _ => true,
        };
        if !ok {
            return Err(format!(
                "attribute {semantic:?} has an invalid accessor type ({})",
                describe(&a)
            ));
        }
        if a.sparse().is_none() && a.view().is_none() {
            return Err(format!("attribute {semantic:?} has no buffer view"));
        }
        if matches!(
            semantic,
            Semantic::Positions | Semantic::Normals | Semantic::TexCoords(0)
        ) {
            check_layout(&a, buffers).map_err(|p| format!("attribute {semantic:?}: {p}"))?;
        }
    }
    if let Some(a) = prim.indices()
        && (a.dimensions() != Dimensions::Scalar
            || !matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32))
    {
        return Err(format!(
            "indices have an invalid accessor type ({})",
            describe(&a)
        ));
    }
    if let Some(a) = prim.indices() {
        if a.sparse().is_none() && a.view().is_none() {
            return Err("the indices have no buffer view".into());
        }
        check_layout(&a, buffers).map_err(|p| format!("indices: {p}"))?;
    }
    Ok(())
}

/// Turns strip or fan indices into a triangle list (glTF 2.0 §3.7.2.1).
fn triangle_list(mode: gltf::mesh::Mode, idx: &[u32]) -> Vec<u32> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .flat_map(|i| {
                let odd = i % 2;
                [idx[i], idx[i + 1 + odd], idx[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (0..idx.len().saturating_sub(2))
            .flat_map(|i| [idx[i + 1], idx[i + 2], idx[0]])
            .collect(),
        // A ragged list is kept as it is: mesh validation reports it.
        _ => idx.to_vec(),
    }
}

fn apply_transform(
    m: &Mat4,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
) -> (Vec<Vec3>, Option<Vec<Vec3>>) {
    if *m == Mat4::IDENTITY {
        return (positions, normals);
    }
    let nm = Mat3::from_mat4(*m).inverse().transpose();
    (
        positions
            .into_iter()
            .map(|p| m.transform_point3(p))
            .collect(),
        normals.map(|ns| {
            ns.into_iter()
                .map(|n| (nm * n).normalize_or_zero())
                .collect()
        }),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesh_ref_splits_a_name_suffix() {
        let r = MeshRef::parse("meshes/makehuman-base.obj#body");
        assert_eq!(r.path, PathBuf::from("meshes/makehuman-base.obj"));
        assert_eq!(r.select.as_deref(), Some("body"));
        assert_eq!(MeshRef::parse("a.obj").select, None);
        assert_eq!(MeshRef::parse("dir#x/a.obj").select, None);
        assert_eq!(MeshRef::parse("a.obj#").select, None);
        let resolved = MeshRef::parse("a.obj#b").resolved(Path::new("scenes"));
        assert_eq!(resolved.to_string(), "scenes/a.obj#b");
    }

    #[test]
    fn strips_and_fans_become_lists() {
        use gltf::mesh::Mode;
        assert_eq!(
            triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![0, 1, 2, 1, 3, 2]
        );
        assert_eq!(
            triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![1, 2, 0, 2, 3, 0]
        );
    }

    #[test]
    fn transform_moves_points_and_keeps_normals_unit() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 1.0),
            glam::Quat::IDENTITY,
            Vec3::Z,
        );
        let (p, n) = apply_transform(&m, vec![Vec3::X], Some(vec![Vec3::new(1.0, 1.0, 0.0)]));
        assert_eq!(p[0], Vec3::new(2.0, 0.0, 1.0));
        let n = n.unwrap()[0];
        assert!((n.length() - 1.0).abs() < 1e-6);
        // Inverse transpose of diag(2, 1, 1) halves x before renormalising.
        assert!((n - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6);
    }
}
