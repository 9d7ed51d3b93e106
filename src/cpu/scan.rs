//! CPU mirror of `shaders/scan.wgsl`: blocked exclusive prefix sum, level by level.

use crate::abi::search::{ScanLevels, ScanParams, SCAN_BLOCK};

/// Scans each block of `sp.n` words at `sp.in_offset` exclusively, in place, and writes each
/// block's total to `data[sp.sums_offset + block]` (WGSL: `scan_blocks`).
pub fn scan_blocks(sp: &ScanParams, data: &mut [u32]) {
    let blocks = sp.n.div_ceil(SCAN_BLOCK);
    for block in 0..blocks {
        let mut sum = 0u32;
        let start = block * SCAN_BLOCK;
        let end = (start + SCAN_BLOCK).min(sp.n);
        for idx in start..end {
            let i = (sp.in_offset + idx) as usize;
            let x = data[i];
            data[i] = sum;
            sum = sum.wrapping_add(x);
        }
        data[(sp.sums_offset + block) as usize] = sum;
    }
}

/// Adds each block's scanned offset back to its words (WGSL: `scan_add`).
pub fn scan_add(sp: &ScanParams, data: &mut [u32]) {
    let blocks = sp.n.div_ceil(SCAN_BLOCK);
    for block in 0..blocks {
        let add = data[(sp.sums_offset + block) as usize];
        let start = block * SCAN_BLOCK;
        let end = (start + SCAN_BLOCK).min(sp.n);
        for idx in start..end {
            let i = (sp.in_offset + idx) as usize;
            data[i] = data[i].wrapping_add(add);
        }
    }
}

/// The whole scan as the host dispatches it: scan_blocks up the levels, scan_add down.
pub fn scan(levels: &ScanLevels, data: &mut [u32]) {
    for i in 0..levels.levels.len() {
        scan_blocks(&levels.params(i), data);
    }
    for i in (0..levels.levels.len().saturating_sub(1)).rev() {
        scan_add(&levels.params(i), data);
    }
}
