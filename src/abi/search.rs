//! Structs and constants shared with the WGSL kernels (twins in `shaders/common.wgsl` and
//! `shaders/scan.wgsl`). Each is `#[repr(C)]`, `Pod`, explicitly padded, size-asserted.

use bytemuck::{Pod, Zeroable};

/// Invocations per workgroup of the one-item-per-invocation kernels (WGSL: `ITEM_WORKGROUP`).
pub const ITEM_WORKGROUP: u32 = 64;

/// Walk positions per group whose walks of the search tree start together at one node
/// (WGSL: `WALK_GROUP` in nearest_facet.wgsl).
pub const WALK_GROUP: u32 = 8;
/// Words scanned per workgroup by `scan.wgsl` (WGSL: `SCAN_BLOCK`).
pub const SCAN_BLOCK: u32 = 1024;
/// Lower corner of an empty box in the search tree (its upper corner is the negation)
/// (WGSL: `EMPTY_LO`).
pub const EMPTY_LO: f32 = 3.0e38;
/// "No facet" in a hit (WGSL: `NO_FACET`).
pub const NO_FACET: u32 = u32::MAX;
/// Flag in [`GpuHit::candidates`]: the closest point lies on a free edge or corner of the master
/// surface (an edge no other facet shares) and the slave is beside it, off the facets — the
/// master ends there, so this is no contact whatever the gap (WGSL: `HIT_BESIDE_FREE_EDGE`).
pub const HIT_BESIDE_FREE_EDGE: u32 = 1 << 31;
/// Flag in [`GpuHit::candidates`]: the hit was written by a settled walk of the local search that
/// left the slave's skin (`Buf::Skins`) valid for it; the global search's hits leave it clear
/// (WGSL: `HIT_WALKED`).
pub const HIT_WALKED: u32 = 1 << 30;
/// The bits of [`GpuHit::candidates`] that count facets (the others are flags) (WGSL:
/// `HIT_COUNT`).
pub const HIT_COUNT: u32 = HIT_WALKED - 1;
/// A skin's margin is shrunk by this fraction of the frame's coordinate scale (the largest
/// coordinate of the slave and the reference node, plus the radius): more than the round-off of
/// a projection or a distance computed in f32 (WGSL: `SKIN_ROUNDOFF`).
pub const SKIN_ROUNDOFF: f32 = 1.0 / 16384.0;

/// Uniform parameters of the search kernels. WGSL twin: `SearchParams` in common.wgsl.
///
/// Coordinates are relative to the search's frame (an origin near the master), in f32.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SearchParams {
    /// Search radius: facets farther than this from a slave node are not its partner.
    pub radius: f32,
    /// Growth of the search tree's leaf boxes: 32 f32 round-offs of the largest master
    /// coordinate in the frame, so a facet's distance computed in f32 is never below its box's.
    pub box_margin: f32,
    /// Active master facets.
    pub n_facets: u32,
    /// Slave nodes.
    pub n_slaves: u32,
    /// Levels of the search tree below its root: `2^tree_levels ≥ n_facets` leaf slots.
    pub tree_levels: u32,
    /// Spatial dimension (2 or 3).
    pub dim: u32,
    /// Local search: the most walk iterations per slave.
    pub max_local_iterations: u32,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Motion budget: a node moving more than half of this since the last global search asks
    /// for a global search (model length units).
    pub budget: f32,
    /// Nodes whose motion is measured (slaves and master nodes).
    pub n_motion_nodes: u32,
    /// The pair's reference master node (model node id): the motion budget measures every
    /// node's displacement relative to this node's, so that a contact model travelling as a
    /// whole uses none of it ([`crate::search::SearchStage::reference_node`]).
    pub ref_node: u32,
    /// The bucket search's cell size, frame units (0 with the tree): the cells are the
    /// largest power of two of box-grid steps at or below it ([`crate::abi::boxes`]), so it is
    /// chosen above the largest facet (a facet then spans at most two cells per axis).
    pub bucket_cell: f32,
    /// The master's box at the last global search, lower corner (xyz; w unused), in the frame.
    pub master_lo: [f32; 4],
    /// Its upper corner (xyz; w unused).
    pub master_hi: [f32; 4],
    /// The bucket search's hash table: `2^bucket_bits` buckets, then one for the facets too
    /// large to bin (0 with the tree).
    pub bucket_bits: u32,
    /// Word of the bucket grid where its entries (leaf slot, facet) start: after the bucket
    /// words and their scan levels ([`crate::abi::buckets::BucketLayout`]).
    pub bucket_entries: u32,
    /// Padding.
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<SearchParams>() == 96);

