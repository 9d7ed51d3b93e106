//! CPU mirror of `shaders/contact_sort.wgsl`: slaves in contact grouped by facet, in order.

use crate::penalty::layout::{ContactOut, PenaltyParams, CSTATUS_MASK, CSTATUS_OPEN};
use crate::search::layout::GpuHit;

/// Counts the slaves in contact with each facet (WGSL: `count_by_facet`).
pub fn count_by_facet(pp: &PenaltyParams, hits: &[GpuHit], out: &[ContactOut], counts: &mut [u32]) {
    for i in 0..pp.n_slaves as usize {
        if out[i].status & CSTATUS_MASK != CSTATUS_OPEN {
            counts[hits[i].facet as usize] += 1;
        }
    }
}

/// Writes each slave in contact into its facet's range (WGSL: `scatter_by_facet`).
pub fn scatter_by_facet(
    pp: &PenaltyParams,
    hits: &[GpuHit],
    out: &[ContactOut],
    cursor: &mut [u32],
    facet_slaves: &mut [u32],
) {
    for i in 0..pp.n_slaves as usize {
        if out[i].status & CSTATUS_MASK != CSTATUS_OPEN {
            let f = hits[i].facet as usize;
            facet_slaves[cursor[f] as usize] = i as u32;
            cursor[f] += 1;
        }
    }
}

/// Orders each facet's slaves increasingly (WGSL: `sort_by_facet`).
pub fn sort_by_facet(pp: &PenaltyParams, starts: &[u32], facet_slaves: &mut [u32]) {
    for f in 0..pp.n_facets as usize {
        let (s, e) = (starts[f] as usize, starts[f + 1] as usize);
        facet_slaves[s..e].sort_unstable();
    }
}
