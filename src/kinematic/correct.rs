//! The correction of the module docs, shared by one process and a rank of a distributed run:
//! each pushed slave's resisting force, its facet nodes' shares of it summed per node
//! ([`NodeSums`]: in one process in the slaves' order, across ranks on the nodes' owners in the
//! same order, so the sums are the same bits), the master nodes' corrections and the slaves'
//! onto the corrected master.

use super::{law_energy, push_target, pushed, SlaveCorrection};
use crate::geometry::V3;
use crate::model::PressureOverclosure;

/// Sums of per-node contributions `(node, key, values)`: each node's added in key order from
/// zero, `None` where none came.
pub(crate) trait NodeSums {
    /// The sums over every node the caller indexes (one process: the model's nodes; a rank:
    /// its own nodes then its ghosts).
    fn node_sums<const K: usize>(&self, rows: Vec<(usize, u64, [f64; K])>)
        -> Vec<Option<[f64; K]>>;
}

/// One process's sums over its `.0` nodes, every contribution here.
pub(crate) struct InProcess(pub usize);

impl NodeSums for InProcess {
    fn node_sums<const K: usize>(
        &self,
        mut rows: Vec<(usize, u64, [f64; K])>,
    ) -> Vec<Option<[f64; K]>> {
        rows.sort_by_key(|r| (r.0, r.1));
        let mut sums: Vec<Option<[f64; K]>> = vec![None; self.0];
        for (n, _, values) in rows {
            let s = sums[n].get_or_insert([0.0; K]);
            for (a, b) in s.iter_mut().zip(values) {
                *a += b;
            }
        }
        sums
    }
}

/// One pushed-or-not slave's contact in a pass: its key (its place in the pair's slave list:
/// the order the sums run in), its index among the pass's slaves and its node, its facet's
/// nodes (`count` of them) and the geometry.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Touch {
    pub key: u64,
    pub slave: usize,
    pub node: usize,
    pub nodes: [u32; 4],
    pub count: usize,
    pub normal: V3<f64>,
    pub weights: [f64; 4],
    pub overclosure: f64,
}

/// The correction of `touch` (the slaves of a pass with a contact; `n_slaves` in the pass) at
/// node masses `masses`, per-slave areas `areas`: adds the master nodes' and the slaves'
/// corrections to `dx` (the nodes it holds: a rank's own, the first `dx.len()`) and returns
/// each slave's correction. A softened law is balanced with the force the contact transmits:
/// the correction adds each pushed slave's mass to its master nodes (`S_j = Σ w_j·m_s`) and
/// moves the slave onto the master's corrected position, so a push of `h − h'` leaves the
/// slave `(h − h')·(1 − Σ_j w_j·S_j/(m_j + S_j))`, and the contact transmits that times
/// `m_s/Δt²` (1 against a fixed master, `m_master/(m_master + m_s)` for one slave on one node).
#[allow(clippy::too_many_arguments)]
pub(crate) fn correct_touches(
    touch: &[Touch],
    n_slaves: usize,
    masses: &[f64],
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
    sums: &impl NodeSums,
    dx: &mut [[f64; 3]],
) -> Vec<SlaveCorrection> {
    // a softened law: the masses the pushed slaves add to each master node
    let shares: Vec<f64> = if law.is_some() {
        let added = sums.node_sums(
            touch
                .iter()
                .filter(|t| pushed(law, t.overclosure))
                .flat_map(|t| {
                    let ms = masses[t.node];
                    (0..t.count).map(move |j| (t.nodes[j] as usize, t.key, [t.weights[j] * ms]))
                })
                .collect(),
        );
        touch
            .iter()
            .map(|t| {
                if !pushed(law, t.overclosure) {
                    return 1.0;
                }
                let taken: f64 = (0..t.count)
                    .map(|j| {
                        let n = t.nodes[j] as usize;
                        let s_j = added[n].map_or(0.0, |a| a[0]);
                        t.weights[j] * s_j / (masses[n] + s_j)
                    })
                    .sum();
                (1.0 - taken).max(f64::MIN_POSITIVE)
            })
            .collect()
    } else {
        vec![1.0; touch.len()]
    };
    // each pushed slave's resisting force, its facet nodes' shares of it
    let mut out = vec![SlaveCorrection::default(); n_slaves];
    let mut push_of = vec![0.0; n_slaves];
    let mut parts = Vec::new();
    for (t, share) in touch.iter().zip(&shares) {
        let ms = masses[t.node];
        let Some(target) = push_target(law, t.overclosure, ms * share, areas[t.slave], dt) else {
            continue;
        };
        let fs = ms * (t.overclosure - target) / (dt * dt);
        for j in 0..t.count {
            let f = (t.normal * (t.weights[j] * fs)) * -1.0;
            parts.push((
                t.nodes[j] as usize,
                t.key,
                [f.x, f.y, f.z, t.weights[j] * ms],
            ));
        }
        out[t.slave] = SlaveCorrection {
            overclosure: t.overclosure,
            target,
            force: fs,
            normal: t.normal.to_array(),
            energy: law.map_or(0.0, |l| law_energy(l, target) * areas[t.slave]),
            applied: [0.0; 3],
        };
        push_of[t.slave] = t.overclosure - target;
    }
    // the master nodes' corrections
    let da: Vec<Option<V3<f64>>> = sums
        .node_sums(parts)
        .iter()
        .zip(masses)
        .map(|(s, &m)| s.map(|s| V3::new(s[0], s[1], s[2]) * (1.0 / (m + s[3]))))
        .collect();
    for (d, a) in dx.iter_mut().zip(&da) {
        if let Some(a) = a {
            let d3 = *a * (dt * dt);
            for (c, value) in d.iter_mut().zip(d3.to_array()) {
                *c += value;
            }
        }
    }
    // the slaves' corrections: onto the corrected master
    for t in touch {
        if out[t.slave].force <= 0.0 {
            continue;
        }
        let mut d = t.normal * push_of[t.slave];
        for j in 0..t.count {
            let a = da[t.nodes[j] as usize].unwrap_or(V3::zero());
            d = d + a * (t.weights[j] * dt * dt);
        }
        for (c, value) in dx[t.node].iter_mut().zip(d.to_array()) {
            *c += value;
        }
        out[t.slave].applied = (d * (masses[t.node] / (dt * dt))).to_array();
    }
    out
}
