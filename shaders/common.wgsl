// common.wgsl — prepended to every kernel by src/gpu/shaders.rs.
// Constants, the structs shared with Rust, dispatch folding and the closest-point geometry.
// Rust twins: src/abi/search.rs (structs), src/geometry.rs (geometry, same operation order).

const NO_NODE: u32 = 0xffffffffu;
const NO_FACET: u32 = 0xffffffffu;
// Flag in Hit.candidates: the closest point lies on a free edge or corner of the master and the
// slave is beside it, off the facets: no contact (Rust twin: HIT_BESIDE_FREE_EDGE).
const HIT_BESIDE_FREE_EDGE: u32 = 0x80000000u;
// Flag in Hit.candidates: written by a settled walk that left the slave's skin valid
// (local_search.wgsl; Rust twin: HIT_WALKED); the bits below it count facets (HIT_COUNT).
const HIT_WALKED: u32 = 0x40000000u;
const HIT_COUNT: u32 = 0x3fffffffu;
const QUAD_ITERATIONS: u32 = 8u;
const QUAD_HALVINGS: u32 = 6u;     // Rust: geometry::QUAD_HALVINGS
const QUAD_TRUST: f32 = 0.25;      // Rust: geometry::QUAD_TRUST
const QUAD_CONVERGED: f32 = 1e-4;   // Rust: geometry::QUAD_CONVERGED
const COS_TENTH_DEGREE: f32 = 0.99999845; // Rust: geometry::COS_TENTH_DEGREE as f32
// Invocations per workgroup of the one-item-per-invocation kernels (Rust: ITEM_WORKGROUP).
const ITEM_WORKGROUP: u32 = 64u;
// Lower corner of an empty box (upper: its negation): no point is within any distance of it.
const EMPTY_LO: f32 = 3.0e38;

// Rust twin: SearchParams (src/abi/search.rs), 96 bytes. Coordinates are relative to the
// search's frame.
struct SearchParams {
    radius: f32,
    box_margin: f32,     // growth of the tree's leaf boxes: the frame's f32 round-off
    n_facets: u32,
    n_slaves: u32,
    tree_levels: u32,    // levels below the tree's root: 2^tree_levels leaf slots
    dim: u32,
    max_local_iterations: u32,
    flags: u32,
    budget: f32,
    n_motion_nodes: u32,
    ref_node: u32,       // the pair's reference master node: motion is measured relative to it
    bucket_cell: f32,    // the bucket search's cell size (buckets.wgsl); 0 with the tree
    master_lo: vec4<f32>, // the master's box at the last global search (xyz)
    master_hi: vec4<f32>,
    bucket_bits: u32,    // 2^bucket_bits hashed buckets, then the one of facets too large to bin
    bucket_entries: u32, // word of the bucket grid where the entries (leaf slot, facet) start
    _pad1: u32,
    _pad2: u32,
}

const FLAG_WIDE_LOCAL: u32 = 1u;
const FLAG_SELF_CONTACT: u32 = 2u;
const FLAG_EVERY_SLAVE: u32 = 4u;   // local increments visit every slave (no compaction)
const FLAG_SLAVES_APART: u32 = 8u;  // no slave node is on an active master facet
const FLAG_BUCKETS: u32 = 16u;      // the global search bins facets in a hashed grid (buckets.wgsl)
// A slave's tracking state, kept in the w of its reference position (motion.wgsl), which the
// motion pass reads in node order instead of the hit (Rust twins: SLAVE_TRACKED, SLAVE_WITHIN):
// below SLAVE_TRACKED untracked, SLAVE_TRACKED tracked with no facet within the radius,
// SLAVE_WITHIN tracked with one. Small whole floats: any backend stores and compares them exactly.
// Invariant: after every pass that writes a slave's hit, its state is slave_state(hit) —
// nearest_facet's hits by active_mark, which follows it in every global increment; local_search
// where the facet word went from none to some or back (the only change a tracked slave's state
// can take between global searches). anchor.wgsl keeps none: an anchored pair runs no motion.
const SLAVE_TRACKED: f32 = 1.0;
const SLAVE_WITHIN: f32 = 2.0;
// The statistics' word of the node-wise bound on the springs' ω² (f32 bits; raised by add_forces,
// read by finish_stats; the other STAT_* words: stats.wgsl; Rust twin: STAT_OMEGA2).
const STAT_OMEGA2: u32 = 3u;

