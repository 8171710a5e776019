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

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use crate::chunks::{
    CHUNK, PARALLEL_COPY_THRESHOLD, PARALLEL_THRESHOLD, Reuse, for_each_at, gather_at, scatter_at,
    zeroed,
};
use crate::error::{CoreError, Result, check_finite};
use crate::fused;
use crate::influence::{ChunkBounds, Influence, Mask};
use crate::mesh::{Deformed, RestMesh, Topology};
use crate::refinement::{EdgePoint, LayerRefinement, RefinedMesh};
use crate::tool::{BindInput, Tool, ToolBind};

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
    /// Active vertices and weights (shared: a cache may reuse a mask that does not depend on
    /// the input, such as an area's).
    pub mask: Arc<Mask>,
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
        Self::bind_masked(&layer.tool, Arc::new(mask), positions, topology)
    }

    /// Binds `tool` on `positions` with an already computed `mask` (which must be the
    /// layer's mask on `positions` for the result to equal [`LayerBinding::bind`]'s).
    pub fn bind_masked(
        tool: &Tool,
        mask: Arc<Mask>,
        positions: &[Vec3],
        topology: &Topology,
    ) -> Result<Self> {
        Self::bind_masked_reusing(tool, mask, positions, topology, None)
    }

    /// [`LayerBinding::bind_masked`], with the tool's per-vertex data of the vertices that
    /// are not stale copied from `previous`, a binding of the same layer (see
    /// [`Tool::bind_reusing`]). The same bits.
    pub fn bind_masked_reusing(
        tool: &Tool,
        mask: Arc<Mask>,
        positions: &[Vec3],
        topology: &Topology,
        previous: Option<Reuse<'_, LayerBinding>>,
    ) -> Result<Self> {
        let bind = if mask.is_empty() {
            None
        } else {
            let input = BindInput {
                positions,
                topology,
                active: &mask.indices,
            };
            let previous = previous.and_then(|p| p.bind.bind.as_ref().map(|b| p.with(b)));
            Some(tool.bind_reusing(&input, previous)?)
        };
        Ok(Self { mask, bind })
    }

    /// [`LayerBinding::apply_refining`], also returning the active vertices' positions
    /// before and after, in mask order (what an incremental evaluator keeps). Same bits as
    /// `apply_refining`. A per-vertex tool is applied in one pass over (parallel) chunks of
    /// the mask — read the input, deform, check, blend — followed by one scatter.
    pub fn apply_recorded(&self, layer: &Layer, positions: &mut Vec<Vec3>) -> Result<Recorded> {
        let indices = &self.mask.indices;
        let Some(bind) = self.bind.as_ref().filter(|_| !layer.tool.is_whole_layer()) else {
            let saved = gather_at(positions, indices);
            let splits = self.apply_refining(layer, positions)?;
            let written = gather_at(positions, indices);
            return Ok(Recorded {
                saved,
                written,
                splits,
            });
        };
        let n = indices.len();
        let (mut saved, mut written) = (zeroed(n), zeroed(n));
        let input: &[Vec3] = positions;
        let weights = &self.mask.weights;
        // One chunk starting at mask position `k0`; returns the position of its first
        // non-finite tool output.
        let work = |k0: usize, active: &[u32], s: &mut [Vec3], o: &mut [Vec3]| {
            for (s, &i) in s.iter_mut().zip(active) {
                *s = input[i as usize];
            }
            layer.tool.deform_gathered(bind, input, s, active, o);
            let bad = first_non_finite(o).map(|j| k0 + j);
            for (j, (o, &p)) in o.iter_mut().zip(s.iter()).enumerate() {
                *o = blend_one(p, *o, weights[k0 + j] * layer.weight);
            }
            bad
        };
        let bad = if n >= PARALLEL_THRESHOLD {
            saved
                .par_chunks_mut(CHUNK)
                .zip(written.par_chunks_mut(CHUNK))
                .zip(indices.par_chunks(CHUNK))
                .enumerate()
                .filter_map(|(c, ((s, o), a))| work(c * CHUNK, a, s, o))
                .min()
        } else {
            work(0, indices, &mut saved, &mut written)
        };
        if let Some(k) = bad {
            return Err(non_finite(layer, indices[k]));
        }
        scatter_at(positions, indices, &written);
        Ok(Recorded {
            saved,
            written,
            splits: None,
        })
    }

    /// Deforms `positions` in place with this binding (see the module documentation). A
    /// refining tool is evaluated without its refinement here; see
    /// [`LayerBinding::apply_refining`].
    pub fn apply(&self, layer: &Layer, positions: &mut [Vec3]) -> Result<()> {
        self.apply_with(layer, positions, &mut Vec::new())
    }

    /// [`LayerBinding::apply`], with the tool's outputs written to `scratch` (grown when
    /// shorter than the mask, its values overwritten): an evaluation that passes the same
    /// buffer to every layer zeroes it once per size it grows to, not once per layer.
    pub fn apply_with(
        &self,
        layer: &Layer,
        positions: &mut [Vec3],
        scratch: &mut Vec<Vec3>,
    ) -> Result<()> {
        let Some(bind) = &self.bind else {
            return Ok(());
        };
        let (out, _) = self.deform(layer, bind, positions, false, scratch)?;
        self.blend(layer, out, positions);
        Ok(())
    }

    /// Like [`LayerBinding::apply`], but a refining tool may add vertices: they are
    /// appended to `positions` (blended like the others, with input position and mask
    /// weight interpolated from their parent edge) and the splits are returned, in order
    /// (see [`crate::refinement`]). Without a refinement this is exactly
    /// [`LayerBinding::apply`].
    pub fn apply_refining(
        &self,
        layer: &Layer,
        positions: &mut Vec<Vec3>,
    ) -> Result<Option<Vec<EdgePoint>>> {
        self.apply_refining_with(layer, positions, &mut Vec::new())
    }

    /// [`LayerBinding::apply_refining`], with the tool's outputs in `scratch`, as in
    /// [`LayerBinding::apply_with`] (a whole-layer tool's own array takes its place).
    pub fn apply_refining_with(
        &self,
        layer: &Layer,
        positions: &mut Vec<Vec3>,
        scratch: &mut Vec<Vec3>,
    ) -> Result<Option<Vec<EdgePoint>>> {
        let Some(bind) = &self.bind else {
            return Ok(None);
        };
        let (out, refinement) = self.deform(layer, bind, positions, true, scratch)?;
        let Some(refinement) = refinement else {
            self.blend(layer, out, positions);
            return Ok(None);
        };
        let mut input = positions.clone();
        let mut weights = vec![0.0_f32; positions.len()];
        for (&i, &w) in self.mask.indices.iter().zip(&self.mask.weights) {
            weights[i as usize] = w;
        }
        self.blend(layer, out, positions);
        for (e, &d) in refinement.splits.iter().zip(&refinement.deformed) {
            let p = e.lerp(&input);
            let w = e.lerp(&weights);
            input.push(p);
            weights.push(w);
            let w = w * layer.weight;
            positions.push(if w == 1.0 { d } else { p + (d - p) * w });
        }
        if let Some(k) = first_non_finite(positions) {
            return Err(CoreError::Degenerate {
                what: format!("layer '{}'", layer.name),
                problem: format!("the refinement produced a non-finite position for vertex {k}"),
            });
        }
        Ok(Some(refinement.splits))
    }

    /// Applies the layer, with this binding, to the active vertices at positions `at` of
    /// the mask only (`at` ascending, each `< mask.len()`): each gets exactly the bits
    /// [`LayerBinding::apply`] would give it, since a per-vertex tool's output for a vertex
    /// depends only on the bind and that vertex's input. The other vertices are not touched.
    /// Returns `Ok(false)`, touching nothing, for a tool that works on the layer as a whole
    /// ([`Tool::deform_whole`]); an error, touching nothing, when an output is not finite.
    pub fn apply_at(&self, layer: &Layer, positions: &mut [Vec3], at: &[u32]) -> Result<bool> {
        let Some(bind) = &self.bind else {
            return Ok(true);
        };
        if at.is_empty() {
            return Ok(true);
        }
        if layer.tool.is_whole_layer() {
            return Ok(false);
        }
        let active: Vec<u32> = at.iter().map(|&k| self.mask.indices[k as usize]).collect();
        let mut out = zeroed(active.len());
        if let Some(k) = deform_chunks(&layer.tool, bind, positions, &active, &mut out) {
            return Err(non_finite(layer, active[k]));
        }
        for ((&k, &i), &d) in at.iter().zip(&active).zip(&out) {
            let w = self.mask.weights[k as usize] * layer.weight;
            let p = &mut positions[i as usize];
            *p = blend_one(*p, d, w);
        }
        Ok(true)
    }

    /// The tool's output for every active vertex, checked to be finite, in the first
    /// `active.len()` values of `scratch`, and a whole-layer tool's refinement. A per-vertex
    /// tool writes them in (parallel) chunks, the buffer grown with zeros when shorter; a
    /// whole-layer tool's own array takes the buffer's place.
    fn deform<'s>(
        &self,
        layer: &Layer,
        bind: &ToolBind,
        positions: &[Vec3],
        refine: bool,
        scratch: &'s mut Vec<Vec3>,
    ) -> Result<(&'s [Vec3], Option<LayerRefinement>)> {
        let active = &self.mask.indices;
        let (refinement, bad) = match layer.tool.deform_whole(bind, positions, refine) {
            Some(r) => {
                let r = r?;
                if r.out.len() != active.len() {
                    return Err(CoreError::Degenerate {
                        what: format!("layer '{}'", layer.name),
                        problem: format!(
                            "the tool returned {} positions for {} active vertices (stale \
                             bind?)",
                            r.out.len(),
                            active.len()
                        ),
                    });
                }
                let bad = first_non_finite(&r.out);
                *scratch = r.out;
                (r.refinement, bad)
            }
            None => (
                None,
                deform_per_vertex(&layer.tool, bind, positions, active, scratch),
            ),
        };
        if let Some(k) = bad {
            return Err(non_finite(layer, active[k]));
        }
        Ok((&scratch[..active.len()], refinement))
    }

    /// `p'ᵢ = pᵢ + weight · wᵢ · (D(pᵢ) − pᵢ)` over the active vertices, exactly `D(pᵢ)` when
    /// `weight · wᵢ = 1`.
    fn blend(&self, layer: &Layer, out: &[Vec3], positions: &mut [Vec3]) {
        blend_mask(layer, &self.mask, out, positions);
    }
}

