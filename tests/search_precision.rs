//! The global search's precision cases (issue 15): a search radius far larger than the master
//! keeps the gaps exact to the master's own round-off, a node beyond f32's range is an error
//! naming it, and a master facet that collapses during the run is skipped and counted — on the
//! CPU path and on every adapter.

mod common;

use abut::mesh::{plate_quads, point_cloud, polyline};
use abut::{Device, Error, GlobalSearch, Model, PairId, SearchResult, Surface};
use common::*;

/// A warped unit plate of 8 × 8 quads at z ≈ 0 (facet size 1/8) and slaves over it and around
/// it: 400 within 0.05 of its plane, 200 from 0.3 below to 0.6 above, some beside the plate.
fn plate_scene(radius: f64, shift: [f64; 3]) -> (Model, PairId) {
    let mut plate = plate_quads(8, 8, 1.0, 1.0, 0.2, 3, &|x, y| {
        0.05 * (5.0 * x).sin() * (4.0 * y).cos()
    });
    let mut slaves = point_cloud(400, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05], 5);
    slaves.extend(point_cloud(200, [-0.3, -0.3, -0.3], [1.3, 1.3, 0.6], 4));
    for x in plate.positions.iter_mut().chain(slaves.iter_mut()) {
        for a in 0..3 {
            x[a] += shift[a];
        }
    }
    scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        radius,
    )
}

/// Every slave against the f64 oracle, within `tol` (model units).
fn check_oracle(r: &SearchResult, m: &Model, p: PairId, radius: f64, tol: f64, what: &str) {
    let pair = m.pair(p).unwrap();
    let master = m.surface(pair.master).unwrap();
    let all: Vec<usize> = (0..r.len()).collect();
    let c = assert_matches_oracle(r, master, m.positions(), radius, tol, &all, what);
    assert!(
        c.found > 100,
        "{what}: too few contacts to be a test: {c:?}"
    );
}

/// Radii of 0.5, 1, 3 and 10⁶ facet sizes (and 10⁶ model sizes), near the origin and far from
/// it: the gaps, points and distances stay within the round-off of the master's own extent
/// (32 ε_f32 × 2 model sizes), not of the radius. Before the frame came from the master's
/// extent, a radius of 10⁶ model sizes put every gap off by about 0.2.
#[test]
fn a_radius_far_beyond_the_master_keeps_the_gaps() {
    let facet = 1.0 / 8.0;
    for shift in [[0.0; 3], [3.0e3, -2.0e3, 1.0e3]] {
        for radius in [0.5 * facet, facet, 3.0 * facet, 1.0e6 * facet, 1.0e6] {
            let (m, p) = plate_scene(radius, shift);
            // the slaves reach 1.6 model sizes from the master's corner
            let tol = 32.0 * f32::EPSILON as f64 * 2.0;
            for d in devices() {
                let what = format!("radius {radius:e}, shift {shift:?}, {d}");
                let r = run(&d, &m, p);
                check_oracle(&r, &m, p, radius, tol, &what);
                let frame = r.frame;
                for a in 0..3 {
                    assert!(
                        (frame[a] - shift[a]).abs() <= 1.0,
                        "{what}: frame {frame:?} is not at the master"
                    );
                }
            }
        }
    }
}

/// A master or slave node whose coordinate is finite in f64 but beyond f32's range in the
/// search's frame (1e39, −1e39, or 1e38 on a master 1e38 away) is an error naming that node,
/// at the first search and at run time, on every device; nothing is returned.
#[test]
fn a_node_beyond_single_precision_is_named() {
    for d in devices() {
        for (node_of, value) in [("master", 1.0e39), ("master", -1.0e39), ("slave", 1.0e39)] {
            for axis in 0..3 {
                let (m, p) = plate_scene(0.2, [0.0; 3]);
                let n = if node_of == "master" { 40 } else { 81 + 17 };
                let mut pos = m.positions().to_vec();
                pos[n][axis] = value;
                let mut s = Both::new(&d, &m, p).unwrap();
                let e = s.run(&pos).unwrap_err();
                assert!(
                    matches!(e, Error::CoordinateOutOfRange { node, axis: a, .. } if node == n && a == axis),
                    "{d}: {node_of} node {n} at {value:e} on axis {axis}: {e}"
                );
                assert!(e.to_string().contains(&format!("node {n}")), "{e}");
                // after a good search too
                let mut s = Both::new(&d, &m, p).unwrap();
                s.run(m.positions()).unwrap();
                assert!(
                    s.run(&pos).is_err(),
                    "{d}: {node_of} at {value:e}, second run"
                );
            }
        }
    }
}

