//! The CPU executor of a device-resident increment's entries (`plan::increment`): one
//! exhaustive match on the kernel, each arm the kernel's mirror on host arrays laid out as the
//! GPU's buffers; an entry sized by a dispatch the device decides runs when that dispatch has
//! workgroups, as an indirect dispatch would.

use super::resident::SearchArrays;
use super::{
    active, anchor, buckets, gather, hits_mut, local_search, motion, nearest_facet, nodal_normals,
    penalty, scan, schedule, stats, to_local, tree, CpuPenalty,
};
use crate::abi::buckets::BucketLayout;
use crate::abi::penalty::{PenaltyParams, ACC_WORDS_PER_NODE};
use crate::abi::search::{
    plan_params, tree_passes, ScanLevels, SearchParams, BEST_WORDS, ITEM_WORKGROUP,
    MAX_GROUPS_PER_DIM,
};
use crate::abi::stats::STATS_WORDS;
use crate::error::{Error, Result};
use crate::penalty::PenaltySetup;
use crate::plan::increment::{Entry, Kernel, Size};
use crate::plan::Prepared;

/// What the penalty and statistics kernels of an entry read and write beside the search's
/// arrays: the pair's penalty arrays and constants, and the increment's (the caller's
/// velocities and forces, the bound rows, the statistics). A search alone has none.
pub(crate) struct PenaltyArrays<'a> {
    /// The penalty's arrays.
    pub penalty: &'a mut CpuPenalty,
    /// The pair's constants.
    pub setup: &'a PenaltySetup,
    /// Its penalty parameters this increment.
    pub params: &'a PenaltyParams,
    /// Velocities, one `[f32; 4]` per model node.
    pub velocities: &'a [[f32; 4]],
    /// Forces, one `[f32; 4]` per model node, xyz summed into.
    pub forces: &'a mut [[f32; 4]],
    /// The node-wise bound's rows, one per model node.
    pub rows: &'a mut [f32],
    /// The statistics words.
    pub stats: &'a mut [u32; STATS_WORDS],
}

/// Whether an entry of `size` gets workgroups, by the plan and chunk words the device reads.
fn dispatched(size: Size, plan: &[u32], args: &[u32; 3]) -> bool {
    match size {
        Size::Items(n, _) => n > 0,
        Size::Slot(offset) => {
            let w = (offset / 4) as usize;
            plan[w..w + 3].iter().all(|&c| c > 0)
        }
        Size::Chunks => args.iter().all(|&c| c > 0),
    }
}

/// The nearest-facet kernels' read-only inputs.
fn candidates<'a>(
    params: &'a SearchParams,
    prep: &'a Prepared,
    walk_points: &'a [[u32; 4]],
    boxes: &'a [[u32; 4]],
    corners: &'a [[[f32; 4]; 2]],
) -> nearest_facet::Candidates<'a> {
    nearest_facet::Candidates {
        params,
        nodes: &prep.nodes,
        facets: &prep.facets,
        slaves: &prep.slaves,
        walk_order: &prep.walk_order,
        walk_points,
        order: &prep.order,
        boxes,
        corners,
        adjacency: &prep.adjacency,
    }
}

