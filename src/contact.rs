//! The per-increment object a host program drives: search and enforcement of every pair.

use crate::abi::penalty::{
    ContactOut, SlaveState, CSTATUS_MASK, CSTATUS_OPEN, CSTATUS_SLIP, CSTATUS_STICK,
};
use crate::device::Device;
use crate::error::{Error, Result};
use crate::geometry::{closest_on_facet, V3};
use crate::kinematic::{
    anchored_pass, facets_from, friction_pass, meshed_pass, rigid_pass, BodyState,
    FrictionCorrection, SlaveCorrection, PASSES,
};
use crate::model::{validate_positions, Model, PairId};
use crate::model::{BodyId, Enforce, MasterSurface, PressureOverclosure, RigidBody, RigidPairId};
use crate::penalty::PenaltySetup;
use crate::search::{GlobalSearch, SearchResult, SearchStage};

#[cfg(feature = "mpi")]
mod anchors;
mod exec;
#[cfg(feature = "mpi")]
mod kinematic_share;
#[cfg(feature = "mpi")]
pub(crate) use kinematic_share::AnchorPlane;
mod kinematic_step;
mod overclosure;
mod rank_rows;
mod report;
mod resident;
mod restart;
mod rigid_parts;
#[cfg(feature = "mpi")]
pub(crate) use rank_rows::row_increment;
#[cfg(feature = "mpi")]
pub(crate) use rigid_parts::RigidPartRun;
mod slave_order;
mod warnings;
pub use report::{
    combined_increment, Anchoring, ContactStatus, FastNode, KinematicReport, OverclosureReport,
    PairOutput, StepReport,
};
pub use resident::ResidentIo;
use slave_order::SlaveMap;

