//! The `abut` command line: the verification suite (the default), scene files, and built-in
//! search and penalty demonstrations.

mod bench;
mod verify;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use abut::cpu::brute_force::brute_force;
use abut::mesh::{plate_quads, point_cloud};
use abut::{Contact, Device, Enforce, GlobalSearch, Model, Pair, Penalty, Stiffness, Surface};
use clap::{Parser, Subcommand, ValueEnum};

#[derive(Parser)]
#[command(
    name = "abut",
    version,
    about = "GPU node-to-surface contact for explicit dynamics"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// The default: runs the VERIFICATION.md cases (§1 bar impacts, §2 patch test, §3 Hertz
    /// cylinder, sphere and impact, §4 incline, §5 penalty stability) through the built-in scene files
    /// with the explicit solver on the default adapter, and prints every measured quantity
    /// against its exact value with the error and the tolerance. Fails when one is outside.
    Verify(VerifyArgs),
    /// Speed against error: a matrix of sizes (10^3–10^6 slave nodes), every adapter and the
    /// CPU path, finite and small sliding, penalty and kinematic enforcement, global search
    /// intervals and penalty scales, timed per increment and measured against the exact
    /// solution and an f64 run; parry3d and a copy kernel's bandwidth as references. Writes
    /// bench.md, bench.json and bench.svg (time against error, Pareto front) to --out.
    Bench(bench::BenchArgs),
    /// Penalty contact end to end: point masses fall onto a rigid plate of quads
    /// and bounce, integrated with central differences. Prints the adapter, the time per
    /// increment and the error against the exact solution of a mass on a linear spring:
    /// contact duration π·√(m/k), rebound at the impact speed, peak penetration v₀·√(m/k).
    Bounce(BounceArgs),
    /// Runs a scene file with the explicit solver and abut's contact; writes history.csv and
    /// summary.json to --output when given, and prints the summary.
    Run(RunArgs),
    /// Global contact search on a built-in scene: a cloud of slave nodes around a wavy quad
    /// plate. Prints the adapter, what was found, the time and the error against an f64
    /// brute-force oracle on a sample of nodes.
    Search(SearchArgs),
}

#[derive(clap::Args, Clone)]
struct SearchArgs {
    /// Where to run.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Number of slave nodes.
    #[arg(long, default_value_t = 100_000)]
    slaves: usize,
    /// Plate facets per side (the plate has side² quads).
    #[arg(long, default_value_t = 200)]
    side: usize,
    /// Steady-state repetitions timed after the first call.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Slave nodes checked against the f64 brute-force oracle.
    #[arg(long, default_value_t = 2000)]
    check: usize,
}

#[derive(clap::Args, Clone, Default)]
struct VerifyArgs {
    /// Where to run.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Only these cases (bars, truss, patch, cylinder, sphere, impact, incline, stability).
    #[arg(long = "case")]
    cases: Vec<String>,
}

#[derive(clap::Args, Clone)]
struct RunArgs {
    /// The scene file (TOML; see `abut::scene`).
    scene: std::path::PathBuf,
    /// Where to run.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Directory for history.csv and summary.json.
    #[arg(long)]
    output: Option<std::path::PathBuf>,
}

#[derive(clap::Args, Clone)]
struct BounceArgs {
    /// Where to run.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Number of falling point masses (slave nodes).
    #[arg(long, default_value_t = 10_000)]
    masses: usize,
    /// Plate quads per side.
    #[arg(long, default_value_t = 100)]
    side: usize,
    /// Increments per contact duration π·√(m/k).
    #[arg(long, default_value_t = 40)]
    resolution: usize,
}

impl Default for BounceArgs {
    fn default() -> Self {
        Self {
            backend: BackendArg::Auto,
            masses: 10_000,
            side: 100,
            resolution: 40,
        }
    }
}

#[derive(ValueEnum, Clone, Copy, PartialEq, Eq, Default)]
enum BackendArg {
    /// The best GPU adapter, else the CPU path.
    #[default]
    Auto,
    /// A GPU adapter (an error if there is none).
    Gpu,
    /// The CPU path.
    Cpu,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli
        .command
        .unwrap_or(Command::Verify(VerifyArgs::default()));
    let result = match command {
        Command::Verify(a) => match device(a.backend).and_then(|d| verify::verify(&d, &a.cases)) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::FAILURE,
            Err(e) => Err(e),
        },
        Command::Bounce(a) => bounce(&a),
        Command::Run(a) => run_scene(&a),
        Command::Bench(a) => bench::bench(&a),
        Command::Search(a) => search(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("abut: {e}");
            ExitCode::FAILURE
        }
    }
}

fn device(b: BackendArg) -> abut::Result<Device> {
    match b {
        BackendArg::Auto => Device::auto(),
        BackendArg::Gpu => Device::gpu(),
        BackendArg::Cpu => Ok(Device::cpu()),
    }
}

