// scan.wgsl — exclusive prefix sum in place: the nearest facet's chunk counts into first work items.
// CPU mirror: src/cpu/scan.rs.
//
// The array is scanned in blocks of SCAN_BLOCK words; each block's total goes to the next level,
// which is scanned the same way, until one block remains; then scan_add adds each level's block
// offsets back down. All levels live in one buffer (`data`), at offsets the host computes.
// Integer sums, no atomics: the result is exact and deterministic.
//
// Bindings: 0 scan params (uniform ScanParams: n words at in_offset, block sums at sums_offset),
//           1 data (all levels).
// Dispatch: one workgroup of SCAN_WORKGROUP invocations per block, folded into 2D.
// Invariants: scan_blocks leaves each block exclusively scanned and writes its total to
//             data[sums_offset + block]; scan_add requires the sums level already scanned.

// 64 invocations of 16 words each: fewer levels of the workgroup scan (each two barriers, which
// a CPU adapter pays by switching between its SIMD groups) than 256 of 4.
const SCAN_WORKGROUP: u32 = 64u;
const SCAN_PER_THREAD: u32 = 16u;
const SCAN_BLOCK: u32 = 1024u;

// Rust twin: ScanParams (src/abi/search.rs), 16 bytes.
struct ScanParams {
    n: u32,
    in_offset: u32,
    sums_offset: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> sp: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;

var<workgroup> partial: array<u32, 64>;

@compute @workgroup_size(64)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let block = wg.y * nwg.x + wg.x;
    let base = block * SCAN_BLOCK + li * SCAN_PER_THREAD;
    var v: array<u32, 16>;
    var sum = 0u;
    for (var i = 0u; i < SCAN_PER_THREAD; i++) {
        let idx = base + i;
        var x = 0u;
        if (idx < sp.n) { x = data[sp.in_offset + idx]; }
        v[i] = sum;
        sum += x;
    }
    partial[li] = sum;
    workgroupBarrier();
    // Hillis–Steele inclusive scan of the per-thread sums.
    for (var offset = 1u; offset < SCAN_WORKGROUP; offset *= 2u) {
        var t = 0u;
        if (li >= offset) { t = partial[li - offset]; }
        workgroupBarrier();
        partial[li] += t;
        workgroupBarrier();
    }
    let before = partial[li] - sum;
    for (var i = 0u; i < SCAN_PER_THREAD; i++) {
        let idx = base + i;
        if (idx < sp.n) { data[sp.in_offset + idx] = v[i] + before; }
    }
    let blocks = (sp.n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    if (li == SCAN_WORKGROUP - 1u && block < blocks) {
        data[sp.sums_offset + block] = partial[li];
    }
}

@compute @workgroup_size(64)
fn scan_add(@builtin(workgroup_id) wg: vec3<u32>,
            @builtin(num_workgroups) nwg: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let block = wg.y * nwg.x + wg.x;
    let blocks = (sp.n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    if (block >= blocks) { return; }
    let add = data[sp.sums_offset + block];
    let base = block * SCAN_BLOCK + li * SCAN_PER_THREAD;
    for (var i = 0u; i < SCAN_PER_THREAD; i++) {
        let idx = base + i;
        if (idx < sp.n) { data[sp.in_offset + idx] += add; }
    }
}
