//! (features `solver` and `mpi`) A scene run across MPI ranks: the nodes split by recursive
//! coordinate bisection, each rank integrating its own nodes with the elements around them and
//! contact through [`DistributedContact`], writing the history and summary a single process
//! writes.
//!
//! Every rank reads and builds the whole scene (the same on each), then keeps its share: its
//! own nodes (the bisection's part), every element with a node of its own (elements cut by the
//! partition are computed by every rank that owns one of their nodes), and the other nodes of
//! those elements as halo copies. An increment: the distributed contact's forces on own nodes;
//! the central-difference update of every local node with them (an own node's internal force
//! sums the same elements in the same order as in one process: bitwise the same); then each
//! owner sends its nodes' new positions and velocities to the ranks holding them as halo (the
//! halo's own update, missing other ranks' elements, is overwritten). Energies count own nodes
//! and the elements whose first node is own, added over the ranks in rank order; the stable
//! increment is the minimum over ranks. Rank 0 writes the output files.
//!
//! 2D scenes run (the contact's master facets are segments). Fixed rigid parts are held nodes;
//! rigid bodies held or moving at a set velocity are moved alike by every rank, each carrying
//! its own nodes of them (a body's nodes belong to no element, so to no halo) and counting the
//! contact forces on those, rank 0 their kinetic energy. An increment of penalty contact issues
//! 7 collectives ([`crate::scene::RankSummary::collectives_per_increment`]).
//!
//! Small- and infinitesimal-sliding pairs anchor each slave once, on the rank that owns it,
//! and keep the anchor through every rebuild of the rank's local model. Kinematic pairs and
//! pairs against analytical surfaces (their bodies free, held or at a set velocity) correct
//! the solver's prediction with every rank's share ([`DistributedContact::kinematic_step`],
//! [`DistributedRigid`]): the single process's arithmetic, at 11–25 collectives an increment.
//!
//! `run.adjust_overclosure`: every rank adjusts the whole model's start as one process does,
//! then keeps its nodes' positions (once, O(model) on every rank).
//!
//! A free rigid body of mesh nodes has its resultants (contact, loads, kinematic impulses)
//! gathered as per-node rows from every rank and summed in its nodes' order, as one process
//! sums them. Under penalty contact every rank also places all of its nodes from the body's
//! state and follows the whole body from them ([`DistributedContact::move_rigid_parts`]), so
//! its springs see the whole body's mass and inertia as one process's do.
//!
//! VTK frames are not written (a warning says so). A node that moves past its pair's search radius
//! within one increment stops the run on every rank with the single process's tunnelling
//! error.

use std::path::Path;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

mod anchoring;
mod rank;
mod share;
use anchoring::anchoring_over_ranks;
use rank::{part_sums, Rank};
use share::{rank_pairs, rank_rigid_pairs};

use super::account::{Account, Ends};
use super::increments;
use super::{
    built_list, clean_run, finish_outputs, open_history, output_error, stress6, ContactNode,
    PartSummary, Progress, RankSummary, Scene, Summary,
};
use crate::contact::Contact;
use crate::device::Device;
use crate::distributed::{
    agree, all_gather, all_gather_fixed, all_max, all_min, collectives_issued, exchange,
    DistributedContact, DistributedRigid, RankModel, RankRigidPart,
};
use crate::error::{Error, Result};
use crate::explicit::{Element, LoadCurve, Prescribed, Solver};

fn refuse(what: &str, expected: &'static str) -> Error {
    Error::BadParameter {
        name: "distributed run",
        value: what.to_string(),
        expected,
    }
}

/// The values every rank holds (the same number on every rank), summed over the ranks in rank
/// order (the same bits on every rank, run after run; one collective).
fn sum_over_ranks(comm: &SimpleCommunicator, values: &[f64]) -> Vec<f64> {
    let all = all_gather_fixed(comm, values);
    let mut sum = vec![0.0; values.len()];
    for chunk in all.chunks_exact(values.len().max(1)) {
        for (s, v) in sum.iter_mut().zip(chunk) {
            *s += v;
        }
    }
    sum
}

/// This process's peak resident memory, bytes (Linux: `VmHWM` in /proc/self/status; `None`
/// where the system does not say).
fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb = status.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    let kb: u64 = kb.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

