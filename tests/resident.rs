//! The device-resident increment (`Contact::encode_increment`) against the host-array one
//! (`Contact::penalty_step`): the same forces and statistics over increments with local and
//! global searches, friction, balanced pairs and a motion-budget trigger; no readback and no
//! wait per increment; a jump past the budget caught in the same increment.

mod common;

use abut::mesh::plate_quads;
use abut::model::Schedule;
use abut::testing::abi::stats::STATS_BYTES;
use abut::{
    Contact, Device, Enforce, Friction, IncrementStats, Model, Pair, Penalty, ResidentIo,
    Stiffness, Surface,
};
use common::{gpus, node_buffers, read_buffer as read, vec4};

/// Rounds to f32 and back: positions both paths see exactly.
fn f32r(v: f64) -> f64 {
    v as f32 as f64
}

/// Positions and velocities of an increment.
type Motion = dyn Fn(usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A scene whose motion is prescribed: a master plate that ripples, a grid of slave nodes that
/// sinks into it and slides (friction), and one slave that starts far above the plate, out of
/// reach of every facet, and jumps into it at increment `jump`.
struct Scene {
    model: Model,
    /// Positions and velocities of increment `k`.
    motion: Box<Motion>,
    dt: f64,
    jumper: usize,
}

fn scene(jump: usize, balanced: bool, interval: u32) -> Scene {
    scene_at(jump, balanced, interval, 0.0, 0.0)
}

/// `scene`, displaced by `shift` along x and travelling `travel` along x per increment.
fn scene_at(jump: usize, balanced: bool, interval: u32, shift: f64, travel: f64) -> Scene {
    let mut plate = plate_quads(10, 10, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    for p in &mut plate.positions {
        p[0] += shift;
    }
    let mut model = Model::new_3d();
    let master_nodes = model
        .add_nodes(&plate.positions, &vec![4.0; plate.positions.len()])
        .unwrap();
    let master = model.add_surface(Surface::quads(&plate.facets)).unwrap();
    let n = 12;
    let mut slaves = Vec::new();
    for j in 0..n {
        for i in 0..n {
            slaves.push([
                0.1 + 0.5 * i as f64 / n as f64,
                0.1 + 0.5 * j as f64 / n as f64,
                0.004,
            ]);
        }
    }
    slaves.push([0.55, 0.45, 2.5]); // the jumper
    for p in &mut slaves {
        p[0] += shift;
    }
    let range = model.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = model.add_node_set(&range.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Absolute(2.0e3),
        damping: 0.05,
        ..Default::default()
    };
    let mut pair = Pair::new(set, master)
        .search_radius(0.25)
        .enforce(Enforce::Penalty(pen))
        .friction(Friction::coulomb(0.3))
        .schedule(Schedule {
            interval,
            budget: 0.5,
            wide_local: false,
            visit_every_slave: false,
        });
    if balanced {
        // the slave grid as a surface of its own (its nodes in quads), weighted 0.5
        let mut quads = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = range.start + (j * n + i) as u32;
                quads.push([a, a + 1, a + 1 + n as u32, a + n as u32]);
            }
        }
        let slave_surface = model.add_surface(Surface::quads(&quads)).unwrap();
        pair = pair.balanced(slave_surface, 0.5);
    }
    model.add_pair(pair).unwrap();
    let x0 = model.positions().to_vec();
    let dt = 1.0e-3;
    let first_slave = range.start as usize;
    let jumper = range.end as usize - 1;
    let master_end = master_nodes.end as usize;
    // node i's position at increment k
    let at = move |i: usize, k: usize| -> [f64; 3] {
        // the scene near the origin (f32-exact), displaced below
        let (t, mut x) = (k as f64, x0[i]);
        x[0] -= shift;
        if i < master_end {
            x[2] = 0.001 * (3.0 * x[0] + 0.7 * t).sin() * (2.0 * x[1]).cos();
        } else if i == jumper {
            if k >= jump {
                x = [0.55, 0.45, -0.003];
            }
        } else if i >= first_slave {
            x[0] += 0.0125 * t;
            x[2] = 0.004 - 0.0015 * t;
        }
        x.map(f32r)
    };
    let n_nodes = model.positions().len();
    let motion = move |k: usize| {
        let near: Vec<[f64; 3]> = (0..n_nodes).map(|i| at(i, k)).collect();
        // velocities at the half step before: from the increment before (without the travel,
        // which moves slaves and master alike)
        let v = (0..n_nodes)
            .map(|i| {
                let prev = at(i, k.saturating_sub(1));
                [0, 1, 2].map(|c| f32r((near[i][c] - prev[c]) / dt))
            })
            .collect();
        let x = near
            .iter()
            .map(|p| [p[0] + shift + travel * k as f64, p[1], p[2]])
            .collect();
        (x, v)
    };
    Scene {
        model,
        motion: Box::new(motion),
        dt,
        jumper,
    }
}

