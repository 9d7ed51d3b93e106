//! `abut bench --search`: the global search alone against parry3d, the same queries and radius
//! for every contestant, in one run. A wavy plate of 100,352 triangles (224 × 224 quads, each
//! split in two) and 10^6 slave nodes in random order in a slab of ±2 facet sizes around it,
//! searched within 0.5, 1 and 3 facet sizes by: parry3d 0.31 (`TriMesh` built, then
//! `project_local_point_with_max_dist` per query) on one thread and over all cores with rayon,
//! and abut's global search with the tree, the buckets and `Auto` on the CPU path and on every
//! GPU adapter; then the same on the graded plate (column widths growing 100× across it, a
//! tenth of the slaves), and a table of `Auto` against the better structure. Each contestant's
//! first run apart, then the median of `REPS` runs taken interleaved (every contestant once per
//! round; an abut contestant over `SLOW` times the fastest first run on its device gets one
//! steady run). Also: projections per slave, the largest distance difference to parry in facet
//! sizes, and the floor — a search of 1,000 slaves on 10^6 facets, where the per-facet work of
//! a global search shows alone. Writes search.md and search.json to --out.

use std::fmt::Write as _;
use std::time::Instant;

use abut::mesh::{plate_triangles, SplitMix64};
use abut::{Device, GlobalSearch, Model, SearchStructure, Surface, SurfaceId};
use parry3d::math::Vector as PVec;
use parry3d::query::PointQuery;
use rayon::prelude::*;
use serde::Serialize;

use crate::bench::{io_err, machine, BenchArgs};

/// Steady runs per contestant (the median is reported).
const REPS: usize = 3;
/// Search radii, in facet sizes.
const RADII: [f64; 3] = [0.5, 1.0, 3.0];
/// An abut contestant whose first run takes more than this many times the fastest one's on the
/// same device gets one steady run, not `REPS`.
const SLOW: f64 = 10.0;
/// The graded plate's largest facet width over its smallest.
const GRADING: f64 = 100.0;
/// The global search's structures each device runs.
const STRUCTURES: [SearchStructure; 3] = [
    SearchStructure::Tree,
    SearchStructure::Buckets,
    SearchStructure::Auto,
];

/// One contestant's figures at one radius.
#[derive(Clone, Debug, Serialize)]
struct SearchRow {
    /// The plate: wavy, or wavy and graded.
    plate: &'static str,
    radius: f64,
    slaves: usize,
    facets: usize,
    who: String,
    first_ms: f64,
    steady_ms: f64,
    ns_per_slave: f64,
    /// Facet projections per slave (abut: the tree walks' and the chunks').
    projections: Option<f64>,
    /// Largest difference of the distance found to parry's, in facet sizes.
    max_distance_difference: f64,
    /// Slaves one side finds within the radius and the other not (beyond round-off).
    disagreements: usize,
}

/// The plate and the queries: (model with the pair, triangles, query points, facet size).
struct Scene {
    model: Model,
    master: SurfaceId,
    slave_ids: Vec<u32>,
    verts: Vec<PVec>,
    tris: Vec<[u32; 3]>,
    queries: Vec<[f64; 3]>,
    h: f64,
}

/// A wavy plate of `side` × `side` quads split into triangles on the unit square, and `slaves`
/// random points (random order) within ±2 facet sizes of it. `graded`: the columns' widths grow
/// geometrically across the plate, 100× from the first to the last (the mean stays
/// 1 / `side`).
fn scene(side: usize, slaves: usize, graded: bool) -> abut::Result<Scene> {
    let h = 1.0 / side as f64;
    let shape = |x: f64, y: f64| 0.02 * (6.0 * x).sin() * (4.0 * y).cos();
    let mut plate = plate_triangles(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let grade = |x: f64| {
        let a = GRADING.ln();
        ((a * x).exp() - 1.0) / (a.exp() - 1.0)
    };
    for p in &mut plate.positions {
        if graded {
            p[0] = grade(p[0]);
        }
        p[2] = shape(p[0], p[1]);
    }
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])?;
    let s = model.add_surface(Surface::triangles(&plate.facets))?;
    let mut rng = SplitMix64::new(2026);
    let queries: Vec<[f64; 3]> = (0..slaves)
        .map(|_| {
            let (x, y) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
            [x, y, shape(x, y) + rng.range(-2.0 * h, 2.0 * h)]
        })
        .collect();
    let r = model.add_nodes(&queries, &vec![1.0; slaves])?;
    let verts = plate
        .positions
        .iter()
        .map(|p| PVec::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    Ok(Scene {
        model,
        master: s,
        slave_ids: r.to_vec(),
        verts,
        tris: plate.facets.clone(),
        queries,
        h,
    })
}

