//! Global search time against the number of slave nodes and master facets: every GPU adapter
//! found, the CPU mirror, f64 brute force (small sizes) and parry3d's `TriMesh` point
//! projection with the same search radius, on the same meshes and queries.
//!
//! `cargo bench --bench global_search` runs the full matrix (10^3–10^6 slaves on 10^3–10^6
//! facets); `-- --quick` a small one. Prints a markdown table (also written to
//! `target/bench/global_search.md`) headed by the machine and adapters. Times are wall-clock:
//! "first" is the first search after the pipelines are built (buffer allocation, driver
//! warm-up), "steady" the median of the following searches; each search includes the binning,
//! the upload of positions and the readback of results. Ratios are taken within this run.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use abut::mesh::{plate_triangles, point_cloud};
use abut::testing::brute_force::brute_force;
use abut::{Device, GlobalSearch, Model, Pair, PairId, SearchResult, Surface};
use parry3d::math::Vector as PVec;
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;

struct Case {
    slaves: usize,
    facets: usize,
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn ms(d: Duration) -> String {
    let x = d.as_secs_f64() * 1e3;
    if x < 10.0 {
        format!("{x:.2}")
    } else if x < 100.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.0}")
    }
}

/// A wavy triangle plate of about `facets` triangles on [0,1]², slaves in a slab of ±2 facet
/// sizes around it, search radius one facet size.
fn build(case: &Case) -> (Model, PairId, f64, Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let n = ((case.facets as f64 / 2.0).sqrt().round() as usize).max(1);
    let h = 1.0 / n as f64;
    let plate = plate_triangles(n, n, 1.0, 1.0, 0.2, 1, &|x, y| {
        0.05 * (6.0 * x).sin() * (4.0 * y).cos()
    });
    let slaves = point_cloud(
        case.slaves,
        [0.0, 0.0, -0.05 - 2.0 * h],
        [1.0, 1.0, 0.05 + 2.0 * h],
        2,
    );
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&plate.facets)).unwrap();
    let r = m.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(h)).unwrap();
    (m, p, h, plate.positions, plate.facets)
}

