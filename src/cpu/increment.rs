//! The CPU executor of a device-resident increment's entries (`plan::increment`): one
//! exhaustive match on the kernel, each arm the kernel's mirror on host arrays laid out as the
//! GPU's buffers; an entry sized by a dispatch the device decides runs when that dispatch has
//! workgroups, as an indirect dispatch would.

use super::resident::SearchArrays;
use super::{
    anchor, gather, hits_mut, local_search, motion, nearest_facet, nodal_normals, penalty, scan,
    schedule, stats, to_local, tree, CpuPenalty,
};
use crate::abi::penalty::{PenaltyParams, ACC_WORDS_PER_NODE};
use crate::abi::search::{
    plan_params, tree_passes, ScanLevels, SearchParams, BEST_WORDS, ITEM_WORKGROUP,
    MAX_GROUPS_PER_DIM,
};
use crate::abi::stats::STATS_WORDS;
use crate::penalty::PenaltySetup;
use crate::plan::increment::{Entry, Kernel, Size};
use crate::plan::Prepared;

/// One pair's arrays for an entry of it.
pub(crate) struct PairArrays<'a> {
    /// The search's resident arrays.
    pub search: SearchArrays<'a>,
    /// The penalty's arrays.
    pub penalty: &'a mut CpuPenalty,
    /// The pair's constants.
    pub setup: &'a PenaltySetup,
    /// Its penalty parameters this increment.
    pub params: &'a PenaltyParams,
}

/// The increment's arrays: the caller's (positions of this pair's search, velocities, forces
/// summed into) and the increment's own (bound rows, statistics).
pub(crate) struct IncrementArrays<'a> {
    /// Positions, one `[f32; 4]` per model node.
    pub positions: &'a [[f32; 4]],
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

/// Runs entry `e` of pair `p` on the CPU.
pub(crate) fn run_entry(e: &Entry, p: PairArrays<'_>, io: IncrementArrays<'_>) {
    let PairArrays {
        search: s,
        penalty: pen,
        setup,
        params: pp,
    } = p;
    if !dispatched(e.size, s.plan, s.args) {
        return;
    }
    // every search kernel reads the params words of the plan (the schedule's grid)
    let params = plan_params(s.plan);
    let prep = &mut *s.prep;
    let ws = &mut *s.ws;
    let status = &mut ws.status;
    match e.kernel {
        Kernel::ToLocal => to_local::to_local(
            &params,
            s.frame,
            io.positions,
            &mut prep.nodes,
            &prep.adjacency,
            status,
        ),
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
            &prep.nodes,
            &ws.reference,
            &prep.motion_nodes,
            status,
            &ws.hits,
        ),
        Kernel::Schedule => schedule::schedule(s.plan, status, s.args),
        Kernel::LocalSearch => local_search::local_search(
            &params,
            &prep.nodes,
            &prep.facets,
            &prep.slaves,
            &prep.adjacency,
            status,
            hits_mut(&mut ws.hits),
        ),
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
        Kernel::NodalNormals => nodal_normals::nodal_normals(
            pp,
            &prep.nodes,
            &prep.facets,
            &setup.pair_nodes,
            &setup.adjacency,
            &mut pen.normals,
        ),
        Kernel::Penalty => {
            pen.out
                .resize(pp.n_slaves as usize, bytemuck::Zeroable::zeroed());
            penalty::penalty(
                pp,
                setup.friction,
                &prep.nodes,
                io.velocities,
                &prep.facets,
                &ws.hits,
                &pen.normals,
                &mut pen.state,
                &mut pen.out,
                status,
            );
        }
        Kernel::ScatterForces => {
            pen.acc.clear();
            pen.acc
                .resize(setup.pair_nodes.len() * ACC_WORDS_PER_NODE, 0);
            gather::scatter_forces(
                pp,
                &setup.facet_nodes,
                &ws.hits,
                &pen.out,
                status,
                &mut pen.acc,
            );
        }
        Kernel::Gather => {
            pen.forces.resize(setup.pair_nodes.len(), [0.0; 4]);
            gather::gather(
                pp,
                &setup.pair_nodes,
                &pen.out,
                status,
                &mut pen.acc,
                &mut pen.forces,
            );
        }
        Kernel::AddForces => {
            gather::add_forces(pp, &setup.pair_nodes, &pen.forces, io.forces, io.rows)
        }
        Kernel::PairStats => stats::pair_stats(status, s.plan, io.stats),
        Kernel::BoundMax => stats::bound_max(&setup.pair_nodes, io.rows, io.stats),
        Kernel::FinishStats => stats::finish_stats(io.stats),
    }
}
