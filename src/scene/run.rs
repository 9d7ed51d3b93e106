//! A scene run in one process: the solver and the contact stepped together, the history, VTK
//! frames and the summary; what it accumulates is the [`Account`] it shares with the run across
//! MPI ranks.

use std::io::Write as _;
use std::path::Path;

use super::account::{Account, Ends};
use super::build::PartNodes;
use super::increments::{self, Limits, Ranks, Sums};
use super::{
    built_list, finish_outputs, open_history, output_error, search_structures, stress6,
    BodySummary, ContactNode, PartSummary, Progress, Scene, Summary,
};
use crate::contact::Contact;
use crate::device::Device;
use crate::error::{Error, Result};
use crate::explicit::Solver;

/// [`super::run`] itself: the outputs written under their partial names, renamed at the end.
pub(super) fn run_into(
    scene: &Scene,
    device: &Device,
    output: Option<&Path>,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Summary> {
    let built = scene.build()?;
    let (mut solver, model) = (built.solver, built.model);
    let x0 = solver.x.clone();
    let has_contact = !model.pairs().is_empty() || !model.rigid_pairs().is_empty();
    let mut contact = if has_contact {
        Some(Contact::new(device, &model)?)
    } else {
        None
    };
    let mut slaves: Vec<u32> = built.slaves.iter().flatten().copied().collect();
    slaves.sort_unstable();
    slaves.dedup();
    let mut built_list = built_list(scene, &solver, &built.slaves);
    if let Some(c) = contact.as_ref() {
        built_list.extend(search_structures(&model, c));
    }
    let io = output_error;
    let history = match output {
        Some(dir) => Some(open_history(dir, &built.parts, &built.bodies).map_err(io)?),
        None => None,
    };
    // VTK frames go to a hidden directory renamed only when the run succeeded
    let series = match output {
        Some(dir) if scene.run.vtk_every > 0 && contact.is_some() => {
            let partial = dir.join(".vtk.partial");
            let _ = std::fs::remove_dir_all(&partial);
            Some(crate::io::vtk::Series::new(&partial, "contact")?)
        }
        _ => None,
    };
    let mut account = Account::new(&scene.run, solver.stable_increment())?;
    super::run_length::check_length(scene, &solver, &built.parts, account.dt)?;
    account.ramp = scene
        .quasi_static
        .as_ref()
        .map_or(f64::NAN, |q| q.ramp_time);
    let bodies0: Vec<[f64; 3]> = solver.bodies.iter().map(|b| b.state.position).collect();
    let mut adjusted = None;
    if let (Some(c), true) = (contact.as_mut(), scene.run.adjust_overclosure) {
        let bodies = solver.body_states();
        let first = account.dt.min(scene.run.end_time - solver.time);
        adjusted = Some(c.adjust_initial_overclosure(&mut solver.x, &bodies, first)?);
    }
    let floor = solver.energy_floor();
    let mut one = OneProcess {
        floor,
        scene,
        model: &model,
        at_peak: bodies0.clone(),
        solver,
        contact,
        slaves,
        x0: &x0,
        bodies0: &bodies0,
        parts: &built.parts,
        bodies: &built.bodies,
        history,
        series,
        node_files: Vec::new(),
        outputs_done: (0, 0, 0),
        history_texts: scene
            .node_histories
            .iter()
            .map(super::deck_output::header)
            .collect(),
    };
    increments::run(&mut account, &mut one, device, progress)?;
    let OneProcess {
        solver,
        contact,
        history,
        series,
        at_peak,
        mut node_files,
        history_texts,
        ..
    } = one;
    let histories = scene.node_histories.iter().map(|o| o.file.clone());
    node_files.extend(histories.zip(history_texts));
    let ends = ends(
        device,
        built_list,
        &solver,
        &x0,
        &bodies0,
        &at_peak,
        &built.parts,
        &built.bodies,
        contact.as_ref(),
        &model,
        adjusted,
        account.seconds_per_increment(),
    );
    let summary = account.summary(scene, device, ends);
    if let (Some(dir), Some(f)) = (output, history) {
        super::deck_output::write(dir, &node_files).map_err(io)?;
        finish_outputs(dir, f, &summary).map_err(io)?;
        if series.is_some() {
            let _ = std::fs::remove_dir_all(dir.join("vtk"));
            std::fs::rename(dir.join(".vtk.partial"), dir.join("vtk")).map_err(io)?;
        }
    }
    Ok(summary)
}

/// One process: the solver stepped with its contact, its totals the values themselves.
struct OneProcess<'a> {
    scene: &'a Scene,
    model: &'a crate::model::Model,
    solver: Solver,
    contact: Option<Contact>,
    /// Every slave node, once (the contact force is summed over them).
    slaves: Vec<u32>,
    x0: &'a [[f64; 3]],
    bodies0: &'a [[f64; 3]],
    /// The rigid bodies' positions when the contact force peaked.
    at_peak: Vec<[f64; 3]>,
    parts: &'a [PartNodes],
    bodies: &'a [(String, usize)],
    history: Option<std::io::BufWriter<std::fs::File>>,
    series: Option<crate::io::vtk::Series>,
    /// A deck's node and element output files as their steps ended (name, text).
    node_files: Vec<(String, String)>,
    /// How many of the deck's node, element and contact requests are written.
    outputs_done: (usize, usize, usize),
    /// A deck's node history requests' text so far (header and rows).
    history_texts: Vec<String>,
    /// The least energy the balance error is measured against (`Solver::energy_floor` at the
    /// start).
    floor: f64,
}

