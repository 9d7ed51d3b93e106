//! Kinematic contact: elastic bar impacts (VERIFICATION §1) with lumped-mass bars, no
//! penetration after a hard correction, momentum, a body on an analytical plane and on a
//! meshed plane, softened laws at equilibrium, rigid bodies, balanced pairs, the master
//! penetrating a coarse slave mesh, initial overclosure, and GPU-search parity.

mod common;

use abut::*;
use common::devices;

fn kinematic(softened: Option<PressureOverclosure>) -> Enforce {
    Enforce::Kinematic(Kinematic { softened })
}

/// A spring between nodes i and j: (i, j, stiffness k, rest length L0).
type Spring = (usize, usize, f64, f64);

/// A rigid body of `mass`, inertia `inertia`·I about its reference point, carrying `surface`.
fn body(mass: f64, inertia: f64, surface: Analytical) -> RigidBody {
    RigidBody {
        mass,
        inertia: [
            [inertia, 0.0, 0.0],
            [0.0, inertia, 0.0],
            [0.0, 0.0, inertia],
        ],
        surface,
    }
}

/// A fixed wall: the analytical plane through the origin with outward `normal`, on a body of
/// mass and inertia 10³⁰.
fn fixed_plane(normal: [f64; 3]) -> RigidBody {
    let surface = Analytical::Plane {
        point: [0.0; 3],
        normal,
    };
    body(1e30, 1e30, surface)
}

/// The node set `slave` against rigid body `body`'s surface, hard (`None`) or softened.
fn rigid_pair(slave: NodeSetId, body: BodyId, softened: Option<PressureOverclosure>) -> RigidPair {
    RigidPair {
        slave,
        body,
        softened,
    }
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
) -> (Vec<u32>, Vec<Spring>) {
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
    /// Kinetic energy change made by the first correction (the impact).
    ke_at_impact: f64,
    t_impact: f64,
    t_release: f64,
    mean_force: f64,
    impulse: f64,
    v_after: f64,
}

impl Impact {
    /// The impact against the exact solution on device `d`: impact at `t0` and release after
    /// `t_exact`, each within one increment `dt`; mean force `f_exact` and its impulse within 1 %;
    /// the body leaving at `v_exact` within 1 % of it.
    fn assert_exact(&self, d: &Device, t0: f64, t_exact: f64, f_exact: f64, dt: f64, v_exact: f64) {
        assert!(
            (self.t_impact - t0).abs() <= dt,
            "{d}: impact at {} (exact {t0})",
            self.t_impact
        );
        assert!(
            (self.t_release - (t0 + t_exact)).abs() <= dt,
            "{d}: release at {} (exact {})",
            self.t_release,
            t0 + t_exact
        );
        assert!(
            (self.mean_force - f_exact).abs() <= 0.01 * f_exact,
            "{d}: mean force {} (exact {f_exact})",
            self.mean_force
        );
        assert!(
            (self.impulse - f_exact * t_exact).abs() <= 0.01 * f_exact * t_exact,
            "{d}: impulse {} (exact {})",
            self.impulse,
            f_exact * t_exact
        );
        assert!(
            (self.v_after - v_exact).abs() <= 0.01 * v_exact.abs(),
            "{d}: leaves at {} (exact {v_exact})",
            self.v_after
        );
    }
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
    let mut ke_at_impact = f64::NAN;
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
        if rep.active > 0 && ke_at_impact.is_nan() {
            ke_at_impact = rep.kinetic_energy_change;
        }
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
        ke_at_impact,
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
        r.assert_exact(&d, t0, t_exact, f_exact, dt, -v0);
        // known behaviour: kinematic contact dissipates the contact nodes' kinetic energy at impact
        assert!(
            r.ke_at_impact < 0.0,
            "{d}: kinetic energy change at impact {}",
            r.ke_at_impact
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
    let wall = m.add_rigid_body(fixed_plane([-1.0, 0.0, 0.0])).unwrap();
    let set = m.add_node_set(&[*ids.last().unwrap()]).unwrap();
    m.add_rigid_pair(rigid_pair(set, wall, None)).unwrap();
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
        r.assert_exact(&d, t0, t_exact, f_exact, dt, -v0);
        assert!(bodies[0].position[0] == l + clear, "the wall does not move");
    }
}

