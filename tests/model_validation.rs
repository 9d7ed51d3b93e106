//! Bad input gets a clear error naming the item, and nothing is added; degenerate facets are
//! reported and never searched; adjacency and nodal normals.

use abut::mesh::{plate_quads, sphere_triangles};
use abut::{Device, Error, Facet, GlobalSearch, Model, NodeSetId, Pair, Surface, SurfaceId};

fn unit_square() -> Model {
    let mut m = Model::new_3d();
    m.add_nodes(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        &[1.0; 4],
    )
    .unwrap();
    m
}

#[test]
fn non_finite_coordinates_name_node_and_axis() {
    let mut m = unit_square();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = m
            .add_nodes(&[[0.0, 0.0, 0.0], [0.0, bad, 0.0]], &[1.0, 1.0])
            .unwrap_err();
        assert!(
            matches!(
                e,
                Error::NonFiniteCoordinate {
                    node: 5,
                    axis: 1,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("node 5"), "{e}");
    }
    assert_eq!(m.positions().len(), 4, "nothing added on error");
}

#[test]
fn bad_masses_and_lengths() {
    let mut m = unit_square();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = m.add_nodes(&[[0.0; 3], [1.0; 3]], &[1.0, bad]).unwrap_err();
        assert!(matches!(e, Error::BadMass { node: 5, .. }), "{e}");
    }
    let e = m.add_nodes(&[[0.0; 3], [1.0; 3]], &[1.0]).unwrap_err();
    assert!(
        matches!(
            e,
            Error::LengthMismatch {
                expected: 2,
                got: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(matches!(m.add_nodes(&[], &[]), Err(Error::Empty { .. })));
    assert_eq!(m.masses().len(), 4);
}

#[test]
fn two_d_models_reject_z_and_3d_facets() {
    let mut m = Model::new_2d();
    let e = m
        .add_nodes(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.5]], &[1.0, 1.0])
        .unwrap_err();
    assert!(matches!(e, Error::NonPlanarNode { node: 1, .. }), "{e}");
    m.add_nodes_2d(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], &[1.0; 3])
        .unwrap();
    let e = m.add_surface(Surface::triangles(&[[0, 1, 2]])).unwrap_err();
    assert!(
        matches!(
            e,
            Error::WrongDimension {
                facet: 0,
                kind: "triangle",
                dim: 2
            }
        ),
        "{e}"
    );
    let mut m3 = unit_square();
    let e = m3.add_surface(Surface::segments(&[[0, 1]])).unwrap_err();
    assert!(matches!(e, Error::WrongDimension { dim: 3, .. }), "{e}");
}

#[test]
fn facet_indices_repeats_and_empty_surfaces() {
    let mut m = unit_square();
    let e = m
        .add_surface(Surface::quads(&[[0, 1, 2, 3], [0, 1, 2, 9]]))
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::IndexOutOfRange {
                index: 9,
                len: 4,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("facet 1"), "{e}");
    let e = m
        .add_surface(Surface::triangles(&[[0, 1, 2], [2, 3, 2]]))
        .unwrap_err();
    assert!(
        matches!(e, Error::RepeatedNode { facet: 1, node: 2 }),
        "{e}"
    );
    assert!(matches!(
        m.add_surface(Surface::quads(&[])),
        Err(Error::Empty { .. })
    ));
}

