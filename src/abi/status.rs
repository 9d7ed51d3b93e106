//! The status words the kernels raise, in one table: each word's index, what it holds, which
//! passes own it (and so reset it at the start of their part of an increment) and the value they
//! reset it to; and [`Status`], the words read back after an increment with typed readers. The
//! indices are the `STATUS_*` constants above (WGSL twins in
//! `shaders/common.wgsl`).

/// Status word: the motion since the last global search used up the budget; the local
/// increment is run again with a global search (WGSL: `STATUS_BUDGET_EXCEEDED`).
pub const STATUS_BUDGET_EXCEEDED: usize = 2;
/// Status word: the most local-search iterations any slave took (WGSL: `STATUS_LOCAL_ITERATIONS`).
pub const STATUS_LOCAL_ITERATIONS: usize = 3;
/// Status word: bits of the smallest stable increment, a positive f32 (WGSL: `STATUS_DT_STABLE`).
pub const STATUS_DT_STABLE: usize = 4;
/// Status word: bits of the smallest approach limit, a positive f32 (WGSL: `STATUS_DT_APPROACH`).
pub const STATUS_DT_APPROACH: usize = 5;
/// Status word: slave nodes in contact (WGSL: `STATUS_ACTIVE`).
pub const STATUS_ACTIVE: usize = 6;
/// Status word: slave nodes slipping (WGSL: `STATUS_SLIPPING`).
pub const STATUS_SLIPPING: usize = 7;
/// Status word: bits of the largest motion since the last global search, a positive f32
/// (WGSL: `STATUS_MOTION`).
pub const STATUS_MOTION: usize = 8;
/// Status word: slaves whose local walk hit the iteration cap (WGSL: `STATUS_LOCAL_CAPPED`).
pub const STATUS_LOCAL_CAPPED: usize = 9;
/// Status word: self-contact slaves with unconnected facets within the radius
/// (WGSL: `STATUS_CROWDED`).
pub const STATUS_CROWDED: usize = 10;
/// Status word: slaves the local search walked (past their skin, or with none) this increment
/// (WGSL: `STATUS_LOCAL_WALKS`).
pub const STATUS_LOCAL_WALKS: usize = 11;
/// Status word: small sliding, slave nodes that slid more than an element length from their
/// anchor (WGSL: `STATUS_SLID_TOO_FAR`).
pub const STATUS_SLID_TOO_FAR: usize = 12;
/// Status word: small sliding, anchors whose tangent plane is more than 10° off the deformed
/// facet (WGSL: `STATUS_PLANE_OFF`).
pub const STATUS_PLANE_OFF: usize = 13;
/// Status word: bits of the largest overclosure (−gap ≥ 0, a non-negative f32) of the penalty
/// springs carrying force this increment (WGSL: `STATUS_MAX_OVERCLOSURE`).
pub const STATUS_MAX_OVERCLOSURE: usize = 14;
/// Status word: slave nodes whose velocity relative to the master near them carries them
/// farther than the search radius within the increment (the penalty pass; WGSL:
/// `STATUS_FAST`).
pub const STATUS_FAST: usize = 15;
/// Status word: bits of the largest force component magnitude of a penalty spring in contact
/// this increment (a non-negative f32): the gather's fixed-point force scale
/// (WGSL: `STATUS_FORCE_SCALE`).
pub const STATUS_FORCE_SCALE: usize = 16;
/// Status word: bits of the largest bound share of a penalty spring in contact this increment:
/// the gather's fixed-point row scale (WGSL: `STATUS_ROW_SCALE`).
pub const STATUS_ROW_SCALE: usize = 17;
/// Status word: slaves whose walk of the search tree reached its visit cap (`WALK_VISITS`); the
/// facets it had not reached were projected in bounded chunks, so the search stayed exact
/// (WGSL: `STATUS_FALLBACK`).
pub const STATUS_FALLBACK: usize = 18;
/// Status word: master facets collapsed at the global search's positions, skipped by the search
/// (WGSL: `STATUS_COLLAPSED`; counted by tree_refit).
pub const STATUS_COLLAPSED: usize = 19;
/// Status words: order-preserving bits (`ordered_bits`) of the box of the master nodes the
/// increment's positions put the master in, min xyz then max xyz (WGSL: `STATUS_BOX`; raised by
/// to_local, read by the schedule).
pub const STATUS_BOX: usize = 20;
/// Status word: the lowest model node with a NaN or infinite coordinate in the increment's
/// positions, `u32::MAX` when none (WGSL: `STATUS_NONFINITE`; raised by to_local).
pub const STATUS_NONFINITE: usize = 26;
/// Status word: bits of the largest relative motion over the search radius of those slaves, a
/// positive f32 (WGSL: `STATUS_FAST_RATIO`).
pub const STATUS_FAST_RATIO: usize = 27;
/// Status word: bits of the largest motion of a master node since the last global search,
/// relative to the pair's reference node, a positive f32 (WGSL: `STATUS_MASTER_MOTION`; the
/// local search's skins read it).
pub const STATUS_MASTER_MOTION: usize = 28;
/// Number of status words.
pub const STATUS_WORDS: usize = 29;

