//! The global contact search of a contact pair: for each slave node, the globally nearest
//! master facet within the search radius (seed: "Global contact searches").
//!
//! The search walks a bounding-box tree over the master facets ([`tree`]: its shape fixed per
//! pair, its boxes refitted at every global search), pruned by the best distance found so far,
//! so its work follows each slave's gap rather than the search radius.
//!
//! One search is an ordered list of [`Step`]s, run by either executor: the GPU kernels
//! (`shaders/*.wgsl`, driven by [`crate::gpu`]) or their CPU mirrors ([`crate::cpu`]). Both
//! work in grid-local f32 coordinates; [`GlobalSearch::run`] converts the result back to model
//! coordinates in f64.

pub mod brute_force;
pub mod tree;

pub use crate::plan::{grid, Prepared, Step, STEPS};

use crate::abi::search as layout;
use crate::abi::status::Status;
use crate::abi::status::STATUS_WORDS;
use crate::cpu::CpuSearch;
use crate::device::{Device, DeviceKind};
use crate::error::{Error, Result};
use crate::gpu::GpuSearch;
use crate::model::Schedule;
use crate::model::{validate_positions, MasterSurface, Model, PairId};
use crate::plan::grid::Grid;
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
    /// The frame the kernels worked in, and its box (a master node leaving it moves the frame).
    pub grid: Grid,
    /// Facet–node distance evaluations in the nearest-facet step (the tree walks' projections
    /// and the chunks' candidates).
    pub candidates: u64,
    /// Slaves whose tree walk reached its visit cap and was finished in chunks (global searches).
    pub fallbacks: u32,
    /// Global searches: active master facets that had collapsed at these positions (zero
    /// length or area, by the model's rule for degenerate facets), skipped by the search; local
    /// searches pass over them too, uncounted.
    pub collapsed_facets: u32,
}

/// The result of a search: one entry per slave node, in node-set order. It holds the kernels'
/// raw f32 hits (shared with the search, not copied) and decodes a slave's [`ContactPoint`]
/// in model coordinates when asked ([`SearchResult::contact`], [`SearchResult::contacts`]),
/// so that a search of 10^6 slaves does not build 10^6 f64 records nobody reads.
#[derive(Clone, Debug)]
pub struct SearchResult {
    /// The slave nodes (model node ids), in the order of the hits (shared, not copied).
    pub slaves: Arc<[u32]>,
    /// The raw results the kernels wrote, one per slave (grid-local f32, relative to
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
    /// A global search with a refitted grid: positions kept on the device took a master node
    /// out of the grid's box.
    Frame,
    /// The local search.
    Local,
    /// Small sliding: the contact points from the fixed anchors (no search at all).
    Anchored,
}

/// A global search bound to one contact pair and one device; reusable every increment.
pub struct GlobalSearch {
    executor: Executor,
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
    /// Grid and parameters of the last global search: the frame local increments work in.
    frame: Option<(Grid, SearchParams)>,
    since_global: u32,
    crowded: bool,
    /// Sliding formulation of the pair (finite unless set).
    sliding: crate::model::Sliding,
    /// Small sliding: the anchors, fixed at the first global search.
    anchors: Option<Vec<layout::Anchor>>,
    /// Small sliding: how far the anchoring search reaches (the pair's stated search radius);
    /// `None`: every master facet, however far a slave starts (the seed's one global search).
    anchor_reach: Option<f64>,
    /// Device-resident increments: the origin the kernels' frame is relative to.
    resident_origin: Option<[f64; 3]>,
    /// Device-resident increments: the extent of the grid the frame was fitted to.
    resident_span: f64,
}

#[allow(clippy::large_enum_variant)] // one per search: its size does not matter
enum Executor {
    Gpu(Box<GpuSearch>),
    Cpu(CpuSearch),
}

