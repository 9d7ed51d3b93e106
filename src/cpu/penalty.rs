//! CPU mirror of `shaders/penalty.wgsl`: penalty force, friction and outputs of each slave.

use rayon::prelude::*;

use super::common::{facet_node_count, node};
use crate::abi::penalty::*;
use crate::abi::search::{GpuHit, NO_FACET};
use crate::abi::status::STATUS_BUDGET_EXCEEDED;
use crate::abi::status::{
    STATUS_ACTIVE, STATUS_DT_APPROACH, STATUS_DT_STABLE, STATUS_FAST, STATUS_FAST_RATIO,
    STATUS_FORCE_SCALE, STATUS_MAX_OVERCLOSURE, STATUS_ROW_SCALE, STATUS_SLIPPING,
};
use crate::geometry::V3;
use crate::model::NO_NODE;

const E_MINUS_1: f32 = 1.718_281_8;

/// Force, tangent stiffness and stored energy of the law at overclosure h (WGSL: `LawValue`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawValue {
    /// Normal force.
    pub force: f32,
    /// Tangent stiffness (at max(h, start of contact)).
    pub stiffness: f32,
    /// Stored elastic energy.
    pub energy: f32,
}

fn table_point(pp: &PenaltyParams, k: u32) -> (f32, f32) {
    let v = pp.table[(k / 2) as usize];
    if k.is_multiple_of(2) {
        (v[0], v[1])
    } else {
        (v[2], v[3])
    }
}

/// The pressure–overclosure law (WGSL: `law`).
pub fn law(pp: &PenaltyParams, h: f32, k: f32, area: f32) -> LawValue {
    let mut r = LawValue {
        force: 0.0,
        stiffness: 0.0,
        energy: 0.0,
    };
    if pp.law == LAW_LINEAR {
        r.stiffness = k;
        if h > 0.0 {
            r.force = k * h;
            r.energy = 0.5 * k * h * h;
        }
    } else if pp.law == LAW_EXPONENTIAL {
        let x = (h.max(0.0) / pp.clearance + 1.0).min(60.0);
        let ex = x.exp();
        r.stiffness = area * pp.pressure / (E_MINUS_1 * pp.clearance) * ((ex - 1.0) + x * ex);
        let xh = h / pp.clearance + 1.0;
        if xh > 0.0 {
            let xc = xh.min(60.0);
            let e2 = xc.exp();
            r.force = area * pp.pressure / E_MINUS_1 * xc * (e2 - 1.0);
            r.energy = area * pp.pressure * pp.clearance / E_MINUS_1
                * ((xc - 1.0) * e2 + 1.0 - 0.5 * xc * xc);
        }
    } else {
        let n = pp.table_len;
        let h_eval = h.max(table_point(pp, 0).0);
        let (mut energy, mut force, mut slope) = (0.0f32, 0.0f32, 0.0f32);
        let mut s = 0;
        while s + 1 < n {
            let a = table_point(pp, s);
            let b = table_point(pp, s + 1);
            let sl = (b.1 - a.1) / (b.0 - a.0);
            let last = s + 2 == n;
            if h_eval >= a.0 && (h_eval < b.0 || last) {
                slope = sl;
            }
            if h > a.0 {
                let top = if last { h } else { h.min(b.0) };
                let p_top = a.1 + sl * (top - a.0);
                energy += 0.5 * (a.1 + p_top) * (top - a.0);
                force = p_top;
            }
            s += 1;
        }
        r.stiffness = area * slope;
        r.force = area * force;
        r.energy = area * energy;
    }
    r
}

/// A spring's shares of the node-wise frequency bound at its light and heavy nodes, and the
/// heavy-node bits of its status, from its row stiffness, the slave's share 1/√m_s and the
/// master nodes' shares |w_j|/√m_j (WGSL: inline in `penalty`).
fn row_shares(k_row: f32, share_s: f32, share: &[f32]) -> ([f32; 2], u32) {
    let top = share.iter().fold(share_s, |a, &u| a.max(u));
    let cut = HEAVY_SHARE * top;
    let (mut q, mut heavy, mut mask) = (0.0f32, 0.0f32, 0u32);
    if share_s >= cut {
        q += share_s * share_s;
    } else {
        q += share_s * cut;
        heavy = heavy.max(share_s);
        mask |= HEAVY_SLAVE;
    }
    for (j, &u) in share.iter().enumerate() {
        if u == 0.0 {
            continue;
        }
        if u >= cut {
            q += u * u;
        } else {
            q += u * cut;
            heavy = heavy.max(u);
            mask |= 1 << (HEAVY_SHIFT + j as u32);
        }
    }
    ([k_row * q, k_row * q * (heavy / cut)], mask)
}