/// Which part of an increment resets a status word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    /// The search passes (global or local, anchors, positions from the device).
    Search,
    /// The penalty passes.
    Penalty,
    /// No pass writes it.
    Unused,
}

/// One status word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusWord {
    /// Its index in the status buffer.
    pub index: usize,
    /// What it holds.
    pub name: &'static str,
    /// Who resets it.
    pub owner: Owner,
    /// The value it is reset to (an f32's bits for the increments).
    pub reset: u32,
}

const fn w(index: usize, name: &'static str, owner: Owner, reset: u32) -> StatusWord {
    StatusWord {
        index,
        name,
        owner,
        reset,
    }
}

/// The bits of `NO_LIMIT` (the largest finite f32), the reset value of the increments.
const NO_LIMIT_BITS: u32 = 0x7f7f_ffff;

/// Every status word, in index order.
pub const STATUS_TABLE: [StatusWord; STATUS_WORDS] = [
    w(0, "unused", Owner::Unused, 0),
    w(1, "unused", Owner::Unused, 0),
    w(
        STATUS_BUDGET_EXCEEDED,
        "motion budget used up",
        Owner::Search,
        0,
    ),
    w(
        STATUS_LOCAL_ITERATIONS,
        "most local-search iterations",
        Owner::Search,
        0,
    ),
    w(
        STATUS_DT_STABLE,
        "smallest stable increment (f32 bits)",
        Owner::Penalty,
        NO_LIMIT_BITS,
    ),
    w(
        STATUS_DT_APPROACH,
        "smallest approach limit (f32 bits)",
        Owner::Penalty,
        NO_LIMIT_BITS,
    ),
    w(STATUS_ACTIVE, "slaves in contact", Owner::Penalty, 0),
    w(STATUS_SLIPPING, "slaves slipping", Owner::Penalty, 0),
    w(
        STATUS_MOTION,
        "largest motion since the global search (f32 bits)",
        Owner::Search,
        0,
    ),
    w(
        STATUS_LOCAL_CAPPED,
        "local walks at the iteration cap",
        Owner::Search,
        0,
    ),
    w(
        STATUS_CROWDED,
        "self-contact slaves crowded",
        Owner::Search,
        0,
    ),
    w(
        STATUS_LOCAL_WALKS,
        "slaves the local search walked",
        Owner::Search,
        0,
    ),
    w(
        STATUS_SLID_TOO_FAR,
        "anchors slid beyond an element",
        Owner::Search,
        0,
    ),
    w(
        STATUS_PLANE_OFF,
        "anchor planes off the facet",
        Owner::Search,
        0,
    ),
    w(
        STATUS_MAX_OVERCLOSURE,
        "largest overclosure (f32 bits)",
        Owner::Penalty,
        0,
    ),
    w(
        STATUS_FAST,
        "slaves moving beyond the radius relative to the master",
        Owner::Penalty,
        0,
    ),
    w(
        STATUS_FORCE_SCALE,
        "gather's force scale (f32 bits)",
        Owner::Penalty,
        0,
    ),
    w(
        STATUS_ROW_SCALE,
        "gather's row scale (f32 bits)",
        Owner::Penalty,
        0,
    ),
    w(
        STATUS_FALLBACK,
        "tree walks finished by chunks",
        Owner::Search,
        0,
    ),
    w(
        STATUS_COLLAPSED,
        "master facets collapsed at the global search",
        Owner::Search,
        0,
    ),
    w(
        STATUS_BOX,
        "master box min x (ordered bits)",
        Owner::Search,
        u32::MAX,
    ),
    w(
        STATUS_BOX + 1,
        "master box min y (ordered bits)",
        Owner::Search,
        u32::MAX,
    ),
    w(
        STATUS_BOX + 2,
        "master box min z (ordered bits)",
        Owner::Search,
        u32::MAX,
    ),
    w(
        STATUS_BOX + 3,
        "master box max x (ordered bits)",
        Owner::Search,
        0,
    ),
    w(
        STATUS_BOX + 4,
        "master box max y (ordered bits)",
        Owner::Search,
        0,
    ),
    w(
        STATUS_BOX + 5,
        "master box max z (ordered bits)",
        Owner::Search,
        0,
    ),
    w(
        STATUS_NONFINITE,
        "lowest node with a non-finite coordinate",
        Owner::Search,
        u32::MAX,
    ),
    w(
        STATUS_FAST_RATIO,
        "largest relative motion over the radius (f32 bits)",
        Owner::Penalty,
        0,
    ),
    w(
        STATUS_MASTER_MOTION,
        "largest master motion since the global search (f32 bits)",
        Owner::Search,
        0,
    ),
];

