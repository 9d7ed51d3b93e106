// search_common.wgsl — functions shared by the search kernels that read facets and adjacency:
// prepended (after common.wgsl) to nearest_facet.wgsl, buckets.wgsl and local_search.wgsl, which declare
// `params`, `nodes`, `facets` and `adjacency`. CPU mirror: src/cpu/common.rs.

// The positions of facet fac's nodes, and their count; the slots beyond it repeat node 1 (not
// loaded again).
struct FacetPoints {
    n: u32,
    x0: vec3<f32>,
    x1: vec3<f32>,
    x2: vec3<f32>,
    x3: vec3<f32>,
}

fn facet_points(fac: vec4<u32>) -> FacetPoints {
    var f: FacetPoints;
    f.n = facet_node_count(fac);
    f.x0 = nodes[fac.x].xyz;
    f.x1 = nodes[fac.y].xyz;
    f.x2 = f.x1;
    f.x3 = f.x1;
    if (f.n >= 3u) { f.x2 = nodes[fac.z].xyz; }
    if (f.n == 4u) { f.x3 = nodes[fac.w].xyz; }
    return f;
}

// A subtree or facet is skipped when its box's distance² exceeds the bound by this factor:
// more than the round-off of a distance² computed in f32 (Rust twin: PRUNE_SLACK).
const PRUNE_SLACK: f32 = 1.0001;

// Distance² from p to the box of facet f's nodes: no point of the facet (a segment, a
// triangle, or a bilinear quad, which lies within its nodes' hull) is nearer. A segment (2D)
// is measured in x and y, as closest_on_segment projects it.
fn points_box_d2(p: vec3<f32>, f: FacetPoints) -> f32 {
    let lo = min(min(f.x0, f.x1), min(f.x2, f.x3));
    let hi = max(max(f.x0, f.x1), max(f.x2, f.x3));
    var d = max(max(lo - p, p - hi), vec3<f32>(0.0));
    if (f.n == 2u) { d.z = 0.0; }
    return dot(d, d);
}

// Closest point of p on the facet whose nodes are f.
fn project_points(p: vec3<f32>, f: FacetPoints) -> Projection {
    if (f.n == 2u) { return closest_on_segment(p, f.x0, f.x1); }
    if (f.n == 3u) { return closest_on_triangle(p, f.x0, f.x1, f.x2); }
    return closest_on_quad(p, f.x0, f.x1, f.x2, f.x3);
}

// Closest point of p on facet fac.
fn project_facet(p: vec3<f32>, fac: vec4<u32>) -> Projection {
    return project_points(p, facet_points(fac));
}

// Self-contact: facet f is the slave's own or touches one of the slave's own facets.
fn excluded(s: u32, fac: vec4<u32>) -> bool {
    if ((params.flags & FLAG_SELF_CONTACT) == 0u) { return false; }
    let n = facet_node_count(fac);
    for (var j = 0u; j < n; j++) {
        let node = fac[j];
        if (node == s) { return true; }
        for (var k = adjacency[s]; k < adjacency[s + 1u]; k++) {
            let own = facets[adjacency[k]];
            let m = facet_node_count(own);
            for (var q = 0u; q < m; q++) {
                if (own[q] == node) { return true; }
            }
        }
    }
    return false;
}

// Free boundaries (CPU mirror: cpu::common::edge_shared, vertex_free, beside_free_edge).
// Whether facet f's edge (a, b) is shared by another facet.
fn edge_shared(f: u32, a: u32, b: u32) -> bool {
    for (var k = adjacency[a]; k < adjacency[a + 1u]; k++) {
        let g = adjacency[k];
        if (g == f) { continue; }
        let fg = facets[g];
        let ng = facet_node_count(fg);
        for (var j = 0u; j < ng; j++) {
            if (fg[j] == b) { return true; }
        }
    }
    return false;
}

// Whether node a ends an unshared edge (3D) or is the end of a single segment (2D).
fn vertex_free(a: u32) -> bool {
    let s = adjacency[a];
    let e = adjacency[a + 1u];
    for (var k = s; k < e; k++) {
        let g = adjacency[k];
        let fg = facets[g];
        let ng = facet_node_count(fg);
        if (ng == 2u) { return e - s < 2u; }
        for (var j = 0u; j < ng; j++) {
            if (fg[j] == a) {
                if (!edge_shared(g, a, fg[(j + 1u) % ng]) || !edge_shared(g, a, fg[(j + ng - 1u) % ng])) {
                    return true;
                }
            }
        }
    }
    return false;
}

// The master's extension zone beyond its free edges, a fraction of the facet's size (Abaqus'
// EXTENSION ZONE, default 0.1; Rust twin: cpu::common::EXTENSION_ZONE).
const EXTENSION_ZONE: f32 = 0.1;

// The slave at p, nearest to facet f at point c (weights w, unit normal nrm), is beside a free
// boundary of the master: c lies on an unshared edge, or on a corner of one, and p is off to
// the side of it by more than the extension zone (EXTENSION_ZONE of the facet's size from the
// normal through c).
fn beside_free_edge(f: u32, fac: vec4<u32>, w: vec4<f32>, p: vec3<f32>, c: vec3<f32>, nrm: vec3<f32>) -> bool {
    let n = facet_node_count(fac);
    var on = 0u;
    var a = NO_NODE;
    var b = NO_NODE;
    for (var j = 0u; j < n; j++) {
        if (w[j] != 0.0) {
            on += 1u;
            if (a == NO_NODE) { a = fac[j]; } else { b = fac[j]; }
        }
    }
    if (on == n) { return false; } // inside the facet
    var h = 0.0;
    for (var j = 0u; j < n; j++) {
        h = max(h, length(nodes[fac[(j + 1u) % n]].xyz - nodes[fac[j]].xyz));
    }
    let d = p - c;
    let lateral = d - dot(d, nrm) * nrm;
    if (dot(lateral, lateral) <= EXTENSION_ZONE * EXTENSION_ZONE * h * h) { return false; }
    if (on == 1u) { return vertex_free(a); }
    if (on == 2u && n > 2u) { return !edge_shared(f, a, b); }
    return false;
}

// The square of the tracking radius, radius + budget: how far the global search looks (Rust
// twin: `cpu::nearest_facet::track_radius2`).
fn track_radius2() -> f32 {
    let r = params.radius + params.budget;
    return r * r;
}

// Whether two facets share a node.
fn share_node(a: vec4<u32>, b: vec4<u32>) -> bool {
    let na = facet_node_count(a);
    let nb = facet_node_count(b);
    for (var i = 0u; i < na; i++) {
        for (var j = 0u; j < nb; j++) {
            if (a[i] == b[j]) { return true; }
        }
    }
    return false;
}