/// [`LayerBinding::blend`] for the vertices of `mask`, `out` in mask order: in parallel
/// chunks for a long mask ([`for_each_at`]), else in order by [`blend_runs`].
fn blend_mask(layer: &Layer, mask: &Mask, out: &[Vec3], positions: &mut [Vec3]) {
    // Slices of the indices' length, so that `k` needs no bounds check.
    let n = mask.indices.len();
    let (weights, out, w) = (&mask.weights[..n], &out[..n], layer.weight);
    if n < PARALLEL_COPY_THRESHOLD {
        blend_runs(positions, &mask.indices, out, weights, w);
        return;
    }
    for_each_at(positions, &mask.indices, |k, p| {
        *p = blend_one(*p, out[k], weights[k] * w);
    });
}

/// Vertices [`blend_runs`] takes at a time.
const BLEND_RUN: usize = 16;

/// `positions[indices[k]]` blended with `out[k]` at weight `weights[k] · w`, for every `k` in
/// order, [`BLEND_RUN`] entries at a time. Where they are consecutive vertices (most of a
/// mask: a volume holds runs of the mesh's vertex order), the run's coordinates are blended
/// as one array of floats, each with its vertex's weight, in a loop of selects that the
/// compiler turns into vector code; other entries one by one. The same single blend per
/// entry either way, so the same bits. On the suite's million-vertex stack (5.7 M of its
/// blended vertex-layers in runs), one evaluation took 2.970 G instructions before, 2.887 G
/// with the runs (one thread, callgrind).
fn blend_runs(positions: &mut [Vec3], indices: &[u32], out: &[Vec3], weights: &[f32], w: f32) {
    let runs = indices
        .chunks(BLEND_RUN)
        .zip(out.chunks(BLEND_RUN))
        .zip(weights.chunks(BLEND_RUN));
    for ((ids, out), weights) in runs {
        // Without a branch per entry (vector compares).
        let consecutive = ids.len() == BLEND_RUN
            && (0..BLEND_RUN as u32)
                .zip(ids)
                .fold(true, |ok, (j, &i)| ok & (i == ids[0].wrapping_add(j)));
        let first = ids[0] as usize;
        match positions.get_mut(first..first + BLEND_RUN) {
            Some(run) if consecutive => {
                // The run's coordinates as one array, each with its vertex's weight: a loop
                // of selects the compiler turns into vector code.
                let mut w3 = [0.0_f32; 3 * BLEND_RUN];
                for (c, &wk) in w3.chunks_exact_mut(3).zip(weights) {
                    c.fill(wk * w);
                }
                let p: &mut [f32] = bytemuck::cast_slice_mut(run);
                let d: &[f32] = bytemuck::cast_slice(out);
                for ((p, &d), &wk) in p.iter_mut().zip(d).zip(&w3) {
                    *p = blend_one(*p, d, wk);
                }
            }
            _ => {
                for ((&i, &d), &wk) in ids.iter().zip(out).zip(weights) {
                    let p = &mut positions[i as usize];
                    *p = blend_one(*p, d, wk * w);
                }
            }
        }
    }
}

