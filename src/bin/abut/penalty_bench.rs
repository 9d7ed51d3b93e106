//! `abut bench --penalty`: what the penalty scale trades — a steel truss of 20 and 40
//! elements hitting a rigid wall (the §1 truss-impact case, VERIFICATION.md) with penalty
//! contact at the automatic stiffness times 0.25–4, and with kinematic contact, on the CPU path
//! and every GPU adapter. Per run: the increment against the elements' own (the cost), how late
//! the force reaches half of ρ·c·v·A (increments), the plateau (the mean over the middle half of
//! the contact) and the edge-to-edge mean force against ρ·c·v·A, the peak, and the wall time
//! per increment.

use std::fmt::Write as _;

use abut::scene::{run, Scene};
use abut::Device;

use crate::bench::{io_err, machine, BenchArgs};

/// Exact solution of the truss impact (scenes/truss_wall.toml): impact time (s) and force (N).
const IMPACT: f64 = 1e-3 / 1.5;
const FORCE: f64 = 1.185e7;

/// The truss-impact scene with `n` elements and `enforce` ("kinematic", or "penalty" with
/// `penalty_scale = scale`), at the scene defaults (bulk viscosity 0.06 and 1.2).
fn truss(n: usize, scale: Option<f64>) -> String {
    let base = include_str!("../../../scenes/truss_wall.toml");
    let enforce = match scale {
        Some(s) => format!("enforce = \"penalty\"\npenalty_scale = {s}"),
        None => "enforce = \"kinematic\"".into(),
    };
    base.replace(
        "divisions = [200, 0, 0]",
        &format!("divisions = [{n}, 0, 0]"),
    )
    .replace("output_every = 10", "output_every = 1")
    .replace("enforce = \"kinematic\"", &enforce)
    // the scene's defaults (Abaqus' bulk viscosity), not the verification case's own zeros
    .replace("bulk_viscosity = 0.0\n", "")
    .replace("bulk_viscosity_quadratic = 0.0\n", "")
}

/// Runs the penalty-scale table and writes penalty.md to `a.out`.
pub fn run_bench(a: &BenchArgs) -> abut::Result<()> {
    let mut devices = vec![Device::cpu()];
    devices.extend(Device::all_gpus().into_iter().filter_map(|d| d.ok()));
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Penalty scale against error: truss impact on a rigid wall\n\n{}\n",
        machine()
    );
    let _ = writeln!(
        md,
        "Steel truss, L = 2 m, A = 0.2 m², v = 1.5 m/s (VERIFICATION §1): exact impact at {IMPACT:.4e} s, \
         F = ρ·c·v·A = {FORCE:.4e} N for 2L/c. Cost: 1 − Δt/Δt_elements (`scene::combined_increment`). \
         Late: the half-force edge after the exact impact, in increments. Plateau: mean over the middle \
         half of the contact. Mean: impulse between the half-force edges over their distance.\n"
    );
    let _ = writeln!(
        md,
        "| device | elements | contact | cost | late (incr) | plateau | mean | peak | µs/incr |\n|---|---|---|---|---|---|---|---|---|"
    );
    for d in &devices {
        for n in [20usize, 40] {
            for scale in [Some(0.25), Some(0.5), Some(1.0), Some(2.0), Some(4.0), None] {
                let scene = Scene::parse(&truss(n, scale))?;
                let s = run(&scene, d, None)?;
                let plateau = s.plateau_force;
                let dt = s.end_time / s.increments as f64;
                let what = match scale {
                    Some(x) => format!("penalty ×{x}"),
                    None => "kinematic".into(),
                };
                let _ = writeln!(
                    md,
                    "| {} | {n} | {what} | {:.1} % | {:.2} | {:+.2} % | {:+.2} % | {:+.1} % | {:.1} |",
                    d.backend_name(),
                    100.0 * (1.0 - dt / s.element_increment),
                    (s.impact_time - IMPACT) / dt,
                    100.0 * (plateau / FORCE - 1.0),
                    100.0 * (s.mean_force / FORCE - 1.0),
                    100.0 * (s.peak_force / FORCE - 1.0),
                    1e6 * s.seconds_per_increment
                );
                eprintln!("{} {n} {what} done", d.backend_name());
            }
        }
    }
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let path = a.out.join("penalty.md");
    std::fs::write(&path, &md).map_err(|e| io_err(&path, e))?;
    print!("{md}");
    Ok(())
}
