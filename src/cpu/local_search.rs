//! CPU mirror of `shaders/local_search.wgsl`: tracking between global searches, and the skin
//! within which a slave is projected on its last facet alone (the shader's header says why that
//! is the walk's result).

use super::common::{excluded, facet_box_d2, facet_collapsed, facet_node_count, node};
use super::nearest_facet::{project, PRUNE_SLACK};
use crate::abi::search::*;
use crate::abi::status::{
    STATUS_BUDGET_EXCEEDED, STATUS_LOCAL_CAPPED, STATUS_LOCAL_ITERATIONS, STATUS_LOCAL_WALKS,
    STATUS_MASTER_MOTION,
};
use crate::geometry::{Projection, V3};
use crate::model::NO_NODE;

struct Best {
    facet: u32,
    d2: f32,
    pr: Option<Projection<f32>>,
    candidates: u32,
    /// The best's box distance² (a lower bound of its distance).
    lb2: f32,
    /// The least lower bound² of the other facets this step examined.
    second: f32,
    /// This step passed over a collapsed facet.
    collapsed: bool,
}

/// Facet `f` around the slave at `p` (WGSL: `consider`): counted unless excluded or collapsed,
/// projected unless its nodes' box is farther than the best by more than round-off
/// ([`PRUNE_SLACK`]), kept when nearer (ties: lowest id); the best itself is counted, not
/// projected again; every other facet's box distance² (a lower bound of its distance) lowers
/// the step's second.
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
    if excluded(params, facets, adjacency, s, fac) {
        return;
    }
    if facet_collapsed(nodes, fac) {
        b.collapsed = true;
        return;
    }
    b.candidates += 1;
    if f == b.facet {
        return;
    }
    let box_d2 = facet_box_d2(nodes, fac, p);
    if b.facet != NO_FACET && box_d2 > b.d2 * PRUNE_SLACK {
        b.second = b.second.min(box_d2);
        return;
    }
    let pr = project(nodes, p, fac);
    if b.facet == NO_FACET || pr.dist2 < b.d2 || (pr.dist2 == b.d2 && f < b.facet) {
        if b.facet != NO_FACET {
            b.second = b.second.min(b.lb2);
        }
        b.facet = f;
        b.d2 = pr.dist2;
        b.pr = Some(pr);
        b.lb2 = box_d2;
    } else {
        b.second = b.second.min(box_d2);
    }
}

/// Whether facet `f` (an active facet id, or [`NO_FACET`]) has node `node` (WGSL: `has_node`).
fn has_node(facets: &[[u32; 4]], f: u32, node: u32) -> bool {
    facets
        .get(f as usize)
        .is_some_and(|fac| fac[..facet_node_count(*fac)].contains(&node))
}

/// The node of facet `fac` nearest `p`, ties to the lowest id (WGSL: `nearest_node`).
fn nearest_node(nodes: &[[f32; 4]], fac: [u32; 4], p: V3<f32>) -> u32 {
    let mut next = NO_NODE;
    let mut nd2 = 0.0f32;
    for &n in &fac[..facet_node_count(fac)] {
        let d2 = (node(nodes, n) - p).length2();
        if next == NO_NODE || d2 < nd2 || (d2 == nd2 && n < next) {
            next = n;
            nd2 = d2;
        }
    }
    next
}

/// The largest absolute coordinate of `x` (WGSL: `max_abs`).
fn max_abs(x: V3<f32>) -> f32 {
    x.x.abs().max(x.y.abs()).max(x.z.abs())
}

/// One "invocation" per active slave (WGSL: `local_search`): `active` holds the count, then
/// the slave indices (`cpu::active`); an untracked slave keeps its hit. A walked slave that
/// crossed the radius has its tracking state written into the w of its `reference` (by model
/// node); a settled walk writes the slave's skin into `skins` (by slave).
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
    skins: &mut [[f32; 4]],
) {
    if status[STATUS_BUDGET_EXCEEDED] != 0 {
        return;
    }
    let n = active.first().map_or(0, |&c| c as usize);
    let list = active.get(1..1 + n).unwrap_or(&[]);
    let masters = f32::from_bits(status[STATUS_MASTER_MOTION]);
    // per chunk of slaves: the most steps of a walk, the walks stopped at the cap, the slaves
    // walked, and the tracking states to write (where a slave crossed the radius: few), reduced
    // as the shader reduces them per workgroup
    type Walks = (u32, u32, u32, Vec<(u32, f32)>);
    let join = |a: Walks, b: Walks| {
        let mut crossed = a.3;
        crossed.extend(b.3);
        (a.0.max(b.0), a.1 + b.1, a.2 + b.2, crossed)
    };
    let (most, capped, walks, crossed) = super::for_listed(
        list,
        hits,
        skins,
        || (0, 0, 0, Vec::new()),
        join,
        |i, hit, skin, w: &mut Walks| {
            if hit.node == NO_NODE {
                return;
            }
            let s = slaves[i];
            let (new, new_skin, (it, cap), walked) =
                track(params, nodes, facets, adjacency, s, *hit, *skin, masters);
            // written where the slave crossed the radius alone (WGSL: the same)
            if (new.facet != NO_FACET) != (hit.facet != NO_FACET) {
                w.3.push((s, slave_state(&new)));
            }
            *hit = new;
            if let Some(k) = new_skin {
                *skin = k;
            }
            w.0 = w.0.max(it);
            w.1 += cap;
            w.2 += u32::from(walked);
        },
    );
    for (s, state) in crossed {
        reference[s as usize][3] = state;
    }
    status[STATUS_LOCAL_ITERATIONS] = status[STATUS_LOCAL_ITERATIONS].max(most);
    status[STATUS_LOCAL_CAPPED] += capped;
    status[STATUS_LOCAL_WALKS] += walks;
}

