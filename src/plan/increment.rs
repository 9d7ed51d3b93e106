//! The device-resident increment as a value: the ordered list of [`Entry`]s — each one kernel
//! of `abi::passes` for one pair, with its size (items known when recording, or a dispatch the
//! device decides) — written once here, from each pair's [`PairShape`], and run by either
//! executor: the GPU records one dispatch per entry, the CPU path calls the entry's mirror.
//! Because both run the same list, an increment can be split at any entry (`run_split`).

use crate::abi::buckets::BucketLayout;
use crate::abi::groups::{self, Group};
use crate::abi::search::{
    fold_dispatch, fresh_plan, ScanLevels, SearchParams, ACTIVE_NODES_SLOT, ACTIVE_SLOT,
    ITEM_WORKGROUP, MAX_PLAN_SLOTS, MAX_RIGID_SLOTS, PLAN_MAX_DIM, PLAN_N_SLOTS, PLAN_OTHER_NODES,
    PLAN_SLOTS, PLAN_SLOT_WORDS, SLOT_GLOBAL, SLOT_LOCAL, TREE_WORKGROUP, WALK_GROUP,
};
use crate::abi::search::{tree_passes, FLAG_BUCKETS, SCAN_BLOCK};
use crate::error::{Error, Result};

mod kernel;
pub(crate) use kernel::Kernel;

/// How many invocations an entry runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Size {
    /// Known when recording: `items`, `per` to a workgroup.
    Items(u32, u32),
    /// Decided on the device: the live (x, y, z) at this byte offset of the pair's plan words
    /// (zero workgroups when the schedule chose the other search).
    Slot(u64),
    /// Decided on the device: the pair's nearest-facet chunk dispatch (its args words).
    Chunks,
}

/// One kernel of an increment for one pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Entry {
    /// The group it is recorded (and timed, and counted) under.
    pub group: &'static Group,
    /// The kernel.
    pub kernel: Kernel,
    /// The pair (index in the increment's pairs; the finishing entries name pair 0).
    pub pair: usize,
    /// Which tree refit pass or scan level (0 otherwise).
    pub level: usize,
    /// Its size.
    pub size: Size,
}

/// The dispatch slots of a search's plan: each names the byte offset of its live indirect
/// arguments in the plan words.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Slots {
    /// Local increments: one invocation per active slave (local_search, penalty_active,
    /// scatter_forces_active): the plan's `ACTIVE_SLOT`, sized by the schedule from the count
    /// the last global search's active_compact left (empty until the first).
    pub active: u64,
    /// Global: one per node of each refit pass's bottom level (tree_refit; the leaves alone for
    /// the bucket search).
    pub tree_passes: Vec<u64>,
    /// Global: one per block of each level of the work-item scan.
    pub work_levels: Vec<u64>,
    /// Global, the bucket search: one per bucket word (bucket_clear).
    pub buckets: u64,
    /// Global, the bucket search: one per block of each level of the bucket words' scan.
    pub bucket_levels: Vec<u64>,
    /// Global: one per slave (nearest_walk, nearest_crowded, nearest_facet, active_mark,
    /// active_compact, penalty, scatter_forces).
    pub slaves: u64,
    /// Global: one per group of `WALK_GROUP` slaves (walk_start).
    pub slave_groups: u64,
    /// Global: one invocation (nearest_args).
    pub one: u64,
    /// Local increments: one invocation per active slave, then per pair node that is no slave
    /// and per rigid part slot the pair may have (gather_active, add_forces_active): the
    /// plan's `ACTIVE_NODES_SLOT`, sized by the schedule.
    pub active_nodes: u64,
    /// Global: one per pair node and rigid part slot the pair may have (gather and add_forces
    /// of a pair whose local increments run the active ones).
    pub pair_nodes: u64,
    /// Global: one per watched node (set_reference).
    pub motion_nodes: u64,
    /// Global: one per model node (to_local).
    pub nodes: u64,
}

