//! One distributed increment: ghosts' positions and velocities to their holders, each rank's
//! contact on its own device, the ghosts' forces back to their owners added in rank order, and the
//! agreement over ranks (faults, stable increment, counts).

use super::collectives::{agree_and_gather, agree_and_max, exchange_known};
use super::*;

impl DistributedContact {
    /// One increment: own nodes at `x` moving at `v` (in [`RankModel::ids`] order), increment
    /// `dt`. Collective: every rank calls it in the same increment with the same `dt`.
    pub fn step(&mut self, x: &[[f64; 3]], v: &[[f64; 3]], dt: f64) -> Result<&DistributedStep> {
        let issued_before = collectives_issued();
        let n_own = self.ids.len();
        // faults are agreed on, never returned by one rank alone (the others would wait in the
        // next exchange for ever)
        let mut fault = None;
        if x.len() != n_own || v.len() != n_own {
            fault = Some(Error::LengthMismatch {
                what: "positions and velocities of the owned nodes",
                expected: n_own,
                got: x.len().min(v.len()),
            });
        } else if let Some((node, axis, value)) = (0..n_own)
            .flat_map(|i| (0..3).map(move |a| (i, a)))
            .map(|(i, a)| {
                (
                    i,
                    a,
                    if x[i][a].is_finite() {
                        v[i][a]
                    } else {
                        x[i][a]
                    },
                )
            })
            .find(|t| !t.2.is_finite())
        {
            fault = Some(Error::NonFiniteCoordinate { node, axis, value });
        }
        // a distributed global search: first, at the interval, or when any node has used up
        // the motion budget (agreed: the largest motion over all ranks)
        let moved = if self.started {
            x.iter()
                .zip(&self.anchor)
                .map(|(p, q)| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt())
                .fold(0.0f64, f64::max)
        } else {
            0.0
        };
        // one collective: the faults, the largest motion, the smallest increment, and each
        // penalty pass's master box and whether a master node is far from its frame
        let mut values = vec![moved, -dt];
        values.extend(self.frame_records(x));
        let agreed = agree_and_max(&self.comm, fault, &values)?;
        let (moved, dt_min) = (agreed[0], -agreed[1]);
        self.move_frames(&agreed[2..]);
        let mut fault = None;
        if self.dt_ref.is_none() {
            // the automatic stiffness' reference: the first increment, on every rank
            self.dt_ref = Some(dt_min);
        }
        let interval = self
            .pairs
            .iter()
            .map(|p| p.interval)
            .min()
            .unwrap_or(u32::MAX);
        let global = !self.started || self.since_search >= interval || moved > self.budget();
        let mut bytes = 0;
        let mut ghost_ids = Vec::new();
        if global {
            let (ids, b) = self.choose_ghosts(x);
            ghost_ids = ids;
            bytes += b;
            self.since_search = 0;
            self.searches += 1;
        }
        self.since_search += 1;
        // the ghosts' state from their owners
        let (gx, gv) = self.ghost_state(x, v);
        bytes += 48 * self.send.iter().map(Vec::len).sum::<usize>();
        self.ghost_x.clone_from(&gx);
        if global {
            if self.started && ghost_ids == self.ghost_ids {
                // the same ghosts, so the same local model: the local contact goes on (its
                // search state, grid frame and friction untouched)
                self.anchor = x.to_vec();
            } else {
                if let Err(e) = self.build_local(x, &gx, &ghost_ids) {
                    self.contact = None;
                    fault = Some(e);
                }
                self.ghost_ids = ghost_ids;
                self.rebuilds += 1;
            }
            // the anchor of the motion budget: own positions now
            self.anchor.truncate(n_own);
            self.started = true;
        }
        let mut forces = vec![[0.0; 3]; n_own];
        let (mut stable, mut over, mut active) = (f64::INFINITY, 0.0f64, 0usize);
        let mut ghost_forces = vec![[0.0; 3]; gx.len()];
        // the fastest pair node here: (distance / radius, global id, pair, distance, radius)
        let mut fast = (0usize, [-1.0, 0.0, 0.0, 0.0, 0.0]);
        // the rows of the bound: the local model's largest, each own node's (its ghosts'
        // shares added below) and each rigid part's share here
        let n_local = n_own + gx.len();
        let (mut local_max, mut damping) = (0.0f32, 0.0f32);
        let mut rows = vec![0.0f32; n_local];
        let mut body_rows = vec![0.0f32; self.parts.len()];
        if !self.parts.take_moved() && fault.is_none() {
            fault = Some(bad(
                "rigid part positions",
                "not given for this increment".into(),
                "DistributedContact::move_rigid_parts before every step",
            ));
        }
        if let Some(c) = self.contact.as_mut() {
            // a fault here is agreed below, never returned alone
            let mut given = Ok(());
            for p in &self.pairs {
                if let (Some(id), Some((origin, span))) = (p.local, p.frame) {
                    given = given.and_then(|_| c.give_search_frame(id, origin, span));
                }
            }
            if !self.parts.local.is_empty() {
                given = given.and_then(|_| c.give_rigid_states(self.parts.local_states()));
            }
            let lx: Vec<[f64; 3]> = x.iter().chain(&gx).copied().collect();
            let lv: Vec<[f64; 3]> = v.iter().chain(&gv).copied().collect();
            match given.and_then(|_| c.penalty_step(&lx, &lv, dt)) {
                Err(e) => fault = Some(e),
                Ok(r) => {
                    forces.copy_from_slice(&r.forces[..n_own]);
                    ghost_forces.copy_from_slice(&r.forces[n_own..]);
                    stable = r.stable_dt;
                    over = r.max_overclosure;
                    active = r.active;
                    let (r, z) = c.node_rows();
                    if r.len() == n_local {
                        rows.copy_from_slice(r);
                        damping = z;
                        local_max = r.iter().fold(0.0, |m, &v| m.max(v));
                        // a body's row is on its lowest local node, which has none of its own
                        for &(k, rep) in &self.parts.local {
                            body_rows[k] = std::mem::take(&mut rows[rep as usize]);
                        }
                    }
                    let rep = c.report();
                    if let Some(f) = rep.fastest {
                        fast = (rep.fast_nodes, self.fast_global(&f).record());
                    }
                }
            }
            if fault.is_none() {
                // small sliding: the anchors the first increment found, kept by global ids
                fault = self.take_anchors().err();
            }
        }
        // ghosts' forces and rows back to their owners, added there in rank order
        let mut back: Vec<Vec<f64>> = Vec::with_capacity(self.recv.len());
        let mut at = n_own;
        for &count in &self.recv {
            back.push(
                (at..at + count)
                    .flat_map(|l| {
                        let f = ghost_forces[l - n_own];
                        [f[0], f[1], f[2], rows[l] as f64]
                    })
                    .collect(),
            );
            at += count;
        }
        bytes += 8 * back.iter().map(Vec::len).sum::<usize>();
        let counts: Vec<usize> = self.send.iter().map(|l| 4 * l.len()).collect();
        let came = exchange_known(&self.comm, &back, &counts);
        for (q, list) in self.send.iter().enumerate() {
            for (k, &i) in list.iter().enumerate() {
                for a in 0..3 {
                    forces[i][a] += came[q][4 * k + a];
                }
                rows[i] += came[q][4 * k + 3] as f32;
            }
        }
        let own_max = rows[..n_own].iter().fold(0.0f32, |m, &v| m.max(v));
        // one collective: the faults and each rank's stable increment, overclosure, counts,
        // fastest node and rows of the bound, folded in rank order (the same bits on every
        // rank)
        let [f0, f1, f2, f3, f4] = fast.1;
        let mut record = vec![
            stable,
            over,
            active as f64,
            fast.0 as f64,
            f0,
            f1,
            f2,
            f3,
            f4,
            local_max as f64,
            own_max as f64,
            damping as f64,
        ];
        record.extend(body_rows.iter().map(|&r| r as f64));
        let rows = agree_and_gather(&self.comm, fault, &record)?;
        let fastest = FastGlobalNode::fastest_of(&rows, 4);
        self.last = DistributedStep {
            forces,
            stable_dt: rows
                .iter()
                .map(|r| r[0])
                .fold(summed_rows_bound(&rows), f64::min),
            max_overclosure: rows.iter().map(|r| r[1]).fold(0.0, f64::max),
            active: rows.iter().map(|r| r[2] as usize).sum(),
            global_search: global,
            bytes_sent: bytes,
            ghosts: gx.len(),
            fast_nodes: rows.iter().map(|r| r[3] as usize).sum(),
            fastest,
            collectives: collectives_issued() - issued_before,
        };
        Ok(&self.last)
    }

