//! Finite-sliding tracking: the local search between global searches finds the facet a global
//! search would, increment after increment, over long sliding runs — many facets crossed,
//! curved cylinder and sphere masters, a surface with a hole and free edges, a sheet folding
//! onto itself — and with large motion the budget triggers a global search before a contact
//! is missed. GPU against CPU parity of the tracking, and determinism.

mod common;

use abut::mesh::{plate_quads, plate_triangles, sphere_triangles};
use abut::model::Schedule;
use abut::search::Trigger;
use abut::*;
use common::{devices, facet_distance, flat_master, gpus};

#[derive(Debug, Default)]
struct Tally {
    increments: usize,
    compared: usize,
    discrepancies: usize,
    /// Largest distance by which a discrepant tracked facet was farther than the global one
    /// (infinite when tracking found none), in units of the radius.
    worst_excess: f64,
    globals: usize,
    budget: usize,
    max_iterations: u32,
}

/// Drives `steps` increments of positions `at(k)` through a tracked search and, each
/// increment, a fresh global search; counts the slaves the global search puts within
/// (1 − budget)·radius of a facet for which tracking found no facet, or one that is not
/// equally near (a tie). (Beyond that, a slave in contact may have a nearer facet that its
/// walk cannot reach — across a hole, on the other half of a folding sheet — until the next
/// global search: the local search's limit, as the seed's.)
fn track(
    d: &Device,
    m: &Model,
    p: PairId,
    schedule: Schedule,
    steps: usize,
    at: &dyn Fn(usize) -> Vec<[f64; 3]>,
) -> Tally {
    let mut tracked = GlobalSearch::new(d, m, p).unwrap();
    tracked.set_schedule(schedule).unwrap();
    let mut global = GlobalSearch::new(&Device::cpu(), m, p).unwrap();
    let radius = tracked.radius();
    let zone = (1.0 - schedule.budget) * radius;
    let master = m.surface(m.pair(p).unwrap().master).unwrap();
    let mut t = Tally::default();
    for k in 0..steps {
        let x = at(k);
        let r = tracked.step(&x).unwrap();
        let g = global.run(&x).unwrap();
        t.increments += 1;
        if r.stats.trigger != Trigger::Local {
            t.globals += 1;
        }
        if r.stats.trigger == Trigger::Budget {
            t.budget += 1;
        }
        t.max_iterations = t.max_iterations.max(r.stats.local_iterations);
        let tol = 1e-4 * radius;
        for (i, gc) in g.contacts().enumerate() {
            let Some(gc) = gc else { continue };
            if gc.distance > zone {
                continue;
            }
            t.compared += 1;
            let excess = match r.contact(i) {
                Some(tc) if tc.facet == gc.facet => 0.0,
                Some(tc) => facet_distance(master, &x, r.slaves[i], tc.facet) - gc.distance,
                None => f64::INFINITY,
            };
            if excess > tol {
                if std::env::var("ABUT_DEBUG_MISSES").is_ok() {
                    eprintln!(
                        "k {k} slave {i} {:?}: global {:?} d {:.4} tracked {:?}",
                        r.stats.trigger,
                        gc.facet,
                        gc.distance / radius,
                        r.contact(i).map(|c| (c.facet, c.distance / radius))
                    );
                }
                t.discrepancies += 1;
                t.worst_excess = t.worst_excess.max(excess / radius);
            }
        }
    }
    t
}

fn model_with(
    dim: u32,
    positions: &[[f64; 3]],
    surface: Surface,
    slaves: &[[f64; 3]],
    radius: f64,
) -> (Model, PairId, usize) {
    let mut m = if dim == 2 {
        Model::new_2d()
    } else {
        Model::new_3d()
    };
    m.add_nodes(positions, &vec![1.0; positions.len()]).unwrap();
    let s = m.add_surface(surface).unwrap();
    let r = m.add_nodes(slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(radius)).unwrap();
    (m, p, r.start as usize)
}

fn schedule(interval: u32) -> Schedule {
    Schedule {
        interval,
        budget: 0.5,
        wide_local: false,
        visit_every_slave: false,
    }
}