/// Slave `s`'s hit (tracked node `tracked`, facets counted `candidates` with its flags): facet
/// `f` with projection `pr` when it is one within the radius, else none (WGSL: `write_hit`,
/// but the tracking state, which the caller writes).
#[allow(clippy::too_many_arguments)]
fn hit_of(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    p: V3<f32>,
    tracked: u32,
    f: u32,
    pr: Option<Projection<f32>>,
    candidates: u32,
) -> GpuHit {
    let mut hit = GpuHit::miss(s, candidates);
    hit.node = tracked;
    match pr {
        Some(pr) if f != NO_FACET && pr.dist2 <= params.radius * params.radius => {
            let q = pr.point;
            hit.facet = f;
            hit.point_gap = [q.x, q.y, q.z, (p - q).dot(pr.normal)];
            hit.normal_dist = [pr.normal.x, pr.normal.y, pr.normal.z, pr.dist2.sqrt()];
            hit.weights = pr.weights;
            if super::common::beside_free_edge(
                nodes,
                facets,
                adjacency,
                f,
                facets[f as usize],
                pr.weights,
                p,
                q,
                pr.normal,
            ) {
                hit.candidates |= HIT_BESIDE_FREE_EDGE;
            }
        }
        _ => hit.candidates &= !HIT_WALKED,
    }
    hit
}

/// Slave `s`'s walk from the tracked node of its last hit `last`, or its projection on that
/// hit's facet alone while within its `skin` (`masters`: how far the master nodes moved since
/// the global search, `STATUS_MASTER_MOTION`): its hit, its new skin when the walk left one,
/// (iterations, 1 when the walk hit the cap), and whether it walked.
#[allow(clippy::too_many_arguments)]
fn track(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    s: u32,
    last: GpuHit,
    skin: [f32; 4],
    masters: f32,
) -> (GpuHit, Option<[f32; 4]>, (u32, u32), bool) {
    let mut tracked = last.node;
    let p = node(nodes, s);
    let r = node(nodes, params.ref_node);
    let roundoff = SKIN_ROUNDOFF * (max_abs(p).max(max_abs(r)) + params.radius);
    let hit = |tracked: u32, f: u32, pr: Option<Projection<f32>>, candidates: u32| {
        hit_of(
            params, nodes, facets, adjacency, s, p, tracked, f, pr, candidates,
        )
    };
    let mut b = Best {
        facet: NO_FACET,
        d2: 0.0,
        pr: None,
        candidates: 0,
        lb2: 0.0,
        second: EMPTY_LO,
        collapsed: false,
    };
    // the first projection: the last search's facet when it is one around the tracked node
    if has_node(facets, last.facet, tracked) {
        let fac = facets[last.facet as usize];
        if !excluded(params, facets, adjacency, s, fac) && !facet_collapsed(nodes, fac) {
            let pr = project(nodes, p, fac);
            b.facet = last.facet;
            b.d2 = pr.dist2;
            b.lb2 = facet_box_d2(nodes, fac, p);
            b.pr = Some(pr);
            if last.candidates & HIT_WALKED != 0 {
                // within the skin: the walk would take the same facet and stay
                let moved = ((p - r) - V3::new(skin[0], skin[1], skin[2]))
                    .length2()
                    .sqrt()
                    + masters;
                if b.d2.sqrt() + moved + roundoff < skin[3]
                    && nearest_node(nodes, fac, p) == tracked
                {
                    let counted = last.candidates & (HIT_COUNT | HIT_WALKED);
                    return (hit(tracked, last.facet, b.pr, counted), None, (1, 0), false);
                }
            }
        }
    }
    let mut it = 0;
    let mut settled = false;
    let mut wide_from;
    loop {
        // a step: the facets counted and the skin's bounds are the last step's
        b.candidates = 0;
        b.second = EMPTY_LO;
        b.collapsed = false;
        // the best carries over: it has the new tracked node
        for k in adjacency[tracked as usize]..adjacency[tracked as usize + 1] {
            let f = adjacency[k as usize];
            consider(&mut b, params, nodes, facets, adjacency, s, p, f);
        }
        wide_from = b.facet;
        if params.flags & FLAG_WIDE_LOCAL != 0 && b.facet != NO_FACET {
            let near = facets[b.facet as usize];
            for &n in &near[..facet_node_count(near)] {
                if n == tracked {
                    continue;
                }
                for q in adjacency[n as usize]..adjacency[n as usize + 1] {
                    let f = adjacency[q as usize];
                    consider(&mut b, params, nodes, facets, adjacency, s, p, f);
                }
            }
        }
        it += 1;
        if b.facet == NO_FACET {
            settled = true;
            break;
        }
        let next = nearest_node(nodes, facets[b.facet as usize], p);
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
    let mut candidates = b.candidates;
    let mut new_skin = None;
    // a skin that would not hold even without motion is not left (its read would be wasted)
    let margin = b.second.sqrt() - masters;
    let within = b.d2 <= params.radius * params.radius;
    if settled
        && b.facet != NO_FACET
        && within
        && !b.collapsed
        && wide_from == b.facet
        && b.d2.sqrt() + roundoff < margin
    {
        let q = p - r;
        new_skin = Some([q.x, q.y, q.z, margin]);
        candidates |= HIT_WALKED;
    }
    (
        hit(tracked, b.facet, b.pr, candidates),
        new_skin,
        outcome,
        true,
    )
}

#[cfg(test)]
#[path = "local_search_tests.rs"]
mod tests;
