//! Issue 38, item 3: a run's memory does not grow with its increments. A point mass bouncing on
//! a penalty spring for 10⁶ increments, every increment an output row: the resident memory
//! after 10⁵ increments and at the end differ by less than a few megabytes (the force history
//! and the curve are bounded; `history.csv` is streamed), `summary.json` stays small, and the
//! summary's impulse is the history's, increment by increment. One test in its own process, so
//! the memory read is this run's alone.

mod common;

use abut::scene::{run_with_progress, Progress};
use abut::Device;
use common::scene_toml::{mass_on_spring, SceneToml};

/// Increments of the run.
const INCREMENTS: u64 = 1_000_000;
/// Where the first reading of the memory is taken.
const FIRST_READING: u64 = 100_000;
/// The increment, s.
const DT: f64 = 1e-3;

/// This process's resident memory, bytes (Linux: `VmRSS` in /proc/self/status).
fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let kb: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .expect("VmRSS in kB");
    kb * 1024
}

/// A unit mass bouncing on a rigid plate's penalty spring (ω = 1000 rad/s, ω·Δt = 1) under a
/// gravity of 1000 m/s², from 5 mm above it, for `INCREMENTS` increments (the last one half
/// an increment, so that round-off in the time adds none).
fn bouncing() -> SceneToml {
    let end = (INCREMENTS as f64 - 0.5) * DT;
    let title = "a point mass bouncing for a million increments";
    mass_on_spring(title, 1e6, 0.005, DT, end).run("output_every", 1)
}

#[test]
fn a_million_increments_run_in_flat_memory_with_a_bounded_summary() {
    let dir = std::env::temp_dir().join(format!("abut-long-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut readings = Vec::new();
    let mut progress = |p: &Progress| {
        if p.increment == FIRST_READING || p.increment == INCREMENTS {
            readings.push(resident_bytes());
        }
    };
    let s = run_with_progress(
        &bouncing().scene(),
        &Device::cpu(),
        Some(&dir),
        &mut progress,
    )
    .expect("the run");
    assert_eq!(s.increments as u64, INCREMENTS);
    let [first, last] = readings[..] else {
        panic!("two readings: {readings:?}")
    };
    let growth = last as f64 - first as f64;
    println!(
        "resident memory: {:.1} MB after {FIRST_READING} increments, {:.1} MB after {INCREMENTS}",
        first as f64 / 1e6,
        last as f64 / 1e6
    );
    // unbounded, the force history alone would add 14 MB and the curve over 70 MB
    assert!(growth < 8e6, "grew by {:.1} MB", growth / 1e6);
    // the curve: at most 4,096 samples, one every so many rows; the force history in blocks
    assert!(
        s.curve.len() <= 4096 && s.curve.len() >= 2048,
        "{}",
        s.curve.len()
    );
    assert_eq!(s.curve_every, 256);
    assert_eq!(s.force_history_every, 8);
    let json = std::fs::metadata(dir.join("summary.json")).unwrap().len();
    println!("summary.json: {:.2} MB", json as f64 / 1e6);
    assert!(json < 2_000_000, "summary.json is {json} bytes");
    // history.csv has every row; the impulse is its force column summed over the increments
    let history = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| h.starts_with("contact_force"))
        .expect("a contact force column");
    let (mut rows, mut impulse, mut t0) = (0u64, 0.0f64, 0.0f64);
    for line in lines {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        impulse += cells[col] * (cells[0] - t0);
        t0 = cells[0];
        rows += 1;
    }
    assert_eq!(rows, INCREMENTS);
    assert!(
        (s.impulse - impulse).abs() < 1e-6 * impulse,
        "{} against {impulse}",
        s.impulse
    );
    // a bouncing mass under gravity: the impulse carries its weight over the run
    let weight = 1000.0 * t0;
    assert!(
        (impulse / weight - 1.0).abs() < 0.01,
        "{impulse} against {weight}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
