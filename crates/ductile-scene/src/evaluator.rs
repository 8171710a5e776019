//! Incremental evaluation of one mesh's stack, for interactive editing (the Studio).
//!
//! [`MeshEvaluator`] keeps, between two calls of [`MeshEvaluator::update`]:
//!
//! * every area's welded vertex set, keyed by name and definition, so that an unchanged area
//!   is never resolved again;
//! * the resolved layers of the last evaluation, and for each layer that was not inert (see
//!   [`Layer::is_inert`]) a *stage*: its [`LayerBinding`], and the welded positions of its
//!   active vertices before (`saved`) and after (`written`) it was applied;
//! * the welded output positions and the stored-order [`Deformed`] output.
//!
//! An update resolves the stack again (cheap: no vertex is visited), finds the first
//! non-inert layer that differs from the cached one, rolls the positions back to that
//! layer's input by writing back the `saved` values of every stage from the top down, and
//! evaluates upwards from there. A later layer whose resolved value is unchanged and whose
//! input is unchanged on every vertex it reads (see below) keeps its binding, and its
//! `written` values are put back without deforming anything. To know which inputs changed,
//! the update tracks a set `D` of welded vertices where the new positions may differ from the
//! old ones at the same point of the stack (exact bitwise comparisons of `saved` and
//! `written`; details in `docs/algorithms/evaluation.md`).
//!
//! A later layer bound again because its input moved copies from its old binding what the
//! moved vertices do not change: the volume weights of the other vertices, and the
//! per-vertex binds of curve, axial and shape-surface tools. Such a layer, and an FFSD layer
//! whose new bind has the same bits as the old one, is *refreshed*: only its active vertices
//! in `D` are deformed again, the others get their old output bits back.
//!
//! A changed layer whose tool must be bound again (its rest state changed: a lattice's
//! control points, an FFSD point) but whose influence, area and masked input are unchanged
//! keeps its *mask*: the volume weights are not computed again (on a million vertices they
//! cost milliseconds), only the tool is bound within the old mask.
//!
//! A layer reads the positions of its *domain*: the vertices of its area when it has one
//! and its tool reads only the active vertices (FFSD, lattice, curve, axial and shape
//! surface tools), every vertex otherwise (no area, or DOGME / Direct FFD constraints
//! anchored at vertices, sketch tools).
//!
//! Finally only the vertices whose output position changed (bitwise) are written to the
//! stored-order output, and only the normals of the vertices of the triangles around them
//! are recomputed — summing the same face normals in the same order as
//! [`smooth_normals`](ductile_core::normals::smooth_normals), so the result is bit-identical
//! to [`Document::evaluate`].
//!
//! A stack in which a layer refines the mesh (a sketch tool with adaptive refinement) is
//! evaluated in full by [`Stack::evaluate`] whenever it changes.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};

use glam::Vec3;

use ductile_core::chunks::{CHUNK, PARALLEL_THRESHOLD, Reuse, map_chunks_at, scatter_at};
use ductile_core::influence::Mask;
use ductile_core::mesh::{Deformed, RestMesh, Topology};
use ductile_core::normals::face_normal;
use ductile_core::stack::{Layer, LayerBinding, Recorded, Stack};
use ductile_core::tool::{Tool, ToolBind};
use rayon::prelude::*;

use crate::document::{Area, Document};
use crate::error::Result;
use crate::resolve::resolve_area;

/// Above this fraction (`1 / OUTPUT_FULL_DIVISOR`) of candidate welded vertices the output is
/// patched by parallel sweeps over the blocks of triangles and stored vertices that hold a
/// change rather than by following each changed vertex (both give the same bits). Measured on
/// the head split 5×5 (221k vertices), with full sweeps: one nose slider moves ~30 % of the
/// vertices and took 4.5 ms with 3, 2.9 ms with 6 to 16. Since the sweeps skip clean blocks,
/// 32: the FFSD drag on the nose (`drag/ffsd-point/head-221k` of the `studio` bench) went
/// 3.96 / 4.25 → 2.98 / 2.43 ms against 8, the other edits there within the host's noise.
/// Meshes under [`PARALLEL_THRESHOLD`] vertices are always patched vertex by vertex (waking
/// the thread pool costs more there).
const OUTPUT_FULL_DIVISOR: usize = 32;

/// On a mesh of [`PARALLEL_THRESHOLD`] vertices or more with a valid face cache, when more
/// than this fraction (`1 / OUTPUT_DENSE_DIVISOR`) of the welded vertices are candidates and
/// a parallel count finds more than that fraction moved, every normal is computed again, as
/// after a full evaluation (the same bits), rather than swept for: the sweeps' stamps and
/// block flags then cost more than the work they skip. Measured on the head split 5×5 (221k
/// vertices) with a Bézier curve layer bound again on the whole head (`rebind/bezier-curve`
/// of the `authoring` bench): the output patch 7.5–10.9 → 3.7–5.1 ms.
const OUTPUT_DENSE_DIVISOR: usize = 2;

/// What one [`MeshEvaluator::update`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Update {
    /// True when [`MeshEvaluator::deformed`] differs from what it was before the call (the
    /// first evaluation always counts as a change).
    pub changed: bool,
    /// Stack index of the first layer that was evaluated again; the stack's length when no
    /// layer was (nothing changed, or only layers at the top were removed or made inert).
    pub first_layer: usize,
    /// How many layers were bound and deformed again (the others kept their binding, or are
    /// inert).
    pub layers_evaluated: usize,
}

/// One layer as resolved from the document: the core layer without its area's vertex set
/// (`layer.influence.area` is `None`) and that set, shared with the area cache.
#[derive(Debug, Clone, PartialEq)]
struct Resolved {
    layer: Layer,
    area: Option<Arc<Vec<u32>>>,
}

impl Resolved {
    /// The complete core layer (with its area's vertices).
    fn full(&self) -> Layer {
        let mut layer = self.layer.clone();
        if let (Some(inf), Some(area)) = (&mut layer.influence, &self.area) {
            inf.area = Some(area.as_ref().clone());
        }
        layer
    }

