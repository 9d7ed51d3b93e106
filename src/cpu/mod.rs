//! The CPU path: a mirror of every shader (same file name, same loop shape, f32 in the frame's
//! coordinates) and a brute-force f64 oracle for the tests.
//!
//! The mirror runs the kernels' "invocations" on all cores (rayon): a kernel whose invocations
//! each write their own output runs them in parallel; one whose invocations combine through
//! atomics uses atomics whose result does not depend on their order (counts), or runs each
//! slave's work items in order on one thread (the nearest facet's chunks); the rest run one
//! after another. The results are bitwise the same on one thread or many, and equal the GPU's up
//! to f32 round-off (exactly for the tree's boxes). It is also the backend used where no
//! adapter exists.

pub mod active;
pub mod anchor;
pub mod buckets;
pub mod common;
pub mod gather;
pub(crate) mod increment;
pub mod integrate;
pub mod local_search;
pub mod motion;
pub mod nearest_facet;
pub mod nodal_normals;
pub mod penalty;
mod resident;
pub mod scan;
pub mod schedule;
pub mod stats;
pub mod to_local;
pub mod tree;

#[cfg(debug_assertions)]
use std::sync::atomic::AtomicU32;
use std::sync::Arc;

use crate::abi::penalty::ACC_WORDS_PER_NODE;
use crate::abi::search::GpuHit;
use crate::abi::status::STATUS_WORDS;

/// Fewest invocations a thread of the CPU path takes at once (below it, splitting costs more
/// than it gains).
pub(crate) const PAR_MIN: usize = 256;

/// Runs `f` on each index of `list` with that index's rows of `a` and `b`, in parallel chunks
/// of at least [`PAR_MIN`] indices, each chunk folding into its own `R` (from `identity`), the
/// chunks' joined by `join`: the mirror of a pass over the active slaves that writes their rows
/// in place, its status words reduced per chunk as the shader reduces them per workgroup (so
/// the result does not depend on the chunks where `join` is an integer sum, minimum or
/// maximum). The active list is increasing (its compaction keeps slave order), so its chunks'
/// rows are disjoint runs of `a` and `b`; a list that is not (an index repeated, out of order
/// or past the rows) is taken sorted, once each, within the rows.
pub(crate) fn for_listed<A: Send, B: Send, R: Send>(
    list: &[u32],
    a: &mut [A],
    b: &mut [B],
    identity: impl Fn() -> R + Sync + Send,
    join: impl Fn(R, R) -> R + Sync + Send,
    f: impl Fn(usize, &mut A, &mut B, &mut R) + Sync + Send,
) -> R {
    use rayon::prelude::*;
    let len = a.len().min(b.len());
    let sorted: Vec<u32>;
    let increasing = list.windows(2).all(|w| w[0] < w[1]);
    let list = if increasing && list.last().is_none_or(|&l| (l as usize) < len) {
        list
    } else {
        let mut v: Vec<u32> = list
            .iter()
            .copied()
            .filter(|&i| (i as usize) < len)
            .collect();
        v.sort_unstable();
        v.dedup();
        sorted = v;
        &sorted
    };
    let mut chunks = Vec::with_capacity(list.len() / PAR_MIN + 1);
    let (mut a, mut b, mut offset) = (&mut a[..len], &mut b[..len], 0usize);
    for ids in list.chunks(PAR_MIN) {
        let end = ids[ids.len() - 1] as usize + 1;
        let (ra, rest_a) = std::mem::take(&mut a).split_at_mut(end - offset);
        let (rb, rest_b) = std::mem::take(&mut b).split_at_mut(end - offset);
        chunks.push((ids, offset, ra, rb));
        (a, b, offset) = (rest_a, rest_b, end);
    }
    chunks
        .into_par_iter()
        .map(|(ids, start, ra, rb)| {
            let mut r = identity();
            for &i in ids {
                let k = i as usize - start;
                f(i as usize, &mut ra[k], &mut rb[k], &mut r);
            }
            r
        })
        .reduce(&identity, &join)
}

