//! The per-increment object a host program drives: search and enforcement of every pair.

use crate::cpu::CpuPenalty;
use crate::device::{Device, DeviceKind};
use crate::error::{Error, Result};
use crate::gpu::GpuPenalty;
use crate::model::{validate_positions, Model, PairId};
use crate::penalty::layout::{ContactOut, CSTATUS_OPEN, CSTATUS_SLIP, CSTATUS_STICK, NO_LIMIT};
use crate::penalty::PenaltySetup;
use crate::search::layout::{STATUS_ACTIVE, STATUS_DT_APPROACH, STATUS_DT_STABLE, STATUS_SLIPPING};
use crate::search::{GlobalSearch, SearchResult};

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

/// What one increment of penalty contact gives the host.
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// Contact force on every model node (model force units), summed over the pairs.
    pub forces: Vec<[f64; 3]>,
    /// The largest increment the penalty springs allow (central differences; with the weights'
    /// share of the master masses and the damping), over contacts within the search radius;
    /// ∞ when there is none.
    pub stable_dt: f64,
    /// Half the smallest remaining gap over its closing speed: an increment beyond this could
    /// carry an approaching node through its master facet in one step; ∞ when none approaches.
    pub approach_dt: f64,
    /// Slave nodes in contact.
    pub active: usize,
    /// Of which slipping.
    pub slipping: usize,
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
}

/// Search and penalty enforcement of every pair of a model, once per increment.
pub struct Contact {
    pairs: Vec<PairRun>,
    dim: u32,
    n_nodes: usize,
    dt_ref: Option<f64>,
    want_outputs: bool,
    report: StepReport,
}

impl Contact {
    /// Builds the passes every pair of `model` needs on `device` (pipelines compiled, buffers
    /// made; a frictionless pair compiles no friction work).
    pub fn new(device: &Device, model: &Model) -> Result<Self> {
        if model.pairs().is_empty() {
            return Err(Error::Empty {
                what: "the model's contact pairs".into(),
            });
        }
        let n_nodes = model.positions().len();
        let mut pairs = Vec::new();
        for k in 0..model.pairs().len() {
            let id = PairId(k);
            let search = GlobalSearch::new(device, model, id)?;
            let slaves = model.node_set(model.pair(id)?.slave)?.to_vec();
            let setup = PenaltySetup::new(model, id, search.master(), &slaves)?;
            let exec = match device.kind() {
                DeviceKind::Gpu(ctx) => {
                    PenaltyExec::Gpu(Box::new(GpuPenalty::new(ctx.clone(), &setup, n_nodes)?))
                }
                DeviceKind::Cpu => PenaltyExec::Cpu(CpuPenalty::new(&setup, n_nodes)),
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
            });
        }
        Ok(Self {
            pairs,
            dim: model.dim(),
            n_nodes,
            dt_ref: None,
            want_outputs: false,
            report: StepReport::default(),
        })
    }

    /// Asks for the contact output variables ([`Contact::outputs`]) to be computed and read
    /// back every increment (off by default: then only forces and increments come back).
    pub fn request_outputs(&mut self, yes: bool) {
        self.want_outputs = yes;
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
        if velocities.len() != self.n_nodes {
            return Err(Error::LengthMismatch {
                what: "velocities (one per model node)",
                expected: self.n_nodes,
                got: velocities.len(),
            });
        }
        validate_positions(velocities, 0, 3).map_err(|e| match e {
            Error::NonFiniteCoordinate { node, axis, value } => Error::BadParameter {
                name: "velocity",
                value: format!("{value} (node {node}, axis {axis})"),
                expected: "must be finite",
            },
            e => e,
        })?;
        let _ = self.dim;
        let dt_ref = *self.dt_ref.get_or_insert(dt);
        let vel: Vec<[f32; 4]> = velocities
            .iter()
            .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0])
            .collect();
        let mut report = StepReport {
            forces: vec![[0.0; 3]; self.n_nodes],
            stable_dt: f64::INFINITY,
            approach_dt: f64::INFINITY,
            active: 0,
            slipping: 0,
        };
        for pr in &mut self.pairs {
            let pp = pr.setup.params(dt, dt_ref);
            let (result, status) = pr.search.run_with_penalty(
                positions,
                &mut pr.exec,
                &pr.setup,
                &pp,
                &vel,
                self.want_outputs,
            )?;
            let forces: &[[f32; 4]] = match &pr.exec {
                PenaltyExec::Gpu(g) => &g.forces_out,
                PenaltyExec::Cpu(c) => &c.forces,
            };
            for (pn, f) in pr.setup.pair_nodes.iter().zip(forces) {
                let r = &mut report.forces[pn.node as usize];
                for a in 0..3 {
                    r[a] += f[a] as f64;
                }
            }
            let limit = |bits: u32| {
                let v = f32::from_bits(bits);
                if v >= NO_LIMIT {
                    f64::INFINITY
                } else {
                    v as f64
                }
            };
            report.stable_dt = report.stable_dt.min(limit(status[STATUS_DT_STABLE]));
            report.approach_dt = report.approach_dt.min(limit(status[STATUS_DT_APPROACH]));
            report.active += status[STATUS_ACTIVE] as usize;
            report.slipping += status[STATUS_SLIPPING] as usize;
            if self.want_outputs {
                let outs: &[ContactOut] = match &pr.exec {
                    PenaltyExec::Gpu(g) => &g.outputs,
                    PenaltyExec::Cpu(c) => &c.out,
                };
                fill_output(&mut pr.output, outs, &pr.setup.areas, result);
            }
        }
        self.report = report;
        Ok(&self.report)
    }

    /// The contact outputs of each pair after the last increment (empty before the first, or
    /// when not requested).
    pub fn outputs(&self) -> Vec<(PairId, &PairOutput)> {
        self.pairs.iter().map(|p| (p.id, &p.output)).collect()
    }

    /// The report of the last increment.
    pub fn report(&self) -> &StepReport {
        &self.report
    }
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
        let found = search.contacts.get(k).is_some_and(|h| h.is_some());
        o.cstatus.push(found.then_some(match c.status {
            CSTATUS_STICK => ContactStatus::Stick,
            CSTATUS_SLIP => ContactStatus::Slip,
            s => {
                debug_assert_eq!(s, CSTATUS_OPEN);
                ContactStatus::Open
            }
        }));
        let area = areas[k] as f64;
        let nrm = [c.normal_gap[0], c.normal_gap[1], c.normal_gap[2]];
        let (t1, t2) = crate::cpu::penalty::tangents(nrm);
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
