//! Kinematic contact: elastic bar impacts (VERIFICATION §1) with lumped-mass bars, no
//! penetration after a hard correction, momentum, a body on an analytical plane and on a
//! meshed plane, softened laws at equilibrium, rigid bodies, balanced pairs, the master
//! penetrating a coarse slave mesh, initial overclosure, and GPU-search parity.

mod common;

use abut::*;
use common::gpus;

fn devices() -> Vec<Device> {
    let mut d = vec![Device::cpu()];
    d.extend(gpus().iter().cloned());
    d
}

fn kinematic(softened: Option<PressureOverclosure>) -> Enforce {
    Enforce::Kinematic(Kinematic { softened })
}

/// A lumped-mass bar as a chain of nodes along x from `x0`: `n` elements of length `h`, total
/// mass `mass`, axial stiffness `ea`. Returns the node ids and the springs (i, j, k, L0).
fn chain(
    m: &mut Model,
    x0: f64,
    y: f64,
    n: usize,
    h: f64,
    mass: f64,
    ea: f64,
    two_d: bool,
) -> (Vec<u32>, Vec<(usize, usize, f64, f64)>) {
    let pos: Vec<[f64; 3]> = (0..=n).map(|i| [x0 + i as f64 * h, y, 0.0]).collect();
    let me = mass / n as f64;
    let masses: Vec<f64> = (0..=n)
        .map(|i| if i == 0 || i == n { 0.5 * me } else { me })
        .collect();
    let r = if two_d {
        m.add_nodes_2d(
            &pos.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>(),
            &masses,
        )
        .unwrap()
    } else {
        m.add_nodes(&pos, &masses).unwrap()
    };
    let ids = r.to_vec();
    let springs = (0..n)
        .map(|i| (ids[i] as usize, ids[i + 1] as usize, ea / h, h))
        .collect();
    (ids, springs)
}

fn spring_forces(x: &[[f64; 3]], springs: &[(usize, usize, f64, f64)], f: &mut [[f64; 3]]) {
    for v in f.iter_mut() {
        *v = [0.0; 3];
    }
    for &(i, j, k, l0) in springs {
        let t = k * ((x[j][0] - x[i][0]) - l0);
        f[i][0] += t;
        f[j][0] -= t;
    }
}

struct Impact {
    t_impact: f64,
    t_release: f64,
    mean_force: f64,
    impulse: f64,
    v_after: f64,
}

/// Integrates with central differences and kinematic contact. The contact force on `body` in
/// each increment is the momentum its nodes gain from the correction over dt, the average over
/// the increment (so it belongs to the increment's midpoint). Impact and release are the
/// rising and falling edges of that discrete signal at half its plateau (linear interpolation
/// between increments); the mean force is the impulse over the time between them.
#[allow(clippy::too_many_arguments)]
fn run_impact(
    d: &Device,
    m: &Model,
    springs: &[(usize, usize, f64, f64)],
    v0: &[[f64; 3]],
    body: &[u32],
    bodies: &mut [BodyState],
    dt: f64,
    t_end: f64,
) -> Impact {
    let mut c = Contact::new(d, m).unwrap();
    let mass = m.masses().to_vec();
    let mut x = m.positions().to_vec();
    let mut v = v0.to_vec();
    let mut f = vec![[0.0; 3]; x.len()];
    let steps = (t_end / dt).ceil() as usize;
    let mut history = Vec::with_capacity(steps);
    for _ in 0..steps {
        spring_forces(&x, springs, &mut f);
        for i in 0..x.len() {
            v[i][0] += dt * f[i][0] / mass[i];
            for a in 0..3 {
                x[i][a] += dt * v[i][a];
            }
        }
        let before: f64 = body
            .iter()
            .map(|&i| mass[i as usize] * v[i as usize][0])
            .sum();
        let rep = c.kinematic_step(&mut x, &mut v, bodies, dt).unwrap();
        assert!(
            rep.max_overclosure_after <= 1e-9,
            "{d}: overclosure {} left after correction",
            rep.max_overclosure_after
        );
        let after: f64 = body
            .iter()
            .map(|&i| mass[i as usize] * v[i as usize][0])
            .sum();
        history.push((after - before).abs() / dt);
    }
    let impulse: f64 = history.iter().sum::<f64>() * dt;
    let first = history.iter().position(|&f| f > 0.0).expect("no contact");
    let last = history.iter().rposition(|&f| f > 0.0).unwrap();
    let mid = &history[first + (last - first) / 4..last - (last - first) / 4];
    let half = 0.5 * mid.iter().sum::<f64>() / mid.len() as f64;
    let t_mid = |n: usize| (n as f64 + 0.5) * dt;
    let rise = (first..=last).find(|&n| history[n] >= half).unwrap();
    let t_impact =
        t_mid(rise - 1) + dt * (half - history[rise - 1]) / (history[rise] - history[rise - 1]);
    let fall = (first..=last).rev().find(|&n| history[n] >= half).unwrap();
    let t_release = t_mid(fall) + dt * (history[fall] - half) / (history[fall] - history[fall + 1]);
    let total: f64 = body.iter().map(|&i| mass[i as usize]).sum();
    let p: f64 = body
        .iter()
        .map(|&i| mass[i as usize] * v[i as usize][0])
        .sum();
    Impact {
        t_impact,
        t_release,
        mean_force: impulse / (t_release - t_impact),
        impulse,
        v_after: p / total,
    }
}

