//! What each pass of a local increment reads and writes per item, declared once beside the
//! pass table: the records it touches (buffer, bytes from the layout types, how many per item,
//! for which items) — from which the benchmarks derive each pass's compulsory bytes per slave,
//! for slaves within the search radius and beyond it, instead of a table written by hand.
//!
//! Conventions (those of the compulsory-traffic estimate): a record a pass reads for one item is
//! counted for that item, even where neighbouring items read the same one (a slave's facet and
//! its nodes) — except the fixed-point sums of the gather, which the slaves sharing a master node
//! update in cache and which are counted once per master node. The status and statistics words (a few
//! atomics per workgroup) and the uniforms are not counted. A walk or loop is counted at its minimum
//! (one step of the local search's walk). The global search's passes are not declared: their
//! traffic follows the data (tree walks, chunks), and `abut bench --search` measures them.

use crate::abi::passes::{self, Buf, Items, Pass};
use crate::abi::penalty::ContactOut;
use crate::abi::search::GpuHit;

/// A `vec4<f32>` or `vec4<u32>` record (a node, a velocity, a normal, a facet), bytes.
const VEC4: u32 = 16;
/// A `u32`, bytes.
const WORD: u32 = 4;
/// A hit record, bytes.
const HIT: u32 = std::mem::size_of::<GpuHit>() as u32;
/// A contact output record, bytes.
const OUT: u32 = std::mem::size_of::<ContactOut>() as u32;
/// A slave's penalty state (friction force and area, history), bytes.
const STATE: u32 = 2 * VEC4;
/// The part of a contact output the scatter and the gather read (force xyz, status and the
/// bound's shares: 28 of its first 32 bytes, one memory sector), bytes.
const OUT_FORCE: u32 = 28;
/// A pair node's fixed-point sums (four 64-bit words), bytes.
const SUMS: u32 = 32;

/// Which of a pass's items a record is touched for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Of {
    /// Every item of the pass.
    Each,
    /// Items that are slave nodes (every item of a slave pass).
    Slave,
    /// Slave nodes within the search radius (tracked: they have a master node to walk from).
    NearSlave,
    /// Slave nodes beyond the search radius.
    FarSlave,
    /// Items that are master nodes (of a pass over nodes, pair nodes or watched nodes).
    Master,
    /// Items that are slave nodes within the search radius or master nodes (a pass over pair
    /// nodes that leaves a slave with no facet after reading its hit).
    NearOrMaster,
    /// Items that are master nodes under the slaves within the search radius (the nodes of
    /// their facets: a spring reads or scatters onto them).
    NearMaster,
    /// Items that are slave nodes within the search radius or master nodes under them (a pass
    /// over pair nodes that leaves the others after one word).
    Near,
    /// Once per master node of the pair whatever the items (records shared by the items that
    /// touch them, updated in cache).
    EachMasterNode,
    /// Slave nodes that crossed the search radius this increment (none in a steady increment:
    /// counted as none).
    Crossing,
    /// Slave nodes within the search radius that moved past their skin and walk (none in a
    /// steady increment: a walk is counted at its minimum, and `abut bench` reports how many
    /// walked).
    Walking,
}

/// How many records an item touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Per {
    /// One.
    One,
    /// One per node of its facet.
    FacetNode,
    /// One per facet around its node.
    NodeFacet,
    /// One per node of each facet around its node.
    NodeFacetNode,
}

/// Read or written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// Read.
    Read,
    /// Written.
    Write,
}

/// One kind of record a pass touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Touch {
    /// The buffer it lives in (one of the pass's bindings).
    pub buf: Buf,
    /// Read or written.
    pub dir: Dir,
    /// Bytes of the record (from the layout types).
    pub bytes: u32,
    /// How many per item.
    pub per: Per,
    /// For which items.
    pub of: Of,
}

const fn t(buf: Buf, dir: Dir, bytes: u32, per: Per, of: Of) -> Touch {
    Touch {
        buf,
        dir,
        bytes,
        per,
        of,
    }
}

use Buf::*;
use Dir::{Read as R, Write as W};
use Of::*;
use Per::*;

