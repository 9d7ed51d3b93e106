//! The `abut` command line: the verification suite (the default), scene files, and built-in
//! search and penalty demonstrations.

mod bench;
mod penalty_bench;
mod resident_bench;
mod search_bench;
mod verify;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use abut::mesh::{plate_quads, point_cloud};
use abut::search::brute_force::brute_force;
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

/// Runs of at least this many increments say so when they start.
const LONG_RUN: u64 = 100_000;

/// Whether this process was started by `mpirun` (Open MPI, MPICH and Intel MPI say so in the
/// environment).
fn under_mpirun() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
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

/// The bounce scene: a rigid plate of quads (huge masses) and point masses above it.
struct BounceScene {
    model: Model,
    /// The point masses' nodes.
    drops: std::ops::Range<u32>,
    m: f64,
    v0: f64,
    k: f64,
    dt: f64,
    steps: usize,
    t_contact: f64,
}

/// What one mode of the bounce measured.
struct BounceRun {
    setup: Duration,
    first: Duration,
    /// Wall time per increment after the first, the device's completion included.
    steady: Duration,
    /// Final velocities of the point masses.
    v: Vec<[f64; 3]>,
    /// Deepest penetration of any mass over the run (model length units, ≥ 0).
    deepest: f64,
    /// Σ over increments of the masses in contact, times dt, over the masses: the mean contact
    /// time.
    mean_contact: f64,
    min_stable: f64,
    /// Submits, bytes read back and blocking waits per increment after the first (GPU).
    traffic: Option<(f64, f64, f64)>,
}

fn bounce_scene(a: &BounceArgs) -> abut::Result<BounceScene> {
    let (m, v0, k) = (1.0f64, 1.0f64, 4.0e5f64);
    let t_contact = std::f64::consts::PI / (k / m).sqrt();
    let dt = t_contact / a.resolution.max(4) as f64;
    let side = a.side.max(1);
    let plate = abut::mesh::plate_quads(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?; // rigid: huge masses
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let n = a.masses.max(1);
    // f32-exact positions: the host and the device modes start from the same bits
    let drops: Vec<[f64; 3]> = point_cloud(n, [0.01, 0.01, 0.01], [0.99, 0.99, 0.05], 3)
        .into_iter()
        .map(|p| p.map(|c| c as f32 as f64))
        .collect();
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
        "scene: {n} point masses (m = {m}) falling at {v0} m/s onto a rigid plate of {} quads; k = {k:.3e}, contact lasts π√(m/k) = {t_contact:.4e} s, dt = {dt:.3e} s ({} per contact)",
        plate.facets.len(),
        a.resolution
    );
    Ok(BounceScene {
        model,
        drops: range.start..range.end,
        m,
        v0,
        k,
        dt,
        steps: ((0.05 / v0 + 1.5 * t_contact) / dt).ceil() as usize,
        t_contact,
    })
}

/// The host-driven mode: positions and velocities in host f64 arrays, `Contact::penalty_step`
/// uploading them and reading the forces back every increment.
fn bounce_host(device: &Device, s: &BounceScene) -> abut::Result<BounceRun> {
    let t0 = Instant::now();
    let mut contact = Contact::new(device, &s.model)?;
    let setup = t0.elapsed();
    let first = s.drops.start as usize;
    let n = s.drops.len();
    let mut x = s.model.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    for vi in &mut v[first..] {
        vi[2] = -s.v0;
    }
    let (mut deepest, mut in_contact, mut min_stable) = (0.0f64, 0u64, f64::INFINITY);
    let mut first_step = Duration::ZERO;
    let before = device.traffic();
    let t1 = Instant::now();
    let mut after_first = None;
    for step in 0..s.steps {
        let ts = Instant::now();
        let r = contact.penalty_step(&x, &v, s.dt)?;
        if step == 0 {
            first_step = ts.elapsed();
            after_first = device.traffic();
        }
        min_stable = min_stable.min(r.stable_dt);
        in_contact += r.active as u64;
        deepest = deepest.max(r.max_overclosure);
        for i in first..x.len() {
            for c in 0..3 {
                v[i][c] += s.dt * r.forces[i][c] / s.m;
                x[i][c] += s.dt * v[i][c];
            }
        }
    }
    let total = t1.elapsed();
    let per = (s.steps.max(2) - 1) as f64;
    let traffic = match (after_first.or(before), device.traffic()) {
        (Some(a), Some(b)) => {
            let t = b.since(&a);
            Some((
                t.submits as f64 / per,
                t.read_back_bytes as f64 / per,
                t.waits as f64 / per,
            ))
        }
        _ => None,
    };
    Ok(BounceRun {
        setup,
        first: first_step,
        steady: (total - first_step) / (s.steps.max(2) - 1) as u32,
        v: v[first..].to_vec(),
        deepest,
        mean_contact: in_contact as f64 * s.dt / n as f64,
        min_stable,
        traffic,
    })
}