fn run_scene(a: &RunArgs) -> abut::Result<()> {
    // mesh files in the scene are relative to its directory
    let scene = abut::scene::Scene::load(&a.scene)?;
    let device = device(a.backend)?;
    println!("device: {device}");
    println!("scene: {}", scene.title);
    let summary = abut::scene::run(&scene, &device, a.output.as_deref())?;
    // the per-node and per-sample lists go to summary.json only: here, how many there are
    let mut shown = serde_json::to_value(&summary).unwrap_or_default();
    for key in ["contact_nodes", "curve"] {
        if let Some(n) = shown.get(key).and_then(|v| v.as_array()).map(Vec::len) {
            shown[key] = serde_json::Value::String(format!(
                "{n} entries{}",
                if a.output.is_some() {
                    " (in summary.json)"
                } else {
                    " (written to summary.json with --output)"
                }
            ));
        }
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&shown).unwrap_or_default()
    );
    Ok(())
}

fn bounce(a: &BounceArgs) -> abut::Result<()> {
    let device = device(a.backend)?;
    println!("device: {device}");
    let (m, v0, k) = (1.0f64, 1.0f64, 4.0e5f64);
    let omega = (k / m).sqrt();
    let t_contact = std::f64::consts::PI / omega;
    let dt = t_contact / a.resolution.max(4) as f64;
    let side = a.side.max(1);
    let plate = abut::mesh::plate_quads(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?; // rigid: huge masses
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let n = a.masses.max(1);
    let drops = point_cloud(n, [0.01, 0.01, 0.01], [0.99, 0.99, 0.05], 3);
    let range = model.add_nodes(&drops, &vec![m; n])?;
    let set = model.add_node_set(&range.to_vec())?;
    let pen = Penalty {
        stiffness: Stiffness::Absolute(k),
        ..Default::default()
    };
    model.add_pair(
        Pair::new(set, master)
            .search_radius(1.0 / side as f64)
            .enforce(Enforce::Penalty(pen)),
    )?;
    println!(
        "scene: {n} point masses (m = {m}) falling at {v0} m/s onto a rigid plate of {} quads; k = {k:.3e}, contact lasts π√(m/k) = {:.4e} s, dt = {dt:.3e} s ({} per contact)",
        plate.facets.len(),
        t_contact,
        a.resolution
    );
    let t0 = Instant::now();
    let mut contact = Contact::new(&device, &model)?;
    let setup = t0.elapsed();
    let first = range.start as usize;
    let mut x = model.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    for vi in &mut v[first..] {
        vi[2] = -v0;
    }
    let steps = ((0.05 / v0 + 1.5 * t_contact) / dt).ceil() as usize;
    let mut in_contact = vec![0usize; n];
    let mut deepest = vec![0.0f64; n];
    let (mut worst_momentum, mut min_stable) = (0.0f64, f64::INFINITY);
    let mut first_step = Duration::ZERO;
    let t1 = Instant::now();
    for step in 0..steps {
        let ts = Instant::now();
        let r = contact.penalty_step(&x, &v, dt)?;
        if step == 0 {
            first_step = ts.elapsed();
        }
        min_stable = min_stable.min(r.stable_dt);
        let mut sum = [0.0f64; 3];
        let mut mag = 0.0f64;
        for f in &r.forces {
            for c in 0..3 {
                sum[c] += f[c];
            }
            mag += f[2].abs();
        }
        if mag > 0.0 {
            worst_momentum =
                worst_momentum.max(sum.iter().map(|s| s.abs()).fold(0.0, f64::max) / mag);
        }
        for (j, i) in (first..x.len()).enumerate() {
            if r.forces[i][2] > 0.0 {
                in_contact[j] += 1;
            }
            for c in 0..3 {
                v[i][c] += dt * r.forces[i][c] / m;
                x[i][c] += dt * v[i][c];
            }
            deepest[j] = deepest[j].min(x[i][2]);
        }
    }
    let total = t1.elapsed();
    let steady = (total - first_step) / (steps.max(2) - 1) as u32;
    let rebound_err = v[first..]
        .iter()
        .map(|vi| (vi[2] - v0).abs() / v0)
        .fold(0.0, f64::max);
    let duration_err = in_contact
        .iter()
        .map(|&c| (c as f64 * dt - t_contact).abs())
        .fold(0.0, f64::max);
    let pen_exact = v0 * (m / k).sqrt();
    let pen_err = deepest
        .iter()
        .map(|d| (-d - pen_exact).abs() / pen_exact)
        .fold(0.0, f64::max);
    let stable_exact = 2.0 / omega;
    println!(
        "time: setup {:.1} ms, first increment {:.1} ms, steady {:.2} ms per increment ({:.0} ns per mass), {steps} increments",
        setup.as_secs_f64() * 1e3,
        first_step.as_secs_f64() * 1e3,
        steady.as_secs_f64() * 1e3,
        steady.as_secs_f64() * 1e9 / n as f64
    );
    println!("error against the exact solution (worst mass):");
    println!("  rebound speed  {:.3} % of v0", 100.0 * rebound_err);
    println!(
        "  contact time   {:.2} increments (measured in whole increments)",
        duration_err / dt
    );
    println!(
        "  penetration    {:.3} % of v0·√(m/k) = {pen_exact:.3e}",
        100.0 * pen_err
    );
    println!("  stable dt      reported {min_stable:.4e} s, exact 2/ω = {stable_exact:.4e} s ({:+.2e} relative)", min_stable / stable_exact - 1.0);
    println!("  momentum       |Σ F| ≤ {worst_momentum:.1e} of Σ |F| in every increment");
    Ok(())
}

fn search(a: &SearchArgs) -> abut::Result<()> {
    let device = device(a.backend)?;
    println!("device: {device}");
    let side = a.side.max(1);
    let l = 1.0;
    let h = l / side as f64;
    let wave = |x: f64, y: f64| 0.05 * (6.0 * x).sin() * (4.0 * y).cos();
    let plate = plate_quads(side, side, l, l, 0.2, 1, &wave);
    let mut model = Model::new_3d();
    let masses = vec![1.0; plate.positions.len()];
    model.add_nodes(&plate.positions, &masses)?;
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let cloud = point_cloud(a.slaves.max(1), [0.0, 0.0, -0.1], [l, l, 0.1], 2);
    let range = model.add_nodes(&cloud, &vec![1.0; cloud.len()])?;
    let slaves = model.add_node_set(&range.to_vec())?;
    let radius = 2.0 * h;
    let pair = model.add_pair(Pair::new(slaves, master).search_radius(radius))?;
    println!(
        "scene: {} slave nodes in a slab of ±0.1 around a wavy plate of {} quads (facet {h:.4}), search radius {radius:.4}",
        cloud.len(),
        plate.facets.len()
    );
    let t0 = Instant::now();
    let mut search = GlobalSearch::new(&device, &model, pair)?;
    let setup = t0.elapsed();
    let t1 = Instant::now();
    let result = search.run(model.positions())?;
    let first = t1.elapsed();
    let t2 = Instant::now();
    for _ in 0..a.repeat {
        search.run(model.positions())?;
    }
    let steady = t2.elapsed() / a.repeat.max(1) as u32;
    let found = result.contacts.iter().flatten().count();
    let penetrating = result
        .contacts
        .iter()
        .flatten()
        .filter(|c| c.gap < 0.0)
        .count();
    let s = &result.stats;
    println!(
        "grid: {}×{}×{} cells of {:.4}, {} bin entries, {:.1} facets examined per node, {} regrowths",
        s.grid.dims[0],
        s.grid.dims[1],
        s.grid.dims[2],
        s.grid.cell_size,
        s.entries,
        s.candidates as f64 / cloud.len() as f64,
        s.regrowths
    );
    println!(
        "found: {found} of {} slave nodes within the radius, {penetrating} penetrating (gap < 0)",
        cloud.len()
    );
    println!(
        "time: setup {:.1} ms, first search {:.1} ms, steady state {:.2} ms per search ({:.1} ns per slave node)",
        setup.as_secs_f64() * 1e3,
        first.as_secs_f64() * 1e3,
        steady.as_secs_f64() * 1e3,
        steady.as_secs_f64() * 1e9 / cloud.len() as f64
    );
    // Error against the f64 oracle on a sample.
    let sample = a.check.min(cloud.len());
    let stride = (cloud.len() / sample.max(1)).max(1);
    let idx: Vec<usize> = (0..cloud.len()).step_by(stride).take(sample).collect();
    let sample_nodes: Vec<u32> = idx.iter().map(|&i| result.slaves[i]).collect();
    let oracle = brute_force(
        model.surface(master)?,
        model.positions(),
        &sample_nodes,
        radius,
    );
    let (mut max_dist_err, mut facet_diff, mut presence_diff) = (0.0f64, 0, 0);
    for (k, &i) in idx.iter().enumerate() {
        match (&result.contacts[i], &oracle[k]) {
            (Some(c), Some(o)) => {
                max_dist_err = max_dist_err.max((c.distance - o.contact.distance).abs());
                if c.facet != o.contact.facet {
                    facet_diff += 1;
                }
            }
            (None, None) => {}
            _ => presence_diff += 1,
        }
    }
    println!(
        "check against f64 brute force on {sample} nodes: max distance error {max_dist_err:.2e}, {facet_diff} other facet (ties), {presence_diff} found/missed differently"
    );
    Ok(())
}