/// The records `pass` touches per item, or `None` for a pass whose traffic is not declared
/// (the global search's).
pub fn touches(pass: &Pass) -> Option<&'static [Touch]> {
    let list: &'static [Touch] = match pass.entry {
        // the node's id and the caller's position (in node order); the node in the frame read
        // (its mass) and written where the local passes read it (not for an untracked slave:
        // FLAG_SLAVES_APART); a master node's adjacency range (the box); the reference of every
        // node the budget counts, whose w is a slave's tracking state, and of a slave within
        // the radius, which the budget does not count, that state word alone
        "motion" => {
            const {
                &[
                    t(MotionNodes, R, WORD, One, Each),
                    t(Positions, R, VEC4, One, Each),
                    t(Reference, R, WORD, One, NearSlave),
                    t(Nodes, R, VEC4, One, NearOrMaster),
                    t(Nodes, W, VEC4, One, NearOrMaster),
                    t(Adjacency, R, 2 * WORD, One, Master),
                    t(Reference, R, VEC4, One, FarSlave),
                    t(Reference, R, VEC4, One, Master),
                ]
            }
        }
        "schedule" | "pair_stats" | "finish_stats" => &[],
        // the active slave's index; its hit's tracked node, facet and count word; for a slave
        // within its skin, its id, node and skin, the facet and its nodes; the hit written back
        // (its items are the active slaves: within the radius, or tracked from within the
        // tracking radius); the tracking state in the slave's reference, written only where it
        // crossed the radius; a slave past its skin walks: the tracked node's facet range and
        // facets with their nodes, and its new skin
        "local_search" => {
            const {
                &[
                    t(Status, R, WORD, One, Each),
                    t(Hits, R, 3 * WORD, One, Slave),
                    t(Slaves, R, WORD, One, NearSlave),
                    t(Nodes, R, VEC4, One, NearSlave),
                    t(Facets, R, VEC4, One, NearSlave),
                    t(Nodes, R, VEC4, FacetNode, NearSlave),
                    t(Skins, R, VEC4, One, NearSlave),
                    t(Hits, W, HIT, One, NearSlave),
                    t(Reference, W, WORD, One, Crossing),
                    t(Adjacency, R, 2 * WORD, One, Walking),
                    t(Adjacency, R, WORD, NodeFacet, Walking),
                    t(Facets, R, VEC4, NodeFacet, Walking),
                    t(Nodes, R, VEC4, NodeFacetNode, Walking),
                    t(Skins, W, VEC4, One, Walking),
                ]
            }
        }
        // a master node's pair node, facets with their nodes, its normal out (the slaves of a
        // pair whose slaves are no master nodes, PENALTY_SLAVES_APART, read nothing)
        "nodal_normals" => {
            const {
                &[
                    t(PairNodes, R, VEC4, One, Master),
                    t(PairAdjacency, R, WORD, NodeFacet, Master),
                    t(Facets, R, VEC4, NodeFacet, Master),
                    t(Nodes, R, VEC4, NodeFacetNode, Master),
                    t(Normals, W, VEC4, One, Master),
                ]
            }
        }
        // the active slave's index; the hit's facet word; for one with a facet, its pair nodes,
        // and each master node's need word marked (once per node: the slaves sharing it meet
        // in cache)
        "need_normals" => {
            const {
                &[
                    t(Status, R, WORD, One, Each),
                    t(Hits, R, WORD, One, Slave),
                    t(FacetNodes, R, VEC4, One, NearSlave),
                    t(Need, R, WORD, One, EachMasterNode),
                    t(Need, W, WORD, One, EachMasterNode),
                ]
            }
        }
        // a master node's need word; for one needed, as nodal_normals (the slaves of a pair
        // whose slaves are no master nodes read nothing)
        "nodal_normals_needed" => {
            const {
                &[
                    t(Need, R, WORD, One, Master),
                    t(PairNodes, R, VEC4, One, NearMaster),
                    t(PairAdjacency, R, WORD, NodeFacet, NearMaster),
                    t(Facets, R, VEC4, NodeFacet, NearMaster),
                    t(Nodes, R, VEC4, NodeFacetNode, NearMaster),
                    t(Normals, W, VEC4, One, NearMaster),
                ]
            }
        }
        // the active slave's index (penalty_active; counted for both: a word), the hit, the
        // state in and out, the output out, the slave's velocity (its fast-node test); in
        // contact, the facet, its nodes' positions, velocities and normals and the slave's
        // position
        "penalty" | "penalty_active" => {
            const {
                &[
                    t(Status, R, WORD, One, Each),
                    t(Hits, R, HIT, One, Slave),
                    t(State, R, STATE, One, Slave),
                    t(State, W, STATE, One, Slave),
                    t(Out, W, OUT, One, Slave),
                    t(Velocities, R, VEC4, One, Slave),
                    t(Facets, R, VEC4, One, NearSlave),
                    t(Nodes, R, VEC4, FacetNode, NearSlave),
                    t(Velocities, R, VEC4, FacetNode, NearSlave),
                    t(Normals, R, VEC4, FacetNode, NearSlave),
                    t(Nodes, R, VEC4, One, NearSlave),
                ]
            }
        }
        // the active slave's index (scatter_forces_active; counted for both), the output's
        // force, status and bound shares, and the hit's facet; in contact, the hit's weights, the facet's pair nodes, and each
        // master node's sums read and written (once per node: the slaves sharing it meet in
        // cache)
        "scatter_forces" | "scatter_forces_active" => {
            const {
                &[
                    t(Status, R, WORD, One, Each),
                    t(Out, R, OUT_FORCE, One, Slave),
                    t(Hits, R, WORD, One, Slave),
                    t(Hits, R, VEC4, One, NearSlave),
                    t(FacetNodes, R, VEC4, One, NearSlave),
                    t(Acc, R, SUMS, One, EachMasterNode),
                    t(Acc, W, SUMS, One, EachMasterNode),
                    t(Need, R, WORD, One, EachMasterNode),
                    t(Need, W, WORD, One, EachMasterNode),
                ]
            }
        }
        "gather" => &GATHER_TOUCHES,
        "add_forces" => &ADD_FORCES_TOUCHES,
        // as gather and add_forces, after an active slave's index (the slaves left out touch
        // nothing)
        "gather_active" => const { &after_active_index::<7, 8>(GATHER_TOUCHES) },
        "add_forces_active" => const { &after_active_index::<9, 10>(ADD_FORCES_TOUCHES) },
        // position, velocity and force read and written, the mass read
        "integrate" => {
            const {
                &[
                    t(Positions, R, VEC4, One, Each),
                    t(Positions, W, VEC4, One, Each),
                    t(Velocities, R, VEC4, One, Each),
                    t(Velocities, W, VEC4, One, Each),
                    t(HostForces, R, VEC4, One, Each),
                    t(HostForces, W, VEC4, One, Each),
                    t(Masses, R, WORD, One, Each),
                ]
            }
        }
        _ => return None,
    };
    Some(list)
}

