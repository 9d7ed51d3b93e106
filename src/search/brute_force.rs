//! Brute-force f64 oracle of the global search: every slave node against every active facet,
//! in model coordinates. Independent of the grid; used by tests and benchmarks.

use super::ContactPoint;
use crate::geometry::{closest_on_facet, V3};
use crate::model::MasterSurface;

/// The oracle's answer for one slave node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleHit {
    /// The nearest facet within the radius (ties: lowest id), as the search reports it.
    pub contact: ContactPoint,
    /// Distance to the nearest facet other than `contact.facet` (∞ when there is none within
    /// the radius): a query whose two distances are within round-off is a tie.
    pub second_distance: f64,
}

/// Nearest active facet of each slave node within `radius`, in f64.
pub fn brute_force(
    master: &MasterSurface,
    positions: &[[f64; 3]],
    slaves: &[u32],
    radius: f64,
) -> Vec<Option<OracleHit>> {
    slaves
        .iter()
        .map(|&s| {
            let p = V3::from_array(positions[s as usize]);
            let mut best: Option<(u32, crate::geometry::Projection<f64>)> = None;
            let mut second = f64::INFINITY;
            for &f in &master.active {
                let nodes = master.facets[f as usize].nodes();
                let x: Vec<V3<f64>> = nodes
                    .iter()
                    .map(|&n| V3::from_array(positions[n as usize]))
                    .collect();
                let pr = closest_on_facet(p, &x);
                if pr.dist2 > radius * radius {
                    continue;
                }
                match best {
                    Some((_, b)) if pr.dist2 >= b.dist2 => second = second.min(pr.dist2.sqrt()),
                    Some((_, b)) => {
                        second = second.min(b.dist2.sqrt());
                        best = Some((f, pr));
                    }
                    None => best = Some((f, pr)),
                }
            }
            best.map(|(f, pr)| {
                let nodes = master.facets[f as usize].nodes();
                let mut tracked = nodes[0];
                let mut tracked_d2 = f64::INFINITY;
                for &n in nodes {
                    let d2 = (V3::from_array(positions[n as usize]) - p).length2();
                    if d2 < tracked_d2 || (d2 == tracked_d2 && n < tracked) {
                        tracked = n;
                        tracked_d2 = d2;
                    }
                }
                OracleHit {
                    contact: ContactPoint {
                        facet: f,
                        tracked_node: tracked,
                        point: pr.point.to_array(),
                        normal: pr.normal.to_array(),
                        gap: pr.gap(p),
                        distance: pr.dist2.sqrt(),
                        weights: pr.weights,
                        // the oracle answers the search's question (the nearest facet); the
                        // free-edge classification is tested against geometry directly
                        beside_free_edge: false,
                    },
                    second_distance: second,
                }
            })
        })
        .collect()
}