fn momentum(v: &[[f64; 3]], m: &[f64]) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (vi, mi) in v.iter().zip(m) {
        for a in 0..3 {
            p[a] += mi * vi[a];
        }
    }
    p
}

/// A wavy deformable plate (master, finite masses) and a cloud of slave nodes driven into it:
/// after the correction no slave penetrates beyond round-off and momentum is unchanged; the
/// GPU's and the CPU's searches give the same corrected state.
#[test]
fn hard_correction_leaves_no_penetration_and_keeps_momentum() {
    let plate = abut::mesh::plate_quads(20, 20, 1.0, 1.0, 0.2, 7, &|x, y| {
        0.03 * (5.0 * x).sin() * (4.0 * y).cos()
    });
    let cloud = abut::mesh::point_cloud(3000, [0.02, 0.02, -0.02], [0.98, 0.98, 0.02], 8);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![3.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.1)
            .enforce(kinematic(None)),
    )
    .unwrap();
    let mut rng = abut::mesh::SplitMix64::new(4);
    let v0: Vec<[f64; 3]> = (0..m.positions().len())
        .map(|_| {
            [
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
            ]
        })
        .collect();
    let dt = 1e-3;
    let mut reference: Option<Vec<[f64; 3]>> = None;
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        let mut x = m.positions().to_vec();
        let mut v = v0.clone();
        let p0 = momentum(&v, m.masses());
        let rep = c
            .kinematic_step(&mut x, &mut v, &mut [], dt)
            .unwrap()
            .clone();
        assert!(rep.active > 500, "{d}: {} corrected", rep.active);
        assert!(rep.max_overclosure > 1e-3);
        assert!(
            rep.max_overclosure_after <= 1e-12,
            "{d}: {} left",
            rep.max_overclosure_after
        );
        let p1 = momentum(&v, m.masses());
        let scale: f64 = v
            .iter()
            .zip(m.masses())
            .map(|(v, m)| m * v.iter().map(|c| c.abs()).sum::<f64>())
            .sum();
        for a in 0..3 {
            assert!(
                (p1[a] - p0[a]).abs() <= 1e-12 * scale,
                "{d}: momentum {p0:?} → {p1:?}"
            );
        }
        match &reference {
            None => reference = Some(x),
            Some(xr) => {
                let worst = xr
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max))
                    .fold(0.0, f64::max);
                assert!(
                    worst <= 1e-12,
                    "{d}: corrected state differs from the CPU search's by {worst}"
                );
            }
        }
    }
}

