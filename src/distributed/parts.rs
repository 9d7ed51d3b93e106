//! Rigid parts of mesh nodes across ranks (free bodies' meshed surfaces under penalty
//! contact): every rank follows each whole part from its nodes' positions — the same on every
//! rank, so the same state, to the bit, as one process's — and gives that state to its local
//! model, which holds only some of the part's nodes; a rigid slave part shares its body among
//! the whole pass's springs; and the node-wise bound's rows of nodes held by several ranks and of
//! the bodies are summed over the ranks, one process's bound being on the sums.

use super::*;
use crate::contact::RigidPartRun;

/// A rigid part of mesh nodes — a free body's meshed surface (as [`crate::Model::add_rigid_part`]),
/// the same on every rank: the penalty springs on it see the whole body's mass and rotational
/// inertia at the contact point, and they add up in the stable increment as one body.
#[derive(Clone, Debug, PartialEq)]
pub struct RankRigidPart {
    /// Global ids of all its nodes (owned by any rank), in the order its positions are given.
    pub ids: Vec<u64>,
    /// Their positions at the start (model length units), in `ids` order.
    pub positions: Vec<[f64; 3]>,
    /// Mass (> 0, model mass units).
    pub mass: f64,
    /// Rotational inertia about the nodes' centroid, model frame at `positions` (symmetric
    /// positive definite).
    pub inertia: [[f64; 3]; 3],
}

/// The rigid parts on one rank.
#[derive(Debug, Default)]
pub(super) struct RankParts {
    /// Global ids of each part's nodes.
    ids: Vec<Vec<u64>>,
    /// Each whole part, followed from its nodes' positions.
    runs: Vec<RigidPartRun>,
    /// Masses and inertias (for the local models' parts).
    bodies: Vec<(f64, [[f64; 3]; 3])>,
    /// Positions given for the coming increment.
    moved: bool,
    /// Each pass's slaves over all ranks (a rigid slave part shares its body among them).
    pass_slaves: Vec<usize>,
    /// The parts the local model holds (by index here), each with its lowest local node (where
    /// the local contact carries the part's row of the bound).
    pub(super) local: Vec<(usize, u32)>,
}

impl RankParts {
    /// The parts of `given` (checked; the same number on every rank, and every node of each
    /// owned by some rank — `owns` tells this rank's — else an error on every rank), with each
    /// of `passes`' slave counts summed over the ranks when there are any. Collective.
    pub(super) fn new(
        comm: &SimpleCommunicator,
        given: &[RankRigidPart],
        two_d: bool,
        passes: &[usize],
        owns: &dyn Fn(u64) -> bool,
    ) -> Result<Self> {
        let fault = given
            .iter()
            .enumerate()
            .find_map(|(k, p)| check(k, p, two_d).err());
        let count = given.len() as f64;
        let uneven = all_min(comm, count) != all_max(comm, count);
        agree(comm, fault)?;
        if uneven {
            return Err(bad(
                "rigid_parts",
                given.len().to_string(),
                "the same rigid parts on every rank",
            ));
        }
        if given.is_empty() {
            return Ok(Self::default());
        }
        // one gather: each pass's slaves here, and how many of each part's nodes are owned here
        let mine: Vec<f64> = passes
            .iter()
            .map(|&n| n as f64)
            .chain(
                given
                    .iter()
                    .map(|p| p.ids.iter().filter(|&&g| owns(g)).count() as f64),
            )
            .collect();
        let all = all_gather_fixed(comm, &mine);
        let total = |k: usize| all.iter().skip(k).step_by(mine.len()).sum::<f64>() as usize;
        for (k, p) in given.iter().enumerate() {
            let owned = total(passes.len() + k);
            if owned != p.ids.len() {
                return Err(bad(
                    "rigid part",
                    format!(
                        "rigid part {k}: {owned} of its {} nodes owned by a rank",
                        p.ids.len()
                    ),
                    "every node of a rigid part owned by one rank",
                ));
            }
        }
        Ok(Self {
            ids: given.iter().map(|p| p.ids.clone()).collect(),
            runs: given
                .iter()
                .map(|p| RigidPartRun::whole(&p.positions, p.mass, p.inertia, two_d))
                .collect(),
            bodies: given.iter().map(|p| (p.mass, p.inertia)).collect(),
            moved: false,
            pass_slaves: (0..passes.len()).map(total).collect(),
            local: Vec::new(),
        })
    }

    /// How many parts there are.
    pub(super) fn len(&self) -> usize {
        self.runs.len()
    }

