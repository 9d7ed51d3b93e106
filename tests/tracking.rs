//! Finite-sliding tracking: the local search between global searches finds the facet a global
//! search would, increment after increment, over long sliding runs — many facets crossed,
//! curved cylinder and sphere masters, a surface with a hole and free edges, a sheet folding
//! onto itself — and with large motion the budget triggers a global search before a contact
//! is missed. GPU against CPU parity of the tracking, and determinism.

mod common;

use abut::mesh::{plate_quads, plate_triangles, sphere_triangles};
use abut::search::{Schedule, Trigger};
use abut::*;
use common::{facet_distance, gpus};

fn devices() -> Vec<Device> {
    let mut d = vec![Device::cpu()];
    d.extend(gpus().iter().cloned());
    d
}

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
/// equally near (a tie).
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
        for (i, gc) in g.contacts.iter().enumerate() {
            let Some(gc) = gc else { continue };
            if gc.distance > zone {
                continue;
            }
            t.compared += 1;
            let excess = match r.contacts[i] {
                Some(tc) if tc.facet == gc.facet => 0.0,
                Some(tc) => facet_distance(master, &x, r.slaves[i], tc.facet) - gc.distance,
                None => f64::INFINITY,
            };
            if excess > tol {
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
    }
}

fn wide(interval: u32) -> Schedule {
    Schedule {
        interval,
        budget: 0.5,
        wide_local: true,
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
