//! The collectives a distributed contact is built from — gathers of every rank's values in rank
//! order, reductions, all-to-all exchanges, the agreement on faults — and the count of those
//! issued, so that each increment's collectives are a figure (`DistributedStep::collectives`),
//! not an estimate.
//!
//! Every MPI call here is a collective: every rank of the communicator makes it, in the same
//! order. Where counts are known on both sides (the ghosts and the halo between global
//! searches), the exchange sends without first exchanging them; where values agree by a rule
//! (faults, the stable increment, counts), they travel in one record per rank and every rank
//! folds the records in rank order, so the result is the same bits on every rank and run.

use std::sync::atomic::{AtomicU64, Ordering};

use super::*;

/// Collectives this process has issued through abut (MPI calls every rank makes).
static ISSUED: AtomicU64 = AtomicU64::new(0);

fn issued(n: u64) {
    ISSUED.fetch_add(n, Ordering::Relaxed);
}

/// MPI collectives this process has issued through abut's distributed contact and scene runs
/// since it started (each MPI call that every rank of a communicator makes counts one; a
/// gather of uneven lengths counts two: its counts, then its values).
pub fn collectives_issued() -> u64 {
    ISSUED.load(Ordering::Relaxed)
}

/// Displacements of consecutive blocks of `counts` items.
fn offsets(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

/// Gathers every rank's `items` on every rank, in rank order; with each rank's count
/// (collective: every rank of `comm` calls it; two collectives, the counts and the items).
pub fn all_gather<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    items: &[T],
) -> (Vec<T>, Vec<usize>) {
    let n = comm.size() as usize;
    let mut counts = vec![0 as Count; n];
    comm.all_gather_into(&(items.len() as Count), &mut counts[..]);
    let displs = offsets(&counts);
    let total: Count = counts.iter().sum();
    let mut all = vec![T::default(); total as usize];
    {
        let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
        comm.all_gather_varcount_into(items, &mut part);
    }
    issued(2);
    (all, counts.iter().map(|&c| c as usize).collect())
}

/// Gathers every rank's `items` on every rank, in rank order, where every rank gives the same
/// number of them (one collective).
pub(crate) fn all_gather_fixed<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    items: &[T],
) -> Vec<T> {
    let mut all = vec![T::default(); items.len() * comm.size() as usize];
    comm.all_gather_into(items, &mut all[..]);
    issued(1);
    all
}

/// The smallest `x` over the ranks (one collective).
pub(crate) fn all_min(comm: &SimpleCommunicator, x: f64) -> f64 {
    let mut y = 0.0;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::min());
    issued(1);
    y
}

/// The largest `x` over the ranks (one collective).
pub(crate) fn all_max(comm: &SimpleCommunicator, x: f64) -> f64 {
    let mut y = 0.0;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::max());
    issued(1);
    y
}

/// Sends `out[r]` to rank r and returns what each rank sent here (two collectives: the counts,
/// then the items).
pub(crate) fn exchange<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    out: &[Vec<T>],
) -> Vec<Vec<T>> {
    let n = comm.size() as usize;
    let send_counts: Vec<Count> = out.iter().map(|v| v.len() as Count).collect();
    let mut recv_counts = vec![0 as Count; n];
    comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
    issued(1);
    let recv: Vec<usize> = recv_counts.iter().map(|&c| c as usize).collect();
    exchange_known(comm, out, &recv)
}

