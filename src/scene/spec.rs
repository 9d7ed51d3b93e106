//! The scene file's tables, as serde reads them, and their checks (each error names the key).
//!
//! Long file: one struct per table of the scene file, each key documented where serde reads
//! it — the file's schema, read as one; split, it would be a schema in pieces.

use serde::Deserialize;

use crate::error::{Error, Result};

/// A scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene is.
    pub title: String,
    /// The exact solution this scene is checked against, for the summary (free text).
    #[serde(default)]
    pub reference: Option<String>,
    /// Run controls.
    pub run: RunSpec,
    /// Materials, by name.
    #[serde(default)]
    pub material: Vec<MaterialSpec>,
    /// Generated parts.
    pub part: Vec<PartSpec>,
    /// Rigid bodies with analytical surfaces.
    #[serde(default)]
    pub rigid: Vec<RigidSpec>,
    /// Fixed, prescribed and loaded faces.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// Contact pairs.
    #[serde(default)]
    pub contact: Vec<ContactSpec>,
    /// The directory mesh files are relative to (the scene file's, set by [`Scene::load`]).
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
    /// A scene read from an Abaqus deck ([`Scene::from_inp`]): what abut made of the deck
    /// beyond its tables — keywords read and not acted on, conversions — listed in the summary.
    #[serde(skip)]
    pub deck_notes: Vec<String>,
    /// A deck's `*STATIC` step, run as explicit quasi-static ([`Scene::from_inp`]).
    #[serde(skip)]
    pub quasi_static: Option<QuasiStatic>,
    /// A curve of time scaling every load (a deck's `*CLOAD` amplitude); none: constant.
    #[serde(skip)]
    pub load_factor: Option<std::sync::Arc<crate::explicit::Amplitude>>,
    /// A deck's node output requests, written at the end under the output directory.
    #[serde(skip)]
    pub node_outputs: Vec<super::deck_output::NodeOutput>,
    /// A deck's node history requests (after `*OUTPUT, HISTORY`): rows at every history row.
    #[serde(skip)]
    pub node_histories: Vec<super::deck_output::NodeOutput>,
    /// A deck's element output requests, written at the end under the output directory.
    #[serde(skip)]
    pub element_outputs: Vec<super::deck_output::ElementOutput>,
    /// A deck's contact output requests, written at the end under the output directory.
    #[serde(skip)]
    pub contact_outputs: Vec<super::deck_output::ContactOutput>,
}

/// How a deck's `*STATIC` step runs: as Abaqus/Explicit users run quasi-static problems, its
/// loads and motions ramped by a smooth step over ten of the model's fundamental periods, then
/// held for five more, with mass-proportional damping at half of critical on the fundamental
/// mode; the summary reports how small the kinetic energy stayed against the internal energy.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct QuasiStatic {
    /// The static step's time period (the time its amplitudes are given in).
    pub step_period: f64,
    /// The model's fundamental period, estimated as 4·L/c (L: the deformable parts' largest
    /// extent, c: the slowest material's bar wave speed √(E/ρ)).
    pub fundamental_period: f64,
    /// Run time over which the loads and motions ramp: 10 fundamental periods.
    pub ramp_time: f64,
    /// Run time they are held after the ramp: 5 fundamental periods.
    pub hold_time: f64,
    /// Mass-proportional damping α = 2π / period (ξ = 0.5 on the fundamental mode).
    pub damping: f64,
}

