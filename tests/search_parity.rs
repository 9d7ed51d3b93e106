//! Global search: GPU against the CPU mirror against the f64 brute-force oracle, on structured
//! and irregular meshes in 2D and 3D; ties, far from the origin, determinism, overflow and
//! dispatch folding.

mod common;

use abut::mesh::{plate_quads, plate_triangles, point_cloud, polyline, sphere_triangles};
use abut::testing::abi::boxes;
use abut::{Device, Error, Facet, GlobalSearch, Model, PairId, Surface};
use common::*;

/// Every `stride`-th slave index.
fn every(n: usize, stride: usize) -> Vec<usize> {
    (0..n).step_by(stride.max(1)).collect()
}

/// CPU mirror against the oracle (on `oracle_stride`-spaced slaves), then each GPU against
/// the CPU mirror on every slave. Returns the CPU result.
fn check_scene(
    model: &Model,
    pair: PairId,
    oracle_stride: usize,
    what: &str,
) -> abut::SearchResult {
    let p = model.pair(pair).unwrap();
    let master = model.surface(p.master).unwrap();
    let radius = p.search_radius.unwrap();
    let cpu = run(&Device::cpu(), model, pair);
    let tol = tolerance(&cpu, radius);
    let n = cpu.len();
    let c = assert_matches_oracle(
        &cpu,
        master,
        model.positions(),
        radius,
        tol,
        &every(n, oracle_stride),
        &format!("{what}: CPU vs oracle"),
    );
    assert!(
        c.found > c.checked / 10,
        "{what}: too few contacts to be a test: {c:?}"
    );
    eprintln!("{what}: CPU vs oracle {c:?}, tol {tol:.2e}");
    for gpu in gpus() {
        let g = run(gpu, model, pair);
        assert_eq!(
            g.stats.fallbacks, cpu.stats.fallbacks,
            "{what}: walks finished in chunks on {gpu}"
        );
        let c = assert_same_search(
            &g,
            &cpu,
            master,
            model.positions(),
            radius,
            tol,
            &format!("{what}: {} vs CPU", gpu.backend_name()),
        );
        eprintln!("{what}: {} vs CPU {c:?}", gpu.backend_name());
    }
    cpu
}

#[test]
fn quads_3d_structured_100k_slaves() {
    let wave = |x: f64, y: f64| 0.05 * (6.0 * x).sin() * (4.0 * y).cos();
    let plate = plate_quads(200, 200, 1.0, 1.0, 0.0, 1, &wave);
    let slaves = point_cloud(100_000, [0.0, 0.0, -0.06], [1.0, 1.0, 0.06], 7);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.01,
    );
    check_scene(&m, p, 50, "structured quads");
}

#[test]
fn triangles_3d_irregular() {
    let wave = |x: f64, y: f64| 0.1 * (3.0 * x + 2.0 * y).sin();
    let plate = plate_triangles(60, 50, 1.2, 1.0, 0.3, 3, &wave);
    let slaves = point_cloud(20_000, [-0.1, -0.1, -0.15], [1.3, 1.1, 0.15], 8);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::triangles(&plate.facets),
        &slaves,
        0.04,
    );
    check_scene(&m, p, 10, "irregular triangles");
}

#[test]
fn warped_and_irregular_quads() {
    // random heights make every quad non-planar
    let mut rng = abut::mesh::SplitMix64::new(11);
    let mut plate = plate_quads(40, 40, 1.0, 1.0, 0.25, 5, &|_, _| 0.0);
    for x in &mut plate.positions {
        x[2] = rng.range(-0.01, 0.01);
    }
    let slaves = point_cloud(20_000, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05], 9);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.05,
    );
    check_scene(&m, p, 10, "warped quads");
}

#[test]
fn sphere_surface() {
    let s = sphere_triangles(24, 48, 1.0, [0.5, -0.25, 2.0]);
    let slaves = point_cloud(20_000, [-0.8, -1.55, 0.7], [1.8, 1.05, 3.3], 10);
    let (m, p) = scene(3, &s.positions, Surface::triangles(&s.facets), &slaves, 0.2);
    check_scene(&m, p, 10, "sphere");
}

