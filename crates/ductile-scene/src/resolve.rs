//! From the document to core's evaluable [`Stack`]: world transforms, tools and volumes in
//! mesh space, areas as welded vertex sets.

use std::collections::HashMap;

use glam::Affine3A;

use ductile_core::influence::{Influence, Volume};
use ductile_core::mesh::{Deformed, RestMesh};
use ductile_core::stack::{Layer, Stack};
use ductile_core::tool::Tool;

use crate::document::{Area, Document, NodeKind, wrong_kind};
use crate::error::{Result, SceneError};

impl Document {
    /// The node's world transform (product of its ancestors' local transforms).
    pub fn world_transform(&self, name: &str) -> Result<Affine3A> {
        let mut m = Affine3A::IDENTITY;
        let mut current = Some(name);
        let mut steps = 0;
        // A short chain walks with name lookups; a long one indexes the names once.
        let index = (self.nodes.len() > 64).then(|| self.name_index());
        while let Some(c) = current {
            let node = match &index {
                Some(index) => index
                    .get(c)
                    .map(|&i| &self.nodes[i])
                    .ok_or_else(|| SceneError::NoSuchNode { name: c.to_owned() })?,
                None => self.node(c)?,
            };
            m = node.transform.affine() * m;
            current = node.parent.as_deref();
            steps += 1;
            if steps > self.nodes.len() {
                return Err(SceneError::Cycle {
                    node: name.to_owned(),
                });
            }
        }
        Ok(m)
    }

    /// The tool of a tool or macro node, in the node's local frame.
    pub fn tool(&self, name: &str) -> Result<Tool> {
        let node = self.node(name)?;
        match &node.kind {
            NodeKind::Tool(t) => Ok(t.clone()),
            NodeKind::Macro(m) => {
                let def = self
                    .macros
                    .get(&m.name)
                    .ok_or_else(|| SceneError::UnknownMacro {
                        node: name.to_owned(),
                        name: m.name.clone(),
                    })?;
                Ok(Tool::Ffsd(def.tool(m.value)))
            }
            other => Err(wrong_kind(name, other, "tool")),
        }
    }

    /// Map from `node`'s local frame to `mesh`'s local frame.
    pub fn to_mesh_space(&self, node: &str, mesh: &str) -> Result<Affine3A> {
        Ok(self.world_transform(mesh)?.inverse() * self.world_transform(node)?)
    }

    /// The welded vertex indices (sorted, unique) of area `area` of mesh `mesh`, whose rest
    /// mesh is `rest`.
    pub fn area_vertices(&self, mesh: &str, area: &str, rest: &RestMesh) -> Result<Vec<u32>> {
        let def = self
            .mesh(mesh)?
            .areas
            .get(area)
            .ok_or_else(|| SceneError::UnknownArea {
                mesh: mesh.to_owned(),
                layer: 0,
                area: area.to_owned(),
            })?;
        resolve_area(def, rest, &format!("mesh '{mesh}', area '{area}'"))
    }

    /// The areas of mesh `mesh` given by stored vertex indices ([`Area::Vertices`]) that its
    /// stack reads through its layers' influences, each once, in stack order.
    ///
    /// Such an area numbers the vertices of the mesh's own file, so it carries over only to
    /// a mesh with the same stored vertex count; a [`Area::Region`] carries over to any mesh
    /// (what `ductile apply --input` checks before applying a stack to other meshes).
    pub fn vertex_index_areas_in_stack(&self, mesh: &str) -> Result<Vec<&str>> {
        let node = self.mesh(mesh)?;
        let mut out: Vec<&str> = Vec::new();
        for spec in &node.stack {
            let Some(area) = spec.influence.as_ref().and_then(|i| i.area.as_deref()) else {
                continue;
            };
            if matches!(node.areas.get(area), Some(Area::Vertices(_))) && !out.contains(&area) {
                out.push(area);
            }
        }
        Ok(out)
    }

    /// Resolves the stack of mesh `mesh` against its rest mesh. Each area is resolved once,
    /// however many layers use it.
    pub fn resolve_stack(&self, mesh: &str, rest: &RestMesh) -> Result<Stack> {
        let mut cache: HashMap<String, Vec<u32>> = HashMap::new();
        let layers = self.resolve_layers_with(mesh, |name, def| {
            if let Some(v) = cache.get(name) {
                return Ok(v.clone());
            }
            let v = resolve_area(def, rest, &format!("mesh '{mesh}', area '{name}'"))?;
            cache.insert(name.to_owned(), v.clone());
            Ok(v)
        })?;
        let layers = layers
            .into_iter()
            .map(|(mut layer, area)| {
                if let Some(inf) = &mut layer.influence {
                    inf.area = area;
                }
                layer
            })
            .collect();
        Ok(Stack { layers })
    }