impl Ranks for OneProcess<'_> {
    fn time(&self) -> f64 {
        self.solver.time
    }

    fn advance(&mut self, step: f64, k: usize, last: bool) -> Result<Limits> {
        // the output variables only when a VTK frame or the final pressures need them
        if let Some(c) = self.contact.as_mut() {
            let frame = self.series.is_some() && (k + 1).is_multiple_of(self.scene.run.vtk_every);
            // a deck's contact output falls due at the end of this increment
            let printed = self.history.is_some()
                && super::deck_output::contact_due(
                    &self.scene.contact_outputs,
                    self.outputs_done.2,
                    self.solver.time + step,
                );
            c.request_outputs(last || frame || printed);
        }
        let t_start = self.solver.time;
        self.solver.step(step, self.contact.as_mut())?;
        let mut limits = Limits::default();
        if let Some(c) = self.contact.as_ref() {
            tunnelling(c, &self.solver, k + 1, t_start)?;
            if c.has_penalty_pairs() {
                let r = c.report();
                limits.penalty = Some((r.stable_dt, r.max_overclosure));
            }
            if c.has_kinematic_pairs() {
                limits.kinematic = Some(c.kinematic_report().max_overclosure);
            }
        }
        Ok(limits)
    }

    fn sums(&mut self, row: bool) -> Result<Sums> {
        let s = &self.solver;
        let mut force = [0.0; 3];
        for &n in &self.slaves {
            for a in 0..3 {
                force[a] += s.contact_force[n as usize][a];
            }
        }
        let moved = if row {
            body_displacements(s, self.bodies0)
        } else {
            Vec::new()
        };
        Ok(Sums {
            force,
            drift: s.energy_drift(),
            scale: s.energy_scale().max(self.floor),
            balance: s.energy.balance(),
            moved,
            kinetic_internal: [s.energy.kinetic, s.energy.internal],
        })
    }

    fn output(&mut self, k: usize, row: bool, force: f64, peak: bool) -> Result<()> {
        let s = &self.solver;
        if peak {
            self.at_peak = s.bodies.iter().map(|b| b.state.position).collect();
        }
        if let (Some(series), Some(c)) = (self.series.as_mut(), self.contact.as_ref()) {
            if k.is_multiple_of(self.scene.run.vtk_every) {
                let frame = crate::io::vtk::Frame::from_contact(self.model, c, &s.x)?;
                series.add(s.time, &frame)?;
            }
        }
        if let (Some(f), true) = (self.history.as_mut(), row) {
            let line = history_row(s, self.x0, self.bodies0, self.parts, self.bodies, force);
            writeln!(f, "{line}").map_err(output_error)?;
        }
        if let (true, Some(_)) = (row, self.history.as_ref()) {
            // a deck's history requests: rows while their step runs
            for (o, text) in self
                .scene
                .node_histories
                .iter()
                .zip(&mut self.history_texts)
            {
                let t = s.time;
                if t > o.from_time * (1.0 + 1e-12) && t <= o.at_time * (1.0 + 1e-12) {
                    *text += &super::deck_output::rows(o, self.parts, s, self.x0);
                }
            }
        }
        if self.history.is_some() {
            let nodes = super::deck_output::due(
                &self.scene.node_outputs,
                self.outputs_done.0,
                self.parts,
                s,
                self.x0,
            );
            let elements = super::deck_output::elements_due(
                &self.scene.element_outputs,
                self.outputs_done.1,
                self.parts,
                s,
            );
            self.outputs_done.0 += nodes.len();
            self.outputs_done.1 += elements.len();
            self.node_files.extend(nodes);
            self.node_files.extend(elements);
            let due = &self.scene.contact_outputs;
            if let (true, Some(c)) = (
                super::deck_output::contact_due(due, self.outputs_done.2, s.time),
                self.contact.as_ref(),
            ) {
                let frame = crate::io::vtk::Frame::from_contact(self.model, c, &s.x)?;
                let label = |n: usize| deck_label(self.scene, self.parts, n);
                let files = super::deck_output::contact_files(
                    due,
                    self.outputs_done.2,
                    s.time,
                    &frame,
                    &label,
                );
                self.outputs_done.2 += files.len();
                self.node_files.extend(files);
            }
        }
        Ok(())
    }
}

