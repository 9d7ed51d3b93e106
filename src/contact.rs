//! The per-increment object a host program drives: search and enforcement of every pair.

use crate::abi::penalty::{
    ContactOut, SlaveState, CSTATUS_MASK, CSTATUS_OPEN, CSTATUS_SLIP, CSTATUS_STICK,
};
use crate::cpu::CpuPenalty;
use crate::device::{Device, DeviceKind};
use crate::error::{Error, Result};
use crate::geometry::{closest_on_facet, V3};
use crate::gpu::GpuPenalty;
use crate::kinematic::{
    anchored_pass, facets_from, friction_pass, meshed_pass, rigid_pass, BodyState,
    FrictionCorrection, SlaveCorrection, PASSES,
};
use crate::model::{validate_positions, Model, PairId};
use crate::model::{BodyId, Enforce, MasterSurface, PressureOverclosure, RigidBody, RigidPairId};
use crate::penalty::PenaltySetup;
use crate::search::{GlobalSearch, SearchResult};

mod resident;
mod restart;
mod rigid_parts;
mod warnings;
pub use resident::ResidentIo;

/// The penalty executor of one pair, on the same device as its search.
pub(crate) enum PenaltyExec {
    Gpu(Box<GpuPenalty>),
    Cpu(CpuPenalty),
}

/// CSTATUS: the state of a slave node's contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactStatus {
    /// Not in contact.
    Open,
    /// In contact, sticking.
    Stick,
    /// In contact, slipping (frictionless contact always slips).
    Slip,
}

/// The increment of a run whose nodes carry elements and penalty springs together: the elements'
/// stable increment `element_dt` (already times `safety`) and the contact's `contact_dt`
/// (`StepReport::stable_dt`) give 1/Δt² = 1/Δt_elements² + 1/(safety·Δt_contact)² — their
/// frequencies add in square, with the same safety on both — and no more than
/// `contact_safety·Δt_contact`, so that every contact spring stays at ω·Δt ≤ 2·contact_safety,
/// where its switching on and off does not pump energy into the node (tests/scene.rs). A host
/// program that integrates its own elements calls this with its elements' increment and the
/// report's `stable_dt` (a scene run does).
pub fn combined_increment(
    element_dt: f64,
    contact_dt: f64,
    safety: f64,
    contact_safety: f64,
) -> f64 {
    let dt_c = safety * contact_dt;
    let both = 1.0 / (1.0 / (element_dt * element_dt) + 1.0 / (dt_c * dt_c)).sqrt();
    both.min(contact_safety * contact_dt)
}

/// What one increment of penalty contact gives the host.
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// Contact force on every model node (model force units), summed over the pairs.
    pub forces: Vec<[f64; 3]>,
    /// The largest increment the penalty springs allow under central differences, with the
    /// damping: the smaller of each spring's own limit 2/ω, ω² = k·(1/m_s + 1/m_master) — the
    /// compliance of each side at the contact point along the normal: a node's 1/mass, the
    /// master nodes' Σ w_j²/m_j by the load-transfer weights, or a rigid part's
    /// ([`Model::add_rigid_part`]) 1/M + (r×n)·I⁻¹·(r×n) about its centre of mass — for the
    /// springs within the search radius, and a node-wise bound on all the springs in contact
    /// together, which covers nodes shared by several springs (a master node under several
    /// slaves, both passes of a balanced pair) and counts a rigid part's springs as one body's;
    /// exact for one spring wherever it sits on the facet (to 1e-4; tests/hard_cases.rs), safe
    /// for many. It bounds the contact springs alone: a node's elements add their own frequency
    /// ([`crate::combined_increment`]); kinematic pairs (meshed or analytical masters) limit
    /// no increment. ∞ when there is none. A linear limit: a spring that switches on and off near
    /// it pumps energy into a node pressed into contact, so take at most about half of it for
    /// contact that persists, unless the contact is damped (10 % of critical lets 0.9 of it
    /// hold; tests/scene.rs).
    pub stable_dt: f64,
    /// Half the smallest remaining gap over its closing speed: an increment beyond this could
    /// carry an approaching node through its master facet in one step; ∞ when none approaches.
    pub approach_dt: f64,
    /// The largest overclosure (penetration, model length units, ≥ 0) of a slave node carrying
    /// penalty force this increment, over every pair; 0 when none. Known without asking for
    /// the output variables.
    pub max_overclosure: f64,
    /// Slave nodes in contact.
    pub active: usize,
    /// Of which slipping.
    pub slipping: usize,
    /// Searches that ran globally this increment (the schedule's choice, made on the device).
    pub global_searches: usize,
    /// Slave nodes whose walk of the search tree reached its visit cap this increment and was
    /// finished in bounded chunks (the search stayed exact; many mean a badly fitting tree).
    pub fallbacks: usize,
    /// Small and infinitesimal sliding (penalty pairs): slave nodes that got no anchor at the
    /// first increment — they project onto no master facet — and so are not constrained
    /// ([`Contact::anchoring`] names them).
    pub unanchored: usize,
    /// `stable_dt` is finite although no slave node is in contact: it is the limit of springs of
    /// slave nodes within the search radius that have not touched yet (one may close within an
    /// increment, so their limit applies before contact).
    pub stable_dt_before_contact: bool,
    /// Slave nodes (per pair; a balanced pair's master nodes in its second pass) whose
    /// velocity relative to the master near them carries them farther than their pair's search
    /// radius within this increment: the search cannot follow them, and a slave may pass
    /// through its master unseen (tunnelling). The master near a slave is the master's
    /// velocity at its contact point, or — for a slave with no facet within the radius — the
    /// velocity of the pair's reference master node ([`GlobalSearch::reference_node`]); so a
    /// contact model that moves as a whole, or a slave carried along by its master, is never
    /// fast, while a slave crossing a still or opposing master is. Counted by the penalty
    /// kernels on every path (host arrays and device-resident: [`crate::IncrementStats::fast_nodes`]).
    pub fast_nodes: usize,
    /// The fastest of them.
    pub fastest: Option<FastNode>,
}

