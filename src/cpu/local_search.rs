//! CPU mirror of `shaders/local_search.wgsl`: tracking between global searches.

use rayon::prelude::*;

use super::common::{excluded, facet_box_d2, facet_collapsed, facet_node_count, node};
use super::nearest_facet::{project, PRUNE_SLACK};
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

/// Facet `f` around the slave at `p` (WGSL: `consider`): counted unless excluded or collapsed,
/// projected unless its nodes' box is farther than the best by more than round-off
/// ([`PRUNE_SLACK`]), kept when nearer (ties: lowest id); the best itself is counted, not
/// projected again.
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
    if b.facet != NO_FACET && (f == b.facet || facet_box_d2(nodes, fac, p) > b.d2 * PRUNE_SLACK) {
        return;
    }
    let pr = project(nodes, p, fac);
    if b.facet == NO_FACET || pr.dist2 < b.d2 || (pr.dist2 == b.d2 && f < b.facet) {
        b.facet = f;
        b.d2 = pr.dist2;
        b.pr = Some(pr);
    }
}

/// Whether facet `f` (an active facet id, or [`NO_FACET`]) has node `node` (WGSL: `has_node`).
fn has_node(facets: &[[u32; 4]], f: u32, node: u32) -> bool {
    facets
        .get(f as usize)
        .is_some_and(|fac| fac[..facet_node_count(*fac)].contains(&node))
}

/// One "invocation" per active slave (WGSL: `local_search`): `active` holds the count, then
/// the slave indices (`cpu::active`); an untracked slave keeps its hit. A walked slave that
/// crossed the radius has its tracking state written into the w of its `reference` (by model
/// node).
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
    reference: &mut [[f32; 4]],
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
                hits_in[i as usize],
            );
            (i, hit, outcome)
        })
        .collect();
    let (mut most, mut capped) = (0, 0);
    for (i, hit, (it, cap)) in walked {
        // written where the slave crossed the radius alone (WGSL: the same)
        if (hit.facet != NO_FACET) != (hits[i as usize].facet != NO_FACET) {
            reference[slaves[i as usize] as usize][3] = slave_state(&hit);
        }
        hits[i as usize] = hit;
        most = most.max(it);
        capped += cap;
    }
    status[STATUS_LOCAL_ITERATIONS] = status[STATUS_LOCAL_ITERATIONS].max(most);
    status[STATUS_LOCAL_CAPPED] += capped;
}