// Rust twin: GpuHit (src/abi/search.rs), 64 bytes. One per slave node.
struct Hit {
    facet: u32,          // index into the active facet list, NO_FACET when none within the radius
    node: u32,           // tracked master node (nearest node of that facet), NO_NODE when none
    candidates: u32,     // facets examined
    slave: u32,          // the slave node (model node id)
    weights: vec4<f32>,     // load-transfer weights of the facet's nodes
    point_gap: vec4<f32>,   // xyz closest point (in the frame), w signed gap along the normal
    normal_dist: vec4<f32>, // xyz unit facet normal at the point, w distance
}

// The tracking state hit h leaves its slave in (Rust twin: abi::search::slave_state).
fn slave_state(h: Hit) -> f32 {
    if (h.node == NO_NODE) { return 0.0; }
    return select(SLAVE_TRACKED, SLAVE_WITHIN, h.facet != NO_FACET);
}

// Status words (Rust twin: STATUS_* in src/abi/status.rs).
const STATUS_BUDGET_EXCEEDED: u32 = 2u; // the motion budget is used up: rerun with a global search
const STATUS_LOCAL_ITERATIONS: u32 = 3u; // most local-search iterations
const STATUS_MOTION: u32 = 8u;         // bits of the largest motion since the last global search
const STATUS_LOCAL_CAPPED: u32 = 9u;   // slaves whose local walk hit the cap
const STATUS_CROWDED: u32 = 10u;       // self-contact slaves with unconnected facets near
const STATUS_LOCAL_WALKS: u32 = 11u;   // slaves the local search walked (past their skin)
const STATUS_SLID_TOO_FAR: u32 = 12u;  // small sliding: slid more than an element length
const STATUS_PLANE_OFF: u32 = 13u;     // small sliding: tangent plane > 10° off the facet
const STATUS_DT_STABLE: u32 = 4u;      // bits of the smallest stable increment (positive f32)
const STATUS_DT_APPROACH: u32 = 5u;    // bits of the smallest approach limit (positive f32)
const STATUS_ACTIVE: u32 = 6u;         // slave nodes in contact
const STATUS_SLIPPING: u32 = 7u;       // of which slipping
const STATUS_FAST: u32 = 15u;          // slaves moving farther than the radius relative to the master
const STATUS_FAST_RATIO: u32 = 27u;    // bits of the largest such relative motion over the radius (f32)
const STATUS_MAX_OVERCLOSURE: u32 = 14u; // bits of the largest overclosure in contact (f32 ≥ 0)
const STATUS_FORCE_SCALE: u32 = 16u;  // bits of the largest |force component| of a spring in contact
const STATUS_ROW_SCALE: u32 = 17u;    // bits of the largest bound share of a spring in contact
const STATUS_FALLBACK: u32 = 18u;     // slaves whose tree walk hit its cap (the chunks finished it)
const STATUS_BOX: u32 = 20u;          // 6 words: order-preserving bits of the master box, min then max
const STATUS_COLLAPSED: u32 = 19u;    // master facets collapsed at the global search's positions (skipped)
const STATUS_NONFINITE: u32 = 26u;    // lowest node with a non-finite coordinate, NO_NODE if none
const STATUS_MASTER_MOTION: u32 = 28u; // bits of the largest master motion since the global search
// After the status words (STATUS_WORDS of them, reset each increment), the same buffer keeps the
// active slaves from one global search to the next: their count, then their slave indices
// (active.wgsl; Rust twin: ACTIVE_LIST). They share the status buffer because the penalty pass
// already binds the eight storage buffers WebGPU's default limits allow.
const ACTIVE_LIST: u32 = 29u;

