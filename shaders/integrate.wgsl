// integrate.wgsl — central differences for point masses, on the device: the integrator of a host
// program that keeps its whole state there (abut bounce --resident, tests/resident.rs), run after
// a device-resident contact increment in the same submit. CPU mirror: src/cpu/integrate.rs.
//
// Bindings: 0 ip (uniform IntegrateParams: increment, acceleration, node range), 1 positions
//           (vec4<f32> per model node, xyz updated, w kept), 2 velocities (vec4<f32>: the half
//           step before on entry, the half step after on exit), 3 forces (vec4<f32>: xyz read,
//           then zeroed for the next increment's sums), 4 masses (f32 per model node).
// Dispatch: one invocation per node of the range, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: v ← v + dt·(f/m + a), x ← x + dt·v for the nodes first..first+count with a positive
//             mass; every node's force is zeroed (nodes outside the range or without mass are
//             held where they are). Each invocation touches only its own node.

// Rust twin: IntegrateParams (src/gpu/integrate.rs), 32 bytes.
struct IntegrateParams {
    acceleration: vec4<f32>, // xyz: a body acceleration (gravity), w: the increment dt
    first: u32,
    count: u32,
    n_nodes: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> ip: IntegrateParams;
@group(0) @binding(1) var<storage, read_write> positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> velocities: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> forces: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> masses: array<f32>;

@compute @workgroup_size(64)
fn integrate(@builtin(workgroup_id) wg: vec3<u32>,
             @builtin(num_workgroups) nwg: vec3<u32>,
             @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= ip.n_nodes) { return; }
    let f = forces[i].xyz;
    forces[i] = vec4<f32>(0.0, 0.0, 0.0, forces[i].w);
    let m = masses[i];
    if (i < ip.first || i - ip.first >= ip.count || !(m > 0.0)) { return; }
    let dt = ip.acceleration.w;
    let v = velocities[i].xyz + dt * (f / m + ip.acceleration.xyz);
    velocities[i] = vec4<f32>(v, velocities[i].w);
    positions[i] = vec4<f32>(positions[i].xyz + dt * v, positions[i].w);
}