/// A per-vertex tool's output for `active` in the first `active.len()` values of `scratch`
/// (grown with zeros when shorter), in (parallel) chunks; returns the position of the first
/// non-finite one.
fn deform_per_vertex(
    tool: &Tool,
    bind: &ToolBind,
    positions: &[Vec3],
    active: &[u32],
    scratch: &mut Vec<Vec3>,
) -> Option<usize> {
    if scratch.len() < active.len() {
        *scratch = zeroed(active.len());
    }
    deform_chunks(tool, bind, positions, active, &mut scratch[..active.len()])
}

/// The error of a layer whose tool produced a non-finite position for `vertex`.
fn non_finite(layer: &Layer, vertex: u32) -> CoreError {
    CoreError::Degenerate {
        what: format!("layer '{}'", layer.name),
        problem: format!("the tool produced a non-finite position for vertex {vertex}"),
    }
}

/// The index of the first position with a non-finite coordinate. The common answer, none,
/// takes one pass without branches over the coordinates as one array of bits (each exponent
/// tested and or-ed), which the compiler turns into vector code: over the positions as
/// `Vec3`s it took about 7 instructions a position, over the flat array about 4
/// (`docs/performance.md`, thirty-first session).
fn first_non_finite(out: &[Vec3]) -> Option<usize> {
    const EXPONENT: u32 = 0x7F80_0000;
    let bits: &[u32] = bytemuck::cast_slice(out);
    let any = bits
        .iter()
        .fold(0, |a, &b| a | u32::from(b & EXPONENT == EXPONENT));
    if any == 0 {
        None
    } else {
        out.iter().position(|p| !p.is_finite())
    }
}

