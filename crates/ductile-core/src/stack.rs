//! The deformation stack: ordered layers evaluated bottom to top on a rest mesh.
//!
//! Evaluation of one layer, given its input positions `p` (welded, mesh space):
//!
//! 1. skip it when it is disabled, its weight is 0 or its tool is the identity;
//! 2. compute its [`Mask`] (influence; all vertices when it has none);
//! 3. bind the tool on the input ([`LayerBinding::bind`]);
//! 4. deform the active vertices, then blend: `p'ᵢ = pᵢ + weight · wᵢ · (D(pᵢ) − pᵢ)`; when
//!    `weight · wᵢ = 1`, `p'ᵢ = D(pᵢ)` exactly.
//!
//! Vertices outside the mask keep their input bits. The rest mesh is never modified.
//! [`LayerBinding`] is the unit a cache keeps between evaluations.

use glam::Vec3;
use rayon::prelude::*;

use crate::error::{CoreError, Result, check_finite};
use crate::influence::{Influence, Mask};
use crate::mesh::{Deformed, RestMesh, Topology};
use crate::tool::{BindInput, Tool, ToolBind};

/// Above this many active vertices a layer deforms in parallel chunks.
const PARALLEL_THRESHOLD: usize = 16_384;
/// Chunk size for parallel deformation.
const CHUNK: usize = 4_096;

/// One resolved layer: a tool in mesh space, its influence, weight and enabled flag.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Name shown in messages (usually the tool node's name).
    pub name: String,
    /// The tool, in the mesh's space.
    pub tool: Tool,
    /// Optional influence; `None` means every vertex with weight 1.
    pub influence: Option<Influence>,
    /// Blend weight in `[0, 1]`.
    pub weight: f32,
    /// Disabled layers are skipped.
    pub enabled: bool,
}

impl Layer {
    /// A full-weight, enabled layer without influence.
    #[must_use]
    pub fn new(name: impl Into<String>, tool: Tool) -> Self {
        Self {
            name: name.into(),
            tool,
            influence: None,
            weight: 1.0,
            enabled: true,
        }
    }

    /// True when evaluating the layer cannot change anything: it is disabled, has weight 0,
    /// or its tool is the identity ([`Tool::is_identity`]).
    #[must_use]
    pub fn is_inert(&self) -> bool {
        !self.enabled || self.weight == 0.0 || self.tool.is_identity()
    }

    /// Checks the weight, the influence and the tool.
    pub fn validate(&self) -> Result<()> {
        let what = format!("layer '{}'", self.name);
        check_finite(|| format!("{what}: weight"), self.weight)?;
        if !(0.0..=1.0).contains(&self.weight) {
            return Err(CoreError::OutOfRange {
                what: format!("{what}: weight"),
                value: f64::from(self.weight),
                expected: "must be in [0, 1]",
            });
        }
        if let Some(inf) = &self.influence {
            inf.validate(&what)?;
        }
        self.tool.validate(&format!("tool '{}'", self.name))
    }
}

/// A layer's cached bind: its mask and the tool's bind on one input.
#[derive(Debug)]
pub struct LayerBinding {
    /// Active vertices and weights.
    pub mask: Mask,
    /// The tool's bind; `None` when the mask is empty.
    pub bind: Option<ToolBind>,
}

impl LayerBinding {
    /// Binds `layer` on `positions` (its input).
    pub fn bind(layer: &Layer, positions: &[Vec3], topology: &Topology) -> Result<Self> {
        let mask = match &layer.influence {
            Some(inf) => inf.mask(positions),
            None => Mask::all(positions.len()),
        };
        let bind = if mask.is_empty() {
            None
        } else {
            Some(layer.tool.bind(&BindInput {
                positions,
                topology,
                active: &mask.indices,
            })?)
        };
        Ok(Self { mask, bind })
    }

    /// Deforms `positions` in place with this binding (see the module documentation).
    pub fn apply(&self, layer: &Layer, positions: &mut [Vec3]) -> Result<()> {
        let Some(bind) = &self.bind else {
            return Ok(());
        };
        let active = &self.mask.indices;
        let mut out = vec![Vec3::ZERO; active.len()];
        {
            let input: &[Vec3] = positions;
            if active.len() >= PARALLEL_THRESHOLD {
                out.par_chunks_mut(CHUNK)
                    .zip(active.par_chunks(CHUNK))
                    .for_each(|(o, a)| layer.tool.deform(bind, input, a, o));
            } else {
                layer.tool.deform(bind, input, active, &mut out);
            }
        }
        if let Some(k) = out.iter().position(|p| !p.is_finite()) {
            return Err(CoreError::Degenerate {
                what: format!("layer '{}'", layer.name),
                problem: format!(
                    "the tool produced a non-finite position for vertex {}",
                    active[k]
                ),
            });
        }
        for ((&i, &w), &d) in active.iter().zip(&self.mask.weights).zip(&out) {
            let w = w * layer.weight;
            let p = &mut positions[i as usize];
            *p = if w == 1.0 { d } else { *p + (d - *p) * w };
        }
        Ok(())
    }
}

/// An ordered list of layers, evaluated bottom (index 0) to top.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Stack {
    /// The layers, bottom first.
    pub layers: Vec<Layer>,
}

impl Stack {
    /// Validates every layer.
    pub fn validate(&self) -> Result<()> {
        self.layers.iter().try_for_each(Layer::validate)
    }

    /// Evaluates the stack on `rest` and returns welded deformed positions.
    pub fn evaluate_welded(&self, rest: &RestMesh) -> Result<Vec<Vec3>> {
        self.validate()?;
        let mut positions = rest.welded_positions().to_vec();
        for layer in self.layers.iter().filter(|l| !l.is_inert()) {
            LayerBinding::bind(layer, &positions, rest.topology())?.apply(layer, &mut positions)?;
        }
        Ok(positions)
    }

    /// Evaluates the stack and returns positions and recomputed normals in the stored
    /// vertex order of `rest`.
    pub fn evaluate(&self, rest: &RestMesh) -> Result<Deformed> {
        Ok(rest.output(&self.evaluate_welded(rest)?))
    }
}
