//! WGSL sources, embedded at build time. Each kernel is `common.wgsl` (and, for the penalty
//! kernels, `penalty_common.wgsl`) followed by its own file.

/// Shared structs, constants and geometry.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");

/// Structs and constants of the penalty kernels.
pub const PENALTY_COMMON: &str = include_str!("../../shaders/penalty_common.wgsl");

/// (file stem, source, needs `penalty_common.wgsl`) of every kernel file.
#[rustfmt::skip]
pub const KERNELS: [(&str, &str, bool); 13] = [
    ("bin_count", include_str!("../../shaders/bin_count.wgsl"), false),
    ("scan", include_str!("../../shaders/scan.wgsl"), false),
    ("bin_scatter", include_str!("../../shaders/bin_scatter.wgsl"), false),
    ("bin_sort", include_str!("../../shaders/bin_sort.wgsl"), false),
    ("nearest_facet", include_str!("../../shaders/nearest_facet.wgsl"), false),
    ("local_search", include_str!("../../shaders/local_search.wgsl"), false),
    ("motion", include_str!("../../shaders/motion.wgsl"), false),
    ("to_local", include_str!("../../shaders/to_local.wgsl"), false),
    ("anchor", include_str!("../../shaders/anchor.wgsl"), false),
    ("nodal_normals", include_str!("../../shaders/nodal_normals.wgsl"), true),
    ("penalty", include_str!("../../shaders/penalty.wgsl"), true),
    ("contact_sort", include_str!("../../shaders/contact_sort.wgsl"), true),
    ("gather", include_str!("../../shaders/gather.wgsl"), true),
];

/// The full source of kernel file `stem` (its preludes prepended), or `None` if unknown.
pub fn source(stem: &str) -> Option<String> {
    KERNELS
        .iter()
        .find(|(s, _, _)| *s == stem)
        .map(|(_, src, penalty)| {
            if *penalty {
                format!("{COMMON}\n{PENALTY_COMMON}\n{src}")
            } else {
                format!("{COMMON}\n{src}")
            }
        })
}
