//! Kinematic contact between two free bodies: the softened law and the Coulomb limit must not
//! depend on how the slave's mass compares with the master's. The correction adds the slave's
//! mass to the master nodes and moves both, so the force the contact transmits is the two-body
//! one, `m*·(h − h')/Δt²` with `1/m* = 1/m_s + 1/m_master`, not the slave's `m_s·(h − h')/Δt²`;
//! a balance or a friction limit written with the slave's mass alone is off by `1 + m_s/m_master`
//! (a softened deck between meshes of equal node masses settled 2× deeper than its law says).
//!
//! Scenes: four slave nodes pressed onto a free quad master (or a free rigid body's analytical
//! plane) held to the ground by damped springs, at master/slave node mass ratios from 0.1 to 10.
//! At rest the law must hold at every slave, `p(h)·A = F` (1 %), and a slave pulled along the
//! surface past the Coulomb limit must feel `μ·F` of friction (2 %).

use abut::*;

const DT: f64 = 1e-3;
/// Push on each slave node (force).
const F: f64 = 3.0;
/// Tributary area of each slave node.
const AREA: f64 = 0.5;
/// Mass of each slave node.
const M_SLAVE: f64 = 0.02;
/// Master node / slave node mass ratios covered.
const RATIOS: [f64; 4] = [0.1, 0.5, 1.0, 10.0];
/// Slave positions in the quad [−1, 1]² (at its plane, z = 0).
const SLAVES: [[f64; 2]; 4] = [[-0.4, -0.3], [0.35, -0.4], [0.4, 0.3], [-0.3, 0.4]];

/// The laws covered: linear, Abaqus' exponential, a table with a clearance.
fn laws() -> Vec<PressureOverclosure> {
    vec![
        PressureOverclosure::linear(600.0),
        PressureOverclosure::Exponential {
            clearance: 0.01,
            pressure: 4.0,
        },
        PressureOverclosure::Tabular(vec![(-0.005, 0.0), (0.005, 2.0), (0.02, 10.0)]),
    ]
}

/// A damped spring to the ground at each listed node: stiffness for angular frequency `omega`
/// on the node's mass, damping ratio 0.3 — forces added to `a` (accelerations).
fn ground(x: &[[f64; 3]], v: &[[f64; 3]], x0: &[[f64; 3]], nodes: &[usize], a: &mut [[f64; 3]]) {
    let omega = 100.0;
    for &n in nodes {
        for c in 0..3 {
            a[n][c] += -omega * omega * (x[n][c] - x0[n][c]) - 0.6 * omega * v[n][c];
        }
    }
}

/// Four slaves over a free quad of four nodes of mass `ratio`·m_s each, `enforce` and
/// `friction` on the pair. Returns the model (masters first, then slaves).
fn quad_scene(ratio: f64, enforce: Enforce, friction: Option<Friction>) -> Model {
    let mut m = Model::new_3d();
    let quad = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    m.add_nodes(&quad, &[ratio * M_SLAVE; 4]).unwrap();
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let pos: Vec<[f64; 3]> = SLAVES.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let r = m.add_nodes(&pos, &[M_SLAVE; 4]).unwrap();
    let set = m.add_node_set_with_areas(&r.to_vec(), &[AREA; 4]).unwrap();
    let mut pair = Pair::new(set, s).search_radius(0.5).enforce(enforce);
    if let Some(f) = friction {
        pair = pair.friction(f);
    }
    m.add_pair(pair).unwrap();
    m
}

/// Runs `steps` increments of the quad scene: slaves pushed down by F (and along x by `pull`
/// after `pull_from` increments), damped while only pushed, masters on their ground springs.
/// Returns the positions and velocities and the contact.
fn run_quad(
    m: &Model,
    steps: usize,
    pull: f64,
    pull_from: usize,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Contact) {
    let mut c = Contact::new(&Device::cpu(), m).unwrap();
    let x0 = m.positions().to_vec();
    let masses = m.masses().to_vec();
    let mut x = x0.clone();
    let mut v = vec![[0.0; 3]; x.len()];
    for step in 0..steps {
        let mut a = vec![[0.0; 3]; x.len()];
        ground(&x, &v, &x0, &[0, 1, 2, 3], &mut a);
        for s in 4..8 {
            a[s][2] -= F / masses[s];
            if step >= pull_from {
                a[s][0] += pull / masses[s];
            } else {
                // the slaves' own damping, so that the normal contact settles
                for c in 0..3 {
                    a[s][c] -= 30.0 * v[s][c];
                }
            }
        }
        for n in 0..x.len() {
            for c in 0..3 {
                v[n][c] += DT * a[n][c];
                x[n][c] += DT * v[n][c];
            }
        }
        c.kinematic_step(&mut x, &mut v, &mut [], DT).unwrap();
    }
    (x, v, c)
}

/// Overclosure of each slave against the (moved) quad's plane, which stays flat by symmetry
/// only approximately: measured against the bilinear interpolation of its nodes' heights.
fn overclosures(x: &[[f64; 3]]) -> Vec<f64> {
    (4..8)
        .map(|s| {
            let (u, w) = ((x[s][0] + 1.0) / 2.0, (x[s][1] + 1.0) / 2.0);
            let z = (1.0 - u) * (1.0 - w) * x[0][2]
                + u * (1.0 - w) * x[1][2]
                + u * w * x[2][2]
                + (1.0 - u) * w * x[3][2];
            z - x[s][2]
        })
        .collect()
}

