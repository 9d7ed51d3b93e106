//! A deck's steps on one time line. Each step starts where the one before ended; what a step
//! gives a degree of freedom (a `*BOUNDARY`, a `*CLOAD`) acts from its start with its amplitude
//! in step time and, in later steps, stays at the value it reached at its step's end
//! (Abaqus' propagation) until a later step gives that degree of freedom another value or an
//! `OP=NEW` removes everything earlier steps gave. The controls (procedure, NLGEOM, increment,
//! bulk viscosity, mass scaling, output cadence) are the first step's in every step.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::error::Result;
use crate::explicit::{Amplitude, Motion};
use crate::io::inp::{Analysis, BoundaryDef, BoundaryKind, CloadDef, StepDef};

use super::refuse;

/// Where each step starts and ends on the run's time line.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Timeline {
    /// Step k's (from 1) start is `starts[k − 1]`; the run's end is `end`.
    pub starts: Vec<f64>,
    /// The run's end: the last step's end.
    pub end: f64,
}

impl Timeline {
    /// The steps' times from their time periods (each checked positive by the caller).
    pub fn new(steps: &[StepDef]) -> Self {
        let mut starts = Vec::with_capacity(steps.len());
        let mut t = 0.0;
        for s in steps {
            starts.push(t);
            t += s.time_period.unwrap_or(0.0);
        }
        Timeline { starts, end: t }
    }

    /// Step `k`'s start (0 for the model data, k = 0).
    pub fn start(&self, k: usize) -> f64 {
        k.checked_sub(1).map_or(0.0, |i| self.starts[i])
    }

    /// Step `k`'s end (the run's end for the model data, which is in force throughout).
    pub fn end_of(&self, k: usize) -> f64 {
        match k {
            0 => self.end,
            k => self.starts.get(k).copied().unwrap_or(self.end),
        }
    }
}

/// `a` in total time for a value given in step `k`: its points moved to the step's start.
pub(super) fn shifted(a: &Amplitude, t: &Timeline, k: usize) -> Amplitude {
    let t0 = t.start(k);
    Amplitude {
        smooth: a.smooth,
        points: a.points.iter().map(|&(s, v)| (s + t0, v)).collect(),
    }
}

/// A constant amplitude (1 throughout).
fn constant() -> Arc<Amplitude> {
    Arc::new(Amplitude {
        smooth: false,
        points: vec![(f64::NEG_INFINITY, 1.0)],
    })
}

/// One stretch of a degree of freedom's prescription: the motion, when it acts, and whether it
/// is a total displacement from the node's reference coordinate.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct MotionWindow {
    /// The motion (in total time).
    pub motion: Motion,
    /// `[from, until)`, total time.
    pub active: (f64, f64),
    /// A displacement (total, from the reference coordinate) rather than a velocity.
    pub total: bool,
    /// A zero displacement over the whole run (a plain fixed degree of freedom).
    pub fixed: bool,
}

/// One stretch of a load on a degree of freedom.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct LoadWindow {
    /// The magnitude the amplitude scales.
    pub value: f64,
    /// The amplitude (in total time).
    pub amplitude: Arc<Amplitude>,
    /// `[from, until)`, total time.
    pub active: (f64, f64),
}

