//! This rank of N in the one increment loop (`scene::increments`): its share of the solver,
//! the distributed contact on its own nodes, the halo from the owners after every increment,
//! and the increment's totals summed over the ranks in rank order.

use std::io::Write as _;

use mpi::topology::SimpleCommunicator;

use super::sum_over_ranks;
use crate::distributed::{
    agree, all_gather, all_max, exchange_known, DistributedContact, DistributedRigid,
    FastGlobalNode,
};
use crate::error::{Error, Result};
use crate::explicit::{KinematicCorrector, ResultantRow, Solver};
use crate::kinematic::BodyState;
use crate::scene::account::Account;
use crate::scene::increments::{Limits, Ranks, Sums};
use crate::scene::output_error;
use crate::scene::run::{body_displacements, push_body_columns};

/// Each part's own nodes (local indices), its whole mass and its node count.
pub(super) type PartNodes = [(Vec<usize>, f64, usize)];

/// Σ w·(x − x0) and Σ w·v over each part's own nodes, w its share of the part's mass: this
/// rank's share of the parts' mean motion.
pub(super) fn part_sums(part_nodes: &PartNodes, solver: &Solver, x0: &[[f64; 3]]) -> Vec<f64> {
    let mut out = Vec::with_capacity(6 * part_nodes.len());
    for (mine, total, count) in part_nodes {
        let (mut u, mut v) = ([0.0; 3], [0.0; 3]);
        for &l in mine {
            let w = if *total > 0.0 {
                solver.mass[l] / total
            } else {
                1.0 / (*count).max(1) as f64
            };
            for a in 0..3 {
                u[a] += w * (solver.x[l][a] - x0[l][a]);
                v[a] += w * solver.v[l][a];
            }
        }
        out.extend(u);
        out.extend(v);
    }
    out
}

/// This rank of N: its share of the solver, the distributed contact on its own nodes, the halo
/// from the owners after every increment, and totals summed over the ranks in rank order.
pub(super) struct Rank<'a> {
    pub(super) comm: &'a SimpleCommunicator,
    pub(super) solver: Solver,
    pub(super) contact: Option<DistributedContact>,
    /// Kinematic contact against analytical surfaces (every rank has it, or none).
    pub(super) rigid: Option<DistributedRigid>,
    /// Own nodes (local indices).
    pub(super) own: &'a [usize],
    /// The own nodes (local indices) each rank holds as halo.
    pub(super) send: &'a [Vec<usize>],
    /// The halo nodes (local indices), in the order their owners send them.
    pub(super) halo_in: &'a [usize],
    /// How many of them each rank owns (sends here), in rank order.
    pub(super) halo_counts: &'a [usize],
    /// The slave nodes this rank owns (local indices).
    pub(super) own_slaves: &'a [usize],
    pub(super) part_nodes: &'a PartNodes,
    pub(super) x0: &'a [[f64; 3]],
    /// The rigid bodies' names and indices, as the history lists them.
    pub(super) bodies: &'a [(String, usize)],
    /// Per rigid body, each of this rank's nodes' place in the whole body's node list.
    pub(super) body_keys: &'a [Vec<u32>],
    /// The bodies' reference points at the start.
    pub(super) bodies0: &'a [[f64; 3]],
    /// Per rigid part of the contact model (a free body of mesh nodes): its body's index and
    /// the whole body's node offsets (every rank places all of its nodes).
    pub(super) rigid_parts: &'a [(usize, Vec<[f64; 3]>)],
    /// The bodies' reference points when the contact force peaked.
    pub(super) at_peak: Vec<[f64; 3]>,
    /// Rank 0's history file.
    pub(super) history: Option<std::io::BufWriter<std::fs::File>>,
    pub(super) halo_bytes: usize,
    pub(super) contact_bytes: usize,
    /// The energy balance at the first increment.
    pub(super) balance0: Option<f64>,
    /// The least energy the balance error is measured against: the whole model's
    /// `Solver::energy_floor` (every rank builds it), as in one process.
    pub(super) floor: f64,
    /// Kinetic, internal, external, contact and damping energies, summed over the ranks.
    pub(super) energy: [f64; 5],
    /// The last increment's sums over the ranks (force, energies, the parts' motion on rows).
    pub(super) last: Vec<f64>,
}