/// (setup, first, steady median, result) of `reps` searches on `device`.
fn time_search(
    device: &Device,
    m: &Model,
    p: PairId,
    reps: usize,
) -> (Duration, Duration, Duration, SearchResult) {
    let t = Instant::now();
    let mut s = GlobalSearch::new(device, m, p).unwrap();
    let setup = t.elapsed();
    let t = Instant::now();
    let first = s.run(m.positions()).unwrap();
    let first_t = t.elapsed();
    let steady = (0..reps)
        .map(|_| {
            let t = Instant::now();
            s.run(m.positions()).unwrap();
            t.elapsed()
        })
        .collect();
    (setup, first_t, median(steady), first)
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{cpu}, {cores} cores")
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let cases: Vec<Case> = if quick {
        vec![
            Case {
                slaves: 1_000,
                facets: 1_000,
            },
            Case {
                slaves: 10_000,
                facets: 10_000,
            },
        ]
    } else {
        let mut v = Vec::new();
        for facets in [1_000, 100_000, 1_000_000] {
            for slaves in [1_000, 10_000, 100_000, 1_000_000] {
                v.push(Case { slaves, facets });
            }
        }
        v.insert(
            4,
            Case {
                slaves: 10_000,
                facets: 10_000,
            },
        );
        v
    };
    let gpus: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(Result::ok)
        .collect();
    let mut out = String::new();
    writeln!(
        out,
        "Machine: {}. abut {}, {}.",
        machine(),
        env!("CARGO_PKG_VERSION"),
        if quick { "quick run" } else { "full run" }
    )
    .unwrap();
    for g in &gpus {
        writeln!(out, "- GPU: {g}").unwrap();
    }
    if gpus.is_empty() {
        writeln!(out, "- GPU: none found (only the CPU rows ran)").unwrap();
    }
    writeln!(
        out,
        "- CPU mirror: abut's f32 mirror of the kernels, one thread"
    )
    .unwrap();
    writeln!(
        out,
        "- parry3d 0.31 `TriMesh::project_local_point_with_max_dist` (BVH), one thread, f32"
    )
    .unwrap();
    writeln!(out).unwrap();
    let mut header = String::from("| slaves | facets | found |");
    let mut rule = String::from("|---:|---:|---:|");
    for g in &gpus {
        header += &format!(
            " {} first ms | {} steady ms | ns/slave |",
            g.backend_name(),
            g.backend_name()
        );
        rule += "---:|---:|---:|";
    }
    header += " CPU mirror ms | brute force ms | parry build ms | parry query ms | parry agrees |";
    rule += "---:|---:|---:|---:|---:|";
    if let Some(g) = gpus.first() {
        header += &format!(
            " {} vs CPU mirror | {} vs parry build+query |",
            g.backend_name(),
            g.backend_name()
        );
        rule += "---:|---:|";
    }
    writeln!(out, "{header}\n{rule}").unwrap();
    print!("{out}");
    for case in &cases {
        let (m, p, h, verts, tris) = build(case);
        let reps = if case.slaves >= 1_000_000 || case.facets >= 1_000_000 {
            3
        } else {
            7
        };
        let mut row = String::new();
        let mut gpu_steady = None;
        let mut found = 0;
        let mut first_result = None;
        for g in &gpus {
            let (_setup, first, steady, r) = time_search(g, &m, p, reps);
            gpu_steady.get_or_insert(steady);
            found = r.contacts().flatten().count();
            row += &format!(
                " {} | {} | {:.0} |",
                ms(first),
                ms(steady),
                steady.as_secs_f64() * 1e9 / case.slaves as f64
            );
            first_result.get_or_insert(r);
        }
        let (_, _, cpu_steady, cpu_r) = time_search(
            &Device::cpu(),
            &m,
            p,
            if case.slaves >= 100_000 { 2 } else { 5 },
        );
        found = found.max(cpu_r.contacts().flatten().count());
        let reference = first_result.unwrap_or(cpu_r);
        let master = m.surface(m.pair(p).unwrap().master).unwrap();
        let brute = if (case.slaves as f64) * (tris.len() as f64) <= 1e8 {
            let t = Instant::now();
            std::hint::black_box(brute_force(master, m.positions(), &reference.slaves, h));
            ms(t.elapsed())
        } else {
            "—".into()
        };
        // parry3d on the same triangles and queries
        let t = Instant::now();
        let pv: Vec<PVec> = verts
            .iter()
            .map(|x| PVec::new(x[0] as f32, x[1] as f32, x[2] as f32))
            .collect();
        let mesh = TriMesh::new(pv, tris.clone()).unwrap();
        let parry_build = t.elapsed();
        let queries: Vec<PVec> = reference
            .slaves
            .iter()
            .map(|&s| {
                let x = m.positions()[s as usize];
                PVec::new(x[0] as f32, x[1] as f32, x[2] as f32)
            })
            .collect();
        let t = Instant::now();
        let proj: Vec<Option<f32>> = queries
            .iter()
            .map(|&q| {
                mesh.project_local_point_with_max_dist(q, false, h as f32)
                    .map(|pp| (pp.point - q).length())
            })
            .collect();
        let parry_query = t.elapsed();
        let tol = 1e-5;
        let agree = reference
            .contacts()
            .zip(&proj)
            .filter(|(a, b)| match (a, b) {
                (Some(a), Some(b)) => (a.distance - *b as f64).abs() < tol,
                (None, None) => true,
                // found by one side only: agreement when the distance is at the radius
                (Some(a), None) => (a.distance - h).abs() < tol,
                (None, Some(b)) => (*b as f64 - h).abs() < tol,
            })
            .count();
        row += &format!(
            " {} | {} | {} | {} | {:.3}% |",
            ms(cpu_steady),
            brute,
            ms(parry_build),
            ms(parry_query),
            100.0 * agree as f64 / case.slaves as f64
        );
        if let Some(g) = gpu_steady {
            row += &format!(
                " {:.1}× | {:.1}× |",
                cpu_steady.as_secs_f64() / g.as_secs_f64(),
                (parry_build + parry_query).as_secs_f64() / g.as_secs_f64()
            );
        }
        let line = format!("| {} | {} | {} |{row}", case.slaves, tris.len(), found);
        println!("{line}");
        out += &line;
        out.push('\n');
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench");
    std::fs::create_dir_all(&dir).ok();
    std::fs::write(dir.join("global_search.md"), out).ok();
}