/// What one increment gave: forces per node, the statistics, and (host path) whether it searched
/// globally and whether the budget made it.
struct Step {
    forces: Vec<[f64; 3]>,
    stable_dt: f64,
    active: u32,
    global: bool,
    budget: bool,
}

fn host_steps(device: &Device, s: &Scene, steps: usize) -> Vec<Step> {
    let mut c = Contact::new(device, &s.model).unwrap();
    c.request_outputs(true);
    (0..steps)
        .map(|k| {
            let (x, v) = (s.motion)(k);
            let r = c.penalty_step(&x, &v, s.dt).unwrap().clone();
            use abut::search::Trigger;
            // every search of the increment (both passes of a balanced pair)
            let triggers: Vec<Trigger> = c
                .outputs()
                .iter()
                .map(|(_, o)| o.search.as_ref().unwrap().stats.trigger)
                .collect();
            Step {
                forces: r.forces,
                stable_dt: r.stable_dt,
                active: r.active as u32,
                global: triggers.iter().any(|t| !matches!(t, Trigger::Local)),
                budget: triggers.iter().any(|t| matches!(t, Trigger::Budget)),
            }
        })
        .collect()
}

fn step_from(forces: &[[f32; 4]], st: &IncrementStats) -> Step {
    Step {
        forces: forces
            .iter()
            .map(|f| [f[0] as f64, f[1] as f64, f[2] as f64])
            .collect(),
        stable_dt: if st.stable_dt >= f32::MAX {
            f64::INFINITY
        } else {
            st.stable_dt as f64
        },
        active: st.active,
        global: st.global_searches > 0,
        budget: st.budget_searches > 0,
    }
}

/// Device buffers of a host program: positions, velocities, forces (vec4<f32> per node).
struct Buffers {
    x: wgpu::Buffer,
    v: wgpu::Buffer,
    f: wgpu::Buffer,
}

fn buffers(device: &Device, n: usize) -> Buffers {
    let [x, v, f] = node_buffers(device, n);
    Buffers { x, v, f }
}

fn resident_steps(device: &Device, s: &Scene, steps: usize) -> Vec<Step> {
    let mut c = Contact::new(device, &s.model).unwrap();
    let n = s.model.positions().len();
    let mut out = Vec::new();
    if device.is_gpu() {
        let b = buffers(device, n);
        let (d, q) = device.wgpu().unwrap();
        for k in 0..steps {
            let (x, v) = (s.motion)(k);
            q.write_buffer(&b.x, 0, bytemuck::cast_slice(&vec4(&x)));
            q.write_buffer(&b.v, 0, bytemuck::cast_slice(&vec4(&v)));
            let mut enc = d.create_command_encoder(&Default::default());
            enc.clear_buffer(&b.f, 0, None);
            c.encode_increment(
                ResidentIo::Gpu {
                    encoder: &mut enc,
                    positions: &b.x,
                    velocities: &b.v,
                    forces: &b.f,
                },
                s.dt,
            )
            .unwrap();
            q.submit([enc.finish()]);
            let forces: Vec<[f32; 4]> =
                bytemuck::pod_collect_to_vec(&read(device, &b.f, (n * 16) as u64));
            let st: IncrementStats =
                bytemuck::pod_read_unaligned(&read(device, c.stats_buffer().unwrap(), STATS_BYTES));
            assert_eq!(st.increment as usize, k + 1, "{device}: increment counter");
            out.push(step_from(&forces, &st));
        }
    } else {
        for k in 0..steps {
            let (x, v) = (s.motion)(k);
            let mut f = vec![[0.0f32; 4]; n];
            c.encode_increment(
                ResidentIo::Cpu {
                    positions: &vec4(&x),
                    velocities: &vec4(&v),
                    forces: &mut f,
                },
                s.dt,
            )
            .unwrap();
            let st = c.collect_stats().unwrap();
            assert_eq!(st.len(), 1);
            out.push(step_from(&f, &st[0]));
        }
    }
    out
}