/// Run controls.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Time to run to.
    pub end_time: f64,
    /// Safety factor on the elements' stable increment (default 0.9).
    #[serde(default = "default_safety")]
    pub safety: f64,
    /// Cap on the penalty contact's stable increment (default 0.5): the increment never exceeds
    /// contact_safety times it, so every spring stays at ω·Δt ≤ 2·contact_safety. Below that
    /// cap, elements and springs share `safety` (`abut::combined_increment`). Not 0.9: a contact
    /// spring switches on and off, and central differences near a spring's linear limit
    /// (ω·Δt → 2) turn that switching into an energy pump — a node pressed slowly into a stiff
    /// penalty contact chatters and runs away at 0.7–0.9 (tests/scene.rs). At 0.5 (ω·Δt ≤ 1
    /// for the contact) it stays quiet; so does 0.9 with 10 % of critical damping on the
    /// contact (`contact.damping`).
    #[serde(default = "default_contact_safety")]
    pub contact_safety: f64,
    /// A fixed increment instead of the stable one (for stability studies).
    #[serde(default)]
    pub dt: Option<f64>,
    /// Gravity (acceleration).
    #[serde(default)]
    pub gravity: [f64; 3],
    /// Mass-proportional damping α (force −α·m·v), for dynamic relaxation to a static state.
    #[serde(default)]
    pub damping: f64,
    /// Linear bulk viscosity b1 (default 0.06, Abaqus/Explicit's; 0 = none).
    #[serde(default = "default_bulk_linear")]
    pub bulk_viscosity: f64,
    /// Quadratic bulk viscosity b2, in compression only (default 1.2, Abaqus/Explicit's;
    /// 0 = none).
    #[serde(default = "default_bulk_quadratic")]
    pub bulk_viscosity_quadratic: f64,
    /// Large-strain kinematics (default true); false: small strain, Abaqus' NLGEOM=NO.
    #[serde(default = "default_true")]
    pub nlgeom: bool,
    /// History rows every this many increments (default 1).
    #[serde(default = "default_every")]
    pub output_every: usize,
    /// A VTK frame of the contact state every this many increments (0, the default: none);
    /// written with the other outputs, as `vtk/contact.pvd` and its `.vtu` frames.
    #[serde(default)]
    pub vtk_every: usize,
    /// Move every slave node that starts overclosed onto its master before the first
    /// increment, strain-free (Abaqus' adjustment of initial positions), instead of resolving
    /// the overclosure within the first increment, which strains the elements under it and
    /// launches the nodes (default false).
    #[serde(default)]
    pub adjust_overclosure: bool,
    /// The most increments a run may take (default 10⁸): a longer one is refused before it
    /// starts, naming the element that sets the increment. Raise it to run longer on purpose.
    #[serde(default = "default_max_increments")]
    pub max_increments: u64,
    /// A deck's step ends before the last (total time): increments land on them, so each
    /// step's boundary conditions and loads start on its first increment.
    #[serde(skip)]
    pub step_ends: Vec<f64>,
}

pub(super) fn default_safety() -> f64 {
    0.9
}
pub(super) fn default_contact_safety() -> f64 {
    0.5
}
/// Abaqus/Explicit's default linear bulk viscosity.
pub const DEFAULT_BULK_VISCOSITY: f64 = 0.06;
/// Abaqus/Explicit's default quadratic bulk viscosity.
pub const DEFAULT_BULK_VISCOSITY_QUADRATIC: f64 = 1.2;

pub(super) fn default_bulk_linear() -> f64 {
    DEFAULT_BULK_VISCOSITY
}
pub(super) fn default_bulk_quadratic() -> f64 {
    DEFAULT_BULK_VISCOSITY_QUADRATIC
}
pub(super) fn default_every() -> usize {
    1
}
pub(super) fn default_max_increments() -> u64 {
    100_000_000
}
fn default_true() -> bool {
    true
}
fn default_one() -> f64 {
    1.0
}
pub(super) fn default_core() -> [usize; 3] {
    [1; 3]
}
pub(super) fn default_grading() -> [f64; 3] {
    [1.0; 3]
}

/// A linear elastic material.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Name parts refer to.
    pub name: String,
    /// Young's modulus.
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Density.
    pub density: f64,
}

/// The shapes a part can have.
pub const SHAPES: &[&str] = &[
    "block", "rect", "bar", "plate", "line", "arc", "sphere", "points", "mesh",
];

