//! Small and infinitesimal sliding: one global search anchors each slave; afterwards no search
//! runs. The tangent plane turns with the master (small) or not (infinitesimal); load transfer
//! stays at the anchor, even for a node that slid off the master (the seed's Figure
//! 38.2.2–7), which the diagnostics report; nodes projecting onto no facet are unconstrained.

mod common;

use abut::mesh::plate_quads;
use abut::search::Trigger;
use abut::*;
use common::{devices, gpus};

fn rotate_x(p: [f64; 3], th: f64) -> [f64; 3] {
    let (s, c) = th.sin_cos();
    [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]]
}

/// A plate rotated rigidly about x with a slave attached to it: the small-sliding plane turns
/// with it (the gap stays), the infinitesimal one keeps its orientation (the gap changes).
#[test]
fn the_small_sliding_plane_follows_a_rotating_master_the_infinitesimal_one_does_not() {
    for sliding in [Sliding::Small, Sliding::Infinitesimal] {
        let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        let r = m.add_nodes(&[[0.3, 0.6, 0.05]], &[1.0]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        let p = m
            .add_pair(Pair::new(set, s).search_radius(0.2).sliding(sliding))
            .unwrap();
        for d in devices() {
            let mut search = GlobalSearch::new(&d, &m, p).unwrap();
            let first = search.step(m.positions()).unwrap();
            assert_eq!(first.stats.trigger, Trigger::First);
            for k in 1..=10 {
                let th = 0.05 * k as f64;
                let x: Vec<[f64; 3]> = m.positions().iter().map(|q| rotate_x(*q, th)).collect();
                let r = search.step(&x).unwrap();
                assert_eq!(
                    r.stats.trigger,
                    Trigger::Anchored,
                    "{d}: no search after the first"
                );
                assert_eq!(r.stats.candidates, 0, "{d}: no facet examined");
                let c = r.contact(0).unwrap();
                let expect_normal = rotate_x([0.0, 0.0, 1.0], th);
                match sliding {
                    Sliding::Small => {
                        assert!(
                            (c.gap - 0.05).abs() < 1e-5,
                            "{d}: small: gap {} after turning {th}",
                            c.gap
                        );
                        assert!(
                            (0..3).all(|a| (c.normal[a] - expect_normal[a]).abs() < 1e-5),
                            "{d}: normal {:?}",
                            c.normal
                        );
                    }
                    _ => {
                        assert!(
                            c.normal == [0.0, 0.0, 1.0],
                            "{d}: infinitesimal: normal {:?}",
                            c.normal
                        );
                        let exact =
                            rotate_x([0.3, 0.6, 0.05], th)[2] - rotate_x([0.3, 0.6, 0.0], th)[2];
                        assert!(
                            (c.gap - exact).abs() < 1e-5,
                            "{d}: infinitesimal gap {} vs {exact}",
                            c.gap
                        );
                    }
                }
            }
        }
    }
}

/// The seed's Figure 38.2.2–7: a slave anchored at the middle of facet 201–202 slides off the
/// master; it keeps loading nodes 201 and 202 equally, and the diagnostic counts it.
#[test]
fn a_node_sliding_off_keeps_loading_its_anchor_facet_and_is_reported() {
    let mut m = Model::new_2d();
    // master: three segments, normals up; the middle one (nodes 1, 2) plays 201–202
    m.add_nodes_2d(&[[3.0, 0.0], [2.0, 0.0], [1.0, 0.0], [0.0, 0.0]], &[1.0; 4])
        .unwrap();
    let s = m
        .add_surface(Surface::segments(&[[0, 1], [1, 2], [2, 3]]))
        .unwrap();
    let r = m.add_nodes_2d(&[[1.5, -0.01]], &[1.0]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Absolute(100.0),
        ..Default::default()
    };
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.5)
            .sliding(Sliding::Small)
            .enforce(Enforce::Penalty(pen)),
    )
    .unwrap();
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        c.request_outputs(true);
        let v = vec![[0.0; 3]; m.positions().len()];
        let mut x = m.positions().to_vec();
        for k in 0..=40 {
            x[4][0] = 1.5 + 0.1 * k as f64; // slides to x = 5.5, far off the master's end at 3
            let rep = c.penalty_step(&x, &v, 1e-3).unwrap().clone();
            let f = 100.0 * 0.01;
            assert!(
                (rep.forces[4][1] - f).abs() < 1e-4,
                "{d} k={k}: slave force {:?}",
                rep.forces[4]
            );
            assert!(
                (rep.forces[1][1] + 0.5 * f).abs() < 1e-4
                    && (rep.forces[2][1] + 0.5 * f).abs() < 1e-4,
                "{d} k={k}: nodes 201, 202 share the load equally: {:?}",
                &rep.forces[..4]
            );
            assert!(
                rep.forces[0][1].abs() < 1e-9 && rep.forces[3][1].abs() < 1e-9,
                "{d}: the other nodes get nothing"
            );
            let out = c.outputs()[0].1.clone();
            let stats = out.search.unwrap().stats;
            assert_eq!(
                stats.slid_too_far,
                (x[4][0] - 1.5 > 1.0) as u32,
                "{d} k={k}: slid {} (element length 1)",
                x[4][0] - 1.5
            );
        }
    }
}