/// Each degree of freedom's boundary windows, keyed by (node index, axis 0–2), from the deck's
/// `*BOUNDARY` entries (rotations and, in a plane model, z left out: the caller notes them).
/// `amplitude` gives a named amplitude's curve (none: applied at once) in step time.
pub(super) fn boundary_windows(
    a: &Analysis,
    t: &Timeline,
    two_d: bool,
    amplitude: &dyn Fn(&Option<String>) -> Arc<Amplitude>,
) -> BTreeMap<(u32, usize), Vec<MotionWindow>> {
    let mut open: BTreeMap<(u32, usize), (&BoundaryDef, f64)> = BTreeMap::new();
    let mut closed: Vec<((u32, usize), &BoundaryDef, f64, f64)> = Vec::new();
    for k in 0..=a.steps.len() {
        let start = t.start(k);
        if k > 0 && a.steps[k - 1].boundary_new {
            for (key, (def, from)) in std::mem::take(&mut open) {
                closed.push((key, def, from, start));
            }
        }
        for b in a.boundaries.iter().filter(|b| b.step == k) {
            for &n in &b.nodes {
                for d in b.first..=b.last {
                    if d > 3 || (two_d && d == 3) {
                        continue;
                    }
                    if let Some((def, from)) = open.insert((n, d - 1), (b, start)) {
                        closed.push(((n, d - 1), def, from, start));
                    }
                }
            }
        }
    }
    for (key, (def, from)) in open {
        closed.push((key, def, from, t.end));
    }
    let mut windows: BTreeMap<(u32, usize), Vec<MotionWindow>> = BTreeMap::new();
    for (key, b, from, until) in closed {
        if until <= from {
            continue; // replaced within its own step
        }
        let curve = Arc::new(shifted(&amplitude(&b.amplitude), t, b.step));
        let velocity = b.kind == BoundaryKind::Velocity;
        let own_end = t.end_of(b.step).min(until);
        let out = windows.entry(key).or_default();
        let whole_run = from == 0.0 && until >= t.end;
        out.push(MotionWindow {
            motion: Motion::Amplitude {
                value: b.value,
                amplitude: curve.clone(),
                velocity,
            },
            active: (from, own_end),
            total: !velocity,
            fixed: whole_run && own_end >= t.end && !velocity && b.value == 0.0,
        });
        if until > own_end {
            // propagated: held at the value it reached at its step's end
            let held = b.value * curve.value(own_end);
            out.push(MotionWindow {
                motion: if velocity {
                    Motion::Velocity(held)
                } else {
                    Motion::Amplitude {
                        value: held,
                        amplitude: constant(),
                        velocity: false,
                    }
                },
                active: (own_end, until),
                total: !velocity,
                fixed: false,
            });
        }
    }
    windows
}

/// Each degree of freedom's load windows, keyed by (node index, axis 0–2), from the deck's
/// `*CLOAD` entries on translations (several in one step add up).
pub(super) fn load_windows(
    a: &Analysis,
    t: &Timeline,
    amplitude: &dyn Fn(&Option<String>) -> Arc<Amplitude>,
) -> BTreeMap<(u32, usize), Vec<LoadWindow>> {
    // a degree of freedom's loads of one step, and when they began
    type Loads<'a> = (Vec<&'a CloadDef>, f64);
    let mut open: BTreeMap<(u32, usize), Loads> = BTreeMap::new();
    // … and when they ended
    let mut closed: Vec<((u32, usize), Loads, f64)> = Vec::new();
    for k in 1..=a.steps.len() {
        let start = t.start(k);
        if a.steps[k - 1].cload_new {
            for (key, loads) in std::mem::take(&mut open) {
                closed.push((key, loads, start));
            }
        }
        for c in a.cloads.iter().filter(|c| c.step == k && c.dof <= 3) {
            for &n in &c.nodes {
                let key = (n, c.dof - 1);
                match open.get_mut(&key) {
                    Some((defs, from)) if *from == start => defs.push(c),
                    _ => {
                        if let Some(loads) = open.insert(key, (vec![c], start)) {
                            closed.push((key, loads, start));
                        }
                    }
                }
            }
        }
    }
    for (key, loads) in open {
        closed.push((key, loads, t.end));
    }
    let mut windows: BTreeMap<(u32, usize), Vec<LoadWindow>> = BTreeMap::new();
    for (key, (defs, from), until) in closed {
        let step = defs[0].step;
        let own_end = t.end_of(step).min(until);
        let out = windows.entry(key).or_default();
        let mut held = 0.0;
        for c in defs {
            let curve = Arc::new(shifted(&amplitude(&c.amplitude), t, step));
            held += c.value * curve.value(own_end);
            out.push(LoadWindow {
                value: c.value,
                amplitude: curve,
                active: (from, own_end),
            });
        }
        if until > own_end {
            out.push(LoadWindow {
                value: held,
                amplitude: constant(),
                active: (own_end, until),
            });
        }
    }
    windows
}