    /// The ghosts' state (positions, velocities) from their owners, own nodes at `x`, `v`
    /// (one collective).
    pub(super) fn ghost_state(
        &self,
        x: &[[f64; 3]],
        v: &[[f64; 3]],
    ) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let out: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&i| [x[i][0], x[i][1], x[i][2], v[i][0], v[i][1], v[i][2]])
                    .collect()
            })
            .collect();
        let counts: Vec<usize> = self.recv.iter().map(|&c| 6 * c).collect();
        let sent = 48 * self.send.iter().map(Vec::len).sum::<usize>();
        self.kinematic_bytes.set(self.kinematic_bytes.get() + sent);
        let flat: Vec<f64> = exchange_known(&self.comm, &out, &counts)
            .into_iter()
            .flatten()
            .collect();
        let gx = flat.chunks_exact(6).map(|c| [c[0], c[1], c[2]]).collect();
        let gv = flat.chunks_exact(6).map(|c| [c[3], c[4], c[5]]).collect();
        (gx, gv)
    }

    /// The masses of the local model's nodes: own, then ghosts.
    pub(super) fn local_masses(&self) -> Vec<f64> {
        self.masses
            .iter()
            .chain(&self.ghost_masses)
            .copied()
            .collect()
    }

    /// Per penalty pass, what one process's search frame is decided from, for the agreement
    /// (each the largest over the ranks): the own master nodes' box at `x` (its lower corner
    /// negated) and whether one of them is farther from the frame than 16 times the extent it
    /// was chosen at (1) or not (0).
    fn frame_records(&self, x: &[[f64; 3]]) -> Vec<f64> {
        let mut out = Vec::new();
        for p in self.pairs.iter().filter(|p| p.kinematic.is_none()) {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &i in &p.own_masters {
                for a in 0..3 {
                    lo[a] = lo[a].min(x[i][a]);
                    hi[a] = hi[a].max(x[i][a]);
                }
            }
            let far = p.frame.is_some_and(|(o, span)| {
                p.own_masters
                    .iter()
                    .any(|&i| (0..3).any(|a| (x[i][a] - o[a]).abs() > 16.0 * span))
            });
            out.extend([
                -lo[0],
                -lo[1],
                -lo[2],
                hi[0],
                hi[1],
                hi[2],
                far as u8 as f64,
            ]);
        }
        out
    }

    /// Each penalty pass's frame from the agreed records ([`Self::frame_records`]): chosen
    /// from the whole master's box at the first increment, and moved when a master node is far
    /// from it — where and when one process's search chooses and moves its own
    /// (`crate::plan::frame::origin`, `SearchStage::rebase_if_far`), so every rank's local
    /// contact rounds in the single process's frame.
    fn move_frames(&mut self, records: &[f64]) {
        let dim = if self.two_d { 2 } else { 3 };
        let passes = self.pairs.iter_mut().filter(|p| p.kinematic.is_none());
        for (p, r) in passes.zip(records.chunks_exact(7)) {
            let (lo, hi) = ([-r[0], -r[1], -r[2]], [r[3], r[4], r[5]]);
            if p.frame.is_some() && r[6] == 0.0 {
                continue;
            }
            let Ok(origin) = crate::plan::frame::origin(lo, hi, p.radius, dim) else {
                continue;
            };
            if p.frame.is_some_and(|(o, _)| o == origin) {
                continue;
            }
            let span = (0..dim as usize).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
            let span = if span > 0.0 && span.is_finite() {
                span
            } else {
                p.radius
            };
            p.frame = Some((origin, span));
        }
    }
}

/// The stable increment of the node-wise bound on the rows summed over the ranks, from the
/// agreed records (from column 9: each rank's local model's largest row, its own nodes' largest
/// summed row, the damping ratio, then each rigid part's row there): infinite unless a sum
/// exceeds every row a local model saw — then a node held by several ranks, or a body, carries
/// a larger row than any one rank's bound counted, as one process's bound would.
fn summed_rows_bound(records: &[Vec<f64>]) -> f64 {
    let local = records.iter().map(|r| r[9] as f32).fold(0.0f32, f32::max);
    let mut summed = records.iter().map(|r| r[10] as f32).fold(0.0f32, f32::max);
    let damping = records.iter().map(|r| r[11] as f32).fold(0.0f32, f32::max);
    let parts = records.first().map_or(0, |r| r.len() - 12);
    for k in 0..parts {
        let body = records
            .iter()
            .map(|r| r[12 + k] as f32)
            .fold(0.0f32, |s, v| s + v);
        summed = summed.max(body);
    }
    if summed > local {
        crate::contact::row_increment(summed, damping)
    } else {
        f64::INFINITY
    }
}
