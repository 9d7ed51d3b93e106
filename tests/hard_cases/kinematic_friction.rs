//! Issue 16, item 3 (what is done of it): Coulomb friction under kinematic enforcement, which has
//! no penalty spring for friction to feed. Point masses slide over a fixed rigid plate of quads
//! (across facet edges and nodes) under gravity turned by θ, from v0 down the slope, with μ above
//! tan θ: each stops at v0²/(2·g·(μ·cos θ − sin θ)) within v0·Δt (kinematic stick has no elastic
//! pre-slip), on the flat and on three inclines; with μ below tan θ they accelerate at
//! g·(sin θ − μ·cos θ); at rest with μ above tan θ they do not creep (1e-9 m in 500 increments,
//! what the plate's 1e9 nodal masses take of the stick).

use abut::explicit::Solver;
use abut::mesh::plate_quads;
use abut::*;

/// Slides four point masses with speed `v0` along x under gravity turned by θ on a fixed
/// plate with friction `mu`: their x and x-velocities after `steps` increments of `dt`, and
/// their starting x.
fn slide(
    theta_deg: f64,
    mu: f64,
    v0: f64,
    dt: f64,
    steps: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let plate = plate_quads(10, 4, 10.0, 4.0, 0.0, 0, &|_, _| 0.0);
    let np = plate.positions.len();
    // across a facet's middle, along an edge (y = 1) and through nodes (y = 2, x = 0.5..)
    let starts = [[0.3, 0.5], [0.7, 1.0], [0.5, 2.0], [0.25, 3.3]];
    let mut x = plate.positions.clone();
    for p in &starts {
        x.push([p[0], p[1], 0.0]);
    }
    let mut model = Model::new_3d();
    let mut masses = vec![1e9; np];
    masses.extend([1.0, 2.0, 0.5, 1.0]);
    model.add_nodes(&x, &masses).unwrap();
    let surf = model.add_surface(Surface::quads(&plate.facets)).unwrap();
    let slaves: Vec<u32> = (np as u32..np as u32 + 4).collect();
    let set = model.add_node_set(&slaves).unwrap();
    model
        .add_pair(
            Pair::new(set, surf)
                .search_radius(0.5)
                .enforce(Enforce::Kinematic(Kinematic::default()))
                .friction(Friction::coulomb(mu)),
        )
        .unwrap();
    let mut solver = Solver::new(x.clone(), Vec::new(), &masses).unwrap();
    let t = theta_deg.to_radians();
    solver.gravity = [9.81 * t.sin(), 0.0, -9.81 * t.cos()];
    for n in 0..np {
        solver.fixed[n] = [true; 3];
    }
    for &s in &slaves {
        solver.v[s as usize] = [v0, 0.0, 0.0];
    }
    let mut c = Contact::new(&Device::cpu(), &model).unwrap();
    for _ in 0..steps {
        solver.step(dt, Some(&mut c)).unwrap();
    }
    let pos = slaves.iter().map(|&s| solver.x[s as usize][0]).collect();
    let vel = slaves.iter().map(|&s| solver.v[s as usize][0]).collect();
    (pos, vel, starts.iter().map(|p| p[0]).collect())
}

#[test]
fn kinematic_friction_slides_to_a_stop_and_sticks() {
    let dt = 1e-3;
    let g = 9.81;
    for (theta, mu, v0) in [
        (0.0, 0.5, 2.0),
        (10.0, 0.5, 1.5),
        (20.0, 0.5, 1.0),
        (25.0, 0.6, 1.0),
    ] {
        let t: f64 = f64::to_radians(theta);
        let a = g * (mu * t.cos() - t.sin());
        let stop = v0 * v0 / (2.0 * a);
        let steps = (1.5 * v0 / a / dt) as usize;
        let (x, v, x0) = slide(theta, mu, v0, dt, steps);
        for k in 0..x.len() {
            let travel = x[k] - x0[k];
            assert!(
                (travel - stop).abs() <= v0 * dt,
                "θ = {theta}°, μ = {mu}, slave {k}: stopped after {travel}, exact {stop}"
            );
            assert!(v[k].abs() < 1e-9, "slave {k} still moves: {}", v[k]);
        }
    }
    // sliding on: μ < tan θ accelerates at g(sin θ − μ cos θ)
    let (theta, mu, v0): (f64, f64, f64) = (30.0, 0.2, 0.5);
    let t = theta.to_radians();
    let a = g * (t.sin() - mu * t.cos());
    let steps = 500;
    let (_, v, _) = slide(theta, mu, v0, dt, steps);
    for (k, vk) in v.iter().enumerate() {
        let exact = v0 + a * (steps as f64 - 0.5) * dt;
        assert!(
            (vk - exact).abs() < 1e-6 * exact,
            "slave {k}: {vk} against {exact}"
        );
    }
    // at rest, μ > tan θ: it stays exactly where it is
    let (x, v, x0) = slide(20.0, 0.5, 0.0, dt, 500);
    for k in 0..x.len() {
        assert!(
            // the plate's nodes weigh 1e9: they take 1e-9 of the stick (round-off aside)
            (x[k] - x0[k]).abs() < 1e-9 && v[k].abs() < 1e-9,
            "slave {k} crept: {} at {}",
            x[k] - x0[k],
            v[k]
        );
    }
}