/// Refuses a later step whose controls differ from the first's, naming it; and a later step's
/// procedure other than `*DYNAMIC, EXPLICIT` (several `*STATIC` steps are not run yet).
pub(super) fn check_controls(steps: &[StepDef]) -> Result<()> {
    let Some(first) = steps.first() else {
        return Ok(());
    };
    for s in &steps[1..] {
        if s.procedure.as_deref() != Some("DYNAMIC EXPLICIT")
            || first.procedure.as_deref() != Some("DYNAMIC EXPLICIT")
        {
            return refuse(
                &s.at,
                "several steps: abut runs several *DYNAMIC, EXPLICIT steps in order (a *STATIC step runs quasi-static alone)",
            );
        }
        let differs = [
            ("NLGEOM", s.nlgeom != first.nlgeom),
            (
                "the increment (DIRECT USER CONTROL)",
                s.fixed_increment != first.fixed_increment,
            ),
            ("SCALE FACTOR", s.scale_factor != first.scale_factor),
            ("*BULK VISCOSITY", s.bulk_viscosity != first.bulk_viscosity),
            ("*FIXED MASS SCALING", s.mass_scaling != first.mass_scaling),
            (
                "*OUTPUT's FREQUENCY",
                s.history_every != first.history_every || s.field_every != first.field_every,
            ),
        ];
        if let Some((what, _)) = differs.iter().find(|(_, d)| *d) {
            return refuse(
                &s.at,
                format!(
                    "this step changes {what}: abut runs every step with the first step's controls"
                ),
            );
        }
    }
    Ok(())
}

/// Refuses gravity given in a later step, and a rigid body's reference node whose boundary
/// conditions or loads change between steps (rigid bodies move one way through every step).
pub(super) fn refuse_across_steps(a: &Analysis, ref_nodes: &BTreeMap<u32, usize>) -> Result<()> {
    if let Some(g) = a.gravity.iter().find(|g| g.step > 1) {
        return refuse(
            &g.at,
            "*DLOAD, GRAV in a later step: abut applies gravity from the start of the run",
        );
    }
    if a.steps.len() < 2 {
        return Ok(());
    }
    let removed = a
        .steps
        .iter()
        .skip(1)
        .any(|s| s.boundary_new || s.cload_new);
    let on_reference = |nodes: &[u32]| nodes.iter().any(|n| ref_nodes.contains_key(n));
    let at = a
        .boundaries
        .iter()
        .filter(|b| on_reference(&b.nodes) && (b.step > 1 || removed))
        .map(|b| &b.at)
        .chain(
            a.cloads
                .iter()
                .filter(|c| on_reference(&c.nodes) && (c.step > 1 || removed))
                .map(|c| &c.at),
        )
        .next();
    match at {
        Some(at) => refuse(
            at,
            "a rigid body's reference node given a boundary condition or load that changes between steps: abut moves a rigid body the same way through every step",
        ),
        None => Ok(()),
    }
}

/// The deck note of a run of `count` steps.
pub(super) fn note(count: usize, t: &Timeline) -> String {
    let ends: Vec<String> = t
        .starts
        .iter()
        .skip(1)
        .chain([&t.end])
        .map(|e| format!("{e:e}"))
        .collect();
    format!(
        "{count} steps run in order on one time line, ending at {}: each step's boundary conditions and loads act from its start, in step time, and stay at their end values in later steps until replaced (OP=NEW removes them)",
        ends.join(", ")
    )
}
