//! Issue 37: an Abaqus deck runs as it is (`Scene::from_inp`, `abut run model.inp`). A deck
//! and the TOML scene of the same model give the same history, bit for bit; boundary
//! conditions with amplitudes move nodes as the amplitude says; what abut does not model is
//! refused naming the keyword, file and line; what it reads and does not act on is listed.

mod common;

use abut::scene::{run, Scene, Summary};
use abut::Device;
use common::scene_toml::{contact, part, part_of, SceneToml};

/// Writes `text` as `name` in a directory of this test's own and reads it as a scene.
fn deck(name: &str, text: &str) -> abut::Result<Scene> {
    let dir = std::env::temp_dir().join(format!("abut-inp-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    Scene::load(&path)
}

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
/// the line; a deck without a step, or with two, is refused by name.
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
                "*END STEP\n*STEP\n*DYNAMIC, EXPLICIT\n, 0.1\n*END STEP\n",
            ),
            "second *STEP",
            "one step",
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
/// path, and the small ones on every adapter too.
#[test]
fn every_verification_deck_gives_its_scenes_history_bit_for_bit() {
    let small = ["truss_wall", "patch_test", "incline", "penalty_stability"];
    for d in common::devices() {
        for case in CASES {
            if d.backend_name() != "cpu" && !small.contains(&case) {
                continue;
            }
            let toml = Scene::load(&scene_file(&format!("{case}.toml"))).unwrap();
            let deck = Scene::load(&scene_file(&format!("{case}.inp"))).unwrap();
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