#[test]
fn degenerate_facets_are_reported_excluded_and_never_found() {
    let mut m = unit_square();
    // 4, 5: a triangle of three collinear nodes; quad 1 collapses to a line
    m.add_nodes(&[[2.0, 0.0, 0.0], [3.0, 0.0, 0.0]], &[1.0, 1.0])
        .unwrap();
    let s = m
        .add_surface(Surface::from_facets(vec![
            Facet::Quad([0, 1, 2, 3]),
            Facet::Triangle([1, 4, 5]),
            Facet::Quad([0, 1, 4, 5]),
        ]))
        .unwrap();
    let surf = m.surface(s).unwrap();
    let degenerate: Vec<u32> = surf.degenerate.iter().map(|d| d.facet).collect();
    assert_eq!(degenerate, vec![1, 2]);
    assert_eq!(surf.active, vec![0]);
    assert!(surf.facets_of_node(4).is_empty());
    // a slave right on the degenerate facets finds the nearest valid facet, never them
    let r = m
        .add_nodes(&[[2.5, 0.0, 0.0], [0.5, 0.5, 0.1]], &[1.0, 1.0])
        .unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(2.0)).unwrap();
    let res = GlobalSearch::new(&Device::cpu(), &m, p)
        .unwrap()
        .run(m.positions())
        .unwrap();
    assert_eq!(res.contact(0).unwrap().facet, 0);
    assert!((res.contact(0).unwrap().distance - 1.5).abs() < 1e-6);
    assert_eq!(res.contact(1).unwrap().facet, 0);
    // all degenerate: an error
    let e = m.add_surface(Surface::triangles(&[[1, 4, 5]])).unwrap_err();
    assert!(matches!(e, Error::AllFacetsDegenerate { count: 1 }), "{e}");
    let mut m2 = Model::new_2d();
    m2.add_nodes_2d(&[[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]], &[1.0; 3])
        .unwrap();
    let s2 = m2
        .add_surface(Surface::segments(&[[0, 1], [1, 2]]))
        .unwrap();
    assert_eq!(m2.surface(s2).unwrap().degenerate[0].facet, 0);
}

#[test]
fn node_sets_and_pairs() {
    let mut m = unit_square();
    assert!(matches!(m.add_node_set(&[]), Err(Error::Empty { .. })));
    let e = m.add_node_set(&[0, 4]).unwrap_err();
    assert!(
        matches!(e, Error::IndexOutOfRange { index: 4, .. }) && e.to_string().contains("entry 1"),
        "{e}"
    );
    assert!(matches!(
        m.add_node_set(&[1, 2, 1]),
        Err(Error::DuplicateNode { node: 1 })
    ));
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let set = m.add_node_set(&[0]).unwrap();
    assert!(matches!(
        m.add_pair(Pair::new(NodeSetId(7), s)),
        Err(Error::UnknownId {
            what: "node set",
            id: 7
        })
    ));
    assert!(matches!(
        m.add_pair(Pair::new(set, SurfaceId(3))),
        Err(Error::UnknownId {
            what: "surface",
            id: 3
        })
    ));
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            m.add_pair(Pair::new(set, s).search_radius(r)),
            Err(Error::BadParameter {
                name: "search_radius",
                ..
            })
        ));
    }
    assert!(m.pairs().is_empty());
}

#[test]
fn adjacency_and_nodal_normals() {
    let plate = plate_quads(3, 2, 3.0, 2.0, 0.0, 0, &|_, _| 0.0);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let surf = m.surface(s).unwrap();
    assert_eq!(surf.facets_of_node(0), &[0]); // corner
    assert_eq!(surf.facets_of_node(5), &[0, 1, 3, 4]); // interior node (1, 1)
    assert!(surf.nodal_normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
    assert!((surf.mean_facet_size() - 1.0).abs() < 1e-12);
    // a sphere's smoothed normals point outwards, close to radial
    let sp = sphere_triangles(12, 24, 2.0, [1.0, 2.0, 3.0]);
    let mut m = Model::new_3d();
    m.add_nodes(&sp.positions, &vec![1.0; sp.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&sp.facets)).unwrap();
    for (x, n) in sp
        .positions
        .iter()
        .zip(&m.surface(s).unwrap().nodal_normals)
    {
        let radial = [(x[0] - 1.0) / 2.0, (x[1] - 2.0) / 2.0, (x[2] - 3.0) / 2.0];
        let dot: f64 = (0..3).map(|a| radial[a] * n[a]).sum();
        assert!(dot > 0.99, "normal {n:?} at {x:?}");
    }
}