/// The seed's Figure 38.2.3–1: pure master–slave keeps slave nodes out of the master, but a
/// master node can still lie beyond a coarse slave surface. A balanced pair pushes it back.
#[test]
fn master_penetrates_a_coarse_slave_mesh_unless_balanced() {
    for balanced in [false, true] {
        let mut m = Model::new_2d();
        // master: a peak whose apex (node 1) rises above the line of the slave nodes
        m.add_nodes_2d(&[[2.0, -0.5], [0.0, 0.3], [-2.0, -0.5]], &[1.0; 3])
            .unwrap();
        let master = m.add_surface(Surface::segments(&[[0, 1], [1, 2]])).unwrap(); // normals up
                                                                                   // slave: a coarse surface of one segment, normal down (towards the master)
        let r = m
            .add_nodes_2d(&[[-1.0, 0.0], [1.0, 0.0]], &[1.0; 2])
            .unwrap();
        let slave_surface = m
            .add_surface(Surface::segments(&[[r.start, r.start + 1]]))
            .unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        let mut pair = Pair::new(set, master)
            .search_radius(1.0)
            .enforce(kinematic(None));
        if balanced {
            pair = pair.balanced(slave_surface, 0.5);
        }
        m.add_pair(pair).unwrap();
        let mut c = Contact::new(&Device::cpu(), &m).unwrap();
        let mut x = m.positions().to_vec();
        let mut v = vec![[0.0; 3]; x.len()];
        let p0 = momentum(&v, m.masses());
        c.kinematic_step(&mut x, &mut v, &mut [], 1e-2).unwrap();
        let slave_line_at_apex = 0.5 * (x[3][1] + x[4][1]);
        if balanced {
            assert!(
                x[1][1] <= slave_line_at_apex + 1e-9 + 0.5 * (0.3 - 0.0),
                "the balanced pass halves the apex's penetration: apex {} line {}",
                x[1][1],
                slave_line_at_apex
            );
            assert!(x[1][1] < 0.3, "the apex was pushed back");
        } else {
            assert_eq!(
                x,
                m.positions().to_vec(),
                "pure master–slave: no slave penetrates, nothing is corrected"
            );
            assert!(
                x[1][1] > slave_line_at_apex,
                "the master apex lies beyond the coarse slave surface"
            );
        }
        let p1 = momentum(&v, m.masses());
        assert!((0..3).all(|a| (p1[a] - p0[a]).abs() < 1e-12));
    }
}

/// Four point masses dropped under gravity on an analytical rigid plane and on a meshed plane
/// of the same geometry (massive nodes): the same motion.
#[test]
fn body_on_analytical_and_meshed_plane_agree() {
    let drops = [
        [0.1, 0.1, 0.05],
        [0.4, 0.1, 0.08],
        [0.4, 0.4, 0.06],
        [0.1, 0.4, 0.07],
    ];
    let run = |meshed: bool, d: &Device| -> Vec<[f64; 3]> {
        let mut m = Model::new_3d();
        let mut bodies = Vec::new();
        let first;
        if meshed {
            let plate = abut::mesh::plate_quads(4, 4, 2.0, 2.0, 0.0, 0, &|_, _| 0.0);
            let pos: Vec<[f64; 3]> = plate
                .positions
                .iter()
                .map(|p| [p[0] - 1.0, p[1] - 1.0, 0.0])
                .collect();
            m.add_nodes(&pos, &vec![1e30; pos.len()]).unwrap();
            let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
            let r = m.add_nodes(&drops, &[0.25; 4]).unwrap();
            first = r.start as usize;
            let set = m.add_node_set(&r.to_vec()).unwrap();
            m.add_pair(
                Pair::new(set, s)
                    .search_radius(0.2)
                    .enforce(kinematic(None)),
            )
            .unwrap();
        } else {
            let body = m.add_rigid_body(fixed_plane([0.0, 0.0, 1.0])).unwrap();
            let r = m.add_nodes(&drops, &[0.25; 4]).unwrap();
            first = r.start as usize;
            let set = m.add_node_set(&r.to_vec()).unwrap();
            m.add_rigid_pair(rigid_pair(set, body, None)).unwrap();
            bodies.push(BodyState::at([0.0; 3]));
        }
        let mut c = Contact::new(d, &m).unwrap();
        let mut x = m.positions().to_vec();
        let mut v = vec![[0.0; 3]; x.len()];
        let dt = 1e-3;
        for _ in 0..400 {
            for i in first..x.len() {
                v[i][2] -= 9.81 * dt;
                v[i][0] += 0.5 * dt; // a sideways push as well
                for a in 0..3 {
                    x[i][a] += dt * v[i][a];
                }
            }
            c.kinematic_step(&mut x, &mut v, &mut bodies, dt).unwrap();
        }
        x[first..].iter().chain(&v[first..]).copied().collect()
    };
    for d in devices() {
        let a = run(false, &d);
        let b = run(true, &d);
        for (p, q) in a.iter().zip(&b) {
            for k in 0..3 {
                assert!(
                    (p[k] - q[k]).abs() <= 1e-9,
                    "{d}: analytical {p:?} vs meshed {q:?}"
                );
            }
        }
        assert!(
            a[..4].iter().all(|p| p[2].abs() < 1e-12),
            "{d}: resting on the plane: {:?}",
            &a[..4]
        );
    }
}

