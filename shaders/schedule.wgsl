// schedule.wgsl — the schedule of a device-resident increment, decided on the device: whether
// this increment searches globally, the frame's box (a grid of cells: to_local checks the master
// against it) and the search tree's round-off margin, and the dispatch sizes of every
// pass that depends on that choice. CPU mirror: src/cpu/schedule.rs.
//
// Bindings: 1 plan (the search's plan words, PLAN_* in common.wgsl; its SearchParams words are
//           the grid of the last global search, and what every later pass binds as its
//           uniform), 2 status (read: the motion budget and the master box; written: the budget
//           flag is cleared once this increment searches globally), 3 args (the nearest-facet
//           chunk dispatch, emptied in a local increment).
// Dispatch: one invocation, after to_local and motion and before every pass it sizes (in the
//           same compute pass: WebGPU's usage scopes are per dispatch).
// Invariants: global when no global search has run yet, when the host asked for one, when the
//             interval came round, when self-contact was crowded at the last one, or when the
//             motion budget is used up (the motion pass ran just before): the host schedule's
//             rules, so both choose the same increments. A global increment fits the grid to the
//             master box to_local raised (STATUS_BOX), as Grid::fit does on the host (the origin snapped to a
//             power of two, cells of base_cell grown until at most cell_capacity cells): the
//             buffers were sized for cell_capacity, so no position can overflow them. A box that
//             cannot be fitted (no finite master node) keeps the last grid and is counted in
//             PLAN_FIT_FAILED. Each dispatch slot gets its full size when its kind matches the
//             increment and zero workgroups otherwise. No loop runs past 64 iterations.

@group(0) @binding(1) var<storage, read_write> plan: array<u32>;
@group(0) @binding(2) var<storage, read_write> status: array<u32>;
@group(0) @binding(3) var<storage, read_write> args: array<u32>;

// Most dispatch slots a plan has (Rust twin: MAX_PLAN_SLOTS).
const MAX_PLAN_SLOTS: u32 = 48u;
// Words of SearchParams the schedule reads and writes (Rust: the struct's field order).
const P_CELL_SIZE: u32 = 0u;
const P_INV_CELL_SIZE: u32 = 1u;
const P_RADIUS: u32 = 2u;
const P_BOX_MARGIN: u32 = 3u;
const P_DIMS: u32 = 4u;
const P_N_CELLS: u32 = 7u;
const P_DIM: u32 = 11u;
const P_FLAGS: u32 = 13u;
const P_GRID_LO: u32 = 16u;
const P_BASE_CELL: u32 = 19u;
const P_CELL_CAPACITY: u32 = 20u;

fn param(k: u32) -> u32 {
    return plan[PLAN_PARAMS + k];
}

// Cells of a grid of cell size h over extents ext in `dim` dimensions.
fn cell_count(ext: vec3<f32>, h: f32, dim: u32) -> f32 {
    var n = 1.0;
    for (var a = 0u; a < dim; a++) { n *= floor(ext[a] / h) + 1.0; }
    return n;
}

