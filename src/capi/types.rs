//! The C ABI's plain types: statuses, the enumerations a host passes as `int32_t`, and the
//! structs it fills or reads. Every struct is `#[repr(C)]` and holds only numbers, fixed arrays
//! and pointers; enumerations cross the boundary as `int32_t` and are checked on the way in.

/// What a call did. Every `abut_*` call but `abut_version` returns one.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutStatus {
    /// Done.
    Ok = 0,
    /// A pointer that must not be null was null (the message names the argument).
    NullPointer = 1,
    /// A handle is not live (freed, or never made by abut) or is of another kind.
    BadHandle = 2,
    /// An array's length does not match what it describes (one entry per node, per slave…).
    Length = 3,
    /// An id or index names nothing (a node, node set, surface, pair, body, pass).
    OutOfRange = 4,
    /// A value is not allowed: NaN or infinite, non-positive mass or increment, an unknown
    /// enumeration value, a misaligned array, a parameter out of its range.
    BadValue = 5,
    /// A surface's facets cannot be used (repeated or degenerate, wrong dimension).
    Geometry = 6,
    /// No adapter, or the GPU failed (lost, out of memory, a limit exceeded).
    Device = 7,
    /// The contact failed during an increment (non-finite result, tunnelling, divergence).
    Contact = 8,
    /// A file could not be read or parsed.
    Io = 9,
    /// An internal error (a panic) was caught at the boundary; the handle refuses further
    /// calls and should be freed.
    Panic = 10,
}

/// Which device `abut_device_new` makes.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutDeviceKind {
    /// The best GPU adapter, else the CPU path (the environment's `ABUT_BACKEND=cpu|gpu`
    /// applies).
    Auto = 0,
    /// The CPU path (the kernels' mirrors, on all cores).
    Cpu = 1,
    /// A GPU adapter of the given backend whose name contains the given text.
    Gpu = 2,
}

/// A graphics API to take a GPU adapter from.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutBackend {
    /// Any, the best adapter first.
    Any = 0,
    /// Vulkan (Mesa's lavapipe is a software Vulkan adapter).
    Vulkan = 1,
    /// OpenGL / OpenGL ES (Mesa's llvmpipe).
    Gl = 2,
    /// Metal.
    Metal = 3,
    /// Direct3D 12.
    Dx12 = 4,
}

/// The facets of a surface: the number is the nodes per facet.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutFacetKind {
    /// Two-node segments (2D models).
    Segments = 2,
    /// Three-node triangles.
    Triangles = 3,
    /// Four-node quadrilaterals; a fourth node of `ABUT_NO_NODE` (0xFFFFFFFF) makes that facet
    /// a triangle, so one array can mix both.
    Quads = 4,
}

/// How a pair's contact is enforced.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutEnforcement {
    /// Penalty springs (`abut_contact_penalty_step`).
    Penalty = 0,
    /// The kinematic predictor/corrector (`abut_contact_kinematic_step`).
    Kinematic = 1,
}

/// The penalty stiffness rule (`stiffness_value`, `stiffness_scale` of `AbutPairOptions`).
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutStiffness {
    /// `k = scale·m_eff/Δt_ref²`, m_eff the two-body mass (the default, scale 1).
    Auto = 0,
    /// `k = scale·E·A_s/h_m` with E = `stiffness_value` (stress units).
    Modulus = 1,
    /// A fixed stiffness `stiffness_value` (force per length) for every slave node.
    Absolute = 2,
    /// `stiffness_value` per unit tributary area (needs a node set with areas).
    PerArea = 3,
}

/// A pressure–overclosure law.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutLawKind {
    /// Penalty: force `k·h` (k by the stiffness rule). Kinematic: hard contact.
    Default = 0,
    /// Abaqus' exponential law from `clearance` (length) with `pressure` at zero clearance.
    Exponential = 1,
    /// Piecewise linear through `table_points` (overclosure, pressure) pairs at `table`.
    Tabular = 2,
    /// Pressure = `slope`·overclosure.
    Slope = 3,
}

/// The sliding formulation.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutSliding {
    /// Any relative motion, searched every increment.
    Finite = 0,
    /// Anchored at the first increment, the tangent plane turning with the facet.
    Small = 1,
    /// Anchored, the plane's orientation fixed too.
    Infinitesimal = 2,
}

/// An analytical rigid surface.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutSurfaceKind {
    /// Plane through `point` with outward `direction` (3D).
    Plane = 0,
    /// Sphere about `point` of `radius` (3D).
    Sphere = 1,
    /// Cylinder about the axis through `point` along `direction`, of `radius` (3D).
    Cylinder = 2,
    /// Line through `point` (x, y) with outward `direction` (x, y) (2D).
    Line = 3,
    /// Circle about `point` (x, y) of `radius` (2D).
    Circle = 4,
}

