//! Every compute pass of abut declared once: its shader file, entry point, bindings and how many
//! items a workgroup covers. The GPU executors build their pipelines and bind groups from these
//! declarations, the benchmark takes its pass names from them, and `tests/shaders.rs` checks each
//! one against naga's reflection of its WGSL (binding numbers, address spaces, access, workgroup
//! size), so a binding cannot be changed in one place and not in the other.
//!
//! Long file: one declaration per pass, read as a table; split, it would be a table in pieces.

use crate::abi::search::{ITEM_WORKGROUP, SCAN_BLOCK};

/// A buffer a pass binds, named by what it holds (one of each per search or penalty pair).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Buf {
    /// Uniform `SearchParams` (grid, radius, counts, flags).
    SearchParams,
    /// Uniform `ScanParams` of one scan level.
    ScanParams,
    /// Uniform `TreeParams` of one refit pass of the search tree.
    TreeParams,
    /// Uniform `FrameParams` (the grid frame of positions kept on the device).
    FrameParams,
    /// Uniform `PenaltyParams`.
    PenaltyParams,
    /// The caller's positions (`vec4<f32>` per model node, model frame).
    Positions,
    /// Grid-local node positions (xyz) and masses (w).
    Nodes,
    /// Active master facets, node ids padded with `NO_NODE`.
    Facets,
    /// The model node id of each slave.
    Slaves,
    /// The model's node→facet adjacency (CSR over active facets).
    Adjacency,
    /// The array a scan level works on: the nearest facet's work items, with all their levels.
    ScanData,
    /// The active facet of each leaf slot of the search tree (Morton order).
    Order,
    /// The search tree's boxes: one packed `vec4<u32>` per heap node.
    Boxes,
    /// The status words (`STATUS_*`, reset each increment), then the active slaves kept from one
    /// global search to the next (`ACTIVE_LIST`: their count, then their slave indices).
    Status,
    /// One `Hit` per slave.
    Hits,
    /// Grid-local positions at the last global search (the motion budget's reference, xyz) and,
    /// in w, each slave's tracking state (`SLAVE_TRACKED`, `SLAVE_WITHIN`), by model node.
    Reference,
    /// Per slave, its skin (`local_search.wgsl`): its position relative to the pair's reference
    /// node at its last settled walk (xyz) and the margin that walk left (w), valid while its hit
    /// carries `HIT_WALKED`.
    Skins,
    /// The nodes whose motion the budget watches.
    MotionNodes,
    /// Small sliding: one `Anchor` per slave.
    Anchors,
    /// Nearest-facet work items: chunk counts per slave, scanned.
    Work,
    /// The slaves in the order the tree walks take them: position in the frame (f32 bits, xyz)
    /// and model node id (w), one `vec4<u32>` per slave.
    WalkPoints,
    /// Nearest-facet record per slave (distance² bits, facet, crowded, candidates).
    Best,
    /// Indirect dispatch arguments (x, y, z).
    Args,
    /// Node velocities (`vec4<f32>` per model node).
    Velocities,
    /// Smoothed nodal normals (`vec4<f32>` per model node).
    Normals,
    /// The pair's nodes (node, slave index, adjacency start, end).
    PairNodes,
    /// The pair's node→facet adjacency.
    PairAdjacency,
    /// Pair-node index of each active facet's nodes.
    FacetNodes,
    /// Per-slave penalty state (friction force, area, dissipation).
    State,
    /// Per-slave penalty results (`ContactOut`).
    Out,
    /// The gather's fixed-point sums (8 words per pair node).
    Acc,
    /// Contact force and bound row per pair node.
    Forces,
    /// The need bits per pair node and rigid slot (`NEED_NORMAL`, `NEED_FORCE`): which nodes a
    /// spring reads or scattered onto this increment.
    Need,
    /// The device-resident plan of a search (schedule state, the fitted grid, dispatch slots).
    Plan,
    /// The caller's force buffer (`vec4<f32>` per model node) of a device-resident increment.
    HostForces,
    /// The node-wise bound's rows per model node, summed over the pairs of an increment.
    Rows,
    /// The statistics of a device-resident increment (`IncrementStats`).
    Stats,
    /// Uniform `IntegrateParams` (the device integrator of a host program).
    IntegrateParams,
    /// Node masses (f32 per model node).
    Masses,
    /// The active slaves: the words of the status buffer from `ACTIVE_LIST` (no pass binds it
    /// by this name; a split increment hands it over as a role of its own).
    Active,
    /// The bucket search's grid: the buckets' words, their scan levels, the entries
    /// (`abi::buckets::BucketLayout`).
    Grid,
}

