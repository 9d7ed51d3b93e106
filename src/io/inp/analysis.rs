//! What a deck asks to run, beside its mesh and contact: materials and sections, rigid bodies,
//! point masses, boundary conditions, initial velocities, amplitudes, loads, the explicit step
//! and its controls, and the keywords read but not acted on (print and file requests of other
//! codes), each with the line it came from.

use std::collections::BTreeMap;

/// Where a definition stands in the deck: its file and line, for messages.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct At {
    /// The file.
    pub file: String,
    /// The line (from 1).
    pub line: usize,
}

impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.file, self.line)
    }
}

/// A `*MATERIAL` with what abut models of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialDef {
    /// `*DENSITY` (mass per volume), when given.
    pub density: Option<f64>,
    /// `*ELASTIC` Young's modulus and Poisson's ratio, when given.
    pub elastic: Option<(f64, f64)>,
    /// `*DAMPING, ALPHA=`: mass-proportional damping α (0: none).
    pub alpha: f64,
    /// Where it was defined.
    pub at: At,
}

/// A `*SOLID SECTION`: an element set, its material and its thickness (plane elements) or
/// cross-section area (trusses).
#[derive(Clone, Debug, PartialEq)]
pub struct SectionDef {
    /// Element set (upper case).
    pub elset: String,
    /// Material name (upper case).
    pub material: String,
    /// Thickness (plane elements) or area (trusses); 1 when not given.
    pub thickness: f64,
    /// Where it was defined.
    pub at: At,
}

/// A `*RIGID BODY`: the elements or analytical surface it carries and its reference node.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBodyDef {
    /// `REF NODE=` (node index).
    pub ref_node: u32,
    /// `ELSET=` (upper case), when given.
    pub elset: Option<String>,
    /// `ELSET=`: the rigid elements (element indices).
    pub elements: Vec<u32>,
    /// `PIN NSET=` and `TIE NSET=`: nodes carried by the body (node indices).
    pub nodes: Vec<u32>,
    /// `ANALYTICAL SURFACE=` (upper case).
    pub analytical: Option<String>,
    /// Where it was defined.
    pub at: At,
}

/// What a `*BOUNDARY` data line prescribes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundaryKind {
    /// `TYPE=DISPLACEMENT` (the default): displacement (rotation for 4–6).
    Displacement,
    /// `TYPE=VELOCITY`.
    Velocity,
}

/// One `*BOUNDARY` data line: degrees of freedom `first..=last` (1–6) of `nodes` held at
/// `value` (times the amplitude).
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryDef {
    /// The nodes (node indices).
    pub nodes: Vec<u32>,
    /// First degree of freedom (1–6).
    pub first: usize,
    /// Last degree of freedom (1–6).
    pub last: usize,
    /// The value (0 for a fixed degree of freedom).
    pub value: f64,
    /// Displacement or velocity.
    pub kind: BoundaryKind,
    /// `AMPLITUDE=` (upper case); none: Abaqus/Explicit's default, applied at once.
    pub amplitude: Option<String>,
    /// The step it was given in (1 for the first `*STEP`), or 0 before the first (model data).
    pub step: usize,
    /// Where it was given.
    pub at: At,
}

/// An `*AMPLITUDE` curve (`DEFINITION=TABULAR` or `SMOOTH STEP`) and where it was defined.
#[derive(Clone, Debug, PartialEq)]
pub struct AmplitudeDef {
    /// The curve, as the solver takes it.
    pub curve: crate::explicit::Amplitude,
    /// Where it was defined.
    pub at: At,
}

/// One `*CLOAD` data line: a force (1–3) or moment (4–6) on each of `nodes`.
#[derive(Clone, Debug, PartialEq)]
pub struct CloadDef {
    /// The nodes (node indices).
    pub nodes: Vec<u32>,
    /// Degree of freedom (1–6).
    pub dof: usize,
    /// Magnitude (force or moment units).
    pub value: f64,
    /// `AMPLITUDE=` (upper case).
    pub amplitude: Option<String>,
    /// The step it was given in (1 for the first `*STEP`).
    pub step: usize,
    /// Where it was given.
    pub at: At,
}