// Fits the grid to the plan's box into the plan's SearchParams words, with the tree's box margin
// (32 ulps of the largest master coordinate in the frame, as search::box_margin on the host);
// false when it cannot.
fn fit_grid() -> bool {
    if (status[STATUS_BOX] > status[STATUS_BOX + 3u]) { return false; } // no finite master node
    let dim = param(P_DIM);
    let r = bitcast<f32>(param(P_RADIUS));
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    var span = 0.0;
    for (var a = 0u; a < dim; a++) {
        lo[a] = from_ordered_bits(status[STATUS_BOX + a]);
        hi[a] = from_ordered_bits(status[STATUS_BOX + 3u + a]);
        span = max(span, hi[a] - lo[a] + 2.0 * r);
    }
    let q = exp2(floor(log2(span / 16.0)));
    var g = vec3<f32>(0.0);
    var ext = vec3<f32>(0.0);
    var volume = 1.0;
    for (var a = 0u; a < dim; a++) {
        g[a] = floor((lo[a] - r) / q) * q;
        ext[a] = hi[a] + r - g[a];
        volume *= ext[a];
    }
    let budget = f32(param(P_CELL_CAPACITY));
    var h = bitcast<f32>(param(P_BASE_CELL));
    if (cell_count(ext, h, dim) > budget) {
        h = max(h, pow(volume / budget, 1.0 / f32(dim)));
        for (var k = 0u; k < 64u && cell_count(ext, h, dim) > budget; k++) { h *= 1.1; }
    }
    if (!(cell_count(ext, h, dim) <= budget) || !(h > 0.0) || non_finite(h)) { return false; }
    var dims = vec3<u32>(1u);
    var top = 0.0;
    for (var a = 0u; a < dim; a++) {
        dims[a] = u32(floor(ext[a] / h)) + 1u;
        top = max(top, f32(dims[a]) * h);
    }
    let b = PLAN_PARAMS;
    plan[b + P_CELL_SIZE] = bitcast<u32>(h);
    plan[b + P_INV_CELL_SIZE] = bitcast<u32>(1.0 / h);
    // the tree's round-off margin: 32 ulps of the largest master coordinate in the frame
    var m = 0.0;
    for (var a = 0u; a < dim; a++) { m = max(m, max(abs(lo[a]), abs(hi[a]))); }
    plan[b + P_BOX_MARGIN] = bitcast<u32>(32.0 * 1.1920929e-7 * m);
    for (var a = 0u; a < 3u; a++) {
        plan[b + P_DIMS + a] = dims[a];
        plan[b + P_GRID_LO + a] = bitcast<u32>(g[a]);
    }
    plan[b + P_N_CELLS] = dims.x * dims.y * dims.z;
    return true;
}

@compute @workgroup_size(1)
fn schedule() {
    var trigger = TRIGGER_LOCAL;
    if (plan[PLAN_SEARCHED] == 0u) {
        trigger = TRIGGER_FIRST;
    } else if (plan[PLAN_FORCE] != 0u) {
        trigger = TRIGGER_REQUESTED;
    } else if (plan[PLAN_SINCE_GLOBAL] + 1u >= plan[PLAN_INTERVAL]) {
        trigger = TRIGGER_INTERVAL;
    } else if ((param(P_FLAGS) & FLAG_SELF_CONTACT) != 0u && plan[PLAN_CROWDED] != 0u) {
        trigger = TRIGGER_CROWDED;
    } else if (status[STATUS_BUDGET_EXCEEDED] != 0u) {
        trigger = TRIGGER_BUDGET;
    }
    let global = trigger != TRIGGER_LOCAL;
    if (global) {
        if (!fit_grid()) { plan[PLAN_FIT_FAILED] += 1u; }
        plan[PLAN_SINCE_GLOBAL] = 0u;
        plan[PLAN_SEARCHED] = 1u;
        plan[PLAN_FORCE] = 0u;
        // the local search this flag stops does not run: the global search replaces it
        status[STATUS_BUDGET_EXCEEDED] = 0u;
    } else {
        plan[PLAN_SINCE_GLOBAL] += 1u;
        args[0] = 0u;
        args[1] = 0u;
        args[2] = 0u;
    }
    plan[PLAN_GLOBAL] = select(0u, 1u, global);
    plan[PLAN_TRIGGER] = trigger;
    let n = min(plan[PLAN_N_SLOTS], MAX_PLAN_SLOTS);
    for (var k = 0u; k < n; k++) {
        let s = PLAN_SLOTS + k * PLAN_SLOT_WORDS;
        let kind = plan[s + 7u];
        let on = (kind == SLOT_GLOBAL && global) || (kind == SLOT_LOCAL && !global);
        for (var c = 0u; c < 3u; c++) {
            plan[s + c] = select(0u, plan[s + 4u + c], on);
        }
    }
}