/// Facets that collapse during the run (a quad pressed flat to a line, a triangle's corners
/// meeting, a 2D segment's ends meeting) are skipped by the global search and counted, no slave
/// is given them or a non-unit normal, and the rest of the search is unchanged; the local
/// search passes over them too. Slaves above the collapsed facet find the next facet, as the
/// f64 oracle over the facets that remain does.
#[test]
fn facets_collapsed_at_run_time_are_skipped_and_counted() {
    // 3D: a plate of 4 × 4 quads; corner facet 0 = [0, 1, 6, 5]: its node 0 (in no other
    // facet) moved onto node 6, its opposite corner, leaves a line along the diagonal with zero
    // area, and the neighbours unchanged.
    let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let slaves = point_cloud(400, [0.0, 0.0, 0.02], [1.0, 1.0, 0.2], 9);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.5,
    );
    let mut pos = m.positions().to_vec();
    pos[0] = pos[6];
    check_collapsed(&m, p, &pos, 0, "3D quad");

    // 2D: a polyline of 8 segments; segment 3's ends meet (node 4 onto node 3)
    let line = polyline(8, 1.0, 0.0, 0, &|_| 0.0);
    let slaves2: Vec<[f64; 3]> = (0..60)
        .map(|i| [i as f64 / 59.0, 0.05 + 0.002 * i as f64, 0.0])
        .collect();
    let (m2, p2) = scene(
        2,
        &line.positions,
        Surface::segments(&line.facets),
        &slaves2,
        0.5,
    );
    let mut pos2 = m2.positions().to_vec();
    pos2[4] = pos2[3];
    check_collapsed(&m2, p2, &pos2, 3, "2D segment");
}

fn check_collapsed(m: &Model, p: PairId, pos: &[[f64; 3]], collapsed: u32, what: &str) {
    let mut reference: Option<SearchResult> = None;
    for d in devices() {
        let mut s = Both::new(&d, m, p).unwrap();
        let before = s.run(m.positions()).unwrap();
        assert_eq!(before.stats.collapsed_facets, 0, "{what}: {d}");
        assert!(
            before.contacts().flatten().any(|c| c.facet == collapsed),
            "{what}: {d}: no slave was on facet {collapsed} before it collapsed: not a test"
        );
        let r = s.run(pos).unwrap();
        assert_eq!(r.stats.collapsed_facets, 1, "{what}: {d}: counted");
        let mut found = 0;
        for c in r.contacts().flatten() {
            assert_ne!(
                c.facet, collapsed,
                "{what}: {d}: a slave was given the collapsed facet"
            );
            let n2: f64 = c.normal.iter().map(|v| v * v).sum();
            assert!(
                (n2 - 1.0).abs() < 1e-5,
                "{what}: {d}: normal {:?}",
                c.normal
            );
            found += 1;
        }
        assert!(found > 20, "{what}: {d}: {found} contacts");
        // local increments pass over it too
        for _ in 0..3 {
            let l = s.step(pos).unwrap();
            for c in l.contacts().flatten() {
                assert_ne!(c.facet, collapsed, "{what}: {d}: local search");
            }
        }
        match &reference {
            None => reference = Some(r),
            Some(cpu) => {
                let pair = m.pair(p).unwrap();
                let master = m.surface(pair.master).unwrap();
                let tol = tolerance(cpu, 0.5);
                assert_same_search(&r, cpu, master, pos, 0.5, tol, &format!("{what}: {d}"));
            }
        }
    }
}

