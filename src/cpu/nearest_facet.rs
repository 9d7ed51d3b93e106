//! CPU mirror of `shaders/nearest_facet.wgsl`: the nearest active facet of each slave node.

use rayon::prelude::*;

use super::common::{excluded, facet_node_count, node, share_node};
use super::PAR_MIN;
use crate::geometry::{closest_on_quad, closest_on_segment, closest_on_triangle, Projection, V3};
use crate::search::layout::{
    GpuHit, SearchParams, FLAG_SELF_CONTACT, HIT_BESIDE_FREE_EDGE, NO_FACET, STATUS_CROWDED,
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

/// Candidates one work item projects at most (WGSL: `CANDIDATE_CHUNK`).
pub const CANDIDATE_CHUNK: u32 = 1024;

/// Words of a slave's `best` record: distance² bits, facet, crowded, candidates.
pub const BEST_WORDS: usize = 4;

/// The candidates of a node (WGSL: `Candidates`): the written bin entries of its cell, then
/// the spill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct NodeCandidates {
    /// First bin entry of the cell.
    start: u32,
    /// Written entries of the cell (those within the entry capacity).
    in_cell: u32,
    /// `in_cell` plus the spill.
    n: u32,
}

/// The candidates of a node at p; none outside the grid (WGSL: `candidates`).
fn candidates(
    params: &SearchParams,
    starts: &[u32],
    entries: &[u32],
    p: V3<f32>,
) -> NodeCandidates {
    let none = NodeCandidates {
        start: 0,
        in_cell: 0,
        n: 0,
    };
    let g = [
        (p.x - params.grid_lo[0]) * params.inv_cell_size,
        (p.y - params.grid_lo[1]) * params.inv_cell_size,
        (p.z - params.grid_lo[2]) * params.inv_cell_size,
    ];
    let dims = [params.dims_x, params.dims_y, params.dims_z];
    if !(0..3).all(|a| g[a] >= 0.0 && g[a] < dims[a] as f32) {
        return none;
    }
    let c = super::common::cell_index(params, [g[0] as u32, g[1] as u32, g[2] as u32]) as usize;
    let cap = params.entry_capacity;
    let start = starts[c].min(cap);
    let in_cell = starts[c + 1].min(cap) - start;
    NodeCandidates {
        start,
        in_cell,
        n: in_cell + entries[cap as usize],
    }
}

/// Candidate k of a node's candidates: a facet id (WGSL: `candidate`).
fn candidate(params: &SearchParams, entries: &[u32], c: NodeCandidates, k: u32) -> u32 {
    if k < c.in_cell {
        entries[(c.start + k) as usize]
    } else {
        entries[(params.entry_capacity + 1 + k - c.in_cell) as usize]
    }
}

/// The inputs every work-item pass reads.
#[derive(Clone, Copy)]
pub struct Candidates<'a> {
    /// Uniform parameters.
    pub params: &'a SearchParams,
    /// Grid-local node positions.
    pub nodes: &'a [[f32; 4]],
    /// Active facets, padded.
    pub facets: &'a [[u32; 4]],
    /// Node id per slave.
    pub slaves: &'a [u32],
    /// Cell starts (scanned counts).
    pub starts: &'a [u32],
    /// Bin entries.
    pub entries: &'a [u32],
    /// Node→facet adjacency.
    pub adjacency: &'a [u32],
}

/// The candidates work item t of slave i (candidates `nc`) covers: at most `CANDIDATE_CHUNK`
/// (WGSL: `chunk_range`).
fn chunk_range(work: &[u32], i: usize, t: u32, nc: NodeCandidates) -> (u32, u32) {
    let k0 = (t - work[i]) * CANDIDATE_CHUNK;
    (k0, nc.n.min(k0 + CANDIDATE_CHUNK))
}

/// The nearest facet (distance², id) of slave i among its work item t's candidates, within the
/// radius, ties to the lowest id (WGSL: `chunk_best`).
fn chunk_best(c: &Candidates<'_>, work: &[u32], i: usize, t: u32) -> (f32, u32) {
    let slave = c.slaves[i];
    let p = node(c.nodes, slave);
    let nc = candidates(c.params, c.starts, c.entries, p);
    let (k0, k1) = chunk_range(work, i, t, nc);
    let mut b = (c.params.radius * c.params.radius, NO_FACET);
    for k in k0..k1 {
        let f = candidate(c.params, c.entries, nc, k);
        if excluded(c.params, c.facets, c.adjacency, slave, c.facets[f as usize]) {
            continue;
        }
        let d2 = project(c.nodes, p, c.facets[f as usize]).dist2;
        if d2 < b.0 || (d2 == b.0 && f < b.1) {
            b = (d2, f);
        }
    }
    b
}

/// One "invocation" per slave: candidate count, chunk count into `work` (word n_slaves set to 0
/// for the scan), `best` reset (WGSL: `nearest_count`).
pub fn nearest_count(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    slaves: &[u32],
    starts: &[u32],
    entries: &[u32],
    work: &mut [u32],
    best: &mut [u32],
) {
    let n = params.n_slaves as usize;
    if n > 0 {
        work[n] = 0;
    }
    work[..n]
        .par_iter_mut()
        .zip(best.par_chunks_mut(BEST_WORDS))
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(i, (w, b))| {
            let count = candidates(params, starts, entries, node(nodes, slaves[i])).n;
            *w = count.div_ceil(CANDIDATE_CHUNK);
            b.copy_from_slice(&[
                (params.radius * params.radius).to_bits(),
                NO_FACET,
                0,
                count,
            ]);
        });
}