// The plan of a device-resident increment: one buffer per search, u32 words (Rust twins:
// PLAN_* in src/abi/search.rs). Words 0..16 the schedule's state, 64..88 the SearchParams
// the schedule fitted (the search passes bind them as their uniform), then PLAN_SLOT_WORDS per
// dispatch slot: the
// live indirect arguments (x, y, z, 0), then the full-size ones (x, y, z, kind).
const PLAN_SINCE_GLOBAL: u32 = 0u;  // increments since the last global search
const PLAN_SEARCHED: u32 = 1u;      // 1 once a global search has run
const PLAN_CROWDED: u32 = 2u;       // self-contact slaves crowded at the last global search
const PLAN_FORCE: u32 = 3u;         // the host asks for a global search next increment
const PLAN_GLOBAL: u32 = 4u;        // this increment searches globally
const PLAN_TRIGGER: u32 = 5u;       // why (TRIGGER_*)
const PLAN_INTERVAL: u32 = 6u;      // the schedule's interval
const PLAN_N_SLOTS: u32 = 7u;       // dispatch slots in use
const PLAN_OTHER_NODES: u32 = 8u;   // pair nodes that are no slaves, and two rigid slots
const PLAN_FIT_FAILED: u32 = 9u;    // the master box could not be taken (the old one was kept)
const PLAN_MAX_DIM: u32 = 10u;      // most workgroups per dispatch dimension (for folding)
const PLAN_PARAMS: u32 = 64u;       // 24 words: the fitted SearchParams (byte 256: bound as the uniform)
const PLAN_SLOTS: u32 = 88u;
const PLAN_SLOT_WORDS: u32 = 8u;
const SLOT_GLOBAL: u32 = 1u;        // slot kind: dispatched in global increments
const SLOT_LOCAL: u32 = 2u;         // slot kind: dispatched in local increments
const TRIGGER_LOCAL: u32 = 0u;
const TRIGGER_FIRST: u32 = 1u;
const TRIGGER_INTERVAL: u32 = 2u;
const TRIGGER_BUDGET: u32 = 3u;
const TRIGGER_CROWDED: u32 = 4u;
const TRIGGER_REQUESTED: u32 = 5u;

