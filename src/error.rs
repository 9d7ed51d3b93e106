//! The one error type of the library.

use thiserror::Error;

/// Everything that can go wrong in abut, each variant naming the item at fault.
#[derive(Debug, Error)]
pub enum Error {
    /// A coordinate of a node is NaN or infinite.
    #[error("node {node}: coordinate {axis} is not finite ({value})")]
    NonFiniteCoordinate {
        /// Index of the node (local to the model or to the array passed in).
        node: usize,
        /// Axis: 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// The offending value.
        value: f64,
    },
    /// A coordinate of a slave or master node, finite in f64, is beyond single precision's range
    /// relative to the search's frame (the kernels work in f32 there).
    #[error(
        "node {node}: coordinate {axis} = {value:e} is beyond single precision (f32) range relative to \
         the search frame at {frame:e}"
    )]
    CoordinateOutOfRange {
        /// Index of the node in the model.
        node: usize,
        /// Axis: 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// The coordinate, model units.
        value: f64,
        /// The frame's origin on that axis, model units.
        frame: f64,
    },
    /// A node mass is zero, negative, NaN or infinite.
    #[error("node {node}: mass {mass} is not a finite positive number")]
    BadMass {
        /// Index of the node.
        node: usize,
        /// The offending mass.
        mass: f64,
    },
    /// Two arrays that must have one entry per item have different lengths.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// What the arrays describe.
        what: &'static str,
        /// The length required.
        expected: usize,
        /// The length passed.
        got: usize,
    },
    /// A set, surface or array that must hold at least one item is empty.
    #[error("{what} is empty")]
    Empty {
        /// What was empty.
        what: String,
    },
    /// An index refers to an item that does not exist.
    #[error("{what}: index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// Where the index was found (e.g. "facet 12 of surface 0, node 3").
        what: String,
        /// The offending index.
        index: u64,
        /// How many items there are.
        len: usize,
    },
    /// A facet names the same node twice.
    #[error("facet {facet}: node {node} appears more than once")]
    RepeatedNode {
        /// Index of the facet within its surface.
        facet: usize,
        /// The repeated node.
        node: u32,
    },
    /// A node appears twice in a node set.
    #[error("node set: node {node} appears more than once")]
    DuplicateNode {
        /// The repeated node.
        node: u32,
    },
    /// Every facet of a surface is degenerate, so nothing is left to search.
    #[error("surface: all {count} facets are degenerate (zero area or zero length)")]
    AllFacetsDegenerate {
        /// How many facets the surface had.
        count: usize,
    },
    /// A facet kind that does not belong in the model's dimension (segments are 2D, triangles
    /// and quads 3D).
    #[error("facet {facet}: a {kind} does not belong in a {dim}D model")]
    WrongDimension {
        /// Index of the facet.
        facet: usize,
        /// What kind of facet it is.
        kind: &'static str,
        /// The model's dimension.
        dim: u32,
    },
    /// A 2D model was given a node with a non-zero z coordinate.
    #[error("node {node}: z = {z} in a 2D model (must be 0)")]
    NonPlanarNode {
        /// Index of the node.
        node: usize,
        /// The offending z.
        z: f64,
    },
    /// A parameter is outside the range it must lie in.
    #[error("{name} = {value}: {expected}")]
    BadParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What it must be.
        expected: &'static str,
    },
    /// No GPU adapter is available (and the CPU path was not allowed).
    #[error("no GPU adapter found{detail}")]
    NoAdapter {
        /// What was searched for (backends, name filter), starting with ": " when not empty.
        detail: String,
    },
    /// The adapter cannot provide a limit the search needs.
    #[error("adapter {adapter}: limit {limit} is {available}, abut needs {needed}")]
    AdapterLimit {
        /// The adapter's name.
        adapter: String,
        /// The wgpu limit's name.
        limit: &'static str,
        /// What the adapter offers.
        available: u64,
        /// What abut asks for.
        needed: u64,
    },
    /// A problem is larger than the device's limits allow, even after growing buffers.
    #[error("{what}: needs {needed} bytes, the device allows {allowed}")]
    TooLarge {
        /// What did not fit.
        what: String,
        /// Bytes needed.
        needed: u64,
        /// Bytes allowed.
        allowed: u64,
    },
    /// The device could not be created.
    #[error("requesting a device from {adapter} failed: {source}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// wgpu's error.
        source: wgpu::RequestDeviceError,
    },
    /// wgpu reported an error (validation, out of memory, internal) while abut ran a pass.
    #[error("GPU error during {during}: {message}")]
    Gpu {
        /// Which pass or operation.
        during: String,
        /// wgpu's message.
        message: String,
    },
    /// The device was lost or a readback failed.
    #[error("GPU device lost or readback failed during {during}: {message}")]
    DeviceLost {
        /// Which pass or operation.
        during: String,
        /// What was reported.
        message: String,
    },
    /// A file that does not parse: the file, the line (0 where the format has none or it is
    /// not known; then not printed) and what was expected.
    #[error("{file}{}: {message}", line_suffix(*.line))]
    Parse {
        /// The file.
        file: String,
        /// The line, from 1 (0: not line-oriented, e.g. binary data).
        line: usize,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A file that cannot be read or written.
    #[error("{file}: {message}")]
    Io {
        /// The file.
        file: String,
        /// The operating system's message.
        message: String,
    },
    /// A surface, node set or pair id that this model did not hand out.
    #[error("{what} {id} does not exist in this model")]
    UnknownId {
        /// "surface", "node set" or "pair".
        what: &'static str,
        /// The id.
        id: usize,
    },
    /// A quantity abut computed from finite input came out NaN or infinite: the error is
    /// abut's result, not the caller's input, and names where it arose.
    #[error("{what} of node {node} computed as {value} (not finite): {cause}")]
    NonFiniteResult {
        /// The quantity ("penalty contact force", "kinematic correction", …) and its pair.
        what: String,
        /// The model node it belongs to.
        node: usize,
        /// The value computed.
        value: f64,
        /// What the inputs there were, and what to look at.
        cause: String,
    },
    /// A slave node moved farther than its pair's search radius relative to the master near it
    /// within one increment: the search cannot follow it, and it may pass through its master
    /// unseen (tunnelling).
    #[error(
        "increment {increment} (t = {time:e}): slave node {node} of contact pair {pair} moves \
         {distance:e} relative to the master near it in one increment, farther than the \
         pair's search radius {radius:e}: contact would be missed (tunnelling); take a smaller \
         increment (run.dt, run.safety) or a larger search radius (the contact's \
         search_radius){more}"
    )]
    Tunnelling {
        /// The increment (1 = the first).
        increment: u64,
        /// The time at its start.
        time: f64,
        /// The fastest node.
        node: usize,
        /// Its pair.
        pair: usize,
        /// Its speed times the increment.
        distance: f64,
        /// The pair's search radius.
        radius: f64,
        /// How many others ("" when none).
        more: String,
    },
    /// The explicit solution blew up: a node's position or velocity, computed by the solver,
    /// left any meaningful range (not finite, or beyond single precision, where the contact
    /// search works) at an increment.
    #[error(
        "the solution diverged at increment {increment} (t = {time:e}): node {node}'s {what} \
         reached {value:e}{cause}"
    )]
    Diverged {
        /// The increment (1 = the first).
        increment: u64,
        /// The time at its end.
        time: f64,
        /// The node.
        node: usize,
        /// "position" or "velocity", and its axis.
        what: String,
        /// The value reached.
        value: f64,
        /// What the increment's contact did ("" when nothing is known), and what to look at.
        cause: String,
    },
}

