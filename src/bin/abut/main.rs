//! The `abut` command line: the verification suite (the default), scene files, and built-in
//! search and penalty demonstrations.

mod bench;
mod bounce;
mod penalty_bench;
mod resident_bench;
mod resident_order;
mod resident_share;
mod search_bench;
mod verify;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use abut::mesh::{plate_quads, point_cloud};
use abut::testing::brute_force::brute_force;
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
    /// Penalty contact end to end: point masses fall onto a rigid plate of quads and bounce,
    /// integrated with central differences, twice: host-driven (host arrays, forces read back
    /// every increment) and device-resident (abut's device increment and a WGSL integrator in
    /// one submit, nothing read back). Prints the adapter, the time per
    /// increment and the error against the exact solution of a mass on a linear spring:
    /// contact duration π·√(m/k), rebound at the impact speed, peak penetration v₀·√(m/k).
    Bounce(BounceArgs),
    /// Runs a scene file with the explicit solver and abut's contact; writes history.csv and
    /// summary.json to --output when given, and prints the summary.
    Run(RunArgs),
    /// Writes a TOML scene as an Abaqus input deck: every node and element as the scene meshes
    /// them, sections, rigid bodies, surfaces, boundary conditions and contact pairs, and one
    /// *DYNAMIC, EXPLICIT step; `abut run` of the deck gives the scene's history bit for bit.
    Inp(InpArgs),
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
    /// The global search's structure (auto: the faster as measured, the tree).
    #[arg(long, value_enum, default_value_t = StructureArg::Auto)]
    structure: StructureArg,
}

/// `abut::SearchStructure` on the command line.
#[derive(ValueEnum, Clone, Copy, PartialEq, Eq, Default)]
enum StructureArg {
    /// Chosen from the facet sizes and the radius.
    #[default]
    Auto,
    /// The seed's bucket sort.
    Buckets,
    /// The bounding-box tree.
    Tree,
}

