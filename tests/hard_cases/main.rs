//! Issue 16's reporting cases: slaves that move farther than the search radius relative to the
//! master in one increment (tunnelling) are counted by the library and stop `abut`'s runs; results abut computes that
//! come out non-finite are errors naming the node and what was computed; a solution that
//! blows up names the increment, the node and the contact overclosure behind it; an initial
//! overclosure can be removed strain-free before the first increment.

#[path = "../common/mod.rs"]
mod common;

use abut::mesh::plate_quads;
use abut::*;
use common::devices;

/// A rigid-like plate of 4 × 2 quads on [-1, 1]² (z = 0), slave point masses at `slaves`, one
/// pair with search radius `radius` enforced by `enforce`, with Coulomb `mu` (0: none).
fn plate_and_points(slaves: &[[f64; 3]], radius: f64, enforce: Enforce, mu: f64) -> Model {
    let plate = plate_quads(4, 2, 2.0, 2.0, 0.0, 0, &|_, _| 0.0);
    let pos: Vec<[f64; 3]> = plate
        .positions
        .iter()
        .map(|p| [p[0] - 1.0, p[1] - 1.0, 0.0])
        .collect();
    let mut m = Model::new_3d();
    m.add_nodes(&pos, &vec![1e3; pos.len()]).unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let r = m.add_nodes(slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let mut pair = Pair::new(set, s).search_radius(radius).enforce(enforce);
    if mu > 0.0 {
        pair = pair.friction(Friction::coulomb(mu));
    }
    m.add_pair(pair).unwrap();
    m
}

fn penalty(k: f64) -> Enforce {
    Enforce::Penalty(Penalty {
        stiffness: Stiffness::Absolute(k),
        ..Default::default()
    })
}

/// Unit vectors towards, away from, along and oblique to the plate.
const DIRECTIONS: [[f64; 3]; 4] = [
    [0.0, 0.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 0.0],
    [0.6, 0.0, -0.8],
];

/// Penalty and kinematic pairs count every slave whose motion relative to the master near it
/// exceeds the search radius within the increment, in any direction, at several distances from
/// the plate (in contact range, near, far beyond the radius), and name the fastest; just below
/// the radius nothing is counted. The motion is relative: the master sweeping under still
/// slaves counts every slave, the slaves and the master closing on each other at 0.6 of the
/// radius each count, and the whole model travelling at 40 radii per increment counts none.
#[test]
fn slaves_faster_than_the_search_radius_relative_to_the_master_are_counted() {
    let radius = 0.25;
    let dt = 1e-3;
    let heights = [0.05, 0.2, 3.0]; // in contact range, near, far beyond the radius
    let slaves: Vec<[f64; 3]> = heights.iter().map(|&z| [0.1, 0.2, z]).collect();
    for enforce in [penalty(1e4), Enforce::Kinematic(Kinematic::default())] {
        let kinematic = matches!(enforce, Enforce::Kinematic(_));
        let m = plate_and_points(&slaves, radius, enforce, 0.0);
        let n = m.positions().len();
        let first_slave = n - slaves.len();
        let step = |d: &Device, v: &mut Vec<[f64; 3]>| {
            let mut c = Contact::new(d, &m).unwrap();
            if kinematic {
                let mut x = m.positions().to_vec();
                let r = c.kinematic_step(&mut x, v, &mut [], dt).unwrap();
                (r.fast_nodes, r.fastest)
            } else {
                let r = c.penalty_step(m.positions(), v, dt).unwrap();
                (r.fast_nodes, r.fastest)
            }
        };
        for d in devices() {
            for dir in DIRECTIONS {
                for (ratio, expect_fast) in [(0.9, false), (1.1, true), (40.0, true)] {
                    let speed = ratio * radius / dt;
                    let what = format!("{d} kinematic={kinematic} dir {dir:?} ratio {ratio}");
                    // one slave moves (in contact range, near, far)
                    for mover in first_slave..n {
                        let mut v = vec![[0.0; 3]; n];
                        v[mover] = dir.map(|c| c * speed);
                        let (fast, fastest) = step(&d, &mut v);
                        let what = format!("{what} slave {mover}");
                        assert_eq!(fast, usize::from(expect_fast), "{what}");
                        match fastest {
                            Some(f) => {
                                assert!(expect_fast, "{what}");
                                assert_eq!(f.node, mover, "{what}");
                                assert!((f.radius - radius).abs() < 1e-12, "{what}");
                                assert!(
                                    (f.distance - ratio * radius).abs() < 1e-9,
                                    "{what}: {}",
                                    f.distance
                                );
                            }
                            None => assert!(!expect_fast, "{what}"),
                        }
                    }
                    // the master sweeps under the still slaves: every slave moves relative to it
                    let mut v = vec![[0.0; 3]; n];
                    for vi in &mut v[..first_slave] {
                        *vi = dir.map(|c| -c * speed);
                    }
                    let (fast, fastest) = step(&d, &mut v);
                    let expect = if expect_fast { slaves.len() } else { 0 };
                    assert_eq!(fast, expect, "{what}: master moving");
                    assert_eq!(fastest.is_some(), expect_fast, "{what}: master moving");
                    // both close on each other at 0.6 of the ratio each
                    let mut v = vec![[0.0; 3]; n];
                    for (k, vi) in v.iter_mut().enumerate() {
                        let sign = if k < first_slave { -0.6 } else { 0.6 };
                        *vi = dir.map(|c| sign * c * speed);
                    }
                    let (fast, _) = step(&d, &mut v);
                    let expect = if 1.2 * ratio > 1.0 { slaves.len() } else { 0 };
                    assert_eq!(fast, expect, "{what}: opposing");
                    // the whole model travels together: nothing is fast
                    let mut v = vec![dir.map(|c| 40.0 * c * radius / dt); n];
                    let (fast, fastest) = step(&d, &mut v);
                    assert_eq!((fast, fastest), (0, None), "{what}: travelling together");
                }
            }
        }
    }
}

/// A slave velocity finite in f64 but beyond what the f32 kernels hold either gives finite
/// forces or an error that names the slave node and says the value was computed by abut, never
/// NaN forces with `Ok`.
#[test]
fn non_finite_penalty_forces_are_errors_naming_the_node() {
    let slaves = [[0.1, 0.2, -0.01], [-0.3, 0.4, 0.02]];
    let m = plate_and_points(
        &slaves,
        0.25,
        Enforce::Penalty(Penalty {
            stiffness: Stiffness::Absolute(1e4),
            damping: 0.2,
            ..Default::default()
        }),
        0.3, // friction too: its trial force grows with the speed
    );
    let n = m.positions().len();
    let slave = n - 2; // the penetrating one
    for d in devices() {
        let mut errors = 0;
        for speed in [1e3, 1e30, 1e36, 1e38, 1e39, 1e300] {
            let mut v = vec![[0.0; 3]; n];
            v[slave] = [0.3 * speed, 0.0, -speed];
            let mut c = Contact::new(&d, &m).unwrap();
            match c.penalty_step(m.positions(), &v, 1e-4) {
                Ok(r) => assert!(
                    r.forces.iter().flatten().all(|f| f.is_finite()),
                    "{d} speed {speed}: non-finite forces returned as Ok"
                ),
                Err(Error::NonFiniteResult { node, what, .. }) => {
                    assert_eq!(node, slave, "{d} speed {speed}: {what}");
                    assert!(what.contains("penalty contact force"), "{what}");
                    errors += 1;
                }
                Err(e) => panic!("{d} speed {speed}: unexpected error {e}"),
            }
        }
        assert!(
            errors >= 1,
            "{d}: no speed overflowed the kernels: not a test"
        );
    }
}

#[cfg(feature = "solver")]
mod scenes;

#[cfg(feature = "solver")]
mod increments;

#[cfg(feature = "solver")]
mod kinematic_friction;

#[cfg(feature = "solver")]
mod penalty_friction;