    /// The layer's mask on `positions` (its input) and its tool's bind: what
    /// [`LayerBinding::bind`] gives for [`Resolved::full`], without copying the area twice.
    ///
    /// `previous` is this layer's binding on an earlier input and the vertices where that
    /// input may differ from `positions` (`D`). A mask that does not depend on the input
    /// positions (no volumes: the area, or every vertex, with weight 1) is shared from it
    /// when it covers the same vertex count; a volume mask weighs only the stale vertices
    /// again ([`Influence::mask_reusing`]); the tool copies the per-vertex bind of the
    /// others ([`LayerBinding::bind_masked_reusing`]). The same bits either way.
    fn bind(
        &self,
        positions: &[Vec3],
        topology: &Topology,
        previous: Option<Reuse<'_, LayerBinding>>,
    ) -> Result<LayerBinding> {
        let n = positions.len();
        let fixed = self
            .layer
            .influence
            .as_ref()
            .is_none_or(|inf| inf.volumes.is_empty());
        let same_count = |m: &Mask| match &self.area {
            Some(_) => m.indices.last().is_none_or(|&i| (i as usize) < n),
            None => m.len() == n,
        };
        let area = self.area.as_deref().map(Vec::as_slice);
        let mask = match (previous, &self.layer.influence) {
            (Some(p), _) if fixed && same_count(&p.bind.mask) => Arc::clone(&p.bind.mask),
            (Some(p), Some(inf)) if !fixed => {
                Arc::new(inf.mask_reusing(area, positions, &p.bind.mask, p.stale))
            }
            (_, Some(inf)) => Arc::new(inf.mask_in(area, positions)),
            (_, None) => Arc::new(Mask::all(n)),
        };
        Ok(LayerBinding::bind_masked_reusing(
            &self.layer.tool,
            mask,
            positions,
            topology,
            previous,
        )?)
    }

    /// True when the layer's mask on an input is the mask `other` has on the same input:
    /// the same layer, influence and area (the tools may differ).
    fn same_mask(&self, other: &Resolved) -> bool {
        let same_area = match (&self.area, &other.area) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b) || a == b,
            (None, None) => true,
            _ => false,
        };
        same_area
            && self.layer.name == other.layer.name
            && self.layer.enabled == other.layer.enabled
            && self.layer.influence == other.layer.influence
    }

    /// The welded vertices whose input positions the layer's mask reads: its area's, or
    /// `None` for every vertex.
    fn mask_domain(&self) -> Option<&[u32]> {
        self.area.as_deref().map(Vec::as_slice)
    }

    /// The welded vertices whose input positions the layer's mask, bind and deformation
    /// read; `None` for every vertex.
    fn domain(&self) -> Option<&[u32]> {
        if reads_only_active(&self.layer.tool) {
            self.area.as_deref().map(Vec::as_slice)
        } else {
            None
        }
    }
}

/// True for tools whose bind and deformation read the input positions of the layer's active
/// vertices only (checked against each tool's `bind` and `deform`); DOGME and Direct FFD
/// constraints may be anchored at any vertex and sketch tools flood-fill the whole surface.
fn reads_only_active(tool: &Tool) -> bool {
    matches!(
        tool,
        Tool::Ffsd(_) | Tool::Lattice(_) | Tool::Curve(_) | Tool::Axial(_) | Tool::ShapeSurface(_)
    )
}

/// A non-inert layer of the last evaluation.
#[derive(Debug)]
struct Stage {
    /// Index of the layer in the stack.
    index: usize,
    /// The layer as resolved.
    resolved: Resolved,
    /// Its mask and bind on its input.
    binding: LayerBinding,
    /// Input positions of `binding.mask.indices`.
    saved: Vec<Vec3>,
    /// Output positions of `binding.mask.indices`.
    written: Vec<Vec3>,
}

impl Stage {
    fn indices(&self) -> &[u32] {
        &self.binding.mask.indices
    }
}

/// What the cached stages and positions describe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Nothing usable (before the first evaluation, or after a failed one).
    Empty,
    /// `stages` and `positions` describe the last evaluation of `layers`.
    Incremental,
    /// The last evaluation refined the mesh; only `layers` and `output` are kept.
    Refined,
}

/// The set `D` of welded vertices whose positions may differ between the new and the old
/// evaluation at the current point of the stack.
#[derive(Debug, Default)]
struct Dirty {
    flag: Vec<bool>,
    list: Vec<u32>,
    count: usize,
}

impl Dirty {
    fn reset(&mut self, n: usize) {
        self.flag.clear();
        self.flag.resize(n, false);
        self.list.clear();
        self.count = 0;
    }

    fn contains(&self, v: u32) -> bool {
        self.flag.get(v as usize).copied().unwrap_or(false)
    }

    fn insert(&mut self, v: u32) {
        if let Some(f) = self.flag.get_mut(v as usize)
            && !*f
        {
            *f = true;
            self.list.push(v);
            self.count += 1;
        }
    }

    fn remove(&mut self, v: u32) {
        if let Some(f) = self.flag.get_mut(v as usize)
            && *f
        {
            *f = false;
            self.count -= 1;
        }
    }

    /// True when some vertex of `domain` (`None`: every vertex) is in the set.
    fn intersects(&self, domain: Option<&[u32]>) -> bool {
        if self.count == 0 {
            return false;
        }
        match domain {
            None => true,
            // A binary search per member beats a scan of the area's flags only when the
            // set is much smaller than the area.
            Some(area) if self.list.len() * 16 < area.len() => self
                .list
                .iter()
                .any(|&v| self.contains(v) && area.binary_search(&v).is_ok()),
            Some(area) => area.iter().any(|&v| self.contains(v)),
        }
    }

    /// The positions `k` (ascending) of the members of `D` in the sorted list `indices`.
    fn positions_in(&self, indices: &[u32]) -> Vec<u32> {
        if self.count == 0 {
            return Vec::new();
        }
        if self.list.len() * 16 < indices.len() {
            let mut at: Vec<u32> = self
                .list
                .iter()
                .filter(|&&v| self.contains(v))
                .filter_map(|v| indices.binary_search(v).ok().map(|k| k as u32))
                .collect();
            at.sort_unstable();
            at.dedup();
            at
        } else {
            indices
                .iter()
                .enumerate()
                .filter(|&(_, &v)| self.contains(v))
                .map(|(k, _)| k as u32)
                .collect()
        }
    }