fn wide(interval: u32) -> Schedule {
    Schedule {
        interval,
        budget: 0.5,
        wide_local: true,
        visit_every_slave: false,
    }
}

/// Slaves slide back and forth across a plate, crossing tens of facets each way.
#[test]
fn sliding_across_many_facets() {
    for irregular in [false, true] {
        let n = 40;
        let h = 1.0 / n as f64;
        let wave = |x: f64, y: f64| 0.03 * (3.0 * x).sin() * (2.0 * y).cos();
        let (positions, surface) = if irregular {
            let plate = plate_triangles(n, n, 1.0, 1.0, 0.3, 1, &wave);
            (plate.positions, Surface::triangles(&plate.facets))
        } else {
            let plate = plate_quads(n, n, 1.0, 1.0, 0.0, 1, &wave);
            (plate.positions, Surface::quads(&plate.facets))
        };
        let slaves: Vec<[f64; 3]> =
            abut::mesh::point_cloud(1500, [0.25, 0.05, -0.01], [0.45, 0.95, 0.01], 2);
        let (m, p, first) = model_with(3, &positions, surface, &slaves, 2.0 * h);
        let base = m.positions().to_vec();
        // amplitude 0.25 (10 facets), at most 0.3 facet sizes per increment
        let at = |k: usize| {
            let mut x = base.clone();
            let (a, w) = (0.25, 0.3 * h / 0.25);
            for p in &mut x[first..] {
                p[0] += a * (w * k as f64).sin();
                p[1] += 0.04 * (0.02 * k as f64).sin();
                p[2] += wave(p[0], p[1]);
            }
            x
        };
        for d in devices() {
            let t = track(&d, &m, p, wide(100), 300, &at);
            eprintln!("{d} irregular={irregular} wide: {t:?}");
            assert!(t.compared > 400_000, "{t:?}");
            assert_eq!(t.discrepancies, 0, "{d}: {t:?}");
            assert_eq!(t.budget, 0, "{d}: every slave is tracked: {t:?}");
            assert!(t.globals == 3, "{d}: the first and every 100th: {t:?}");
            let fast = track(&d, &m, p, schedule(100), 300, &at);
            eprintln!("{d} irregular={irregular} fast: {fast:?}");
            if irregular {
                // The seed's fast walk can settle on a node none of whose facets is the nearest
                // (obtuse triangles) and stay there until the next global search: here about 2 %
                // of the contacts, at most about one facet size farther. Measured, not hidden:
                // this is what the wide alternative is for.
                assert!(
                    fast.discrepancies * 100 < 3 * fast.compared && fast.worst_excess < 1.0,
                    "{d}: {fast:?}"
                );
            } else {
                assert_eq!(fast.discrepancies, 0, "{d}: {fast:?}");
            }
        }
    }
}

