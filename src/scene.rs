//! Scene files (TOML): generated parts, contact pairs and run controls, run by the explicit
//! solver with abut's contact; `abut run SCENE` writes a CSV history and a JSON summary.
//!
//! ```toml
//! title = "two blocks"
//! [run]
//! end_time = 30.0          # model time units
//! safety = 0.9             # on the elements' stable increment (default 0.9)
//! gravity = [0, 0, -9.81]  # default none
//! output_every = 10        # history rows every this many increments (default 1)
//! [[material]]
//! name = "rubber"
//! young = 1.0
//! poisson = 0.0
//! density = 1.0
//! [[part]]
//! name = "left"
//! shape = "block"          # tetrahedral block, or "plate": a rigid, fixed plate of quads
//! material = "rubber"
//! origin = [0, 0, 0]
//! size = [10, 2, 2]
//! divisions = [40, 1, 1]
//! velocity = [0.1, 0, 0]
//! [[contact]]
//! slave = "left"           # part whose face nodes are the slave nodes
//! slave_face = "x+"        # x-, x+, y-, y+, z-, z+ of the part's box
//! master = "right"         # part whose face is the master surface
//! master_face = "x-"
//! enforce = "kinematic"    # or "penalty" (default)
//! friction = 0.0           # Coulomb coefficient (penalty only)
//! ```
//!
//! Errors name the key and, for syntax and type errors, the line (toml's own messages).

use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::contact::Contact;
use crate::device::Device;

use crate::error::{Error, Result};
use crate::explicit::{Element, Material, Solver};
use crate::mesh::{block_tets, plate_quads};
use crate::model::{Enforce, Friction, Kinematic, Model, Pair, Penalty, Surface};

/// A scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene is.
    pub title: String,
    /// Run controls.
    pub run: RunSpec,
    /// Materials, by name.
    #[serde(default)]
    pub material: Vec<MaterialSpec>,
    /// Parts.
    pub part: Vec<PartSpec>,
    /// Contact pairs.
    #[serde(default)]
    pub contact: Vec<ContactSpec>,
}

/// Run controls.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Time to run to.
    pub end_time: f64,
    /// Safety factor on the elements' stable increment.
    #[serde(default = "default_safety")]
    pub safety: f64,
    /// Gravity.
    #[serde(default)]
    pub gravity: [f64; 3],
    /// History rows every this many increments.
    #[serde(default = "default_every")]
    pub output_every: usize,
}

fn default_safety() -> f64 {
    0.9
}
fn default_every() -> usize {
    1
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

/// A generated part.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Name contacts refer to.
    pub name: String,
    /// "block" (tetrahedra) or "plate" (rigid quads in the x–y plane, normal +z, fixed).
    pub shape: String,
    /// Material (blocks).
    #[serde(default)]
    pub material: Option<String>,
    /// Lower corner.
    pub origin: [f64; 3],
    /// Box size (a plate's z size is ignored).
    pub size: [f64; 3],
    /// Divisions per axis (a plate's z ignored).
    pub divisions: [usize; 3],
    /// Initial velocity.
    #[serde(default)]
    pub velocity: [f64; 3],
}

/// A contact pair between faces of two parts.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Part whose face nodes are the slaves.
    pub slave: String,
    /// Face of the slave part's box: x-, x+, y-, y+, z-, z+.
    pub slave_face: String,
    /// Part whose face is the master surface.
    pub master: String,
    /// Face of the master part's box.
    pub master_face: String,
    /// "penalty" (default) or "kinematic".
    #[serde(default)]
    pub enforce: Option<String>,
    /// Coulomb coefficient (penalty).
    #[serde(default)]
    pub friction: f64,
}

impl Scene {
    /// Parses a scene from TOML text; errors name the key or line.
    pub fn parse(text: &str) -> Result<Self> {
        let scene: Scene = toml::from_str(text).map_err(|e| Error::BadParameter {
            name: "scene file",
            value: e.to_string(),
            expected: "a valid scene (see abut::scene)",
        })?;
        scene.check()?;
        Ok(scene)
    }