/// Appends a slot of `items` items, `per` per workgroup, of `kind` to the plan words; returns
/// the byte offset of its live arguments.
fn add_slot(plan: &mut [u32], items: u32, per: u32, kind: u32, max_dim: u32) -> Result<u64> {
    let k = plan[PLAN_N_SLOTS] as usize;
    if k >= MAX_PLAN_SLOTS {
        return Err(Error::Gpu {
            during: "planning a device-resident increment".into(),
            message: format!("more than {MAX_PLAN_SLOTS} dispatch slots"),
        });
    }
    let (x, y) = fold_dispatch(items, per, max_dim);
    let s = PLAN_SLOTS + k * PLAN_SLOT_WORDS;
    plan[s..s + 8].copy_from_slice(&[0, 0, 0, 0, x, y, 1, kind]);
    plan[PLAN_N_SLOTS] += 1;
    Ok(4 * s as u64)
}

/// The words of a fresh plan for `params` (the device's grid, flags and capacities) and a
/// schedule interval, with its dispatch slots (folded beyond `max_dim` workgroups) for
/// `n_nodes_watched` motion nodes of a model of `n_nodes` nodes.
pub(crate) fn initial_plan(
    params: &SearchParams,
    interval: u32,
    n_nodes_watched: u32,
    n_nodes: u32,
    max_dim: u32,
) -> Result<(Vec<u32>, Slots)> {
    let work_levels = ScanLevels::new(params.n_slaves + 1);
    let mut plan = fresh_plan(params, interval);
    plan[PLAN_MAX_DIM] = max_dim;
    let (g, l) = (SLOT_GLOBAL, SLOT_LOCAL);
    let iw = ITEM_WORKGROUP;
    // the active slaves' slot, empty until a global search sizes it
    let active = add_slot(&mut plan, 0, iw, l, max_dim)?;
    debug_assert_eq!(
        active,
        4 * (PLAN_SLOTS + ACTIVE_SLOT * PLAN_SLOT_WORDS) as u64
    );
    let s = PLAN_SLOTS + ACTIVE_SLOT * PLAN_SLOT_WORDS;
    plan[s + 4..s + 7].copy_from_slice(&[0, 0, 0]);
    // the active slaves' and other pair nodes' slot, sized by the schedule too
    let active_nodes = add_slot(&mut plan, 0, iw, l, max_dim)?;
    debug_assert_eq!(
        active_nodes,
        4 * (PLAN_SLOTS + ACTIVE_NODES_SLOT * PLAN_SLOT_WORDS) as u64
    );
    let s = PLAN_SLOTS + ACTIVE_NODES_SLOT * PLAN_SLOT_WORDS;
    plan[s + 4..s + 7].copy_from_slice(&[0, 0, 0]);
    // a penalty pair's nodes are its slaves, then the master nodes that are no slaves: the
    // search's motion nodes; then at most two rigid part slots
    let other_nodes = n_nodes_watched.saturating_sub(params.n_slaves) + MAX_RIGID_SLOTS;
    plan[PLAN_OTHER_NODES] = other_nodes;
    let mut slots = Slots {
        active,
        active_nodes,
        ..Default::default()
    };
    // the bucket search refits the tree's leaves alone
    let refits = if params.flags & FLAG_BUCKETS != 0 {
        1
    } else {
        usize::MAX
    };
    for tp in tree_passes(params.tree_levels).into_iter().take(refits) {
        slots.tree_passes.push(add_slot(
            &mut plan,
            1 << tp.bottom,
            TREE_WORKGROUP,
            g,
            max_dim,
        )?);
    }
    for level in &work_levels.levels {
        slots
            .work_levels
            .push(add_slot(&mut plan, level.1, SCAN_BLOCK, g, max_dim)?);
    }
    if params.flags & FLAG_BUCKETS != 0 {
        let layout = BucketLayout::new(params.n_facets);
        slots.buckets = add_slot(&mut plan, layout.buckets(), iw, g, max_dim)?;
        for level in &layout.levels.levels {
            slots
                .bucket_levels
                .push(add_slot(&mut plan, level.1, SCAN_BLOCK, g, max_dim)?);
        }
    }
    slots.slaves = add_slot(&mut plan, params.n_slaves, iw, g, max_dim)?;
    slots.slave_groups = add_slot(
        &mut plan,
        params.n_slaves.div_ceil(WALK_GROUP),
        iw,
        g,
        max_dim,
    )?;
    slots.one = add_slot(&mut plan, 1, 1, g, max_dim)?;
    slots.pair_nodes = add_slot(&mut plan, params.n_slaves + other_nodes, iw, g, max_dim)?;
    slots.motion_nodes = add_slot(&mut plan, n_nodes_watched, iw, g, max_dim)?;
    slots.nodes = add_slot(&mut plan, n_nodes, iw, g, max_dim)?;
    Ok((plan, slots))
}

