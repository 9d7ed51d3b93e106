//! What a user describes: nodes, master surfaces, slave node sets and contact pairs.
//!
//! Ids handed out here are local to the model (plan for a model that is one subdomain of a
//! larger one: nothing assumes the model is the world).

mod pair;
mod rigid;
mod surface;

pub use pair::{
    Enforce, Friction, Kinematic, Pair, Penalty, PressureOverclosure, Schedule, SearchStructure,
    SlaveOrder, Sliding, Stiffness, DEFAULT_CONTACT_DAMPING, MAX_TABLE_POINTS,
};
pub use rigid::{Analytical, BodyId, RigidBody, RigidPair, RigidPairId, RigidPart, RigidPartId};
pub use surface::{facet_node_count, DegenerateFacet, Facet, MasterSurface, Surface, NO_NODE};

use crate::error::{Error, Result};

/// Id of a master surface within its [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SurfaceId(pub usize);

/// Id of a slave node set within its [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NodeSetId(pub usize);

/// Id of a contact pair within its [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PairId(pub usize);

/// A contiguous range of node indices returned by [`Model::add_nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeRange {
    /// First node index.
    pub start: u32,
    /// One past the last node index.
    pub end: u32,
}

impl NodeRange {
    /// The node indices as a vector.
    pub fn to_vec(&self) -> Vec<u32> {
        (self.start..self.end).collect()
    }
    /// Number of nodes.
    pub fn len(&self) -> usize {
        (self.end - self.start) as usize
    }
    /// True when the range holds no node.
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// The contact model: nodes (positions in model units, masses), master surfaces, slave node sets
/// and contact pairs. Every `add_*` validates its input and names the offending item.
#[derive(Clone, Debug)]
pub struct Model {
    dim: u32,
    positions: Vec<[f64; 3]>,
    masses: Vec<f64>,
    surfaces: Vec<MasterSurface>,
    node_sets: Vec<Vec<u32>>,
    node_set_areas: Vec<Option<Vec<f64>>>,
    pairs: Vec<Pair>,
    bodies: Vec<RigidBody>,
    rigid_pairs: Vec<RigidPair>,
    rigid_parts: Vec<RigidPart>,
}

impl Model {
    /// An empty three-dimensional model (triangle and quad facets).
    pub fn new_3d() -> Self {
        Self::new(3)
    }

    /// An empty two-dimensional model (segment facets; every z is 0).
    pub fn new_2d() -> Self {
        Self::new(2)
    }

    fn new(dim: u32) -> Self {
        Self {
            dim,
            positions: Vec::new(),
            masses: Vec::new(),
            surfaces: Vec::new(),
            node_sets: Vec::new(),
            node_set_areas: Vec::new(),
            pairs: Vec::new(),
            bodies: Vec::new(),
            rigid_pairs: Vec::new(),
            rigid_parts: Vec::new(),
        }
    }

    /// Spatial dimension: 2 or 3.
    pub fn dim(&self) -> u32 {
        self.dim
    }

    /// Appends nodes with positions (model units) and lumped masses (model mass units).
    ///
    /// Errors: mismatched lengths, an empty list, a non-finite coordinate, a mass that is not
    /// finite and positive, a non-zero z in a 2D model. Nothing is added on error.
    pub fn add_nodes(&mut self, positions: &[[f64; 3]], masses: &[f64]) -> Result<NodeRange> {
        if positions.is_empty() {
            return Err(Error::Empty {
                what: "node list".into(),
            });
        }
        if masses.len() != positions.len() {
            return Err(Error::LengthMismatch {
                what: "masses (one per node)",
                expected: positions.len(),
                got: masses.len(),
            });
        }
        let base = self.positions.len();
        validate_positions(positions, base, self.dim)?;
        for (i, &m) in masses.iter().enumerate() {
            if !(m.is_finite() && m > 0.0) {
                return Err(Error::BadMass {
                    node: base + i,
                    mass: m,
                });
            }
        }
        if base + positions.len() > (u32::MAX - 1) as usize {
            return Err(Error::BadParameter {
                name: "node count",
                value: (base + positions.len()).to_string(),
                expected: "below 2^32 - 1",
            });
        }
        self.positions.extend_from_slice(positions);
        self.masses.extend_from_slice(masses);
        Ok(NodeRange {
            start: base as u32,
            end: self.positions.len() as u32,
        })
    }