/// Softened contact under a constant push settles where the law balances it: p(h)·A = F.
#[test]
fn softened_contact_reproduces_its_law_at_equilibrium() {
    // softened kinematic contact damps like backward Euler: |λ|² = 1/(1 + k_p·A·dt²/m) per step
    let (f, area, mass) = (3.0, 0.5, 0.02);
    for law in [
        PressureOverclosure::Exponential {
            clearance: 0.01,
            pressure: 4.0,
        },
        PressureOverclosure::Tabular(vec![(-0.005, 0.0), (0.005, 2.0), (0.02, 10.0)]),
    ] {
        for meshed in [false, true] {
            let mut m = Model::new_3d();
            let mut bodies = Vec::new();
            if meshed {
                m.add_nodes(
                    &[
                        [-1.0, -1.0, 0.0],
                        [1.0, -1.0, 0.0],
                        [1.0, 1.0, 0.0],
                        [-1.0, 1.0, 0.0],
                    ],
                    &[1e30; 4],
                )
                .unwrap();
                let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
                let r = m.add_nodes(&[[0.2, 0.3, 0.0]], &[mass]).unwrap();
                let set = m.add_node_set_with_areas(&r.to_vec(), &[area]).unwrap();
                m.add_pair(
                    Pair::new(set, s)
                        .search_radius(0.5)
                        .enforce(kinematic(Some(law.clone()))),
                )
                .unwrap();
            } else {
                let body = m.add_rigid_body(fixed_plane([0.0, 0.0, 1.0])).unwrap();
                let r = m.add_nodes(&[[0.2, 0.3, 0.0]], &[mass]).unwrap();
                let set = m.add_node_set_with_areas(&r.to_vec(), &[area]).unwrap();
                m.add_rigid_pair(rigid_pair(set, body, Some(law.clone())))
                    .unwrap();
                bodies.push(BodyState::at([0.0; 3]));
            }
            let mut c = Contact::new(&Device::cpu(), &m).unwrap();
            let mut x = m.positions().to_vec();
            let mut v = vec![[0.0; 3]; x.len()];
            let n = x.len() - 1;
            let dt = 1e-3;
            for _ in 0..3000 {
                v[n][2] -= dt * f / mass;
                x[n][2] += dt * v[n][2];
                c.kinematic_step(&mut x, &mut v, &mut bodies, dt).unwrap();
            }
            let h = -x[n][2];
            let p = law.pressure(h).0;
            assert!(
                (p * area - f).abs() <= 0.01 * f,
                "{law:?} meshed={meshed}: p(h)·A = {} at h = {h}, push {f}",
                p * area
            );
            assert!(v[n][2].abs() < 1e-3, "settled: v = {}", v[n][2]);
            // outputs: COPEN is the overclosure left, CPRESS the pressure of the law there
            let out = if meshed {
                c.outputs()[0].1.clone()
            } else {
                c.rigid_outputs()[0].1.clone()
            };
            assert_eq!(out.cstatus[0], Some(ContactStatus::Slip));
            assert!(
                (out.copen[0] + h).abs() <= 1e-3 * h.abs().max(1e-3),
                "{law:?}: copen {} vs {}",
                out.copen[0],
                -h
            );
            assert!(
                (out.cpress[0] * area - f).abs() <= 0.02 * f,
                "{law:?} meshed={meshed}: cpress {}",
                out.cpress[0]
            );
            assert!(out.contact_energy > 0.0);
        }
    }
}

