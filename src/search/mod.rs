//! The global contact search of a contact pair: for each slave node, the globally nearest
//! master facet within the search radius (seed: "Global contact searches").
//!
//! The search walks a bounding-box tree over the master facets (`tree`: its shape fixed per
//! pair, its boxes refitted at every global search), pruned by the best distance found so far,
//! so its work follows each slave's gap rather than the search radius.
//!
//! A search is its part of the device-resident plan (`plan::increment::search`: positions into
//! the frame, the motion budget, the schedule's choice on the device, the local search or the
//! tree's refit and walks), run by either executor: the GPU kernels (`shaders/*.wgsl`, driven
//! by `crate::gpu`) or their CPU mirrors (`crate::cpu`). Both work in f32 relative to a frame
//! near the master; a [`SearchResult`] decodes the hits back to model coordinates in f64.

mod anchors;
pub(crate) mod brute_force;
mod exec;
mod prepare;
mod resident;
mod run;
mod structure;
pub(crate) mod tree;

pub use crate::plan::{frame, Prepared};
#[cfg(feature = "mpi")]
pub(crate) use anchors::KeyedAnchor;

use crate::abi::search as layout;
use crate::abi::status::Status;
use crate::abi::status::STATUS_WORDS;
use crate::device::Device;
use crate::error::{Error, Result};
use crate::model::Schedule;
use crate::model::{validate_positions, MasterSurface, Model, PairId, SearchStructure};
pub(crate) use exec::SearchExec;
use layout::{GpuHit, SearchParams, NO_FACET};
use std::sync::Arc;

/// The contact partner found for one slave node, in model coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// Master facet id (index into the surface's facets).
    pub facet: u32,
    /// Tracked master node: the node of that facet nearest the slave node (ties: lowest id).
    pub tracked_node: u32,
    /// Nearest point on the facet, model units.
    pub point: [f64; 3],
    /// Unit facet normal at that point.
    pub normal: [f64; 3],
    /// Signed gap along the normal, `(x_slave − point)·normal`; negative means penetration.
    pub gap: f64,
    /// Distance from the slave node to the point (≥ |gap|).
    pub distance: f64,
    /// Load-transfer weights of the facet's nodes at the point (sum to 1; unused slots 0).
    pub weights: [f64; 4],
    /// The point lies on a free edge or corner of the master (an edge no other facet shares)
    /// and the slave is beside it, off the facets: the master ends there, so enforcement treats
    /// the slave as not in contact whatever the gap.
    pub beside_free_edge: bool,
}

/// What one search did, for diagnostics and benchmarks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchStats {
    /// Global or local, and why.
    pub trigger: Trigger,
    /// Most local-search iterations a slave took (local increments).
    pub local_iterations: u32,
    /// Small sliding: slave nodes that slid more than an element length from their anchor
    /// (the formulation's own assumption no longer holds for them).
    pub slid_too_far: u32,
    /// Small sliding: anchors whose tangent plane is more than 10° off the deformed facet.
    pub plane_off: u32,
    /// Slaves whose local walk hit the iteration cap.
    pub local_capped: u32,
    /// Largest motion of a pair node since the last global search, model units.
    pub motion: f64,
    /// The master's box at the last global search (lower, upper corner), model units, as the
    /// device took it in the kernels' frame ([`SearchResult::frame`]).
    pub master_box: [[f64; 3]; 2],
    /// Facet–node distance evaluations in the nearest-facet step (the tree walks' projections
    /// and the chunks' candidates), or in a local increment those of the walks' last steps.
    pub candidates: u64,
    /// Slaves whose walk (of the tree or the buckets) reached its visit cap and was finished in
    /// chunks (global searches).
    pub fallbacks: u32,
    /// Global searches: active master facets that had collapsed at these positions (zero
    /// length or area, by the model's rule for degenerate facets), skipped by the search; local
    /// searches pass over them too, uncounted.
    pub collapsed_facets: u32,
    /// The structure the global search uses for this pair ([`SearchStructure::Buckets`] or
    /// [`SearchStructure::Tree`]; `Auto` resolved).
    pub structure: SearchStructure,
}

