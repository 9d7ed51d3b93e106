//! Issue 16's reporting cases: nodes that move farther than the search radius in one increment
//! (tunnelling) are counted by the library and stop `abut`'s runs; results abut computes that
//! come out non-finite are errors naming the node and what was computed; a solution that
//! blows up names the increment, the node and the contact overclosure behind it; an initial
//! overclosure can be removed strain-free before the first increment.

mod common;

use abut::mesh::plate_quads;
use abut::*;
use common::gpus;

fn devices() -> Vec<Device> {
    let mut d = vec![Device::cpu()];
    d.extend(gpus().iter().cloned());
    d
}

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

/// Penalty and kinematic pairs count every pair node whose speed × increment exceeds the search
/// radius, slave or master, in any direction, at several distances from the plate, and name the
/// fastest; just below the radius nothing is counted.
#[test]
fn nodes_faster_than_the_search_radius_are_counted() {
    let radius = 0.25;
    let dt = 1e-3;
    let heights = [0.05, 0.2, 3.0]; // in contact range, near, far beyond the radius
    let slaves: Vec<[f64; 3]> = heights.iter().map(|&z| [0.1, 0.2, z]).collect();
    for enforce in [penalty(1e4), Enforce::Kinematic(Kinematic::default())] {
        let kinematic = matches!(enforce, Enforce::Kinematic(_));
        let m = plate_and_points(&slaves, radius, enforce, 0.0);
        let n = m.positions().len();
        let first_slave = n - slaves.len();
        for d in devices() {
            for dir in DIRECTIONS {
                for (ratio, expect_fast) in [(0.9, false), (1.1, true), (40.0, true)] {
                    for mover in [first_slave + 1, n - 1, 0] {
                        // one node moves: a slave (near or far) or a master node
                        let speed = ratio * radius / dt;
                        let mut v = vec![[0.0; 3]; n];
                        v[mover] = dir.map(|c| c * speed);
                        let mut c = Contact::new(&d, &m).unwrap();
                        let (fast, fastest) = if kinematic {
                            let mut x = m.positions().to_vec();
                            let r = c.kinematic_step(&mut x, &mut v, &mut [], dt).unwrap();
                            (r.fast_nodes, r.fastest)
                        } else {
                            let r = c.penalty_step(m.positions(), &v, dt).unwrap();
                            (r.fast_nodes, r.fastest)
                        };
                        let what = format!(
                            "{d} kinematic={kinematic} dir {dir:?} ratio {ratio} node {mover}"
                        );
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
mod scenes {
    use abut::scene::{run, Scene};
    use abut::{Device, Error};

    /// A block of 2 × 2 × 2 cells on a rigid floor, its base at `z0`, moving at `vz`.
    fn block_on_floor(z0: f64, vz: f64, enforce: &str, adjust: bool, end: f64) -> String {
        format!(
            r#"
title = "block and floor"
[run]
end_time = {end}
output_every = 10
adjust_overclosure = {adjust}
[[material]]
name = "m"
young = 1.0e7
poisson = 0.3
density = 1000.0
[[part]]
name = "block"
shape = "block"
material = "m"
origin = [0.0, 0.0, {z0}]
size = [0.1, 0.1, 0.1]
divisions = [2, 2, 2]
velocity = [0.0, 0.0, {vz}]
[[part]]
name = "floor"
shape = "plate"
origin = [-0.2, -0.2, 0.0]
size = [0.5, 0.5, 0.0]
divisions = [5, 5, 0]
[[contact]]
slave = "block"
slave_face = "z-"
master = "floor"
master_face = "z+"
enforce = "{enforce}"
"#
        )
    }

    fn scene(text: &str) -> Scene {
        Scene::parse(text).unwrap()
    }

    /// Tunnelling stops the run with an error naming the node, its motion and the radius (the
    /// search radius is one floor facet, 0.1); a block approaching at a speed the search can
    /// follow runs.
    #[test]
    fn tunnelling_stops_the_run() {
        for enforce in ["penalty", "kinematic"] {
            // increment ≈ 1.58e-4 s: 2000 m/s moves 0.32 per increment
            let e = run(
                &scene(&block_on_floor(0.3, -2000.0, enforce, false, 2e-3)),
                &Device::cpu(),
                None,
            )
            .unwrap_err();
            match &e {
                Error::Tunnelling {
                    increment,
                    distance,
                    radius,
                    ..
                } => {
                    assert_eq!(*increment, 1, "{enforce}: {e}");
                    assert!(*distance > *radius, "{enforce}: {e}");
                    assert!((radius - 0.1).abs() < 1e-9, "{enforce}: {e}");
                }
                other => panic!("{enforce}: {other}"),
            }
            run(
                &scene(&block_on_floor(0.03, -2.0, enforce, false, 5e-3)),
                &Device::cpu(),
                None,
            )
            .unwrap_or_else(|e| panic!("{enforce}: a slow block: {e}"));
        }
    }

    /// A kinematic pair whose block starts half its height inside the floor: the correction of
    /// the first increment inverts the elements and the solution blows up — an error that says
    /// so, names the increment, and points at the overclosure resolved at increment 1 (not a
    /// complaint about the user's coordinates). With `adjust_overclosure` the slave nodes are
    /// moved onto the floor strain-free first and the run completes, warning what it moved.
    #[test]
    fn an_initial_overclosure_blows_up_named_or_is_adjusted() {
        let e = run(
            &scene(&block_on_floor(-0.05, 0.0, "kinematic", false, 0.01)),
            &Device::cpu(),
            None,
        )
        .unwrap_err();
        // the elements launch the nodes: caught as a blow-up, or as nodes outrunning the
        // search, either way with the overclosure behind it named
        let (increment, cause) = match &e {
            Error::Diverged {
                increment, cause, ..
            } => (*increment, cause),
            Error::Tunnelling {
                increment, more, ..
            } => (*increment, more),
            other => panic!("{other}"),
        };
        assert!(increment > 1, "{e}");
        let h: f64 = cause
            .split("overclosure of ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no overclosure named: {e}"));
        assert!((h - 0.05).abs() < 1e-4, "{e}");
        assert!(cause.contains("at increment 1"), "{e}");
        assert!(cause.contains("adjust_overclosure"), "{e}");
        let s = run(
            &scene(&block_on_floor(-0.05, 0.0, "kinematic", true, 0.01)),
            &Device::cpu(),
            None,
        )
        .unwrap();
        assert!(
            s.warnings
                .iter()
                .any(|w| w.starts_with("9 slave nodes started overclosed")),
            "{:?}",
            s.warnings
        );
    }

    /// A bar of `n` elements (length `l`, area `a`, E, ρ) at speed `v` towards a rigid wall
    /// `gap` away (`two = false`), or two such bars towards each other `2·gap` apart, with
    /// penalty contact at the default settings.
    #[allow(clippy::too_many_arguments)]
    fn bars(n: usize, l: f64, a: f64, e: f64, rho: f64, v: f64, gap: f64, two: bool) -> String {
        let c = (e / rho).sqrt();
        let end = 1.5 * (gap / v + 2.0 * l / c);
        let other = if two {
            format!(
                r#"[[part]]
name = "other"
shape = "bar"
material = "m"
origin = [0.0, 0.0, {z}]
size = [0.0, 0.0, {l}]
area = {a}
divisions = [{n}, 0, 0]
velocity = [0.0, 0.0, {v}]
[[contact]]
slave = "bar"
slave_face = "z-"
master = "other"
master_face = "z+"
enforce = "penalty"
"#,
                z = -gap - l
            )
        } else {
            r#"[[part]]
name = "wall"
shape = "plate"
origin = [-1.0, -1.0, 0.0]
size = [2.0, 2.0, 0.0]
divisions = [2, 2, 0]
[[contact]]
slave = "bar"
slave_face = "z-"
master = "wall"
master_face = "z+"
enforce = "penalty"
"#
            .to_string()
        };
        let z0 = gap;
        format!(
            r#"
title = "bar impact"
[run]
end_time = {end}
[[material]]
name = "m"
young = {e}
poisson = 0.0
density = {rho}
[[part]]
name = "bar"
shape = "bar"
material = "m"
origin = [0.0, 0.0, {z0}]
size = [0.0, 0.0, {l}]
area = {a}
divisions = [{n}, 0, 0]
velocity = [0.0, 0.0, {mv}]
{other}"#,
            mv = -v
        )
    }

    /// The contact force history of a run's output: (time, total contact force).
    fn force_history(dir: &std::path::Path) -> Vec<(f64, f64)> {
        let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = head.iter().position(|h| *h == "contact_force").unwrap();
        lines
            .map(|l| {
                let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                (f[0], f[col])
            })
            .collect()
    }

    /// Issue 16, item 4: penalty contact at its default (automatic) stiffness follows a bar's
    /// impact as kinematic contact does — the force reaches half of ρ·c·v·A within two
    /// increments of the exact impact time and its plateau (the mean over the middle half of
    /// the contact) is within 2 % of it — on a wall and between two bars, for two materials,
    /// speeds and meshes; and it costs at most 14 % of the elements' increment.
    #[test]
    fn default_penalty_follows_bar_impacts_within_two_increments_and_two_percent() {
        // (elements, length, area, E, ρ, speed, gap, two bars)
        let cases = [
            (20, 2.0, 0.2, 200e9, 7800.0, 1.5, 1e-3, false),
            (40, 1.0, 0.01, 70e9, 2700.0, 5.0, 2e-3, false),
            (20, 10.0, 4.0, 1.0, 1.0, 0.1, 0.1, true),
            (40, 0.5, 1e-4, 3e9, 1200.0, 2.0, 1e-3, true),
        ];
        for d in [Device::cpu()]
            .into_iter()
            .chain(super::gpus().iter().cloned())
        {
            for &(n, l, a, e, rho, v, gap, two) in &cases {
                let sc = scene(&bars(n, l, a, e, rho, v, gap, two));
                let dir = std::env::temp_dir().join(format!(
                    "abut-bar-default-penalty-{}-{n}-{two}",
                    d.backend_name()
                ));
                let _ = std::fs::remove_dir_all(&dir);
                let s = run(&sc, &d, Some(&dir)).unwrap();
                let exact_force = rho * (e / rho).sqrt() * v * a;
                let exact_impact = gap / v;
                let dt = s.end_time / s.increments as f64;
                let late = (s.impact_time - exact_impact) / dt;
                let what = format!("{d}, {n} elements, two bars {two}");
                assert!(late.abs() <= 2.0, "{what}: impact {late} increments late");
                let h = force_history(&dir);
                let first = h.iter().position(|x| x.1 > 0.0).unwrap();
                let last = h.iter().rposition(|x| x.1 > 0.0).unwrap();
                let span = last - first;
                let mid = &h[first + span / 4..=last - span / 4];
                let plateau = mid.iter().map(|x| x.1).sum::<f64>() / mid.len() as f64;
                assert!(
                    (plateau / exact_force - 1.0).abs() <= 0.02,
                    "{what}: plateau {plateau} against {exact_force}"
                );
                // the contact lasts 2L/c (the wave's round trip), to within the rise and fall
                let c = (e / rho).sqrt();
                let duration = s.release_time - s.impact_time;
                assert!(
                    (duration - 2.0 * l / c).abs() <= 2.0 * dt,
                    "{what}: contact lasts {duration} against {}",
                    2.0 * l / c
                );
                assert!(
                    s.contact_lowered_increment <= 0.14,
                    "{what}: the increment cost {}",
                    s.contact_lowered_increment
                );
            }
        }
    }

    /// Issue 16, item 2: an axisymmetric bar hits a rigid line whose end lies at, just around
    /// or beyond the axis node (x = 0), with penalty and kinematic contact. The axis node is
    /// held on the axis (u_r = 0 by symmetry) — left free it drifted off the axis, beside the
    /// line's free end, and was launched when it came back (energy ×4 with the line starting
    /// at x = 0) — so no placement gains energy: kinetic plus internal never exceeds its
    /// initial value by more than 1 %, and the axis node stays at r = 0.
    #[test]
    fn an_axisymmetric_bar_on_a_line_ending_at_its_axis_gains_no_energy() {
        for (width, cells) in [(0.2, 2), (0.3, 5)] {
            for start in [0.0, 1e-7, -1e-7, -1e-3, 0.02, -0.1] {
                for enforce in ["penalty", "kinematic"] {
                    let text = format!(
                        r#"
title = "axisymmetric bar on a wall"
[run]
end_time = 1.5
[[material]]
name = "m"
young = 1.0
poisson = 0.3
density = 1.0
[[part]]
name = "bar"
shape = "rect"
axisymmetric = true
material = "m"
origin = [0.0, 0.01, 0.0]
size = [{width}, 1.0, 0.0]
divisions = [{cells}, 10, 0]
velocity = [0.0, -0.1, 0.0]
[[part]]
name = "wall"
shape = "line"
origin = [{start}, 0.0, 0.0]
size = [1.0, 0.0, 0.0]
divisions = [4, 0, 0]
[[contact]]
slave = "bar"
slave_face = "y-"
master = "wall"
master_face = "y+"
enforce = "{enforce}"
"#
                    );
                    let dir = std::env::temp_dir()
                        .join(format!("abut-axi-edge-{width}-{start}-{enforce}"));
                    let _ = std::fs::remove_dir_all(&dir);
                    let s = run(&scene(&text), &Device::cpu(), Some(&dir)).unwrap();
                    let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
                    let mut lines = csv.lines();
                    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
                    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
                    let (k, u) = (col("kinetic"), col("internal"));
                    let energy: Vec<f64> = lines
                        .map(|l| {
                            let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                            f[k] + f[u]
                        })
                        .collect();
                    let e0 = energy[0];
                    let top = energy.iter().cloned().fold(0.0, f64::max);
                    let what = format!("width {width}, line from x = {start}, {enforce}");
                    assert!(
                        top <= 1.01 * e0,
                        "{what}: energy rose to {} of its start",
                        top / e0
                    );
                    // still in contact at the end (the wave returns at about t = 2)
                    assert!(!s.contact_nodes.is_empty(), "{what}: no contact at the end");
                    for n in &s.contact_nodes {
                        if n.position[0].abs() < 0.5 * width / cells as f64 {
                            assert_eq!(n.position[0], 0.0, "{what}: the axis node left the axis");
                        }
                    }
                }
            }
        }
    }

    /// Kinetic plus internal energy less the work of gravity over a run's history (its
    /// largest value and its last), from the output directory.
    fn mechanical_energy(dir: &std::path::Path) -> (f64, f64, f64) {
        let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
        let (k, u, w) = (col("kinetic"), col("internal"), col("external_work"));
        let e: Vec<f64> = lines
            .map(|l| {
                let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                f[k] + f[u] - f[w]
            })
            .collect();
        (
            e[0],
            e.iter().cloned().fold(f64::MIN, f64::max),
            e[e.len() - 1],
        )
    }

    /// A 0.1 m elastic block (2 × 2 × 2 cells) at `velocity`, its base at `z0`, on a rigid
    /// plate of 0.1 m facets spanning [x0, x0 + sx] × [y0, y0 + sy], with `gravity`.
    #[allow(clippy::too_many_arguments)]
    fn block_on_plate(
        enforce: &str,
        z0: f64,
        velocity: [f64; 3],
        plate: [f64; 4],
        gravity: f64,
        end: f64,
    ) -> String {
        let [x0, y0, sx, sy] = plate;
        let (nx, ny) = ((sx / 0.1).round() as usize, (sy / 0.1).round() as usize);
        format!(
            r#"
title = "block on a plate's edge"
[run]
end_time = {end}
gravity = [0.0, 0.0, {g}]
[[material]]
name = "m"
young = 1.0e7
poisson = 0.3
density = 1000.0
[[part]]
name = "block"
shape = "block"
material = "m"
origin = [0.0, 0.0, {z0}]
size = [0.1, 0.1, 0.1]
divisions = [2, 2, 2]
velocity = [{vx}, {vy}, {vz}]
[[part]]
name = "plate"
shape = "plate"
origin = [{x0}, {y0}, 0.0]
size = [{sx}, {sy}, 0.0]
divisions = [{nx}, {ny}, 0]
[[contact]]
slave = "block"
slave_face = "z-"
master = "plate"
master_face = "z+"
enforce = "{enforce}"
"#,
            g = -gravity,
            vx = velocity[0],
            vy = velocity[1],
            vz = velocity[2]
        )
    }

    /// Issue 16, item 2, in 3D: a block dropped at 1 m/s onto a rigid plate whose free edge,
    /// or corner, lies exactly under a row of its nodes or beside it by up to twice the
    /// extension zone (0.1 of a facet) — where the Poisson bulge carries nodes across the
    /// edge or across the zone's boundary while they are pressed in. Kinematic contact never
    /// raises the block's energy; penalty contact raises it by at most 1.5 % of the start more
    /// than the same drop far from any edge does (before: ×3–×7 at and around the edge, the
    /// nodes released beside it and launched when they came back). A block sliding at 2 m/s off
    /// the plate's edge under gravity gains nothing either.
    #[test]
    fn slaves_at_and_around_free_edges_and_corners_gain_no_energy() {
        let h = 0.1;
        let offsets = [0.0, 1e-6, 0.03, 0.095, 0.099, 0.101, 0.11, 0.2];
        let devices: Vec<Device> = [Device::cpu()]
            .into_iter()
            .chain(super::gpus().iter().cloned())
            .collect();
        for (d, enforce) in devices
            .iter()
            .flat_map(|d| ["penalty", "kinematic"].map(|e| (d, e)))
        {
            let run_dir = |tag: String, text: String| {
                let dir = std::env::temp_dir()
                    .join(format!("abut-edge-{}-{enforce}-{tag}", d.backend_name()));
                let _ = std::fs::remove_dir_all(&dir);
                run(&scene(&text), d, Some(&dir)).unwrap();
                mechanical_energy(&dir)
            };
            let drop = |plate: [f64; 4]| {
                block_on_plate(enforce, 0.001, [0.0, 0.0, -1.0], plate, 0.0, 0.02)
            };
            let (e0, base_top, _) = run_dir("inside".into(), drop([-0.1, -0.1, 0.5, 0.5]));
            let allowed = if enforce == "kinematic" {
                e0 * (1.0 + 1e-9)
            } else {
                base_top + 0.015 * e0
            };
            for f in offsets {
                let s = f * h;
                for (what, plate) in [("corner", [s, s, 0.5, 0.5]), ("edge", [s, -0.1, 0.5, 0.5])] {
                    let (start, top, last) = run_dir(format!("{what}-{f}"), drop(plate));
                    assert!((start - e0).abs() <= 1e-12 * e0);
                    assert!(
                        top <= allowed && last <= allowed,
                        "{d}, {enforce}: plate's {what} {f} of a facet beside the nodes: energy \
                         {top} at most, {last} at the end, against {e0} (allowed {allowed})"
                    );
                }
            }
            // sliding off the edge x = 0.2 (at 2 m/s, in 0.1 s) under gravity
            for sx in [0.3, 0.35] {
                let text = block_on_plate(
                    enforce,
                    0.0,
                    [2.0, 0.0, 0.0],
                    [-0.1, -0.1, sx, 0.3],
                    9.81,
                    0.25,
                );
                let (start, top, last) = run_dir(format!("slide-{sx}"), text);
                // the trapezoidal booking of gravity's work: 1e-5 (kinematic) of round-off
                let tol = if enforce == "kinematic" { 1e-5 } else { 0.005 };
                assert!(
                    top <= start * (1.0 + tol) && last <= start * (1.0 + tol),
                    "{d}, {enforce}: sliding off an edge: energy {top} at most, {last} at the end, \
                     against {start}"
                );
            }
        }
    }
}
