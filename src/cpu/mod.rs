//! The CPU path: a mirror of every shader (same file name, same loop shape, f32 in grid-local
//! coordinates) and a brute-force f64 oracle for the tests.
//!
//! The mirror runs the kernels' "invocations" on all cores (rayon): a kernel whose invocations
//! each write their own output runs them in parallel; one whose invocations combine through
//! atomics uses atomics whose result does not depend on their order (counts), or runs each
//! slave's work items in order on one thread (the nearest facet's chunks); the rest run one
//! after another. The results are bitwise the same on one thread or many, and equal the GPU's up
//! to f32 round-off (exactly for the tree's boxes). It is also the backend used where no
//! adapter exists.

pub mod anchor;
pub mod brute_force;
pub mod common;
pub mod gather;
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

use std::sync::atomic::AtomicU32;

use crate::error::Result;
use crate::search::layout::{tree_passes, GpuHit, ScanLevels, STATUS_WORDS};
use crate::search::{Prepared, Step, STEPS};

/// Fewest invocations a thread of the CPU path takes at once (below it, splitting costs more
/// than it gains).
pub(crate) const PAR_MIN: usize = 256;

// an AtomicU32 is a u32 in memory (same size and bit validity; alignment checked here)
const _: () = assert!(std::mem::align_of::<AtomicU32>() == std::mem::align_of::<u32>());

/// `words` as atomics, for a mirror whose invocations run on several threads and combine through
/// atomics whose result does not depend on their order, as on the GPU.
pub(crate) fn as_atomic(words: &mut [u32]) -> &[AtomicU32] {
    // SAFETY: AtomicU32 has the size and bit validity of u32 and (asserted above) its
    // alignment, and the exclusive borrow keeps every other access out while the result lives.
    unsafe { &*(words as *mut [u32] as *const [AtomicU32]) }
}

/// The buffers of one search on the CPU; they only grow.
#[derive(Clone, Debug, Default)]
pub struct CpuWorkspace {
    /// The search tree's boxes (two vec4 per heap node: lower, upper corner).
    pub boxes: Vec<[f32; 4]>,
    /// Status words (`STATUS_*`).
    pub status: [u32; STATUS_WORDS],
    /// One result per slave node (the tracked nodes between increments).
    pub hits: Vec<GpuHit>,
    /// Positions at the last global search (motion budget).
    pub reference: Vec<[f32; 4]>,
    /// Nearest-facet work items: each slave's chunk count, scanned to its first item.
    pub work: Vec<u32>,
    /// Nearest-facet record per slave (`nearest_facet::BEST_WORDS` words).
    pub best: Vec<u32>,
}

/// The CPU executor of the global search.
#[derive(Clone, Debug, Default)]
pub struct CpuSearch {
    /// Small sliding: the slaves' anchors (local runs evaluate them instead of searching).
    anchors: Option<Vec<crate::search::layout::Anchor>>,
    ws: CpuWorkspace,
    /// Device-resident increments: the plan and the nodes they keep.
    resident: Option<Box<resident::CpuResident>>,
}

impl CpuSearch {
    /// Runs a global search (`local` false) or the motion check and the local search from
    /// the tracked nodes of the previous increment. Returns the hits and the status words.
    pub fn run_mode(
        &mut self,
        prep: &Prepared,
        local: bool,
    ) -> Result<(Vec<GpuHit>, [u32; STATUS_WORDS])> {
        if !local {
            let hits = self.run(prep)?;
            self.ws.reference.clear();
            self.ws.reference.extend_from_slice(&prep.nodes);
            return Ok((hits, self.ws.status));
        }
        if self.ws.hits.len() != prep.slaves.len() || self.ws.reference.len() != prep.nodes.len() {
            return Err(crate::error::Error::BadParameter {
                name: "local search",
                value: "before any global search".into(),
                expected: "a global search first",
            });
        }
        let mut status = crate::status::reset_image();
        if let Some(anchors) = &self.anchors {
            anchor::anchor(
                &prep.params,
                &prep.nodes,
                &prep.facets,
                &prep.slaves,
                anchors,
                &mut status,
                &mut self.ws.hits,
                &prep.adjacency,
            );
            self.ws.status = status;
            return Ok((self.ws.hits.clone(), status));
        }
        motion::motion(
            &prep.params,
            &prep.nodes,
            &self.ws.reference,
            &prep.motion_nodes,
            &mut status,
            &self.ws.hits,
        );
        local_search::local_search(
            &prep.params,
            &prep.nodes,
            &prep.facets,
            &prep.slaves,
            &prep.adjacency,
            &mut status,
            &mut self.ws.hits,
        );
        self.ws.status = status;
        Ok((self.ws.hits.clone(), status))
    }

    /// Small sliding: installs the slaves' anchors.
    pub fn set_anchors(&mut self, anchors: &[crate::search::layout::Anchor]) {
        self.anchors = Some(anchors.to_vec());
    }