/// Analytical surfaces on a free rigid body: slaves pushed into a sphere, a cylinder (3D), a
/// circle and a line (2D) end on the surface, and body plus slaves keep their linear momentum.
#[test]
fn rigid_bodies_with_analytical_surfaces() {
    let cases: Vec<(u32, Analytical, Vec<[f64; 3]>)> = vec![
        (
            3,
            Analytical::Sphere {
                centre: [0.0; 3],
                radius: 1.0,
            },
            vec![[0.95, 0.0, 0.0], [0.0, 0.6, 0.7], [-0.5, -0.5, -0.5]],
        ),
        (
            3,
            Analytical::Cylinder {
                point: [0.0; 3],
                axis: [0.0, 0.0, 1.0],
                radius: 0.5,
            },
            vec![[0.45, 0.0, 3.0], [0.0, -0.4, -1.0]],
        ),
        (
            2,
            Analytical::Circle {
                centre: [0.0, 0.0],
                radius: 1.0,
            },
            vec![[0.9, 0.1, 0.0], [-0.2, -0.95, 0.0]],
        ),
        (
            2,
            Analytical::Line {
                point: [0.0, 0.0],
                normal: [0.0, 1.0],
            },
            vec![[0.3, -0.05, 0.0], [-2.0, -0.01, 0.0]],
        ),
    ];
    for (dim, surface, nodes) in cases {
        let mut m = if dim == 2 {
            Model::new_2d()
        } else {
            Model::new_3d()
        };
        let body = m.add_rigid_body(body(5.0, 2.0, surface)).unwrap();
        let r = m.add_nodes(&nodes, &vec![0.7; nodes.len()]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        m.add_rigid_pair(rigid_pair(set, body, None)).unwrap();
        let mut c = Contact::new(&Device::cpu(), &m).unwrap();
        let mut x = m.positions().to_vec();
        let mut v = vec![[0.0; 3]; x.len()];
        let mut bodies = [BodyState::at([0.0; 3])];
        let rep = c
            .kinematic_step(&mut x, &mut v, &mut bodies, 1e-2)
            .unwrap()
            .clone();
        assert_eq!(rep.active, nodes.len(), "{surface:?}");
        assert!(
            rep.max_overclosure_after <= 1e-3 * rep.max_overclosure,
            "{surface:?}: {} left of {}",
            rep.max_overclosure_after,
            rep.max_overclosure
        );
        let mut p = momentum(&v, m.masses());
        for a in 0..3 {
            p[a] += 5.0 * bodies[0].velocity[a];
        }
        assert!(
            p.iter().all(|c| c.abs() < 1e-9),
            "{surface:?}: momentum {p:?}"
        );
        assert!(
            bodies[0].velocity.iter().any(|c| c.abs() > 0.0),
            "{surface:?}: the body takes the reaction"
        );
        if dim == 2 {
            assert!(
                x.iter().all(|p| p[2] == 0.0) && bodies[0].velocity[2] == 0.0,
                "2D stays in its plane"
            );
        }
    }
}

/// Initial overclosure: penetrating slave nodes are moved onto the master, strain-free, and
/// the report names them with the energy the first increment would otherwise have injected.
#[test]
fn initial_overclosure_is_adjusted_and_reported() {
    let mut m = Model::new_3d();
    m.add_nodes(
        &[
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ],
        &[1.0; 4],
    )
    .unwrap();
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let r = m
        .add_nodes(
            &[[0.1, 0.1, -0.02], [0.3, 0.2, 0.05], [-0.4, 0.5, -0.001]],
            &[2.0; 3],
        )
        .unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.2)
            .enforce(kinematic(None)),
    )
    .unwrap();
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        let mut x = m.positions().to_vec();
        let dt = 1e-3;
        let rep = c.adjust_initial_overclosure(&mut x, &[], dt).unwrap();
        let moved: Vec<u32> = rep.moved.iter().map(|(n, _)| *n).collect();
        assert_eq!(moved, vec![4, 6], "{d}");
        assert!((rep.max_distance - 0.02).abs() < 1e-6);
        let energy = 0.5 * 2.0 * ((0.02f64 / dt).powi(2) + (0.001f64 / dt).powi(2));
        assert!(
            (rep.energy_avoided - energy).abs() < 1e-3 * energy,
            "{d}: {}",
            rep.energy_avoided
        );
        assert!(
            x[4][2].abs() < 1e-12 && x[6][2].abs() < 1e-12 && x[5][2] == 0.05,
            "{d}: {x:?}"
        );
        assert_eq!(x[4][0], 0.1, "moved along the normal only");
    }
}