impl Ranks for Rank<'_> {
    fn time(&self) -> f64 {
        self.solver.time
    }

    fn advance(&mut self, step: f64, k: usize, last: bool) -> Result<Limits> {
        let t_start = self.solver.time;
        let solver = &mut self.solver;
        let mut f = vec![[0.0; 3]; solver.x.len()];
        let mut limits = Limits::default();
        if let Some(c) = self.contact.as_mut() {
            c.request_outputs(last);
            if !self.rigid_parts.is_empty() {
                let at: Vec<Vec<[f64; 3]>> = self
                    .rigid_parts
                    .iter()
                    .map(|(b, offsets)| solver.bodies[*b].positions_of(offsets))
                    .collect();
                c.move_rigid_parts(&at)?;
            }
            let ox: Vec<[f64; 3]> = self.own.iter().map(|&l| solver.x[l]).collect();
            let ov: Vec<[f64; 3]> = self.own.iter().map(|&l| solver.v[l]).collect();
            let r = c.step(&ox, &ov, step)?;
            for (j, &l) in self.own.iter().enumerate() {
                f[l] = r.forces[j];
            }
            limits.penalty = Some((r.stable_dt, r.max_overclosure));
            self.contact_bytes += r.bytes_sent;
            // the same on every rank: every rank returns it
            if let Some(f) = r.fastest {
                return Err(tunnelling(&f, r.fast_nodes, k, t_start));
            }
        }
        // kinematic contact, or a free body of mesh nodes whose resultants every rank sums
        let kinematic = self.rigid.is_some()
            || self
                .contact
                .as_ref()
                .is_some_and(|c| c.has_kinematic_pairs())
            || solver.bodies.iter().any(|b| b.free_meshed());
        let mut fastest = None;
        let stepped = if kinematic {
            let mut corrector = RankCorrector {
                comm: self.comm,
                body_keys: self.body_keys,
                contact: self.contact.as_mut(),
                rigid: self.rigid.as_mut(),
                own: self.own,
                deepest: 0.0,
                fast: (0, None),
                bytes: 0,
            };
            let stepped = solver.step_with_forces_and(step, &f, &mut corrector);
            limits.kinematic = Some(corrector.deepest);
            self.contact_bytes += corrector.bytes;
            fastest = corrector.fast.1.map(|f| (f, corrector.fast.0));
            stepped
        } else {
            solver.step_with_forces(step, &f)
        };
        agree(self.comm, stepped.err())?;
        // a kinematic pair's slave past its search radius: the same on every rank
        if let Some((f, count)) = fastest {
            return Err(tunnelling(&f, count, k, t_start));
        }
        // the halo from the owners
        let out: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&i| {
                        let (x, v) = (solver.x[i], solver.v[i]);
                        [x[0], x[1], x[2], v[0], v[1], v[2]]
                    })
                    .collect()
            })
            .collect();
        self.halo_bytes += 8 * out.iter().map(Vec::len).sum::<usize>();
        let counts: Vec<usize> = self.halo_counts.iter().map(|&c| 6 * c).collect();
        let came: Vec<f64> = exchange_known(self.comm, &out, &counts)
            .into_iter()
            .flatten()
            .collect();
        for (&l, s) in self.halo_in.iter().zip(came.chunks_exact(6)) {
            solver.x[l] = [s[0], s[1], s[2]];
            solver.v[l] = [s[3], s[4], s[5]];
        }
        Ok(limits)
    }

    fn counted(&mut self, account: &mut Account<'_>) {
        if account.k == 1 {
            account.first_seconds = all_max(self.comm, account.first_seconds);
        }
    }

    fn sums(&mut self, row: bool) -> Result<Sums> {
        // the ranks' shares, added in rank order: contact force on the slaves, energies, and
        // the parts' motion on output rows
        let solver = &self.solver;
        let e = &solver.energy;
        let mut mine = vec![0.0; 3];
        for &l in self.own_slaves {
            for a in 0..3 {
                mine[a] += solver.contact_force[l][a];
            }
        }
        mine.extend([
            e.kinetic,
            e.internal,
            e.external_work,
            e.contact_work,
            e.damping,
        ]);
        if row {
            mine.extend(part_sums(self.part_nodes, solver, self.x0));
        }
        self.last = sum_over_ranks(self.comm, &mine);
        self.energy.copy_from_slice(&self.last[3..8]);
        let [kinetic, internal, external, contact_work, damping] = self.energy;
        let balance = kinetic + internal - external - contact_work + damping;
        let b0 = *self.balance0.get_or_insert(balance);
        Ok(Sums {
            force: [self.last[0], self.last[1], self.last[2]],
            drift: (balance - b0).abs(),
            scale: (self.energy.iter())
                .fold(0.0f64, |m, x| m.max(x.abs()))
                .max(self.floor),
            balance,
            // the bodies' displacements on rows: the same on every rank
            moved: if row {
                body_displacements(solver, self.bodies0)
            } else {
                Vec::new()
            },
            kinetic_internal: [kinetic, internal],
        })
    }

    fn output(&mut self, _k: usize, row: bool, force: f64, peak: bool) -> Result<()> {
        if peak {
            self.at_peak = self
                .solver
                .bodies
                .iter()
                .map(|b| b.state.position)
                .collect();
        }
        if !row {
            return Ok(());
        }
        let [kinetic, internal, external, contact_work, damping] = self.energy;
        let balance = kinetic + internal - external - contact_work + damping;
        let drift = (balance - self.balance0.unwrap_or(balance)).abs();
        let scale = (self.energy.iter())
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(self.floor);
        // rank 0 writes; a failure there is agreed, so no rank is left waiting
        let mut fault = None;
        if let Some(f) = self.history.as_mut() {
            let mut line = format!(
                "{},{kinetic},{internal},{external},{contact_work},{},{force}",
                self.solver.time,
                drift / scale.max(1e-300)
            );
            for c in &self.last[8..] {
                line.push_str(&format!(",{c}"));
            }
            // the bodies: the same state on every rank
            push_body_columns(&mut line, &self.solver, self.bodies, self.bodies0);
            if let Err(e) = writeln!(f, "{line}") {
                fault = Some(output_error(e));
            }
        }
        agree(self.comm, fault)
    }
}