/// The result of a search: one entry per slave node, in node-set order. It holds the kernels'
/// raw f32 hits (shared with the search, not copied) and decodes a slave's [`ContactPoint`]
/// in model coordinates when asked ([`SearchResult::contact`], [`SearchResult::contacts`]),
/// so that a search of 10^6 slaves does not build 10^6 f64 records nobody reads.
#[derive(Clone, Debug)]
pub struct SearchResult {
    /// The slave nodes (model node ids), in the order of the hits (shared, not copied).
    pub slaves: Arc<[u32]>,
    /// The raw results the kernels wrote, one per slave (f32, relative to
    /// `frame`; for parity checks). Empty when the hits were not read back
    /// ([`GlobalSearch::step_device`] with `read_hits` false).
    pub raw: Arc<Vec<GpuHit>>,
    /// The origin of the kernels' local frame, model units: a raw point plus `frame` is the
    /// point in model coordinates.
    pub frame: [f64; 3],
    /// The master's facet id of each active facet (raw hits name active facets).
    active: Arc<[u32]>,
    /// What the search did.
    pub stats: SearchStats,
}

impl SearchResult {
    /// Slave nodes with a result (the slave count; 0 when the hits were not read back).
    pub fn len(&self) -> usize {
        self.raw.len()
    }

    /// Whether there is no result (no slave, or the hits were not read back).
    pub fn is_empty(&self) -> bool {
        self.raw.is_empty()
    }

    /// The partner of slave `i` (index into `slaves`) in model coordinates; `None` when no
    /// facet lies within the search radius, or when `i` is beyond [`SearchResult::len`].
    pub fn contact(&self, i: usize) -> Option<ContactPoint> {
        self.raw.get(i).and_then(|h| self.decode(h))
    }

    /// The partner of every slave node, in order (`None` where no facet lies within the search
    /// radius), decoded as the iterator goes.
    pub fn contacts(&self) -> impl ExactSizeIterator<Item = Option<ContactPoint>> + Clone + '_ {
        self.raw.iter().map(|h| self.decode(h))
    }

    /// A raw hit in model coordinates.
    fn decode(&self, h: &GpuHit) -> Option<ContactPoint> {
        let o = self.frame;
        (h.facet != NO_FACET).then(|| ContactPoint {
            facet: self.active[h.facet as usize],
            tracked_node: h.node,
            point: [
                o[0] + h.point_gap[0] as f64,
                o[1] + h.point_gap[1] as f64,
                o[2] + h.point_gap[2] as f64,
            ],
            normal: [
                h.normal_dist[0] as f64,
                h.normal_dist[1] as f64,
                h.normal_dist[2] as f64,
            ],
            gap: h.point_gap[3] as f64,
            distance: h.normal_dist[3] as f64,
            weights: h.weights.map(|w| w as f64),
            beside_free_edge: h.candidates & layout::HIT_BESIDE_FREE_EDGE != 0,
        })
    }
}

/// The master node nearest the centroid of `master_nodes` at `positions` (ties: the lowest id;
/// `NO_NODE` for an empty list).
fn reference_node(master_nodes: &[u32], positions: &[[f64; 3]]) -> u32 {
    let n = master_nodes.len().max(1) as f64;
    let mut c = [0.0; 3];
    for &m in master_nodes {
        let x = positions[m as usize];
        for a in 0..3 {
            c[a] += x[a] / n;
        }
    }
    let mut best = (f64::INFINITY, crate::model::NO_NODE);
    for &m in master_nodes {
        let x = positions[m as usize];
        let d2: f64 = (0..3).map(|a| (x[a] - c[a]) * (x[a] - c[a])).sum();
        if d2 < best.0 {
            best = (d2, m);
        }
    }
    best.1
}

