//! Active slaves: the local increments visit only the slaves the last global search left
//! tracked — those within the tracking radius, radius + budget — and that is invisible. A slave
//! coming from beyond the radius is found the increment it comes within it (host positions,
//! device positions, the CPU path; 2D, 3D, self-contact), and the results with and without the
//! compaction (`Schedule::visit_every_slave`) are the same bits, on host arrays and in the
//! device-resident increment.

mod common;

use abut::mesh::plate_quads;
use abut::model::Schedule;
use abut::search::Trigger;
use abut::*;
use common::{devices, f32r, facet_distance, flat_master, node_buffers, resident_run, unit, vec4};

/// Positions of increment `k`.
type Motion = dyn Fn(usize) -> Vec<[f64; 3]>;

/// A model, its pair and prescribed motion.
struct Scene {
    what: &'static str,
    model: Model,
    pair: PairId,
    at: Box<Motion>,
    steps: usize,
}

/// Slaves over a master (a 16×16 quad plate in 3D, a 40-segment polyline in 2D) at heights from
/// half the radius to four radii, each closing on it at its own speed (up to a fifth of the
/// radius per increment: well within the motion budget's half of half a radius over a few
/// increments, so most approaches happen in local increments) and sliding along it; a few move
/// away. The master ripples and travels a little, so its nodes use the budget too.
fn approach(dim: u32, penalty: bool, every: bool) -> Scene {
    let (mut model, master, h) = flat_master(dim);
    let radius = 1.5 * h;
    let n_master = model.positions().len();
    let side = if dim == 3 { 24 } else { 300 };
    let count = if dim == 3 { side * side } else { side };
    let mut slaves = Vec::new();
    let mut motion = Vec::new();
    for i in 0..count {
        let (x, y) = if dim == 3 {
            (
                0.1 + 0.8 * (i % side) as f64 / side as f64,
                0.1 + 0.8 * (i / side) as f64 / side as f64,
            )
        } else {
            (0.1 + 0.8 * i as f64 / side as f64, 0.0)
        };
        let height = radius * (0.5 + 3.5 * unit(i, 1));
        let closing = radius * 0.2 * unit(i, 2) * if unit(i, 3) < 0.15 { -0.5 } else { 1.0 };
        let slide = 0.3 * h * (unit(i, 4) - 0.5);
        if dim == 3 {
            slaves.push([x, y, height]);
        } else {
            slaves.push([x, height, 0.0]);
        }
        motion.push((closing, slide));
    }
    let r = model.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = model.add_node_set(&r.to_vec()).unwrap();
    let pair = model
        .add_pair(contact(
            Pair::new(set, master).search_radius(radius),
            penalty,
            every,
            false,
        ))
        .unwrap();
    let x0 = model.positions().to_vec();
    let up = if dim == 3 { 2 } else { 1 };
    let at = move |k: usize| -> Vec<[f64; 3]> {
        let t = k as f64;
        x0.iter()
            .enumerate()
            .map(|(i, p)| {
                let mut q = *p;
                if i < n_master {
                    q[up] = 0.002 * (7.0 * q[0] + 0.3 * t).sin();
                } else {
                    let (closing, slide) = motion[i - n_master];
                    // down to a fifth of the radius below the master, then resting there
                    q[up] = (q[up] - closing * t).max(-0.2 * radius);
                    q[0] += slide * t / 60.0;
                }
                q[0] += 0.001 * t;
                f32r(q)
            })
            .collect()
    };
    Scene {
        what: if dim == 3 { "3D plate" } else { "2D polyline" },
        model,
        pair,
        at: Box::new(at),
        steps: 60,
    }
}

