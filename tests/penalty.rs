//! Penalty contact: GPU against CPU parity of forces and outputs, determinism, momentum, the
//! stable increment under central differences (VERIFICATION §5), friction on an incline (§4),
//! laws and stiffness rules, and the hard cases of §6.

mod common;

use abut::mesh::{plate_quads, point_cloud, SplitMix64};
use abut::*;
use common::gpus;

fn devices() -> Vec<Device> {
    let mut d = vec![Device::cpu()];
    d.extend(gpus().iter().cloned());
    d
}

fn penalty(k: f64) -> Enforce {
    Enforce::Penalty(Penalty {
        stiffness: Stiffness::Absolute(k),
        ..Default::default()
    })
}

/// Sum of the forces over all nodes, and the sum of their magnitudes.
fn momentum(forces: &[[f64; 3]]) -> ([f64; 3], f64) {
    let mut s = [0.0; 3];
    let mut m = 0.0;
    for f in forces {
        for a in 0..3 {
            s[a] += f[a];
        }
        m += (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    }
    (s, m)
}

/// A wavy quad plate (master, nodes of mass 2) and a cloud of slave nodes around it (mass 1),
/// random velocities; pair with `friction`.
fn cloud_scene(friction: Friction, law: PressureOverclosure) -> (Model, Vec<[f64; 3]>) {
    let plate = plate_quads(30, 30, 1.0, 1.0, 0.2, 3, &|x, y| {
        0.05 * (4.0 * x).sin() * (3.0 * y).cos()
    });
    let slaves = point_cloud(4000, [0.0, 0.0, -0.08], [1.0, 1.0, 0.08], 5);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![2.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let r = m.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Auto { scale: 1.0 },
        law,
        damping: 0.1,
    };
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.05)
            .enforce(Enforce::Penalty(pen))
            .friction(friction),
    )
    .unwrap();
    let mut rng = SplitMix64::new(9);
    let vel = (0..m.positions().len())
        .map(|_| {
            [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ]
        })
        .collect();
    (m, vel)
}

/// Runs `steps` increments, moving nodes by v·dt, and returns every report and output.
fn run_steps(
    d: &Device,
    m: &Model,
    vel: &[[f64; 3]],
    steps: usize,
) -> Vec<(StepReport, PairOutput)> {
    let mut c = Contact::new(d, m).unwrap();
    c.request_outputs(true);
    let dt = 1e-3;
    let mut x = m.positions().to_vec();
    let mut out = Vec::new();
    for _ in 0..steps {
        let r = c.penalty_step(&x, vel, dt).unwrap().clone();
        out.push((r, c.outputs()[0].1.clone()));
        for (xi, v) in x.iter_mut().zip(vel) {
            for a in 0..3 {
                xi[a] += v[a] * dt;
            }
        }
    }
    out
}

