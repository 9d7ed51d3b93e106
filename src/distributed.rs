//! (feature `mpi`) Penalty contact across MPI ranks: one model split over processes, each rank
//! holding its own nodes and running abut's search and enforcement on its own device.
//!
//! Each rank gives a [`RankModel`]: the nodes it owns (global ids, positions, masses) and, per
//! pair, its own slave nodes and the master facets it owns (by global node ids; their nodes may
//! be owned anywhere). At construction the facets' topology is gathered on every rank (a few
//! words per facet). At every *distributed global search* — at the start, every
//! `search_interval` increments, and as soon as any node of any rank has moved more than the
//! motion budget (half the search radius) since the last one, agreed by all ranks in the same
//! increment — each rank's slave region (the box of its slaves grown by the search radius, twice
//! the budget and two facet sizes: the longest facet edge at the start, or of any rank's local
//! or own facets at a distributed global search if facets have stretched beyond it) is gathered, and every rank sends each other rank the master
//! nodes it owns inside that region: those are the other rank's ghosts. A rank then builds its
//! local contact model: its own nodes, its ghosts, and every master facet all of whose nodes it
//! has — so every facet within the search radius of its slaves until the next distributed global
//! search is there, with all the facets around each of its nodes (the smoothed normals are the
//! single process's). Between them, each increment exchanges only the ghosts' positions and
//! velocities (owner to holder) and, after the local penalty step, the ghosts' forces back to
//! their owners, which add them to their own in rank order: a contact is enforced once, by the
//! rank that owns its slave. The stable increment is the minimum over ranks.
//!
//! Coulomb friction carries each slave's stick force from one local model to the next (a slave
//! never changes rank). Self-contact is a pair whose slaves lie on its own master surface, as in
//! a single process: each rank's slaves are its own nodes of the surface, against the own and
//! ghost facets around them. A balanced pair ([`RankPair::balanced`]) runs as its two passes,
//! each a pure pair weighted as in [`crate::Pair::balanced`]: the slaves against the master
//! facets (on the slaves' owners), and the master surface's nodes against the slave facets (on
//! the master nodes' owners, each with its tributary area on the whole master surface): every
//! contact of either pass is enforced once, by the rank that owns its slave node.
//!
//! Slave areas (the penalty's area per slave) are fixed at construction from the whole surface
//! at the start positions, as a single process fixes them when it builds its contact: the
//! given [`RankPair::slave_areas`], else the mean area of the whole master surface's facets.

use std::collections::HashMap;

use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;

use crate::contact::Contact;
use crate::device::Device;
use crate::error::{Error, Result};
use crate::model::Schedule;
use crate::model::{
    Enforce, Facet, Friction, MasterSurface, Model, Pair, PairId, Penalty, Surface,
};

/// Marks the unused fourth node of a triangle in [`RankPair::facets`].
pub const NO_GLOBAL_NODE: u64 = u64::MAX;

/// One rank's share of a model.
#[derive(Clone, Debug, Default)]
pub struct RankModel {
    /// Global ids of the nodes this rank owns (each node owned by exactly one rank).
    pub ids: Vec<u64>,
    /// Their positions (model length units), in `ids` order.
    pub positions: Vec<[f64; 3]>,
    /// Their lumped masses (> 0), in `ids` order.
    pub masses: Vec<f64>,
    /// The contact pairs, the same pairs in the same order on every rank.
    pub pairs: Vec<RankPair>,
}

/// One penalty pair's share on a rank.
#[derive(Clone, Debug)]
pub struct RankPair {
    /// This rank's slave nodes of the pair (global ids of nodes it owns; may be empty).
    pub slaves: Vec<u64>,
    /// The master facets this rank owns: 3D triangles (fourth id [`NO_GLOBAL_NODE`]) or quads,
    /// by global node ids, nodes counter-clockwise seen from the side contact comes from.
    pub facets: Vec<[u64; 4]>,
    /// Search radius (model length units), the same on every rank.
    pub search_radius: f64,
    /// Penalty enforcement, the same on every rank.
    pub penalty: Penalty,
    /// Friction, the same on every rank.
    pub friction: Friction,
    /// Distributed global search at least every this many increments (≥ 1).
    pub search_interval: u32,
    /// The tributary area of each slave (one per entry of `slaves`, model area units);
    /// `None`: every slave takes the mean facet area of the whole master surface.
    pub slave_areas: Option<Vec<f64>>,
    /// Makes the pair balanced ([`crate::Pair::balanced`]): the slave surface's share and the
    /// weight of the slave-on-master pass.
    pub balanced: Option<RankBalance>,
}

