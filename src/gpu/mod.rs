//! The GPU executor: shader composition, a workspace of buffers that only grows, pipelines,
//! and the global search's dispatch sequence (one encoder, one submit, one readback).

mod buffers;
mod global_search;
pub mod shaders;

pub use global_search::GpuSearch;