/// Why an increment searched the way it did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trigger {
    /// A global search, the first of the run.
    First,
    /// A global search, because the interval came round.
    Interval,
    /// A global search, because the motion budget was used up (the local search ran first and
    /// was discarded).
    Budget,
    /// A global search, self-contact: unconnected facets were near a slave at the last one.
    Crowded,
    /// A global search asked for by the caller (`run`).
    Requested,
    /// A global search in a new frame: a master node had travelled more than 16 times the
    /// master's extent from the frame's origin (where f32 loses precision), so the frame moved
    /// to the master (host positions).
    Frame,
    /// The local search.
    Local,
    /// Small sliding: the contact points from the fixed anchors (no search at all).
    Anchored,
}

/// The bucket search's cells are at most this many times the largest facet at the model's
/// positions, and more than half of it (a power of two of box-grid steps): larger than every
/// facet, so a facet spans at most two cells per axis until it grows.
pub const BUCKET_CELL_FACETS: f64 = 2.0;

/// A global search bound to one contact pair and one device; reusable every increment: its
/// stage (the host's data and schedule, [`SearchStage`], whose methods it has through `Deref`)
/// and the executor chosen once from the device.
pub struct GlobalSearch {
    stage: SearchStage,
    exec: Box<dyn SearchExec>,
}

/// The host side of a search: the master and slaves in the kernels' layouts, the schedule, the
/// frame, small sliding's anchors, and the decoding of hits into [`ContactPoint`]s. The device
/// work is its executor's (a [`GlobalSearch`] holds one; a `Contact` holds its pairs' in one
/// increment executor).
pub struct SearchStage {
    master: MasterSurface,
    radius: f64,
    dim: u32,
    masses: Vec<f32>,
    adjacency: Arc<[u32]>,
    motion_nodes: Arc<[u32]>,
    /// The master node whose motion every other motion is measured against.
    ref_node: u32,
    /// Active facets, padded: the kernels' facet list.
    facets: Arc<[[u32; 4]]>,
    /// The search tree's leaf slots ([`tree::leaf_order`] of the facet centroids).
    order: Arc<[u32]>,
    /// The slaves in Morton order of their start positions (indices into `slave_ids`).
    walk_order: Arc<[u32]>,
    /// The slaves, shared with every `Prepared`.
    slave_ids: Arc<[u32]>,
    /// The master's facet id of each active facet, shared with every result.
    active: Arc<[u32]>,
    schedule: Schedule,
    self_contact: bool,
    /// Increments run since the search was made resident.
    runs: u64,
    /// Sliding formulation of the pair (finite unless set).
    sliding: crate::model::Sliding,
    /// Small sliding: the anchors, fixed at the first global search.
    anchors: Option<Vec<layout::Anchor>>,
    /// Small sliding: how far the anchoring search reaches (the pair's stated search radius);
    /// `None`: every master facet, however far a slave starts (the seed's one global search).
    anchor_reach: Option<f64>,
    /// Device-resident increments: the origin the kernels' frame is relative to.
    resident_origin: Option<[f64; 3]>,
    /// Device-resident increments: the master's extent when the frame was chosen.
    resident_span: f64,
    /// The frame's origin and the master's extent it was chosen at, given by the caller in
    /// place of this search's own choice (a distributed run's local model: the whole master's,
    /// the same on every rank); `None`: chosen here.
    given_frame: Option<([f64; 3], f64)>,
    /// The structure the global search uses (never `Auto`: resolved when set).
    structure: SearchStructure,
    /// The largest side of an active facet's nodes' box at the model's positions (model
    /// units): what the bucket search's cells are sized to.
    largest_facet: f64,
}

impl std::ops::Deref for GlobalSearch {
    type Target = SearchStage;
    fn deref(&self) -> &SearchStage {
        &self.stage
    }
}