/// The slave side of a balanced pair on one rank.
#[derive(Clone, Debug)]
pub struct RankBalance {
    /// The facets of the surface the slave nodes lie on that this rank owns (as
    /// [`RankPair::facets`]: by global node ids, facing the master).
    pub slave_facets: Vec<[u64; 4]>,
    /// The weight of the slave-on-master pass in [0, 1] (the master-on-slave pass gets
    /// 1 − weight), the same on every rank; ½ is the usual choice.
    pub weight: f64,
}

impl RankPair {
    /// A frictionless penalty pair with the default enforcement, searched globally every 100
    /// increments (Abaqus' default for two-surface pairs).
    pub fn new(slaves: Vec<u64>, facets: Vec<[u64; 4]>, search_radius: f64) -> Self {
        Self {
            slaves,
            facets,
            search_radius,
            penalty: Penalty::default(),
            friction: Friction::Frictionless,
            search_interval: 100,
            slave_areas: None,
            balanced: None,
        }
    }
}

/// What one distributed increment did, the same on every rank where it says so.
#[derive(Clone, Debug, Default)]
pub struct DistributedStep {
    /// Contact forces on this rank's own nodes, in [`RankModel::ids`] order: its own contacts'
    /// and those other ranks' contacts put on its nodes, summed in rank order.
    pub forces: Vec<[f64; 3]>,
    /// The smallest stable increment of any rank's springs (s); infinite when none limits it.
    pub stable_dt: f64,
    /// The largest overclosure of any rank.
    pub max_overclosure: f64,
    /// Slave nodes in contact, all ranks.
    pub active: usize,
    /// Whether this increment began with a distributed global search (on every rank).
    pub global_search: bool,
    /// Bytes this rank sent to other ranks in this increment (ghost exchange and forces back).
    pub bytes_sent: usize,
    /// Ghost nodes this rank holds now.
    pub ghosts: usize,
    /// Slave nodes the ranks' local contacts saw move farther than their pair's search radius
    /// relative to the master near them in this increment (see
    /// [`crate::StepReport::fast_nodes`]; each slave is counted by the rank that owns it).
    pub fast_nodes: usize,
    /// The fastest of them over all ranks (relative to its radius), the same on every rank.
    pub fastest: Option<FastGlobalNode>,
}

/// A node that moved farther than its pair's search radius within one increment, by global id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FastGlobalNode {
    /// Its global id.
    pub node: u64,
    /// Its pair ([`RankModel::pairs`] index).
    pub pair: usize,
    /// Its speed times the increment, model length units.
    pub distance: f64,
    /// The pair's search radius.
    pub radius: f64,
}

/// A slave node of this rank in contact after the last increment (see
/// [`DistributedContact::request_outputs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlaveOutput {
    /// The pair ([`RankModel::pairs`] index; a balanced pair's two passes both report here).
    pub pair: usize,
    /// Whether it is a balanced pair's second pass (the slave a master node).
    pub reverse: bool,
    /// The slave's global node id.
    pub node: u64,
    /// Contact pressure (force over tributary area).
    pub pressure: f64,
    /// The contact force on the slave.
    pub force: [f64; 3],
}

/// A rank's contact: its local model of own and ghost nodes, and the exchange plan with its
/// neighbours (see the module's documentation).
pub struct DistributedContact {
    comm: SimpleCommunicator,
    device: Device,
    ids: Vec<u64>,
    masses: Vec<f64>,
    index: HashMap<u64, usize>,
    pairs: Vec<PairTopology>,
    /// The largest facet edge of any pair, all ranks: at the start, then the largest of that and
    /// every rank's local facets at each distributed global search (facets that stretch widen
    /// the ghost margin).
    h_max: f64,
    /// The local model's facets (local node indices, `u32::MAX` pads a triangle), every pass.
    local_facets: Vec<[u32; 4]>,
    /// The facets all of whose nodes this rank owns (own indices, padded likewise).
    own_facets: Vec<[u32; 4]>,
    /// The ghosts' positions of the last increment, in the local model's ghost order.
    ghost_x: Vec<[f64; 3]>,
    /// Owned nodes that are master nodes of some pair.
    master_nodes: Vec<usize>,
    /// Per destination rank: own nodes whose state it receives, in send order.
    send: Vec<Vec<usize>>,
    /// Per source rank: how many ghosts come from it (ghosts are numbered by source rank, then
    /// in the order sent).
    recv: Vec<usize>,
    ghost_masses: Vec<f64>,
    contact: Option<Contact>,
    dt_ref: Option<f64>,
    since_search: u32,
    /// Positions of own and ghost nodes at the last distributed global search.
    anchor: Vec<[f64; 3]>,
    started: bool,
    last: DistributedStep,
    /// Whether the local contacts compute per-slave outputs.
    outputs: bool,
    /// Distributed global searches so far.
    searches: u64,
    /// The ghosts' global ids (by source rank, then in the order sent) of the local model.
    ghost_ids: Vec<u64>,
    /// Local models built (the first, and after every distributed global search that changed
    /// the ghosts).
    rebuilds: u64,
}

