//! Parallel per-vertex work in chunks: the sizes from which work goes parallel, and helpers
//! that visit, scatter and gather values at ascending vertex indices in disjoint chunks. The
//! stack, the influence masks and the tools all use them; this module uses none of them, so
//! the dependencies run one way (tools → chunks ← stack).
//!
//! Every helper gives each element the same single computation whether it runs in parallel
//! or in order, so results are the same bits on any number of threads.

use std::borrow::Cow;

use rayon::prelude::*;

/// Above this many active vertices a layer deforms (and blends, masks, binds) in parallel
/// chunks.
pub const PARALLEL_THRESHOLD: usize = 16_384;
/// Chunk size for parallel per-vertex work.
pub const CHUNK: usize = 4_096;
/// Above this many entries, plain copies (scatter, gather) run in parallel chunks; below
/// it, waking the pool costs more than the copy (and much more on a loaded machine).
pub const PARALLEL_COPY_THRESHOLD: usize = 1 << 17;

/// Vertices per parallel task when a tool binds every vertex on its own (curves, axes,
/// shape surfaces).
pub const BIND_CHUNK: usize = 4096;

/// From this many bytes on, [`zeroed`] writes its zeros in parallel chunks.
pub const PARALLEL_ZERO_BYTES: usize = 1 << 18;

/// `n` zeros of a plain type. From [`PARALLEL_ZERO_BYTES`] on, the zeros are written in
/// parallel chunks: `calloc` (what `vec![0.0; n]` and `bytemuck::zeroed_vec` call) writes them
/// on the calling thread with `memset` whenever the allocator reuses memory it already holds,
/// which in an evaluation (one layer's buffers freed, the next layer's allocated) is the
/// usual case; a million-vertex stack zeroes a few hundred megabytes of bind and deform
/// buffers. The cost: where the allocator maps fresh pages instead (blocks of 32 MiB and more
/// with glibc), `calloc` wrote nothing and this writes the zeros once more, in parallel.
/// Below 256 KiB, `calloc`: such a `memset` takes an estimated 10–20 µs (not measured), about
/// what waking a sleeping pool thread takes (8–17 µs from wake-up to running, traced). The
/// threshold was 2 MiB until the twenty-first session, when a scheduler trace showed the
/// pool's second thread asleep for about 24 ms of each 175 ms evaluation of the suite's
/// million-vertex stack, with the calling thread's `memset` (the joined masks' and the binds'
/// buffers) the largest single part; at 256 KiB the masks take about 1 ms less, and so do the
/// binds (`docs/performance.md`).
#[must_use]
pub fn zeroed<T: bytemuck::Zeroable + Copy + Send + Sync>(n: usize) -> Vec<T> {
    if n.saturating_mul(size_of::<T>()) < PARALLEL_ZERO_BYTES {
        return bytemuck::zeroed_vec(n);
    }
    let mut v = Vec::with_capacity(n);
    (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|_| T::zeroed())
        .collect_into_vec(&mut v);
    v
}

/// `spare`, a buffer an earlier bind on this thread no longer needs, made `n` values long
/// for a bind that writes again every value that is later read: its stale values kept,
/// zeros added after them. Without the room for `n`, [`zeroed`]. The blocks of a run of per-vertex layers
/// (`fused.rs`) bind one block after another on each thread; reusing the buffers of the
/// block before spares each bind its allocation and its zeros (`docs/performance.md`,
/// thirty-second session).
#[must_use]
pub(crate) fn recycled<T: bytemuck::Zeroable + Copy + Send + Sync>(
    mut spare: Vec<T>,
    n: usize,
) -> Vec<T> {
    if spare.capacity() < n {
        return zeroed(n);
    }
    spare.truncate(n);
    spare.resize(n, T::zeroed());
    spare
}

/// Whether `indices` is strictly ascending (sorted, each once), as an influence mask's
/// indices are.
///
/// The pairs are compared 64 at a time (`ASCENDING_BLOCK`) without a branch per pair, which
/// compiles to vector compares, stopping after the first block with a pair out of order.
/// The evaluation checks every layer's mask this way (the blend, the binds' slots), on the
/// thread that then starts the parallel work: 500,000 indices take 66 µs here against 250 µs
/// with a test and branch per pair (`docs/performance.md`, twenty-first session).
#[must_use]
pub fn strictly_ascending(indices: &[u32]) -> bool {
    let Some(pairs) = indices.len().checked_sub(1) else {
        return true;
    };
    let (left, right) = (&indices[..pairs], &indices[1..]);
    left.chunks(ASCENDING_BLOCK)
        .zip(right.chunks(ASCENDING_BLOCK))
        .all(|(a, b)| a.iter().zip(b).fold(true, |ok, (x, y)| ok & (x < y)))
}

