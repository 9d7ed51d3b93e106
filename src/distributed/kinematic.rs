//! Kinematic pairs across ranks: the seed's predictor/corrector with the master nodes'
//! corrections summed on their owners.
//!
//! Each rank searches its own slaves against its local model at the predicted positions (the
//! ghosts' predicted state from their owners), and computes each pushed slave's resisting force
//! and the shares of it its facet's nodes take. Those shares go to the nodes' owners, which add
//! them in the pair's slave order — the single process's order, so the sums are its bits — and
//! send each sum back to every rank holding the node as a ghost; every holder then has the
//! node's acceleration correction, and each rank corrects its own slaves onto the corrected
//! master and its own master nodes. A softened law's transmitted shares (the masses the pushed
//! slaves add to each master node) and Coulomb friction's velocity changes are summed the same
//! way. Hard contact repeats the correction on the corrected geometry (`PASSES` times), each pass
//! with the ghosts' corrected state from their owners.

use super::collectives::{agree_and_gather, exchange, exchange_known};
use super::*;
use crate::geometry::{closest_on_facet, V3};
use crate::kinematic::{
    change_velocity, correct_touches, slave_friction, NodeSums, SlaveCorrection, Touch, PASSES,
};
use crate::model::Kinematic;
use crate::model::PressureOverclosure;

/// What a rank's kinematic correction of one increment left, the same on every rank where it
/// says so.
#[derive(Clone, Debug, Default)]
pub struct KinematicStep {
    /// The largest overclosure corrected, over every rank (model length units).
    pub max_overclosure: f64,
    /// Slaves of kinematic pairs that moved farther than their pair's search radius relative
    /// to the master near them (all ranks).
    pub fast_nodes: usize,
    /// The fastest of them, by global id (the same on every rank).
    pub fastest: Option<FastGlobalNode>,
    /// Bytes this rank sent to other ranks in the correction (the ghosts' state, the master
    /// nodes' shares and their sums back).
    pub bytes_sent: usize,
}

/// A slave's contact in a kinematic pass: its local node, its key and its facet's local nodes
/// (`u32::MAX` pads); none where it has none.
type Contact1 = Option<(usize, u64, [u32; 4])>;

/// Small sliding: an anchored slave's plane as the search gave it.
type Plane = crate::contact::AnchorPlane;

/// The pushed-or-not geometry of each slave with a contact: on its facet at the local
/// positions `lx`, or its anchor's plane (`planes`, small sliding).
fn touches(lx: &[[f64; 3]], contacts: &[Contact1], planes: Option<&[Plane]>) -> Vec<Touch> {
    let mut out = Vec::new();
    for (s, c) in contacts.iter().enumerate() {
        let Some((node, key, nodes)) = *c else {
            continue;
        };
        let count = facet_node_count(&nodes, u32::MAX);
        let (normal, weights, overclosure) = match planes {
            Some(planes) => {
                let Some((normal, weights, overclosure)) = planes[s] else {
                    continue;
                };
                (V3::from_array(normal), weights, overclosure)
            }
            None => {
                let xs: Vec<V3<f64>> = nodes[..count]
                    .iter()
                    .map(|&n| V3::from_array(lx[n as usize]))
                    .collect();
                let p = V3::from_array(lx[node]);
                let pr = closest_on_facet(p, &xs);
                (pr.normal, pr.weights, -pr.gap(p))
            }
        };
        out.push(Touch {
            key,
            slave: s,
            node,
            nodes,
            count,
            normal,
            weights,
            overclosure,
        });
    }
    out
}

impl DistributedContact {
    /// Whether any pair is kinematic (the same on every rank).
    pub fn has_kinematic_pairs(&self) -> bool {
        self.pairs.iter().any(|p| p.kinematic.is_some())
    }

    /// Whether every rank got on (one collective; see the module's agreement on faults).
    pub fn agree(&self, fault: Option<Error>) -> Result<()> {
        agree(&self.comm, fault)
    }

