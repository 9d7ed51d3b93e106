//! The statistics of a device-resident increment (WGSL twin: the `STAT_*` words of
//! `shaders/stats.wgsl`): [`IncrementStats`], its words by name and the images it is reset to.

use bytemuck::{Pod, Zeroable};

/// What a device-resident increment leaves in its statistics buffer (76 bytes, WGSL twin: the
/// `STAT_*` words of stats.wgsl). A host integrator running on the device can bind the buffer
/// and read `stable_dt` there; the host reads it a few increments late without waiting.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct IncrementStats {
    /// The largest increment the penalty springs allow (s), as `StepReport::stable_dt`;
    /// `NO_LIMIT` (f32::MAX) when no spring limits it.
    pub stable_dt: f32,
    /// The approach limit (s), as `StepReport::approach_dt`; `NO_LIMIT` when none.
    pub approach_dt: f32,
    /// The largest overclosure of a spring carrying force (model length units, ≥ 0).
    pub max_overclosure: f32,
    /// The node-wise bound on the springs' ω² (1/s²).
    pub omega2: f32,
    /// Slave nodes in contact.
    pub active: u32,
    /// Of which slipping.
    pub slipping: u32,
    /// Searches that ran globally this increment.
    pub global_searches: u32,
    /// Of which because the motion budget was used up.
    pub budget_searches: u32,
    /// Slaves whose walk of the search tree reached its visit cap and was finished by the
    /// bounded chunks (the search stayed exact; many mean the tree fits the surface badly).
    pub fallbacks: u32,
    /// Master facets collapsed at a global search's positions (skipped by the search).
    pub collapsed: u32,
    /// The lowest model node with a NaN or infinite coordinate, `u32::MAX` when none.
    pub nonfinite_node: u32,
    /// Local walks stopped at the iteration cap.
    pub local_capped: u32,
    /// Slaves the local search walked this increment; the other tracked slaves were within
    /// their skin and projected on their facet alone.
    pub local_walks: u32,
    /// The largest motion since a global search (model length units).
    pub motion: f32,
    /// Global searches whose master box could not be taken (no finite master node), since
    /// the start (the last box was kept).
    pub fit_failed: u32,
    /// Slave nodes whose velocity relative to the master near them (its velocity at their
    /// contact point, or the pair's reference master node's for a slave with no facet within
    /// the radius) carries them farther than their pair's search radius within this increment:
    /// the search cannot follow them and they may pass through the master unseen (tunnelling).
    pub fast_nodes: u32,
    /// The largest such relative motion over its pair's search radius (> 1 when `fast_nodes`
    /// is not 0; 0 when none).
    pub fast_ratio: f32,
    /// The largest contact damping ratio of the penalty pairs (constant).
    pub damping: f32,
    /// Increments completed since the start (this one included).
    pub increment: u32,
}
const _: () = assert!(std::mem::size_of::<IncrementStats>() == 76);

/// Bytes of [`IncrementStats`].
pub const STATS_BYTES: u64 = std::mem::size_of::<IncrementStats>() as u64;

/// Words of [`IncrementStats`].
pub const STATS_WORDS: usize = std::mem::size_of::<IncrementStats>() / 4;

/// Words of [`IncrementStats`] reset at the start of every increment (the last two persist).
pub const STATS_RESET_WORDS: usize = 17;

// Words of the statistics (WGSL: `STAT_*`), in [`IncrementStats`] order.
/// The word of [`IncrementStats::stable_dt`] (WGSL: `STAT_STABLE_DT`).
pub const STAT_STABLE_DT: usize = 0;
/// The word of [`IncrementStats::approach_dt`] (WGSL: `STAT_APPROACH_DT`).
pub const STAT_APPROACH_DT: usize = 1;
/// The word of [`IncrementStats::max_overclosure`] (WGSL: `STAT_MAX_OVERCLOSURE`).
pub const STAT_MAX_OVERCLOSURE: usize = 2;
/// The word of [`IncrementStats::omega2`] (WGSL: `STAT_OMEGA2`).
pub const STAT_OMEGA2: usize = 3;
/// The word of [`IncrementStats::active`] (WGSL: `STAT_ACTIVE`).
pub const STAT_ACTIVE: usize = 4;
/// The word of [`IncrementStats::slipping`] (WGSL: `STAT_SLIPPING`).
pub const STAT_SLIPPING: usize = 5;
/// The word of [`IncrementStats::global_searches`] (WGSL: `STAT_GLOBAL`).
pub const STAT_GLOBAL: usize = 6;
/// The word of [`IncrementStats::budget_searches`] (WGSL: `STAT_BUDGET`).
pub const STAT_BUDGET: usize = 7;
/// The word of [`IncrementStats::fallbacks`] (WGSL: `STAT_FALLBACKS`).
pub const STAT_FALLBACKS: usize = 8;
/// The word of [`IncrementStats::collapsed`] (WGSL: `STAT_COLLAPSED`).
pub const STAT_COLLAPSED: usize = 9;
/// The word of [`IncrementStats::nonfinite_node`] (WGSL: `STAT_NONFINITE`).
pub const STAT_NONFINITE: usize = 10;
/// The word of [`IncrementStats::local_capped`] (WGSL: `STAT_LOCAL_CAPPED`).
pub const STAT_LOCAL_CAPPED: usize = 11;
/// The word of [`IncrementStats::local_walks`] (WGSL: `STAT_LOCAL_WALKS`).
pub const STAT_LOCAL_WALKS: usize = 12;
/// The word of [`IncrementStats::motion`] (WGSL: `STAT_MOTION`).
pub const STAT_MOTION: usize = 13;
/// The word of [`IncrementStats::fit_failed`] (WGSL: `STAT_FIT_FAILED`).
pub const STAT_FIT_FAILED: usize = 14;
/// The word of [`IncrementStats::fast_nodes`] (WGSL: `STAT_FAST`).
pub const STAT_FAST: usize = 15;
/// The word of [`IncrementStats::fast_ratio`] (WGSL: `STAT_FAST_RATIO`).
pub const STAT_FAST_RATIO: usize = 16;
/// The word of [`IncrementStats::damping`] (WGSL: `STAT_DAMPING`).
pub const STAT_DAMPING: usize = 17;
/// The word of [`IncrementStats::increment`] (WGSL: `STAT_INCREMENT`).
pub const STAT_INCREMENT: usize = 18;

/// The reset values of the statistics' first [`STATS_RESET_WORDS`] words.
pub fn reset_image() -> [u32; STATS_RESET_WORDS] {
    let mut w = [0u32; STATS_RESET_WORDS];
    w[STAT_STABLE_DT] = super::penalty::NO_LIMIT.to_bits();
    w[STAT_APPROACH_DT] = super::penalty::NO_LIMIT.to_bits();
    w[STAT_NONFINITE] = u32::MAX;
    w
}

/// The statistics before the first increment: the reset words, and the largest contact
/// damping ratio `damping` of the penalty pairs (a constant word).
pub fn first_image(damping: f32) -> [u32; STATS_WORDS] {
    let mut w = [0u32; STATS_WORDS];
    w[..STATS_RESET_WORDS].copy_from_slice(&reset_image());
    w[STAT_DAMPING] = damping.to_bits();
    w
}
