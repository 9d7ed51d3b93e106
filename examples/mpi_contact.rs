//! Penalty contact across MPI ranks against the single process (issue 18), run by
//! tests/mpi.rs under `mpirun -n N` (or by hand: `mpirun -n 4 target/release/examples/mpi_contact`).
//!
//! Every rank builds the same model: a wavy plate of 16 × 16 quads (the master, its nodes free
//! and sliding along x by more than a rank's width over the run, so slaves' nearest facets pass
//! from one rank's nodes to another's), a cloud of 300 slave points pressed into it and moving
//! (two pairs on the one plate: half the cloud frictionless, half with Coulomb friction 0.3),
//! and a block of 200 nodes far away in no pair (with four ranks, recursive coordinate bisection
//! gives them a rank of their own: a rank with no contact at all). The nodes are split by
//! recursive coordinate bisection of all of them, so the slaves and the plate are cut across
//! ranks differently. Positions are prescribed (x = x0 + v·t), so each increment's forces can be
//! compared with a single `Contact` over the whole model exactly: rank 0 runs it beside its share
//! and compares every node's force after every increment (relative to the largest force). It
//! prints one line per run — the largest difference, the distributed global searches, the bytes
//! sent per increment by each rank, and a checksum of every force's bits (equal on reruns with
//! the same rank count) — and exits non-zero when a force differs by more than f32 round-off.
//!
//! `ABUT_MPI_CASE` picks another model: `self` (a self-contact sheet), `balanced` (a balanced
//! pair of two plates), `stretch` (a plate stretched tenfold under slaves that lie in the middle
//! of one of its facets), `bad-slave` (a rank names a slave it does not own: refused
//! everywhere), `bad-facet` (a rank gives a 2D segment as a facet of this 3D model: likewise),
//! `bad-part` (every rank gives a rigid part of the first three nodes, the last with a negative
//! mass: likewise), `lost-part` (every rank gives a rigid part one of whose nodes no rank owns:
//! refused on every rank alike).
//! The line also gives the MPI collectives per increment, between distributed global searches
//! and at them.

use abut::distributed::{
    all_gather, DistributedContact, RankBalance, RankModel, RankPair, RankRigidPart, NO_GLOBAL_NODE,
};
use abut::mesh::{plate_quads, point_cloud};
use abut::partition::recursive_bisection;
use abut::*;
use mpi::traits::*;

const INCREMENTS: usize = 60;
const DT: f64 = 1e-3;
const MU: f64 = 0.3;
/// The weight of a balanced pair's slave-on-master pass (not ½, so that the passes differ).
const BALANCE: f64 = 0.6;