/// The device-resident mode: positions, velocities and forces stay in device buffers; each
/// increment records abut's device-resident contact increment and a WGSL central-difference
/// integrator into one encoder and submits it — no readback and no wait until the end. The
/// statistics come back through the lagged ring. On the CPU path, the same program runs the
/// mirrors on f32 arrays.
fn bounce_resident(device: &Device, s: &BounceScene) -> abut::Result<BounceRun> {
    let t0 = Instant::now();
    let mut contact = Contact::new(device, &s.model)?;
    let n_nodes = s.model.positions().len();
    let n = s.drops.len();
    let x0: Vec<[f32; 4]> = s
        .model
        .positions()
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect();
    let mut v0 = vec![[0.0f32; 4]; n_nodes];
    for v in &mut v0[s.drops.start as usize..] {
        v[2] = -s.v0 as f32;
    }
    let (mut deepest, mut in_contact, mut min_stable) = (0.0f64, 0u64, f64::INFINITY);
    let mut fold = |stats: Vec<abut::IncrementStats>| {
        for st in stats {
            deepest = deepest.max(st.max_overclosure as f64);
            in_contact += st.active as u64;
            if st.stable_dt < f32::MAX {
                min_stable = min_stable.min(st.stable_dt as f64);
            }
        }
    };
    let masses = s.model.masses().to_vec();
    match device.wgpu() {
        Some((d, q)) => {
            let make = |label, data: &[[f32; 4]]| {
                let b = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: (n_nodes * 16) as u64,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                q.write_buffer(&b, 0, bytemuck::cast_slice(data));
                b
            };
            let (x, v, f) = (
                make("bounce positions", &x0),
                make("bounce velocities", &v0),
                make("bounce forces", &vec![[0.0f32; 4]; n_nodes]),
            );
            let mut integ = abut::gpu::CentralDifference::new(device, &masses)?;
            let setup = t0.elapsed();
            let mut record = |contact: &mut Contact| -> abut::Result<()> {
                let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("bounce increment"),
                });
                contact.encode_increment(
                    abut::ResidentIo::Gpu {
                        encoder: &mut enc,
                        positions: &x,
                        velocities: &v,
                        forces: &f,
                    },
                    s.dt,
                )?;
                integ.encode(&mut enc, &x, &v, &f, s.dt, [0.0; 3], s.drops.clone())?;
                q.submit([enc.finish()]);
                Ok(())
            };
            let t1 = Instant::now();
            record(&mut contact)?;
            let _ = d.poll(wgpu::PollType::wait_indefinitely());
            let first = t1.elapsed();
            fold(contact.collect_stats()?);
            let before = device.traffic();
            let t2 = Instant::now();
            for _ in 1..s.steps {
                record(&mut contact)?;
                fold(contact.collect_stats()?);
            }
            let traffic = before.zip(device.traffic()).map(|(a, b)| {
                let t = b.since(&a);
                let per = (s.steps.max(2) - 1) as f64;
                (
                    // this program submits each increment itself (abut submits nothing)
                    1.0 + t.submits as f64 / per,
                    t.read_back_bytes as f64 / per,
                    t.waits as f64 / per,
                )
            });
            // the one readback of the run, which also waits for the device to finish
            let vel = read_vec4(d, q, &v, n_nodes);
            let steady = t2.elapsed() / (s.steps.max(2) - 1) as u32;
            for _ in 0..3 {
                fold(contact.collect_stats()?);
            }
            if contact.dropped_stats() > 0 {
                println!(
                    "  note: {} increments' statistics were dropped from the ring (the host fell behind)",
                    contact.dropped_stats()
                );
            }
            Ok(BounceRun {
                setup,
                first,
                steady,
                v: vel[s.drops.start as usize..]
                    .iter()
                    .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
                    .collect(),
                deepest,
                mean_contact: in_contact as f64 * s.dt / n as f64,
                min_stable,
                traffic,
            })
        }
        None => {
            let setup = t0.elapsed();
            let m32: Vec<f32> = masses.iter().map(|&m| m as f32).collect();
            let ip = abut::abi::integrate::IntegrateParams {
                acceleration: [0.0, 0.0, 0.0, s.dt as f32],
                first: s.drops.start,
                count: s.drops.len() as u32,
                n_nodes: n_nodes as u32,
                _pad: 0,
            };
            let (mut x, mut v, mut f) = (x0, v0, vec![[0.0f32; 4]; n_nodes]);
            let mut first = Duration::ZERO;
            let t1 = Instant::now();
            for step in 0..s.steps {
                let ts = Instant::now();
                contact.encode_increment(
                    abut::ResidentIo::Cpu {
                        positions: &x,
                        velocities: &v,
                        forces: &mut f,
                    },
                    s.dt,
                )?;
                abut::cpu::integrate::integrate(&ip, &mut x, &mut v, &mut f, &m32);
                fold(contact.collect_stats()?);
                if step == 0 {
                    first = ts.elapsed();
                }
            }
            Ok(BounceRun {
                setup,
                first,
                steady: (t1.elapsed() - first) / (s.steps.max(2) - 1) as u32,
                v: v[s.drops.start as usize..]
                    .iter()
                    .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
                    .collect(),
                deepest,
                mean_contact: in_contact as f64 * s.dt / n as f64,
                min_stable,
                traffic: None,
            })
        }
    }
}

