//! The C ABI's model calls against the Rust API: every pair option and analytical body built
//! through C and compared with the `Pair` and `Analytical` built directly.

use super::*;

#[test]
fn every_pair_option_reaches_the_rust_pair() {
    let table = [0.0, 0.0, 0.1, 5.0, 0.3, 40.0];
    let mut o = default_options();
    assert_eq!(
        pair_from(1, 2, &o, "t").unwrap(),
        Pair::new(NodeSetId(1), SurfaceId(2))
    );
    o.stiffness = AbutStiffness::Modulus as i32;
    o.stiffness_value = 2.1e11;
    o.stiffness_scale = 0.1;
    o.law = AbutLaw {
        kind: AbutLawKind::Tabular as i32,
        table: table.as_ptr(),
        table_points: 3,
        ..o.law
    };
    o.damping = 0.2;
    o.friction = 1;
    o.mu = 0.4;
    o.mu_kinetic = 0.2;
    o.decay = 3.0;
    o.stick_stiffness = 0.5;
    o.sliding = AbutSliding::Small as i32;
    o.search_radius = 0.25;
    o.has_schedule = 1;
    o.schedule_interval = 7;
    o.schedule_budget = 0.3;
    o.schedule_wide_local = 1;
    o.balanced = 1;
    o.balanced_surface = 4;
    o.balanced_weight = 0.6;
    o.pass_weight = 0.9;
    let want = Pair {
        slave: NodeSetId(1),
        master: SurfaceId(2),
        search_radius: Some(0.25),
        enforce: Enforce::Penalty(Penalty {
            stiffness: Stiffness::Modulus {
                modulus: 2.1e11,
                scale: 0.1,
            },
            law: PressureOverclosure::Tabular(vec![(0.0, 0.0), (0.1, 5.0), (0.3, 40.0)]),
            damping: 0.2,
        }),
        friction: Friction::Coulomb {
            mu: 0.4,
            mu_kinetic: 0.2,
            decay: 3.0,
            stick_stiffness: 0.5,
        },
        balanced: Some((SurfaceId(4), 0.6)),
        sliding: Sliding::Small,
        schedule: Some(Schedule {
            interval: 7,
            budget: 0.3,
            wide_local: true,
            visit_every_slave: false,
        }),
        pass_weight: 0.9,
        slave_order: crate::model::SlaveOrder::Morton,
        search_structure: crate::model::SearchStructure::Auto,
    };
    assert_eq!(pair_from(1, 2, &o, "t").unwrap(), want);
    for (kind, value, rule) in [
        (AbutStiffness::Auto, 0.0, Stiffness::Auto { scale: 0.1 }),
        (AbutStiffness::Absolute, 5e4, Stiffness::Absolute(5e4)),
        (AbutStiffness::PerArea, 3e6, Stiffness::PerArea(3e6)),
    ] {
        o.stiffness = kind as i32;
        o.stiffness_value = value;
        let Enforce::Penalty(p) = pair_from(1, 2, &o, "t").unwrap().enforce else {
            panic!("penalty")
        };
        assert_eq!(p.stiffness, rule);
    }
    o.enforcement = AbutEnforcement::Kinematic as i32;
    o.law = AbutLaw {
        kind: AbutLawKind::Exponential as i32,
        clearance: 1e-3,
        pressure: 2e5,
        ..o.law
    };
    let k = pair_from(1, 2, &o, "t").unwrap().enforce;
    let law = PressureOverclosure::Exponential {
        clearance: 1e-3,
        pressure: 2e5,
    };
    assert_eq!(
        k,
        Enforce::Kinematic(Kinematic {
            softened: Some(law)
        })
    );
    o.law.kind = AbutLawKind::Slope as i32;
    o.law.slope = 1e7;
    let k = pair_from(1, 2, &o, "t").unwrap().enforce;
    let law = PressureOverclosure::linear(1e7);
    assert_eq!(
        k,
        Enforce::Kinematic(Kinematic {
            softened: Some(law)
        })
    );
    o.law.kind = AbutLawKind::Default as i32;
    let k = pair_from(1, 2, &o, "t").unwrap().enforce;
    assert_eq!(k, Enforce::Kinematic(Kinematic { softened: None }));
}

#[test]
fn every_analytical_surface_reaches_the_rust_one() {
    let a = |kind: AbutSurfaceKind| AbutAnalytical {
        kind: kind as i32,
        point: [1.0, 2.0, 3.0],
        direction: [0.0, 0.0, 2.0],
        radius: 0.5,
    };
    let cases = [
        (
            AbutSurfaceKind::Plane,
            Analytical::Plane {
                point: [1.0, 2.0, 3.0],
                normal: [0.0, 0.0, 2.0],
            },
        ),
        (
            AbutSurfaceKind::Sphere,
            Analytical::Sphere {
                centre: [1.0, 2.0, 3.0],
                radius: 0.5,
            },
        ),
        (
            AbutSurfaceKind::Cylinder,
            Analytical::Cylinder {
                point: [1.0, 2.0, 3.0],
                axis: [0.0, 0.0, 2.0],
                radius: 0.5,
            },
        ),
        (
            AbutSurfaceKind::Line,
            Analytical::Line {
                point: [1.0, 2.0],
                normal: [0.0, 0.0],
            },
        ),
        (
            AbutSurfaceKind::Circle,
            Analytical::Circle {
                centre: [1.0, 2.0],
                radius: 0.5,
            },
        ),
    ];
    for (kind, want) in cases {
        assert_eq!(analytical_from(&a(kind), "t").unwrap(), want);
    }
    let mut bad = a(AbutSurfaceKind::Plane);
    bad.kind = 9;
    assert!(analytical_from(&bad, "t")
        .unwrap_err()
        .message
        .contains("AbutSurfaceKind"));
}