/// Slaves beyond the master's free edge project onto no facet: no anchor, no constraint.
#[test]
fn nodes_outside_the_masters_projection_are_unconstrained() {
    let plate = plate_quads(2, 2, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    // inside (penetrating), beyond the edge x = 1 (below the plane's extension), on a ridge-free corner
    let r = m
        .add_nodes(
            &[[0.5, 0.5, -0.01], [1.05, 0.5, -0.01], [-0.02, -0.02, -0.01]],
            &[1.0; 3],
        )
        .unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Absolute(100.0),
        ..Default::default()
    };
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.3)
            .sliding(Sliding::Small)
            .enforce(Enforce::Penalty(pen)),
    )
    .unwrap();
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        let v = vec![[0.0; 3]; m.positions().len()];
        for _ in 0..3 {
            let rep = c.penalty_step(m.positions(), &v, 1e-3).unwrap();
            let n = plate.positions.len();
            assert!(
                (rep.forces[n][2] - 1.0).abs() < 1e-4,
                "{d}: the inside node is pushed: {:?}",
                rep.forces[n]
            );
            assert_eq!(
                rep.forces[n + 1],
                [0.0; 3],
                "{d}: beyond the free edge: unconstrained"
            );
            assert_eq!(
                rep.forces[n + 2],
                [0.0; 3],
                "{d}: beyond the corner: unconstrained"
            );
        }
    }
}

/// GPU against CPU: anchored contact points and penalty forces on a deforming master, and
/// kinematic small sliding keeps the slave on the anchor's plane.
#[test]
fn anchored_parity_and_kinematic_small_sliding() {
    let plate = plate_quads(10, 10, 1.0, 1.0, 0.2, 3, &|x, y| 0.02 * (x + y));
    let cloud = abut::mesh::point_cloud(500, [0.1, 0.1, -0.01], [0.9, 0.9, 0.03], 4);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m
        .add_pair(Pair::new(set, s).search_radius(0.2).sliding(Sliding::Small))
        .unwrap();
    let at = |k: usize| -> Vec<[f64; 3]> {
        m.positions()
            .iter()
            .map(|q| {
                [
                    q[0] + 0.002 * k as f64 * q[1],
                    q[1],
                    q[2] + 0.01 * (k as f64 * 0.3).sin() * q[0],
                ]
            })
            .collect()
    };
    let run = |d: &Device| -> Vec<abut::SearchResult> {
        let mut search = GlobalSearch::new(d, &m, p).unwrap();
        (0..12).map(|k| search.step(&at(k)).unwrap()).collect()
    };
    let cpu = run(&Device::cpu());
    for g in gpus() {
        for (a, b) in run(g).iter().zip(&cpu) {
            for (x, y) in a.contacts().zip(b.contacts()) {
                match (x, y) {
                    (Some(x), Some(y)) => {
                        assert_eq!(x.facet, y.facet, "{g}: anchors are fixed");
                        assert!(
                            (x.gap - y.gap).abs() < 1e-5,
                            "{g}: gap {} vs {}",
                            x.gap,
                            y.gap
                        );
                    }
                    (None, None) => {}
                    _ => panic!("{g}: anchored on one side only"),
                }
            }
        }
    }
    // kinematic: a slave slid off its anchor facet is still held on the anchor's plane
    let mut mk = Model::new_2d();
    mk.add_nodes_2d(&[[1.0, 0.0], [0.0, 0.0]], &[1e6, 1e6])
        .unwrap();
    let sk = mk.add_surface(Surface::segments(&[[0, 1]])).unwrap();
    let rk = mk.add_nodes_2d(&[[0.5, 0.02]], &[1.0]).unwrap();
    let setk = mk.add_node_set(&rk.to_vec()).unwrap();
    mk.add_pair(
        Pair::new(setk, sk)
            .search_radius(0.5)
            .sliding(Sliding::Small)
            .enforce(Enforce::Kinematic(Kinematic::default())),
    )
    .unwrap();
    for d in devices() {
        let mut c = Contact::new(&d, &mk).unwrap();
        let mut x = mk.positions().to_vec();
        let mut v = vec![[0.0; 3]; x.len()];
        c.kinematic_step(&mut x, &mut v, &mut [], 1e-3).unwrap();
        x[2] = [2.5, -0.05, 0.0]; // far beyond the segment's end, below its line
        let rep = c.kinematic_step(&mut x, &mut v, &mut [], 1e-3).unwrap();
        assert_eq!(rep.active, 1, "{d}");
        assert!(
            x[2][1].abs() < 1e-6,
            "{d}: put back on the anchor's plane: {:?}",
            x[2]
        );
    }
}

