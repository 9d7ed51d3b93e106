//! A penalty pair keeps its slaves in Morton order of their positions inside abut
//! (`SlaveOrder::Morton`, the default), and the caller never sees it: with the slave node sets
//! listed in a shuffled order, a `Contact` gives the same bits as one keeping the node set's
//! order (`SlaveOrder::Given`) — forces, reports and their warnings, every output variable and
//! contact point in the node set's order, penalty states, saved states, the anchoring report,
//! the initial-overclosure adjustment, and the device-resident forces and statistics — on the
//! CPU path and every adapter, in 2D and 3D, with friction, self-contact, a balanced pair, small
//! sliding, tributary areas given with the node set, and equally fast slaves (the first in the
//! node set is named).

mod common;

use abut::mesh::plate_quads;
use abut::*;
use common::{devices, f32r, flat_master, resident_run, unit};

/// Positions (and velocities) of increment `k`.
type Motion = dyn Fn(usize) -> Vec<[f64; 3]>;

/// A model built for one slave order, and its prescribed motion.
struct Scene {
    what: &'static str,
    model: Model,
    pair: PairId,
    at: Box<Motion>,
    vel: Box<Motion>,
    steps: usize,
}

/// `nodes` in a shuffled order (the caller's node set: nothing like space).
fn shuffled(nodes: &[u32]) -> Vec<u32> {
    let mut keyed: Vec<(u64, u32)> = nodes
        .iter()
        .map(|&n| ((unit(n as usize, 77) * 1e15) as u64, n))
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, n)| n).collect()
}

/// Penalty contact with friction.
fn penalty(pair: Pair) -> Pair {
    pair.enforce(Enforce::Penalty(Penalty {
        stiffness: Stiffness::Absolute(50.0),
        damping: 0.05,
        ..Default::default()
    }))
    .friction(Friction::coulomb(0.3))
}

/// Velocities of increment `k` (the half step before) from the positions.
fn differenced(at: &Motion, k: usize, dt: f64) -> Vec<[f64; 3]> {
    let (a, b) = (at(k.saturating_sub(1)), at(k));
    a.iter()
        .zip(&b)
        .map(|(p, q)| [0, 1, 2].map(|c| ((q[c] - p[c]) / dt) as f32 as f64))
        .collect()
}

const DT: f64 = 1.0e-3;