/// Slave `s`'s walk from the tracked node of its last hit `last`: its hit, and (iterations, 1
/// when the walk hit the cap).
fn track(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    last: GpuHit,
) -> (GpuHit, (u32, u32)) {
    let mut tracked = last.node;
    let p = node(nodes, s);
    let mut hit = GpuHit::miss(s, 0);
    let mut b = Best {
        facet: NO_FACET,
        d2: 0.0,
        pr: None,
        candidates: 0,
    };
    // the first projection: the last search's facet when it is one around the tracked node
    if has_node(facets, last.facet, tracked) {
        let fac = facets[last.facet as usize];
        if !excluded(params, facets, adjacency, s, fac) && !facet_collapsed(nodes, fac) {
            let pr = project(nodes, p, fac);
            b.facet = last.facet;
            b.d2 = pr.dist2;
            b.pr = Some(pr);
        }
    }
    let mut it = 0;
    let mut settled = false;
    loop {
        // the best carries over: it has the new tracked node
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The walk as it was before the box test and the carried best: every facet around the
    /// tracked node projected at every step. The reference the pruned walk must equal.
    fn track_every_facet(
        params: &SearchParams,
        nodes: &[[f32; 4]],
        facets: &[[u32; 4]],
        adjacency: &[u32],
        s: u32,
        mut tracked: u32,
    ) -> (u32, u32, f32, u32, (u32, u32)) {
        let p = node(nodes, s);
        let mut candidates = 0;
        let mut consider = |f: u32, best: &mut u32, d2: &mut f32| {
            let fac = facets[f as usize];
            if excluded(params, facets, adjacency, s, fac) || facet_collapsed(nodes, fac) {
                return;
            }
            candidates += 1;
            let pr = project(nodes, p, fac);
            if *best == NO_FACET || pr.dist2 < *d2 || (pr.dist2 == *d2 && f < *best) {
                *best = f;
                *d2 = pr.dist2;
            }
        };
        let mut it = 0;
        let mut found: (u32, f32);
        let settled = loop {
            let (mut best, mut d2) = (NO_FACET, 0.0f32);
            for k in adjacency[tracked as usize]..adjacency[tracked as usize + 1] {
                consider(adjacency[k as usize], &mut best, &mut d2);
            }
            if params.flags & FLAG_WIDE_LOCAL != 0 && best != NO_FACET {
                let near = facets[best as usize];
                for &n in &near[..facet_node_count(near)] {
                    if n != tracked {
                        for q in adjacency[n as usize]..adjacency[n as usize + 1] {
                            consider(adjacency[q as usize], &mut best, &mut d2);
                        }
                    }
                }
            }
            it += 1;
            found = (best, d2);
            if best == NO_FACET {
                break true;
            }
            let fac = facets[best as usize];
            let mut next = NO_NODE;
            let mut nd2 = 0.0f32;
            for &n in &fac[..facet_node_count(fac)] {
                let e = (node(nodes, n) - p).length2();
                if next == NO_NODE || e < nd2 || (e == nd2 && n < next) {
                    next = n;
                    nd2 = e;
                }
            }
            if next == tracked {
                break true;
            }
            tracked = next;
            if it >= params.max_local_iterations {
                break false;
            }
        };
        (
            found.0,
            tracked,
            found.1,
            candidates,
            (it, u32::from(!settled)),
        )
    }

    /// A warped grid of `nx` × `ny` nodes (heights and in-plane jitter from `bumps`), meshed in
    /// quads, in triangles or (`dim` 2) in segments along x, some facets collapsed onto a
    /// line; the slaves are extra nodes after the grid. Returns nodes, facets and adjacency
    /// (each node's facets, increasing, as local_search.wgsl reads them).
    fn mesh(
        nx: usize,
        ny: usize,
        kind: u8,
        bumps: &[f32],
        slaves: &[[f32; 3]],
    ) -> (Vec<[f32; 4]>, Vec<[u32; 4]>, Vec<u32>) {
        let mut nodes = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let b = |k: usize| bumps[(3 * (j * nx + i) + k) % bumps.len()];
                nodes.push([i as f32 + 0.3 * b(0), j as f32 + 0.3 * b(1), b(2), 0.0]);
            }
        }
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        let mut facets = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                match kind {
                    0 => facets.push(q),
                    1 => {
                        facets.push([q[0], q[1], q[2], NO_NODE]);
                        facets.push([q[0], q[2], q[3], NO_NODE]);
                    }
                    _ => {}
                }
            }
        }
        if kind == 2 {
            for j in 0..ny {
                for i in 0..nx - 1 {
                    facets.push([id(i, j), id(i + 1, j), NO_NODE, NO_NODE]);
                }
            }
        }
        // a few facets collapsed: a node moved onto its neighbour
        let n_grid = nodes.len();
        for k in (0..n_grid).step_by(17) {
            if bumps[k % bumps.len()] > 0.8 && k + 1 < n_grid {
                nodes[k] = nodes[k + 1];
            }
        }
        nodes.extend(slaves.iter().map(|s| [s[0], s[1], s[2], 0.0]));
        let n = nodes.len();
        let mut around = vec![Vec::new(); n];
        for (f, fac) in facets.iter().enumerate() {
            for &k in &fac[..facet_node_count(*fac)] {
                around[k as usize].push(f as u32);
            }
        }
        let mut adjacency = Vec::with_capacity(n + 1);
        let mut start = n as u32 + 1;
        for list in &around {
            adjacency.push(start);
            start += list.len() as u32;
        }
        adjacency.push(start);
        for list in around {
            adjacency.extend(list);
        }
        (nodes, facets, adjacency)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]
        /// The box test, the carried best and the first projection from the last hit's facet
        /// change nothing but the time: the facet, tracked node, distance, facets counted and
        /// steps are those of the walk that projects every facet at every step — on warped
        /// quads, triangles and segments, with and without the wide search, with self-contact
        /// (the slave one of the grid's own nodes), from any tracked node and any last facet.
        #[test]
        fn pruning_changes_nothing_but_the_time(
            kind in 0u8..3,
            bumps in prop::collection::vec(-1.0f32..1.0, 16..64),
            slaves in prop::collection::vec(
                (-1.0f32..8.0, -1.0f32..8.0, -2.0f32..2.0).prop_map(|(x, y, z)| [x, y, z]),
                1..8,
            ),
            start in 0u32..64,
            last in 0u32..300,
            wide in any::<bool>(),
            self_contact in any::<bool>(),
            iterations in 1u32..6,
        ) {
            let (nx, ny) = (8, if kind == 2 { 1 } else { 7 });
            let (nodes, facets, adjacency) = mesh(nx, ny, kind, &bumps, &slaves);
            let n_grid = (nx * ny) as u32;
            let params = SearchParams {
                radius: 1.5,
                n_facets: facets.len() as u32,
                max_local_iterations: iterations,
                flags: (u32::from(wide) * FLAG_WIDE_LOCAL) | (u32::from(self_contact) * FLAG_SELF_CONTACT),
                ..bytemuck::Zeroable::zeroed()
            };
            let mut s_list: Vec<u32> = (n_grid..nodes.len() as u32).collect();
            if self_contact {
                s_list.push(start % n_grid);
            }
            for s in s_list {
                let tracked = (start * 7 + s) % n_grid;
                // the last hit's facet: mostly one around the tracked node, else any or none
                let around = &adjacency[adjacency[tracked as usize] as usize
                    ..adjacency[tracked as usize + 1] as usize];
                let facet = match (last, around.len() as u32) {
                    (l, n) if l < 200 && n > 0 => around[(l % n) as usize],
                    (l, _) if l < 250 && l < facets.len() as u32 => l,
                    _ => NO_FACET,
                };
                let hit_in = GpuHit { node: tracked, facet, ..GpuHit::miss(s, 0) };
                let (hit, outcome) = track(&params, &nodes, &facets, &adjacency, s, hit_in);
                let (best, node, d2, candidates, steps) =
                    track_every_facet(&params, &nodes, &facets, &adjacency, s, tracked);
                prop_assert_eq!(outcome, steps);
                prop_assert_eq!(hit.node, node);
                prop_assert_eq!(hit.candidates & !HIT_BESIDE_FREE_EDGE, candidates);
                if best != NO_FACET && d2 <= params.radius * params.radius {
                    prop_assert_eq!(hit.facet, best);
                    prop_assert_eq!(hit.normal_dist[3].to_bits(), d2.sqrt().to_bits());
                } else {
                    prop_assert_eq!(hit.facet, NO_FACET);
                }
            }
        }
    }
}
