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
//! ```
//!
//! Errors name the key and the `[[section]]` entry; from a file (`Scene::load`) also the file
//! and line. A few checks need the built geometry (a master face with no facets) and come from
//! `run`, naming the key and part but no line.

mod build;
mod check;
#[cfg(feature = "mpi")]
mod distributed;
mod spec;
mod summary;

pub use build::Built;
#[cfg(feature = "mpi")]
pub use distributed::run_distributed;
pub use spec::{
    BoundarySpec, ContactSpec, MaterialSpec, PartSpec, RigidSpec, RunSpec, Scene,
    DEFAULT_BULK_VISCOSITY, DEFAULT_BULK_VISCOSITY_QUADRATIC,
};

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::contact::Contact;
use crate::device::{Device, Traffic};
use crate::error::{Error, Result};
use crate::explicit::{Element, Solver};
use build::PartNodes;
pub use summary::{BodySummary, ContactNode, CurveSample, PartSummary, RankSummary, Summary};

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
    clean_run(output, || run_into(scene, device, output, progress))
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

/// What a run built, in words: elements by kind, rigid bodies, each contact pair.
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

/// What the contact force history (time of each increment's middle, total force) says: first
/// and last time with force, the half-plateau edges, impulse, plateau and mean force.
struct ForceStats {
    start: f64,
    end: f64,
    impact: f64,
    release: f64,
    impulse: f64,
    plateau: f64,
    mean: f64,
}

fn force_stats(forces: &[(f64, f64)], dt: f64) -> ForceStats {
    let first = forces.iter().position(|h| h.1 > 0.0);
    let last = forces.iter().rposition(|h| h.1 > 0.0);
    let (impact, release, impulse, plateau) = half_plateau_edges(forces);
    ForceStats {
        start: first.map_or(f64::NAN, |i| forces[i].0 - 0.5 * dt),
        end: last.map_or(f64::NAN, |i| forces[i].0 + 0.5 * dt),
        impact,
        release,
        impulse,
        plateau,
        mean: if release > impact {
            let inside: f64 = forces
                .windows(2)
                .filter(|w| w[1].0 > impact && w[0].0 < release)
                .map(|w| w[1].1 * (w[1].0 - w[0].0))
                .sum();
            inside / (release - impact)
        } else {
            0.0
        },
    }
}

/// The warning of a fixed `run_dt` that exceeded the penalty contact's stable increment by up
/// to `over_ratio`, from `over_from`.
fn over_increment_warning(run_dt: f64, over_ratio: f64, over_from: f64, safety: f64) -> String {
    format!(
        "run.dt = {run_dt:e} exceeds the penalty contact's stable increment (by up to \
         {over_ratio:.3}×, from t = {over_from:e}): central differences are unstable there and \
         the contact results cannot be trusted. Lower run.dt below it — with the automatic \
         stiffness, which follows the first increment (k ∝ 1/run.dt²), multiply the contact's \
         penalty_scale by {:.3e} or less instead (ω·Δt ≤ 1, run.contact_safety) — or, in a \
         scene with elements, leave run.dt out and the increment follows both limits",
        (safety / over_ratio).powi(2)
    )
}

