// anchor.wgsl — small and infinitesimal sliding: each slave's contact point from its fixed
// anchor, in place of any search (seed: "Small-sliding tracking approach").
// CPU mirror: src/cpu/anchor.rs.
//
// Bindings: 0 params (uniform SearchParams), 1 nodes, 2 facets, 3 slaves, 4 anchors (one Anchor
//           per slave, fixed at the first global search), 5 status, 6 hits (written),
//           7 adjacency (as in local_search.wgsl: for the current smoothed normal).
// Dispatch: one invocation per slave node, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: the anchor point X0 = Σ w_j x_j keeps its place among the facet's nodes (fixed
//             weights); the tangent plane through it has the normal N(X0) of the start, turned
//             by the facet's rotation since (small sliding) or never turned (ANCHOR_FROZEN,
//             infinitesimal); the gap is measured along it. A slave that projected onto no
//             facet gets facet = NO_FACET and no constraint. Diagnostics: a slave that slid more
//             than its facet's element length in the plane counts in STATUS_SLID_TOO_FAR; a
//             plane more than 10° off the current smoothed normal at X0 (the deformed master),
//             in STATUS_PLANE_OFF.

// Rust twin: Anchor (src/abi/search.rs), 64 bytes.
struct Anchor {
    facet: u32,
    node: u32,
    flags: u32,
    _pad: u32,
    weights: vec4<f32>,
    normal0: vec4<f32>,
    facet_normal0: vec4<f32>,
}

const ANCHOR_FROZEN: u32 = 1u;
const COS_10_DEGREES: f32 = 0.9848077;

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> anchors: array<Anchor>;
@group(0) @binding(5) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(7) var<storage, read> adjacency: array<u32>;

// Area vector of a facet (twin of nodal_normals.wgsl's).
fn area_normal(fac: vec4<u32>) -> vec3<f32> {
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    let n = facet_node_count(fac);
    if (n == 2u) {
        let t = x1 - x0;
        return vec3<f32>(t.y, -t.x, 0.0);
    }
    let x2 = nodes[fac.z].xyz;
    if (n == 3u) { return 0.5 * cross(x1 - x0, x2 - x0); }
    return 0.5 * cross(x2 - x0, nodes[fac.w].xyz - x1);
}

// The current smoothed normal at the point with weights w on facet fac.
fn smoothed_normal(fac: vec4<u32>, w: vec4<f32>) -> vec3<f32> {
    let n = facet_node_count(fac);
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < n; j++) {
        let node = fac[j];
        var nn = vec3<f32>(0.0);
        for (var k = adjacency[node]; k < adjacency[node + 1u]; k++) {
            nn += area_normal(facets[adjacency[k]]);
        }
        sum += w[j] * normalize_or_zero(nn);
    }
    return normalize_or_zero(sum);
}

// The facet's normal at the point with weights w (the bilinear normal for a quad).
fn facet_normal_at(fac: vec4<u32>, w: vec4<f32>) -> vec3<f32> {
    let n = facet_node_count(fac);
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    if (n == 2u) {
        let t = x1 - x0;
        return normalize_or_zero(vec3<f32>(t.y, -t.x, 0.0));
    }
    let x2 = nodes[fac.z].xyz;
    if (n == 3u) {
        return normalize_or_zero(cross(x1 - x0, x2 - x0));
    }
    let x3 = nodes[fac.w].xyz;
    // ξ, η of the point from the bilinear weights: ξ = (w1 + w2) − (w0 + w3), η = (w2 + w3) − (w0 + w1)
    let xi = (w.y + w.z) - (w.x + w.w);
    let eta = (w.z + w.w) - (w.x + w.y);
    let gx = (x1 - x0 + x2 - x3) * 0.25 + (x0 - x1 + x2 - x3) * (0.25 * eta);
    let ge = (x2 + x3 - x0 - x1) * 0.25 + (x0 - x1 + x2 - x3) * (0.25 * xi);
    var nn = normalize_or_zero(cross(gx, ge));
    if (dot(nn, nn) == 0.0) { nn = normalize_or_zero(cross(x2 - x0, x3 - x1)); }
    return nn;
}

// The rotation taking unit a onto unit b, applied to v (the shortest one).
fn rotate_like(a: vec3<f32>, b: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let c = dot(a, b);
    let k = cross(a, b);
    if (c <= -0.999999) { return -v; }
    return v * c + cross(k, v) + k * (dot(k, v) / (1.0 + c));
}

@compute @workgroup_size(64)
fn anchor(@builtin(workgroup_id) wg: vec3<u32>,
          @builtin(num_workgroups) nwg: vec3<u32>,
          @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    let a = anchors[i];
    let s = slaves[i];
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = a.node;
    hit.candidates = 0u;
    hit.slave = s;
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    if (a.facet == NO_FACET) {
        hits[i] = hit;
        return;
    }
    let fac = facets[a.facet];
    let n = facet_node_count(fac);
    var x0 = vec3<f32>(0.0);
    for (var j = 0u; j < n; j++) {
        x0 += a.weights[j] * nodes[fac[j]].xyz;
    }
    let nf = facet_normal_at(fac, a.weights);
    var nrm = a.normal0.xyz;
    if ((a.flags & ANCHOR_FROZEN) == 0u) {
        nrm = normalize_or_zero(rotate_like(a.facet_normal0.xyz, nf, a.normal0.xyz));
    }
    let p = nodes[s].xyz;
    let d = p - x0;
    let gap = dot(d, nrm);
    let slide = length(d - nrm * gap);
    if (slide > a.normal0.w) { atomicAdd(&status[STATUS_SLID_TOO_FAR], 1u); }
    if (dot(nrm, smoothed_normal(fac, a.weights)) < COS_10_DEGREES) { atomicAdd(&status[STATUS_PLANE_OFF], 1u); }
    hit.facet = a.facet;
    hit.point_gap = vec4<f32>(x0, gap);
    hit.normal_dist = vec4<f32>(nrm, length(d));
    hit.weights = a.weights;
    hits[i] = hit;
}