fn main() {
    let universe = mpi::initialize().expect("MPI initialises");
    // a rank that panics (a failed check on rank 0) takes the job down: unwinding would
    // finalise MPI while the other ranks wait in a collective, and none would ever return
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        report(info);
        mpi::topology::SimpleCommunicator::world().abort(1);
    }));
    let world = universe.world();
    let (rank, size) = (world.rank() as usize, world.size() as usize);

    // the whole model, the same on every rank
    let case = std::env::var("ABUT_MPI_CASE").unwrap_or_default();
    let Scene {
        x0,
        masses,
        vel,
        facets: surface,
        pairs: specs,
        slave_facets,
    } = if case == "self" {
        sheet()
    } else if case == "balanced" {
        two_plates()
    } else if case == "stretch" {
        stretching_plate()
    } else {
        plate_and_cloud()
    };
    let n = x0.len();
    let at = |t: f64| -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| [0, 1, 2].map(|a| x0[i][a] + vel[i][a] * t))
            .collect()
    };
    let radius = if case == "stretch" { 0.2 } else { 0.1 };

    // this rank's share
    let part = recursive_bisection(&x0, size).expect("a partition");
    let own: Vec<usize> = (0..n).filter(|&i| part[i] as usize == rank).collect();
    let facets: Vec<[u64; 4]> = surface
        .iter()
        .filter(|f| part[f[0] as usize] as usize == rank)
        .map(|f| f.map(|g| g as u64))
        .collect();
    let pairs: Vec<RankPair> = specs
        .iter()
        .map(|(half, friction)| {
            let mut pair = RankPair::new(
                half.iter()
                    .filter(|&&s| part[s] as usize == rank)
                    .map(|&s| s as u64)
                    .collect(),
                facets.clone(),
                radius,
            );
            pair.friction = friction.clone();
            pair.search_interval = 10;
            pair.balanced = slave_facets.as_ref().map(|sf| RankBalance {
                slave_facets: sf
                    .iter()
                    .filter(|f| part[f[0] as usize] as usize == rank)
                    .map(|f| f.map(|g| g as u64))
                    .collect(),
                weight: BALANCE,
            });
            pair
        })
        .collect();
    let my_slaves: usize = pairs.iter().map(|p| p.slaves.len()).sum();
    let model = RankModel {
        two_d: false,
        ids: own.iter().map(|&i| i as u64).collect(),
        positions: own.iter().map(|&i| x0[i]).collect(),
        masses: own.iter().map(|&i| masses[i]).collect(),
        pairs,
        rigid_parts: Vec::new(),
    };
    let device = Device::cpu();
    if case.starts_with("bad-") || case == "lost-part" {
        // the last rank names a slave it does not own, gives a 2D segment as a facet of this
        // 3D model, or a rigid part of negative mass: every rank is refused, none hangs
        let mut bad = model.clone();
        if case == "bad-part" || case == "lost-part" {
            // lost-part: every rank alike, one node no rank owns
            let unit = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let mut ids = vec![0, 1, 2];
            if case == "lost-part" {
                ids[2] = u64::MAX - 1;
            }
            bad.rigid_parts.push(RankRigidPart {
                ids,
                positions: x0[..3].to_vec(),
                mass: if rank == size - 1 && case == "bad-part" {
                    -1.0
                } else {
                    1.0
                },
                inertia: unit,
            });
        } else if rank == size - 1 && case == "bad-slave" {
            bad.pairs[0].slaves.push(u64::MAX - 1);
        } else if rank == size - 1 {
            bad.pairs[0]
                .facets
                .push([0, 1, NO_GLOBAL_NODE, NO_GLOBAL_NODE]);
        }
        let e = DistributedContact::new(&world, &device, bad)
            .err()
            .expect("refused");
        println!("rank {rank} refused: {e}");
        return;
    }
    let mut dc = DistributedContact::new(&world, &device, model).expect("a distributed contact");

    // the single process's contact, on rank 0
    let mut single = (rank == 0).then(|| {
        let mut m = Model::new_3d();
        m.add_nodes(&x0, &masses).unwrap();
        let surf = m.add_surface(Surface::quads(&surface)).unwrap();
        let slave_surf = slave_facets
            .as_ref()
            .map(|sf| m.add_surface(Surface::quads(sf)).unwrap());
        for (half, friction) in &specs {
            let set = m
                .add_node_set(&half.iter().map(|&s| s as u32).collect::<Vec<_>>())
                .unwrap();
            let mut pair = Pair::new(set, surf)
                .search_radius(radius)
                .friction(friction.clone());
            if let Some(s) = slave_surf {
                pair = pair.balanced(s, BALANCE);
            }
            m.add_pair(pair).unwrap();
        }
        let mut c = Contact::new(&device, &m).unwrap();
        c.request_outputs(true);
        c
    });
    // the rank owning each slave's facet at the last increment (facets belong to the rank of
    // their first node), and how often it changed
    let mut facet_rank = vec![u32::MAX; specs.iter().map(|s| s.0.len()).sum()];
    let mut handovers = 0usize;

    let (mut worst, mut scale, mut searches, mut bytes) = (0.0f64, 0.0f64, 0, 0usize);
    let mut checksum: u64 = 0xcbf2_9ce4_8422_2325;
    let mut active = 0;
    let mut micros = 0.0f64;
    // the collectives of each kind of increment: (fewest, most) between distributed global
    // searches and at them
    let (mut local_calls, mut global_calls) = ((u64::MAX, 0u64), (u64::MAX, 0u64));
    for k in 0..INCREMENTS {
        let x = at(k as f64 * DT);
        let xo: Vec<[f64; 3]> = own.iter().map(|&i| x[i]).collect();
        let vo: Vec<[f64; 3]> = own.iter().map(|&i| vel[i]).collect();
        let t = std::time::Instant::now();
        let step = dc.step(&xo, &vo, DT).expect("a distributed increment");
        micros += t.elapsed().as_secs_f64() * 1e6;
        searches += step.global_search as usize;
        let calls = if step.global_search {
            &mut global_calls
        } else {
            &mut local_calls
        };
        *calls = (calls.0.min(step.collectives), calls.1.max(step.collectives));
        bytes += step.bytes_sent;
        active = step.active;
        // every rank's forces on rank 0, by global id
        let ids: Vec<u64> = own.iter().map(|&i| i as u64).collect();
        let flat: Vec<f64> = step.forces.iter().flatten().copied().collect();
        let (all_ids, _) = all_gather(&world, &ids);
        let (all_f, _) = all_gather(&world, &flat);
        if let Some(c) = single.as_mut() {
            let r = c.penalty_step(&x, &vel, DT).expect("a single increment");
            let mut dist = vec![[0.0; 3]; n];
            for (j, &g) in all_ids.iter().enumerate() {
                dist[g as usize] = [all_f[3 * j], all_f[3 * j + 1], all_f[3 * j + 2]];
            }
            for i in 0..n {
                for a in 0..3 {
                    scale = scale.max(r.forces[i][a].abs());
                    worst = worst.max((r.forces[i][a] - dist[i][a]).abs());
                    for b in dist[i][a].to_bits().to_le_bytes() {
                        checksum = (checksum ^ b as u64).wrapping_mul(0x100_0000_01b3);
                    }
                }
            }
            assert_eq!(r.active, step.active, "increment {k}: slaves in contact");
            let outs = c.outputs();
            // the slave-on-master passes (a balanced pair's second pass searches the slave
            // surface, whose facets are not counted here)
            let passes = outs.iter().filter_map(|o| o.1.search.as_ref());
            let step_by = if slave_facets.is_some() { 2 } else { 1 };
            for (h, sr) in passes.step_by(step_by).enumerate() {
                for (j, cp) in sr.contacts().enumerate() {
                    let j = j + specs[..h].iter().map(|s| s.0.len()).sum::<usize>();
                    let owner =
                        cp.map_or(u32::MAX, |p| part[surface[p.facet as usize][0] as usize]);
                    if owner != facet_rank[j] && facet_rank[j] != u32::MAX && owner != u32::MAX {
                        handovers += 1;
                    }
                    facet_rank[j] = owner;
                }
            }
        }
    }
    let all_bytes = gather_counts(
        &world,
        [
            bytes as u64,
            my_slaves as u64,
            (micros / INCREMENTS as f64) as u64,
        ],
    );
    if rank == 0 {
        let rel = worst / scale;
        let per: Vec<String> = all_bytes
            .iter()
            .map(|[b, s, us]| format!("{}B/{s}slaves/{us}us", b / INCREMENTS as u64))
            .collect();
        println!(
            "ranks {size}: largest force difference {rel:.3e} of the largest force {scale:.4e}; \
             {active} slaves in contact; {handovers} hand-overs of a slave's facet between \
             ranks; {searches} distributed global searches; collectives per increment \
             {}-{} local {}-{} global; per rank: bytes sent per increment, \
             slaves, time per increment {}; \
             checksum {checksum:016x}",
            local_calls.0,
            local_calls.1,
            global_calls.0,
            global_calls.1,
            per.join(" ")
        );
        if !(rel <= 1e-5) || scale == 0.0 {
            eprintln!("forces differ from the single process's");
            world.abort(1);
        }
    }
}