    /// Appends 2D nodes (x, y); z is set to 0.
    pub fn add_nodes_2d(&mut self, positions: &[[f64; 2]], masses: &[f64]) -> Result<NodeRange> {
        let p: Vec<[f64; 3]> = positions.iter().map(|p| [p[0], p[1], 0.0]).collect();
        self.add_nodes(&p, masses)
    }

    /// Validates and adds a master surface. Degenerate facets (zero area or length) are
    /// excluded from the search and listed in [`MasterSurface::degenerate`].
    pub fn add_surface(&mut self, surface: Surface) -> Result<SurfaceId> {
        let built = MasterSurface::build(&surface, &self.positions, self.dim)?;
        self.surfaces.push(built);
        Ok(SurfaceId(self.surfaces.len() - 1))
    }

    /// Validates and adds a slave node set. Errors: empty, out-of-range or repeated nodes.
    pub fn add_node_set(&mut self, nodes: &[u32]) -> Result<NodeSetId> {
        if nodes.is_empty() {
            return Err(Error::Empty {
                what: "node set".into(),
            });
        }
        let mut seen = vec![false; self.positions.len()];
        for (k, &n) in nodes.iter().enumerate() {
            let Some(s) = seen.get_mut(n as usize) else {
                return Err(Error::IndexOutOfRange {
                    what: format!("node set entry {k}"),
                    index: n as u64,
                    len: self.positions.len(),
                });
            };
            if *s {
                return Err(Error::DuplicateNode { node: n });
            }
            *s = true;
        }
        self.node_sets.push(nodes.to_vec());
        self.node_set_areas.push(None);
        Ok(NodeSetId(self.node_sets.len() - 1))
    }

    /// Adds a slave node set with the tributary area of each node (model area units; length
    /// in 2D, per unit thickness), used for contact pressures and the modulus stiffness rule.
    /// Without areas a node's area is the mean master facet area (length in 2D).
    pub fn add_node_set_with_areas(&mut self, nodes: &[u32], areas: &[f64]) -> Result<NodeSetId> {
        if areas.len() != nodes.len() {
            return Err(Error::LengthMismatch {
                what: "tributary areas (one per node of the set)",
                expected: nodes.len(),
                got: areas.len(),
            });
        }
        if let Some(k) = areas.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(Error::BadParameter {
                name: "tributary area",
                value: format!("{} (node set entry {k})", areas[k]),
                expected: "must be finite and positive",
            });
        }
        let id = self.add_node_set(nodes)?;
        self.node_set_areas[id.0] = Some(areas.to_vec());
        Ok(id)
    }

    /// Tributary areas of a node set, if given.
    pub fn node_set_areas(&self, id: NodeSetId) -> Result<Option<&[f64]>> {
        self.node_set(id)?;
        Ok(self.node_set_areas[id.0].as_deref())
    }

    /// Adds a contact pair after checking that its slave set and master surface exist and its
    /// parameters are in range.
    pub fn add_pair(&mut self, pair: Pair) -> Result<PairId> {
        self.node_set(pair.slave)?;
        self.surface(pair.master)?;
        if let Some((s, _)) = pair.balanced {
            self.surface(s)?;
        }
        pair.validate()?;
        if let Enforce::Penalty(p) = &pair.enforce {
            if matches!(p.stiffness, Stiffness::PerArea(_))
                && self.node_set_areas(pair.slave)?.is_none()
            {
                return Err(Error::BadParameter {
                    name: "penalty stiffness",
                    value: format!("PerArea on node set {}", pair.slave.0),
                    expected: "a slave node set with areas (Model::add_node_set_with_areas)",
                });
            }
        }
        self.pairs.push(pair);
        Ok(PairId(self.pairs.len() - 1))
    }

    /// Adds a rigid body carrying an analytical surface (validated: finite positive mass,
    /// symmetric positive-definite inertia, surface parameters).
    pub fn add_rigid_body(&mut self, body: RigidBody) -> Result<BodyId> {
        body.validate(self.dim)?;
        self.bodies.push(body);
        Ok(BodyId(self.bodies.len() - 1))
    }

    /// Adds a kinematic contact pair of slave nodes against a rigid body's analytical surface.
    pub fn add_rigid_pair(&mut self, pair: RigidPair) -> Result<RigidPairId> {
        self.node_set(pair.slave)?;
        self.body(pair.body)?;
        if let Some(law) = &pair.softened {
            law.validate()?;
        }
        self.rigid_pairs.push(pair);
        Ok(RigidPairId(self.rigid_pairs.len() - 1))
    }