    /// The members, once each, and an empty set.
    fn drain(&mut self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.count);
        for v in std::mem::take(&mut self.list) {
            if let Some(f) = self.flag.get_mut(v as usize)
                && *f
            {
                *f = false;
                out.push(v);
            }
        }
        self.count = 0;
        out
    }

    /// The old evaluation went through `stage` while the new one did not (yet): a vertex
    /// not in `D` had the stage's input position in both, so it now differs exactly when
    /// the stage moved it.
    fn advance_old(&mut self, stage: &Stage) {
        self.advance(stage);
    }

    /// The new evaluation went through `stage` while the old one did not: same rule.
    fn advance_new(&mut self, stage: &Stage) {
        self.advance(stage);
    }

    fn advance(&mut self, stage: &Stage) {
        for ((&v, &a), &b) in stage.indices().iter().zip(&stage.saved).zip(&stage.written) {
            if !self.contains(v) && !same_bits(a, b) {
                self.insert(v);
            }
        }
    }

    /// [`Dirty::advance_old`], [`Dirty::advance_new`] and [`Dirty::settle_common`] in one
    /// pass, for two stages with the same active vertices: every vertex they touch is
    /// settled, so only the last rule's outcome remains.
    fn settle_same(&mut self, old: &Stage, new: &Stage) {
        self.settle_written(old.indices(), &old.written, &new.written);
    }

    /// [`Dirty::settle_same`] on the active vertices `idx` of both stages and their old
    /// (`a`) and new (`b`) outputs.
    fn settle_written(&mut self, idx: &[u32], a: &[Vec3], b: &[Vec3]) {
        if idx.len() < PARALLEL_THRESHOLD || self.flag.len() <= idx[idx.len() - 1] as usize {
            for ((&v, &a), &b) in idx.iter().zip(a).zip(b) {
                if same_bits(a, b) {
                    self.remove(v);
                } else {
                    self.insert(v);
                }
            }
            return;
        }
        // In parallel chunks (each owns the flags of its vertices): the change of the count
        // and the vertices added, merged in chunk order.
        let parts = map_chunks_at(&mut self.flag, idx, |k0, chunk, flags| {
            let mut tally = Tally::default();
            for (j, &v) in chunk.iter().enumerate() {
                tally.mark(flags.get(v), v, !same_bits(a[k0 + j], b[k0 + j]), true);
            }
            tally
        });
        self.absorb(parts);
    }

    /// Takes the changes counted by parallel chunks, in chunk order.
    fn absorb(&mut self, parts: Vec<Tally>) {
        for Tally { removed, added } in parts {
            self.count = self.count - removed + added.len();
            self.list.extend(added);
        }
    }

    /// [`Dirty::advance_old`], [`Dirty::advance_new`] and [`Dirty::settle_common`] in one
    /// merge of the two stages' active vertices (in parallel chunks of `new`'s, each owning
    /// the flags of its vertices): a vertex active in both is settled by the two outputs, one
    /// active in one stage only is added when that stage moved it. The flags, the count and
    /// the members are those of the three passes; the list only lacks the entries they would
    /// have added and removed again.
    fn settle_merged(&mut self, old: &Stage, new: &Stage) {
        let (a, b) = (old.indices(), new.indices());
        let n = self.flag.len();
        if [a, b]
            .iter()
            .any(|s| s.last().is_some_and(|&v| v as usize >= n))
        {
            self.advance_old(old);
            self.advance_new(new);
            self.settle_common(old, new);
            return;
        }
        let parts = map_chunks_at(&mut self.flag, b, |k0, chunk, flags| {
            // The chunk owns the vertices from its first (0 for the first chunk) to the
            // next chunk's first (`n` for the last).
            let lo = if k0 == 0 { 0 } else { b[k0] };
            let hi = b.get(k0 + chunk.len()).map_or(n, |&v| v as usize);
            let i1 = a.partition_point(|&v| (v as usize) < hi);
            let mut i = a[..i1].partition_point(|&v| v < lo);
            let mut tally = Tally::default();
            let mut mark = |v: u32, differs: bool, settles: bool| {
                tally.mark(flags.get(v), v, differs, settles);
            };
            let mut j = 0;
            while i < i1 || j < chunk.len() {
                let k = k0 + j;
                match (a[..i1].get(i), chunk.get(j)) {
                    (Some(&u), Some(&v)) if u == v => {
                        mark(u, !same_bits(old.written[i], new.written[k]), true);
                        i += 1;
                        j += 1;
                    }
                    (Some(&u), v) if v.is_none_or(|&v| u < v) => {
                        mark(u, !same_bits(old.saved[i], old.written[i]), false);
                        i += 1;
                    }
                    (_, Some(&v)) => {
                        mark(v, !same_bits(new.saved[k], new.written[k]), false);
                        j += 1;
                    }
                    // Not reached: the loop runs while either list has entries left.
                    (_, None) => break,
                }
            }
            tally
        });
        self.absorb(parts);
    }

    /// Both evaluations went through a stage (`old`, `new`) after [`Dirty::advance_old`]
    /// and [`Dirty::advance_new`]: a vertex active in both now holds each stage's output, so
    /// it differs exactly when those differ.
    fn settle_common(&mut self, old: &Stage, new: &Stage) {
        let (a, b) = (old.indices(), new.indices());
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            match a[i].cmp(&b[j]) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    if same_bits(old.written[i], new.written[j]) {
                        self.remove(a[i]);
                    } else {
                        self.insert(a[i]);
                    }
                    i += 1;
                    j += 1;
                }
            }
        }
    }
}

/// The changes a parallel chunk made to the flags of [`Dirty`]: how many it cleared and the
/// vertices it set.
#[derive(Default)]
struct Tally {
    removed: usize,
    added: Vec<u32>,
}

impl Tally {
    /// Sets flag `f` of vertex `v` when `differs`; otherwise clears it when `settles`.
    fn mark(&mut self, f: &mut bool, v: u32, differs: bool, settles: bool) {
        if differs {
            if !*f {
                *f = true;
                self.added.push(v);
            }
        } else if settles && *f {
            *f = false;
            self.removed += 1;
        }
    }
}

/// Bitwise equality of two positions.
fn same_bits(a: Vec3, b: Vec3) -> bool {
    a.x.to_bits() == b.x.to_bits()
        && a.y.to_bits() == b.y.to_bits()
        && a.z.to_bits() == b.z.to_bits()
}

/// Welded vertex → incident triangles (ascending) and welded vertex → stored copies, as
/// compressed rows.
#[derive(Debug)]
struct Links {
    tri_offsets: Vec<u32>,
    tris: Vec<u32>,
    copy_offsets: Vec<u32>,
    copies: Vec<u32>,
    tri_mark: Vec<bool>,
    /// The current patch's stamp (1 to 255): a welded vertex is moved, or around a moved
    /// one, in this patch when its entry of `moved` or `around` holds it, so nothing is
    /// cleared after a patch (only all of them when the stamp wraps).
    stamp: u8,
    /// Welded vertices that moved (stamped in parallel by the block sweeps).
    moved: Vec<AtomicU8>,
    /// Welded vertices whose normal must be summed again (stamped, in parallel by the block
    /// sweeps).
    around: Vec<AtomicU8>,
    /// Blocks of [`BLOCK`] triangles that hold a triangle with a moved corner (set in
    /// parallel, cleared by the sweep that reads them).
    tri_blocks: Vec<AtomicBool>,
    /// Blocks of [`BLOCK`] stored vertices that hold a copy of a moved vertex or of a corner
    /// of such a triangle (set in parallel, cleared by the sweep that reads them).
    stored_blocks: Vec<AtomicBool>,
}

/// Triangles and stored vertices are swept in blocks of this many; a block holding nothing
/// that changed is skipped whole. Small enough that a lattice's region of a mesh whose
/// vertices are ordered face by face (as subdivision and most exporters order them) leaves
/// most blocks clean, large enough that the block flags stay in the first-level cache.
const BLOCK: usize = 64;