/// parry3d: the tree built, then the nearest point within `radius` of every query, on one
/// thread or over all cores; the distances (infinite where none).
fn parry(sc: &Scene, radius: f64, parallel: bool) -> Vec<f64> {
    let mesh = parry3d::shape::TriMesh::new(sc.verts.clone(), sc.tris.clone()).expect("valid mesh");
    let q = |p: &[f64; 3]| {
        let q = PVec::new(p[0] as f32, p[1] as f32, p[2] as f32);
        mesh.project_local_point_with_max_dist(q, false, radius as f32)
            .map_or(f64::INFINITY, |pr| (pr.point - q).length() as f64)
    };
    if parallel {
        sc.queries.par_iter().map(q).collect()
    } else {
        sc.queries.iter().map(q).collect()
    }
}

/// A contestant: its name and one run (distances, projections per slave).
type Run<'a> = Box<dyn FnMut() -> abut::Result<(Vec<f64>, Option<f64>)> + 'a>;

/// abut's global search on `device` within `radius` with `structure`; the structure it uses
/// (`Auto` resolved).
fn abut_run<'a>(
    device: &Device,
    sc: &'a Scene,
    radius: f64,
    structure: SearchStructure,
) -> abut::Result<(Run<'a>, SearchStructure)> {
    let master = sc.model.surface(sc.master)?.clone();
    let mut search =
        GlobalSearch::from_parts(device, &sc.model, master, sc.slave_ids.clone(), radius)?;
    search.set_search_structure(structure);
    let used = search.search_structure();
    let n = sc.queries.len() as f64;
    let run: Run<'a> = Box::new(move || {
        let r = search.run(sc.model.positions())?;
        let d = r
            .contacts()
            .map(|c| c.as_ref().map_or(f64::INFINITY, |c| c.distance))
            .collect();
        Ok((d, Some(r.stats.candidates as f64 / n)))
    });
    Ok((run, used))
}

/// A structure's name in the tables.
fn structure_name(s: SearchStructure) -> &'static str {
    match s {
        SearchStructure::Tree => "tree",
        SearchStructure::Buckets => "buckets",
        SearchStructure::Auto => "auto",
    }
}