/// A slave node that moves farther than its pair's search radius relative to the master near
/// it within one increment ([`StepReport::fast_nodes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FastNode {
    /// The model node.
    pub node: usize,
    /// Its pair (a meshed pair's id).
    pub pair: PairId,
    /// Its speed relative to the master near it times the increment, model length units.
    pub distance: f64,
    /// The pair's search radius.
    pub radius: f64,
}

/// The slaves of `search` (pair `pair`) whose velocity relative to the master near them
/// carries them farther than the pair's search radius within `dt`: their count, and the slave
/// with the largest relative motion over the radius whether or not it is fast (`None` without
/// slaves). The master near a slave is its velocity at the slave's contact point in `hits` (the
/// kernels' raw hits, one per slave: the facet's nodes weighted by the load-transfer weights),
/// or, for a slave with no facet within the radius, the pair's reference master node's
/// ([`GlobalSearch::reference_node`]). The penalty kernels apply the same rule in f32
/// (`STATUS_FAST`); this is its f64 twin, for kinematic pairs and to name the fastest slave.
fn fast_slaves(
    pair: PairId,
    search: &GlobalSearch,
    hits: &[crate::abi::search::GpuHit],
    velocities: &[[f64; 3]],
    dt: f64,
) -> (usize, Option<FastNode>) {
    let radius = search.radius();
    let facets = search.kernel_facets();
    let reference = search.reference_node();
    let (mut count, mut fastest) = (0, None::<FastNode>);
    for (&slave, h) in search.slaves().iter().zip(hits) {
        let mut vm = [0.0; 3];
        if h.facet != crate::abi::search::NO_FACET {
            let fac = facets[h.facet as usize];
            for j in 0..crate::model::facet_node_count(fac) {
                let v = velocities[fac[j] as usize];
                for a in 0..3 {
                    vm[a] += h.weights[j] as f64 * v[a];
                }
            }
        } else if reference != crate::model::NO_NODE {
            vm = velocities[reference as usize];
        } else {
            continue;
        }
        let v = velocities[slave as usize];
        let rel = [v[0] - vm[0], v[1] - vm[1], v[2] - vm[2]];
        let distance = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt() * dt;
        if distance > radius {
            count += 1;
        }
        if fastest.is_none_or(|f| distance / radius > f.distance / f.radius) {
            fastest = Some(FastNode {
                node: slave as usize,
                pair,
                distance,
                radius,
            });
        }
    }
    (count, fastest)
}

/// Small or infinitesimal sliding: what one pass of a pair anchored at the first increment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Anchoring {
    /// The pair.
    pub pair: PairId,
    /// The slave nodes of this pass (the master's nodes for a balanced pair's second pass).
    pub slaves: usize,
    /// Of which anchored to a master facet.
    pub anchored: usize,
    /// The others (model node ids): they project onto no master facet — beyond a free edge,
    /// or beyond the pair's stated search radius — and are not constrained.
    pub unanchored: Vec<u32>,
}

/// Contact output variables of one pair after an increment (when requested).
#[derive(Clone, Debug, Default)]
pub struct PairOutput {
    /// The slave nodes, in node-set order.
    pub slaves: Vec<u32>,
    /// CSTATUS per slave.
    pub cstatus: Vec<Option<ContactStatus>>,
    /// COPEN: gap along the contact normal (model length units; negative = penetration).
    pub copen: Vec<f64>,
    /// CPRESS: normal force over the tributary area.
    pub cpress: Vec<f64>,
    /// CSHEAR1: friction force along t1 over the tributary area.
    pub cshear1: Vec<f64>,
    /// CSHEAR2: friction force along t2 over the tributary area.
    pub cshear2: Vec<f64>,
    /// The contact normal used at each slave (smoothed master normal).
    pub normal: Vec<[f64; 3]>,
    /// Total contact force on each slave node.
    pub force: Vec<[f64; 3]>,
    /// CFN: resultant normal contact force on the slaves.
    pub cfn: [f64; 3],
    /// CFS: resultant friction force on the slaves.
    pub cfs: [f64; 3],
    /// Elastic energy stored in the contact springs.
    pub contact_energy: f64,
    /// Frictional dissipation since the start.
    pub frictional_dissipation: f64,
    /// The search result of this increment (contact points, facets, weights).
    pub search: Option<SearchResult>,
}

struct PairRun {
    id: PairId,
    search: GlobalSearch,
    setup: PenaltySetup,
    exec: PenaltyExec,
    output: PairOutput,
    /// Host-array increments: what the host knows of the device's schedule.
    schedule: resident::HostSchedule,
}

/// A kinematic pair against a meshed master (pure or balanced).
struct KinematicRun {
    id: PairId,
    search: GlobalSearch,
    /// Balanced: the master-on-slave search, its slave surface, and the weight of pass one.
    back: Option<(GlobalSearch, MasterSurface, f64)>,
    master: MasterSurface,
    slaves: Vec<u32>,
    areas: Vec<f64>,
    law: Option<PressureOverclosure>,
    /// Small or infinitesimal sliding: corrections along the anchors' planes.
    anchored: bool,
    /// Coulomb friction (μ static, μ kinetic, decay), after the normal correction.
    friction: Option<(f64, f64, f64)>,
    /// The energy its friction dissipated since the start.
    dissipated: f64,
    /// Per slave (pass one, then the balanced pass's): behind a free edge of the master
    /// ([`facets_from`]).
    behind: (Vec<bool>, Vec<bool>),
    output: PairOutput,
}

