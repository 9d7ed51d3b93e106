//! CPU mirror of `shaders/active.wgsl`: the active slaves a global search leaves, compacted in
//! slave order for the local increments' slave passes.

use crate::abi::search::{slave_state, GpuHit, SearchParams, FLAG_EVERY_SLAVE};
use crate::model::NO_NODE;

/// Whether local increments visit slave `i` (WGSL: `visited`).
fn visited(params: &SearchParams, hits: &[GpuHit], i: usize) -> bool {
    params.flags & FLAG_EVERY_SLAVE != 0 || hits[i].node != NO_NODE
}

/// 1 for each slave to visit, 0 for the others, and a last 0 (WGSL: `active_mark`); `work`
/// holds at least `n_slaves + 1` words. Each slave's tracking state into the w of its
/// reference (`slaves`: their model node ids).
pub fn active_mark(
    params: &SearchParams,
    hits: &[GpuHit],
    work: &mut [u32],
    slaves: &[u32],
    reference: &mut [[f32; 4]],
) {
    let n = params.n_slaves as usize;
    for (i, w) in work[..n].iter_mut().enumerate() {
        *w = u32::from(visited(params, hits, i));
        reference[slaves[i] as usize][3] = slave_state(&hits[i]);
    }
    work[n] = 0;
}

/// The visited slaves at their scanned places in `active`, the count first (WGSL:
/// `active_compact`); `active` holds at least `n_slaves + 1` words.
pub fn active_compact(params: &SearchParams, hits: &[GpuHit], work: &[u32], active: &mut [u32]) {
    let n = params.n_slaves as usize;
    for i in 0..n {
        if visited(params, hits, i) {
            active[1 + work[i] as usize] = i as u32;
        }
    }
    active[0] = work[n];
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abi::search::{
        fresh_plan, ACTIVE_SLOT, ITEM_WORKGROUP, PLAN_MAX_DIM, PLAN_SEARCHED, PLAN_SLOTS,
        PLAN_SLOT_WORDS,
    };

    /// The tracked slaves in slave order, the count first, and the schedule's slot for them
    /// folded as the host folds a dispatch; with `FLAG_EVERY_SLAVE`, every slave; with none
    /// tracked, no dispatch.
    #[test]
    fn compacts_the_tracked_slaves_in_order() {
        let n = 200u32;
        let hits: Vec<GpuHit> = (0..n)
            .map(|i| {
                let mut h = GpuHit::miss(i, 0);
                if i % 7 == 3 {
                    h.node = i;
                }
                h
            })
            .collect();
        for (flags, none) in [(0, false), (FLAG_EVERY_SLAVE, false), (0, true)] {
            let params = SearchParams {
                n_slaves: n,
                flags,
                ..bytemuck::Zeroable::zeroed()
            };
            let hits: Vec<GpuHit> = if none {
                (0..n).map(|i| GpuHit::miss(i, 0)).collect()
            } else {
                hits.clone()
            };
            let levels = crate::abi::search::ScanLevels::new(n + 1);
            let mut work = vec![7; levels.words as usize];
            let slaves: Vec<u32> = (0..n).collect();
            let mut reference = vec![[0.0; 4]; n as usize];
            active_mark(&params, &hits, &mut work, &slaves, &mut reference);
            for (h, r) in hits.iter().zip(&reference) {
                assert_eq!(r[3], slave_state(h));
            }
            crate::cpu::scan::scan(&levels, &mut work);
            let mut active = vec![0; n as usize + 1];
            active_compact(&params, &hits, &work, &mut active);
            // a local increment's schedule, two workgroups per dimension at most
            let mut plan = fresh_plan(&params, 100);
            plan[PLAN_SEARCHED] = 1;
            plan[PLAN_MAX_DIM] = 2;
            crate::cpu::schedule::schedule(&mut plan, &mut [0; 32], &mut [0; 3], active[0]);
            let expect: Vec<u32> = (0..n)
                .filter(|&i| visited(&params, &hits, i as usize))
                .collect();
            assert_eq!(active[0] as usize, expect.len());
            assert_eq!(&active[1..1 + expect.len()], &expect[..]);
            let s = PLAN_SLOTS + ACTIVE_SLOT * PLAN_SLOT_WORDS;
            let groups = (expect.len() as u32).div_ceil(ITEM_WORKGROUP);
            let size = &plan[s + 4..s + 7];
            if groups == 0 {
                assert_eq!(size, [0, 0, 0]);
            } else {
                assert!(size[0] <= 2 && size[0] * size[1] >= groups && size[2] == 1);
            }
        }
    }
}
