//! Penalty enforcement of a contact pair: the static data its kernels need, and the
//! parameters of one increment. The kernels are `shaders/{nodal_normals,penalty,gather}.wgsl` (GPU, [`crate::gpu::GpuPenalty`]) and their mirrors in [`crate::cpu`].

use crate::abi::penalty::*;
use crate::error::Result;
use crate::model::{
    Friction, MasterSurface, Model, Pair, PairId, Penalty, PressureOverclosure, Stiffness,
};

/// A rigid part's state for one increment: what a penalty spring on it needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidState {
    /// Centre of mass now, model units.
    pub centre: [f64; 3],
    /// 1 / mass.
    pub inv_mass: f64,
    /// Inverse rotational inertia about the centre, model frame now.
    pub inv_inertia: [[f64; 3]; 3],
}

/// The static description of a penalty pair in the kernels' layout.
#[derive(Clone, Debug)]
pub struct PenaltySetup {
    /// Slave nodes then master nodes not already listed (a node in both appears once); then
    /// one slot per rigid part of the pair (its row of the node-wise bound, carried to the
    /// part's lowest node).
    pub pair_nodes: Vec<PairNode>,
    /// Pair nodes proper (before the rigid parts' slots).
    pub n_nodes: usize,
    /// The rigid part (model index) the master surface lies on, and the slave nodes'.
    pub rigid: (Option<usize>, Option<usize>),
    /// Active facet indices adjacent to each pair node, increasing.
    pub adjacency: Vec<u32>,
    /// The pair-node index of each node of each active facet (`u32::MAX` pads segments and
    /// triangles): where the gather sums a contact's reaction.
    pub facet_nodes: Vec<[u32; 4]>,
    /// Tributary area of each slave node (length in 2D).
    pub areas: Vec<f32>,
    /// Whether friction work is compiled in.
    pub friction: bool,
    /// Parameters except the increment and the reference increment.
    pub params: PenaltyParams,
}

impl PenaltySetup {
    /// Builds the setup of pair `id` whose master surface is `master` and slaves `slaves`
    /// (the slave-on-master pass; weighted when the pair is balanced).
    pub fn new(model: &Model, id: PairId, master: &MasterSurface, slaves: &[u32]) -> Result<Self> {
        let given: Vec<u32> = (0..slaves.len() as u32).collect();
        Self::ordered(model, id, master, slaves, &given)
    }

    /// As [`PenaltySetup::new`], with the slave nodes `slaves` in the order the pair keeps them
    /// ([`crate::model::SlaveOrder`]): slave `k` is entry `node_set_index[k]` of the pair's node
    /// set (where its tributary area, when the node set has them, is found).
    pub fn ordered(
        model: &Model,
        id: PairId,
        master: &MasterSurface,
        slaves: &[u32],
        node_set_index: &[u32],
    ) -> Result<Self> {
        let pair: &Pair = model.pair(id)?;
        if node_set_index.len() != slaves.len() {
            return Err(crate::error::Error::LengthMismatch {
                what: "node-set index of each slave node",
                expected: slaves.len(),
                got: node_set_index.len(),
            });
        }
        let areas: Vec<f64> = match model.node_set_areas(pair.slave)? {
            Some(a) => node_set_index
                .iter()
                .map(|&c| {
                    a.get(c as usize)
                        .copied()
                        .ok_or(crate::error::Error::IndexOutOfRange {
                            what: format!("node-set index of a slave node of pair {}", id.0),
                            index: c as u64,
                            len: a.len(),
                        })
                })
                .collect::<Result<_>>()?,
            None => vec![master.mean_facet_area(); slaves.len()],
        };
        let weight = pair.balanced.map_or(pair.pass_weight, |(_, w)| w);
        Self::from_parts(model, id, master, slaves, &areas, weight)
    }

    /// The master-on-slave pass of a balanced pair: the nodes of the pair's master surface
    /// `master` against the slave surface `slave_surface`, weighted 1 − w; each master node
    /// carries its tributary area on `master`.
    pub fn reverse(
        model: &Model,
        id: PairId,
        master: &MasterSurface,
        slave_surface: &MasterSurface,
        master_nodes: &[u32],
    ) -> Result<Self> {
        let pair: &Pair = model.pair(id)?;
        let w = pair.balanced.map_or(0.5, |(_, w)| w);
        let areas: Vec<f64> = master_nodes
            .iter()
            .map(|&n| master.tributary_area(n))
            .collect();
        Self::from_parts(model, id, slave_surface, master_nodes, &areas, 1.0 - w)
    }

