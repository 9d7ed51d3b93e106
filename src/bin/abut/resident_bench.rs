//! `abut bench --resident`: the device-resident increment beside the host-array one, on the
//! bench's scene (point masses falling obliquely onto a rigid plate and bouncing, penalty), for
//! 10^4–10^6 slaves on every GPU adapter. Per increment: submits, bytes read back and blocking
//! waits (`Device::traffic`), the host's time (recording and submitting, for the resident one;
//! the whole call minus the GPU's time, for the host-array one), the wall time, the GPU time of
//! each pass (timestamp queries, in a separate timed run, where the adapter has them) as a
//! fraction of the copy kernel's bandwidth, and the time an H100-class GPU would need for the
//! compulsory bytes — an estimate, labelled as one.

use std::fmt::Write as _;
use std::time::Instant;

use abut::testing::abi::groups::{self, Group};
use abut::CentralDifference;
use abut::{Contact, Device, ResidentIo};

use crate::bench::{copy_bandwidth, io_err, machine, scene, BenchArgs, Config};
use crate::resident_share::{positions, state_buffer, velocities, wgpu_of};

/// Increments timed per mode (after the first).
const INCREMENTS: usize = 24;
/// H100 SXM (HBM3) memory bandwidth, bytes/s, for the estimate.
const H100_BANDWIDTH: f64 = 3.35e12;
/// Assumed cost of one dispatch (launch and the barrier after it) on such a GPU, seconds.
const H100_DISPATCH: f64 = 2.0e-6;

/// Compulsory bytes per slave of each compute pass of a local device-resident increment, with
/// the share `near` of the slaves within the search radius: the sum of each group's declared
/// kernels (`abi::traffic`) on the bench's plate. The global search's dispatches get zero
/// workgroups in a local increment.
pub(crate) fn resident_bytes(near: f64) -> abut::Result<Vec<(&'static str, f64)>> {
    let kb = crate::bench::kernel_bytes(near);
    let of = |g: &Group| {
        crate::bench::group_bytes(g, &kb).map_err(|value| abut::Error::BadParameter {
            name: "bench pass",
            value,
            expected: "compulsory bytes for every kernel of the group",
        })
    };
    let mut out = vec![(groups::GLOBAL_SEARCH.label, 0.0)];
    for g in [
        &groups::MOTION_SCHEDULE,
        &groups::LOCAL,
        &groups::NORMALS_PENALTY,
        &groups::SCATTER_GATHER_ADD,
        &groups::STATS_PAIR,
        &groups::STATS_FINISH,
        &groups::INTEGRATOR,
    ] {
        out.push((g.label, of(g)?));
    }
    Ok(out)
}

/// One mode's measurements at one size on one device.
struct Measured {
    /// Wall time per increment, device completion included (ms).
    wall_ms: f64,
    /// Host time per increment (µs): recording the increment and the integrator and finishing
    /// the command buffer (resident), or the wall time minus the GPU's (host arrays).
    host_us: f64,
    /// Of which abut's `encode_increment` (µs; resident).
    abut_us: f64,
    /// Recording, submitting and collecting the statistics (µs; resident): on a software
    /// adapter the submit runs the shaders on the calling thread.
    submit_us: f64,
    /// Host time per increment recorded with the device idle, just after it ran (µs; resident;
    /// median): the host's own cost, without a software adapter's shaders on the same cores but
    /// with the caches they evicted.
    idle_host_us: f64,
    /// Of which abut's `encode_increment` (µs; resident; median).
    idle_abut_us: f64,
    /// Host time of the second of two increments recorded back to back, device idle (µs;
    /// resident; median): the host's own cost with warm caches.
    warm_host_us: f64,
    /// Of which abut's `encode_increment` (µs; resident; median).
    warm_abut_us: f64,
    submits: f64,
    read_back: f64,
    waits: f64,
    /// GPU time per increment by pass label (ms), from the timed run; empty without timestamps.
    pass_ms: Vec<(String, f64)>,
}

/// The median of `v` (NaN when empty).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn per(t: &abut::Traffic, n: usize) -> (f64, f64, f64) {
    let n = n as f64;
    (
        t.submits as f64 / n,
        t.read_back_bytes as f64 / n,
        t.waits as f64 / n,
    )
}

