//! Counts past 65,536 in one place (DESIGN.md convention 13): Mesa's software adapters stop a
//! shader loop silently after 65,535 iterations, so no kernel may loop over a count the data can
//! make large. Each case here puts more than that many items where a loop once went over them
//! all, and checks the GPU adapters against the CPU path and against the physics (momentum).

mod common;

use abut::mesh::SplitMix64;
use abut::*;
use common::{devices, gpus, Both};

/// One quad master facet (the unit square at z = 0, normal +z, corner masses 1e3) and `n`
/// slave nodes scattered over it, each `depth` below it: every slave is in contact with the one
/// facet. Frictionless, linear penalty of stiffness `k`.
fn one_facet(n: usize, depth: f64, k: f64) -> Model {
    let mut m = Model::new_3d();
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    m.add_nodes(&corners, &[1e3; 4]).unwrap();
    let s = m.add_surface(Surface::quads(&[[0, 1, 2, 3]])).unwrap();
    let mut rng = SplitMix64::new(n as u64);
    let slaves: Vec<[f64; 3]> = (0..n)
        .map(|_| [rng.range(0.01, 0.99), rng.range(0.01, 0.99), -depth])
        .collect();
    let r = m.add_nodes(&slaves, &vec![1.0; n]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.5)
            .enforce(Enforce::Penalty(Penalty {
                stiffness: Stiffness::Absolute(k),
                ..Default::default()
            })),
    )
    .unwrap();
    m
}