    /// The kinematic pairs' correction of one increment (collective): `x` the positions this
    /// rank predicted for its own nodes at the end of the increment `dt` without contact, `v`
    /// the velocities that took them there ([`RankModel::ids`] order), both corrected in place
    /// as one process corrects them. Call after [`Self::step`] of the same increment.
    pub fn kinematic_step(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        dt: f64,
    ) -> Result<KinematicStep> {
        let mut deepest = 0.0f64;
        let mut fault = None;
        let mut fast = (0usize, [-1.0, 0.0, 0.0, 0.0, 0.0]);
        self.kinematic_bytes.set(0);
        for k in 0..self.pairs.len() {
            let p = &self.pairs[k];
            let (Some(law), false) = (p.kinematic.clone(), p.of.1) else {
                continue;
            };
            // a balanced pair: its second pass (the master's nodes on the slave surface) is
            // the next, weighted 1 − w
            let partner = self
                .pairs
                .get(k + 1)
                .filter(|q| q.of == (p.of.0, true))
                .map(|_| (k + 1, p.weight));
            match self.kinematic_pair(k, partner, &law, x, v, dt, &mut fast) {
                Ok(h) => deepest = deepest.max(h),
                Err(e) => fault = fault.or(Some(e)),
            }
        }
        let [f0, f1, f2, f3, f4] = fast.1;
        let record = [deepest, fast.0 as f64, f0, f1, f2, f3, f4];
        let rows = agree_and_gather(&self.comm, fault, &record)?;
        let fastest = FastGlobalNode::fastest_of(&rows, 2);
        Ok(KinematicStep {
            max_overclosure: rows.iter().map(|r| r[0]).fold(0.0, f64::max),
            fast_nodes: rows.iter().map(|r| r[1] as usize).sum(),
            fastest,
            bytes_sent: self.kinematic_bytes.get(),
        })
    }