/// Times every contestant at one radius: the first run, then `REPS` interleaved rounds.
fn race(
    sc: &Scene,
    plate: &'static str,
    radius_h: f64,
    devices: &[Device],
) -> abut::Result<Vec<SearchRow>> {
    let radius = radius_h * sc.h;
    let mut who: Vec<(String, Run<'_>)> = vec![
        (
            "parry3d 0.31 TriMesh, 1 thread (build + project)".into(),
            Box::new(move || Ok((parry(sc, radius, false), None))),
        ),
        (
            format!(
                "parry3d 0.31 TriMesh, rayon on {} threads (build + project)",
                rayon::current_num_threads()
            ),
            Box::new(move || Ok((parry(sc, radius, true), None))),
        ),
    ];
    for d in devices {
        for st in STRUCTURES {
            let (run, used) = abut_run(d, sc, radius, st)?;
            let name = match st {
                SearchStructure::Auto => format!("abut auto (→ {}), {d}", structure_name(used)),
                _ => format!("abut {}, {d}", structure_name(st)),
            };
            who.push((name, run));
        }
    }
    let mut first = Vec::new();
    let mut result = Vec::new();
    for (_, run) in who.iter_mut() {
        let t = Instant::now();
        result.push(run()?);
        first.push(t.elapsed().as_secs_f64());
    }
    // an abut contestant more than SLOW times the fastest first run on its device is timed
    // once: its first run (each device's contestants are STRUCTURES.len() in a row, after
    // parry's two)
    let parry = who.len() - devices.len() * STRUCTURES.len();
    let once: Vec<bool> = (0..who.len())
        .map(|k| {
            if k < parry {
                return false;
            }
            let on_device = parry + (k - parry) / STRUCTURES.len() * STRUCTURES.len();
            let fastest = first[on_device..on_device + STRUCTURES.len()]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            first[k] > SLOW * fastest
        })
        .collect();
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); who.len()];
    for round in 0..REPS {
        for (k, (_, run)) in who.iter_mut().enumerate() {
            if once[k] && round > 0 {
                continue;
            }
            let t = Instant::now();
            run()?;
            times[k].push(t.elapsed().as_secs_f64());
        }
    }
    let reference = &result[0].0;
    let n = sc.queries.len();
    Ok(who
        .iter()
        .enumerate()
        .map(|(k, (name, _))| {
            let mut t = times[k].clone();
            t.sort_by(f64::total_cmp);
            let steady = t[t.len() / 2];
            let (mut worst, mut disagree) = (0.0f64, 0);
            for (a, b) in result[k].0.iter().zip(reference) {
                match (a.is_finite(), b.is_finite()) {
                    (true, true) => worst = worst.max((a - b).abs() / sc.h),
                    (false, false) => {}
                    // found by one side only: agreement when it lies at the radius
                    (true, false) | (false, true) => {
                        let d = if a.is_finite() { *a } else { *b };
                        if (d - radius).abs() > 1e-4 * sc.h {
                            disagree += 1;
                        }
                    }
                }
            }
            SearchRow {
                plate,
                radius: radius_h,
                slaves: n,
                facets: sc.tris.len(),
                who: if once[k] {
                    format!("{name} (one steady run: over {SLOW}× the fastest on its device)")
                } else {
                    name.clone()
                },
                first_ms: 1e3 * first[k],
                steady_ms: 1e3 * steady,
                ns_per_slave: 1e9 * steady / n as f64,
                projections: result[k].1,
                max_distance_difference: worst,
                disagreements: disagree,
            }
        })
        .collect())
}

/// `Auto` against the better of the tree and the buckets, per plate, radius and device: its
/// steady time over the better one's (1 when it chose the faster; the noise of the rounds
/// shows in the rows where it chose the same one as the better).
fn auto_table(md: &mut String, rows: &[SearchRow], devices: &[Device]) {
    let _ = writeln!(
        md,
        "\n## Auto against the better structure\n\n| plate | radius [facets] | device | tree [ms] | buckets [ms] | auto chose | auto [ms] | auto / better |\n|---|---:|---|---:|---:|---|---:|---:|"
    );
    let find = |plate: &str, r: f64, prefix: &str, d: &Device| {
        rows.iter().find(|s| {
            s.plate == plate
                && s.radius == r
                && s.who.starts_with(prefix)
                && s.who.contains(&d.to_string())
        })
    };
    for plate in ["wavy", "graded"] {
        for r in RADII {
            for d in devices {
                let (Some(t), Some(b), Some(a)) = (
                    find(plate, r, "abut tree", d),
                    find(plate, r, "abut buckets", d),
                    find(plate, r, "abut auto", d),
                ) else {
                    continue;
                };
                let better = t.steady_ms.min(b.steady_ms);
                let chose = if a.who.contains("→ buckets") {
                    "buckets"
                } else {
                    "tree"
                };
                let _ = writeln!(
                    md,
                    "| {plate} | {r} | {} | {:.1} | {:.1} | {chose} | {:.1} | {:.2} |",
                    d.backend_name(),
                    t.steady_ms,
                    b.steady_ms,
                    a.steady_ms,
                    a.steady_ms / better
                );
            }
        }
    }
}