/// A kinematic pair against a rigid body's analytical surface.
struct RigidRun {
    id: RigidPairId,
    body: BodyId,
    spec: RigidBody,
    slaves: Vec<u32>,
    areas: Vec<f64>,
    law: Option<PressureOverclosure>,
    output: PairOutput,
}

/// What one kinematic increment did.
#[derive(Clone, Debug, Default)]
pub struct KinematicReport {
    /// Slave nodes corrected (over all kinematic and rigid pairs, first pass).
    pub active: usize,
    /// Largest overclosure before the correction.
    pub max_overclosure: f64,
    /// Largest overclosure left after it, measured again on the corrected positions (hard
    /// contact: round-off; softened: the law's equilibrium overclosure).
    pub max_overclosure_after: f64,
    /// Change of kinetic energy made by the corrections (negative: the energy kinematic contact
    /// dissipates at impact).
    pub kinetic_energy_change: f64,
    /// Sum over slaves of the resisting force magnitudes (first pass).
    pub total_force: f64,
    /// Sum over slaves of the kinematic friction force magnitudes (pairs with friction).
    pub friction_force: f64,
    /// Slave nodes of meshed kinematic pairs that the velocities (the predictor's) carry
    /// farther than their pair's search radius relative to the master near them within this
    /// increment, by [`StepReport::fast_nodes`]'s rule.
    pub fast_nodes: usize,
    /// The fastest of them.
    pub fastest: Option<FastNode>,
}

/// The strain-free adjustment of initially overclosed slave nodes.
#[derive(Clone, Debug, Default)]
pub struct OverclosureReport {
    /// (node, distance moved) of every node moved.
    pub moved: Vec<(u32, f64)>,
    /// Largest distance moved.
    pub max_distance: f64,
    /// Kinetic energy the first kinematic increment would have injected had the overclosure
    /// been resolved then, Σ ½·m·(h/dt)²: the cost the adjustment avoids.
    pub energy_avoided: f64,
}

/// Search and enforcement of every pair of a model, once per increment.
pub struct Contact {
    pairs: Vec<PairRun>,
    kinematic: Vec<KinematicRun>,
    rigid: Vec<RigidRun>,
    masses: Vec<f64>,
    kin_report: KinematicReport,
    n_nodes: usize,
    dt_ref: Option<f64>,
    want_outputs: bool,
    report: StepReport,
    /// The model's positions (the frame and anchors of device-resident increments).
    initial_positions: Vec<[f64; 3]>,
    /// Device-resident increments: rows, statistics and their ring.
    resident: Option<resident::Resident>,
    /// Global searches of the penalty pairs since the start (host-array increments).
    global_total: u64,
    /// Which kind of penalty increment this Contact runs (set by the first).
    mode: Option<resident::Mode>,
    /// Host-array increments run.
    host_increments: u64,
    /// Spatial dimension.
    dim: u32,
    /// The model's rigid parts, followed from the positions of host-array increments.
    parts: Vec<rigid_parts::RigidPartRun>,
}

impl Contact {
    /// Builds the passes every pair of `model` needs on `device` (pipelines compiled, buffers
    /// made; a frictionless pair compiles no friction work).
    pub fn new(device: &Device, model: &Model) -> Result<Self> {
        if model.pairs().is_empty() && model.rigid_pairs().is_empty() {
            return Err(Error::Empty {
                what: "the model's contact pairs".into(),
            });
        }
        let n_nodes = model.positions().len();
        let mut pairs = Vec::new();
        let mut kinematic = Vec::new();
        for k in 0..model.pairs().len() {
            let id = PairId(k);
            let pair = model.pair(id)?;
            let search = GlobalSearch::new(device, model, id)?;
            let slaves = model.node_set(pair.slave)?.to_vec();
            match &pair.enforce {
                Enforce::Penalty(_) => {
                    let make_exec = |setup: &PenaltySetup| -> Result<PenaltyExec> {
                        Ok(match device.kind() {
                            DeviceKind::Gpu(ctx) => PenaltyExec::Gpu(Box::new(GpuPenalty::new(
                                ctx.clone(),
                                setup,
                                n_nodes,
                            )?)),
                            DeviceKind::Cpu => PenaltyExec::Cpu(CpuPenalty::new(setup, n_nodes)),
                        })
                    };
                    let setup = PenaltySetup::new(model, id, search.master(), &slaves)?
                        .with_search(search.radius(), search.reference_node());
                    let exec = make_exec(&setup)?;
                    let back = match pair.balanced {
                        // balanced: the master surface's nodes against the slave surface too
                        Some((surface, _)) => {
                            let slave_surface = model.surface(surface)?.clone();
                            let nodes = search.master().nodes();
                            let rsearch = GlobalSearch::from_parts(
                                device,
                                model,
                                slave_surface.clone(),
                                nodes.clone(),
                                search.radius(),
                            )?;
                            let reverse = PenaltySetup::reverse(
                                model,
                                id,
                                search.master(),
                                &slave_surface,
                                &nodes,
                            )?
                            .with_search(rsearch.radius(), rsearch.reference_node());
                            let rexec = make_exec(&reverse)?;
                            Some(PairRun {
                                id,
                                search: rsearch,
                                setup: reverse,
                                exec: rexec,
                                output: PairOutput {
                                    slaves: nodes,
                                    ..Default::default()
                                },
                                schedule: Default::default(),
                            })
                        }
                        None => None,
                    };
                    pairs.push(PairRun {
                        id,
                        search,
                        setup,
                        exec,
                        output: PairOutput {
                            slaves,
                            ..Default::default()
                        },
                        schedule: Default::default(),
                    });
                    pairs.extend(back);
                }
                Enforce::Kinematic(kin) => {
                    let master = search.master().clone();
                    let areas = slave_areas(model, pair.slave, &master)?;
                    let back = match pair.balanced {
                        Some((surface, w)) => {
                            let slave_surface = model.surface(surface)?.clone();
                            let nodes = master.nodes();
                            let radius = search.radius();
                            Some((
                                GlobalSearch::from_parts(
                                    device,
                                    model,
                                    slave_surface.clone(),
                                    nodes,
                                    radius,
                                )?,
                                slave_surface,
                                w,
                            ))
                        }
                        None => None,
                    };
                    let behind = (
                        vec![false; search.slaves().len()],
                        vec![false; back.as_ref().map_or(0, |b| b.0.slaves().len())],
                    );
                    let friction = match pair.friction {
                        crate::model::Friction::Frictionless => None,
                        crate::model::Friction::Coulomb {
                            mu,
                            mu_kinetic,
                            decay,
                            ..
                        } => Some((mu, mu_kinetic, decay)),
                    };
                    kinematic.push(KinematicRun {
                        id,
                        search,
                        friction,
                        dissipated: 0.0,
                        behind,
                        back,
                        master,
                        slaves: slaves.clone(),
                        areas,
                        law: kin.softened.clone(),
                        anchored: pair.sliding != crate::model::Sliding::Finite,
                        output: PairOutput {
                            slaves,
                            ..Default::default()
                        },
                    });
                }
            }
        }
        let mut rigid = Vec::new();
        for (k, rp) in model.rigid_pairs().iter().enumerate() {
            let slaves = model.node_set(rp.slave)?.to_vec();
            let areas = match model.node_set_areas(rp.slave)? {
                Some(a) => a.to_vec(),
                None => vec![1.0; slaves.len()],
            };
            rigid.push(RigidRun {
                id: RigidPairId(k),
                body: rp.body,
                spec: model.body(rp.body)?.clone(),
                slaves: slaves.clone(),
                areas,
                law: rp.softened.clone(),
                output: PairOutput {
                    slaves,
                    ..Default::default()
                },
            });
        }
        Ok(Self {
            pairs,
            kinematic,
            rigid,
            masses: model.masses().to_vec(),
            kin_report: KinematicReport::default(),
            n_nodes,
            dt_ref: None,
            want_outputs: false,
            report: StepReport::default(),
            initial_positions: model.positions().to_vec(),
            resident: None,
            mode: None,
            global_total: 0,
            host_increments: 0,
            dim: model.dim(),
            parts: rigid_parts::RigidPartRun::all(model),
        })
    }