/// Curved masters: slaves orbit a cylinder and slide over a sphere.
#[test]
fn curved_cylinder_and_sphere_masters() {
    // cylinder of radius 1 around z, as quads (n_theta × n_z)
    let (nt, nz) = (48, 20);
    let mut pos = Vec::new();
    for j in 0..=nz {
        for i in 0..nt {
            let th = 2.0 * std::f64::consts::PI * i as f64 / nt as f64;
            pos.push([th.cos(), th.sin(), j as f64 * 0.1]);
        }
    }
    let mut quads = Vec::new();
    for j in 0..nz {
        for i in 0..nt {
            let a = (j * nt + i) as u32;
            let b = (j * nt + (i + 1) % nt) as u32;
            quads.push([a, b, b + nt as u32, a + nt as u32]); // outward normals
        }
    }
    let h = 2.0 * std::f64::consts::PI / nt as f64;
    let n_s = 600;
    let mut rng = abut::mesh::SplitMix64::new(5);
    let sl: Vec<(f64, f64, f64)> = (0..n_s)
        .map(|_| {
            (
                rng.range(0.0, std::f64::consts::TAU),
                rng.range(0.2, 1.8),
                rng.range(0.99, 1.02),
            )
        })
        .collect();
    let slaves: Vec<[f64; 3]> = sl
        .iter()
        .map(|&(t, z, r)| [r * t.cos(), r * t.sin(), z])
        .collect();
    let (m, p, first) = model_with(3, &pos, Surface::quads(&quads), &slaves, 2.0 * h);
    let base = m.positions().to_vec();
    let at = |k: usize| {
        let mut x = base.clone();
        for (q, &(t, z, r)) in x[first..].iter_mut().zip(&sl) {
            let th = t + 0.3 * h * k as f64; // a full turn in ~ 160 increments
            *q = [
                r * th.cos(),
                r * th.sin(),
                z + 0.05 * (0.03 * k as f64).sin(),
            ];
        }
        x
    };
    let s = sphere_triangles(24, 48, 1.0, [0.0; 3]);
    let hs = std::f64::consts::PI / 24.0;
    let sph_sl: Vec<(f64, f64, f64)> = (0..n_s)
        .map(|_| {
            (
                rng.range(0.0, std::f64::consts::TAU),
                rng.range(0.3, 2.8),
                rng.range(0.99, 1.02),
            )
        })
        .collect();
    let sph_slaves: Vec<[f64; 3]> = sph_sl
        .iter()
        .map(|&(ph, th, r)| {
            [
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ]
        })
        .collect();
    let (ms, ps, fs) = model_with(
        3,
        &s.positions,
        Surface::triangles(&s.facets),
        &sph_slaves,
        2.0 * hs,
    );
    let bs = ms.positions().to_vec();
    let at_s = |k: usize| {
        let mut x = bs.clone();
        for (q, &(ph, th, r)) in x[fs..].iter_mut().zip(&sph_sl) {
            let ph = ph + 0.3 * hs * k as f64;
            let th = th + 0.2 * (0.02 * k as f64).sin();
            *q = [
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ];
        }
        x
    };
    for d in devices() {
        let t = track(&d, &m, p, wide(100), 200, &at);
        eprintln!("{d} cylinder: {t:?}");
        assert!(
            t.compared > 100_000 && t.discrepancies == 0 && t.budget == 0,
            "{d} cylinder: {t:?}"
        );
        let fast = track(&d, &m, p, schedule(100), 200, &at);
        assert_eq!(fast.discrepancies, 0, "{d} cylinder fast: {fast:?}");
        let t = track(&d, &ms, ps, wide(100), 200, &at_s);
        eprintln!("{d} sphere: {t:?}");
        assert!(
            t.compared > 100_000 && t.discrepancies == 0,
            "{d} sphere: {t:?}"
        );
    }
}

/// A plate with a hole and free edges: slaves cross the hole and slide off the edges and back.
#[test]
fn holes_and_free_edges() {
    let n = 30;
    let h = 1.0 / n as f64;
    let plate = plate_quads(n, n, 1.0, 1.0, 0.0, 3, &|_, _| 0.0);
    // remove a 6 × 6 hole in the middle
    let quads: Vec<[u32; 4]> = plate
        .facets
        .iter()
        .enumerate()
        .filter(|(k, _)| {
            let (i, j) = (k % n, k / n);
            !(12..18).contains(&i) || !(12..18).contains(&j)
        })
        .map(|(_, q)| *q)
        .collect();
    let slaves: Vec<[f64; 3]> =
        abut::mesh::point_cloud(1500, [0.05, 0.05, -0.02], [0.95, 0.95, 0.02], 4);
    let (m, p, first) = model_with(
        3,
        &plate.positions,
        Surface::quads(&quads),
        &slaves,
        2.0 * h,
    );
    let base = m.positions().to_vec();
    let at = |k: usize| {
        let mut x = base.clone();
        for (i, q) in x[first..].iter_mut().enumerate() {
            let a = 0.3 + 0.1 * (i % 5) as f64; // some slide off the plate and come back
            let w = 0.3 * h / a;
            q[0] += a * (w * k as f64).sin();
            q[1] += 0.2 * (0.5 * w * k as f64).cos() - 0.2;
        }
        x
    };
    for d in devices() {
        let t = track(&d, &m, p, wide(100), 300, &at);
        eprintln!("{d}: {t:?}");
        assert!(t.compared > 100_000 && t.discrepancies == 0, "{d}: {t:?}");
        assert!(
            t.budget > 0,
            "{d}: slaves leaving the plate become untracked and trigger the budget: {t:?}"
        );
    }
}