// f32 bits as a u32 whose unsigned order is the floats' order (for atomicMin/Max of any sign).
fn ordered_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered_bits(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// Whether x is NaN or infinite (by its bits: compilers may assume finite arithmetic).
fn non_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

// Flat invocation id of a dispatch folded into 2D (x up to 65,535 workgroups, then y).
fn folded_id(wg: vec3<u32>, nwg: vec3<u32>, local: u32, size: u32) -> u32 {
    return (wg.y * nwg.x + wg.x) * size + local;
}

// Number of nodes of a facet (2, 3 or 4) from its padded node list.
fn facet_node_count(f: vec4<u32>) -> u32 {
    if (f.z == NO_NODE) { return 2u; }
    if (f.w == NO_NODE) { return 3u; }
    return 4u;
}

// Whether a facet with corners x0..x3 (n of them) has collapsed: its length (2D) or area (3D),
// in units of its longest edge, is not above 1e-6 — the model's rule for degenerate facets
// (src/model/surface.rs) applied to the current positions. Rust twin: cpu::common::facet_collapsed.
fn facet_collapsed(x0: vec3<f32>, x1: vec3<f32>, x2: vec3<f32>, x3: vec3<f32>, n: u32) -> bool {
    var size = length(x1 - x0);
    if (n == 3u) {
        size = max(size, max(length(x2 - x1), length(x0 - x2)));
    } else if (n == 4u) {
        size = max(max(size, length(x2 - x1)), max(length(x3 - x2), length(x0 - x3)));
    }
    if (!(size > 0.0) || size > 3.0e38) { return true; }
    let inv = 1.0 / size;
    if (n == 2u) { return false; }
    var a: vec3<f32>;
    if (n == 3u) {
        a = cross((x1 - x0) * inv, (x2 - x0) * inv);
    } else {
        a = cross((x2 - x0) * inv, (x3 - x1) * inv);
    }
    return !(0.5 * length(a) > 1.0e-6);
}

// ---- geometry (twin of src/geometry.rs) ----

struct Projection {
    point: vec3<f32>,
    weights: vec4<f32>,
    normal: vec3<f32>,
    dist2: f32,
}

fn div_or_zero(a: f32, b: f32) -> f32 {
    if (b != 0.0) { return a / b; }
    return 0.0;
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    if (l2 > 0.0) { return v * (1.0 / sqrt(l2)); }
    return vec3<f32>(0.0);
}

fn closest_on_segment(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> Projection {
    let ab = vec3<f32>(b.x - a.x, b.y - a.y, 0.0);
    let ap = vec3<f32>(p.x - a.x, p.y - a.y, 0.0);
    let t = clamp(div_or_zero(dot(ap, ab), dot(ab, ab)), 0.0, 1.0);
    var r: Projection;
    r.point = vec3<f32>(a.x + ab.x * t, a.y + ab.y * t, 0.0);
    r.normal = normalize_or_zero(vec3<f32>(ab.y, -ab.x, 0.0));
    let d = vec3<f32>(p.x - r.point.x, p.y - r.point.y, 0.0);
    r.dist2 = dot(d, d);
    r.weights = vec4<f32>(1.0 - t, t, 0.0, 0.0);
    return r;
}

fn closest_on_triangle(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> Projection {
    let ab = b - a;
    let ac = c - a;
    var r: Projection;
    r.normal = normalize_or_zero(cross(ab, ac));
    // Voronoi regions, Ericson §5.1.5
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    if (d1 <= 0.0 && d2 <= 0.0) {
        r.point = a; r.weights = vec4<f32>(1.0, 0.0, 0.0, 0.0);
    } else if (d3 >= 0.0 && d4 <= d3) {
        r.point = b; r.weights = vec4<f32>(0.0, 1.0, 0.0, 0.0);
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        let v = div_or_zero(d1, d1 - d3);
        r.point = a + ab * v; r.weights = vec4<f32>(1.0 - v, v, 0.0, 0.0);
    } else if (d6 >= 0.0 && d5 <= d6) {
        r.point = c; r.weights = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        let w = div_or_zero(d2, d2 - d6);
        r.point = a + ac * w; r.weights = vec4<f32>(1.0 - w, 0.0, w, 0.0);
    } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        let w = div_or_zero(d4 - d3, (d4 - d3) + (d5 - d6));
        r.point = b + (c - b) * w; r.weights = vec4<f32>(0.0, 1.0 - w, w, 0.0);
    } else {
        let denom = va + vb + vc;
        let v = div_or_zero(vb, denom);
        let w = div_or_zero(vc, denom);
        r.point = a + ab * v + ac * w; r.weights = vec4<f32>(1.0 - v - w, v, w, 0.0);
    }
    let d = p - r.point;
    r.dist2 = dot(d, d);
    return r;
}

fn quad_shape(xi: f32, eta: f32) -> vec4<f32> {
    let xm = 1.0 - xi;
    let xp = 1.0 + xi;
    let em = 1.0 - eta;
    let ep = 1.0 + eta;
    return vec4<f32>(0.25 * xm * em, 0.25 * xp * em, 0.25 * xp * ep, 0.25 * xm * ep);
}

// (ξ, η) of a point q in or near the plane of the quad y0..y3, by inverting the bilinear map
// there (exact for a planar quad), clamped to the square (Rust: geometry::quad_parameters).
fn quad_parameters(q: vec3<f32>, y0: vec3<f32>, y1: vec3<f32>, y2: vec3<f32>, y3: vec3<f32>) -> vec2<f32> {
    let e = y1 - y0;
    let f = y3 - y0;
    let g = y0 - y1 + y2 - y3;
    let h = q - y0;
    let n = cross(y2 - y0, y3 - y1);
    let k2 = dot(cross(g, f), n);
    let k1 = dot(cross(e, f), n) + dot(cross(h, g), n);
    let k0 = dot(cross(h, e), n);
    let sq = sqrt(max(k1 * k1 - 4.0 * k0 * k2, 0.0));
    var t = -k1 + sq;
    if (k1 >= 0.0) { t = -k1 - sq; }
    let va = div_or_zero(2.0 * k0, t);
    let vb = div_or_zero(t, 2.0 * k2);
    var v = vb;
    if (k2 == 0.0 || max(max(-va, va - 1.0), 0.0) <= max(max(-vb, vb - 1.0), 0.0)) { v = va; }
    let ev = e + g * v;
    let u = div_or_zero(dot(h - f * v, ev), dot(ev, ev));
    return vec2<f32>(clamp(u + u - 1.0, -1.0, 1.0), clamp(v + v - 1.0, -1.0, 1.0));
}

// y(ξ,η) − p of a quad relative to its node 0 (closest_on_quad).
fn quad_residual(c0: vec3<f32>, cx: vec3<f32>, ce: vec3<f32>, cxe: vec3<f32>, pl: vec3<f32>, xi: f32, eta: f32) -> vec3<f32> {
    return c0 + cx * xi + ce * eta + cxe * (xi * eta) - pl;
}

fn closest_on_quad(p: vec3<f32>, x0: vec3<f32>, x1: vec3<f32>, x2: vec3<f32>, x3: vec3<f32>) -> Projection {
    // relative to node 0, as in src/geometry.rs
    let y = array<vec3<f32>, 4>(vec3<f32>(0.0), x1 - x0, x2 - x0, x3 - x0);
    let pl = p - x0;
    let c0 = (y[1] + y[2] + y[3]) * 0.25;
    let cx = (y[1] + y[2] - y[3]) * 0.25;
    let ce = (y[2] + y[3] - y[1]) * 0.25;
    let cxe = (y[2] - y[1] - y[3]) * 0.25;
    // Newton starts from the nearest point of the nearer triangle, (y0, y1, y2) or
    // (y0, y2, y3), mapped to (ξ, η) in the quad's plane: the answer for a planar quad, near it
    // otherwise
    let t1 = closest_on_triangle(pl, y[0], y[1], y[2]);
    let t2 = closest_on_triangle(pl, y[0], y[2], y[3]);
    var start = t1.point;
    if (t2.dist2 < t1.dist2) { start = t2.point; }
    let st = quad_parameters(start, y[0], y[1], y[2], y[3]);
    var xi = st.x;
    var eta = st.y;
    let r0 = quad_residual(c0, cx, ce, cxe, pl, xi, eta);
    var f = dot(r0, r0);
    var step = 1.0;
    for (var k = 0u; k < QUAD_ITERATIONS; k++) {
        let before = vec3<u32>(bitcast<u32>(xi), bitcast<u32>(eta), bitcast<u32>(f));
        let r = quad_residual(c0, cx, ce, cxe, pl, xi, eta);
        let gx = cx + cxe * eta;
        let ge = ce + cxe * xi;
        let a11 = dot(gx, gx);
        let a22 = dot(ge, ge);
        let b1 = dot(gx, r);
        let b2 = dot(ge, r);
        // Newton; Gauss–Newton where the Hessian is not positive definite
        var a12 = dot(gx, ge) + dot(r, cxe);
        var det = a11 * a22 - a12 * a12;
        if (!(det > 0.0)) {
            a12 = dot(gx, ge);
            det = a11 * a22 - a12 * a12;
        }
        let dxi = div_or_zero(a22 * b1 - a12 * b2, det);
        let deta = div_or_zero(a11 * b2 - a12 * b1, det);
        // a step within QUAD_TRUST is taken whole; a longer one backtracks: the first of the
        // step, its half, quarter, … that does not increase |y − p|²; none: stay, unconverged
        let whole = max(abs(dxi), abs(deta)) <= QUAD_TRUST;
        var s = 1.0;
        step = 1.0;
        for (var h = 0u; h < QUAD_HALVINGS; h++) {
            let nxi = clamp(xi - dxi * s, -1.0, 1.0);
            let neta = clamp(eta - deta * s, -1.0, 1.0);
            let nr = quad_residual(c0, cx, ce, cxe, pl, nxi, neta);
            let nf = dot(nr, nr);
            if (whole || nf <= f) {
                step = max(abs(nxi - xi), abs(neta - eta));
                xi = nxi;
                eta = neta;
                f = nf;
                break;
            }
            s = s * 0.5;
        }
        // a fixed point: the next steps start from the same (ξ, η, f) and leave them and the
        // step as this one did, so stopping here changes no bit
        if (all(vec3<u32>(bitcast<u32>(xi), bitcast<u32>(eta), bitcast<u32>(f)) == before)) { break; }
    }
    var best_point = c0 + cx * xi + ce * eta + cxe * (xi * eta);
    var bd = pl - best_point;
    var best_d2 = dot(bd, bd);
    var best_xi = xi;
    var best_eta = eta;
    let strictly_inside = abs(xi) < 1.0 && abs(eta) < 1.0;
    if (!(strictly_inside && step < QUAD_CONVERGED)) {
        // a clamped end point lies on an edge: only an unconverged interior one stays a candidate
        var have = strictly_inside;
        for (var e = 0u; e < 4u; e++) {
            let a = y[e];
            let b = y[(e + 1u) % 4u];
            let ab = b - a;
            let t = clamp(div_or_zero(dot(pl - a, ab), dot(ab, ab)), 0.0, 1.0);
            let point = a + ab * t;
            let d = pl - point;
            let d2 = dot(d, d);
            if (!have || d2 < best_d2) {
                have = true;
                let s = t + t - 1.0;
                var exi = -1.0;
                var eeta = -s;
                if (e == 0u) { exi = s; eeta = -1.0; }
                else if (e == 1u) { exi = 1.0; eeta = s; }
                else if (e == 2u) { exi = -s; eeta = 1.0; }
                best_point = point;
                best_d2 = d2;
                best_xi = exi;
                best_eta = eeta;
            }
        }
    }
    var r: Projection;
    let gx = cx + cxe * best_eta;
    let ge = ce + cxe * best_xi;
    r.normal = normalize_or_zero(cross(gx, ge));
    if (dot(r.normal, r.normal) == 0.0) {
        r.normal = normalize_or_zero(cross(y[2], y[3] - y[1]));
    }
    r.point = best_point + x0;
    r.weights = quad_shape(best_xi, best_eta);
    r.dist2 = best_d2;
    return r;
}

// ---- the search tree's boxes, quantised (Rust twin: search::tree::boxes) ----
// A box is one vec4<u32>: its six bounds (lo.xyz, hi.xyz) as 21-bit codes q on a grid of step
// s, a power of two (box_step): the bound is (q − BOX_BIAS)·s, exact in f32. Lower bounds round
// down and upper ones up, so a box always holds what it was made from; a bound beyond the grid
// gets code 0 (lower) or BOX_TOP (upper), which lie outside the grid's finite range
// ±(BOX_BIAS − 1)·s, and the box tests measure from the point clamped into that range
// (box_point): those codes then act as −∞ and +∞, and a distance is never overestimated. An
// empty box has lo codes BOX_TOP and hi codes 0 (box_empty).
const BOX_BIAS: f32 = 1048576.0;    // 2^20
const BOX_TOP: u32 = 0x1fffffu;     // 2^21 − 1

// The step of the box grid, and its inverse: the power of two at or below the box margin
// (2^-100 at least), so the grid's ±2^20 steps reach 2^19 margins, twice the largest master
// coordinate, and a code widens a box by at most one margin. Built from exponent bits: every
// device gets the same two numbers.
fn box_step(margin: f32) -> vec2<f32> {
    let e = clamp(i32((bitcast<u32>(margin) >> 23u) & 0xffu) - 127, -100, 100);
    return vec2<f32>(bitcast<f32>(u32(e + 127) << 23u), bitcast<f32>(u32(127 - e) << 23u));
}

fn box_code_lo(x: f32, inv_step: f32) -> u32 {
    return u32(clamp(floor(x * inv_step) + BOX_BIAS, 0.0, f32(BOX_TOP - 1u)));
}

fn box_code_hi(x: f32, inv_step: f32) -> u32 {
    return u32(clamp(ceil(x * inv_step) + BOX_BIAS, 1.0, f32(BOX_TOP)));
}

// Packs codes (lo, hi) into one vec4<u32>: 21 bits each, lo.x from bit 0 upwards.
fn box_pack(lo: vec3<u32>, hi: vec3<u32>) -> vec4<u32> {
    return vec4<u32>(
        lo.x | (lo.y << 21u),
        (lo.y >> 11u) | (lo.z << 10u) | (hi.x << 31u),
        (hi.x >> 1u) | (hi.y << 20u),
        (hi.y >> 12u) | (hi.z << 9u));
}

fn box_codes_lo(b: vec4<u32>) -> vec3<u32> {
    return vec3<u32>(b.x & BOX_TOP, ((b.x >> 21u) | (b.y << 11u)) & BOX_TOP, (b.y >> 10u) & BOX_TOP);
}

fn box_codes_hi(b: vec4<u32>) -> vec3<u32> {
    return vec3<u32>(((b.y >> 31u) | (b.z << 1u)) & BOX_TOP, ((b.z >> 20u) | (b.w << 12u)) & BOX_TOP, (b.w >> 9u) & BOX_TOP);
}

// The bounds of three codes.
fn box_bounds(q: vec3<u32>, step: f32) -> vec3<f32> {
    return (vec3<f32>(q) - vec3<f32>(BOX_BIAS)) * step;
}

// Whether a packed box is empty (no facet below it, or only collapsed ones).
fn box_empty(b: vec4<u32>) -> bool {
    return (b.x & BOX_TOP) == BOX_TOP;
}

// The point box tests measure from: p clamped into the grid's finite range.
fn box_point(p: vec3<f32>, step: f32) -> vec3<f32> {
    let g = (BOX_BIAS - 1.0) * step;
    return clamp(p, vec3<f32>(-g), vec3<f32>(g));
}

// Distance² from the box point q (box_point) to the non-empty packed box b.
fn packed_box_d2(b: vec4<u32>, q: vec3<f32>, step: f32) -> f32 {
    let lo = box_bounds(box_codes_lo(b), step);
    let hi = box_bounds(box_codes_hi(b), step);
    let d = max(max(lo - q, q - hi), vec3<f32>(0.0));
    return dot(d, d);
}