/// Writes to distinct elements of a slice from several threads: a mirror's invocations that
/// each write one element chosen by a permutation (as a shader's scattered store does). On
/// x86-64 a 64-byte, 64-aligned element is written with non-temporal stores (one whole cache
/// line, not read first: a scattered write then costs a third of a plain store's time at 10^6
/// elements); every thread that wrote calls [`Scatter::fence`] before its task ends.
pub(crate) struct Scatter<'a, T> {
    ptr: *mut T,
    len: usize,
    /// Which elements were written (checked in debug builds: each at most once).
    #[cfg(debug_assertions)]
    written: Vec<AtomicU32>,
    _slice: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: `write` stores each element at most once (asserted in debug builds; the callers'
// indices are permutations), so no two threads touch the same element, and the exclusive
// borrow of the slice keeps every other access out while the Scatter lives.
unsafe impl<T: Send> Sync for Scatter<'_, T> {}

impl<'a, T: Copy> Scatter<'a, T> {
    /// Scattered writes into `out`.
    pub(crate) fn new(out: &'a mut [T]) -> Self {
        Self {
            ptr: out.as_mut_ptr(),
            len: out.len(),
            #[cfg(debug_assertions)]
            written: (0..out.len()).map(|_| AtomicU32::new(0)).collect(),
            _slice: std::marker::PhantomData,
        }
    }

    /// Whether `write` uses non-temporal stores for T (x86-64 only).
    #[cfg(target_arch = "x86_64")]
    const STREAM: bool = cfg!(target_arch = "x86_64")
        && std::mem::size_of::<T>() == 64
        && std::mem::align_of::<T>() == 64;

    /// Stores `value` at `i`. Panics when `i` is out of range (and, in debug builds, when `i`
    /// was written before).
    pub(crate) fn write(&self, i: usize, value: T) {
        assert!(i < self.len, "scattered write {i} beyond {}", self.len);
        #[cfg(debug_assertions)]
        assert_eq!(
            self.written[i].swap(1, std::sync::atomic::Ordering::Relaxed),
            0,
            "element {i} written twice"
        );
        #[cfg(target_arch = "x86_64")]
        if Self::STREAM {
            use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm_stream_si128};
            let src = (&value as *const T).cast::<__m128i>();
            // SAFETY: i is in range and no other thread writes element i (see the Sync impl);
            // the element is 64 bytes, 64-aligned: four aligned 16-byte stores cover it, read
            // from the 64 bytes of `value`. SSE2 is part of x86-64.
            unsafe {
                let dst = self.ptr.add(i).cast::<__m128i>();
                for k in 0..4 {
                    _mm_stream_si128(dst.add(k), _mm_loadu_si128(src.add(k)));
                }
            }
            return;
        }
        // SAFETY: i is in range, and no other thread writes element i (see the Sync impl).
        unsafe { self.ptr.add(i).write(value) }
    }

    /// Orders this thread's non-temporal stores before its later stores (the end of its
    /// task), so that whoever joins the task sees them.
    pub(crate) fn fence(&self) {
        #[cfg(target_arch = "x86_64")]
        if Self::STREAM {
            // SAFETY: sfence has no preconditions; SSE is part of x86-64.
            #[allow(unused_unsafe)]
            unsafe {
                std::arch::x86_64::_mm_sfence()
            }
        }
    }
}

/// The hits to write: in place when no result shares them any more, else a copy.
pub(crate) fn hits_mut(hits: &mut Arc<Vec<GpuHit>>) -> &mut Vec<GpuHit> {
    Arc::make_mut(hits)
}

/// The buffers of one search on the CPU; they only grow.
#[derive(Clone, Debug, Default)]
pub struct CpuWorkspace {
    /// The search tree's packed boxes (one per heap node, `abi::boxes`).
    pub boxes: Vec<[u32; 4]>,
    /// The same boxes decoded (lower, upper corner per heap node; the bits the kernels decode
    /// at each test): the CPU walk reads these instead of decoding every box it tests.
    pub corners: Vec<[[f32; 4]; 2]>,
    /// Status words (`STATUS_*`).
    pub status: [u32; STATUS_WORDS],
    /// One result per slave node (the tracked nodes between increments), shared with the last
    /// result returned: the next search writes in place when the caller has dropped it, and
    /// copies it first when not.
    pub hits: Arc<Vec<GpuHit>>,
    /// Positions at the last global search (motion budget).
    pub reference: Vec<[f32; 4]>,
    /// Per slave, its skin (`Buf::Skins`), sized with the hits by the local search.
    pub skins: Vec<[f32; 4]>,
    /// Nearest-facet work items: each slave's chunk count, scanned to its first item.
    pub work: Vec<u32>,
    /// Nearest-facet record per walk position (`BEST_WORDS` words).
    pub best: Vec<u32>,
    /// The slaves' positions and node ids in walk order (`nearest_facet::walk_start`).
    pub walk_points: Vec<[u32; 4]>,
    /// The active slaves the last global search left (count, then slave indices:
    /// `active::active_compact`; on a GPU the status buffer's words from `ACTIVE_LIST`).
    pub active: Vec<u32>,
    /// The bucket search's grid (`abi::buckets::BucketLayout`; empty with the tree).
    pub grid: Vec<u32>,
}

/// The CPU executor of the global search.
#[derive(Clone, Debug, Default)]
pub struct CpuSearch {
    /// Small sliding: the slaves' anchors (local runs evaluate them instead of searching).
    anchors: Option<Vec<crate::abi::search::Anchor>>,
    ws: CpuWorkspace,
    /// Device-resident increments: the plan and the nodes they keep.
    resident: Option<Box<resident::CpuResident>>,
}