/// `n` slaves on one facet: the master nodes take the whole reaction (Σ over every node is zero
/// to f32 round-off of the total action), the forces match the CPU path's, and two identical
/// increments give the same bits.
fn slaves_on_one_facet(n: usize) {
    let depth = 1e-2;
    let k = 2.0;
    let m = one_facet(n, depth, k);
    let x = m.positions().to_vec();
    let v = vec![[0.0; 3]; x.len()];
    let mut reference: Option<Vec<[f64; 3]>> = None;
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        let first = c.penalty_step(&x, &v, 1e-6).unwrap().clone();
        let second = c.penalty_step(&x, &v, 1e-6).unwrap().clone();
        assert_eq!(first.active, n, "{d}: every slave in contact");
        // the slaves' action: k·depth each along +z (gaps in f32 in the grid's frame)
        let action: f64 = first.forces[4..].iter().map(|f| f[2]).sum();
        let expected = n as f64 * k * depth;
        assert!(
            (action - expected).abs() <= 1e-4 * expected,
            "{d}: slave action {action} vs {expected}"
        );
        let reaction: [f64; 3] = (0..3)
            .map(|a| first.forces[..4].iter().map(|f| f[a]).sum())
            .collect::<Vec<f64>>()
            .try_into()
            .unwrap();
        // the master's reaction equals the slaves' action to f32 round-off
        assert!(
            (reaction[2] + action).abs() <= 1e-6 * action,
            "{d}, {n} slaves: master reaction {reaction:?} against slave action {action} \
             (fraction {})",
            -reaction[2] / action
        );
        assert!(reaction[0].abs() + reaction[1].abs() <= 1e-6 * action);
        // two identical increments: the same bits on every node
        for (i, (a, b)) in first.forces.iter().zip(&second.forces).enumerate() {
            for ax in 0..3 {
                assert_eq!(
                    a[ax].to_bits(),
                    b[ax].to_bits(),
                    "{d}: node {i} axis {ax} differs between identical increments"
                );
            }
        }
        match &reference {
            None => reference = Some(first.forces.clone()),
            Some(r) => {
                let scale = r.iter().map(|f| f[2].abs()).fold(0.0, f64::max);
                for (i, (a, b)) in first.forces.iter().zip(r).enumerate() {
                    for ax in 0..3 {
                        assert!(
                            (a[ax] - b[ax]).abs() <= 1e-5 * scale,
                            "{d}: node {i} axis {ax}: {} against the CPU path's {}",
                            a[ax],
                            b[ax]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn hundred_thousand_slaves_on_one_facet() {
    slaves_on_one_facet(100_000);
}

#[test]
fn million_slaves_on_one_facet() {
    slaves_on_one_facet(1_000_000);
}

/// The search of `slaves` (added to `m` as a node set) against surface `s` within `radius` on
/// the CPU path and every GPU adapter: each slave's nearest facet matches the brute-force f64
/// oracle's (the distance to round-off, the facet unless another is as near), the GPUs match the
/// CPU path, and two runs give the same contacts. Returns the CPU path's result.
fn searched_like_the_oracle(
    mut m: Model,
    s: SurfaceId,
    slaves: &[[f64; 3]],
    radius: f64,
    name: &str,
) -> SearchResult {
    use abut::testing::brute_force::brute_force;
    use common::{assert_same_search, tolerance};
    let r = m.add_nodes(slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(radius)).unwrap();
    let master = m.surface(s).unwrap();
    let mut cpu = Both::new(&Device::cpu(), &m, p).unwrap();
    let cpu_r = cpu.run(m.positions()).unwrap();
    let tol = tolerance(&cpu_r, radius);
    // the oracle (f64, every facet): the nearest distance, and the facet unless another is as
    // near within round-off (the tracked node is left to the CPU comparison: small facets in a
    // larger frame leave node-distance near-ties to f32)
    let oracle = brute_force(master, m.positions(), &r.to_vec(), radius);
    let check_oracle = |res: &SearchResult, what: &str| {
        for (i, (h, o)) in res.contacts().zip(&oracle).enumerate() {
            let (h, o) = (h.as_ref().unwrap(), o.as_ref().unwrap());
            assert!(
                (h.distance - o.contact.distance).abs() <= tol,
                "{what}: slave {i}: distance {} vs the oracle's {}",
                h.distance,
                o.contact.distance
            );
            assert!(
                h.facet == o.contact.facet || o.second_distance - o.contact.distance <= 2.0 * tol,
                "{what}: slave {i}: facet {} but the oracle's {} is nearer",
                h.facet,
                o.contact.facet
            );
        }
    };
    check_oracle(&cpu_r, name);
    for gpu in gpus() {
        let mut search = Both::new(gpu, &m, p).unwrap();
        let r = search.run(m.positions()).unwrap();
        let what = format!("{name}, {gpu}");
        assert_same_search(&r, &cpu_r, master, m.positions(), radius, tol, &what);
        check_oracle(&r, &what);
        assert_eq!(
            r.stats.fallbacks, cpu_r.stats.fallbacks,
            "{what}: fallbacks"
        );
        let again = search.run(m.positions()).unwrap();
        assert_eq!(
            r.contacts().collect::<Vec<_>>(),
            again.contacts().collect::<Vec<_>>(),
            "{what}: two runs differ"
        );
    }
    cpu_r
}

/// 10^5 small triangles on a 0.3 × 0.3 patch searched with a radius of 1 (every facet within
/// the radius of every slave, gaps up to 40 facet sizes): each slave's nearest facet matches
/// the CPU path's and the brute-force oracle's, in a tilted and a wavy patch, with slaves over
/// the patch, over its edges and far beside it; and the walk's work follows the gap, not the
/// radius — about the same projections as with a radius just above the largest gap (within a
/// quarter: only the first facets found before the walk narrows down differ), a median of a
/// few dozen per slave, and walks cut off only where a concave fold puts many facets at nearly
/// the slave's distance.
#[test]
fn hundred_thousand_facets_within_the_radius() {
    use abut::mesh::plate_triangles;
    type Shape<'a> = (&'a str, &'a dyn Fn(f64, f64) -> f64);
    let shapes: [Shape; 2] = [
        ("tilted", &|x, y| 0.2 * x - 0.1 * y),
        ("wavy", &|x, y| 0.01 * (40.0 * x).sin() * (30.0 * y).cos()),
    ];
    for (name, shape) in shapes {
        // 224 × 224 quads, two triangles each: 100,352 facets
        let plate = plate_triangles(224, 224, 0.3, 0.3, 0.0, 0, shape);
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::triangles(&plate.facets)).unwrap();
        let mut rng = SplitMix64::new(7);
        let slaves: Vec<[f64; 3]> = (0..300)
            .map(|k| {
                let (lo, hi) = if k % 3 == 0 { (-0.2, 0.5) } else { (0.0, 0.3) };
                let (x, y) = (rng.range(lo, hi), rng.range(lo, hi));
                [x, y, shape(x, y) + rng.range(-0.05, 0.05)]
            })
            .collect();
        let wide = searched_like_the_oracle(m.clone(), s, &slaves, 1.0, name);
        let per_slave = |r: &SearchResult| -> Vec<u32> {
            r.raw
                .iter()
                .map(|h| h.candidates & abut::testing::abi::search::HIT_COUNT)
                .collect()
        };
        let mut counts = per_slave(&wide);
        counts.sort_unstable();
        let median = counts[counts.len() / 2];
        assert!(
            median < 100,
            "{name}: median {median} projections per slave"
        );
        assert!(
            (wide.stats.fallbacks as usize) * 100 <= slaves.len(),
            "{name}: {} of {} walks cut off",
            wide.stats.fallbacks,
            slaves.len()
        );
        // the slaves over the patch again, with a radius just above their largest gap
        let over: Vec<[f64; 3]> = slaves
            .iter()
            .enumerate()
            .filter(|(k, _)| k % 3 != 0)
            .map(|(_, x)| *x)
            .collect();
        let near = searched_like_the_oracle(m.clone(), s, &over, 0.06, name);
        let far = searched_like_the_oracle(m, s, &over, 1.0, name);
        let (a, b) = (near.stats.candidates as f64, far.stats.candidates as f64);
        assert!(
            b <= 1.25 * a,
            "{name}: {b} projections within a radius of 1, {a} within 0.06"
        );
    }
}

/// A slave at (or near) the centre of a sphere of 10^5 triangles is nearly as far from every
/// facet: no box can be pruned, the walk reaches its cap, and the facets it did not reach are
/// projected in chunks — past 65,536 candidates per slave. The nearest facet still matches the
/// oracle's on the CPU path and both adapters.
#[test]
fn hundred_thousand_facets_at_one_distance() {
    // a sphere of radius 1 without its polar caps: 224 rings × 224 sectors, two triangles each
    let (rings, sectors) = (224usize, 224usize);
    let mut nodes = Vec::new();
    for i in 0..=rings {
        let theta = std::f64::consts::PI * (0.1 + 0.8 * i as f64 / rings as f64);
        for j in 0..sectors {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / sectors as f64;
            nodes.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
        }
    }
    let id = |i: usize, j: usize| (i * sectors + j % sectors) as u32;
    let mut facets = Vec::new();
    for i in 0..rings {
        for j in 0..sectors {
            facets.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            facets.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mut m = Model::new_3d();
    m.add_nodes(&nodes, &vec![1.0; nodes.len()]).unwrap();
    let s = m.add_surface(Surface::triangles(&facets)).unwrap();
    let mut rng = SplitMix64::new(5);
    let mut slaves = vec![[0.0; 3]];
    slaves.extend((0..7).map(|_| {
        [
            rng.range(-1e-3, 1e-3),
            rng.range(-1e-3, 1e-3),
            rng.range(-1e-3, 1e-3),
        ]
    }));
    let r = searched_like_the_oracle(m, s, &slaves, 2.0, "sphere");
    assert_eq!(
        r.stats.fallbacks as usize,
        slaves.len(),
        "walks not cut off"
    );
    let per_slave = r.stats.candidates as f64 / slaves.len() as f64;
    assert!(
        per_slave > 65_536.0,
        "{per_slave} candidates per slave: the case needs more than 65,536"
    );
}

/// Every dispatch abut folds stays within the workgroups per dimension a device allows, and
/// covers all its items: wgpu's own check of indirect arguments is off in abut's instances
/// (`WGPU_VALIDATION_INDIRECT_CALL=1` turns it back on), so the plan's slots, folded by
/// `fold_dispatch` on the host and copied by the schedule, must be valid by construction.
#[test]
fn folded_dispatches_stay_within_the_limits() {
    use abut::testing::abi::search::fold_dispatch;
    use proptest::prelude::*;
    let check = |items: u32, per: u32, max: u32| {
        let (x, y) = fold_dispatch(items, per, max);
        assert!(
            (1..=max).contains(&x) && (1..=max).contains(&y),
            "{items} items, {per} per workgroup, at most {max}: ({x}, {y})"
        );
        let covered = x as u64 * y as u64 * per as u64;
        assert!(covered >= items as u64, "{items} items: ({x}, {y}) x {per}");
        // no more than one row of workgroups left over
        assert!((x as u64) * (y as u64 - 1) * (per as u64) < (items as u64).max(1));
    };
    for items in [0, 1, 63, 64, 65, 65_535 * 64, 65_535 * 64 + 1, u32::MAX] {
        for per in [1, 64, 256] {
            for max in [65_535, 256, 1] {
                // a device's limit cannot fold more than max² workgroups
                if items.div_ceil(per) as u64 <= max as u64 * max as u64 {
                    check(items, per, max);
                }
            }
        }
    }
    proptest!(ProptestConfig::with_cases(4000), |(items in 0u32.., per in 1u32..=1024)| {
        prop_assume!(items.div_ceil(per) as u64 <= 65_535 * 65_535);
        check(items, per, 65_535);
    });
}
