//! Tests of the increment's entries: kernels, groups, slots.

use super::*;
use crate::abi::passes::{self, Pass};

/// The plan's slots hold the largest search there can be: a tree of 32 levels (one refit
/// pass per level, 33) and the most slaves a u32 counts (four scan levels); with one level
/// fewer per pass this was where 16 slots ran out.
#[test]
fn the_largest_search_fits_the_plan() {
    for (levels, slaves) in [(0, 1), (17, 1_000_000), (32, u32::MAX - 1)] {
        for flags in [0, FLAG_BUCKETS] {
            let params = SearchParams {
                tree_levels: levels,
                n_slaves: slaves,
                n_facets: ((1u64 << levels) - 1).min(u32::MAX as u64) as u32,
                flags,
                ..bytemuck::Zeroable::zeroed()
            };
            let (plan, slots) = initial_plan(&params, 100, slaves, slaves, 65_535)
                .unwrap_or_else(|e| panic!("{levels} levels, {slaves} slaves: {e}"));
            // the buckets refit the tree's leaves alone
            let refits = if flags == 0 { levels as usize + 1 } else { 1 };
            assert_eq!(slots.tree_passes.len(), refits);
            assert!(plan[PLAN_N_SLOTS] as usize <= MAX_PLAN_SLOTS);
        }
    }
}

/// `Kernel::ALL` is every pass of `abi::passes::PASSES` but the host integrator's, in
/// order, and each kernel is its pass once (but the bucket words' scan, the scan's passes on
/// another buffer).
#[test]
fn every_pass_but_the_integrator_is_a_kernel() {
    let passes: Vec<&Pass> = passes::PASSES
        .iter()
        .filter(|p| p.entry != "integrate")
        .collect();
    let kernels: Vec<&Pass> = Kernel::ALL
        .iter()
        .filter(|k| !matches!(k, Kernel::BucketScanBlocks | Kernel::BucketScanAdd))
        .map(|k| k.pass())
        .collect();
    assert_eq!(kernels, passes);
}

/// Every entry's kernel is a pass of the group it is recorded under, so the benchmarks'
/// rows and the timestamps name what ran.
#[test]
fn entries_belong_to_their_groups() {
    for (anchored, self_contact, local_only, gather_active, buckets) in [
        (false, false, false, false, false),
        (false, true, false, false, false),
        (true, false, false, false, false),
        (false, false, true, false, false),
        (false, false, false, true, false),
        (false, false, true, true, false),
        (false, false, false, false, true),
        (false, true, false, true, true),
    ] {
        let flags = if buckets { FLAG_BUCKETS } else { 0 };
        let (_, slots) = initial_plan(
            &SearchParams {
                tree_levels: 5,
                n_slaves: 1000,
                n_facets: 30,
                flags,
                ..bytemuck::Zeroable::zeroed()
            },
            100,
            1200,
            2000,
            65_535,
        )
        .unwrap();
        assert_eq!(slots.bucket_levels.is_empty(), !buckets);
        let shape = PairShape {
            anchored,
            self_contact,
            buckets,
            local_only,
            global_only: false,
            n_nodes: 2000,
            n_motion_nodes: 1200,
            n_slaves: 1000,
            n_pair_nodes: 1200,
            gather_active,
            slots: slots.clone(),
        };
        let entries = increment(&[shape.clone(), shape]);
        for e in &entries {
            assert!(
                e.group.passes.iter().any(|p| *p == e.kernel.pass()),
                "{:?} under {}",
                e.kernel,
                e.group.label
            );
        }
        let globals = entries
            .iter()
            .filter(|e| e.kernel == Kernel::TreeRefit)
            .count();
        // the tree's six refit passes, or its leaves alone for the buckets
        let refits = if buckets { 1 } else { 6 };
        assert_eq!(
            globals,
            if anchored || local_only {
                0
            } else {
                2 * refits
            }
        );
        let walks = |k: Kernel| entries.iter().filter(|e| e.kernel == k).count();
        let global = !(anchored || local_only);
        assert_eq!(walks(Kernel::BucketWalk) > 0, global && buckets);
        assert_eq!(walks(Kernel::NearestWalk) > 0, global && !buckets);
        assert_eq!(
            walks(Kernel::BucketCrowded) > 0,
            global && buckets && self_contact
        );
    }
}