/// The diagnostic of planes that stopped representing the master: an infinitesimal plane
/// under a master turned 17°, and a small-sliding plane on a master folded about its anchor
/// facet; a small-sliding plane under a rigid rotation stays fine.
#[test]
fn planes_that_stop_representing_the_master_are_reported() {
    let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    for (sliding, fold, expect) in [
        (Sliding::Infinitesimal, false, 1u32),
        (Sliding::Small, false, 0),
        (Sliding::Small, true, 1),
    ] {
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        // on the shared edge x = 0.5 between two facets
        let r = m.add_nodes(&[[0.5, 0.4, 0.01]], &[1.0]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        let p = m
            .add_pair(Pair::new(set, s).search_radius(0.2).sliding(sliding))
            .unwrap();
        for d in devices() {
            let mut search = GlobalSearch::new(&d, &m, p).unwrap();
            search.step(m.positions()).unwrap();
            let x: Vec<[f64; 3]> = m
                .positions()
                .iter()
                .map(|q| {
                    if fold {
                        // the half x > 0.5 folds up by 40° about the line x = 0.5
                        if q[0] > 0.5 {
                            [
                                0.5 + (q[0] - 0.5) * 40f64.to_radians().cos(),
                                q[1],
                                (q[0] - 0.5) * 40f64.to_radians().sin() + q[2],
                            ]
                        } else {
                            *q
                        }
                    } else {
                        rotate_x(*q, 0.3)
                    }
                })
                .collect();
            let r = search.step(&x).unwrap();
            assert_eq!(r.stats.plane_off, expect, "{d} {sliding:?} fold={fold}");
        }
    }
}

/// A rigid cylinder's arc (120°) over a long row of slave nodes, pressed in at the middle, the
/// arc drawn finely (facets a twentieth of the slave spacing) and coarsely (the reverse), no
/// search radius stated: with small and infinitesimal sliding every slave whose normal meets
/// the arc is anchored however far it starts (up to a whole radius away: hundreds of fine
/// facets), the slaves beyond the arc's ends are named, the counts are reported
/// (`Contact::anchoring`, `StepReport::unanchored`), and the forces equal finite sliding's.
#[test]
fn every_slave_that_projects_is_anchored_however_far() {
    use abut::mesh::arc_segments;
    // pressed in by less than a fine facet's length: within finite sliding's default radius
    let delta = 0.001;
    let centre = [0.0, 1.0 - delta, 0.0];
    for (segments, n_slaves) in [(1200usize, 61usize), (24, 601)] {
        let arc = arc_segments(
            centre,
            1.0,
            210f64.to_radians(),
            330f64.to_radians(),
            segments,
            1.0,
        );
        let xs: Vec<f64> = (0..n_slaves)
            .map(|k| -2.4 + 4.8 * k as f64 / (n_slaves - 1) as f64)
            .collect();
        // the f64 expectation: a slave is left out when its nearest point on the arc is one of
        // the arc's two end nodes (beyond the free ends)
        let ends = [arc.positions[0], arc.positions[segments]];
        let beyond: Vec<bool> = xs
            .iter()
            .map(|&x| {
                let p = [x, 0.0];
                let mut best = (f64::INFINITY, false);
                for s in &arc.facets {
                    let (a, b) = (arc.positions[s[0] as usize], arc.positions[s[1] as usize]);
                    let ab = [b[0] - a[0], b[1] - a[1]];
                    let t = (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1])
                        / (ab[0] * ab[0] + ab[1] * ab[1]))
                        .clamp(0.0, 1.0);
                    let q = [a[0] + t * ab[0], a[1] + t * ab[1]];
                    let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                    let at_end = ends
                        .iter()
                        .any(|e| (e[0] - q[0]).abs() + (e[1] - q[1]).abs() < 1e-12);
                    if d < best.0 - 1e-12 {
                        best = (d, at_end);
                    }
                }
                best.1
            })
            .collect();
        let expected_out = beyond.iter().filter(|&&b| b).count();
        assert!(
            expected_out > 0 && expected_out < n_slaves / 2,
            "the case needs slaves on both sides of the arc's ends: {expected_out}"
        );
        for d in devices() {
            let mut forces: Vec<Vec<[f64; 3]>> = Vec::new();
            for sliding in [Sliding::Finite, Sliding::Small, Sliding::Infinitesimal] {
                let mut m = Model::new_2d();
                let arc2: Vec<[f64; 2]> = arc.positions.iter().map(|p| [p[0], p[1]]).collect();
                m.add_nodes_2d(&arc2, &vec![1e6; arc2.len()]).unwrap();
                let s = m.add_surface(Surface::segments(&arc.facets)).unwrap();
                let row: Vec<[f64; 2]> = xs.iter().map(|&x| [x, 0.0]).collect();
                let r = m.add_nodes_2d(&row, &vec![1.0; row.len()]).unwrap();
                let set = m.add_node_set(&r.to_vec()).unwrap();
                m.add_pair(
                    Pair::new(set, s)
                        .sliding(sliding)
                        .enforce(Enforce::Penalty(Penalty {
                            stiffness: Stiffness::Absolute(1e3),
                            ..Default::default()
                        })),
                )
                .unwrap();
                let mut c = Contact::new(&d, &m).unwrap();
                let v = vec![[0.0; 3]; m.positions().len()];
                let rep = c.penalty_step(m.positions(), &v, 1e-4).unwrap().clone();
                let what = format!("{segments} segments, {n_slaves} slaves, {sliding:?}, {d}");
                assert!(rep.active > 0, "{what}: nothing in contact");
                let anchoring = c.anchoring();
                if sliding == Sliding::Finite {
                    assert!(anchoring.is_empty(), "{what}: {anchoring:?}");
                    assert_eq!(rep.unanchored, 0, "{what}");
                } else {
                    assert_eq!(anchoring.len(), 1, "{what}");
                    let a = &anchoring[0];
                    let out: Vec<u32> = (0..n_slaves)
                        .filter(|&k| beyond[k])
                        .map(|k| r.start + k as u32)
                        .collect();
                    assert_eq!(a.unanchored, out, "{what}: the slaves left out");
                    assert_eq!(a.anchored, n_slaves - out.len(), "{what}");
                    assert_eq!(a.slaves, n_slaves, "{what}");
                    assert_eq!(rep.unanchored, out.len(), "{what}: the report");
                }
                forces.push(rep.forces.clone());
            }
            let scale = forces[0]
                .iter()
                .flatten()
                .fold(0.0f64, |x, f| x.max(f.abs()));
            assert!(scale > 0.0);
            for (k, f) in forces.iter().enumerate().skip(1) {
                for (i, (a, b)) in forces[0].iter().zip(f).enumerate() {
                    for ax in 0..3 {
                        assert!(
                            (a[ax] - b[ax]).abs() <= 1e-5 * scale,
                            "{segments} segments, {d}: sliding {k}, node {i}: {a:?} finite, {b:?}"
                        );
                    }
                }
            }
        }
    }
}
