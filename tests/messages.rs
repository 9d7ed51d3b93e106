//! Issue 38, item 2: a run that fails names what was in force and what changed, not what it
//! blew up. A point mass bouncing on a penalty spring with a fixed `run.dt` over the spring's
//! stable increment is told about that increment first (the warning a finished run prints),
//! over the range of increments where it gains energy until it fails; a NaN or infinite input
//! set through the library mid-run is named in the increment it would have entered, by what it
//! is (gravity, damping, bulk viscosity, a node's load, a body's load).

mod common;

use abut::explicit::Solver;
use abut::scene::run;
use abut::{Device, Error};
use common::scene_toml::{deck, mass_on_spring, part, SceneToml};

/// A unit mass resting on a rigid plate with a penalty spring of stiffness `k` (undamped),
/// pressed by a gravity of 1000 m/s², at a fixed `dt`, for `end` seconds.
fn bouncing(k: f64, dt: f64, end: f64) -> SceneToml {
    mass_on_spring("a point mass on a stiff spring", k, 0.0, dt, end)
}

#[test]
fn a_fixed_increment_over_the_contact_limit_is_named_first_when_the_run_fails() {
    // ω = 1000 rad/s: the undamped spring's limit is Δt = 2/ω = 2e-3. Over it the mass gains
    // energy at every bounce: it fails (tunnelling, divergence, energy) or, thrown high
    // enough, runs to the end; either way it is told why, first
    let mut failed = 0;
    for ratio in [1.02, 1.05, 1.1, 1.2, 1.5, 2.5] {
        let dt = ratio * 2e-3;
        let text = match run(&bouncing(1e6, dt, 20.0).scene(), &Device::cpu(), None) {
            Err(e) => {
                failed += 1;
                e.to_string()
            }
            Ok(s) => s.warnings.join("\n"),
        };
        let at = text.find("exceeds the penalty contact's stable increment");
        assert!(at.is_some(), "ω·Δt = {}: {text}", 2.0 * ratio);
        // before any hint about overclosures or elements
        for later in ["overclosure", "elements"] {
            if let Some(k) = text.find(later) {
                assert!(at.unwrap() < k, "ω·Δt = {}: {text}", 2.0 * ratio);
            }
        }
    }
    assert!(
        failed >= 2,
        "the mass pressed on an unstable spring fails the run"
    );
    // under the limit the same scene runs, and warns of nothing
    let s = run(&bouncing(1e6, 1.8e-3, 0.5).scene(), &Device::cpu(), None).unwrap();
    assert!(s.impulse > 0.0 && s.warnings.iter().all(|w| !w.contains("exceeds")));
}

/// Two point masses under gravity, one of them loaded, stepped a few increments.
fn solver() -> Solver {
    let mut s = Solver::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], Vec::new(), &[1.0, 2.0]).unwrap();
    s.gravity = [0.0, 0.0, -9.81];
    s.loads = vec![[0.0; 3], [1.0, 0.0, 0.0]];
    for _ in 0..3 {
        s.step(1e-3, None).unwrap();
    }
    s
}

#[test]
fn a_non_finite_input_set_mid_run_is_named() {
    type Set = fn(&mut Solver);
    let cases: [(&str, &str, Set); 6] = [
        ("gravity", "NaN", |s| s.gravity[2] = f64::NAN),
        ("gravity", "inf", |s| s.gravity[0] = f64::INFINITY),
        ("damping", "NaN", |s| s.damping = f64::NAN),
        ("damping", "-1", |s| s.damping = -1.0),
        ("bulk_viscosity", "inf", |s| {
            s.bulk_viscosity = f64::INFINITY
        }),
        ("loads", "node 1", |s| s.loads[1][1] = f64::NAN),
    ];
    for (name, shown, set) in cases {
        let mut s = solver();
        let (x, v) = (s.x.clone(), s.v.clone());
        set(&mut s);
        let e = s.step(1e-3, None).unwrap_err();
        match &e {
            Error::BadParameter { name: n, value, .. } => {
                assert_eq!(*n, name, "{e}");
                assert!(value.contains(shown), "{name}: {e}");
                assert!(value.contains("before increment 4"), "{name}: {e}");
            }
            other => panic!("{name}: {other}"),
        }
        // nothing moved: the increment did not run
        assert_eq!((s.x, s.v), (x, v), "{name}");
    }
}

