//! The scene file's tables, as serde reads them, and their checks (each error names the key).

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
}

fn default_safety() -> f64 {
    0.9
}
fn default_contact_safety() -> f64 {
    0.5
}
/// Abaqus/Explicit's default linear bulk viscosity.
pub const DEFAULT_BULK_VISCOSITY: f64 = 0.06;
/// Abaqus/Explicit's default quadratic bulk viscosity.
pub const DEFAULT_BULK_VISCOSITY_QUADRATIC: f64 = 1.2;

fn default_bulk_linear() -> f64 {
    DEFAULT_BULK_VISCOSITY
}
fn default_bulk_quadratic() -> f64 {
    DEFAULT_BULK_VISCOSITY_QUADRATIC
}
fn default_every() -> usize {
    1
}
fn default_true() -> bool {
    true
}
fn default_one() -> f64 {
    1.0
}
fn default_core() -> [usize; 3] {
    [1; 3]
}
fn default_grading() -> [f64; 3] {
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
    /// from `file` (Gmsh `.msh` or Abaqus `.inp`), deformable (its tetrahedra, or plane
    /// triangles in a 2D scene) or, with `rigid = true`, fixed.
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
    /// Prescribed displacement per direction, reached by a smooth ramp over `ramp`.
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
}

/// What a part may take in memory, estimated from its divisions before anything is built.
const MAX_SCENE_BYTES: u128 = 16 << 30;
/// Bytes per node of a built part, generously: positions, velocities, forces, masses, the
/// contact arrays, the mesh's indices (f64 and u32 arrays over the whole run).
const BYTES_PER_NODE: u128 = 400;
/// Bytes per cell: up to six tetrahedra (a block's hexahedron) with their state.
const BYTES_PER_CELL: u128 = 6 * 200;

/// The largest magnitude, and the inverse of the smallest non-zero one, a scene's quantities may
/// have in its units: everything derived from them (increments, stiffnesses, masses, forces)
/// then stays well within f64, and a typo such as `young = 1e300` is caught where it is read.
const MAGNITUDE: f64 = 1e100;

/// `Ok` when every one of `values` is finite and, where not zero, within 1e±100.
fn finite_values(key: &'static str, values: &[f64], what: &str) -> Result<()> {
    match values.iter().find(|v| {
        !v.is_finite() || (**v != 0.0 && !(1.0 / MAGNITUDE..=MAGNITUDE).contains(&v.abs()))
    }) {
        None => Ok(()),
        Some(v) => bad(
            key,
            format!("{v} in {values:?} ({what})"),
            "must be finite, and where not zero within 1e±100 in the scene's units",
        ),
    }
}

