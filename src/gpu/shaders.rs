//! WGSL sources, embedded at build time. Each kernel is `common.wgsl` followed by its own file.

/// Shared structs, constants and geometry.
pub const COMMON: &str = include_str!("../../shaders/common.wgsl");

/// (file stem, source) of every kernel file.
pub const KERNELS: [(&str, &str); 5] = [
    ("bin_count", include_str!("../../shaders/bin_count.wgsl")),
    ("scan", include_str!("../../shaders/scan.wgsl")),
    (
        "bin_scatter",
        include_str!("../../shaders/bin_scatter.wgsl"),
    ),
    ("bin_sort", include_str!("../../shaders/bin_sort.wgsl")),
    (
        "nearest_facet",
        include_str!("../../shaders/nearest_facet.wgsl"),
    ),
];

/// The full source of kernel file `stem` (common.wgsl prepended), or `None` if unknown.
pub fn source(stem: &str) -> Option<String> {
    KERNELS
        .iter()
        .find(|(s, _)| *s == stem)
        .map(|(_, src)| format!("{COMMON}\n{src}"))
}