/// What the entries of one pair depend on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct PairShape {
    /// Small sliding: the anchors are evaluated, nothing searched.
    pub anchored: bool,
    /// Self-contact: the crowding pass runs.
    pub self_contact: bool,
    /// The global search bins the facets into buckets (`FLAG_BUCKETS`) in place of the tree's
    /// walk: the tree's leaf boxes alone are refitted.
    pub buckets: bool,
    /// The host proved the schedule will choose the local search: the global search's
    /// entries (which would get zero workgroups) are left out.
    pub local_only: bool,
    /// The host knows the schedule will choose the global search (it asked for one, or none
    /// has run): the motion budget, which only decides for a local search, and the local
    /// search (zero workgroups) are left out.
    pub global_only: bool,
    /// Model nodes.
    pub n_nodes: u32,
    /// Nodes the motion budget watches.
    pub n_motion_nodes: u32,
    /// Slave nodes.
    pub n_slaves: u32,
    /// Nodes of the penalty pair (slaves and master nodes).
    pub n_pair_nodes: u32,
    /// Local increments gather and add forces for the active slaves and the other pair nodes
    /// only (`gather_active`, `add_forces_active`), global ones for every pair node from the
    /// plan's `pair_nodes` slot: a penalty pair whose slaves are no master nodes
    /// (`PENALTY_SLAVES_APART`), whose other pair nodes are the search's motion nodes that are
    /// no slaves, with at most two rigid part slots. Otherwise every increment gathers every
    /// pair node.
    pub gather_active: bool,
    /// The search plan's dispatch slots.
    pub slots: Slots,
}

/// The search's entries of pair `k` of shape `p`, in the order they run: small sliding, every
/// node into the frame and the anchors' evaluation; otherwise the motion nodes into the frame
/// with the motion budget, the schedule, the local search and (unless `local_only`) the
/// global search the schedule may choose, which puts every model node into the frame first
/// (and names a non-finite one).
pub(crate) fn search(k: usize, p: &PairShape) -> Vec<Entry> {
    let mut out = Vec::new();
    let mut push = |group: &'static Group, kernel: Kernel, level: usize, size: Size| {
        out.push(Entry {
            group,
            kernel,
            pair: k,
            level,
            size,
        })
    };
    let iw = ITEM_WORKGROUP;
    let s = &p.slots;
    if p.anchored {
        let g = &groups::TO_LOCAL_ANCHOR;
        push(g, Kernel::ToLocal, 0, Size::Items(p.n_nodes, iw));
        push(g, Kernel::Anchor, 0, Size::Items(p.n_slaves, iw));
        return out;
    }
    let g = &groups::MOTION_SCHEDULE;
    push(g, Kernel::Motion, 0, Size::Items(p.n_motion_nodes, iw));
    push(g, Kernel::Schedule, 0, Size::Items(1, 1));
    push(&groups::LOCAL, Kernel::LocalSearch, 0, Size::Slot(s.active));
    if p.local_only {
        return out;
    }
    let g = &groups::GLOBAL_SEARCH;
    push(g, Kernel::ToLocal, 0, Size::Slot(s.nodes));
    if p.buckets {
        // the leaf boxes, then the facets binned: counted, scanned, written
        let leaves = s.tree_passes[0];
        push(g, Kernel::TreeRefit, 0, Size::Slot(leaves));
        push(g, Kernel::BucketClear, 0, Size::Slot(s.buckets));
        push(g, Kernel::BucketCount, 0, Size::Slot(leaves));
        for (i, &slot) in s.bucket_levels.iter().enumerate() {
            push(g, Kernel::BucketScanBlocks, i, Size::Slot(slot));
        }
        for i in (0..s.bucket_levels.len().saturating_sub(1)).rev() {
            push(g, Kernel::BucketScanAdd, i, Size::Slot(s.bucket_levels[i]));
        }
        push(g, Kernel::BucketFill, 0, Size::Slot(leaves));
        push(g, Kernel::WalkStart, 0, Size::Slot(s.slave_groups));
        push(g, Kernel::BucketWalk, 0, Size::Slot(s.slaves));
    } else {
        for (i, &slot) in s.tree_passes.iter().enumerate() {
            push(g, Kernel::TreeRefit, i, Size::Slot(slot));
        }
        push(g, Kernel::WalkStart, 0, Size::Slot(s.slave_groups));
        push(g, Kernel::NearestWalk, 0, Size::Slot(s.slaves));
    }
    for (i, &slot) in s.work_levels.iter().enumerate() {
        push(g, Kernel::ScanBlocks, i, Size::Slot(slot));
    }
    for i in (0..s.work_levels.len().saturating_sub(1)).rev() {
        push(g, Kernel::ScanAdd, i, Size::Slot(s.work_levels[i]));
    }
    push(g, Kernel::NearestArgs, 0, Size::Slot(s.one));
    push(g, Kernel::NearestChunks, 0, Size::Chunks);
    push(g, Kernel::NearestTies, 0, Size::Chunks);
    if p.self_contact {
        let crowded = if p.buckets {
            Kernel::BucketCrowded
        } else {
            Kernel::NearestCrowded
        };
        push(g, crowded, 0, Size::Slot(s.slaves));
    }
    push(g, Kernel::NearestFacet, 0, Size::Slot(s.slaves));
    push(g, Kernel::SetReference, 0, Size::Slot(s.motion_nodes));
    // the active slaves for the local increments that follow: marked, scanned in the work
    // items' levels (free once the chunks are done), compacted
    push(g, Kernel::ActiveMark, 0, Size::Slot(s.slaves));
    for (i, &slot) in s.work_levels.iter().enumerate() {
        push(g, Kernel::ScanBlocks, i, Size::Slot(slot));
    }
    for i in (0..s.work_levels.len().saturating_sub(1)).rev() {
        push(g, Kernel::ScanAdd, i, Size::Slot(s.work_levels[i]));
    }
    push(g, Kernel::ActiveCompact, 0, Size::Slot(s.slaves));
    out
}