/// What `abut_contact_penalty_step` does with the caller's force array.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutForceMode {
    /// Overwrite it with the contact forces.
    Write = 0,
    /// Add the contact forces to what it holds (the host's internal and external forces).
    Add = 1,
}

/// CSTATUS of a slave node.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutCstatus {
    /// Not computed for this slave this increment.
    Unknown = -1,
    /// Not in contact.
    Open = 0,
    /// In contact, sticking.
    Stick = 1,
    /// In contact, slipping.
    Slip = 2,
}

/// Which pairs an output call reads.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbutPairKind {
    /// A pair of `abut_model_add_pair` (penalty or kinematic).
    Meshed = 0,
    /// A pair of `abut_model_add_rigid_pair`.
    Rigid = 1,
}

/// A pressure–overclosure law. `table` is read during the call that takes the law only.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbutLaw {
    /// An `AbutLawKind`.
    pub kind: i32,
    /// Exponential: the clearance at which contact starts (> 0, length).
    pub clearance: f64,
    /// Exponential: the pressure at zero clearance (> 0, stress).
    pub pressure: f64,
    /// Slope: pressure per overclosure (stress per length).
    pub slope: f64,
    /// Tabular: `table_points` (overclosure, pressure) pairs, interleaved; may be null
    /// otherwise.
    pub table: *const f64,
    /// Tabular: the number of pairs at `table` (2 to 16).
    pub table_points: usize,
}

/// Everything a contact pair can be told; `abut_pair_options_default` fills the defaults (penalty
/// with the automatic stiffness, linear law, 3 % damping, frictionless, finite sliding, the
/// default radius and schedule, pure master–slave).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbutPairOptions {
    /// An `AbutEnforcement`.
    pub enforcement: i32,
    /// Penalty: an `AbutStiffness`.
    pub stiffness: i32,
    /// Penalty: the modulus (Modulus), stiffness (Absolute) or stiffness per area (PerArea).
    pub stiffness_value: f64,
    /// Penalty: the factor of the Auto and Modulus rules (1 and 0.1 are the usual ones).
    pub stiffness_scale: f64,
    /// Penalty: the pressure–overclosure law; kinematic: hard (Default) or softened.
    pub law: AbutLaw,
    /// Penalty: viscous damping, a fraction of critical (0.03 by default).
    pub damping: f64,
    /// 0: frictionless; 1: Coulomb friction with the four values below.
    pub friction: i32,
    /// Static friction coefficient.
    pub mu: f64,
    /// Kinetic friction coefficient; NaN (the default) takes `mu`.
    pub mu_kinetic: f64,
    /// Decay of the coefficient with slip rate (time per length; 0 = none).
    pub decay: f64,
    /// Penalty: tangential stiffness as a fraction of the normal (1 by default).
    pub stick_stiffness: f64,
    /// An `AbutSliding`.
    pub sliding: i32,
    /// Search radius (length); 0 takes one mean facet size of the master.
    pub search_radius: f64,
    /// 0: the default schedule (a global search every 100 increments, every 4 for
    /// self-contact, budget ½); 1: the three values below.
    pub has_schedule: i32,
    /// A global search every this many increments (≥ 1).
    pub schedule_interval: u32,
    /// The motion budget, a fraction of the radius (0 < budget ≤ 1).
    pub schedule_budget: f64,
    /// Non-zero: the wider local search (Abaqus' FAST LOCAL TRACKING=NO).
    pub schedule_wide_local: i32,
    /// Non-zero: a balanced pair, the slave nodes' own surface `balanced_surface` searched by
    /// the master's nodes, the slave-on-master pass weighted `balanced_weight`.
    pub balanced: i32,
    /// Balanced: the surface of the slave nodes.
    pub balanced_surface: u32,
    /// Balanced: the weight of the slave-on-master pass (0.5 for a symmetric pair).
    pub balanced_weight: f64,
    /// Penalty, pure pairs: the fraction of each contact's force this pair applies (1).
    pub pass_weight: f64,
}

/// An analytical rigid surface (see `AbutSurfaceKind` for which fields each kind reads).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbutAnalytical {
    /// An `AbutSurfaceKind`.
    pub kind: i32,
    /// A point of a plane or line, the centre of a sphere or circle, a point of a cylinder's
    /// axis (2D kinds read x, y).
    pub point: [f64; 3],
    /// The outward normal of a plane or line, the axis of a cylinder (need not be unit).
    pub direction: [f64; 3],
    /// The radius of a sphere, cylinder or circle.
    pub radius: f64,
}