fn assert_same(what: &str, host: &[Step], dev: &[Step], jumper: usize) {
    let scale = host
        .iter()
        .flat_map(|s| s.forces.iter().flatten())
        .fold(0.0f64, |a, f| a.max(f.abs()));
    assert!(scale > 0.0, "{what}: no contact force at all");
    for (k, (h, d)) in host.iter().zip(dev).enumerate() {
        assert_eq!(h.global, d.global, "{what} increment {k}: global search");
        assert_eq!(h.budget, d.budget, "{what} increment {k}: budget trigger");
        assert_eq!(
            h.active, d.active,
            "{what} increment {k}: slaves in contact"
        );
        for (i, (a, b)) in h.forces.iter().zip(&d.forces).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 3e-5 * scale,
                    "{what} increment {k}: node {i} force {a:?} vs {b:?}"
                );
            }
        }
        let rel = if h.stable_dt.is_finite() {
            (h.stable_dt - d.stable_dt).abs() / h.stable_dt
        } else {
            if d.stable_dt.is_finite() {
                1.0
            } else {
                0.0
            }
        };
        assert!(
            rel < 1e-4,
            "{what} increment {k}: stable dt {} vs {}",
            h.stable_dt,
            d.stable_dt
        );
        let _ = jumper;
    }
}

#[test]
fn resident_increments_match_host_arrays() {
    let steps = 16;
    for balanced in [false, true] {
        let s = scene(7, balanced, 5);
        let cpu_host = host_steps(&Device::cpu(), &s, steps);
        // the scene does what it is meant to: local and global searches, an interval, the
        // budget, and the jumper in contact from the increment it jumped
        assert!(cpu_host.iter().any(|h| !h.global), "no local increment");
        assert!(cpu_host.iter().filter(|h| h.global).count() >= 4);
        assert!(cpu_host[7].budget, "the jump did not trigger the budget");
        if !balanced {
            assert_eq!(cpu_host.iter().filter(|h| h.budget).count(), 1);
        }
        assert!(
            cpu_host[7].forces[s.jumper][2] > 0.0,
            "the jumper is not pushed out in the increment it jumped"
        );
        assert!(cpu_host[6].forces[s.jumper] == [0.0; 3]);
        let what = format!("balanced {balanced}");
        let cpu_dev = resident_steps(&Device::cpu(), &s, steps);
        assert_same(&format!("{what}, CPU path"), &cpu_host, &cpu_dev, s.jumper);
        for g in gpus() {
            let host = host_steps(g, &s, steps);
            let dev = resident_steps(g, &s, steps);
            assert_same(&format!("{what}, {g}"), &host, &dev, s.jumper);
            // and the device-resident increment on the GPU against the CPU path's
            assert_same(
                &format!("{what}, {g} against the CPU path"),
                &cpu_dev,
                &dev,
                s.jumper,
            );
        }
    }
}

