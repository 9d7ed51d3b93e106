//! (feature `mpi`) Contact across MPI ranks: one model split over processes, each rank
//! holding its own nodes and running abut's search and enforcement on its own device —
//! penalty and kinematic pairs (finite, small and infinitesimal sliding; pure and balanced;
//! self-contact), and kinematic contact against analytical surfaces ([`DistributedRigid`]).
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
//! Small and infinitesimal sliding anchor each slave once, on its rank's local model, and
//! keep the anchor by global node ids through every rebuild (the anchored facets stay among
//! the rank's ghosts). A kinematic pair ([`RankPair::kinematic`]) runs after the solver's
//! prediction ([`DistributedContact::kinematic_step`]): each rank corrects its own slaves, and
//! the master nodes' shares of the corrections are summed on their owners in the pair's slave
//! order — the single process's bits — and sent back to the ranks holding them as ghosts.
//!
//! Rigid parts of mesh nodes ([`RankModel::rigid_parts`], free bodies' meshed surfaces under
//! penalty contact): every rank follows each whole part from its nodes' positions, given before
//! each increment ([`DistributedContact::move_rigid_parts`]), so the springs on it see the whole
//! body. The stable increment's node-wise bound is taken on rows summed over the ranks: each
//! ghost's row goes back to its owner with its force, and each body's share travels in the
//! increment's agreement.
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
use crate::model::Kinematic;
use crate::model::Schedule;
use crate::model::{
    Enforce, Facet, Friction, MasterSurface, Model, Pair, PairId, Penalty, Sliding, Surface,
};
use crate::search::KeyedAnchor;

mod anchors;
pub use anchors::PassAnchoring;
mod collectives;
mod rigid;
pub use rigid::{DistributedRigid, RankRigidPair};
mod ghosts;
mod outputs;
mod parts;
pub use parts::RankRigidPart;
mod share;
pub use outputs::SlaveOutput;
pub use share::{RankBalance, RankModel, RankPair};
mod kinematic;
pub use kinematic::KinematicStep;
mod step;
mod validate;

pub(crate) use collectives::{agree, all_gather_fixed, all_max, all_min, exchange, exchange_known};
pub use collectives::{all_gather, collectives_issued};
use collectives::{gather_facets, whole_surface};
use validate::validate;

/// Marks the unused nodes of a facet in [`RankPair::facets`]: a triangle's fourth, a 2D
/// segment's third and fourth.
pub const NO_GLOBAL_NODE: u64 = u64::MAX;

/// How many nodes facet `f` has (2: a segment, 3: a triangle, 4: a quad), its unused ids being
/// `none` ([`NO_GLOBAL_NODE`], or `u32::MAX` for local indices).
pub(crate) fn facet_node_count<T: PartialEq + Copy>(f: &[T; 4], none: T) -> usize {
    if f[2] == none {
        2
    } else if f[3] == none {
        3
    } else {
        4
    }
}