/// The state of a rigid body: predicted on entry to `abut_contact_kinematic_step`, corrected on
/// exit.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbutBodyState {
    /// Position of the reference point.
    pub position: [f64; 3],
    /// Rotation from the body frame to the model frame, row by row.
    pub rotation: [f64; 9],
    /// Velocity of the reference point.
    pub velocity: [f64; 3],
    /// Angular velocity (model frame).
    pub angular_velocity: [f64; 3],
}

/// What the last penalty increment gave (`abut_contact_report`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct AbutReport {
    /// The largest increment the penalty springs allow under central differences (∞ if none).
    pub stable_dt: f64,
    /// Half the smallest gap over its closing speed (∞ when nothing approaches).
    pub approach_dt: f64,
    /// The largest overclosure of a slave carrying penalty force (length, ≥ 0).
    pub max_overclosure: f64,
    /// Slave nodes in contact.
    pub active: u64,
    /// Of which slipping.
    pub slipping: u64,
    /// Searches that ran globally this increment.
    pub global_searches: u64,
    /// Slaves whose tree walk was finished in bounded chunks.
    pub fallbacks: u64,
    /// Small/infinitesimal sliding slaves left without an anchor.
    pub unanchored: u64,
    /// Slaves moving farther than their pair's search radius relative to the master within
    /// the increment (contact may be missed: lower the increment or widen the radius).
    pub fast_nodes: u64,
    /// The fastest slave node relative to its master, −1 when there is none.
    pub fastest_node: i64,
    /// Its pair.
    pub fastest_pair: u32,
    /// Its relative speed times the increment (length).
    pub fastest_distance: f64,
    /// Its pair's search radius.
    pub fastest_radius: f64,
    /// Non-zero: `stable_dt` is finite though no slave touches yet.
    pub stable_dt_before_contact: i32,
}

/// What the last kinematic increment did (`abut_contact_kinematic_report`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct AbutKinematicReport {
    /// Slave nodes corrected.
    pub active: u64,
    /// Largest overclosure before the correction.
    pub max_overclosure: f64,
    /// Largest overclosure left after it.
    pub max_overclosure_after: f64,
    /// Change of kinetic energy the corrections made.
    pub kinetic_energy_change: f64,
    /// Sum of the resisting force magnitudes.
    pub total_force: f64,
    /// Sum of the friction force magnitudes.
    pub friction_force: f64,
    /// Slaves moving farther than their pair's search radius relative to the master.
    pub fast_nodes: u64,
    /// The fastest slave node, −1 when there is none.
    pub fastest_node: i64,
    /// Its relative speed times the increment (length).
    pub fastest_distance: f64,
    /// Its pair's search radius.
    pub fastest_radius: f64,
}

/// Caller-owned arrays that `abut_contact_output` fills, one entry per slave of the pass (`len`
/// must be `abut_contact_output_len`'s count). Any pointer may be null: that variable is skipped.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AbutOutputArrays {
    /// Entries in each array (slaves of the pass).
    pub len: usize,
    /// The slave nodes (model node ids), `len`.
    pub slaves: *mut u32,
    /// CSTATUS (`AbutCstatus`), `len`.
    pub cstatus: *mut i32,
    /// COPEN: gap along the contact normal (length; negative = penetration), `len`.
    pub copen: *mut f64,
    /// CPRESS: normal force over the tributary area, `len`.
    pub cpress: *mut f64,
    /// CSHEAR1: friction force along t1 over the tributary area, `len`.
    pub cshear1: *mut f64,
    /// CSHEAR2: friction force along t2 over the tributary area, `len`.
    pub cshear2: *mut f64,
    /// The contact normal at each slave, xyz interleaved, `3·len`.
    pub normal: *mut f64,
    /// The total contact force on each slave, xyz interleaved, `3·len`.
    pub force: *mut f64,
}

/// A pass's resultants (`abut_contact_output`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct AbutOutputTotals {
    /// CFN: resultant normal contact force on the slaves.
    pub cfn: [f64; 3],
    /// CFS: resultant friction force on the slaves.
    pub cfs: [f64; 3],
    /// Elastic energy in the contact springs.
    pub contact_energy: f64,
    /// Frictional dissipation since the start.
    pub frictional_dissipation: f64,
}

/// Reads an `int32_t` enumeration value of `T` (`what` names the argument in the error).
pub(crate) fn enum_value<T: Copy>(
    value: i32,
    what: &str,
    all: &[(i32, T)],
) -> Result<T, super::handles::Fail> {
    all.iter()
        .find(|(v, _)| *v == value)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            super::handles::Fail::new(
                AbutStatus::BadValue,
                format!(
                    "{what}: {value} is not one of {:?}",
                    all.iter().map(|(v, _)| *v).collect::<Vec<_>>()
                ),
            )
        })
}
