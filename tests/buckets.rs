//! The bucket search beside the tree: both structures give the same contact bit for bit (every
//! hit word but the count of facets projected), on the CPU path and every adapter, on regular and
//! irregular meshes in 2D and 3D, self-contact, far from the origin, collapsed and grown facets,
//! crowded cells; the bucket search is deterministic and GPU against the CPU mirror agrees; `Auto`
//! follows the facet sizes and the radius.

mod common;

use abut::mesh::{plate_quads, plate_triangles, point_cloud, polyline, sphere_triangles};
use abut::{Device, GlobalSearch, Model, PairId, SearchResult, SearchStructure, Surface};
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