#[test]
fn gpu_matches_cpu_forces_and_outputs_and_conserves_momentum() {
    for (friction, law) in [
        (Friction::Frictionless, PressureOverclosure::Linear),
        (Friction::coulomb(0.3), PressureOverclosure::Linear),
        (
            Friction::Coulomb {
                mu: 0.4,
                mu_kinetic: 0.2,
                decay: 2.0,
                stick_stiffness: 0.5,
            },
            PressureOverclosure::Exponential {
                clearance: 0.01,
                pressure: 50.0,
            },
        ),
        (
            Friction::coulomb(0.2),
            PressureOverclosure::Tabular(vec![
                (-0.005, 0.0),
                (0.0, 20.0),
                (0.02, 400.0),
                (0.05, 2000.0),
            ]),
        ),
    ] {
        let what = format!("{friction:?} {law:?}");
        let (m, vel) = cloud_scene(friction, law);
        let cpu = run_steps(&Device::cpu(), &m, &vel, 4);
        for (r, o) in &cpu {
            assert!(r.active > 100, "{what}: only {} active", r.active);
            let (s, mag) = momentum(&r.forces);
            for a in 0..3 {
                assert!(s[a].abs() <= 1e-5 * mag, "{what}: momentum {s:?} of {mag}");
            }
            assert!(r.stable_dt.is_finite() && r.stable_dt > 0.0);
            assert!(o.contact_energy > 0.0);
        }
        for g in gpus() {
            let gpu = run_steps(g, &m, &vel, 4);
            for (step, ((rc, oc), (rg, og))) in cpu.iter().zip(&gpu).enumerate() {
                let scale = rc
                    .forces
                    .iter()
                    .flatten()
                    .fold(0.0f64, |a, f| a.max(f.abs()));
                let mut status_diff = 0;
                for (i, (a, b)) in rc.forces.iter().zip(&rg.forces).enumerate() {
                    for k in 0..3 {
                        assert!(
                            (a[k] - b[k]).abs() <= 2e-3 * scale,
                            "{what} {g} step {step}: node {i} force {a:?} vs {b:?}"
                        );
                    }
                }
                for i in 0..oc.copen.len() {
                    if oc.cstatus[i] != og.cstatus[i] {
                        status_diff += 1;
                        continue;
                    }
                    assert!((oc.copen[i] - og.copen[i]).abs() < 1e-5, "{what}: copen");
                    assert!(
                        (oc.cpress[i] - og.cpress[i]).abs() <= 2e-3 * (1.0 + oc.cpress[i].abs()),
                        "{what}: cpress {} vs {}",
                        oc.cpress[i],
                        og.cpress[i]
                    );
                    assert!(
                        (oc.cshear1[i] - og.cshear1[i]).abs() <= 2e-3 * (1.0 + oc.cpress[i].abs()),
                        "{what}: cshear1"
                    );
                    assert!(
                        (oc.cshear2[i] - og.cshear2[i]).abs() <= 2e-3 * (1.0 + oc.cpress[i].abs()),
                        "{what}: cshear2"
                    );
                }
                assert!(
                    status_diff <= oc.copen.len() / 500,
                    "{what}: {status_diff} statuses differ"
                );
                assert!((rc.stable_dt - rg.stable_dt).abs() <= 1e-5 * rc.stable_dt);
                assert_eq!(rc.active, rg.active, "{what}: active");
                assert!((oc.contact_energy - og.contact_energy).abs() <= 1e-3 * oc.contact_energy);
                assert!(
                    (oc.frictional_dissipation - og.frictional_dissipation).abs()
                        <= 1e-3 * (1e-9 + oc.frictional_dissipation)
                );
                for a in 0..3 {
                    assert!((oc.cfn[a] - og.cfn[a]).abs() <= 1e-4 * (1.0 + oc.cfn[2].abs()));
                    assert!((oc.cfs[a] - og.cfs[a]).abs() <= 1e-3 * (1.0 + oc.cfn[2].abs()));
                }
            }
            // determinism: a second run gives the same bits
            let again = run_steps(g, &m, &vel, 4);
            for ((a, _), (b, _)) in gpu.iter().zip(&again) {
                assert!(
                    a.forces == b.forces,
                    "{what} {g}: forces differ between runs"
                );
            }
        }
    }
}

/// Integrates with central differences: returns the slave's gap history.
/// `masters` are the master node ids (given the masses of the model), `ext` an external force
/// per node (constant).
fn integrate(
    d: &Device,
    m: &Model,
    ext: &[[f64; 3]],
    dt: f64,
    steps: usize,
) -> (Vec<Vec<[f64; 3]>>, Vec<f64>) {
    let mut c = Contact::new(d, m).unwrap();
    let mass = m.masses().to_vec();
    let mut x = m.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    let mut hist = Vec::new();
    let mut dts = Vec::new();
    for _ in 0..steps {
        let r = c.penalty_step(&x, &v, dt).unwrap();
        dts.push(r.stable_dt);
        for i in 0..x.len() {
            for a in 0..3 {
                v[i][a] += dt * (ext[i][a] + r.forces[i][a]) / mass[i];
                x[i][a] += dt * v[i][a];
            }
        }
        hist.push(x.clone());
    }
    (hist, dts)
}

fn amplitude(hist: &[Vec<[f64; 3]>], node: usize, from: usize, to: usize, eq: f64) -> f64 {
    hist[from..to]
        .iter()
        .map(|x| (x[node][2] - eq).abs())
        .fold(0.0, f64::max)
}