/// GPU time per increment by pass over `n` increments of `traffic`.
fn passes(t: &abut::Traffic, n: usize) -> Vec<(String, f64)> {
    t.pass_ns
        .iter()
        .map(|(k, v)| (k.clone(), v / n as f64 / 1e6))
        .collect()
}

fn host_arrays(device: &Device, c: &Config) -> abut::Result<Measured> {
    let sc = scene(c)?;
    let run = |timed: bool| -> abut::Result<(f64, abut::Traffic)> {
        device.enable_timestamps(timed);
        let mut contact = Contact::new(device, &sc.model)?;
        let mut x = sc.model.positions().to_vec();
        let mut v = vec![[0.0; 3]; x.len()];
        for vi in &mut v[sc.first..] {
            *vi = [sc.u, 0.0, -sc.v0];
        }
        let mut step = |x: &mut Vec<[f64; 3]>, v: &mut Vec<[f64; 3]>| -> abut::Result<()> {
            let r = contact.penalty_step(x, v, sc.dt)?;
            for i in sc.first..x.len() {
                for a in 0..3 {
                    v[i][a] += sc.dt * r.forces[i][a];
                    x[i][a] += sc.dt * v[i][a];
                }
            }
            Ok(())
        };
        step(&mut x, &mut v)?;
        let before = device.traffic().unwrap_or_default();
        let t = Instant::now();
        for _ in 0..INCREMENTS {
            step(&mut x, &mut v)?;
        }
        let wall = t.elapsed().as_secs_f64() / INCREMENTS as f64;
        Ok((wall, device.traffic().unwrap_or_default().since(&before)))
    };
    let (wall, traffic) = run(false)?;
    let (_, timed) = run(true)?;
    device.enable_timestamps(false);
    let pass_ms = passes(&timed, INCREMENTS);
    let gpu_s = pass_ms.iter().map(|(_, ms)| ms).sum::<f64>() / 1e3;
    let (submits, read_back, waits) = per(&traffic, INCREMENTS);
    Ok(Measured {
        wall_ms: wall * 1e3,
        host_us: if pass_ms.is_empty() {
            f64::NAN
        } else {
            (wall - gpu_s).max(0.0) * 1e6
        },
        abut_us: f64::NAN,
        submit_us: f64::NAN,
        idle_host_us: f64::NAN,
        idle_abut_us: f64::NAN,
        warm_host_us: f64::NAN,
        warm_abut_us: f64::NAN,
        submits,
        read_back,
        waits,
        pass_ms,
    })
}