/// A generated part.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Name contacts and boundaries refer to.
    pub name: String,
    /// Deformable: "block" (tetrahedra), "rect" (plane-strain triangles, x–y plane), "bar"
    /// (2-node bars along one axis). Rigid and fixed: "plate" (quads in the x–y plane, normal
    /// +z), "line" (2D segments along x, normal +y), "arc" (2D segments of a circle, normals
    /// outward), "sphere" (triangles, normals outward). "points": point masses. "mesh": read
    /// from `file` (Gmsh `.msh` or Abaqus `.inp`), deformable (its tetrahedra and hexahedra —
    /// C3D8, selectively reduced —, or plane triangles in a 2D scene) or, with `rigid = true`,
    /// fixed.
    pub shape: String,
    /// Material (deformable shapes).
    #[serde(default)]
    pub material: Option<String>,
    /// Lower corner (block, rect, plate, line), first node (bar), centre (arc, sphere).
    #[serde(default)]
    pub origin: [f64; 3],
    /// Box size (block, rect; plate and line use x and y / x); the bar's extent (one non-zero
    /// component).
    #[serde(default)]
    pub size: [f64; 3],
    /// Cells per axis (the first for bars, lines and arcs; sphere: [latitudes, longitudes]).
    #[serde(default)]
    pub divisions: [usize; 3],
    /// Ratio of consecutive cell sizes per axis (1: uniform; negative: finest at the far end).
    #[serde(default = "default_grading")]
    pub grading: [f64; 3],
    /// Cells per axis kept at the finest size at the graded axis' fine end before the sizes
    /// start to grow by `grading` (default 1: growth from the first cell) — a uniform zone
    /// under a contact patch.
    #[serde(default = "default_core")]
    pub grading_core: [usize; 3],
    /// Cross-section area (bar), slave area per point (points).
    #[serde(default = "default_one")]
    pub area: f64,
    /// Out-of-plane thickness (rect).
    #[serde(default = "default_one")]
    pub thickness: f64,
    /// Radius (arc, sphere).
    #[serde(default)]
    pub radius: f64,
    /// Start and end angles of an arc, degrees from +x, counter-clockwise.
    #[serde(default)]
    pub angles: [f64; 2],
    /// Positions of point masses.
    #[serde(default)]
    pub points: Vec<[f64; 3]>,
    /// Mass of each point.
    #[serde(default)]
    pub mass: f64,
    /// Initial velocity.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// The mesh file of a "mesh" part, relative to the scene file's directory (or the working
    /// directory for scenes parsed from text). Its faces are named by its physical groups
    /// (Gmsh) or surfaces and sets (Abaqus); `origin` translates it.
    #[serde(default)]
    pub file: Option<String>,
    /// A "mesh" part that is fixed and rigid (its faces are master surfaces).
    #[serde(default)]
    pub rigid: bool,
    /// The dimension a "mesh" part is read in (3, or 2 for plane-strain scenes).
    #[serde(default)]
    pub dimension: Option<u32>,
    /// A part read from an Abaqus deck ([`Scene::from_inp`]): its mesh and what the deck says
    /// about its elements and nodes (then `file` names the deck, for messages).
    #[serde(skip)]
    pub deck: Option<std::sync::Arc<super::from_inp::DeckPiece>>,
    /// A "rect" or 2D "mesh" part that is axisymmetric about the y axis (x = radius ≥ 0): its
    /// triangles (a mesh's quadrilaterals split in two) and everything measured on it are per
    /// radian of circumference (forces, masses, areas). A deck's CAX3/CAX4(R) elements make a
    /// mesh part axisymmetric without it.
    #[serde(default)]
    pub axisymmetric: bool,
    /// How a rigid part (plate, line, arc, sphere, rigid mesh) moves: "fixed" (the default),
    /// "free" (a rigid body of `mass`, its nodes' centroid the reference point, moved by
    /// gravity and contact from `velocity`) or "velocity" (translating at `velocity`).
    #[serde(default)]
    pub motion: Option<String>,
}