/// Each rank's three counters (bytes, slaves, µs per increment) on every rank.
fn gather_counts(world: &mpi::topology::SimpleCommunicator, c: [u64; 3]) -> Vec<[u64; 3]> {
    let size = world.size() as usize;
    let mut all = vec![0u64; 3 * size];
    world.all_gather_into(&c[..], &mut all[..]);
    all.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// A model: start positions, masses, velocities, the master surface (quads by node), and the
/// pairs on it (slave nodes, friction).
struct Scene {
    x0: Vec<[f64; 3]>,
    masses: Vec<f64>,
    vel: Vec<[f64; 3]>,
    facets: Vec<[u32; 4]>,
    pairs: Vec<(Vec<usize>, Friction)>,
    /// The slave surface of a balanced pair (quads by node, facing the master).
    slave_facets: Option<Vec<[u32; 4]>>,
}

/// The wavy plate sliding under the cloud of slaves, two pairs on it (the first half of the
/// cloud frictionless, the second with Coulomb friction μ = 0.3, its stick force carried through
/// the rebuilds), and the far block.
fn plate_and_cloud() -> Scene {
    let plate = plate_quads(16, 16, 1.0, 1.0, 0.0, 0, &|x, y| {
        0.02 * (6.0 * x).sin() * (4.0 * y).cos()
    });
    let np = plate.positions.len();
    let cloud = point_cloud(300, [0.1, 0.1, -0.004], [0.9, 0.9, -0.001], 7);
    let far = point_cloud(200, [50.0, 50.0, 50.0], [51.0, 51.0, 51.0], 9);
    let mut x0: Vec<[f64; 3]> = plate.positions.clone();
    // the slaves follow the wavy surface, pressed in by 1–4 mm
    for p in &cloud {
        let z = 0.02 * (6.0 * p[0]).sin() * (4.0 * p[1]).cos();
        x0.push([p[0], p[1], z + p[2]]);
    }
    x0.extend(&far);
    let n = x0.len();
    let slaves: Vec<usize> = (np..np + cloud.len()).collect();
    let mut masses = vec![1.0; n];
    for &s in &slaves {
        masses[s] = 0.5;
    }
    // the plate slides along +x by 0.3 over the run, the slaves drift along y and sink a little
    let mut vel = vec![[0.0; 3]; n];
    for v in vel.iter_mut().take(np) {
        *v = [0.3 / (INCREMENTS as f64 * DT), 0.0, 0.0];
    }
    for (k, &s) in slaves.iter().enumerate() {
        vel[s] = [0.0, 0.5 * ((k % 7) as f64 - 3.0), -0.02];
    }
    let half = slaves.len() / 2;
    Scene {
        x0,
        masses,
        vel,
        facets: plate.facets.clone(),
        pairs: vec![
            (slaves[..half].to_vec(), Friction::Frictionless),
            (slaves[half..].to_vec(), Friction::coulomb(MU)),
        ],
        slave_facets: None,
    }
}

/// A self-contact sheet: one surface of two layers, the lower facing up and the upper (shifted,
/// facing down) pressed 1–3 mm through it and sliding along x by 0.2 over the run; every node
/// of both layers a slave of the one pair, with friction.
fn sheet() -> Scene {
    let lower = plate_quads(12, 12, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let upper = plate_quads(12, 12, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let nl = lower.positions.len() as u32;
    let mut x0 = lower.positions.clone();
    x0.extend(upper.positions.iter().map(|p| {
        [
            p[0] + 0.021,
            p[1] + 0.033,
            -0.002 + 0.001 * (5.0 * p[0]).sin(),
        ]
    }));
    let mut facets = lower.facets.clone();
    // the upper layer faces down: its quads wound the other way
    facets.extend(
        upper
            .facets
            .iter()
            .map(|f| [f[0], f[3], f[2], f[1]].map(|k| k + nl)),
    );
    let n = x0.len();
    let mut vel = vec![[0.0; 3]; n];
    for v in vel.iter_mut().skip(nl as usize) {
        *v = [0.2 / (INCREMENTS as f64 * DT), 0.0, -0.01];
    }
    Scene {
        x0,
        masses: vec![1.0; n],
        vel,
        facets,
        pairs: vec![((0..n).collect(), Friction::coulomb(MU))],
        slave_facets: None,
    }
}

/// A balanced pair: a wavy plate of 14 × 14 quads (the master, facing up) and a finer flat
/// plate of 17 × 17 quads above it (the slave surface, facing down, its nodes the slaves),
/// pressed 1–3 mm into the crests and sliding along x by 0.25 and along y by 0.05 over the run,
/// with friction 0.3; the passes weighted 0.6 and 0.4. Both passes' contacts cross ranks: the
/// plates are cut by the same bisection of all nodes, which their different meshes do not align
/// with.
fn two_plates() -> Scene {
    let lower = plate_quads(14, 14, 1.0, 1.0, 0.0, 0, &|x, y| {
        0.004 * (5.0 * x).cos() * (3.0 * y).cos()
    });
    let upper = plate_quads(17, 17, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let nl = lower.positions.len();
    let mut x0 = lower.positions.clone();
    x0.extend(upper.positions.iter().map(|p| {
        [
            p[0] + 0.013,
            p[1] - 0.021,
            0.002 - 0.001 * (4.0 * p[1]).sin(),
        ]
    }));
    let n = x0.len();
    let mut vel = vec![[0.0; 3]; n];
    for v in vel.iter_mut().skip(nl) {
        *v = [
            0.25 / (INCREMENTS as f64 * DT),
            0.05 / (INCREMENTS as f64 * DT),
            -0.01,
        ];
    }
    let mut masses = vec![1.0; n];
    for m in masses.iter_mut().skip(nl) {
        *m = 0.7;
    }
    Scene {
        x0,
        masses,
        vel,
        facets: lower.facets.clone(),
        pairs: vec![((nl..n).collect(), Friction::coulomb(MU))],
        slave_facets: Some(
            upper
                .facets
                .iter()
                .map(|f| [f[0], f[3], f[2], f[1]].map(|k| k + nl as u32))
                .collect(),
        ),
    }
}

/// A plate of 4 × 4 quads on [0, 1]² stretched tenfold along x over the run (x = x0·(1 + 9t/T)),
/// arriving under a strip of 24 static slaves at x ≈ 5 pressed 2 mm below its plane: late in
/// the run they lie in the middle of one facet 2 m long whose nodes are farther from them than
/// the ghost margin of the start's facet size (0.25) allows — a rank must widen the margin as
/// facets stretch, or its slaves lose that facet.
fn stretching_plate() -> Scene {
    let plate = plate_quads(4, 4, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let np = plate.positions.len();
    let mut x0 = plate.positions.clone();
    for k in 0..24 {
        x0.push([
            5.0 + 0.05 * (k % 2) as f64,
            0.3 + 0.4 * (k / 2) as f64 / 11.0,
            -0.002,
        ]);
    }
    let n = x0.len();
    let mut vel = vec![[0.0; 3]; n];
    for (v, p) in vel.iter_mut().zip(&plate.positions) {
        *v = [9.0 * p[0] / (INCREMENTS as f64 * DT), 0.0, 0.0];
    }
    Scene {
        x0,
        masses: vec![1.0; n],
        vel,
        facets: plate.facets.clone(),
        pairs: vec![((np..n).collect(), Friction::Frictionless)],
        slave_facets: None,
    }
}
