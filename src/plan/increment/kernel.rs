//! The kernels an increment runs, each one entry point of `abi::passes` (the bucket words'
//! scan runs the scan's passes on another buffer).

use crate::abi::passes::{self, Pass};

/// A kernel an increment runs: one entry point of `abi::passes`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Kernel {
    /// Positions into the search's frame.
    ToLocal,
    /// Small sliding: each slave's anchor evaluated.
    Anchor,
    /// The motion budget.
    Motion,
    /// The schedule's choice of search (and the dispatch slots for it).
    Schedule,
    /// The local search.
    LocalSearch,
    /// One refit pass of the search tree (`Entry::level`: which).
    TreeRefit,
    /// The tree walks' start: walk points and work counts.
    WalkStart,
    /// The tree walks.
    NearestWalk,
    /// The bucket search: the bucket words zeroed.
    BucketClear,
    /// The bucket search: facets counted per bucket.
    BucketCount,
    /// One level of the bucket words' scan, up (`Entry::level`).
    BucketScanBlocks,
    /// One level of the bucket words' scan, down (`Entry::level`).
    BucketScanAdd,
    /// The bucket search: the entries written.
    BucketFill,
    /// The bucket search's walks (in place of the tree walks).
    BucketWalk,
    /// Self-contact's crowding, over the buckets.
    BucketCrowded,
    /// One level of the work items' scan, up (`Entry::level`).
    ScanBlocks,
    /// One level of the work items' scan, down (`Entry::level`).
    ScanAdd,
    /// The chunks' dispatch.
    NearestArgs,
    /// The bounded chunks.
    NearestChunks,
    /// The chunks' ties.
    NearestTies,
    /// Self-contact's crowding.
    NearestCrowded,
    /// Each slave's hit.
    NearestFacet,
    /// The slaves the local increments visit, marked for the scan.
    ActiveMark,
    /// The marked slaves compacted into the active list (the schedule sizes the active slot
    /// from its count).
    ActiveCompact,
    /// The motion budget's reference positions.
    SetReference,
    /// The master's nodal normals (every master node's).
    NodalNormals,
    /// The facet nodes of the active slaves marked: the normals their springs read.
    NeedNormals,
    /// The nodal normals of the marked nodes.
    NodalNormalsNeeded,
    /// The penalty springs.
    Penalty,
    /// The active slaves' penalty springs.
    PenaltyActive,
    /// Forces into the fixed-point sums.
    ScatterForces,
    /// The active slaves' forces into the fixed-point sums.
    ScatterForcesActive,
    /// The sums per pair node.
    Gather,
    /// The sums of the active slaves and the other pair nodes.
    GatherActive,
    /// The pair's forces added into the caller's array, and its bound rows.
    AddForces,
    /// The same for the active slaves and the other pair nodes.
    AddForcesActive,
    /// The pair's status words into the statistics.
    PairStats,
    /// The stable increment and the statistics' last words.
    FinishStats,
}

impl Kernel {
    /// Every kernel, in the order `abi::passes::PASSES` declares their passes (for the tests
    /// that go over them all).
    #[cfg(test)]
    pub(crate) const ALL: [Kernel; 38] = [
        Kernel::ToLocal,
        Kernel::Anchor,
        Kernel::Motion,
        Kernel::Schedule,
        Kernel::LocalSearch,
        Kernel::TreeRefit,
        Kernel::ScanBlocks,
        Kernel::ScanAdd,
        Kernel::WalkStart,
        Kernel::NearestWalk,
        Kernel::BucketClear,
        Kernel::BucketCount,
        Kernel::BucketScanBlocks,
        Kernel::BucketScanAdd,
        Kernel::BucketFill,
        Kernel::BucketWalk,
        Kernel::BucketCrowded,
        Kernel::NearestArgs,
        Kernel::NearestChunks,
        Kernel::NearestTies,
        Kernel::NearestCrowded,
        Kernel::NearestFacet,
        Kernel::ActiveMark,
        Kernel::ActiveCompact,
        Kernel::NodalNormals,
        Kernel::NeedNormals,
        Kernel::NodalNormalsNeeded,
        Kernel::Penalty,
        Kernel::PenaltyActive,
        Kernel::ScatterForces,
        Kernel::ScatterForcesActive,
        Kernel::Gather,
        Kernel::GatherActive,
        Kernel::SetReference,
        Kernel::AddForces,
        Kernel::AddForcesActive,
        Kernel::PairStats,
        Kernel::FinishStats,
    ];

    /// The pass it is (shader, entry point, bindings).
    pub(crate) fn pass(self) -> &'static Pass {
        match self {
            Kernel::ToLocal => &passes::TO_LOCAL,
            Kernel::Anchor => &passes::ANCHOR,
            Kernel::Motion => &passes::MOTION,
            Kernel::Schedule => &passes::SCHEDULE,
            Kernel::LocalSearch => &passes::LOCAL_SEARCH,
            Kernel::TreeRefit => &passes::TREE_REFIT,
            Kernel::WalkStart => &passes::WALK_START,
            Kernel::NearestWalk => &passes::NEAREST_WALK,
            Kernel::BucketClear => &passes::BUCKET_CLEAR,
            Kernel::BucketCount => &passes::BUCKET_COUNT,
            Kernel::BucketScanBlocks => &passes::SCAN_BLOCKS,
            Kernel::BucketScanAdd => &passes::SCAN_ADD,
            Kernel::BucketFill => &passes::BUCKET_FILL,
            Kernel::BucketWalk => &passes::BUCKET_WALK,
            Kernel::BucketCrowded => &passes::BUCKET_CROWDED,
            Kernel::ScanBlocks => &passes::SCAN_BLOCKS,
            Kernel::ScanAdd => &passes::SCAN_ADD,
            Kernel::NearestArgs => &passes::NEAREST_ARGS,
            Kernel::NearestChunks => &passes::NEAREST_CHUNKS,
            Kernel::NearestTies => &passes::NEAREST_TIES,
            Kernel::NearestCrowded => &passes::NEAREST_CROWDED,
            Kernel::NearestFacet => &passes::NEAREST_FACET,
            Kernel::ActiveMark => &passes::ACTIVE_MARK,
            Kernel::ActiveCompact => &passes::ACTIVE_COMPACT,
            Kernel::SetReference => &passes::SET_REFERENCE,
            Kernel::NodalNormals => &passes::NODAL_NORMALS,
            Kernel::NeedNormals => &passes::NEED_NORMALS,
            Kernel::NodalNormalsNeeded => &passes::NODAL_NORMALS_NEEDED,
            Kernel::Penalty => &passes::PENALTY,
            Kernel::PenaltyActive => &passes::PENALTY_ACTIVE,
            Kernel::ScatterForces => &passes::SCATTER_FORCES,
            Kernel::ScatterForcesActive => &passes::SCATTER_FORCES_ACTIVE,
            Kernel::Gather => &passes::GATHER,
            Kernel::GatherActive => &passes::GATHER_ACTIVE,
            Kernel::AddForces => &passes::ADD_FORCES,
            Kernel::AddForcesActive => &passes::ADD_FORCES_ACTIVE,
            Kernel::PairStats => &passes::PAIR_STATS,
            Kernel::FinishStats => &passes::FINISH_STATS,
        }
    }
}