/// Model node `n`'s label in the deck its part came from (its index + 1 elsewhere).
fn deck_label(scene: &Scene, parts: &[PartNodes], n: usize) -> u64 {
    parts
        .iter()
        .zip(&scene.part)
        .find(|(p, _)| n >= p.base && n < p.base + p.count)
        .and_then(|(p, spec)| {
            let piece = spec.deck.as_ref()?;
            piece.mesh.node_labels.get(n - p.base).copied()
        })
        .unwrap_or(n as u64 + 1)
}

/// The error of a node that moved past its pair's search radius in the increment `k` from
/// `t_start` (the contact counted and named it).
fn tunnelling(c: &Contact, solver: &Solver, k: usize, t_start: f64) -> Result<()> {
    let (p, q) = (c.report(), c.kinematic_report());
    let fast = p.fast_nodes + q.fast_nodes;
    let fastest = [p.fastest, q.fastest]
        .into_iter()
        .flatten()
        .max_by(|a, b| (a.distance / a.radius).total_cmp(&(b.distance / b.radius)));
    let Some(f) = fastest else { return Ok(()) };
    Err(Error::Tunnelling {
        increment: k as u64,
        time: t_start,
        node: f.node,
        pair: f.pair.0,
        distance: f.distance,
        radius: f.radius,
        more: format!(
            "{}{}",
            if fast > 1 {
                format!(" ({} more nodes move that far)", fast - 1)
            } else {
                String::new()
            },
            // a node launched by a resolved overclosure is a blow-up, not a fast body
            if k > 1 {
                solver.blow_up_hint()
            } else {
                String::new()
            }
        ),
    })
}

/// One history row: time, energies, balance error, contact force, then each part's mean
/// displacement and velocity (mass-weighted) and each rigid body's.
fn history_row(
    solver: &Solver,
    x0: &[[f64; 3]],
    bodies0: &[[f64; 3]],
    parts: &[PartNodes],
    bodies: &[(String, usize)],
    force: f64,
) -> String {
    let e = &solver.energy;
    let mut row = format!(
        "{},{},{},{},{},{},{}",
        solver.time,
        e.kinetic,
        e.internal,
        e.external_work,
        e.contact_work,
        solver.balance_error(),
        force
    );
    for p in parts {
        let (u, v) = part_motion(solver, x0, p.base..p.base + p.count);
        for c in u.iter().chain(&v) {
            row.push_str(&format!(",{c}"));
        }
    }
    push_body_columns(&mut row, solver, bodies, bodies0);
    row
}