impl GlobalSearch {
    /// Prepares the search of contact pair `pair` of `model` on `device` (pipelines compiled,
    /// nothing searched yet).
    pub fn new(device: &Device, model: &Model, pair: PairId) -> Result<Self> {
        let p = model.pair(pair)?;
        let master = model.surface(p.master)?.clone();
        let slaves = model.node_set(p.slave)?.to_vec();
        let radius = p.search_radius.unwrap_or_else(|| master.mean_facet_size());
        let mut search = Self::from_parts(device, model, master, slaves, radius)?;
        search.set_anchor_reach(p.search_radius);
        if let Some(schedule) = p.schedule {
            search.set_schedule(schedule)?;
        }
        search.set_sliding(p.sliding);
        Ok(search)
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
        let executor = match device.kind() {
            DeviceKind::Gpu(ctx) => Executor::Gpu(Box::new(GpuSearch::new(ctx.clone())?)),
            DeviceKind::Cpu => Executor::Cpu(CpuSearch::default()),
        };
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
        let mut motion_nodes = slaves.clone();
        let mut sorted = slaves.clone();
        sorted.sort_unstable();
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
        Ok(Self {
            executor,
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
            frame: None,
            since_global: 0,
            crowded: false,
            sliding: crate::model::Sliding::Finite,
            anchors: None,
            anchor_reach: None,
            resident_origin: None,
            resident_span: 0.0,
        })
    }

    /// Sets the sliding formulation (before the first increment).
    pub fn set_sliding(&mut self, sliding: crate::model::Sliding) {
        self.sliding = sliding;
    }

    /// Small sliding: how far the anchoring search reaches — `Some(r)`: facets within `r` of a
    /// slave (the pair's stated search radius); `None` (the default of a search made with
    /// [`GlobalSearch::from_parts`], and of a pair without a radius): every master facet, so
    /// every slave that projects onto the master is anchored however far it starts. Before the
    /// first increment.
    pub fn set_anchor_reach(&mut self, reach: Option<f64>) {
        self.anchor_reach = reach;
    }

    /// Small sliding: the slave nodes (model node ids) that got no anchor at the first
    /// increment — none of the master's facets lies along their normal from the slave (beyond
    /// a free edge) or within the anchoring search's reach — and so are not constrained; empty
    /// for finite sliding and before the first increment.
    pub fn unanchored(&self) -> Vec<u32> {
        match &self.anchors {
            Some(a) => a
                .iter()
                .zip(self.slave_ids.iter())
                .filter(|(a, _)| a.facet == NO_FACET)
                .map(|(_, &s)| s)
                .collect(),
            None => Vec::new(),
        }
    }