impl CpuSearch {
    /// Small sliding: installs the slaves' anchors.
    pub fn set_anchors(&mut self, anchors: &[crate::abi::search::Anchor]) {
        self.anchors = Some(anchors.to_vec());
    }

    /// The search tree's packed boxes after the last global search (one per heap node,
    /// `abi::boxes`).
    pub fn tree_boxes(&self) -> &[[u32; 4]] {
        &self.ws.boxes
    }
}

/// The CPU executor of the penalty passes of one pair; its state persists between increments.
#[derive(Clone, Debug)]
pub struct CpuPenalty {
    /// Friction force and area per slave.
    pub state: Vec<crate::abi::penalty::SlaveState>,
    /// Smoothed normal per model node.
    pub normals: Vec<[f32; 4]>,
    /// Result per slave.
    pub out: Vec<crate::abi::penalty::ContactOut>,
    /// Fixed-point force sums per pair node (gather's accumulator).
    pub acc: Vec<u32>,
    /// Force per pair node.
    pub forces: Vec<[f32; 4]>,
    /// Need bits per pair node and rigid slot (`NEED_*`), zero between increments.
    pub need: Vec<u32>,
}

impl CpuPenalty {
    /// A fresh executor for `setup` in a model of `n_nodes` nodes.
    pub fn new(setup: &crate::penalty::PenaltySetup, n_nodes: usize) -> Self {
        Self {
            state: setup.initial_state(),
            normals: vec![[0.0; 4]; n_nodes],
            out: Vec::new(),
            acc: Vec::new(),
            forces: Vec::new(),
            need: vec![0; setup.pair_nodes.len()],
        }
    }

    /// The bytes of the array holding role `buf` (`None` for a role it does not hold), sized
    /// for `setup` as the GPU's buffers are: what a split increment hands over.
    pub(crate) fn role_bytes(
        &mut self,
        buf: crate::abi::passes::Buf,
        setup: &crate::penalty::PenaltySetup,
    ) -> Option<&mut [u8]> {
        use crate::abi::passes::Buf;
        self.out
            .resize(setup.areas.len(), bytemuck::Zeroable::zeroed());
        self.acc
            .resize(setup.pair_nodes.len() * ACC_WORDS_PER_NODE, 0);
        self.forces.resize(setup.pair_nodes.len(), [0.0; 4]);
        Some(match buf {
            Buf::Normals => bytemuck::cast_slice_mut(&mut self.normals),
            Buf::State => bytemuck::cast_slice_mut(&mut self.state),
            Buf::Out => bytemuck::cast_slice_mut(&mut self.out),
            Buf::Acc => bytemuck::cast_slice_mut(&mut self.acc),
            Buf::Forces => bytemuck::cast_slice_mut(&mut self.forces),
            Buf::Need => bytemuck::cast_slice_mut(&mut self.need),
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `for_listed` visits each listed row once, in place, with its own index, and joins the
    /// chunks' results to what one pass over the list gives, for lists of one to many chunks;
    /// a list repeated, out of order or past the rows is taken sorted, once each, within them.
    #[test]
    fn listed_rows_are_visited_once_in_place() {
        for n in [0usize, 1, 5, PAR_MIN, PAR_MIN + 1, 10 * PAR_MIN + 7] {
            let list: Vec<u32> = (0..n as u32).filter(|i| i % 3 != 1).collect();
            let mut a = vec![0u32; n];
            let mut b = vec![0u64; n];
            let (count, sum, most) = for_listed(
                &list,
                &mut a,
                &mut b,
                || (0u32, 0u64, 0u32),
                |x, y| (x.0 + y.0, x.1 + y.1, x.2.max(y.2)),
                |i, ra, rb, r| {
                    *ra += 1;
                    *rb = 2 * i as u64;
                    *r = (r.0 + 1, r.1 + i as u64, r.2.max(i as u32));
                },
            );
            assert_eq!(count as usize, list.len());
            assert_eq!(sum, list.iter().map(|&i| i as u64).sum::<u64>());
            assert_eq!(most, list.last().copied().unwrap_or(0));
            for i in 0..n {
                let listed = list.contains(&(i as u32));
                assert_eq!(a[i], u32::from(listed), "row {i}");
                assert_eq!(b[i], if listed { 2 * i as u64 } else { 0 });
            }
        }
        let mut a = vec![0u32; 10];
        let mut b = vec![0u32; 10];
        let seen = for_listed(
            &[7, 3, 3, 42, 0, 9],
            &mut a,
            &mut b,
            Vec::new,
            |mut x, y| {
                x.extend(y);
                x
            },
            |i, ra, _, r| {
                *ra += 1;
                r.push(i);
            },
        );
        assert_eq!(seen, vec![0, 3, 7, 9]);
        assert_eq!(a, vec![1, 0, 0, 1, 0, 0, 0, 1, 0, 1]);
    }
}