impl PartSpec {
    /// Whether the part is a fixed rigid surface.
    pub fn is_rigid(&self) -> bool {
        matches!(self.shape.as_str(), "plate" | "line" | "arc" | "sphere")
            || (self.shape == "mesh" && self.rigid)
    }
    /// Whether the part belongs in a 2D (plane-strain) scene.
    pub fn is_2d(&self) -> bool {
        matches!(self.shape.as_str(), "rect" | "line" | "arc")
            || (self.shape == "mesh" && (self.dimension == Some(2) || self.axisymmetric))
    }
}

/// A rigid body carrying an analytical surface.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidSpec {
    /// Name contacts refer to.
    pub name: String,
    /// "plane", "sphere", "cylinder" (3D), "line", "circle" (2D).
    pub surface: String,
    /// Reference point: a point of the plane or line, the centre of a sphere or circle, a
    /// point of a cylinder's axis.
    pub point: [f64; 3],
    /// Outward normal (plane, line) or axis (cylinder).
    #[serde(default)]
    pub direction: [f64; 3],
    /// Radius (sphere, cylinder, circle).
    #[serde(default)]
    pub radius: f64,
    /// Mass.
    pub mass: f64,
    /// Inertia about the reference point (default: a solid sphere's 2/5·m·r² for spheres,
    /// circles and cylinders, m·I otherwise).
    #[serde(default)]
    pub inertia: Option<[[f64; 3]; 3]>,
    /// "free" (default), "fixed", or "velocity" (constant `velocity`).
    #[serde(default)]
    pub motion: Option<String>,
    /// Initial (or prescribed) velocity.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Held motions of a free body: any of "x", "y", "z" (translations, at zero velocity) and
    /// "rotation" — for bodies cut by symmetry planes.
    #[serde(default)]
    pub fix: Vec<String>,
    /// A constant force on a free body at its reference point (model force units).
    #[serde(default)]
    pub load: Option<[f64; 3]>,
    /// A constant moment on a free body (model force × length units).
    #[serde(default)]
    pub moment: Option<[f64; 3]>,
}

/// Fixed, prescribed or loaded nodes: the nodes of a face of a part.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// The part.
    pub part: String,
    /// Its face (x-, x+, y-, y+, z-, z+, or "all").
    pub face: String,
    /// Directions held at zero displacement: any of "x", "y", "z".
    #[serde(default)]
    pub fix: Vec<String>,
    /// Prescribed displacement per direction, reached by a smooth step over `ramp` (Abaqus'
    /// `SMOOTH STEP` amplitude: 10ξ³ − 15ξ⁴ + 6ξ⁵, at rest at both ends).
    #[serde(default)]
    pub displacement: Option<[f64; 3]>,
    /// Ramp time of `displacement`.
    #[serde(default)]
    pub ramp: f64,
    /// Directions `displacement` prescribes (default: its non-zero ones).
    #[serde(default)]
    pub directions: Vec<String>,
    /// Total force spread over the face's nodes in proportion to their tributary areas
    /// (equally for faces without area).
    #[serde(default)]
    pub load: Option<[f64; 3]>,
}

