//! The order a penalty pass keeps its slaves in inside abut ([`SlaveOrder`]), and the maps
//! between it and the node set's order, where the caller reads.
//!
//! Every per-slave array of a pass — its search's slaves, hits, active list and walk, its penalty
//! state, areas and outputs, and its pair nodes (slaves first) — is kept in the pass's order, so
//! the passes read them in that order. The caller's view is put back in the node set's order at
//! the few places it reads: the output variables and their search result, the penalty states
//! (and the saved state), the anchoring report, and the nodes a report names. Forces are summed
//! by node in fixed point, so they do not depend on the order at all.

use crate::model::SlaveOrder;
use crate::search::SearchResult;
use std::sync::Arc;

/// Which node-set entry each of a pass's slaves is, and back; empty when the pass keeps the
/// node set's order.
#[derive(Clone, Debug, Default)]
pub(super) struct SlaveMap {
    /// The node-set index of the pass's slave k.
    set_index: Vec<u32>,
    /// The pass's index of node-set entry c.
    pass_index: Vec<u32>,
}

impl SlaveMap {
    /// The pass's slaves for the node set `set` (model node ids) ordered by `order` at
    /// `positions` (`dim` coordinates used), and the map back to the node set.
    pub(super) fn new(
        set: &[u32],
        order: SlaveOrder,
        positions: &[[f64; 3]],
        dim: u32,
    ) -> (Vec<u32>, Self) {
        if order == SlaveOrder::Given || set.len() < 2 {
            return (set.to_vec(), Self::default());
        }
        let points: Vec<[f64; 3]> = set.iter().map(|&s| positions[s as usize]).collect();
        let set_index = crate::search::tree::morton_order(&points, dim);
        let mut pass_index = vec![0; set.len()];
        for (k, &c) in set_index.iter().enumerate() {
            pass_index[c as usize] = k as u32;
        }
        let slaves = set_index.iter().map(|&c| set[c as usize]).collect();
        (
            slaves,
            Self {
                set_index,
                pass_index,
            },
        )
    }

    /// The node-set index of each of the pass's slaves (`n` of them).
    pub(super) fn set_indices(&self, n: usize) -> Vec<u32> {
        if self.set_index.is_empty() {
            (0..n as u32).collect()
        } else {
            self.set_index.clone()
        }
    }

    /// The pass's index of each node-set entry in turn (`n` of them): the order to visit the
    /// pass's slaves in to meet them in the caller's order.
    pub(super) fn caller_sequence(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        (0..n).map(move |c| self.pass_index.get(c).map_or(c, |&k| k as usize))
    }

    /// `a`, one entry per slave in the pass's order, in the node set's order.
    pub(super) fn to_caller<T: Clone>(&self, a: &[T]) -> Vec<T> {
        if self.pass_index.is_empty() {
            return a.to_vec();
        }
        self.pass_index
            .iter()
            .map(|&k| a[k as usize].clone())
            .collect()
    }

    /// `a`, one entry per slave in the node set's order, in the pass's order.
    pub(super) fn to_pass<T: Clone>(&self, a: &[T]) -> Vec<T> {
        if self.set_index.is_empty() {
            return a.to_vec();
        }
        self.set_index
            .iter()
            .map(|&c| a[c as usize].clone())
            .collect()
    }

    /// `nodes`, some of the pass's slave nodes in its order, in the order of the node set
    /// `set`.
    pub(super) fn nodes_in_caller_order(&self, mut nodes: Vec<u32>, set: &[u32]) -> Vec<u32> {
        if self.pass_index.is_empty() {
            return nodes;
        }
        nodes.sort_unstable();
        set.iter()
            .copied()
            .filter(|n| nodes.binary_search(n).is_ok())
            .collect()
    }

    /// A search result of the pass (slaves and hits in its order) in the node set's order.
    pub(super) fn result_to_caller(&self, mut r: SearchResult) -> SearchResult {
        if self.pass_index.is_empty() {
            return r;
        }
        r.slaves = self.to_caller(&r.slaves).into();
        if !r.raw.is_empty() {
            r.raw = Arc::new(self.to_caller(&r.raw));
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Morton map is a permutation whose two halves invert each other, and it carries
    /// arrays there and back unchanged; `Given` is the identity.
    #[test]
    fn the_map_and_its_inverse_carry_arrays_there_and_back() {
        let positions: Vec<[f64; 3]> = (0..50)
            .map(|i| {
                let i = (i * 37) % 50;
                [(i % 7) as f64, (i / 7) as f64, 0.25 * i as f64]
            })
            .collect();
        let set: Vec<u32> = (0..50).rev().step_by(2).collect();
        let (slaves, map) = SlaveMap::new(&set, SlaveOrder::Morton, &positions, 3);
        assert_ne!(slaves, set);
        let mut sorted = slaves.clone();
        sorted.sort_unstable();
        let mut want = set.clone();
        want.sort_unstable();
        assert_eq!(sorted, want);
        assert_eq!(map.to_caller(&slaves), set);
        assert_eq!(map.to_pass(&set), slaves);
        let seq: Vec<u32> = map.caller_sequence(set.len()).map(|k| slaves[k]).collect();
        assert_eq!(seq, set);
        let idx = map.set_indices(set.len());
        assert!(idx.iter().zip(&slaves).all(|(&c, &s)| set[c as usize] == s));
        let (same, id) = SlaveMap::new(&set, SlaveOrder::Given, &positions, 3);
        assert_eq!(same, set);
        assert_eq!(id.to_caller(&set), set);
        assert_eq!(id.set_indices(3), vec![0, 1, 2]);
    }
}
