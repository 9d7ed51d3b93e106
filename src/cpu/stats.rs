//! CPU mirror of `shaders/stats.wgsl`: the statistics of a device-resident increment.

use crate::penalty::layout::PairNode;
use crate::search::layout::*;

/// Words of the statistics (WGSL: `STAT_*`), in [`IncrementStats`] order.
const STABLE_DT: usize = 0;
const APPROACH_DT: usize = 1;
const MAX_OVERCLOSURE: usize = 2;
const OMEGA2: usize = 3;
const ACTIVE: usize = 4;
const SLIPPING: usize = 5;
const GLOBAL: usize = 6;
const BUDGET: usize = 7;
const FALLBACKS: usize = 8;
const COLLAPSED: usize = 9;
const NONFINITE: usize = 10;
const LOCAL_CAPPED: usize = 11;
const MOTION: usize = 12;
const FIT_FAILED: usize = 13;
const FAST: usize = 14;
const FAST_RATIO: usize = 15;
const DAMPING: usize = 16;
const INCREMENT: usize = 17;

/// The reset values of the statistics' first [`STATS_RESET_WORDS`] words.
pub fn reset_image() -> [u32; STATS_RESET_WORDS] {
    let mut w = [0u32; STATS_RESET_WORDS];
    w[STABLE_DT] = crate::penalty::layout::NO_LIMIT.to_bits();
    w[APPROACH_DT] = crate::penalty::layout::NO_LIMIT.to_bits();
    w[NONFINITE] = u32::MAX;
    w
}

/// The statistics before the first increment: the reset words, and the largest contact
/// damping ratio `damping` of the penalty pairs (a constant word).
pub fn first_image(damping: f32) -> [u32; STATS_WORDS] {
    let mut w = [0u32; STATS_WORDS];
    w[..STATS_RESET_WORDS].copy_from_slice(&reset_image());
    w[DAMPING] = damping.to_bits();
    w
}

/// One "invocation" per pair: its status words into the statistics (WGSL: `pair_stats`).
pub fn pair_stats(status: &[u32], plan: &mut [u32], stats: &mut [u32; STATS_WORDS]) {
    stats[STABLE_DT] = stats[STABLE_DT].min(status[STATUS_DT_STABLE]);
    stats[APPROACH_DT] = stats[APPROACH_DT].min(status[STATUS_DT_APPROACH]);
    stats[MAX_OVERCLOSURE] = stats[MAX_OVERCLOSURE].max(status[STATUS_MAX_OVERCLOSURE]);
    stats[ACTIVE] += status[STATUS_ACTIVE];
    stats[SLIPPING] += status[STATUS_SLIPPING];
    stats[FALLBACKS] += status[STATUS_FALLBACK];
    stats[COLLAPSED] += status[STATUS_COLLAPSED];
    stats[LOCAL_CAPPED] += status[STATUS_LOCAL_CAPPED];
    stats[MOTION] = stats[MOTION].max(status[STATUS_MOTION]);
    stats[FAST] += status[STATUS_FAST];
    stats[FAST_RATIO] = stats[FAST_RATIO].max(status[STATUS_FAST_RATIO]);
    stats[NONFINITE] = stats[NONFINITE].min(status[STATUS_NONFINITE]);
    stats[FIT_FAILED] = stats[FIT_FAILED].max(plan[PLAN_FIT_FAILED]);
    if plan[PLAN_GLOBAL] != 0 {
        stats[GLOBAL] += 1;
        if plan[PLAN_TRIGGER] == TRIGGER_BUDGET {
            stats[BUDGET] += 1;
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
        stats[OMEGA2] = stats[OMEGA2].max(rows[pn.node as usize].max(0.0).to_bits());
    }
}

/// One "invocation": the stable increment from the bound, the increment counted
/// (WGSL: `finish_stats`).
pub fn finish_stats(stats: &mut [u32; STATS_WORDS]) {
    let w2 = f32::from_bits(stats[OMEGA2]);
    if w2 > 0.0 {
        let z = f32::from_bits(stats[DAMPING]);
        let dt = 2.0 / w2.sqrt() * ((1.0 + z * z).sqrt() - z);
        stats[STABLE_DT] = stats[STABLE_DT].min(dt.to_bits());
    }
    stats[INCREMENT] += 1;
}