    /// Declares `nodes` one rigid part of `mass` and `inertia` (about the nodes' centroid, model
    /// frame at the model's positions): see [`RigidPart`]. Errors: an empty list, a node out of
    /// range, repeated or already in a rigid part, a mass or inertia a body cannot have.
    pub fn add_rigid_part(
        &mut self,
        nodes: &[u32],
        mass: f64,
        inertia: [[f64; 3]; 3],
    ) -> Result<RigidPartId> {
        if nodes.is_empty() {
            return Err(Error::Empty {
                what: "rigid part".into(),
            });
        }
        rigid::validate_mass_inertia(mass, inertia)?;
        let mut taken = vec![false; self.positions.len()];
        for p in &self.rigid_parts {
            for &n in &p.nodes {
                taken[n as usize] = true;
            }
        }
        for (k, &n) in nodes.iter().enumerate() {
            let Some(t) = taken.get_mut(n as usize) else {
                return Err(Error::IndexOutOfRange {
                    what: format!("rigid part node {k}"),
                    index: n as u64,
                    len: self.positions.len(),
                });
            };
            if *t {
                return Err(Error::DuplicateNode { node: n });
            }
            *t = true;
        }
        self.rigid_parts.push(RigidPart {
            nodes: nodes.to_vec(),
            mass,
            inertia,
        });
        Ok(RigidPartId(self.rigid_parts.len() - 1))
    }

    /// All rigid parts, in the order added.
    pub fn rigid_parts(&self) -> &[RigidPart] {
        &self.rigid_parts
    }

    /// The rigid part holding each of `nodes` when they all lie on one; `None` when none does.
    /// Errors: some but not all do, or they lie on two parts — `what` names the node list.
    pub(crate) fn rigid_part_of(&self, nodes: &[u32], what: &str) -> Result<Option<usize>> {
        if self.rigid_parts.is_empty() || nodes.is_empty() {
            return Ok(None);
        }
        let mut part_of = std::collections::HashMap::new();
        for (k, p) in self.rigid_parts.iter().enumerate() {
            for &n in &p.nodes {
                part_of.insert(n, k);
            }
        }
        let first = part_of.get(&nodes[0]).copied();
        if let Some(&n) = nodes.iter().find(|n| part_of.get(n).copied() != first) {
            return Err(Error::BadParameter {
                name: "rigid part",
                value: format!("{what}: node {} and node {n}", nodes[0]),
                expected: "a surface or slave set wholly on one rigid part, or on none",
            });
        }
        Ok(first)
    }

    /// The rigid body `id`.
    pub fn body(&self, id: BodyId) -> Result<&RigidBody> {
        self.bodies.get(id.0).ok_or(Error::UnknownId {
            what: "rigid body",
            id: id.0,
        })
    }

    /// All rigid bodies, in the order added.
    pub fn bodies(&self) -> &[RigidBody] {
        &self.bodies
    }

    /// All rigid pairs, in the order added.
    pub fn rigid_pairs(&self) -> &[RigidPair] {
        &self.rigid_pairs
    }

    /// Node positions, model units.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Lumped nodal masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The master surface `id`.
    pub fn surface(&self, id: SurfaceId) -> Result<&MasterSurface> {
        self.surfaces.get(id.0).ok_or(Error::UnknownId {
            what: "surface",
            id: id.0,
        })
    }

    /// The slave node set `id`.
    pub fn node_set(&self, id: NodeSetId) -> Result<&[u32]> {
        self.node_sets
            .get(id.0)
            .map(|v| v.as_slice())
            .ok_or(Error::UnknownId {
                what: "node set",
                id: id.0,
            })
    }

    /// The contact pair `id`.
    pub fn pair(&self, id: PairId) -> Result<&Pair> {
        self.pairs.get(id.0).ok_or(Error::UnknownId {
            what: "pair",
            id: id.0,
        })
    }

    /// All contact pairs, in the order added.
    pub fn pairs(&self) -> &[Pair] {
        &self.pairs
    }
}

/// Checks a position array: finite coordinates, z = 0 in 2D. `base` offsets the reported index.
pub(crate) fn validate_positions(positions: &[[f64; 3]], base: usize, dim: u32) -> Result<()> {
    for (i, p) in positions.iter().enumerate() {
        for (axis, &v) in p.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::NonFiniteCoordinate {
                    node: base + i,
                    axis,
                    value: v,
                });
            }
        }
        if dim == 2 && p[2] != 0.0 {
            return Err(Error::NonPlanarNode {
                node: base + i,
                z: p[2],
            });
        }
    }
    Ok(())
}