    /// Asks for the contact output variables ([`Contact::outputs`]) to be computed and read
    /// back every increment (off by default: then only forces and increments come back).
    pub fn request_outputs(&mut self, yes: bool) {
        self.want_outputs = yes;
    }

    /// The per-slave state of penalty pair `pair` — the carried friction (stick) force, the
    /// tributary area and the history (dissipation, behind-a-free-edge flag) — one list per pass
    /// (two for a balanced pair: the slave nodes', then the master nodes'), in the order of the
    /// pair's slave node set. With [`Contact::set_penalty_states`] it carries a contact's
    /// friction into another Contact over the same slaves (a rebuilt local model of a
    /// distributed run). Reads back from the device on a GPU.
    pub fn penalty_states(&self, pair: PairId) -> Result<Vec<Vec<SlaveState>>> {
        let mut out = Vec::new();
        for p in self.pairs.iter().filter(|p| p.id == pair) {
            out.push(match &p.exec {
                PenaltyExec::Cpu(c) => c.state.clone(),
                PenaltyExec::Gpu(g) => g.read_state()?,
            });
        }
        if out.is_empty() {
            return Err(Error::UnknownId {
                what: "penalty pair",
                id: pair.0,
            });
        }
        Ok(out)
    }

    /// Replaces the per-slave state of penalty pair `pair` (as [`Contact::penalty_states`]
    /// gives it: one list per pass, each as long as that pass's slaves).
    pub fn set_penalty_states(&mut self, pair: PairId, states: &[Vec<SlaveState>]) -> Result<()> {
        let runs: Vec<usize> = (0..self.pairs.len())
            .filter(|&k| self.pairs[k].id == pair)
            .collect();
        if runs.is_empty() {
            return Err(Error::UnknownId {
                what: "penalty pair",
                id: pair.0,
            });
        }
        if runs.len() != states.len() {
            return Err(Error::LengthMismatch {
                what: "penalty states (one list per pass of the pair)",
                expected: runs.len(),
                got: states.len(),
            });
        }
        for (&k, s) in runs.iter().zip(states) {
            let n = self.pairs[k].output.slaves.len();
            if s.len() != n {
                return Err(Error::LengthMismatch {
                    what: "penalty states (one per slave of the pass)",
                    expected: n,
                    got: s.len(),
                });
            }
        }
        for (&k, s) in runs.iter().zip(states) {
            match &mut self.pairs[k].exec {
                PenaltyExec::Cpu(c) => c.state.copy_from_slice(s),
                PenaltyExec::Gpu(g) => g.write_state(s),
            }
        }
        Ok(())
    }

    /// Sets the reference increment of the automatic penalty stiffness (by default the first
    /// increment's `dt`).
    pub fn set_reference_increment(&mut self, dt: f64) -> Result<()> {
        positive_dt(dt)?;
        self.dt_ref = Some(dt);
        Ok(())
    }