impl std::ops::DerefMut for GlobalSearch {
    fn deref_mut(&mut self) -> &mut SearchStage {
        &mut self.stage
    }
}

impl GlobalSearch {
    /// Prepares the search of contact pair `pair` of `model` on `device` (pipelines compiled,
    /// nothing searched yet).
    pub fn new(device: &Device, model: &Model, pair: PairId) -> Result<Self> {
        let stage = SearchStage::new(model, pair)?;
        Ok(Self {
            stage,
            exec: exec::for_device(device)?,
        })
    }

    /// A search of the nodes `slaves` against `master` (a surface of `model`) within `radius`
    /// (e.g. the master-on-slave pass of a balanced pair).
    pub fn from_parts(
        device: &Device,
        model: &Model,
        master: MasterSurface,
        slaves: Vec<u32>,
        radius: f64,
    ) -> Result<Self> {
        let stage = SearchStage::from_parts(model, master, slaves, radius)?;
        Ok(Self {
            stage,
            exec: exec::for_device(device)?,
        })
    }

    /// Folds GPU dispatches into 2D beyond `groups` workgroups per dimension (no effect on the
    /// CPU path). Meant for tests of the folding, which otherwise needs millions of items.
    pub fn set_max_workgroups_per_dim(&mut self, groups: u32) {
        self.exec.set_max_workgroups_per_dim(groups);
    }

    /// Runs a global search at node positions `positions` (one per model node, model units),
    /// whatever the schedule (it resets the schedule's count).
    pub fn run(&mut self, positions: &[[f64; 3]]) -> Result<SearchResult> {
        self.stage.run_on(&mut *self.exec, positions)
    }

    /// One increment of finite-sliding tracking: a global search when the schedule calls for
    /// one (the first increment, every `interval` increments, a used-up motion budget, crowded
    /// self-contact), the local search otherwise. `stats.trigger` says which ran and why.
    pub fn step(&mut self, positions: &[[f64; 3]]) -> Result<SearchResult> {
        self.stage.step(&mut *self.exec, positions)
    }

    /// The search tree's packed boxes after the last global search (one per heap node, node 0
    /// unused; local frame, decoded by `abi::boxes::unpack` with the step of
    /// [`layout::SearchParams::box_margin`]; read back from the GPU on a GPU device): for tests
    /// of the refit and for debugging.
    pub fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        self.exec.tree_boxes()
    }

    /// A search of `stage` on `device`.
    pub(crate) fn from_stage(device: &Device, stage: SearchStage) -> Result<Self> {
        Ok(Self {
            stage,
            exec: exec::for_device(device)?,
        })
    }

    /// The stage and the executor, borrowed apart.
    pub(crate) fn parts(&mut self) -> (&mut SearchStage, &mut dyn SearchExec) {
        (&mut self.stage, &mut *self.exec)
    }
}

impl SearchStage {
    /// The stage of the search of contact pair `pair` of `model`: its radius, anchoring reach,
    /// schedule and sliding from the pair.
    pub(crate) fn new(model: &Model, pair: PairId) -> Result<Self> {
        let slaves = model.node_set(model.pair(pair)?.slave)?.to_vec();
        Self::for_pair(model, pair, slaves)
    }

    /// As [`SearchStage::new`], with the pair's slave nodes `slaves` in the order the search
    /// keeps them (a permutation of its node set: [`crate::model::SlaveOrder`]).
    pub(crate) fn for_pair(model: &Model, pair: PairId, slaves: Vec<u32>) -> Result<Self> {
        let p = model.pair(pair)?;
        let master = model.surface(p.master)?.clone();
        let radius = p.search_radius.unwrap_or_else(|| master.mean_facet_size());
        let mut search = Self::from_parts(model, master, slaves, radius)?;
        search.set_anchor_reach(p.search_radius);
        if let Some(schedule) = p.schedule {
            search.set_schedule(schedule)?;
        }
        search.set_sliding(p.sliding);
        search.set_search_structure(p.search_structure);
        Ok(search)
    }

