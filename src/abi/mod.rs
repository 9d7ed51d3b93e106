//! The Rust twins of abut's WGSL and nothing else: the byte layouts the kernels read and write,
//! the status, plan and statistics words, the pass table (each kernel entry point's bindings and
//! workgroup), and the shader sources. Everything here is data shared with `shaders/*.wgsl`; the
//! stages (`search`, `penalty`, `contact`) and both executors (the GPU's and the CPU mirror)
//! build on it, and it depends on nothing else in the crate, so no executor has to borrow a
//! constant from the other. `tests/shaders.rs` checks the twins against naga's reflection of the
//! WGSL.

pub mod boxes;
pub mod buckets;
pub mod groups;
pub mod integrate;
pub mod passes;
pub mod penalty;
pub mod search;
pub mod shaders;
pub mod stats;
pub mod status;
pub mod traffic;