/// Runs entry `e` on the CPU: a search kernel on the search's resident arrays `s` and the
/// positions `positions` (one `[f32; 4]` per model node) it reads; a penalty or statistics
/// kernel also on `pen`, which an increment has and a search alone does not (an error names
/// the kernel if it is missing).
pub(crate) fn run_entry(
    e: &Entry,
    positions: &[[f32; 4]],
    s: SearchArrays<'_>,
    pen: Option<PenaltyArrays<'_>>,
) -> Result<()> {
    if !dispatched(e.size, s.plan, s.args) {
        return Ok(());
    }
    let missing = || Error::BadParameter {
        name: "increment entry",
        value: format!("{} without penalty arrays", e.kernel.pass().entry),
        expected: "a search kernel, or an increment's penalty arrays",
    };
    // every search kernel reads the params words of the plan (the schedule's grid)
    let params = plan_params(s.plan);
    let prep = &mut *s.prep;
    let ws = &mut *s.ws;
    let status = &mut ws.status;
    match e.kernel {
        Kernel::ToLocal => {
            to_local::to_local(s.frame, positions, &mut prep.nodes, &prep.adjacency, status)
        }
        Kernel::Anchor => anchor::anchor(
            &params,
            &prep.nodes,
            &prep.facets,
            &prep.slaves,
            s.anchors,
            status,
            hits_mut(&mut ws.hits),
            &prep.adjacency,
        ),
        Kernel::Motion => motion::motion(
            &params,
            s.frame,
            positions,
            &mut prep.nodes,
            &ws.reference,
            &prep.motion_nodes,
            status,
            &prep.adjacency,
        ),
        Kernel::Schedule => {
            let count = ws.active.first().copied().unwrap_or(0);
            schedule::schedule(s.plan, status, s.args, count)
        }
        Kernel::LocalSearch => {
            ws.skins.resize(ws.hits.len(), [0.0; 4]);
            local_search::local_search(
                &params,
                &prep.nodes,
                &prep.facets,
                &prep.slaves,
                &prep.adjacency,
                status,
                hits_mut(&mut ws.hits),
                &ws.active,
                &mut ws.reference,
                &mut ws.skins,
            )
        }
        Kernel::TreeRefit => {
            if let Some(tp) = tree_passes(params.tree_levels).get(e.level) {
                tree::tree_refit(
                    &params,
                    tp,
                    &prep.nodes,
                    &prep.facets,
                    &prep.order,
                    &mut ws.boxes,
                    &mut ws.corners,
                    status,
                );
            }
        }
        Kernel::WalkStart => {
            let n = params.n_slaves as usize;
            ws.work.clear();
            ws.work
                .resize(ScanLevels::new(params.n_slaves + 1).words as usize, 0);
            ws.best.clear();
            ws.best.resize(n * BEST_WORDS, 0);
            ws.walk_points.resize(n, [0; 4]);
            nearest_facet::walk_start(
                &params,
                &ws.corners,
                &prep.nodes,
                &prep.slaves,
                &prep.walk_order,
                &mut ws.walk_points,
                &mut ws.work,
            );
        }
        Kernel::NearestWalk => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            nearest_facet::nearest_walk(&c, &mut ws.work, &mut ws.best);
        }
        Kernel::BucketClear => buckets::bucket_clear(&params, &mut ws.grid),
        Kernel::BucketCount => buckets::bucket_count(&params, &ws.boxes, &mut ws.grid),
        Kernel::BucketScanBlocks => scan::scan_blocks(
            &BucketLayout::new(params.n_facets).levels.params(e.level),
            &mut ws.grid,
        ),
        Kernel::BucketScanAdd => scan::scan_add(
            &BucketLayout::new(params.n_facets).levels.params(e.level),
            &mut ws.grid,
        ),
        Kernel::BucketFill => buckets::bucket_fill(&params, &prep.order, &ws.boxes, &mut ws.grid),
        Kernel::BucketWalk => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            buckets::bucket_walk(&c, &ws.grid, &mut ws.work, &mut ws.best);
        }
        Kernel::BucketCrowded => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            buckets::bucket_crowded(&c, &ws.grid, &mut ws.best);
        }
        Kernel::ScanBlocks => scan::scan_blocks(
            &ScanLevels::new(params.n_slaves + 1).params(e.level),
            &mut ws.work,
        ),
        Kernel::ScanAdd => scan::scan_add(
            &ScanLevels::new(params.n_slaves + 1).params(e.level),
            &mut ws.work,
        ),
        Kernel::NearestArgs => {
            let items = nearest_facet::nearest_args(&params, &ws.work);
            let groups = items.div_ceil(ITEM_WORKGROUP);
            let x = groups.min(MAX_GROUPS_PER_DIM);
            *s.args = [x, if x > 0 { groups.div_ceil(x) } else { 0 }, 1];
        }
        Kernel::NearestChunks => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            nearest_facet::nearest_chunks(&c, &ws.work, &mut ws.best);
        }
        Kernel::NearestTies => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            nearest_facet::nearest_ties(&c, &ws.work, &mut ws.best);
        }
        Kernel::NearestCrowded => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            nearest_facet::nearest_crowded(&c, &mut ws.best);
        }
        Kernel::NearestFacet => {
            let c = candidates(&params, prep, &ws.walk_points, &ws.boxes, &ws.corners);
            nearest_facet::nearest_facet(&c, &mut ws.status, hits_mut(&mut ws.hits), &ws.best);
        }
        Kernel::SetReference => {
            motion::set_reference(&params, &prep.nodes, &mut ws.reference, &prep.motion_nodes)
        }
        Kernel::ActiveMark => active::active_mark(
            &params,
            &ws.hits,
            &mut ws.work,
            &prep.slaves,
            &mut ws.reference,
        ),
        Kernel::ActiveCompact => {
            ws.active.resize(params.n_slaves as usize + 1, 0);
            active::active_compact(&params, &ws.hits, &ws.work, &mut ws.active)
        }
        Kernel::NodalNormals | Kernel::NodalNormalsNeeded => {
            let p = pen.ok_or_else(missing)?;
            p.penalty.need.resize(p.setup.pair_nodes.len(), 0);
            let need = (e.kernel == Kernel::NodalNormalsNeeded).then_some(&p.penalty.need[..]);
            nodal_normals::nodal_normals(
                p.params,
                &prep.nodes,
                &prep.facets,
                &p.setup.pair_nodes,
                &p.setup.adjacency,
                &mut p.penalty.normals,
                need,
            )
        }
        Kernel::NeedNormals => {
            let p = pen.ok_or_else(missing)?;
            p.penalty.need.resize(p.setup.pair_nodes.len(), 0);
            nodal_normals::need_normals(
                p.params,
                &ws.hits,
                &ws.active,
                &p.setup.facet_nodes,
                &mut p.penalty.need,
            )
        }
        Kernel::Penalty | Kernel::PenaltyActive => {
            let p = pen.ok_or_else(missing)?;
            let active = (e.kernel == Kernel::PenaltyActive).then_some(&ws.active[..]);
            p.penalty
                .out
                .resize(p.params.n_slaves as usize, bytemuck::Zeroable::zeroed());
            penalty::penalty(
                p.params,
                p.setup.friction,
                &prep.nodes,
                p.velocities,
                &prep.facets,
                &ws.hits,
                &p.penalty.normals,
                &mut p.penalty.state,
                &mut p.penalty.out,
                status,
                active,
            );
        }
        Kernel::ScatterForces | Kernel::ScatterForcesActive => {
            let p = pen.ok_or_else(missing)?;
            let active = (e.kernel == Kernel::ScatterForcesActive).then_some(&ws.active[..]);
            let acc = &mut p.penalty.acc;
            acc.clear();
            acc.resize(p.setup.pair_nodes.len() * ACC_WORDS_PER_NODE, 0);
            p.penalty.need.resize(p.setup.pair_nodes.len(), 0);
            gather::scatter_forces(
                p.params,
                &p.setup.facet_nodes,
                &ws.hits,
                &p.penalty.out,
                status,
                acc,
                &mut p.penalty.need,
                active,
            );
        }
        Kernel::Gather | Kernel::GatherActive => {
            let p = pen.ok_or_else(missing)?;
            let active = (e.kernel == Kernel::GatherActive).then_some(&ws.active[..]);
            let pn = &mut *p.penalty;
            pn.forces.resize(p.setup.pair_nodes.len(), [0.0; 4]);
            gather::gather(
                p.params,
                &p.setup.pair_nodes,
                &ws.hits,
                &pn.out,
                status,
                &mut pn.acc,
                &mut pn.forces,
                &pn.need,
                active,
            );
        }
        Kernel::AddForces | Kernel::AddForcesActive => {
            let p = pen.ok_or_else(missing)?;
            let active = (e.kernel == Kernel::AddForcesActive).then_some(&ws.active[..]);
            gather::add_forces(
                p.params,
                &p.setup.pair_nodes,
                &ws.hits,
                &p.penalty.forces,
                p.forces,
                p.rows,
                p.stats,
                &mut p.penalty.need,
                active,
            )
        }
        Kernel::PairStats => stats::pair_stats(status, s.plan, pen.ok_or_else(missing)?.stats),
        Kernel::FinishStats => stats::finish_stats(pen.ok_or_else(missing)?.stats),
    }
    Ok(())
}
