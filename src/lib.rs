#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub(crate) mod abi;
#[cfg(feature = "capi")]
pub mod capi;
pub mod contact;
pub(crate) mod cpu;
pub mod device;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod error;
#[cfg(feature = "solver")]
pub mod explicit;
pub mod geometry;
pub(crate) mod gpu;
#[cfg(feature = "solver")]
pub mod io;
pub mod kinematic;
pub mod mesh;
pub mod model;
pub mod partition;
pub(crate) mod penalty;
pub(crate) mod plan;
pub mod query;
#[cfg(feature = "solver")]
pub mod scene;
pub mod search;
#[doc(hidden)]
pub mod testing;

pub use abi::penalty::SlaveState;
pub use abi::stats::IncrementStats;
pub use contact::{
    combined_increment, Anchoring, Contact, ContactStatus, FastNode, KinematicReport,
    OverclosureReport, PairOutput, ResidentIo, StepReport,
};
pub use device::{Backend, Device, Traffic};
pub use error::{Error, ErrorKind, Result};
pub use gpu::CentralDifference;
pub use kinematic::BodyState;
pub use model::{
    Analytical, BodyId, Enforce, Facet, Friction, Kinematic, Model, NodeRange, NodeSetId, Pair,
    PairId, Penalty, PressureOverclosure, RigidBody, RigidPair, RigidPairId, RigidPart,
    RigidPartId, Schedule, SearchStructure, SlaveOrder, Sliding, Stiffness, Surface, SurfaceId,
    DEFAULT_CONTACT_DAMPING,
};
pub use search::{ContactPoint, GlobalSearch, SearchResult, SearchStats};