/// How a shader declares a binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>` (atomics included).
    ReadWrite,
}

/// One binding of group 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// `@binding(n)`.
    pub index: u32,
    /// The buffer bound there.
    pub buf: Buf,
    /// Its declared access.
    pub access: Access,
}

/// What a pass's invocations are one of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Items {
    /// One per slave node.
    Slaves,
    /// One per active slave (indirect, from the plan's active slot: the slaves the last global
    /// search left tracked).
    ActiveSlaves,
    /// One per group of `WALK_GROUP` slave nodes (walk positions).
    SlaveGroups,
    /// One per active facet.
    Facets,
    /// One per watched node (motion budget).
    MotionNodes,
    /// One per model node.
    Nodes,
    /// One per node of a penalty pair.
    PairNodes,
    /// One per active slave, then per node of a penalty pair that is no slave and per rigid
    /// part slot (indirect, from the plan's active nodes slot).
    ActivePairNodes,
    /// One invocation in all.
    One,
    /// One per nearest-facet work item, dispatched indirectly from `Buf::Args`.
    WorkItems,
    /// One per node of one level of the search tree (a refit pass's bottom level).
    TreeNodes,
    /// One workgroup per block of `SCAN_BLOCK` words of a scan level.
    ScanBlocks,
    /// One per leaf slot of the search tree (the bucket search's binning).
    LeafSlots,
    /// One per word of the bucket search's buckets (`2^bits + 1`).
    Buckets,
}

/// A compute pass: one entry point of one shader file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pass {
    /// The shader file's stem (`shaders/<stem>.wgsl`, preludes per `abi::shaders`).
    pub stem: &'static str,
    /// The entry point, also the pass's name in counters and benchmarks.
    pub entry: &'static str,
    /// Its bindings, increasing.
    pub bindings: &'static [Binding],
    /// What its invocations are one of.
    pub items: Items,
    /// Items a workgroup covers (the workgroup size, or `SCAN_BLOCK` words for a scan).
    pub per_workgroup: u32,
}

const fn b(index: u32, buf: Buf, access: Access) -> Binding {
    Binding { index, buf, access }
}

use Access::{Read as R, ReadWrite as RW, Uniform as U};
use Buf::*;

/// `tree.wgsl`: one refit pass of the search tree's boxes (the leaves from the facets, or up to
/// six levels above the last pass's).
pub const TREE_REFIT: Pass = Pass {
    stem: "tree",
    entry: "tree_refit",
    bindings: &[
        b(0, SearchParams, U),
        b(1, TreeParams, U),
        b(2, Nodes, R),
        b(3, Facets, R),
        b(4, Order, R),
        b(5, Boxes, RW),
        b(6, Status, RW),
    ],
    items: Items::TreeNodes,
    per_workgroup: crate::abi::search::TREE_WORKGROUP,
};

const SCAN_BINDINGS: &[Binding] = &[b(0, ScanParams, U), b(1, ScanData, RW)];

/// `scan.wgsl`: one level's blocks scanned, their totals to the next level.
pub const SCAN_BLOCKS: Pass = Pass {
    stem: "scan",
    entry: "scan_blocks",
    bindings: SCAN_BINDINGS,
    items: Items::ScanBlocks,
    per_workgroup: SCAN_BLOCK,
};

/// `scan.wgsl`: the next level's scanned totals added back.
pub const SCAN_ADD: Pass = Pass {
    stem: "scan",
    entry: "scan_add",
    bindings: SCAN_BINDINGS,
    items: Items::ScanBlocks,
    per_workgroup: SCAN_BLOCK,
};

/// The bindings of the nearest-facet passes that read a work item's candidates.
const CHUNK_BINDINGS: &[Binding] = &[
    b(0, SearchParams, U),
    b(1, Nodes, R),
    b(2, Facets, R),
    b(4, Order, R),
    b(5, Boxes, R),
    b(8, Adjacency, R),
    b(9, Work, RW),
    b(10, Best, RW),
    b(12, WalkPoints, RW),
];

