//! The compute passes of an increment as the executors record them: each [`Group`] is a few
//! kernel entry points ([`Pass`]es) dispatched together under one label — the key of
//! `Traffic::dispatches`, the name of a GPU timestamp, and the row of a benchmark. The executors
//! take their labels from here (never a string of their own), and the benchmarks name the groups
//! they report by these constants, so a label cannot drift from what an increment records.

use super::passes::*;

/// Dispatches recorded under one label.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    /// The label: the key of `Traffic::dispatches` and of the GPU timestamps.
    pub label: &'static str,
    /// The passes it may dispatch, in order.
    pub passes: &'static [&'static Pass],
}

// ---- the device-resident increment (the plan every increment runs) ----

/// Small sliding: positions into the frame, then each slave's anchor evaluated.
pub const TO_LOCAL_ANCHOR: Group = Group {
    label: "to_local + anchor",
    passes: &[&TO_LOCAL, &ANCHOR],
};
/// Positions into the frame with the motion budget, and the schedule's choice of search.
pub const MOTION_SCHEDULE: Group = Group {
    label: "motion + schedule",
    passes: &[&MOTION, &SCHEDULE],
};
/// The local search (indirect: no workgroups when the schedule chose a global search).
pub const LOCAL: Group = Group {
    label: "local_search",
    passes: &[&LOCAL_SEARCH],
};
/// The global search (indirect: no workgroups in a local increment) on every node in the
/// frame, and the active slaves it leaves compacted for the local increments.
pub const GLOBAL_SEARCH: Group = Group {
    label: "global search",
    passes: &[
        &TO_LOCAL,
        &TREE_REFIT,
        &BUCKET_CLEAR,
        &BUCKET_COUNT,
        &BUCKET_FILL,
        &WALK_START,
        &NEAREST_WALK,
        &BUCKET_WALK,
        &SCAN_BLOCKS,
        &SCAN_ADD,
        &NEAREST_ARGS,
        &NEAREST_CHUNKS,
        &NEAREST_TIES,
        &NEAREST_CROWDED,
        &BUCKET_CROWDED,
        &NEAREST_FACET,
        &SET_REFERENCE,
        &ACTIVE_MARK,
        &ACTIVE_COMPACT,
    ],
};
/// Nodal normals of the master (of every master node for small sliding; otherwise of those
/// the springs read, marked first), then the penalty springs (every slave's in a global
/// increment, the active slaves' in a local one).
pub const NORMALS_PENALTY: Group = Group {
    label: "nodal_normals + penalty",
    passes: &[
        &NODAL_NORMALS,
        &NEED_NORMALS,
        &NODAL_NORMALS_NEEDED,
        &PENALTY,
        &PENALTY_ACTIVE,
    ],
};
/// The forces summed per pair node in fixed point and added into the caller's buffer.
pub const SCATTER_GATHER_ADD: Group = Group {
    label: "scatter_forces + gather + add_forces",
    passes: &[
        &SCATTER_FORCES,
        &SCATTER_FORCES_ACTIVE,
        &GATHER,
        &GATHER_ACTIVE,
        &ADD_FORCES,
        &ADD_FORCES_ACTIVE,
    ],
};
/// A pair's status words into the increment's statistics.
pub const STATS_PAIR: Group = Group {
    label: "pair_stats",
    passes: &[&PAIR_STATS],
};
/// The bound's largest row and the stable increment.
pub const STATS_FINISH: Group = Group {
    label: "finish_stats",
    passes: &[&FINISH_STATS],
};
/// A host program's central-difference integrator on the device.
pub const INTEGRATOR: Group = Group {
    label: "integrate",
    passes: &[&INTEGRATE],
};

/// Every group, each label once.
pub const GROUPS: [Group; 9] = [
    TO_LOCAL_ANCHOR,
    MOTION_SCHEDULE,
    LOCAL,
    GLOBAL_SEARCH,
    NORMALS_PENALTY,
    SCATTER_GATHER_ADD,
    STATS_PAIR,
    STATS_FINISH,
    INTEGRATOR,
];

/// The group labelled `label`, if one is declared.
pub fn by_label(label: &str) -> Option<&'static Group> {
    GROUPS.iter().find(|g| g.label == label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_unique_and_every_pass_is_in_a_group() {
        for (i, g) in GROUPS.iter().enumerate() {
            assert!(
                GROUPS[..i].iter().all(|h| h.label != g.label),
                "label '{}' twice",
                g.label
            );
            for p in g.passes {
                assert!(PASSES.contains(p), "{}: {} undeclared", g.label, p.entry);
            }
        }
        for p in &PASSES {
            assert!(
                GROUPS.iter().any(|g| g.passes.contains(&p)),
                "{} is in no group",
                p.entry
            );
        }
    }
}