/// Symmetric two-bar impact (Cirak & West 2005): bars 2×2×10, E = 1, ν = 0, ρ = 1, ±0.1.
/// Exact: F = ρ·c·v0·A = 0.4 for T = 2L/c = 20, each bar leaves at ∓0.1. Each bar is two
/// lumped-mass chains in 2D; bar 2's end is a master segment, bar 1's end nodes its slaves.
#[test]
fn symmetric_two_bar_impact() {
    let (e, rho, a, l, v0, n) = (1.0f64, 1.0, 4.0, 10.0, 0.1, 100);
    let c = (e / rho).sqrt();
    let h = l / n as f64;
    let gap = 0.18;
    let mut m = Model::new_2d();
    let mut springs = Vec::new();
    let mut bar1 = Vec::new();
    let mut ends1 = Vec::new();
    for y in [0.5, -0.5] {
        let (ids, s) = chain(&mut m, 0.0, y, n, h, rho * a * l / 2.0, e * a / 2.0, true);
        springs.extend(s);
        ends1.push(*ids.last().unwrap());
        bar1.extend(ids);
    }
    let mut ends2 = Vec::new();
    for y in [1.0, -1.0] {
        let (ids, s) = chain(
            &mut m,
            l + gap,
            y,
            n,
            h,
            rho * a * l / 2.0,
            e * a / 2.0,
            true,
        );
        springs.extend(s);
        ends2.push(ids[0]);
    }
    let face = m
        .add_surface(Surface::segments(&[[ends2[0], ends2[1]]]))
        .unwrap(); // normal −x
    let set = m.add_node_set(&ends1).unwrap();
    m.add_pair(
        Pair::new(set, face)
            .search_radius(1.0)
            .enforce(kinematic(None)),
    )
    .unwrap();
    let v: Vec<[f64; 3]> = (0..m.positions().len())
        .map(|i| {
            if bar1.contains(&(i as u32)) {
                [v0, 0.0, 0.0]
            } else {
                [-v0, 0.0, 0.0]
            }
        })
        .collect();
    let dt = 0.9 * h / c; // Courant 0.9 (never exactly 1)
    let (f_exact, t_exact, t0) = (rho * c * v0 * a, 2.0 * l / c, gap / (2.0 * v0));
    for d in devices() {
        let r = run_impact(&d, &m, &springs, &v, &bar1, &mut [], dt, 30.0);
        assert!(
            (r.t_impact - t0).abs() <= dt,
            "{d}: impact at {} (exact {t0})",
            r.t_impact
        );
        assert!(
            (r.t_release - (t0 + t_exact)).abs() <= dt,
            "{d}: release at {} (exact {})",
            r.t_release,
            t0 + t_exact
        );
        assert!(
            (r.mean_force - f_exact).abs() <= 0.01 * f_exact,
            "{d}: mean force {} (exact {f_exact})",
            r.mean_force
        );
        assert!(
            (r.impulse - f_exact * t_exact).abs() <= 0.01 * f_exact * t_exact,
            "{d}: impulse {}",
            r.impulse
        );
        assert!(
            (r.v_after + v0).abs() <= 0.01 * v0,
            "{d}: bar 1 leaves at {} (exact {})",
            r.v_after,
            -v0
        );
    }
}

/// Truss impact on a rigid wall (Abaqus Benchmarks): L = 2 m, A = 0.2 m², E = 200 GPa,
/// ρ = 7800 kg/m³, v0 = 1.5 m/s, clearance 1 mm; the wall is an analytical plane on a rigid body.
#[test]
fn truss_impact_on_a_rigid_wall() {
    let (e, rho, a, l, v0, n, clear) = (200e9f64, 7800.0, 0.2, 2.0, 1.5, 100, 1e-3);
    let c = (e / rho).sqrt();
    let h = l / n as f64;
    let mut m = Model::new_3d();
    let (ids, springs) = chain(&mut m, 0.0, 0.0, n, h, rho * a * l, e * a, false);
    let wall = m
        .add_rigid_body(RigidBody {
            mass: 1e30,
            inertia: [[1e30, 0.0, 0.0], [0.0, 1e30, 0.0], [0.0, 0.0, 1e30]],
            surface: Analytical::Plane {
                point: [0.0; 3],
                normal: [-1.0, 0.0, 0.0],
            },
        })
        .unwrap();
    let set = m.add_node_set(&[*ids.last().unwrap()]).unwrap();
    m.add_rigid_pair(RigidPair {
        slave: set,
        body: wall,
        softened: None,
    })
    .unwrap();
    let v = vec![[v0, 0.0, 0.0]; m.positions().len()];
    let dt = 0.9 * h / c;
    let (f_exact, t_exact, t0) = (rho * c * v0 * a, 2.0 * l / c, clear / v0);
    assert!(
        (t0 - 6.67e-4).abs() < 1e-6
            && (f_exact - 1.185e7).abs() < 1e4
            && (t_exact - 7.90e-4).abs() < 1e-6
    );
    for d in devices() {
        let mut bodies = [BodyState::at([l + clear, 0.0, 0.0])];
        let r = run_impact(&d, &m, &springs, &v, &ids, &mut bodies, dt, 2.2e-3);
        assert!(
            (r.t_impact - t0).abs() <= dt,
            "{d}: impact at {} (exact {t0})",
            r.t_impact
        );
        assert!(
            (r.t_release - (t0 + t_exact)).abs() <= dt,
            "{d}: release at {} (exact {})",
            r.t_release,
            t0 + t_exact
        );
        assert!(
            (r.mean_force - f_exact).abs() <= 0.01 * f_exact,
            "{d}: mean force {} (exact {f_exact})",
            r.mean_force
        );
        assert!(
            (r.impulse - f_exact * t_exact).abs() <= 0.01 * f_exact * t_exact,
            "{d}: impulse {}",
            r.impulse
        );
        assert!(
            (r.v_after + v0).abs() <= 0.01 * v0,
            "{d}: rebound {} (exact {})",
            r.v_after,
            -v0
        );
        assert!(bodies[0].position[0] == l + clear, "the wall does not move");
    }
}
