//! CPU mirror of `shaders/gather.wgsl`: the contact force on every node of the pair, summed
//! exactly in 64-bit fixed point (two u32 words with a carry, as the shader does).

use super::common::facet_node_count;
use crate::abi::penalty::{
    ContactOut, PairNode, PenaltyParams, CSTATUS_MASK, CSTATUS_OPEN, HEAVY_SHIFT, HEAVY_SLAVE,
    NEED_FORCE, NO_SLAVE, PENALTY_SLAVES_APART,
};
use crate::abi::search::GpuHit;
use crate::abi::stats::{STATS_WORDS, STAT_OMEGA2};
use crate::abi::status::{STATUS_BUDGET_EXCEEDED, STATUS_FORCE_SCALE, STATUS_ROW_SCALE};

/// Bits below the sign that a fixed-point sum may use (WGSL: `FIXED_BITS`).
pub const FIXED_BITS: i32 = 60;
const TWO_32: f32 = 4_294_967_296.0;

/// 2^e for e in [−126, 127], built from its bits (WGSL: `pow2`).
pub fn pow2(e: i32) -> f32 {
    f32::from_bits(((e + 127) as u32) << 23)
}

/// The exponent E of the fixed-point scale for sums of at most 4·n_terms terms, each at most the
/// f32 whose bits are `max_bits` in magnitude (WGSL: `fixed_exponent`).
pub fn fixed_exponent(max_bits: u32, n_terms: u32) -> i32 {
    let e = ((max_bits >> 23) & 0xff) as i32 - 126;
    let k = (32 - (n_terms.max(1) - 1).leading_zeros()) as i32 + 2;
    (FIXED_BITS - e - k).clamp(-126, 126)
}

/// −a in 64-bit two's complement (WGSL: `negate`).
pub fn negate(a: [u32; 2]) -> [u32; 2] {
    let lo = (!a[0]).wrapping_add(1);
    [lo, (!a[1]).wrapping_add(u32::from(lo == 0))]
}

/// v · scale as a 64-bit integer (low, high), truncated toward zero (WGSL: `to_fixed`).
pub fn to_fixed(v: f32, scale: f32) -> [u32; 2] {
    let x = (v.abs() * scale).min(4.0e18);
    let hi = (x * (1.0 / TWO_32)).floor();
    let lo = x - hi * TWO_32;
    let r = [lo as u32, hi as u32];
    if v < 0.0 {
        negate(r)
    } else {
        r
    }
}

/// The 64-bit integer `a` times `inv_scale`, rounded to f32 (WGSL: `from_fixed`).
pub fn from_fixed(a: [u32; 2], inv_scale: f32) -> f32 {
    let neg = a[1] & 0x8000_0000 != 0;
    let m = if neg { negate(a) } else { a };
    let x = (m[1] as f32 * TWO_32 + m[0] as f32) * inv_scale;
    if neg {
        -x
    } else {
        x
    }
}

/// Adds `a` to the sum at words 2w, 2w + 1 of `acc` with the carry (WGSL: `add_fixed`).
fn add_fixed(acc: &mut [u32], w: usize, a: [u32; 2]) {
    let old = acc[2 * w];
    acc[2 * w] = old.wrapping_add(a[0]);
    let carry = u32::from(old.wrapping_add(a[0]) < old);
    acc[2 * w + 1] = acc[2 * w + 1].wrapping_add(a[1].wrapping_add(carry));
}

/// A spring's share of the node-wise bound at one of its nodes: heavy if its status has `bit`
/// (WGSL: `row_share`).
fn row_share(o: &ContactOut, bit: u32) -> f32 {
    if o.status & bit != 0 {
        o.bound_heavy
    } else {
        o.bound_light
    }
}