    /// The stage of a search of the nodes `slaves` against `master` within `radius`.
    pub(crate) fn from_parts(
        model: &Model,
        master: MasterSurface,
        slaves: Vec<u32>,
        radius: f64,
    ) -> Result<Self> {
        if slaves.is_empty() {
            return Err(Error::Empty {
                what: "slave node list".into(),
            });
        }
        if let Some(&bad) = slaves
            .iter()
            .find(|&&s| s as usize >= model.positions().len())
        {
            return Err(Error::IndexOutOfRange {
                what: "slave node".into(),
                index: bad as u64,
                len: model.positions().len(),
            });
        }
        let n_nodes = model.positions().len();
        let mut active_index = vec![u32::MAX; master.facets.len()];
        for (k, &f) in master.active.iter().enumerate() {
            active_index[f as usize] = k as u32;
        }
        let mut adjacency = Vec::with_capacity(n_nodes + 1 + 4 * master.active.len());
        adjacency.resize(n_nodes + 1, 0);
        for n in 0..n_nodes {
            adjacency[n] = adjacency.len() as u32;
            let list: Vec<u32> = master
                .facets_of_node(n as u32)
                .iter()
                .map(|&f| active_index[f as usize])
                .collect();
            adjacency.extend(list);
        }
        adjacency[n_nodes] = adjacency.len() as u32;
        let master_nodes = master.nodes();
        let ref_node = reference_node(&master_nodes, model.positions());
        let self_contact = slaves.iter().any(|s| master_nodes.binary_search(s).is_ok());
        // the slaves in node order, then the master's other nodes: motion reads by node
        let mut sorted = slaves.clone();
        sorted.sort_unstable();
        let mut motion_nodes = sorted.clone();
        motion_nodes.extend(
            master_nodes
                .iter()
                .filter(|n| sorted.binary_search(n).is_err()),
        );
        let facets: Arc<[[u32; 4]]> = master
            .active
            .iter()
            .map(|&f| master.facets[f as usize].padded())
            .collect();
        let slave_ids: Arc<[u32]> = slaves.into();
        let centroids: Vec<[f64; 3]> = facets
            .iter()
            .map(|fac| {
                let n = crate::model::facet_node_count(*fac);
                let mut c = [0.0; 3];
                for &id in &fac[..n] {
                    let x = model.positions()[id as usize];
                    for a in 0..3 {
                        c[a] += x[a] / n as f64;
                    }
                }
                c
            })
            .collect();
        let order = tree::leaf_order(&centroids, model.dim()).into();
        let slave_points: Vec<[f64; 3]> = slave_ids
            .iter()
            .map(|&s| model.positions()[s as usize])
            .collect();
        let walk_order = tree::morton_order(&slave_points, model.dim()).into();
        let largest_facet = structure::largest_facet(&facets, model.positions());
        let mut stage = Self {
            active: master.active.as_slice().into(),
            master,
            facets,
            order,
            walk_order,
            slave_ids,
            radius,
            dim: model.dim(),
            masses: model.masses().iter().map(|&m| m as f32).collect(),
            adjacency: adjacency.into(),
            motion_nodes: motion_nodes.into(),
            ref_node,
            schedule: Schedule::default_for(self_contact),
            self_contact,
            runs: 0,
            sliding: crate::model::Sliding::Finite,
            anchors: None,
            anchor_reach: None,
            resident_origin: None,
            resident_span: 0.0,
            given_frame: None,
            structure: SearchStructure::Tree,
            largest_facet,
        };
        stage.set_search_structure(SearchStructure::Auto);
        Ok(stage)
    }

