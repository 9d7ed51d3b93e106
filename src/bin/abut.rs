//! The `abut` command line: runs contact searches on built-in scenes.

use std::process::ExitCode;
use std::time::Instant;

use abut::cpu::brute_force::brute_force;
use abut::mesh::{plate_quads, point_cloud};
use abut::{Device, GlobalSearch, Model, Pair, Surface};
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

#[derive(ValueEnum, Clone, Copy, PartialEq, Eq)]
enum BackendArg {
    /// The best GPU adapter, else the CPU path.
    Auto,
    /// A GPU adapter (an error if there is none).
    Gpu,
    /// The CPU path.
    Cpu,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Search(SearchArgs {
        backend: BackendArg::Auto,
        slaves: 100_000,
        side: 200,
        repeat: 5,
        check: 2000,
    }));
    let result = match command {
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

fn search(a: &SearchArgs) -> abut::Result<()> {
    let device = match a.backend {
        BackendArg::Auto => Device::auto()?,
        BackendArg::Gpu => Device::gpu()?,
        BackendArg::Cpu => Device::cpu(),
    };
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
