//! CPU mirror of `shaders/stats.wgsl`: the statistics of a device-resident increment.

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
    stats[STAT_LOCAL_WALKS] += status[STATUS_LOCAL_WALKS];
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