    fn from_parts(
        model: &Model,
        id: PairId,
        master: &MasterSurface,
        slaves: &[u32],
        areas: &[f64],
        weight: f64,
    ) -> Result<Self> {
        let pair: &Pair = model.pair(id)?;
        let crate::model::Enforce::Penalty(pen) = &pair.enforce else {
            return Err(crate::error::Error::BadParameter {
                name: "enforce",
                value: format!("pair {}", id.0),
                expected: "a penalty pair",
            });
        };
        let areas: Vec<f32> = areas.iter().map(|&a| a as f32).collect();
        // active index of each surface facet
        let mut active_index = vec![u32::MAX; master.facets.len()];
        for (k, &f) in master.active.iter().enumerate() {
            active_index[f as usize] = k as u32;
        }
        let mut pair_nodes = Vec::new();
        let mut adjacency = Vec::new();
        let mut slave_of = std::collections::HashMap::new();
        for (i, &s) in slaves.iter().enumerate() {
            slave_of.insert(s, i as u32);
        }
        let mut push = |node: u32, slave: u32, adjacency: &mut Vec<u32>| {
            let start = adjacency.len() as u32;
            adjacency.extend(
                master
                    .facets_of_node(node)
                    .iter()
                    .map(|&f| active_index[f as usize]),
            );
            pair_nodes.push(PairNode {
                node,
                slave,
                adj_start: start,
                adj_end: adjacency.len() as u32,
            });
        };
        for (i, &s) in slaves.iter().enumerate() {
            push(s, i as u32, &mut adjacency);
        }
        for n in master.nodes() {
            if !slave_of.contains_key(&n) {
                push(n, NO_SLAVE, &mut adjacency);
            }
        }
        let pair_index: std::collections::HashMap<u32, u32> = pair_nodes
            .iter()
            .enumerate()
            .map(|(i, pn)| (pn.node, i as u32))
            .collect();
        // rigid parts: one row slot each after the nodes, carried to the part's lowest node
        let n_nodes = pair_nodes.len();
        let master_part =
            model.rigid_part_of(&master.nodes(), &format!("master of pair {}", id.0))?;
        let slave_part = model.rigid_part_of(slaves, &format!("slave nodes of pair {}", id.0))?;
        if master_part.is_some() && master_part == slave_part {
            return Err(crate::error::Error::BadParameter {
                name: "rigid part",
                value: format!("pair {}", id.0),
                expected: "slave nodes and a master surface on different bodies",
            });
        }
        let mut slots = [NO_SLAVE; 2];
        for (k, part) in [master_part, slave_part].into_iter().enumerate() {
            if let Some(part) = part {
                let rep = *model.rigid_parts()[part]
                    .nodes
                    .iter()
                    .min()
                    .expect("a rigid part has nodes");
                slots[k] = pair_nodes.len() as u32;
                pair_nodes.push(PairNode {
                    node: rep,
                    slave: NO_SLAVE,
                    adj_start: 0,
                    adj_end: 0,
                });
            }
        }
        let facet_nodes = master
            .active
            .iter()
            .map(|&f| {
                master.facets[f as usize].padded().map(|n| {
                    if n == u32::MAX {
                        n
                    } else {
                        pair_index[&n]
                    }
                })
            })
            .collect();
        let mut params = base_params(pen, &pair.friction, slaves.len(), master.active.len());
        params.weight = weight as f32;
        params.body_slots = [slots[0], slots[1], (pair_nodes.len() - n_nodes) as u32, 0];
        if slave_part.is_some() {
            params.slave_share = slaves.len().max(1) as f32;
        }
        if pair.sliding != crate::model::Sliding::Finite {
            params.flags |= PENALTY_ANCHORED;
        }
        // the slaves come first among the pair nodes; one on a master facet (self-contact, or
        // surfaces sharing nodes) may be a master partner whatever its own hit
        if pair_nodes[..slaves.len()]
            .iter()
            .all(|pn| pn.adj_start == pn.adj_end)
        {
            params.flags |= PENALTY_SLAVES_APART;
        }
        Ok(Self {
            pair_nodes,
            n_nodes,
            rigid: (master_part, slave_part),
            adjacency,
            facet_nodes,
            areas,
            friction: !matches!(pair.friction, Friction::Frictionless),
            params,
        })
    }

    /// Binds the setup to its pair's search: the search `radius` (model units) and the
    /// reference master node `ref_node` the fast-node test measures against
    /// (`GlobalSearch::reference_node`).
    pub fn with_search(mut self, radius: f64, ref_node: u32) -> Self {
        self.params.search_radius = radius as f32;
        self.params.ref_node = ref_node;
        self
    }

