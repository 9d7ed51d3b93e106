//! The search tree's boxes, quantised (WGSL twins in `common.wgsl`: `box_step`, `box_code_lo`,
//! `box_code_hi`, `box_pack`, `box_codes_lo`, `box_codes_hi`, `box_bounds`, `box_empty`,
//! `box_point`).
//!
//! A box is one `[u32; 4]` (a `vec4<u32>` on the device: one load per box test where two
//! `vec4<f32>` corners cost two — on a software adapter every load is a loop over the SIMD
//! lanes, and the walk is mostly loads). Its six bounds are 21-bit codes q on a grid of step
//! s, a power of two: the bound is (q − 2^20)·s, exact in f32 on every device. Lower bounds
//! round down and upper bounds up, so a box always holds what it was made from, and min/max of
//! codes is the exact union. A bound beyond the grid gets code 0 (lower) or
//! [`BOX_TOP`] (upper), which lie outside the grid's finite range
//! ±(2^20 − 1)·s, and box tests measure from the point clamped into that range
//! ([`point`]): those codes then act as −∞ and +∞ whatever the master does, and
//! no distance is overestimated (clamping a point into a box that holds another only brings it
//! nearer). An empty box has lo codes `BOX_TOP` and hi codes 0.

/// The largest code (a lower bound's code is at most `BOX_TOP − 1`).
pub const BOX_TOP: u32 = 0x1f_ffff;
/// The code of the grid's origin: 2^20.
pub const BOX_BIAS: f32 = 1_048_576.0;

/// The step of the box grid and its inverse for a tree whose leaf boxes grow by `margin`:
/// the power of two at or below the margin (2^-100 at least), so the grid's ±2^20 steps
/// reach 2^19 margins — twice the largest master coordinate, the margin being 2^-18 of it
/// — and a code widens a box by at most one margin. Built from the exponent bits, so
/// every device gets the same two numbers.
pub fn box_step(margin: f32) -> (f32, f32) {
    let e = (((margin.to_bits() >> 23) & 0xff) as i32 - 127).clamp(-100, 100);
    (
        f32::from_bits(((e + 127) as u32) << 23),
        f32::from_bits(((127 - e) as u32) << 23),
    )
}

/// The code of a lower bound `x` (rounded down; 0 below the grid).
pub fn code_lo(x: f32, inv_step: f32) -> u32 {
    (floor(x * inv_step) + BOX_BIAS).clamp(0.0, (BOX_TOP - 1) as f32) as u32
}

/// The code of an upper bound `x` (rounded up; `BOX_TOP` above the grid).
pub fn code_hi(x: f32, inv_step: f32) -> u32 {
    (-floor(-(x * inv_step)) + BOX_BIAS).clamp(1.0, BOX_TOP as f32) as u32
}

/// `t.floor()`, the same value for every `t`, without the library call that `floor` is on
/// x86-64 targets without SSE4.1 (one per bound of every leaf at each refit).
fn floor(t: f32) -> f32 {
    if t.abs() < 8_388_608.0 {
        // |t| < 2^23: the truncation is exact, one below for a negative fraction
        let i = t as i32 as f32;
        if i > t {
            i - 1.0
        } else {
            i
        }
    } else {
        t // an integer already, or ±∞, or NaN
    }
}

/// The bound of code `q`: (q − 2^20)·s.
pub fn bound(q: u32, step: f32) -> f32 {
    (q as f32 - BOX_BIAS) * step
}

/// The point box tests measure from: `p` clamped into the grid's finite range.
pub fn point(p: f32, step: f32) -> f32 {
    let g = (BOX_BIAS - 1.0) * step;
    p.clamp(-g, g)
}

/// Packs the codes of a box: 21 bits each, lo.x from bit 0 upwards, then lo.y, lo.z, hi.x,
/// hi.y, hi.z.
pub fn pack(lo: [u32; 3], hi: [u32; 3]) -> [u32; 4] {
    [
        lo[0] | lo[1] << 21,
        lo[1] >> 11 | lo[2] << 10 | hi[0] << 31,
        hi[0] >> 1 | hi[1] << 20,
        hi[1] >> 12 | hi[2] << 9,
    ]
}

/// The codes (lo, hi) of a packed box.
pub fn codes(b: [u32; 4]) -> ([u32; 3], [u32; 3]) {
    (
        [
            b[0] & BOX_TOP,
            (b[0] >> 21 | b[1] << 11) & BOX_TOP,
            (b[1] >> 10) & BOX_TOP,
        ],
        [
            (b[1] >> 31 | b[2] << 1) & BOX_TOP,
            (b[2] >> 20 | b[3] << 12) & BOX_TOP,
            (b[3] >> 9) & BOX_TOP,
        ],
    )
}

/// The packed empty box.
pub const EMPTY: [u32; 4] = [BOX_TOP | BOX_TOP << 21, BOX_TOP >> 11 | BOX_TOP << 10, 0, 0];

/// Whether a packed box is empty (no facet below it, or only collapsed ones).
pub fn is_empty(b: [u32; 4]) -> bool {
    b[0] & BOX_TOP == BOX_TOP
}

/// The lower and upper corner of a packed box on the grid of `step` (the search's local
/// frame; the codes 0 and `BOX_TOP` decode to the grid's edges, beyond every box point).
pub fn unpack(b: [u32; 4], step: f32) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = codes(b);
    (lo.map(|q| bound(q, step)), hi.map(|q| bound(q, step)))
}
