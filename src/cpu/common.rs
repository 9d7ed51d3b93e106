//! CPU twin of the non-geometry helpers of `shaders/common.wgsl` (the geometry itself is
//! [`crate::geometry`], run in f32).

use crate::abi::search::SearchParams;
use crate::geometry::V3;
pub use crate::model::facet_node_count;
use crate::model::NO_NODE;

/// Grid-local position of node `n` (WGSL: `nodes[n].xyz`).
pub fn node(nodes: &[[f32; 4]], n: u32) -> V3<f32> {
    let x = nodes[n as usize];
    V3::new(x[0], x[1], x[2])
}

/// Whether facet `fac` has collapsed at `nodes`: its length (2D) or area (3D), in units of its
/// longest edge, is not above 1e-6 — the model's rule for degenerate facets applied to the
/// current positions (WGSL: `facet_collapsed` in common.wgsl, `collapsed` in
/// search_common.wgsl).
pub fn facet_collapsed(nodes: &[[f32; 4]], fac: [u32; 4]) -> bool {
    let n = facet_node_count(fac);
    let x: [V3<f32>; 4] = std::array::from_fn(|j| node(nodes, fac[j.min(n - 1)]));
    let len = |v: V3<f32>| v.length2().sqrt();
    let mut size = len(x[1] - x[0]);
    if n == 3 {
        size = size.max(len(x[2] - x[1]).max(len(x[0] - x[2])));
    } else if n == 4 {
        size = size
            .max(len(x[2] - x[1]))
            .max(len(x[3] - x[2]).max(len(x[0] - x[3])));
    }
    if !(size > 0.0) || size > 3.0e38 {
        return true;
    }
    let inv = 1.0 / size;
    let a = match n {
        2 => return false,
        3 => ((x[1] - x[0]) * inv).cross((x[2] - x[0]) * inv),
        _ => ((x[2] - x[0]) * inv).cross((x[3] - x[1]) * inv),
    };
    !(0.5 * len(a) > 1.0e-6)
}

/// Distance² from `p` to the box of facet `fac`'s nodes (WGSL: `points_box_d2`): no point of
/// the facet is nearer. A segment (2D) is measured in x and y, as it is projected.
pub fn facet_box_d2(nodes: &[[f32; 4]], fac: [u32; 4], p: V3<f32>) -> f32 {
    let n = facet_node_count(fac);
    let first = node(nodes, fac[0]);
    let (mut lo, mut hi) = (first, first);
    for &k in &fac[1..n] {
        let x = node(nodes, k);
        lo = V3::new(lo.x.min(x.x), lo.y.min(x.y), lo.z.min(x.z));
        hi = V3::new(hi.x.max(x.x), hi.y.max(x.y), hi.z.max(x.z));
    }
    let d = |l: f32, h: f32, q: f32| (l - q).max(q - h).max(0.0);
    let dz = if n == 2 { 0.0 } else { d(lo.z, hi.z, p.z) };
    let d = V3::new(d(lo.x, hi.x, p.x), d(lo.y, hi.y, p.y), dz);
    d.length2()
}

/// Self-contact exclusion: facet `fac` is slave `s`'s own or touches one of its own facets
/// (WGSL: `excluded`). `adjacency` as in local_search.wgsl.
pub fn excluded(
    p: &SearchParams,
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    fac: [u32; 4],
) -> bool {
    use crate::abi::search::FLAG_SELF_CONTACT;
    if p.flags & FLAG_SELF_CONTACT == 0 {
        return false;
    }
    for &node in &fac[..facet_node_count(fac)] {
        if node == s {
            return true;
        }
        for k in adjacency[s as usize]..adjacency[s as usize + 1] {
            let own = facets[adjacency[k as usize] as usize];
            if own[..facet_node_count(own)].contains(&node) {
                return true;
            }
        }
    }
    false
}

/// Whether two facets share a node (WGSL: `share_node`).
pub fn share_node(a: [u32; 4], b: [u32; 4]) -> bool {
    a[..facet_node_count(a)]
        .iter()
        .any(|n| b[..facet_node_count(b)].contains(n))
}

/// Whether facet `f`'s edge (`a`, `b`) is shared by another active facet (WGSL: `edge_shared`;
/// `f` and the adjacency entries are active facet indices).
pub fn edge_shared(facets: &[[u32; 4]], adjacency: &[u32], f: u32, a: u32, b: u32) -> bool {
    (adjacency[a as usize]..adjacency[a as usize + 1]).any(|k| {
        let g = adjacency[k as usize];
        let fg = facets[g as usize];
        g != f && fg[..facet_node_count(fg)].contains(&b)
    })
}

/// Whether node `a` ends an unshared edge (3D) or is the end of a single segment (2D)
/// (WGSL: `vertex_free`).
pub fn vertex_free(facets: &[[u32; 4]], adjacency: &[u32], a: u32) -> bool {
    let (s, e) = (adjacency[a as usize], adjacency[a as usize + 1]);
    for k in s..e {
        let g = adjacency[k as usize];
        let fg = facets[g as usize];
        let ng = facet_node_count(fg);
        if ng == 2 {
            return e - s < 2;
        }
        for j in 0..ng {
            if fg[j] == a
                && (!edge_shared(facets, adjacency, g, a, fg[(j + 1) % ng])
                    || !edge_shared(facets, adjacency, g, a, fg[(j + ng - 1) % ng]))
            {
                return true;
            }
        }
    }
    false
}

/// The master surface's extension zone beyond its free edges and corners, a fraction of the
/// facet's size (longest edge): Abaqus/Explicit's `EXTENSION ZONE` of contact pairs, default
/// 0.1. A slave within it is on the edge (in contact with the facet extended), not beside it,
/// so that a node pressed onto a master that ends under it — which bulges out by its Poisson
/// strain, or sits there to round-off — is neither released nor launched when it moves back
/// (WGSL: `EXTENSION_ZONE`).
pub const EXTENSION_ZONE: f32 = 0.1;

/// The slave at `p`, nearest to facet `f` (nodes `fac`) at point `c` with weights `w` and unit
/// normal `nrm`, is beside a free boundary of the master: `c` lies on an unshared edge or on a
/// corner of one, and `p` is off to the side of it by more than the extension zone
/// ([`EXTENSION_ZONE`] of the facet's size) (WGSL: `beside_free_edge`).
#[allow(clippy::too_many_arguments)]
pub fn beside_free_edge(
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    f: u32,
    fac: [u32; 4],
    w: [f32; 4],
    p: V3<f32>,
    c: V3<f32>,
    nrm: V3<f32>,
) -> bool {
    let n = facet_node_count(fac);
    let (mut on, mut a, mut b) = (0, NO_NODE, NO_NODE);
    for j in 0..n {
        if w[j] != 0.0 {
            on += 1;
            if a == NO_NODE {
                a = fac[j];
            } else {
                b = fac[j];
            }
        }
    }
    if on == n {
        return false; // inside the facet
    }
    let mut h = 0.0f32;
    for j in 0..n {
        h = h.max(
            (node(nodes, fac[(j + 1) % n]) - node(nodes, fac[j]))
                .length2()
                .sqrt(),
        );
    }
    let d = p - c;
    let lateral = d - nrm * d.dot(nrm);
    if lateral.length2() <= EXTENSION_ZONE * EXTENSION_ZONE * h * h {
        return false;
    }
    match on {
        1 => vertex_free(facets, adjacency, a),
        2 if n > 2 => !edge_shared(facets, adjacency, f, a, b),
        _ => false,
    }
}