    /// The parameters of one increment `dt` with reference increment `dt_ref`.
    pub fn params(&self, dt: f64, dt_ref: f64) -> PenaltyParams {
        let mut p = self.params;
        p.n_pair_nodes = self.n_nodes as u32;
        p.dt = dt as f32;
        p.dt_ref = dt_ref as f32;
        p
    }

    /// Puts the states of the pair's rigid parts (`states`, by model index) into `p`, their
    /// centres relative to the kernels' `frame` origin.
    pub fn set_rigid(&self, p: &mut PenaltyParams, states: &[RigidState], frame: [f64; 3]) {
        for (part, body, inertia) in [
            (self.rigid.0, &mut p.master_body, &mut p.master_inv_inertia),
            (self.rigid.1, &mut p.slave_body, &mut p.slave_inv_inertia),
        ] {
            if let Some(k) = part {
                let s = &states[k];
                *body = [
                    (s.centre[0] - frame[0]) as f32,
                    (s.centre[1] - frame[1]) as f32,
                    (s.centre[2] - frame[2]) as f32,
                    s.inv_mass as f32,
                ];
                for (row, j) in inertia.iter_mut().zip(&s.inv_inertia) {
                    *row = [j[0] as f32, j[1] as f32, j[2] as f32, 0.0];
                }
            }
        }
    }

    /// The initial per-slave state: no friction force, the tributary area.
    pub fn initial_state(&self) -> Vec<SlaveState> {
        self.areas
            .iter()
            .map(|&a| SlaveState {
                tangential_area: [0.0, 0.0, 0.0, a],
                history: [0.0; 4],
            })
            .collect()
    }
}

fn base_params(
    pen: &Penalty,
    friction: &Friction,
    n_slaves: usize,
    n_facets: usize,
) -> PenaltyParams {
    let mut p = PenaltyParams {
        n_slaves: n_slaves as u32,
        n_pair_nodes: 0,
        n_facets: n_facets as u32,
        law: LAW_LINEAR,
        stiffness_mode: STIFFNESS_AUTO,
        table_len: 0,
        flags: 0,
        ref_node: crate::model::NO_NODE,
        stiffness: 1.0,
        modulus: 0.0,
        dt: 0.0,
        dt_ref: 0.0,
        damping: pen.damping as f32,
        mu: 0.0,
        mu_kinetic: 0.0,
        decay: 0.0,
        stick_stiffness: 1.0,
        clearance: 0.0,
        pressure: 0.0,
        weight: 1.0,
        table: [[0.0; 4]; 8],
        master_body: [0.0; 4],
        master_inv_inertia: [[0.0; 4]; 3],
        slave_body: [0.0; 4],
        slave_inv_inertia: [[0.0; 4]; 3],
        body_slots: [NO_SLAVE, NO_SLAVE, 0, 0],
        search_radius: f32::MAX,
        slave_share: 1.0,
        _pad: [0; 2],
    };
    match pen.stiffness {
        Stiffness::Auto { scale } => p.stiffness = (AUTO_STIFFNESS * scale) as f32,
        Stiffness::Modulus { modulus, scale } => {
            p.stiffness_mode = STIFFNESS_MODULUS;
            p.stiffness = scale as f32;
            p.modulus = modulus as f32;
        }
        Stiffness::Absolute(k) => {
            p.stiffness_mode = STIFFNESS_ABSOLUTE;
            p.stiffness = k as f32;
        }
        Stiffness::PerArea(k) => {
            p.stiffness_mode = STIFFNESS_PER_AREA;
            p.stiffness = k as f32;
        }
    }
    match &pen.law {
        PressureOverclosure::Linear => {}
        PressureOverclosure::Exponential {
            clearance,
            pressure,
        } => {
            p.law = LAW_EXPONENTIAL;
            p.clearance = *clearance as f32;
            p.pressure = *pressure as f32;
        }
        PressureOverclosure::Tabular(t) => {
            p.law = LAW_TABULAR;
            p.table_len = t.len() as u32;
            for (k, (h, pr)) in t.iter().enumerate() {
                p.table[k / 2][2 * (k % 2)] = *h as f32;
                p.table[k / 2][2 * (k % 2) + 1] = *pr as f32;
            }
        }
    }
    if let Friction::Coulomb {
        mu,
        mu_kinetic,
        decay,
        stick_stiffness,
    } = *friction
    {
        p.mu = mu as f32;
        p.mu_kinetic = mu_kinetic as f32;
        p.decay = decay as f32;
        p.stick_stiffness = stick_stiffness as f32;
    }
    p
}