/// `gather`: a slave's hit word (one with no facet stops there: PENALTY_SLAVES_APART), a master
/// node's need word (one no spring scattered onto stops there); the pair node, a slave's own
/// output, the sums read and zeroed, the force out.
const GATHER_TOUCHES: [Touch; 7] = [
    t(Hits, R, WORD, One, Slave),
    t(Need, R, WORD, One, Master),
    t(PairNodes, R, VEC4, One, Near),
    t(Out, R, OUT_FORCE, One, NearSlave),
    t(Acc, R, SUMS, One, Near),
    t(Acc, W, SUMS, One, Near),
    t(Forces, W, VEC4, One, Near),
];

/// `add_forces`: a slave's hit word and a master node's need word (as gather; the need word
/// cleared where it was set); the pair node and its force; the caller's force read and written,
/// the bound row (and with it the largest row, a statistics word).
const ADD_FORCES_TOUCHES: [Touch; 9] = [
    t(Hits, R, WORD, One, Slave),
    t(Need, R, WORD, One, Master),
    t(Need, W, WORD, One, NearMaster),
    t(PairNodes, R, VEC4, One, Near),
    t(Forces, R, VEC4, One, Near),
    t(HostForces, R, VEC4, One, Near),
    t(HostForces, W, VEC4, One, Near),
    t(Rows, R, WORD, One, Near),
    t(Rows, W, WORD, One, Near),
];

/// `list` after the word of an active slave's index in the status words (a pass over the active
/// slaves and the pair's other nodes).
const fn after_active_index<const N: usize, const M: usize>(list: [Touch; N]) -> [Touch; M] {
    let mut out = [t(Status, R, WORD, One, Slave); M];
    let mut i = 0;
    while i < N {
        out[i + 1] = list[i];
        i += 1;
    }
    out
}

/// The shape of a contact surface the declared bytes are evaluated on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Topology {
    /// Master nodes per slave node.
    pub masters_per_slave: f64,
    /// Facets around a master node.
    pub facets_per_node: f64,
    /// Nodes of a facet.
    pub nodes_per_facet: f64,
}

impl Topology {
    /// How many records `per` is for one item.
    fn count(&self, per: Per) -> f64 {
        match per {
            One => 1.0,
            FacetNode => self.nodes_per_facet,
            NodeFacet => self.facets_per_node,
            NodeFacetNode => self.facets_per_node * self.nodes_per_facet,
        }
    }

