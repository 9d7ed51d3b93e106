//! The uniform of `shaders/integrate.wgsl`, the device-side central-difference integrator.

use bytemuck::{Pod, Zeroable};

/// Uniform parameters of `integrate.wgsl` (WGSL twin: `IntegrateParams`, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct IntegrateParams {
    /// xyz: a body acceleration applied to every integrated node (gravity, length/s²); w: the
    /// increment dt (s).
    pub acceleration: [f32; 4],
    /// First node integrated.
    pub first: u32,
    /// Nodes integrated from `first`.
    pub count: u32,
    /// Model nodes (every node's force is zeroed).
    pub n_nodes: u32,
    /// Padding.
    pub _pad: u32,
}
const _: () = assert!(std::mem::size_of::<IntegrateParams>() == 32);