/// Pairs per block of [`strictly_ascending`].
const ASCENDING_BLOCK: usize = 64;

/// Whether `indices` is strictly ascending and every index is below `n`: a mask's indices
/// into `n` values, which parallel chunks may visit as disjoint runs.
#[must_use]
fn ascending_below(indices: &[u32], n: usize) -> bool {
    strictly_ascending(indices) && indices.last().is_none_or(|&i| (i as usize) < n)
}

/// The slots of a compact per-vertex bind of `n` vertices: `slot[v]` is the position of
/// vertex `v` in the bind's active list (`u32::MAX` for a vertex that is not active), with
/// that list (the vertices of `active` below `n`, each once, in order): `active` itself
/// where it is already such a list (a mask's indices always are), not a copy of it.
#[must_use]
pub fn bind_slots(n: usize, active: &[u32]) -> (Vec<u32>, Cow<'_, [u32]>) {
    bind_slots_in(Vec::new(), n, active)
}

/// [`bind_slots`] written into `slot`, a buffer an earlier bind no longer needs (its values
/// are not read).
#[must_use]
pub(crate) fn bind_slots_in(
    mut slot: Vec<u32>,
    n: usize,
    active: &[u32],
) -> (Vec<u32>, Cow<'_, [u32]>) {
    slot.clear();
    if n >= PARALLEL_COPY_THRESHOLD {
        (0..n)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|_| u32::MAX)
            .collect_into_vec(&mut slot);
    } else {
        slot.resize(n, u32::MAX);
    }
    // A mask's indices (strictly ascending, in range) are the list itself; their slots are
    // written in order, or in parallel chunks from `PARALLEL_COPY_THRESHOLD` indices on.
    if ascending_below(active, n) {
        // Checked here: not again in `for_each_at`.
        let parallel = active.len() >= PARALLEL_COPY_THRESHOLD;
        visit_at(&mut slot, active, parallel, |k, s| *s = k as u32);
        return (slot, Cow::Borrowed(active));
    }
    let mut list = Vec::with_capacity(active.len());
    for &i in active {
        if let Some(s) = slot.get_mut(i as usize).filter(|s| **s == u32::MAX) {
            *s = list.len() as u32;
            list.push(i);
        }
    }
    (slot, Cow::Owned(list))
}

/// An earlier bind of the same tool (the same rest state) on an input that differs from the
/// new one only at the `stale` vertices (`stale[v]`; a vertex past its end counts as stale).
/// A tool whose per-vertex bind data is a function of that vertex's input alone (curves,
/// axes, shape surfaces) copies the entry of a vertex that is not stale instead of computing
/// it again: the same bits, without the closest-point search.
#[derive(Debug)]
pub struct Reuse<'a, B> {
    /// The earlier bind.
    pub bind: &'a B,
    /// Per welded vertex, whether its input may differ from the one `bind` read.
    pub stale: &'a [bool],
}

impl<B> Clone for Reuse<'_, B> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<B> Copy for Reuse<'_, B> {}

impl<'a, B> Reuse<'a, B> {
    /// The same stale vertices with another bind.
    #[must_use]
    pub fn with<C>(self, bind: &'a C) -> Reuse<'a, C> {
        Reuse {
            bind,
            stale: self.stale,
        }
    }
}

/// A bind that keeps its per-vertex data in compact arrays, with a slot per welded vertex
/// (`u32::MAX` where the vertex was not active; see [`bind_slots`]).
pub trait Slotted {
    /// The slot of each welded vertex.
    fn slots(&self) -> &[u32];
}

impl<'a, B: Slotted> Reuse<'a, B> {
    /// The earlier bind and the slot of vertex `i` in its compact arrays, when `i`'s entry
    /// may be copied: `i` is not stale and had a slot.
    #[must_use]
    pub fn entry(self, i: u32) -> Option<(&'a B, usize)> {
        if self.stale.get(i as usize).copied().unwrap_or(true) {
            return None;
        }
        let s = *self.bind.slots().get(i as usize)?;
        (s != u32::MAX).then_some((self.bind, s as usize))
    }

