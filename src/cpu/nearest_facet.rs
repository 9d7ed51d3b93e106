//! CPU mirror of `shaders/nearest_facet.wgsl`: the nearest active facet of each slave node.

use super::common::{excluded, facet_node_count, node, share_node};
use crate::geometry::{closest_on_quad, closest_on_segment, closest_on_triangle, Projection, V3};
use crate::search::layout::{
    GpuHit, SearchParams, FLAG_SELF_CONTACT, HIT_BESIDE_FREE_EDGE, NO_FACET, STATUS_CROWDED,
    STATUS_OVERFLOW,
};

/// Nearest point on a padded facet (WGSL: `project`).
pub fn project(nodes: &[[f32; 4]], p: V3<f32>, fac: [u32; 4]) -> Projection<f32> {
    let n = facet_node_count(fac);
    let x0 = node(nodes, fac[0]);
    let x1 = node(nodes, fac[1]);
    if n == 2 {
        return closest_on_segment(p, x0, x1);
    }
    let x2 = node(nodes, fac[2]);
    if n == 3 {
        return closest_on_triangle(p, x0, x1, x2);
    }
    closest_on_quad(p, [x0, x1, x2, node(nodes, fac[3])])
}

/// One "invocation" per slave node; writes `hits[i]`. Skipped when the binning overflowed.
#[allow(clippy::too_many_arguments)]
pub fn nearest_facet(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    slaves: &[u32],
    starts: &[u32],
    entries: &[u32],
    status: &mut [u32],
    hits: &mut [GpuHit],
    adjacency: &[u32],
) {
    if status[STATUS_OVERFLOW] != 0 {
        return;
    }
    for i in 0..params.n_slaves as usize {
        let p = node(nodes, slaves[i]);
        let g = [
            p.x * params.inv_cell_size,
            p.y * params.inv_cell_size,
            p.z * params.inv_cell_size,
        ];
        let dims = [params.dims_x, params.dims_y, params.dims_z];
        let inside = (0..3).all(|a| g[a] >= 0.0 && g[a] < dims[a] as f32);
        if !inside {
            hits[i] = GpuHit::miss(slaves[i], 0);
            continue;
        }
        let c = super::common::cell_index(params, [g[0] as u32, g[1] as u32, g[2] as u32]) as usize;
        let (s, e) = (starts[c], starts[c + 1]);
        let mut best: Option<Projection<f32>> = None;
        let mut best_f = NO_FACET;
        let mut best_d2 = params.radius * params.radius;
        let slave = slaves[i];
        for k in s..e {
            let f = entries[k as usize];
            if excluded(params, facets, adjacency, slave, facets[f as usize]) {
                continue;
            }
            let pr = project(nodes, p, facets[f as usize]);
            if pr.dist2 < best_d2 || (best_f == NO_FACET && pr.dist2 == best_d2) {
                best = Some(pr);
                best_d2 = pr.dist2;
                best_f = f;
            }
        }
        if best_f != NO_FACET && params.flags & FLAG_SELF_CONTACT != 0 {
            let r2 = params.radius * params.radius;
            let crowded = (s..e).map(|k| entries[k as usize]).any(|f| {
                f != best_f
                    && !excluded(params, facets, adjacency, slave, facets[f as usize])
                    && !share_node(facets[f as usize], facets[best_f as usize])
                    && {
                        let pr = project(nodes, p, facets[f as usize]);
                        let gap = (p - pr.point).dot(pr.normal);
                        pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2
                    }
            });
            if crowded {
                status[STATUS_CROWDED] += 1;
            }
        }
        let Some(best) = best else {
            hits[i] = GpuHit::miss(slaves[i], e - s);
            continue;
        };
        let fac = facets[best_f as usize];
        let mut best_node = u32::MAX;
        let mut best_nd2 = 0.0f32;
        for &id in &fac[..facet_node_count(fac)] {
            let d2 = (node(nodes, id) - p).length2();
            if best_node == u32::MAX || d2 < best_nd2 || (d2 == best_nd2 && id < best_node) {
                best_node = id;
                best_nd2 = d2;
            }
        }
        let q = best.point;
        let fac = facets[best_f as usize];
        let beside = super::common::beside_free_edge(
            nodes,
            facets,
            adjacency,
            best_f,
            fac,
            best.weights,
            p,
            q,
            best.normal,
        );
        hits[i] = GpuHit {
            facet: best_f,
            node: best_node,
            candidates: (e - s) | if beside { HIT_BESIDE_FREE_EDGE } else { 0 },
            slave: slaves[i],
            point_gap: [q.x, q.y, q.z, (p - q).dot(best.normal)],
            normal_dist: [
                best.normal.x,
                best.normal.y,
                best.normal.z,
                best.dist2.sqrt(),
            ],
            weights: best.weights,
        };
    }
}
