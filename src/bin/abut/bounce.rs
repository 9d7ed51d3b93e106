//! `abut bounce`: point masses dropped on a plate, once through host arrays (`penalty_step`) and
//! once device-resident with the WGSL integrator, against the exact contact time and rebound.

use super::*;

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
            let mut integ = abut::CentralDifference::new(device, &masses)?;
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
            let ip = abut::testing::abi::integrate::IntegrateParams {
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
                abut::testing::cpu::integrate::integrate(&ip, &mut x, &mut v, &mut f, &m32);
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

pub(crate) fn bounce(a: &BounceArgs) -> abut::Result<()> {
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