/// 1,000 device-resident increments, each recorded with a WGSL integrator into one encoder and
/// submitted: no readback, no wait, no upload by abut (the statistics ring aside), and the masses
/// bounce as on the CPU path's mirror of the same program.
#[test]
fn resident_increments_neither_read_back_nor_wait() {
    use abut::testing::abi::integrate::IntegrateParams;
    use abut::CentralDifference;
    let (model, range, dt) = abut::testing::scenes::bounce(300).unwrap();
    let n = model.positions().len();
    let steps = 1000;
    let masses = model.masses().to_vec();
    let x0 = vec4(model.positions());
    let mut v0 = vec![[0.0f32; 4]; n];
    for v in &mut v0[range.start as usize..] {
        v[2] = -1.0;
    }
    // the CPU path: the same program with the mirrors
    let cpu = {
        let mut c = Contact::new(&Device::cpu(), &model).unwrap();
        let (mut x, mut v, mut f) = (x0.clone(), v0.clone(), vec![[0.0f32; 4]; n]);
        let m32: Vec<f32> = masses.iter().map(|&m| m as f32).collect();
        let ip = IntegrateParams {
            acceleration: [0.0, 0.0, 0.0, dt as f32],
            first: range.start,
            count: range.end - range.start,
            n_nodes: n as u32,
            _pad: 0,
        };
        let mut active = 0u64;
        for _ in 0..steps {
            c.encode_increment(
                ResidentIo::Cpu {
                    positions: &x,
                    velocities: &v,
                    forces: &mut f,
                },
                dt,
            )
            .unwrap();
            abut::testing::cpu::integrate::integrate(&ip, &mut x, &mut v, &mut f, &m32);
            active += c.collect_stats().unwrap()[0].active as u64;
        }
        (x, v, active)
    };
    // every mass came back up at about its impact speed
    for i in range.start as usize..range.end as usize {
        assert!(
            (cpu.1[i][2] - 1.0).abs() < 0.02,
            "CPU path: node {i} rebounds at {}",
            cpu.1[i][2]
        );
    }
    // devices of this test's own (the shared ones count other tests' traffic too)
    let own: Vec<Device> = Device::all_gpus().into_iter().flatten().collect();
    assert_eq!(own.len(), gpus().len(), "adapters found");
    for g in &own {
        let (d, q) = g.wgpu().unwrap();
        let b = buffers(g, n);
        q.write_buffer(&b.x, 0, bytemuck::cast_slice(&x0));
        q.write_buffer(&b.v, 0, bytemuck::cast_slice(&v0));
        let mut c = Contact::new(g, &model).unwrap();
        let mut integ = CentralDifference::new(g, &masses).unwrap();
        let mut record = |c: &mut Contact| {
            let mut enc = d.create_command_encoder(&Default::default());
            c.encode_increment(
                ResidentIo::Gpu {
                    encoder: &mut enc,
                    positions: &b.x,
                    velocities: &b.v,
                    forces: &b.f,
                },
                dt,
            )
            .unwrap();
            integ
                .encode(&mut enc, &b.x, &b.v, &b.f, dt, [0.0; 3], range.clone())
                .unwrap();
            q.submit([enc.finish()]);
        };
        // the first increment readies the pairs (pipelines, buffers, constants uploaded)
        record(&mut c);
        let mut stats = c.collect_stats().unwrap();
        let before = g.traffic().unwrap();
        for _ in 1..steps {
            record(&mut c);
            stats.extend(c.collect_stats().unwrap());
        }
        let t = g.traffic().unwrap().since(&before);
        assert_eq!(t.read_back_bytes, 0, "{g}: bytes read back");
        assert_eq!(t.waits, 0, "{g}: blocking waits");
        assert_eq!(t.uploaded_bytes, 0, "{g}: bytes uploaded");
        assert!(t.total_dispatches() > 0);
        eprintln!(
            "{g}: {} increments, {} statistics collected on the way, {} dropped from the ring, {} bytes of them",
            steps,
            stats.len(),
            c.dropped_stats(),
            t.lagged_read_bytes
        );
        // the test's own readback: every statistic arrives, in order, none lost
        let x: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(g, &b.x, (n * 16) as u64));
        let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(g, &b.v, (n * 16) as u64));
        stats.extend(c.collect_stats().unwrap());
        stats.extend(c.collect_stats().unwrap());
        assert_eq!(
            stats.len() as u64 + c.dropped_stats(),
            steps as u64,
            "{g}: statistics collected and dropped"
        );
        assert!(stats.windows(2).all(|w| w[0].increment < w[1].increment));
        for i in range.start as usize..range.end as usize {
            for a in 0..3 {
                assert!(
                    (v[i][a] - cpu.1[i][a]).abs() < 1e-3,
                    "{g}: node {i} velocity {:?} vs the CPU path's {:?}",
                    v[i],
                    cpu.1[i]
                );
                assert!(
                    (x[i][a] - cpu.0[i][a]).abs() < 1e-5,
                    "{g}: node {i} position"
                );
            }
        }
        if c.dropped_stats() == 0 {
            let active: u64 = stats.iter().map(|s| s.active as u64).sum();
            assert_eq!(active, cpu.2, "{g}: slave-increments in contact");
        }
    }
}