    /// Items of `of` per slave node for a pass over `items`, with `near` the share of slaves
    /// within the search radius.
    fn items(&self, items: Items, of: Of, near: f64) -> f64 {
        if items == Items::ActivePairNodes {
            // the active slaves (those within the radius in the bench), then every master node
            let m = self.masters_per_slave;
            return match of {
                Each | NearOrMaster => near + m,
                Slave | NearSlave => near,
                FarSlave => 0.0,
                Master | EachMasterNode => m,
                NearMaster => m * near,
                Near => near + m * near,
                Crossing | Walking => 0.0,
            };
        }
        if items == Items::ActiveSlaves {
            // every item is a slave within the radius (the bench's active slaves are those),
            // and the master nodes they touch are the share of the master under them
            return match of {
                Each | Slave | NearSlave => near,
                FarSlave | Master | NearMaster | Crossing | Walking => 0.0,
                NearOrMaster | Near => near,
                EachMasterNode => self.masters_per_slave * near,
            };
        }
        let per_slave = match items {
            Items::Slaves => 1.0,
            // a pass over nodes, pair nodes or watched nodes: the slaves and the master nodes
            Items::Nodes | Items::PairNodes | Items::MotionNodes => 1.0 + self.masters_per_slave,
            _ => 0.0,
        };
        match of {
            Each => per_slave,
            Slave => per_slave.min(1.0),
            NearSlave => per_slave.min(1.0) * near,
            FarSlave => per_slave.min(1.0) * (1.0 - near),
            Master => (per_slave - 1.0).max(0.0),
            NearOrMaster => per_slave.min(1.0) * near + (per_slave - 1.0).max(0.0),
            NearMaster => (per_slave - 1.0).max(0.0) * near,
            Near => per_slave.min(1.0) * near + (per_slave - 1.0).max(0.0) * near,
            EachMasterNode => self.masters_per_slave,
            Crossing | Walking => 0.0,
        }
    }
}

/// Bytes `pass` reads and writes per slave node on `topology` when the share `near` of the
/// slaves is within the search radius (0 to 1), or `None` when its traffic is not declared.
pub fn bytes_per_slave(pass: &Pass, topology: &Topology, near: f64) -> Option<f64> {
    let touches = touches(pass)?;
    Some(
        touches
            .iter()
            .map(|t| {
                topology.items(pass.items, t.of, near) * topology.count(t.per) * t.bytes as f64
            })
            .sum(),
    )
}

/// Of [`bytes_per_slave`], the records that are the slave's own: one per slave item (its id,
/// position, velocity, hit, skin, reference, penalty state, output, pair node, sums and
/// forces) — not its facet's, the facet's nodes' or the master nodes' records, which the slaves
/// near a master node share. `None` where `pass` declares no traffic.
pub fn own_bytes_per_slave(pass: &Pass, topology: &Topology, near: f64) -> Option<f64> {
    let touches = touches(pass)?;
    // with no master node per slave, a pass's items are its slave items alone
    let slaves_only = Topology {
        masters_per_slave: 0.0,
        ..*topology
    };
    Some(
        touches
            .iter()
            .filter(|t| t.per == Per::One && !MASTER_RECORDS.contains(&t.buf))
            .map(|t| slaves_only.items(pass.items, t.of, near) * t.bytes as f64)
            .sum(),
    )
}

/// Buffers whose records are the master's whichever item reads them: the facets, their pair
/// nodes and the master's adjacency.
const MASTER_RECORDS: [Buf; 4] = [Facets, FacetNodes, Adjacency, PairAdjacency];

/// The passes whose traffic is declared: a local increment's (the slave passes over the active
/// slaves) and the integrator.
pub const DECLARED: [&Pass; 12] = [
    &passes::MOTION,
    &passes::SCHEDULE,
    &passes::LOCAL_SEARCH,
    &passes::NEED_NORMALS,
    &passes::NODAL_NORMALS_NEEDED,
    &passes::PENALTY_ACTIVE,
    &passes::SCATTER_FORCES_ACTIVE,
    &passes::GATHER_ACTIVE,
    &passes::ADD_FORCES_ACTIVE,
    &passes::PAIR_STATS,
    &passes::FINISH_STATS,
    &passes::INTEGRATE,
];

/// Passes of a local increment's groups that a local increment does not run: the penalty
/// passes over every slave and the gather and add over every pair node, which run after a global
/// search (and for small sliding, or slaves that are master nodes) in place of the active
/// slaves' ones, and every master node's normals (small sliding).
pub const NOT_LOCAL: [&Pass; 5] = [
    &passes::PENALTY,
    &passes::SCATTER_FORCES,
    &passes::GATHER,
    &passes::ADD_FORCES,
    &passes::NODAL_NORMALS,
];

#[cfg(test)]
#[path = "traffic_tests.rs"]
mod tests;