/// `nearest_facet.wgsl`: the slaves' positions and node ids gathered in the order the walks
/// take them, and the tree node where each group of `WALK_GROUP` walks starts.
pub const WALK_START: Pass = Pass {
    stem: "nearest_facet",
    entry: "walk_start",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(3, Slaves, R),
        b(5, Boxes, R),
        b(9, Work, RW),
        b(12, WalkPoints, RW),
    ],
    items: Items::SlaveGroups,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nearest_facet.wgsl`: each slave's pruned walk of the search tree; the chunks of what a
/// capped walk did not reach counted.
pub const NEAREST_WALK: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_walk",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(4, Order, R),
        b(5, Boxes, R),
        b(8, Adjacency, R),
        b(9, Work, RW),
        b(12, WalkPoints, RW),
        b(13, Best, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `buckets.wgsl`: the bucket words zeroed before the count.
pub const BUCKET_CLEAR: Pass = Pass {
    stem: "buckets",
    entry: "bucket_clear",
    bindings: &[b(0, SearchParams, U), b(14, Grid, RW)],
    items: Items::Buckets,
    per_workgroup: ITEM_WORKGROUP,
};

/// `buckets.wgsl`: each leaf slot's facet counted in the buckets of its cells.
pub const BUCKET_COUNT: Pass = Pass {
    stem: "buckets",
    entry: "bucket_count",
    bindings: &[b(0, SearchParams, U), b(5, Boxes, R), b(14, Grid, RW)],
    items: Items::LeafSlots,
    per_workgroup: ITEM_WORKGROUP,
};

/// `buckets.wgsl`: each leaf slot's entries written into its buckets (after the scan).
pub const BUCKET_FILL: Pass = Pass {
    stem: "buckets",
    entry: "bucket_fill",
    bindings: &[
        b(0, SearchParams, U),
        b(4, Order, R),
        b(5, Boxes, R),
        b(14, Grid, RW),
    ],
    items: Items::LeafSlots,
    per_workgroup: ITEM_WORKGROUP,
};

/// `buckets.wgsl`: each slave's cells in rings outward, pruned; the chunks of what a capped walk
/// did not reach counted (as `nearest_walk`).
pub const BUCKET_WALK: Pass = Pass {
    stem: "buckets",
    entry: "bucket_walk",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(5, Boxes, R),
        b(8, Adjacency, R),
        b(9, Work, RW),
        b(12, WalkPoints, RW),
        b(13, Best, RW),
        b(15, Grid, R),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `buckets.wgsl`: self-contact's crowding check over the cells within the radius.
pub const BUCKET_CROWDED: Pass = Pass {
    stem: "buckets",
    entry: "bucket_crowded",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(5, Boxes, R),
        b(8, Adjacency, R),
        b(10, Best, RW),
        b(12, WalkPoints, RW),
        b(15, Grid, R),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nearest_facet.wgsl`: the indirect dispatch of the work items.
pub const NEAREST_ARGS: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_args",
    bindings: &[b(0, SearchParams, U), b(9, Work, RW), b(11, Args, RW)],
    items: Items::One,
    per_workgroup: 1,
};

/// `nearest_facet.wgsl`: each chunk's nearest facet, the best distance per slave.
pub const NEAREST_CHUNKS: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_chunks",
    bindings: CHUNK_BINDINGS,
    items: Items::WorkItems,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nearest_facet.wgsl`: the lowest facet id at the best distance.
pub const NEAREST_TIES: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_ties",
    bindings: CHUNK_BINDINGS,
    items: Items::WorkItems,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nearest_facet.wgsl`: self-contact's crowding, by a walk bounded by the radius.
