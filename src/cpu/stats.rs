//! CPU mirror of `shaders/stats.wgsl`: the statistics of a device-resident increment.

use crate::abi::penalty::PairNode;
use crate::abi::search::*;
use crate::abi::stats::*;
use crate::abi::status::*;

/// One "invocation" per pair: its status words into the statistics (WGSL: `pair_stats`).
pub fn pair_stats(status: &[u32], plan: &mut [u32], stats: &mut [u32; STATS_WORDS]) {
    stats[STAT_STABLE_DT] = stats[STAT_STABLE_DT].min(status[STATUS_DT_STABLE]);
    stats[STAT_APPROACH_DT] = stats[STAT_APPROACH_DT].min(status[STATUS_DT_APPROACH]);
    stats[STAT_MAX_OVERCLOSURE] = stats[STAT_MAX_OVERCLOSURE].max(status[STATUS_MAX_OVERCLOSURE]);
    stats[STAT_ACTIVE] += status[STATUS_ACTIVE];
    stats[STAT_SLIPPING] += status[STATUS_SLIPPING];
    stats[STAT_FALLBACKS] += status[STATUS_FALLBACK];
    stats[STAT_COLLAPSED] += status[STATUS_COLLAPSED];
    stats[STAT_LOCAL_CAPPED] += status[STATUS_LOCAL_CAPPED];
    stats[STAT_MOTION] = stats[STAT_MOTION].max(status[STATUS_MOTION]);
    stats[STAT_FAST] += status[STATUS_FAST];
    stats[STAT_FAST_RATIO] = stats[STAT_FAST_RATIO].max(status[STATUS_FAST_RATIO]);
    stats[STAT_NONFINITE] = stats[STAT_NONFINITE].min(status[STATUS_NONFINITE]);
    stats[STAT_FIT_FAILED] = stats[STAT_FIT_FAILED].max(plan[PLAN_FIT_FAILED]);
    if plan[PLAN_GLOBAL] != 0 {
        stats[STAT_GLOBAL] += 1;
        if plan[PLAN_TRIGGER] == TRIGGER_BUDGET {
            stats[STAT_BUDGET] += 1;
        }
        plan[PLAN_CROWDED] = status[STATUS_CROWDED];
    }
    plan[PLAN_GLOBAL] = 0;
}

/// One "invocation" per pair node: the largest row of the node-wise bound (WGSL: `bound_max`).
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
/// spring's share, the gather sums them per pair node, add_forces over the pairs per node.
pub fn bound_max(pair_nodes: &[PairNode], rows: &[f32], stats: &mut [u32; STATS_WORDS]) {
    for pn in pair_nodes {
        stats[STAT_OMEGA2] = stats[STAT_OMEGA2].max(rows[pn.node as usize].max(0.0).to_bits());
    }
}

/// One "invocation": the stable increment from the bound, the increment counted
/// (WGSL: `finish_stats`).
pub fn finish_stats(stats: &mut [u32; STATS_WORDS]) {
    let w2 = f32::from_bits(stats[STAT_OMEGA2]);
    if w2 > 0.0 {
        let z = f32::from_bits(stats[STAT_DAMPING]);
        let dt = 2.0 / w2.sqrt() * ((1.0 + z * z).sqrt() - z);
        stats[STAT_STABLE_DT] = stats[STAT_STABLE_DT].min(dt.to_bits());
    }
    stats[STAT_INCREMENT] += 1;
}