/// `Ok` when `v` is finite, positive and within 1e±100.
fn positive(key: &'static str, v: f64, what: &str) -> Result<()> {
    if v.is_finite() && (1.0 / MAGNITUDE..=MAGNITUDE).contains(&v) {
        Ok(())
    } else {
        bad(
            key,
            format!("{v} ({what})"),
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

const FACES: &[&str] = &["x-", "x+", "y-", "y+", "z-", "z+", "all", "out"];

/// A check's error with the `[[section]]` entry it was found in (none: the run controls or
/// the scene as a whole).
struct Located {
    error: Error,
    entry: Option<(&'static str, usize)>,
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
    fn parse_located(text: &str) -> std::result::Result<Self, (Error, Option<usize>)> {
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

    /// Reads and parses the scene file at `path`; mesh files are then relative to its
    /// directory. Errors name the file, and the key or line.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        })?;
        let mut s = Self::parse_located(&text).map_err(|(e, line)| Error::Parse {
            file: path.display().to_string(),
            line: line.unwrap_or(0),
            message: e.to_string(),
        })?;
        s.base_dir = path.parent().map(|p| p.to_path_buf());
        Ok(s)
    }

    /// Whether the scene is plane strain (2D).
    pub fn is_2d(&self) -> bool {
        self.part.iter().any(PartSpec::is_2d)
    }

    fn check(&self) -> std::result::Result<(), Located> {
        let run: Result<()> = (|| {
            let r = &self.run;
            if !(r.end_time.is_finite() && r.end_time > 0.0) {
                return bad(
                    "run.end_time",
                    r.end_time.to_string(),
                    "must be finite and positive",
                );
            }
            for (key, v) in [
                ("run.safety", r.safety),
                ("run.contact_safety", r.contact_safety),
            ] {
                if !(v > 0.0 && v <= 1.0) {
                    return bad(key, v.to_string(), "must lie in (0, 1]");
                }
            }
            if let Some(dt) = r.dt {
                if !(dt.is_finite() && dt > 0.0) {
                    return bad("run.dt", dt.to_string(), "must be finite and positive");
                }
            }
            for (key, v) in [
                ("run.damping", r.damping),
                ("run.bulk_viscosity", r.bulk_viscosity),
                ("run.bulk_viscosity_quadratic", r.bulk_viscosity_quadratic),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return bad(key, v.to_string(), "must be finite and not negative");
                }
            }
            finite_values("run.gravity", &r.gravity, "run")?;
            if self.part.is_empty() {
                return bad("part", "none".into(), "a scene needs at least one [[part]]");
            }
            Ok(())
        })();
        run.map_err(|error| Located { error, entry: None })?;
        let two_d = self.is_2d();
        let mut names = std::collections::HashSet::new();
        for (i, p) in self.part.iter().enumerate() {
            let r: Result<()> = (|| {
                if !names.insert(p.name.as_str()) {
                    return bad("part.name", p.name.clone(), "must be unique");
                }
                if !SHAPES.contains(&p.shape.as_str()) {
                    return bad(
                        "part.shape",
                        format!("{} (part {})", p.shape, p.name),
                        "must be block, rect, bar, plate, line, arc, sphere, points or mesh",
                    );
                }
                if two_d && matches!(p.shape.as_str(), "block" | "plate" | "sphere" | "bar") {
                    return bad(
                        "part.shape",
                        format!("{} (part {}) with 2D parts", p.shape, p.name),
                        "a scene is either 2D (rect, line, arc, points) or 3D",
                    );
                }
                let axes = match p.shape.as_str() {
                    "block" => 3,
                    "rect" | "plate" => 2,
                    "bar" | "line" | "arc" => 1,
                    "sphere" => 2,
                    _ => 0,
                };
                if p.divisions.iter().take(axes).any(|&d| d == 0) {
                    return bad(
                        "part.divisions",
                        format!("{:?} (part {})", p.divisions, p.name),
                        "must be positive for each axis the shape uses",
                    );
                }
                // the memory the part would take, estimated before anything is allocated
                let (nodes, cells) = p
                    .divisions
                    .iter()
                    .take(axes)
                    .fold((1u128, 1u128), |(n, c), &d| {
                        (n * (d as u128 + 1), c * d as u128)
                    });
                let bytes = nodes * BYTES_PER_NODE + cells * BYTES_PER_CELL;
                if bytes > MAX_SCENE_BYTES {
                    return bad(
                        "part.divisions",
                        format!(
                            "{:?} (part {}): {nodes} nodes and {cells} cells, about {:.1e} bytes",
                            p.divisions, p.name, bytes as f64
                        ),
                        "a part must fit in 16 GiB (nodes, elements and their state)",
                    );
                }
                let sized = match p.shape.as_str() {
                    "block" => 3,
                    "rect" | "plate" => 2,
                    "line" => 1,
                    _ => 0,
                };
                if p.size
                    .iter()
                    .take(sized)
                    .any(|&s| !(s.is_finite() && s > 0.0))
                {
                    return bad(
                        "part.size",
                        format!("{:?} (part {})", p.size, p.name),
                        "must be finite and positive",
                    );
                }
                let what = format!("part {}", p.name);
                finite_values("part.origin", &p.origin, &what)?;
                finite_values("part.velocity", &p.velocity, &what)?;
                finite_values("part.size", &p.size, &what)?;
                for x in &p.points {
                    finite_values("part.points", x, &what)?;
                }
                if p.grading.iter().any(|g| !(g.is_finite() && g.abs() > 0.0)) {
                    return bad(
                        "part.grading",
                        format!("{:?} (part {})", p.grading, p.name),
                        "ratios must be finite and non-zero",
                    );
                }
                if (0..3).any(|a| p.grading_core[a] > p.divisions[a].max(1)) {
                    return bad(
                        "part.grading_core",
                        format!("{:?} (part {})", p.grading_core, p.name),
                        "cannot exceed the divisions along the axis",
                    );
                }
                if p.shape == "bar" && p.size.iter().filter(|s| **s != 0.0).count() != 1 {
                    return bad(
                        "part.size",
                        format!("{:?} (bar {})", p.size, p.name),
                        "a bar runs along one axis: exactly one non-zero component",
                    );
                }
                if matches!(p.shape.as_str(), "arc" | "sphere") {
                    positive("part.radius", p.radius, &what)?;
                }
                if p.shape == "points" {
                    if p.points.is_empty() {
                        return bad(
                            "part.points",
                            format!("part {}", p.name),
                            "points need at least one position",
                        );
                    }
                    positive("part.mass", p.mass, &what)?;
                }
                for (key, v) in [("part.area", p.area), ("part.thickness", p.thickness)] {
                    positive(key, v, &what)?;
                }
                let axi_shape = (p.shape == "rect" && p.origin[0] >= 0.0)
                    || (p.shape == "mesh" && p.dimension != Some(3) && !p.rigid);
                if p.axisymmetric && !axi_shape {
                    return bad(
                        "part.axisymmetric",
                        format!("part {}", p.name),
                        "a rect part with origin x ≥ 0 (x is the radius) or a deformable 2D mesh part",
                    );
                }
                if let Some(m) = p.motion.as_deref() {
                    if !p.is_rigid() || !["fixed", "free", "velocity"].contains(&m) {
                        return bad(
                            "part.motion",
                            format!("{m} (part {})", p.name),
                            "rigid parts only: fixed, free or velocity",
                        );
                    }
                    if m != "fixed" {
                        positive(
                            "part.mass",
                            p.mass,
                            &format!("moving rigid part {}", p.name),
                        )?;
                    }
                }
                if p.shape == "mesh" {
                    match p.file.as_deref() {
                        Some(f) if f.ends_with(".msh") || f.ends_with(".inp") => {}
                        _ => {
                            return bad(
                                "part.file",
                                format!("{:?} (part {})", p.file, p.name),
                                "a mesh part needs a Gmsh .msh or Abaqus .inp file",
                            )
                        }
                    }
                    if !matches!(p.dimension, None | Some(2) | Some(3)) {
                        return bad(
                            "part.dimension",
                            format!("{:?} (part {})", p.dimension, p.name),
                            "must be 2 or 3",
                        );
                    }
                }
                let deformable = matches!(p.shape.as_str(), "block" | "rect" | "bar")
                    || (p.shape == "mesh" && !p.rigid);
                if deformable
                    && !self
                        .material
                        .iter()
                        .any(|m| Some(&m.name) == p.material.as_ref())
                {
                    return bad(
                        "part.material",
                        format!("{:?} (part {})", p.material, p.name),
                        "must name a [[material]]",
                    );
                }
                Ok(())
            })();
            r.map_err(|error| Located {
                error,
                entry: Some(("part", i)),
            })?;
        }
        for (i, m) in self.material.iter().enumerate() {
            let r: Result<()> = (|| {
                let what = format!("material {}", m.name);
                positive("material.young", m.young, &what)?;
                positive("material.density", m.density, &what)?;
                if !(m.poisson > -1.0 && m.poisson < 0.5) {
                    return bad(
                        "material.poisson",
                        format!("{} ({what})", m.poisson),
                        "must lie in (−1, 0.5)",
                    );
                }
                Ok(())
            })();
            r.map_err(|error| Located {
                error,
                entry: Some(("material", i)),
            })?;
        }
        for (i, b) in self.rigid.iter().enumerate() {
            let r: Result<()> = (|| {
                if !names.insert(b.name.as_str()) {
                    return bad(
                        "rigid.name",
                        b.name.clone(),
                        "must be unique among parts and bodies",
                    );
                }
                if !["plane", "sphere", "cylinder", "line", "circle"].contains(&b.surface.as_str())
                {
                    return bad(
                        "rigid.surface",
                        format!("{} (body {})", b.surface, b.name),
                        "must be plane, sphere, cylinder, line or circle",
                    );
                }
                let what = format!("body {}", b.name);
                finite_values("rigid.point", &b.point, &what)?;
                finite_values("rigid.direction", &b.direction, &what)?;
                finite_values("rigid.velocity", &b.velocity, &what)?;
                positive("rigid.mass", b.mass, &what)?;
                if matches!(b.surface.as_str(), "sphere" | "cylinder" | "circle") {
                    positive("rigid.radius", b.radius, &what)?;
                }
                if let Some(i) = &b.inertia {
                    for row in i {
                        finite_values("rigid.inertia", row, &what)?;
                    }
                }
                if let Some(f) = b
                    .fix
                    .iter()
                    .find(|f| axis_of(f).is_none() && *f != "rotation")
                {
                    return bad("rigid.fix", f.clone(), "must be x, y, z or rotation");
                }
                if !matches!(
                    b.motion.as_deref(),
                    None | Some("free" | "fixed" | "velocity")
                ) {
                    return bad(
                        "rigid.motion",
                        format!("{:?} (body {})", b.motion, b.name),
                        "must be free, fixed or velocity",
                    );
                }
                for (key, v) in [("rigid.load", &b.load), ("rigid.moment", &b.moment)] {
                    if let Some(v) = v {
                        finite_values(key, v, &what)?;
                        if !matches!(b.motion.as_deref(), None | Some("free")) {
                            return bad(
                                key,
                                format!("body {} (motion {:?})", b.name, b.motion),
                                "a free body (a fixed or moving body is held on its path whatever acts on it)",
                            );
                        }
                    }
                }
                Ok(())
            })();
            r.map_err(|error| Located {
                error,
                entry: Some(("rigid", i)),
            })?;
        }
        for (i, b) in self.boundary.iter().enumerate() {
            let r: Result<()> = (|| {
                let Some(p) = self.part.iter().find(|p| p.name == b.part) else {
                    return bad("boundary.part", b.part.clone(), "must name a [[part]]");
                };
                if p.shape != "mesh" && (!FACES.contains(&b.face.as_str()) || b.face == "out") {
                    return bad(
                        "boundary.face",
                        b.face.clone(),
                        "must be x-, x+, y-, y+, z-, z+ or all",
                    );
                }
                if p.is_rigid() {
                    // a free rigid part takes loads (its body sums them); nothing else
                    let free = p.motion.as_deref() == Some("free");
                    if !free || !b.fix.is_empty() || b.displacement.is_some() || b.load.is_none() {
                        return bad(
                            "boundary.part",
                            b.part.clone(),
                            "a rigid part takes only a load, and only when it is free (motion = \"free\"); fixed and moving ones are held already",
                        );
                    }
                }
                for d in b.fix.iter().chain(&b.directions) {
                    if axis_of(d).is_none() {
                        return bad(
                            "boundary.fix / boundary.directions",
                            d.clone(),
                            "must be x, y or z",
                        );
                    }
                }
                let what = format!("part {}, face {}", b.part, b.face);
                if let Some(d) = &b.displacement {
                    finite_values("boundary.displacement", d, &what)?;
                }
                if let Some(l) = &b.load {
                    finite_values("boundary.load", l, &what)?;
                }
                if b.displacement.is_some() && !(b.ramp.is_finite() && b.ramp > 0.0) {
                    return bad(
                        "boundary.ramp",
                        format!("{} (part {})", b.ramp, b.part),
                        "a prescribed displacement needs a positive ramp time",
                    );
                }
                Ok(())
            })();
            r.map_err(|error| Located {
                error,
                entry: Some(("boundary", i)),
            })?;
        }
        for (i, c) in self.contact.iter().enumerate() {
            let r: Result<()> = (|| {
                let Some(sp) = self.part.iter().find(|p| p.name == c.slave) else {
                    return bad("contact.slave", c.slave.clone(), "must name a [[part]]");
                };
                if sp.is_rigid() && sp.motion.as_deref().is_none_or(|m| m == "fixed") {
                    return bad(
                        "contact.slave",
                        c.slave.clone(),
                        "slave nodes must move: not a fixed rigid part",
                    );
                }
                if sp.shape != "mesh"
                    && (!FACES.contains(&c.slave_face.as_str()) || c.slave_face == "out")
                {
                    return bad(
                        "contact.slave_face",
                        c.slave_face.clone(),
                        "must be x-, x+, y-, y+, z-, z+ or all",
                    );
                }
                let master_part = self.part.iter().any(|p| p.name == c.master);
                let master_body = self.rigid.iter().any(|b| b.name == c.master);
                if !master_part && !master_body {
                    return bad(
                        "contact.master",
                        c.master.clone(),
                        "must name a [[part]] or a [[rigid]] body",
                    );
                }
                let master_mesh = self
                    .part
                    .iter()
                    .any(|p| p.name == c.master && p.shape == "mesh");
                if master_part {
                    match c.master_face.as_deref() {
                        Some(_) if master_mesh => {}
                        Some(f) if FACES.contains(&f) && f != "all" => {}
                        _ => {
                            return bad(
                                "contact.master_face",
                                format!("{:?} (master {})", c.master_face, c.master),
                                "a part master needs a face: x-, x+, y-, y+, z-, z+, or out",
                            )
                        }
                    }
                }
                if !matches!(c.enforce.as_deref(), None | Some("penalty" | "kinematic")) {
                    return bad(
                        "contact.enforce",
                        format!("{:?}", c.enforce),
                        "must be \"penalty\" or \"kinematic\"",
                    );
                }
                if master_body && c.enforce.as_deref() != Some("kinematic") {
                    return bad(
                    "contact.enforce",
                    format!("{:?} (master {})", c.enforce, c.master),
                    "analytical rigid surfaces are enforced kinematically: set enforce = \"kinematic\"",
                );
                }
                if !matches!(
                    c.sliding.as_deref(),
                    None | Some("finite" | "small" | "infinitesimal")
                ) {
                    return bad(
                        "contact.sliding",
                        format!("{:?}", c.sliding),
                        "must be finite, small or infinitesimal",
                    );
                }
                let stiffness_rules = [c.penalty_scale, c.stiffness, c.stiffness_per_area]
                    .iter()
                    .filter(|s| s.is_some())
                    .count();
                if stiffness_rules > 1 {
                    return bad(
                        "contact.penalty_scale / stiffness / stiffness_per_area",
                        format!("master {}", c.master),
                        "give at most one stiffness rule",
                    );
                }
                let what = format!("master {}", c.master);
                if let Some(k) = c.stiffness {
                    positive("contact.stiffness", k, &what)?;
                }
                if let Some(k) = c.stiffness_per_area {
                    positive("contact.stiffness_per_area", k, &what)?;
                }
                if let Some(f) = c.penalty_scale {
                    // a factor on the default stiffness: beyond 10⁸ either way it is a typo, and
                    // it would set increments far below any the run could take
                    if !(f.is_finite() && (1e-8..=1e8).contains(&f)) {
                        return bad(
                            "contact.penalty_scale",
                            format!("{f} ({what})"),
                            "a factor on the default stiffness within 1e±8",
                        );
                    }
                }
                if let Some(r) = c.search_radius {
                    if !(r.is_finite() && r > 0.0) {
                        return bad(
                            "contact.search_radius",
                            format!("{r} (master {})", c.master),
                            "must be finite and positive",
                        );
                    }
                }
                if !(c.friction.is_finite() && c.friction >= 0.0) {
                    return bad(
                        "contact.friction",
                        c.friction.to_string(),
                        "must be finite and not negative",
                    );
                }
                if let Some(z) = c.damping {
                    if !(z.is_finite() && (0.0..=1.0).contains(&z)) {
                        return bad(
                            "contact.damping",
                            format!("{z} (master {})", c.master),
                            "a fraction of critical damping in [0, 1]",
                        );
                    }
                    if c.enforce.as_deref() == Some("kinematic") {
                        return bad(
                            "contact.damping",
                            format!("{z} (master {})", c.master),
                            "penalty contact only: kinematic contact has no springs to damp",
                        );
                    }
                }
                Ok(())
            })();
            r.map_err(|error| Located {
                error,
                entry: Some(("contact", i)),
            })?;
        }
        Ok(())
    }
}
