//! The penalty pass against the search's cost: per device, the steady-state time of a global
//! search alone and of a whole penalty increment (search + nodal normals + penalty + contact
//! sort + gather, one submit), frictionless and with Coulomb friction. The increments here
//! search globally every time (schedule interval 1) so that their difference to the search
//! alone is the penalty passes; with the default schedule most increments search locally and
//! cost less (see the tracking benchmark).
//!
//! `cargo bench --bench penalty` (`-- --quick` for the smallest size). Prints a markdown table
//! (also `target/bench/penalty.md`). A search alone reads back its hits (64 bytes per slave);
//! an increment reads back only the forces of the pair's nodes (16 bytes each): the difference
//! of the two times is the penalty passes' cost plus that change in readback.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use abut::mesh::{plate_triangles, point_cloud, SplitMix64};
use abut::model::Schedule;
use abut::{
    Contact, Device, Enforce, Friction, GlobalSearch, Model, Pair, PairId, Penalty, Stiffness,
    Surface,
};

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn build(slaves: usize, facets: usize, friction: Friction) -> (Model, PairId, Vec<[f64; 3]>) {
    let n = ((facets as f64 / 2.0).sqrt().round() as usize).max(1);
    let h = 1.0 / n as f64;
    let plate = plate_triangles(n, n, 1.0, 1.0, 0.2, 1, &|x, y| {
        0.05 * (6.0 * x).sin() * (4.0 * y).cos()
    });
    let cloud = point_cloud(
        slaves,
        [0.0, 0.0, -0.05 - 2.0 * h],
        [1.0, 1.0, 0.05 + 2.0 * h],
        2,
    );
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&plate.facets)).unwrap();
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Auto { scale: 1.0 },
        ..Default::default()
    };
    let p = m
        .add_pair(
            Pair::new(set, s)
                .search_radius(h)
                .enforce(Enforce::Penalty(pen))
                .friction(friction)
                .schedule(Schedule {
                    interval: 1,
                    budget: 0.5,
                    wide_local: false,
                    visit_every_slave: false,
                }),
        )
        .unwrap();
    let mut rng = SplitMix64::new(3);
    let v = (0..m.positions().len())
        .map(|_| {
            [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ]
        })
        .collect();
    (m, p, v)
}

fn time(reps: usize, mut f: impl FnMut()) -> (Duration, Duration) {
    let t = Instant::now();
    f();
    let first = t.elapsed();
    let steady = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .collect();
    (first, median(steady))
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let sizes: &[(usize, usize)] = if quick {
        &[(10_000, 10_000)]
    } else {
        &[(10_000, 10_000), (100_000, 100_000), (1_000_000, 100_000)]
    };
    let mut devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(Result::ok)
        .collect();
    devices.push(Device::cpu());
    let mut out = String::new();
    writeln!(out, "| device | slaves | facets | in contact | search ms | increment ms (frictionless) | increment ms (friction) | penalty ns/slave (frictionless) | penalty ns/slave (friction) | first increment ms |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|").unwrap();
    print!("{out}");
    for &(slaves, facets) in sizes {
        for d in &devices {
            let reps = if slaves >= 1_000_000 { 3 } else { 7 };
            let (m, p, v) = build(slaves, facets, Friction::Frictionless);
            let mut search = GlobalSearch::new(d, &m, p).unwrap();
            let (_, t_search) = time(reps, || {
                search.run(m.positions()).unwrap();
            });
            let mut c = Contact::new(d, &m).unwrap();
            let mut active = 0;
            let (first, t_free) = time(reps, || {
                active = c.penalty_step(m.positions(), &v, 1e-3).unwrap().active;
            });
            let (mf, _, vf) = build(slaves, facets, Friction::coulomb(0.3));
            let mut cf = Contact::new(d, &mf).unwrap();
            let (_, t_fric) = time(reps, || {
                cf.penalty_step(mf.positions(), &vf, 1e-3).unwrap();
            });
            let per =
                |t: Duration| (t.as_secs_f64() - t_search.as_secs_f64()) * 1e9 / slaves as f64;
            let ms = |t: Duration| t.as_secs_f64() * 1e3;
            let name = if d.is_gpu() {
                format!("{} ({})", d.backend_name(), short(d))
            } else {
                "CPU mirror".into()
            };
            let line = format!(
                "| {name} | {slaves} | {facets} | {active} | {:.1} | {:.1} | {:.1} | {:.0} | {:.0} | {:.1} |",
                ms(t_search),
                ms(t_free),
                ms(t_fric),
                per(t_free),
                per(t_fric),
                ms(first)
            );
            println!("{line}");
            out += &line;
            out.push('\n');
        }
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench");
    std::fs::create_dir_all(&dir).ok();
    std::fs::write(dir.join("penalty.md"), out).ok();
}

fn short(d: &Device) -> String {
    d.to_string().split(" (").next().unwrap_or("").to_string()
}
