//! The CPU path: a mirror of every shader (same file name, same loop shape, f32 in grid-local
//! coordinates) and a brute-force f64 oracle for the tests.
//!
//! The mirror runs the kernels' "invocations" on all cores (rayon): a kernel whose invocations
//! each write their own output runs them in parallel; one whose invocations combine through
//! atomics uses atomics whose result does not depend on their order (counts), or runs each
//! slave's work items in order on one thread (the nearest facet's chunks); the rest run one
//! after another. The results are bitwise the same on one thread or many, and equal the GPU's up
//! to f32 round-off (exactly for the integer binning). It is also the backend used where no
//! adapter exists.

pub mod anchor;
pub mod bin_count;
pub mod bin_scatter;
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

use std::sync::atomic::AtomicU32;

use crate::error::Result;
use crate::search::layout::{
    GpuHit, ScanLevels, STATUS_NEEDED_ENTRIES, STATUS_OVERFLOW, STATUS_WORDS,
};
use crate::search::{Bins, Prepared, Step, STEPS};

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
    /// All scan levels; words 0..=n_cells hold counts, then cell starts.
    pub scan: Vec<u32>,
    /// Atomic cursors of the scatter.
    pub cursor: Vec<u32>,
    /// Bin entries (facet ids grouped by cell).
    pub entries: Vec<u32>,
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
#[derive(Clone, Debug)]
pub struct CpuSearch {
    /// Small sliding: the slaves' anchors (local runs evaluate them instead of searching).
    anchors: Option<Vec<crate::search::layout::Anchor>>,
    ws: CpuWorkspace,
    entry_capacity: u32,
    presize: bool,
    /// Cells of the last search.
    n_cells: u32,
    /// Device-resident increments: the plan and the nodes they keep.
    resident: Option<Box<resident::CpuResident>>,
}

impl Default for CpuSearch {
    fn default() -> Self {
        Self {
            anchors: None,
            ws: CpuWorkspace::default(),
            entry_capacity: 0,
            presize: true,
            n_cells: 0,
            resident: None,
        }
    }
}

impl CpuSearch {
    /// Sets the entry buffer's size (words) and stops sizing it from the host's estimate, so
    /// that the overflow path can be tested; it still grows on overflow.
    pub fn set_entry_capacity(&mut self, words: u32) {
        self.entry_capacity = words;
        self.presize = false;
        self.ws.entries.truncate(words as usize);
    }