#[test]
fn softened_law_holds_between_free_meshed_bodies_of_any_mass_ratio() {
    for law in laws() {
        for ratio in RATIOS {
            let m = quad_scene(
                ratio,
                Enforce::Kinematic(Kinematic {
                    softened: Some(law.clone()),
                }),
                None,
            );
            let (x, v, c) = run_quad(&m, 4000, 0.0, usize::MAX);
            let out = &c.outputs()[0].1;
            for (k, h) in overclosures(&x).into_iter().enumerate() {
                let p = law.pressure(h).0;
                assert!(
                    (p * AREA - F).abs() <= 0.01 * F,
                    "{law:?}, master/slave mass {ratio}: slave {k} at h = {h:e} has p(h)·A = {} \
                     for a push of {F}",
                    p * AREA
                );
                assert!(v[4 + k][2].abs() < 1e-3, "settled: {:?}", v[4 + k]);
                assert!(
                    (out.cpress[k] * AREA - F).abs() <= 0.01 * F,
                    "{law:?}, ratio {ratio}: CPRESS·A = {} for {F}",
                    out.cpress[k] * AREA
                );
                assert!((out.copen[k] + h).abs() <= 1e-3 * h.abs().max(1e-3));
            }
        }
    }
}

#[test]
fn coulomb_limit_holds_between_free_meshed_bodies_of_any_mass_ratio() {
    let mu = 0.3;
    for law in [None, Some(PressureOverclosure::linear(600.0))] {
        for ratio in RATIOS {
            let m = quad_scene(
                ratio,
                Enforce::Kinematic(Kinematic {
                    softened: law.clone(),
                }),
                Some(Friction::coulomb(mu)),
            );
            // settle pressed, then pull at 1.5× the limit for 0.1 s
            let (x, v, c) = run_quad(&m, 2100, 1.5 * mu * F, 2000);
            let out = &c.outputs()[0].1;
            let friction = out.cfs[0];
            assert!(
                (friction + 4.0 * mu * F).abs() <= 0.02 * 4.0 * mu * F,
                "{law:?}, master/slave mass {ratio}: friction {friction} for a limit of {}",
                4.0 * mu * F
            );
            for s in 4..8 {
                assert!(
                    v[s][0] > 0.0 && x[s][0] > SLAVES[s - 4][0],
                    "slave {s} slides"
                );
            }
        }
    }
}

#[test]
fn softened_law_holds_on_a_free_rigid_body_of_any_mass() {
    for law in laws() {
        for ratio in RATIOS {
            let mut m = Model::new_3d();
            let mass = 4.0 * ratio * M_SLAVE;
            let body = m
                .add_rigid_body(RigidBody {
                    mass,
                    inertia: [[mass, 0.0, 0.0], [0.0, mass, 0.0], [0.0, 0.0, mass]],
                    surface: Analytical::Plane {
                        point: [0.0; 3],
                        normal: [0.0, 0.0, 1.0],
                    },
                })
                .unwrap();
            // placed symmetrically, so that the pushes turn the body by round-off only
            let pos = [
                [-0.4, -0.4, 0.0],
                [0.4, -0.4, 0.0],
                [0.4, 0.4, 0.0],
                [-0.4, 0.4, 0.0],
            ];
            let r = m.add_nodes(&pos, &[M_SLAVE; 4]).unwrap();
            let set = m.add_node_set_with_areas(&r.to_vec(), &[AREA; 4]).unwrap();
            m.add_rigid_pair(RigidPair {
                slave: set,
                body,
                softened: Some(law.clone()),
            })
            .unwrap();
            let mut c = Contact::new(&Device::cpu(), &m).unwrap();
            let mut x = m.positions().to_vec();
            let mut v = vec![[0.0; 3]; x.len()];
            let mut bodies = vec![BodyState::at([0.0; 3])];
            let omega = 100.0;
            for _ in 0..4000 {
                let b = &mut bodies[0];
                // the body on a damped ground spring along z, held in x, y and rotation
                let az = -omega * omega * b.position[2] - 0.6 * omega * b.velocity[2];
                b.velocity = [0.0, 0.0, b.velocity[2] + DT * az];
                b.angular_velocity = [0.0; 3];
                b.rotation = BodyState::at([0.0; 3]).rotation;
                b.position[2] += DT * b.velocity[2];
                for s in 0..4 {
                    v[s][2] += DT * (-F / M_SLAVE - 30.0 * v[s][2]);
                    x[s][2] += DT * v[s][2];
                }
                c.kinematic_step(&mut x, &mut v, &mut bodies, DT).unwrap();
            }
            for s in 0..4 {
                let h = bodies[0].position[2] - x[s][2];
                let p = law.pressure(h).0;
                assert!(
                    (p * AREA - F).abs() <= 0.01 * F,
                    "{law:?}, body/slave mass {}: slave {s} at h = {h:e} has p(h)·A = {} for {F}",
                    4.0 * ratio,
                    p * AREA
                );
            }
        }
    }
}
