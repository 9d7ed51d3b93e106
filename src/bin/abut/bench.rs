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

use abut::abi::groups::{self, Group};
use abut::mesh::{plate_quads, SplitMix64};
use abut::model::Schedule;
use abut::{
    Contact, Device, Enforce, GlobalSearch, Kinematic, Model, Pair, Penalty, Sliding, Stiffness,
    Surface,
};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

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
    /// Only the device-resident increment beside the host-array one (10^4–10^6 slaves, every
    /// GPU adapter): submits, readbacks and waits, host time, GPU time per pass against the copy
    /// kernel's bandwidth, and an H100 estimate. Writes resident.md to --out.
    #[arg(long)]
    pub resident: bool,
    /// Only the global search against parry3d (one thread and rayon), every device, 10^6
    /// slaves on 10^5 triangles within 0.5, 1 and 3 facet sizes, and the floor at 10^6 facets.
    /// Writes search.md and search.json to --out.
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
}

impl Config {
    pub(crate) fn base(slaves: usize) -> Self {
        Config {
            slaves,
            enforce: Enf::Penalty,
            small: false,
            interval: Interval::Every(100),
            scale: 1.0,
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
}

const INCREMENTS: usize = 48;
/// Search radius in facet sizes (the masses start at most 2.5 facets above the plate).
const RADIUS: f64 = 3.0;

pub(crate) fn scene(c: &Config) -> abut::Result<BenchScene> {
    let side = ((c.slaves as f64 / 4.0).sqrt().round() as usize).max(4);
    let h = 1.0 / side as f64;
    let dt = 1e-3;
    // each mass falls a quarter of a facet per increment and lands between increments 2 and 10
    let v0 = 0.25 * h / dt;
    let u = (0.25 * h).min(0.4 / INCREMENTS as f64) / dt;
    let plate = plate_quads(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?;
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let mut rng = SplitMix64::new(7);
    let travel = u * dt * INCREMENTS as f64;
    let mut pos = Vec::with_capacity(c.slaves);
    let mut z0 = Vec::with_capacity(c.slaves);
    for _ in 0..c.slaves {
        let z = v0 * dt * rng.range(2.0, 10.0);
        pos.push([rng.range(0.02, 0.98 - travel), rng.range(0.02, 0.98), z]);
        z0.push(z);
    }
    let range = model.add_nodes(&pos, &vec![1.0; c.slaves])?;
    let set = model.add_node_set(&range.to_vec())?;
    let enforce = match c.enforce {
        Enf::Penalty => Enforce::Penalty(Penalty {
            stiffness: Stiffness::Auto { scale: c.scale },
            ..Default::default()
        }),
        Enf::Kinematic => Enforce::Kinematic(Kinematic::default()),
    };
    let schedule = match c.interval {
        Interval::Every(n) => Schedule {
            interval: n,
            ..Schedule::default_for(false)
        },
        Interval::Budget => Schedule {
            interval: u32::MAX,
            ..Schedule::default_for(false)
        },
    };
    model.add_pair(
        Pair::new(set, master)
            .search_radius(RADIUS * h)
            .enforce(enforce)
            .sliding(if c.small {
                Sliding::Small
            } else {
                Sliding::Finite
            })
            .schedule(schedule),
    )?;
    Ok(BenchScene {
        model,
        first: range.start as usize,
        h,
        dt,
        v0,
        u,
        z0,
    })
}

/// The exact height at time t of a mass released at z0 falling at v0: free flight, then a
/// half-sine on the penalty spring of circular frequency ω and a rebound at v0 (penalty), or
/// a landing that stops it (kinematic).
fn exact_z(z0: f64, v0: f64, omega: Option<f64>, t: f64) -> f64 {
    let t_hit = z0 / v0;
    if t <= t_hit {
        return z0 - v0 * t;
    }
    match omega {
        None => 0.0,
        Some(w) => {
            let s = t - t_hit;
            if s <= std::f64::consts::PI / w {
                -(v0 / w) * (w * s).sin()
            } else {
                v0 * (s - std::f64::consts::PI / w)
            }
        }
    }
}

/// The same central-difference run in f64 with exact geometry (flat plate z = 0, linear
/// spring k or a kinematic stop): the final heights.
fn f64_reference(sc: &BenchScene, k: Option<f64>) -> Vec<f64> {
    sc.z0
        .iter()
        .map(|&z0| {
            let (mut z, mut v) = (z0, -sc.v0);
            for _ in 0..INCREMENTS {
                if let Some(k) = k {
                    v += sc.dt * k * (-z).max(0.0);
                }
                z += sc.dt * v;
                if k.is_none() && z < 0.0 {
                    z = 0.0;
                    v = 0.0;
                }
            }
            z
        })
        .collect()
}

/// Runs configuration `c` on `device`.
fn measure(device: &Device, c: &Config) -> abut::Result<Row> {
    let sc = scene(c)?;
    let timed = device.enable_timestamps(true);
    let mut contact = Contact::new(device, &sc.model)?;
    let n = c.slaves;
    let mut x = sc.model.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    for vi in &mut v[sc.first..] {
        *vi = [sc.u, 0.0, -sc.v0];
    }
    // k of the automatic rule on a rigid master: AUTO_STIFFNESS·scale·m/dt² (m = 1)
    let k = abut::abi::penalty::AUTO_STIFFNESS * c.scale / (sc.dt * sc.dt);
    let omega = (c.enforce == Enf::Penalty).then(|| k.sqrt());
    let mut touched = vec![false; n];
    let mut deepest = vec![0.0f64; n];
    let mut first_ms = 0.0;
    let mut traffic0 = None;
    let mut t_steady = Instant::now();
    for step in 0..INCREMENTS {
        let t = Instant::now();
        match c.enforce {
            Enf::Penalty => {
                let r = contact.penalty_step(&x, &v, sc.dt)?;
                for (j, i) in (sc.first..x.len()).enumerate() {
                    let f = r.forces[i];
                    if f[2] != 0.0 {
                        touched[j] = true;
                    }
                    for a in 0..3 {
                        v[i][a] += sc.dt * f[a];
                        x[i][a] += sc.dt * v[i][a];
                    }
                    deepest[j] = deepest[j].min(x[i][2]);
                }
            }
            Enf::Kinematic => {
                for i in sc.first..x.len() {
                    for a in 0..3 {
                        x[i][a] += sc.dt * v[i][a];
                    }
                }
                let before: Vec<f64> = v[sc.first..].iter().map(|w| w[2]).collect();
                contact.kinematic_step(&mut x, &mut v, &mut [], sc.dt)?;
                for (j, i) in (sc.first..x.len()).enumerate() {
                    if v[i][2] != before[j] {
                        touched[j] = true;
                    }
                    deepest[j] = deepest[j].min(x[i][2]);
                }
            }
        }
        if step == 0 {
            first_ms = 1e3 * t.elapsed().as_secs_f64();
            traffic0 = device.traffic();
            t_steady = Instant::now();
        }
    }
    let steady_ms = 1e3 * t_steady.elapsed().as_secs_f64() / (INCREMENTS - 1) as f64;
    let traffic = match (device.traffic(), traffic0) {
        (Some(a), Some(b)) => a.since(&b),
        _ => abut::Traffic::default(),
    };
    let per = (INCREMENTS - 1) as f64;
    let t_end = sc.dt * INCREMENTS as f64;
    let reference = f64_reference(&sc, omega.map(|_| k));
    let mut e = Errors::default();
    let (mut ke, mut ke_exact, mut ke0) = (0.0, 0.0, 0.0);
    for j in 0..n {
        let i = sc.first + j;
        let z = x[i][2];
        let ze = exact_z(sc.z0[j], sc.v0, omega, t_end);
        e.position = e.position.max((z - ze).abs() / sc.h);
        e.vs_f64 = e.vs_f64.max((z - reference[j]).abs() / sc.h);
        let (dv, dv_exact) = (
            v[i][2] + sc.v0,
            if omega.is_some() { 2.0 * sc.v0 } else { sc.v0 },
        );
        e.impulse = e.impulse.max((dv - dv_exact).abs() / dv_exact);
        match omega {
            Some(w) => {
                let pen = sc.v0 / w;
                e.penetration = e.penetration.max((-deepest[j] - pen).abs() / pen);
            }
            None => e.penetration = e.penetration.max(-deepest[j] / sc.h),
        }
        if !touched[j] || z < -2.0 * omega.map_or(sc.h, |w| sc.v0 / w) {
            e.missed += 1;
        }
        ke += 0.5 * v[i][2] * v[i][2];
        ke_exact += 0.5 * if omega.is_some() { sc.v0 * sc.v0 } else { 0.0 };
        ke0 += 0.5 * sc.v0 * sc.v0;
    }
    e.energy = (ke - ke_exact).abs() / ke0;
    Ok(Row {
        device: device.to_string(),
        backend: device.backend_name(),
        config: *c,
        label: c.label(),
        increments: INCREMENTS,
        first_ms,
        steady_ms,
        gpu_ms: timed.then(|| traffic.pass_ns.values().sum::<f64>() / per / 1e6),
        pass_ms: traffic
            .pass_ns
            .iter()
            .map(|(k, v)| (k.clone(), v / per / 1e6))
            .collect(),
        ns_per_slave: steady_ms * 1e6 / n as f64,
        errors: e,
        dispatches: traffic.total_dispatches() as f64 / per,
        uploaded_bytes: traffic.uploaded_bytes as f64 / per,
        read_back_bytes: traffic.read_back_bytes as f64 / per,
    })
}

/// A search-only row: abut's global search and parry3d's nearest-point queries on the same
/// plate (quads split into triangles) and the same points.
#[derive(Clone, Debug, Serialize)]
struct SearchRow {
    slaves: usize,
    facets: usize,
    who: String,
    first_ms: f64,
    steady_ms: f64,
    ns_per_slave: f64,
    /// Largest difference of the distance found to parry's, in facet sizes.
    max_distance_difference: f64,
}

fn search_rows(devices: &[Device], slaves: usize) -> abut::Result<Vec<SearchRow>> {
    use parry3d::math::Vector as PVec;
    use parry3d::query::PointQuery;
    let sc = scene(&Config::base(slaves))?;
    let pos = sc.model.positions();
    let plate: Vec<[f64; 3]> = pos[..sc.first].to_vec();
    let side = ((plate.len() as f64).sqrt() as usize) - 1;
    let mut tris = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let id = |i: usize, j: usize| (j * (side + 1) + i) as u32;
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let radius = RADIUS * sc.h;
    let verts: Vec<PVec> = plate
        .iter()
        .map(|p| PVec::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let queries: Vec<PVec> = pos[sc.first..]
        .iter()
        .map(|p| PVec::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let run_parry = || {
        let mesh = parry3d::shape::TriMesh::new(verts.clone(), tris.clone()).expect("valid mesh");
        // the same question abut answers: the nearest point within the search radius
        queries
            .iter()
            .map(|&q| {
                mesh.project_local_point_with_max_dist(q, false, radius as f32)
                    .map_or(f64::INFINITY, |p| (p.point - q).length() as f64)
            })
            .collect::<Vec<f64>>()
    };
    let t = Instant::now();
    let parry = run_parry();
    let first = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _ = run_parry();
    let steady = t.elapsed().as_secs_f64();
    let mut rows = vec![SearchRow {
        slaves,
        facets: side * side,
        who: "parry3d 0.31 TriMesh (build + project, 1 CPU thread)".into(),
        first_ms: 1e3 * first,
        steady_ms: 1e3 * steady,
        ns_per_slave: 1e9 * steady / slaves as f64,
        max_distance_difference: 0.0,
    }];
    for d in devices {
        let pair = abut::PairId(0);
        let mut s = GlobalSearch::new(d, &sc.model, pair)?;
        let t = Instant::now();
        let r = s.run(pos)?;
        let first = t.elapsed().as_secs_f64();
        let reps = 3;
        let t = Instant::now();
        for _ in 0..reps {
            s.run(pos)?;
        }
        let steady = t.elapsed().as_secs_f64() / reps as f64;
        // found by both: the distances; by one side only: agreement when it is at the radius
        let mut worst = 0.0f64;
        for (j, hit) in r.contacts().enumerate() {
            let p = parry[j];
            let diff = match (hit, p.is_finite()) {
                (Some(h), true) => (h.distance - p).abs(),
                (Some(h), false) => (h.distance - radius).abs(),
                (None, true) => (p - radius).abs(),
                (None, false) => 0.0,
            };
            worst = worst.max(diff / sc.h);
        }
        rows.push(SearchRow {
            slaves,
            facets: side * side,
            who: format!("abut global search, {d}"),
            first_ms: 1e3 * first,
            steady_ms: 1e3 * steady,
            ns_per_slave: 1e9 * steady / slaves as f64,
            max_distance_difference: worst,
        });
    }
    Ok(rows)
}

/// Bytes each kernel of a steady penalty increment (local search) reads and writes per slave
/// node on this scene — the compulsory traffic of its storage bindings, from the layout types:
/// a node is 16 B (vec4<f32>), a hit `GpuHit` (64 B), a facet 16 B (four u32), a contact output
/// `ContactOut`, a quad facet touches 4 nodes; a plate node has 4 facets; there are about 4
/// slaves per facet and per master node (the scene's ratio).
pub(crate) fn kernel_bytes() -> Vec<(&'static str, f64)> {
    use abut::abi::passes;
    // (kernel, bytes per slave); the groups that run them are in PASSES
    let node = 16.0;
    let hit = std::mem::size_of::<abut::abi::search::GpuHit>() as f64;
    let out = std::mem::size_of::<abut::abi::penalty::ContactOut>() as f64;
    let facet = 16.0;
    let per_master = 0.25; // master nodes (or facets) per slave
    let nodes = 1.0 + per_master; // slaves and master nodes, per slave
    vec![
        // the caller's positions in (16 B) and the frame's nodes out (16 B), per node
        (passes::TO_LOCAL.entry, 32.0 * nodes),
        // positions now and at the last global search, of slaves and master nodes
        (
            passes::MOTION.entry,
            (2.0 * node) * (1.0 + per_master) + 4.0,
        ),
        // the hit in and out, the tracked node's 4 facets with their 4 nodes
        (
            passes::LOCAL_SEARCH.entry,
            2.0 * hit + 4.0 * (facet + 4.0 * node) + 4.0,
        ),
        // per master node: its facets and their nodes, the normal out
        (
            passes::NODAL_NORMALS.entry,
            per_master * (4.0 * (facet + 4.0 * node) + node),
        ),
        // hit, node, velocity, the facet's 4 nodes and normals, state in/out, output out
        (
            passes::PENALTY.entry,
            hit + 2.0 * node + 8.0 * node + 2.0 * 32.0 + out,
        ),
        // each slave in contact: its output's force, status and bound shares (28 B), its hit's
        // weights and facet (20 B) and the facet's pair nodes; the 32 B fixed-point sums of each
        // master node read and written once (the atomics of the slaves sharing a node meet in
        // cache)
        (
            passes::SCATTER_FORCES.entry,
            28.0 + 20.0 + facet + per_master * 2.0 * 32.0,
        ),
        // each pair node: its pair-node record, its sums in and its force and bound row out;
        // a slave node also reads its own output (28 B)
        (
            passes::GATHER.entry,
            (node + 32.0 + node + 28.0) + per_master * (node + 32.0 + node),
        ),
        // each pair node: its record (16 B), its force (16 B), the caller's force read and
        // written (32 B) and its bound row (8 B)
        (passes::ADD_FORCES.entry, 72.0 * nodes),
    ]
}

/// Compulsory bytes per slave of `group` in a steady local increment: the sum over its kernels,
/// the schedule's one invocation counted as nothing. A kernel with no declared bytes is an error
/// naming it (a group changed and this table did not).
pub(crate) fn group_bytes(group: &Group, kb: &[(&'static str, f64)]) -> Result<f64, String> {
    group
        .passes
        .iter()
        .filter(|p| p.entry != abut::abi::passes::SCHEDULE.entry)
        .map(|p| {
            kb.iter()
                .find(|e| e.0 == p.entry)
                .map(|e| e.1)
                .ok_or_else(|| {
                    format!(
                        "no compulsory bytes declared for kernel '{}' (group '{}')",
                        p.entry, group.label
                    )
                })
        })
        .sum()
}

/// The compute passes (groups, as the increment records them) of a steady penalty increment.
const PASSES: [&Group; 4] = [
    &groups::TO_LOCAL_MOTION_SCHEDULE,
    &groups::LOCAL,
    &groups::NORMALS_PENALTY,
    &groups::SCATTER_GATHER_ADD,
];

/// The bandwidth of a copy kernel on `device` (bytes read + written per second), or of a host
/// memory copy on the CPU path.
pub(crate) fn copy_bandwidth(device: &Device) -> f64 {
    const BYTES: usize = 64 << 20;
    let Some((d, q)) = device.wgpu() else {
        let src = vec![1u8; BYTES];
        let mut dst = vec![0u8; BYTES];
        dst.copy_from_slice(&src);
        let t = Instant::now();
        for _ in 0..5 {
            dst.copy_from_slice(std::hint::black_box(&src));
            std::hint::black_box(&mut dst);
        }
        return 5.0 * 2.0 * BYTES as f64 / t.elapsed().as_secs_f64();
    };
    let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("copy"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<storage, read> src: array<vec4<u32>>;
             @group(0) @binding(1) var<storage, read_write> dst: array<vec4<u32>>;
             @compute @workgroup_size(256)
             fn main(@builtin(global_invocation_id) g: vec3<u32>) {
                 let i = g.x + g.y * 65535u * 256u;
                 if (i < arrayLength(&dst)) { dst[i] = src[i]; }
             }"
            .into(),
        ),
    });
    let pipe = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("copy"),
        layout: None,
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let size = (BYTES as u64).min(d.limits().max_storage_buffer_binding_size / 16 * 16);
    let buf = |usage| {
        d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage,
            mapped_at_creation: false,
        })
    };
    let src = buf(wgpu::BufferUsages::STORAGE);
    let dst = buf(wgpu::BufferUsages::STORAGE);
    let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: src.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: dst.as_entire_binding(),
            },
        ],
    });
    let groups = (size / 16).div_ceil(256) as u32;
    let run = |reps: usize| {
        let mut enc = d.create_command_encoder(&Default::default());
        for _ in 0..reps {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        }
        q.submit([enc.finish()]);
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
    };
    run(1);
    let t = Instant::now();
    run(5);
    5.0 * 2.0 * size as f64 / t.elapsed().as_secs_f64()
}