/// One pass of a pair on this rank: its own slaves (or, for a balanced pair's second pass, its
/// own master nodes) against every facet of the pass's master side.
struct PairTopology {
    slaves: Vec<usize>,
    /// Each slave's area.
    areas: Vec<f64>,
    /// The fraction of each contact's force this pass applies.
    weight: f64,
    facets: Vec<[u64; 4]>,
    radius: f64,
    penalty: Penalty,
    friction: Friction,
    interval: u32,
    /// This pair's id in the local contact, when it has one.
    local: Option<PairId>,
    /// The [`RankModel::pairs`] index it is a pass of, and whether it is the reverse pass.
    of: (usize, bool),
}

fn bad(name: &'static str, value: String, expected: &'static str) -> Error {
    Error::BadParameter {
        name,
        value,
        expected,
    }
}

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

/// Sends `out[r]` to rank r and returns what each rank sent here (all-to-all with counts).
pub(crate) fn exchange<T: Equivalence + Clone + Default>(
    comm: &SimpleCommunicator,
    out: &[Vec<T>],
) -> Vec<Vec<T>> {
    let n = comm.size() as usize;
    let send_counts: Vec<Count> = out.iter().map(|v| v.len() as Count).collect();
    let mut recv_counts = vec![0 as Count; n];
    comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
    let offsets = |c: &[Count]| -> Vec<Count> {
        c.iter()
            .scan(0, |acc, &x| {
                let d = *acc;
                *acc += x;
                Some(d)
            })
            .collect()
    };
    let (sd, rd) = (offsets(&send_counts), offsets(&recv_counts));
    let flat: Vec<T> = out.iter().flatten().cloned().collect();
    let mut back = vec![T::default(); recv_counts.iter().sum::<Count>() as usize];
    {
        let send = Partition::new(&flat[..], &send_counts[..], &sd[..]);
        let mut recv = PartitionMut::new(&mut back[..], &recv_counts[..], &rd[..]);
        comm.all_to_all_varcount_into(&send, &mut recv);
    }
    let mut res = Vec::with_capacity(n);
    for r in 0..n {
        let (a, b) = (rd[r] as usize, (rd[r] + recv_counts[r]) as usize);
        res.push(back[a..b].to_vec());
    }
    res
}

pub(crate) fn all_min(comm: &SimpleCommunicator, x: f64) -> f64 {
    let mut y = 0.0;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::min());
    y
}

pub(crate) fn all_max(comm: &SimpleCommunicator, x: f64) -> f64 {
    let mut y = 0.0;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::max());
    y
}

fn all_sum(comm: &SimpleCommunicator, x: u64) -> u64 {
    let mut y = 0u64;
    comm.all_reduce_into(&x, &mut y, mpi::collective::SystemOperation::sum());
    y
}

