//! CPU mirror of `shaders/local_search.wgsl`: tracking between global searches.

use rayon::prelude::*;

use super::common::{excluded, facet_collapsed, facet_node_count, node};
use super::nearest_facet::project;
use crate::abi::search::*;
use crate::abi::status::{STATUS_BUDGET_EXCEEDED, STATUS_LOCAL_CAPPED, STATUS_LOCAL_ITERATIONS};
use crate::geometry::{Projection, V3};
use crate::model::NO_NODE;

struct Best {
    facet: u32,
    d2: f32,
    pr: Option<Projection<f32>>,
    candidates: u32,
}

#[allow(clippy::too_many_arguments)]
fn consider(
    b: &mut Best,
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    p: V3<f32>,
    f: u32,
) {
    let fac = facets[f as usize];
    if excluded(params, facets, adjacency, s, fac) || facet_collapsed(nodes, fac) {
        return;
    }
    b.candidates += 1;
    let pr = project(nodes, p, fac);
    if b.facet == NO_FACET || pr.dist2 < b.d2 || (pr.dist2 == b.d2 && f < b.facet) {
        b.facet = f;
        b.d2 = pr.dist2;
        b.pr = Some(pr);
    }
}

/// One "invocation" per active slave (WGSL: `local_search`): `active` holds the count, then
/// the slave indices (`cpu::active`); an untracked slave keeps its hit.
#[allow(clippy::too_many_arguments)]
pub fn local_search(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    slaves: &[u32],
    adjacency: &[u32],
    status: &mut [u32],
    hits: &mut [GpuHit],
    active: &[u32],
) {
    if status[STATUS_BUDGET_EXCEEDED] != 0 {
        return;
    }
    let n = active.first().map_or(0, |&c| c as usize);
    let list = active.get(1..1 + n).unwrap_or(&[]);
    let hits_in: &[GpuHit] = hits;
    // per slave: its new hit and (iterations, 1 when its walk hit the cap), reduced as the
    // GPU's atomics are
    let walked: Vec<(u32, GpuHit, (u32, u32))> = list
        .par_iter()
        .with_min_len(super::PAR_MIN)
        .filter(|&&i| hits_in[i as usize].node != NO_NODE)
        .map(|&i| {
            let (hit, outcome) = track(
                params,
                nodes,
                facets,
                adjacency,
                slaves[i as usize],
                hits_in[i as usize].node,
            );
            (i, hit, outcome)
        })
        .collect();
    let (mut most, mut capped) = (0, 0);
    for (i, hit, (it, cap)) in walked {
        hits[i as usize] = hit;
        most = most.max(it);
        capped += cap;
    }
    status[STATUS_LOCAL_ITERATIONS] = status[STATUS_LOCAL_ITERATIONS].max(most);
    status[STATUS_LOCAL_CAPPED] += capped;
}

/// Slave `s`'s walk from its tracked node `tracked`: its hit, and (iterations, 1 when the walk
/// hit the cap).
fn track(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    mut tracked: u32,
) -> (GpuHit, (u32, u32)) {
    let p = node(nodes, s);
    let mut hit = GpuHit::miss(s, 0);
    let mut b = Best {
        facet: NO_FACET,
        d2: 0.0,
        pr: None,
        candidates: 0,
    };
    let mut it = 0;
    let mut settled = false;
    loop {
        b.facet = NO_FACET;
        b.d2 = 0.0;
        for k in adjacency[tracked as usize]..adjacency[tracked as usize + 1] {
            consider(
                &mut b,
                params,
                nodes,
                facets,
                adjacency,
                s,
                p,
                adjacency[k as usize],
            );
        }
        if params.flags & FLAG_WIDE_LOCAL != 0 && b.facet != NO_FACET {
            let near = facets[b.facet as usize];
            for &n in &near[..facet_node_count(near)] {
                if n == tracked {
                    continue;
                }
                for q in adjacency[n as usize]..adjacency[n as usize + 1] {
                    consider(
                        &mut b,
                        params,
                        nodes,
                        facets,
                        adjacency,
                        s,
                        p,
                        adjacency[q as usize],
                    );
                }
            }
        }
        it += 1;
        if b.facet == NO_FACET {
            settled = true;
            break;
        }
        let fac = facets[b.facet as usize];
        let mut next = NO_NODE;
        let mut nd2 = 0.0f32;
        for &n in &fac[..facet_node_count(fac)] {
            let d2 = (node(nodes, n) - p).length2();
            if next == NO_NODE || d2 < nd2 || (d2 == nd2 && n < next) {
                next = n;
                nd2 = d2;
            }
        }
        if next == tracked {
            settled = true;
            break;
        }
        tracked = next;
        if it >= params.max_local_iterations {
            break;
        }
    }
    let outcome = (it, u32::from(!settled));
    hit.candidates = b.candidates;
    hit.node = tracked;
    if let (true, Some(pr)) = (
        b.facet != NO_FACET && b.d2 <= params.radius * params.radius,
        b.pr,
    ) {
        let q = pr.point;
        hit.facet = b.facet;
        hit.point_gap = [q.x, q.y, q.z, (p - q).dot(pr.normal)];
        hit.normal_dist = [pr.normal.x, pr.normal.y, pr.normal.z, b.d2.sqrt()];
        hit.weights = pr.weights;
        if super::common::beside_free_edge(
            nodes,
            facets,
            adjacency,
            b.facet,
            facets[b.facet as usize],
            pr.weights,
            p,
            q,
            pr.normal,
        ) {
            hit.candidates |= HIT_BESIDE_FREE_EDGE;
        }
    }
    (hit, outcome)
}