#[test]
fn mixed_triangles_and_quads() {
    let plate = plate_quads(30, 30, 1.0, 1.0, 0.2, 4, &|x, y| 0.05 * (5.0 * x * y).cos());
    let facets: Vec<Facet> = plate
        .facets
        .iter()
        .enumerate()
        .flat_map(|(k, q)| {
            if k % 3 == 0 {
                vec![
                    Facet::Triangle([q[0], q[1], q[2]]),
                    Facet::Triangle([q[0], q[2], q[3]]),
                ]
            } else {
                vec![Facet::Quad(*q)]
            }
        })
        .collect();
    let slaves = point_cloud(10_000, [0.0, 0.0, -0.1], [1.0, 1.0, 0.1], 12);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::from_facets(facets),
        &slaves,
        0.05,
    );
    check_scene(&m, p, 5, "mixed triangles and quads");
}

#[test]
fn polylines_2d_structured_and_irregular() {
    for (jitter, what) in [(0.0, "2D structured"), (0.35, "2D irregular")] {
        let line = polyline(2000, 2.0, jitter, 13, &|x| 0.1 * (4.0 * x).sin());
        let slaves = point_cloud(30_000, [-0.05, -0.15, 0.0], [2.05, 0.15, 0.0], 14);
        let (m, p) = scene(
            2,
            &line.positions,
            Surface::segments(&line.facets),
            &slaves,
            0.03,
        );
        check_scene(&m, p, 10, what);
    }
}

/// Slave nodes exactly on shared vertices and edges of a dyadic grid (all arithmetic exact):
/// every backend must pick the lowest facet id, as the oracle does; and ±ε off an edge the
/// facet on that side, not a tie.
#[test]
fn ties_on_shared_edges_and_vertices() {
    for tri in [false, true] {
        let (positions, surface) = if tri {
            let m = plate_triangles(8, 8, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
            (m.positions, Surface::triangles(&m.facets))
        } else {
            let m = plate_quads(8, 8, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
            (m.positions, Surface::quads(&m.facets))
        };
        let h = 0.125;
        let mut slaves = Vec::new();
        for j in 1..8 {
            for i in 1..8 {
                let (x, y) = (i as f64 * h, j as f64 * h);
                for z in [0.0, 0.25, -0.0625] {
                    slaves.push([x, y, z]); // interior vertex (4–6 facets)
                    slaves.push([x + 0.5 * h, y, z]); // shared edge midpoint
                    slaves.push([x, y + 0.25 * h, z]); // on an edge, off-centre
                }
            }
        }
        let exact = slaves.len();
        let eps = 1e-4 * h;
        for j in 1..8 {
            for i in 1..7 {
                let (x, y) = (i as f64 * h + 0.5 * h, j as f64 * h);
                slaves.push([x, y + eps, 0.0]);
                slaves.push([x, y - eps, 0.0]);
            }
        }
        let (m, p) = scene(3, &positions, surface, &slaves, 0.3);
        let master = m.surface(m.pair(p).unwrap().master).unwrap();
        let nodes: Vec<u32> = (0..slaves.len() as u32)
            .map(|i| i + positions.len() as u32)
            .collect();
        let oracle = abut::testing::brute_force::brute_force(master, m.positions(), &nodes, 0.3);
        let mut devices = vec![Device::cpu()];
        devices.extend(gpus().iter().cloned());
        for d in &devices {
            let r = run(d, &m, p);
            for (i, (h, o)) in r.contacts().zip(&oracle).enumerate() {
                let (h, o) = (h.expect("within radius"), o.expect("within radius"));
                assert_eq!(
                    h.facet, o.contact.facet,
                    "{d} tri={tri}: slave {i} at {:?}: facet",
                    slaves[i]
                );
                assert_eq!(
                    h.tracked_node, o.contact.tracked_node,
                    "{d} tri={tri}: slave {i}: tracked node"
                );
                if i < exact {
                    assert!(
                        (h.distance - slaves[i][2].abs()).abs() < 1e-6,
                        "{d}: slave {i}: distance {}",
                        h.distance
                    );
                } else {
                    assert!(
                        o.second_distance - o.contact.distance > 1e-6,
                        "±ε case is not a tie"
                    );
                }
            }
        }
    }
}

/// A 1 mm mesh 10 km from the origin: the f32 path (grid-local coordinates) agrees with the f64
/// oracle to well below the mesh size.
#[test]
fn far_from_origin() {
    let shift = [1.0e4, -1.0e4, 1.0e4];
    let mut plate = plate_triangles(20, 20, 0.02, 0.02, 0.2, 21, &|x, y| {
        0.002 * (300.0 * x).sin() * (200.0 * y).cos()
    });
    for x in &mut plate.positions {
        for a in 0..3 {
            x[a] += shift[a];
        }
    }
    let mut slaves = point_cloud(5_000, [0.0, 0.0, -0.004], [0.02, 0.02, 0.004], 22);
    for x in &mut slaves {
        for a in 0..3 {
            x[a] += shift[a];
        }
    }
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::triangles(&plate.facets),
        &slaves,
        0.003,
    );
    let cpu = check_scene(&m, p, 1, "far from origin");
    // the stated tolerance is relative to the 2 cm local frame, not to 10 km
    assert!(
        tolerance(&cpu, 0.003) < 1e-6,
        "tolerance {}",
        tolerance(&cpu, 0.003)
    );
}

#[test]
fn gpu_runs_are_bitwise_identical() {
    let s = sphere_triangles(16, 32, 1.0, [0.0; 3]);
    let slaves = point_cloud(20_000, [-1.3; 3], [1.3; 3], 31);
    let (m, p) = scene(3, &s.positions, Surface::triangles(&s.facets), &slaves, 0.3);
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for d in &devices {
        let mut search = Both::new(d, &m, p).unwrap();
        let a = search.run(m.positions()).unwrap();
        let b = search.run(m.positions()).unwrap();
        let c = Both::new(d, &m, p).unwrap().run(m.positions()).unwrap();
        assert!(
            bytemuck::cast_slice::<_, u8>(&a.raw) == bytemuck::cast_slice::<_, u8>(&b.raw),
            "{d}: runs differ"
        );
        assert!(
            bytemuck::cast_slice::<_, u8>(&a.raw) == bytemuck::cast_slice::<_, u8>(&c.raw),
            "{d}: instances differ"
        );
    }
}

/// Dispatches folded into 2D by a low per-dimension cap give the same bytes, and a second run
/// on the same search the same bytes again.
#[test]
fn dispatch_folding_gives_the_same_bytes() {
    let plate = plate_quads(40, 40, 1.0, 1.0, 0.2, 41, &|x, _| 0.1 * x);
    let slaves = point_cloud(10_000, [0.0, 0.0, -0.1], [1.0, 1.0, 0.2], 42);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.05,
    );
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for d in &devices {
        let mut search = Both::new(d, &m, p).unwrap();
        let reference = search.run(m.positions()).unwrap();
        let again = search.run(m.positions()).unwrap();
        assert_eq!(again.raw, reference.raw, "{d}: a second run differs");
        let mut folded = Both::new(d, &m, p).unwrap();
        folded.set_max_workgroups_per_dim(3);
        let f = folded.run(m.positions()).unwrap();
        assert_eq!(f.raw, reference.raw, "{d}: folded dispatch differs");
    }
}