/// A contact pair: a part's face nodes against another part's face or a rigid body.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Part whose face nodes are the slaves.
    pub slave: String,
    /// Face of the slave part: x-, x+, y-, y+, z-, z+, "all".
    pub slave_face: String,
    /// Part whose face is the master surface, or a `[[rigid]]` body.
    pub master: String,
    /// Face of the master part ("out" for arcs and spheres); none for rigid bodies.
    #[serde(default)]
    pub master_face: Option<String>,
    /// "penalty" (default) or "kinematic".
    #[serde(default)]
    pub enforce: Option<String>,
    /// Coulomb coefficient (penalty, and kinematic pure finite-sliding pairs).
    #[serde(default)]
    pub friction: f64,
    /// "finite" (default), "small", "infinitesimal".
    #[serde(default)]
    pub sliding: Option<String>,
    /// Balanced master–slave weight of the slave surface's pass (e.g. 0.5); none: pure.
    #[serde(default)]
    pub balanced: Option<f64>,
    /// Penalty scale factor on the automatic stiffness k = scale·m*/Δt_ref² (default 1: each
    /// spring at ω·Δt_ref = 1, about 13 % off the increment; docs/BENCHMARKS.md).
    #[serde(default)]
    pub penalty_scale: Option<f64>,
    /// Penalty stiffness, force per length per slave node.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Penalty stiffness per unit area (pressure per length).
    #[serde(default)]
    pub stiffness_per_area: Option<f64>,
    /// Viscous damping of each penalty spring, a fraction of its critical damping (default
    /// 0.03, Abaqus/Explicit's: `abut::DEFAULT_CONTACT_DAMPING`; penalty only; 0 turns it off).
    /// It takes energy out of impacts, keeps bodies from rocking on their contact springs for
    /// ever (friction lets go where the normal force dips), and keeps contact chatter from
    /// pumping energy into light nodes (see `run.contact_safety`).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Global search every this many increments.
    #[serde(default)]
    pub search_interval: Option<u32>,
    /// Search radius, model length units (default: the master's mean facet size): a slave node
    /// farther than this from every master facet is not in the pair's contacts.
    #[serde(default)]
    pub search_radius: Option<f64>,
    /// The global search's structure: "auto" (default: the tree, as measured), "tree" or
    /// "buckets" (`abut::SearchStructure`; results do not depend on it).
    #[serde(default)]
    pub search_structure: Option<String>,
    /// A pair read from an Abaqus deck: its enforcement, friction, sliding and schedule as the
    /// deck defines them (the keys above then only name the faces).
    #[serde(skip)]
    pub deck: Option<crate::io::inp::PairSettings>,
}

/// What a part may take in memory, estimated from its divisions before anything is built.
pub(super) const MAX_SCENE_BYTES: u128 = 16 << 30;
/// Bytes per node of a built part, generously: positions, velocities, forces, masses, the
/// contact arrays, the mesh's indices (f64 and u32 arrays over the whole run).
pub(super) const BYTES_PER_NODE: u128 = 400;
/// Bytes per cell: up to six tetrahedra (a block's hexahedron) with their state.
pub(super) const BYTES_PER_CELL: u128 = 6 * 200;

/// The largest magnitude, and the inverse of the smallest non-zero one, a scene's quantities may
/// have in its units: everything derived from them (increments, stiffnesses, masses, forces)
/// then stays well within f64, and a typo such as `young = 1e300` is caught where it is read.
const MAGNITUDE: f64 = 1e100;

/// `Ok` when every one of `values` is finite and, where not zero, within 1e±100.
pub(super) fn finite_values(key: &'static str, values: &[f64], what: &str) -> Result<()> {
    match values.iter().find(|v| {
        !v.is_finite() || (**v != 0.0 && !(1.0 / MAGNITUDE..=MAGNITUDE).contains(&v.abs()))
    }) {
        None => Ok(()),
        Some(v) => bad(
            key,
            format!("{} in {values:?} ({what})", super::check::num(*v)),
            "must be finite, and where not zero within 1e±100 in the scene's units",
        ),
    }
}

/// `Ok` when `v` is finite, positive and within 1e±100.
pub(super) fn positive(key: &'static str, v: f64, what: &str) -> Result<()> {
    if v.is_finite() && (1.0 / MAGNITUDE..=MAGNITUDE).contains(&v) {
        Ok(())
    } else {
        bad(
            key,
            format!("{} ({what})", super::check::num(v)),
            "must be finite and positive, within 1e±100 in the scene's units",
        )
    }
}

pub(crate) fn bad<T>(name: &'static str, value: String, expected: &'static str) -> Result<T> {
    Err(Error::BadParameter {
        name,
        value,
        expected,
    })
}

