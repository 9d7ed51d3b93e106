//! Point queries (`abut::query`): the nearest facet of a surface to arbitrary points, with the
//! signed distance and the feature (face, edge, vertex) the nearest point lies on, against the
//! f64 brute force, on the CPU path and every adapter; nodes that move between queries.

mod common;

use abut::mesh::{plate_quads, plate_triangles, point_cloud, polyline};
use abut::query::{Feature, PointQuery};
use abut::testing::brute_force::brute_force;
use abut::{Model, Surface};
use common::devices;

/// The feature of a brute-force contact from its weights (the rule `PointQuery` documents).
fn feature(weights: &[f64; 4], n: usize) -> Feature {
    let on = weights[..n].iter().filter(|w| w.abs() > 1e-9).count();
    match (n, on) {
        (_, 1) => Feature::Vertex,
        (2, _) => Feature::Face,
        (_, 2) => Feature::Edge,
        _ => Feature::Face,
    }
}

/// Every point against the f64 oracle: facet (unless tied), distance, signed distance's sign
/// (the oracle's gap), and the feature (unless the point is within round-off of another).
fn check(
    dim: u32,
    nodes: &[[f64; 3]],
    surface: Surface,
    points: &[[f64; 3]],
    radius: f64,
    what: &str,
) -> [usize; 3] {
    let mut m = if dim == 2 {
        Model::new_2d()
    } else {
        Model::new_3d()
    };
    m.add_nodes(nodes, &vec![1.0; nodes.len()]).unwrap();
    let s = m.add_surface(surface.clone()).unwrap();
    let r = m.add_nodes(points, &vec![1.0; points.len()]).unwrap();
    let master = m.surface(s).unwrap().clone();
    let oracle = brute_force(&master, m.positions(), &r.to_vec(), radius);
    let mut seen = [0usize; 3];
    for d in devices() {
        let mut q = PointQuery::new(&d, dim, nodes, surface.clone(), points.len(), radius).unwrap();
        let hits = q.query(nodes, points).unwrap();
        for (i, (h, o)) in hits.iter().zip(&oracle).enumerate() {
            let tol = 1e-5;
            match (h, o) {
                (None, None) => {}
                (Some(h), Some(o)) => {
                    let oc = &o.contact;
                    assert!(
                        (h.distance - oc.distance).abs() <= tol,
                        "{what}, {d}: point {i}: distance {} vs {}",
                        h.distance,
                        oc.distance
                    );
                    let tie = o.second_distance - oc.distance <= 2.0 * tol;
                    assert!(h.facet == oc.facet || tie, "{what}, {d}: point {i}: facet");
                    if h.facet == oc.facet {
                        let n = master.facets[oc.facet as usize].nodes().len();
                        assert_eq!(h.feature, feature(&oc.weights, n), "{what}, {d}: point {i}");
                        assert_eq!(
                            h.signed_distance < 0.0,
                            oc.gap < 0.0,
                            "{what}, {d}: point {i}: side"
                        );
                    }
                    assert!((h.signed_distance.abs() - h.distance).abs() <= 1e-12);
                    seen[h.feature as usize] += 1;
                }
                (Some(h), None) => assert!((h.distance - radius).abs() <= tol, "{what}: {i}"),
                (None, Some(o)) => {
                    assert!((o.contact.distance - radius).abs() <= tol, "{what}: {i}")
                }
            }
        }
    }
    seen
}

#[test]
fn point_queries_match_the_brute_force() {
    // a warped quad plate: points over it, beside its edges and beyond its corners
    let plate = plate_quads(12, 12, 1.0, 1.0, 0.2, 3, &|x, y| 0.1 * (3.0 * x).sin() * y);
    let points = point_cloud(1500, [-0.3, -0.3, -0.3], [1.3, 1.3, 0.4], 11);
    let seen = check(
        3,
        &plate.positions,
        Surface::quads(&plate.facets),
        &points,
        2.0,
        "quads",
    );
    assert!(
        seen.iter().all(|&n| n > 20),
        "faces, edges and vertices all met: {seen:?}"
    );
    // triangles
    let tris = plate_triangles(10, 10, 1.0, 1.0, 0.1, 5, &|x, y| 0.05 * x * y);
    let seen = check(
        3,
        &tris.positions,
        Surface::triangles(&tris.facets),
        &points,
        0.3,
        "tris",
    );
    assert!(seen.iter().all(|&n| n > 10), "{seen:?}");
    // a 2D polyline
    let line = polyline(30, 1.0, 0.01, 7, &|x| 0.1 * (6.0 * x).sin());
    let pts2: Vec<[f64; 3]> = point_cloud(800, [-0.2, -0.3, 0.0], [1.2, 0.3, 0.0], 13);
    let seen = check(
        2,
        &line.positions,
        Surface::segments(&line.facets),
        &pts2,
        1.0,
        "2D",
    );
    assert!(seen[0] > 10 && seen[2] > 10 && seen[1] == 0, "{seen:?}");
}

/// The surface's nodes move between queries (a plate translated and lifted): the hits follow.
#[test]
fn point_queries_follow_moving_nodes() {
    let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let points = [[0.3, 0.3, 0.5], [0.6, 0.2, -0.2]];
    for d in devices() {
        let mut q = PointQuery::new(
            &d,
            3,
            &plate.positions,
            Surface::quads(&plate.facets),
            2,
            1.0,
        )
        .unwrap();
        for k in 0..3 {
            let dz = 0.1 * k as f64;
            let moved: Vec<[f64; 3]> = plate
                .positions
                .iter()
                .map(|p| [p[0], p[1], p[2] + dz])
                .collect();
            let h = q.query(&moved, &points).unwrap();
            let a = h[0].unwrap();
            let b = h[1].unwrap();
            assert!((a.signed_distance - (0.5 - dz)).abs() < 1e-6, "{d}: {a:?}");
            assert!((b.signed_distance - (-0.2 - dz)).abs() < 1e-6, "{d}: {b:?}");
            assert_eq!(a.feature, Feature::Face);
        }
        assert!(
            q.query(&plate.positions[1..], &points).is_err(),
            "{d}: wrong node count"
        );
        assert!(
            q.query(&plate.positions, &points[..1]).is_err(),
            "{d}: wrong point count"
        );
    }
}