    /// The reach of the anchoring search at `positions`: the stated one, or one that holds
    /// every master facet from every slave (twice the diagonal of their common box).
    fn anchoring_radius(&self, positions: &[[f64; 3]]) -> f64 {
        if let Some(r) = self.anchor_reach {
            return r;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let master_nodes = self.master.nodes();
        for x in master_nodes
            .iter()
            .chain(self.slave_ids.iter())
            .filter_map(|&n| positions.get(n as usize))
        {
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
        let d2: f64 = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum();
        // within f32 (the kernels square the radius), and never below the search's own
        (2.0 * d2.sqrt()).min(1.0e18).max(self.radius)
    }

    /// Small sliding: the anchors (after the first increment).
    pub fn anchors(&self) -> Option<&[layout::Anchor]> {
        self.anchors.as_deref()
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

    /// Folds GPU dispatches into 2D beyond `groups` workgroups per dimension (no effect on the
    /// CPU path). Meant for tests of the folding, which otherwise needs millions of items.
    pub fn set_max_workgroups_per_dim(&mut self, groups: u32) {
        if let Executor::Gpu(g) = &mut self.executor {
            g.set_max_workgroups_per_dim(groups);
        }
    }

    /// Runs a global search at node positions `positions` (one per model node, model units),
    /// whatever the schedule (it resets the schedule's count).
    pub fn run(&mut self, positions: &[[f64; 3]]) -> Result<SearchResult> {
        Ok(self.execute(positions, Some(Trigger::Requested))?.0)
    }

    /// One increment of finite-sliding tracking: a global search when the schedule calls for
    /// one (the first increment, every `interval` increments, a used-up motion budget, crowded
    /// self-contact), the local search otherwise. `stats.trigger` says which ran and why.
    pub fn step(&mut self, positions: &[[f64; 3]]) -> Result<SearchResult> {
        let trigger = self.decide();
        Ok(self.execute(positions, trigger)?.0)
    }

    /// The schedule's choice for the next increment: `Some(trigger)` for a global search,
    /// `None` for the local search.
    fn decide(&self) -> Option<Trigger> {
        if self.sliding != crate::model::Sliding::Finite {
            return if self.anchors.is_none() {
                Some(Trigger::First)
            } else {
                None
            };
        }
        if self.frame.is_none() {
            Some(Trigger::First)
        } else if self.since_global + 1 >= self.schedule.interval {
            Some(Trigger::Interval)
        } else if self.self_contact && self.crowded {
            Some(Trigger::Crowded)
        } else {
            None
        }
    }

    /// Runs one increment, global (`Some(trigger)`) or local (`None`); a local increment whose
    /// motion budget is used up is run again globally.
    fn execute(
        &mut self,
        positions: &[[f64; 3]],
        mut global: Option<Trigger>,
    ) -> Result<(SearchResult, [u32; STATUS_WORDS])> {
        let mut anchored_first = false;
        loop {
            // small sliding's first increment: the global search alone, to anchor the slaves,
            // reaching as far as the pair allows; then the same increment from the anchors
            let anchoring = self.sliding != crate::model::Sliding::Finite && self.anchors.is_none();
            let prepared = match global {
                Some(_) if anchoring => {
                    let reach = self.anchoring_radius(positions);
                    let own = std::mem::replace(&mut self.radius, reach);
                    let prepared = self.prepare(positions);
                    self.radius = own;
                    prepared?
                }
                Some(_) => self.prepare(positions)?,
                None => self.prepare_local(positions)?,
            };
            let local = global.is_none();
            let (raw, status) = match &mut self.executor {
                Executor::Gpu(g) => g.run_mode(&prepared, local, true)?,
                Executor::Cpu(c) => c.run_mode(&prepared, local)?,
            };
            if local && Status(status).budget_exceeded() {
                global = Some(Trigger::Budget);
                continue;
            }
            match global {
                Some(_) => {
                    self.frame = Some((prepared.grid, prepared.params));
                    self.since_global = 0;
                    self.crowded = Status(status).crowded() > 0;
                }
                None => self.since_global += 1,
            }
            let anchored = self.anchors.is_some();
            let trigger = if anchored_first {
                Trigger::First
            } else {
                global.unwrap_or(if anchored {
                    Trigger::Anchored
                } else {
                    Trigger::Local
                })
            };
            if anchoring {
                let anchors = self.build_anchors(positions, &raw);
                match &mut self.executor {
                    Executor::Gpu(g) => g.set_anchors(&anchors)?,
                    Executor::Cpu(c) => c.set_anchors(&anchors),
                }
                self.anchors = Some(anchors);
                global = None;
                anchored_first = true;
                continue;
            }
            return Ok((
                self.finish(prepared.grid.frame, prepared.grid, raw, trigger, &status),
                status,
            ));
        }
    }

    /// One increment like [`GlobalSearch::step`], with the positions read from the caller's own
    /// buffer on this search's GPU (one `vec4<f32>` per model node, model frame; usage
    /// STORAGE, and COPY_SRC for the rare refit below): nothing is uploaded, and the hits are
    /// read back only when `read_hits` (otherwise `contacts` is empty; the status words and the
    /// bin total, 96 bytes, always come back). The frame is the last global search's grid: the first
    /// increment must be a host one ([`GlobalSearch::step`] or `run`). If a master node leaves
    /// the grid's box, the buffer is read back once, the grid refitted and the increment run
    /// again (`Trigger::Frame`). Needs a GPU device made with [`Device::from_wgpu`] on the
    /// buffer's device (or one of abut's own, for buffers it made).
    pub fn step_device(
        &mut self,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<SearchResult> {
        if self.frame.is_none() {
            return Err(Error::BadParameter {
                name: "step_device",
                value: "no global search yet".into(),
                expected: "a first increment from host positions (step or run)",
            });
        }
        let mut global = self.decide();
        loop {
            let prepared = self.prepare_device(global.is_none())?;
            let local = global.is_none();
            let Executor::Gpu(g) = &mut self.executor else {
                return Err(Error::BadParameter {
                    name: "step_device",
                    value: "CPU path".into(),
                    expected: "a GPU device",
                });
            };
            g.set_device_positions(Some(positions.clone()));
            let run = g.run_mode(&prepared, local, read_hits);
            g.set_device_positions(None);
            let (raw, status) = run?;
            if Status(status).frame_stale() {
                let host = g.read_positions(positions, prepared.n_nodes)?;
                return Ok(self.execute(&host, Some(Trigger::Frame))?.0);
            }
            if local && Status(status).budget_exceeded() {
                global = Some(Trigger::Budget);
                continue;
            }
            match global {
                Some(_) => {
                    self.since_global = 0;
                    self.crowded = Status(status).crowded() > 0;
                }
                None => self.since_global += 1,
            }
            return Ok(self.finish(
                prepared.grid.frame,
                prepared.grid,
                raw,
                global.unwrap_or(Trigger::Local),
                &status,
            ));
        }
    }

    /// Small sliding: each slave's anchor from the first global search, in f64 — the nearest
    /// point X0 on its facet, its weights, the smoothed normal N(X0) and the facet's own normal
    /// there. A slave projects onto the surface when it lies along the facet's normal from X0,
    /// or when X0 is on an edge or vertex the facet shares with another (a ridge); otherwise
    /// (beyond a free edge) it gets no anchor and no constraint.
    fn build_anchors(&self, positions: &[[f64; 3]], raw: &[GpuHit]) -> Vec<layout::Anchor> {
        let frozen = if self.sliding == crate::model::Sliding::Infinitesimal {
            layout::ANCHOR_FROZEN
        } else {
            0
        };
        raw.iter()
            .zip(self.slave_ids.iter())
            .map(|(h, &s)| {
                let none = layout::Anchor {
                    facet: NO_FACET,
                    node: u32::MAX,
                    flags: frozen,
                    _pad: 0,
                    weights: [0.0; 4],
                    normal0: [0.0; 4],
                    facet_normal0: [0.0; 4],
                };
                if h.facet == NO_FACET {
                    return none;
                }
                let f = self.master.active[h.facet as usize];
                let nodes = self.master.facets[f as usize].nodes();
                let xs: Vec<crate::geometry::V3<f64>> = nodes
                    .iter()
                    .map(|&n| crate::geometry::V3::from_array(positions[n as usize]))
                    .collect();
                let p = crate::geometry::V3::from_array(positions[s as usize]);
                let pr = crate::geometry::closest_on_facet(p, &xs);
                let dist = pr.dist2.sqrt();
                let size = self.master.facet_size[f as usize];
                let orthogonal = dist <= 1e-9 * size || pr.gap(p).abs() >= (1.0 - 1e-9) * dist;
                let on: Vec<u32> = nodes
                    .iter()
                    .zip(&pr.weights)
                    .filter(|(_, w)| **w > 1e-9)
                    .map(|(n, _)| *n)
                    .collect();
                let shared = match on.len() {
                    // on an edge: shared with another facet (a ridge, not a free edge)
                    2 => self.edge_facets(on[0], on[1]) >= 2,
                    // at a vertex: an interior one (every edge around it shared)
                    1 => self.master.facets_of_node(on[0]).iter().all(|&g| {
                        let gn = self.master.facets[g as usize].nodes();
                        let k = gn.iter().position(|&n| n == on[0]).unwrap_or(0);
                        let (prev, next) =
                            (gn[(k + gn.len() - 1) % gn.len()], gn[(k + 1) % gn.len()]);
                        (gn.len() == 2 || self.edge_facets(on[0], prev) >= 2)
                            && self.edge_facets(on[0], next) >= 2
                    }),
                    _ => false,
                };
                if !(orthogonal || shared) {
                    return none;
                }
                let mut n0 = crate::geometry::V3::<f64>::zero();
                for (k, &n) in nodes.iter().enumerate() {
                    n0 = n0
                        + crate::geometry::V3::from_array(self.master.nodal_normals[n as usize])
                            * pr.weights[k];
                }
                let n0 = n0.normalize_or_zero();
                let mut w = [0.0f32; 4];
                for k in 0..4 {
                    w[k] = pr.weights[k] as f32;
                }
                layout::Anchor {
                    facet: h.facet,
                    node: h.node,
                    flags: frozen,
                    _pad: 0,
                    weights: w,
                    normal0: [n0.x as f32, n0.y as f32, n0.z as f32, size as f32],
                    facet_normal0: [
                        pr.normal.x as f32,
                        pr.normal.y as f32,
                        pr.normal.z as f32,
                        0.0,
                    ],
                }
            })
            .collect()
    }

    /// Active facets containing both nodes `a` and `b` (2 for an interior edge, 1 for a free
    /// one; for 2D segments, facets containing node `a` when `a` is a segment end).
    fn edge_facets(&self, a: u32, b: u32) -> usize {
        let fa = self.master.facets_of_node(a);
        if self.dim == 2 {
            return fa.len();
        }
        fa.iter()
            .filter(|&&g| self.master.facets[g as usize].nodes().contains(&b))
            .count()
    }

    /// The kernels' input when the positions stay on the device: the last global search's
    /// frame and grid, no node array.
    fn prepare_device(&self, local: bool) -> Result<Prepared> {
        let Some((grid, mut params)) = self.frame else {
            return Err(Error::BadParameter {
                name: "step_device",
                value: "no global search yet".into(),
                expected: "a first increment from host positions",
            });
        };
        params.flags = self.flags();
        params.budget = (self.schedule.budget * self.radius) as f32;
        Ok(Prepared {
            params,
            grid,
            nodes: Vec::new(),
            facets: self.facets.clone(),
            slaves: self.slave_ids.clone(),
            order: self.order.clone(),
            walk_order: self.walk_order.clone(),
            adjacency: self.adjacency.clone(),
            motion_nodes: self.motion_nodes.clone(),
            local,
            n_nodes: self.masses.len(),
        })
    }

    /// Runs `STEPS[..first_gpu_step]` on the CPU mirror and the rest on this search's GPU,
    /// handing the intermediate buffers over: when GPU and CPU disagree, the first split that
    /// reproduces the CPU result names the step that diverges. On the CPU path it is `run`.
    pub fn run_split(
        &mut self,
        positions: &[[f64; 3]],
        first_gpu_step: usize,
    ) -> Result<SearchResult> {
        let prepared = self.prepare(positions)?;
        let first = first_gpu_step.min(STEPS.len());
        let (raw, status) = match &mut self.executor {
            Executor::Gpu(g) => {
                let mut cpu = CpuSearch::default();
                let ws = cpu.run_prefix(&prepared, first)?;
                g.run_split(&prepared, first, ws)?
            }
            Executor::Cpu(c) => c.run_mode(&prepared, false)?,
        };
        self.frame = Some((prepared.grid, prepared.params));
        self.since_global = 0;
        Ok(self.finish(
            prepared.grid.frame,
            prepared.grid,
            raw,
            Trigger::Requested,
            &status,
        ))
    }

    /// Readies this search for device-resident increments at `positions` (the frame's box is
    /// fitted on the device at every global search, within `Grid::cell_budget` cells). The kernels work relative to the origin of the grid the host
    /// fits at `positions` (near the master, snapped to a power of two: [`GlobalSearch::
    /// resident_frame`]): the positions the increments read are in the model frame when
    /// `caller_frame` (the caller's f32 buffers; the kernels subtract the origin in f32), or
    /// already relative to the origin (host arrays, subtracted in f64 by the host). Small
    /// sliding anchors its slaves here, by a global search at `positions`, as its first
    /// increment would.
    pub(crate) fn make_resident(
        &mut self,
        positions: &[[f64; 3]],
        caller_frame: bool,
    ) -> Result<()> {
        let anchored = self.sliding != crate::model::Sliding::Finite;
        if anchored && self.anchors.is_none() {
            self.step(positions)?;
        }
        let mut prep = self.prepare(positions)?;
        prep.params.cell_capacity = Grid::cell_budget(self.facets.len());
        let origin = prep.grid.frame;
        let frame = if caller_frame {
            origin.map(|o| o as f32)
        } else {
            [0.0; 3]
        };
        let interval = self.schedule.interval;
        self.resident_origin = Some(origin);
        self.resident_span = self.master_span(positions);
        match &mut self.executor {
            Executor::Gpu(g) => g.make_resident(&prep, interval, anchored, frame),
            Executor::Cpu(c) => {
                c.make_resident(&prep, interval, anchored, frame);
                Ok(())
            }
        }
    }

    /// Where the master nodes start in the watched nodes: after the slaves, unless the slaves
    /// are master nodes themselves (self-contact), when every watched node is one.
    fn master_start(&self) -> usize {
        if self.self_contact {
            0
        } else {
            self.slave_ids.len()
        }
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

    /// The origin of the device-resident frame (model units).
    pub(crate) fn resident_frame(&self) -> [f64; 3] {
        self.resident_origin.unwrap_or([0.0; 3])
    }

    /// The largest extent of the master's nodes along an axis at `positions` (model length
    /// units; the search radius for a master of no extent): what the frame's reach is measured
    /// in — the master's own size, never the radius, so that a large radius does not let the
    /// master travel far from the frame's origin.
    fn master_span(&self, positions: &[[f64; 3]]) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &n in &self.motion_nodes[self.master_start()..] {
            let x = positions[n as usize];
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
        let span = (0..self.dim as usize)
            .map(|a| hi[a] - lo[a])
            .fold(0.0, f64::max);
        if span > 0.0 && span.is_finite() {
            span
        } else {
            self.radius
        }
    }

    /// Host arrays: when a node of the master has travelled more than 16 times the master's own
    /// extent ([`Self::master_span`], not the search radius) from the frame's origin (f32 would
    /// lose precision there, and contact is only ever near the master), the frame moves to the
    /// grid the host fits at `positions` and the next increment searches globally, which resets
    /// everything that was relative to the old origin. Returns whether it moved.
    pub(crate) fn rebase_if_far(&mut self, positions: &[[f64; 3]]) -> Result<bool> {
        let o = self.resident_frame();
        let reach = 16.0 * self.resident_span;
        let masters = &self.motion_nodes[self.master_start()..];
        let far = masters.iter().any(|&n| {
            let x = positions[n as usize];
            (0..3).any(|a| (x[a] - o[a]).abs() > reach)
        });
        if !far {
            return Ok(false);
        }
        let prep = self.prepare(positions)?;
        if prep.grid.frame == o {
            return Ok(false);
        }
        self.resident_origin = Some(prep.grid.frame);
        self.resident_span = self.master_span(positions);
        match &mut self.executor {
            Executor::Gpu(g) => g.request_global(),
            Executor::Cpu(c) => c.request_global(),
        }
        Ok(true)
    }

    /// The search result of a device-resident increment from its hits (grid-local, relative to
    /// the resident origin), status words, params and trigger code.
    pub(crate) fn resident_result(
        &self,
        raw: Vec<GpuHit>,
        status: &[u32; STATUS_WORDS],
        params: &SearchParams,
        trigger: u32,
        first: bool,
    ) -> SearchResult {
        let origin = self.resident_origin.unwrap_or([0.0; 3]);
        let grid = Grid {
            frame: origin,
            origin: [0, 1, 2].map(|a| origin[a] + params.grid_lo[a] as f64),
            cell_size: params.cell_size as f64,
            dims: [params.dims_x, params.dims_y, params.dims_z],
        };
        let trigger = if self.sliding != crate::model::Sliding::Finite {
            if first {
                Trigger::First
            } else {
                Trigger::Anchored
            }
        } else {
            match trigger {
                layout::TRIGGER_FIRST => Trigger::First,
                layout::TRIGGER_INTERVAL => Trigger::Interval,
                layout::TRIGGER_BUDGET => Trigger::Budget,
                layout::TRIGGER_CROWDED => Trigger::Crowded,
                layout::TRIGGER_REQUESTED => Trigger::Requested,
                _ => Trigger::Local,
            }
        };
        self.finish(origin, grid, Arc::new(raw), trigger, status)
    }

    /// The GPU executor, if this search runs on one.
    pub(crate) fn gpu_mut(&mut self) -> Option<&mut GpuSearch> {
        match &mut self.executor {
            Executor::Gpu(g) => Some(g),
            Executor::Cpu(_) => None,
        }
    }

    /// The GPU executor, if this search runs on one.
    pub(crate) fn gpu(&self) -> Option<&GpuSearch> {
        match &self.executor {
            Executor::Gpu(g) => Some(g),
            Executor::Cpu(_) => None,
        }
    }

    /// The CPU executor, if this search runs on the CPU path.
    pub(crate) fn cpu(&self) -> Option<&CpuSearch> {
        match &self.executor {
            Executor::Gpu(_) => None,
            Executor::Cpu(c) => Some(c),
        }
    }

    /// The CPU executor, if this search runs on the CPU path.
    pub(crate) fn cpu_mut(&mut self) -> Option<&mut CpuSearch> {
        match &mut self.executor {
            Executor::Gpu(_) => None,
            Executor::Cpu(c) => Some(c),
        }
    }

    /// The slave nodes searched, in order.
    pub fn slaves(&self) -> &[u32] {
        &self.slave_ids
    }

    /// The master surface searched.
    pub fn master(&self) -> &MasterSurface {
        &self.master
    }

    /// The search tree's packed boxes after the last global search (one per heap node, node 0
    /// unused; local frame, decoded by [`crate::abi::boxes::unpack`] with the step
    /// [`crate::abi::boxes::box_step`] of [`layout::SearchParams::box_margin`]; read back from the
    /// GPU on a GPU device): for tests of the refit and for debugging.
    pub fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        match &self.executor {
            Executor::Gpu(g) => g.tree_boxes(),
            Executor::Cpu(c) => Ok(c.tree_boxes().to_vec()),
        }
    }

    /// The search tree's leaf slots: the active facet of each, `NO_FACET` when empty.
    pub fn tree_order(&self) -> &[u32] {
        &self.order
    }

    fn finish(
        &self,
        o: [f64; 3],
        grid: Grid,
        raw: Arc<Vec<GpuHit>>,
        trigger: Trigger,
        status: &[u32; STATUS_WORDS],
    ) -> SearchResult {
        let candidates = raw
            .iter()
            .map(|h| (h.candidates & !layout::HIT_BESIDE_FREE_EDGE) as u64)
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
                grid,
                candidates,
                fallbacks: Status(*status).fallbacks(),
                collapsed_facets: Status(*status).collapsed(),
            },
        }
    }

    /// Builds the kernels' input: validates positions, fits the grid, converts to local f32.
    pub fn prepare(&self, positions: &[[f64; 3]]) -> Result<Prepared> {
        if positions.len() != self.masses.len() {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.masses.len(),
                got: positions.len(),
            });
        }
        validate_positions(positions, 0, self.dim)?;
        // the master's box and its facets' mean extent, from the padded active facets (unused
        // slots repeat node 1, which changes no box); four lanes of f64 per corner
        let mut lo = glam::DVec4::splat(f64::INFINITY);
        let mut hi = glam::DVec4::splat(f64::NEG_INFINITY);
        let mut extent_sum = 0.0;
        for fac in self.facets.iter() {
            let n = crate::model::facet_node_count(*fac);
            let x = |j: usize| {
                let p = positions[fac[j.min(n - 1)] as usize];
                glam::DVec4::new(p[0], p[1], p[2], 0.0)
            };
            let (x0, x1, x2, x3) = (x(0), x(1), x(2), x(3));
            let flo = x0.min(x1).min(x2.min(x3));
            let fhi = x0.max(x1).max(x2.max(x3));
            lo = lo.min(flo);
            hi = hi.max(fhi);
            let e = fhi - flo;
            extent_sum += e.x.max(e.y).max(e.z);
        }
        let (lo, hi) = ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
        let n_facets = self.facets.len();
        let grid = Grid::fit(
            lo,
            hi,
            self.radius,
            extent_sum / n_facets as f64,
            n_facets,
            self.dim,
        )?;
        let nodes = self.in_frame(positions, grid.frame)?;
        let params = SearchParams {
            cell_size: grid.cell_size as f32,
            inv_cell_size: (1.0 / grid.cell_size) as f32,
            radius: self.radius as f32,
            box_margin: box_margin(lo, hi, grid.frame),
            dims_x: grid.dims[0],
            dims_y: grid.dims[1],
            dims_z: grid.dims[2],
            n_cells: grid.n_cells(),
            n_facets: n_facets as u32,
            n_slaves: self.slave_ids.len() as u32,
            tree_levels: tree::levels(n_facets),
            dim: self.dim,
            max_local_iterations: layout::MAX_LOCAL_ITERATIONS,
            flags: self.flags(),
            budget: (self.schedule.budget * self.radius) as f32,
            n_motion_nodes: self.motion_nodes.len() as u32,
            grid_lo: grid.lo_in_frame(),
            base_cell: Grid::base_cell(self.radius, extent_sum / n_facets as f64) as f32,
            cell_capacity: grid.n_cells(),
            ref_node: self.ref_node,
            _pad: [0; 2],
        };
        Ok(Prepared {
            params,
            grid,
            nodes,
            facets: self.facets.clone(),
            slaves: self.slave_ids.clone(),
            order: self.order.clone(),
            walk_order: self.walk_order.clone(),
            adjacency: self.adjacency.clone(),
            motion_nodes: self.motion_nodes.clone(),
            local: false,
            n_nodes: self.masses.len(),
        })
    }