    fn check(&self) -> Result<()> {
        let bad = |name: &'static str, value: String, expected: &'static str| {
            Err(Error::BadParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.run.end_time.is_finite() && self.run.end_time > 0.0) {
            return bad(
                "run.end_time",
                self.run.end_time.to_string(),
                "must be finite and positive",
            );
        }
        if !(self.run.safety > 0.0 && self.run.safety <= 1.0) {
            return bad(
                "run.safety",
                self.run.safety.to_string(),
                "must lie in (0, 1]",
            );
        }
        for p in &self.part {
            if p.shape != "block" && p.shape != "plate" {
                return bad(
                    "part.shape",
                    format!("{} (part {})", p.shape, p.name),
                    "must be \"block\" or \"plate\"",
                );
            }
            if p.divisions
                .iter()
                .take(if p.shape == "plate" { 2 } else { 3 })
                .any(|&d| d == 0)
                || p.size
                    .iter()
                    .take(if p.shape == "plate" { 2 } else { 3 })
                    .any(|&s| !(s > 0.0))
            {
                return bad(
                    "part.size / part.divisions",
                    format!("part {}", p.name),
                    "must be positive",
                );
            }
            if p.shape == "block"
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
        }
        for c in &self.contact {
            for (key, name) in [("contact.slave", &c.slave), ("contact.master", &c.master)] {
                if !self.part.iter().any(|p| &p.name == name) {
                    return bad(key, name.clone(), "must name a [[part]]");
                }
            }
            for (key, f) in [
                ("contact.slave_face", &c.slave_face),
                ("contact.master_face", &c.master_face),
            ] {
                if !["x-", "x+", "y-", "y+", "z-", "z+"].contains(&f.as_str()) {
                    return bad(key, f.clone(), "must be one of x-, x+, y-, y+, z-, z+");
                }
            }
            if !matches!(
                c.enforce.as_deref(),
                None | Some("penalty") | Some("kinematic")
            ) {
                return bad(
                    "contact.enforce",
                    format!("{:?}", c.enforce),
                    "must be \"penalty\" or \"kinematic\"",
                );
            }
        }
        Ok(())
    }

    /// Builds the solver and the contact model.
    pub fn build(&self) -> Result<(Solver, Model)> {
        let mut x: Vec<[f64; 3]> = Vec::new();
        let mut elements = Vec::new();
        let mut point = Vec::new();
        let mut fixed = Vec::new();
        let mut velocity = Vec::new();
        // per part: node range and its box faces' quads and nodes
        let mut parts: Vec<(String, usize, Vec<[f64; 3]>, [usize; 3], [f64; 3], [f64; 3])> =
            Vec::new();
        for p in &self.part {
            let base = x.len();
            if p.shape == "block" {
                let m = self
                    .material
                    .iter()
                    .find(|m| Some(&m.name) == p.material.as_ref())
                    .expect("checked");
                let mat = Material {
                    young: m.young,
                    poisson: m.poisson,
                    density: m.density,
                };
                let mesh = block_tets(p.divisions, p.size, p.origin);
                let all: Vec<[f64; 3]> = mesh.positions.clone();
                x.extend(mesh.positions.iter().copied());
                for t in &mesh.facets {
                    let tet = t.map(|n| n + base as u32);
                    elements.push(Element::tet4(tet, &x, mat).ok_or(Error::BadParameter {
                        name: "part",
                        value: p.name.clone(),
                        expected: "a block with positive volumes",
                    })?);
                }
                point.extend(vec![0.0; all.len()]);
                fixed.extend(vec![[false; 3]; all.len()]);
                velocity.extend(vec![p.velocity; all.len()]);
                parts.push((p.name.clone(), base, all, p.divisions, p.origin, p.size));
            } else {
                let mesh = plate_quads(
                    p.divisions[0],
                    p.divisions[1],
                    p.size[0],
                    p.size[1],
                    0.0,
                    0,
                    &|_, _| 0.0,
                );
                let pos: Vec<[f64; 3]> = mesh
                    .positions
                    .iter()
                    .map(|q| [q[0] + p.origin[0], q[1] + p.origin[1], p.origin[2]])
                    .collect();
                x.extend(pos.iter().copied());
                point.extend(vec![1e12; pos.len()]);
                fixed.extend(vec![[true; 3]; pos.len()]);
                velocity.extend(vec![[0.0; 3]; pos.len()]);
                parts.push((
                    p.name.clone(),
                    base,
                    pos,
                    [p.divisions[0], p.divisions[1], 0],
                    p.origin,
                    [p.size[0], p.size[1], 0.0],
                ));
            }
        }
        let mut solver = Solver::new(x.clone(), elements, &point)?;
        solver.fixed = fixed;
        solver.v = velocity;
        solver.gravity = self.run.gravity;
        solver.safety = self.run.safety;
        let mut model = Model::new_3d();
        model.add_nodes(&x, &solver.mass)?;
        for c in &self.contact {
            let sp = parts.iter().find(|p| p.0 == c.slave).expect("checked");
            let mp = parts.iter().find(|p| p.0 == c.master).expect("checked");
            let slaves = face_nodes(sp, &c.slave_face);
            let set = model.add_node_set(&slaves)?;
            let quads = face_quads(mp, &c.master_face)?;
            let surf = model.add_surface(Surface::quads(&quads))?;
            let enforce = match c.enforce.as_deref() {
                Some("kinematic") => Enforce::Kinematic(Kinematic::default()),
                _ => Enforce::Penalty(Penalty::default()),
            };
            let friction = if c.friction > 0.0 {
                Friction::coulomb(c.friction)
            } else {
                Friction::Frictionless
            };
            model.add_pair(Pair::new(set, surf).enforce(enforce).friction(friction))?;
        }
        Ok((solver, model))
    }
}

type PartGeom = (String, usize, Vec<[f64; 3]>, [usize; 3], [f64; 3], [f64; 3]);

/// Axis and side of a face name.
fn face_axis(face: &str) -> (usize, bool) {
    let axis = match &face[..1] {
        "x" => 0,
        "y" => 1,
        _ => 2,
    };
    (axis, face.ends_with('+'))
}

/// The nodes of a part lying on a face of its box.
fn face_nodes(p: &PartGeom, face: &str) -> Vec<u32> {
    let (axis, plus) = face_axis(face);
    let target = p.4[axis] + if plus { p.5[axis] } else { 0.0 };
    let tol = 1e-9 * (1.0 + p.5.iter().fold(0.0f64, |a, b| a.max(*b)));
    p.2.iter()
        .enumerate()
        .filter(|(_, q)| (q[axis] - target).abs() <= tol)
        .map(|(i, _)| (p.1 + i) as u32)
        .collect()
}

/// The quads of a face of a part's box, outward normals (a plate has only "z+").
fn face_quads(p: &PartGeom, face: &str) -> Result<Vec<[u32; 4]>> {
    let (axis, plus) = face_axis(face);
    let n = p.3;
    if n[2] == 0 {
        if face != "z+" {
            return Err(Error::BadParameter {
                name: "contact.master_face",
                value: format!("{face} (plate {})", p.0),
                expected: "a plate's only face is z+",
            });
        }
        let mut q = Vec::new();
        for j in 0..n[1] {
            for i in 0..n[0] {
                let id = |i: usize, j: usize| (p.1 + j * (n[0] + 1) + i) as u32;
                q.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        return Ok(q);
    }
    let id = |i: usize, j: usize, k: usize| {
        (p.1 + k * (n[1] + 1) * (n[0] + 1) + j * (n[0] + 1) + i) as u32
    };
    let (u, v) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let fixed = if plus { n[axis] } else { 0 };
    let at = |a: usize, b: usize| {
        let mut c = [0usize; 3];
        c[axis] = fixed;
        c[u] = a;
        c[v] = b;
        id(c[0], c[1], c[2])
    };
    let mut q = Vec::new();
    for b in 0..n[v] {
        for a in 0..n[u] {
            let quad = [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
            // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis
            q.push(if plus {
                quad
            } else {
                [quad[0], quad[3], quad[2], quad[1]]
            });
        }
    }
    Ok(q)
}

/// What a scene run measured (also written as summary.json).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The scene's title.
    pub title: String,
    /// Where it ran.
    pub device: String,
    /// Increments taken.
    pub increments: usize,
    /// Time reached.
    pub end_time: f64,
    /// Wall-clock seconds per increment (all increments).
    pub seconds_per_increment: f64,
    /// First time a contact force acted (NaN if none).
    pub contact_start: f64,
    /// Last time a contact force acted.
    pub contact_end: f64,
    /// Largest total contact force on the slave nodes.
    pub peak_force: f64,
    /// Impulse over the contact duration divided by it.
    pub mean_force: f64,
    /// Impulse of the contact force on the slave nodes.
    pub impulse: f64,
    /// Largest overclosure met (before kinematic corrections; penalty penetration).
    pub max_penetration: f64,
    /// Largest energy balance error over the run.
    pub energy_balance_error: f64,
    /// Final kinetic energy.
    pub kinetic: f64,
    /// Final strain energy.
    pub internal: f64,
}

/// Runs `scene` on `device`. With `output`, writes `history.csv` (time, energies, contact
/// force, balance error every `output_every` increments) and `summary.json` there; both are
/// written to temporary names and renamed only when the run succeeded, so a failed run leaves
/// nothing that looks valid.
pub fn run(scene: &Scene, device: &Device, output: Option<&Path>) -> Result<Summary> {
    let (mut solver, model) = scene.build()?;
    let mut contact = if model.pairs().is_empty() {
        None
    } else {
        Some(Contact::new(device, &model)?)
    };
    let slaves: Vec<u32> = model
        .pairs()
        .iter()
        .flat_map(|p| {
            model
                .node_set(p.slave)
                .map(|s| s.to_vec())
                .unwrap_or_default()
        })
        .collect();
    if let Some(c) = contact.as_mut() {
        c.request_outputs(true);
    }
    let io = |e: std::io::Error| Error::BadParameter {
        name: "output",
        value: e.to_string(),
        expected: "a writable directory",
    };
    let mut history = match output {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(io)?;
            let mut f = std::io::BufWriter::new(
                std::fs::File::create(dir.join(".history.csv.partial")).map_err(io)?,
            );
            writeln!(
                f,
                "time,kinetic,internal,external_work,contact_work,balance_error,contact_force"
            )
            .map_err(io)?;
            Some(f)
        }
        None => None,
    };
    let element_dt = solver.stable_increment();
    let mut dt = element_dt;
    let (mut start, mut end, mut peak, mut impulse, mut pen, mut worst) =
        (f64::NAN, f64::NAN, 0.0f64, 0.0, 0.0f64, 0.0f64);
    let t0 = Instant::now();
    let mut k = 0;
    while solver.time < scene.run.end_time {
        let step = dt.min(scene.run.end_time - solver.time).max(1e-15);
        solver.step(step, contact.as_mut())?;
        k += 1;
        if let Some(c) = contact.as_ref() {
            if c.has_penalty_pairs() {
                // the increment is the smaller of the elements' and the contact's limits
                dt = element_dt.min(0.9 * c.report().stable_dt);
                for (_, o) in c.outputs() {
                    for g in &o.copen {
                        if g.is_finite() {
                            pen = pen.max(-g);
                        }
                    }
                }
            }
        }
        let force: f64 = {
            let mut f = [0.0; 3];
            for &s in &slaves {
                for a in 0..3 {
                    f[a] += solver.contact_force[s as usize][a];
                }
            }
            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
        };
        if force > 0.0 {
            if start.is_nan() {
                start = solver.time - step;
            }
            end = solver.time;
            impulse += force * step;
            peak = peak.max(force);
        }
        worst = worst.max(solver.balance_error());
        if let Some(f) = history.as_mut() {
            if k % scene.run.output_every.max(1) == 0 {
                let e = &solver.energy;
                writeln!(
                    f,
                    "{},{},{},{},{},{},{}",
                    solver.time,
                    e.kinetic,
                    e.internal,
                    e.external_work,
                    e.contact_work,
                    solver.balance_error(),
                    force
                )
                .map_err(io)?;
            }
        }
    }
    let summary = Summary {
        title: scene.title.clone(),
        device: device.to_string(),
        increments: k,
        end_time: solver.time,
        seconds_per_increment: t0.elapsed().as_secs_f64() / k.max(1) as f64,
        contact_start: start,
        contact_end: end,
        peak_force: peak,
        mean_force: if end > start {
            impulse / (end - start)
        } else {
            0.0
        },
        impulse,
        max_penetration: pen,
        energy_balance_error: worst,
        kinetic: solver.energy.kinetic,
        internal: solver.energy.internal,
    };
    if let (Some(dir), Some(mut f)) = (output, history) {
        f.flush().map_err(io)?;
        drop(f);
        let json = serde_json::to_string_pretty(&summary).map_err(|e| Error::BadParameter {
            name: "summary",
            value: e.to_string(),
            expected: "serialisable",
        })?;
        std::fs::write(dir.join(".summary.json.partial"), json).map_err(io)?;
        std::fs::rename(dir.join(".history.csv.partial"), dir.join("history.csv")).map_err(io)?;
        std::fs::rename(dir.join(".summary.json.partial"), dir.join("summary.json")).map_err(io)?;
    }
    Ok(summary)
}