/// What kind of fault an [`Error`](enum@Error) is: the class a binding reports it as (the C
/// ABI's status, the Python exception).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// An array's length does not match what it describes.
    Length,
    /// An id or index names nothing.
    OutOfRange,
    /// A value is not allowed (NaN, infinite, out of its range; an empty or repeated set).
    BadValue,
    /// A surface's facets cannot be used.
    Geometry,
    /// No adapter, or the GPU failed.
    Device,
    /// The contact or the solution failed during an increment.
    Contact,
    /// A file could not be read or parsed.
    Io,
}

impl Error {
    /// The kind of fault this is.
    pub fn kind(&self) -> ErrorKind {
        use ErrorKind as K;
        match self {
            Error::LengthMismatch { .. } => K::Length,
            Error::IndexOutOfRange { .. } | Error::UnknownId { .. } => K::OutOfRange,
            Error::NonFiniteCoordinate { .. }
            | Error::CoordinateOutOfRange { .. }
            | Error::BadMass { .. }
            | Error::BadParameter { .. }
            | Error::Empty { .. }
            | Error::DuplicateNode { .. } => K::BadValue,
            Error::RepeatedNode { .. }
            | Error::AllFacetsDegenerate { .. }
            | Error::WrongDimension { .. }
            | Error::NonPlanarNode { .. } => K::Geometry,
            Error::NoAdapter { .. }
            | Error::AdapterLimit { .. }
            | Error::TooLarge { .. }
            | Error::RequestDevice { .. }
            | Error::Gpu { .. }
            | Error::DeviceLost { .. } => K::Device,
            Error::NonFiniteResult { .. } | Error::Tunnelling { .. } | Error::Diverged { .. } => {
                K::Contact
            }
            Error::Parse { .. } | Error::Io { .. } => K::Io,
        }
    }
}

/// Result with the library's [`Error`](enum@Error).
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// ":line" for a known line, nothing for 0.
fn line_suffix(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}
