//! `abut bench --resident`, second part: a local device-resident increment as the share of the
//! slaves within the search radius falls (100 %, 20 %, 5 %, 1 %; the others hang still far above
//! the plate), on the CPU path and every GPU adapter — the time per increment beside the
//! compulsory bytes the passes declare (`abi::traffic`) for that share, and beside the same
//! increment visiting every slave (`Schedule::visit_every_slave`: no active-slave compaction).

use std::fmt::Write as _;
use std::time::Instant;

use abut::testing::abi::groups;
use abut::CentralDifference;
use abut::{Contact, Device, GlobalSearch, PairId, ResidentIo};

use crate::bench::{scene, BenchScene, Config};
use crate::resident_bench::{median, resident_bytes};

/// Shares of the slaves within the search radius (the first, 100 %, is the ratios' reference).
pub(crate) const SHARES: [f64; 4] = [1.0, 0.2, 0.05, 0.01];
/// Local increments timed per run (after the first, global, one).
const INCREMENTS: usize = 8;
/// Global searches timed per run (increments with a global search asked for, after the local
/// ones).
const GLOBALS: usize = 2;
/// Rounds over every share and mode, one after another; each figure is the median over the
/// rounds, and each ratio the median of the ratios taken within a round (this machine's
/// timings drift between runs more than a share changes them).
const ROUNDS: usize = 3;

/// Compulsory bytes per slave of abut's passes in a local increment (the integrator left out)
/// with the share `near` of the slaves within the radius.
fn contact_bytes(near: f64) -> abut::Result<f64> {
    Ok(resident_bytes(near)?
        .iter()
        .filter(|(label, _)| *label != groups::INTEGRATOR.label)
        .map(|(_, b)| b)
        .sum())
}

/// The wgpu device and queue of a GPU `device` (the CPU path is an error).
pub(crate) fn wgpu_of(device: &Device) -> abut::Result<(&wgpu::Device, &wgpu::Queue)> {
    device.wgpu().ok_or_else(|| abut::Error::BadParameter {
        name: "device",
        value: "CPU path".into(),
        expected: "a GPU adapter",
    })
}

/// Positions of the bench scene as `vec4<f32>` rows.
pub(crate) fn positions(sc: &BenchScene) -> Vec<[f32; 4]> {
    sc.model
        .positions()
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect()
}

/// A storage buffer on `d` holding `data` (the bench's state: one `vec4<f32>` per node).
pub(crate) fn state_buffer(d: &wgpu::Device, q: &wgpu::Queue, data: &[[f32; 4]]) -> wgpu::Buffer {
    let b = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bench state"),
        size: std::mem::size_of_val(data) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    q.write_buffer(&b, 0, bytemuck::cast_slice(data));
    b
}

/// Velocities of the bench scene: the falling masses move, the others hang still.
pub(crate) fn velocities(sc: &BenchScene) -> Vec<[f32; 4]> {
    let n = sc.model.positions().len();
    let mut v = vec![[0.0f32; 4]; n];
    for (k, &falls) in sc.near.iter().enumerate() {
        if falls {
            v[sc.first + k] = [sc.u as f32, 0.0, -sc.v0 as f32, 0.0];
        }
    }
    v
}

/// The mean of `local_walks` over the local increments among `stats` (none: `None`).
fn mean_walks(stats: &[abut::IncrementStats]) -> Option<f64> {
    let local: Vec<f64> = stats
        .iter()
        .filter(|s| s.global_searches == 0)
        .map(|s| s.local_walks as f64)
        .collect();
    (!local.is_empty()).then(|| local.iter().sum::<f64>() / local.len() as f64)
}

/// Seconds per local increment of abut's passes on the CPU path (the host's integration left
/// out), over `INCREMENTS` after the first, and the slaves walked per local increment.
fn cpu_run(sc: &BenchScene) -> abut::Result<(f64, Option<f64>)> {
    let mut contact = Contact::new(&Device::cpu(), &sc.model)?;
    let masses = sc.model.masses();
    let mut x = positions(sc);
    let mut v = velocities(sc);
    let mut f = vec![[0.0f32; 4]; x.len()];
    let mut spent = 0.0;
    for inc in 0..=INCREMENTS {
        let t = Instant::now();
        contact.encode_increment(
            ResidentIo::Cpu {
                positions: &x,
                velocities: &v,
                forces: &mut f,
            },
            sc.dt,
        )?;
        if inc > 0 {
            spent += t.elapsed().as_secs_f64();
        }
        let dt = sc.dt as f32;
        for i in sc.first..x.len() {
            for a in 0..3 {
                v[i][a] += dt * f[i][a] / masses[i] as f32;
                x[i][a] += dt * v[i][a];
                f[i][a] = 0.0;
            }
        }
    }
    Ok((
        spent / INCREMENTS as f64,
        mean_walks(&contact.collect_stats()?),
    ))
}

