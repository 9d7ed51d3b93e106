//! CPU mirror of `shaders/integrate.wgsl`: central differences for point masses.

use crate::abi::integrate::IntegrateParams;

/// One "invocation" per node: v ← v + dt·(f/m + a), x ← x + dt·v for the nodes of the range
/// with a positive mass; every force zeroed (xyz).
pub fn integrate(
    ip: &IntegrateParams,
    positions: &mut [[f32; 4]],
    velocities: &mut [[f32; 4]],
    forces: &mut [[f32; 4]],
    masses: &[f32],
) {
    let dt = ip.acceleration[3];
    for i in 0..ip.n_nodes as usize {
        let f = [forces[i][0], forces[i][1], forces[i][2]];
        forces[i][..3].fill(0.0);
        let m = masses[i];
        let first = ip.first as usize;
        if i < first || i - first >= ip.count as usize || !(m > 0.0) {
            continue;
        }
        for c in 0..3 {
            velocities[i][c] += dt * (f[c] / m + ip.acceleration[c]);
            positions[i][c] += dt * velocities[i][c];
        }
    }
}