/// Word of `SearchParams` the schedule writes: the tree's box margin (WGSL: `P_BOX_MARGIN`).
pub const P_BOX_MARGIN: usize = std::mem::offset_of!(SearchParams, box_margin) / 4;
/// Word of `SearchParams`: the spatial dimension (WGSL: `P_DIM`).
pub const P_DIM: usize = std::mem::offset_of!(SearchParams, dim) / 4;
/// Word of `SearchParams`: the `FLAG_*` bits (WGSL: `P_FLAGS`).
pub const P_FLAGS: usize = std::mem::offset_of!(SearchParams, flags) / 4;
/// Word of `SearchParams`: the master box's lower corner (WGSL: `P_MASTER_LO`).
pub const P_MASTER_LO: usize = std::mem::offset_of!(SearchParams, master_lo) / 4;
/// Word of `SearchParams`: the master box's upper corner (WGSL: `P_MASTER_HI`).
pub const P_MASTER_HI: usize = std::mem::offset_of!(SearchParams, master_hi) / 4;

/// Flag: the local search walks the facets around every node of the tracked node's facets
/// (the more expensive, more robust alternative) (WGSL: `FLAG_WIDE_LOCAL`).
pub const FLAG_WIDE_LOCAL: u32 = 1;
/// Flag: self-contact, a slave's own facets and their neighbours are skipped
/// (WGSL: `FLAG_SELF_CONTACT`).
pub const FLAG_SELF_CONTACT: u32 = 2;
/// Flag: local increments visit every slave, tracked or not, instead of the active slaves the
/// last global search compacted (the baseline the compaction is tested and measured against;
/// the results are the same bits) (WGSL: `FLAG_EVERY_SLAVE`).
pub const FLAG_EVERY_SLAVE: u32 = 4;
/// Flag: no slave node is on an active master facet, so a slave the last global search left
/// untracked is nobody's facet node: the motion pass reads its position for the budget and
/// writes nothing (WGSL: `FLAG_SLAVES_APART`).
pub const FLAG_SLAVES_APART: u32 = 8;
/// Flag: the global search bins the facets into a hashed grid of cells and visits a slave's
/// cells in rings outward (`buckets.wgsl`) in place of the tree's walk (WGSL: `FLAG_BUCKETS`).
pub const FLAG_BUCKETS: u32 = 16;
/// A slave's tracking state, in the w of its motion reference (by node, which the motion pass
/// reads in node order): tracked, with no facet within the radius; below it, untracked
/// (WGSL: `SLAVE_TRACKED`).
pub const SLAVE_TRACKED: f32 = 1.0;
/// A slave's tracking state: tracked, with a facet within the radius (WGSL: `SLAVE_WITHIN`).
pub const SLAVE_WITHIN: f32 = 2.0;

/// The tracking state `hit` leaves its slave in: 0 untracked, [`SLAVE_TRACKED`] or
/// [`SLAVE_WITHIN`] (WGSL: `slave_state`).
pub fn slave_state(hit: &GpuHit) -> f32 {
    if hit.node == u32::MAX {
        0.0
    } else if hit.facet == NO_FACET {
        SLAVE_TRACKED
    } else {
        SLAVE_WITHIN
    }
}
/// Walk iterations of the local search before it gives up (WGSL default).
pub const MAX_LOCAL_ITERATIONS: u32 = 16;