/// A per-vertex tool's output for `active`, in parallel chunks above
/// [`PARALLEL_THRESHOLD`] vertices; returns the position in `out` of its first non-finite
/// output (each chunk checks its own while it is in the cache).
fn deform_chunks(
    tool: &Tool,
    bind: &ToolBind,
    positions: &[Vec3],
    active: &[u32],
    out: &mut [Vec3],
) -> Option<usize> {
    if active.len() >= PARALLEL_THRESHOLD {
        out.par_chunks_mut(CHUNK)
            .zip(active.par_chunks(CHUNK))
            .enumerate()
            .filter_map(|(c, (o, a))| {
                tool.deform(bind, positions, a, o);
                first_non_finite(o).map(|j| c * CHUNK + j)
            })
            .min()
    } else {
        tool.deform(bind, positions, active, out);
        first_non_finite(out)
    }
}

/// Deforms the vertices of `mask` with `bind`, a bind of `layer`'s per-vertex tool (not a
/// whole-layer one) for them, and blends them into `positions`: what
/// [`LayerBinding::apply_with`] does, with the same bits, for a bind held elsewhere. The
/// positions are the welded vertices from `offset` on of a larger mesh (a block, see
/// `fused.rs`), and an error names a vertex by its index in the whole mesh.
pub(crate) fn apply_per_vertex(
    layer: &Layer,
    bind: &ToolBind,
    mask: &Mask,
    positions: &mut [Vec3],
    offset: u32,
    scratch: &mut Vec<Vec3>,
) -> Result<()> {
    debug_assert!(!layer.tool.is_whole_layer());
    let active = &mask.indices;
    if let Some(k) = deform_per_vertex(&layer.tool, bind, positions, active, scratch) {
        return Err(non_finite(layer, offset + active[k]));
    }
    blend_mask(layer, mask, &scratch[..active.len()], positions);
    Ok(())
}

