//! Structs shared with the penalty kernels (twins in `shaders/penalty_common.wgsl`).

use bytemuck::{Pod, Zeroable};

/// No slave index (WGSL: `NO_SLAVE`).
pub const NO_SLAVE: u32 = u32::MAX;
/// Contact status: open (WGSL: `CSTATUS_OPEN`).
pub const CSTATUS_OPEN: u32 = 0;
/// Contact status: closed and sticking (WGSL: `CSTATUS_STICK`).
pub const CSTATUS_STICK: u32 = 1;
/// Contact status: closed and slipping (frictionless contact is always slipping)
/// (WGSL: `CSTATUS_SLIP`).
pub const CSTATUS_SLIP: u32 = 2;
/// The bits of [`ContactOut::status`] that hold the `CSTATUS_*` value (WGSL: `CSTATUS_MASK`);
/// the bits above say which of the spring's nodes are heavy in the stable-increment bound.
pub const CSTATUS_MASK: u32 = 0xff;
/// [`ContactOut::status`] bit of facet slot j's node being heavy: `1 << (HEAVY_SHIFT + j)`
/// (WGSL: `HEAVY_SHIFT`).
pub const HEAVY_SHIFT: u32 = 8;
/// [`ContactOut::status`] bit of the slave node being heavy (WGSL: `HEAVY_SLAVE`).
pub const HEAVY_SLAVE: u32 = 1 << 12;
/// A node of a spring is heavy when its share of the spring's motion, |c|/√m (c: 1 for the
/// slave, the weight for a master node), is below this fraction of the largest share — a rigid
/// or immovable node (WGSL: `HEAVY_SHARE`).
pub const HEAVY_SHARE: f32 = 0.01;
/// Linear law (WGSL: `LAW_LINEAR`).
pub const LAW_LINEAR: u32 = 0;
/// Exponential law (WGSL: `LAW_EXPONENTIAL`).
pub const LAW_EXPONENTIAL: u32 = 1;
/// Tabular law (WGSL: `LAW_TABULAR`).
pub const LAW_TABULAR: u32 = 2;
/// The automatic stiffness at scale 1, `k = AUTO_STIFFNESS·m*/Δt_ref²`: each contact spring has
/// ω·Δt_ref = 1 (see [`crate::Stiffness::Auto`]); the kernels get `AUTO_STIFFNESS·scale`.
pub const AUTO_STIFFNESS: f64 = 1.0;
/// Automatic mass-and-increment stiffness (WGSL: `STIFFNESS_AUTO`).
pub const STIFFNESS_AUTO: u32 = 0;
/// Modulus-based stiffness (WGSL: `STIFFNESS_MODULUS`).
pub const STIFFNESS_MODULUS: u32 = 1;
/// Absolute stiffness (WGSL: `STIFFNESS_ABSOLUTE`).
pub const STIFFNESS_ABSOLUTE: u32 = 2;
/// Stiffness per unit tributary area (WGSL: `STIFFNESS_PER_AREA`).
pub const STIFFNESS_PER_AREA: u32 = 3;
/// Flag: small sliding, the contact normal and gap are the hit's (the anchor's tangent plane),
/// not the smoothed normal at the closest point (WGSL: `PENALTY_ANCHORED`).
pub const PENALTY_ANCHORED: u32 = 1;
/// Flag: no slave node is a node of the master surface, so a slave whose hit has no facet has
/// no force, no bound row and no normal: `nodal_normals`, `gather` and `add_forces` leave it
/// after reading one word of its hit (WGSL: `PENALTY_SLAVES_APART`).
pub const PENALTY_SLAVES_APART: u32 = 2;
/// Need bit of a pair node: a spring reads its normal this increment (`need_normals` sets it,
/// `nodal_normals_needed` reads it; WGSL: `NEED_NORMAL`).
pub const NEED_NORMAL: u32 = 1;
/// Need bit of a pair node or rigid slot: a spring scattered onto it this increment, its sums
/// are not zero (`scatter_forces` sets it, `gather` and `add_forces` read it, `add_forces`
/// clears the word; WGSL: `NEED_FORCE`).
pub const NEED_FORCE: u32 = 2;
/// "No limit" for increments (largest finite f32; WGSL: `NO_LIMIT`).
pub const NO_LIMIT: f32 = f32::MAX;