/// The compliance (1/effective mass) of a rigid body (centre xyz and inverse mass w `body`,
/// inverse inertia rows `j`) at point `p` along unit direction `n`: 1/M + (r×n)·J·(r×n)
/// (WGSL: `body_compliance`).
pub fn body_compliance(body: [f32; 4], j: &[[f32; 4]; 3], p: V3<f32>, n: V3<f32>) -> f32 {
    let u = (p - V3::new(body[0], body[1], body[2])).cross(n);
    let row = |r: [f32; 4]| V3::new(r[0], r[1], r[2]).dot(u);
    let ju = V3::new(row(j[0]), row(j[1]), row(j[2]));
    body[3] + u.dot(ju)
}

/// The master's velocity at a contact point: facet `fac`'s nodes by the load-transfer weights
/// `w`, summed in the penalty pass's order (WGSL: `facet_velocity`).
fn facet_velocity(vel: &[[f32; 4]], fac: [u32; 4], w: [f32; 4]) -> V3<f32> {
    let mut vm = V3::<f32>::zero();
    for j in 0..facet_node_count(fac) {
        vm = vm + node(vel, fac[j]) * w[j];
    }
    vm
}

/// The status words the springs raise, reduced per chunk of slaves before they reach the
/// status (WGSL: `wg_words`, per workgroup): counts added, largest values and smallest
/// increments on their bits (non-negative and positive f32 order as their bits).
#[derive(Clone, Copy)]
struct Raised {
    fast: u32,
    active: u32,
    slipping: u32,
    fast_ratio: u32,
    overclosure: u32,
    force_scale: u32,
    row_scale: u32,
    dt_stable: u32,
    dt_approach: u32,
}

impl Raised {
    /// Nothing raised: each word at its operation's identity.
    fn none() -> Self {
        Self {
            fast: 0,
            active: 0,
            slipping: 0,
            fast_ratio: 0,
            overclosure: 0,
            force_scale: 0,
            row_scale: 0,
            dt_stable: u32::MAX,
            dt_approach: u32::MAX,
        }
    }

    /// Two chunks' words together.
    fn join(self, o: Self) -> Self {
        Self {
            fast: self.fast.wrapping_add(o.fast),
            active: self.active.wrapping_add(o.active),
            slipping: self.slipping.wrapping_add(o.slipping),
            fast_ratio: self.fast_ratio.max(o.fast_ratio),
            overclosure: self.overclosure.max(o.overclosure),
            force_scale: self.force_scale.max(o.force_scale),
            row_scale: self.row_scale.max(o.row_scale),
            dt_stable: self.dt_stable.min(o.dt_stable),
            dt_approach: self.dt_approach.min(o.dt_approach),
        }
    }

    /// Raised into the status words (WGSL: `words_finish`).
    fn into_status(self, status: &mut [u32]) {
        for (k, v) in [
            (STATUS_FAST, self.fast),
            (STATUS_ACTIVE, self.active),
            (STATUS_SLIPPING, self.slipping),
        ] {
            status[k] = status[k].wrapping_add(v);
        }
        for (k, v) in [
            (STATUS_FAST_RATIO, self.fast_ratio),
            (STATUS_MAX_OVERCLOSURE, self.overclosure),
            (STATUS_FORCE_SCALE, self.force_scale),
            (STATUS_ROW_SCALE, self.row_scale),
        ] {
            status[k] = status[k].max(v);
        }
        for (k, v) in [
            (STATUS_DT_STABLE, self.dt_stable),
            (STATUS_DT_APPROACH, self.dt_approach),
        ] {
            status[k] = status[k].min(v);
        }
    }
}