/// Large motion (more than a facet per increment): the budget fires before any contact in the
/// guaranteed zone is missed.
#[test]
fn large_motion_triggers_the_budget() {
    let n = 30;
    let h = 1.0 / n as f64;
    let plate = plate_quads(n, n, 1.0, 1.0, 0.0, 3, &|_, _| 0.0);
    // slaves start far above and fall through the radius at 1.5 facets per increment, some
    // landing; others sweep sideways fast
    let slaves: Vec<[f64; 3]> = abut::mesh::point_cloud(1000, [0.1, 0.1, 0.3], [0.9, 0.9, 0.6], 6);
    let (m, p, first) = model_with(
        3,
        &plate.positions,
        Surface::quads(&quads_of(&plate)),
        &slaves,
        2.0 * h,
    );
    let base = m.positions().to_vec();
    let at = |k: usize| {
        let mut x = base.clone();
        for q in &mut x[first..] {
            q[2] = (q[2] - 1.5 * h * k as f64).max(0.005);
        }
        x
    };
    for d in devices() {
        let t = track(&d, &m, p, schedule(100), 40, &at);
        eprintln!("{d}: {t:?}");
        assert!(t.compared > 10_000 && t.discrepancies == 0, "{d}: {t:?}");
        assert!(t.budget >= 3, "{d}: {t:?}");
    }
}

/// A tracked slave's state follows it between global searches. A slave within the radius is
/// not counted by the motion budget (the local search follows it); one that leaves the radius in
/// a local increment is counted from the next one on (tracked from beyond the radius, its walk
/// may have far to go), so moving more than half the budget away asks for a global search then.
/// The motion pass visits the slaves in node order and reads each one's state by node: the node
/// set lists them against node order here, so a state read for the wrong slave shows. 2D and
/// 3D, with and without slaves leaving, every device.
#[test]
fn a_slave_leaving_the_radius_is_counted_by_the_budget_from_the_next_increment() {
    for dim in [2, 3] {
        let (mut m, master, h) = flat_master(dim);
        let radius = 1.5 * h;
        let up = if dim == 3 { 2 } else { 1 };
        let count = if dim == 3 { 49 } else { 30 };
        let start: Vec<[f64; 3]> = (0..count)
            .map(|i| {
                let mut q = if dim == 3 {
                    [0.2 + 0.1 * (i % 7) as f64, 0.2 + 0.1 * (i / 7) as f64, 0.0]
                } else {
                    [0.2 + 0.02 * i as f64, 0.0, 0.0]
                };
                q[up] = 0.5 * radius;
                q
            })
            .collect();
        let first = m.positions().len();
        let r = m.add_nodes(&start, &vec![1.0; count]).unwrap();
        let listed: Vec<u32> = r.to_vec().into_iter().rev().collect();
        let set = m.add_node_set(&listed).unwrap();
        let p = m
            .add_pair(Pair::new(set, master).search_radius(radius))
            .unwrap();
        let base = m.positions().to_vec();
        for leaving in [false, true] {
            // increment 1: every slave slides 0.4 radius (within the radius: not counted, though
            // more than half the budget), and every fifth rises 0.8 radius, out of it;
            // increment 2: nobody moves
            let at = |k: usize| {
                let mut x = base.clone();
                if k >= 1 {
                    for (i, q) in x[first..].iter_mut().enumerate() {
                        q[0] += 0.4 * radius;
                        if leaving && i % 5 == 2 {
                            q[up] += 0.8 * radius;
                        }
                    }
                }
                x
            };
            for d in devices() {
                let mut s = GlobalSearch::new(&d, &m, p).unwrap();
                s.set_schedule(schedule(100)).unwrap();
                let triggers: Vec<(Trigger, f64)> = (0..3)
                    .map(|k| {
                        let r = s.step(&at(k)).unwrap();
                        (r.stats.trigger, r.stats.motion / radius)
                    })
                    .collect();
                let what = format!("{d}, {dim}D, slaves leaving: {leaving}: {triggers:?}");
                assert_eq!(triggers[0].0, Trigger::First, "{what}");
                assert_eq!(triggers[1], (Trigger::Local, 0.0), "{what}");
                if leaving {
                    assert_eq!(triggers[2].0, Trigger::Budget, "{what}");
                    // the leavers' slide and rise
                    assert!((triggers[2].1 - 0.4f64.hypot(0.8)).abs() < 1e-3, "{what}");
                } else {
                    assert_eq!(triggers[2], (Trigger::Local, 0.0), "{what}");
                }
            }
        }
    }
}