/// Uniform parameters of the penalty kernels. WGSL twin: `PenaltyParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PenaltyParams {
    /// Slave nodes.
    pub n_slaves: u32,
    /// Nodes of the pair (slave ∪ master), the gather's items.
    pub n_pair_nodes: u32,
    /// Active master facets.
    pub n_facets: u32,
    /// `LAW_*`.
    pub law: u32,
    /// `STIFFNESS_*`.
    pub stiffness_mode: u32,
    /// Points in `table`.
    pub table_len: u32,
    /// `PENALTY_*` flag bits.
    pub flags: u32,
    /// The pair's reference master node (model node id): a slave with no facet within the
    /// search radius is judged fast on its velocity relative to this node's.
    pub ref_node: u32,
    /// Auto: scale; modulus: scale; absolute: k (force per length).
    pub stiffness: f32,
    /// Young's modulus for the modulus rule.
    pub modulus: f32,
    /// This increment.
    pub dt: f32,
    /// Reference increment of the automatic stiffness.
    pub dt_ref: f32,
    /// Damping as a fraction of critical.
    pub damping: f32,
    /// Static friction coefficient (0: frictionless).
    pub mu: f32,
    /// Kinetic friction coefficient.
    pub mu_kinetic: f32,
    /// Friction decay coefficient.
    pub decay: f32,
    /// Tangential stiffness / normal stiffness.
    pub stick_stiffness: f32,
    /// Exponential law: clearance c0.
    pub clearance: f32,
    /// Exponential law: pressure p0 at zero clearance.
    pub pressure: f32,
    /// Weight of this pass (balanced pairs: w and 1 − w; pure master–slave: 1): the force,
    /// outputs and energy of each contact are scaled by it.
    pub weight: f32,
    /// Tabular law: (overclosure, pressure) points, two per vec4.
    pub table: [[f32; 4]; 8],
    /// The rigid part the master surface lies on: its centre of mass (xyz, the kernels' frame)
    /// and 1/mass (w; 0: the master is not rigid — its nodes' own masses count).
    pub master_body: [f32; 4],
    /// Its inverse rotational inertia in the model frame now (rows, xyz).
    pub master_inv_inertia: [[f32; 4]; 3],
    /// The rigid part the slave nodes lie on, as `master_body`.
    pub slave_body: [f32; 4],
    /// Its inverse rotational inertia, as `master_inv_inertia`.
    pub slave_inv_inertia: [[f32; 4]; 3],
    /// Rows of the node-wise bound of the rigid parts: the pair-node slot of the master's (x)
    /// and the slave's (y) rigid part (`NO_SLAVE`: none), and how many such slots follow the
    /// pair's nodes (z); w unused.
    pub body_slots: [u32; 4],
    /// The pair's search radius (model length units): a slave whose velocity relative to the
    /// master near it carries it farther within the increment is counted fast (`STATUS_FAST`).
    pub search_radius: f32,
    /// Slaves of a rigid part (`slave_body`): the number of slave nodes the part's effective
    /// mass is shared among by the automatic stiffness (each spring gets 1/n of it, so the
    /// body on its n springs has the frequency one slave of a meshed body has); 1 otherwise.
    pub slave_share: f32,
    /// Padding.
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<PenaltyParams>() == 368);

/// Per-slave state kept between increments. WGSL twin: `SlaveState`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SlaveState {
    /// Friction force carried over (xyz) and the node's tributary area (w).
    pub tangential_area: [f32; 4],
    /// Frictional dissipation accumulated since the start (x); 1 in y while the node is behind a
    /// free edge of the master (it was beside the edge below the facet's plane and has not risen
    /// above the surface since: no contact, so that it is not launched out); z, w unused.
    pub history: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<SlaveState>() == 32);

/// Per-slave result of the penalty kernel. WGSL twin: `ContactOut`. What the scatter and the
/// gather read (the force, the status and the bound's shares) is its first 32 bytes, one
/// 32-byte memory sector; the rest is read by the host's outputs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ContactOut {
    /// Total contact force on the slave node (xyz) and the normal force magnitude (w).
    pub force: [f32; 4],
    /// `CSTATUS_*` in the low byte ([`CSTATUS_MASK`]); above it, the heavy nodes of the
    /// spring ([`HEAVY_SHIFT`], [`HEAVY_SLAVE`]).
    pub status: u32,
    /// Frictional dissipation of this slave since the start.
    pub dissipation: f32,
    /// This spring's share of the node-wise bound on the contact's highest frequency, ω²
    /// (1/s²), at each of its light nodes (0 when there is no spring). See `contact.rs`.
    pub bound_light: f32,
    /// Its share at each of its heavy nodes (at most `bound_light`).
    pub bound_heavy: f32,
    /// Friction force (xyz) and the elastic energy stored in the contact springs (w).
    pub tangential: [f32; 4],
    /// Contact normal used (xyz, smoothed) and the signed gap along it, COPEN (w).
    pub normal_gap: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ContactOut>() == 64);

/// A node of a pair for the normals and the gather. WGSL twin: `vec4<u32>` in `pair_nodes`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct PairNode {
    /// Model node id.
    pub node: u32,
    /// Index in the slave set, or [`NO_SLAVE`].
    pub slave: u32,
    /// Start of its adjacent active facets in the adjacency list.
    pub adj_start: u32,
    /// End of its adjacent active facets.
    pub adj_end: u32,
}

/// Words of the fixed-point accumulator per pair node: fx, fy, fz and the bound row, each as a
/// (low, high) pair (WGSL: `acc`).
pub const ACC_WORDS_PER_NODE: usize = 8;
