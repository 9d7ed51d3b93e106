//! Small against finite sliding on the same scene: cost per increment, and the error small
//! sliding makes (penalty force against finite sliding's) as the sliding distance grows — the
//! speed-against-error trade-off in one table.
//!
//! `cargo bench --bench small_sliding` (`-- --quick` for a small scene). Prints a markdown
//! table (also `target/bench/small_sliding.md`).

use std::fmt::Write as _;
use std::time::Instant;

use abut::mesh::{plate_quads, point_cloud};
use abut::{Contact, Device, Enforce, Model, Pair, Penalty, Sliding, Stiffness, Surface};

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (n, slaves, increments) = if quick {
        (40, 2_000, 20)
    } else {
        (140, 20_000, 50)
    };
    let h = 1.0 / n as f64;
    let wave = |x: f64, y: f64| 0.04 * (6.0 * x).sin() * (5.0 * y).cos();
    let plate = plate_quads(n, n, 1.0, 1.0, 0.0, 1, &wave);
    let cloud = point_cloud(slaves, [0.2, 0.2, 0.0], [0.6, 0.8, 0.0], 2);
    let build = |sliding: Sliding| {
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![1e9; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        // slaves 0.1 h into the surface
        let pos: Vec<[f64; 3]> = cloud
            .iter()
            .map(|p| [p[0], p[1], wave(p[0], p[1]) - 0.1 * h])
            .collect();
        let r = m.add_nodes(&pos, &vec![1.0; pos.len()]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        let pen = Penalty {
            stiffness: Stiffness::Absolute(1e3),
            ..Default::default()
        };
        m.add_pair(
            Pair::new(set, s)
                .search_radius(2.0 * h)
                .sliding(sliding)
                .enforce(Enforce::Penalty(pen)),
        )
        .unwrap();
        (m, r.start as usize)
    };
    let mut devices: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(Result::ok)
        .take(1)
        .collect();
    devices.push(Device::cpu());
    let mut out = String::new();
    writeln!(out, "Scene: {slaves} slave nodes 0.1 element lengths into a wavy plate of {} quads (element length h = {h:.4}), sliding along x by the distance in the first column over {increments} increments; penalty k = 1e3, rigid master.", plate.facets.len()).unwrap();
    writeln!(out).unwrap();
    writeln!(out, "| device | slide (h) | finite ms/increment | small ms/increment | finite ÷ small | force error of small (mean, max) | slid > h at the end |").unwrap();
    writeln!(out, "|---|---:|---:|---:|---:|---:|---:|").unwrap();
    print!("{out}");
    for d in &devices {
        for slide in [0.1, 0.5, 1.0, 2.0, 4.0] {
            let mut times = Vec::new();
            let mut forces = Vec::new();
            let mut slid = 0;
            for sliding in [Sliding::Finite, Sliding::Small] {
                let (m, first) = build(sliding);
                let mut c = Contact::new(d, &m).unwrap();
                c.request_outputs(sliding == Sliding::Small);
                let v = vec![[0.0; 3]; m.positions().len()];
                let mut x = m.positions().to_vec();
                c.penalty_step(&x, &v, 1e-3).unwrap(); // first increment (anchoring, warm-up)
                let t = Instant::now();
                let mut last = Vec::new();
                for k in 1..=increments {
                    let dx = slide * h * k as f64 / increments as f64;
                    for (i, p) in x[first..].iter_mut().enumerate() {
                        let c0 = cloud[i];
                        p[0] = c0[0] + dx;
                        p[2] = wave(p[0], p[1]) - 0.1 * h;
                    }
                    last = c.penalty_step(&x, &v, 1e-3).unwrap().forces[first..].to_vec();
                }
                times.push(t.elapsed().as_secs_f64() * 1e3 / increments as f64);
                forces.push(last);
                if sliding == Sliding::Small {
                    slid = c.outputs()[0]
                        .1
                        .search
                        .as_ref()
                        .map_or(0, |s| s.stats.slid_too_far);
                }
            }
            let mut errs: Vec<f64> = forces[0]
                .iter()
                .zip(&forces[1])
                .filter(|(f, _)| f[2].abs() > 0.0)
                .map(|(f, g)| {
                    ((0..3).map(|a| (f[a] - g[a]).powi(2)).sum::<f64>()).sqrt()
                        / (0..3).map(|a| f[a] * f[a]).sum::<f64>().sqrt()
                })
                .collect();
            errs.sort_by(f64::total_cmp);
            let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
            let max = errs.last().copied().unwrap_or(0.0);
            let name = if d.is_gpu() {
                d.backend_name()
            } else {
                "CPU mirror".into()
            };
            let line = format!(
                "| {name} | {slide} | {:.2} | {:.2} | {:.1}× | {:.1} %, {:.0} % | {slid} |",
                times[0],
                times[1],
                times[0] / times[1],
                100.0 * mean,
                100.0 * max
            );
            println!("{line}");
            out += &line;
            out.push('\n');
        }
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench");
    std::fs::create_dir_all(&dir).ok();
    std::fs::write(dir.join("small_sliding.md"), out).ok();
}