/// One "invocation" per slave in contact: −w_j·f and the bound share onto each facet node's
/// fixed-point sums (WGSL: `scatter_forces`); with `active` (the count, then the slave
/// indices: `cpu::active`) the active slaves only (WGSL: `scatter_forces_active`). `acc` must
/// be zeroed first; each node or rigid slot added onto is marked `NEED_FORCE` in `need`.
#[allow(clippy::too_many_arguments)]
pub fn scatter_forces(
    pp: &PenaltyParams,
    facet_nodes: &[[u32; 4]],
    hits: &[GpuHit],
    out: &[ContactOut],
    status: &[u32],
    acc: &mut [u32],
    need: &mut [u32],
    active: Option<&[u32]>,
) {
    let sf = pow2(fixed_exponent(status[STATUS_FORCE_SCALE], pp.n_slaves));
    let sr = pow2(fixed_exponent(status[STATUS_ROW_SCALE], pp.n_slaves));
    // the penalty pass did not run (the increment will run again): its outputs are stale
    if status[STATUS_BUDGET_EXCEEDED] != 0 {
        return;
    }
    let mut scatter = |i: usize| {
        let o = &out[i];
        let hit = &hits[i];
        if o.status & CSTATUS_MASK == CSTATUS_OPEN || hit.facet >= pp.n_facets {
            return;
        }
        let fac = facet_nodes[hit.facet as usize];
        let n = facet_node_count(fac);
        let rigid_master = pp.body_slots[0] != NO_SLAVE;
        for (j, &node) in fac.iter().enumerate().take(n) {
            let w = hit.weights[j];
            let base = 4 * node as usize;
            need[node as usize] |= NEED_FORCE;
            for c in 0..3 {
                add_fixed(acc, base + c, to_fixed(-w * o.force[c], sf));
            }
            let share = if w != 0.0 && !rigid_master {
                row_share(o, 1 << (HEAVY_SHIFT + j as u32))
            } else {
                0.0
            };
            add_fixed(acc, base + 3, to_fixed(share, sr));
        }
        if rigid_master {
            need[pp.body_slots[0] as usize] |= NEED_FORCE;
            let slot = 4 * pp.body_slots[0] as usize + 3;
            add_fixed(acc, slot, to_fixed(row_share(o, 1 << HEAVY_SHIFT), sr));
        }
        if pp.body_slots[1] != NO_SLAVE {
            need[pp.body_slots[1] as usize] |= NEED_FORCE;
            let slot = 4 * pp.body_slots[1] as usize + 3;
            add_fixed(acc, slot, to_fixed(row_share(o, HEAVY_SLAVE), sr));
        }
    };
    match active {
        Some(active) => {
            let count = active.first().map_or(0, |&c| c as usize);
            for &i in active.get(1..1 + count).unwrap_or(&[]) {
                scatter(i as usize);
            }
        }
        None => (0..pp.n_slaves as usize).for_each(scatter),
    }
}

/// Pair node `i` has no force and no row this increment, left by `gather` and `add_forces`
/// (WGSL: `no_force`): a slave with no facet in a pair whose slaves are no master nodes, or a
/// master node or rigid slot no spring scattered onto (`need_word`, its need bits; 0 for a
/// slave).
fn no_force(pp: &PenaltyParams, hits: &[GpuHit], i: usize, need_word: u32) -> bool {
    if i < pp.n_slaves as usize {
        return pp.flags & PENALTY_SLAVES_APART != 0
            && hits[i].facet == crate::abi::search::NO_FACET;
    }
    need_word & NEED_FORCE == 0
}

/// The pair nodes `gather` and `add_forces` visit, in order: every one (`active` `None`), or,
/// for `gather_active` and `add_forces_active`, the active slaves (`active`: the count, then
/// the slave indices) and then the pair's other nodes and rigid slots (WGSL: `active_pair_node`
/// of each item).
fn visited<'a>(
    pp: &PenaltyParams,
    active: Option<&'a [u32]>,
) -> Box<dyn Iterator<Item = usize> + 'a> {
    let total = (pp.n_pair_nodes + pp.body_slots[2]) as usize;
    match active {
        None => Box::new(0..total),
        Some(active) => {
            let count = active.first().map_or(0, |&c| c as usize);
            let slaves = active.get(1..1 + count).unwrap_or(&[]);
            let others = (pp.n_slaves as usize).min(total)..total;
            Box::new(slaves.iter().map(|&i| i as usize).chain(others))
        }
    }
}

/// One "invocation" per pair node (or per active slave and other pair node: `active`, as
/// [`scatter_forces`]): its own contact force (a slave) plus the decoded sums of the springs on
/// its facets (WGSL: `gather`, `gather_active`).
#[allow(clippy::too_many_arguments)]
pub fn gather(
    pp: &PenaltyParams,
    pair_nodes: &[PairNode],
    hits: &[GpuHit],
    out: &[ContactOut],
    status: &[u32],
    acc: &mut [u32],
    forces: &mut [[f32; 4]],
    need: &[u32],
    active: Option<&[u32]>,
) {
    let inv_f = pow2(-fixed_exponent(status[STATUS_FORCE_SCALE], pp.n_slaves));
    let inv_r = pow2(-fixed_exponent(status[STATUS_ROW_SCALE], pp.n_slaves));
    for i in visited(pp, active) {
        let pn = &pair_nodes[i];
        let need_word = if i >= pp.n_slaves as usize {
            need[i]
        } else {
            0
        };
        if no_force(pp, hits, i, need_word) {
            continue;
        }
        let mut f = [0.0f32; 3];
        let mut row = 0.0f32;
        if pn.slave != NO_SLAVE {
            let o = out[pn.slave as usize].force;
            f = [o[0], o[1], o[2]];
            if pp.body_slots[1] == NO_SLAVE {
                row = row_share(&out[pn.slave as usize], HEAVY_SLAVE);
            }
        }
        let mut sum = [0.0f32; 4];
        for (c, s) in sum.iter_mut().enumerate() {
            let w = 2 * (4 * i + c);
            let inv = if c == 3 { inv_r } else { inv_f };
            *s = from_fixed([acc[w], acc[w + 1]], inv);
            acc[w] = 0;
            acc[w + 1] = 0;
        }
        forces[i] = [f[0] + sum[0], f[1] + sum[1], f[2] + sum[2], row + sum[3]];
    }
}