/// The single process's error for `count` nodes past their search radius in increment `k`
/// (from 0) starting at `t_start`, the fastest `f`.
fn tunnelling(f: &FastGlobalNode, count: usize, k: usize, t_start: f64) -> Error {
    Error::Tunnelling {
        increment: k as u64 + 1,
        time: t_start,
        node: f.node as usize,
        pair: f.pair,
        distance: f.distance,
        radius: f.radius,
        more: if count > 1 {
            format!(" ({} more nodes move that far)", count - 1)
        } else {
            String::new()
        },
    }
}

/// A rank's kinematic contact as the solver's corrector: the meshed kinematic pairs of its
/// distributed contact (its own nodes), then the pairs against analytical surfaces, in the
/// order one process corrects them.
struct RankCorrector<'a> {
    comm: &'a SimpleCommunicator,
    /// Per rigid body, each of this rank's nodes' place in the whole body's node list.
    body_keys: &'a [Vec<u32>],
    contact: Option<&'a mut DistributedContact>,
    rigid: Option<&'a mut DistributedRigid>,
    /// Own nodes (local indices), in the distributed contact's order.
    own: &'a [usize],
    /// The largest overclosure corrected, over every rank.
    deepest: f64,
    /// Kinematic slaves past their search radius, and the fastest (every rank's).
    fast: (usize, Option<FastGlobalNode>),
    /// Bytes the correction sent to other ranks.
    bytes: usize,
}

impl KinematicCorrector for RankCorrector<'_> {
    /// Every rank's rows, each body's in its nodes' order (one collective pair: the counts and
    /// the rows).
    fn share_body_rows(
        &mut self,
        rows: Vec<(usize, Vec<ResultantRow>)>,
    ) -> Result<Vec<Vec<ResultantRow>>> {
        // each row keyed by its node's place in the whole body
        let keys = self.body_keys;
        let flat: Vec<f64> = rows
            .iter()
            .enumerate()
            .flat_map(|(i, (body, list))| {
                list.iter().flat_map(move |(j, f, m)| {
                    let key = keys[*body][*j as usize];
                    [i as f64, key as f64, f[0], f[1], f[2], m[0], m[1], m[2]]
                })
            })
            .collect();
        let (all, _) = all_gather(self.comm, &flat);
        let mut out = vec![Vec::new(); rows.len()];
        for r in all.chunks_exact(8) {
            out[r[0] as usize].push((r[1] as u32, [r[2], r[3], r[4]], [r[5], r[6], r[7]]));
        }
        for list in &mut out {
            list.sort_by_key(|row| row.0);
        }
        Ok(out)
    }

    fn has_kinematic_pairs(&self) -> bool {
        self.rigid.is_some()
            || self
                .contact
                .as_ref()
                .is_some_and(|c| c.has_kinematic_pairs())
    }

    fn agree(&mut self, fault: Option<Error>) -> Result<()> {
        match (&self.contact, &mut self.rigid) {
            (Some(c), _) => c.agree(fault),
            (None, Some(r)) => r.agree(fault),
            (None, None) => fault.map_or(Ok(()), Err),
        }
    }

    fn correct(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<f64> {
        let mut deepest = 0.0f64;
        if let Some(c) = self.contact.as_mut().filter(|c| c.has_kinematic_pairs()) {
            let mut ox: Vec<[f64; 3]> = self.own.iter().map(|&l| x[l]).collect();
            let mut ov: Vec<[f64; 3]> = self.own.iter().map(|&l| v[l]).collect();
            let r = c.kinematic_step(&mut ox, &mut ov, dt)?;
            for (j, &l) in self.own.iter().enumerate() {
                (x[l], v[l]) = (ox[j], ov[j]);
            }
            deepest = r.max_overclosure;
            self.fast = (r.fast_nodes, r.fastest);
            self.bytes += r.bytes_sent;
        }
        if let Some(r) = self.rigid.as_mut() {
            deepest = deepest.max(r.correct(x, v, bodies, dt)?);
            self.bytes += r.bytes_sent();
        }
        self.deepest = deepest;
        Ok(deepest)
    }
}