/// Small sliding: a slave node's anchor on its master facet, fixed at the first global search.
/// WGSL twin: `Anchor` in anchor.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Anchor {
    /// Active facet index, `NO_FACET` when the slave projects onto no facet (unconstrained).
    pub facet: u32,
    /// The facet node nearest the anchor point at the start.
    pub node: u32,
    /// `ANCHOR_*` bits.
    pub flags: u32,
    /// Padding.
    pub _pad: u32,
    /// Load-transfer weights of the anchor point X0, fixed.
    pub weights: [f32; 4],
    /// Smoothed master normal N(X0) at the start (xyz); w: the facet's element length.
    pub normal0: [f32; 4],
    /// The facet's own normal at X0 at the start (xyz; its rotation turns the plane).
    pub facet_normal0: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<Anchor>() == 64);

/// Anchor flag: infinitesimal sliding, the plane's orientation never changes
/// (WGSL: `ANCHOR_FROZEN`).
pub const ANCHOR_FROZEN: u32 = 1;

/// The local frame of positions kept on the device. WGSL twin: `FrameParams` in motion.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameParams {
    /// Grid origin in model coordinates, rounded to f32 (w unused).
    pub origin: [f32; 4],
    /// Model nodes.
    pub n_nodes: u32,
    /// Padding.
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<FrameParams>() == 32);

/// Parameters of one pass of the tree's refit. WGSL twin: `TreeParams` in tree.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct TreeParams {
    /// The level whose boxes the pass computes: the leaves (`tree_levels`) from their facets,
    /// any other from the level below. One level per pass, so that no pass needs a workgroup
    /// barrier (on a CPU adapter a barrier switches between every SIMD group of the workgroup:
    /// a reduction of six levels in workgroup memory cost 4 µs per workgroup, 60 ms at 10^6
    /// facets on lavapipe).
    pub bottom: u32,
    /// Padding.
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<TreeParams>() == 16);

/// Invocations per workgroup of the tree's refit (WGSL: `TREE_WORKGROUP`).
pub const TREE_WORKGROUP: u32 = 64;

/// The refit passes of a tree of `levels` levels below its root, one per level, leaves first.
pub fn tree_passes(levels: u32) -> Vec<TreeParams> {
    (0..=levels)
        .rev()
        .map(|bottom| TreeParams {
            bottom,
            _pad: [0; 3],
        })
        .collect()
}

/// Parameters of one scan level. WGSL twin: `ScanParams` in scan.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct ScanParams {
    /// Words to scan.
    pub n: u32,
    /// Offset of the first word in the scan buffer.
    pub in_offset: u32,
    /// Offset where the block totals go.
    pub sums_offset: u32,
    /// Padding.
    pub _pad: u32,
}
const _: () = assert!(std::mem::size_of::<ScanParams>() == 16);

/// The raw search result of one slave node, f32 in the kernels' frame. WGSL twin: `Hit` in common.wgsl.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuHit {
    /// Index into the active facet list, [`NO_FACET`] when none lies within the radius.
    pub facet: u32,
    /// Tracked master node (model node id), `u32::MAX` when none: the nearest node of the
    /// nearest facet within the tracking radius (radius + budget) at the last global search,
    /// then where the local search's walk took it.
    pub node: u32,
    /// Facets examined for this node by the search that wrote the hit (an untracked slave's,
    /// which the local increments do not visit, by the last global search; a walk's, in its
    /// last step; a slave within its skin carries its last walk's), in the bits of
    /// [`HIT_COUNT`], with [`HIT_BESIDE_FREE_EDGE`] and [`HIT_WALKED`] above them.
    pub candidates: u32,
    /// The slave node (model node id).
    pub slave: u32,
    /// Load-transfer weights of the facet's nodes (shape functions at the closest point): in
    /// the first 32 bytes with the facet, one memory sector, all the scatter reads.
    pub weights: [f32; 4],
    /// Closest point (xyz, in the frame) and signed gap along the normal (w).
    pub point_gap: [f32; 4],
    /// Unit facet normal at the closest point (xyz) and distance (w).
    pub normal_dist: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuHit>() == 64);

