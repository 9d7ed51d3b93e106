//! Issue 37: a deck's several steps run in order, state carried. Each step's boundary
//! conditions and loads act from its start in step time, stay at their end values in later
//! steps until replaced, and `OP=NEW` removes them; increments land on the step ends, and each
//! step's `*NODE PRINT` is written at its end. Checked against the central-difference answers,
//! which are exact for these motions; what abut cannot run across steps is refused by name.

mod common;

use abut::scene::{run, Scene, Summary};
use abut::Device;
use common::scene_toml::deck;

/// Runs `scene` with its outputs in a fresh directory: the summary and each CSV's rows (header
/// first) by file name.
fn run_with_outputs(
    scene: &Scene,
    tag: &str,
) -> (
    Summary,
    std::collections::BTreeMap<String, Vec<Vec<String>>>,
) {
    let dir = std::env::temp_dir().join(format!("abut-inp-steps-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let summary = run(scene, &Device::cpu(), Some(&dir)).unwrap();
    let mut files = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with("node-") {
            let text = std::fs::read_to_string(&path).unwrap();
            files.insert(
                name,
                text.lines()
                    .map(|l| l.split(',').map(String::from).collect())
                    .collect(),
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    (summary, files)
}

/// The value of `column` in the row of `node` of a CSV's rows.
fn value(rows: &[Vec<String>], node: &str, column: &str) -> f64 {
    let k = rows[0].iter().position(|c| c == column).unwrap();
    let row = rows[1..].iter().find(|r| r[1] == node).unwrap();
    row[k].parse().unwrap()
}

/// A point mass `M` at node 1, free, pushed along x by `F` for step 1 (T1), then coasting in
/// step 2 (T2: `*CLOAD, OP=NEW` removes the load), with increments of `DT`.
const M: f64 = 2.0;
const F: f64 = 4.0;
const T1: f64 = 0.1;
const T2: f64 = 0.2;
const DT: f64 = 1e-3;

fn mass_deck(step2_load: &str) -> String {
    format!(
        "*HEADING\na point mass pushed, then coasting\n*NODE\n1, 0.0, 0.0, 0.0\n\
         *ELEMENT, TYPE=MASS, ELSET=BALL\n1, 1\n*MASS, ELSET=BALL\n{M:?}\n*NSET, NSET=P\n1\n\
         *STEP, NAME=PUSH\n*DYNAMIC, EXPLICIT, DIRECT USER CONTROL\n{DT:?}, {T1:?}\n\
         *CLOAD\nP, 1, {F:?}\n*NODE PRINT, NSET=P\nU, V, CF\n*END STEP\n\
         *STEP, NAME=COAST\n*DYNAMIC, EXPLICIT, DIRECT USER CONTROL\n{DT:?}, {T2:?}\n\
         {step2_load}*NODE PRINT, NSET=P\nU, V, CF\n*END STEP\n"
    )
}

#[test]
fn a_load_removed_by_the_next_step_leaves_the_mass_coasting() {
    let scene = deck("coast.inp", &mass_deck("*CLOAD, OP=NEW\n")).unwrap();
    let (summary, files) = run_with_outputs(&scene, "coast");
    // the increments land on the step end: 100 + 200 of exactly DT
    assert_eq!(summary.increments, 300);
    let a = F / M;
    let (one, two) = (
        &files["node-print-P-step1.csv"],
        &files["node-print-P-step2.csv"],
    );
    // central differences with the half-increment start are exact for a constant force: x =
    // a·t²/2 at T1; the velocity then holds a·(T1 − DT/2) (the last half increment's force is
    // the next step's, zero)
    let x1 = 0.5 * a * T1 * T1;
    let v = a * (T1 - 0.5 * DT);
    approx::assert_relative_eq!(value(one, "1", "U1"), x1, max_relative = 1e-12);
    approx::assert_relative_eq!(value(one, "1", "V1"), v, max_relative = 1e-12);
    assert_eq!(
        value(one, "1", "CF1"),
        F,
        "the load in force up to step 1's end"
    );
    approx::assert_relative_eq!(value(two, "1", "U1"), x1 + v * T2, max_relative = 1e-12);
    assert_eq!(value(two, "1", "CF1"), 0.0, "OP=NEW removed it");
}

#[test]
fn a_load_not_restated_stays_at_its_end_value_and_a_restated_one_replaces_it() {
    // step 1's load ramps 0 → 1 over the step (tabular amplitude in step time); step 2 says
    // nothing: it stays at F; a third variant replaces it by 3F in step 2
    let ramped = mass_deck("").replace("*CLOAD\nP, 1", "*CLOAD, AMPLITUDE=RAMP\nP, 1");
    let ramped = ramped.replace(
        "*STEP, NAME=PUSH",
        &format!("*AMPLITUDE, NAME=RAMP\n0.0, 0.0, {T1:?}, 1.0\n*STEP, NAME=PUSH"),
    );
    let scene = deck("held.inp", &ramped).unwrap();
    let (_, files) = run_with_outputs(&scene, "held");
    let two = &files["node-print-P-step2.csv"];
    assert_eq!(value(two, "1", "CF1"), F);
    // v(T1 + T2) = ∫ F/M: F·T1/2 (the ramp) + F·T2 (held), within the half-increment start's
    // and the ramp's first-order error
    let v = value(two, "1", "V1");
    let exact = F / M * (0.5 * T1 + T2);
    approx::assert_relative_eq!(v, exact, max_relative = 2.0 * DT / T1);
    let replaced = ramped.replacen(
        &format!("{DT:?}, {T2:?}\n"),
        &format!("{DT:?}, {T2:?}\n*CLOAD\nP, 1, {:?}\n", 3.0 * F),
        1,
    );
    let scene = deck("replaced.inp", &replaced).unwrap();
    let (_, files) = run_with_outputs(&scene, "replaced");
    let two = &files["node-print-P-step2.csv"];
    assert_eq!(value(two, "1", "CF1"), 3.0 * F);
    let v = value(two, "1", "V1");
    let exact = F / M * (0.5 * T1 + 3.0 * T2);
    approx::assert_relative_eq!(v, exact, max_relative = 2.0 * DT / T1);
}

#[test]
fn loads_on_different_amplitudes_in_one_step_each_follow_their_own() {
    // x: F on a linear ramp over the step; y: F at once
    let text = format!(
        "*HEADING\ntwo loads, two curves\n*NODE\n1, 0.0, 0.0, 0.0\n\
         *ELEMENT, TYPE=MASS, ELSET=BALL\n1, 1\n*MASS, ELSET=BALL\n{M:?}\n*NSET, NSET=P\n1\n\
         *AMPLITUDE, NAME=RAMP\n0.0, 0.0, {T1:?}, 1.0\n\
         *STEP\n*DYNAMIC, EXPLICIT, DIRECT USER CONTROL\n{DT:?}, {T1:?}\n\
         *CLOAD, AMPLITUDE=RAMP\nP, 1, {F:?}\n*CLOAD\nP, 2, {F:?}\n\
         *NODE PRINT, NSET=P\nV, CF\n*END STEP\n"
    );
    let scene = deck("two-curves.inp", &text).unwrap();
    let (_, files) = run_with_outputs(&scene, "two-curves");
    let rows = &files["node-print-P.csv"];
    approx::assert_relative_eq!(value(rows, "1", "CF1"), F, max_relative = 1e-12);
    assert_eq!(value(rows, "1", "CF2"), F);
    let (vx, vy) = (value(rows, "1", "V1"), value(rows, "1", "V2"));
    approx::assert_relative_eq!(vx, F / M * 0.5 * T1, max_relative = 2.0 * DT / T1);
    approx::assert_relative_eq!(vy, F / M * (T1 - 0.5 * DT), max_relative = 1e-12);
}

/// A unit cube of one C3D8 element (E = 1000, ν = 0, ρ = 1), its base held in z (and enough in
/// x and y to stop rigid motion), its top moved by `steps` (each: the step's keyword lines
/// after its procedure).
fn cube_deck(steps: &[&str]) -> String {
    let mut s = String::from("*HEADING\na cube moved through steps\n*NODE\n");
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    for (k, c) in corners.iter().enumerate() {
        s += &format!("{}, {:?}, {:?}, {:?}\n", k + 1, c[0], c[1], c[2]);
    }
    s += "*ELEMENT, TYPE=C3D8, ELSET=CUBE\n1, 1, 2, 3, 4, 5, 6, 7, 8\n";
    s += "*NSET, NSET=BASE\n1, 2, 3, 4\n*NSET, NSET=TOP\n5, 6, 7, 8\n";
    s += "*MATERIAL, NAME=SOFT\n*ELASTIC\n1000.0, 0.0\n*DENSITY\n1.0\n";
    s += "*SOLID SECTION, ELSET=CUBE, MATERIAL=SOFT\n";
    s += "*AMPLITUDE, NAME=RAMP, DEFINITION=SMOOTH STEP\n0.0, 0.0, 0.05, 1.0\n";
    s += "*BOUNDARY\nBASE, 3, 3\n1, 1, 2\n2, 2, 2\n";
    for (k, body) in steps.iter().enumerate() {
        s += &format!(
            "*STEP, NAME=S{}\n*DYNAMIC, EXPLICIT\n, 0.05\n{body}*NODE PRINT, NSET=TOP\nU, V, RF\n*NODE PRINT, NSET=BASE\nU\n*END STEP\n",
            k + 1
        );
    }
    s
}

#[test]
fn a_displacement_holds_in_the_next_step_and_a_velocity_replaces_it_in_the_one_after() {
    let text = cube_deck(&[
        "*BOUNDARY, AMPLITUDE=RAMP\nTOP, 3, 3, -0.01\n",
        "",
        "*BOUNDARY, TYPE=VELOCITY\nTOP, 3, 3, 0.2\n",
    ]);
    let scene = deck("cube-steps.inp", &text).unwrap();
    let (summary, files) = run_with_outputs(&scene, "cube-steps");
    assert!(
        summary
            .deck_notes
            .iter()
            .any(|n| n.contains("3 steps run in order")),
        "{:?}",
        summary.deck_notes
    );
    for node in ["5", "6", "7", "8"] {
        // the smooth ramp reaches −0.01 at step 1's end, held through step 2 (the total
        // displacement from the reference), then the top rises at 0.2 for 0.05
        let u1 = value(&files["node-print-TOP-step1.csv"], node, "U3");
        let u2 = value(&files["node-print-TOP-step2.csv"], node, "U3");
        let u3 = value(&files["node-print-TOP-step3.csv"], node, "U3");
        approx::assert_abs_diff_eq!(u1, -0.01, epsilon = 1e-12);
        approx::assert_abs_diff_eq!(u2, -0.01, epsilon = 1e-12);
        approx::assert_abs_diff_eq!(u3, -0.01 + 0.2 * 0.05, epsilon = 1e-12);
        approx::assert_abs_diff_eq!(
            value(&files["node-print-TOP-step3.csv"], node, "V3"),
            0.2,
            epsilon = 1e-12
        );
    }
    for node in ["1", "2", "3", "4"] {
        assert_eq!(value(&files["node-print-BASE-step3.csv"], node, "U3"), 0.0);
    }
}

#[test]
fn op_new_removes_every_earlier_boundary_condition() {
    // step 1 squeezes the top at a set velocity; step 2 removes everything and holds only the
    // base again: the top is free, springs back and moves on its own
    let text = cube_deck(&[
        "*BOUNDARY, TYPE=VELOCITY\nTOP, 3, 3, -0.2\n",
        "*BOUNDARY, OP=NEW\nBASE, 3, 3\n1, 1, 2\n2, 2, 2\n",
    ]);
    let scene = deck("cube-new.inp", &text).unwrap();
    let (_, files) = run_with_outputs(&scene, "cube-new");
    let (one, two) = (
        &files["node-print-TOP-step1.csv"],
        &files["node-print-TOP-step2.csv"],
    );
    approx::assert_abs_diff_eq!(value(one, "5", "U3"), -0.2 * 0.05, epsilon = 1e-12);
    approx::assert_abs_diff_eq!(value(one, "5", "V3"), -0.2, epsilon = 1e-12);
    // no longer held at −0.2: the compressed cube pushes the top back up, and nothing holds it
    let v = value(two, "5", "V3");
    assert!(v > -0.19, "the top still moves as held: {v}");
    assert!(value(one, "5", "RF3") < 0.0, "held in step 1");
    assert_eq!(value(two, "5", "RF3"), 0.0, "no reaction once released");
    assert_eq!(value(&files["node-print-BASE-step2.csv"], "1", "U3"), 0.0);
    // without OP=NEW the velocity condition carries on
    let kept = cube_deck(&["*BOUNDARY, TYPE=VELOCITY\nTOP, 3, 3, -0.2\n", ""]);
    let (_, files) = run_with_outputs(&deck("cube-kept.inp", &kept).unwrap(), "cube-kept");
    approx::assert_abs_diff_eq!(
        value(&files["node-print-TOP-step2.csv"], "5", "U3"),
        -0.2 * 0.1,
        epsilon = 1e-12
    );
}

#[test]
fn what_cannot_run_across_steps_is_refused_by_name_and_line() {
    let base = cube_deck(&["*BOUNDARY, TYPE=VELOCITY\nTOP, 3, 3, -0.2\n", ""]);
    let second_step = |text: &str| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.starts_with("*STEP"))
            .nth(1)
            .map(|(k, _)| k + 1)
            .unwrap()
    };
    // `from` replaced by `to` in the second step only
    let in_step2 = |from: &str, to: &str| {
        let k = base.find("*STEP, NAME=S2").unwrap();
        format!("{}{}", &base[..k], base[k..].replacen(from, to, 1))
    };
    let cases = [
        (
            in_step2(
                "*DYNAMIC, EXPLICIT\n, 0.05\n",
                "*DYNAMIC, EXPLICIT\n, 0.05\n*BULK VISCOSITY\n0.1, 1.5\n",
            ),
            "*BULK VISCOSITY",
        ),
        (
            in_step2("*DYNAMIC, EXPLICIT\n, 0.05\n", "*STATIC\n0.1, 0.05\n"),
            "several *DYNAMIC, EXPLICIT steps",
        ),
    ];
    for (text, why) in cases {
        let line = second_step(&text);
        let e = deck("refused-steps.inp", &text).unwrap_err().to_string();
        assert!(e.contains(why), "{why}: {e}");
        assert!(
            e.contains(&format!("refused-steps.inp:{line}:")),
            "{why}: the second step's line {line}: {e}"
        );
    }
    // gravity from the second step on, a contact pair defined there
    let gravity = in_step2(
        ", 0.05\n",
        ", 0.05\n*DLOAD\nCUBE, GRAV, 9.81, 0.0, 0.0, -1.0\n",
    );
    let e = deck("refused-steps.inp", &gravity).unwrap_err().to_string();
    assert!(e.contains("GRAV in a later step"), "{e}");
    let pair = in_step2(", 0.05\n", ", 0.05\n*CONTACT PAIR\nA, B\n");
    let e = deck("refused-steps.inp", &pair).unwrap_err().to_string();
    assert!(e.contains("*CONTACT PAIR in a later step"), "{e}");
}

#[test]
fn a_node_output_under_history_output_is_a_time_series_of_its_step() {
    // `*OUTPUT, HISTORY, FREQUENCY=10` in step 1: a row every 10 increments while it runs
    let text = mass_deck("").replacen(
        "*CLOAD\nP, 1",
        "*OUTPUT, HISTORY, FREQUENCY=10\n*NODE OUTPUT, NSET=P\nU\n*CLOAD\nP, 1",
        1,
    );
    // every step shares the first's output cadence
    let text = text.replacen(
        &format!("{DT:?}, {T2:?}\n"),
        &format!("{DT:?}, {T2:?}\n*OUTPUT, HISTORY, FREQUENCY=10\n"),
        1,
    );
    let scene = deck("history.inp", &text).unwrap();
    let (_, files) = run_with_outputs(&scene, "history");
    let rows = &files["node-output-P-step1.csv"];
    assert_eq!(rows[0], ["time", "node", "U1", "U2", "U3"]);
    assert_eq!(
        rows.len() - 1,
        10,
        "one row per 10 increments of step 1's 100"
    );
    for r in &rows[1..] {
        let t: f64 = r[0].parse().unwrap();
        let u: f64 = r[2].parse().unwrap();
        approx::assert_relative_eq!(u, 0.5 * F / M * t * t, max_relative = 1e-9);
    }
}
