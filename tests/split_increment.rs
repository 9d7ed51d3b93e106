//! `Contact::run_split`: one device-resident increment whose first k entries run on the CPU
//! mirrors and the rest on the GPU, every buffer the increment writes handed over at the split.
//! For every k — every kernel of a global and of a local increment, of a balanced
//! finite-sliding pair with friction, a small-sliding pair and a self-contact pair (its crowding
//! pass), so every kernel an increment has — the split increment gives the full GPU increment's
//! forces and statistics within the two executors' round-off, and the increment after it
//! continues from the state the split left, as it would from the GPU's.

mod common;

use abut::mesh::plate_quads;
use abut::model::Schedule;
use abut::testing::abi::stats::STATS_BYTES;
use abut::{
    Contact, Device, Enforce, Friction, IncrementStats, Model, Pair, Penalty, ResidentIo, Sliding,
    Stiffness, Surface,
};
use common::{gpus, node_buffers, read_buffer as read, vec4};

/// Positions and velocities of an increment.
type Motion = dyn Fn(usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A plate, a grid of slave nodes sinking into it and sliding with friction (a balanced pair),
/// a second grid held by small sliding, and the plate against itself (self-contact); positions
/// and velocities of increment `k`.
struct Scene {
    model: Model,
    motion: Box<Motion>,
    dt: f64,
}

fn scene() -> Scene {
    let plate = plate_quads(8, 8, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    let master_nodes = model
        .add_nodes(&plate.positions, &vec![4.0; plate.positions.len()])
        .unwrap();
    let master = model.add_surface(Surface::quads(&plate.facets)).unwrap();
    let grid = |x0: f64, y0: f64, n: usize| -> Vec<[f64; 3]> {
        (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                [
                    x0 + 0.3 * i as f64 / n as f64,
                    y0 + 0.3 * j as f64 / n as f64,
                    0.004,
                ]
            })
            .collect()
    };
    let n = 7;
    let sliding = model
        .add_nodes(&grid(0.1, 0.1, n), &vec![1.0; n * n])
        .unwrap();
    let anchored = model.add_nodes(&grid(0.55, 0.55, 4), &[1.0; 16]).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Absolute(2.0e3),
        damping: 0.05,
        ..Default::default()
    };
    let mut quads = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = sliding.start + (j * n + i) as u32;
            quads.push([a, a + 1, a + 1 + n as u32, a + n as u32]);
        }
    }
    let slave_surface = model.add_surface(Surface::quads(&quads)).unwrap();
    let set = model.add_node_set(&sliding.to_vec()).unwrap();
    model
        .add_pair(
            Pair::new(set, master)
                .search_radius(0.2)
                .enforce(Enforce::Penalty(pen.clone()))
                .friction(Friction::coulomb(0.3))
                .schedule(Schedule {
                    interval: 50,
                    budget: 0.5,
                    wide_local: false,
                    visit_every_slave: false,
                })
                .balanced(slave_surface, 0.5),
        )
        .unwrap();
    let set = model.add_node_set(&anchored.to_vec()).unwrap();
    model
        .add_pair(
            Pair::new(set, master)
                .search_radius(0.2)
                .enforce(Enforce::Penalty(pen.clone()))
                .sliding(Sliding::Small),
        )
        .unwrap();
    let set = model.add_node_set(&master_nodes.to_vec()).unwrap();
    model
        .add_pair(
            Pair::new(set, master)
                .search_radius(0.05)
                .enforce(Enforce::Penalty(pen))
                // the bucket search's kernels split too (self-contact: its crowding check)
                .search_structure(abut::SearchStructure::Buckets),
        )
        .unwrap();
    let x0 = model.positions().to_vec();
    let dt = 1.0e-3;
    let master_end = master_nodes.end as usize;
    let first_slave = sliding.start as usize;
    let at = move |i: usize, k: usize| -> [f64; 3] {
        let (t, mut x) = (k as f64, x0[i]);
        if i < master_end {
            x[2] = 0.001 * (3.0 * x[0] + 0.7 * t).sin() * (2.0 * x[1]).cos();
        } else if i >= first_slave {
            x[0] += 0.01 * t;
            x[2] = 0.004 - 0.0015 * t;
        }
        x.map(|v| v as f32 as f64)
    };
    let n_nodes = model.positions().len();
    let motion = move |k: usize| {
        let x: Vec<[f64; 3]> = (0..n_nodes).map(|i| at(i, k)).collect();
        let v = (0..n_nodes)
            .map(|i| {
                let prev = at(i, k.saturating_sub(1));
                [0, 1, 2].map(|c| (x[i][c] - prev[c]) / dt)
            })
            .collect();
        (x, v)
    };
    Scene {
        model,
        motion: Box::new(motion),
        dt,
    }
}

/// Forces (xyz per node) and statistics after an increment.
struct After {
    forces: Vec<[f32; 4]>,
    stats: IncrementStats,
}