#[test]
fn nothing_within_the_radius() {
    let plate = plate_quads(10, 10, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let slaves = point_cloud(1000, [-5.0, -5.0, 1.0], [5.0, 5.0, 5.0], 51);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.5,
    );
    let mut devices = vec![Device::cpu()];
    devices.extend(gpus().iter().cloned());
    for d in &devices {
        let r = run(d, &m, p);
        assert!(r.contacts().all(|c| c.is_none()), "{d}");
    }
}

#[test]
fn bad_positions_at_run_time_are_errors() {
    let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &[[0.5, 0.5, 0.1]],
        0.5,
    );
    let mut s = Both::new(&Device::cpu(), &m, p).unwrap();
    let mut pos = m.positions().to_vec();
    assert!(matches!(
        s.run(&pos[1..]),
        Err(Error::LengthMismatch { .. })
    ));
    pos[7][1] = f64::NAN;
    let e = s.run(&pos).unwrap_err();
    assert!(
        matches!(
            e,
            Error::NonFiniteCoordinate {
                node: 7,
                axis: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("node 7"), "{e}");
}

/// The tree's refit gives the same bits on every executor (min and max are exact), its boxes
/// hold what they must (each leaf its facet's nodes, each inner node its children), and the
/// search on each adapter gives the CPU's result, the first search and a requested one after
/// it. (Each kernel on its own against its mirror: `tests/split_increment.rs`, which splits an
/// increment, search included, at every entry.)
#[test]
fn the_tree_and_the_search_match_the_mirror() {
    let plate = plate_triangles(30, 30, 1.0, 1.0, 0.3, 61, &|x, y| {
        0.05 * (5.0 * x + y).sin()
    });
    let slaves = point_cloud(5_000, [0.0, 0.0, -0.1], [1.0, 1.0, 0.1], 62);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::triangles(&plate.facets),
        &slaves,
        0.05,
    );
    let master = m.surface(m.pair(p).unwrap().master).unwrap();
    let mut cpu_search = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    cpu_search.set_search_structure(abut::SearchStructure::Tree);
    let cpu = cpu_search.run(m.positions()).unwrap();
    let cpu_boxes = cpu_search.tree_boxes().unwrap();
    let order = cpu_search.tree_order().to_vec();
    let leaves = order.len().next_power_of_two();
    assert_eq!(cpu_boxes.len(), 2 * leaves);
    let frame = cpu.frame;
    // the grid step the kernels quantise on: from the box margin of the master's extent
    let (mut lo_m, mut hi_m) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &f in &master.active {
        for &n in master.facets[f as usize].nodes() {
            for a in 0..3 {
                lo_m[a] = lo_m[a].min(m.positions()[n as usize][a]);
                hi_m[a] = hi_m[a].max(m.positions()[n as usize][a]);
            }
        }
    }
    let margin = abut::search::box_margin(lo_m, hi_m, frame);
    let (step, _) = boxes::box_step(margin);
    let mut placed: Vec<u32> = order.iter().copied().filter(|&f| f != u32::MAX).collect();
    placed.sort_unstable();
    assert_eq!(
        placed,
        (0..master.active.len() as u32).collect::<Vec<_>>(),
        "every active facet in exactly one leaf slot"
    );
    for (j, &f) in order.iter().enumerate() {
        let b = cpu_boxes[leaves + j];
        if f == u32::MAX {
            assert!(boxes::is_empty(b), "leaf {j}: an empty slot with a box");
            continue;
        }
        let (lo, hi) = boxes::unpack(b, step);
        for &n in master.facets[master.active[f as usize] as usize].nodes() {
            let x = m.positions()[n as usize];
            for a in 0..3 {
                let xl = (x[a] - frame[a]) as f32;
                // holds the node with the margin (quantising only widens)
                assert!(
                    lo[a] <= xl - margin && xl + margin <= hi[a],
                    "leaf {j}: node {n} outside its box"
                );
            }
        }
        let (qlo, qhi) = boxes::codes(b);
        for a in 0..3 {
            assert!(
                qlo[a] > 0 && qhi[a] < boxes::BOX_TOP,
                "leaf {j}: an infinite bound"
            );
        }
    }
    for k in 1..leaves {
        let (lo, hi) = boxes::codes(cpu_boxes[k]);
        let (l_lo, l_hi) = boxes::codes(cpu_boxes[2 * k]);
        let (r_lo, r_hi) = boxes::codes(cpu_boxes[2 * k + 1]);
        for a in 0..3 {
            assert_eq!(
                lo[a],
                l_lo[a].min(r_lo[a]),
                "node {k}: not its children's union"
            );
            assert_eq!(
                hi[a],
                l_hi[a].max(r_hi[a]),
                "node {k}: not its children's union"
            );
        }
    }
    let tol = tolerance(&cpu, 0.05);
    for gpu in gpus() {
        let mut search = GlobalSearch::new(gpu, &m, p).unwrap();
        search.set_search_structure(abut::SearchStructure::Tree);
        search.run(m.positions()).unwrap();
        assert!(
            search.tree_boxes().unwrap()[2..] == cpu_boxes[2..],
            "{gpu}: tree boxes differ from the CPU mirror's"
        );
        for k in 0..2 {
            let r = search.run(m.positions()).unwrap();
            assert_same_search(
                &r,
                &cpu,
                master,
                m.positions(),
                0.05,
                tol,
                &format!("{gpu}: search {k}"),
            );
            assert!(
                search.tree_boxes().unwrap()[2..] == cpu_boxes[2..],
                "{gpu}: search {k}: tree boxes differ"
            );
        }
    }
}