impl From<StructureArg> for abut::SearchStructure {
    fn from(s: StructureArg) -> Self {
        match s {
            StructureArg::Auto => Self::Auto,
            StructureArg::Buckets => Self::Buckets,
            StructureArg::Tree => Self::Tree,
        }
    }
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
struct InpArgs {
    /// The scene file (TOML).
    scene: std::path::PathBuf,
    /// Where to write the deck (standard output without it).
    #[arg(long)]
    output: Option<std::path::PathBuf>,
}

#[derive(clap::Args, Clone)]
struct RunArgs {
    /// The scene file (TOML; see `abut::scene`) or an Abaqus input deck (`.inp`: its
    /// explicit-dynamics keywords; see `abut::scene::Scene::from_inp`).
    scene: std::path::PathBuf,
    /// Where to run.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Directory for history.csv and summary.json.
    #[arg(long)]
    output: Option<std::path::PathBuf>,
    /// Run as one rank of an MPI job, the model split over the ranks (needs a build with the
    /// `mpi` feature; the default when `mpirun` started the process).
    #[arg(long)]
    mpi: bool,
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

/// Mesa's drivers look for a Wayland display through `XDG_RUNTIME_DIR` when abut asks for
/// adapters, and print `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` — on
/// every headless machine, before abut's first line, where a new user reads it as abut failing.
/// abut draws nothing: when the variable does not name a directory, point it at a private one
/// (mode 0700, under the temporary directory) before any adapter is probed.
fn quiet_display_probe() {
    let valid =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if valid {
        return;
    }
    let user = std::env::var("USER")
        .or_else(|_| std::env::var("LOGNAME"))
        .unwrap_or_else(|_| "user".into());
    for name in [
        format!("abut-runtime-{user}"),
        format!("abut-runtime-{user}-{}", std::process::id()),
    ] {
        let dir = std::env::temp_dir().join(name);
        let mut builder = std::fs::DirBuilder::new();
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        let _ = builder.create(&dir);
        #[cfg(unix)]
        let ours = {
            use std::os::unix::fs::{MetadataExt, PermissionsExt};
            std::fs::metadata(&dir).is_ok_and(|m| {
                m.is_dir() && m.permissions().mode() & 0o777 == 0o700 && {
                    // owned by this process's user: a file made here has the same owner
                    let probe = dir.join(format!(".probe-{}", std::process::id()));
                    let same = std::fs::write(&probe, b"")
                        .and_then(|_| std::fs::metadata(&probe))
                        .is_ok_and(|p| p.uid() == m.uid());
                    let _ = std::fs::remove_file(&probe);
                    same
                }
            })
        };
        #[cfg(not(unix))]
        let ours = dir.is_dir();
        if ours {
            // at the start of main, before any thread exists
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
            return;
        }
    }
}

fn main() -> ExitCode {
    quiet_display_probe();
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
        Command::Bounce(a) => bounce::bounce(&a),
        Command::Run(a) => run_scene(&a),
        Command::Inp(a) => write_inp(&a),
        Command::Bench(a) => bench::bench(&a),
        Command::Search(a) => search(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // one write of the whole line: ranks of an MPI run that fail together share a
            // stderr, and a message written in pieces interleaves with another rank's
            use std::io::Write as _;
            let line = format!("abut: {e}\n");
            let _ = std::io::stderr().lock().write_all(line.as_bytes());
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

/// Runs of at least this many increments say so when they start.
const LONG_RUN: u64 = 100_000;

/// Whether this process was started by `mpirun` (Open MPI, MPICH and Intel MPI say so in the
/// environment).
fn under_mpirun() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

fn write_inp(a: &InpArgs) -> abut::Result<()> {
    let deck = abut::scene::Scene::load(&a.scene)?.to_inp()?;
    match &a.output {
        Some(path) => std::fs::write(path, deck).map_err(|e| abut::Error::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        }),
        None => {
            print!("{deck}");
            Ok(())
        }
    }
}

fn run_scene(a: &RunArgs) -> abut::Result<()> {
    // mesh files in the scene are relative to its directory
    let scene = abut::scene::Scene::load(&a.scene)?;
    #[cfg(feature = "mpi")]
    let universe = if a.mpi || under_mpirun() {
        Some(mpi::initialize().ok_or(abut::Error::BadParameter {
            name: "--mpi",
            value: "MPI initialisation".into(),
            expected: "MPI not initialised before",
        })?)
    } else {
        None
    };
    #[cfg(not(feature = "mpi"))]
    if a.mpi || under_mpirun() {
        return Err(abut::Error::BadParameter {
            name: "--mpi",
            value: "an MPI run".into(),
            expected: "a build with the mpi feature: cargo build --release --features mpi",
        });
    }
    #[cfg(feature = "mpi")]
    let world = universe.as_ref().map(|u| u.world());
    #[cfg(feature = "mpi")]
    if world.is_some() {
        // a rank that panics takes the job down (unwinding would finalise MPI while the others
        // wait in a collective for ever)
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            report(info);
            mpi::traits::Communicator::abort(&mpi::topology::SimpleCommunicator::world(), 70);
        }));
    }
    #[cfg(feature = "mpi")]
    let root = world
        .as_ref()
        .is_none_or(|w| mpi::traits::Communicator::rank(w) == 0);
    #[cfg(not(feature = "mpi"))]
    let root = true;
    let device = device(a.backend)?;
    let notes = scene.notes();
    if root {
        println!("device: {device}");
        println!("scene: {}", scene.title);
        for n in &notes {
            eprintln!("abut: warning: {n}");
        }
        for n in &scene.deck_notes {
            eprintln!("abut: deck: {n}");
        }
    }
    // a bar on a terminal (hidden otherwise), and the estimate once for long runs
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] increment {pos}/{len} (estimated) t = {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut told = false;
    let mut progress = |p: &abut::scene::Progress| {
        if root && !told && p.estimated >= LONG_RUN {
            eprintln!(
                "abut: about {} increments to t = {:e}",
                p.estimated, p.end_time
            );
            told = true;
        }
        bar.set_length(p.estimated);
        bar.set_position(p.increment);
        if p.increment.is_multiple_of(64) {
            bar.set_message(format!("{:.4e}", p.time));
        }
    };
    if !root {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    #[cfg(feature = "mpi")]
    let run = match world.as_ref() {
        Some(w) => {
            abut::scene::run_distributed(&scene, &device, a.output.as_deref(), w, &mut progress)
        }
        None => abut::scene::run_with_progress(&scene, &device, a.output.as_deref(), &mut progress),
    };
    #[cfg(not(feature = "mpi"))]
    let run = abut::scene::run_with_progress(&scene, &device, a.output.as_deref(), &mut progress);
    bar.finish_and_clear();
    let summary = run?;
    if !root {
        return Ok(());
    }
    for w in summary.warnings.iter().filter(|w| !notes.contains(w)) {
        eprintln!("abut: warning: {w}");
    }
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
    let pair = model.add_pair(
        Pair::new(slaves, master)
            .search_radius(radius)
            .search_structure(a.structure.into()),
    )?;
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
    let found = result.contacts().flatten().count();
    let penetrating = result.contacts().flatten().filter(|c| c.gap < 0.0).count();
    let s = &result.stats;
    println!(
        "{} over {} facets: {:.1} facets projected per node, {} walks finished in chunks",
        match s.structure {
            abut::SearchStructure::Buckets => "buckets",
            _ => "tree",
        },
        search.master().active.len(),
        s.candidates as f64 / cloud.len() as f64,
        s.fallbacks
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
        match (&result.contact(i), &oracle[k]) {
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