/// A `*DLOAD` of type `GRAV`: gravity on an element set.
#[derive(Clone, Debug, PartialEq)]
pub struct GravityDef {
    /// The element set (upper case), or an element label.
    pub elset: String,
    /// The acceleration vector (magnitude times the direction given).
    pub acceleration: [f64; 3],
    /// The step it was given in (1 for the first `*STEP`).
    pub step: usize,
    /// Where it was given.
    pub at: At,
}

/// The `*STEP` with its `*DYNAMIC, EXPLICIT` procedure and step-level controls.
#[derive(Clone, Debug, PartialEq)]
pub struct StepDef {
    /// `NAME=`, when given.
    pub name: Option<String>,
    /// `NLGEOM=` (Abaqus/Explicit's default is YES; a `*STATIC` step's, as in Abaqus/Standard
    /// and CalculiX, NO).
    pub nlgeom: bool,
    /// Whether the step wrote `NLGEOM=` (else the default for its procedure).
    pub nlgeom_written: bool,
    /// The procedure: `DYNAMIC EXPLICIT` or `STATIC`.
    pub procedure: Option<String>,
    /// The step's time period.
    pub time_period: Option<f64>,
    /// `DIRECT USER CONTROL`: the fixed increment.
    pub fixed_increment: Option<f64>,
    /// `SCALE FACTOR=` on the stable increment.
    pub scale_factor: Option<f64>,
    /// `*BULK VISCOSITY`: linear and quadratic coefficients.
    pub bulk_viscosity: Option<(f64, f64)>,
    /// `*FIXED MASS SCALING, FACTOR=` over the whole model.
    pub mass_scaling: Option<f64>,
    /// `*OUTPUT, HISTORY, FREQUENCY=`: a history row every this many increments.
    pub history_every: Option<usize>,
    /// `*OUTPUT, FIELD, FREQUENCY=`: a contact frame every this many increments.
    pub field_every: Option<usize>,
    /// `*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`: node variables asked for, in order.
    pub node_outputs: Vec<NodeOutputDef>,
    /// `*EL PRINT`, `*ELEMENT OUTPUT`, `*EL FILE`: element variables asked for, in order.
    pub element_outputs: Vec<NodeOutputDef>,
    /// `*CONTACT PRINT`, `*CONTACT OUTPUT`, `*CONTACT FILE`: contact variables asked for.
    pub contact_outputs: Vec<NodeOutputDef>,
    /// A `*BOUNDARY, OP=NEW` in the step: the boundary conditions of earlier steps removed.
    pub boundary_new: bool,
    /// A `*CLOAD, OP=NEW` in the step: the loads of earlier steps removed.
    pub cload_new: bool,
    /// Where the step began.
    pub at: At,
}

/// A request for node variables (`*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`) or element ones
/// (`*EL PRINT`, `*ELEMENT OUTPUT`, `*EL FILE`).
#[derive(Clone, Debug, PartialEq)]
pub struct NodeOutputDef {
    /// The keyword, as written (`NODE PRINT`, …).
    pub keyword: String,
    /// `NSET=` (`ELSET=` for elements): the set (none: the whole model).
    pub nset: Option<String>,
    /// The variables asked for (upper case: `U`, `V`, `A`, `RF`, `CF`, `COORD`, …).
    pub variables: Vec<String>,
    /// After `*OUTPUT, HISTORY` (a `*NODE OUTPUT` there): a row at every history output of
    /// the step rather than once at its end.
    pub history: bool,
    /// Where it is.
    pub at: At,
}

