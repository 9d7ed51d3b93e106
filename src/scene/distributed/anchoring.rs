//! Small sliding across ranks in a scene: every rank's anchored and unanchored slaves gathered
//! into the single process's account of them (the summary's counts and warnings).

use mpi::topology::SimpleCommunicator;

use crate::distributed::{all_gather, DistributedContact};
use crate::error::Result;
use crate::model::{Model, PairId};
use crate::Anchoring;

/// Small sliding: each anchored pass's slaves over every rank and those left unanchored, as
/// a single process's [`crate::Contact::anchoring`] gives them (a pass's unanchored nodes in
/// its node set's order; one collective).
pub(super) fn anchoring_over_ranks(
    comm: &SimpleCommunicator,
    model: &Model,
    contact: Option<&DistributedContact>,
) -> Result<Vec<Anchoring>> {
    let mine: Vec<u64> = contact
        .map(|c| c.anchoring())
        .unwrap_or_default()
        .into_iter()
        .flat_map(|a| {
            let head = [
                a.pair as u64,
                a.reverse as u64,
                a.slaves as u64,
                a.unanchored.len() as u64,
            ];
            head.into_iter().chain(a.unanchored)
        })
        .collect();
    let (all, _) = all_gather(comm, &mine);
    // (pair, reverse) -> (slaves, unanchored), over the ranks
    let mut passes: std::collections::BTreeMap<(u64, u64), (usize, Vec<u32>)> = Default::default();
    let mut at = 0;
    while at + 4 <= all.len() {
        let (key, slaves, n) = ((all[at], all[at + 1]), all[at + 2], all[at + 3] as usize);
        let e = passes.entry(key).or_default();
        e.0 += slaves as usize;
        e.1.extend(all[at + 4..at + 4 + n].iter().map(|&g| g as u32));
        at += 4 + n;
    }
    let mut out = Vec::new();
    for ((pair, reverse), (slaves, mut unanchored)) in passes {
        // the node set's order (a reverse pass: the master's nodes, in id order)
        let order: Vec<u32> = if reverse == 0 {
            model.node_set(model.pairs()[pair as usize].slave)?.to_vec()
        } else {
            unanchored
                .iter()
                .copied()
                .collect::<std::collections::BTreeSet<u32>>()
                .into_iter()
                .collect()
        };
        let rank: std::collections::HashMap<u32, usize> =
            order.iter().enumerate().map(|(k, &n)| (n, k)).collect();
        unanchored.sort_by_key(|n| rank.get(n).copied().unwrap_or(usize::MAX));
        out.push(Anchoring {
            pair: PairId(pair as usize),
            slaves,
            anchored: slaves - unanchored.len(),
            unanchored,
        });
    }
    Ok(out)
}