/// VERIFICATION §5: a node on a rigid facet (master masses 1e12) pushed by a constant force;
/// k ≤ 4·m_s/dt². Bounded at 0.99× the reported increment, growing at 1.01×.
#[test]
fn stable_increment_node_on_rigid_facet() {
    let (k, ms, f) = (400.0, 0.5, 2.0);
    let mut m = Model::new_3d();
    m.add_nodes(
        &[
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ],
        &[1e12; 4],
    )
    .unwrap();
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let h_eq = f / k;
    // start 10 % off equilibrium: at ω·dt near 2 central differences amplifies the offset
    // about sevenfold, which must not open the contact
    let r = m.add_nodes(&[[0.1, 0.2, -1.1 * h_eq]], &[ms]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    m.add_pair(Pair::new(set, s).search_radius(0.5).enforce(penalty(k)))
        .unwrap();
    let ext = [[0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3], [0.0, 0.0, -f]];
    let exact = 2.0 / (k * (1.0 / ms + 4.0 * 0.0)).sqrt(); // masters: weight² / 1e12 ≈ 0
    for d in devices() {
        let (_, dts) = integrate(&d, &m, &ext, 1e-3, 1);
        assert!(
            (dts[0] - exact).abs() <= 1e-5 * exact,
            "{d}: reported {} vs 2/√(k/m) = {exact}",
            dts[0]
        );
        let a0 = 0.1 * h_eq;
        let (hist, _) = integrate(&d, &m, &ext, 0.99 * dts[0], 1500);
        let early = amplitude(&hist, 4, 0, 500, -h_eq);
        let late = amplitude(&hist, 4, 1000, 1500, -h_eq);
        assert!(
            late <= 1.01 * early && late < 20.0 * a0,
            "{d}: 0.99×: amplitude {early} then {late}"
        );
        let (hist, _) = integrate(&d, &m, &ext, 1.01 * dts[0], 200);
        assert!(
            amplitude(&hist, 4, 100, 200, -h_eq) > 100.0 * a0,
            "{d}: 1.01×: no growth"
        );
    }
}

/// VERIFICATION §5, two bodies: a 2D slave node against a free segment (two nodes of mass m_m,
/// slave at its midpoint, weights ½): dt ≤ 2/√(k(1/m_s + Σ w²/m_i)). Mass ratios 1e±6 too,
/// with momentum conserved.
#[test]
fn stable_increment_two_bodies_and_mass_ratios() {
    for (ms, mm) in [(1.0f64, 0.5f64), (1e-6, 1.0), (1.0, 1e-6)] {
        let k = 100.0;
        let mut m = Model::new_2d();
        m.add_nodes_2d(&[[1.0, 0.0], [-1.0, 0.0]], &[mm, mm])
            .unwrap();
        let s = m.add_surface(Surface::segments(&[[0, 1]])).unwrap(); // normal +y
        let f = 1e-3 * k; // h_eq = 1e-3, well above f32 round-off of the unit-size frame
        let h_eq = f / k;
        let r = m.add_nodes_2d(&[[0.0, -1.1 * h_eq]], &[ms]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        m.add_pair(Pair::new(set, s).search_radius(0.5).enforce(penalty(k)))
            .unwrap();
        // equal and opposite pushes: the slave (below) up into the segment, its nodes down
        let ext = [[0.0, f / 2.0, 0.0], [0.0, f / 2.0, 0.0], [0.0, -f, 0.0]];
        let exact = 2.0 / (k * (1.0 / ms + 2.0 * 0.25 / mm)).sqrt();
        for d in devices() {
            let (_, dts) = integrate(&d, &m, &ext, 1e-4 * exact, 1);
            assert!(
                (dts[0] - exact).abs() <= 1e-4 * exact,
                "{d} ms={ms} mm={mm}: reported {} vs {exact}",
                dts[0]
            );
            let (hist, _) = integrate(&d, &m, &ext, 0.99 * dts[0], 1500);
            let gap = |x: &Vec<[f64; 3]>| x[2][1] - 0.5 * (x[0][1] + x[1][1]);
            let dev = |a: usize, b: usize| {
                hist[a..b]
                    .iter()
                    .map(|x| (gap(x) + h_eq).abs())
                    .fold(0.0, f64::max)
            };
            assert!(
                dev(1000, 1500) <= 1.01 * dev(0, 500),
                "{d} ms={ms}: 0.99× not bounded: {} then {}",
                dev(0, 500),
                dev(1000, 1500)
            );
            // momentum: external forces sum to zero, so Σ m v stays 0
            let last = &hist[hist.len() - 1];
            let prev = &hist[hist.len() - 2];
            let p: f64 = (0..3)
                .map(|i| [mm, mm, ms][i] * (last[i][1] - prev[i][1]))
                .sum();
            let scale = ms * (last[2][1] - prev[2][1]).abs() + 1e-30;
            assert!(
                p.abs() <= 1e-4 * scale.max(1e-12),
                "{d} ms={ms}: momentum {p}"
            );
            let (hist, _) = integrate(&d, &m, &ext, 1.01 * dts[0], 200);
            let grown = hist[100..]
                .iter()
                .map(|x| (gap(x) + h_eq).abs())
                .fold(0.0, f64::max);
            assert!(
                grown > 100.0 * 0.1 * h_eq,
                "{d} ms={ms}: 1.01× did not grow ({grown})"
            );
        }
    }
}