    /// One increment: the global search of every pair at `positions`, then penalty forces from
    /// the gaps and the relative velocities `velocities` (at the half step before, as central
    /// differences has them), over increment `dt`. Returns forces on every node and the
    /// increments the contact allows.
    pub fn penalty_step(
        &mut self,
        positions: &[[f64; 3]],
        velocities: &[[f64; 3]],
        dt: f64,
    ) -> Result<&StepReport> {
        positive_dt(dt)?;
        if matches!(self.mode, Some(resident::Mode::Device)) {
            return Err(Error::BadParameter {
                name: "penalty_step",
                value: "a Contact running device-resident increments".into(),
                expected: "one kind of increment per Contact (make another for host arrays)",
            });
        }
        for (what, len) in [
            ("positions (one per model node)", positions.len()),
            ("velocities (one per model node)", velocities.len()),
        ] {
            if len != self.n_nodes {
                return Err(Error::LengthMismatch {
                    what,
                    expected: self.n_nodes,
                    got: len,
                });
            }
        }
        validate_positions(positions, 0, self.dim)?;
        validate_velocities(velocities)?;
        if self.pairs.is_empty() {
            self.report = StepReport {
                forces: vec![[0.0; 3]; self.n_nodes],
                stable_dt: f64::INFINITY,
                approach_dt: f64::INFINITY,
                ..Default::default()
            };
            return Ok(&self.report);
        }
        self.host_increment(positions, velocities, dt)?;
        Ok(&self.report)
    }

    /// Global searches the penalty pairs' host-array increments ran since the start (each
    /// pass of a balanced pair counts).
    pub fn global_searches(&self) -> u64 {
        self.global_total
    }

    /// Small and infinitesimal sliding: each anchored pass's count of anchored slave nodes and
    /// the nodes left unconstrained, after the first increment (empty before it and for
    /// finite sliding). Penalty passes first, then kinematic ones.
    pub fn anchoring(&self) -> Vec<Anchoring> {
        let penalty = self.pairs.iter().map(|p| (p.id, &p.search));
        let kinematic = self.kinematic.iter().flat_map(|k| {
            std::iter::once((k.id, &k.search)).chain(k.back.iter().map(|b| (k.id, &b.0)))
        });
        penalty
            .chain(kinematic)
            .filter(|(_, s)| s.anchors().is_some())
            .map(|(pair, s)| {
                let unanchored = s.unanchored();
                Anchoring {
                    pair,
                    slaves: s.slaves().len(),
                    anchored: s.slaves().len() - unanchored.len(),
                    unanchored,
                }
            })
            .collect()
    }

    /// Whether any pair is enforced by penalty.
    pub fn has_penalty_pairs(&self) -> bool {
        !self.pairs.is_empty()
    }

    /// Whether any pair (meshed or rigid) is enforced kinematically.
    pub fn has_kinematic_pairs(&self) -> bool {
        !self.kinematic.is_empty() || !self.rigid.is_empty()
    }

    /// The report of the last penalty increment.
    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// The contact outputs of each penalty and kinematic pair after its last increment (empty
    /// before the first; penalty outputs only when requested). A balanced penalty pair gives
    /// two entries: its slave-on-master pass, then its master-on-slave pass.
    pub fn outputs(&self) -> Vec<(PairId, &PairOutput)> {
        let mut v: Vec<(PairId, &PairOutput)> =
            self.pairs.iter().map(|p| (p.id, &p.output)).collect();
        v.extend(self.kinematic.iter().map(|p| (p.id, &p.output)));
        v.sort_by_key(|(id, _)| id.0);
        v
    }

    /// What the last kinematic increment did.
    pub fn kinematic_report(&self) -> &KinematicReport {
        &self.kin_report
    }

    /// The contact outputs of each rigid pair after the last kinematic increment.
    pub fn rigid_outputs(&self) -> Vec<(RigidPairId, &PairOutput)> {
        self.rigid.iter().map(|p| (p.id, &p.output)).collect()
    }