/// One penalty pass of a pair (a balanced pair has two): its search's stage and its penalty
/// setup; their device work is the `Contact`'s executor's (pair run k is its pair k).
struct PairRun {
    id: PairId,
    search: SearchStage,
    setup: PenaltySetup,
    output: PairOutput,
    /// Host-array increments: what the host knows of the device's schedule.
    schedule: resident::HostSchedule,
    /// The pass's slave order against the node set's (the output's `slaves`).
    map: SlaveMap,
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
    /// Every penalty pass's device work: searches, penalty, statistics, abut's own arrays;
    /// chosen once, from the device, in `new`.
    exec: Box<dyn exec::IncrementExec>,
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
    /// The rigid parts' states given for the next host-array increments instead (a rank's
    /// local model holds part of a body: its state comes from the whole body).
    given_parts: Option<Vec<crate::penalty::RigidState>>,
    /// What a rank's local model reads back beside the forces ([`rank_rows::NodeRows`]).
    rows: rank_rows::NodeRows,
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
        let mut exec = exec::for_device(device, n_nodes);
        for k in 0..model.pairs().len() {
            let id = PairId(k);
            let pair = model.pair(id)?;
            let set = model.node_set(pair.slave)?.to_vec();
            // a penalty pass keeps its slaves in the pair's order; a kinematic pair, the set's
            let (slaves, map) = match pair.enforce {
                Enforce::Penalty(_) => {
                    SlaveMap::new(&set, pair.slave_order, model.positions(), model.dim())
                }
                Enforce::Kinematic(_) => (set.clone(), SlaveMap::default()),
            };
            let search = SearchStage::for_pair(model, id, slaves.clone())?;
            match &pair.enforce {
                Enforce::Penalty(_) => {
                    let set_index = map.set_indices(slaves.len());
                    let setup =
                        PenaltySetup::ordered(model, id, search.master(), &slaves, &set_index)?
                            .with_search(search.radius(), search.reference_node());
                    exec.add_pair(&setup)?;
                    let back = match pair.balanced {
                        // balanced: the master surface's nodes against the slave surface too
                        Some((surface, _)) => {
                            let slave_surface = model.surface(surface)?.clone();
                            let nodes = search.master().nodes();
                            let (rnodes, rmap) = SlaveMap::new(
                                &nodes,
                                pair.slave_order,
                                model.positions(),
                                model.dim(),
                            );
                            let rsearch = SearchStage::from_parts(
                                model,
                                slave_surface.clone(),
                                rnodes.clone(),
                                search.radius(),
                            )?;
                            let reverse = PenaltySetup::reverse(
                                model,
                                id,
                                search.master(),
                                &slave_surface,
                                &rnodes,
                            )?
                            .with_search(rsearch.radius(), rsearch.reference_node());
                            Some(PairRun {
                                id,
                                search: rsearch,
                                setup: reverse,
                                output: PairOutput {
                                    slaves: nodes,
                                    ..Default::default()
                                },
                                schedule: Default::default(),
                                map: rmap,
                            })
                        }
                        None => None,
                    };
                    pairs.push(PairRun {
                        id,
                        search,
                        setup,
                        output: PairOutput {
                            slaves: set,
                            ..Default::default()
                        },
                        schedule: Default::default(),
                        map,
                    });
                    if let Some(b) = back {
                        exec.add_pair(&b.setup)?;
                        pairs.push(b);
                    }
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
                        search: GlobalSearch::from_stage(device, search)?,
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
            exec,
            mode: None,
            global_total: 0,
            host_increments: 0,
            dim: model.dim(),
            parts: rigid_parts::RigidPartRun::all(model),
            given_parts: None,
            rows: rank_rows::NodeRows::default(),
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
        self.penalty_runs(pair)?
            .into_iter()
            .map(|k| Ok(self.pairs[k].map.to_caller(&self.exec.penalty_state(k)?)))
            .collect()
    }

    /// The runs (passes) of penalty pair `pair`, in order; errors when it has none.
    fn penalty_runs(&self, pair: PairId) -> Result<Vec<usize>> {
        let runs: Vec<usize> = (0..self.pairs.len())
            .filter(|&k| self.pairs[k].id == pair)
            .collect();
        if runs.is_empty() {
            return Err(Error::UnknownId {
                what: "penalty pair",
                id: pair.0,
            });
        }
        Ok(runs)
    }

    /// Replaces the per-slave state of penalty pair `pair` (as [`Contact::penalty_states`]
    /// gives it: one list per pass, each as long as that pass's slaves).
    pub fn set_penalty_states(&mut self, pair: PairId, states: &[Vec<SlaveState>]) -> Result<()> {
        let runs = self.penalty_runs(pair)?;
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
            let s = self.pairs[k].map.to_pass(s);
            self.exec.set_penalty_state(k, &s);
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
        if self.mode == Some(resident::Mode::Device) {
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
        // the unanchored nodes in the node set's order (a penalty pass's own may differ)
        let penalty = self
            .pairs
            .iter()
            .map(|p| (p.id, &p.search, Some((&p.map, &p.output.slaves))));
        let kinematic = self.kinematic.iter().flat_map(|k| {
            std::iter::once((k.id, &*k.search, None))
                .chain(k.back.iter().map(|b| (k.id, &*b.0, None)))
        });
        penalty
            .chain(kinematic)
            .filter(|(_, s, _)| s.anchors().is_some())
            .map(|(pair, s, map)| {
                let unanchored = match map {
                    Some((m, set)) => m.nodes_in_caller_order(s.unanchored(), set),
                    None => s.unanchored(),
                };
                Anchoring {
                    pair,
                    slaves: s.slaves().len(),
                    anchored: s.slaves().len() - unanchored.len(),
                    unanchored,
                }
            })
            .collect()
    }

    /// The slave nodes of each penalty pass of pair `pair` (two for a balanced pair) in the
    /// order the pass keeps them inside abut ([`crate::model::SlaveOrder`]); every result comes
    /// back in the node set's order whatever this is.
    pub fn pass_slaves(&self, pair: PairId) -> Result<Vec<Vec<u32>>> {
        Ok(self
            .penalty_runs(pair)?
            .into_iter()
            .map(|k| self.pairs[k].search.slaves().to_vec())
            .collect())
    }

    /// The global search's structure of each pass of pair `pair` (two for a balanced pair),
    /// `Auto` resolved ([`crate::model::SearchStructure`]).
    pub fn search_structures(&self, pair: PairId) -> Result<Vec<crate::model::SearchStructure>> {
        let mut out: Vec<_> = self
            .pairs
            .iter()
            .filter(|p| p.id == pair)
            .map(|p| p.search.search_structure())
            .collect();
        for k in self.kinematic.iter().filter(|k| k.id == pair) {
            out.push(k.search.search_structure());
            out.extend(k.back.iter().map(|b| b.0.search_structure()));
        }
        if out.is_empty() {
            return Err(Error::UnknownId {
                what: "meshed contact pair",
                id: pair.0,
            });
        }
        Ok(out)
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
