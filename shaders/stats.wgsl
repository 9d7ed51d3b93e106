// stats.wgsl — the statistics of a device-resident increment, reduced on the device into one
// buffer the host's own integrator can read there (and the host a few increments late).
// CPU mirror: src/cpu/stats.rs.
//
// Bindings: 0 status (a pair's status words), 1 plan (its search's plan), 2 stats (the
//           increment's words, STAT_* below; Rust twin: IncrementStats).
// Dispatch: pair_stats one invocation per pair after its passes; finish_stats one invocation,
//           last (after every pair's add_forces, which raise the largest bound row).
// Invariants: increments are positive f32 and overclosures and rows non-negative f32, so their
//             minima and maxima are taken on the bits; every other word is an integer sum, so
//             the words do not depend on the order of the invocations. pair_stats also keeps the
//             crowding of a global search for the next schedule.

@group(0) @binding(0) var<storage, read> status: array<u32>;
@group(0) @binding(1) var<storage, read_write> plan: array<u32>;
@group(0) @binding(2) var<storage, read_write> stats: array<atomic<u32>>;

// Words of the statistics (Rust twin: IncrementStats, 76 bytes).
const STAT_STABLE_DT: u32 = 0u;      // f32: the largest stable increment the penalty springs allow
const STAT_APPROACH_DT: u32 = 1u;    // f32: the approach limit
const STAT_MAX_OVERCLOSURE: u32 = 2u; // f32: the largest overclosure of a spring in contact
// STAT_OMEGA2 = 3 (f32: the node-wise bound on the springs' ω², raised by add_forces in
// gather.wgsl): common.wgsl
const STAT_ACTIVE: u32 = 4u;         // slaves in contact
const STAT_SLIPPING: u32 = 5u;       // of which slipping
const STAT_GLOBAL: u32 = 6u;         // searches that ran globally
const STAT_BUDGET: u32 = 7u;         // of which because the motion budget was used up
const STAT_FALLBACKS: u32 = 8u;      // slaves whose tree walk hit its cap (all pairs)
const STAT_COLLAPSED: u32 = 9u;      // master facets collapsed at a global search (all pairs)
const STAT_NONFINITE: u32 = 10u;     // the lowest node with a non-finite coordinate, NO_NODE if none
const STAT_LOCAL_CAPPED: u32 = 11u;  // local walks stopped at the iteration cap
const STAT_LOCAL_WALKS: u32 = 12u;   // slaves the local search walked (past their skin)
const STAT_MOTION: u32 = 13u;        // f32: the largest motion since a global search
const STAT_FIT_FAILED: u32 = 14u;    // master boxes that could not be taken (since the start)
const STAT_FAST: u32 = 15u;          // slaves moving farther than the radius relative to the master
const STAT_FAST_RATIO: u32 = 16u;    // f32: the largest such relative motion over the radius
const STAT_DAMPING: u32 = 17u;       // f32: the largest contact damping ratio (constant)
const STAT_INCREMENT: u32 = 18u;     // increments completed (since the start)

@compute @workgroup_size(1)
fn pair_stats() {
    atomicMin(&stats[STAT_STABLE_DT], status[STATUS_DT_STABLE]);
    atomicMin(&stats[STAT_APPROACH_DT], status[STATUS_DT_APPROACH]);
    atomicMax(&stats[STAT_MAX_OVERCLOSURE], status[STATUS_MAX_OVERCLOSURE]);
    atomicAdd(&stats[STAT_ACTIVE], status[STATUS_ACTIVE]);
    atomicAdd(&stats[STAT_SLIPPING], status[STATUS_SLIPPING]);
    atomicAdd(&stats[STAT_FALLBACKS], status[STATUS_FALLBACK]);
    atomicAdd(&stats[STAT_COLLAPSED], status[STATUS_COLLAPSED]);
    atomicAdd(&stats[STAT_LOCAL_CAPPED], status[STATUS_LOCAL_CAPPED]);
    atomicAdd(&stats[STAT_LOCAL_WALKS], status[STATUS_LOCAL_WALKS]);
    atomicMax(&stats[STAT_MOTION], status[STATUS_MOTION]);
    atomicAdd(&stats[STAT_FAST], status[STATUS_FAST]);
    atomicMax(&stats[STAT_FAST_RATIO], status[STATUS_FAST_RATIO]);
    atomicMin(&stats[STAT_NONFINITE], status[STATUS_NONFINITE]);
    atomicMax(&stats[STAT_FIT_FAILED], plan[PLAN_FIT_FAILED]);
    if (plan[PLAN_GLOBAL] != 0u) {
        atomicAdd(&stats[STAT_GLOBAL], 1u);
        if (plan[PLAN_TRIGGER] == TRIGGER_BUDGET) { atomicAdd(&stats[STAT_BUDGET], 1u); }
        plan[PLAN_CROWDED] = status[STATUS_CROWDED];
    }
    plan[PLAN_GLOBAL] = 0u;
}

@compute @workgroup_size(1)
fn finish_stats() {
    let w2 = bitcast<f32>(atomicLoad(&stats[STAT_OMEGA2]));
    if (w2 > 0.0) {
        let z = bitcast<f32>(atomicLoad(&stats[STAT_DAMPING]));
        let dt = 2.0 / sqrt(w2) * (sqrt(1.0 + z * z) - z);
        atomicMin(&stats[STAT_STABLE_DT], bitcast<u32>(dt));
    }
    atomicAdd(&stats[STAT_INCREMENT], 1u);
}
