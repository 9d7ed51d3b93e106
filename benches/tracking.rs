//! Local tracking against a global search every increment (the seed: "performing a global
//! contact search in every increment will more than double the run time"), and the default
//! schedule's total, on the same sliding scene, per device.
//!
//! `cargo bench --bench tracking` (`-- --quick` for a small scene). Prints a markdown table
//! (also `target/bench/tracking.md`).

use std::fmt::Write as _;
use std::time::Instant;

use abut::mesh::{plate_triangles, point_cloud};
use abut::model::Schedule;
use abut::search::Trigger;
use abut::{Device, GlobalSearch, Model, Pair, Surface};

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (slaves, facets, increments) = if quick {
        (10_000, 10_000, 40)
    } else {
        (100_000, 100_000, 200)
    };
    let n = ((facets as f64 / 2.0).sqrt().round() as usize).max(1);
    let h = 1.0 / n as f64;
    let wave = |x: f64, y: f64| 0.03 * (3.0 * x).sin() * (2.0 * y).cos();
    let plate = plate_triangles(n, n, 1.0, 1.0, 0.2, 1, &wave);
    let cloud = point_cloud(slaves, [0.25, 0.05, -0.5 * h], [0.45, 0.95, 0.5 * h], 2);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&plate.facets)).unwrap();
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m
        .add_pair(Pair::new(set, s).search_radius(2.0 * h))
        .unwrap();
    let base = m.positions().to_vec();
    let first = r.start as usize;
    // slide back and forth at 0.3 facet sizes per increment
    let at = |k: usize| {
        let mut x = base.clone();
        for q in &mut x[first..] {
            q[0] += 0.25 * (0.3 * h / 0.25 * k as f64).sin();
            q[2] += wave(q[0], q[1]);
        }
        x
    };
    let positions: Vec<Vec<[f64; 3]>> = (0..increments).map(at).collect();
    let mut devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(Result::ok)
        .collect();
    devices.push(Device::cpu());
    let mut out = String::new();
    writeln!(out, "Scene: {slaves} slave nodes sliding back and forth (0.3 facet sizes per increment) over a wavy plate of {} triangles, {increments} increments.", plate.facets.len()).unwrap();
    writeln!(out).unwrap();
    writeln!(out, "| device | global every increment, ms | local (fast), ms | local (wide), ms | global ÷ local | default schedule total, s (globals) | wide schedule total, s |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|").unwrap();
    print!("{out}");
    for d in &devices {
        let run = |sched: Schedule| -> (f64, f64, f64, usize) {
            let mut search = GlobalSearch::new(d, &m, p).unwrap();
            search.set_schedule(sched).unwrap();
            search.step(&positions[0]).unwrap(); // warm-up: pipelines, buffers, first global
            let (mut t_local, mut n_local, mut t_global, mut n_global) = (0.0, 0, 0.0, 0);
            let total = Instant::now();
            for x in &positions[1..] {
                let t = Instant::now();
                let r = search.step(x).unwrap();
                let e = t.elapsed().as_secs_f64();
                if r.stats.trigger == Trigger::Local {
                    t_local += e;
                    n_local += 1;
                } else {
                    t_global += e;
                    n_global += 1;
                }
            }
            let total = total.elapsed().as_secs_f64();
            let per = |t: f64, n: usize| if n > 0 { t / n as f64 * 1e3 } else { f64::NAN };
            (
                per(t_global, n_global),
                per(t_local, n_local),
                total,
                n_global,
            )
        };
        let (g_every, _, _, _) = run(Schedule {
            interval: 1,
            budget: 0.5,
            wide_local: false,
            visit_every_slave: false,
        });
        let (_, l_fast, total_fast, globals) = run(Schedule {
            interval: 100,
            budget: 0.5,
            wide_local: false,
            visit_every_slave: false,
        });
        let (_, l_wide, total_wide, _) = run(Schedule {
            interval: 100,
            budget: 0.5,
            wide_local: true,
            visit_every_slave: false,
        });
        let name = if d.is_gpu() {
            d.backend_name()
        } else {
            "CPU mirror".into()
        };
        let line = format!("| {name} | {g_every:.1} | {l_fast:.1} | {l_wide:.1} | {:.1}× | {total_fast:.2} ({globals}) | {total_wide:.2} |", g_every / l_fast);
        println!("{line}");
        out += &line;
        out.push('\n');
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench");
    std::fs::create_dir_all(&dir).ok();
    std::fs::write(dir.join("tracking.md"), out).ok();
}