pub(crate) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines().next().and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|k| k.parse::<f64>().ok())
            })
        })
        .map_or(String::new(), |kb| format!(", {:.0} GiB", kb / 1048576.0));
    format!("{cpu}, {cores} cores{mem}")
}

/// Least-squares slope of log t against log n.
fn exponent(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0.ln(), a.1 + p.1.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = points.iter().fold((0.0, 0.0), |a, p| {
        let dx = p.0.ln() - mx;
        (a.0 + dx * (p.1.ln() - my), a.1 + dx * dx)
    });
    num / den
}

/// Rows on the Pareto front of (time per increment, position error): no other row is at least
/// as fast and as accurate and better in one.
fn pareto(rows: &[Row]) -> Vec<usize> {
    let err = |r: &Row| r.errors.position.max(1e-12);
    (0..rows.len())
        .filter(|&i| {
            !rows.iter().enumerate().any(|(j, r)| {
                j != i
                    && r.steady_ms <= rows[i].steady_ms
                    && err(r) <= err(&rows[i])
                    && (r.steady_ms < rows[i].steady_ms || err(r) < err(&rows[i]))
            })
        })
        .collect()
}

fn plot(rows: &[Row], front: &[usize], path: &std::path::Path, title: &str) -> Result<(), String> {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (1000, 680)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let err = |r: &Row| r.errors.position.max(1e-9);
    let (t_lo, t_hi) = rows.iter().fold((f64::MAX, 0.0f64), |a, r| {
        (a.0.min(r.steady_ms), a.1.max(r.steady_ms))
    });
    let (e_lo, e_hi) = rows.iter().fold((f64::MAX, 0.0f64), |a, r| {
        (a.0.min(err(r)), a.1.max(err(r)))
    });
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 16))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (t_lo * 0.7..t_hi * 1.4).log_scale(),
            (e_lo * 0.5..e_hi * 2.0).log_scale(),
        )
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("time per increment, steady state [ms]")
        .y_desc("final position error [facet sizes]")
        .draw()
        .map_err(|e| e.to_string())?;
    let backends: Vec<String> = {
        let mut b: Vec<String> = rows.iter().map(|r| r.backend.clone()).collect();
        b.sort();
        b.dedup();
        b
    };
    let colours = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    for (k, b) in backends.iter().enumerate() {
        let c = colours[k % colours.len()];
        chart
            .draw_series(
                rows.iter()
                    .filter(|r| &r.backend == b)
                    .map(|r| Circle::new((r.steady_ms, err(r)), 4, c.filled())),
            )
            .map_err(|e| e.to_string())?
            .label(b.clone())
            .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
    }
    let mut f: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| (rows[i].steady_ms, err(&rows[i])))
        .collect();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(f.clone(), BLACK.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(f.iter().map(|&p| Circle::new(p, 7, BLACK.stroke_width(2))))
        .map_err(|e| e.to_string())?;
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// Runs the benchmark.
pub fn bench(a: &BenchArgs) -> abut::Result<()> {
    if a.resident {
        return crate::resident_bench::run(a);
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
    let kb = kernel_bytes();
    let total: f64 = kb.iter().map(|k| k.1).sum();
    let largest = *sizes.last().unwrap_or(&1);
    let _ = writeln!(md, "Bytes a steady penalty increment (local search) moves per slave node, by kernel: the compulsory traffic of its bindings (see `kernel_bytes` in src/bin/abut/bench.rs). The bound is that traffic at the bandwidth of a copy kernel measured on the same adapter in this run (a host memory copy for the CPU path); the fraction is the bound over the measured time, per pass from the GPU timestamps where there are some, and for the whole increment from the wall clock — base configuration, {largest} slaves.\n");
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

pub(crate) fn io_err(p: &std::path::Path, e: std::io::Error) -> abut::Error {
    abut::Error::BadParameter {
        name: "bench output",
        value: format!("{}: {e}", p.display()),
        expected: "a writable directory",
    }
}

#[cfg(test)]
mod tests {
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
