//! The GPU executor: shader composition, a workspace of buffers that only grows, pipelines,
//! and the global search's dispatch sequence (one encoder, one submit, one readback).

pub(crate) mod buffers;
mod global_search;
mod penalty;
pub mod shaders;

pub use global_search::{AfterSearch, GpuSearch, SharedBuffers};
pub use penalty::GpuPenalty;