    /// Adds to `model` (a rank's local model, node `local_of[g]` for global id `g`) each part
    /// it holds nodes of, as its nodes there; remembers which, with their lowest local nodes.
    pub(super) fn add_to(&mut self, model: &mut Model, local_of: &HashMap<u64, u32>) -> Result<()> {
        self.local.clear();
        for (k, ids) in self.ids.iter().enumerate() {
            let mut nodes: Vec<u32> = ids
                .iter()
                .filter_map(|g| local_of.get(g).copied())
                .collect();
            if nodes.is_empty() {
                continue;
            }
            nodes.sort_unstable();
            let (mass, inertia) = self.bodies[k];
            model.add_rigid_part(&nodes, mass, inertia)?;
            self.local.push((k, nodes[0]));
        }
        Ok(())
    }

    /// The states of the parts the local model holds, in its order.
    pub(super) fn local_states(&self) -> Vec<crate::penalty::RigidState> {
        self.local
            .iter()
            .map(|&(k, _)| self.runs[k].state())
            .collect()
    }

    /// Each pass's slaves over all ranks.
    pub(super) fn pass_slaves(&self, pass: usize) -> usize {
        self.pass_slaves[pass]
    }

    /// Whether positions were given for the coming increment (cleared: once per increment).
    pub(super) fn take_moved(&mut self) -> bool {
        std::mem::take(&mut self.moved) || self.runs.is_empty()
    }
}

/// Part `k` checked: one position per id, finite, unique ids, a body's mass and inertia.
fn check(k: usize, p: &RankRigidPart, two_d: bool) -> Result<()> {
    if p.ids.is_empty() {
        return Err(Error::Empty {
            what: format!("rigid part {k}"),
        });
    }
    if p.positions.len() != p.ids.len() {
        return Err(Error::LengthMismatch {
            what: "rigid part positions (one per node id)",
            expected: p.ids.len(),
            got: p.positions.len(),
        });
    }
    let mut seen = std::collections::HashSet::with_capacity(p.ids.len());
    if let Some(g) = p
        .ids
        .iter()
        .find(|&&g| g == NO_GLOBAL_NODE || !seen.insert(g))
    {
        return Err(bad(
            "rigid part node",
            format!("global id {g} of rigid part {k}"),
            "unique in the part, not u64::MAX",
        ));
    }
    if p.positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err(bad(
            "rigid part positions",
            format!("rigid part {k}"),
            "finite coordinates",
        ));
    }
    // a whole model of its nodes checks the body as one process does
    let mut m = if two_d {
        Model::new_2d()
    } else {
        Model::new_3d()
    };
    m.add_nodes(&p.positions, &vec![1.0; p.positions.len()])?;
    let nodes: Vec<u32> = (0..p.ids.len() as u32).collect();
    m.add_rigid_part(&nodes, p.mass, p.inertia).map_err(|e| {
        bad(
            "rigid part",
            format!("rigid part {k}: {e}"),
            "a body's mass and inertia",
        )
    })?;
    Ok(())
}

impl DistributedContact {
    /// Every rigid part's nodes at the coming increment's positions: `positions[k]` holds
    /// part k's nodes in [`RankRigidPart::ids`] order, the same on every rank (a rigid body's
    /// nodes follow its state, which every rank keeps alike). Call it before each
    /// [`DistributedContact::step`] of a model with rigid parts (not collective).
    ///
    /// Errors: a list per part of the part's length, finite.
    pub fn move_rigid_parts(&mut self, positions: &[Vec<[f64; 3]>]) -> Result<()> {
        let parts = &mut self.parts;
        if positions.len() != parts.len() {
            return Err(Error::LengthMismatch {
                what: "rigid parts' positions (one list per rigid part)",
                expected: parts.len(),
                got: positions.len(),
            });
        }
        for (k, (x, ids)) in positions.iter().zip(&parts.ids).enumerate() {
            if x.len() != ids.len() {
                return Err(Error::LengthMismatch {
                    what: "rigid part positions (one per node id)",
                    expected: ids.len(),
                    got: x.len(),
                });
            }
            if x.iter().flatten().any(|c| !c.is_finite()) {
                return Err(bad(
                    "rigid part positions",
                    format!("rigid part {k}"),
                    "finite coordinates",
                ));
            }
        }
        for (run, x) in parts.runs.iter_mut().zip(positions) {
            run.update(x);
        }
        parts.moved = true;
        Ok(())
    }
}
