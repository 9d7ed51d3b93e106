//! abut's internals for its own twin tests, benchmarks and command line: the WGSL twins, both
//! executors' kernels, the prepared inputs and the brute-force oracle. Hidden from the
//! documentation and not part of the API: nothing here is promised to stay.

/// The Rust twins of the WGSL (`crate::abi`).
pub mod abi {
    pub use crate::abi::*;
}

/// The CPU mirror of each kernel (`crate::cpu`).
pub mod cpu {
    pub use crate::cpu::*;
}

/// The GPU executors (`crate::gpu`).
pub mod gpu {
    pub use crate::gpu::*;
}

/// What a stage hands an executor (`crate::plan`).
pub mod plan {
    pub use crate::plan::*;
}

/// Per-pair penalty setup and parameters (`crate::penalty`).
pub mod penalty {
    pub use crate::penalty::*;
}

/// The f64 brute-force oracle of the global search.
pub mod brute_force {
    pub use crate::search::brute_force::*;
}

/// The search tree's leaf slots.
pub mod tree {
    pub use crate::search::tree::*;
}

/// Scenes the tests share, native and in a browser.
pub mod scenes;

/// The web page's scene, run on the CPU path or device-resident on a GPU.
pub mod incline;

/// Each pass's hits of the last penalty increment (the pass's slave order): on the CPU path at
/// once, on a GPU read back and waited for (native only).
pub fn resident_hits(contact: &crate::Contact) -> crate::Result<Vec<Vec<abi::search::GpuHit>>> {
    contact.pass_hits()
}

/// Each pass's device buffer of hits and the bytes its slaves' take; empty on the CPU path.
pub fn resident_hits_buffers(contact: &crate::Contact) -> Vec<(&wgpu::Buffer, u64)> {
    contact.pass_hits_buffers()
}