fn quads_of(m: &abut::mesh::Mesh<[u32; 4]>) -> Vec<[u32; 4]> {
    m.facets.clone()
}

/// A sheet folding onto itself (self-contact): the folding half comes down onto the other;
/// slaves are all the sheet's nodes, their own facets and neighbours excluded.
#[test]
fn sheet_folding_onto_itself() {
    let (nx, ny) = (30, 10);
    let sheet = plate_quads(nx, ny, 2.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let h = 2.0 / nx as f64;
    let mut m = Model::new_3d();
    m.add_nodes(&sheet.positions, &vec![1.0; sheet.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&sheet.facets)).unwrap();
    let all: Vec<u32> = (0..sheet.positions.len() as u32).collect();
    let set = m.add_node_set(&all).unwrap();
    let p = m
        .add_pair(Pair::new(set, s).search_radius(2.0 * h))
        .unwrap();
    let base = m.positions().to_vec();
    // fold the right half about the line x = 1 (lifted so that it lands 0.4 h above the left
    // half): θ from 0 to 178° in 150 increments
    let at = |k: usize| {
        let th = (178.0f64 * k as f64 / 150.0).min(178.0).to_radians();
        base.iter()
            .map(|q| {
                if q[0] <= 1.0 {
                    *q
                } else {
                    let r = q[0] - 1.0;
                    [
                        1.0 + r * th.cos(),
                        q[1],
                        r * th.sin() + 0.4 * h * (th / std::f64::consts::PI),
                    ]
                }
            })
            .collect()
    };
    let probe = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    assert!(probe.is_self_contact());
    assert_eq!(probe.schedule().interval, 4, "self-contact default");
    for d in devices() {
        let t = track(
            &d,
            &m,
            p,
            Schedule {
                interval: 4,
                budget: 0.5,
                wide_local: true,
                visit_every_slave: false,
            },
            160,
            &at,
        );
        eprintln!("{d}: {t:?}");
        assert!(
            t.compared > 3_000,
            "{d}: the folded half comes into contact: {t:?}"
        );
        assert_eq!(t.discrepancies, 0, "{d}: {t:?}");
    }
}

/// The local search on the GPU gives the CPU mirror's results increment by increment, and the
/// same bytes on every run.
#[test]
fn local_search_parity_and_determinism() {
    let plate = plate_triangles(30, 30, 1.0, 1.0, 0.3, 8, &|x, y| 0.02 * (4.0 * x * y).sin());
    let h = 1.0 / 30.0;
    let slaves: Vec<[f64; 3]> =
        abut::mesh::point_cloud(3000, [0.2, 0.2, -0.01], [0.8, 0.8, 0.01], 9);
    let (m, p, first) = model_with(
        3,
        &plate.positions,
        Surface::triangles(&plate.facets),
        &slaves,
        2.0 * h,
    );
    let base = m.positions().to_vec();
    let at = |k: usize| {
        let mut x = base.clone();
        for q in &mut x[first..] {
            q[0] += 0.15 * (0.05 * k as f64).sin();
            q[2] += 0.02 * (4.0 * q[0] * q[1]).sin();
        }
        x
    };
    for schedule in [schedule(100), wide(100)] {
        let run = |d: &Device| -> Vec<Vec<abut::testing::abi::search::GpuHit>> {
            let mut s = GlobalSearch::new(d, &m, p).unwrap();
            s.set_schedule(schedule).unwrap();
            (0..60)
                .map(|k| s.step(&at(k)).unwrap().raw.to_vec())
                .collect()
        };
        let cpu = run(&Device::cpu());
        for g in gpus() {
            let a = run(g);
            let b = run(g);
            assert!(a == b, "{g}: two runs differ");
            let mut differ = 0;
            for (x, y) in a.iter().zip(&cpu) {
                for (hg, hc) in x.iter().zip(y) {
                    if hg.facet != hc.facet || hg.node != hc.node {
                        differ += 1;
                    }
                }
            }
            // ties (a slave equally near two facets) may go either way in f32; nothing else
            assert!(
                differ * 1000 < 60 * 3000,
                "{g}: {differ} hits differ from the CPU mirror"
            );
        }
    }
}

/// A master that travels far (here 60 times its own size, with its slaves) moves the frame: the
/// increment after it passes 16 sizes from the frame's origin searches globally in a frame at
/// the master (`Trigger::Frame`), and every increment's contacts — points in model coordinates
/// included — are a fresh global search's, on the CPU path and every adapter.
#[test]
fn a_master_travelling_far_moves_the_frame() {
    let n = 16;
    let h = 1.0 / n as f64;
    let plate = plate_quads(n, n, 1.0, 1.0, 0.0, 2, &|x, y| 0.01 * (x + 2.0 * y));
    let slaves = abut::mesh::point_cloud(400, [0.05, 0.05, 0.02], [0.95, 0.95, 0.03], 8);
    let (m, p, _) = model_with(
        3,
        &plate.positions,
        Surface::quads(&quads_of(&plate)),
        &slaves,
        2.0 * h,
    );
    let base = m.positions().to_vec();
    let at = |k: usize| {
        let shift = [3.0 * k as f64, -1.25 * k as f64, 0.5 * k as f64];
        base.iter()
            .map(|q| [q[0] + shift[0], q[1] + shift[1], q[2] + shift[2]])
            .collect::<Vec<_>>()
    };
    for d in devices() {
        let mut tracked = GlobalSearch::new(&d, &m, p).unwrap();
        let mut fresh = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
        let mut moves = Vec::new();
        for k in 0..20 {
            let x = at(k);
            let r = tracked.step(&x).unwrap();
            let g = fresh.run(&x).unwrap();
            if r.stats.trigger == Trigger::Frame {
                moves.push(k);
                // the new frame is at the master
                assert!(
                    (r.frame[0] - x[0][0]).abs() < 4.0 && (r.frame[1] - x[0][1]).abs() < 4.0,
                    "{d} k={k}: frame {:?} far from the master at {:?}",
                    r.frame,
                    x[0]
                );
            }
            let mut compared = 0;
            for (i, (a, b)) in r.contacts().zip(g.contacts()).enumerate() {
                let (Some(a), Some(b)) = (a, b) else {
                    assert_eq!(a.is_some(), b.is_some(), "{d} k={k}: slave {i}");
                    continue;
                };
                compared += 1;
                assert!(
                    (a.distance - b.distance).abs() < 1e-5,
                    "{d} k={k}: slave {i}"
                );
                for c in 0..3 {
                    assert!(
                        (a.point[c] - b.point[c]).abs() < 1e-5,
                        "{d} k={k}: slave {i}: point {:?} vs {:?}",
                        a.point,
                        b.point
                    );
                }
            }
            assert_eq!(compared, 400, "{d} k={k}");
        }
        // 16 plate sizes are passed in the sixth increment (3.3 per increment), and again 16
        // sizes after that
        assert!(
            moves.len() >= 2 && moves[0] <= 6,
            "{d}: the frame moved at {moves:?}"
        );
    }
}