    /// Splits a chunk of active vertices `ids` of a bind into those whose entry an earlier
    /// bind gives — `copy(j, old, s)` copies entry `s` of `old` into the chunk's slot `j` —
    /// and the others, whose chunk slots and input `positions` it returns: the queries the
    /// new bind answers (a lane group at a time). Without an earlier bind every vertex is a
    /// query, in order, and only the positions are gathered.
    pub fn split_chunk(
        previous: Option<Self>,
        ids: &[u32],
        positions: &[glam::Vec3],
        mut copy: impl FnMut(usize, &'a B, usize),
    ) -> (Fresh, Vec<glam::Vec3>) {
        let Some(previous) = previous else {
            let xs = ids.iter().map(|&i| positions[i as usize]).collect();
            return (Fresh::Every, xs);
        };
        let mut fresh = Vec::with_capacity(ids.len());
        let mut xs = Vec::with_capacity(ids.len());
        for (j, &i) in ids.iter().enumerate() {
            match previous.entry(i) {
                Some((old, s)) => copy(j, old, s),
                None => {
                    fresh.push(j);
                    xs.push(positions[i as usize]);
                }
            }
        }
        if fresh.len() == ids.len() {
            return (Fresh::Every, xs);
        }
        (Fresh::Listed(fresh), xs)
    }
}

/// The chunk slots of the queries a bind answers ([`Reuse::split_chunk`]): query `k` goes to
/// slot [`Fresh::slot`]`(k)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fresh {
    /// Every slot of the chunk, in order: query `k` is slot `k`.
    Every,
    /// These slots, ascending, one per query.
    Listed(Vec<usize>),
}

impl Fresh {
    /// The chunk slot of query `k`.
    ///
    /// # Panics
    /// When `k` is past the listed slots.
    #[must_use]
    #[inline]
    pub fn slot(&self, k: usize) -> usize {
        match self {
            Self::Every => k,
            Self::Listed(slots) => slots[k],
        }
    }
}

/// Calls `f(k, &mut values[indices[k]])` for every `k`. When `indices` has at least
/// [`PARALLEL_COPY_THRESHOLD`] entries and is strictly ascending (as an influence mask's
/// indices are), the calls run in parallel chunks of [`CHUNK`] entries, each owning a
/// disjoint range of `values`; otherwise in order. Each element sees the same single call
/// either way, so a per-element `f` gives the same bits. Indices must be in range (panics
/// otherwise, like indexing).
pub fn for_each_at<T: Send>(
    values: &mut [T],
    indices: &[u32],
    f: impl Fn(usize, &mut T) + Sync + Send,
) {
    let parallel =
        indices.len() >= PARALLEL_COPY_THRESHOLD && ascending_below(indices, values.len());
    visit_at(values, indices, parallel, f);
}

/// [`for_each_at`]'s calls: in parallel chunks when `parallel` (which needs `indices`
/// strictly ascending and below `values.len()`, [`ascending_below`]), otherwise in order.
fn visit_at<T: Send>(
    values: &mut [T],
    indices: &[u32],
    parallel: bool,
    f: impl Fn(usize, &mut T) + Sync + Send,
) {
    if !parallel {
        for (k, &i) in indices.iter().enumerate() {
            f(k, &mut values[i as usize]);
        }
        return;
    }
    map_ascending_chunks(values, indices, |k0, chunk, part| {
        for (j, &i) in chunk.iter().enumerate() {
            f(k0 + j, part.get(i));
        }
    });
}

/// The part of `values` that one chunk of strictly ascending indices owns (see
/// [`map_chunks_at`]).
pub struct ChunkValues<'a, T> {
    slice: &'a mut [T],
    base: usize,
}

impl<T> ChunkValues<'_, T> {
    /// `values[i]`, for an index `i` of the chunk.
    pub fn get(&mut self, i: u32) -> &mut T {
        &mut self.slice[i as usize - self.base]
    }
}

