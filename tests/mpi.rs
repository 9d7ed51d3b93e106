//! Contact across MPI ranks (issue 18, feature `mpi`): examples/mpi_contact.rs under
//! `mpirun -n 1, 2 and 4` (oversubscribed on a two-core machine) gives every node's force after
//! every one of 60 increments equal to a single process's to f32 round-off — two penalty pairs
//! on one plate, frictionless and with Coulomb friction (the stick force carried through each
//! rank's rebuilt local model), whose slaves and master are cut across ranks differently by
//! recursive coordinate bisection,
//! the plate sliding by more than a rank's width so that slaves' facets pass between ranks,
//! distributed global searches at the interval, and with four ranks one rank with no contact —
//! and a rerun with the same rank count gives the same bits; a self-contact sheet and a balanced
//! pair likewise.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

mod common;

/// Runs the example under `mpirun -n ranks`; its one line.
fn run(ranks: usize) -> String {
    run_case(ranks, None)
}

/// Runs the example's `case` under `mpirun -n ranks`; its one line.
fn run_case(ranks: usize, case: Option<&str>) -> String {
    let out = mpirun(ranks, case);
    out.lines()
        .find(|l| l.starts_with("ranks "))
        .expect("the example's line")
        .to_string()
}

/// `mpirun` under a time limit of 10 minutes: a job whose ranks deadlock fails the test
/// instead of holding CI for ever.
fn mpirun_command() -> Command {
    let mut c = Command::new("timeout");
    c.args(["600", "mpirun"]);
    c
}

/// The example's output under `mpirun -n ranks`, with `ABUT_MPI_CASE=case`.
fn mpirun(ranks: usize, case: Option<&str>) -> String {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().parent().unwrap();
    let example = dir.join("examples").join("mpi_contact");
    assert!(
        example.exists(),
        "{} not built: cargo build --release --features mpi --example mpi_contact",
        example.display()
    );
    let out = mpirun_command()
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "-x",
            "ABUT_MPI_CASE",
            "-n",
        ])
        .arg(ranks.to_string())
        .arg(&example)
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .env("ABUT_MPI_CASE", case.unwrap_or(""))
        .output()
        .expect("mpirun runs (Open MPI installed: .ci/run installs it)");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "mpirun -n {ranks}: {}\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("{stdout}");
    stdout
}

/// The number just before `what` in the example's line.
fn count_before(line: &str, what: &str) -> usize {
    line.split(what)
        .next()
        .and_then(|h| h.rsplit(' ').next())
        .and_then(|h| h.parse().ok())
        .unwrap_or_else(|| panic!("a count before '{what}' in {line}"))
}

fn checksum(line: &str) -> &str {
    line.rsplit("checksum ").next().unwrap()
}

#[test]
fn forces_across_ranks_equal_the_single_process_and_reruns_are_bitwise() {
    for ranks in [1, 2, 4] {
        let a = run(ranks);
        if ranks == 2 {
            let b = run(ranks);
            assert_eq!(checksum(&a), checksum(&b), "reruns with {ranks} ranks");
        }
        // one increment's collectives: the agreement on faults, motion and increment, the ghosts'
        // state, their forces back, the agreement on the results; a distributed global search
        // adds the slave boxes and the ghosts' counts, ids and masses (before issue 34: 13 and
        // 19-20)
        assert!(
            a.contains("collectives per increment 4-4 local 7-7 global"),
            "{a}"
        );
        if ranks > 1 {
            // slaves' facets passed from one rank's nodes to another's
            let handovers = count_before(&a, " hand-overs");
            assert!(handovers > 0, "{a}");
        }
        if ranks == 4 {
            // the far block's rank: no slaves (and only its box sent at each global search)
            assert!(a.contains("/0slaves"), "{a}");
        }
    }
}

/// A rank that names a slave it does not own, gives a 2D segment as a facet of a 3D model or
/// a rigid part of negative mass, is refused, and so is every other rank, with an error naming
/// the rank at fault — none of them is left waiting in a collective. A rigid part naming a node
/// no rank owns is refused on every rank alike.
#[test]
fn a_bad_share_is_refused_on_every_rank() {
    for (case, says) in [
        ("bad-slave", "global id 18446744073709551614"),
        ("bad-facet", "a triangle or a quad in a 3D model"),
        ("bad-part", "rigid part 0"),
    ] {
        let out = mpirun(3, Some(case));
        for r in 0..3 {
            let line = out
                .lines()
                .find(|l| l.starts_with(&format!("rank {r} refused")))
                .unwrap_or_else(|| panic!("{case}: rank {r} was not refused: {out}"));
            if r == 2 {
                assert!(line.contains(says), "{case}: {line}");
            } else {
                assert!(
                    line.contains("rank") && line.contains('2'),
                    "{case}: {line}"
                );
            }
        }
    }
    // a rigid part one of whose nodes no rank owns: every rank finds it alike and says so
    let out = mpirun(3, Some("lost-part"));
    for r in 0..3 {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("rank {r} refused")))
            .unwrap_or_else(|| panic!("lost-part: rank {r} was not refused: {out}"));
        assert!(
            line.contains("rigid part 0: 2 of its 3 nodes owned by a rank"),
            "{line}"
        );
    }
}

