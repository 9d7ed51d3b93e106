//! `abut bench`: speed against error. A matrix of configurations (scene size, backend, sliding
//! formulation, enforcement, global search interval, penalty scale) runs the same scene — point
//! masses falling obliquely onto a rigid plate of quads, bouncing (penalty) or landing
//! (kinematic) while they slide across its facets — and each is timed per increment (the first
//! apart from the steady state) and measured against the exact solution and against the same
//! discrete algorithm in f64 with exact geometry. Rows a user compares against: parry3d's
//! nearest-point queries on the same meshes (search only) and the bandwidth bound of a copy
//! kernel measured on the same adapter in the same run. Writes a markdown table, a JSON file and
//! an SVG plot of time per increment against error with the Pareto front marked.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use abut::mesh::{plate_quads, SplitMix64};
use abut::model::{Schedule, SlaveOrder};
use abut::testing::abi::groups::{self, Group};
use abut::{
    Contact, Device, Enforce, GlobalSearch, Kinematic, Model, Pair, Penalty, Sliding, Stiffness,
    Surface,
};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

mod bandwidth;
mod report;
pub(crate) use report::{io_err, machine};
mod runs;

use bandwidth::PASSES;
pub(crate) use bandwidth::{copy_bandwidth, group_bytes, kernel_bytes, PLATE};
use report::{exponent, pareto, plot};
pub(crate) use runs::scene;
use runs::{measure, search_rows};

/// Arguments of `abut bench`.
#[derive(clap::Args, Clone, Default)]
pub struct BenchArgs {
    /// The small matrix (10^3 and 10^4 slaves): under two minutes on a software adapter.
    #[arg(long)]
    pub quick: bool,
    /// Directory for bench.md, bench.json and bench.svg.
    #[arg(long, default_value = "target/bench")]
    pub out: PathBuf,
    /// Leave out the CPU path (it dominates the run time at 10^6 slaves).
    #[arg(long)]
    pub gpu_only: bool,
    /// Only the device-resident increment beside the host-array one (10^4–10^6 slaves): submits,
    /// readbacks, waits, host and GPU time per pass, an H100 estimate. Writes resident.md.
    #[arg(long)]
    pub resident: bool,
    /// Only --resident's second table: a local increment as the share of slaves within the
    /// search radius falls (100, 20, 5, 1 %), with and without the active-slave compaction,
    /// beside one global search, at 10^5 and 10^6 slaves (--quick: 10^4). Writes share.md.
    #[arg(long)]
    pub share: bool,
    /// --share at these slave counts only (comma-separated; default 10^5 and 10^6).
    #[arg(long, value_delimiter = ',')]
    pub sizes: Vec<usize>,
    /// --share at these shares within the radius only, percent (default 100,20,5,1; 100 first).
    #[arg(long, value_delimiter = ',')]
    pub shares: Vec<f64>,
    /// --share with the masses resting on the plate and sliding 1 % of a facet per increment.
    #[arg(long)]
    pub slow: bool,
    /// Only the slave order's effect: a local increment with the slaves in the caller's order
    /// (at random) and in Morton order, per group of passes, at 10^5 and 10^6 slaves (--quick:
    /// 10^4). Writes order.md.
    #[arg(long)]
    pub order: bool,
    /// Only the global search against parry3d (one thread and rayon), 10^6 slaves on 10^5
    /// triangles within 0.5, 1 and 3 facet sizes, the floor at 10^6 facets. Writes search.md.
    #[arg(long)]
    pub search: bool,
    /// Only the penalty scale's trade on the §1 truss impact (20 and 40 elements, scales
    /// 0.25–4 and kinematic contact, every device): the increment's cost, how late the force
    /// arrives, the plateau and the mean force. Writes penalty.md to --out.
    #[arg(long)]
    pub penalty: bool,
}

/// Enforcement of a configuration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
enum Enf {
    Penalty,
    Kinematic,
}