fn resident(device: &Device, c: &Config) -> abut::Result<Measured> {
    let sc = scene(c)?;
    let (d, q) = wgpu_of(device)?;
    let n_nodes = sc.model.positions().len();
    let (x0, v0) = (positions(&sc), velocities(&sc));
    let drops = sc.first as u32..n_nodes as u32;
    let run = |timed: bool| -> abut::Result<(f64, [f64; 7], abut::Traffic)> {
        device.enable_timestamps(timed);
        let make = |data: &[[f32; 4]]| state_buffer(d, q, data);
        let (x, v, f) = (make(&x0), make(&v0), make(&vec![[0.0; 4]; n_nodes]));
        let mut contact = Contact::new(device, &sc.model)?;
        let mut integ = CentralDifference::new(device, sc.model.masses())?;
        // records one increment (abut's passes, then the integrator) into a new command buffer:
        // (seconds in encode_increment, seconds recording in all, the command buffer)
        let mut encode = |contact: &mut Contact| -> abut::Result<(f64, f64, wgpu::CommandBuffer)> {
            let t0 = Instant::now();
            let mut enc = d.create_command_encoder(&Default::default());
            let ta = Instant::now();
            contact.encode_increment(
                ResidentIo::Gpu {
                    encoder: &mut enc,
                    positions: &x,
                    velocities: &v,
                    forces: &f,
                },
                sc.dt,
            )?;
            let abut_s = ta.elapsed().as_secs_f64();
            integ.encode(&mut enc, &x, &v, &f, sc.dt, [0.0; 3], drops.clone())?;
            let cmd = enc.finish();
            Ok((abut_s, t0.elapsed().as_secs_f64(), cmd))
        };
        let submit = |cmds: Vec<wgpu::CommandBuffer>| -> abut::Result<()> {
            if timed {
                // through abut, which reads the timestamps (and waits for them)
                let mut e = d.create_command_encoder(&Default::default());
                e.insert_debug_marker("timed increment");
                q.submit(cmds);
                device.submit(e)
            } else {
                q.submit(cmds);
                Ok(())
            }
        };
        let mut record = |contact: &mut Contact| -> abut::Result<(f64, f64)> {
            let (abut_s, recorded, cmd) = encode(contact)?;
            submit(vec![cmd])?;
            contact.collect_stats()?;
            Ok((abut_s, recorded))
        };
        record(&mut contact)?;
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let before = device.traffic().unwrap_or_default();
        let (mut host, mut recording, mut abut_s) = (0.0, 0.0, 0.0);
        let t = Instant::now();
        for _ in 0..INCREMENTS {
            let th = Instant::now();
            let (a, rec) = record(&mut contact)?;
            abut_s += a;
            recording += rec;
            host += th.elapsed().as_secs_f64();
        }
        let traffic = device.traffic().unwrap_or_default().since(&before);
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let wall = t.elapsed().as_secs_f64() / INCREMENTS as f64;
        // the host's own cost, with the device idle (on a software adapter the shaders of earlier
        // increments otherwise share the host's cores): two increments recorded back to back,
        // then submitted together — the first after the device ran (its shaders have evicted the
        // host's caches here), the second warm. Medians: this virtual machine's scheduler adds
        // outliers of several times the median.
        let (mut cold, mut warm) = (Vec::new(), Vec::new());
        for _ in 0..INCREMENTS / 2 {
            let _ = d.poll(wgpu::PollType::wait_indefinitely());
            let (a1, r1, c1) = encode(&mut contact)?;
            let (a2, r2, c2) = encode(&mut contact)?;
            submit(vec![c1, c2])?;
            contact.collect_stats()?;
            cold.push((a1, r1));
            warm.push((a2, r2));
        }
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
        let med = |v: &[(f64, f64)], k: usize| {
            median(v.iter().map(|p| if k == 0 { p.0 } else { p.1 }).collect())
        };
        let per = |v: f64| v / INCREMENTS as f64;
        Ok((
            wall,
            [
                per(abut_s),
                per(recording),
                per(host),
                med(&cold, 0),
                med(&cold, 1),
                med(&warm, 0),
                med(&warm, 1),
            ],
            traffic,
        ))
    };
    let (wall, host, traffic) = run(false)?;
    let (_, _, timed) = run(true)?;
    device.enable_timestamps(false);
    let (submits, read_back, waits) = per(&traffic, INCREMENTS);
    Ok(Measured {
        wall_ms: wall * 1e3,
        host_us: host[1] * 1e6,
        abut_us: host[0] * 1e6,
        submit_us: host[2] * 1e6,
        idle_abut_us: host[3] * 1e6,
        idle_host_us: host[4] * 1e6,
        warm_abut_us: host[5] * 1e6,
        warm_host_us: host[6] * 1e6,
        // this program submits each increment itself (through Device::submit only when timed)
        submits: submits.max(1.0),
        read_back,
        waits,
        pass_ms: passes(&timed, INCREMENTS),
    })
}