/// The facet of the first `m` nodes of `l` (a segment, a triangle or a quad).
pub(crate) fn facet_of(l: [u32; 4], m: usize) -> Facet {
    match m {
        2 => Facet::Segment([l[0], l[1]]),
        3 => Facet::Triangle([l[0], l[1], l[2]]),
        _ => Facet::Quad(l),
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
    /// MPI collectives this increment issued (the same on every rank): 4 for an increment
    /// between distributed global searches — the agreement on faults, motion and increment;
    /// the ghosts' state; their forces back; the agreement on the results — and 3 more for one
    /// that begins with a distributed global search (the slave boxes, the ghost counts and the
    /// ghosts' ids and masses).
    pub collectives: u64,
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

impl FastGlobalNode {
    /// A rank's fastest node as it travels in an agreement's record: its distance over its
    /// radius (−1: none), global id, pair, distance and radius.
    fn record(&self) -> [f64; 5] {
        [
            self.distance / self.radius,
            // the id travels as its bits (any u64, exactly)
            f64::from_bits(self.node),
            self.pair as f64,
            self.distance,
            self.radius,
        ]
    }

    /// The fastest of every rank's records (each `record` at `at` in its row), the first rank's
    /// of equal ones; none where no rank's node moved past its radius.
    fn fastest_of(rows: &[Vec<f64>], at: usize) -> Option<Self> {
        rows.iter()
            .map(|r| &r[at..at + 5])
            .filter(|f| f[0] > 1.0)
            .fold(None::<&[f64]>, |best, f| match best {
                Some(b) if b[0] >= f[0] => Some(b),
                _ => Some(f),
            })
            .map(|f| Self {
                node: f[1].to_bits(),
                pair: f[2] as usize,
                distance: f[3],
                radius: f[4],
            })
    }
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
    /// Whether the model is 2D ([`RankModel::two_d`]).
    two_d: bool,
    /// The local model's facets (local node indices, `u32::MAX` pads a triangle or segment),
    /// every pass.
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
    /// Bytes the kinematic correction of this increment sent so far.
    kinematic_bytes: std::cell::Cell<usize>,
    /// The rigid parts of mesh nodes ([`RankModel::rigid_parts`]).
    parts: parts::RankParts,
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
    sliding: Sliding,
    anchor_reach: Option<f64>,
    /// Small sliding: each slave's anchor (in `slaves` order) once found, its facet and node by
    /// global ids ([`NO_GLOBAL_NODE`] pads; all of them: unanchored), carried through rebuilds.
    anchors: Option<Vec<GlobalAnchor>>,
    /// Kinematic enforcement (`None`: penalty).
    kinematic: Option<Kinematic>,
    /// Each slave's place in the pair's whole slave list (the order a kinematic pair's sums
    /// over its slaves run in).
    keys: Vec<u64>,
    /// A kinematic pair: the energy its friction dissipated on this rank's nodes.
    dissipated: f64,
    /// A kinematic pair: each slave's contact pressure and force after the last increment.
    corrections: Vec<(f64, [f64; 3])>,
    /// A kinematic pair: each slave's behind-a-free-edge flag, carried through rebuilds.
    behind: Option<Vec<bool>>,
    /// The own nodes (own indices) of the pass's master facets.
    own_masters: Vec<usize>,
    /// A penalty pass: its search's frame (origin, and the master's extent it was chosen at)
    /// as one process's search would choose it from the whole master, the same on every rank
    /// (see [`DistributedContact::step`]).
    frame: Option<([f64; 3], f64)>,
}

impl PairTopology {
    /// A kinematic pair's Coulomb friction (μ static, μ kinetic, decay), if any.
    fn coulomb(&self) -> Option<(f64, f64, f64)> {
        match (&self.kinematic, &self.friction) {
            (
                Some(_),
                Friction::Coulomb {
                    mu,
                    mu_kinetic,
                    decay,
                    ..
                },
            ) => Some((*mu, *mu_kinetic, *decay)),
            _ => None,
        }
    }
}

/// A slave's anchor keyed by global node ids: its facet's nodes, its nearest node, the rest.
#[derive(Clone, Copy, Debug)]
struct GlobalAnchor {
    facet: [u64; 4],
    node: u64,
    anchor: KeyedAnchor,
}

/// The own nodes (own indices, increasing) of `facets` (global ids).
fn own_nodes_of(facets: &[[u64; 4]], index: &HashMap<u64, usize>) -> Vec<usize> {
    let mut own: Vec<usize> = facets
        .iter()
        .flatten()
        .filter_map(|g| index.get(g).copied())
        .collect();
    own.sort_unstable();
    own.dedup();
    own
}

fn bad(name: &'static str, value: String, expected: &'static str) -> Error {
    Error::BadParameter {
        name,
        value,
        expected,
    }
}

/// Own node index by global id, and each pair's slaves as own indices; or the first fault of
/// this rank's share (no collective: see [`agree`]).
type Validated = (HashMap<u64, usize>, Vec<Vec<usize>>);

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
        let dim = if model.two_d { 2.0 } else { 3.0 };
        let mixed = all_min(&comm, dim) != all_max(&comm, dim);
        agree(&comm, fault)?;
        if uneven {
            return Err(bad(
                "pairs",
                model.pairs.len().to_string(),
                "the same number of pairs on every rank",
            ));
        }
        if mixed {
            return Err(bad(
                "two_d",
                model.two_d.to_string(),
                "the same dimension on every rank",
            ));
        }
        let (index, slaves_of) = valid.expect("agreed: every share valid");
        // balanced or not, and the sliding, the same on every rank (the passes' collectives
        // and the ghost regions must match)
        for (k, p) in model.pairs.iter().enumerate() {
            let w = p.balanced.as_ref().map_or(-1.0, |b| b.weight);
            if all_min(&comm, w) != all_max(&comm, w) {
                return Err(bad(
                    "balanced",
                    format!("pair {k}"),
                    "the same balance and weight on every rank",
                ));
            }
            let sliding = match p.sliding {
                Sliding::Finite => -1.0,
                Sliding::Small => -2.0,
                Sliding::Infinitesimal => -3.0,
            };
            let how = [sliding, p.anchor_reach.unwrap_or(0.0)];
            if how.iter().any(|&v| all_min(&comm, v) != all_max(&comm, v)) {
                return Err(bad(
                    "sliding",
                    format!("pair {k}"),
                    "the same sliding and anchor reach on every rank",
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
            let (whole, local_of) = whole_surface(&master, &at, k, model.two_d)?;
            edge = edge.max(whole.facet_size.iter().copied().fold(0.0, f64::max));
            let areas = match &p.slave_areas {
                Some(a) => a.clone(),
                None => vec![whole.mean_facet_area(); slaves.len()],
            };
            let pass = |slaves: Vec<usize>,
                        areas: Vec<f64>,
                        weight: f64,
                        facets: Vec<[u64; 4]>,
                        reverse| PairTopology {
                own_masters: own_nodes_of(&facets, &index),
                frame: None,
                keys: match (&p.slave_keys, reverse) {
                    (Some(k), false) => k.clone(),
                    _ => slaves.iter().map(|&i| model.ids[i]).collect(),
                },
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
                sliding: p.sliding,
                anchor_reach: p.anchor_reach,
                anchors: None,
                kinematic: p.kinematic.clone(),
                dissipated: 0.0,
                corrections: Vec::new(),
                behind: None,
            };
            let weight = slave.as_ref().map_or(1.0, |s| s.1);
            pairs.push(pass(slaves, areas, weight, master, false));
            if let Some((slave_facets, w)) = slave {
                // the master-on-slave pass: this rank's nodes of the master surface, each with
                // its tributary area on the whole surface
                let (slave_whole, _) = whole_surface(&slave_facets, &at, k, model.two_d)?;
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
                for j in 0..facet_node_count(f, NO_GLOBAL_NODE) {
                    l[j] = *index.get(&f[j])? as u32;
                }
                Some(l)
            })
            .collect();
        let pass_slaves: Vec<usize> = pairs.iter().map(|p| p.slaves.len()).collect();
        let owns = |g: u64| index.contains_key(&g);
        let parts =
            parts::RankParts::new(&comm, &model.rigid_parts, model.two_d, &pass_slaves, &owns)?;
        let size = comm.size() as usize;
        Ok(Self {
            comm,
            device: device.clone(),
            two_d: model.two_d,
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
            kinematic_bytes: std::cell::Cell::new(0),
            parts,
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
}
