//! CPU mirror of `shaders/anchor.wgsl`: small sliding's contact points from fixed anchors.

use super::common::{facet_node_count, node};
use crate::abi::search::*;
use crate::abi::status::{STATUS_PLANE_OFF, STATUS_SLID_TOO_FAR};
use crate::geometry::V3;

const COS_10_DEGREES: f32 = 0.984_807_7;

/// The facet's normal at the point with weights `w` (WGSL: `facet_normal_at`).
pub fn facet_normal_at(nodes: &[[f32; 4]], fac: [u32; 4], w: [f32; 4]) -> V3<f32> {
    let n = facet_node_count(fac);
    let x0 = node(nodes, fac[0]);
    let x1 = node(nodes, fac[1]);
    if n == 2 {
        let t = x1 - x0;
        return V3::new(t.y, -t.x, 0.0).normalize_or_zero();
    }
    let x2 = node(nodes, fac[2]);
    if n == 3 {
        return (x1 - x0).cross(x2 - x0).normalize_or_zero();
    }
    let x3 = node(nodes, fac[3]);
    let xi = (w[1] + w[2]) - (w[0] + w[3]);
    let eta = (w[2] + w[3]) - (w[0] + w[1]);
    let gx = (x1 - x0 + x2 - x3) * 0.25 + (x0 - x1 + x2 - x3) * (0.25 * eta);
    let ge = (x2 + x3 - x0 - x1) * 0.25 + (x0 - x1 + x2 - x3) * (0.25 * xi);
    let nn = gx.cross(ge).normalize_or_zero();
    if nn.length2() == 0.0 {
        (x2 - x0).cross(x3 - x1).normalize_or_zero()
    } else {
        nn
    }
}

/// The shortest rotation taking unit `a` onto unit `b`, applied to `v` (WGSL: `rotate_like`).
pub fn rotate_like(a: V3<f32>, b: V3<f32>, v: V3<f32>) -> V3<f32> {
    let c = a.dot(b);
    let k = a.cross(b);
    if c <= -0.999_999 {
        return v * -1.0;
    }
    v * c + k.cross(v) + k * (k.dot(v) / (1.0 + c))
}

/// The current smoothed normal at the point with weights `w` on `fac` (WGSL: `smoothed_normal`).
pub fn smoothed_normal(
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    adjacency: &[u32],
    fac: [u32; 4],
    w: [f32; 4],
) -> V3<f32> {
    let mut sum = V3::zero();
    for j in 0..facet_node_count(fac) {
        let n = fac[j] as usize;
        let mut nn = V3::zero();
        for k in adjacency[n]..adjacency[n + 1] {
            nn = nn
                + super::nodal_normals::facet_area_normal(
                    nodes,
                    facets[adjacency[k as usize] as usize],
                );
        }
        sum = sum + nn.normalize_or_zero() * w[j];
    }
    sum.normalize_or_zero()
}

/// One "invocation" per slave node.
#[allow(clippy::too_many_arguments)]
pub fn anchor(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    slaves: &[u32],
    anchors: &[Anchor],
    status: &mut [u32],
    hits: &mut [GpuHit],
    adjacency: &[u32],
) {
    for i in 0..params.n_slaves as usize {
        let a = anchors[i];
        let s = slaves[i];
        let mut hit = GpuHit::miss(s, 0);
        hit.node = a.node;
        if a.facet == NO_FACET {
            hits[i] = hit;
            continue;
        }
        let fac = facets[a.facet as usize];
        let mut x0 = V3::<f32>::zero();
        for j in 0..facet_node_count(fac) {
            x0 = x0 + node(nodes, fac[j]) * a.weights[j];
        }
        let nf = facet_normal_at(nodes, fac, a.weights);
        let n0 = V3::new(a.normal0[0], a.normal0[1], a.normal0[2]);
        let nrm = if a.flags & ANCHOR_FROZEN == 0 {
            rotate_like(
                V3::new(a.facet_normal0[0], a.facet_normal0[1], a.facet_normal0[2]),
                nf,
                n0,
            )
            .normalize_or_zero()
        } else {
            n0
        };
        let p = node(nodes, s);
        let d = p - x0;
        let gap = d.dot(nrm);
        let slide = (d - nrm * gap).length2().sqrt();
        if slide > a.normal0[3] {
            status[STATUS_SLID_TOO_FAR] += 1;
        }
        if nrm.dot(smoothed_normal(nodes, facets, adjacency, fac, a.weights)) < COS_10_DEGREES {
            status[STATUS_PLANE_OFF] += 1;
        }
        hit.facet = a.facet;
        hit.point_gap = [x0.x, x0.y, x0.z, gap];
        hit.normal_dist = [nrm.x, nrm.y, nrm.z, d.length2().sqrt()];
        hit.weights = a.weights;
        hits[i] = hit;
    }
}