/// [`run`] itself: the outputs written under their partial names, renamed at the end.
fn run_into(
    scene: &Scene,
    device: &Device,
    output: Option<&Path>,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Summary> {
    let built = scene.build()?;
    let (mut solver, model) = (built.solver, built.model);
    let x0 = solver.x.clone();
    let has_contact = !model.pairs().is_empty() || !model.rigid_pairs().is_empty();
    let mut contact = if has_contact {
        Some(Contact::new(device, &model)?)
    } else {
        None
    };
    let mut slaves: Vec<u32> = built.slaves.iter().flatten().copied().collect();
    slaves.sort_unstable();
    slaves.dedup();
    let built_list = built_list(scene, &solver, &built.slaves);
    let io = output_error;
    let mut history = match output {
        Some(dir) => Some(open_history(dir, &built.parts, &built.bodies).map_err(io)?),
        None => None,
    };
    // VTK frames go to a hidden directory renamed only when the run succeeded
    let mut series = match output {
        Some(dir) if scene.run.vtk_every > 0 && contact.is_some() => {
            let partial = dir.join(".vtk.partial");
            let _ = std::fs::remove_dir_all(&partial);
            Some(crate::io::vtk::Series::new(&partial, "contact")?)
        }
        _ => None,
    };
    let element_dt = solver.stable_increment();
    let mut dt = scene.run.dt.unwrap_or(element_dt);
    if !dt.is_finite() {
        return Err(Error::BadParameter {
            name: "run.dt",
            value: "none".into(),
            expected: "a scene without elements needs a fixed increment",
        });
    }
    let (mut pen, mut contact_dt) = (0.0f64, f64::INFINITY);
    // the balance error is judged against the largest energy of the run: early on, when every
    // energy is still near zero, the first contact's round-off would read as a large fraction
    let (mut drift, mut scale) = (0.0f64, 0.0f64);
    let mut forces: Vec<(f64, f64)> = Vec::new();
    let mut curve: Vec<CurveSample> = Vec::new();
    let mut final_force = [0.0; 3];
    let mut peak = 0.0f64;
    let bodies0: Vec<[f64; 3]> = solver.bodies.iter().map(|b| b.state.position).collect();
    let mut at_peak = bodies0.clone();
    let mut first_seconds = 0.0;
    let mut traffic0: Option<Traffic> = None;
    let mut t_steady = Instant::now();
    let mut k = 0;
    let mut adjusted = None;
    if let (Some(c), true) = (contact.as_mut(), scene.run.adjust_overclosure) {
        let bodies = solver.body_states();
        let first = dt.min(scene.run.end_time - solver.time);
        adjusted = Some(c.adjust_initial_overclosure(&mut solver.x, &bodies, first)?);
    }
    // where penalty contact lowered the increment below the elements' limit: the smallest ratio
    // and the first time
    let (mut lowest_ratio, mut lowered_from) = (1.0f64, f64::NAN);
    // a fixed run.dt above the penalty contact's stable increment: the largest ratio and when
    // it first happened
    let (mut over_ratio, mut over_from) = (1.0f64, f64::NAN);
    while solver.time < scene.run.end_time * (1.0 - 1e-12) {
        let step = dt.min(scene.run.end_time - solver.time);
        // (round-off of the combined formula aside)
        if scene.run.dt.is_none() && dt < element_dt * (1.0 - 1e-12) {
            lowest_ratio = lowest_ratio.min(dt / element_dt);
            if lowered_from.is_nan() && dt < 0.999 * element_dt {
                lowered_from = solver.time;
            }
        }
        // the output variables only when a VTK frame or the final pressures need them
        if let Some(c) = contact.as_mut() {
            let last = solver.time + step >= scene.run.end_time * (1.0 - 1e-12);
            let frame = series.is_some() && (k + 1) % scene.run.vtk_every == 0;
            c.request_outputs(last || frame);
        }
        let t_step = Instant::now();
        let t_start = solver.time;
        solver.step(step, contact.as_mut())?;
        k += 1;
        progress(&Progress {
            increment: k as u64,
            estimated: (k as u64)
                .saturating_add(increments_for(scene.run.end_time - solver.time, dt)),
            time: solver.time,
            end_time: scene.run.end_time,
        });
        if let Some(c) = contact.as_ref() {
            let (p, q) = (c.report(), c.kinematic_report());
            let fast = p.fast_nodes + q.fast_nodes;
            let fastest = [p.fastest, q.fastest]
                .into_iter()
                .flatten()
                .max_by(|a, b| (a.distance / a.radius).total_cmp(&(b.distance / b.radius)));
            if let Some(f) = fastest {
                return Err(Error::Tunnelling {
                    increment: k as u64,
                    time: t_start,
                    node: f.node,
                    pair: f.pair.0,
                    distance: f.distance,
                    radius: f.radius,
                    more: format!(
                        "{}{}",
                        if fast > 1 {
                            format!(" ({} more nodes move that far)", fast - 1)
                        } else {
                            String::new()
                        },
                        // a node launched by a resolved overclosure is a blow-up, not a fast body
                        if k > 1 {
                            solver.blow_up_hint()
                        } else {
                            String::new()
                        }
                    ),
                });
            }
        }
        if k == 1 {
            first_seconds = t_step.elapsed().as_secs_f64();
            traffic0 = device.traffic();
            t_steady = Instant::now();
        }
        if let Some(c) = contact.as_ref() {
            if c.has_penalty_pairs() {
                let reported = c.report().stable_dt;
                contact_dt = contact_dt.min(reported);
                if scene.run.dt.is_some() && step > reported * (1.0 + 1e-9) {
                    if over_from.is_nan() {
                        over_from = t_start;
                    }
                    over_ratio = over_ratio.max(step / reported);
                }
                // a node carries its elements' and its contact springs' stiffness together:
                // the frequencies add in square (1/dt² = 1/dt_e² + 1/(safety·dt_c)², the same
                // safety on both); and a spring that switches on and off must stay at
                // ω·dt ≤ 2·contact_safety, where central differences do not pump energy
                if scene.run.dt.is_none() {
                    dt = crate::combined_increment(
                        element_dt,
                        reported,
                        scene.run.safety,
                        scene.run.contact_safety,
                    );
                }
                pen = pen.max(c.report().max_overclosure);
            }
            if c.has_kinematic_pairs() {
                pen = pen.max(c.kinematic_report().max_overclosure);
            }
        }
        let force: f64 = {
            let mut f = [0.0; 3];
            for &s in &slaves {
                for a in 0..3 {
                    f[a] += solver.contact_force[s as usize][a];
                }
            }
            final_force = f;
            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
        };
        if force > peak {
            peak = force;
            at_peak = solver.bodies.iter().map(|b| b.state.position).collect();
        }
        forces.push((solver.time - 0.5 * step, force));
        if k % scene.run.output_every.max(1) == 0 {
            curve.push(CurveSample {
                time: solver.time,
                force: final_force,
                body_displacement: solver
                    .bodies
                    .iter()
                    .zip(&bodies0)
                    .map(|(b, p0)| std::array::from_fn(|a| b.state.position[a] - p0[a]))
                    .collect(),
            });
        }
        drift = drift.max(solver.energy_drift());
        scale = scale.max(solver.energy_scale());
        if !solver.energy.balance().is_finite() {
            return Err(Error::BadParameter {
                name: "run",
                value: format!("energy not finite at t = {}", solver.time),
                expected: "a stable run (reduce run.dt or the penalty scale)",
            });
        }
        if let (Some(s), Some(c)) = (series.as_mut(), contact.as_ref()) {
            if k % scene.run.vtk_every == 0 {
                s.add(
                    solver.time,
                    &crate::io::vtk::Frame::from_contact(&model, c, &solver.x)?,
                )?;
            }
        }
        if let Some(f) = history.as_mut() {
            if k % scene.run.output_every.max(1) == 0 {
                let e = &solver.energy;
                let mut row = format!(
                    "{},{},{},{},{},{},{}",
                    solver.time,
                    e.kinetic,
                    e.internal,
                    e.external_work,
                    e.contact_work,
                    solver.balance_error(),
                    force
                );
                // each part's mean displacement and velocity (mass-weighted), each rigid body's
                for p in &built.parts {
                    let (u, v) = part_motion(&solver, &x0, p.base..p.base + p.count);
                    for c in u.iter().chain(&v) {
                        row.push_str(&format!(",{c}"));
                    }
                }
                for (_, k) in &built.bodies {
                    let b = &solver.bodies[*k].state;
                    for a in 0..3 {
                        row.push_str(&format!(",{}", b.position[a] - bodies0[*k][a]));
                    }
                    for a in 0..3 {
                        row.push_str(&format!(",{}", b.velocity[a]));
                    }
                }
                writeln!(f, "{row}").map_err(io)?;
            }
        }
    }
    let steady = k.saturating_sub(1).max(1) as f64;
    let seconds = t_steady.elapsed().as_secs_f64() / steady;
    let traffic = match (device.traffic(), traffic0) {
        (Some(now), Some(then)) => now.since(&then),
        _ => Traffic::default(),
    };
    let stats = force_stats(&forces, dt);
    let mut parts = Vec::new();
    let mut el = 0;
    for p in &built.parts {
        let nodes = p.base..p.base + p.count;
        let m: f64 = nodes.clone().map(|n| solver.mass[n]).sum();
        let mean = |f: &dyn Fn(usize) -> [f64; 3]| {
            let mut s = [0.0; 3];
            for n in nodes.clone() {
                let v = f(n);
                for a in 0..3 {
                    s[a] += solver.mass[n] * v[a] / m;
                }
            }
            s
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 6], [f64::NEG_INFINITY; 6]);
        for k in el..el + p.elements {
            let s = stress6(solver.stress(k));
            for c in 0..6 {
                lo[c] = lo[c].min(s[c]);
                hi[c] = hi[c].max(s[c]);
            }
        }
        el += p.elements;
        if p.elements == 0 {
            (lo, hi) = ([0.0; 6], [0.0; 6]);
        }
        parts.push(PartSummary {
            name: p.name.clone(),
            displacement: mean(&|n| [0, 1, 2].map(|a| solver.x[n][a] - x0[n][a])),
            velocity: mean(&|n| solver.v[n]),
            stress_min: lo,
            stress_max: hi,
        });
    }
    let bodies = built
        .bodies
        .iter()
        .map(|(name, k)| BodySummary {
            name: name.clone(),
            position: solver.bodies[*k].state.position,
            velocity: solver.bodies[*k].state.velocity,
            displacement_at_peak_force: [0, 1, 2].map(|a| at_peak[*k][a] - bodies0[*k][a]),
        })
        .collect();
    let mut contact_nodes = Vec::new();
    let mut friction = 0.0;
    if let Some(c) = contact.as_ref() {
        let outs: Vec<(usize, &crate::contact::PairOutput)> = c
            .outputs()
            .into_iter()
            .map(|(id, o)| (id.0, o))
            .chain(
                c.rigid_outputs()
                    .into_iter()
                    .map(|(id, o)| (model.pairs().len() + id.0, o)),
            )
            .collect();
        for (pair, o) in outs {
            friction += o.frictional_dissipation;
            for (i, &n) in o.slaves.iter().enumerate() {
                let p = o.cpress.get(i).copied().unwrap_or(0.0);
                if p > 0.0 {
                    let f = o
                        .force
                        .get(i)
                        .map_or(0.0, |f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
                    contact_nodes.push(ContactNode {
                        contact: pair,
                        node: n,
                        position: solver.x[n as usize],
                        pressure: p,
                        force: f,
                    });
                }
            }
        }
    }
    let e = solver.energy;
    let (governing_limit, increment_note) = governing_limit(
        scene.run.dt.is_some(),
        contact_dt.is_finite(),
        lowest_ratio,
        lowered_from,
        stats.start,
        scene.run.contact_safety,
    );
    let anchoring = contact.as_ref().map(|c| c.anchoring()).unwrap_or_default();
    let mut warnings = scene.notes();
    if over_ratio > 1.0 {
        warnings.push(over_increment_warning(
            scene.run.dt.unwrap_or(f64::NAN),
            over_ratio,
            over_from,
            scene.run.contact_safety,
        ));
    }
    if let Some(a) = adjusted.filter(|a| !a.moved.is_empty()) {
        warnings.push(format!(
            "{} slave nodes started overclosed and were moved onto their masters strain-free \
             (run.adjust_overclosure), by up to {:e}",
            a.moved.len(),
            a.max_distance
        ));
    }
    for a in anchoring.iter().filter(|a| !a.unanchored.is_empty()) {
        let shown: Vec<String> = a.unanchored.iter().take(8).map(|n| n.to_string()).collect();
        warnings.push(format!(
            "contact pair {}: {} of {} slave nodes project onto no master facet and are not \
             constrained (small sliding anchors each slave once, at the start): nodes {}{}",
            a.pair.0,
            a.unanchored.len(),
            a.slaves,
            shown.join(", "),
            if a.unanchored.len() > shown.len() {
                ", …"
            } else {
                ""
            }
        ));
    }
    let summary = Summary {
        title: scene.title.clone(),
        anchored_slaves: anchoring.iter().map(|a| a.anchored).sum(),
        unanchored_slaves: anchoring
            .iter()
            .flat_map(|a| a.unanchored.iter().copied())
            .collect(),
        warnings,
        reference: scene.reference.clone(),
        device: device.to_string(),
        built: built_list,
        increments: k,
        end_time: solver.time,
        first_increment_seconds: first_seconds,
        seconds_per_increment: seconds,
        element_increment: element_dt,
        contact_increment: contact_dt,
        governing_limit,
        contact_lowered_increment: 1.0 - lowest_ratio,
        contact_limit_from: lowered_from,
        increment_note,
        contact_start: stats.start,
        contact_end: stats.end,
        impact_time: stats.impact,
        release_time: stats.release,
        peak_force: peak,
        plateau_force: stats.plateau,
        mean_force: stats.mean,
        impulse: stats.impulse,
        final_contact_force: final_force,
        max_penetration: pen,
        energy_balance_error: if scale > 0.0 { drift / scale } else { 0.0 },
        kinetic: e.kinetic,
        internal: e.internal,
        external_work: e.external_work,
        contact_work: e.contact_work,
        frictional_dissipation: friction,
        parts,
        bodies,
        contact_nodes,
        curve,
        dispatches_per_increment: traffic
            .dispatches
            .iter()
            .map(|(k, v)| (k.clone(), *v as f64 / steady))
            .collect(),
        uploaded_bytes_per_increment: traffic.uploaded_bytes as f64 / steady,
        read_back_bytes_per_increment: traffic.read_back_bytes as f64 / steady,
        global_searches: contact.as_ref().map_or(0, |c| c.global_searches()),
        ranks: Vec::new(),
    };
    if let (Some(dir), Some(f)) = (output, history) {
        finish_outputs(dir, f, &summary).map_err(io)?;
        if series.is_some() {
            let _ = std::fs::remove_dir_all(dir.join("vtk"));
            std::fs::rename(dir.join(".vtk.partial"), dir.join("vtk")).map_err(io)?;
        }
    }
    Ok(summary)
}

/// The mean displacement (from `x0`) and velocity of `nodes`, weighted by their masses (plain
/// means when the nodes carry no mass).
fn part_motion(
    solver: &crate::explicit::Solver,
    x0: &[[f64; 3]],
    nodes: std::ops::Range<usize>,
) -> ([f64; 3], [f64; 3]) {
    let total: f64 = nodes.clone().map(|n| solver.mass[n]).sum();
    let count = nodes.len().max(1) as f64;
    let (mut u, mut v) = ([0.0; 3], [0.0; 3]);
    for n in nodes {
        let w = if total > 0.0 {
            solver.mass[n] / total
        } else {
            1.0 / count
        };
        for a in 0..3 {
            u[a] += w * (solver.x[n][a] - x0[n][a]);
            v[a] += w * solver.v[n][a];
        }
    }
    (u, v)
}

/// The summary's account of the increment: its governing limit and a note in words.
fn governing_limit(
    fixed: bool,
    contact_limit: bool,
    lowest_ratio: f64,
    lowered_from: f64,
    contact_start: f64,
    safety: f64,
) -> (String, String) {
    if fixed {
        return (
            "fixed".into(),
            "the increment is fixed by run.dt; the stability limits are not applied".into(),
        );
    }
    if !contact_limit || lowered_from.is_nan() {
        let why = if contact_limit {
            "penalty contact's limit stayed far above it"
        } else {
            "no penalty pair reported a limit"
        };
        return (
            "elements".into(),
            format!("the elements' stable increment times the safety factor set it; {why}"),
        );
    }
    let lowered = format!(
        "penalty contact (its stable increment times contact_safety = {safety}) lowered the \
         increment by up to {:.1} % below the elements' from t = {lowered_from:.6e}",
        100.0 * (1.0 - lowest_ratio)
    );
    let why = if contact_start.is_nan() || lowered_from < contact_start {
        " — before any contact force acted, because the springs of slave nodes within the \
         search radius set their limit before they touch (one may close within an increment)"
    } else {
        ""
    };
    ("elements and contact".into(), format!("{lowered}{why}"))
}
