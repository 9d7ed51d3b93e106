//! CPU mirror of `shaders/schedule.wgsl`: the schedule of a device-resident increment.

use crate::abi::search::*;
use crate::abi::status::{STATUS_BOX, STATUS_BUDGET_EXCEEDED};

/// Takes the master box into the plan's SearchParams words with the tree's box margin; false
/// when there is none (WGSL: `take_master_box`).
fn take_master_box(params: &SearchParams, plan: &mut [u32], status: &[u32]) -> bool {
    if status[STATUS_BOX] > status[STATUS_BOX + 3] {
        return false;
    }
    let b = PLAN_PARAMS;
    let mut m = 0.0f32;
    for a in 0..3 {
        let (mut lo, mut hi) = (0.0f32, 0.0f32);
        if a < params.dim as usize {
            lo = from_ordered_bits(status[STATUS_BOX + a]);
            hi = from_ordered_bits(status[STATUS_BOX + 3 + a]);
            m = m.max(lo.abs().max(hi.abs()));
        }
        plan[b + P_MASTER_LO + a] = lo.to_bits();
        plan[b + P_MASTER_HI + a] = hi.to_bits();
    }
    plan[b + P_BOX_MARGIN] = (32.0 * 1.192_092_9e-7 * m).to_bits();
    true
}

/// Slot `slot`'s full size: `count` items in workgroups, folded, none for none (WGSL:
/// `size_slot`).
fn size_slot(plan: &mut [u32], slot: usize, count: u32) {
    let a = PLAN_SLOTS + slot * PLAN_SLOT_WORDS;
    let size = if count == 0 {
        [0, 0, 0]
    } else {
        let (x, y) = fold_dispatch(count, ITEM_WORKGROUP, plan[PLAN_MAX_DIM].max(1));
        [x, y, 1]
    };
    plan[a + 4..a + 7].copy_from_slice(&size);
}

/// One "invocation": global or local, the fitted grid, the dispatch slots (the active slaves'
/// from their count `active_count`, the active pair nodes' from it and `PLAN_OTHER_NODES`); `args` is the nearest-facet chunk dispatch (WGSL:
/// `schedule`, which reads the params from the plan and the count from the status buffer).
pub fn schedule(plan: &mut [u32], status: &mut [u32], args: &mut [u32; 3], active_count: u32) {
    let params = plan_params(plan);
    let trigger = if plan[PLAN_SEARCHED] == 0 {
        TRIGGER_FIRST
    } else if plan[PLAN_FORCE] != 0 {
        TRIGGER_REQUESTED
    } else if plan[PLAN_SINCE_GLOBAL] + 1 >= plan[PLAN_INTERVAL] {
        TRIGGER_INTERVAL
    } else if params.flags & FLAG_SELF_CONTACT != 0 && plan[PLAN_CROWDED] != 0 {
        TRIGGER_CROWDED
    } else if status[STATUS_BUDGET_EXCEEDED] != 0 {
        TRIGGER_BUDGET
    } else {
        TRIGGER_LOCAL
    };
    let global = trigger != TRIGGER_LOCAL;
    if global {
        if !take_master_box(&params, plan, status) {
            plan[PLAN_FIT_FAILED] += 1;
        }
        plan[PLAN_SINCE_GLOBAL] = 0;
        plan[PLAN_SEARCHED] = 1;
        plan[PLAN_FORCE] = 0;
        status[STATUS_BUDGET_EXCEEDED] = 0;
    } else {
        plan[PLAN_SINCE_GLOBAL] += 1;
        *args = [0; 3];
    }
    plan[PLAN_GLOBAL] = global as u32;
    plan[PLAN_TRIGGER] = trigger;
    size_slot(plan, ACTIVE_SLOT, active_count);
    let other = plan[PLAN_OTHER_NODES];
    size_slot(plan, ACTIVE_NODES_SLOT, active_count + other);
    let n = (plan[PLAN_N_SLOTS] as usize).min(MAX_PLAN_SLOTS);
    for k in 0..n {
        let s = PLAN_SLOTS + k * PLAN_SLOT_WORDS;
        let kind = plan[s + 7];
        let on = (kind == SLOT_GLOBAL && global) || (kind == SLOT_LOCAL && !global);
        for c in 0..3 {
            plan[s + c] = if on { plan[s + 4 + c] } else { 0 };
        }
    }
}