/// Every word at its reset value (the image the GPU executors copy resets from).
pub fn reset_image() -> [u32; STATUS_WORDS] {
    STATUS_TABLE.map(|w| w.reset)
}

/// The runs of consecutive words `owner` resets, as (first word, number of words).
pub fn owned_runs(owner: Owner) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for w in STATUS_TABLE.iter().filter(|w| w.owner == owner) {
        match runs.last_mut() {
            Some((s, n)) if *s + *n == w.index => *n += 1,
            _ => runs.push((w.index, 1)),
        }
    }
    runs
}

/// Sets the words `owner` resets to their reset values.
pub fn reset(status: &mut [u32; STATUS_WORDS], owner: Owner) {
    for w in STATUS_TABLE.iter().filter(|w| w.owner == owner) {
        status[w.index] = w.reset;
    }
}

/// The status words after an increment, read by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Status(pub [u32; STATUS_WORDS]);

impl Status {
    fn f32(&self, i: usize) -> f32 {
        f32::from_bits(self.0[i])
    }
    /// Slaves whose walk of the search tree reached its visit cap (finished by chunks).
    pub fn fallbacks(&self) -> u32 {
        self.0[STATUS_FALLBACK]
    }
    /// The motion since the last global search used up the budget.
    pub fn budget_exceeded(&self) -> bool {
        self.0[STATUS_BUDGET_EXCEEDED] != 0
    }
    /// The most local-search iterations any slave took.
    pub fn local_iterations(&self) -> u32 {
        self.0[STATUS_LOCAL_ITERATIONS]
    }
    /// Slaves whose local walk hit the iteration cap.
    pub fn local_capped(&self) -> u32 {
        self.0[STATUS_LOCAL_CAPPED]
    }
    /// Slaves the local search walked (the others were within their skin).
    pub fn local_walks(&self) -> u32 {
        self.0[STATUS_LOCAL_WALKS]
    }
    /// The largest motion since the last global search (grid units of length).
    pub fn motion(&self) -> f32 {
        self.f32(STATUS_MOTION)
    }
    /// Self-contact slaves with unconnected facets near and facing them.
    pub fn crowded(&self) -> u32 {
        self.0[STATUS_CROWDED]
    }
    /// Master facets collapsed at the global search's positions (skipped).
    pub fn collapsed(&self) -> u32 {
        self.0[STATUS_COLLAPSED]
    }
    /// Small sliding: anchors slid more than an element length.
    pub fn slid_too_far(&self) -> u32 {
        self.0[STATUS_SLID_TOO_FAR]
    }
    /// Small sliding: anchor planes more than 10° off the deformed facet.
    pub fn plane_off(&self) -> u32 {
        self.0[STATUS_PLANE_OFF]
    }
    /// The smallest stable increment of the penalty springs (`NO_LIMIT` when none).
    pub fn dt_stable(&self) -> f32 {
        self.f32(STATUS_DT_STABLE)
    }
    /// The smallest approach limit (`NO_LIMIT` when none).
    pub fn dt_approach(&self) -> f32 {
        self.f32(STATUS_DT_APPROACH)
    }
    /// Slave nodes in contact.
    pub fn active(&self) -> u32 {
        self.0[STATUS_ACTIVE]
    }
    /// Slave nodes slipping.
    pub fn slipping(&self) -> u32 {
        self.0[STATUS_SLIPPING]
    }
    /// The largest overclosure of a penalty spring carrying force (model length, ≥ 0).
    pub fn max_overclosure(&self) -> f32 {
        self.f32(STATUS_MAX_OVERCLOSURE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_index_order_and_resets_by_owner() {
        for (i, w) in STATUS_TABLE.iter().enumerate() {
            assert_eq!(w.index, i, "{}", w.name);
        }
        assert_eq!(NO_LIMIT_BITS, crate::abi::penalty::NO_LIMIT.to_bits());
        assert_eq!(owned_runs(Owner::Penalty), vec![(4, 4), (14, 4), (27, 1)]);
        let mut s = [7u32; STATUS_WORDS];
        reset(&mut s, Owner::Penalty);
        assert_eq!(Status(s).dt_stable(), crate::abi::penalty::NO_LIMIT);
        assert_eq!(s[STATUS_FALLBACK], 7, "the search's words are left alone");
        reset(&mut s, Owner::Search);
        assert_eq!(s[STATUS_FALLBACK], 0);
        assert_eq!(s[0], 7, "an unused word is nobody's");
    }
}
