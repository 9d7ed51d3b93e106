//! Scene files (TOML): generated parts, rigid bodies, boundary conditions, contact pairs and
//! run controls, run by the explicit solver with abut's contact; `abut run SCENE` writes a CSV
//! history and a JSON summary. `scenes/` holds one scene per verification case.
//!
//! ```toml
//! title = "two blocks"
//! reference = "VERIFICATION §1"   # what the scene is checked against (free text)
//! [run]
//! end_time = 30.0          # model time units
//! safety = 0.9             # on the elements' stable increment (default 0.9)
//! contact_safety = 0.5     # cap on the penalty contact's stable increment (default 0.5)
//! # dt = 1e-3              # a fixed increment instead (stability studies)
//! gravity = [0, 0, -9.81]  # default none
//! damping = 0.0            # mass-proportional α, for dynamic relaxation
//! bulk_viscosity = 0.06    # linear b1 (default 0.06, Abaqus/Explicit's; 0: none)
//! bulk_viscosity_quadratic = 1.2  # b2, in compression only (default 1.2, Abaqus'; 0: none)
//! nlgeom = true            # false: small-strain kinematics (Abaqus' NLGEOM=NO)
//! output_every = 10        # history rows every this many increments (default 1)
//! vtk_every = 100          # a VTK frame of the contact state (vtk/contact.pvd) every 100
//! # max_increments = 100000000  # a longer run is refused before it starts (default 10^8)
//! [[material]]
//! name = "rubber"
//! young = 1.0
//! poisson = 0.0
//! density = 1.0
//! [[part]]
//! name = "left"
//! shape = "block"          # block | rect | bar | plate | line | arc | sphere | points | mesh
//! # file = "part.msh"      # mesh parts: Gmsh .msh or Abaqus .inp, faces by physical group,
//! # rigid = false          #   *SURFACE or set name, or "boundary" (the mesh's outer surface,
//! #                        #   no group needed); deformable (tets / plane elements) or rigid
//! # axisymmetric = false   # rect and 2D mesh parts: x is the radius (a deck's CAX3/CAX4(R)
//! #                        #   elements are axisymmetric without it); axis nodes held radially
//! material = "rubber"
//! origin = [0, 0, 0]
//! size = [10, 2, 2]
//! divisions = [40, 1, 1]
//! grading = [1, 1, 1]      # ratio of consecutive cells; negative: finest at the far end
//! # grading_core = [1, 1, 1]  # cells kept at the finest size before the growth starts
//! velocity = [0.1, 0, 0]
//! # motion = "free"        # rigid parts (plate, line, arc, sphere, rigid mesh): fixed (default),
//! # mass = 2.0             #   free (a rigid body carrying the part's nodes) or velocity
//! [[rigid]]                # a rigid body with an analytical surface
//! name = "ball"
//! surface = "sphere"       # plane | sphere | cylinder | line | circle
//! point = [0, 0, 5]
//! radius = 1.0
//! mass = 2.0
//! motion = "free"          # free | fixed | velocity
//! # load = [0, 0, -1]      # free bodies: a constant force at the point, and a moment
//! # moment = [0, 0, 0]
//! [[boundary]]
//! part = "left"            # a free rigid part takes a load (its body sums it), nothing else
//! face = "x-"              # x-, x+, y-, y+, z-, z+, all
//! fix = ["y", "z"]
//! # displacement = [0, -0.01, 0], ramp = 0.01   # smooth ramp; load = [0, 0, -1]: total force
//! [[contact]]
//! slave = "left"           # part whose face nodes are the slave nodes
//! slave_face = "x+"
//! master = "right"         # part (with master_face) or rigid body
//! master_face = "x-"       # x-, ..., z+, or "out" for arcs and spheres
//! enforce = "kinematic"    # or "penalty" (default)
//! friction = 0.0           # Coulomb coefficient (kinematic: pure finite-sliding pairs)
//! sliding = "finite"       # finite | small | infinitesimal
//! # balanced = 0.5         # balanced master–slave weight
//! # penalty_scale = 1.0 | stiffness = k | stiffness_per_area = eps
//! # damping = 0.1         # of each penalty spring's critical damping
//! # search_interval = 100
//! # search_radius = 0.1   # model length (default: the master's mean facet size)
//! # search_structure = "auto"   # auto (the tree, as measured) | tree | buckets
//! ```
//!
//! Errors name the key and the `[[section]]` entry; from a file (`Scene::load`) also the file
//! and line. A few checks need the built geometry (a master face with no facets) and come from
//! `run`, naming the key and part but no line.

mod account;
mod build;
mod check;
pub mod deck_output;
#[cfg(feature = "mpi")]
mod distributed;
mod force_history;
mod from_inp;
mod increments;
mod run;
mod run_length;
mod spec;
mod summary;
mod to_inp;