    /// One kinematic increment (seed: "Kinematic contact algorithm"): `x` are the positions
    /// the host predicted for the end of the increment without contact and `v` the velocities
    /// that took it there (mid-increment, central differences); `bodies` the predicted states
    /// of the model's rigid bodies (index = [`BodyId`]). Every kinematic pair is searched at
    /// `x` and its penetrating slave nodes corrected (and the masters with them); `x`, `v` and
    /// `bodies` are corrected in place. Pairs are corrected in the order they were added.
    pub fn kinematic_step(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<&KinematicReport> {
        positive_dt(dt)?;
        for (what, a) in [
            ("positions (one per model node)", x.len()),
            ("velocities (one per model node)", v.len()),
        ] {
            if a != self.n_nodes {
                return Err(Error::LengthMismatch {
                    what,
                    expected: self.n_nodes,
                    got: a,
                });
            }
        }
        validate_positions(x, 0, 3)?;
        validate_velocities(v)?;
        if let Some(r) = self.rigid.iter().find(|r| r.body.0 >= bodies.len()) {
            return Err(Error::IndexOutOfRange {
                what: "rigid body states".into(),
                index: r.body.0 as u64,
                len: bodies.len(),
            });
        }
        for r in &self.rigid {
            let b = &bodies[r.body.0];
            let values = b
                .position
                .iter()
                .chain(&b.velocity)
                .chain(&b.angular_velocity)
                .chain(b.rotation.iter().flatten());
            if let Some(v) = values.copied().find(|v| !v.is_finite()) {
                return Err(Error::BadParameter {
                    name: "rigid body state",
                    value: format!("{v} in body {}", r.body.0),
                    expected: "finite position, rotation, velocity and angular velocity",
                });
            }
        }
        let ke = |v: &[[f64; 3]], masses: &[f64]| -> f64 {
            v.iter()
                .zip(masses)
                .map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
                .sum()
        };
        let before = ke(v, &self.masses) + bodies_kinetic_energy(&self.rigid, bodies);
        let mut report = KinematicReport::default();
        let masses = &self.masses;
        for kr in &mut self.kinematic {
            let result = kr.search.step(x)?;
            let mut fast = |search: &GlobalSearch, r: &SearchResult, v: &[[f64; 3]]| {
                let (count, top) = fast_slaves(kr.id, search, &r.raw, v, dt);
                report.fast_nodes += count;
                if let Some(t) = top.filter(|_| count > 0) {
                    if report
                        .fastest
                        .is_none_or(|f| t.distance / t.radius > f.distance / f.radius)
                    {
                        report.fastest = Some(t);
                    }
                }
            };
            fast(&kr.search, &result, v);
            let facets = facets_from(&result, &mut kr.behind.0);
            let back_facets = match &mut kr.back {
                Some((search, _, _)) => {
                    let r = search.step(x)?;
                    fast(search, &r, v);
                    Some(facets_from(&r, &mut kr.behind.1))
                }
                None => None,
            };
            let back = kr
                .back
                .as_ref()
                .zip(back_facets.as_ref())
                .map(|((search, surface, w), bf)| (bf, surface, *w, search.slaves()));
            let mut first: Option<Vec<SlaveCorrection>> = None;
            let mut normal_force: Vec<f64> = Vec::new();
            // hard contact is re-projected on the corrected geometry; a softened law is applied once
            let passes = if kr.law.is_some() || kr.anchored {
                1
            } else {
                PASSES
            };
            for _ in 0..passes {
                let mut dx = vec![[0.0; 3]; x.len()];
                let c = match &back {
                    None if kr.anchored => anchored_pass(
                        &kr.master,
                        masses,
                        &result,
                        &kr.areas,
                        kr.law.as_ref(),
                        dt,
                        &mut dx,
                    ),
                    None => meshed_pass(
                        &kr.master,
                        masses,
                        x,
                        &kr.slaves,
                        &facets,
                        &kr.areas,
                        kr.law.as_ref(),
                        dt,
                        &mut dx,
                    ),
                    Some((bf, surface, w, nodes)) => {
                        let mut dx_a = vec![[0.0; 3]; x.len()];
                        let c = meshed_pass(
                            &kr.master,
                            masses,
                            x,
                            &kr.slaves,
                            &facets,
                            &kr.areas,
                            kr.law.as_ref(),
                            dt,
                            &mut dx_a,
                        );
                        let mut dx_b = vec![[0.0; 3]; x.len()];
                        let areas_b: Vec<f64> =
                            nodes.iter().map(|&n| kr.master.tributary_area(n)).collect();
                        meshed_pass(
                            surface,
                            masses,
                            x,
                            nodes,
                            bf,
                            &areas_b,
                            kr.law.as_ref(),
                            dt,
                            &mut dx_b,
                        );
                        for i in 0..x.len() {
                            for a in 0..3 {
                                dx[i][a] = w * dx_a[i][a] + (1.0 - w) * dx_b[i][a];
                            }
                        }
                        c
                    }
                };
                for i in 0..x.len() {
                    for a in 0..3 {
                        x[i][a] += dx[i][a];
                        v[i][a] += dx[i][a] / dt;
                    }
                }
                // the normal force of every pass (the friction limit's)
                if normal_force.is_empty() {
                    normal_force = vec![0.0; c.len()];
                }
                for (f, ck) in normal_force.iter_mut().zip(&c) {
                    *f += ck.force.max(0.0);
                }
                first.get_or_insert(c);
            }
            let c = first.unwrap_or_default();
            let mut friction = None;
            if let (Some(mu), None, false) = (kr.friction, &back, kr.anchored) {
                let ft = friction_pass(
                    &kr.master,
                    masses,
                    x,
                    v,
                    &kr.slaves,
                    &facets,
                    &normal_force,
                    mu,
                    dt,
                );
                report.friction_force += ft
                    .force
                    .iter()
                    .map(|f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt())
                    .sum::<f64>();
                kr.dissipated += ft.dissipation;
                friction = Some(ft);
            }
            // what is left, measured on the corrected positions
            let left = if kr.anchored {
                // on the anchors' planes, moved with the corrected masters
                result
                    .contacts()
                    .zip(&kr.slaves)
                    .filter_map(|(cp, &s)| {
                        let cp = cp?;
                        let nodes = kr.master.facets[cp.facet as usize].nodes();
                        let mut x0 = [0.0; 3];
                        for (j, &n) in nodes.iter().enumerate() {
                            for a in 0..3 {
                                x0[a] += cp.weights[j] * x[n as usize][a];
                            }
                        }
                        Some(
                            -(0..3)
                                .map(|a| (x[s as usize][a] - x0[a]) * cp.normal[a])
                                .sum::<f64>(),
                        )
                    })
                    .fold(0.0f64, f64::max)
            } else {
                let mut probe = vec![[0.0; 3]; x.len()];
                let after = meshed_pass(
                    &kr.master, masses, x, &kr.slaves, &facets, &kr.areas, None, dt, &mut probe,
                );
                after.iter().map(|a| a.overclosure).fold(0.0f64, f64::max)
            };
            report.max_overclosure_after = report.max_overclosure_after.max(left);
            tally(&mut report, &c);
            fill_kinematic_output(&mut kr.output, &c, &kr.areas, Some(result));
            if let Some(ft) = &friction {
                add_kinematic_friction(&mut kr.output, ft, &kr.areas);
            }
            kr.output.frictional_dissipation = kr.dissipated;
        }
        for rr in &mut self.rigid {
            let body = &mut bodies[rr.body.0];
            let mut first: Option<Vec<SlaveCorrection>> = None;
            let passes = if rr.law.is_some() { 1 } else { PASSES };
            for _ in 0..passes {
                let c = rigid_pass(
                    &rr.spec.surface,
                    rr.spec.mass,
                    &rr.spec.inertia,
                    body,
                    masses,
                    x,
                    v,
                    &rr.slaves,
                    &rr.areas,
                    rr.law.as_ref(),
                    dt,
                )?;
                first.get_or_insert(c);
            }
            let c = first.unwrap_or_default();
            let mut xs = x.to_vec();
            let mut vs = v.to_vec();
            let mut probe = *body;
            let after = rigid_pass(
                &rr.spec.surface,
                rr.spec.mass,
                &rr.spec.inertia,
                &mut probe,
                masses,
                &mut xs,
                &mut vs,
                &rr.slaves,
                &rr.areas,
                None,
                dt,
            )?;
            let left = after.iter().map(|a| a.overclosure).fold(0.0f64, f64::max);
            report.max_overclosure_after = report.max_overclosure_after.max(left);
            tally(&mut report, &c);
            fill_kinematic_output(&mut rr.output, &c, &rr.areas, None);
        }
        report.kinetic_energy_change =
            ke(v, &self.masses) + bodies_kinetic_energy(&self.rigid, bodies) - before;
        // the corrections are abut's results: the input was finite
        for (what, values) in [("position", &*x), ("velocity", &*v)] {
            if let Some((node, value)) = first_non_finite(values) {
                return Err(Error::NonFiniteResult {
                    what: format!("kinematic contact's corrected {what}"),
                    node,
                    value,
                    cause: format!(
                        "the kinematic pass moved it from finite input (largest overclosure \
                         corrected this increment: {:e}; check the masses and the increment)",
                        report.max_overclosure
                    ),
                });
            }
        }
        self.kin_report = report;
        Ok(&self.kin_report)
    }

    /// Moves every initially overclosed slave node of every pair (penalty, kinematic, rigid)
    /// onto its master, strain-free, as Abaqus adjusts initial positions: call once with the
    /// initial positions (and the first increment, for the energy report). Velocities are
    /// untouched.
    pub fn adjust_initial_overclosure(
        &mut self,
        x: &mut [[f64; 3]],
        bodies: &[BodyState],
        dt: f64,
    ) -> Result<OverclosureReport> {
        positive_dt(dt)?;
        if x.len() != self.n_nodes {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.n_nodes,
                got: x.len(),
            });
        }
        validate_positions(x, 0, 3)?;
        let mut rep = OverclosureReport::default();
        let mut searches: Vec<&mut GlobalSearch> =
            self.pairs.iter_mut().map(|p| &mut p.search).collect();
        searches.extend(self.kinematic.iter_mut().map(|k| &mut k.search));
        let masses = &self.masses;
        let record = |rep: &mut OverclosureReport, node: u32, h: f64| {
            rep.moved.push((node, h));
            rep.max_distance = rep.max_distance.max(h);
            rep.energy_avoided += 0.5 * masses[node as usize] * (h / dt) * (h / dt);
        };
        for search in searches {
            let result = search.run(x)?;
            let master = search.master();
            for (&s, c) in result.slaves.iter().zip(result.contacts()) {
                let Some(c) = c else { continue };
                let nodes = master.facets[c.facet as usize].nodes();
                let xs: Vec<V3<f64>> = nodes
                    .iter()
                    .map(|&n| V3::from_array(x[n as usize]))
                    .collect();
                let p = V3::from_array(x[s as usize]);
                let pr = closest_on_facet(p, &xs);
                let gap = pr.gap(p);
                if gap < 0.0 {
                    let moved = p - pr.normal * gap;
                    x[s as usize] = moved.to_array();
                    record(&mut rep, s, -gap);
                }
            }
        }
        for rr in &self.rigid {
            let Some(b) = bodies.get(rr.body.0) else {
                return Err(Error::IndexOutOfRange {
                    what: "rigid body states".into(),
                    index: rr.body.0 as u64,
                    len: bodies.len(),
                });
            };
            let xb = V3::from_array(b.position);
            for &s in &rr.slaves {
                let p = V3::from_array(x[s as usize]);
                let local = crate::kinematic::to_body(&b.rotation, p - xb);
                let (gap, nb) = rr.spec.surface.gap(local);
                if gap < 0.0 {
                    let n = crate::kinematic::to_model(&b.rotation, nb);
                    x[s as usize] = (p - n * gap).to_array();
                    record(&mut rep, s, -gap);
                }
            }
        }
        Ok(rep)
    }
}