/// Seconds of one global search of the bench pair on the CPU path (`GlobalSearch::run`, the
/// median of [`GLOBALS`] after a first one).
fn cpu_search(sc: &BenchScene) -> abut::Result<f64> {
    let mut search = GlobalSearch::new(&Device::cpu(), &sc.model, PairId(0))?;
    search.run(sc.model.positions())?;
    let mut t: Vec<f64> = (0..GLOBALS)
        .map(|_| {
            let start = Instant::now();
            search.run(sc.model.positions())?;
            Ok(start.elapsed().as_secs_f64())
        })
        .collect::<abut::Result<_>>()?;
    t.sort_by(f64::total_cmp);
    Ok(t[t.len() / 2])
}

/// One run's times (on the CPU path, `wall` is abut's passes alone).
#[derive(Clone)]
pub(crate) struct GpuTimes {
    /// Wall seconds per local increment (abut's passes and the integrator, device completion
    /// included).
    pub(crate) wall: f64,
    /// GPU seconds of abut's passes per local increment, where the adapter has timestamps.
    pub(crate) gpu: Option<f64>,
    /// GPU seconds of the global search group per global increment (the same pairs, the same
    /// device), where the adapter has timestamps.
    pub(crate) search: Option<f64>,
    /// GPU seconds per local increment of each group of abut's passes (its label), where the
    /// adapter has timestamps.
    pub(crate) groups: Vec<(String, f64)>,
    /// Slaves the local search walked per local increment (`IncrementStats::local_walks`; the
    /// other tracked slaves were within their skin).
    pub(crate) walks: Option<f64>,
}

/// Times the local increments of `sc` on an adapter, then [`GLOBALS`] increments that search
/// globally.
fn gpu_run(device: &Device, sc: &BenchScene) -> abut::Result<GpuTimes> {
    let (d, q) = wgpu_of(device)?;
    let n_nodes = sc.model.positions().len();
    let (x0, v0) = (positions(sc), velocities(sc));
    // the statistics of every increment, collected as the device finishes them
    let stats = std::cell::RefCell::new(Vec::new());
    let run = |timed: bool| -> abut::Result<(f64, abut::Traffic, abut::Traffic)> {
        device.enable_timestamps(timed);
        let make = |data: &[[f32; 4]]| state_buffer(d, q, data);
        let (x, v, f) = (make(&x0), make(&v0), make(&vec![[0.0; 4]; n_nodes]));
        let mut contact = Contact::new(device, &sc.model)?;
        let mut integ = CentralDifference::new(device, sc.model.masses())?;
        let mut step = |contact: &mut Contact| -> abut::Result<()> {
            let mut enc = d.create_command_encoder(&Default::default());
            let io = ResidentIo::Gpu {
                encoder: &mut enc,
                positions: &x,
                velocities: &v,
                forces: &f,
            };
            contact.encode_increment(io, sc.dt)?;
            let range = sc.first as u32..n_nodes as u32;
            integ.encode(&mut enc, &x, &v, &f, sc.dt, [0.0; 3], range)?;
            q.submit([enc.finish()]);
            if timed {
                // through abut, which reads the timestamps back
                device.submit(d.create_command_encoder(&Default::default()))?;
            }
            stats.borrow_mut().extend(contact.collect_stats()?);
            Ok(())
        };
        step(&mut contact)?;
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let before = device.traffic().unwrap_or_default();
        let t = Instant::now();
        for _ in 0..INCREMENTS {
            step(&mut contact)?;
        }
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let wall = t.elapsed().as_secs_f64() / INCREMENTS as f64;
        stats.borrow_mut().extend(contact.collect_stats()?);
        let local = device.traffic().unwrap_or_default().since(&before);
        let before = device.traffic().unwrap_or_default();
        for _ in 0..GLOBALS {
            contact.request_global_search();
            step(&mut contact)?;
        }
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let global = device.traffic().unwrap_or_default().since(&before);
        Ok((wall, local, global))
    };
    let (wall, _, _) = run(false)?;
    let (_, timed, global) = run(true)?;
    device.enable_timestamps(false);
    let gpu: f64 = timed
        .pass_ns
        .iter()
        .filter(|(label, _)| label.as_str() != groups::INTEGRATOR.label)
        .map(|(_, ns)| ns / INCREMENTS as f64 / 1e9)
        .sum();
    let search = global
        .pass_ns
        .get(groups::GLOBAL_SEARCH.label)
        .map(|ns| ns / GLOBALS as f64 / 1e9);
    let groups = timed
        .pass_ns
        .iter()
        .filter(|(label, _)| label.as_str() != groups::INTEGRATOR.label)
        .map(|(label, ns)| (label.clone(), ns / INCREMENTS as f64 / 1e9))
        .collect();
    let walks = mean_walks(&stats.borrow());
    Ok(GpuTimes {
        wall,
        gpu: (!timed.pass_ns.is_empty()).then_some(gpu),
        search,
        groups,
        walks,
    })
}