/// Runs the comparison and writes resident.md into `a.out`.
pub fn run(a: &BenchArgs) -> abut::Result<()> {
    let devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(|d| d.ok())
        .collect();
    if devices.is_empty() {
        return Err(abut::Error::NoAdapter {
            detail: ": the device-resident increment needs a GPU adapter".into(),
        });
    }
    let sizes: &[usize] = if a.quick {
        &[1_000, 10_000]
    } else {
        &[10_000, 100_000, 1_000_000]
    };
    let share_sizes: &[usize] = if a.quick {
        &[10_000]
    } else {
        &[100_000, 1_000_000]
    };
    let bytes: std::collections::HashMap<&str, f64> = resident_bytes(1.0)?.into_iter().collect();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Device-resident increment beside the host-array one\n\n`abut bench --resident{}` on {} — \
         {} increments per mode after the first; the bench scene (point masses falling obliquely onto a \
         rigid plate of quads, penalty, global search every 100 increments). Host arrays: \
         `Contact::penalty_step` with the integration on the host. Device-resident: \
         `Contact::encode_increment` and `gpu::CentralDifference` recorded into one encoder, one \
         submit per increment, statistics collected from the lagged ring without waiting.\n",
        if a.quick { " --quick" } else { "" },
        machine(),
        INCREMENTS
    );
    for device in &devices {
        let bandwidth = copy_bandwidth(device);
        let _ = writeln!(
            md,
            "## {device}\n\nCopy kernel: {:.1} GB/s (read + written).\n",
            bandwidth / 1e9
        );
        let _ = writeln!(
            md,
            "| slaves | mode | submits / incr. | bytes read back / incr. | blocking waits / incr. | host time / incr. | of which abut | host time, device idle: cold / warm (median) | of which abut: cold / warm | recording + submit (software adapter) | wall / incr. | GPU time / incr. | H100 estimate / incr. |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
        let mut detail = String::new();
        let us = |v: f64| {
            if v.is_nan() {
                "–".to_string()
            } else {
                format!("{v:.0} µs")
            }
        };
        let pair = |a: f64, b: f64| {
            if a.is_nan() {
                "–".to_string()
            } else {
                format!("{a:.0} / {b:.0} µs")
            }
        };
        for &n in sizes {
            eprintln!("{device}: {n} slaves");
            let c = Config::base(n);
            let h = host_arrays(device, &c)?;
            let r = resident(device, &c)?;
            let compulsory: f64 = bytes.values().sum::<f64>() * n as f64;
            // the dispatches with work in a local increment (one pair, the integrator's included);
            // the global search's, empty in a local increment, are left out
            let dispatches = 14.0;
            let h100 = compulsory / H100_BANDWIDTH + dispatches * H100_DISPATCH;
            for (mode, m) in [("host arrays", &h), ("device-resident", &r)] {
                let gpu: f64 = m.pass_ms.iter().map(|(_, v)| v).sum();
                let _ = writeln!(
                    md,
                    "| {n} | {mode} | {:.2} | {:.0} | {:.2} | {} | {} | {} | {} | {} | {:.2} ms | {} | {} |",
                    m.submits,
                    m.read_back,
                    m.waits,
                    us(m.host_us),
                    us(m.abut_us),
                    pair(m.idle_host_us, m.warm_host_us),
                    pair(m.idle_abut_us, m.warm_abut_us),
                    us(m.submit_us),
                    m.wall_ms,
                    if m.pass_ms.is_empty() {
                        "no timestamps".into()
                    } else {
                        format!("{gpu:.2} ms")
                    },
                    if mode == "device-resident" {
                        format!("≈ {:.0} µs (estimate)", h100 * 1e6)
                    } else {
                        "–".into()
                    }
                );
            }
            if !r.pass_ms.is_empty() {
                let _ = writeln!(
                    detail,
                    "\n{n} slaves, device-resident, GPU time per pass (timed run) and the share of the copy kernel's bandwidth its compulsory bytes reach:\n\n| pass | GPU time / incr. | compulsory bytes | fraction of copy bandwidth |\n|---|---|---|---|"
                );
                for (label, ms) in &r.pass_ms {
                    let Some(&b) = bytes.get(label.as_str()) else {
                        return Err(abut::Error::BadParameter {
                            name: "bench pass",
                            value: format!("'{label}' has no compulsory bytes here"),
                            expected: "a group of abi::groups listed in resident_bytes",
                        });
                    };
                    let b = b * n as f64;
                    let frac = if *ms > 0.0 && b > 0.0 {
                        format!("{:.2}", b / (ms / 1e3) / bandwidth)
                    } else {
                        "–".into()
                    };
                    let _ = writeln!(
                        detail,
                        "| {label} | {ms:.3} ms | {:.1} MB | {frac} |",
                        b / 1e6
                    );
                }
            }
        }
        md.push_str(&detail);
        md.push('\n');
    }
    md.push_str(&crate::resident_share::section(
        &devices,
        share_sizes,
        &crate::resident_share::SHARES,
        true,
        false,
    )?);
    let _ = writeln!(
        md,
        "The H100 estimate is the compulsory bytes of a local increment (the table's passes, {:.0} B \
         per slave) at {:.2} TB/s plus {:.0} µs per dispatch for 14 dispatches — not a measurement: \
         no GPU machine is lent to this project.",
        bytes.values().sum::<f64>(),
        H100_BANDWIDTH / 1e12,
        H100_DISPATCH * 1e6
    );
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let path = a.out.join("resident.md");
    std::fs::write(&path, &md).map_err(|e| io_err(&path, e))?;
    println!("{md}");
    println!("written: {}", path.display());
    Ok(())
}