/// An error naming the first non-finite velocity.
fn validate_velocities(velocities: &[[f64; 3]]) -> Result<()> {
    validate_positions(velocities, 0, 3).map_err(|e| match e {
        Error::NonFiniteCoordinate { node, axis, value } => Error::BadParameter {
            name: "velocity",
            value: format!("{value} (node {node}, axis {axis})"),
            expected: "must be finite",
        },
        e => e,
    })
}

/// The first node with a non-finite component, and that component.
pub(crate) fn first_non_finite(values: &[[f64; 3]]) -> Option<(usize, f64)> {
    values
        .iter()
        .enumerate()
        .find_map(|(i, v)| v.iter().find(|c| !c.is_finite()).map(|&c| (i, c)))
}

/// Kinetic energy of the rigid bodies the rigid pairs act on (each counted once), translation
/// and rotation.
fn bodies_kinetic_energy(rigid: &[RigidRun], bodies: &[BodyState]) -> f64 {
    let mut seen = std::collections::BTreeSet::new();
    rigid
        .iter()
        .filter(|r| seen.insert(r.body.0))
        .map(|r| {
            let b = &bodies[r.body.0];
            let (m, i, rot, w) = (
                r.spec.mass,
                &r.spec.inertia,
                &b.rotation,
                b.angular_velocity,
            );
            // ω·(R I Rᵀ)ω = (Rᵀω)·I(Rᵀω)
            let wb: Vec<f64> = (0..3)
                .map(|a| (0..3).map(|k| rot[k][a] * w[k]).sum())
                .collect();
            let rot_ke: f64 = (0..3)
                .map(|a| (0..3).map(|c| wb[a] * i[a][c] * wb[c]).sum::<f64>())
                .sum();
            0.5 * m * b.velocity.iter().map(|c| c * c).sum::<f64>() + 0.5 * rot_ke
        })
        .sum()
}