/// A slave that jumps from out of reach into the master, farther than the motion budget, in
/// one increment gets its contact force in that increment (the schedule runs the global search
/// on the device in the same increment), wherever on the plate it lands and whenever it jumps.
#[test]
fn a_jump_past_the_budget_is_caught_in_the_same_increment() {
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for (target, jump) in [
        ([0.55, 0.45, -0.003], 3),
        ([0.05, 0.93, -0.001], 4),
        ([0.999, 0.5, -0.002], 6),
        ([0.3, 0.3, -0.0005], 8),
    ] {
        let s = scene(jump, false, 100);
        let jumper = s.jumper;
        let moved = Scene {
            motion: Box::new({
                let m = s.motion;
                move |k| {
                    let (mut x, mut v) = m(k);
                    if k >= jump {
                        x[jumper] = target.map(f32r);
                        v[jumper] = [0.0; 3];
                    }
                    (x, v)
                }
            }),
            ..s
        };
        for d in &devices {
            let steps = resident_steps(d, &moved, jump + 2);
            for (k, st) in steps.iter().enumerate() {
                let pushed = st.forces[jumper][2] > 0.0;
                assert_eq!(
                    pushed,
                    k >= jump,
                    "{d}: jump to {target:?} at {jump}: increment {k} force {:?}",
                    st.forces[jumper]
                );
                assert_eq!(st.budget, k == jump, "{d}: increment {k}: budget search");
            }
        }
    }
}

/// Host arrays far from the model origin, and a pair that travels far during the run: the frame
/// follows (a new origin and a global search once the pair is 16 times its grid's extent away),
/// so the forces equal those of the same motion near the origin to f32 round-off of the contact
/// forces, however far it goes.
#[test]
fn host_arrays_keep_their_precision_far_away() {
    let steps = 16;
    let near = scene(7, false, 5);
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for (shift, travel) in [(1.0e4, 0.0), (-3.0e5, 0.0), (0.0, 40.0), (2.0e3, -25.0)] {
        let far = scene_at(7, false, 5, shift, travel);
        for d in &devices {
            let a = host_steps(d, &near, steps);
            let b = host_steps(d, &far, steps);
            let scale = a
                .iter()
                .flat_map(|s| s.forces.iter().flatten())
                .fold(0.0f64, |m, f| m.max(f.abs()));
            for (k, (sa, sb)) in a.iter().zip(&b).enumerate() {
                assert_eq!(
                    sa.active, sb.active,
                    "{d} shift {shift} travel {travel}: increment {k}"
                );
                for (i, (fa, fb)) in sa.forces.iter().zip(&sb.forces).enumerate() {
                    for c in 0..3 {
                        assert!(
                            (fa[c] - fb[c]).abs() <= 1e-4 * scale,
                            "{d} shift {shift} travel {travel}: increment {k}, node {i}: {fa:?} vs {fb:?}"
                        );
                    }
                }
            }
        }
    }
}