/// The global search of `params` alone, every entry sized by the host (the sizes
/// [`initial_plan`]'s global slots hold): the tree's refit and walks, the scan, the chunks
/// and each slave's hit, on nodes already in the frame — no schedule, no motion budget. For
/// tests that run the kernels on inputs they prepared themselves (`GpuSearch::run_prepared`).
pub(crate) fn prepared_global(params: &SearchParams) -> Vec<Entry> {
    let mut out = Vec::new();
    let mut push = |kernel: Kernel, level: usize, size: Size| {
        out.push(Entry {
            group: &groups::GLOBAL_SEARCH,
            kernel,
            pair: 0,
            level,
            size,
        })
    };
    let (iw, n) = (ITEM_WORKGROUP, params.n_slaves);
    let buckets = params.flags & FLAG_BUCKETS != 0;
    for (i, tp) in tree_passes(params.tree_levels).iter().enumerate() {
        if buckets && i > 0 {
            break;
        }
        push(
            Kernel::TreeRefit,
            i,
            Size::Items(1 << tp.bottom, TREE_WORKGROUP),
        );
    }
    if buckets {
        let layout = BucketLayout::new(params.n_facets);
        let leaves = Size::Items(1 << params.tree_levels, iw);
        push(Kernel::BucketClear, 0, Size::Items(layout.buckets(), iw));
        push(Kernel::BucketCount, 0, leaves);
        let levels = &layout.levels.levels;
        for (i, level) in levels.iter().enumerate() {
            push(
                Kernel::BucketScanBlocks,
                i,
                Size::Items(level.1, SCAN_BLOCK),
            );
        }
        for i in (0..levels.len().saturating_sub(1)).rev() {
            push(
                Kernel::BucketScanAdd,
                i,
                Size::Items(levels[i].1, SCAN_BLOCK),
            );
        }
        push(Kernel::BucketFill, 0, leaves);
    }
    push(
        Kernel::WalkStart,
        0,
        Size::Items(n.div_ceil(WALK_GROUP), iw),
    );
    let walk = if buckets {
        Kernel::BucketWalk
    } else {
        Kernel::NearestWalk
    };
    push(walk, 0, Size::Items(n, iw));
    let levels = ScanLevels::new(n + 1).levels;
    for (i, level) in levels.iter().enumerate() {
        push(Kernel::ScanBlocks, i, Size::Items(level.1, SCAN_BLOCK));
    }
    for i in (0..levels.len().saturating_sub(1)).rev() {
        push(Kernel::ScanAdd, i, Size::Items(levels[i].1, SCAN_BLOCK));
    }
    push(Kernel::NearestArgs, 0, Size::Items(1, 1));
    push(Kernel::NearestChunks, 0, Size::Chunks);
    push(Kernel::NearestTies, 0, Size::Chunks);
    if params.flags & crate::abi::search::FLAG_SELF_CONTACT != 0 {
        let crowded = if buckets {
            Kernel::BucketCrowded
        } else {
            Kernel::NearestCrowded
        };
        push(crowded, 0, Size::Items(n, iw));
    }
    push(Kernel::NearestFacet, 0, Size::Items(n, iw));
    out
}

