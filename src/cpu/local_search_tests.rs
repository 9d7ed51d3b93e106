//! Tests of the CPU mirror of the local search (`super`): the pruned walk and the skin against
//! the walk that projects every facet at every step.

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
    let mut candidates: u32;
    let consider = |candidates: &mut u32, f: u32, best: &mut u32, d2: &mut f32| {
        let fac = facets[f as usize];
        if excluded(params, facets, adjacency, s, fac) || facet_collapsed(nodes, fac) {
            return;
        }
        *candidates += 1;
        let pr = project(nodes, p, fac);
        if *best == NO_FACET || pr.dist2 < *d2 || (pr.dist2 == *d2 && f < *best) {
            *best = f;
            *d2 = pr.dist2;
        }
    };
    let mut it = 0;
    let mut found: (u32, f32);
    let settled = loop {
        // the facets counted are the last step's
        candidates = 0;
        let (mut best, mut d2) = (NO_FACET, 0.0f32);
        for k in adjacency[tracked as usize]..adjacency[tracked as usize + 1] {
            consider(&mut candidates, adjacency[k as usize], &mut best, &mut d2);
        }
        if params.flags & FLAG_WIDE_LOCAL != 0 && best != NO_FACET {
            let near = facets[best as usize];
            for &n in &near[..facet_node_count(near)] {
                if n != tracked {
                    for q in adjacency[n as usize]..adjacency[n as usize + 1] {
                        consider(&mut candidates, adjacency[q as usize], &mut best, &mut d2);
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

/// On a flat grid of quads, a slave over a facet that moves less than its margin is
/// projected on that facet alone (no new skin: no walk), with the walk's bits; one that moves
/// past it, or nearer another node of the facet, walks again.
#[test]
fn a_slave_within_its_skin_does_not_walk() {
    let (mut nodes, facets, adjacency) = mesh(6, 6, 0, &[0.0], &[[2.3, 2.3, 0.05]]);
    let s = 36;
    let params = SearchParams {
        radius: 0.5,
        n_facets: facets.len() as u32,
        max_local_iterations: 8,
        ref_node: 0,
        ..bytemuck::Zeroable::zeroed()
    };
    let first = GpuHit {
        node: 14,
        ..GpuHit::miss(s, 0)
    };
    let (walked, skin, _, _) = track(
        &params, &nodes, &facets, &adjacency, s, first, [0.0; 4], 0.0,
    );
    let skin = skin.expect("a settled walk within the radius leaves a skin");
    assert!(walked.candidates & HIT_WALKED != 0);
    // the nearest other facet, 0.3 away in the plane and 0.05 below
    let margin = (0.3f32 * 0.3 + 0.05 * 0.05).sqrt();
    assert!((skin[3] - margin).abs() < 1e-5, "{skin:?}");
    // within: 0.05 + 0.15 < 0.304; past the margin: 0.05 + 0.27 > 0.304; past the nearest
    // node: 2.6 is nearer node 15
    for (shift, walks) in [(0.1f32, false), (0.15, false), (-0.27, true), (0.3, true)] {
        nodes[s as usize][0] = 2.3 + shift;
        let unskinned = GpuHit {
            candidates: walked.candidates & !HIT_WALKED,
            ..walked
        };
        let (kept, _, _, walked_again) =
            track(&params, &nodes, &facets, &adjacency, s, walked, skin, 0.0);
        let (full, _, _, _) = track(
            &params, &nodes, &facets, &adjacency, s, unskinned, skin, 0.0,
        );
        assert_eq!(walked_again, walks, "moved {shift}");
        assert_eq!(bytemuck::bytes_of(&kept), bytemuck::bytes_of(&full));
    }
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
            let (hit, _, outcome, _) =
                track(&params, &nodes, &facets, &adjacency, s, hit_in, [0.0; 4], 0.0);
            let (best, node, d2, candidates, steps) =
                track_every_facet(&params, &nodes, &facets, &adjacency, s, tracked);
            prop_assert_eq!(outcome, steps);
            prop_assert_eq!(hit.node, node);
            prop_assert_eq!(hit.candidates & HIT_COUNT, candidates);
            if best != NO_FACET && d2 <= params.radius * params.radius {
                prop_assert_eq!(hit.facet, best);
                prop_assert_eq!(hit.normal_dist[3].to_bits(), d2.sqrt().to_bits());
            } else {
                prop_assert_eq!(hit.facet, NO_FACET);
            }
        }
    }

    /// The skin changes nothing but the time: after a walk on moved positions, the slave
    /// and the master moved again (each master node by its own amount, all of them by a
    /// common drift the reference node shares), the hit from the skin equals the walk's from
    /// the same tracked node in every field — on warped quads, triangles and segments, with
    /// and without the wide search and self-contact, at motions from none to half a facet.
    #[test]
    fn the_skin_changes_nothing_but_the_time(
        kind in 0u8..3,
        bumps in prop::collection::vec(-1.0f32..1.0, 16..64),
        slaves in prop::collection::vec(
            (-1.0f32..8.0, -1.0f32..8.0, -1.2f32..1.2).prop_map(|(x, y, z)| [x, y, z]),
            1..8,
        ),
        moves in prop::collection::vec(-1.0f32..1.0, 16..64),
        scale in prop::sample::select(vec![0.0f32, 1e-4, 1e-3, 1e-2, 0.1, 0.5]),
        drift in (-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0),
        start in 0u32..64,
        wide in any::<bool>(),
        self_contact in any::<bool>(),
    ) {
        let (nx, ny) = (8, if kind == 2 { 1 } else { 7 });
        let (reference, facets, adjacency) = mesh(nx, ny, kind, &bumps, &slaves);
        let n_grid = (nx * ny) as u32;
        let params = SearchParams {
            radius: 1.5,
            n_facets: facets.len() as u32,
            max_local_iterations: 8,
            ref_node: 3,
            flags: (u32::from(wide) * FLAG_WIDE_LOCAL) | (u32::from(self_contact) * FLAG_SELF_CONTACT),
            ..bytemuck::Zeroable::zeroed()
        };
        let planar = kind == 2;
        // two moves from the reference: the walk's positions, then the skin's
        let moved = |step: usize| -> Vec<[f32; 4]> {
            let k = step as f32;
            reference
                .iter()
                .enumerate()
                .map(|(n, x)| {
                    let m = |a: usize| moves[(7 * n + 3 * a + step) % moves.len()] * scale * 0.5;
                    let z = if planar { 0.0 } else { m(2) + k * drift.2 };
                    [x[0] + m(0) + k * drift.0, x[1] + m(1) + k * drift.1, x[2] + z, 0.0]
                })
                .collect()
        };
        // how far the master nodes moved from the reference, relative to the reference node
        // (motion.wgsl's measure, STATUS_MOTION)
        let masters = |x: &[[f32; 4]]| -> f32 {
            let r = params.ref_node as usize;
            let base = node(x, r as u32) - node(&reference, r as u32);
            (0..n_grid)
                .map(|n| ((node(x, n) - node(&reference, n)) - base).length2().sqrt())
                .fold(0.0f32, f32::max)
        };
        let (walk_at, skin_at) = (moved(1), moved(2));
        let mut s_list: Vec<u32> = (n_grid..reference.len() as u32).collect();
        if self_contact {
            s_list.push(start % n_grid);
        }
        for s in s_list {
            let tracked = (start * 7 + s) % n_grid;
            let first = GpuHit { node: tracked, ..GpuHit::miss(s, 0) };
            let (walked, skin, _, _) = track(
                &params, &walk_at, &facets, &adjacency, s, first, [0.0; 4], masters(&walk_at),
            );
            prop_assert_eq!(skin.is_some(), walked.candidates & HIT_WALKED != 0);
            let now = masters(&skin_at);
            let skin = skin.unwrap_or([0.0; 4]);
            let (kept, _, steps, _) =
                track(&params, &skin_at, &facets, &adjacency, s, walked, skin, now);
            let unskinned = GpuHit { candidates: walked.candidates & !HIT_WALKED, ..walked };
            let (full, _, full_steps, _) =
                track(&params, &skin_at, &facets, &adjacency, s, unskinned, skin, now);
            prop_assert_eq!(steps, full_steps);
            prop_assert_eq!(bytemuck::bytes_of(&kept), bytemuck::bytes_of(&full));
        }
    }
}