/// A NaN coordinate in the caller's device positions cannot be checked on the host before the
/// increment: the device names the lowest such node in the statistics, and `collect_stats`
/// turns it into an error that names it.
#[test]
fn a_nan_in_device_positions_is_named() {
    let s = scene(7, false, 5);
    let n = s.model.positions().len();
    let (x, v) = (s.motion)(0);
    let mut x4 = vec4(&x);
    x4[37][1] = f32::NAN;
    x4[90][2] = f32::INFINITY;
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for d in &devices {
        let mut c = Contact::new(d, &s.model).unwrap();
        if let Some((dev, q)) = d.wgpu() {
            let b = buffers(d, n);
            q.write_buffer(&b.x, 0, bytemuck::cast_slice(&x4));
            q.write_buffer(&b.v, 0, bytemuck::cast_slice(&vec4(&v)));
            let mut enc = dev.create_command_encoder(&Default::default());
            c.encode_increment(
                ResidentIo::Gpu {
                    encoder: &mut enc,
                    positions: &b.x,
                    velocities: &b.v,
                    forces: &b.f,
                },
                s.dt,
            )
            .unwrap();
            q.submit([enc.finish()]);
            read(d, &b.f, 16); // the test's wait, so that the ring has the increment
        } else {
            let mut f = vec![[0.0f32; 4]; n];
            c.encode_increment(
                ResidentIo::Cpu {
                    positions: &x4,
                    velocities: &vec4(&v),
                    forces: &mut f,
                },
                s.dt,
            )
            .unwrap();
        }
        let mut err = None;
        for _ in 0..4 {
            if let Err(e) = c.collect_stats() {
                err = Some(e.to_string());
                break;
            }
        }
        let e = err.unwrap_or_else(|| panic!("{d}: no error for a NaN position"));
        assert!(e.contains("node 37"), "{d}: {e}");
    }
}

/// Pipelines are compiled once per device: a balanced pair (two searches and two penalty
/// sides) compiles each pass at most once, and a second `Contact` on the same device compiles
/// nothing (each search used to compile its 14 pipelines, each penalty side its 5).
#[test]
fn pipelines_are_compiled_once_per_device() {
    if gpus().is_empty() {
        return;
    }
    // fresh devices: the shared ones' counters move with the other tests of this binary
    for device in Device::all_gpus().into_iter().flatten() {
        let s = scene(usize::MAX, true, 4);
        let before = device.traffic().unwrap();
        let mut first = Contact::new(&device, &s.model).unwrap();
        for k in 0..3 {
            let (x, v) = (s.motion)(k);
            first.penalty_step(&x, &v, s.dt).unwrap();
        }
        let once = device.traffic().unwrap().since(&before);
        assert!(
            once.pipelines_compiled > 0
                && once.pipelines_compiled <= abut::testing::abi::passes::PASSES.len() as u64,
            "{device}: {} pipelines for {} passes",
            once.pipelines_compiled,
            abut::testing::abi::passes::PASSES.len()
        );
        assert!(
            once.shader_modules_compiled <= abut::testing::abi::shaders::KERNELS.len() as u64,
            "{device}: {} shader modules for {} kernel files",
            once.shader_modules_compiled,
            abut::testing::abi::shaders::KERNELS.len()
        );
        let mid = device.traffic().unwrap();
        let mut second = Contact::new(&device, &s.model).unwrap();
        for k in 0..3 {
            let (x, v) = (s.motion)(k);
            second.penalty_step(&x, &v, s.dt).unwrap();
        }
        let again = device.traffic().unwrap().since(&mid);
        assert_eq!(
            (again.pipelines_compiled, again.shader_modules_compiled),
            (0, 0),
            "{device}: a second contact compiled again"
        );
        // every pass the increments recorded is a declared group (the benchmarks' rows)
        for label in device.traffic().unwrap().dispatches.keys() {
            assert!(
                abut::testing::abi::groups::by_label(label).is_some(),
                "{device}: pass '{label}' is declared by no group"
            );
        }
        eprintln!(
            "{device}: {} pipelines, {} shader modules for a balanced pair and a second contact",
            once.pipelines_compiled, once.shader_modules_compiled
        );
    }
}
