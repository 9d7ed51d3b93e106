// schedule.wgsl — the schedule of a device-resident increment, decided on the device: whether
// this increment searches globally, the master's box and the search tree's round-off margin
// from it, and the dispatch sizes of every pass that depends on that choice. CPU mirror:
// src/cpu/schedule.rs.
//
// Bindings: 1 plan (the search's plan words, PLAN_* in common.wgsl; its SearchParams words are
//           what every later pass binds as its uniform), 2 status (read: the motion budget,
//           the master box and the active slaves' count; written: the budget flag is cleared
//           once this increment searches globally), 3 args (the nearest-facet chunk dispatch, emptied in a local increment).
// Dispatch: one invocation, after to_local and motion and before every pass it sizes (in the
//           same compute pass: WebGPU's usage scopes are per dispatch).
// Invariants: global when no global search has run yet, when the host asked for one, when the
//             interval came round, when self-contact was crowded at the last one, or when the
//             motion budget is used up (the motion pass ran just before). A global increment
//             takes the master box to_local raised (STATUS_BOX) and the tree's box margin from
//             it; a box that cannot be taken (no finite master node) keeps the last one and is
//             counted in PLAN_FIT_FAILED. ACTIVE_SLOT's full size is the active slaves' count
//             (status[ACTIVE_LIST]) in workgroups, ACTIVE_NODES_SLOT's that count and
//             PLAN_OTHER_NODES (the pair nodes that are no slaves, and two rigid slots), both
//             folded by PLAN_MAX_DIM. Each dispatch slot
//             gets its full size when its kind matches the increment and zero workgroups
//             otherwise. No loop runs past
//             MAX_PLAN_SLOTS iterations.

@group(0) @binding(1) var<storage, read_write> plan: array<u32>;
@group(0) @binding(2) var<storage, read_write> status: array<u32>;
@group(0) @binding(3) var<storage, read_write> args: array<u32>;

// Most dispatch slots a plan has (Rust twin: MAX_PLAN_SLOTS).
const MAX_PLAN_SLOTS: u32 = 48u;
// The active slaves' slot, the plan's first (Rust twin: ACTIVE_SLOT).
const ACTIVE_SLOT: u32 = 0u;
// The active slaves' and the other pair nodes' slot, the second (Rust twin: ACTIVE_NODES_SLOT).
const ACTIVE_NODES_SLOT: u32 = 1u;
// Words of SearchParams the schedule reads and writes (Rust twins: P_* in src/abi/search.rs,
// from the struct's field offsets).
const P_BOX_MARGIN: u32 = 1u;
const P_DIM: u32 = 5u;
const P_FLAGS: u32 = 7u;
const P_MASTER_LO: u32 = 12u;
const P_MASTER_HI: u32 = 16u;

fn param(k: u32) -> u32 {
    return plan[PLAN_PARAMS + k];
}

// Takes the master box to_local raised (STATUS_BOX) into the plan's SearchParams words, with
// the tree's round-off margin (32 ulps of the largest master coordinate in the frame, as
// search::box_margin on the host); false when there is none (no finite master node).
fn take_master_box() -> bool {
    if (status[STATUS_BOX] > status[STATUS_BOX + 3u]) { return false; }
    let dim = param(P_DIM);
    let b = PLAN_PARAMS;
    var m = 0.0;
    for (var a = 0u; a < 3u; a++) {
        var lo = 0.0;
        var hi = 0.0;
        if (a < dim) {
            lo = from_ordered_bits(status[STATUS_BOX + a]);
            hi = from_ordered_bits(status[STATUS_BOX + 3u + a]);
            m = max(m, max(abs(lo), abs(hi)));
        }
        plan[b + P_MASTER_LO + a] = bitcast<u32>(lo);
        plan[b + P_MASTER_HI + a] = bitcast<u32>(hi);
    }
    plan[b + P_BOX_MARGIN] = bitcast<u32>(32.0 * 1.1920929e-7 * m);
    return true;
}

// Slot `slot`'s full size: `count` items in workgroups, folded as the host folds a dispatch
// (fold_dispatch), none for none.
fn size_slot(slot: u32, count: u32) {
    let groups = (count + ITEM_WORKGROUP - 1u) / ITEM_WORKGROUP;
    let max_dim = max(plan[PLAN_MAX_DIM], 1u);
    var y = min(groups, 1u);
    if (groups > max_dim) { y = (groups + max_dim - 1u) / max_dim; }
    let a = PLAN_SLOTS + slot * PLAN_SLOT_WORDS;
    plan[a + 4u] = select(0u, (groups + y - 1u) / max(y, 1u), groups > 0u);
    plan[a + 5u] = y;
    plan[a + 6u] = min(groups, 1u);
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
        if (!take_master_box()) { plan[PLAN_FIT_FAILED] += 1u; }
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
    // the active slaves' slot: the count the last global search left (active.wgsl); the
    // active pair nodes' slot: that count and the other pair nodes
    let count = status[ACTIVE_LIST];
    size_slot(ACTIVE_SLOT, count);
    size_slot(ACTIVE_NODES_SLOT, count + plan[PLAN_OTHER_NODES]);
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
