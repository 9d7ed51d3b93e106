//! CPU mirror of `shaders/schedule.wgsl`: the schedule of a device-resident increment.

use crate::abi::search::*;
use crate::abi::status::{STATUS_BOX, STATUS_BUDGET_EXCEEDED};

/// Cells of a grid of cell size h over extents `ext` in `dim` dimensions (WGSL: `cell_count`).
fn cell_count(ext: [f32; 3], h: f32, dim: u32) -> f32 {
    (0..dim as usize)
        .map(|a| (ext[a] / h).floor() + 1.0)
        .product()
}

/// Fits the grid to the plan's box into the plan's SearchParams words; false when it cannot
/// (WGSL: `fit_grid`).
fn fit_grid(params: &SearchParams, plan: &mut [u32], status: &[u32]) -> bool {
    if status[STATUS_BOX] > status[STATUS_BOX + 3] {
        return false;
    }
    let dim = params.dim as usize;
    let r = params.radius;
    let (mut lo, mut hi) = ([0.0f32; 3], [0.0f32; 3]);
    let mut span = 0.0f32;
    for a in 0..dim {
        lo[a] = from_ordered_bits(status[STATUS_BOX + a]);
        hi[a] = from_ordered_bits(status[STATUS_BOX + 3 + a]);
        span = span.max(hi[a] - lo[a] + 2.0 * r);
    }
    let q = (span / 16.0).log2().floor().exp2();
    let (mut g, mut ext) = ([0.0f32; 3], [0.0f32; 3]);
    let mut volume = 1.0f32;
    for a in 0..dim {
        g[a] = ((lo[a] - r) / q).floor() * q;
        ext[a] = hi[a] + r - g[a];
        volume *= ext[a];
    }
    let budget = params.cell_capacity as f32;
    let mut h = params.base_cell;
    if cell_count(ext, h, dim as u32) > budget {
        h = h.max((volume / budget).powf(1.0 / dim as f32));
        let mut k = 0;
        while k < 64 && cell_count(ext, h, dim as u32) > budget {
            h *= 1.1;
            k += 1;
        }
    }
    if !(cell_count(ext, h, dim as u32) <= budget) || !(h > 0.0) || !h.is_finite() {
        return false;
    }
    let mut dims = [1u32; 3];
    let mut top = 0.0f32;
    for a in 0..dim {
        dims[a] = (ext[a] / h).floor() as u32 + 1;
        top = top.max(dims[a] as f32 * h);
    }
    let b = PLAN_PARAMS;
    plan[b] = h.to_bits();
    plan[b + 1] = (1.0 / h).to_bits();
    let mut m = 0.0f32;
    for a in 0..dim {
        m = m.max(lo[a].abs().max(hi[a].abs()));
    }
    plan[b + 3] = (32.0 * 1.192_092_9e-7 * m).to_bits();
    plan[b + 4] = dims[0];
    plan[b + 5] = dims[1];
    plan[b + 6] = dims[2];
    plan[b + 7] = dims[0] * dims[1] * dims[2];
    plan[b + 16] = g[0].to_bits();
    plan[b + 17] = g[1].to_bits();
    plan[b + 18] = g[2].to_bits();
    true
}

/// One "invocation": global or local, the fitted grid, the dispatch slots; `args` is the
/// nearest-facet chunk dispatch (WGSL: `schedule`, which reads the params from the plan too).
pub fn schedule(plan: &mut [u32], status: &mut [u32], args: &mut [u32; 3]) {
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
        if !fit_grid(&params, plan, status) {
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
