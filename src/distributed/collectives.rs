//! The collectives a distributed contact is built from: gathers of every rank's values in rank
//! order, sums, and the master surface gathered whole.

use super::*;

/// Gathers every rank's `items` on every rank, in rank order; with each rank's count
/// (collective: every rank of `comm` calls it).
pub fn all_gather<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    items: &[T],
) -> (Vec<T>, Vec<usize>) {
    let n = comm.size() as usize;
    let mut counts = vec![0 as Count; n];
    comm.all_gather_into(&(items.len() as Count), &mut counts[..]);
    let displs: Vec<Count> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let total: Count = counts.iter().sum();
    let mut all = vec![T::default(); total as usize];
    {
        let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
        comm.all_gather_varcount_into(items, &mut part);
    }
    (all, counts.iter().map(|&c| c as usize).collect())
}

pub(super) fn all_sum(comm: &SimpleCommunicator, x: u64) -> u64 {
    let mut y = 0u64;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::sum());
    y
}

/// Gathers one pair's facets (listed by `k`'s owners) on every rank, in rank order; each facet
/// must be listed once, by one rank (the same result, and so the same error, on every rank).
pub(super) fn gather_facets(
    comm: &SimpleCommunicator,
    facets: &[[u64; 4]],
    k: usize,
) -> Result<Vec<[u64; 4]>> {
    let flat: Vec<u64> = facets.iter().flatten().copied().collect();
    let (all, _) = all_gather(comm, &flat);
    let facets: Vec<[u64; 4]> = all
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    let mut seen = std::collections::HashSet::with_capacity(facets.len());
    for f in &facets {
        let mut key = *f;
        key.sort_unstable();
        if !seen.insert(key) {
            return Err(bad(
                "master facet",
                format!("{f:?} of pair {k}"),
                "listed by one rank only, once",
            ));
        }
    }
    Ok(facets)
}

/// The whole surface of `facets` at the start positions `at` (by global id), numbered in the
/// order its nodes first appear; and that numbering. Errors: a node no rank owns.
pub(super) fn whole_surface(
    facets: &[[u64; 4]],
    at: &HashMap<u64, [f64; 3]>,
    k: usize,
) -> Result<(MasterSurface, HashMap<u64, u32>)> {
    let mut local_of: HashMap<u64, u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut list = Vec::with_capacity(facets.len());
    for f in facets {
        let m = if f[3] == NO_GLOBAL_NODE { 3 } else { 4 };
        let mut l = [0u32; 4];
        for j in 0..m {
            let p = at.get(&f[j]).ok_or_else(|| {
                bad(
                    "master facet",
                    format!("{f:?} of pair {k}"),
                    "nodes that some rank owns",
                )
            })?;
            l[j] = *local_of.entry(f[j]).or_insert_with(|| {
                positions.push(*p);
                (positions.len() - 1) as u32
            });
        }
        list.push(if m == 3 {
            Facet::Triangle([l[0], l[1], l[2]])
        } else {
            Facet::Quad(l)
        });
    }
    let surface = MasterSurface::build(&Surface::from_facets(list), &positions, 3)?;
    Ok((surface, local_of))
}
