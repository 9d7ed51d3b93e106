//! CPU mirror of `shaders/bin_sort.wgsl`: order each cell's facet ids increasingly.

use crate::search::layout::SearchParams;

/// One "invocation" per cell: insertion sort of `entries[starts[c]..starts[c+1]]`.
pub fn bin_sort(params: &SearchParams, starts: &[u32], entries: &mut [u32]) {
    if starts[params.n_cells as usize] > params.entry_capacity {
        return;
    }
    for c in 0..params.n_cells as usize {
        let (s, e) = (starts[c] as usize, starts[c + 1] as usize);
        for i in s + 1..e {
            let key = entries[i];
            let mut j = i;
            while j > s && entries[j - 1] > key {
                entries[j] = entries[j - 1];
                j -= 1;
            }
            entries[j] = key;
        }
    }
}