/// `e` with its nodes renumbered through `local_of`.
fn renumbered(e: &Element, local_of: &[u32]) -> Element {
    let mut e = e.clone();
    let nodes: &mut [u32] = match &mut e {
        Element::Bar { nodes, .. } => nodes,
        Element::Tri3 { nodes, .. } => nodes,
        Element::Tet4 { nodes, .. } => nodes,
        Element::Hex8(h) => &mut h.nodes,
    };
    for n in nodes {
        *n = local_of[*n as usize];
    }
    e
}

/// Runs `scene` as one rank of `comm` on `device` (collective: every rank calls it with the
/// same scene). Rank 0 writes `history.csv` and `summary.json` to `output` as [`super::run`]
/// does; every rank returns the same summary. Errors are returned on every rank.
pub fn run_distributed(
    scene: &Scene,
    device: &Device,
    output: Option<&Path>,
    comm: &SimpleCommunicator,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Summary> {
    let written = output.filter(|_| comm.rank() == 0);
    clean_run(written, || run_into(scene, device, output, comm, progress))
}

fn run_into(
    scene: &Scene,
    device: &Device,
    output: Option<&Path>,
    comm: &SimpleCommunicator,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Summary> {
    // every rank builds the same scene, so every rank refuses the same things
    let built = scene.build()?;
    let (g, model) = (&built.solver, &built.model);
    let (size, me) = (comm.size() as usize, comm.rank() as u32);
    let n = g.x.len();
    let part = crate::partition::recursive_bisection(&g.x, size)?;
    let owned: Vec<bool> = part.iter().map(|&p| p == me).collect();
    // this rank's elements (in the model's order) and nodes (own and halo, in the model's order)
    let local_elements: Vec<usize> = (0..g.elements.len())
        .filter(|&k| g.elements[k].nodes().iter().any(|&v| owned[v as usize]))
        .collect();
    let mut is_local = owned.clone();
    for &k in &local_elements {
        for &v in g.elements[k].nodes() {
            is_local[v as usize] = true;
        }
    }
    let nodes: Vec<usize> = (0..n).filter(|&i| is_local[i]).collect();
    let mut local_of = vec![u32::MAX; n];
    for (l, &i) in nodes.iter().enumerate() {
        local_of[i] = l as u32;
    }
    let mut solver = Solver::new(
        nodes.iter().map(|&i| g.x[i]).collect(),
        local_elements
            .iter()
            .map(|&k| renumbered(&g.elements[k], &local_of))
            .collect(),
        &nodes.iter().map(|&i| g.mass[i]).collect::<Vec<_>>(),
    )?;
    // the whole model's masses (a halo node misses the other ranks' elements' shares)
    solver.mass = nodes.iter().map(|&i| g.mass[i]).collect();
    solver.v = nodes.iter().map(|&i| g.v[i]).collect();
    solver.fixed = nodes.iter().map(|&i| g.fixed[i]).collect();
    solver.loads = nodes.iter().map(|&i| g.loads[i]).collect();
    solver.load_factor = g.load_factor.clone();
    solver.prescribed = g
        .prescribed
        .iter()
        .filter(|p| is_local[p.node as usize])
        .map(|p| Prescribed {
            node: local_of[p.node as usize],
            ..p.clone()
        })
        .collect();
    solver.load_curves = g
        .load_curves
        .iter()
        .filter(|c| is_local[c.node as usize])
        .map(|c| LoadCurve {
            node: local_of[c.node as usize],
            ..c.clone()
        })
        .collect();
    solver.gravity = g.gravity;
    solver.damping = g.damping;
    solver.bulk_viscosity = g.bulk_viscosity;
    solver.bulk_viscosity_quadratic = g.bulk_viscosity_quadratic;
    solver.nlgeom = g.nlgeom;
    solver.safety = g.safety;
    solver.counted = Some((
        nodes.iter().map(|&i| owned[i]).collect(),
        local_elements
            .iter()
            .map(|&k| owned[g.elements[k].nodes()[0] as usize])
            .collect(),
    ));
    // the rigid bodies, held or moving at a set velocity: every rank moves them alike and
    // carries its own nodes of theirs (a body's nodes belong to no element, so to no halo);
    // rank 0 counts their kinetic energy, each rank the contact forces on its own nodes
    let body_keys: Vec<Vec<u32>> = g
        .bodies
        .iter()
        .map(|b| {
            (0..b.nodes.len() as u32)
                .filter(|&j| is_local[b.nodes[j as usize] as usize])
                .collect()
        })
        .collect();
    for b in &g.bodies {
        let mut local = b.clone();
        (local.nodes, local.offsets) = b
            .nodes
            .iter()
            .zip(&b.offsets)
            .filter(|(&n, _)| is_local[n as usize])
            .map(|(&n, &o)| (local_of[n as usize], o))
            .unzip();
        solver.add_body(local)?;
    }
    solver.bodies_counted = me == 0;
    let bodies0: Vec<[f64; 3]> = g.bodies.iter().map(|b| b.state.position).collect();
    let own: Vec<usize> = (0..nodes.len()).filter(|&l| owned[nodes[l]]).collect();
    // the halo plan: ask each owner for its nodes held here; learn which own nodes to send where
    let mut asks: Vec<Vec<u64>> = vec![Vec::new(); size];
    for &i in nodes.iter().filter(|&&i| !owned[i]) {
        asks[part[i] as usize].push(i as u64);
    }
    let wanted = exchange(comm, &asks);
    let send: Vec<Vec<usize>> = wanted
        .iter()
        .map(|l| l.iter().map(|&i| local_of[i as usize] as usize).collect())
        .collect();
    let halo_in: Vec<usize> = asks
        .iter()
        .flatten()
        .map(|&i| local_of[i as usize] as usize)
        .collect();
    let halo_counts: Vec<usize> = asks.iter().map(Vec::len).collect();
    // the contact share
    let pairs = rank_pairs(model, &part, me)?;
    let has_contact = !pairs.is_empty();
    let own_ids: Vec<u64> = own.iter().map(|&l| nodes[l] as u64).collect();
    let contact = if has_contact {
        Some(DistributedContact::new(
            comm,
            device,
            RankModel {
                ids: own_ids,
                positions: own.iter().map(|&l| solver.x[l]).collect(),
                masses: own.iter().map(|&l| solver.mass[l]).collect(),
                pairs,
                two_d: model.dim() == 2,
                rigid_parts: model
                    .rigid_parts()
                    .iter()
                    .map(|p| RankRigidPart {
                        ids: p.nodes.iter().map(|&n| n as u64).collect(),
                        positions: p
                            .nodes
                            .iter()
                            .map(|&n| model.positions()[n as usize])
                            .collect(),
                        mass: p.mass,
                        inertia: p.inertia,
                    })
                    .collect(),
            },
        )?)
    } else {
        None
    };
    // kinematic contact against analytical surfaces: every rank takes part in each pair
    let rigid_pairs = rank_rigid_pairs(model, &part, me, &local_of)?;
    let rigid = if rigid_pairs.is_empty() {
        None
    } else {
        Some(DistributedRigid::new(
            comm,
            solver.mass.clone(),
            rigid_pairs,
        )?)
    };
    let has_contact = has_contact || rigid.is_some();
    // the slave nodes this rank owns (local indices), for the total contact force
    let mut slaves: Vec<u32> = built.slaves.iter().flatten().copied().collect();
    slaves.sort_unstable();
    slaves.dedup();
    let own_slaves: Vec<usize> = slaves
        .iter()
        .filter(|&&s| owned[s as usize])
        .map(|&s| local_of[s as usize] as usize)
        .collect();
    // each part's own nodes (local indices) and whole mass
    let part_nodes: Vec<(Vec<usize>, f64, usize)> = built
        .parts
        .iter()
        .map(|p| {
            let range = p.base..p.base + p.count;
            let total: f64 = range.clone().map(|i| g.mass[i]).sum();
            let mine = range
                .filter(|&i| owned[i])
                .map(|i| local_of[i] as usize)
                .collect();
            (mine, total, p.count)
        })
        .collect();
    // each rigid part of the contact model is a free body of mesh nodes with the same nodes
    let rigid_parts: Vec<(usize, Vec<[f64; 3]>)> = model
        .rigid_parts()
        .iter()
        .map(|p| {
            let b = g
                .bodies
                .iter()
                .position(|b| b.nodes == p.nodes)
                .ok_or_else(|| {
                    refuse(
                        "a rigid part that is no free body's nodes",
                        "rigid parts from the scene's free bodies",
                    )
                })?;
            Ok((b, g.bodies[b].offsets.clone()))
        })
        .collect::<Result<_>>()?;
    let x0 = solver.x.clone();
    let mut built_list = built_list(scene, g, &built.slaves);
    built_list.push(format!(
        "{size} MPI ranks, the nodes split by recursive coordinate bisection (see ranks)"
    ));

    let io = output_error;
    // rank 0 writes; a failure there is agreed, so no rank is left waiting
    let mut history = None;
    let mut fault = None;
    if let (Some(dir), true) = (output, comm.rank() == 0) {
        match open_history(dir, &built.parts, &built.bodies) {
            Ok(f) => history = Some(f),
            Err(e) => fault = Some(io(e)),
        }
    }
    agree(comm, fault)?;

    let mut account = Account::new(&scene.run, all_min(comm, solver.stable_increment()))?;
    super::run_length::check_length(scene, g, &built.parts, account.dt)?;
    // the start's overclosure adjustment: every rank moves the whole model's slaves as one
    // process does (in its order, each on the positions the ones before left), and keeps its
    // own and halo nodes' (once, O(model) on every rank)
    let mut adjusted = None;
    if scene.run.adjust_overclosure && has_contact {
        let first = account.dt.min(scene.run.end_time - solver.time);
        let mut x = g.x.clone();
        let report = Contact::new(device, model)
            .and_then(|mut c| c.adjust_initial_overclosure(&mut x, &g.body_states(), first));
        // agreed: a rank's failure stops every rank here
        let (report, fault) = match report {
            Ok(r) => (Some(r), None),
            Err(e) => (None, Some(e)),
        };
        agree(comm, fault)?;
        for (l, &i) in nodes.iter().enumerate() {
            solver.x[l] = x[i];
        }
        adjusted = report;
    }
    account.ramp = scene
        .quasi_static
        .as_ref()
        .map_or(f64::NAN, |q| q.ramp_time);
    let mut rank = Rank {
        comm,
        solver,
        contact,
        rigid,
        own: &own,
        send: &send,
        halo_in: &halo_in,
        halo_counts: &halo_counts,
        own_slaves: &own_slaves,
        part_nodes: &part_nodes,
        x0: &x0,
        bodies: &built.bodies,
        body_keys: &body_keys,
        bodies0: &bodies0,
        rigid_parts: &rigid_parts,
        at_peak: bodies0.clone(),
        history,
        halo_bytes: 0,
        contact_bytes: 0,
        balance0: None,
        floor: g.energy_floor(),
        energy: [0.0; 5],
        last: Vec::new(),
    };
    let issued = collectives_issued();
    increments::run(&mut account, &mut rank, device, progress)?;
    let issued = collectives_issued() - issued;
    let Rank {
        solver,
        contact,
        rigid,
        history,
        halo_bytes,
        contact_bytes,
        energy,
        at_peak,
        ..
    } = rank;
    let k = account.k;
    let my_seconds = account.seconds_per_increment();
    let seconds = all_max(comm, my_seconds);
    let per_increment = |b: usize| b as f64 / k.max(1) as f64;
    let mine = [
        own.len() as f64,
        (nodes.len() - own.len()) as f64,
        local_elements.len() as f64,
        contact.as_ref().map_or(0.0, |c| c.last().ghosts as f64),
        contact.as_ref().map_or(0.0, |c| c.slaves() as f64),
        per_increment(halo_bytes),
        per_increment(contact_bytes),
        my_seconds,
        contact.as_ref().map_or(0.0, |c| c.rebuilds() as f64),
        per_increment(issued as usize),
        peak_resident_bytes().map_or(-1.0, |b| b as f64),
    ];
    let ranks: Vec<RankSummary> = all_gather(comm, &mine)
        .0
        .chunks_exact(mine.len())
        .map(|r| RankSummary {
            own_nodes: r[0] as usize,
            halo_nodes: r[1] as usize,
            elements: r[2] as usize,
            contact_ghosts: r[3] as usize,
            slaves: r[4] as usize,
            halo_bytes_per_increment: r[5],
            contact_bytes_per_increment: r[6],
            seconds_per_increment: r[7],
            contact_rebuilds: r[8] as u64,
            collectives_per_increment: r[9],
            peak_resident_bytes: (r[10] >= 0.0).then_some(r[10] as u64),
        })
        .collect();
    // the parts: motion summed over the ranks, stress extremes over each rank's own elements
    let motion = sum_over_ranks(comm, &part_sums(&part_nodes, &solver, &x0));
    let mut parts = Vec::new();
    let mut el = 0;
    let counted_of: Vec<Option<usize>> = {
        let mut v = vec![None; g.elements.len()];
        for (l, &k) in local_elements.iter().enumerate() {
            if owned[g.elements[k].nodes()[0] as usize] {
                v[k] = Some(l);
            }
        }
        v
    };
    for (j, p) in built.parts.iter().enumerate() {
        let (mut lo, mut hi) = ([f64::INFINITY; 6], [f64::NEG_INFINITY; 6]);
        for l in counted_of[el..el + p.elements].iter().flatten() {
            let s = stress6(solver.stress(*l));
            for c in 0..6 {
                lo[c] = lo[c].min(s[c]);
                hi[c] = hi[c].max(s[c]);
            }
        }
        for c in 0..6 {
            lo[c] = all_min(comm, lo[c]);
            hi[c] = all_max(comm, hi[c]);
        }
        el += p.elements;
        if p.elements == 0 {
            (lo, hi) = ([0.0; 6], [0.0; 6]);
        }
        parts.push(PartSummary {
            name: p.name.clone(),
            displacement: [0, 1, 2].map(|a| motion[6 * j + a]),
            velocity: [0, 1, 2].map(|a| motion[6 * j + 3 + a]),
            stress_min: lo,
            stress_max: hi,
        });
    }
    // the slaves in contact at the end, every rank's, in (pair, pass, node) order
    let (outs, dissipated) = contact
        .as_ref()
        .map(|c| c.contact_outputs())
        .unwrap_or_default();
    let row = |pair: usize, reverse: bool, l: usize, pressure: f64, f: [f64; 3]| {
        let x = solver.x[l];
        let fm = (0..3).map(|a| f[a] * f[a]).sum::<f64>().sqrt();
        let node = nodes[l] as f64;
        [
            pair as f64,
            reverse as u8 as f64,
            node,
            pressure,
            fm,
            x[0],
            x[1],
            x[2],
        ]
    };
    let meshed = outs.iter().flat_map(|o| {
        let l = local_of[o.node as usize] as usize;
        row(o.pair, o.reverse, l, o.pressure, o.force)
    });
    // against analytical surfaces: numbered after the meshed pairs, as in one process
    let analytical = rigid
        .iter()
        .flat_map(|r| r.contact_outputs())
        .flat_map(|(k, l, p, f)| row(model.pairs().len() + k, false, l as usize, p, f));
    let flat: Vec<f64> = meshed.chain(analytical).collect();
    let (all, _) = all_gather(comm, &flat);
    let mut rows: Vec<&[f64]> = all.chunks_exact(8).collect();
    rows.sort_by(|a, b| a[..3].partial_cmp(&b[..3]).expect("finite keys"));
    let contact_nodes = rows
        .iter()
        .map(|r| ContactNode {
            contact: r[0] as usize,
            node: r[2] as u32,
            position: [r[5], r[6], r[7]],
            pressure: r[3],
            force: r[4],
        })
        .collect();
    let friction = sum_over_ranks(comm, &[dissipated])[0];
    let anchoring = anchoring_over_ranks(comm, model, contact.as_ref())?;
    let mut warnings = Vec::new();
    warnings.extend(adjusted.as_ref().and_then(super::run::adjusted_warning));
    for a in anchoring.iter().filter(|a| !a.unanchored.is_empty()) {
        warnings.push(super::run::unanchored_warning(a));
    }
    if scene.run.vtk_every > 0 && has_contact {
        warnings.push(
            "run.vtk_every: a distributed run writes no VTK frames (run the scene in one \
             process for them)"
                .into(),
        );
    }
    let nodes = scene.node_outputs.iter().chain(&scene.node_histories);
    let files = nodes
        .map(|o| &o.file)
        .chain(scene.element_outputs.iter().map(|o| &o.file));
    for file in files.chain(scene.contact_outputs.iter().map(|o| &o.file)) {
        warnings.push(format!(
            "{file}: a distributed run writes no deck output request (run the deck in one \
             process for it)"
        ));
    }
    let [kinetic, internal, external_work, contact_work, _] = energy;
    let ends = Ends {
        device: format!("{device} (rank 0 of {size})"),
        built: built_list,
        end_time: solver.time,
        seconds_per_increment: seconds,
        energies: [kinetic, internal, external_work, contact_work],
        frictional_dissipation: friction,
        parts,
        bodies: super::run::body_summaries(&solver, &built.bodies, &bodies0, &at_peak),
        contact_nodes,
        anchored_slaves: anchoring.iter().map(|a| a.anchored).sum(),
        unanchored_slaves: anchoring
            .iter()
            .flat_map(|a| a.unanchored.iter().copied())
            .collect(),
        warnings,
        global_searches: contact.as_ref().map_or(0, |c| c.global_searches()),
        ranks,
    };
    let summary = account.summary(scene, device, ends);
    let mut fault = None;
    if let (Some(dir), Some(f)) = (output, history) {
        fault = finish_outputs(dir, f, &summary).err().map(io);
    }
    agree(comm, fault)?;
    Ok(summary)
}