    /// Resolves every layer of mesh `mesh`'s stack in order, leaving each influence's area
    /// to the caller: `area(name, definition)` gives the area's vertex set (of any type `A`),
    /// returned next to the layer (whose `influence.area` is `None`). Errors are those of
    /// [`Document::resolve_stack`], in the same order.
    pub(crate) fn resolve_layers_with<A>(
        &self,
        mesh: &str,
        mut area: impl FnMut(&str, &Area) -> Result<A>,
    ) -> Result<Vec<(Layer, Option<A>)>> {
        let node = self.mesh(mesh)?;
        let mut layers = Vec::with_capacity(node.stack.len());
        // When a layer is soloed, only the soloed layers evaluate.
        let solo = node.stack.iter().any(|l| l.solo);
        for (i, spec) in node.stack.iter().enumerate() {
            let tool_node = self.node(&spec.tool).map_err(|_| SceneError::UnknownTool {
                mesh: mesh.to_owned(),
                layer: i,
                tool: spec.tool.clone(),
            })?;
            if !tool_node.kind.is_tool() {
                return Err(wrong_kind(&spec.tool, &tool_node.kind, "tool"));
            }
            let tool = self
                .tool(&spec.tool)?
                .transformed(&self.to_mesh_space(&spec.tool, mesh)?);
            let mut vertices = None;
            let influence = match &spec.influence {
                None => None,
                Some(inf) => {
                    let mut volumes = Vec::with_capacity(inf.volumes.len());
                    for v in &inf.volumes {
                        let vnode = self.node(v).map_err(|_| SceneError::UnknownVolume {
                            mesh: mesh.to_owned(),
                            layer: i,
                            volume: v.clone(),
                        })?;
                        let NodeKind::Volume(vol) = &vnode.kind else {
                            return Err(wrong_kind(v, &vnode.kind, "volume"));
                        };
                        let placement = self.to_mesh_space(v, mesh)?;
                        volumes.push(Volume::new(
                            vol.shape.clone(),
                            placement,
                            &format!("volume '{v}'"),
                        )?);
                    }
                    if let Some(a) = &inf.area {
                        let def = node.areas.get(a).ok_or_else(|| SceneError::UnknownArea {
                            mesh: mesh.to_owned(),
                            layer: i,
                            area: a.clone(),
                        })?;
                        vertices = Some(area(a, def)?);
                    }
                    Some(Influence {
                        volumes,
                        area: None,
                        falloff: inf.falloff.clone(),
                        inner: inf.inner,
                        invert: inf.invert,
                    })
                }
            };
            layers.push((
                Layer {
                    name: spec.tool.clone(),
                    tool,
                    influence,
                    weight: spec.weight,
                    enabled: spec.enabled && (!solo || spec.solo),
                },
                vertices,
            ));
        }
        Ok(layers)
    }

    /// Resolves and evaluates the stack of mesh `mesh` on `rest`.
    pub fn evaluate(&self, mesh: &str, rest: &RestMesh) -> Result<Deformed> {
        Ok(self.resolve_stack(mesh, rest)?.evaluate(rest)?)
    }
}

/// Resolves an area definition to sorted, unique welded vertex indices.
pub fn resolve_area(area: &Area, rest: &RestMesh, what: &str) -> Result<Vec<u32>> {
    let topo = rest.topology();
    let mut out: Vec<u32> = match area {
        Area::Vertices(stored) => {
            let mut v = Vec::with_capacity(stored.len());
            for &i in stored {
                let w = topo
                    .weld
                    .get(i as usize)
                    .ok_or_else(|| SceneError::IndexOutOfRange {
                        what: format!("{what}: vertex"),
                        index: i as usize,
                        len: topo.stored_count(),
                    })?;
                v.push(*w);
            }
            v
        }
        Area::Region(shapes) => {
            // Each shape with its mesh-space bounding box: most vertices are outside every
            // box, and the box test is much cheaper than the shape's.
            let mut vols = Vec::with_capacity(shapes.len());
            for (k, s) in shapes.iter().enumerate() {
                let placement = s.transform.affine();
                let volume =
                    Volume::new(s.shape.clone(), placement, &format!("{what}: shape {k}"))?;
                vols.push((s.shape.bounds_in(&placement), volume));
            }
            rest.welded_positions()
                .iter()
                .enumerate()
                .filter(|(_, p)| {
                    vols.iter().any(|((lo, hi), v)| {
                        p.cmpge(*lo).all()
                            && p.cmple(*hi).all()
                            && v.normalized_distance(**p) <= 1.0
                    })
                })
                .map(|(i, _)| i as u32)
                .collect()
        }
    };
    out.sort_unstable();
    out.dedup();
    Ok(out)
}
