//! The warnings an increment's report carries, as sentences a host program can print.

use super::{FastNode, KinematicReport, StepReport};

fn fast(kind: &str, count: usize, fastest: Option<FastNode>) -> Option<String> {
    let f = fastest.filter(|_| count > 0)?;
    Some(format!(
        "{count} slave node(s) of {kind} pairs moved farther than their pair's search radius \
         relative to the master within this increment (fastest: node {} of pair {}, {:e} \
         against a radius of {:e}): contact may be missed (tunnelling); lower the increment or \
         widen the search radius",
        f.node, f.pair.0, f.distance, f.radius
    ))
}

impl StepReport {
    /// What in this report a host program should be told (empty when nothing): slave nodes
    /// faster than the search can follow, slaves of small-sliding pairs left without an anchor,
    /// tree walks finished in chunks.
    pub fn warnings(&self) -> Vec<String> {
        let mut w: Vec<String> = fast("penalty", self.fast_nodes, self.fastest)
            .into_iter()
            .collect();
        if self.unanchored > 0 {
            w.push(format!(
                "{} slave node(s) of small- or infinitesimal-sliding pairs project onto no \
                 master facet and are not constrained (Contact::anchoring names them)",
                self.unanchored
            ));
        }
        if self.fallbacks > 0 {
            w.push(format!(
                "{} slave node(s) reached the search tree's visit cap and were finished in \
                 bounded chunks (exact, slower: the tree fits the master badly)",
                self.fallbacks
            ));
        }
        w
    }
}

impl KinematicReport {
    /// What in this report a host program should be told (empty when nothing): slave nodes
    /// faster than the search can follow.
    pub fn warnings(&self) -> Vec<String> {
        fast("kinematic", self.fast_nodes, self.fastest)
            .into_iter()
            .collect()
    }
}