impl GpuHit {
    /// A hit of slave node `slave` meaning "no facet within the radius".
    pub fn miss(slave: u32, candidates: u32) -> Self {
        Self {
            facet: NO_FACET,
            node: u32::MAX,
            candidates,
            slave,
            ..Self::zeroed()
        }
    }
}

/// The levels of the blocked scan over `n0` words: (offset, length) of each level in one
/// buffer; the last level has one block and its total lands at the returned `total_offset`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanLevels {
    /// (offset, words) of each level; level 0 is the data itself at offset 0.
    pub levels: Vec<(u32, u32)>,
    /// Offset of the grand total.
    pub total_offset: u32,
    /// Words the whole buffer needs.
    pub words: u32,
}

impl ScanLevels {
    /// Lays out the levels for `n0` words.
    pub fn new(n0: u32) -> Self {
        let mut levels = vec![(0u32, n0)];
        let mut offset = n0;
        let mut n = n0;
        loop {
            let blocks = n.div_ceil(SCAN_BLOCK).max(1);
            if blocks == 1 {
                break;
            }
            levels.push((offset, blocks));
            offset += blocks;
            n = blocks;
        }
        Self {
            levels,
            total_offset: offset,
            words: offset + 1,
        }
    }

    /// The [`ScanParams`] of level `i` (its block totals go to level i+1, or to the total).
    pub fn params(&self, i: usize) -> ScanParams {
        let (in_offset, n) = self.levels[i];
        let sums_offset = self
            .levels
            .get(i + 1)
            .map(|l| l.0)
            .unwrap_or(self.total_offset);
        ScanParams {
            n,
            in_offset,
            sums_offset,
            _pad: 0,
        }
    }
}

/// Workgroup counts (x, y) for `items` items at `per_group` per workgroup, folded so that x
/// stays within `max_per_dim` (65,535 by default).
pub fn fold_dispatch(items: u32, per_group: u32, max_per_dim: u32) -> (u32, u32) {
    let groups = items.div_ceil(per_group).max(1);
    if groups <= max_per_dim {
        (groups, 1)
    } else {
        let y = groups.div_ceil(max_per_dim);
        (groups.div_ceil(y), y)
    }
}