/// The penalty's entries of pair `k` of shape `p`: normals and springs, the forces scattered,
/// gathered and added, and the pair's statistics.
pub(crate) fn penalty(k: usize, p: &PairShape) -> Vec<Entry> {
    let iw = ITEM_WORKGROUP;
    let entry = |group: &'static Group, kernel: Kernel, size: Size| Entry {
        group,
        kernel,
        pair: k,
        level: 0,
        size,
    };
    let (np, ns) = (p.n_pair_nodes, p.n_slaves);
    let (g, s) = (&groups::NORMALS_PENALTY, &groups::SCATTER_GATHER_ADD);
    let mut out = Vec::new();
    if p.anchored {
        // small sliding: every master node's normal, every slave, every increment
        out.push(entry(g, Kernel::NodalNormals, Size::Items(np, iw)));
        out.push(entry(g, Kernel::Penalty, Size::Items(ns, iw)));
        out.push(entry(s, Kernel::ScatterForces, Size::Items(ns, iw)));
    } else {
        // every slave after a global search, the active ones after a local one; the normals
        // the springs read marked from the active list (fresh after a global search) first
        let (all, active) = (Size::Slot(p.slots.slaves), Size::Slot(p.slots.active));
        let (global, local) = (!p.local_only, !p.global_only);
        for (on, size) in [(global, all), (local, active)] {
            if on {
                out.push(entry(g, Kernel::NeedNormals, size));
            }
        }
        out.push(entry(g, Kernel::NodalNormalsNeeded, Size::Items(np, iw)));
        for (on, kernel, size) in [
            (global, Kernel::Penalty, all),
            (local, Kernel::PenaltyActive, active),
        ] {
            if on {
                out.push(entry(g, kernel, size));
            }
        }
        for (on, kernel, size) in [
            (global, Kernel::ScatterForces, all),
            (local, Kernel::ScatterForcesActive, active),
        ] {
            if on {
                out.push(entry(s, kernel, size));
            }
        }
    }
    if p.gather_active && !p.anchored {
        // every pair node after a global search, the active slaves and the others after a
        // local one (a slave left out has no facet: nothing to gather or add)
        let (all, active) = (
            Size::Slot(p.slots.pair_nodes),
            Size::Slot(p.slots.active_nodes),
        );
        let (global, local) = (!p.local_only, !p.global_only);
        for (gather, add, size, on) in [
            (Kernel::Gather, Kernel::AddForces, all, global),
            (Kernel::GatherActive, Kernel::AddForcesActive, active, local),
        ] {
            if on {
                out.extend([entry(s, gather, size), entry(s, add, size)]);
            }
        }
    } else {
        out.extend([
            entry(s, Kernel::Gather, Size::Items(np, iw)),
            entry(s, Kernel::AddForces, Size::Items(np, iw)),
        ]);
    }
    out.push(entry(
        &groups::STATS_PAIR,
        Kernel::PairStats,
        Size::Items(1, 1),
    ));
    out
}

/// The increment's finish: the stable increment from the largest bound row (which every pair's
/// add_forces raised), the increment counted.
pub(crate) fn finish() -> Vec<Entry> {
    vec![Entry {
        group: &groups::STATS_FINISH,
        kernel: Kernel::FinishStats,
        pair: 0,
        level: 0,
        size: Size::Items(1, 1),
    }]
}

/// The entries of one device-resident increment of `pairs`, in the order they run: each
/// pair's search, penalty and statistics, then the finish. A search alone is its
/// [`search`] part.
pub(crate) fn increment(pairs: &[PairShape]) -> Vec<Entry> {
    let mut out = Vec::new();
    for (k, p) in pairs.iter().enumerate() {
        out.extend(search(k, p));
        out.extend(penalty(k, p));
    }
    out.extend(finish());
    out
}

#[cfg(test)]
mod tests;
