//! The bucket search beside the tree: both structures give the same contact bit for bit (every
//! hit word but the count of facets projected), on the CPU path and every adapter: meshes in 3D
//! at several radii, self-contact tracked over increments, facets grown past their cells, a
//! crowded cell, more than 65,536 slaves with folded dispatches; the bucket search is
//! deterministic and agrees with the CPU mirror; `Auto` takes the tree. (Every search parity,
//! precision, tie, far-from-origin, collapsed-facet and bounded-work test also runs both
//! structures: `common::Both`.)

mod common;

use abut::mesh::{plate_quads, plate_triangles, point_cloud, sphere_triangles};
use abut::{
    Device, GlobalSearch, Model, Pair, PairId, Schedule, SearchResult, SearchStructure, Surface,
};
use common::*;

/// Runs the search of `pair` with `structure` on `device` at the model's positions, or at
/// `moved` when given.
fn run_with(
    device: &Device,
    model: &Model,
    pair: PairId,
    structure: SearchStructure,
    moved: Option<&[[f64; 3]]>,
) -> SearchResult {
    let mut s = GlobalSearch::new(device, model, pair).unwrap();
    s.set_search_structure(structure);
    assert_eq!(s.search_structure(), structure);
    s.run(moved.unwrap_or(model.positions())).unwrap()
}

/// Both structures on every device (the CPU path first): the same hits but for the count,
/// bit for bit; each adapter's bucket search against the CPU path's within round-off, and
/// run twice with the same bytes. Returns the CPU path's bucket result.
fn check(model: &Model, pair: PairId, moved: Option<&[[f64; 3]]>, what: &str) -> SearchResult {
    let p = model.pair(pair).unwrap();
    let master = model.surface(p.master).unwrap();
    let radius = p.search_radius.unwrap();
    let positions = moved.unwrap_or(model.positions());
    let mut cpu = None;
    for device in devices() {
        let tree = run_with(&device, model, pair, SearchStructure::Tree, moved);
        let buckets = run_with(&device, model, pair, SearchStructure::Buckets, moved);
        assert_same_contacts(
            &tree,
            &buckets,
            &format!("{what} on {device}: tree vs buckets"),
        );
        let again = run_with(&device, model, pair, SearchStructure::Buckets, moved);
        assert_eq!(
            again.raw, buckets.raw,
            "{what} on {device}: not deterministic"
        );
        assert_eq!(again.stats.candidates, buckets.stats.candidates);
        match &cpu {
            None => cpu = Some(buckets),
            Some(c) => {
                let tol = tolerance(c, radius);
                assert_same_search(
                    &buckets,
                    c,
                    master,
                    positions,
                    radius,
                    tol,
                    &format!("{what}: buckets on {device} vs CPU"),
                );
                assert_eq!(
                    buckets.stats.fallbacks, c.stats.fallbacks,
                    "{what}: {device}"
                );
            }
        }
    }
    let cpu = cpu.unwrap();
    assert!(
        cpu.contacts().flatten().count() > cpu.len() / 10,
        "{what}: too few contacts to be a test"
    );
    cpu
}

#[test]
fn quads_and_triangles_3d() {
    let wave = |x: f64, y: f64| 0.05 * (6.0 * x).sin() * (4.0 * y).cos();
    let plate = plate_quads(60, 50, 1.0, 1.0, 0.0, 1, &wave);
    let slaves = point_cloud(20_000, [-0.05, -0.05, -0.06], [1.05, 1.05, 0.06], 7);
    for radius in [0.01, 0.02, 0.05] {
        let (m, p) = scene(
            3,
            &plate.positions,
            Surface::quads(&plate.facets),
            &slaves,
            radius,
        );
        check(&m, p, None, &format!("wavy quads, radius {radius}"));
    }
    let plate = plate_triangles(40, 30, 1.2, 1.0, 0.3, 3, &|x, y| {
        0.1 * (3.0 * x + 2.0 * y).sin()
    });
    let slaves = point_cloud(20_000, [-0.1, -0.1, -0.15], [1.3, 1.1, 0.15], 8);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::triangles(&plate.facets),
        &slaves,
        0.06,
    );
    check(&m, p, None, "irregular triangles");
    let s = sphere_triangles(24, 48, 1.0, [0.5, -0.25, 2.0]);
    let slaves = point_cloud(10_000, [-0.8, -1.55, 0.7], [1.8, 1.05, 3.3], 10);
    let (m, p) = scene(3, &s.positions, Surface::triangles(&s.facets), &slaves, 0.2);
    check(&m, p, None, "sphere");
}