// The plan of a device-resident increment: one u32 buffer per search (WGSL twins: PLAN_* in
// common.wgsl; the passes: schedule.wgsl, motion.wgsl, stats.wgsl).
/// Plan word: increments since the last global search.
pub const PLAN_SINCE_GLOBAL: usize = 0;
/// Plan word: 1 once a global search has run.
pub const PLAN_SEARCHED: usize = 1;
/// Plan word: self-contact slaves crowded at the last global search.
pub const PLAN_CROWDED: usize = 2;
/// Plan word: the host asks for a global search in the next increment.
pub const PLAN_FORCE: usize = 3;
/// Plan word: this increment searches globally.
pub const PLAN_GLOBAL: usize = 4;
/// Plan word: why (`TRIGGER_*`).
pub const PLAN_TRIGGER: usize = 5;
/// Plan word: the schedule's interval.
pub const PLAN_INTERVAL: usize = 6;
/// Plan word: dispatch slots in use.
pub const PLAN_N_SLOTS: usize = 7;
/// Plan word: the pair nodes that are no slaves (the search's motion nodes that are no slaves:
/// the penalty's master pair nodes), and two rigid part slots, which `ACTIVE_NODES_SLOT` counts
/// beside the active slaves.
pub const PLAN_OTHER_NODES: usize = 8;
/// Most rigid part slots a penalty pair's nodes end with (the master's part and the slaves').
pub const MAX_RIGID_SLOTS: u32 = 2;
/// Plan word: global searches whose master box could not be taken (no finite master node; the
/// last box and margin kept).
pub const PLAN_FIT_FAILED: usize = 9;
/// Plan word: the most workgroups per dispatch dimension (the schedule folds the active
/// slaves' dispatch by it).
pub const PLAN_MAX_DIM: usize = 10;
/// The dispatch slot of the active slaves, the plan's first (`SLOT_LOCAL`: the local
/// increments' slave passes), sized by the schedule from the count the last global search's
/// `active_compact` left (WGSL: `ACTIVE_SLOT` in schedule.wgsl).
pub const ACTIVE_SLOT: usize = 0;
/// The dispatch slot of the active slaves and the pair's other nodes, the plan's second
/// (`SLOT_LOCAL`: `gather_active`, `add_forces_active`), sized by the schedule from the active
/// slaves' count and `PLAN_OTHER_NODES` (WGSL: `ACTIVE_NODES_SLOT` in schedule.wgsl).
pub const ACTIVE_NODES_SLOT: usize = 1;
/// Plan words: the `SearchParams` of the increment (24 words, from byte 256: the search passes
/// bind them as their uniform).
pub const PLAN_PARAMS: usize = 64;
/// Plan words: the dispatch slots, `PLAN_SLOT_WORDS` each: live (x, y, z, 0), full (x, y, z, kind).
pub const PLAN_SLOTS: usize = 88;
/// Words per dispatch slot.
pub const PLAN_SLOT_WORDS: usize = 8;
/// Most dispatch slots of a plan (WGSL: `MAX_PLAN_SLOTS` in schedule.wgsl).
pub const MAX_PLAN_SLOTS: usize = 48;
/// Words of a plan.
pub const PLAN_WORDS: usize = PLAN_SLOTS + MAX_PLAN_SLOTS * PLAN_SLOT_WORDS;
/// Slot kind: dispatched in global increments.
pub const SLOT_GLOBAL: u32 = 1;
/// Slot kind: dispatched in local increments.
pub const SLOT_LOCAL: u32 = 2;
/// Trigger code: the local search.
pub const TRIGGER_LOCAL: u32 = 0;
/// Trigger code: the first global search.
pub const TRIGGER_FIRST: u32 = 1;
/// Trigger code: the interval came round.
pub const TRIGGER_INTERVAL: u32 = 2;
/// Trigger code: the motion budget was used up.
pub const TRIGGER_BUDGET: u32 = 3;
/// Trigger code: self-contact was crowded.
pub const TRIGGER_CROWDED: u32 = 4;
/// Trigger code: the host asked for it.
pub const TRIGGER_REQUESTED: u32 = 5;

/// The words of a fresh plan: the schedule's `interval`, the search's `params` (the master box
/// and margin a first global search starts from), no dispatch slot yet.
pub fn fresh_plan(params: &SearchParams, interval: u32) -> Vec<u32> {
    let mut plan = vec![0u32; PLAN_WORDS];
    plan[PLAN_INTERVAL] = interval;
    plan[PLAN_PARAMS..PLAN_PARAMS + 24].copy_from_slice(bytemuck::cast_slice(&[*params]));
    plan
}

/// f32 bits as a u32 whose unsigned order is the floats' order (WGSL: `ordered_bits`).
pub fn ordered_bits(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The inverse of [`ordered_bits`] (WGSL: `from_ordered_bits`).
pub fn from_ordered_bits(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 {
        u & 0x7fff_ffff
    } else {
        !u
    })
}

/// Packed boxes (`[u32; 4]`, `abi::boxes`) of a tree of `levels` levels: one per heap
/// node, nodes 0..2^(levels+1) (node 0 unused).
pub fn box_words(levels: u32) -> usize {
    2usize << levels
}

/// Words of a slave's `best` record (WGSL: `BEST_WORDS`): distance² bits, the chunks' facet at
/// it, unused, candidates, the walk's facet, the first leaf slot left to the chunks, the walk's
/// distance² bits, unused.
pub const BEST_WORDS: usize = 8;
/// Most workgroups per dimension of the chunks' indirect dispatch (WebGPU's default limit;
/// WGSL: `MAX_GROUPS_PER_DIM` in nearest_facet.wgsl).
pub const MAX_GROUPS_PER_DIM: u32 = 65_535;

/// The SearchParams words of a plan.
pub fn plan_params(plan: &[u32]) -> SearchParams {
    bytemuck::pod_read_unaligned(bytemuck::cast_slice(&plan[PLAN_PARAMS..PLAN_PARAMS + 24]))
}