/// `abut bench --search`.
pub fn run(a: &BenchArgs) -> abut::Result<()> {
    let mut devices: Vec<Device> = vec![Device::cpu()];
    devices.extend(Device::all_gpus().into_iter().filter_map(|d| d.ok()));
    let (slaves, floor_side) = if a.quick {
        (100_000, 224)
    } else {
        (1_000_000, 708)
    };
    let sc = scene(224, slaves, false)?;
    // the graded plate with a tenth of the slaves: where the buckets' cells are crowded, their
    // walks fall back to every facet in chunks, and the run would take an hour at 10^6
    let graded = scene(224, slaves / 10, true)?;
    let mut rows = Vec::new();
    for (plate, sc) in [("wavy", &sc), ("graded", &graded)] {
        for r in RADII {
            let n = sc.queries.len();
            eprintln!("the {plate} plate: search within {r} facet sizes, {n} slaves");
            rows.extend(race(sc, plate, r, &devices)?);
        }
    }
    eprintln!(
        "the floor: 1,000 slaves on {} facets",
        2 * floor_side * floor_side
    );
    let floor_scene = scene(floor_side, 1_000, false)?;
    let floor = race(&floor_scene, "wavy", 1.0, &devices)?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# abut bench --search{}\n",
        if a.quick { " --quick" } else { "" }
    );
    let _ = writeln!(md, "- machine: {}", machine());
    for d in &devices {
        let _ = writeln!(md, "- device: {d}");
    }
    let _ = writeln!(
        md,
        "- scene: a wavy plate of {} triangles on the unit square; {slaves} slaves in random order within ±2 facet sizes of it; the graded plate: the same with the columns' widths growing {GRADING}× across it, and {} slaves; times per whole search (abut: host preparation, upload, every pass, readback of the hits; parry3d: the tree's build and every query); first run apart, then the median of {REPS} interleaved rounds (an abut contestant over {SLOW}× the fastest first run on its device: one steady run)\n",
        sc.tris.len(),
        graded.queries.len()
    );
    let table = |md: &mut String, rows: &[SearchRow]| {
        let _ = writeln!(md, "| plate | radius [facets] | slaves | facets | who | first [ms] | steady [ms] | ns/slave | projections/slave | max distance difference to parry [facets] | found by one side only |");
        let _ = writeln!(md, "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|");
        for s in rows {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.0} | {} | {:.1e} | {} |",
                s.plate,
                s.radius,
                s.slaves,
                s.facets,
                s.who,
                s.first_ms,
                s.steady_ms,
                s.ns_per_slave,
                s.projections.map_or("–".into(), |p| format!("{p:.2}")),
                s.max_distance_difference,
                s.disagreements
            );
        }
    };
    table(&mut md, &rows);
    auto_table(&mut md, &rows, &devices);
    let _ = writeln!(
        md,
        "\n## The floor: 1,000 slaves on {} facets, radius 1 facet\n",
        floor_scene.tris.len()
    );
    table(&mut md, &floor);
    std::fs::create_dir_all(&a.out).map_err(|e| io_err(&a.out, e))?;
    let md_path = a.out.join("search.md");
    std::fs::write(&md_path, &md).map_err(|e| io_err(&md_path, e))?;
    let json = serde_json::json!({
        "machine": machine(),
        "devices": devices.iter().map(|d| d.to_string()).collect::<Vec<_>>(),
        "rows": rows,
        "floor": floor,
    });
    let json_path = a.out.join("search.json");
    std::fs::write(
        &json_path,
        serde_json::to_string_pretty(&json).unwrap_or_default(),
    )
    .map_err(|e| io_err(&json_path, e))?;
    println!("{md}");
    println!("wrote {} and {}", md_path.display(), json_path.display());
    Ok(())
}