/// One "invocation" per slave node (WGSL: `penalty`), or with `active` (the count, then the
/// slave indices: `cpu::active`) one per active slave (WGSL: `penalty_active`); `friction` is
/// the FRICTION override.
#[allow(clippy::too_many_arguments)]
pub fn penalty(
    pp: &PenaltyParams,
    friction: bool,
    nodes: &[[f32; 4]],
    vel: &[[f32; 4]],
    facets: &[[u32; 4]],
    hits: &[GpuHit],
    normals: &[[f32; 4]],
    state: &mut [SlaveState],
    out: &mut [ContactOut],
    status: &mut [u32],
    active: Option<&[u32]>,
) {
    if status[STATUS_BUDGET_EXCEEDED] != 0 {
        return;
    }
    let n = pp.n_slaves as usize;
    // the fast-node test (WGSL: `count_fast`)
    let count_fast = |r: &mut Raised, s: u32, v_master: V3<f32>| {
        let reach = (node(vel, s) - v_master).length2().sqrt() * pp.dt;
        if reach > pp.search_radius {
            r.fast += 1;
            r.fast_ratio = r.fast_ratio.max((reach / pp.search_radius).to_bits());
        }
    };
    let spring = |i: usize, slave_state: &mut SlaveState, slot: &mut ContactOut, r: &mut Raised| {
        let hit = hits[i];
        let mut o = ContactOut {
            force: [0.0; 4],
            tangential: [0.0; 4],
            normal_gap: [0.0; 4],
            status: CSTATUS_OPEN,
            dissipation: 0.0,
            bound_light: 0.0,
            bound_heavy: 0.0,
        };
        let (mut dt_stable, mut dt_approach) = (NO_LIMIT, NO_LIMIT);
        let area = slave_state.tangential_area[3];
        o.dissipation = slave_state.history[0];
        let beside = hit.candidates & crate::abi::search::HIT_BESIDE_FREE_EDGE != 0;
        if hit.facet == NO_FACET || beside {
            if hit.facet != NO_FACET {
                let fac = facets[hit.facet as usize];
                count_fast(r, hit.slave, facet_velocity(vel, fac, hit.weights));
            } else if pp.ref_node != NO_NODE {
                count_fast(r, hit.slave, node(vel, pp.ref_node));
            }
            slave_state.tangential_area = [0.0, 0.0, 0.0, area];
            let behind = if beside && hit.point_gap[3] < 0.0 {
                1.0
            } else {
                0.0
            };
            slave_state.history = [o.dissipation, behind, 0.0, 0.0];
            *slot = o;
            return;
        }
        let s = hit.slave;
        let fac = facets[hit.facet as usize];
        let n = facet_node_count(fac);
        let (mut nsum, mut vm) = (V3::<f32>::zero(), V3::<f32>::zero());
        let (mut inv_mm, mut h_facet) = (0.0f32, 0.0f32);
        let mut share = [0.0f32; 4];
        for j in 0..n {
            let w = hit.weights[j];
            let id = fac[j];
            let nn = normals[id as usize];
            nsum = nsum + V3::new(nn[0], nn[1], nn[2]) * w;
            let v = vel[id as usize];
            vm = vm + V3::new(v[0], v[1], v[2]) * w;
            inv_mm += w * w / nodes[id as usize][3];
            share[j] = w.abs() / nodes[id as usize][3].sqrt();
            h_facet = h_facet.max(
                (node(nodes, fac[(j + 1) % n]) - node(nodes, id))
                    .length2()
                    .sqrt(),
            );
        }
        count_fast(r, s, vm);
        let mut nrm = nsum.normalize_or_zero();
        if nrm.length2() == 0.0 {
            nrm = V3::new(hit.normal_dist[0], hit.normal_dist[1], hit.normal_dist[2]);
        }
        let p = node(nodes, s);
        let c = V3::new(hit.point_gap[0], hit.point_gap[1], hit.point_gap[2]);
        let mut gap = (p - c).dot(nrm);
        if pp.flags & PENALTY_ANCHORED != 0 {
            nrm = V3::new(hit.normal_dist[0], hit.normal_dist[1], hit.normal_dist[2]);
            gap = hit.point_gap[3];
        }
        if slave_state.history[1] != 0.0 && gap < 0.0 {
            slave_state.tangential_area = [0.0, 0.0, 0.0, area];
            *slot = o;
            return;
        }
        let mut inv_ms = 1.0 / nodes[s as usize][3];
        if pp.master_body[3] > 0.0 {
            inv_mm = body_compliance(pp.master_body, &pp.master_inv_inertia, c, nrm);
            share = [inv_mm.sqrt(), 0.0, 0.0, 0.0];
        }
        if pp.slave_body[3] > 0.0 {
            inv_ms = body_compliance(pp.slave_body, &pp.slave_inv_inertia, p, nrm);
        }
        let m_eff = 1.0 / (inv_ms + inv_mm);
        let mut k = pp.stiffness;
        if pp.stiffness_mode == STIFFNESS_AUTO {
            let m_auto = 1.0 / (inv_ms * pp.slave_share + inv_mm);
            k = pp.stiffness * m_auto / (pp.dt_ref * pp.dt_ref);
        } else if pp.stiffness_mode == STIFFNESS_MODULUS {
            k = pp.stiffness * pp.modulus * area / h_facet;
        } else if pp.stiffness_mode == STIFFNESS_PER_AREA {
            k = pp.stiffness * area;
        }
        let lv = law(pp, -gap, k, area);
        let vs = vel[s as usize];
        let v_rel = V3::new(vs[0], vs[1], vs[2]) - vm;
        let v_close = -v_rel.dot(nrm);
        let omega = (lv.stiffness / m_eff).sqrt();
        let z = pp.damping;
        if omega > 0.0 {
            dt_stable = 2.0 / omega * ((1.0 + z * z).sqrt() - z);
        }
        if gap > 0.0 && v_close > 0.0 {
            dt_approach = 0.5 * gap / v_close;
        }
        let mut k_row = pp.weight * lv.stiffness;
        if friction {
            k_row *= pp.stick_stiffness.max(1.0);
        }
        let (bound, mask) = row_shares(k_row, inv_ms.sqrt(), &share[..n]);
        o.bound_light = bound[0];
        o.bound_heavy = bound[1];
        o.normal_gap = [nrm.x, nrm.y, nrm.z, gap];
        let mut f_t = V3::<f32>::zero();
        if lv.force > 0.0 {
            let cdamp = 2.0 * z * (lv.stiffness * m_eff).sqrt();
            let f_n = (lv.force + cdamp * v_close).max(0.0);
            o.status = CSTATUS_SLIP;
            if friction {
                let st = slave_state.tangential_area;
                let mut t_prev = V3::new(st[0], st[1], st[2]);
                let mag = t_prev.length2().sqrt();
                t_prev = (t_prev - nrm * t_prev.dot(nrm)).normalize_or_zero() * mag;
                let v_t = v_rel - nrm * v_rel.dot(nrm);
                let k_t = pp.stick_stiffness * lv.stiffness;
                let trial = t_prev - v_t * (k_t * pp.dt);
                let mu = pp.mu_kinetic
                    + (pp.mu - pp.mu_kinetic) * (-pp.decay * v_t.length2().sqrt()).exp();
                let limit = mu * f_n;
                let t_len = trial.length2().sqrt();
                if t_len <= limit {
                    f_t = trial;
                    o.status = CSTATUS_STICK;
                } else {
                    f_t = trial * (limit / t_len);
                    if k_t > 0.0 {
                        o.dissipation += pp.weight * limit * (t_len - limit) / k_t;
                    }
                }
                if k_t > 0.0 {
                    o.tangential[3] = 0.5 * f_t.dot(f_t) / k_t;
                }
            }
            let w = pp.weight;
            let f = (nrm * f_n + f_t) * w;
            o.force = [f.x, f.y, f.z, w * f_n];
            let ft = f_t * w;
            o.tangential = [ft.x, ft.y, ft.z, w * (o.tangential[3] + lv.energy)];
            r.active += 1;
            if o.status == CSTATUS_SLIP {
                r.slipping += 1;
            }
            r.overclosure = r.overclosure.max((-gap).max(0.0).to_bits());
        }
        slave_state.tangential_area = [f_t.x, f_t.y, f_t.z, area];
        slave_state.history = [o.dissipation, 0.0, 0.0, 0.0];
        r.dt_stable = r.dt_stable.min(dt_stable.to_bits());
        r.dt_approach = r.dt_approach.min(dt_approach.to_bits());
        o.status |= mask;
        if o.status & CSTATUS_MASK != CSTATUS_OPEN {
            // the fixed-point scales of the gather: the largest magnitudes it will sum
            let a = o.force[0].abs().max(o.force[1].abs().max(o.force[2].abs()));
            r.force_scale = r.force_scale.max(a.to_bits());
            r.row_scale = r.row_scale.max(o.bound_light.max(o.bound_heavy).to_bits());
        }
        *slot = o;
    };
    let raised = match active {
        None => state[..n]
            .par_iter_mut()
            .zip(out[..n].par_iter_mut())
            .enumerate()
            .with_min_len(super::PAR_MIN)
            .fold(Raised::none, |mut r, (i, (slave_state, slot))| {
                spring(i, slave_state, slot, &mut r);
                r
            })
            .reduce(Raised::none, Raised::join),
        Some(active) => {
            // the active slaves (WGSL: `penalty_active`): an untracked one is left as it is
            let count = active.first().map_or(0, |&c| c as usize);
            let list = active.get(1..1 + count).unwrap_or(&[]);
            super::for_listed(
                list,
                &mut state[..n],
                &mut out[..n],
                Raised::none,
                Raised::join,
                |i, slave_state, slot, r| {
                    if hits[i].node != NO_NODE {
                        spring(i, slave_state, slot, r);
                    }
                },
            )
        }
    };
    raised.into_status(status);
}