/// `n` cleared flags.
fn flags(n: usize) -> Vec<AtomicBool> {
    (0..n).map(|_| AtomicBool::new(false)).collect()
}

/// `n` stamps that hold no sweep's stamp.
fn stamps(n: usize) -> Vec<AtomicU8> {
    (0..n).map(|_| AtomicU8::new(0)).collect()
}

impl Links {
    fn new(topology: &Topology) -> Self {
        let n = topology.vertex_count();
        let (tri_offsets, tris) = rows(
            n,
            topology
                .triangles
                .iter()
                .enumerate()
                .flat_map(|(t, tri)| tri.iter().map(move |&v| (v, t as u32))),
        );
        let (copy_offsets, copies) = rows(
            n,
            topology
                .weld
                .iter()
                .enumerate()
                .map(|(s, &w)| (w, s as u32)),
        );
        Self {
            tri_offsets,
            tris,
            copy_offsets,
            copies,
            tri_mark: vec![false; topology.triangles.len()],
            stamp: 0,
            moved: stamps(n),
            around: stamps(n),
            tri_blocks: flags(topology.triangles.len().div_ceil(BLOCK)),
            stored_blocks: flags(topology.stored_count().div_ceil(BLOCK)),
        }
    }

    fn triangles_of(&self, v: u32) -> &[u32] {
        row(&self.tri_offsets, &self.tris, v)
    }

    fn copies_of(&self, v: u32) -> &[u32] {
        row(&self.copy_offsets, &self.copies, v)
    }

    /// A stamp that no entry of `moved` or `around` holds yet, for a new block sweep.
    fn next_stamp(&mut self) -> u8 {
        if self.stamp == u8::MAX {
            for a in self.moved.iter_mut().chain(self.around.iter_mut()) {
                *a.get_mut() = 0;
            }
            self.stamp = 0;
        }
        self.stamp += 1;
        self.stamp
    }

    /// Flags the blocks of `v`'s triangles and stored copies for the block sweeps.
    fn flag_blocks(&self, v: u32) {
        for &t in self.triangles_of(v) {
            self.tri_blocks[t as usize / BLOCK].store(true, Ordering::Relaxed);
        }
        for &s in self.copies_of(v) {
            self.stored_blocks[s as usize / BLOCK].store(true, Ordering::Relaxed);
        }
    }
}

/// Row `v` of compressed rows.
fn row<'a>(offsets: &[u32], values: &'a [u32], v: u32) -> &'a [u32] {
    let v = v as usize;
    &values[offsets[v] as usize..offsets[v + 1] as usize]
}