/// Each rigid body's history columns (`bodies`: name and index): its displacement from
/// `bodies0` and its velocity, appended to `row`.
pub(super) fn push_body_columns(
    row: &mut String,
    solver: &Solver,
    bodies: &[(String, usize)],
    bodies0: &[[f64; 3]],
) {
    for (_, k) in bodies {
        let b = &solver.bodies[*k].state;
        for a in 0..3 {
            row.push_str(&format!(",{}", b.position[a] - bodies0[*k][a]));
        }
        for a in 0..3 {
            row.push_str(&format!(",{}", b.velocity[a]));
        }
    }
}

/// Every rigid body's displacement from `bodies0` (a history row's `Sums::moved`).
pub(super) fn body_displacements(solver: &Solver, bodies0: &[[f64; 3]]) -> Vec<[f64; 3]> {
    (solver.bodies.iter().zip(bodies0))
        .map(|(b, p0)| std::array::from_fn(|a| b.state.position[a] - p0[a]))
        .collect()
}

/// What the run knows at its end beside the account: the parts, bodies and contact nodes, the
/// energies, small sliding's anchoring and the warnings about it.
#[allow(clippy::too_many_arguments)]
fn ends(
    device: &Device,
    built: Vec<String>,
    solver: &Solver,
    x0: &[[f64; 3]],
    bodies0: &[[f64; 3]],
    at_peak: &[[f64; 3]],
    part_nodes: &[PartNodes],
    body_names: &[(String, usize)],
    contact: Option<&Contact>,
    model: &crate::model::Model,
    adjusted: Option<crate::contact::OverclosureReport>,
    seconds_per_increment: f64,
) -> Ends {
    let mut parts = Vec::new();
    let mut el = 0;
    for p in part_nodes {
        let nodes = p.base..p.base + p.count;
        let m: f64 = nodes.clone().map(|n| solver.mass[n]).sum();
        let mean = |f: &dyn Fn(usize) -> [f64; 3]| {
            let mut s = [0.0; 3];
            for n in nodes.clone() {
                let v = f(n);
                for a in 0..3 {
                    s[a] += solver.mass[n] * v[a] / m;
                }
            }
            s
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 6], [f64::NEG_INFINITY; 6]);
        for k in el..el + p.elements {
            let s = stress6(solver.stress(k));
            for c in 0..6 {
                lo[c] = lo[c].min(s[c]);
                hi[c] = hi[c].max(s[c]);
            }
        }
        el += p.elements;
        if p.elements == 0 {
            (lo, hi) = ([0.0; 6], [0.0; 6]);
        }
        parts.push(PartSummary {
            name: p.name.clone(),
            displacement: mean(&|n| [0, 1, 2].map(|a| solver.x[n][a] - x0[n][a])),
            velocity: mean(&|n| solver.v[n]),
            stress_min: lo,
            stress_max: hi,
        });
    }
    let bodies = body_summaries(solver, body_names, bodies0, at_peak);
    let mut contact_nodes = Vec::new();
    let mut friction = 0.0;
    if let Some(c) = contact {
        let outs: Vec<(usize, &crate::contact::PairOutput)> = c
            .outputs()
            .into_iter()
            .map(|(id, o)| (id.0, o))
            .chain(
                c.rigid_outputs()
                    .into_iter()
                    .map(|(id, o)| (model.pairs().len() + id.0, o)),
            )
            .collect();
        for (pair, o) in outs {
            friction += o.frictional_dissipation;
            for (i, &n) in o.slaves.iter().enumerate() {
                let p = o.cpress.get(i).copied().unwrap_or(0.0);
                if p > 0.0 {
                    let f = o
                        .force
                        .get(i)
                        .map_or(0.0, |f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
                    contact_nodes.push(ContactNode {
                        contact: pair,
                        node: n,
                        position: solver.x[n as usize],
                        pressure: p,
                        force: f,
                    });
                }
            }
        }
    }
    let anchoring = contact.map(|c| c.anchoring()).unwrap_or_default();
    let mut warnings = Vec::new();
    warnings.extend(adjusted.as_ref().and_then(adjusted_warning));
    for a in anchoring.iter().filter(|a| !a.unanchored.is_empty()) {
        warnings.push(unanchored_warning(a));
    }
    let e = solver.energy;
    Ends {
        device: device.to_string(),
        built,
        end_time: solver.time,
        seconds_per_increment,
        energies: [e.kinetic, e.internal, e.external_work, e.contact_work],
        frictional_dissipation: friction,
        parts,
        bodies,
        contact_nodes,
        anchored_slaves: anchoring.iter().map(|a| a.anchored).sum(),
        unanchored_slaves: anchoring
            .iter()
            .flat_map(|a| a.unanchored.iter().copied())
            .collect(),
        warnings,
        global_searches: contact.map_or(0, |c| c.global_searches()),
        ranks: Vec::new(),
    }
}

