#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod cpu;
pub mod device;
pub mod error;
pub mod geometry;
pub mod gpu;
pub mod mesh;
pub mod model;
pub mod search;

pub use device::Device;
pub use error::{Error, Result};
pub use model::{Facet, Model, NodeRange, NodeSetId, Pair, PairId, Surface, SurfaceId};
pub use search::{ContactPoint, GlobalSearch, SearchResult, SearchStats};