/// Compressed rows of `(row, value)` pairs, each row keeping the pairs' order.
fn rows(n: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = vec![0_u32; n + 1];
    for (r, _) in pairs.clone() {
        offsets[r as usize + 1] += 1;
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut next = offsets.clone();
    let mut values = vec![0_u32; offsets[n] as usize];
    for (r, v) in pairs {
        let slot = &mut next[r as usize];
        values[*slot as usize] = v;
        *slot += 1;
    }
    (offsets, values)
}

/// The smooth normal of welded vertex `v`, exactly as
/// [`smooth_normals`](ductile_core::normals::smooth_normals) computes it: the face normals
/// `(b − a) × (c − a)` of its triangles summed in triangle order from zero, normalised
/// (`Vec3::Z` when the sum is zero).
fn vertex_normal(v: u32, links: &Links, faces: &[Vec3]) -> Vec3 {
    let mut acc = Vec3::ZERO;
    for &t in links.triangles_of(v) {
        acc += faces[t as usize];
    }
    acc.try_normalize().unwrap_or(Vec3::Z)
}

/// The whole output again, in parallel: every face normal into `faces` and every welded
/// vertex's normal into `normals` (both resized to fit) — the face normals once, then each
/// vertex's sum over its triangles in ascending order (the same additions as
/// `smooth_normals`) — then every stored vertex of `out` (see [`write_stored`]). The caller
/// keeps both buffers between updates: fresh ones of this size would cost a page fault every
/// 4 KiB.
fn rewrite_all(
    out: &mut Deformed,
    topology: &Topology,
    links: &Links,
    positions: &[Vec3],
    faces: &mut Vec<Vec3>,
    normals: &mut Vec<Vec3>,
) {
    let triangles = &topology.triangles;
    faces.resize(triangles.len(), Vec3::ZERO);
    faces
        .par_iter_mut()
        .zip(triangles.par_iter())
        .with_min_len(CHUNK)
        .for_each(|(f, &t)| *f = face_normal(t, positions));
    let faces = &*faces;
    normals.resize(positions.len(), Vec3::ZERO);
    normals
        .par_iter_mut()
        .enumerate()
        .with_min_len(CHUNK)
        .for_each(|(v, n)| *n = vertex_normal(v as u32, links, faces));
    write_stored(out, &topology.weld, positions, normals);
}

/// Every stored vertex `s` of `out` takes the welded position and normal of `weld[s]` (in
/// parallel chunks).
fn write_stored(out: &mut Deformed, weld: &[u32], positions: &[Vec3], normals: &[Vec3]) {
    out.positions
        .par_iter_mut()
        .zip(out.normals.par_iter_mut())
        .zip(weld.par_iter())
        .with_min_len(CHUNK)
        .for_each(|((p, n), &w)| {
            *p = positions[w as usize];
            *n = normals[w as usize];
        });
}

/// Caches the evaluation of one mesh node's stack and brings it up to date with a
/// [`Document`] incrementally (see the module documentation). Its results are bit-identical
/// to [`Document::evaluate`].
///
/// The evaluator is `Send`: it may be moved into a background task and back.
#[derive(Debug)]
pub struct MeshEvaluator {
    mesh: String,
    rest: RestMesh,
    /// Area name → (definition, welded vertices).
    areas: HashMap<String, (Area, Arc<Vec<u32>>)>,
    area_resolutions: usize,
    /// Every layer of the stack at the last successful evaluation.
    layers: Vec<Resolved>,
    mode: Mode,
    /// Non-inert layers of `layers`, bottom first (in [`Mode::Incremental`]).
    stages: Vec<Stage>,
    /// Welded output positions (in [`Mode::Incremental`]).
    positions: Vec<Vec3>,
    output: Option<Deformed>,
    links: Option<Links>,
    /// Face normals `(b − a) × (c − a)` of the output's welded triangles; empty when not
    /// known (they are rebuilt with the next full output).
    faces: Vec<Vec3>,
    /// Scratch space for the welded normals of a full output rebuild.
    normals: Vec<Vec3>,
    dirty: Dirty,
    /// How many stages were refreshed (see [`refresh`]) since the evaluator was made.
    refreshed: usize,
    /// How many layer bindings were made since the evaluator was made.
    binds: usize,
}

impl MeshEvaluator {
    /// An evaluator for mesh node `mesh`, whose rest mesh is `rest` (a [`RestMesh`] is
    /// already a shared, cheaply cloned handle). Nothing is evaluated before the first
    /// [`MeshEvaluator::update`].
    #[must_use]
    pub fn new(mesh: &str, rest: RestMesh) -> Self {
        Self {
            mesh: mesh.to_owned(),
            rest,
            areas: HashMap::new(),
            area_resolutions: 0,
            layers: Vec::new(),
            mode: Mode::Empty,
            stages: Vec::new(),
            positions: Vec::new(),
            output: None,
            links: None,
            faces: Vec::new(),
            normals: Vec::new(),
            dirty: Dirty::default(),
            refreshed: 0,
            binds: 0,
        }
    }

    /// How many layer bindings (mask and tool bind: for a sketch tool its region of
    /// interest, skinning and Eq. 9 factorisation) were made since the evaluator was made.
    /// A layer whose tool changed only in its deformed state (a sketch target, a lattice's
    /// control points, an axis's deformed points), on an unchanged input, keeps its binding.
    #[must_use]
    pub fn binds(&self) -> usize {
        self.binds
    }

    /// The mesh node's name.
    #[must_use]
    pub fn mesh(&self) -> &str {
        &self.mesh
    }

    /// The rest mesh.
    #[must_use]
    pub fn rest(&self) -> &RestMesh {
        &self.rest
    }

    /// How many times an area was resolved against the rest mesh since the evaluator was
    /// made (an area is resolved again only when its definition changes).
    #[must_use]
    pub fn area_resolutions(&self) -> usize {
        self.area_resolutions
    }

    /// The deformed mesh of the last successful update, in stored vertex order with
    /// recomputed normals (as [`Document::evaluate`] returns it); `None` before the first.
    /// After a failed update it still holds the last good result.
    #[must_use]
    pub fn deformed(&self) -> Option<&Deformed> {
        self.output.as_ref()
    }

    /// Brings the evaluation up to date with `doc`: resolves the mesh's stack (cached
    /// areas), and evaluates again from the first non-inert layer that changed, keeping
    /// the binding of every later layer whose input it reads is unchanged. Returns what it
    /// did; `changed` is false, and nothing is evaluated, when nothing the mesh depends on
    /// changed.
    ///
    /// # Errors
    /// The errors of [`Document::evaluate`]: unknown names, invalid layers, failed binds.
    /// After an error the previous result stays available and the next update evaluates
    /// the whole stack again.
    pub fn update(&mut self, doc: &Document) -> Result<Update> {
        let layers = self.resolve(doc)?;
        for (i, r) in layers.iter().enumerate() {
            if self.layers.get(i) != Some(r) {
                r.layer.validate()?;
            }
        }
        let old_chain: Vec<usize> = non_inert(&self.layers);
        let new_chain: Vec<usize> = non_inert(&layers);
        let k = (0..)
            .find(|&j| {
                j >= old_chain.len()
                    || j >= new_chain.len()
                    || self.layers[old_chain[j]] != layers[new_chain[j]]
            })
            .unwrap_or(0);
        let first_layer = new_chain.get(k).copied().unwrap_or(layers.len());
        if self.mode != Mode::Empty && k == old_chain.len() && k == new_chain.len() {
            for (stage, &index) in self.stages.iter_mut().zip(&new_chain) {
                stage.index = index;
            }
            self.layers = layers;
            return Ok(Update {
                changed: false,
                first_layer,
                layers_evaluated: 0,
            });
        }
        let result = match self.mode {
            Mode::Incremental => self.evaluate_from(k, &layers, &new_chain),
            Mode::Empty | Mode::Refined => self.evaluate_all(&layers, &new_chain),
        };
        match result {
            Ok((layers_evaluated, changed)) => {
                self.layers = layers;
                Ok(Update {
                    changed,
                    first_layer: if self.mode == Mode::Refined {
                        0
                    } else {
                        first_layer
                    },
                    layers_evaluated,
                })
            }
            Err(e) => {
                self.mode = Mode::Empty;
                self.layers.clear();
                self.stages.clear();
                self.positions.clear();
                Err(e)
            }
        }
    }

    /// The heat-map weight of stack layer `k` per stored vertex: the layer's mask weight
    /// times its layer weight, 0 outside its mask. A disabled layer or one of weight 0 gives
    /// zeros; a layer whose tool is the identity (a macro at 0) gives the mask it would have
    /// on its input. `None` when `k` is out of range, before the first evaluation, after a
    /// failed one, or when a layer refined the mesh (the layers below the refinement see
    /// another vertex set than the output).
    #[must_use]
    pub fn layer_weights(&self, k: usize) -> Option<Vec<f32>> {
        if self.mode != Mode::Incremental {
            return None;
        }
        let r = self.layers.get(k)?;
        let mut w = vec![0.0_f32; self.positions.len()];
        let mask = match self.stages.iter().find(|s| s.index == k) {
            Some(stage) => Some(Mask::clone(&stage.binding.mask)),
            None if r.layer.enabled && r.layer.weight != 0.0 => {
                let input = self.input_of(k);
                Some(match &r.full().influence {
                    Some(inf) => inf.mask(&input),
                    None => Mask::all(input.len()),
                })
            }
            None => None,
        };
        if let Some(mask) = mask {
            for (&i, &m) in mask.indices.iter().zip(&mask.weights) {
                w[i as usize] = m * r.layer.weight;
            }
        }
        Some(self.rest.topology().scatter(&w))
    }

    /// The displacement `|output − input|` of stack layer `k` per stored vertex (zeros for
    /// an inert layer). `None` as for [`MeshEvaluator::layer_weights`].
    #[must_use]
    pub fn layer_displacement(&self, k: usize) -> Option<Vec<f32>> {
        if self.mode != Mode::Incremental {
            return None;
        }
        self.layers.get(k)?;
        let mut d = vec![0.0_f32; self.positions.len()];
        if let Some(stage) = self.stages.iter().find(|s| s.index == k) {
            for ((&i, &a), &b) in stage.indices().iter().zip(&stage.saved).zip(&stage.written) {
                d[i as usize] = (b - a).length();
            }
        }
        Some(self.rest.topology().scatter(&d))
    }

    /// The welded input positions of stack layer `k`: the output with every stage above
    /// `k` rolled back.
    fn input_of(&self, k: usize) -> Vec<Vec3> {
        let mut p = self.positions.clone();
        for stage in self.stages.iter().rev().take_while(|s| s.index >= k) {
            for (&i, &a) in stage.indices().iter().zip(&stage.saved) {
                p[i as usize] = a;
            }
        }
        p
    }

    /// Resolves the stack through the area cache.
    fn resolve(&mut self, doc: &Document) -> Result<Vec<Resolved>> {
        let Self {
            mesh,
            rest,
            areas,
            area_resolutions,
            ..
        } = self;
        let node = doc.mesh(mesh)?;
        areas.retain(|name, _| node.areas.contains_key(name));
        // Areas checked against the cache during this call.
        let mut checked: HashMap<String, Arc<Vec<u32>>> = HashMap::new();
        let layers = doc.resolve_layers_with(mesh, |name, def| {
            if let Some(v) = checked.get(name) {
                return Ok(Arc::clone(v));
            }
            let v = match areas.get(name) {
                Some((cached, v)) if cached == def => Arc::clone(v),
                _ => {
                    let v = Arc::new(resolve_area(
                        def,
                        rest,
                        &format!("mesh '{mesh}', area '{name}'"),
                    )?);
                    *area_resolutions += 1;
                    areas.insert(name.to_owned(), (def.clone(), Arc::clone(&v)));
                    v
                }
            };
            checked.insert(name.to_owned(), Arc::clone(&v));
            Ok(v)
        })?;
        Ok(layers
            .into_iter()
            .map(|(layer, area)| Resolved { layer, area })
            .collect())
    }

    /// Evaluates every layer from the rest positions. Returns (layers evaluated, changed).
    fn evaluate_all(&mut self, layers: &[Resolved], chain: &[usize]) -> Result<(usize, bool)> {
        self.stages.clear();
        self.positions = self.rest.welded_positions().to_vec();
        self.mode = Mode::Empty;
        self.dirty.reset(self.positions.len());
        match self.run_from(0, layers, chain)? {
            Some(n) => {
                self.mode = Mode::Incremental;
                self.dirty.drain();
                let new = self.rest.output(&self.positions);
                let changed = self.output.as_ref() != Some(&new);
                self.faces.clear();
                self.output = Some(new);
                Ok((n, changed))
            }
            None => self.evaluate_refined(layers, chain),
        }
    }

    /// Evaluates a stack with a refining layer with [`Stack::evaluate`].
    fn evaluate_refined(&mut self, layers: &[Resolved], chain: &[usize]) -> Result<(usize, bool)> {
        self.stages.clear();
        self.positions.clear();
        self.dirty.reset(0);
        self.mode = Mode::Empty;
        let stack = Stack {
            layers: layers.iter().map(Resolved::full).collect(),
        };
        let new = stack.evaluate(&self.rest)?;
        self.mode = if new.refined.is_some() {
            Mode::Refined
        } else {
            Mode::Empty
        };
        let changed = self.output.as_ref() != Some(&new);
        self.faces.clear();
        self.output = Some(new);
        Ok((chain.len(), changed))
    }

    /// Evaluates again from chain position `k` on the cached state. Returns (layers
    /// evaluated, changed).
    fn evaluate_from(
        &mut self,
        k: usize,
        layers: &[Resolved],
        chain: &[usize],
    ) -> Result<(usize, bool)> {
        let n = self.positions.len();
        if self.dirty.flag.len() != n {
            self.dirty.reset(n);
        }
        let Some(evaluated) = self.run_from(k, layers, chain)? else {
            return self.evaluate_refined(layers, chain);
        };
        let candidates = self.dirty.drain();
        let changed = self.patch_output(&candidates);
        Ok((evaluated, changed))
    }

    /// Rolls the positions back to the input of chain position `k` and evaluates the chain
    /// from there, reusing stages whose layer and read input are unchanged. Returns the
    /// number of layers evaluated, or `None` when a layer refined the mesh (the state is
    /// then unusable).
    fn run_from(
        &mut self,
        k: usize,
        layers: &[Resolved],
        chain: &[usize],
    ) -> Result<Option<usize>> {
        let rest = self.rest.clone();
        let k = k.min(self.stages.len());
        // The input of stage `k`: the output with every stage from `k` on rolled back, or
        // the rest positions with the outputs of the stages below `k` written in order (the
        // same bits), whichever writes fewer vertices (a copy counting a quarter).
        let count = |stages: &[Stage]| stages.iter().map(|s| s.indices().len()).sum::<usize>();
        if count(&self.stages[..k]) + self.positions.len() / 4 < count(&self.stages[k..]) {
            self.positions.copy_from_slice(rest.welded_positions());
            for stage in &self.stages[..k] {
                scatter_at(&mut self.positions, stage.indices(), &stage.written);
            }
        } else {
            for stage in self.stages[k..].iter().rev() {
                scatter_at(&mut self.positions, stage.indices(), &stage.saved);
            }
        }
        let mut old: Vec<Option<Stage>> = self.stages.drain(k..).map(Some).collect();
        // The stages kept below `k` are the same layers, but inert layers inserted or
        // removed before them move their stack indices (the heat maps look stages up by
        // index).
        for (stage, &li) in self.stages.iter_mut().zip(chain) {
            stage.index = li;
        }
        let mut next_old = 0;
        let mut evaluated = 0;
        for &li in chain.iter().skip(k) {
            let r = &layers[li];
            let mut matched = None;
            if let Some(q) =
                (next_old..old.len()).find(|&q| old[q].as_ref().is_some_and(|s| s.resolved == *r))
            {
                for s in old[next_old..q].iter().flatten() {
                    self.dirty.advance_old(s);
                }
                next_old = q + 1;
                matched = old[q].take();
            }
            if let Some(mut stage) =
                matched.take_if(|s| !self.dirty.intersects(s.resolved.domain()))
            {
                scatter_at(&mut self.positions, stage.indices(), &stage.written);
                stage.index = li;
                self.stages.push(stage);
                continue;
            }
            // The next old stage of the same layer, when its influence and the input its
            // mask reads are unchanged: its mask is still the mask on this input (the volume
            // weights of a million vertices cost milliseconds). Its tool's bind is kept too
            // when only the deformed state (or the weight) changed and nothing the tool
            // reads changed; otherwise (a lattice's control points, an FFSD point) only the
            // tool binds again, within that mask.
            if matched.is_none()
                && let Some(Some(o)) = old.get(next_old)
                && o.resolved.same_mask(r)
                && !self.dirty.intersects(o.resolved.mask_domain())
                && let Some(o) = old[next_old].take()
            {
                next_old += 1;
                let keep = o.resolved.layer.tool.same_rest_state(&r.layer.tool)
                    && !self.dirty.intersects(o.resolved.domain());
                let Stage {
                    binding,
                    written: old_written,
                    ..
                } = o;
                let binding = if keep {
                    binding
                } else {
                    self.binds += 1;
                    LayerBinding::bind_masked(
                        &r.layer.tool,
                        binding.mask,
                        &self.positions,
                        rest.topology(),
                    )?
                };
                let Recorded {
                    saved,
                    written,
                    splits,
                } = binding.apply_recorded(&r.layer, &mut self.positions)?;
                if splits.is_some() {
                    return Ok(None);
                }
                self.dirty
                    .settle_written(&binding.mask.indices, &old_written, &written);
                evaluated += 1;
                self.stages.push(Stage {
                    index: li,
                    resolved: r.clone(),
                    binding,
                    saved,
                    written,
                });
                continue;
            }
            self.binds += 1;
            let binding = r.bind(
                &self.positions,
                rest.topology(),
                matched.as_ref().map(|s| Reuse {
                    bind: &s.binding,
                    stale: &self.dirty.flag,
                }),
            )?;
            // Deforming the vertices of `D` again costs more than a full application (which
            // runs in parallel chunks) once they are half of the active ones.
            let refreshable = matched
                .as_ref()
                .is_some_and(|o| agrees_per_vertex(&r.layer.tool, &o.binding, &binding));
            let at = if refreshable {
                self.dirty.positions_in(&binding.mask.indices)
            } else {
                Vec::new()
            };
            if let Some(old) = matched.take_if(|_| refreshable && 2 * at.len() < binding.mask.len())
            {
                let stage = refresh(
                    &mut self.positions,
                    &mut self.dirty,
                    old,
                    binding,
                    &at,
                    r,
                    li,
                )?;
                evaluated += 1;
                self.refreshed += 1;
                self.stages.push(stage);
                continue;
            }
            let Recorded {
                saved,
                written,
                splits,
            } = binding.apply_recorded(&r.layer, &mut self.positions)?;
            if splits.is_some() {
                return Ok(None);
            }
            let stage = Stage {
                index: li,
                resolved: r.clone(),
                binding,
                saved,
                written,
            };
            evaluated += 1;
            match &matched {
                Some(o)
                    if Arc::ptr_eq(&o.binding.mask, &stage.binding.mask)
                        || o.indices() == stage.indices() =>
                {
                    self.dirty.settle_same(o, &stage)
                }
                Some(o) => self.dirty.settle_merged(o, &stage),
                None => self.dirty.advance_new(&stage),
            }
            self.stages.push(stage);
        }
        for s in old[next_old..].iter().flatten() {
            self.dirty.advance_old(s);
        }
        Ok(Some(evaluated))
    }

    /// Writes the welded positions of the vertices among `candidates` that moved into the
    /// output and recomputes the normals around them. Returns whether anything changed.
    fn patch_output(&mut self, candidates: &[u32]) -> bool {
        let rest = self.rest.clone();
        let topology = rest.topology();
        let Some(out) = self
            .output
            .as_mut()
            .filter(|o| o.refined.is_none() && o.positions.len() == topology.stored_count())
        else {
            self.faces.clear();
            self.output = Some(rest.output(&self.positions));
            return true;
        };
        let links = self.links.get_or_insert_with(|| Links::new(topology));
        let triangles = &topology.triangles;
        let positions = &self.positions;
        let faces = &mut self.faces;
        let differs = |v: u32| {
            let s = topology.representative[v as usize] as usize;
            !same_bits(positions[v as usize], out.positions[s])
        };
        // The block sweeps and the dense path read and keep the face cache, on big meshes.
        let sweepable = faces.len() == triangles.len() && positions.len() >= PARALLEL_THRESHOLD;
        if sweepable && candidates.len() * OUTPUT_DENSE_DIVISOR > positions.len() {
            let moved = candidates
                .par_iter()
                .with_min_len(CHUNK)
                .filter(|&&v| differs(v))
                .count();
            if moved == 0 {
                return false;
            }
            if moved * OUTPUT_DENSE_DIVISOR > positions.len() {
                // Most vertices moved: every normal again (as after a full evaluation),
                // without the sweeps' stamps and block flags.
                rewrite_all(out, topology, links, positions, faces, &mut self.normals);
                return true;
            }
        }
        if sweepable && candidates.len() * OUTPUT_FULL_DIVISOR > positions.len() {
            // Many candidates: sweeps in order (and in parallel) instead of following each
            // moved vertex, over the blocks that hold something that changed. One parallel
            // pass keeps the candidates that moved, stamps them and flags the blocks of their
            // triangles and stored copies. In a flagged block, a triangle with a moved corner
            // gets a new face normal and stamps its corners (flagging their copies' blocks);
            // in a flagged block of stored vertices, every copy of a moved or stamped vertex
            // takes its position and sums its normal again.
            let stamp = links.next_stamp();
            let links = &*links;
            let moved = candidates
                .par_iter()
                .with_min_len(CHUNK)
                .filter(|&&v| {
                    if !differs(v) {
                        return false;
                    }
                    links.moved[v as usize].store(stamp, Ordering::Relaxed);
                    links.flag_blocks(v);
                    true
                })
                .count();
            if moved == 0 {
                return false;
            }
            let is =
                |marks: &[AtomicU8], v: u32| marks[v as usize].load(Ordering::Relaxed) == stamp;
            faces
                .par_chunks_mut(BLOCK)
                .zip(triangles.par_chunks(BLOCK))
                .zip(links.tri_blocks.par_iter())
                .with_min_len(CHUNK / BLOCK)
                .for_each(|((faces, tris), dirty)| {
                    if !dirty.swap(false, Ordering::Relaxed) {
                        return;
                    }
                    for (f, &t) in faces.iter_mut().zip(tris) {
                        if t.iter().any(|&c| is(&links.moved, c)) {
                            *f = face_normal(t, positions);
                            for c in t {
                                if !is(&links.around, c) {
                                    links.around[c as usize].store(stamp, Ordering::Relaxed);
                                    for &s in links.copies_of(c) {
                                        links.stored_blocks[s as usize / BLOCK]
                                            .store(true, Ordering::Relaxed);
                                    }
                                }
                            }
                        }
                    }
                });
            let faces = &*faces;
            out.positions
                .par_chunks_mut(BLOCK)
                .zip(out.normals.par_chunks_mut(BLOCK))
                .zip(topology.weld.par_chunks(BLOCK))
                .zip(links.stored_blocks.par_iter())
                .with_min_len(CHUNK / BLOCK)
                .for_each(|(((ps, ns), weld), dirty)| {
                    if !dirty.swap(false, Ordering::Relaxed) {
                        return;
                    }
                    for ((p, n), &w) in ps.iter_mut().zip(ns.iter_mut()).zip(weld) {
                        if is(&links.moved, w) || is(&links.around, w) {
                            *p = positions[w as usize];
                            *n = vertex_normal(w, links, faces);
                        }
                    }
                });
            return true;
        }
        let moved: Vec<u32> = if candidates.len() >= PARALLEL_THRESHOLD {
            candidates
                .par_iter()
                .copied()
                .with_min_len(CHUNK)
                .filter(|&v| differs(v))
                .collect()
        } else {
            candidates.iter().copied().filter(|&v| differs(v)).collect()
        };
        if moved.is_empty() {
            return false;
        }
        if faces.len() != triangles.len() {
            // No face cache yet: every normal.
            rewrite_all(out, topology, links, positions, faces, &mut self.normals);
            return true;
        }
        // The triangles around the moved vertices get new face normals (the others keep
        // theirs: same corners, same bits), then every corner of those triangles its sum.
        let stamp = links.next_stamp();
        let mut changed = Vec::new();
        for &v in &moved {
            for &s in links.copies_of(v) {
                out.positions[s as usize] = positions[v as usize];
            }
            for &t in row(&links.tri_offsets, &links.tris, v) {
                if !links.tri_mark[t as usize] {
                    links.tri_mark[t as usize] = true;
                    changed.push(t);
                }
            }
        }
        let mut around = Vec::new();
        for &t in &changed {
            links.tri_mark[t as usize] = false;
            faces[t as usize] = face_normal(triangles[t as usize], positions);
            for c in triangles[t as usize] {
                let a = links.around[c as usize].get_mut();
                if *a != stamp {
                    *a = stamp;
                    around.push(c);
                }
            }
        }
        let (links, faces) = (&*links, &*faces);
        let normal = |&v: &u32| vertex_normal(v, links, faces);
        let normals: Vec<Vec3> = if around.len() >= PARALLEL_THRESHOLD {
            around.par_iter().with_min_len(CHUNK).map(normal).collect()
        } else {
            around.iter().map(normal).collect()
        };
        for (&v, &n) in around.iter().zip(&normals) {
            for &s in links.copies_of(v) {
                out.normals[s as usize] = n;
            }
        }
        true
    }
}

/// True when a layer bound again (`new`) agrees with its old binding (`old`) on every
/// vertex whose input is unchanged: the same weight (a mask is a function of each vertex's
/// input) and, for a tool that [binds per vertex](Tool::binds_per_vertex), the same
/// per-vertex bind; an FFSD tool's bind depends on every active vertex, so it must have the
/// same bits. Such a vertex then keeps its old output bits, and the stage can be
/// [`refresh`]ed.
fn agrees_per_vertex(tool: &Tool, old: &LayerBinding, new: &LayerBinding) -> bool {
    tool.binds_per_vertex()
        || match (&old.bind, &new.bind) {
            (Some(ToolBind::Ffsd(a)), Some(ToolBind::Ffsd(b))) => a.same_bits(b),
            _ => false,
        }
}

/// Evaluates a matched stage `old` again with `binding`, which [agrees](agrees_per_vertex)
/// with the old binding outside `D`, on the current positions (the stage's input): an active
/// vertex outside `D` had the same input, so it gets its old `written` bits back; only the
/// active vertices in `D` are deformed again (with [`LayerBinding::apply_at`], the same
/// arithmetic as a full application). A vertex that left the mask (it is in `D`) keeps its
/// input. Afterwards a vertex of `D` touched here stays in `D` exactly when its new output
/// may differ from the old. `at` holds the positions in the new mask of its vertices in `D`,
/// ascending.
fn refresh(
    positions: &mut [Vec3],
    dirty: &mut Dirty,
    old: Stage,
    binding: LayerBinding,
    at: &[u32],
    resolved: &Resolved,
    index: usize,
) -> Result<Stage> {
    let layer = &resolved.layer;
    if Arc::ptr_eq(&old.binding.mask, &binding.mask) || old.indices() == binding.mask.indices {
        // The same active vertices: the old records are updated in place.
        let mut stage = Stage {
            index,
            resolved: resolved.clone(),
            binding,
            ..old
        };
        let indices = &stage.binding.mask.indices;
        for &k in at {
            stage.saved[k as usize] = positions[indices[k as usize] as usize];
        }
        scatter_at(positions, indices, &stage.written);
        for &k in at {
            positions[indices[k as usize] as usize] = stage.saved[k as usize];
        }
        stage.binding.apply_at(layer, positions, at)?;
        for &k in at {
            let v = indices[k as usize];
            let new = positions[v as usize];
            if same_bits(new, stage.written[k as usize]) {
                dirty.remove(v);
            }
            stage.written[k as usize] = new;
        }
        return Ok(stage);
    }
    // The active vertices changed (only vertices of `D` enter or leave a mask): new records
    // merged from the old ones, in the new mask's order.
    let (new_idx, old_idx) = (&binding.mask.indices, old.indices());
    let m = new_idx.len();
    let (mut saved, mut written) = (Vec::with_capacity(m), Vec::with_capacity(m));
    // The mask positions deformed again, and where each was in the old mask.
    let (mut at, mut was) = (Vec::new(), Vec::new());
    let mut j = 0;
    let left = |v: u32, j: usize, dirty: &mut Dirty| {
        // It left the mask: its output is now its input.
        if same_bits(positions[v as usize], old.written[j]) {
            dirty.remove(v);
        } else {
            dirty.insert(v);
        }
    };
    for (k, &i) in new_idx.iter().enumerate() {
        while j < old_idx.len() && old_idx[j] < i {
            left(old_idx[j], j, dirty);
            j += 1;
        }
        let in_old = old_idx.get(j) == Some(&i);
        if in_old && !dirty.contains(i) {
            saved.push(old.saved[j]);
            written.push(old.written[j]);
        } else {
            let p = positions[i as usize];
            saved.push(p);
            written.push(p);
            at.push(k as u32);
            was.push(in_old.then_some(j));
        }
        j += usize::from(in_old);
    }
    for (j, &v) in old_idx.iter().enumerate().skip(j) {
        left(v, j, dirty);
    }
    scatter_at(positions, new_idx, &written);
    binding.apply_at(layer, positions, &at)?;
    for (&k, was) in at.iter().zip(was) {
        let (k, v) = (k as usize, new_idx[k as usize]);
        let new = positions[v as usize];
        written[k] = new;
        // The old output: the old record's, or (not active before) the old input, which is
        // the current one outside `D` and unknown inside.
        let before = match was {
            Some(j) => Some(old.written[j]),
            None if !dirty.contains(v) => Some(saved[k]),
            None => None,
        };
        match before {
            Some(b) if same_bits(new, b) => dirty.remove(v),
            _ => dirty.insert(v),
        }
    }
    Ok(Stage {
        index,
        resolved: resolved.clone(),
        binding,
        saved,
        written,
    })
}

/// Indices of the non-inert layers.
fn non_inert(layers: &[Resolved]) -> Vec<usize> {
    layers
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.layer.is_inert())
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests;