/// The mean displacement (from `x0`) and velocity of `nodes`, weighted by their masses (plain
/// means when the nodes carry no mass).
fn part_motion(
    solver: &crate::explicit::Solver,
    x0: &[[f64; 3]],
    nodes: std::ops::Range<usize>,
) -> ([f64; 3], [f64; 3]) {
    let total: f64 = nodes.clone().map(|n| solver.mass[n]).sum();
    let count = nodes.len().max(1) as f64;
    let (mut u, mut v) = ([0.0; 3], [0.0; 3]);
    for n in nodes {
        let w = if total > 0.0 {
            solver.mass[n] / total
        } else {
            1.0 / count
        };
        for a in 0..3 {
            u[a] += w * (solver.x[n][a] - x0[n][a]);
            v[a] += w * solver.v[n][a];
        }
    }
    (u, v)
}

/// Each rigid body's end state (`names`: name and index), and its displacement from `bodies0`
/// to `at_peak` (the reference points at the start and when the contact force peaked).
pub(super) fn body_summaries(
    solver: &Solver,
    names: &[(String, usize)],
    bodies0: &[[f64; 3]],
    at_peak: &[[f64; 3]],
) -> Vec<BodySummary> {
    names
        .iter()
        .map(|(name, k)| BodySummary {
            name: name.clone(),
            position: solver.bodies[*k].state.position,
            velocity: solver.bodies[*k].state.velocity,
            displacement_at_peak_force: [0, 1, 2].map(|a| at_peak[*k][a] - bodies0[*k][a]),
        })
        .collect()
}

/// The warning about the slaves of an anchored pass that no master facet anchors.
pub(super) fn unanchored_warning(a: &crate::Anchoring) -> String {
    let shown: Vec<String> = a.unanchored.iter().take(8).map(|n| n.to_string()).collect();
    format!(
        "contact pair {}: {} of {} slave nodes project onto no master facet and are not \
         constrained (small sliding anchors each slave once, at the start): nodes {}{}",
        a.pair.0,
        a.unanchored.len(),
        a.slaves,
        shown.join(", "),
        if a.unanchored.len() > shown.len() {
            ", …"
        } else {
            ""
        }
    )
}

/// The warning about the slaves the start's overclosure adjustment moved, if it moved any.
pub(super) fn adjusted_warning(a: &crate::contact::OverclosureReport) -> Option<String> {
    (!a.moved.is_empty()).then(|| {
        format!(
            "{} slave nodes started overclosed and were moved onto their masters strain-free \
             (run.adjust_overclosure), by up to {:e}",
            a.moved.len(),
            a.max_distance
        )
    })
}