    /// Sets when the search runs globally.
    pub fn set_schedule(&mut self, schedule: Schedule) -> Result<()> {
        if schedule.interval == 0 || !(schedule.budget > 0.0 && schedule.budget <= 1.0) {
            return Err(Error::BadParameter {
                name: "search schedule",
                value: format!("{schedule:?}"),
                expected: "needs an interval ≥ 1 and a budget in (0, 1]",
            });
        }
        self.schedule = schedule;
        // the plan holds the interval: the next increment makes a fresh one
        self.resident_origin = None;
        Ok(())
    }

    /// The schedule in use.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    /// Whether this is a self-contact search (slave nodes lie on the master surface).
    pub fn is_self_contact(&self) -> bool {
        self.self_contact
    }

    /// The search radius in use, model units.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The active facets in the kernels' layout (padded node ids; a raw hit's `facet` indexes
    /// this list).
    pub(crate) fn kernel_facets(&self) -> &[[u32; 4]] {
        &self.facets
    }

    /// The nodes the motion budget watches: the slaves, then the master nodes that are not.
    pub(crate) fn motion_nodes(&self) -> &[u32] {
        &self.motion_nodes
    }

    /// The pair's reference master node (model node id): the master node nearest the centroid
    /// of the master's nodes at the model's positions (ties: the lowest id). Motion is judged
    /// relative to the master, not to the model's frame: the motion budget measures every
    /// watched node's displacement since the last global search minus this node's, and a slave
    /// with no facet within the radius is judged fast ([`crate::StepReport::fast_nodes`]) on
    /// its velocity minus this node's — so a contact model that travels as a whole uses neither.
    pub fn reference_node(&self) -> u32 {
        self.ref_node
    }

    /// Whether this search evaluates fixed anchors (small or infinitesimal sliding).
    pub(crate) fn is_anchored(&self) -> bool {
        self.sliding != crate::model::Sliding::Finite
    }

    /// The slave nodes searched, in order.
    pub fn slaves(&self) -> &[u32] {
        &self.slave_ids
    }

    /// The master surface searched.
    pub fn master(&self) -> &MasterSurface {
        &self.master
    }

    /// The search tree's leaf slots: the active facet of each, `NO_FACET` when empty.
    pub fn tree_order(&self) -> &[u32] {
        &self.order
    }

    fn finish(
        &self,
        o: [f64; 3],
        master_box: [[f64; 3]; 2],
        raw: Arc<Vec<GpuHit>>,
        trigger: Trigger,
        status: &[u32; STATUS_WORDS],
    ) -> SearchResult {
        // a local increment's work is its tracked slaves' walks: an untracked slave's hit is
        // still the last global search's, and so is its count
        let candidates = raw
            .iter()
            .filter(|h| trigger != Trigger::Local || h.node != crate::model::NO_NODE)
            .map(|h| (h.candidates & layout::HIT_COUNT) as u64)
            .sum();
        SearchResult {
            slaves: self.slave_ids.clone(),
            raw,
            frame: o,
            active: self.active.clone(),
            stats: SearchStats {
                trigger,
                local_iterations: Status(*status).local_iterations(),
                slid_too_far: Status(*status).slid_too_far(),
                plane_off: Status(*status).plane_off(),
                local_capped: Status(*status).local_capped(),
                motion: Status(*status).motion() as f64,
                master_box,
                candidates,
                fallbacks: Status(*status).fallbacks(),
                collapsed_facets: Status(*status).collapsed(),
                structure: self.structure,
            },
        }
    }
}

/// The growth of the search tree's leaf boxes for a master within `[lo, hi]` (model units) in
/// the frame at `frame`: 32 f32 round-offs of the largest coordinate there, more than the error
/// of a closest point computed in f32 (WGSL: the schedule's device fit, the same rule).
pub fn box_margin(lo: [f64; 3], hi: [f64; 3], frame: [f64; 3]) -> f32 {
    let m = (0..3)
        .map(|a| (lo[a] - frame[a]).abs().max((hi[a] - frame[a]).abs()))
        .filter(|m| m.is_finite())
        .fold(0.0, f64::max);
    (32.0 * f32::EPSILON as f64 * m) as f32
}