/// Two blocks, one of them a sliver `thickness` thick, run to `end`.
fn with_sliver(thickness: f64, end: f64) -> SceneToml {
    SceneToml::new("a block and a sliver", end)
        .material("m", 1.0e7, 0.3, 1000.0)
        .part(part("block", "block", [0.0; 3], [0.1, 0.1, 0.1], [2, 2, 2]).with("material", "m"))
        .part(
            part(
                "thin",
                "block",
                [0.0, 0.0, 0.2],
                [0.1, 0.1, thickness],
                [2, 2, 1],
            )
            .with("material", "m"),
        )
}

#[test]
fn a_run_too_long_to_take_is_refused_naming_the_element_that_makes_it() {
    // c = 100 m/s: the sliver's increment is about its thickness / c
    for (thickness, end) in [(1e-7, 1.0), (1e-9, 0.1), (1e-5, 100.0)] {
        let e = run(&with_sliver(thickness, end).scene(), &Device::cpu(), None).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("run.end_time")
                && text.contains("of part thin")
                && text.contains("max_increments"),
            "{thickness}: {text}"
        );
        assert!(!text.contains(&"0".repeat(20)), "{text}");
    }
    // the same sliver over a short time runs; a limit set below a normal run refuses it, naming
    // the block's element, and raising it lets it run
    run(&with_sliver(1e-5, 1e-4).scene(), &Device::cpu(), None).unwrap();
    let short = SceneToml::new("a block", 1e-2)
        .material("m", 1.0e7, 0.3, 1000.0)
        .part(part("block", "block", [0.0; 3], [0.1, 0.1, 0.1], [2, 2, 2]).with("material", "m"));
    let e = run(
        &short.clone().run("max_increments", 10).scene(),
        &Device::cpu(),
        None,
    )
    .unwrap_err();
    assert!(e.to_string().contains("of part block"), "{e}");
    run(
        &short.run("max_increments", 100_000).scene(),
        &Device::cpu(),
        None,
    )
    .unwrap();
}

/// A deck of three hexahedra in a row along x, labelled 7, 42 and 99, the middle one
/// `thickness` long, for a `period` of explicit dynamics.
fn sliver_deck(thickness: f64, period: f64) -> String {
    let xs = [0.0, 1.0, 1.0 + thickness, 2.0 + thickness];
    let mut s = String::from("*HEADING\nthree bricks, one a sliver\n*NODE\n");
    for (i, x) in xs.iter().enumerate() {
        for (j, (y, z)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .enumerate()
        {
            s += &format!("{}, {x:?}, {y:?}, {z:?}\n", 10 * (i + 1) + j);
        }
    }
    s += "*ELEMENT, TYPE=C3D8, ELSET=ROW\n";
    for (i, label) in [7, 42, 99].into_iter().enumerate() {
        let (a, b) = (10 * (i + 1), 10 * (i + 2));
        s += &format!(
            "{label}, {}, {}, {}, {}, {}, {}, {}, {}\n",
            a,
            b,
            b + 1,
            a + 1,
            a + 3,
            b + 3,
            b + 2,
            a + 2
        );
    }
    s += "*MATERIAL, NAME=M\n*ELASTIC\n1.0e7, 0.3\n*DENSITY\n1000.0\n";
    s += "*SOLID SECTION, ELSET=ROW, MATERIAL=M\n";
    s += &format!("*STEP\n*DYNAMIC, EXPLICIT\n, {period:?}\n*END STEP\n");
    s
}

#[test]
fn a_deck_sliver_is_named_by_its_label_in_the_deck() {
    let scene = deck("sliver.inp", &sliver_deck(1e-7, 10.0)).unwrap();
    let e = run(&scene, &Device::cpu(), None).unwrap_err().to_string();
    assert!(e.contains("element 42 of part"), "{e}");
    assert!(e.contains("max_increments"), "{e}");
    // the same row without the sliver runs its first increments
    let fine = deck("fine.inp", &sliver_deck(1.0, 1e-3)).unwrap();
    run(&fine, &Device::cpu(), None).unwrap();
}