fn slave_areas(
    model: &Model,
    set: crate::model::NodeSetId,
    master: &MasterSurface,
) -> Result<Vec<f64>> {
    Ok(match model.node_set_areas(set)? {
        Some(a) => a.to_vec(),
        None => vec![master.mean_facet_area(); model.node_set(set)?.len()],
    })
}

fn tally(report: &mut KinematicReport, c: &[SlaveCorrection]) {
    for s in c {
        if s.force > 0.0 {
            report.active += 1;
            report.total_force += s.force;
            report.max_overclosure = report.max_overclosure.max(s.overclosure);
        }
    }
}

/// Books a kinematic pair's friction in its outputs: CSHEAR1/2 (the friction force along the
/// contact's tangent directions over the tributary area), the slave's total force, CFS, and the
/// stick or slip state of each slave in contact.
fn add_kinematic_friction(o: &mut PairOutput, ft: &FrictionCorrection, areas: &[f64]) {
    for k in 0..o.force.len().min(ft.force.len()) {
        let f = ft.force[k];
        if o.cstatus[k] == Some(ContactStatus::Slip) && ft.stick[k] {
            o.cstatus[k] = Some(ContactStatus::Stick);
        }
        if f == [0.0; 3] {
            continue;
        }
        let (t1, t2) = crate::geometry::tangent_directions(V3::from_array(o.normal[k]));
        let f3 = V3::from_array(f);
        o.cshear1[k] = f3.dot(t1) / areas[k];
        o.cshear2[k] = f3.dot(t2) / areas[k];
        for a in 0..3 {
            o.force[k][a] += f[a];
            o.cfs[a] += f[a];
        }
    }
}

fn fill_kinematic_output(
    o: &mut PairOutput,
    c: &[SlaveCorrection],
    areas: &[f64],
    search: Option<SearchResult>,
) {
    o.cstatus = c
        .iter()
        .map(|s| {
            Some(if s.force > 0.0 {
                ContactStatus::Slip
            } else {
                ContactStatus::Open
            })
        })
        .collect();
    o.copen = c
        .iter()
        .map(|s| if s.force > 0.0 { -s.target } else { f64::NAN })
        .collect();
    let applied_normal =
        |s: &SlaveCorrection| (0..3).map(|a| s.applied[a] * s.normal[a]).sum::<f64>();
    o.cpress = c
        .iter()
        .zip(areas)
        .map(|(s, a)| applied_normal(s) / a)
        .collect();
    o.cshear1 = vec![0.0; c.len()];
    o.cshear2 = vec![0.0; c.len()];
    o.normal = c.iter().map(|s| s.normal).collect();
    o.force = c.iter().map(|s| s.applied).collect();
    o.cfn = [0.0; 3];
    for f in &o.force {
        for a in 0..3 {
            o.cfn[a] += f[a];
        }
    }
    o.cfs = [0.0; 3];
    o.contact_energy = c.iter().map(|s| s.energy).sum();
    o.frictional_dissipation = 0.0;
    o.search = search;
}

fn positive_dt(dt: f64) -> Result<()> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(Error::BadParameter {
            name: "dt",
            value: dt.to_string(),
            expected: "must be finite and positive",
        })
    }
}

fn fill_output(o: &mut PairOutput, outs: &[ContactOut], areas: &[f32], search: SearchResult) {
    let n = outs.len();
    o.cstatus.clear();
    o.copen.clear();
    o.cpress.clear();
    o.cshear1.clear();
    o.cshear2.clear();
    o.normal.clear();
    o.force.clear();
    o.cfn = [0.0; 3];
    o.cfs = [0.0; 3];
    o.contact_energy = 0.0;
    o.frictional_dissipation = 0.0;
    for (k, c) in outs.iter().enumerate().take(n) {
        let found = search.contact(k).is_some();
        o.cstatus
            .push(found.then_some(match c.status & CSTATUS_MASK {
                CSTATUS_STICK => ContactStatus::Stick,
                CSTATUS_SLIP => ContactStatus::Slip,
                s => {
                    debug_assert_eq!(s, CSTATUS_OPEN);
                    ContactStatus::Open
                }
            }));
        let area = areas[k] as f64;
        let nrm = [c.normal_gap[0], c.normal_gap[1], c.normal_gap[2]];
        let (t1, t2) = crate::geometry::tangents_f32(nrm);
        let ft = [
            c.tangential[0] as f64,
            c.tangential[1] as f64,
            c.tangential[2] as f64,
        ];
        o.copen.push(c.normal_gap[3] as f64);
        o.cpress.push(c.force[3] as f64 / area);
        o.cshear1
            .push((0..3).map(|a| ft[a] * t1[a] as f64).sum::<f64>() / area);
        o.cshear2
            .push((0..3).map(|a| ft[a] * t2[a] as f64).sum::<f64>() / area);
        o.normal.push(nrm.map(|x| x as f64));
        o.force
            .push([c.force[0] as f64, c.force[1] as f64, c.force[2] as f64]);
        for a in 0..3 {
            o.cfn[a] += c.force[3] as f64 * nrm[a] as f64;
            o.cfs[a] += ft[a];
        }
        o.contact_energy += c.tangential[3] as f64;
        o.frictional_dissipation += c.dissipation as f64;
    }
    o.search = Some(search);
}