pub use build::Built;
#[cfg(feature = "mpi")]
pub use distributed::run_distributed;
pub use from_inp::{DeckPiece, DeckRigid};
pub use spec::{
    BoundarySpec, ContactSpec, MaterialSpec, PartSpec, QuasiStatic, RigidSpec, RunSpec, Scene,
    DEFAULT_BULK_VISCOSITY, DEFAULT_BULK_VISCOSITY_QUADRATIC,
};

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::device::Device;
use crate::error::{Error, Result};
use crate::explicit::{Element, Integration, Solver};
use build::PartNodes;
pub use summary::{
    BodySummary, ContactNode, CurveSample, PartSummary, QuasiStaticSummary, RankSummary, Summary,
};

/// Rising and falling edges of a force history (time, force per increment) at half its
/// plateau (the mean over the middle half of the contact), by linear interpolation; the
/// impulse; the plateau.
fn half_plateau_edges(history: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    let Some(first) = history.iter().position(|h| h.1 > 0.0) else {
        return (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    };
    let last = history
        .iter()
        .rposition(|h| h.1 > 0.0)
        .expect("first exists");
    let span = last - first;
    let mid = &history[first + span / 4..=last - span / 4];
    let plateau = mid.iter().map(|h| h.1).sum::<f64>() / mid.len() as f64;
    let half = 0.5 * plateau;
    let rise = (first..=last)
        .find(|&n| history[n].1 >= half)
        .expect("the mean is reached");
    let fall = (first..=last)
        .rev()
        .find(|&n| history[n].1 >= half)
        .expect("as above");
    let lerp = |a: (f64, f64), b: (f64, f64)| {
        if b.1 == a.1 {
            a.0
        } else {
            a.0 + (b.0 - a.0) * (half - a.1) / (b.1 - a.1)
        }
    };
    let t_rise = if rise == 0 {
        history[0].0
    } else {
        lerp(history[rise - 1], history[rise])
    };
    let t_fall = if fall + 1 >= history.len() {
        history[fall].0
    } else {
        lerp(history[fall], history[fall + 1])
    };
    let impulse: f64 = (0..history.len())
        .map(|n| {
            let dt = if n == 0 {
                2.0 * history[0].0
            } else {
                history[n].0 - history[n - 1].0
            };
            history[n].1 * dt
        })
        .sum();
    (t_rise, t_fall, impulse, plateau)
}

fn stress6(s: [[f64; 3]; 3]) -> [f64; 6] {
    [s[0][0], s[1][1], s[2][2], s[0][1], s[1][2], s[2][0]]
}

/// The files a run writes into its output directory, and their names while it runs.
const OUTPUTS: [&str; 3] = ["history.csv", "summary.json", "vtk"];
const PARTIALS: [&str; 3] = [
    ".history.csv.partial",
    ".summary.json.partial",
    ".vtk.partial",
];

/// Removes `names` (files or directories) from `dir`, what is not there ignored.
fn remove_all(dir: &Path, names: &[&str]) {
    for n in names {
        let p = dir.join(n);
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
}

/// Runs `scene` on `device`. With `output`, writes `history.csv` (time, energies, contact
/// force, balance error every `output_every` increments) and `summary.json` there; both are
/// written to temporary names and renamed only when the run succeeded. A run into a directory
/// first removes what an earlier run wrote there, and a failed run removes its partial files:
/// a failed run leaves nothing that looks valid, and no earlier run's files pass for its own.
pub fn run(scene: &Scene, device: &Device, output: Option<&Path>) -> Result<Summary> {
    run_with_progress(scene, device, output, &mut |_| {})
}

/// Where a run is: called after every increment of [`run_with_progress`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Increments taken.
    pub increment: u64,
    /// Increments the whole run will take at the present increment (taken plus what is left
    /// of the time over the present increment).
    pub estimated: u64,
    /// Time reached.
    pub time: f64,
    /// The run's end time.
    pub end_time: f64,
}

/// The number of increments a run of `duration` takes at the increment `dt`, saturating.
fn increments_for(duration: f64, dt: f64) -> u64 {
    let n = (duration / dt).ceil();
    if n.is_finite() && n < u64::MAX as f64 {
        n.max(0.0) as u64
    } else {
        u64::MAX
    }
}

/// [`run`], calling `progress` after every increment (a progress bar, a log line every so
/// often, or nothing).
pub fn run_with_progress(
    scene: &Scene,
    device: &Device,
    output: Option<&Path>,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Summary> {
    clean_run(output, || run::run_into(scene, device, output, progress))
}

/// `run` into `output`: first what an earlier run wrote there is removed, and when `run` fails
/// its partial files are (see [`run`]).
fn clean_run(output: Option<&Path>, run: impl FnOnce() -> Result<Summary>) -> Result<Summary> {
    if let Some(dir) = output.filter(|d| d.is_dir()) {
        remove_all(dir, &OUTPUTS);
        remove_all(dir, &PARTIALS);
    }
    let result = run();
    if let (Err(_), Some(dir)) = (&result, output.filter(|d| d.is_dir())) {
        remove_all(dir, &PARTIALS);
    }
    result
}

impl Scene {
    /// Reads and parses the scene file at `path`; mesh files are then relative to its
    /// directory. An Abaqus deck (`.inp`) is read by [`Scene::from_inp`]. Errors name the
    /// file, and the key or line.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("inp"))
        {
            return Self::from_inp(path);
        }
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
}

/// What a run built, in words: elements by kind, rigid bodies, each contact pair.
/// The global search's structure of each meshed pair's passes, one line per pair (the
/// scene summary's `built`).
fn search_structures(
    model: &crate::model::Model,
    contact: &crate::contact::Contact,
) -> Vec<String> {
    use crate::model::SearchStructure;
    (0..model.pairs().len())
        .filter_map(|k| {
            let passes = contact.search_structures(crate::model::PairId(k)).ok()?;
            let names: Vec<&str> = passes
                .iter()
                .map(|s| match s {
                    SearchStructure::Buckets => "buckets",
                    _ => "tree",
                })
                .collect();
            Some(format!(
                "pair {k}: global search by {}",
                names.join(" and ")
            ))
        })
        .collect()
}

fn built_list(scene: &Scene, solver: &Solver, slaves: &[Vec<u32>]) -> Vec<String> {
    let mut list = Vec::new();
    let mut kinds = BTreeMap::<&str, usize>::new();
    for e in &solver.elements {
        *kinds
            .entry(match e {
                Element::Bar { .. } => "bar",
                Element::Tri3 { hoop: Some(_), .. } => "axisymmetric triangle",
                Element::Tri3 { .. } => "plane-strain triangle",
                Element::Tet4 { .. } => "tetrahedron",
                Element::Hex8(h) => match h.integration {
                    Integration::Selective => "hexahedron (C3D8)",
                    Integration::Reduced => "reduced hexahedron (C3D8R)",
                },
            })
            .or_default() += 1;
    }
    for (k, n) in &kinds {
        list.push(format!("{n} {k} elements"));
    }
    if !solver.bodies.is_empty() {
        list.push(format!("{} rigid bodies", solver.bodies.len()));
    }
    for (i, (c, p)) in scene.contact.iter().zip(slaves).enumerate() {
        list.push(format!(
            "contact {i}: {} slave nodes of {} against {}, {}{}{}{}",
            p.len(),
            c.slave,
            c.master,
            c.enforce.as_deref().unwrap_or("penalty"),
            match (c.friction > 0.0, c.enforce.as_deref()) {
                (true, _) => ", friction",
                (false, Some("kinematic")) => ", frictionless",
                (false, _) => ", frictionless (friction compiled out of the penalty kernel)",
            },
            if c.balanced.is_some() {
                ", balanced"
            } else {
                ""
            },
            match c.sliding.as_deref() {
                Some(s) => format!(", {s} sliding"),
                None => String::new(),
            }
        ));
    }
    list
}

/// history.csv's header: the energies and force, then each part's and rigid body's mean
/// displacement and velocity.
fn history_header(parts: &[PartNodes], bodies: &[(String, usize)]) -> String {
    let mut header =
        "time,kinetic,internal,external_work,contact_work,balance_error,contact_force".to_string();
    for name in parts
        .iter()
        .map(|p| &p.name)
        .chain(bodies.iter().map(|b| &b.0))
    {
        for q in ["ux", "uy", "uz", "vx", "vy", "vz"] {
            header.push_str(&format!(",{name}.{q}"));
        }
    }
    header
}

/// A history.csv under its partial name in `dir`, its header written (see
/// [`history_header`]).
fn open_history(
    dir: &Path,
    parts: &[PartNodes],
    bodies: &[(String, usize)],
) -> std::io::Result<std::io::BufWriter<std::fs::File>> {
    std::fs::create_dir_all(dir)?;
    let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join(".history.csv.partial"))?);
    writeln!(f, "{}", history_header(parts, bodies))?;
    Ok(f)
}

/// The end of a run's output: the history flushed, summary.json written, both renamed to
/// their final names.
fn finish_outputs(
    dir: &Path,
    history: std::io::BufWriter<std::fs::File>,
    summary: &Summary,
) -> std::io::Result<()> {
    history.into_inner().map_err(|e| e.into_error())?;
    let json = serde_json::to_string_pretty(summary).map_err(std::io::Error::other)?;
    std::fs::write(dir.join(".summary.json.partial"), json)?;
    std::fs::rename(dir.join(".history.csv.partial"), dir.join("history.csv"))?;
    std::fs::rename(dir.join(".summary.json.partial"), dir.join("summary.json"))
}

/// The output error of a run.
fn output_error(e: std::io::Error) -> Error {
    Error::BadParameter {
        name: "output",
        value: e.to_string(),
        expected: "a writable directory",
    }
}