/// Runs increments `0..=last` of `s` on `device`, increment `split.0` split at entry `split.1`
/// (`None`: none split). Returns what each increment left and the split's entry count.
fn run(
    device: &Device,
    s: &Scene,
    last: usize,
    split: Option<(usize, usize)>,
) -> (Vec<After>, usize) {
    let n = s.model.positions().len();
    let mut c = Contact::new(device, &s.model).unwrap();
    let [x, v, f] = node_buffers(device, n);
    let (d, q) = device.wgpu().unwrap();
    let mut out = Vec::new();
    let mut entries = 0;
    for k in 0..=last {
        let (xk, vk) = (s.motion)(k);
        q.write_buffer(&x, 0, bytemuck::cast_slice(&vec4(&xk)));
        q.write_buffer(&v, 0, bytemuck::cast_slice(&vec4(&vk)));
        q.write_buffer(&f, 0, &vec![0u8; n * 16]);
        match split {
            Some((at, first_gpu)) if at == k => {
                entries = c.run_split(&x, &v, &f, s.dt, first_gpu).unwrap();
            }
            _ => {
                let mut enc = d.create_command_encoder(&Default::default());
                c.encode_increment(
                    ResidentIo::Gpu {
                        encoder: &mut enc,
                        positions: &x,
                        velocities: &v,
                        forces: &f,
                    },
                    s.dt,
                )
                .unwrap();
                q.submit([enc.finish()]);
            }
        }
        out.push(After {
            forces: bytemuck::pod_collect_to_vec(&read(device, &f, (n * 16) as u64)),
            stats: bytemuck::pod_read_unaligned(&read(
                device,
                c.stats_buffer().unwrap(),
                STATS_BYTES,
            )),
        });
    }
    (out, entries)
}

/// Whether two increments agree: forces within `tol` of the largest force, the same active
/// and slipping counts and global searches, the stable increment within `tol`.
fn differs(a: &After, b: &After, tol: f32) -> Option<String> {
    let scale = a
        .forces
        .iter()
        .flat_map(|f| f[..3].iter())
        .fold(0.0f32, |m, v| m.max(v.abs()));
    for (i, (fa, fb)) in a.forces.iter().zip(&b.forces).enumerate() {
        for c in 0..3 {
            if (fa[c] - fb[c]).abs() > tol * scale {
                return Some(format!("node {i} force {:?} vs {:?}", &fa[..3], &fb[..3]));
            }
        }
    }
    let (sa, sb) = (&a.stats, &b.stats);
    if (sa.active, sa.slipping, sa.global_searches) != (sb.active, sb.slipping, sb.global_searches)
    {
        return Some(format!(
            "active/slipping/global {:?} vs {:?}",
            (sa.active, sa.slipping, sa.global_searches),
            (sb.active, sb.slipping, sb.global_searches)
        ));
    }
    if (sa.stable_dt - sb.stable_dt).abs() > tol * sa.stable_dt.abs() {
        return Some(format!("stable_dt {} vs {}", sa.stable_dt, sb.stable_dt));
    }
    None
}

#[test]
fn a_split_at_every_entry_gives_the_gpu_increment() {
    let s = scene();
    for device in gpus() {
        let last = 3;
        let (full, _) = run(device, &s, last, None);
        assert!(
            full[last].stats.active > 0 && full[0].stats.global_searches > 0,
            "{device}: the scene must be in contact and search globally"
        );
        // increment 0 searches globally, increment 2 locally
        for at in [0, 2] {
            let (_, entries) = run(device, &s, at, Some((at, usize::MAX)));
            assert!(entries > 80, "{device}: {entries} entries");
            eprintln!("{device}: increment {at}: {entries} entries");
            for first_gpu in 0..=entries {
                let (split, _) = run(device, &s, at + 1, Some((at, first_gpu)));
                for k in at..=at + 1 {
                    if let Some(why) = differs(&full[k], &split[k], 2e-5) {
                        panic!(
                            "{device}: increment {at} split at entry {first_gpu} of {entries}: \
                             increment {k} differs: {why}"
                        );
                    }
                }
            }
        }
    }
}

/// The CPU path has nothing to split: an error, not a silent full run — and one that leaves
/// the `Contact` as it was (not made device-resident: its host-array increments still run).
#[test]
fn the_cpu_path_refuses_a_split() {
    let s = scene();
    let mut c = Contact::new(&Device::cpu(), &s.model).unwrap();
    let Some(gpu) = gpus().first() else { return };
    let [x, v, f] = node_buffers(gpu, s.model.positions().len());
    let e = c.run_split(&x, &v, &f, s.dt, 0).unwrap_err();
    assert!(e.to_string().contains("CPU path"), "{e}");
    let rest = vec![[0.0; 3]; s.model.positions().len()];
    c.penalty_step(s.model.positions(), &rest, s.dt)
        .unwrap_or_else(|e| panic!("a host-array increment after the refused split: {e}"));
}