    /// Sums over the ranks of per-node contributions (`(local node, key, values)`), each
    /// node's on its owner in key order, starting from zero: every own node's sum, and every
    /// ghost's from its owner; `None` where no rank contributed (three collectives).
    fn node_sums<const K: usize>(
        &self,
        contributions: Vec<(usize, u64, [f64; K])>,
    ) -> Vec<Option<[f64; K]>> {
        let (n_own, size) = (self.ids.len(), self.comm.size() as usize);
        let me = self.comm.rank() as usize;
        // the owner of each ghost: ghosts are numbered by source rank
        let mut owner_of = Vec::with_capacity(self.ghost_ids.len());
        for (r, &c) in self.recv.iter().enumerate() {
            owner_of.extend(std::iter::repeat_n(r, c));
        }
        let mut out: Vec<Vec<f64>> = vec![Vec::new(); size];
        let mut rows: Vec<(usize, u64, [f64; K])> = Vec::new();
        for (l, key, values) in contributions {
            if l < n_own {
                rows.push((l, key, values));
            } else {
                let o = owner_of[l - n_own];
                debug_assert_ne!(o, me);
                // ids and keys travel as their bits (any u64, exactly)
                out[o].push(f64::from_bits(self.ghost_ids[l - n_own]));
                out[o].push(f64::from_bits(key));
                out[o].extend(values);
            }
        }
        let sent = |lists: &[Vec<f64>]| 8 * lists.iter().map(Vec::len).sum::<usize>();
        self.kinematic_bytes
            .set(self.kinematic_bytes.get() + sent(&out));
        for list in exchange(&self.comm, &out) {
            for r in list.chunks_exact(K + 2) {
                // a ghost's owner: the node is this rank's
                let Some(&l) = self.index.get(&r[0].to_bits()) else {
                    continue;
                };
                let mut values = [0.0; K];
                values.copy_from_slice(&r[2..]);
                rows.push((l, r[1].to_bits(), values));
            }
        }
        rows.sort_by_key(|r| (r.0, r.1));
        let mut sums: Vec<Option<[f64; K]>> = vec![None; n_own + self.ghost_ids.len()];
        for (l, _, values) in rows {
            let s = sums[l].get_or_insert([0.0; K]);
            for (a, b) in s.iter_mut().zip(values) {
                *a += b;
            }
        }
        // each sum to the ranks holding the node as a ghost: a flag, then the values
        let back: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&i| match sums[i] {
                        Some(s) => std::iter::once(1.0).chain(s),
                        None => std::iter::once(0.0).chain([0.0; K]),
                    })
                    .collect()
            })
            .collect();
        let counts: Vec<usize> = self.recv.iter().map(|&c| (K + 1) * c).collect();
        self.kinematic_bytes
            .set(self.kinematic_bytes.get() + sent(&back));
        let came: Vec<f64> = exchange_known(&self.comm, &back, &counts)
            .into_iter()
            .flatten()
            .collect();
        for (g, r) in came.chunks_exact(K + 1).enumerate() {
            if r[0] != 0.0 {
                let mut values = [0.0; K];
                values.copy_from_slice(&r[1..]);
                sums[n_own + g] = Some(values);
            }
        }
        sums
    }

    /// This rank's contacts of kinematic pass `k` at the predicted positions (own `x`, `v`;
    /// ghosts `gx`, `gv`): per slave its local node, key and facet (none: no contact), and the
    /// slaves' areas. A search fault goes to `fault`, agreed on at the end: the exchanges go
    /// on without this pass's slaves.
    #[allow(clippy::too_many_arguments)]
    fn pass_contacts(
        &mut self,
        k: usize,
        (x, gx): (&[[f64; 3]], &[[f64; 3]]),
        (v, gv): (&[[f64; 3]], &[[f64; 3]]),
        dt: f64,
        fast: &mut (usize, [f64; 5]),
        fault: &mut Option<Error>,
    ) -> (Vec<Contact1>, Vec<f64>, Option<Vec<Plane>>) {
        let p = &self.pairs[k];
        let (id, n, keys) = (p.local, p.slaves.len(), p.keys.clone());
        let mut contacts: Vec<Contact1> = vec![None; n];
        let mut areas = vec![0.0; n];
        let mut planes = None;
        let (Some(c), Some(id)) = (self.contact.as_mut(), id) else {
            return (contacts, areas, planes);
        };
        let lx: Vec<[f64; 3]> = x.iter().chain(gx).copied().collect();
        let lv: Vec<[f64; 3]> = v.iter().chain(gv).copied().collect();
        match c.kinematic_contacts(id, &lx, &lv, dt) {
            Ok(kc) => {
                // the local pair's slaves are this pass's, in the same order
                for (s, f) in kc.facets.iter().enumerate() {
                    contacts[s] = f.map(|f| (kc.slaves[s] as usize, keys[s], f));
                }
                areas = kc.areas;
                if kc.anchored.is_some() {
                    planes = kc.anchored;
                }
                let (count, top) = kc.fast;
                fast.0 += count;
                if let Some(t) = top.filter(|_| count > 0) {
                    let t = self.fast_global(&t).record();
                    if t[0] > fast.1[0] {
                        fast.1 = t;
                    }
                }
            }
            Err(e) => *fault = fault.take().or(Some(e)),
        }
        (contacts, areas, planes)
    }

    /// One correction of a pass with `contacts` (and slave `areas`) at the local positions
    /// `lx` (masses `masses`): each own node's displacement and each slave's correction, as
    /// [`crate::kinematic::meshed_pass`] gives them — the master nodes' sums on their owners
    /// (three collectives; six with a softened law).
    #[allow(clippy::too_many_arguments)]
    /// The correction of one pass's `contacts` (the slaves' areas `areas`) at the local
    /// positions `lx` (or small sliding's anchor planes): `kinematic::correct_touches` with the
    /// master nodes' shares summed on their owners — one process's arithmetic. Returns the own
    /// nodes' corrections and each slave's.
    fn correction(
        &self,
        contacts: &[Contact1],
        areas: &[f64],
        law: Option<&PressureOverclosure>,
        (lx, planes): (&[[f64; 3]], Option<&[Plane]>),
        masses: &[f64],
        dt: f64,
    ) -> (Vec<[f64; 3]>, Vec<SlaveCorrection>) {
        let touch = touches(lx, contacts, planes);
        let mut dx = vec![[0.0; 3]; self.ids.len()];
        let out = correct_touches(
            &touch,
            contacts.len(),
            masses,
            areas,
            law,
            dt,
            self,
            &mut dx,
        );
        (dx, out)
    }

    /// One kinematic pair's correction, its pass `k` and, for a balanced pair, the second pass
    /// `partner` with the first pass's weight; returns the largest overclosure this rank
    /// corrected.
    #[allow(clippy::too_many_arguments)]
    fn kinematic_pair(
        &mut self,
        k: usize,
        partner: Option<(usize, f64)>,
        law: &Kinematic,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        dt: f64,
        fast: &mut (usize, [f64; 5]),
    ) -> Result<f64> {
        let law = law.softened.as_ref();
        let (gx, gv) = self.ghost_state(x, v);
        let masses = self.local_masses();
        let mut fault = None;
        let (contacts, areas, planes) =
            self.pass_contacts(k, (x, &gx), (v, &gv), dt, fast, &mut fault);
        let back = partner.map(|(b, w)| {
            let (c, a, _) = self.pass_contacts(b, (x, &gx), (v, &gv), dt, fast, &mut fault);
            (c, a, w)
        });
        // hard contact is corrected again on the corrected geometry (not on anchors' planes)
        let anchored = self.pairs[k].anchored();
        let passes = if law.is_some() || anchored { 1 } else { PASSES };
        let mut normal_force = vec![0.0; contacts.len()];
        let mut first: Option<Vec<SlaveCorrection>> = None;
        let mut gx = gx;
        for pass in 0..passes {
            if pass > 0 {
                gx = self.ghost_state(x, v).0;
            }
            let lx: Vec<[f64; 3]> = x.iter().chain(&gx).copied().collect();
            let geometry = (&lx[..], planes.as_deref());
            let (mut dx, out) = self.correction(&contacts, &areas, law, geometry, &masses, dt);
            if let Some((bc, ba, w)) = &back {
                let (dx_b, _) = self.correction(bc, ba, law, (&lx, None), &masses, dt);
                for (d, b) in dx.iter_mut().zip(&dx_b) {
                    for a in 0..3 {
                        d[a] = w * d[a] + (1.0 - w) * b[a];
                    }
                }
            }
            for (i, d) in dx.iter().enumerate() {
                for a in 0..3 {
                    x[i][a] += d[a];
                    v[i][a] += d[a] / dt;
                }
            }
            for (f, c) in normal_force.iter_mut().zip(&out) {
                let along: f64 = (0..3).map(|a| c.applied[a] * c.normal[a]).sum();
                *f += along.max(0.0);
            }
            first.get_or_insert(out);
        }
        let first = first.unwrap_or_default();
        let mut friction = vec![[0.0; 3]; contacts.len()];
        if let (Some(mu), None, false) = (self.pairs[k].coulomb(), &back, anchored) {
            let (gx, gv) = self.ghost_state(x, v);
            let lx: Vec<[f64; 3]> = x.iter().chain(&gx).copied().collect();
            let lv: Vec<[f64; 3]> = v.iter().chain(&gv).copied().collect();
            let dissipated = self.friction(
                mu,
                &contacts,
                &normal_force,
                (&lx, &lv),
                &masses,
                dt,
                (x, v),
                &mut friction,
            );
            self.pairs[k].dissipated += dissipated;
        }
        // the first pass's corrections are the pair's outputs (a balanced pair's too)
        self.pairs[k].corrections = first
            .iter()
            .zip(&friction)
            .zip(&areas)
            .map(|((c, f), &a)| {
                let along: f64 = (0..3).map(|j| c.applied[j] * c.normal[j]).sum();
                (along / a, [0, 1, 2].map(|j| c.applied[j] + f[j]))
            })
            .collect();
        if let Some(e) = fault {
            return Err(e);
        }
        Ok(first
            .iter()
            .filter(|c| c.force > 0.0)
            .map(|c| c.overclosure)
            .fold(0.0, f64::max))
    }

    /// Coulomb friction after the normal correction, as [`crate::kinematic::friction_pass`]:
    /// each slave's tangential force at the corrected state `(lx, lv)` (own and ghost nodes),
    /// its velocity changes and its facet nodes' summed on their owners in slave order, and
    /// applied to own nodes (`x`, `v`); each slave's force into `force`. Returns the energy it
    /// dissipated on this rank's nodes.
    #[allow(clippy::too_many_arguments)]
    fn friction(
        &self,
        mu: (f64, f64, f64),
        contacts: &[Contact1],
        normal_force: &[f64],
        (lx, lv): (&[[f64; 3]], &[[f64; 3]]),
        masses: &[f64],
        dt: f64,
        (x, v): (&mut [[f64; 3]], &mut [[f64; 3]]),
        force: &mut [[f64; 3]],
    ) -> f64 {
        let mut parts = Vec::new();
        for (k, c) in contacts.iter().enumerate() {
            let (Some((s, key, nodes)), &f_n) = (*c, &normal_force[k]) else {
                continue;
            };
            if f_n <= 0.0 {
                continue;
            }
            let nodes = &nodes[..facet_node_count(&nodes, u32::MAX)];
            let (ft, weights, _) = slave_friction(mu, (lx, lv, masses), s, nodes, f_n, dt);
            let Some(ft) = ft else { continue };
            force[k] = ft.to_array();
            let d = ft * (dt / masses[s]);
            parts.push((s, key, [d.x, d.y, d.z]));
            for (j, &m) in nodes.iter().enumerate() {
                // the single process subtracts each share from its node's sum
                let d = (ft * (weights[j] * dt / masses[m as usize])) * -1.0;
                parts.push((m as usize, key, [d.x, d.y, d.z]));
            }
        }
        let dv = self.node_sums(parts);
        let mut dissipated = 0.0;
        for (i, d) in dv.iter().take(x.len()).enumerate() {
            if let Some(d) = *d {
                dissipated += change_velocity((&mut *x, &mut *v), self.masses[i], i, d, dt);
            }
        }
        dissipated
    }
}

/// A rank's sums for the shared correction: on the nodes' owners, in key order.
impl NodeSums for DistributedContact {
    fn node_sums<const K: usize>(
        &self,
        rows: Vec<(usize, u64, [f64; K])>,
    ) -> Vec<Option<[f64; K]>> {
        DistributedContact::node_sums(self, rows)
    }
}