/// One "invocation" per pair node: its force into the caller's array (xyz; w left alone), its
/// bound row into `rows`, and the largest row so far into the statistics' `STAT_OMEGA2`
/// (WGSL: `add_forces`).
///
/// The bound on the highest frequency of all penalty springs together (ω², 1/s²): each spring s
/// adds k_s·(u_s·x)² to xᵀKx, where x are the nodes' mass-scaled displacements and u_s its
/// nodes' shares: 1/√m for the slave, |w_j|/√m_j for a master node. Weighted Cauchy–Schwarz,
/// (u·x)² ≤ (Σ_n u_n²/α_n)·(Σ_n α_n·|x_n|²) for any α > 0, with α = 1 at the spring's light
/// nodes and α = u_n/cut at its heavy ones (share below `HEAVY_SHARE` of its largest, `cut`),
/// gives xᵀKx ≤ Σ_n |x_n|²·Λ_n, Λ_n the sum over the springs at node n of k_s·q_s·α_n with
/// q_s = Σ u²/α. So ω² ≤ max_n Λ_n. One spring alone gets its exact k·Σu² (to the heavy nodes'
/// 1e-4 or less); a rigid node (u ≈ 1e-6 of the slave's) takes only ~1e-4 of each spring it
/// carries, and a node a contact does not weigh (w = 0) none. The penalty pass computes each
/// spring's share, the gather sums them per pair node, add_forces over the pairs per node; no
/// share is negative, so a row only grows within an increment and the largest value written
/// is max_n Λ_n once every pair has added its rows.
///
/// With `active` (as [`gather`]): the active slaves and the other pair nodes only (WGSL:
/// `add_forces_active`).
#[allow(clippy::too_many_arguments)]
pub fn add_forces(
    pp: &PenaltyParams,
    pair_nodes: &[PairNode],
    hits: &[GpuHit],
    forces: &[[f32; 4]],
    host_forces: &mut [[f32; 4]],
    rows: &mut [f32],
    stats: &mut [u32; STATS_WORDS],
    need: &mut [u32],
    active: Option<&[u32]>,
) {
    for i in visited(pp, active) {
        // the need word read and cleared for the next increment
        let mut need_word = 0;
        if i >= pp.n_slaves as usize || pp.flags & PENALTY_SLAVES_APART == 0 {
            need_word = std::mem::take(&mut need[i]);
        }
        if no_force(pp, hits, i, need_word) {
            continue;
        }
        let node = pair_nodes[i].node as usize;
        let f = forces[i];
        if i < pp.n_pair_nodes as usize {
            for a in 0..3 {
                host_forces[node][a] += f[a];
            }
        }
        if f[3] != 0.0 {
            rows[node] += f[3];
            stats[STAT_OMEGA2] = stats[STAT_OMEGA2].max(rows[node].max(0.0).to_bits());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fixed-point sum of many terms in any order equals the exact (f64) sum to f32 round-off
    /// of the result, and two orders give the same bits.
    #[test]
    fn fixed_point_sums_are_exact_and_order_free() {
        let terms: Vec<f32> = (0..100_000)
            .map(|k| ((k as f32) * 0.618_034).sin() * 10f32.powi(k % 7 - 3))
            .collect();
        let max = terms.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let e = fixed_exponent(max.to_bits(), terms.len() as u32);
        let (scale, inv) = (pow2(e), pow2(-e));
        let mut a = [0u32; 2];
        let mut b = [0u32; 2];
        for &t in &terms {
            add_fixed(&mut a, 0, to_fixed(t, scale));
        }
        for &t in terms.iter().rev() {
            add_fixed(&mut b, 0, to_fixed(t, scale));
        }
        assert_eq!(a, b);
        let exact: f64 = terms.iter().map(|&t| t as f64).sum();
        let got = from_fixed(a, inv) as f64;
        // quantisation: at most one unit 2^-E per term; rounding: half an ulp of the result
        let tol = terms.len() as f64 * inv as f64 + exact.abs() * 2f64.powi(-23);
        assert!((got - exact).abs() <= tol, "{got} vs {exact}");
        // negative totals and cancellation to exactly zero
        let mut z = [0u32; 2];
        for &t in &terms {
            add_fixed(&mut z, 0, to_fixed(t, scale));
            add_fixed(&mut z, 0, to_fixed(-t, scale));
        }
        assert_eq!(z, [0, 0]);
        assert_eq!(from_fixed(to_fixed(-3.5, 2.0), 0.5), -3.5);
        assert_eq!(
            from_fixed(to_fixed(-3.5, 1.0), 1.0),
            -3.0,
            "truncated toward zero"
        );
    }
}