    /// Runs only `STEPS[..first]` and returns the workspace as those steps leave it: the CPU
    /// half of a split run.
    pub fn run_prefix(&mut self, prep: &Prepared, first: usize) -> Result<&CpuWorkspace> {
        self.reset(prep);
        for step in &STEPS[..first] {
            run_step(*step, &prep.params, prep, &mut self.ws);
        }
        Ok(&self.ws)
    }

    /// The search tree's boxes after the last global search (two vec4 per heap node).
    pub fn tree_boxes(&self) -> &[[f32; 4]] {
        &self.ws.boxes
    }

    /// Sizes and resets the workspace for a global search of `prep`.
    fn reset(&mut self, prep: &Prepared) {
        crate::status::reset(&mut self.ws.status, crate::status::Owner::Search);
        self.ws.boxes.clear();
        self.ws
            .boxes
            .resize(tree::box_words(prep.params.tree_levels), [0.0; 4]);
        self.ws.hits.resize(prep.slaves.len(), GpuHit::miss(0, 0));
    }

    /// Runs all steps of a global search. Returns the hits.
    pub fn run(&mut self, prep: &Prepared) -> Result<Vec<GpuHit>> {
        self.reset(prep);
        for step in STEPS {
            run_step(step, &prep.params, prep, &mut self.ws);
        }
        Ok(self.ws.hits.clone())
    }
}

/// Runs one step of the search on the CPU workspace (the CPU half of a split run).
pub fn run_step(
    step: Step,
    params: &crate::search::layout::SearchParams,
    prep: &Prepared,
    ws: &mut CpuWorkspace,
) {
    match step {
        Step::TreeRefit => {
            for tp in tree_passes(params.tree_levels) {
                tree::tree_refit(
                    params,
                    &tp,
                    &prep.nodes,
                    &prep.facets,
                    &prep.order,
                    &mut ws.boxes,
                    &mut ws.status,
                );
            }
        }
        Step::NearestFacet => {
            let n = params.n_slaves as usize;
            let work_levels = ScanLevels::new(params.n_slaves + 1);
            ws.work.clear();
            ws.work.resize(work_levels.words as usize, 0);
            ws.best.clear();
            ws.best.resize(n * nearest_facet::BEST_WORDS, 0);
            let c = nearest_facet::Candidates {
                params,
                nodes: &prep.nodes,
                facets: &prep.facets,
                slaves: &prep.slaves,
                walk_order: &prep.walk_order,
                order: &prep.order,
                boxes: &ws.boxes,
                adjacency: &prep.adjacency,
            };
            nearest_facet::nearest_walk(&c, &mut ws.work, &mut ws.best);
            scan::scan(&work_levels, &mut ws.work);
            nearest_facet::nearest_chunks(&c, &ws.work, &mut ws.best);
            nearest_facet::nearest_ties(&c, &ws.work, &mut ws.best);
            nearest_facet::nearest_crowded(&c, &mut ws.best);
            nearest_facet::nearest_facet(&c, &mut ws.status, &mut ws.hits, &ws.best);
        }
    }
}

/// The CPU executor of the penalty passes of one pair; its state persists between increments.
#[derive(Clone, Debug)]
pub struct CpuPenalty {
    /// Friction force and area per slave.
    pub state: Vec<crate::penalty::layout::SlaveState>,
    /// Smoothed normal per model node.
    pub normals: Vec<[f32; 4]>,
    /// Result per slave.
    pub out: Vec<crate::penalty::layout::ContactOut>,
    /// Fixed-point force sums per pair node (gather's accumulator).
    pub acc: Vec<u32>,
    /// Force per pair node.
    pub forces: Vec<[f32; 4]>,
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
        }
    }

    /// Runs nodal_normals, penalty and gather (scatter_forces, gather).
    pub fn run(
        &mut self,
        setup: &crate::penalty::PenaltySetup,
        pp: &crate::penalty::layout::PenaltyParams,
        prep: &Prepared,
        vel: &[[f32; 4]],
        hits: &[GpuHit],
        status: &mut [u32; STATUS_WORDS],
    ) {
        crate::status::reset(status, crate::status::Owner::Penalty);
        let n_slaves = pp.n_slaves as usize;
        nodal_normals::nodal_normals(
            pp,
            &prep.nodes,
            &prep.facets,
            &setup.pair_nodes,
            &setup.adjacency,
            &mut self.normals,
        );
        self.out.resize(n_slaves, bytemuck::Zeroable::zeroed());
        penalty::penalty(
            pp,
            setup.friction,
            &prep.nodes,
            vel,
            &prep.facets,
            hits,
            &self.normals,
            &mut self.state,
            &mut self.out,
            status,
        );
        self.acc.clear();
        self.acc
            .resize(setup.pair_nodes.len() * gather::ACC_WORDS_PER_NODE, 0);
        gather::scatter_forces(
            pp,
            &setup.facet_nodes,
            hits,
            &self.out,
            status,
            &mut self.acc,
        );
        self.forces.resize(setup.pair_nodes.len(), [0.0; 4]);
        gather::gather(
            pp,
            &setup.pair_nodes,
            &self.out,
            status,
            &mut self.acc,
            &mut self.forces,
        );
    }
}