pub const NEAREST_CROWDED: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_crowded",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(4, Order, R),
        b(5, Boxes, R),
        b(8, Adjacency, R),
        b(10, Best, RW),
        b(12, WalkPoints, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nearest_facet.wgsl`: the hit of each slave from its winning facet; fallbacks and crowding
/// counted.
pub const NEAREST_FACET: Pass = Pass {
    stem: "nearest_facet",
    entry: "nearest_facet",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(3, Slaves, R),
        b(6, Status, RW),
        b(7, Hits, RW),
        b(8, Adjacency, R),
        b(12, WalkPoints, RW),
        b(13, Best, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `motion.wgsl`: every increment, the motion nodes (in node order) into the frame where the
/// local passes read them (the master's box raised, non-finite nodes named), and the largest
/// motion since the last global search against the budget.
pub const MOTION: Pass = Pass {
    stem: "motion",
    entry: "motion",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, RW),
        b(2, Reference, RW),
        b(3, MotionNodes, R),
        b(4, Status, RW),
        b(6, Adjacency, R),
        b(7, FrameParams, U),
        b(8, Positions, R),
    ],
    items: Items::MotionNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `motion.wgsl`: the watched nodes' positions become the budget's reference (global
/// increments of a device-resident increment).
pub const SET_REFERENCE: Pass = Pass {
    stem: "motion",
    entry: "set_reference",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, RW),
        b(2, Reference, RW),
        b(3, MotionNodes, R),
    ],
    items: Items::MotionNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `schedule.wgsl`: global or local, the fitted grid and the dispatch sizes, on the device.
pub const SCHEDULE: Pass = Pass {
    stem: "schedule",
    entry: "schedule",
    bindings: &[b(1, Plan, RW), b(2, Status, RW), b(3, Args, RW)],
    items: Items::One,
    per_workgroup: 1,
};

/// `local_search.wgsl`: each active slave's walk from its tracked node (its hit, and its tracking
/// state in its reference's w).
pub const LOCAL_SEARCH: Pass = Pass {
    stem: "local_search",
    entry: "local_search",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(3, Slaves, R),
        b(4, Adjacency, R),
        b(5, Status, RW),
        b(6, Hits, RW),
        b(7, Reference, RW),
        b(8, Skins, RW),
    ],
    items: Items::ActiveSlaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `active.wgsl`: each slave marked for the local increments (tracked, or every slave with
/// `FLAG_EVERY_SLAVE`) into the work items' first level, to be scanned; its tracking state
/// into its reference's w.
pub const ACTIVE_MARK: Pass = Pass {
    stem: "active",
    entry: "active_mark",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Hits, R),
        b(2, Work, RW),
        b(4, Slaves, R),
        b(5, Reference, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `active.wgsl`: the marked slaves compacted in slave order into the active list (the schedule
/// sizes the active slot from its count).
pub const ACTIVE_COMPACT: Pass = Pass {
    stem: "active",
    entry: "active_compact",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Hits, R),
        b(2, Work, RW),
        b(3, Status, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `motion.wgsl`: every model node into the search's frame, the master's box raised and a
/// non-finite node named (small sliding: every increment; otherwise global increments, before
/// the search).
pub const TO_LOCAL: Pass = Pass {
    stem: "motion",
    entry: "to_local",
    bindings: &[
        b(1, Nodes, RW),
        b(4, Status, RW),
        b(6, Adjacency, R),
        b(7, FrameParams, U),
        b(8, Positions, R),
    ],
    items: Items::Nodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `anchor.wgsl`: small sliding's anchors evaluated on the deformed master.
pub const ANCHOR: Pass = Pass {
    stem: "anchor",
    entry: "anchor",
    bindings: &[
        b(0, SearchParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(3, Slaves, R),
        b(4, Anchors, R),
        b(5, Status, RW),
        b(6, Hits, RW),
        b(7, Adjacency, R),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nodal_normals.wgsl`: smoothed normals of every master node of the pair (small sliding).
pub const NODAL_NORMALS: Pass = Pass {
    stem: "nodal_normals",
    entry: "nodal_normals",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(3, PairNodes, R),
        b(4, PairAdjacency, R),
        b(5, Normals, RW),
    ],
    items: Items::PairNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nodal_normals.wgsl`: the facet nodes of each active slave with a facet marked: the
/// normals its spring reads.
pub const NEED_NORMALS: Pass = Pass {
    stem: "nodal_normals",
    entry: "need_normals",
    bindings: &[
        b(0, PenaltyParams, U),
        b(6, Need, RW),
        b(7, Hits, R),
        b(8, Status, R),
        b(9, FacetNodes, R),
    ],
    items: Items::ActiveSlaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `nodal_normals.wgsl`: smoothed normals of the master nodes marked needed.
pub const NODAL_NORMALS_NEEDED: Pass = Pass {
    stem: "nodal_normals",
    entry: "nodal_normals_needed",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, Nodes, R),
        b(2, Facets, R),
        b(3, PairNodes, R),
        b(4, PairAdjacency, R),
        b(5, Normals, RW),
        b(6, Need, RW),
    ],
    items: Items::PairNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `penalty.wgsl`: force, friction, outputs and limits of each slave.
pub const PENALTY: Pass = Pass {
    stem: "penalty",
    entry: "penalty",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, Nodes, R),
        b(2, Velocities, R),
        b(3, Facets, R),
        b(4, Hits, R),
        b(5, Normals, R),
        b(6, State, RW),
        b(7, Out, RW),
        b(8, Status, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `penalty.wgsl`: the same for the active slaves only (local increments).
pub const PENALTY_ACTIVE: Pass = Pass {
    entry: "penalty_active",
    items: Items::ActiveSlaves,
    ..PENALTY
};

/// `gather.wgsl`: each contact's reaction onto its facet's nodes in fixed point.
pub const SCATTER_FORCES: Pass = Pass {
    stem: "gather",
    entry: "scatter_forces",
    bindings: &[
        b(0, PenaltyParams, U),
        b(2, FacetNodes, R),
        b(3, Hits, R),
        b(4, Out, R),
        b(5, Status, R),
        b(6, Acc, RW),
        b(11, Need, RW),
    ],
    items: Items::Slaves,
    per_workgroup: ITEM_WORKGROUP,
};

/// `gather.wgsl`: the same for the active slaves only (local increments).
pub const SCATTER_FORCES_ACTIVE: Pass = Pass {
    entry: "scatter_forces_active",
    items: Items::ActiveSlaves,
    ..SCATTER_FORCES
};

/// `gather.wgsl`: each pair node's force from its own contact and its sums.
pub const GATHER: Pass = Pass {
    stem: "gather",
    entry: "gather",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, PairNodes, R),
        b(3, Hits, R),
        b(4, Out, R),
        b(5, Status, R),
        b(6, Acc, RW),
        b(7, Forces, RW),
        b(11, Need, RW),
    ],
    items: Items::PairNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `gather.wgsl`: the same for the active slaves and the pair's other nodes (local increments
/// of a pair whose slaves are no master nodes).
pub const GATHER_ACTIVE: Pass = Pass {
    entry: "gather_active",
    items: Items::ActivePairNodes,
    ..GATHER
};

/// `gather.wgsl`: each pair node's force into the caller's buffer, its row into the rows.
pub const ADD_FORCES: Pass = Pass {
    stem: "gather",
    entry: "add_forces",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, PairNodes, R),
        b(3, Hits, R),
        b(7, Forces, RW),
        b(8, HostForces, RW),
        b(9, Rows, RW),
        b(10, Stats, RW),
        b(11, Need, RW),
    ],
    items: Items::PairNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `gather.wgsl`: the same for the active slaves and the pair's other nodes (local increments
/// of a pair whose slaves are no master nodes), which it reads from the status words.
pub const ADD_FORCES_ACTIVE: Pass = Pass {
    stem: "gather",
    entry: "add_forces_active",
    bindings: &[
        b(0, PenaltyParams, U),
        b(1, PairNodes, R),
        b(3, Hits, R),
        b(5, Status, R),
        b(7, Forces, RW),
        b(8, HostForces, RW),
        b(9, Rows, RW),
        b(10, Stats, RW),
        b(11, Need, RW),
    ],
    items: Items::ActivePairNodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// `stats.wgsl`: a pair's status words into the increment's statistics.
pub const PAIR_STATS: Pass = Pass {
    stem: "stats",
    entry: "pair_stats",
    bindings: &[b(0, Status, R), b(1, Plan, RW), b(2, Stats, RW)],
    items: Items::One,
    per_workgroup: 1,
};

/// `stats.wgsl`: the stable increment from the bound, the increment counted.
pub const FINISH_STATS: Pass = Pass {
    stem: "stats",
    entry: "finish_stats",
    bindings: &[b(2, Stats, RW)],
    items: Items::One,
    per_workgroup: 1,
};

/// `integrate.wgsl`: central differences for point masses (a host program's integrator).
pub const INTEGRATE: Pass = Pass {
    stem: "integrate",
    entry: "integrate",
    bindings: &[
        b(0, IntegrateParams, U),
        b(1, Positions, RW),
        b(2, Velocities, RW),
        b(3, HostForces, RW),
        b(4, Masses, R),
    ],
    items: Items::Nodes,
    per_workgroup: ITEM_WORKGROUP,
};

/// Every pass, in the order an increment may run them.
pub const PASSES: [Pass; 37] = [
    TO_LOCAL,
    ANCHOR,
    MOTION,
    SCHEDULE,
    LOCAL_SEARCH,
    TREE_REFIT,
    SCAN_BLOCKS,
    SCAN_ADD,
    WALK_START,
    NEAREST_WALK,
    BUCKET_CLEAR,
    BUCKET_COUNT,
    BUCKET_FILL,
    BUCKET_WALK,
    BUCKET_CROWDED,
    NEAREST_ARGS,
    NEAREST_CHUNKS,
    NEAREST_TIES,
    NEAREST_CROWDED,
    NEAREST_FACET,
    ACTIVE_MARK,
    ACTIVE_COMPACT,
    NODAL_NORMALS,
    NEED_NORMALS,
    NODAL_NORMALS_NEEDED,
    PENALTY,
    PENALTY_ACTIVE,
    SCATTER_FORCES,
    SCATTER_FORCES_ACTIVE,
    GATHER,
    GATHER_ACTIVE,
    SET_REFERENCE,
    ADD_FORCES,
    ADD_FORCES_ACTIVE,
    PAIR_STATS,
    FINISH_STATS,
    INTEGRATE,
];