#[test]
fn bad_kinematic_input_is_an_error() {
    let mut m = Model::new_3d();
    m.add_nodes(
        &[
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [0.0, 0.0, 0.1],
        ],
        &[1.0; 5],
    )
    .unwrap();
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let set = m.add_node_set(&[4]).unwrap();
    let hard = || Pair::new(set, s).enforce(kinematic(None));
    let coulomb = || Friction::coulomb(0.2);
    assert!(m.clone().add_pair(hard().friction(coulomb())).is_ok());
    // each refused by what is wrong with it
    for (pair, says) in [
        // kinematic friction: pure finite-sliding pairs only
        (
            hard().sliding(Sliding::Small).friction(coulomb()),
            "friction",
        ),
        (hard().balanced(s, 0.5).friction(coulomb()), "friction"),
        (
            Pair::new(set, s).enforce(kinematic(Some(PressureOverclosure::Linear))),
            "softened",
        ),
        (hard().balanced(s, 1.5), "weight"),
    ] {
        let e = m.add_pair(pair).unwrap_err();
        assert!(e.to_string().contains(says), "{says}: {e}");
    }
    let e = m.add_pair(hard().balanced(SurfaceId(9), 0.5)).unwrap_err();
    assert!(
        matches!(
            e,
            Error::UnknownId {
                what: "surface",
                id: 9
            }
        ),
        "{e}"
    );
    let sphere = Analytical::Sphere {
        centre: [0.0; 3],
        radius: 1.0,
    };
    let circle = Analytical::Circle {
        centre: [0.0; 2],
        radius: 1.0,
    };
    for (rigid, says) in [
        (body(-1.0, 1.0, sphere), "mass"),
        (body(1.0, 1.0, circle), "2D"),
    ] {
        let e = m.add_rigid_body(rigid).unwrap_err();
        assert!(e.to_string().contains(says), "{says}: {e}");
    }
    let body = m.add_rigid_body(body(1.0, 1.0, sphere)).unwrap();
    m.add_rigid_pair(rigid_pair(set, body, None)).unwrap();
    let mut c = Contact::new(&Device::cpu(), &m).unwrap();
    let mut x = m.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    let e = c.kinematic_step(&mut x, &mut v, &mut [], 1e-3).unwrap_err();
    assert!(e.to_string().contains("rigid body states"), "{e}");
    let e = c
        .kinematic_step(&mut x, &mut v, &mut [BodyState::at([0.0; 3])], -1.0)
        .unwrap_err();
    assert!(e.to_string().contains("dt"), "{e}");
    let mut bad = BodyState::at([0.0; 3]);
    bad.angular_velocity[2] = f64::INFINITY;
    let e = c
        .kinematic_step(&mut x, &mut v, &mut [bad], 1e-3)
        .unwrap_err();
    assert!(
        e.to_string().contains("rigid body state") && e.to_string().contains("body 0"),
        "{e}"
    );
    x[2][1] = f64::NAN;
    let e = c
        .kinematic_step(&mut x, &mut v, &mut [BodyState::at([0.0; 3])], 1e-3)
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::NonFiniteCoordinate {
                node: 2,
                axis: 1,
                ..
            }
        ),
        "{e}"
    );
}