/// A 2×1 sheet whose right half, already folded to 150°, folds over onto its left half
/// (self-contact: every node a slave of the sheet itself), landing 0.4 h above it — or, with penalty contact, a twentieth
/// of an element into it.
fn folding_sheet(penalty: bool, every: bool) -> Scene {
    let plate = plate_quads(24, 12, 2.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let h = 1.0 / 12.0;
    let mut model = Model::new_3d();
    let nodes = model
        .add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = model.add_surface(Surface::quads(&plate.facets)).unwrap();
    let set = model.add_node_set(&nodes.to_vec()).unwrap();
    let pair = model
        .add_pair(contact(
            Pair::new(set, s).search_radius(1.5 * h),
            penalty,
            every,
            true,
        ))
        .unwrap();
    Scene {
        what: "folding sheet (self-contact)",
        at: fold(&model, penalty, h),
        model,
        pair,
        steps: 70,
    }
}

/// The same fold without self-contact: the right half's nodes are the slaves of the left
/// half's facets, and the fold line's nodes are both (slave nodes on master facets: the passes
/// that leave an untracked slave or a slave with no facet after a word must not leave these).
fn folding_halves(penalty: bool, every: bool) -> Scene {
    let plate = plate_quads(24, 12, 2.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let h = 1.0 / 12.0;
    let mut model = Model::new_3d();
    model
        .add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let x = |n: u32| plate.positions[n as usize][0];
    let left: Vec<[u32; 4]> = plate
        .facets
        .iter()
        .copied()
        .filter(|f| f.iter().all(|&n| x(n) <= 1.0))
        .collect();
    let master = model.add_surface(Surface::quads(&left)).unwrap();
    let right: Vec<u32> = (0..plate.positions.len() as u32)
        .filter(|&n| x(n) >= 1.0)
        .collect();
    let set = model.add_node_set(&right).unwrap();
    let pair = model
        .add_pair(contact(
            Pair::new(set, master).search_radius(1.5 * h),
            penalty,
            every,
            false,
        ))
        .unwrap();
    Scene {
        what: "folding halves (slaves on the master's edge)",
        at: fold(&model, penalty, h),
        model,
        pair,
        steps: 70,
    }
}

/// The 2×1 sheet's right half (x > 1), already folded to 150°, folding over its left half to
/// 178° over 50 increments (the motion budget lets a few local increments run between global
/// searches), landing 0.4 h above it — or, with penalty contact, a twentieth of an element into
/// it.
fn fold(model: &Model, penalty: bool, h: f64) -> Box<Motion> {
    let base = model.positions().to_vec();
    let land = if penalty { -0.05 * h } else { 0.4 * h };
    Box::new(move |k: usize| -> Vec<[f64; 3]> {
        let th = (150.0f64 + 28.0 * k as f64 / 50.0).min(178.0).to_radians();
        base.iter()
            .map(|q| {
                if q[0] <= 1.0 {
                    *q
                } else {
                    let r = q[0] - 1.0;
                    f32r([
                        1.0 + r * th.cos(),
                        q[1],
                        r * th.sin() + land * (th / std::f64::consts::PI),
                    ])
                }
            })
            .collect()
    })
}

/// `pair` with penalty contact and friction (or the default enforcement), its default
/// schedule visiting every slave or not.
fn contact(pair: Pair, penalty: bool, every: bool, self_contact: bool) -> Pair {
    let pair = pair.schedule(Schedule {
        visit_every_slave: every,
        ..Schedule::default_for(self_contact)
    });
    if !penalty {
        return pair;
    }
    pair.enforce(Enforce::Penalty(Penalty {
        stiffness: Stiffness::Absolute(50.0),
        damping: 0.05,
        ..Default::default()
    }))
    .friction(Friction::coulomb(0.3))
}

fn scenes(penalty: bool, every: bool) -> Vec<Scene> {
    vec![
        approach(3, penalty, every),
        approach(2, penalty, every),
        folding_sheet(penalty, every),
        folding_halves(penalty, every),
    ]
}

/// What a tracked run did against a fresh global search each increment.
#[derive(Debug, Default)]
struct Tally {
    /// Slaves the global search put within the radius.
    within: usize,
    /// Of which the tracked search missed (no facet, or one not equally near).
    missed: usize,
    /// Slaves the tracked search found in a local increment that it had not found in the
    /// increment before: arrivals from beyond the radius caught between global searches.
    arrived_locally: usize,
    locals: usize,
}

/// Runs `s` through a tracked search on `d` (positions from the host, or from a device buffer)
/// and a fresh CPU global search every increment.
fn track(d: &Device, s: &Scene, schedule: Option<Schedule>, device_positions: bool) -> Tally {
    let mut tracked = GlobalSearch::new(d, &s.model, s.pair).unwrap();
    if let Some(sc) = schedule {
        tracked.set_schedule(sc).unwrap();
    }
    let mut global = GlobalSearch::new(&Device::cpu(), &s.model, s.pair).unwrap();
    let radius = tracked.radius();
    let master = s
        .model
        .surface(s.model.pair(s.pair).unwrap().master)
        .unwrap();
    let n = s.model.positions().len();
    let buffers = device_positions.then(|| node_buffers(d, n));
    let mut t = Tally::default();
    let mut before: Vec<bool> = Vec::new();
    for k in 0..s.steps {
        let x = (s.at)(k);
        let r = match &buffers {
            // a search on device positions starts from host ones
            Some([b, _, _]) if k > 0 => {
                let (_, q) = d.wgpu().unwrap();
                q.write_buffer(b, 0, bytemuck::cast_slice(&vec4(&x)));
                tracked.step_device(b, true).unwrap()
            }
            _ => tracked.step(&x).unwrap(),
        };
        let g = global.run(&x).unwrap();
        let local = r.stats.trigger == Trigger::Local;
        t.locals += usize::from(local);
        let found: Vec<bool> = (0..r.slaves.len())
            .map(|i| r.contact(i).is_some())
            .collect();
        for (i, gc) in g.contacts().enumerate() {
            let Some(gc) = gc else { continue };
            // at the rim, f32 against f32 round-off may say either
            if gc.distance > radius * (1.0 - 1e-5) {
                continue;
            }
            t.within += 1;
            let excess = match r.contact(i) {
                Some(tc) if tc.facet == gc.facet => 0.0,
                Some(tc) => facet_distance(master, &x, r.slaves[i], tc.facet) - gc.distance,
                None => f64::INFINITY,
            };
            if excess > 1e-4 * radius {
                t.missed += 1;
                if std::env::var("ABUT_DEBUG_MISSES").is_ok() {
                    eprintln!(
                        "miss k {k} slave {i} {:?}: global {gc:?} tracked {:?} excess {excess}",
                        r.stats.trigger,
                        r.contact(i)
                    );
                }
            } else if local && !before.get(i).copied().unwrap_or(true) {
                t.arrived_locally += 1;
            }
        }
        before = found;
    }
    t
}

/// Every slave within the radius is found, in local increments too: slaves that come from
/// beyond the radius between global searches are caught the increment they arrive, on every
/// device, from host positions and from device positions, with the compaction and without.
#[test]
fn slaves_entering_the_radius_are_caught_the_increment_they_arrive() {
    for s in scenes(false, false) {
        for d in devices() {
            for every in [false, true] {
                let mut sc = GlobalSearch::new(&d, &s.model, s.pair).unwrap().schedule();
                sc.visit_every_slave = every;
                for device_positions in [false, true] {
                    if device_positions && !d.is_gpu() {
                        continue;
                    }
                    let t = track(&d, &s, Some(sc), device_positions);
                    let what = format!(
                        "{} on {d} (every slave: {every}, device positions: {device_positions})",
                        s.what
                    );
                    eprintln!("{what}: {t:?}");
                    assert!(
                        t.locals > s.steps / 3,
                        "{what}: local increments ran: {t:?}"
                    );
                    assert!(
                        t.arrived_locally > 0,
                        "{what}: slaves arrived locally: {t:?}"
                    );
                    assert!(t.within > 1000, "{what}: contacts compared: {t:?}");
                    assert_eq!(t.missed, 0, "{what}: {t:?}");
                }
            }
        }
    }
}

/// One increment of a `Contact`, as the caller sees it: forces, stable increment and count in
/// contact, and every output variable of every pair with its search's contact points.
#[derive(PartialEq, Debug)]
struct Seen {
    forces: Vec<[f64; 3]>,
    stable_dt: f64,
    active: usize,
    outputs: Vec<String>,
}

/// The output variables of a pair, with its contact points, as text (every f64 to its bits).
fn outputs_of(c: &Contact) -> Vec<String> {
    c.outputs()
        .iter()
        .map(|(name, o)| {
            let search = o.search.as_ref().map(|r| {
                (
                    r.stats.trigger,
                    r.contacts().collect::<Vec<_>>(),
                    r.stats.local_iterations,
                )
            });
            format!(
                "{name:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {search:?}",
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

/// Velocities of increment `k` (the half step before), from the positions.
fn velocities(s: &Scene, k: usize, dt: f64) -> Vec<[f64; 3]> {
    let (a, b) = ((s.at)(k.saturating_sub(1)), (s.at)(k));
    a.iter()
        .zip(&b)
        .map(|(p, q)| [0, 1, 2].map(|c| ((q[c] - p[c]) / dt) as f32 as f64))
        .collect()
}

/// With and without the compaction, a `Contact`'s increments give the same bits: forces,
/// stable increment, outputs and contact points on host arrays (every device), and forces and
/// statistics in the device-resident increment (every device).
#[test]
fn results_with_and_without_the_compaction_are_the_same_bits() {
    let dt = 1.0e-3;
    for (s, s_every) in scenes(true, false).into_iter().zip(scenes(true, true)) {
        for d in devices() {
            let host = |every: bool| -> Vec<Seen> {
                let m = if every { &s_every.model } else { &s.model };
                let mut c = Contact::new(&d, m).unwrap();
                c.request_outputs(true);
                (0..s.steps)
                    .map(|k| {
                        let r = c
                            .penalty_step(&(s.at)(k), &velocities(&s, k, dt), dt)
                            .unwrap()
                            .clone();
                        Seen {
                            forces: r.forces,
                            stable_dt: r.stable_dt,
                            active: r.active,
                            outputs: outputs_of(&c),
                        }
                    })
                    .collect()
            };
            let (on, off) = (host(false), host(true));
            assert!(
                on.iter().any(|x| x.active > 0),
                "{} on {d}: no contact at all",
                s.what
            );
            for (k, (a, b)) in on.iter().zip(&off).enumerate() {
                assert!(
                    a == b,
                    "{} on {d}: host arrays, increment {k} differ",
                    s.what
                );
            }
            let resident = |every: bool| -> Vec<(Vec<[f32; 4]>, Vec<u8>)> {
                let m = if every { &s_every.model } else { &s.model };
                let mut c = Contact::new(&d, m).unwrap();
                let state = |k: usize| ((s.at)(k), velocities(&s, k, dt));
                resident_run(&d, &mut c, m.positions().len(), s.steps, &state, dt)
            };
            let (on, off) = (resident(false), resident(true));
            for (k, (a, b)) in on.iter().zip(&off).enumerate() {
                assert!(
                    a.0 == b.0,
                    "{} on {d}: resident forces, increment {k}",
                    s.what
                );
                assert!(
                    a.1 == b.1,
                    "{} on {d}: resident statistics, increment {k}",
                    s.what
                );
            }
        }
    }
}

/// The statistics that the slave passes reduce in each workgroup before one global atomic per
/// word (the counts in contact, slipping and walked, the largest overclosure and motion, the
/// smallest increments) are the CPU path's on every device, in every increment of scenes with
/// several workgroups of slaves in 3D and 2D and with self-contact: the counts exactly, the
/// f32 extremes to 10⁻⁵ (the devices' own arithmetic), the first increment's motion (since the
/// positions the contact was made with) included. Each kind of reduction moves: slaves come
/// into contact, slip (the sliding scenes), walk, and the increments and motions change.
#[test]
fn reduced_statistics_are_the_cpu_paths_on_every_device() {
    use abut::testing::abi::stats::STATS_BYTES;
    let dt = 1.0e-3;
    let mut slipping = 0;
    let mut overclosed = false;
    for s in scenes(true, false) {
        let runs: Vec<(String, Vec<IncrementStats>)> = devices()
            .into_iter()
            .map(|d| {
                let mut c = Contact::new(&d, &s.model).unwrap();
                let state = |k: usize| ((s.at)(k), velocities(&s, k, dt));
                let run = resident_run(&d, &mut c, s.model.positions().len(), s.steps, &state, dt);
                let stats = run
                    .iter()
                    .map(|(_, st)| {
                        assert_eq!(st.len() as u64, STATS_BYTES);
                        bytemuck::pod_read_unaligned(st)
                    })
                    .collect();
                (d.to_string(), stats)
            })
            .collect();
        // devices() lists the CPU path first
        let reference = &runs[0].1;
        let sum =
            |f: fn(&IncrementStats) -> u32| reference.iter().map(|x| f(x) as u64).sum::<u64>();
        assert!(sum(|x| x.active) > 0, "{}: no contact", s.what);
        slipping += sum(|x| x.slipping);
        assert!(sum(|x| x.local_walks) > 0, "{}: no walk", s.what);
        assert!(
            reference.iter().any(|x| x.motion > 0.0),
            "{}: no motion",
            s.what
        );
        overclosed |= reference.iter().any(|x| x.max_overclosure > 0.0);
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
        for (d, stats) in &runs[1..] {
            for (k, (a, b)) in reference.iter().zip(stats).enumerate() {
                let counts = |x: &IncrementStats| {
                    [
                        x.active,
                        x.slipping,
                        x.local_walks,
                        x.local_capped,
                        x.fast_nodes,
                        x.global_searches,
                        x.budget_searches,
                        x.increment,
                    ]
                };
                assert_eq!(
                    counts(a),
                    counts(b),
                    "{} on {d}, increment {k}: counts",
                    s.what
                );
                for (what, x, y) in [
                    ("stable_dt", a.stable_dt, b.stable_dt),
                    ("approach_dt", a.approach_dt, b.approach_dt),
                    ("max_overclosure", a.max_overclosure, b.max_overclosure),
                    ("motion", a.motion, b.motion),
                    ("omega2", a.omega2, b.omega2),
                ] {
                    assert!(
                        close(x, y),
                        "{} on {d}, increment {k}: {what} {x} against {y}",
                        s.what
                    );
                }
            }
        }
    }
    assert!(slipping > 0, "no slave slipped in any scene");
    assert!(overclosed, "no overclosure in any scene");
}

/// Past 65,536 active slaves (69,696 of 139,392; the others hang beyond the tracking radius),
/// and with a cap of 3 workgroups per dispatch dimension, so that the schedule folds the active
/// slaves' dispatch into 2D: the local increments give the same bytes folded and not, on every
/// device, and find every near slave.
#[test]
fn active_slaves_past_65536_folded_give_the_same_bytes() {
    let plate = plate_quads(64, 64, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let h = 1.0 / 64.0;
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let side = 264;
    let slaves: Vec<[f64; 3]> = (0..2 * side * side)
        .map(|k| {
            let (i, j) = (k % side, (k / side) % side);
            let far = k >= side * side;
            f32r([
                (i as f64 + 0.5) / side as f64,
                (j as f64 + 0.5) / side as f64,
                if far { 10.0 } else { 0.3 * h },
            ])
        })
        .collect();
    let first = m.positions().len();
    let r = m.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(h)).unwrap();
    let base = m.positions().to_vec();
    // the near slaves slide a tenth of a facet per increment: local increments throughout
    let at = |k: usize| -> Vec<[f64; 3]> {
        let mut x = base.clone();
        for q in &mut x[first..first + side * side] {
            q[0] += 0.1 * h * k as f64;
            *q = f32r(*q);
        }
        x
    };
    for d in devices() {
        let run = |cap: Option<u32>| -> Vec<Vec<u8>> {
            let mut search = GlobalSearch::new(&d, &m, p).unwrap();
            if let Some(c) = cap {
                search.set_max_workgroups_per_dim(c);
            }
            (0..4)
                .map(|k| {
                    let r = search.step(&at(k)).unwrap();
                    assert_eq!(
                        r.stats.trigger == Trigger::Local,
                        k > 0,
                        "{d}: increment {k} searches locally"
                    );
                    let tracked = r.contacts().filter(|c| c.is_some()).count();
                    assert_eq!(tracked, side * side, "{d}: increment {k}");
                    bytemuck::cast_slice::<_, u8>(&r.raw).to_vec()
                })
                .collect()
        };
        let (plain, folded) = (run(None), run(Some(3)));
        for (k, (a, b)) in plain.iter().zip(&folded).enumerate() {
            assert!(a == b, "{d}: increment {k} folded differs");
        }
    }
}

/// The normals the springs use are those of the master at the current positions: only the
/// normals a spring reads are computed each increment (`need_normals`), so one left stale — a
/// node its slave's walk reached this increment, say — would show. On the 3D plate, whose
/// waves travel a third of a radian per increment under slaves sliding and pressing in, every
/// slave in contact has the normal of its contact point from the nodal normals of this
/// increment's positions (area-weighted over each node's facets, in f64), on every device,
/// in local increments and global ones.
#[test]
fn springs_read_the_normals_of_the_current_positions() {
    let dt = 1.0e-3;
    let s = approach(3, true, false);
    let pair = s.model.pair(s.pair).unwrap();
    let surface = s.model.surface(pair.master).unwrap();
    let area_normal = |x: &[[f64; 3]], f: [u32; 4]| {
        let p = |j: usize| glam::DVec3::from(x[f[j] as usize]);
        0.5 * (p(2) - p(0)).cross(p(3) - p(1))
    };
    for d in devices() {
        let mut c = Contact::new(&d, &s.model).unwrap();
        c.request_outputs(true);
        let (mut checked, mut locals) = (0, 0);
        for k in 0..s.steps {
            let x = (s.at)(k);
            c.penalty_step(&x, &velocities(&s, k, dt), dt).unwrap();
            let outputs = c.outputs();
            let (_, out) = outputs.iter().find(|(id, _)| *id == s.pair).unwrap();
            let search = out.search.as_ref().unwrap();
            if search.stats.trigger == Trigger::Local {
                locals += 1;
            }
            for (i, status) in out.cstatus.iter().enumerate() {
                if !matches!(status, Some(ContactStatus::Stick | ContactStatus::Slip)) {
                    continue;
                }
                let cp = search.contact(i).unwrap();
                let fac = surface.facets[cp.facet as usize].padded();
                let mut sum = glam::DVec3::ZERO;
                for (j, &node) in fac.iter().enumerate() {
                    let n: glam::DVec3 = surface
                        .facets_of_node(node)
                        .iter()
                        .map(|&f| area_normal(&x, surface.facets[f as usize].padded()))
                        .sum();
                    sum += cp.weights[j] * n.normalize();
                }
                let want = sum.normalize();
                let got = glam::DVec3::from(out.normal[i]);
                assert!(
                    (got - want).length() < 2e-5,
                    "{d}: increment {k}, slave {i}: normal {got} where the master's is {want}"
                );
                checked += 1;
            }
        }
        assert!(
            checked > 2000 && locals > s.steps / 3,
            "{d}: {checked} contacts, {locals} local increments"
        );
    }
}