/// Calls `f(k0, chunk, part)` for consecutive chunks of [`CHUNK`] entries of `indices`
/// (`k0` the position of the chunk's first entry), giving each the part of `values` its
/// indices fall in, and returns the results in chunk order. When `indices` is strictly
/// ascending and in range, the chunks own disjoint parts and run in parallel; otherwise
/// there is one chunk, the whole list, run in place.
pub fn map_chunks_at<T: Send, R: Send>(
    values: &mut [T],
    indices: &[u32],
    f: impl Fn(usize, &[u32], &mut ChunkValues<'_, T>) -> R + Sync + Send,
) -> Vec<R> {
    if !ascending_below(indices, values.len()) || indices.len() <= CHUNK {
        return vec![f(
            0,
            indices,
            &mut ChunkValues {
                slice: values,
                base: 0,
            },
        )];
    }
    map_ascending_chunks(values, indices, f)
}

/// [`map_chunks_at`]'s parallel chunks, for `indices` already known to be strictly
/// ascending and below `values.len()` ([`ascending_below`]).
fn map_ascending_chunks<T: Send, R: Send>(
    values: &mut [T],
    indices: &[u32],
    f: impl Fn(usize, &[u32], &mut ChunkValues<'_, T>) -> R + Sync + Send,
) -> Vec<R> {
    debug_assert!(ascending_below(indices, values.len()));
    let mut parts = Vec::with_capacity(indices.len().div_ceil(CHUNK));
    let mut rest = values;
    let mut base = 0_usize;
    for (c, chunk) in indices.chunks(CHUNK).enumerate() {
        let end = indices
            .get((c + 1) * CHUNK)
            .map_or(base + rest.len(), |&next| next as usize);
        let (head, tail) = rest.split_at_mut(end - base);
        parts.push((c * CHUNK, chunk, ChunkValues { slice: head, base }));
        rest = tail;
        base = end;
    }
    parts
        .into_par_iter()
        .map(|(k0, chunk, mut part)| f(k0, chunk, &mut part))
        .collect()
}

/// `values[indices[k]] = src[k]` for every `k` (`src` as long as `indices`): a plain loop,
/// or [`for_each_at`]'s parallel chunks from [`PARALLEL_COPY_THRESHOLD`] entries.
pub fn scatter_at<T: Copy + Send + Sync>(values: &mut [T], indices: &[u32], src: &[T]) {
    if indices.len() >= PARALLEL_COPY_THRESHOLD {
        for_each_at(values, indices, |k, v| *v = src[k]);
    } else {
        for (&i, &s) in indices.iter().zip(src) {
            values[i as usize] = s;
        }
    }
}

/// `values[i]` for every `i` of `indices`, gathered in parallel chunks above
/// [`PARALLEL_COPY_THRESHOLD`] indices.
#[must_use]
pub fn gather_at<T: Copy + Send + Sync>(values: &[T], indices: &[u32]) -> Vec<T> {
    if indices.len() >= PARALLEL_COPY_THRESHOLD {
        indices
            .par_iter()
            .with_min_len(CHUNK)
            .map(|&i| values[i as usize])
            .collect()
    } else {
        indices.iter().map(|&i| values[i as usize]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeroed_is_all_zeros_on_both_paths() {
        for n in [
            0,
            5,
            PARALLEL_ZERO_BYTES / 4 - 1,
            PARALLEL_ZERO_BYTES / 4 + 4_099,
        ] {
            // Memory the allocator may hand back (small blocks; glibc returns big ones to the
            // system): written, then freed.
            drop(vec![1.5_f32; n]);
            let v: Vec<f32> = zeroed(n);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|x| x.to_bits() == 0), "{n} zeros");
            let w: Vec<glam::Vec3> = zeroed(n);
            let zero_bits = |x: &glam::Vec3| x.to_array().iter().all(|c| c.to_bits() == 0);
            assert!(w.len() == n && w.iter().all(zero_bits), "{n} zero vectors");
        }
    }

    #[test]
    fn strictly_ascending_finds_any_pair_out_of_order() {
        // Lengths around the block size, with the one bad pair at every position (both
        // within a block and across two), as a repeat and as a step down.
        for n in [0, 1, 2, 63, 64, 65, 66, 129, 300] {
            let list: Vec<u32> = (0..n as u32).map(|i| 3 * i + 1).collect();
            assert!(strictly_ascending(&list), "{n} ascending");
            for k in 1..n {
                for bad in [list[k - 1], list[k - 1] - 1] {
                    let mut l = list.clone();
                    l[k] = bad;
                    assert!(!strictly_ascending(&l), "n {n}, pair {k}, {bad}");
                }
            }
        }
    }

    #[test]
    fn bind_slots_number_each_active_vertex_in_range_once() {
        let (slot, list) = bind_slots(6, &[1, 4, 4, 9, 2]);
        assert_eq!(*list, [1, 4, 2]);
        assert_eq!(slot, [u32::MAX, 0, 2, u32::MAX, 1, u32::MAX]);
        // An ascending list (a mask's), long enough to go parallel.
        let n = 3 * PARALLEL_COPY_THRESHOLD;
        let active: Vec<u32> = (0..n as u32).filter(|i| i % 3 != 1).collect();
        let (slot, list) = bind_slots(n, &active);
        assert!(
            matches!(list, Cow::Borrowed(_)),
            "a mask's indices are not copied"
        );
        assert_eq!(list, active);
        for (v, &s) in slot.iter().enumerate() {
            match active.binary_search(&(v as u32)) {
                Ok(k) => assert_eq!(s, k as u32),
                Err(_) => assert_eq!(s, u32::MAX),
            }
        }
    }
}