    fn flags(&self) -> u32 {
        (if self.schedule.wide_local {
            layout::FLAG_WIDE_LOCAL
        } else {
            0
        }) | (if self.self_contact {
            layout::FLAG_SELF_CONTACT
        } else {
            0
        })
    }

    /// The kernels' input for a local increment: positions in the frame of the last global
    /// search (no grid is fitted).
    pub fn prepare_local(&self, positions: &[[f64; 3]]) -> Result<Prepared> {
        if positions.len() != self.masses.len() {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.masses.len(),
                got: positions.len(),
            });
        }
        validate_positions(positions, 0, self.dim)?;
        let mut prepared = self.prepare_device(true)?;
        prepared.nodes = self.in_frame(positions, prepared.grid.frame)?;
        Ok(prepared)
    }

    /// Every node's position relative to `frame` in f32, with its mass; an error naming the
    /// first slave or master node whose coordinate there is beyond f32's range (finite in f64,
    /// 1e39 say, but infinite to the kernels).
    fn in_frame(&self, positions: &[[f64; 3]], frame: [f64; 3]) -> Result<Vec<[f32; 4]>> {
        let nodes: Vec<[f32; 4]> = positions
            .iter()
            .zip(&self.masses)
            .map(|(x, &m)| {
                [
                    (x[0] - frame[0]) as f32,
                    (x[1] - frame[1]) as f32,
                    (x[2] - frame[2]) as f32,
                    m,
                ]
            })
            .collect();
        // every coordinate finite in f32 in both frames (the common case, sequential passes):
        // nothing to name
        let finite = |x: [f32; 3]| x[0].is_finite() && x[1].is_finite() && x[2].is_finite();
        if nodes.iter().all(|x| finite([x[0], x[1], x[2]]))
            && positions
                .iter()
                .all(|x| finite([x[0] as f32, x[1] as f32, x[2] as f32]))
        {
            return Ok(nodes);
        }
        // the lowest node beyond f32 in the model frame itself, else in the search's frame
        let lowest = |beyond: &dyn Fn(usize, usize) -> bool| {
            let mut bad: Option<(usize, usize)> = None;
            for &n in self.motion_nodes.iter() {
                let n = n as usize;
                if let Some(axis) = (0..3).find(|&a| beyond(n, a)) {
                    if bad.is_none_or(|(b, _)| n < b) {
                        bad = Some((n, axis));
                    }
                }
            }
            bad
        };
        let bad = lowest(&|n, a| !(positions[n][a] as f32).is_finite())
            .or_else(|| lowest(&|n, a| !nodes[n][a].is_finite()));
        match bad {
            None => Ok(nodes),
            Some((node, axis)) => Err(Error::CoordinateOutOfRange {
                node,
                axis,
                value: positions[node][axis],
                frame: frame[axis],
            }),
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