/// `abut bench --share`: the section alone, written to share.md in `a.out`.
pub(crate) fn run(a: &crate::bench::BenchArgs) -> abut::Result<()> {
    let devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(|d| d.ok())
        .collect();
    let sizes: &[usize] = if !a.sizes.is_empty() {
        &a.sizes
    } else if a.quick {
        &[10_000]
    } else {
        &[100_000, 1_000_000]
    };
    let mut shares = vec![1.0];
    if a.shares.is_empty() {
        shares = SHARES.to_vec();
    }
    for &s in &a.shares {
        if !(s > 0.0 && s <= 100.0) {
            return Err(abut::Error::BadParameter {
                name: "--shares",
                value: format!("{s}"),
                expected: "percentages above 0 and at most 100",
            });
        }
        if s < 100.0 {
            shares.push(s / 100.0);
        }
    }
    let md = format!(
        "# abut bench --share{}{} on {}\n\n{}",
        if a.quick { " --quick" } else { "" },
        if a.slow { " --slow" } else { "" },
        crate::bench::machine(),
        section(&devices, sizes, &shares, !a.gpu_only, a.slow)?
    );
    let io_err = crate::bench::io_err;
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let path = a.out.join("share.md");
    std::fs::write(&path, &md).map_err(|e| io_err(&path, e))?;
    println!("{md}");
    println!("written: {}", path.display());
    Ok(())
}

/// Time of abut's passes per local increment of `sc` on `device` (wall or CPU time; GPU time
/// from the timestamps where there are some) and of one global search of the same pair on the
/// same device (the GPU time of the global search group where there are timestamps; on the
/// CPU path `GlobalSearch::run`).
pub(crate) fn time_of(device: &Device, sc: &BenchScene) -> abut::Result<GpuTimes> {
    if device.wgpu().is_some() {
        gpu_run(device, sc)
    } else {
        let (wall, walks) = cpu_run(sc)?;
        Ok(GpuTimes {
            wall,
            gpu: None,
            search: Some(cpu_search(sc)?),
            groups: Vec::new(),
            walks,
        })
    }
}