/// Reads `n` `vec4<f32>` of `buffer` back (blocking: the end of a device-resident run).
fn read_vec4(d: &wgpu::Device, q: &wgpu::Queue, buffer: &wgpu::Buffer, n: usize) -> Vec<[f32; 4]> {
    let staging = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bounce readback"),
        size: (n * 16) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("bounce readback"),
    });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, (n * 16) as u64);
    q.submit([enc.finish()]);
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    let _ = d.poll(wgpu::PollType::wait_indefinitely());
    let out = slice
        .get_mapped_range()
        .map(|v| bytemuck::pod_collect_to_vec(&v))
        .unwrap_or_default();
    staging.unmap();
    out
}

fn bounce(a: &BounceArgs) -> abut::Result<()> {
    let device = device(a.backend)?;
    println!("device: {device}");
    let s = bounce_scene(a)?;
    let host = bounce_host(&device, &s)?;
    let dev = bounce_resident(&device, &s)?;
    let n = s.drops.len();
    let pen_exact = s.v0 * (s.m / s.k).sqrt();
    let stable_exact = 2.0 / (s.k / s.m).sqrt();
    let rebound = |r: &BounceRun| {
        r.v.iter()
            .map(|vi| (vi[2] - s.v0).abs() / s.v0)
            .fold(0.0, f64::max)
    };
    let parity = host
        .v
        .iter()
        .zip(&dev.v)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    println!(
        "{} increments; host-driven (penalty_step: host f64 arrays, forces read back) beside device-resident (encode_increment + WGSL integrator, one submit per increment, nothing read back until the end):",
        s.steps
    );
    println!("{:<38} {:>16} {:>16}", "", "host-driven", "device-resident");
    let ms = |d: Duration| format!("{:.2} ms", d.as_secs_f64() * 1e3);
    let row = |name: &str, a: String, b: String| println!("{name:<38} {a:>16} {b:>16}");
    row("setup", ms(host.setup), ms(dev.setup));
    row("first increment", ms(host.first), ms(dev.first));
    row("steady, per increment", ms(host.steady), ms(dev.steady));
    row(
        "steady, per mass",
        format!("{:.0} ns", host.steady.as_secs_f64() * 1e9 / n as f64),
        format!("{:.0} ns", dev.steady.as_secs_f64() * 1e9 / n as f64),
    );
    let tr = |t: Option<(f64, f64, f64)>, k: usize| {
        t.map_or("-".to_string(), |t| format!("{:.2}", [t.0, t.1, t.2][k]))
    };
    row(
        "submits per increment",
        tr(host.traffic, 0),
        tr(dev.traffic, 0),
    );
    row(
        "bytes read back per increment",
        tr(host.traffic, 1),
        tr(dev.traffic, 1),
    );
    row(
        "blocking waits per increment",
        tr(host.traffic, 2),
        tr(dev.traffic, 2),
    );
    let pct = |v: f64| format!("{:.3} %", 100.0 * v);
    row(
        "rebound speed error (worst mass)",
        pct(rebound(&host)),
        pct(rebound(&dev)),
    );
    row(
        "penetration error (deepest)",
        pct((host.deepest - pen_exact).abs() / pen_exact),
        pct((dev.deepest - pen_exact).abs() / pen_exact),
    );
    row(
        "mean contact time error",
        pct((host.mean_contact - s.t_contact).abs() / s.t_contact),
        pct((dev.mean_contact - s.t_contact).abs() / s.t_contact),
    );
    row(
        "reported stable dt / exact 2/ω",
        format!("{:.5}", host.min_stable / stable_exact),
        format!("{:.5}", dev.min_stable / stable_exact),
    );
    println!(
        "the two modes' final velocities differ by at most {parity:.2e} m/s (f32 parity; exact: penetration v0·√(m/k) = {pen_exact:.3e}, contact time {:.4e} s)",
        s.t_contact
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
    let found = result.contacts().flatten().count();
    let penetrating = result.contacts().flatten().filter(|c| c.gap < 0.0).count();
    let s = &result.stats;
    println!(
        "tree over {} facets: {:.1} facets projected per node, {} walks finished in chunks",
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