/// The number of work items, from the scanned `work` (WGSL: `nearest_args`, which writes the
/// indirect dispatch instead).
pub fn nearest_args(params: &SearchParams, work: &[u32]) -> u32 {
    work[params.n_slaves as usize]
}

/// The work items of each slave (`work` scanned: slave i owns items `work[i]..work[i + 1]`), in
/// parallel over the slaves on all cores, each slave's items in order, with its `best` record.
/// The GPU runs every work item as one invocation and combines a slave's through atomics whose
/// result does not depend on their order, so running a slave's items one after another on one
/// thread gives the same bits, whatever the number of threads.
fn per_slave_items(
    c: &Candidates<'_>,
    work: &[u32],
    best: &mut [u32],
    item: impl Fn(usize, u32, &mut [u32]) + Sync,
) {
    let n = c.params.n_slaves as usize;
    best[..BEST_WORDS * n]
        .par_chunks_mut(BEST_WORDS)
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(i, b)| {
            for t in work[i]..work[i + 1] {
                item(i, t, b);
            }
        });
}

/// One "invocation" per work item: the chunk's nearest facet (WGSL: `nearest_chunks`).
pub fn nearest_chunks(c: &Candidates<'_>, work: &[u32], best: &mut [u32]) {
    per_slave_items(c, work, best, |i, t, b| {
        let (d2, f) = chunk_best(c, work, i, t);
        if f == NO_FACET {
            return;
        }
        if work[i + 1] - work[i] == 1 {
            b[0] = d2.to_bits();
            b[1] = f;
        } else {
            b[0] = b[0].min(d2.to_bits());
        }
    });
}

/// One "invocation" per work item of slaves with several chunks: the lowest id at the best
/// distance (WGSL: `nearest_ties`).
pub fn nearest_ties(c: &Candidates<'_>, work: &[u32], best: &mut [u32]) {
    per_slave_items(c, work, best, |i, t, b| {
        if work[i + 1] - work[i] == 1 {
            return;
        }
        let (d2, f) = chunk_best(c, work, i, t);
        if f != NO_FACET && d2.to_bits() == b[0] {
            b[1] = b[1].min(f);
        }
    });
}

/// One "invocation" per work item, self-contact only: flags a slave with another facet near and
/// facing it (WGSL: `nearest_crowded`).
pub fn nearest_crowded(c: &Candidates<'_>, work: &[u32], best: &mut [u32]) {
    if c.params.flags & FLAG_SELF_CONTACT == 0 {
        return;
    }
    let r2 = c.params.radius * c.params.radius;
    per_slave_items(c, work, best, |i, t, b| {
        let best_f = b[1];
        if best_f == NO_FACET {
            return;
        }
        let slave = c.slaves[i];
        let p = node(c.nodes, slave);
        let nc = candidates(c.params, c.starts, c.entries, p);
        let (k0, k1) = chunk_range(work, i, t, nc);
        for k in k0..k1 {
            let f = candidate(c.params, c.entries, nc, k);
            if f == best_f
                || excluded(c.params, c.facets, c.adjacency, slave, c.facets[f as usize])
                || share_node(c.facets[f as usize], c.facets[best_f as usize])
            {
                continue;
            }
            let pr = project(c.nodes, p, c.facets[f as usize]);
            let gap = (p - pr.point).dot(pr.normal);
            if pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2 {
                b[2] = 1;
                break;
            }
        }
    });
}

/// One "invocation" per slave node: the hit from the winning facet; writes `hits[i]`
/// (WGSL: `nearest_facet`).
pub fn nearest_facet(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    slaves: &[u32],
    status: &mut [u32],
    hits: &mut [GpuHit],
    adjacency: &[u32],
    best: &[u32],
) {
    let n = params.n_slaves as usize;
    let crowded: u32 = hits[..n]
        .par_iter_mut()
        .enumerate()
        .with_min_len(PAR_MIN)
        .map(|(i, hit)| {
            let p = node(nodes, slaves[i]);
            let candidates = best[BEST_WORDS * i + 3];
            let best_f = best[BEST_WORDS * i + 1];
            if best_f == NO_FACET {
                *hit = GpuHit::miss(slaves[i], candidates);
                return 0;
            }
            let fac = facets[best_f as usize];
            let best_pr = project(nodes, p, fac);
            let mut best_node = u32::MAX;
            let mut best_nd2 = 0.0f32;
            for &id in &fac[..facet_node_count(fac)] {
                let d2 = (node(nodes, id) - p).length2();
                if best_node == u32::MAX || d2 < best_nd2 || (d2 == best_nd2 && id < best_node) {
                    best_node = id;
                    best_nd2 = d2;
                }
            }
            let q = best_pr.point;
            let beside = super::common::beside_free_edge(
                nodes,
                facets,
                adjacency,
                best_f,
                fac,
                best_pr.weights,
                p,
                q,
                best_pr.normal,
            );
            *hit = GpuHit {
                facet: best_f,
                node: best_node,
                candidates: candidates | if beside { HIT_BESIDE_FREE_EDGE } else { 0 },
                slave: slaves[i],
                point_gap: [q.x, q.y, q.z, (p - q).dot(best_pr.normal)],
                normal_dist: [
                    best_pr.normal.x,
                    best_pr.normal.y,
                    best_pr.normal.z,
                    best_pr.dist2.sqrt(),
                ],
                weights: best_pr.weights,
            };
            u32::from(best[BEST_WORDS * i + 2] != 0)
        })
        .sum();
    status[STATUS_CROWDED] += crowded;
}