/// The section of resident.md: per device (the CPU path first, with `cpu`) and size, a local
/// increment at each of `shares` (the first is the ratios' reference), with the active-slave
/// compaction and visiting every slave; with `slow`, the masses rest on the plate and slide
/// (`--slow`).
pub(crate) fn section(
    devices: &[Device],
    sizes: &[usize],
    shares: &[f64],
    cpu: bool,
    slow: bool,
) -> abut::Result<String> {
    let mut md = String::new();
    let (near, far) = (contact_bytes(1.0)?, contact_bytes(0.0)?);
    let _ = writeln!(
        md,
        "## A local increment against the share of slaves within the search radius\n\n\
         The bench scene with only a share of the masses falling onto the plate; the others hang \
         still a thousand facets above it (beyond the tracking radius: the local increments' \
         slave passes do not visit them). Compulsory bytes of abut's passes in a local increment, \
         derived from each pass's declared records (`abi::traffic`): {near:.0} B per slave within \
         the radius, {far:.0} B per slave beyond it (the integrator left out). Time per local \
         increment after the first (global) one, mean of {INCREMENTS}, median over {ROUNDS} \
         rounds: on the CPU path abut's \
         passes alone; on an adapter the wall time of the increment with its integrator, device \
         completion included, and the GPU time of abut's passes from the timestamps where there \
         are some. *Every slave*: the same increment visiting every slave \
         (`Schedule::visit_every_slave`, the same results bit for bit), abut's passes. \
         *Global search*: one global search of the same pair on the same device — on an adapter \
         the GPU time of the `global search` group in {GLOBALS} increments that search \
         globally after the local ones, on the CPU path `GlobalSearch::run` (median of \
         {GLOBALS}).{} *Walked*: the slaves the local search walked per local increment \
         (`IncrementStats::local_walks`), against those within the radius: the others were \
         within their skin and projected on their facet alone.\n",
        if slow {
            " *Slow* (`--slow`): the masses rest on the plate instead, 0.1 % of a facet into it, \
             and slide 1 % of a facet per increment."
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "| device | slaves | within radius | compulsory bytes / slave | MB / incr. | time / incr. | GPU time of abut's passes | every slave | against every slave | against 100 % | global search | against the global search | walked |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut all = if cpu { vec![Device::cpu()] } else { Vec::new() };
    all.extend(devices.iter().cloned());
    for device in &all {
        for &n in sizes {
            // runs[share][round]: (with the compaction, visiting every slave)
            let mut runs: Vec<Vec<(GpuTimes, GpuTimes)>> = vec![Vec::new(); shares.len()];
            for round in 0..ROUNDS {
                for (k, share) in shares.iter().enumerate() {
                    eprintln!(
                        "{device}: {n} slaves, {:.0} % within the radius, round {}",
                        share * 100.0,
                        round + 1
                    );
                    let mut config = Config::base(n);
                    config.near = *share;
                    config.slow = slow;
                    let t = time_of(device, &scene(&config)?)?;
                    config.every_slave = true;
                    let e = time_of(device, &scene(&config)?)?;
                    runs[k].push((t, e));
                }
            }
            let key = |t: &GpuTimes| t.gpu.unwrap_or(t.wall);
            for (k, share) in shares.iter().enumerate() {
                let of = |f: &dyn Fn(usize) -> Option<f64>| -> Option<f64> {
                    let v: Option<Vec<f64>> = (0..ROUNDS).map(f).collect();
                    v.map(median)
                };
                let (r, full) = (&runs[k], &runs[0]);
                let wall = of(&|i| Some(r[i].0.wall)).unwrap_or(0.0);
                let gpu = of(&|i| r[i].0.gpu);
                let every = of(&|i| Some(key(&r[i].1))).unwrap_or(0.0);
                let search = of(&|i| r[i].0.search);
                let against_every = of(&|i| Some(key(&r[i].0) / key(&r[i].1)));
                let against_full = of(&|i| Some(key(&r[i].0) / key(&full[i].0)));
                let against_search = of(&|i| r[i].0.search.map(|s| key(&r[i].0) / s));
                let walked = of(&|i| r[i].0.walks.map(|w| w / (share * n as f64)));
                let bytes = contact_bytes(*share)?;
                let ms = |s: Option<f64>| s.map_or("–".into(), |s| format!("{:.2} ms", s * 1e3));
                let ratio = |x: Option<f64>| x.map_or("–".into(), |x| format!("{x:.2}"));
                let _ = writeln!(
                    md,
                    "| {} | {n} | {:.0} % | {bytes:.0} | {:.1} | {:.2} ms | {} | {:.2} ms | {} | {} | {} | {} | {} |",
                    device.backend_name(),
                    share * 100.0,
                    bytes * n as f64 / 1e6,
                    wall * 1e3,
                    ms(gpu),
                    every * 1e3,
                    ratio(against_every),
                    ratio(against_full),
                    ms(search),
                    ratio(against_search),
                    walked.map_or("–".into(), |w| format!("{:.1} %", w * 100.0)),
                );
            }
        }
    }
    let _ = writeln!(
        md,
        "\nThe ratio columns compare abut's passes (GPU time where there are timestamps, else \
         the time column) with the same increment visiting every slave, with the same size \
         at 100 %, and with one global search of the same pair on the same device. Every \
         figure is the median over {ROUNDS} rounds (each round runs every share and mode once), \
         and every ratio the median of the ratios within a round.\n"
    );
    md.push_str(&own_and_master_bytes());
    Ok(md)
}

/// The declared bytes per slave within the radius of each pass of a local increment, split
/// into the slave's own records and the master's (its facet, the facet's nodes, the master
/// nodes'), which the slaves near a master node share (`abi::traffic::own_bytes_per_slave`).
fn own_and_master_bytes() -> String {
    use abut::testing::abi::traffic::{bytes_per_slave, own_bytes_per_slave, DECLARED, NOT_LOCAL};
    let mut md = String::from(
        "Declared bytes per slave within the radius, by pass of a local increment (the \
         integrator and the one-invocation passes left out): the slave's own records (one per \
         slave: its position, hit, skin, state, output, pair node, sums, forces) and the \
         master's (its facet, the facet's nodes, the master nodes' own records), which the \
         slaves near a master node share.\n\n\
         | pass | declared | the slave's own | the master's |\n|---|---|---|---|\n",
    );
    let (mut all, mut own) = (0.0, 0.0);
    for p in DECLARED
        .iter()
        .filter(|p| p.entry != "integrate" && !NOT_LOCAL.contains(p))
    {
        let a = bytes_per_slave(p, &crate::bench::PLATE, 1.0).unwrap_or(0.0);
        let o = own_bytes_per_slave(p, &crate::bench::PLATE, 1.0).unwrap_or(0.0);
        if a > 0.0 {
            let _ = writeln!(md, "| `{}` | {a:.0} | {o:.0} | {:.0} |", p.entry, a - o);
            (all, own) = (all + a, own + o);
        }
    }
    let _ = writeln!(md, "| all | {all:.0} | {own:.0} | {:.0} |\n", all - own);
    md
}
