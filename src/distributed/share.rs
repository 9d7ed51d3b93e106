//! What a rank gives to take part in a distributed contact: the nodes it owns and its share
//! of each pair.

use crate::model::{Friction, Kinematic, Penalty, Sliding};

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
    /// The model is 2D (the x–y plane; [`crate::Model::new_2d`]): its facets are segments,
    /// `[a, b, NO_GLOBAL_NODE, NO_GLOBAL_NODE]`. The same on every rank.
    pub two_d: bool,
    /// The rigid parts of mesh nodes (free bodies' meshed surfaces), the same on every rank;
    /// give their nodes' positions before every increment
    /// ([`super::DistributedContact::move_rigid_parts`]).
    pub rigid_parts: Vec<super::RankRigidPart>,
}

/// One penalty pair's share on a rank.
#[derive(Clone, Debug)]
pub struct RankPair {
    /// This rank's slave nodes of the pair (global ids of nodes it owns; may be empty).
    pub slaves: Vec<u64>,
    /// The master facets this rank owns: 3D triangles (fourth id
    /// [`NO_GLOBAL_NODE`](super::NO_GLOBAL_NODE)) or quads, or in a 2D model segments (third
    /// and fourth [`NO_GLOBAL_NODE`](super::NO_GLOBAL_NODE)), by global node ids,
    /// nodes counter-clockwise seen from the side contact comes from.
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
    /// The sliding formulation, the same on every rank. Small and infinitesimal sliding anchor
    /// each slave once, at the first increment, on the nearest master facet within
    /// `anchor_reach` (as [`crate::Pair::sliding`]); the anchor stays with the slave's rank
    /// through every rebuild of its local model, keyed by global node ids.
    pub sliding: Sliding,
    /// Small sliding: how far the anchoring search reaches (model length units, the same on
    /// every rank); `None`: every master facet, however far a slave starts, as a single
    /// process's pair without a stated search radius — the first local models then hold
    /// every master node near no rank's slaves as well (O(surface) per rank, once).
    pub anchor_reach: Option<f64>,
    /// `Some`: the pair is enforced kinematically (the seed's predictor/corrector,
    /// [`super::DistributedContact::kinematic_step`]; `penalty` unused); finite sliding, pure or
    /// balanced.
    pub kinematic: Option<Kinematic>,
    /// Each slave's place in the pair's whole slave list (one per entry of `slaves`, unique
    /// over the ranks): a kinematic pair's sums over its slaves run in this order, the single
    /// process's for its node set's order; `None`: the slaves' global ids.
    pub slave_keys: Option<Vec<u64>>,
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
            sliding: Sliding::Finite,
            anchor_reach: None,
            kinematic: None,
            slave_keys: None,
        }
    }
}