/// A self-contact sheet across ranks: one surface of two layers pressed through each other and
/// sliding, every node of both a slave of the one pair (with friction), the layers cut across
/// ranks: every node's force equals the single process's at 1, 2 and 4 ranks.
#[test]
fn a_self_contact_sheet_across_ranks_equals_the_single_process() {
    for ranks in [1, 2, 4] {
        let line = run_case(ranks, Some("self"));
        let active = count_before(&line, " slaves in contact");
        assert!(active > 100, "{line}");
    }
}

/// A balanced pair across ranks (passes weighted 0.6 and 0.4, with friction): two plates of
/// different meshes, the upper sliding over the lower's crests, both cut across ranks; every
/// node's force equals the single process's balanced pair at 1, 2 and 4 ranks (the example
/// fails on a difference: with the single process weighted ½ instead, it differs by 8·10⁻²),
/// contacts of the slave-on-master pass change rank, and reruns give the same bits.
#[test]
fn a_balanced_pair_across_ranks_equals_the_single_process() {
    for ranks in [1, 2, 4] {
        let line = run_case(ranks, Some("balanced"));
        let active = count_before(&line, " slaves in contact");
        assert!(active > 40, "{line}");
        if ranks == 4 {
            assert!(!line.contains(" 0 hand-overs"), "{line}");
            let again = run_case(ranks, Some("balanced"));
            assert_eq!(
                checksum(&line),
                checksum(&again),
                "reruns with {ranks} ranks"
            );
        }
    }
}

/// `abut run` (this build, with the `mpi` feature) on `scene` into `out` on the CPU path:
/// alone (`ranks` 0), or under `mpirun -n ranks`. Returns its stderr; panics when it fails.
fn abut_run(scene: &Path, out: &Path, ranks: usize) -> String {
    abut_run_on(scene, out, ranks, None)
}

/// [`abut_run`] on the GPU adapter of `gpu` (a wgpu backend name: every rank takes one of
/// that backend), or on the CPU path.
fn abut_run_on(scene: &Path, out: &Path, ranks: usize, gpu: Option<&str>) -> String {
    let exe = env!("CARGO_BIN_EXE_abut");
    let mut cmd = if ranks == 0 {
        Command::new(exe)
    } else {
        let mut c = mpirun_command();
        c.args(["--allow-run-as-root", "--oversubscribe", "-n"])
            .arg(ranks.to_string())
            .arg(exe);
        c
    };
    if let Some(b) = gpu {
        cmd.env("WGPU_BACKEND", b);
    }
    let o = cmd
        .arg("run")
        .arg(scene)
        .args(["--backend", if gpu.is_some() { "gpu" } else { "cpu" }])
        .arg("--output")
        .arg(out)
        .output()
        .expect("abut runs");
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        o.status.success(),
        "abut run {} with {ranks} ranks: {}\n{}\n{err}",
        scene.display(),
        o.status,
        String::from_utf8_lossy(&o.stdout)
    );
    err
}

/// What describes the run rather than its results: where, how long, how it was split.
const RUN_ONLY: [&str; 10] = [
    "device",
    "built",
    "warnings",
    "first_increment_seconds",
    "seconds_per_increment",
    "dispatches_per_increment",
    "uploaded_bytes_per_increment",
    "read_back_bytes_per_increment",
    "global_searches",
    "ranks",
];

/// Whether summary values `a` and `b` agree: integers and strings exactly, each number to
/// `tol` of the larger of itself and `scale` (a list of numbers: its largest entry; a curve
/// sample's or the final contact force: the peak force).
fn agree(a: &Value, b: &Value, scale: f64, tol: f64, path: &str, peak: f64) -> Vec<String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut bad = Vec::new();
            for (k, v) in x {
                if RUN_ONLY.contains(&k.as_str()) {
                    continue;
                }
                let s = if k == "force" && v.is_array() || k == "final_contact_force" {
                    peak
                } else if k == "energy_balance_error" {
                    // a fraction of the energies' scale already: compared in those units
                    1.0
                } else {
                    0.0
                };
                bad.extend(agree(v, &y[k], s, tol, &format!("{path}.{k}"), peak));
            }
            bad
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return vec![format!("{path}: {} entries against {}", x.len(), y.len())];
            }
            let big = x
                .iter()
                .chain(y)
                .filter_map(Value::as_f64)
                .fold(scale, |m, v| m.max(v.abs()));
            x.iter()
                .zip(y)
                .enumerate()
                .flat_map(|(i, (p, q))| agree(p, q, big, tol, &format!("{path}[{i}]"), peak))
                .collect()
        }
        (Value::Number(p), Value::Number(q)) if p.is_f64() || q.is_f64() => {
            let (p, q) = (p.as_f64().unwrap(), q.as_f64().unwrap());
            if (p - q).abs() <= tol * p.abs().max(q.abs()).max(scale) {
                Vec::new()
            } else {
                vec![format!("{path}: {p:e} against {q:e}")]
            }
        }
        _ if a == b => Vec::new(),
        _ => vec![format!("{path}: {a} against {b}")],
    }
}