/// Global search schedule of a configuration: every n increments (with the motion budget), or
/// the motion budget alone.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
enum Interval {
    Every(u32),
    Budget,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct Config {
    slaves: usize,
    enforce: Enf,
    small: bool,
    interval: Interval,
    scale: f64,
    /// The share of the masses that fall onto the plate (0 to 1); the others hang far above.
    pub(crate) near: f64,
    /// Local increments visit every slave instead of the active ones
    /// (`Schedule::visit_every_slave`: the baseline of the compaction).
    pub(crate) every_slave: bool,
    /// The order the pair keeps its slaves in (the bench's node set lists them at random;
    /// only `--order` changes it).
    #[serde(skip)]
    pub(crate) slave_order: SlaveOrder,
    /// The masses rest on the plate and slide (`--share --slow`).
    #[serde(skip)]
    pub(crate) slow: bool,
}

impl Config {
    pub(crate) fn base(slaves: usize) -> Self {
        Config {
            slaves,
            enforce: Enf::Penalty,
            small: false,
            interval: Interval::Every(100),
            scale: 1.0,
            near: 1.0,
            every_slave: false,
            slave_order: SlaveOrder::Morton,
            slow: false,
        }
    }
    fn label(&self) -> String {
        format!(
            "{} {} {} scale {}",
            match self.enforce {
                Enf::Penalty => "penalty",
                Enf::Kinematic => "kinematic",
            },
            if self.small { "small" } else { "finite" },
            match self.interval {
                Interval::Every(n) => format!("global/{n}"),
                Interval::Budget => "budget only".into(),
            },
            self.scale
        )
    }
}

/// Errors of a run (see [`measure`]).
#[derive(Clone, Copy, Debug, Default, Serialize)]
struct Errors {
    /// Largest |z − z_exact| at the end, in facet sizes.
    position: f64,
    /// Largest relative error of the deepest penetration (penalty: against v0/ω; kinematic:
    /// the deepest overclosure left after correction, in facet sizes).
    penetration: f64,
    /// Largest relative error of the normal impulse (penalty 2·m·v0, kinematic m·v0).
    impulse: f64,
    /// |KE − KE_exact| / KE_0 at the end.
    energy: f64,
    /// Masses that never felt a contact force or ended beyond the plate.
    missed: usize,
    /// Largest |z − z_f64| at the end (the same algorithm in f64 with exact geometry), in facet
    /// sizes: what f32 and the search add.
    vs_f64: f64,
}

#[derive(Clone, Debug, Serialize)]
struct Row {
    device: String,
    backend: String,
    config: Config,
    label: String,
    increments: usize,
    first_ms: f64,
    steady_ms: f64,
    /// GPU time per steady increment from timestamp queries around every pass (None where the
    /// adapter has none, and on the CPU path).
    gpu_ms: Option<f64>,
    /// GPU time per steady increment of each pass.
    pass_ms: std::collections::BTreeMap<String, f64>,
    ns_per_slave: f64,
    errors: Errors,
    dispatches: f64,
    uploaded_bytes: f64,
    read_back_bytes: f64,
}

/// The bench scene: `n` point masses above a rigid plate of about n/4 quads.
pub(crate) struct BenchScene {
    pub(crate) model: Model,
    pub(crate) first: usize,
    h: f64,
    pub(crate) dt: f64,
    pub(crate) v0: f64,
    pub(crate) u: f64,
    /// Start heights.
    z0: Vec<f64>,
    /// Whether each mass falls onto the plate (else it hangs still beyond the search radius).
    pub(crate) near: Vec<bool>,
}

const INCREMENTS: usize = 48;
/// Search radius in facet sizes (the masses start at most 2.5 facets above the plate).
const RADIUS: f64 = 3.0;

/// Runs the benchmark.
pub fn bench(a: &BenchArgs) -> abut::Result<()> {
    if a.resident {
        return crate::resident_bench::run(a);
    }
    if a.share {
        return crate::resident_share::run(a);
    }
    if a.order {
        return crate::resident_order::run(a);
    }
    if a.search {
        return crate::search_bench::run(a);
    }
    if a.penalty {
        return crate::penalty_bench::run_bench(a);
    }
    let mut devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(|d| d.ok())
        .collect();
    if !a.gpu_only || devices.is_empty() {
        devices.push(Device::cpu());
    }
    let (sizes, sweep): (Vec<usize>, usize) = if a.quick {
        (vec![1_000, 10_000], 10_000)
    } else {
        (vec![1_000, 10_000, 100_000, 1_000_000], 100_000)
    };
    let mut configs: Vec<Config> = sizes.iter().map(|&n| Config::base(n)).collect();
    let base = Config::base(sweep);
    for i in [
        Interval::Every(1),
        Interval::Every(4),
        Interval::Every(20),
        Interval::Budget,
    ] {
        configs.push(Config {
            interval: i,
            ..base
        });
    }
    // ω·dt = √scale at the bench's fixed increment: 2.5 keeps it at 1.6, inside the limit of 2
    for s in [0.1, 2.5] {
        configs.push(Config { scale: s, ..base });
    }
    configs.push(Config {
        small: true,
        ..base
    });
    configs.push(Config {
        enforce: Enf::Kinematic,
        ..base
    });
    configs.push(Config {
        enforce: Enf::Kinematic,
        interval: Interval::Every(1),
        ..base
    });
    let search_sizes: Vec<usize> = sizes.clone();
    let bar = ProgressBar::new(
        (configs.len() * devices.len() + search_sizes.len() + devices.len()) as u64,
    );
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    for d in &devices {
        for c in &configs {
            bar.set_message(format!(
                "{} {} slaves: {}",
                d.backend_name(),
                c.slaves,
                c.label()
            ));
            rows.push(measure(d, c)?);
            bar.inc(1);
        }
    }
    let mut search = Vec::new();
    for &n in &search_sizes {
        bar.set_message(format!("search only, {n} slaves (parry3d and abut)"));
        search.extend(search_rows(&devices, n)?);
        bar.inc(1);
    }
    let mut bandwidth = Vec::new();
    for d in &devices {
        bar.set_message(format!("copy kernel on {}", d.backend_name()));
        bandwidth.push((d.to_string(), d.backend_name(), copy_bandwidth(d)));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let front = pareto(&rows);
    // report
    let mut md = String::new();
    let now = std::process::Command::new("date")
        .arg("-u")
        .arg("+%Y-%m-%d %H:%M UTC")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let _ = writeln!(
        md,
        "# abut bench{}\n",
        if a.quick { " --quick" } else { "" }
    );
    let _ = writeln!(md, "- machine: {}", machine());
    for d in &devices {
        let _ = writeln!(md, "- adapter: {d}");
    }
    let _ = writeln!(
        md,
        "- abut {} ({} build), {now}; command: `cargo run --release -- bench{}`",
        env!("CARGO_PKG_VERSION"),
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        if a.quick { " --quick" } else { "" }
    );
    let _ = writeln!(
        md,
        "- scene: N point masses (m = 1) falling obliquely (a quarter of a facet per increment down and across) onto a rigid plate of N/4 quads; {INCREMENTS} increments, each mass lands between increments 2 and 10; search radius {RADIUS} facets. Exact solution: free flight, then a half-sine on the penalty spring (k = scale·m/dt², ω·dt = √scale) and a rebound at v0 (penalty), or a stop on the plate (kinematic). Errors: final height against the exact solution and against the same algorithm in f64 with exact geometry, in facet sizes; impulse and penetration relative; energy relative to the initial kinetic energy; missed = never touched or ended beyond the plate.\n"
    );
    let _ = writeln!(md, "## Speed against error\n");
    let _ = writeln!(md, "Times per increment: *first* is the first increment (pipelines, uploads, the first global search), *steady* the mean wall-clock time of the other {} increments, *GPU* the sum of the GPU timestamps around every compute pass of a steady increment (where the adapter has timestamp queries). Errors are the largest over all masses.\n", INCREMENTS - 1);
    let _ = writeln!(md, "| backend | slaves | configuration | first [ms] | steady [ms] | GPU [ms] | ns/slave | position err | vs f64 | penetration err | impulse err | energy err | missed | dispatches/inc | up B/inc | back B/inc | Pareto |");
    let _ = writeln!(
        md,
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|"
    );
    for (i, r) in rows.iter().enumerate() {
        let e = &r.errors;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.3} | {} | {:.0} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {} | {:.1} | {:.0} | {:.0} | {} |",
            r.backend,
            r.config.slaves,
            r.label,
            r.first_ms,
            r.steady_ms,
            r.gpu_ms.map_or("–".to_string(), |g| format!("{g:.3}")),
            r.ns_per_slave,
            e.position,
            e.vs_f64,
            e.penetration,
            e.impulse,
            e.energy,
            e.missed,
            r.dispatches,
            r.uploaded_bytes,
            r.read_back_bytes,
            if front.contains(&i) { "●" } else { "" }
        );
    }
    let _ = writeln!(md, "\n## Scaling (base configuration: penalty, finite sliding, global search every 100 increments with the motion budget, scale 1)\n");
    let _ = writeln!(
        md,
        "| backend | fitted exponent of time per increment in N | points |"
    );
    let _ = writeln!(md, "|---|---:|---|");
    let mut exponents = Vec::new();
    for d in &devices {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.device == d.to_string() && sizes.contains(&r.config.slaves))
            .filter(|r| r.label == Config::base(0).label())
            .map(|r| (r.config.slaves as f64, r.steady_ms))
            .collect();
        if pts.len() >= 2 {
            let b = exponent(&pts);
            exponents.push((d.backend_name(), b));
            let list: Vec<String> = pts
                .iter()
                .map(|p| format!("{}: {:.3} ms", p.0, p.1))
                .collect();
            let _ = writeln!(
                md,
                "| {} | {b:.2} | {} |",
                d.backend_name(),
                list.join(", ")
            );
        }
    }
    let _ = writeln!(
        md,
        "\n## Search only: abut's global search against parry3d\n"
    );
    let _ = writeln!(md, "| slaves | facets | who | first [ms] | steady [ms] | ns/slave | max distance difference to parry [facets] |");
    let _ = writeln!(md, "|---:|---:|---|---:|---:|---:|---:|");
    for s in &search {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.2} | {:.0} | {:.1e} |",
            s.slaves,
            s.facets,
            s.who,
            s.first_ms,
            s.steady_ms,
            s.ns_per_slave,
            s.max_distance_difference
        );
    }
    let _ = writeln!(md, "\n## Bandwidth bound\n");
    // every slave of the bench scene lands: all within the radius
    let kb: Vec<(&str, f64)> = kernel_bytes(1.0)
        .into_iter()
        .filter(|(k, _)| {
            PASSES
                .iter()
                .any(|g| g.passes.iter().any(|p| p.entry == *k))
        })
        .collect();
    let total: f64 = kb.iter().map(|k| k.1).sum();
    let largest = *sizes.last().unwrap_or(&1);
    let _ = writeln!(md, "Bytes a steady penalty increment (local search) moves per slave node, by kernel: the compulsory traffic of its bindings, derived from each pass's declared records (`abi::traffic`) on the bench's plate (0.25 master nodes per slave, 4 facets per node, 4 nodes per facet), per pass as the increment records its passes (`abi::groups`). The bound is that traffic at the bandwidth of a copy kernel measured on the same adapter in this run (a host memory copy for the CPU path); the fraction is the bound over the measured time, per pass from the GPU timestamps where there are some, and for the whole increment from the wall clock — base configuration, {largest} slaves.\n");
    let _ = writeln!(
        md,
        "| kernel | bytes/slave | share of the increment's bytes |"
    );
    let _ = writeln!(md, "|---|---:|---:|");
    for (k, b) in &kb {
        let _ = writeln!(md, "| {k} | {b:.0} | {:.1} % |", 100.0 * b / total);
    }
    let _ = writeln!(md, "| **increment** | **{total:.0}** | 100 % |\n");
    let _ = writeln!(md, "| adapter | copy bandwidth [GB/s] | pass | bytes/slave | bound [ns/slave] | measured [ns/slave] | fraction of the bound |");
    let _ = writeln!(md, "|---|---:|---|---:|---:|---:|---:|");
    let mut fractions = Vec::new();
    for (name, backend, bw) in &bandwidth {
        let Some(r) = rows.iter().find(|r| {
            &r.device == name && r.config.slaves == largest && r.label == Config::base(0).label()
        }) else {
            continue;
        };
        let per_slave = |ms: f64| ms * 1e6 / largest as f64;
        if let Some(k) = r.pass_ms.keys().find(|k| groups::by_label(k).is_none()) {
            return Err(pass_err(format!("a pass '{k}' that no group declares")));
        }
        for group in PASSES {
            let pass = group.label;
            let bytes = group_bytes(group, &kb).map_err(pass_err)?;
            let bound = bytes / bw * 1e9;
            if r.pass_ms.is_empty() {
                continue; // no timestamps on this adapter: the whole increment below
            }
            let Some(&ms) = r.pass_ms.get(pass) else {
                return Err(pass_err(format!("{backend}: no pass '{pass}'")));
            };
            {
                let measured = per_slave(ms);
                fractions.push((backend.clone(), pass.to_string(), bound / measured));
                let _ = writeln!(
                    md,
                    "| {backend} | {:.1} | {pass} (GPU timestamps) | {bytes:.0} | {bound:.2} | {measured:.1} | {:.2} % |",
                    bw / 1e9,
                    100.0 * bound / measured
                );
            }
        }
        let bound = total / bw * 1e9;
        fractions.push((backend.clone(), "increment".into(), bound / r.ns_per_slave));
        let _ = writeln!(
            md,
            "| {backend} | {:.1} | whole increment (wall clock) | {total:.0} | {bound:.2} | {:.0} | {:.2} % |",
            bw / 1e9,
            r.ns_per_slave,
            100.0 * bound / r.ns_per_slave
        );
    }
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let svg = a.out.join("bench.svg");
    let title = format!(
        "abut bench{}: time per increment against error ({})",
        if a.quick { " --quick" } else { "" },
        devices
            .iter()
            .map(|d| d.backend_name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    plot(&rows, &front, &svg, &title).map_err(|e| abut::Error::BadParameter {
        name: "bench plot",
        value: e,
        expected: "an SVG written",
    })?;
    let _ = writeln!(md, "\n![time per increment against error](bench.svg)");
    let md_path = a.out.join("bench.md");
    std::fs::write(&md_path, &md).map_err(|e| io_err(&md_path, e))?;
    let json = serde_json::json!({
        "machine": machine(),
        "adapters": devices.iter().map(|d| d.to_string()).collect::<Vec<_>>(),
        "rows": rows,
        "pareto": front,
        "search": search,
        "scaling_exponents": exponents,
        "bandwidth": bandwidth.iter().map(|b| (b.1.clone(), b.2)).collect::<Vec<_>>(),
        "bound_fraction": fractions,
        "kernel_bytes": kb,
    });
    let json_path = a.out.join("bench.json");
    std::fs::write(
        &json_path,
        serde_json::to_string_pretty(&json).unwrap_or_default(),
    )
    .map_err(|e| io_err(&json_path, e))?;
    println!("{md}");
    println!(
        "wrote {}, {} and {}",
        md_path.display(),
        svg.display(),
        json_path.display()
    );
    Ok(())
}

/// A benchmark pass that does not match what the increment records.
fn pass_err(value: String) -> abut::Error {
    abut::Error::BadParameter {
        name: "bench pass",
        value,
        expected: "the groups the increment records (abi::groups)",
    }
}

#[cfg(test)]
mod tests {
    use super::runs::exact_z;
    use super::*;

    #[test]
    fn exponent_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1e3f64, 1e4, 1e5]
            .iter()
            .map(|&n| (n, 3.0 * n.powf(0.8)))
            .collect();
        assert!((exponent(&pts) - 0.8).abs() < 1e-12);
    }

    #[test]
    fn exact_height_is_continuous_and_rebounds() {
        let (z0, v0, w) = (0.01, 1.0, 100.0);
        let t_hit = z0 / v0;
        for t in [t_hit, t_hit + std::f64::consts::PI / w] {
            let (a, b) = (
                exact_z(z0, v0, Some(w), t - 1e-9),
                exact_z(z0, v0, Some(w), t + 1e-9),
            );
            assert!((a - b).abs() < 1e-8, "{a} {b}");
        }
        // deepest at a quarter period, v0/ω deep; after the half period it rises at v0
        let deep = exact_z(z0, v0, Some(w), t_hit + 0.5 * std::f64::consts::PI / w);
        assert!((deep + v0 / w).abs() < 1e-12);
        let t1 = t_hit + std::f64::consts::PI / w;
        assert!((exact_z(z0, v0, Some(w), t1 + 0.5) - 0.5 * v0).abs() < 1e-12);
        assert_eq!(exact_z(z0, v0, None, t_hit + 1.0), 0.0);
    }

    fn row(ms: f64, err: f64) -> Row {
        Row {
            device: String::new(),
            backend: String::new(),
            config: Config::base(1),
            label: String::new(),
            increments: 1,
            first_ms: 0.0,
            steady_ms: ms,
            gpu_ms: None,
            pass_ms: Default::default(),
            ns_per_slave: 0.0,
            errors: Errors {
                position: err,
                ..Default::default()
            },
            dispatches: 0.0,
            uploaded_bytes: 0.0,
            read_back_bytes: 0.0,
        }
    }

    #[test]
    fn pareto_front_keeps_only_undominated_rows() {
        let rows = vec![
            row(1.0, 1.0),
            row(2.0, 0.5),
            row(2.0, 2.0),
            row(3.0, 0.5),
            row(0.5, 5.0),
        ];
        assert_eq!(pareto(&rows), vec![0, 1, 4]);
    }
}