/// Slaves over a master plate (16×16 quads in 3D, 40 segments in 2D) closing on it at their own
/// speeds, sliding, and resting a fifth of the radius into it, while the master ripples; eight
/// more slaves far above it all move sideways at the same speed, three radii per increment
/// (equally fast: the report names the first of them in the node set). The node set lists the
/// slaves shuffled, with tributary areas of their own in 3D.
fn approach(dim: u32, order: SlaveOrder) -> Scene {
    let (mut model, master, h) = flat_master(dim);
    let radius = 1.5 * h;
    let n_master = model.positions().len();
    let side = if dim == 3 { 20 } else { 240 };
    let count = if dim == 3 { side * side } else { side };
    let up = if dim == 3 { 2 } else { 1 };
    let mut slaves = Vec::new();
    let mut motion = Vec::new();
    for i in 0..count + 8 {
        let (x, y) = if i >= count {
            (0.1 * (i - count) as f64, 0.5)
        } else if dim == 3 {
            (
                0.1 + 0.8 * (i % side) as f64 / side as f64,
                0.1 + 0.8 * (i / side) as f64 / side as f64,
            )
        } else {
            (0.1 + 0.8 * i as f64 / side as f64, 0.0)
        };
        let height = if i >= count {
            10.0
        } else {
            radius * (0.5 + 3.0 * unit(i, 1))
        };
        let closing = radius * 0.2 * unit(i, 2) * if unit(i, 3) < 0.15 { -0.5 } else { 1.0 };
        let slide = 0.3 * h * (unit(i, 4) - 0.5);
        let mut p = [x, y, 0.0];
        p[up] = height;
        if dim == 2 {
            p[2] = 0.0;
        }
        slaves.push(p);
        motion.push((closing, slide, i >= count));
    }
    let r = model.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set_nodes = shuffled(&r.to_vec());
    let set = if dim == 3 {
        let areas: Vec<f64> = set_nodes
            .iter()
            .map(|&n| h * h * (0.5 + unit(n as usize, 9)))
            .collect();
        model.add_node_set_with_areas(&set_nodes, &areas).unwrap()
    } else {
        model.add_node_set(&set_nodes).unwrap()
    };
    let pair = model
        .add_pair(penalty(Pair::new(set, master).search_radius(radius)).slave_order(order))
        .unwrap();
    let x0 = model.positions().to_vec();
    let fast = 3.0 * radius;
    let place = {
        let x0 = x0.clone();
        let motion = motion.clone();
        move |k: usize| -> Vec<[f64; 3]> {
            let t = k as f64;
            x0.iter()
                .enumerate()
                .map(|(i, p)| {
                    let mut q = *p;
                    if i < n_master {
                        q[up] = 0.002 * (7.0 * q[0] + 0.3 * t).sin();
                    } else if motion[i - n_master].2 {
                        q[0] += fast * t;
                    } else {
                        let (closing, slide, _) = motion[i - n_master];
                        q[up] = (q[up] - closing * t).max(-0.2 * radius);
                        q[0] += slide * t / 60.0;
                    }
                    f32r(q)
                })
                .collect()
        }
    };
    let at: Box<Motion> = Box::new(place.clone());
    let vel: Box<Motion> = Box::new(move |k| {
        let mut v = differenced(&place, k, DT);
        for (i, vi) in v.iter_mut().enumerate().skip(n_master) {
            if motion[i - n_master].2 {
                *vi = [fast / DT, 0.0, 0.0];
            }
        }
        v
    });
    Scene {
        what: if dim == 3 { "3D plate" } else { "2D polyline" },
        model,
        pair,
        at,
        vel,
        steps: 40,
    }
}