pub(crate) fn axis_of(name: &str) -> Option<usize> {
    match name {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

pub(super) const FACES: &[&str] = &["x-", "x+", "y-", "y+", "z-", "z+", "all", "out"];

/// A check's error with the `[[section]]` entry it was found in (none: the run controls or
/// the scene as a whole).
pub(super) struct Located {
    pub(super) error: Error,
    pub(super) entry: Option<(&'static str, usize)>,
}

impl Located {
    /// The error with its entry named in the value ("in [[part]] 2").
    fn named(self) -> Error {
        match (self.error, self.entry) {
            (
                Error::BadParameter {
                    name,
                    value,
                    expected,
                },
                Some((section, i)),
            ) => Error::BadParameter {
                name,
                value: format!("{value}, in [[{section}]] {}", i + 1),
                expected,
            },
            (e, _) => e,
        }
    }

    /// The line the error points at in `text`: the key's line in its entry (for "a / b"
    /// keys, the first of them present), else the entry's first line; the key's line in the
    /// run controls.
    fn line(&self, text: &str) -> Option<usize> {
        use toml::de::{DeTable, DeValue};
        let Error::BadParameter { name, .. } = &self.error else {
            return None;
        };
        let doc = DeTable::parse(text).ok()?;
        let (section, fields) = name.split_once('.').unwrap_or((name, ""));
        let value = doc
            .get_ref()
            .iter()
            .find(|(k, _)| k.get_ref() == section)?
            .1;
        let table = match (value.get_ref(), self.entry) {
            (DeValue::Table(t), _) => t,
            (DeValue::Array(a), Some((_, i))) => a.get(i)?.get_ref().as_table()?,
            _ => return Some(line_of(text, value.span().start)),
        };
        let key = fields.split(" / ").find_map(|f| {
            table
                .iter()
                .find(|(k, _)| k.get_ref() == f.trim())
                .map(|(k, _)| k.span().start)
        });
        let first = table.iter().map(|(k, _)| k.span().start).min();
        key.or(first).map(|at| line_of(text, at))
    }
}

/// The line (from 1) holding byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

impl Scene {
    /// Parses a scene from TOML text; errors name the key and the `[[section]]` entry, and
    /// the line for syntax and type errors (toml's own messages). [`Scene::load`] names the
    /// file and line of every error.
    pub fn parse(text: &str) -> Result<Self> {
        Self::parse_located(text).map_err(|(e, _)| e)
    }

    /// As [`Scene::parse`], with the line the error points at when one is known.
    pub(super) fn parse_located(text: &str) -> std::result::Result<Self, (Error, Option<usize>)> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start));
            let error = Error::BadParameter {
                name: "scene file",
                value: e.to_string(),
                expected: "a valid scene (see abut::scene)",
            };
            (error, line)
        })?;
        scene.check().map_err(|l| {
            let line = l.line(text);
            (l.named(), line)
        })?;
        Ok(scene)
    }

    /// What a user should know before running: each material whose Poisson's ratio makes its
    /// dilatational wave more than 30 times faster than its shear wave (ν above about 0.4995),
    /// which shrinks the explicit increment by that factor against a compressible material of
    /// the same shear stiffness.
    pub fn notes(&self) -> Vec<String> {
        self.material
            .iter()
            .filter_map(|m| {
                let nu = m.poisson;
                // c_d / c_s = √(2(1 − ν)/(1 − 2ν))
                let ratio = (2.0 * (1.0 - nu) / (1.0 - 2.0 * nu)).sqrt();
                (nu > 0.0 && ratio > 30.0).then(|| {
                    format!(
                        "material {}: poisson = {nu} makes its dilatational wave {ratio:.0} times \
                         faster than its shear wave, and the stable increment {:.0} times smaller \
                         than with poisson = 0.3 (an explicit model of a nearly incompressible \
                         material usually takes poisson ≤ 0.495)",
                        m.name,
                        ratio / 3.5f64.sqrt()
                    )
                })
            })
            .collect()
    }

    /// Checks a scene built from a deck as a scene file is checked.
    pub(super) fn check_deck(&self) -> Result<()> {
        self.check().map_err(Located::named)
    }

    /// Whether the scene is plane strain (2D).
    pub fn is_2d(&self) -> bool {
        self.part.iter().any(PartSpec::is_2d)
    }
}