/// Every history cell agrees to `tol` of its column's largest magnitude (the balance error, a
/// fraction of the energies' scale already, to `tol` of 1).
fn same_history(a: &str, b: &str, tol: f64) -> Vec<String> {
    let balance = a
        .lines()
        .next()
        .and_then(|h| h.split(',').position(|c| c == "balance_error"));
    let rows = |t: &str| -> Vec<Vec<f64>> {
        t.lines()
            .skip(1)
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect()
    };
    let (x, y) = (rows(a), rows(b));
    if x.len() != y.len() || a.lines().next() != b.lines().next() {
        return vec![format!("{} rows against {}", x.len(), y.len())];
    }
    let mut bad = Vec::new();
    for c in 0..x.first().map_or(0, Vec::len) {
        let floor: f64 = if Some(c) == balance { 1.0 } else { 0.0 };
        let big = x.iter().chain(&y).fold(floor, |m, r| m.max(r[c].abs()));
        for (i, (p, q)) in x.iter().zip(&y).enumerate() {
            if (p[c] - q[c]).abs() > tol * big {
                bad.push(format!("row {i}, column {c}: {} against {}", p[c], q[c]));
            }
        }
    }
    bad
}

fn read(dir: &Path) -> (Value, String) {
    let s = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json written");
    let h = std::fs::read_to_string(dir.join("history.csv")).expect("history.csv written");
    (serde_json::from_str(&s).unwrap(), h)
}

/// A scene under `abut run` across 1, 2 and 4 ranks against the single process: the summary
/// and the history agree to `tol`; a rerun with 2 ranks gives the same history bytes. Returns
/// the 4-rank summary.
fn scene_across_ranks(scene: &Path, name: &str, tol: f64) -> Value {
    scene_across(scene, name, tol, &[1, 2, 4])
}

/// As [`scene_across_ranks`], at each of `rank_counts` ranks.
fn scene_across(scene: &Path, name: &str, tol: f64, rank_counts: &[usize]) -> Value {
    scene_across_calls(scene, name, tol, rank_counts, 7.0..8.0)
}

/// As [`scene_across`], with `calls` the range the collectives per increment must fall in.
fn scene_across_calls(
    scene: &Path,
    name: &str,
    tol: f64,
    rank_counts: &[usize],
    calls_per_increment: std::ops::Range<f64>,
) -> Value {
    let base = std::env::temp_dir().join(format!("abut-mpi-{}-{name}", std::process::id()));
    let one = base.join("single");
    abut_run(scene, &one, 0);
    let (single, history) = read(&one);
    let peak = single["peak_force"].as_f64().unwrap_or(0.0);
    let mut last = Value::Null;
    for &ranks in rank_counts {
        let dir = base.join(format!("ranks{ranks}"));
        abut_run(scene, &dir, ranks);
        let (s, h) = read(&dir);
        let mut bad = agree(&single, &s, 0.0, tol, "", peak);
        bad.extend(same_history(&history, &h, tol));
        assert!(bad.is_empty(), "{name}, {ranks} ranks:\n{}", bad.join("\n"));
        let split = s["ranks"].as_array().expect("the ranks' account");
        assert_eq!(split.len(), ranks, "{name}");
        // 7 collectives per increment between distributed global searches (the contact's 4,
        // the solver's agreement, the halo, the sums; 18 before issue 34), a search adding 3
        // and an output row 1: the same count on every rank
        let calls = split[0]["collectives_per_increment"].as_f64().unwrap();
        assert!(
            calls_per_increment.contains(&calls),
            "{name}, {ranks} ranks: {calls}"
        );
        for r in split {
            assert_eq!(
                r["collectives_per_increment"].as_f64(),
                Some(calls),
                "{name}"
            );
        }
        if ranks == 2 {
            let again = base.join("again");
            abut_run(scene, &again, 2);
            assert_eq!(read(&again).1, h, "{name}: a rerun with 2 ranks");
        }
        last = s;
    }
    let _ = std::fs::remove_dir_all(&base);
    last
}