/// A 2×1 sheet whose right half, folded to 150°, folds over onto its left half to land a
/// twentieth of an element into it (self-contact: every node a slave of the sheet itself,
/// listed shuffled).
fn folding_sheet(order: SlaveOrder) -> Scene {
    let plate = plate_quads(24, 12, 2.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let h = 1.0 / 12.0;
    let mut model = Model::new_3d();
    let nodes = model
        .add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = model.add_surface(Surface::quads(&plate.facets)).unwrap();
    let set = model.add_node_set(&shuffled(&nodes.to_vec())).unwrap();
    let pair = model
        .add_pair(penalty(Pair::new(set, s).search_radius(1.5 * h)).slave_order(order))
        .unwrap();
    let base = model.positions().to_vec();
    let place = move |k: usize| -> Vec<[f64; 3]> {
        let th = (150.0f64 + 28.0 * k as f64 / 50.0).min(178.0).to_radians();
        base.iter()
            .map(|q| {
                if q[0] <= 1.0 {
                    *q
                } else {
                    let r = q[0] - 1.0;
                    let land = -0.05 * h * (th / std::f64::consts::PI);
                    f32r([1.0 + r * th.cos(), q[1], r * th.sin() + land])
                }
            })
            .collect()
    };
    Scene {
        what: "folding sheet (self-contact)",
        model,
        pair,
        at: Box::new(place.clone()),
        vel: Box::new(move |k| differenced(&place, k, DT)),
        steps: 60,
    }
}

/// A 10×10 plate pressed a little into a 14×14 one below it and sliding across it: a balanced
/// pair (the upper plate's nodes, listed shuffled, against the lower plate, and the lower
/// plate's nodes against the upper plate's facets) — or, with `small`, a pure small-sliding
/// pair whose slaves hang partly beyond the lower plate's edge (some unanchored).
fn plates(order: SlaveOrder, small: bool) -> Scene {
    let lower = plate_quads(14, 14, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let offset = if small { 0.45 } else { 0.2 };
    let upper = plate_quads(10, 10, 0.6, 0.6, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model
        .add_nodes(&lower.positions, &vec![2.0; lower.positions.len()])
        .unwrap();
    let master = model.add_surface(Surface::quads(&lower.facets)).unwrap();
    let up: Vec<[f64; 3]> = upper
        .positions
        .iter()
        .map(|p| [p[0] + offset, p[1] + 0.2, 0.02])
        .collect();
    let r = model.add_nodes(&up, &vec![1.0; up.len()]).unwrap();
    let first = r.to_vec()[0];
    let shifted: Vec<[u32; 4]> = upper.facets.iter().map(|f| f.map(|n| n + first)).collect();
    let top = model.add_surface(Surface::quads(&shifted)).unwrap();
    let set = model.add_node_set(&shuffled(&r.to_vec())).unwrap();
    let mut pair = penalty(Pair::new(set, master).search_radius(0.1)).slave_order(order);
    pair = if small {
        pair.sliding(Sliding::Small)
    } else {
        pair.balanced(top, 0.5)
    };
    let pair = model.add_pair(pair).unwrap();
    let n_lower = lower.positions.len();
    let base = model.positions().to_vec();
    let place = move |k: usize| -> Vec<[f64; 3]> {
        let t = k as f64;
        base.iter()
            .enumerate()
            .map(|(i, q)| {
                if i < n_lower {
                    f32r([q[0], q[1], 0.001 * (5.0 * q[1] + 0.2 * t).sin()])
                } else {
                    let z = (q[2] - 0.002 * t).max(-0.004) + 0.001 * (3.0 * q[0]).cos();
                    f32r([q[0] + 0.002 * t, q[1], z])
                }
            })
            .collect()
    };
    Scene {
        what: if small {
            "small sliding, partly beyond the master"
        } else {
            "balanced plates"
        },
        model,
        pair,
        at: Box::new(place.clone()),
        vel: Box::new(move |k| differenced(&place, k, DT)),
        steps: 40,
    }
}

fn scenes(order: SlaveOrder) -> Vec<Scene> {
    vec![
        approach(3, order),
        approach(2, order),
        folding_sheet(order),
        plates(order, false),
        plates(order, true),
    ]
}

/// The output variables of every pair with their contact points, as text (every f64 to its
/// bits: Debug prints the shortest text that reads back to the same bits).
fn outputs_of(c: &Contact) -> Vec<String> {
    c.outputs()
        .iter()
        .map(|(id, o)| {
            let search = o.search.as_ref().map(|r| {
                (
                    &r.slaves,
                    r.stats.trigger,
                    r.contacts().collect::<Vec<_>>(),
                    r.raw.iter().map(|h| h.facet).collect::<Vec<_>>(),
                )
            });
            format!(
                "{id:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {search:?}",
                o.slaves,
                o.cstatus,
                o.copen,
                o.cpress,
                o.cshear1,
                o.cshear2,
                o.normal,
                o.force,
                o.cfn,
                o.cfs,
                o.contact_energy,
                o.frictional_dissipation
            )
        })
        .collect()
}

/// Everything a caller reads from `s` run on host arrays on `d`, increment by increment.
fn host_run(d: &Device, s: &Scene) -> Vec<String> {
    let mut c = Contact::new(d, &s.model).unwrap();
    c.request_outputs(true);
    let mut seen = Vec::new();
    for k in 0..s.steps {
        let r = c.penalty_step(&(s.at)(k), &(s.vel)(k), DT).unwrap().clone();
        seen.push(format!("{k}: {r:?} {:?}", r.warnings()));
        seen.extend(outputs_of(&c));
        if k % 7 == 3 {
            seen.push(format!("{:?}", c.penalty_states(s.pair).unwrap()));
            seen.push(format!("{:?}", c.save_state().unwrap()));
            seen.push(format!("{:?}", c.anchoring()));
        }
    }
    seen
}

/// The forces and statistics of `s` run device-resident on `d`, increment by increment.
fn resident(d: &Device, s: &Scene) -> Vec<(Vec<[f32; 4]>, Vec<u8>)> {
    let mut c = Contact::new(d, &s.model).unwrap();
    let state = |k: usize| ((s.at)(k), (s.vel)(k));
    resident_run(d, &mut c, s.model.positions().len(), s.steps, &state, DT)
}

/// The initial-overclosure adjustment at the positions of the scene's last increment (slaves
/// resting in the master): the positions it leaves and its report.
fn adjusted(d: &Device, s: &Scene) -> (OverclosureReport, Vec<[f64; 3]>) {
    let mut c = Contact::new(d, &s.model).unwrap();
    let mut x = (s.at)(s.steps - 1);
    let rep = c.adjust_initial_overclosure(&mut x, &[], DT).unwrap();
    (rep, x)
}

/// Morton order inside, the node set's order outside: the same bits as keeping the node set's
/// order, everywhere the caller reads, on every device.
#[test]
fn morton_order_is_invisible_to_the_caller() {
    for (given, morton) in scenes(SlaveOrder::Given)
        .into_iter()
        .zip(scenes(SlaveOrder::Morton))
    {
        let what = given.what;
        for d in devices() {
            // the orders do differ inside (a test that could not fail otherwise)
            let set = given
                .model
                .node_set(given.model.pair(given.pair).unwrap().slave)
                .unwrap()
                .to_vec();
            let kept = |s: &Scene| Contact::new(&d, &s.model).unwrap().pass_slaves(s.pair);
            let (g, m) = (kept(&given).unwrap(), kept(&morton).unwrap());
            assert_eq!(g[0], set, "{what}: Given keeps the node set's order");
            assert_ne!(m[0], set, "{what}: Morton reorders");
            for (a, b) in g.iter().zip(&m).skip(1) {
                assert_ne!(a, b, "{what}: the balanced pass reorders too");
            }

            let (a, b) = (host_run(&d, &given), host_run(&d, &morton));
            assert_eq!(a.len(), b.len());
            assert!(
                a.iter()
                    .any(|l| l.contains("Some(Stick)") || l.contains("Some(Slip)")),
                "{what} on {d}: no contact at all"
            );
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!(x == y, "{what} on {d}: host arrays, record {k}:\n{x}\n{y}");
            }
            let (a, b) = (resident(&d, &given), resident(&d, &morton));
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!(x.0 == y.0, "{what} on {d}: resident forces, increment {k}");
                assert!(
                    x.1 == y.1,
                    "{what} on {d}: resident statistics, increment {k}"
                );
            }
            let (a, b) = (adjusted(&d, &given), adjusted(&d, &morton));
            assert_eq!(
                format!("{a:?}"),
                format!("{b:?}"),
                "{what} on {d}: initial overclosure"
            );
        }
    }
}

/// What the scenes exercise is there: equally fast slaves named, unanchored slaves reported,
/// slaves moved by the overclosure adjustment.
#[test]
fn the_scenes_reach_what_they_test() {
    let d = Device::cpu();
    let s = approach(3, SlaveOrder::Morton);
    let mut c = Contact::new(&d, &s.model).unwrap();
    let r = c.penalty_step(&(s.at)(2), &(s.vel)(2), DT).unwrap();
    assert!(r.fast_nodes >= 8, "fast slaves: {}", r.fast_nodes);
    let s = plates(SlaveOrder::Morton, true);
    let mut c = Contact::new(&d, &s.model).unwrap();
    c.penalty_step(&(s.at)(0), &(s.vel)(0), DT).unwrap();
    let a = c.anchoring();
    assert!(a[0].unanchored.len() > 3, "{a:?}");
    let (moved, _) = adjusted(&d, &approach(3, SlaveOrder::Morton));
    assert!(moved.moved.len() > 100, "{moved:?}");
}