    /// Runs a global search (`local` false) or the motion check and the local search from
    /// the tracked nodes of the previous increment. Returns hits, bin entries, regrowths and
    /// the status words.
    pub fn run_mode(
        &mut self,
        prep: &Prepared,
        local: bool,
    ) -> Result<(Vec<GpuHit>, u32, u32, [u32; STATUS_WORDS])> {
        if !local {
            let (hits, total, regrowths) = self.run(prep)?;
            self.ws.reference.clear();
            self.ws.reference.extend_from_slice(&prep.nodes);
            return Ok((hits, total, regrowths, self.ws.status));
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
            return Ok((self.ws.hits.clone(), 0, 0, status));
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
        Ok((self.ws.hits.clone(), 0, 0, status))
    }

    /// Small sliding: installs the slaves' anchors.
    pub fn set_anchors(&mut self, anchors: &[crate::search::layout::Anchor]) {
        self.anchors = Some(anchors.to_vec());
    }

    /// Runs a full search (which settles the entry capacity), then only `STEPS[..first]`
    /// again, and returns the workspace as those steps leave it: the CPU half of a split run.
    pub fn run_prefix(&mut self, prep: &Prepared, first: usize) -> Result<&CpuWorkspace> {
        self.run(prep)?;
        let mut params = prep.params;
        params.entry_capacity = self.entry_capacity;
        let levels = ScanLevels::new(params.n_cells + 1);
        self.ws.scan.iter_mut().for_each(|w| *w = 0);
        self.ws.entries.iter_mut().for_each(|w| *w = 0);
        crate::status::reset(&mut self.ws.status, crate::status::Owner::Search);
        for step in &STEPS[..first] {
            run_step(*step, &params, &levels, prep, &mut self.ws);
        }
        Ok(&self.ws)
    }

    /// The bins of the last search: cell starts and entries (in the scatter's order within a cell).
    pub fn bins(&self) -> Bins {
        let n = self.n_cells as usize;
        let total = self.ws.scan.get(n).copied().unwrap_or(0) as usize;
        Bins {
            starts: self.ws.scan[..=n].to_vec(),
            entries: self.ws.entries[..total].to_vec(),
        }
    }

    /// Runs all steps; on overflow grows the entry buffer and runs again.
    /// Returns the hits, the bin entries written and the number of regrowths.
    pub fn run(&mut self, prep: &Prepared) -> Result<(Vec<GpuHit>, u32, u32)> {
        let mut regrowths = 0;
        if self.presize {
            self.entry_capacity = presized_capacity(prep, self.entry_capacity);
        }
        loop {
            let mut params = prep.params;
            params.entry_capacity = self.entry_capacity;
            let levels = ScanLevels::new(params.n_cells + 1);
            self.ws.scan.clear();
            self.ws.scan.resize(levels.words as usize, 0);
            crate::status::reset(&mut self.ws.status, crate::status::Owner::Search);
            self.ws
                .entries
                .resize(entry_words(self.entry_capacity, prep.facets.len()), 0);
            self.ws.hits.resize(prep.slaves.len(), GpuHit::miss(0, 0));
            for step in STEPS {
                run_step(step, &params, &levels, prep, &mut self.ws);
            }
            self.n_cells = params.n_cells;
            if self.ws.status[STATUS_OVERFLOW] == 0 {
                let total = self.ws.scan[params.n_cells as usize];
                return Ok((self.ws.hits.clone(), total, regrowths));
            }
            self.entry_capacity = grown_capacity(self.ws.status[STATUS_NEEDED_ENTRIES]);
            regrowths += 1;
        }
    }
}

/// Entry capacity for `prep`: the host's estimate with an eighth more for round-off at cell
/// boundaries, never less than `current` (the workspace only grows).
pub fn presized_capacity(prep: &Prepared, current: u32) -> u32 {
    let want = prep.estimated_entries + prep.estimated_entries / 8 + 64;
    want.clamp(current as u64, u32::MAX as u64) as u32
}

/// Words of an entry buffer of `capacity` bin entries for `n_facets` facets: the bins, the
/// spill's count, and room for every facet to spill.
pub fn entry_words(capacity: u32, n_facets: usize) -> usize {
    capacity as usize + 1 + n_facets
}

/// Capacity after an overflow that needed `needed` words: a quarter more, for headroom.
pub fn grown_capacity(needed: u32) -> u32 {
    (needed as u64 + needed as u64 / 4 + 64).min(u32::MAX as u64) as u32
}

/// Runs one step of the search on the CPU workspace (the CPU half of a split run).
pub fn run_step(
    step: Step,
    params: &crate::search::layout::SearchParams,
    levels: &ScanLevels,
    prep: &Prepared,
    ws: &mut CpuWorkspace,
) {
    let n_cells = params.n_cells as usize;
    match step {
        Step::BinCount => {
            bin_count::bin_count(params, &prep.nodes, &prep.facets, &mut ws.scan[..=n_cells])
        }
        Step::Scan => scan::scan(levels, &mut ws.scan),
        Step::BinScatter => {
            ws.cursor.resize(ws.cursor.len().max(n_cells + 1), 0);
            bin_scatter::copy_starts(params, &ws.scan, &mut ws.cursor, &mut ws.entries);
            bin_scatter::bin_scatter(
                params,
                &prep.nodes,
                &prep.facets,
                &ws.scan[..=n_cells],
                &mut ws.cursor,
                &mut ws.entries,
                &mut ws.status,
            )
        }
        Step::NearestFacet => {
            let n = params.n_slaves as usize;
            let work_levels = ScanLevels::new(params.n_slaves + 1);
            ws.work.clear();
            ws.work.resize(work_levels.words as usize, 0);
            ws.best.clear();
            ws.best.resize(n * nearest_facet::BEST_WORDS, 0);
            nearest_facet::nearest_count(
                params,
                &prep.nodes,
                &prep.slaves,
                &ws.scan[..=n_cells],
                &ws.entries,
                &mut ws.work,
                &mut ws.best,
            );
            scan::scan(&work_levels, &mut ws.work);
            let c = nearest_facet::Candidates {
                params,
                nodes: &prep.nodes,
                facets: &prep.facets,
                slaves: &prep.slaves,
                starts: &ws.scan[..=n_cells],
                entries: &ws.entries,
                adjacency: &prep.adjacency,
            };
            nearest_facet::nearest_chunks(&c, &ws.work, &mut ws.best);
            nearest_facet::nearest_ties(&c, &ws.work, &mut ws.best);
            nearest_facet::nearest_crowded(&c, &ws.work, &mut ws.best);
            nearest_facet::nearest_facet(
                params,
                &prep.nodes,
                &prep.facets,
                &prep.slaves,
                &mut ws.status,
                &mut ws.hits,
                &prep.adjacency,
                &ws.best,
            );
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