/// What [`LayerBinding::apply_recorded`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Recorded {
    /// Input positions of the mask's vertices, in mask order.
    pub saved: Vec<Vec3>,
    /// Output positions of the mask's vertices, in mask order.
    pub written: Vec<Vec3>,
    /// The splits of a refining layer (see [`LayerBinding::apply_refining`]).
    pub splits: Option<Vec<EdgePoint>>,
}

/// The blend of one vertex: `p + w · (d − p)`, exactly `d` when `w = 1`. Generic so that a
/// run of vertices can be blended a coordinate at a time (`f32`, [`blend_runs`]) with the
/// very operations of a `Vec3` (glam's are per coordinate).
#[inline]
fn blend_one<T>(p: T, d: T, w: f32) -> T
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    if w == 1.0 { d } else { p + (d - p) * w }
}

/// A stack's result on welded vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Deformed welded positions: the rest mesh's welded vertices first, then the vertices
    /// added by refining layers, in order.
    pub positions: Vec<Vec3>,
    /// The refined surface, when a layer refined the mesh; `None` keeps the rest topology.
    pub refined: Option<RefinedMesh>,
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

    /// Evaluates the stack on `rest`. Each layer binds on the surface the layers below
    /// produced: the rest topology, or the refined one after a refining layer. Consecutive
    /// per-vertex layers (volumes without a named area; lattices, curves, axial tools,
    /// shape surfaces, and DOGME and Direct FFD with point anchors) go a block of vertices
    /// at a time through all of them (`fused.rs`), with the bits of one layer at a time.
    pub fn evaluate_surface(&self, rest: &RestMesh) -> Result<Evaluation> {
        self.validate()?;
        let mut positions = rest.welded_positions().to_vec();
        let mut refined: Option<RefinedMesh> = None;
        // The boxes of the vertex chunks, for the masks of volumes over every vertex of a
        // big mesh (built at the first such mask, then kept up to date).
        let mut bounds: Option<ChunkBounds> = None;
        // The per-vertex tools' outputs, one buffer for every layer.
        let mut scratch = Vec::new();
        let layers: Vec<&Layer> = self.layers.iter().filter(|l| !l.is_inert()).collect();
        let mut next = 0;
        while let Some(&layer) = layers.get(next) {
            let topology = refined.as_ref().map_or(rest.topology(), |r| &r.topology);
            // A run of per-vertex layers goes a block of vertices at a time (`fused.rs`).
            let run = layers[next..]
                .iter()
                .take_while(|l| fused::is_per_vertex(l))
                .count();
            if run > 0 {
                let run = &layers[next..next + run];
                let moved = fused::evaluate_run(run, &mut positions, topology)?;
                if let Some(b) = &mut bounds {
                    for span in moved {
                        b.mark_span(span);
                    }
                }
                next += run.len();
                continue;
            }
            next += 1;
            let mask = match &layer.influence {
                Some(inf) if inf.reads_chunk_bounds(positions.len()) => {
                    let b = bounds.get_or_insert_with(|| ChunkBounds::new(&positions));
                    b.refresh(&positions);
                    inf.mask_bounded(&positions, b)
                }
                Some(inf) => inf.mask(&positions),
                None => Mask::all(positions.len()),
            };
            let binding =
                LayerBinding::bind_masked(&layer.tool, Arc::new(mask), &positions, topology)?;
            if let Some(b) = &mut bounds {
                // A layer moves its active vertices only (a refinement appends vertices, and
                // the boxes are built again for the new count).
                b.mark(&binding.mask.indices);
            }
            if let Some(splits) =
                binding.apply_refining_with(layer, &mut positions, &mut scratch)?
            {
                let base = match refined.take() {
                    Some(r) => r,
                    None => RefinedMesh::unrefined(rest.mesh(), rest.topology()),
                };
                refined = Some(base.split(&splits));
            }
        }
        Ok(Evaluation { positions, refined })
    }

    /// Evaluates the stack on `rest` and returns welded deformed positions (with the
    /// vertices of refining layers appended, see [`Evaluation::positions`]).
    pub fn evaluate_welded(&self, rest: &RestMesh) -> Result<Vec<Vec3>> {
        Ok(self.evaluate_surface(rest)?.positions)
    }

    /// Evaluates the stack and returns positions and recomputed normals in the stored
    /// vertex order of `rest` (followed by the stored vertices a refining layer added, see
    /// [`Deformed::refined`]).
    pub fn evaluate(&self, rest: &RestMesh) -> Result<Deformed> {
        let ev = self.evaluate_surface(rest)?;
        Ok(match ev.refined {
            None => rest.output(&ev.positions),
            Some(r) => rest.output_refined(&ev.positions, r),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chunks::PARALLEL_COPY_THRESHOLD;

    #[test]
    fn first_non_finite_finds_the_first_nan_or_infinity_in_any_coordinate() {
        let mut v = vec![Vec3::new(1.0, -2.0, f32::MAX); 50];
        assert_eq!(first_non_finite(&v), None);
        assert_eq!(first_non_finite(&[]), None);
        v[31].z = f32::NEG_INFINITY;
        v[17].y = f32::NAN;
        assert_eq!(first_non_finite(&v), Some(17));
        v[3].x = f32::INFINITY;
        assert_eq!(first_non_finite(&v), Some(3));
        // Subnormals and zeros are finite.
        let tiny = vec![Vec3::new(f32::from_bits(1), -0.0, f32::MIN_POSITIVE); 5];
        assert_eq!(first_non_finite(&tiny), None);
    }

    /// A long, strictly ascending index list with gaps (parallel path) and its values.
    fn sparse(n: u32) -> (Vec<Vec3>, Vec<u32>) {
        let values: Vec<Vec3> = (0..3 * n).map(|i| Vec3::splat(i as f32 * 0.5)).collect();
        let indices: Vec<u32> = (0..n).map(|k| 3 * k + k % 3).collect();
        (values, indices)
    }

    /// A 200×200 sheet, an FFSD layer of half weight limited by a smooth sphere: the one-pass
    /// recorded application (parallel chunks) gives the bits of `apply_refining`, and its
    /// record holds the input and output of every active vertex.
    #[test]
    fn recorded_application_matches_the_plain_one() {
        use crate::ffsd::{ControlPoint, FfsdTool, HeightLimit};
        use crate::influence::{Falloff, Shape, Volume};
        let mesh = crate::primitives::grid(200, 200, false, |r, c| {
            Vec3::new(
                c as f32 / 100.0,
                r as f32 / 100.0,
                ((r * c) % 7) as f32 * 1e-3,
            )
        });
        let rest = RestMesh::new(mesh, "sheet").unwrap();
        let mut tool = FfsdTool::new(vec![
            ControlPoint::basic(Vec3::new(1.0, 1.0, 0.3), 0.4, 2.0, 0.3),
            ControlPoint::basic(Vec3::new(0.7, 1.2, 0.2), -0.2, 0.8, 0.2),
        ]);
        tool.height = Some(HeightLimit::Above { theta: 0.8 });
        let mut layer = Layer::new("bump", Tool::Ffsd(tool));
        layer.weight = 0.5;
        let placement = glam::Affine3A::from_translation(Vec3::new(1.0, 1.0, 0.0));
        layer.influence = Some(Influence {
            volumes: vec![Volume::new(Shape::Sphere { radius: 0.9 }, placement, "v").unwrap()],
            falloff: Falloff::Smooth,
            ..Influence::default()
        });
        let input = rest.welded_positions().to_vec();
        let binding = LayerBinding::bind(&layer, &input, rest.topology()).unwrap();
        assert!(binding.mask.len() > PARALLEL_THRESHOLD + CHUNK);
        assert!(binding.mask.weights.iter().any(|&w| w < 1.0));
        let mut plain = input.clone();
        assert!(
            binding
                .apply_refining(&layer, &mut plain)
                .unwrap()
                .is_none()
        );
        let mut recorded = input.clone();
        let rec = binding.apply_recorded(&layer, &mut recorded).unwrap();
        let bits = |p: &[Vec3]| -> Vec<[u32; 3]> {
            p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
        };
        assert_eq!(bits(&recorded), bits(&plain));
        assert!(rec.splits.is_none());
        let idx = &binding.mask.indices;
        assert_eq!(bits(&rec.saved), bits(&gather_at(&input, idx)));
        assert_eq!(bits(&rec.written), bits(&gather_at(&plain, idx)));
        assert!(rec.saved.iter().zip(&rec.written).any(|(a, b)| a != b));
        // Through a scratch buffer left by a bigger layer (longer than the mask, every value
        // not finite), or one too short: the same bits, and the buffer keeps its length or
        // grows to the mask's.
        for len in [binding.mask.len() + 1000, 17] {
            let mut scratch = vec![Vec3::NAN; len];
            let mut through = input.clone();
            binding
                .apply_with(&layer, &mut through, &mut scratch)
                .unwrap();
            assert_eq!(bits(&through), bits(&plain), "scratch of {len}");
            assert_eq!(scratch.len(), len.max(binding.mask.len()));
        }
    }

    /// A per-vertex layer over a parallel number of vertices, two of whose inputs are not
    /// finite (in different chunks, the later chunk's first): the error names the first.
    #[test]
    fn a_non_finite_output_is_named_by_its_first_vertex_on_the_parallel_path() {
        use crate::ffsd::{ControlPoint, FfsdTool};
        let mesh = crate::primitives::grid(200, 200, false, |r, c| {
            Vec3::new(c as f32 / 100.0, r as f32 / 100.0, 0.0)
        });
        let rest = RestMesh::new(mesh, "sheet").unwrap();
        let tool = FfsdTool::new(vec![ControlPoint::basic(
            Vec3::new(1.0, 1.0, 0.3),
            0.4,
            2.0,
            0.3,
        )]);
        let layer = Layer::new("bump", Tool::Ffsd(tool));
        let mut input = rest.welded_positions().to_vec();
        let binding = LayerBinding::bind(&layer, &input, rest.topology()).unwrap();
        assert!(binding.mask.len() > PARALLEL_THRESHOLD + CHUNK);
        let (early, late) = (2 * CHUNK + 100, 5 * CHUNK + 3);
        input[late].x = f32::NAN;
        input[early].z = f32::INFINITY;
        for result in [
            binding.apply(&layer, &mut input.clone()),
            binding
                .apply_refining(&layer, &mut input.clone())
                .map(|_| ()),
        ] {
            let message = result.unwrap_err().to_string();
            assert!(message.contains(&format!("vertex {early}")), "{message}");
        }
    }

    #[test]
    fn blend_runs_give_the_per_entry_blends_bits() {
        // Runs of 16 consecutive vertices at several alignments, runs broken by one gap, a
        // repeated vertex (each entry blended in turn), a run reaching the end of the
        // positions, a short last chunk of consecutive vertices; weights of 1 (exactly `d`)
        // and fractions.
        let positions: Vec<Vec3> = (0..200)
            .map(|i| Vec3::new(i as f32 * 0.37, (i as f32 * 0.11).sin(), -(i as f32) * 0.05))
            .collect();
        let mut indices: Vec<u32> = (3..35).collect();
        indices.extend((40..56).filter(|&i| i != 47));
        indices.extend([60, 60, 61]);
        indices.extend(64..80);
        indices.extend(184..200);
        indices.extend([2, 190, 7]);
        // Entries 85 to 95, then a short last chunk of consecutive vertices.
        indices.extend(110..121);
        indices.extend(100..105);
        let out: Vec<Vec3> = (0..indices.len())
            .map(|k| Vec3::new(k as f32, 1.0 - k as f32 * 0.3, 0.25))
            .collect();
        let weights: Vec<f32> = (0..indices.len())
            .map(|k| if k % 5 == 0 { 1.0 } else { k as f32 / 97.0 })
            .collect();
        for w in [1.0, 0.3] {
            let mut expected = positions.clone();
            for (k, &i) in indices.iter().enumerate() {
                let p = &mut expected[i as usize];
                *p = blend_one(*p, out[k], weights[k] * w);
            }
            let mut runs = positions.clone();
            blend_runs(&mut runs, &indices, &out, &weights, w);
            let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&runs), bits(&expected), "weight {w}");
        }
    }

    #[test]
    fn parallel_scatter_and_gather_match_the_serial_loops() {
        let n = (PARALLEL_COPY_THRESHOLD + CHUNK + 17) as u32;
        let (values, indices) = sparse(n);
        let mut serial = values.clone();
        for (k, &i) in indices.iter().enumerate() {
            serial[i as usize] = serial[i as usize] * 3.0 + Vec3::splat(k as f32);
        }
        let mut parallel = values.clone();
        for_each_at(&mut parallel, &indices, |k, p| {
            *p = *p * 3.0 + Vec3::splat(k as f32);
        });
        assert_eq!(parallel, serial);
        let gathered = gather_at(&values, &indices);
        assert_eq!(gathered.len(), indices.len());
        assert!(
            indices
                .iter()
                .zip(&gathered)
                .all(|(&i, &g)| values[i as usize] == g)
        );
        // Not ascending: done in order, so a repeated index sees both calls.
        let mut repeated = vec![0_u32; 2];
        let twice: Vec<u32> = (0..PARALLEL_COPY_THRESHOLD as u32).map(|k| k % 2).collect();
        for_each_at(&mut repeated, &twice, |_, c| *c += 1);
        assert_eq!(repeated, vec![PARALLEL_COPY_THRESHOLD as u32 / 2; 2]);
    }
}
