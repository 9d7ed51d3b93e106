//! WGSL sources, embedded at build time. Each kernel is `common.wgsl`, its prelude
//! (`search_common.wgsl` for the search kernels that read facets and adjacency,
//! `penalty_common.wgsl` for the penalty kernels), then its own file.

/// Shared structs, constants and geometry.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");

/// Structs and constants of the penalty kernels.
pub const PENALTY_COMMON: &str = include_str!("../../shaders/penalty_common.wgsl");
/// Functions of the search kernels that read facets and adjacency (projection, self-contact
/// exclusion, free boundaries).
pub const SEARCH_COMMON: &str = include_str!("../../shaders/search_common.wgsl");

/// The prelude a kernel needs after `common.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prelude {
    /// None.
    None,
    /// `search_common.wgsl`.
    Search,
    /// `penalty_common.wgsl`.
    Penalty,
}

/// (file stem, source, prelude) of every kernel file.
#[rustfmt::skip]
pub const KERNELS: [(&str, &str, Prelude); 14] = [
    ("tree", include_str!("../../shaders/tree.wgsl"), Prelude::None),
    ("scan", include_str!("../../shaders/scan.wgsl"), Prelude::None),
    ("nearest_facet", include_str!("../../shaders/nearest_facet.wgsl"), Prelude::Search),
    ("buckets", include_str!("../../shaders/buckets.wgsl"), Prelude::Search),
    ("local_search", include_str!("../../shaders/local_search.wgsl"), Prelude::Search),
    ("motion", include_str!("../../shaders/motion.wgsl"), Prelude::None),
    ("active", include_str!("../../shaders/active.wgsl"), Prelude::None),
    ("anchor", include_str!("../../shaders/anchor.wgsl"), Prelude::None),
    ("nodal_normals", include_str!("../../shaders/nodal_normals.wgsl"), Prelude::Penalty),
    ("penalty", include_str!("../../shaders/penalty.wgsl"), Prelude::Penalty),
    ("gather", include_str!("../../shaders/gather.wgsl"), Prelude::Penalty),
    ("schedule", include_str!("../../shaders/schedule.wgsl"), Prelude::None),
    ("stats", include_str!("../../shaders/stats.wgsl"), Prelude::None),
    ("integrate", include_str!("../../shaders/integrate.wgsl"), Prelude::None),
];

/// The full source of kernel file `stem` (its preludes prepended), or `None` if unknown.
pub fn source(stem: &str) -> Option<String> {
    KERNELS
        .iter()
        .find(|(s, _, _)| *s == stem)
        .map(|(_, src, prelude)| match prelude {
            Prelude::None => format!("{COMMON}\n{src}"),
            Prelude::Search => format!("{COMMON}\n{SEARCH_COMMON}\n{src}"),
            Prelude::Penalty => format!("{COMMON}\n{PENALTY_COMMON}\n{src}"),
        })
}
