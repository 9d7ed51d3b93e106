//! `abut bench --order`: what keeping a pair's slaves in Morton order takes off each pass of a
//! local device-resident increment. The bench scene places its slaves at random over the plate
//! and lists them in that order, so `SlaveOrder::Given` reads the master's facets and nodes as
//! scattered as a caller's order can make them; `SlaveOrder::Morton` (the default) reads them
//! slave by neighbouring slave. Every slave is within the radius (the pair's whole work).

use std::fmt::Write as _;

use abut::model::SlaveOrder;
use abut::Device;

use crate::bench::{scene, Config};
use crate::resident_bench::median;
use crate::resident_share::{time_of, GpuTimes};

/// Rounds over both orders, one after another; each figure is the median over the rounds, and
/// each ratio the median of the ratios taken within a round.
const ROUNDS: usize = 3;

/// The groups of passes a local increment runs, in their order.
const GROUPS: [&str; 5] = [
    "motion + schedule",
    "local_search",
    "nodal_normals + penalty",
    "scatter_forces + gather + add_forces",
    "pair_stats",
];

/// `abut bench --order`: the section alone, written to order.md in `a.out`.
pub(crate) fn run(a: &crate::bench::BenchArgs) -> abut::Result<()> {
    let mut devices = vec![Device::cpu()];
    devices.extend(Device::all_gpus().into_iter().filter_map(|d| d.ok()));
    let sizes: &[usize] = if a.quick {
        &[10_000]
    } else {
        &[100_000, 1_000_000]
    };
    let md = format!(
        "# abut bench --order{} on {}\n\n{}",
        if a.quick { " --quick" } else { "" },
        crate::bench::machine(),
        section(&devices, sizes)?
    );
    let io_err = crate::bench::io_err;
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let path = a.out.join("order.md");
    std::fs::write(&path, &md).map_err(|e| io_err(&path, e))?;
    println!("{md}");
    println!("written: {}", path.display());
    Ok(())
}

/// The seconds of group `label` in `t` (0 when it did not run or there are no timestamps).
fn group(t: &GpuTimes, label: &str) -> f64 {
    t.groups
        .iter()
        .find(|(l, _)| l == label)
        .map_or(0.0, |(_, s)| *s)
}

/// The table: per device and size, both orders, the time per local increment and per group.
fn section(devices: &[Device], sizes: &[usize]) -> abut::Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## A local increment with the slaves in the caller's order and in Morton order\n\n\
         The bench scene with every mass falling onto the plate (100 % within the radius). The \
         node set lists the slaves as the bench places them, at random over the plate: *given* \
         keeps that order inside abut, *Morton* (the default) keeps them in Morton order of their \
         positions; the results are the same bits (tests/slave_order.rs). Time per local \
         increment after the first (global) one: on the CPU path abut's passes (wall clock), on \
         an adapter the GPU time of abut's passes and of each group from the timestamps. \
         Medians over {ROUNDS} rounds; *Morton against given* is the median of the ratios \
         within a round.\n"
    );
    let _ = writeln!(
        md,
        "| device | slaves | order | time / incr. | {} | Morton against given |\n|---|---|---|---|{}---|",
        GROUPS.join(" | "),
        "---|".repeat(GROUPS.len())
    );
    for device in devices {
        for &n in sizes {
            // runs[order][round]
            let mut runs: [Vec<GpuTimes>; 2] = [Vec::new(), Vec::new()];
            for round in 0..ROUNDS {
                for (k, order) in [SlaveOrder::Given, SlaveOrder::Morton].iter().enumerate() {
                    eprintln!("{device}: {n} slaves, {order:?} order, round {}", round + 1);
                    let mut config = Config::base(n);
                    config.slave_order = *order;
                    runs[k].push(time_of(device, &scene(&config)?)?);
                }
            }
            let key = |t: &GpuTimes| t.gpu.unwrap_or(t.wall);
            for (k, name) in ["given", "Morton"].iter().enumerate() {
                let total = median(runs[k].iter().map(key).collect());
                let ratio = median(
                    (0..ROUNDS)
                        .map(|i| key(&runs[1][i]) / key(&runs[0][i]))
                        .collect(),
                );
                let cells: Vec<String> = GROUPS
                    .iter()
                    .map(|g| {
                        if device.is_gpu() {
                            let s = median(runs[k].iter().map(|t| group(t, g)).collect());
                            format!("{:.2} ms", s * 1e3)
                        } else {
                            "–".into()
                        }
                    })
                    .collect();
                let _ = writeln!(
                    md,
                    "| {} | {n} | {name} | {:.2} ms | {} | {} |",
                    device.backend_name(),
                    total * 1e3,
                    cells.join(" | "),
                    if k == 1 {
                        format!("{ratio:.2}")
                    } else {
                        "1.00".into()
                    }
                );
            }
        }
    }
    Ok(md)
}
