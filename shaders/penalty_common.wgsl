// penalty_common.wgsl — shared by the penalty kernels (prepended after common.wgsl).
// Rust twins: src/abi/penalty.rs.

const NO_SLAVE: u32 = 0xffffffffu;
const CSTATUS_OPEN: u32 = 0u;
const CSTATUS_STICK: u32 = 1u;
const CSTATUS_SLIP: u32 = 2u;
const CSTATUS_MASK: u32 = 0xffu;      // status bits holding CSTATUS_*
const HEAVY_SHIFT: u32 = 8u;          // status bit of facet slot j's node heavy: 1 << (8 + j)
const HEAVY_SLAVE: u32 = 4096u;       // status bit of the slave node heavy (1 << 12)
const HEAVY_SHARE: f32 = 0.01;        // heavy: share |c|/√m below this fraction of the largest
const LAW_LINEAR: u32 = 0u;
const LAW_EXPONENTIAL: u32 = 1u;
const LAW_TABULAR: u32 = 2u;
const STIFFNESS_AUTO: u32 = 0u;
const STIFFNESS_MODULUS: u32 = 1u;
const STIFFNESS_ABSOLUTE: u32 = 2u;
const STIFFNESS_PER_AREA: u32 = 3u;
// f32::MAX, written as the double it is exactly (a literal above it is an error in Tint, WebGPU's
// compiler in Chromium, though naga rounds it down)
const NO_LIMIT: f32 = 3.4028234663852886e38;
const PENALTY_ANCHORED: u32 = 1u;
// no slave node is a master node: a slave with no facet is no one's partner (its force, row and
// normal are nothing), so the per-node passes leave it at one hit word
const PENALTY_SLAVES_APART: u32 = 2u;
// Bits of a pair node's need word (nodal_normals.wgsl, gather.wgsl): a spring reads its normal
// this increment; a spring scattered onto it (its sums are not zero)
const NEED_NORMAL: u32 = 1u;
const NEED_FORCE: u32 = 2u;

// Rust twin: PenaltyParams, 208 bytes.
struct PenaltyParams {
    n_slaves: u32,
    n_pair_nodes: u32,
    n_facets: u32,
    law: u32,
    stiffness_mode: u32,
    table_len: u32,
    flags: u32,
    ref_node: u32,                       // the pair's reference master node (fast-node test)
    stiffness: f32,
    modulus: f32,
    dt: f32,
    dt_ref: f32,
    damping: f32,
    mu: f32,
    mu_kinetic: f32,
    decay: f32,
    stick_stiffness: f32,
    clearance: f32,
    pressure: f32,
    weight: f32,
    table: array<vec4<f32>, 8>,
    master_body: vec4<f32>,              // rigid master: centre (xyz, kernel frame), 1/mass (w; 0: none)
    master_inv_inertia: array<vec4<f32>, 3>,  // its inverse inertia, model frame (rows)
    slave_body: vec4<f32>,               // rigid slave part, as master_body
    slave_inv_inertia: array<vec4<f32>, 3>,
    body_slots: vec4<u32>,               // pair-node slots of the master's, slave's part rows; count
    search_radius: f32,                  // the pair's search radius (fast-node test)
    slave_share: f32,                    // rigid slave part: slaves sharing its effective mass (1: none)
    _pad0: u32,
    _pad1: u32,
}

// The compliance (1/effective mass) of a rigid body (centre c, inverse mass w; inverse inertia
// rows j) at point p along unit direction n: 1/M + (r×n)·J·(r×n), r = p − c.
fn body_compliance(body: vec4<f32>, j: array<vec4<f32>, 3>, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let u = cross(p - body.xyz, n);
    let ju = vec3<f32>(dot(j[0].xyz, u), dot(j[1].xyz, u), dot(j[2].xyz, u));
    return body.w + dot(u, ju);
}

// Rust twin: SlaveState, 32 bytes.
struct SlaveState {
    tangential_area: vec4<f32>,   // carried friction force (xyz), tributary area (w)
    history: vec4<f32>,           // accumulated frictional dissipation (x), behind a free edge (y)
}

// Rust twin: ContactOut, 64 bytes; what scatter_forces and gather read is its first 32 bytes
// (one memory sector): force, status and the bound's shares.
struct ContactOut {
    force: vec4<f32>,
    status: u32,          // CSTATUS_* (low byte), heavy-node bits above
    dissipation: f32,
    bound_light: f32,     // ω² share of the spring at its light nodes
    bound_heavy: f32,     // and at its heavy ones
    tangential: vec4<f32>,
    normal_gap: vec4<f32>,
}
