//! Issue 30, items 5 and 6: the automatic penalty stiffness gives a rigid part on n slave nodes
//! the frequency one slave of a meshed body has (not √n more), and kinematic friction is booked
//! like penalty friction — its force in CSHEAR1/2, CFS and each slave's force, its state in
//! CSTATUS, and the energy it removes as the pair's frictional dissipation, which closes the
//! energy balance of a block sliding to a stop.

mod common;

use abut::mesh::plate_quads;
use abut::*;
use common::devices;

/// A fixed master plate (4 × 4 quads on [0, 4]², nodes of mass 10¹²) and `k × k` slave nodes in
/// a square at the plate's middle, overclosed by 10⁻⁴: as one free rigid part of mass `mass`
/// (`rigid`), or as point masses of `mass / k²` each. The automatic stiffness, default
/// damping. Returns the stable increment the first increment (Δt = 10⁻⁴) reports.
fn reported_increment(d: &Device, k: usize, mass: f64, rigid: bool) -> f64 {
    let plate = plate_quads(4, 4, 4.0, 4.0, 0.0, 0, &|_, _| 0.0);
    let np = plate.positions.len();
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1e12; np]).unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let n = k * k;
    let step = 1.0 / k as f64;
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let (a, b) = ((i % k) as f64, (i / k) as f64);
            [1.55 + step * a, 1.45 + step * b, -1e-4]
        })
        .collect();
    let node_mass = if rigid { mass } else { mass / n as f64 };
    let ids = m.add_nodes(&pts, &vec![node_mass; n]).unwrap();
    let slaves: Vec<u32> = ids.to_vec();
    if rigid {
        // a thin square plate's inertia about its centroid
        let side = step * k as f64;
        let i_xy = mass * side * side / 12.0;
        m.add_rigid_part(
            &slaves,
            mass,
            [[i_xy, 0.0, 0.0], [0.0, i_xy, 0.0], [0.0, 0.0, 2.0 * i_xy]],
        )
        .unwrap();
    }
    let set = m.add_node_set(&slaves).unwrap();
    m.add_pair(Pair::new(set, s).search_radius(0.3)).unwrap();
    let mut c = Contact::new(d, &m).unwrap();
    let x = m.positions().to_vec();
    let r = c.penalty_step(&x, &vec![[0.0; 3]; x.len()], 1e-4).unwrap();
    assert_eq!(r.active, n, "{d}: every slave in contact");
    r.stable_dt
}

/// n slaves of one rigid part give the body the stable increment one slave of the same body
/// with a 1/n share has (n point masses of M/n), for n = 4, 9, 25, on every device: the
/// automatic rule's ω·Δt_ref = 1 holds for the body as it does for a meshed slave, instead of
/// √n.
#[test]
fn slaves_of_a_rigid_part_share_its_mass_in_the_automatic_stiffness() {
    let z = DEFAULT_CONTACT_DAMPING;
    // ω·Δt_ref = 1: 2·Δt_ref·(√(1 + ξ²) − ξ)
    let one_slave = 2.0 * 1e-4 * ((1.0 + z * z).sqrt() - z);
    for d in devices() {
        for k in [2, 3, 5] {
            let rigid = reported_increment(&d, k, 2.0, true);
            let meshed = reported_increment(&d, k, 2.0, false);
            let what = format!("{d}, {} slaves", k * k);
            assert!(
                (rigid / meshed - 1.0).abs() < 2e-3,
                "{what}: rigid part {rigid:e}, point masses of M/n {meshed:e}"
            );
            assert!(
                (rigid / one_slave - 1.0).abs() < 2e-3,
                "{what}: rigid part {rigid:e}, one slave {one_slave:e}"
            );
        }
    }
}

#[cfg(feature = "solver")]
mod kinematic_friction {
    use crate::common::scene_toml::{contact, part, SceneToml};
    use abut::scene::{run, Scene};
    use abut::*;

    /// §4's elastic block (0.1 m, E = 10⁷ Pa, ρ = 1000) launched at `v0` along +x on a fixed
    /// rigid plate under gravity, kinematic contact with Coulomb μ, no bulk viscosity (so that
    /// friction is the only thing that takes its energy).
    fn sliding_block(v0: f64, mu: f64, end: f64) -> Scene {
        SceneToml::new("a block sliding to a stop under kinematic friction", end)
            .run("gravity", [0.0, 0.0, -9.81])
            .run("output_every", 20)
            .run("bulk_viscosity", 0.0)
            .run("bulk_viscosity_quadratic", 0.0)
            .material("block", 1.0e7, 0.3, 1000.0)
            .part(
                part("block", "block", [0.0; 3], [0.1, 0.1, 0.1], [2, 2, 2])
                    .with("material", "block")
                    .with("velocity", [v0, 0.0, 0.0]),
            )
            .part(part(
                "floor",
                "plate",
                [-0.2, -0.2, 0.0],
                [1.0, 0.5, 0.0],
                [20, 10, 0],
            ))
            .contact(
                contact("block", "z-", "floor", "z+")
                    .with("enforce", "kinematic")
                    .with("friction", mu),
            )
            .scene()
    }

    /// The block slides to a stop: the frictional dissipation the summary books equals the
    /// kinetic energy it lost (to 2 % — what else there is: the elastic energy of the block's
    /// own vibration), where it booked 0 before; the friction force appears in CFS and
    /// CSHEAR1 while it slides (opposing the motion), on every device.
    #[test]
    fn kinematic_friction_is_booked_in_the_outputs_and_the_dissipation() {
        let (v0, mu) = (0.5, 0.4);
        let mass = 1000.0 * 0.1f64.powi(3);
        let ke0 = 0.5 * mass * v0 * v0;
        // stops after v0/(μ g) = 0.127 s
        let scene = sliding_block(v0, mu, 0.25);
        for d in super::devices() {
            let s = run(&scene, &d, None).unwrap();
            let dissipated = s.frictional_dissipation;
            assert!(
                (dissipated / ke0 - 1.0).abs() < 0.02,
                "{d}: dissipation {dissipated} against the kinetic energy {ke0}"
            );
            // while sliding: one increment's outputs
            let mut built = scene.build().unwrap();
            let mut contact = Contact::new(&d, &built.model).unwrap();
            contact.request_outputs(true);
            let dt = built.solver.stable_increment();
            for _ in 0..40 {
                built.solver.step(dt, Some(&mut contact)).unwrap();
            }
            let out = contact.outputs();
            let o = out[0].1;
            assert!(o.cfs[0] < 0.0, "{d}: CFS {:?} opposes the slide", o.cfs);
            let weight = mass * 9.81;
            assert!(
                (-o.cfs[0] / (mu * weight) - 1.0).abs() < 0.2,
                "{d}: CFS {} against μ·m·g {}",
                o.cfs[0],
                mu * weight
            );
            assert!(
                o.cshear1.iter().any(|&t| t.abs() > 0.0),
                "{d}: CSHEAR1 {:?}",
                o.cshear1
            );
            assert!(o.cstatus.contains(&Some(ContactStatus::Slip)));
        }
    }
}