/// Self-contact over device-resident penalty increments: a sheet folded over itself, every
/// node a slave of its own surface, moving; the pair with the buckets gives the tree's forces
/// bit for bit and the same statistics but the fallbacks — the same global searches among
/// them, so the crowding check (which asks for the next one) agrees.
#[test]
fn self_contact_tracked_over_increments() {
    use abut::testing::abi::stats::IncrementStats;
    use abut::{Contact, Enforce, Penalty, Stiffness};
    let plate = plate_quads(40, 8, 2.0, 0.4, 0.0, 0, &|_, _| 0.0);
    // the right half folded back over the left, 0.03 above it
    let folded: Vec<[f64; 3]> = plate
        .positions
        .iter()
        .map(|p| {
            if p[0] > 1.0 {
                let t = ((p[0] - 1.0) * std::f64::consts::PI / 0.06).min(std::f64::consts::PI);
                let beyond = (p[0] - 1.06).max(0.0);
                [
                    1.0 + 0.015 * t.sin() - beyond,
                    p[1],
                    0.015 * (1.0 - t.cos()),
                ]
            } else {
                *p
            }
        })
        .collect();
    let n = folded.len();
    let model = |structure| {
        let mut m = Model::new_3d();
        let nodes = m.add_nodes(&folded, &vec![1.0; n]).unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        let set = m.add_node_set(&nodes.to_vec()).unwrap();
        let pair = Pair::new(set, s)
            .search_radius(0.12)
            .search_structure(structure)
            .schedule(Schedule {
                interval: 1000,
                ..Schedule::default_for(true)
            })
            .enforce(Enforce::Penalty(Penalty {
                stiffness: Stiffness::Absolute(50.0),
                ..Default::default()
            }));
        m.add_pair(pair).unwrap();
        m
    };
    // the upper sheet pressed down through the lower one, everything sliding a little
    let state = |k: usize| {
        let x: Vec<[f64; 3]> = folded
            .iter()
            .zip(&plate.positions)
            .enumerate()
            .map(|(i, (p, flat))| {
                let s = 1e-3 * k as f64;
                let down = if flat[0] > 1.06 { 6.0 * s } else { 0.0 };
                [p[0] + s * ((i * 7) % 5) as f64, p[1], p[2] - down]
            })
            .collect();
        (x, vec![[0.0, 0.0, -0.1]; n])
    };
    for d in devices() {
        let runs: Vec<_> = [SearchStructure::Tree, SearchStructure::Buckets]
            .map(|st| {
                let m = model(st);
                let mut c = Contact::new(&d, &m).unwrap();
                resident_run(&d, &mut c, n, 10, &state, 1e-4)
            })
            .into_iter()
            .collect();
        let mut searches = 0;
        for (k, (t, b)) in runs[0].iter().zip(&runs[1]).enumerate() {
            assert_eq!(t.0, b.0, "{d}: increment {k}: forces");
            let mut st: [IncrementStats; 2] = [
                bytemuck::pod_read_unaligned(&t.1[..std::mem::size_of::<IncrementStats>()]),
                bytemuck::pod_read_unaligned(&b.1[..std::mem::size_of::<IncrementStats>()]),
            ];
            for s in &mut st {
                s.fallbacks = 0;
            }
            assert_eq!(st[0], st[1], "{d}: increment {k}: statistics");
            searches += st[0].global_searches;
        }
        let loaded = runs[0]
            .iter()
            .flat_map(|r| &r.0)
            .filter(|f| f[2] != 0.0)
            .count();
        assert!(
            loaded > 100,
            "{d}: too few contact forces ({loaded}): not a test"
        );
        assert!(
            searches >= 3,
            "{d}: {searches} global searches: never crowded, not a test"
        );
    }
}