/// An analytical rigid surface (`*SURFACE, TYPE=REVOLUTION | SEGMENTS | CYLINDER`): its
/// local system and its profile, as written.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalyticalDef {
    /// `REVOLUTION`, `SEGMENTS` or `CYLINDER`.
    pub kind: String,
    /// The local system's points: a (origin) and b (on the local axis), and for a cylinder c
    /// (on the generator); empty for `SEGMENTS`.
    pub points: Vec<[f64; 3]>,
    /// The profile: `START`, then `LINE` and `CIRCL` segments, each with its values.
    pub profile: Vec<(String, Vec<f64>)>,
    /// Where it was defined.
    pub at: At,
}

/// What a deck asks to run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Analysis {
    /// Materials by name (upper case).
    pub materials: BTreeMap<String, MaterialDef>,
    /// Sections in deck order.
    pub sections: Vec<SectionDef>,
    /// Analytical rigid surfaces by name (upper case).
    pub analytical: BTreeMap<String, AnalyticalDef>,
    /// Rigid bodies in deck order.
    pub rigid_bodies: Vec<RigidBodyDef>,
    /// Point masses (`*MASS` on `TYPE=MASS` elements): node index and mass.
    pub point_masses: Vec<(u32, f64, At)>,
    /// Rotary inertia (`*ROTARY INERTIA` on `TYPE=ROTARYI` elements): node index and the
    /// inertia tensor about it.
    pub rotary_inertia: Vec<(u32, [[f64; 3]; 3], At)>,
    /// Boundary conditions in deck order (model data, then the step's).
    pub boundaries: Vec<BoundaryDef>,
    /// `*INITIAL CONDITIONS, TYPE=VELOCITY`: node index, degree of freedom (1–3), value.
    pub initial_velocities: Vec<(u32, usize, f64, At)>,
    /// Amplitudes by name (upper case).
    pub amplitudes: BTreeMap<String, AmplitudeDef>,
    /// Concentrated loads in deck order.
    pub cloads: Vec<CloadDef>,
    /// Gravity loads.
    pub gravity: Vec<GravityDef>,
    /// The steps, in order.
    pub steps: Vec<StepDef>,
    /// Each `*ELEMENT` keyword: the index of its first element, its `TYPE=` and where it is.
    pub element_blocks: Vec<(u32, String, At)>,
    /// Surface elements (`*SURFACE SECTION`), by element index: they carry surfaces only.
    pub surface_elements: Vec<u32>,
    /// Plane-stress elements (CPS3, CPS4, CPS4R), by element index: read as plane meshes, not
    /// modelled as deformable (abut's plane elements are plane strain).
    pub plane_stress: Vec<u32>,
    /// The element sets of `TYPE=MASS` and `TYPE=ROTARYI` elements (upper case).
    pub mass_sets: std::collections::BTreeSet<String>,
    /// Keywords read but not acted on, with why: print and file requests of other codes,
    /// output variables abut does not write.
    pub ignored: Vec<String>,
}

/// The degrees of freedom a `*BOUNDARY` type word holds: ENCASTRE, PINNED and the
/// symmetry conditions, as (first, last) ranges.
pub(crate) fn boundary_type(word: &str) -> Option<&'static [(usize, usize)]> {
    Some(match word {
        "ENCASTRE" => &[(1, 6)],
        "PINNED" => &[(1, 3)],
        "XSYMM" => &[(1, 1), (5, 6)],
        "YSYMM" => &[(2, 2), (4, 4), (6, 6)],
        "ZSYMM" => &[(3, 5)],
        "XASYMM" => &[(2, 4)],
        "YASYMM" => &[(1, 1), (3, 3), (5, 5)],
        "ZASYMM" => &[(1, 2), (6, 6)],
        _ => return None,
    })
}

impl Analysis {
    /// The `*ELEMENT` keyword element `e` was defined under: its `TYPE=` and where it is.
    pub fn element_block(&self, e: u32) -> Option<(&str, &At)> {
        let k = self.element_blocks.partition_point(|b| b.0 <= e);
        self.element_blocks
            .get(k.checked_sub(1)?)
            .map(|b| (b.1.as_str(), &b.2))
    }
}