/// Sends `out[r]` to rank r and returns what each rank sent here, where this rank knows how
/// many items each rank sends it (`recv[r]`, agreed when the lists were made; one collective).
pub(crate) fn exchange_known<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    out: &[Vec<T>],
    recv: &[usize],
) -> Vec<Vec<T>> {
    let send_counts: Vec<Count> = out.iter().map(|v| v.len() as Count).collect();
    let recv_counts: Vec<Count> = recv.iter().map(|&c| c as Count).collect();
    let (sd, rd) = (offsets(&send_counts), offsets(&recv_counts));
    let flat: Vec<T> = out.iter().flatten().cloned().collect();
    let mut back = vec![T::default(); recv.iter().sum()];
    {
        let send = Partition::new(&flat[..], &send_counts[..], &sd[..]);
        let mut part = PartitionMut::new(&mut back[..], &recv_counts[..], &rd[..]);
        comm.all_to_all_varcount_into(&send, &mut part);
    }
    issued(1);
    let mut res = Vec::with_capacity(recv.len());
    for (&d, &c) in rd.iter().zip(recv) {
        res.push(back[d as usize..d as usize + c].to_vec());
    }
    res
}

/// This rank's own error, or, where another rank failed (`first`: the lowest such rank), an
/// error naming it.
fn verdict(own: Option<Error>, first: Option<usize>) -> Result<()> {
    match (own, first) {
        (Some(e), _) => Err(e),
        (None, Some(r)) => Err(bad(
            "rank",
            format!("{r}"),
            "every rank to get through (that rank failed: its own error says why)",
        )),
        (None, None) => Ok(()),
    }
}

/// Whether every rank got on (one collective): this rank's own error, or, where another rank
/// failed, an error naming the first such rank.
pub(crate) fn agree(comm: &SimpleCommunicator, own: Option<Error>) -> Result<()> {
    agree_and_max(comm, own, &[]).map(|_| ())
}

/// [`agree`] and the largest of each of `values` over the ranks, in one collective (a
/// fault travels as a number that the largest keeps: the lowest failing rank's).
pub(crate) fn agree_and_max(
    comm: &SimpleCommunicator,
    own: Option<Error>,
    values: &[f64],
) -> Result<Vec<f64>> {
    let size = comm.size() as f64;
    let mut x = Vec::with_capacity(1 + values.len());
    x.push(if own.is_some() {
        size - comm.rank() as f64
    } else {
        0.0
    });
    x.extend_from_slice(values);
    let mut y = vec![0.0; x.len()];
    comm.all_reduce_into(&x[..], &mut y[..], mpi::collective::SystemOperation::max());
    issued(1);
    let first = (y[0] > 0.0).then(|| (size - y[0]) as usize);
    verdict(own, first)?;
    Ok(y[1..].to_vec())
}

/// [`agree`] and every rank's `record` (each rank's the same length), in rank order, in one
/// collective: the caller folds them in rank order, the same on every rank.
pub(crate) fn agree_and_gather(
    comm: &SimpleCommunicator,
    own: Option<Error>,
    record: &[f64],
) -> Result<Vec<Vec<f64>>> {
    let mut x = Vec::with_capacity(1 + record.len());
    x.push(if own.is_some() { 1.0 } else { 0.0 });
    x.extend_from_slice(record);
    let all = all_gather_fixed(comm, &x);
    let rows: Vec<&[f64]> = all.chunks_exact(x.len()).collect();
    let first = rows.iter().position(|r| r[0] != 0.0);
    verdict(own, first)?;
    Ok(rows.iter().map(|r| r[1..].to_vec()).collect())
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
/// order its nodes first appear, of a 2D model when `two_d`; and that numbering. Errors: a node
/// no rank owns.
pub(super) fn whole_surface(
    facets: &[[u64; 4]],
    at: &HashMap<u64, [f64; 3]>,
    k: usize,
    two_d: bool,
) -> Result<(MasterSurface, HashMap<u64, u32>)> {
    let mut local_of: HashMap<u64, u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut list = Vec::with_capacity(facets.len());
    for f in facets {
        let m = facet_node_count(f, NO_GLOBAL_NODE);
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
        list.push(facet_of(l, m));
    }
    let dim = if two_d { 2 } else { 3 };
    let surface = MasterSurface::build(&Surface::from_facets(list), &positions, dim)?;
    Ok((surface, local_of))
}