/// Facets that grew beyond their cells after the pair was made (the plate stretched threefold)
/// go to the last bucket, which every walk visits: the same contacts.
#[test]
fn grown_facets_in_the_last_bucket() {
    let plate = plate_quads(30, 30, 1.0, 1.0, 0.1, 5, &|x, y| 0.02 * (5.0 * x + y).sin());
    let slaves = point_cloud(5_000, [0.0, 0.0, -0.05], [3.0, 1.0, 0.05], 17);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.05,
    );
    let mut moved = m.positions().to_vec();
    let n_plate = plate.positions.len();
    for x in &mut moved[..n_plate] {
        x[0] *= 3.0;
    }
    check(&m, p, Some(&moved), "stretched plate");
}

/// A cell crowded past the walks' visit cap (3,600 small facets inside one large facet's cell):
/// the slaves there fall back to every facet in chunks, with the tree's contacts.
#[test]
fn a_crowded_cell_falls_back_to_chunks() {
    let small = plate_quads(60, 60, 0.05, 0.05, 0.0, 0, &|_, _| 0.0);
    let mut positions = small.positions.clone();
    let mut facets: Vec<[u32; 4]> = small.facets.clone();
    // one large facet beside them, which sizes the cells
    let base = positions.len() as u32;
    positions.extend([
        [0.1, 0.0, 0.0],
        [1.1, 0.0, 0.0],
        [1.1, 1.0, 0.0],
        [0.1, 1.0, 0.0],
    ]);
    facets.push([base, base + 1, base + 2, base + 3]);
    let slaves = point_cloud(2_000, [0.0, 0.0, -0.01], [0.05, 0.05, 0.01], 23);
    let (m, p) = scene(3, &positions, Surface::quads(&facets), &slaves, 0.01);
    let r = check(&m, p, None, "crowded cell");
    assert!(r.stats.fallbacks > 0, "no walk was cut off: not a test");
    assert_eq!(r.stats.structure, SearchStructure::Buckets);
}

/// More than 65,536 slaves with dispatches folded into 2D by a cap of 3 workgroups per
/// dimension: the same bytes as unfolded, and the tree's contacts.
#[test]
fn past_65536_slaves_folded() {
    let plate = plate_quads(100, 100, 1.0, 1.0, 0.0, 0, &|x, y| {
        0.01 * (9.0 * x * y).sin()
    });
    let slaves = point_cloud(70_000, [0.0, 0.0, -0.02], [1.0, 1.0, 0.02], 29);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.02,
    );
    for device in devices() {
        let plain = run_with(&device, &m, p, SearchStructure::Buckets, None);
        let mut both = Both::new(&device, &m, p).unwrap();
        both.set_max_workgroups_per_dim(3);
        both.run(m.positions()).unwrap();
        let folded = both.buckets.run(m.positions()).unwrap();
        assert_eq!(folded.raw, plain.raw, "{device}: folded dispatches differ");
    }
}

/// `Auto` resolves to the tree, and the statistics and the scene summary's line say which
/// structure ran.
#[test]
fn auto_takes_the_tree_and_says_so() {
    let plate = plate_quads(10, 10, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let slaves = point_cloud(100, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05], 3);
    let (m, p) = scene(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &slaves,
        0.1,
    );
    assert_eq!(m.pair(p).unwrap().search_structure, SearchStructure::Auto);
    let mut s = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    assert_eq!(s.search_structure(), SearchStructure::Tree);
    assert_eq!(
        s.run(m.positions()).unwrap().stats.structure,
        SearchStructure::Tree
    );
    let r = run_with(&Device::cpu(), &m, p, SearchStructure::Buckets, None);
    assert_eq!(r.stats.structure, SearchStructure::Buckets);
}