/// One surface whose facet sizes vary a hundredfold: a warped plate of 60 × 60 quads whose
/// spacing grows geometrically from 0.002 to 0.2 along x and along y, slaves over it at gaps up
/// to three local facet sizes and beside it. Within radii of 0.5, 1 and 3 of the smallest
/// facet size, of the largest, and 10⁶ model sizes, every slave matches the f64 oracle on the
/// CPU path and every adapter, and the walk's work follows the gap: the median slave projects
/// the same few facets whatever the radius.
#[test]
fn facet_sizes_varying_a_hundredfold() {
    let n = 60usize;
    // spacing h_i = h0·q^i, q^(n−1) = 100
    let q = 100f64.powf(1.0 / (n - 1) as f64);
    let h0 = 0.002;
    let mut coord = vec![0.0];
    for i in 0..n {
        coord.push(coord[i] + h0 * q.powi(i as i32));
    }
    let span = coord[n];
    let warp = |x: f64, y: f64| 0.05 * span * (3.0 * x / span).sin() * (2.0 * y / span).cos();
    let mut nodes = Vec::new();
    for &y in &coord {
        for &x in &coord {
            nodes.push([x, y, warp(x, y)]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut quads = Vec::new();
    for j in 0..n {
        for i in 0..n {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    // slaves: over the plate at up to 3 local facet sizes, and beside it
    let mut rng = abut::mesh::SplitMix64::new(99);
    let local = |x: f64| {
        let i = coord.partition_point(|&c| c <= x).clamp(1, n) - 1;
        coord[i + 1] - coord[i]
    };
    let mut slaves: Vec<[f64; 3]> = (0..600)
        .map(|_| {
            let (x, y) = (rng.range(0.0, span), rng.range(0.0, span));
            let h = local(x).min(local(y));
            [x, y, warp(x, y) + rng.range(-3.0 * h, 3.0 * h)]
        })
        .collect();
    slaves.extend(point_cloud(100, [-0.2 * span; 3], [1.2 * span; 3], 98));
    let (hmin, hmax) = (h0, h0 * q.powi(n as i32 - 1));
    for radius in [
        0.5 * hmin,
        hmin,
        3.0 * hmin,
        0.5 * hmax,
        hmax,
        3.0 * hmax,
        1.0e6 * span,
    ] {
        let (m, p) = scene(3, &nodes, Surface::quads(&quads), &slaves, radius);
        let tol = 32.0 * f32::EPSILON as f64 * 2.0 * span;
        let mut medians = Vec::new();
        for d in devices() {
            let what = format!("radius {radius:e}, {d}");
            let r = run(&d, &m, p);
            let pair = m.pair(p).unwrap();
            let master = m.surface(pair.master).unwrap();
            let all: Vec<usize> = (0..r.len()).collect();
            let c = assert_matches_oracle(&r, master, m.positions(), radius, tol, &all, &what);
            if radius >= 3.0 * hmax {
                assert!(c.found >= 600, "{what}: too few contacts: {c:?}");
            }
            let mut counts: Vec<u32> = r
                .raw
                .iter()
                .map(|h| h.candidates & abut::testing::abi::search::HIT_COUNT)
                .collect();
            counts.sort_unstable();
            medians.push(counts[counts.len() / 2]);
        }
        assert!(
            medians.iter().all(|&m| m <= 40),
            "radius {radius:e}: median projections per slave {medians:?}"
        );
    }
}

/// The tree's boxes are 21-bit codes on a power-of-two grid around the frame reaching twice the
/// master's extent; a bound beyond it saturates, and box tests clamp the point into the grid so
/// that saturated bounds act as ±∞ (a master that travelled far since the grid was fitted: device
/// positions under a large radius, say). Here the grid is made 2^24 times too small, so that
/// every bound of every box saturates: the walks can prune nothing, run into their visit cap and
/// leave the rest to the chunks — and every hit is still the one the fitted grid gives, on the
/// CPU path and every adapter, the adapters bit for bit with the CPU mirror.
#[test]
fn box_bounds_beyond_the_box_grid_act_as_infinite() {
    use abut::device::DeviceKind;
    use abut::testing::cpu::CpuSearch;
    use abut::testing::gpu::GpuSearch;
    let facet = 1.0 / 8.0;
    let (m, p) = plate_scene(facet, [0.0; 3]);
    let search = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    let fitted = search.prepare(m.positions()).unwrap();
    let mut tiny = fitted.clone();
    tiny.params.box_margin *= 2f32.powi(-24);
    let reference = CpuSearch::default().run_prepared(&fitted).unwrap();
    let cpu = CpuSearch::default().run_prepared(&tiny).unwrap();
    let same = |a: &abut::testing::abi::search::GpuHit, b: &abut::testing::abi::search::GpuHit| {
        a.facet == b.facet
            && a.node == b.node
            && a.point_gap.map(f32::to_bits) == b.point_gap.map(f32::to_bits)
            && a.normal_dist.map(f32::to_bits) == b.normal_dist.map(f32::to_bits)
            && a.weights.map(f32::to_bits) == b.weights.map(f32::to_bits)
    };
    let found = reference.iter().filter(|h| h.facet != u32::MAX).count();
    assert!(found > 100, "too few contacts to be a test: {found}");
    let candidates = |h: &[abut::testing::abi::search::GpuHit]| -> u64 {
        h.iter()
            .map(|h| (h.candidates & abut::testing::abi::search::HIT_COUNT) as u64)
            .sum()
    };
    assert!(
        candidates(&cpu) > 10 * candidates(&reference),
        "the tiny grid pruned: {} vs {} projections",
        candidates(&cpu),
        candidates(&reference)
    );
    for (i, (a, b)) in reference.iter().zip(cpu.iter()).enumerate() {
        assert!(same(a, b), "CPU path: slave {i}: {a:?} vs {b:?}");
    }
    for gpu in gpus() {
        let DeviceKind::Gpu(ctx) = gpu.kind() else {
            continue;
        };
        let mut g = GpuSearch::new(ctx.clone()).unwrap();
        let on_fitted: Vec<_> = g.run_prepared(&fitted).unwrap().to_vec();
        let hits = g.run_prepared(&tiny).unwrap();
        assert_eq!(hits.len(), cpu.len());
        for (i, ((a, b), c)) in on_fitted
            .iter()
            .zip(hits.iter())
            .zip(cpu.iter())
            .enumerate()
        {
            // the same bits as with the fitted grid on this adapter; the same facet, node and
            // projection count as the CPU mirror (whose quads' last bits may differ)
            assert!(same(a, b), "{gpu}: slave {i}: {a:?} vs {b:?}");
            assert!(
                b.facet == c.facet && b.node == c.node && b.candidates == c.candidates,
                "{gpu}: slave {i}: {b:?} vs the CPU mirror's {c:?}"
            );
        }
    }
}
