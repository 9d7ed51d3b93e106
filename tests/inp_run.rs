//! Issue 37: an Abaqus deck runs as it is (`Scene::from_inp`, `abut run model.inp`). A deck
//! and the TOML scene of the same model give the same history, bit for bit; boundary
//! conditions with amplitudes move nodes as the amplitude says; what abut does not model is
//! refused naming the keyword, file and line; what it reads and does not act on is listed.

mod common;

use abut::scene::{run, Scene, Summary};
use abut::Device;
use common::scene_toml::{contact, deck, part, part_of, SceneToml};

/// The history's rows without the header (the columns are named after the parts, which a
/// deck names by its sets).
fn history(scene: &Scene, tag: &str) -> (Summary, Vec<String>) {
    let dir = std::env::temp_dir().join(format!("abut-inp-history-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let s = run(scene, &Device::cpu(), Some(&dir)).unwrap();
    let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (s, csv.lines().skip(1).map(String::from).collect())
}

/// A 2 × 2 rigid plate on [0, 1]² (nodes 1–9, R3D4 elements, reference node 10 held), a point
/// mass `m` at node 11 above it at (0.4, 0.6, `z`) falling at `v` under gravity, penalty
/// contact of `k` per unit area (the mass's node surface has area 1).
fn drop_deck(m: f64, z: f64, v: f64, k: f64, extra_step: &str) -> String {
    let mut s = String::from("*HEADING\na point mass dropped on a rigid plate\n*NODE\n");
    for j in 0..3 {
        for i in 0..3 {
            s += &format!(
                "{}, {:?}, {:?}, 0.0\n",
                1 + j * 3 + i,
                0.5 * i as f64,
                0.5 * j as f64
            );
        }
    }
    s += &format!("10, 0.5, 0.5, 0.0\n11, 0.4, 0.6, {z:?}\n");
    s += "*ELEMENT, TYPE=R3D4, ELSET=PLATE\n1, 1, 2, 5, 4\n2, 2, 3, 6, 5\n3, 4, 5, 8, 7\n4, 5, 6, 9, 8\n";
    s += "*RIGID BODY, REF NODE=10, ELSET=PLATE\n";
    s += "*ELEMENT, TYPE=MASS, ELSET=BALL\n100, 11\n";
    s += &format!("*MASS, ELSET=BALL\n{m:?}\n");
    s += "*NSET, NSET=BALLN\n11\n";
    s += "*SURFACE, NAME=TOP\nPLATE, SPOS\n";
    s += "*SURFACE, NAME=BALLS, TYPE=NODE\nBALLN, 1.0\n";
    s += &format!("*SURFACE INTERACTION, NAME=SPRING\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{k:?}\n");
    s += "*CONTACT PAIR, INTERACTION=SPRING, MECHANICAL CONSTRAINT=PENALTY\nBALLS, TOP\n";
    s += "*BOUNDARY\n10, ENCASTRE\n";
    s += &format!("*INITIAL CONDITIONS, TYPE=VELOCITY\n11, 3, {v:?}\n");
    s += "*STEP, NAME=DROP\n*DYNAMIC, EXPLICIT, DIRECT USER CONTROL\n1e-3, 0.3\n";
    s += "*DLOAD\nBALL, GRAV, 9.81, 0.0, 0.0, -1.0\n";
    s += "*OUTPUT, HISTORY, FREQUENCY=5\n*NODE OUTPUT\nU, V\n*NODE PRINT\nU\n";
    s += extra_step;
    s += "*END STEP\n";
    s
}

/// The TOML scene of [`drop_deck`].
fn drop_toml(m: f64, z: f64, v: f64, k: f64) -> Scene {
    SceneToml::new("a point mass dropped on a rigid plate", 0.3)
        .run("dt", 1e-3)
        .run("gravity", [0.0, 0.0, -9.81])
        .run("output_every", 5)
        .part(part("plate", "plate", [0.0; 3], [1.0, 1.0, 0.0], [2, 2, 0]))
        .part(
            part_of("ball", "points")
                .with("points", [[0.4, 0.6, z]])
                .with("mass", m)
                .with("velocity", [0.0, 0.0, v]),
        )
        .contact(contact("ball", "all", "plate", "z+").with("stiffness_per_area", k))
        .scene()
}

/// The same drop as a deck and as a TOML scene: the same history to the last bit, over masses,
/// heights, speeds and stiffnesses (touching, bouncing, resting); the print requests listed as
/// not acted on.
#[test]
fn a_deck_and_its_toml_scene_give_the_same_history() {
    for (m, z, v, k) in [
        (1.0, 0.05, -1.0, 1e4),
        (2.5, 0.001, 0.0, 3e3),
        (0.1, 0.2, -3.0, 1e5),
    ] {
        let d = deck("drop.inp", &drop_deck(m, z, v, k, "")).unwrap();
        assert_eq!(d.title, "a point mass dropped on a rigid plate");
        let (sd, hd) = history(&d, "deck");
        let (st, ht) = history(&drop_toml(m, z, v, k), "toml");
        assert!(sd.impulse > 0.0, "m {m}: it lands");
        assert_eq!(hd.len(), ht.len());
        assert_eq!(hd, ht, "m {m} z {z} v {v} k {k}");
        assert_eq!(sd.increments, st.increments);
        assert!(
            sd.deck_notes.iter().any(|n| n.contains("*NODE PRINT")),
            "{:?}",
            sd.deck_notes
        );
        assert!(sd.deck_notes.iter().any(|n| n.contains("*NODE OUTPUT")));
    }
}

/// A prescribed velocity with a tabular amplitude and a displacement with a smooth step move a
/// node as the amplitudes say: a truss element (T3D2, area 0.01), its far end held, its near end
/// pulled along it; at the end of the run the near end has moved the amplitude's integral
/// (velocity) or its value (displacement) — the part's mass-weighted mean, half of it.
#[test]
fn boundary_amplitudes_move_nodes_as_they_say() {
    let bar = |bc: &str, end: f64| {
        format!(
            "*HEADING\nbar\n*NODE\n1, 0, 0, 0\n2, 1.0, 0, 0\n\
             *ELEMENT, TYPE=T3D2, ELSET=BAR\n1, 1, 2\n\
             *MATERIAL, NAME=STEEL\n*DENSITY\n7800.\n*ELASTIC\n2.0e11, 0.3\n\
             *SOLID SECTION, ELSET=BAR, MATERIAL=STEEL\n0.01\n\
             *NSET, NSET=FAR\n1\n*NSET, NSET=NEAR\n2\n*NSET, NSET=ALL\n1, 2\n\
             *AMPLITUDE, NAME=RAMP\n0.0, 0.0, 1e-3, 1.0, 2e-3, 1.0\n\
             *AMPLITUDE, NAME=SMOOTH, DEFINITION=SMOOTH STEP\n0.0, 0.0, 2e-3, 1.0\n\
             *BOUNDARY\nFAR, 1, 3\nALL, 2, 3\n\
             *STEP\n*DYNAMIC, EXPLICIT\n, {end:?}\n{bc}*END STEP\n"
        )
    };
    let mean_x = |text: String, name: &str| {
        let s = run(&deck(name, &text).unwrap(), &Device::cpu(), None).unwrap();
        assert_eq!(s.parts.len(), 1);
        (s.parts[0].displacement[0], s.end_time)
    };
    for end in [0.5e-3, 1.5e-3, 3e-3] {
        // a velocity of 0.5 on the tabular ramp 0 → 1 over 1e-3, then 1
        let (u, t) = mean_x(
            bar(
                "*BOUNDARY, TYPE=VELOCITY, AMPLITUDE=RAMP\nNEAR, 1, 1, 0.5\n",
                end,
            ),
            "velocity.inp",
        );
        let exact = 0.5
            * if t <= 1e-3 {
                t * t / 2e-3
            } else {
                0.5e-3 + (t - 1e-3)
            };
        assert!((t - end).abs() < 1e-12, "{t}");
        assert!(
            (2.0 * u / exact - 1.0).abs() < 1e-9,
            "velocity, t = {t}: {u} against {exact}/2"
        );
        // a displacement of 1e-3 on the smooth step over 2e-3
        let (u, t) = mean_x(
            bar("*BOUNDARY, AMPLITUDE=SMOOTH\nNEAR, 1, 1, 1e-3\n", end),
            "displacement.inp",
        );
        let xi = (t / 2e-3).min(1.0);
        let exact = 1e-3 * xi * xi * xi * (10.0 - 15.0 * xi + 6.0 * xi * xi);
        assert!(
            (2.0 * u / exact - 1.0).abs() < 1e-9,
            "displacement, t = {t}: {u} against {exact}/2"
        );
    }
}

/// What abut does not model is refused before anything runs, naming the keyword, the file and
/// the line; a deck without a step, or with a static step after a dynamic one, is refused by
/// name.
#[test]
fn what_abut_does_not_model_is_refused_by_name_and_line() {
    let base = drop_deck(1.0, 0.05, -1.0, 1e4, "");
    let cases = [
        (
            base.replace(
                "*STEP, NAME=DROP",
                "*EQUATION\n2\n11, 1, 1.0, 10, 1, -1.0\n*STEP, NAME=DROP",
            ),
            "*EQUATION",
            "a constraint between nodes",
        ),
        (
            base.replace(
                "*MASS, ELSET=BALL",
                "*MATERIAL, NAME=M\n*PLASTIC\n1.0, 0.0\n*MASS, ELSET=BALL",
            ),
            "*PLASTIC",
            "beyond linear elasticity",
        ),
        (
            base.replace(
                "*DYNAMIC, EXPLICIT, DIRECT USER CONTROL\n1e-3, 0.3",
                "*DYNAMIC\n0.1, 1.0",
            ),
            "*DYNAMIC",
            "explicit steps only",
        ),
        (
            base.replace(
                "*END STEP\n",
                "*END STEP\n*STEP\n*STATIC\n0.1, 1.0\n*END STEP\n",
            ),
            "second *STEP",
            "several *DYNAMIC, EXPLICIT steps",
        ),
        (
            base.replace(
                "*SURFACE, NAME=TOP",
                "*TIE, NAME=T\nBALLS, TOP\n*SURFACE, NAME=TOP",
            ),
            "*TIE",
            "constraint",
        ),
        (
            base.replace(
                "*BOUNDARY\n10, ENCASTRE",
                "*BOUNDARY\n10, ENCASTRE\n1, 1, 1, 0.1",
            ),
            "node 1 of a rigid body",
            "reference node",
        ),
        (
            base.replace(
                "*STEP, NAME=DROP",
                "*AMPLITUDE, NAME=RAMP\n0.0, 0.0, 0.3, 1.0\n*STEP, NAME=DROP",
            )
            .replace(
                "*END STEP\n",
                "*CLOAD, AMPLITUDE=RAMP\n10, 3, 1.0\n*CLOAD\n11, 1, 1.0\n*END STEP\n",
            ),
            "a rigid body's loads on another curve",
            "scales a rigid body's loads by one curve",
        ),
    ];
    for (text, what, why) in cases {
        let line = text
            .lines()
            .position(|l| {
                l.starts_with(what.trim_start_matches("second "))
                    || (what.starts_with("node 1") && l == "1, 1, 1, 0.1")
            })
            .map(|k| k + 1);
        let e = deck("refused.inp", &text).unwrap_err().to_string();
        assert!(e.contains(why), "{what}: {e}");
        assert!(e.contains("refused.inp:"), "{what}: the file is named: {e}");
        if what.starts_with('*') {
            let line = if what == "second *STEP" {
                text.lines()
                    .enumerate()
                    .filter(|(_, l)| l.starts_with("*STEP"))
                    .nth(1)
                    .map(|(k, _)| k + 1)
            } else {
                line
            };
            assert!(
                e.contains(&format!(":{}:", line.unwrap())),
                "{what}: the line: {e}"
            );
        }
    }
}

/// The verification cases of `abut verify`.
const CASES: [&str; 8] = [
    "bar_impact",
    "truss_wall",
    "patch_test",
    "hertz_cylinder",
    "hertz_sphere",
    "hertz_impact",
    "incline",
    "penalty_stability",
];

fn scene_file(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// Each verification case exists as a deck, `scenes/NAME.inp`, written by `abut inp` from its
/// TOML scene (regenerated with `ABUT_BLESS=1`): the deck in the repository is what the scene
/// writes today.
#[test]
fn every_verification_case_has_its_deck() {
    for case in CASES {
        let scene = Scene::load(&scene_file(&format!("{case}.toml"))).unwrap();
        let written = scene.to_inp().unwrap();
        let path = scene_file(&format!("{case}.inp"));
        if std::env::var("ABUT_BLESS").is_ok_and(|v| v == "1") {
            std::fs::write(&path, &written).unwrap();
        }
        let kept = std::fs::read_to_string(&path).unwrap();
        assert!(
            kept == written,
            "scenes/{case}.inp is not what scenes/{case}.toml writes (ABUT_BLESS=1 cargo test --release --test inp_run rewrites it)"
        );
    }
}

/// Each verification deck gives its TOML scene's history bit for bit: every case on the CPU
/// path, and the small ones on every adapter too. The two long runs on the CPU path (the Hertz
/// sphere and cylinder: 45,000 and 26,000 increments) and every run on an adapter (a few
/// thousand host-array increments each) take their first fifth, both scenes alike: what is
/// compared is how the deck was read, which acts from the first increment (contact starts in
/// the first few hundred), and tests/verification.rs runs the whole cases on every device.
#[test]
fn every_verification_deck_gives_its_scenes_history_bit_for_bit() {
    let small = ["truss_wall", "patch_test", "incline", "penalty_stability"];
    let long = ["hertz_sphere", "hertz_cylinder"];
    for d in common::devices() {
        for case in CASES {
            if d.backend_name() != "cpu" && !small.contains(&case) {
                continue;
            }
            let mut toml = Scene::load(&scene_file(&format!("{case}.toml"))).unwrap();
            let mut deck = Scene::load(&scene_file(&format!("{case}.inp"))).unwrap();
            assert_eq!(toml.run.end_time, deck.run.end_time, "{case}");
            if long.contains(&case) || d.backend_name() != "cpu" {
                toml.run.end_time /= 5.0;
                deck.run.end_time /= 5.0;
            }
            let rows = |s: &Scene, tag: &str| {
                let dir = std::env::temp_dir().join(format!(
                    "abut-inp-verify-{case}-{tag}-{}-{}",
                    d.backend_name(),
                    std::process::id()
                ));
                let _ = std::fs::remove_dir_all(&dir);
                let summary = run(s, &d, Some(&dir)).unwrap();
                let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
                let _ = std::fs::remove_dir_all(&dir);
                let rows: Vec<String> = csv.lines().skip(1).map(String::from).collect();
                (summary, rows)
            };
            let (st, ht) = rows(&toml, "toml");
            let (sd, hd) = rows(&deck, "deck");
            assert!(ht.len() > 5, "{d} {case}");
            assert_eq!(st.increments, sd.increments, "{d} {case}");
            assert!(ht == hd, "{d} {case}: the deck's history differs");
            assert_eq!(st.impulse.to_bits(), sd.impulse.to_bits(), "{d} {case}");
        }
    }
}

/// A block pressed on a block, then pushed sideways until it slides, as a `*STATIC` deck of
/// C3D4 tetrahedra (no `*DENSITY`): two unit cubes of E = 1000, ν = 0 (uniaxial: the static
/// answer is exact), the lower one held at its base, the upper one's top pressed down by
/// δ = 0.01 over the first half of the step and then moved 0.03 sideways over the second;
/// penalty contact of 10⁵ per area with Coulomb μ = 0.3. Static answer: a uniform pressure
/// p = δ/(H/E + H/E + 1/k) = 4.975 over the unit area, the normal force N = p, and once the
/// top block slides (the blocks' shear takes less than half of the 0.03; the edge nodes then
/// stand less than 0.02 beyond the lower block's edge, within its extension zone) a tangential
/// force μ·N, which the stopped interface holds within 5 % below it.
#[test]
fn a_static_deck_of_a_block_pressed_and_slid_on_a_block_runs_quasi_static() {
    let n = 3;
    let grid = |z0: f64| {
        let c: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
        abut::mesh::block_tets_on([c.clone(), c.clone(), c.iter().map(|z| z + z0).collect()])
    };
    let (lower, upper) = (grid(0.0), grid(1.0));
    let per = lower.positions.len();
    let mut s = String::from("*HEADING\nblock pressed and slid on a block\n*NODE\n");
    for (k, p) in lower.positions.iter().chain(&upper.positions).enumerate() {
        s += &format!("{}, {:?}, {:?}, {:?}\n", k + 1, p[0], p[1], p[2]);
    }
    let mut label = 0;
    for (name, mesh, base) in [("LOWER", &lower, 0), ("UPPER", &upper, per)] {
        s += &format!("*ELEMENT, TYPE=C3D4, ELSET={name}\n");
        for t in &mesh.facets {
            label += 1;
            s += &format!(
                "{label}, {}, {}, {}, {}\n",
                t[0] as usize + base + 1,
                t[1] as usize + base + 1,
                t[2] as usize + base + 1,
                t[3] as usize + base + 1
            );
        }
        s += &format!("*SOLID SECTION, ELSET={name}, MATERIAL=SOFT\n");
    }
    // node sets by height (the base and the top each on one block)
    let at = |z: f64| -> Vec<usize> {
        lower
            .positions
            .iter()
            .chain(&upper.positions)
            .enumerate()
            .filter(|(_, p)| (p[2] - z).abs() < 1e-12)
            .map(|(k, _)| k + 1)
            .collect()
    };
    let base: Vec<usize> = at(0.0);
    let top: Vec<usize> = at(2.0);
    let lower_top: Vec<usize> = (0..per)
        .filter(|&k| (lower.positions[k][2] - 1.0).abs() < 1e-12)
        .map(|k| k + 1)
        .collect();
    let upper_bottom: Vec<usize> = (0..per)
        .filter(|&k| (upper.positions[k][2] - 1.0).abs() < 1e-12)
        .map(|k| k + per + 1)
        .collect();
    let list = |v: &[usize]| {
        v.iter()
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(",\n")
            + "\n"
    };
    s += &format!(
        "*NSET, NSET=BASE\n{}*NSET, NSET=TOP\n{}",
        list(&base),
        list(&top)
    );
    // the lower block's top as surface elements, the upper block's bottom as its nodes with
    // their tributary areas (a node of the 3 × 3 grid: 1/36 at a corner, 1/18 on an edge, 1/9
    // inside)
    s += "*ELEMENT, TYPE=SFM3D4, ELSET=LOWER-TOP\n";
    for j in 0..n {
        for i in 0..n {
            let id = |i: usize, j: usize| {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                lower_top[lower_top
                    .iter()
                    .position(|&k| {
                        let p = lower.positions[k - 1];
                        (p[0] - x).abs() < 1e-12 && (p[1] - y).abs() < 1e-12
                    })
                    .unwrap()]
            };
            label += 1;
            s += &format!(
                "{label}, {}, {}, {}, {}\n",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    s += "*SURFACE SECTION, ELSET=LOWER-TOP\n*SURFACE, NAME=MASTER\nLOWER-TOP, SPOS\n";
    s += "*SURFACE, NAME=SLAVE, TYPE=NODE\n";
    for &k in &upper_bottom {
        let p = upper.positions[k - per - 1];
        let edge = |c: f64| {
            if c.abs() < 1e-12 || (c - 1.0).abs() < 1e-12 {
                0.5
            } else {
                1.0
            }
        };
        s += &format!("{k}, {:?}\n", edge(p[0]) * edge(p[1]) / 9.0);
    }
    s += "*MATERIAL, NAME=SOFT\n*ELASTIC\n1000.0, 0.0\n";
    s += "*SURFACE INTERACTION, NAME=GRIP\n*FRICTION\n0.3\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n1.0e5\n";
    s += "*CONTACT PAIR, INTERACTION=GRIP, MECHANICAL CONSTRAINT=PENALTY\nSLAVE, MASTER\n";
    s += "*AMPLITUDE, NAME=PRESS, DEFINITION=SMOOTH STEP\n0.0, 0.0, 0.5, 1.0\n";
    s += "*AMPLITUDE, NAME=SLIDE, DEFINITION=SMOOTH STEP\n0.0, 0.0, 0.5, 0.0, 1.0, 1.0\n";
    s += "*BOUNDARY\nBASE, ENCASTRE\n";
    s += "*STEP, NLGEOM=NO\n*STATIC\n0.1, 1.0\n";
    s += "*BOUNDARY, AMPLITUDE=PRESS\nTOP, 3, 3, -0.01\n*BOUNDARY, AMPLITUDE=SLIDE\nTOP, 1, 1, 0.03\n*BOUNDARY\nTOP, 2, 2\n";
    s += "*NODE PRINT, NSET=TOP\nRF\n*END STEP\n";
    let scene = deck("blocks.inp", &s).unwrap();
    let q = scene
        .quasi_static
        .clone()
        .expect("a *STATIC step runs quasi-static");
    let summary = run(&scene, &Device::cpu(), None).unwrap();
    let exact_p = 0.01 / (1e-3 + 1e-3 + 1e-5);
    let f = summary.final_contact_force;
    let qs = summary
        .quasi_static
        .clone()
        .expect("the summary reports the quasi-static run");
    eprintln!(
        "quasi-static blocks: {} increments, ramp {:.3e} over a period of {:.3e}; N = {:.5} (static {exact_p:.5}), T = {:.5} (μN {:.5}); KE/IE at the ramp's end {:.2e}, at the end {:.2e}, largest {:.2e}",
        summary.increments,
        q.ramp_time,
        q.fundamental_period,
        f[2],
        f[0].hypot(f[1]),
        0.3 * f[2],
        qs.kinetic_to_internal_at_ramp_end,
        qs.kinetic_to_internal_at_end,
        qs.kinetic_to_internal_max
    );
    assert!(
        (f[2] / exact_p - 1.0).abs() < 0.02,
        "normal force {} against {exact_p}",
        f[2]
    );
    // it slid (Coulomb's limit reached) and stopped: the interface holds what it slid at, less
    // what the blocks relax once the top stops (statics allows any force up to μN then)
    let ratio = f[0].hypot(f[1]) / (0.3 * f[2]);
    assert!(
        ratio <= 1.001 && ratio > 0.95,
        "tangential {f:?} against μN: {ratio}"
    );
    // every contact node carries the static pressure, in the mean; the moment of the
    // tangential force tilts the distribution linearly about it
    let mean = summary
        .contact_nodes
        .iter()
        .map(|n| n.pressure)
        .sum::<f64>()
        / summary.contact_nodes.len() as f64;
    assert_eq!(summary.contact_nodes.len(), (n + 1) * (n + 1));
    assert!(
        (mean / exact_p - 1.0).abs() < 0.05,
        "mean pressure {mean} against {exact_p}"
    );
    assert!(
        qs.kinetic_to_internal_max < 0.05 && qs.kinetic_to_internal_at_end < 1e-3,
        "{qs:?}"
    );
    assert!(
        summary
            .deck_notes
            .iter()
            .any(|n| n.contains("quasi-static")),
        "{:?}",
        summary.deck_notes
    );
}