fn scenes() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Issue 18's scene across ranks: scenes/mesh_drop.toml (a Gmsh box of 984 tetrahedra dropped
/// on an Abaqus deck's base with friction) run by `abut run` under `mpirun -n 1, 2, 4` writes
/// the summary and history of the single process (the contact's f32 round-off aside: 1e-6 of
/// each quantity's scale); every rank computes elements and exchanges halo and contact state.
#[test]
fn a_mesh_drop_across_ranks_gives_the_single_process_summary() {
    let s = scene_across_ranks(&scenes().join("mesh_drop.toml"), "mesh-drop", 1e-6);
    for r in s["ranks"].as_array().unwrap() {
        assert!(r["own_nodes"].as_u64().unwrap() > 0, "{r}");
        assert!(
            r["elements"].as_u64().unwrap() > 0 || r["slaves"] == 0,
            "{r}"
        );
    }
    let halo: f64 = s["ranks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["halo_bytes_per_increment"].as_f64().unwrap())
        .sum();
    assert!(halo > 0.0, "the box is cut between ranks: {s}");
}

/// The incline of VERIFICATION §4 (a block sliding 1.6 m down a plate, friction 0.2, 7,278
/// increments): the slaves' facets pass from rank to rank, and the summary is the single
/// process's.
#[test]
fn a_block_sliding_across_ranks_gives_the_single_process_summary() {
    scene_across_ranks(&scenes().join("incline.toml"), "incline", 1e-6);
}

/// A 2D scene across ranks (issue 34): segments as master facets, each rank's local model a 2D
/// one. The Hertz cylinder's first 8 s (VERIFICATION §3: a graded plane-strain half-space
/// pressed onto a fixed rigid arc of 120 segments) is the single process's to 10⁻¹²: the same
/// arithmetic, energies summed in rank order (the energy balance error, a difference of
/// energies, to 10⁻¹² of their scale).
#[test]
fn a_two_d_scene_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-2d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(scenes().join("hertz_cylinder.toml"))
        .unwrap()
        .replace("end_time = 40.0", "end_time = 8.0");
    assert!(text.contains("end_time = 8.0"));
    let hertz = dir.join("hertz_cylinder.toml");
    std::fs::write(&hertz, text).unwrap();
    let s = scene_across_ranks(&hertz, "hertz-cylinder", 1e-12);
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene's text with `edits` (from, to) made, each exactly once, written to `dir/name`.
fn edited_scene(dir: &Path, scene: &str, name: &str, edits: &[(&str, &str)]) -> std::path::PathBuf {
    let mut text = std::fs::read_to_string(scenes().join(scene)).unwrap();
    for (from, to) in edits {
        assert_eq!(text.matches(from).count(), 1, "{scene}: {from}");
        text = text.replacen(from, to, 1);
    }
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Rigid bodies moving at a set velocity across ranks (issue 34): every rank moves each body
/// alike and carries its own nodes of it, rank 0 counts its kinetic energy, each rank the
/// contact forces on its own nodes; the body's columns in the history and its summary are the
/// single process's. In 2D, the axisymmetric Hertz sphere pushed in for 4 time units on a
/// coarser mesh, at 1, 2 and 4 ranks to 10⁻⁶ (measured: the contact the same bits, the energies
/// summed in rank order). In 3D, the block drop with its plate driven up into the falling block
/// at 0.5 m/s, at 1 and 2 ranks to 10⁻⁵ (measured 7·10⁻¹⁰ since every rank searches in the
/// single process's frame): a moving master is searched globally at other increments across
/// ranks (a node's absolute motion triggers a distributed global search, one process's is
/// relative to the master), and a global and a local search find the same facet with
/// last-bit different projections. At 4 ranks the impact carries that round-off into the
/// contact-limited increment, and the run drifts to 5·10⁻⁵ in time and 3·10⁻³ in the force
/// curve by the end of contact (docs/BENCHMARKS.md).
#[test]
fn a_rigid_body_at_a_set_velocity_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-bodies-{}", std::process::id()));
    let plate = edited_scene(
        &dir,
        "block_drop.toml",
        "moving_plate.toml",
        &[(
            "divisions = [30, 30, 0]",
            "divisions = [30, 30, 0]\nmotion = \"velocity\"\nvelocity = [0.0, 0.0, 0.5]\nmass = 1.0e3",
        )],
    );
    let s = scene_across(&plate, "moving-plate", 1e-5, &[1, 2]);
    let body = &s["bodies"][0];
    assert!(
        (body["velocity"][2].as_f64().unwrap() - 0.5).abs() < 1e-12,
        "{s}"
    );
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let sphere = edited_scene(
        &dir,
        "hertz_sphere.toml",
        "hertz_sphere.toml",
        &[
            ("end_time = 20.0", "end_time = 4.0"),
            ("divisions = [79, 79, 0]", "divisions = [24, 24, 0]"),
            ("grading_core = [22, 22, 1]\n", ""),
        ],
    );
    let s = scene_across_ranks(&sphere, "hertz-sphere", 1e-6);
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Small and infinitesimal sliding across ranks (issue 34): each slave is anchored once, by
/// the rank that owns it, and keeps its anchor through every rebuild of that rank's local
/// model (the anchored facets stay among its ghosts). The block drop with the block moved
/// over the plate's free edge (136 of its 289 bottom nodes project onto no facet: the warning
/// and the list are the single process's), small sliding and no stated radius (the anchoring
/// reaches every facet, so the first local models hold the whole plate); then infinitesimal
/// sliding with a radius of 0.02 (distributed global searches every few increments). At 1, 2
/// and 4 ranks to 10⁻¹²: the contact the same bits, the energies summed in rank order.
#[test]
fn small_sliding_across_ranks_keeps_each_anchor_through_the_rebuilds() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-small-{}", std::process::id()));
    let overhang = edited_scene(
        &dir,
        "block_drop.toml",
        "small_sliding.toml",
        &[
            ("friction = 0.3", "friction = 0.3\nsliding = \"small\""),
            ("origin = [0.0, 0.0, 0.001]", "origin = [0.75, 0.0, 0.001]"),
            ("end_time = 0.15", "end_time = 0.06"),
        ],
    );
    let s = scene_across_ranks(&overhang, "small-sliding", 1e-12);
    assert_eq!(s["anchored_slaves"], 153, "{s}");
    let warned = s["warnings"].as_array().unwrap().iter().any(|w| {
        w.as_str()
            .unwrap()
            .starts_with("contact pair 0: 136 of 289 slave nodes project onto no master facet")
    });
    assert!(warned, "{s}");
    assert_eq!(s["unanchored_slaves"].as_array().unwrap().len(), 136, "{s}");
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let tight = edited_scene(
        &dir,
        "block_drop.toml",
        "infinitesimal_sliding.toml",
        &[(
            "friction = 0.3",
            "friction = 0.3\nsliding = \"infinitesimal\"\nsearch_radius = 0.02",
        )],
    );
    let s = scene_across_ranks(&tight, "infinitesimal-sliding", 1e-12);
    assert_eq!(s["anchored_slaves"], 289, "{s}");
    for r in s["ranks"].as_array().unwrap() {
        // the local model rebuilt after the first, its anchors carried over
        assert!(r["contact_rebuilds"].as_u64().unwrap() >= 2, "{r}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Kinematic contact against analytical surfaces across ranks (issue 34): each rank corrects
/// its own slaves, and the sums over a pair's pushed slaves (the body's generalized mass and
/// the push on it) run over every rank's, gathered and taken in the pair's slave order, so
/// every rank moves the body alike. The Hertz impact's first 4 time units (a free rigid sphere
/// dropped on a half-space of tetrahedra, VERIFICATION §2), and the block drop onto a rigid
/// plane moving up at 0.2 m/s, at 1, 2 and 4 ranks to 10⁻¹²: the same arithmetic, the
/// energies summed in rank order. 11 collectives per increment: the scene's 3 without penalty
/// contact, the agreement on the predicted state, 2 per correction pass (3 passes) and the
/// largest overclosure.
#[test]
fn kinematic_contact_against_analytical_surfaces_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-analytical-{}", std::process::id()));
    let impact = edited_scene(
        &dir,
        "hertz_impact.toml",
        "hertz_impact.toml",
        &[("end_time = 16.0", "end_time = 4.0")],
    );
    let s = scene_across_calls(&impact, "hertz-impact", 1e-12, &[1, 2, 4], 11.0..12.0);
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let sphere = &s["bodies"][0];
    assert!(
        sphere["velocity"][2].as_f64().unwrap() > -0.01,
        "slowed by the contact: {s}"
    );
    let plane = edited_scene(
        &dir,
        "block_drop.toml",
        "rigid_plane.toml",
        &[
            (
                "[[part]]\nname = \"plate\"\nshape = \"plate\"\norigin = [-0.25, -0.25, 0.0]\n\
                 size = [1.5, 1.5, 0.0]\ndivisions = [30, 30, 0]\n",
                "[[rigid]]\nname = \"plate\"\nsurface = \"plane\"\npoint = [0.0, 0.0, 0.0]\n\
                 direction = [0.0, 0.0, 1.0]\nmass = 1.0e3\nmotion = \"velocity\"\n\
                 velocity = [0.0, 0.0, 0.2]\n",
            ),
            (
                "master_face = \"z+\"\nfriction = 0.3\n",
                "enforce = \"kinematic\"\n",
            ),
        ],
    );
    let s = scene_across_calls(&plane, "rigid-plane", 1e-12, &[1, 2, 4], 11.0..12.0);
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Kinematic pairs across ranks (issue 34): each rank corrects its own slaves, their facet
/// nodes' shares of each resisting force (and of friction's velocity changes) are summed on
/// the nodes' owners in the pair's slave order — one process's order — and sent back to the
/// ranks holding them as ghosts, and hard contact is corrected again on the corrected
/// geometry with the ghosts' corrected state. The two-bar impact (VERIFICATION §1: at 2 ranks
/// the slave's bar on one rank and its master node on the other) and the block drop made
/// kinematic with its friction of 0.3 (12 ms: 289 slaves in contact at the end), made a
/// balanced kinematic pair, and made a small-sliding one, at 1, 2 and 4 ranks to 10⁻¹²: the
/// same arithmetic, the energies summed in rank order.
#[test]
fn kinematic_pairs_across_ranks_give_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-kinematic-{}", std::process::id()));
    // the bars: 3 scene collectives, the corrector's agreement, the ghosts' predicted state,
    // 4 per pass (the shares there and back, the corrected ghosts), the last agreement; the
    // distributed contact's 4 (and 3 at its global searches)
    let s = scene_across_calls(
        &scenes().join("bar_impact.toml"),
        "bar-impact",
        1e-12,
        &[1, 2, 4],
        21.0..23.0,
    );
    assert!(s["peak_force"].as_f64().unwrap() > 0.3, "{s}");
    let block = edited_scene(
        &dir,
        "block_drop.toml",
        "kinematic_drop.toml",
        &[
            ("friction = 0.3", "friction = 0.3\nenforce = \"kinematic\""),
            ("end_time = 0.15", "end_time = 0.012"),
        ],
    );
    // and friction: its velocity changes there and back, the ghosts' state before it
    let s = scene_across_calls(&block, "kinematic-drop", 1e-12, &[1, 2, 4], 24.0..27.0);
    assert_eq!(s["contact_nodes"].as_array().unwrap().len(), 289, "{s}");
    assert!(s["frictional_dissipation"].as_f64().unwrap() > 0.0, "{s}");
    // balanced (frictionless): the plate's nodes against the block's bottom too, each pass
    // summed on the owners, the two corrections weighted as in one process
    let balanced = edited_scene(
        &dir,
        "block_drop.toml",
        "balanced_kinematic_drop.toml",
        &[
            ("friction = 0.3", "enforce = \"kinematic\"\nbalanced = 0.5"),
            ("end_time = 0.15", "end_time = 0.012"),
        ],
    );
    let s = scene_across_calls(
        &balanced,
        "balanced-kinematic",
        1e-12,
        &[1, 2, 4],
        29.0..32.0,
    );
    assert_eq!(s["contact_nodes"].as_array().unwrap().len(), 289, "{s}");
    // small sliding (the block over the plate's free edge: 136 slaves anchored), one
    // correction on the anchors' planes, the anchors kept through the local models' rebuilds
    let anchored = edited_scene(
        &dir,
        "block_drop.toml",
        "small_sliding_kinematic.toml",
        &[
            (
                "friction = 0.3",
                "enforce = \"kinematic\"\nsliding = \"small\"",
            ),
            ("end_time = 0.15", "end_time = 0.03"),
            ("origin = [0.0, 0.0, 0.001]", "origin = [0.75, 0.0, 0.001]"),
        ],
    );
    let s = scene_across_calls(&anchored, "small-kinematic", 1e-12, &[1, 2, 4], 12.0..15.0);
    assert_eq!(s["anchored_slaves"], 136, "{s}");
    assert!(!s["contact_nodes"].as_array().unwrap().is_empty(), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The start's overclosure adjustment across ranks (`run.adjust_overclosure`): every rank
/// moves the whole model's overclosed slaves as one process does, then keeps its own and halo
/// nodes. The block drop started 2 mm into the plate (289 slaves moved, the warning the single
/// process's), at 1, 2 and 4 ranks to 10⁻¹².
#[test]
fn the_overclosure_adjustment_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-adjusted-{}", std::process::id()));
    let sunk = edited_scene(
        &dir,
        "block_drop.toml",
        "sunk.toml",
        &[
            (
                "end_time = 0.15",
                "end_time = 0.03\nadjust_overclosure = true",
            ),
            ("origin = [0.0, 0.0, 0.001]", "origin = [0.0, 0.0, -0.002]"),
        ],
    );
    let s = scene_across_ranks(&sunk, "adjusted", 1e-12);
    let warned = s["warnings"].as_array().unwrap().iter().any(|w| {
        w.as_str().unwrap().starts_with(
            "289 slave nodes started overclosed and were moved onto their masters strain-free",
        )
    });
    assert!(warned, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A free rigid body of mesh nodes across ranks (issue 34): its resultants — contact, loads and
/// the kinematic corrections of its nodes, taken as impulses — gathered as per-node rows from
/// every rank and summed in the body's node order, as one process sums them; every rank moves
/// the body alike. The block drop with its plate made a free body of 1,000 kg (both fall; the
/// block, thrown down, hits the plate) under kinematic contact with friction, at 1, 2 and 4
/// ranks to 10⁻¹². 29 collectives per increment: the kinematic pair's 25, and two gathers
/// (counts and rows): the contact forces' and loads' resultants together, then the kinematic
/// impulses' (31 when each resultant had its own).
#[test]
fn a_free_meshed_rigid_body_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-free-body-{}", std::process::id()));
    let free = edited_scene(
        &dir,
        "block_drop.toml",
        "free_plate_kinematic.toml",
        &[
            (
                "divisions = [30, 30, 0]",
                "divisions = [30, 30, 0]\nmotion = \"free\"\nmass = 1.0e3",
            ),
            ("friction = 0.3", "friction = 0.3\nenforce = \"kinematic\""),
            ("end_time = 0.15", "end_time = 0.012"),
        ],
    );
    let s = scene_across_calls(&free, "free-body", 1e-12, &[1, 2, 4], 28.0..31.0);
    let plate = &s["bodies"][0];
    assert!(plate["velocity"][2].as_f64().unwrap() < 0.0, "falling: {s}");
    assert!(!s["contact_nodes"].as_array().unwrap().is_empty(), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A balanced pair in a scene: the mesh drop with `balanced = 0.5` (the base's nodes against
/// the box's bottom too, on their owners): the summary is the single process's.
#[test]
fn a_balanced_mesh_drop_across_ranks_gives_the_single_process_summary() {
    let text = std::fs::read_to_string(scenes().join("mesh_drop.toml"))
        .unwrap()
        .replace("friction = 0.3", "friction = 0.3\nbalanced = 0.5")
        .replace(
            "\"meshes/",
            &format!("\"{}/", scenes().join("meshes").display()),
        );
    assert!(text.contains("balanced = 0.5"));
    let dir = std::env::temp_dir().join(format!("abut-mpi-{}-balanced", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("balanced_drop.toml");
    std::fs::write(&scene, text).unwrap();
    scene_across_ranks(&scene, "balanced-drop", 1e-6);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A free rigid body of mesh nodes under penalty contact across ranks (issue 34): every rank
/// follows the whole body from its nodes' positions (placed from the body's state, the same on
/// every rank), so each rank's springs on it see the whole body's mass and inertia at the
/// contact point as one process's do; the body's row of the stable-increment bound is summed
/// over the ranks (in the block drop it governs: each of 2 ranks saw half of it). The block drop with its plate made a free body of 1,000 kg (3D, 12 ms), and
/// the Hertz sphere's arc set free (2D), at 1, 2 and 4 ranks to 10⁻⁶: a master node's force is
/// one fixed-point sum over its springs in one process, and a sum of each rank's share (in that
/// rank's scale) here, which the body's resultant carries — f32 round-off of the springs, as in
/// the mesh drop, whose master is deformable. 9 collectives per increment: penalty's 7 and one
/// gather (counts and rows) of the body's contact and load resultants.
#[test]
fn a_free_meshed_rigid_body_under_penalty_across_ranks_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-{}-free-penalty", std::process::id()));
    let free = edited_scene(
        &dir,
        "block_drop.toml",
        "free_plate.toml",
        &[
            (
                "divisions = [30, 30, 0]",
                "divisions = [30, 30, 0]\nmotion = \"free\"\nmass = 1.0e3",
            ),
            ("end_time = 0.15", "end_time = 0.012"),
        ],
    );
    let s = scene_across_calls(&free, "free-plate-penalty", 1e-5, &[1, 2, 4], 9.0..10.0);
    let plate = &s["bodies"][0];
    assert!(
        plate["velocity"][2].as_f64().unwrap() < 0.0,
        "pushed down: {s}"
    );
    assert!(!s["contact_nodes"].as_array().unwrap().is_empty(), "{s}");
    // in 2D too: the Hertz sphere's arc set free (4 time units on a coarser mesh)
    let free_arc = edited_scene(
        &dir,
        "hertz_sphere.toml",
        "free_arc.toml",
        &[
            ("motion = \"velocity\"", "motion = \"free\""),
            ("end_time = 20.0", "end_time = 4.0"),
            ("divisions = [79, 79, 0]", "divisions = [24, 24, 0]"),
            ("grading_core = [22, 22, 1]\n", ""),
        ],
    );
    let s = scene_across_calls(&free_arc, "free-arc-penalty", 1e-5, &[1, 2, 4], 9.0..10.0);
    assert!(!s["contact_nodes"].as_array().unwrap().is_empty(), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stable increment of a master node whose springs are on several ranks (issue 34): the
/// block drop onto a light elastic slab (20 kg/m³, 6 × 6 elements under the block's 16 × 16
/// bottom nodes), whose master nodes each carry some 16 springs from slaves on both sides of the
/// ranks' cuts. A master node's row of the node-wise bound is the sum of its springs' shares;
/// each rank's local contact sees only its own springs', so the ranks holding a node send their
/// shares to its owner, which adds them. Measured: with the rows summed the summary is within
/// 10⁻⁸ of the single process at 2 and 4 ranks; with each rank's share alone (before) the
/// contact's increment came out 4·10⁻⁴ larger than one process's, the force 10⁻⁵ off.
#[test]
fn a_master_node_row_summed_over_ranks_gives_the_single_process_increment() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-{}-slab", std::process::id()));
    let slab = edited_scene(
        &dir,
        "block_drop.toml",
        "light_slab.toml",
        &[
            ("end_time = 0.15", "end_time = 0.012"),
            (
                "[[part]]\nname = \"block\"",
                "[[material]]\nname = \"foil\"\nyoung = 1.0e7\npoisson = 0.3\ndensity = 20.0\n\n\
                 [[part]]\nname = \"block\"",
            ),
            (
                "shape = \"plate\"\norigin = [-0.25, -0.25, 0.0]\nsize = [1.5, 1.5, 0.0]\n\
                 divisions = [30, 30, 0]",
                "shape = \"block\"\nmaterial = \"foil\"\norigin = [-0.25, -0.25, -0.05]\n\
                 size = [1.5, 1.5, 0.05]\ndivisions = [6, 6, 1]",
            ),
        ],
    );
    let s = scene_across(&slab, "light-slab", 1e-6, &[1, 2, 4]);
    assert!(s["peak_force"].as_f64().unwrap() > 0.0, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every rank on a GPU adapter: the mesh drop under `mpirun -n 2` with each rank's search and
/// penalty on the adapter (lavapipe, llvmpipe's GL), and the block drop made kinematic (each
/// rank's kinematic search on the adapter, 12 ms), give the summary and history of a single
/// process on the same adapter.
#[test]
fn a_mesh_drop_across_ranks_on_each_gpu_backend_gives_the_single_process_summary() {
    let dir = std::env::temp_dir().join(format!("abut-mpi-gpu-scenes-{}", std::process::id()));
    let kinematic = edited_scene(
        &dir,
        "block_drop.toml",
        "kinematic_drop.toml",
        &[
            ("friction = 0.3", "friction = 0.3\nenforce = \"kinematic\""),
            ("end_time = 0.15", "end_time = 0.012"),
        ],
    );
    for d in common::gpus() {
        let backend = d.backend_name();
        let backend = backend.as_str();
        for scene in [scenes().join("mesh_drop.toml"), kinematic.clone()] {
            let base =
                std::env::temp_dir().join(format!("abut-mpi-{}-gpu-{backend}", std::process::id()));
            abut_run_on(&scene, &base.join("single"), 0, Some(backend));
            abut_run_on(&scene, &base.join("ranks2"), 2, Some(backend));
            let (single, history) = read(&base.join("single"));
            let (split, h) = read(&base.join("ranks2"));
            assert!(
                split["device"].as_str().unwrap().contains(backend),
                "{backend}: {}",
                split["device"]
            );
            let peak = single["peak_force"].as_f64().unwrap();
            assert!(peak > 0.0, "{backend}: no contact");
            let mut bad = agree(&single, &split, 0.0, 1e-6, "", peak);
            bad.extend(same_history(&history, &h, 1e-6));
            let name = scene.display();
            assert!(
                bad.is_empty(),
                "{backend}, {name}, 2 ranks:\n{}",
                bad.join("\n")
            );
            let _ = std::fs::remove_dir_all(&base);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A node past its pair's search radius within one increment (the mesh drop's box thrown at
/// 3 km/s) stops the run with the single process's tunnelling error — the same node, pair and
/// count — and no rank is left waiting.
#[test]
fn tunnelling_across_ranks_stops_the_run_with_the_single_process_error() {
    let text = std::fs::read_to_string(scenes().join("mesh_drop.toml"))
        .unwrap()
        .replace(
            "velocity = [0.0, 0.0, -0.5]",
            "velocity = [0.0, 0.0, -3000.0]",
        )
        .replace(
            "\"meshes/",
            &format!("\"{}/", scenes().join("meshes").display()),
        );
    assert!(text.contains("-3000.0"));
    let dir = std::env::temp_dir().join(format!("abut-mpi-{}-fast", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("fast_drop.toml");
    std::fs::write(&scene, text).unwrap();
    let run = |ranks: usize| {
        let exe = env!("CARGO_BIN_EXE_abut");
        let mut cmd = if ranks == 0 {
            Command::new(exe)
        } else {
            mpirun_command()
        };
        if ranks > 0 {
            cmd.args(["--allow-run-as-root", "--oversubscribe", "-n"])
                .arg(ranks.to_string())
                .arg(exe);
        }
        let o = cmd
            .arg("run")
            .arg(&scene)
            .args(["--backend", "cpu"])
            .output()
            .unwrap();
        assert!(!o.status.success());
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let single = run(0);
    let line = single
        .lines()
        .find(|l| l.contains("tunnelling"))
        .unwrap_or_else(|| panic!("{single}"))
        .to_string();
    for ranks in [2, 4] {
        let err = run(ranks);
        // (mpirun stops the other ranks once one has failed, so not every rank's line need
        // come out; that the run ends at all shows that none was left waiting. Two ranks'
        // lines may interleave at the "abut: " prefix, written apart from the message: the
        // message itself is looked for)
        let message = line.trim_start_matches("abut: ");
        assert!(
            err.contains(message),
            "{ranks} ranks: the single process's error ({line}):\n{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Facets that stretch widen the ghost margin: a plate stretched tenfold arrives under a strip
/// of slaves that then lie in the middle of one 2 m facet, its nodes beyond the margin of the
/// start's facet size — every node's force equals the single process's at 1, 2 and 4 ranks
/// (with the start's margin the slaves' rank loses that facet and the example fails).
#[test]
fn a_stretching_master_stays_in_contact_across_ranks() {
    for ranks in [1, 2, 4] {
        let line = run_case(ranks, Some("stretch"));
        let active = count_before(&line, " slaves in contact");
        assert!(active >= 10, "{line}");
    }
}
