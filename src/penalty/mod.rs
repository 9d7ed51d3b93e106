//! Penalty enforcement of a contact pair: the static data its kernels need, and the
//! parameters of one increment. The kernels are `shaders/{nodal_normals,penalty,gather}.wgsl` (GPU, [`crate::gpu::GpuPenalty`]) and their mirrors in [`crate::cpu`].

pub mod layout;

use crate::error::Result;
use crate::model::{
    Friction, MasterSurface, Model, Pair, PairId, Penalty, PressureOverclosure, Stiffness,
};
use layout::*;

/// The static description of a penalty pair in the kernels' layout.
#[derive(Clone, Debug)]
pub struct PenaltySetup {
    /// Slave nodes then master nodes not already listed (a node in both appears once).
    pub pair_nodes: Vec<PairNode>,
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
        let pair: &Pair = model.pair(id)?;
        let areas: Vec<f64> = match model.node_set_areas(pair.slave)? {
            Some(a) => a.to_vec(),
            None => vec![master.mean_facet_area(); slaves.len()],
        };
        let weight = pair.balanced.map_or(1.0, |(_, w)| w);
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
        if pair.sliding != crate::model::Sliding::Finite {
            params.flags |= PENALTY_ANCHORED;
        }
        Ok(Self {
            pair_nodes,
            adjacency,
            facet_nodes,
            areas,
            friction: !matches!(pair.friction, Friction::Frictionless),
            params,
        })
    }

    /// The parameters of one increment `dt` with reference increment `dt_ref`.
    pub fn params(&self, dt: f64, dt_ref: f64) -> PenaltyParams {
        let mut p = self.params;
        p.n_pair_nodes = self.pair_nodes.len() as u32;
        p.dt = dt as f32;
        p.dt_ref = dt_ref as f32;
        p
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
        _pad0: 0,
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