/// Gathers one pair's facets (listed by `k`'s owners) on every rank, in rank order; each facet
/// must be listed once, by one rank (the same result, and so the same error, on every rank).
fn gather_facets(
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
fn whole_surface(
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

/// Own node index by global id, and each pair's slaves as own indices; or the first fault of
/// this rank's share (no collective: see [`agree`]).
type Validated = (HashMap<u64, usize>, Vec<Vec<usize>>);

fn validate(model: &RankModel) -> Result<Validated> {
    let n = model.ids.len();
    if model.positions.len() != n || model.masses.len() != n {
        return Err(Error::LengthMismatch {
            what: "positions and masses (one per owned node)",
            expected: n,
            got: model.positions.len().min(model.masses.len()),
        });
    }
    let mut index = HashMap::with_capacity(n);
    for (i, &g) in model.ids.iter().enumerate() {
        if g == NO_GLOBAL_NODE || index.insert(g, i).is_some() {
            return Err(bad(
                "global node id",
                g.to_string(),
                "unique on the rank, not u64::MAX",
            ));
        }
        if !(model.masses[i] > 0.0 && model.masses[i].is_finite()) {
            return Err(Error::BadMass {
                node: i,
                mass: model.masses[i],
            });
        }
        for (axis, &value) in model.positions[i].iter().enumerate() {
            if !value.is_finite() {
                return Err(Error::NonFiniteCoordinate {
                    node: i,
                    axis,
                    value,
                });
            }
        }
    }
    let mut slaves_of = Vec::with_capacity(model.pairs.len());
    for (k, p) in model.pairs.iter().enumerate() {
        if !(p.search_radius > 0.0 && p.search_radius.is_finite()) {
            return Err(bad(
                "search_radius",
                p.search_radius.to_string(),
                "finite and positive",
            ));
        }
        if p.search_interval == 0 {
            return Err(bad("search_interval", "0".into(), "at least 1"));
        }
        if let Some(a) = &p.slave_areas {
            if a.len() != p.slaves.len() {
                return Err(Error::LengthMismatch {
                    what: "slave areas (one per slave of the pair)",
                    expected: p.slaves.len(),
                    got: a.len(),
                });
            }
            if let Some(j) = a.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(bad(
                    "slave area",
                    format!("{} (slave {} of pair {k})", a[j], p.slaves[j]),
                    "finite and positive",
                ));
            }
        }
        if let Some(b) = &p.balanced {
            if !(b.weight.is_finite() && (0.0..=1.0).contains(&b.weight)) {
                return Err(bad(
                    "balanced weight",
                    format!("{} (pair {k})", b.weight),
                    "must lie in [0, 1]",
                ));
            }
        }
        let mut slaves = Vec::with_capacity(p.slaves.len());
        for &g in &p.slaves {
            slaves.push(*index.get(&g).ok_or_else(|| {
                bad(
                    "slave node",
                    format!("global id {g} of pair {k}"),
                    "a node this rank owns",
                )
            })?);
        }
        slaves_of.push(slaves);
    }
    Ok((index, slaves_of))
}

/// Whether every rank got on (collective): this rank's own error, or, where another rank failed,
/// an error naming the first such rank.
pub(crate) fn agree(comm: &SimpleCommunicator, own: Option<Error>) -> Result<()> {
    let me = comm.rank() as f64;
    let first = all_min(comm, if own.is_some() { me } else { f64::INFINITY });
    match own {
        Some(e) => Err(e),
        None if first.is_finite() => Err(bad(
            "rank",
            format!("{first}"),
            "every rank to get through (that rank failed: its own error says why)",
        )),
        None => Ok(()),
    }
}

impl DistributedContact {
    /// This rank's contact over `comm` (duplicated: abut's messages never mix with the
    /// host's), running on `device`. Collective: every rank of `comm` calls it.
    ///
    /// Errors (on every rank, naming the rank at fault on the others): a repeated global id, a
    /// slave this rank does not own, a bad radius or interval, mismatched lengths, bad masses or
    /// coordinates, a facet listed twice or naming a node no rank owns.
    pub fn new(comm: &SimpleCommunicator, device: &Device, model: RankModel) -> Result<Self> {
        let comm = comm.duplicate();
        // every rank checks its own share first and all agree before any gather: a rank that
        // returned alone would leave the others waiting in a collective for ever
        let (valid, fault) = match validate(&model) {
            Ok(v) => (Some(v), None),
            Err(e) => (None, Some(e)),
        };
        let count = model.pairs.len() as f64;
        let uneven = all_min(&comm, count) != all_max(&comm, count);
        agree(&comm, fault)?;
        if uneven {
            return Err(bad(
                "pairs",
                model.pairs.len().to_string(),
                "the same number of pairs on every rank",
            ));
        }
        let (index, slaves_of) = valid.expect("agreed: every share valid");
        // balanced or not, the same on every rank (the passes' collectives must match)
        for (k, p) in model.pairs.iter().enumerate() {
            let w = p.balanced.as_ref().map_or(-1.0, |b| b.weight);
            if all_min(&comm, w) != all_max(&comm, w) {
                return Err(bad(
                    "balanced",
                    format!("pair {k}"),
                    "the same balance and weight on every rank",
                ));
            }
        }
        let n = model.ids.len();
        // each pair's facets on every rank, in rank order (a balanced pair's slave facets too)
        let mut gathered = Vec::with_capacity(model.pairs.len());
        for (k, p) in model.pairs.iter().enumerate() {
            let master = gather_facets(&comm, &p.facets, k)?;
            let slave = match &p.balanced {
                Some(b) => Some((gather_facets(&comm, &b.slave_facets, k)?, b.weight)),
                None => None,
            };
            gathered.push((master, slave));
        }
        let mut is_master = vec![false; n];
        for (master, slave) in &gathered {
            for f in master.iter().chain(slave.iter().flat_map(|s| &s.0)) {
                for &g in f {
                    if let Some(&i) = index.get(&g) {
                        is_master[i] = true;
                    }
                }
            }
        }
        // every master node's start position on every rank, once: the longest facet edge (the
        // ghost region's margin), the whole surfaces' areas, and facets naming a node nobody
        // owns
        let own_masters: Vec<usize> = (0..n).filter(|&i| is_master[i]).collect();
        let ids: Vec<u64> = own_masters.iter().map(|&i| model.ids[i]).collect();
        let pos: Vec<f64> = own_masters
            .iter()
            .flat_map(|&i| model.positions[i])
            .collect();
        let (all_ids, _) = all_gather(&comm, &ids);
        let (all_pos, _) = all_gather(&comm, &pos);
        let at: HashMap<u64, [f64; 3]> = all_ids
            .iter()
            .enumerate()
            .map(|(k, &g)| (g, [all_pos[3 * k], all_pos[3 * k + 1], all_pos[3 * k + 2]]))
            .collect();
        let mut edge = 0.0f64;
        let mut pairs = Vec::new();
        for (k, ((master, slave), (p, slaves))) in gathered
            .into_iter()
            .zip(model.pairs.iter().zip(slaves_of))
            .enumerate()
        {
            let (whole, local_of) = whole_surface(&master, &at, k)?;
            edge = edge.max(whole.facet_size.iter().copied().fold(0.0, f64::max));
            let areas = match &p.slave_areas {
                Some(a) => a.clone(),
                None => vec![whole.mean_facet_area(); slaves.len()],
            };
            let pass =
                |slaves: Vec<usize>, areas: Vec<f64>, weight: f64, facets, reverse| PairTopology {
                    slaves,
                    areas,
                    weight,
                    facets,
                    radius: p.search_radius,
                    penalty: p.penalty.clone(),
                    friction: p.friction.clone(),
                    interval: p.search_interval,
                    local: None,
                    of: (k, reverse),
                };
            let weight = slave.as_ref().map_or(1.0, |s| s.1);
            pairs.push(pass(slaves, areas, weight, master, false));
            if let Some((slave_facets, w)) = slave {
                // the master-on-slave pass: this rank's nodes of the master surface, each with
                // its tributary area on the whole surface
                let (slave_whole, _) = whole_surface(&slave_facets, &at, k)?;
                edge = edge.max(slave_whole.facet_size.iter().copied().fold(0.0, f64::max));
                let mine: Vec<usize> = (0..n)
                    .filter(|&i| {
                        local_of
                            .get(&model.ids[i])
                            .is_some_and(|&l| !whole.facets_of_node(l).is_empty())
                    })
                    .collect();
                let areas = mine
                    .iter()
                    .map(|&i| whole.tributary_area(local_of[&model.ids[i]]))
                    .collect();
                pairs.push(pass(mine, areas, 1.0 - w, slave_facets, true));
            }
        }
        let h_max = edge;
        // facets inside this rank's nodes: measured at every distributed global search
        let own_facets: Vec<[u32; 4]> = pairs
            .iter()
            .flat_map(|p| &p.facets)
            .filter_map(|f| {
                let mut l = [u32::MAX; 4];
                for j in 0..if f[3] == NO_GLOBAL_NODE { 3 } else { 4 } {
                    l[j] = *index.get(&f[j])? as u32;
                }
                Some(l)
            })
            .collect();
        let size = comm.size() as usize;
        Ok(Self {
            comm,
            device: device.clone(),
            ids: model.ids,
            masses: model.masses,
            index,
            pairs,
            h_max,
            local_facets: Vec::new(),
            own_facets,
            ghost_x: Vec::new(),
            master_nodes: (0..n).filter(|&i| is_master[i]).collect(),
            send: vec![Vec::new(); size],
            recv: vec![0; size],
            ghost_masses: Vec::new(),
            contact: None,
            dt_ref: None,
            since_search: 0,
            anchor: Vec::new(),
            started: false,
            last: DistributedStep::default(),
            outputs: false,
            searches: 0,
            ghost_ids: Vec::new(),
            rebuilds: 0,
        })
    }

    /// What the last increment did.
    pub fn last(&self) -> &DistributedStep {
        &self.last
    }

    /// Distributed global searches so far.
    pub fn global_searches(&self) -> u64 {
        self.searches
    }

    /// This rank's slave nodes, over every pass (a balanced pair's master nodes count in its
    /// second pass).
    pub fn slaves(&self) -> usize {
        self.pairs.iter().map(|p| p.slaves.len()).sum()
    }

    /// Local models built so far: the first, and one after each distributed global search that
    /// changed this rank's ghosts (an unchanged ghost set keeps the local contact).
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Whether the next increments compute per-slave outputs for [`Self::contact_outputs`]
    /// (as [`Contact::request_outputs`]; off by default).
    pub fn request_outputs(&mut self, on: bool) {
        self.outputs = on;
        if let Some(c) = self.contact.as_mut() {
            c.request_outputs(on);
        }
    }

    /// This rank's slaves in contact after the last increment (outputs requested before it), in
    /// pass order and each pass's slave order; and the energy its slaves' friction has
    /// dissipated since the start (carried through the rebuilds; every increment, requested or
    /// not, on the CPU path; with outputs on a GPU).
    pub fn contact_outputs(&self) -> (Vec<SlaveOutput>, f64) {
        let (mut list, mut dissipated) = (Vec::new(), 0.0);
        let Some(c) = self.contact.as_ref() else {
            return (list, dissipated);
        };
        let outs = c.outputs();
        for p in &self.pairs {
            let Some(id) = p.local else { continue };
            for (_, o) in outs.iter().filter(|(k, _)| *k == id) {
                dissipated += o.frictional_dissipation;
                for (k, &i) in p.slaves.iter().enumerate() {
                    let pressure = o.cpress.get(k).copied().unwrap_or(0.0);
                    if pressure > 0.0 {
                        list.push(SlaveOutput {
                            pair: p.of.0,
                            reverse: p.of.1,
                            node: self.ids[i],
                            pressure,
                            force: o.force.get(k).copied().unwrap_or([0.0; 3]),
                        });
                    }
                }
            }
        }
        (list, dissipated)
    }

    /// The motion budget: how far any node may move between distributed global searches (half
    /// the smallest search radius).
    fn budget(&self) -> f64 {
        0.5 * self
            .pairs
            .iter()
            .map(|p| p.radius)
            .fold(f64::INFINITY, f64::min)
    }

    /// The longest edge of this rank's local facets (at own positions `x` and the last
    /// increment's ghost positions) and of the facets all of whose nodes it owns. A facet cut
    /// between ranks and near no rank's slaves is not measured: one that stretches beyond twice
    /// the margin before it comes near a slave can still be missed.
    fn longest_local_edge(&self, x: &[[f64; 3]]) -> f64 {
        let n_own = x.len();
        let at = |i: u32| -> Option<[f64; 3]> {
            let i = i as usize;
            if i < n_own {
                Some(x[i])
            } else {
                self.ghost_x.get(i - n_own).copied()
            }
        };
        let mut longest = 0.0f64;
        for f in self.local_facets.iter().chain(&self.own_facets) {
            let m = if f[3] == u32::MAX { 3 } else { 4 };
            for j in 0..m {
                if let (Some(a), Some(b)) = (at(f[j]), at(f[(j + 1) % m])) {
                    let d = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
                    longest = longest.max(d);
                }
            }
        }
        longest
    }

    /// New ghosts for own positions `x`: the send lists, the ghosts' ids and masses. Returns
    /// the ghosts' global ids (by source rank, then in the order sent) and the bytes sent.
    fn choose_ghosts(&mut self, x: &[[f64; 3]]) -> (Vec<u64>, usize) {
        let size = self.comm.size() as usize;
        let grow = self.pairs.iter().map(|p| p.radius).fold(0.0f64, f64::max)
            + 2.0 * self.budget()
            + 2.0 * self.h_max;
        // this rank's slave region (none: an inverted box, which contains nothing)
        let mut region = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in &self.pairs {
            for &s in &p.slaves {
                for a in 0..3 {
                    region[a] = region[a].min(x[s][a] - grow);
                    region[3 + a] = region[3 + a].max(x[s][a] + grow);
                }
            }
        }
        let (regions, _) = all_gather(&self.comm, &region);
        let me = self.comm.rank() as usize;
        self.send = vec![Vec::new(); size];
        for r in (0..size).filter(|&r| r != me) {
            let b = &regions[6 * r..6 * r + 6];
            for &i in &self.master_nodes {
                if (0..3).all(|a| x[i][a] >= b[a] && x[i][a] <= b[3 + a]) {
                    self.send[r].push(i);
                }
            }
        }
        let ids_out: Vec<Vec<u64>> = self
            .send
            .iter()
            .map(|l| l.iter().map(|&i| self.ids[i]).collect())
            .collect();
        let mass_out: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|l| l.iter().map(|&i| self.masses[i]).collect())
            .collect();
        let ids_in = exchange(&self.comm, &ids_out);
        let mass_in = exchange(&self.comm, &mass_out);
        self.recv = ids_in.iter().map(Vec::len).collect();
        self.ghost_masses = mass_in.into_iter().flatten().collect();
        let sent: usize = self.send.iter().map(Vec::len).sum();
        (ids_in.into_iter().flatten().collect(), 16 * sent + 48)
    }

    /// The local model of own nodes at `x` and ghosts at `gx` (global ids `ghost_ids`), and its
    /// contact (none when this rank has no slave near any facet).
    fn build_local(&mut self, x: &[[f64; 3]], gx: &[[f64; 3]], ghost_ids: &[u64]) -> Result<()> {
        let n_own = self.ids.len();
        let mut local_of: HashMap<u64, u32> = HashMap::with_capacity(n_own + ghost_ids.len());
        for (&g, &i) in &self.index {
            local_of.insert(g, i as u32);
        }
        for (k, &g) in ghost_ids.iter().enumerate() {
            local_of.insert(g, (n_own + k) as u32);
        }
        let mut model = Model::new_3d();
        let positions: Vec<[f64; 3]> = x.iter().chain(gx).copied().collect();
        let masses: Vec<f64> = self
            .masses
            .iter()
            .chain(&self.ghost_masses)
            .copied()
            .collect();
        model.add_nodes(&positions, &masses)?;
        // the friction each slave carries, from the contact being replaced (same slaves, same
        // order: a slave never changes rank)
        let mut carried = Vec::with_capacity(self.pairs.len());
        for p in &self.pairs {
            carried.push(match (self.contact.as_ref(), p.local) {
                (Some(c), Some(id)) => Some(c.penalty_states(id)?),
                _ => None,
            });
        }
        let mut any = false;
        let mut local_facets = Vec::new();
        for p in self.pairs.iter_mut() {
            p.local = None;
            if p.slaves.is_empty() {
                continue;
            }
            let facets: Vec<Facet> = p
                .facets
                .iter()
                .filter_map(|f| {
                    let m = if f[3] == NO_GLOBAL_NODE { 3 } else { 4 };
                    let mut l = [0u32; 4];
                    for j in 0..m {
                        l[j] = *local_of.get(&f[j])?;
                    }
                    Some(if m == 3 {
                        Facet::Triangle([l[0], l[1], l[2]])
                    } else {
                        Facet::Quad(l)
                    })
                })
                .collect();
            if facets.is_empty() {
                continue;
            }
            local_facets.extend(facets.iter().map(|f| {
                let n = f.nodes();
                [n[0], n[1], n[2], n.get(3).copied().unwrap_or(u32::MAX)]
            }));
            let surf = model.add_surface(Surface::from_facets(facets.clone()))?;
            let slaves: Vec<u32> = p.slaves.iter().map(|&s| s as u32).collect();
            let set = model.add_node_set_with_areas(&slaves, &p.areas)?;
            // the single process's schedule: its interval, the defaults otherwise
            let on_surface: std::collections::HashSet<u32> =
                facets.iter().flat_map(|f| f.nodes().to_vec()).collect();
            let self_contact = slaves.iter().any(|s| on_surface.contains(s));
            let schedule = Schedule {
                interval: p.interval,
                ..Schedule::default_for(self_contact)
            };
            p.local = Some(
                model.add_pair(
                    Pair::new(set, surf)
                        .schedule(schedule)
                        .search_radius(p.radius)
                        .enforce(Enforce::Penalty(p.penalty.clone()))
                        .friction(p.friction.clone())
                        .pass_weight(p.weight),
                )?,
            );
            any = true;
        }
        self.contact = if any {
            let mut c = Contact::new(&self.device, &model)?;
            c.request_outputs(self.outputs);
            if let Some(dt) = self.dt_ref {
                c.set_reference_increment(dt)?;
            }
            for (p, states) in self.pairs.iter().zip(carried) {
                if let (Some(id), Some(s)) = (p.local, states) {
                    c.set_penalty_states(id, &s)?;
                }
            }
            Some(c)
        } else {
            None
        };
        self.anchor = positions;
        self.local_facets = local_facets;
        Ok(())
    }

    /// One increment: own nodes at `x` moving at `v` (in [`RankModel::ids`] order), increment
    /// `dt`. Collective: every rank calls it in the same increment with the same `dt`.
    pub fn step(&mut self, x: &[[f64; 3]], v: &[[f64; 3]], dt: f64) -> Result<&DistributedStep> {
        let n_own = self.ids.len();
        // faults are agreed on, never returned by one rank alone (the others would wait in the
        // next exchange for ever)
        let mut fault = None;
        if x.len() != n_own || v.len() != n_own {
            fault = Some(Error::LengthMismatch {
                what: "positions and velocities of the owned nodes",
                expected: n_own,
                got: x.len().min(v.len()),
            });
        } else if let Some((node, axis, value)) = (0..n_own)
            .flat_map(|i| (0..3).map(move |a| (i, a)))
            .map(|(i, a)| {
                (
                    i,
                    a,
                    if x[i][a].is_finite() {
                        v[i][a]
                    } else {
                        x[i][a]
                    },
                )
            })
            .find(|t| !t.2.is_finite())
        {
            fault = Some(Error::NonFiniteCoordinate { node, axis, value });
        }
        agree(&self.comm, fault)?;
        let mut fault = None;
        if self.dt_ref.is_none() {
            // the automatic stiffness' reference: the first increment, on every rank
            self.dt_ref = Some(all_min(&self.comm, dt));
        }
        // a distributed global search: first, at the interval, or when any node has used up
        // the motion budget (agreed: the largest motion over all ranks)
        let moved = if self.started {
            x.iter()
                .zip(&self.anchor)
                .map(|(p, q)| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt())
                .fold(0.0f64, f64::max)
        } else {
            0.0
        };
        let interval = self
            .pairs
            .iter()
            .map(|p| p.interval)
            .min()
            .unwrap_or(u32::MAX);
        let global = !self.started
            || self.since_search >= interval
            || all_max(&self.comm, moved) > self.budget();
        let mut bytes = 0;
        let mut ghost_ids = Vec::new();
        if global {
            // facets that stretched since the start widen the ghost margin (never narrowed)
            let longest = all_max(&self.comm, self.longest_local_edge(x));
            self.h_max = self.h_max.max(longest);
            let (ids, b) = self.choose_ghosts(x);
            ghost_ids = ids;
            bytes += b;
            self.since_search = 0;
            self.searches += 1;
        }
        self.since_search += 1;
        // the ghosts' state from their owners
        let state_out: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&i| [x[i][0], x[i][1], x[i][2], v[i][0], v[i][1], v[i][2]])
                    .collect()
            })
            .collect();
        bytes += 8 * state_out.iter().map(Vec::len).sum::<usize>();
        let state_in: Vec<f64> = exchange(&self.comm, &state_out)
            .into_iter()
            .flatten()
            .collect();
        let gx: Vec<[f64; 3]> = state_in
            .chunks_exact(6)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let gv: Vec<[f64; 3]> = state_in
            .chunks_exact(6)
            .map(|c| [c[3], c[4], c[5]])
            .collect();
        self.ghost_x.clone_from(&gx);
        if global {
            if self.started && ghost_ids == self.ghost_ids {
                // the same ghosts, so the same local model: the local contact goes on (its
                // search state, grid frame and friction untouched)
                self.anchor = x.to_vec();
            } else {
                if let Err(e) = self.build_local(x, &gx, &ghost_ids) {
                    self.contact = None;
                    fault = Some(e);
                }
                self.ghost_ids = ghost_ids;
                self.rebuilds += 1;
            }
            // the anchor of the motion budget: own positions now
            self.anchor.truncate(n_own);
            self.started = true;
        }
        let mut forces = vec![[0.0; 3]; n_own];
        let (mut stable, mut over, mut active) = (f64::INFINITY, 0.0f64, 0usize);
        let mut ghost_forces = vec![[0.0; 3]; gx.len()];
        // the fastest pair node here: (distance / radius, global id, pair, distance, radius)
        let mut fast = (0usize, [-1.0, 0.0, 0.0, 0.0, 0.0]);
        if let Some(c) = self.contact.as_mut() {
            let lx: Vec<[f64; 3]> = x.iter().chain(&gx).copied().collect();
            let lv: Vec<[f64; 3]> = v.iter().chain(&gv).copied().collect();
            match c.penalty_step(&lx, &lv, dt) {
                Ok(r) => {
                    forces.copy_from_slice(&r.forces[..n_own]);
                    ghost_forces.copy_from_slice(&r.forces[n_own..]);
                    stable = r.stable_dt;
                    over = r.max_overclosure;
                    active = r.active;
                    let rep = c.report();
                    if let Some(f) = rep.fastest {
                        let node = if f.node < n_own {
                            self.ids[f.node]
                        } else {
                            self.ghost_ids[f.node - n_own]
                        };
                        let pair = self
                            .pairs
                            .iter()
                            .find(|p| p.local == Some(f.pair))
                            .map_or(0, |p| p.of.0);
                        fast = (
                            rep.fast_nodes,
                            [
                                f.distance / f.radius,
                                node as f64,
                                pair as f64,
                                f.distance,
                                f.radius,
                            ],
                        );
                    }
                }
                Err(e) => fault = Some(e),
            }
        }
        // ghosts' forces back to their owners, added there in rank order
        let mut back: Vec<Vec<f64>> = Vec::with_capacity(self.recv.len());
        let mut at = 0;
        for &count in &self.recv {
            back.push(
                ghost_forces[at..at + count]
                    .iter()
                    .flat_map(|f| f.iter().copied())
                    .collect(),
            );
            at += count;
        }
        bytes += 8 * back.iter().map(Vec::len).sum::<usize>();
        let came = exchange(&self.comm, &back);
        for (q, list) in self.send.iter().enumerate() {
            for (k, &i) in list.iter().enumerate() {
                for a in 0..3 {
                    forces[i][a] += came[q][3 * k + a];
                }
            }
        }
        agree(&self.comm, fault)?;
        let (all_fast, _) = all_gather(&self.comm, &fast.1);
        let fastest = all_fast
            .chunks_exact(5)
            .filter(|f| f[0] > 1.0)
            .fold(None::<&[f64]>, |best, f| match best {
                Some(b) if b[0] >= f[0] => Some(b),
                _ => Some(f),
            })
            .map(|f| FastGlobalNode {
                node: f[1] as u64,
                pair: f[2] as usize,
                distance: f[3],
                radius: f[4],
            });
        self.last = DistributedStep {
            forces,
            stable_dt: all_min(&self.comm, stable),
            max_overclosure: all_max(&self.comm, over),
            active: all_sum(&self.comm, active as u64) as usize,
            global_search: global,
            bytes_sent: bytes,
            ghosts: gx.len(),
            fast_nodes: all_sum(&self.comm, fast.0 as u64) as usize,
            fastest,
        };
        Ok(&self.last)
    }
}
