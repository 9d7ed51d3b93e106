//! What a scene run accounts for increment by increment — the increment and the limits that
//! set it, the contact force history, the energy balance, timing and traffic — and the summary
//! built from it: one account for the run in one process (`run_into` in `run.rs`) and the run
//! across MPI ranks (`distributed.rs`), which differ only in how they take an increment and add
//! up the ranks' shares.

use std::time::Instant;

use super::force_history::ForceHistory;
use super::summary::QuasiStaticSummary;
use super::{CurveSample, Progress, RunSpec, Scene, Summary};
use crate::device::{Device, Traffic};
use crate::error::{Error, Result};

/// Samples the force–displacement curve keeps at most; a power of two (about 0.5 MB of
/// `summary.json` with one rigid body).
pub const CURVE_SAMPLES: usize = 1 << 12;

/// A run's accumulators.
pub(super) struct Account<'a> {
    run: &'a RunSpec,
    /// The elements' stable increment (the whole model's).
    pub element_dt: f64,
    /// The increment in force: `run.dt`, or the elements' and the contact's combined.
    pub dt: f64,
    /// Increments taken.
    pub k: usize,
    /// The largest penetration reported.
    pen: f64,
    /// The smallest stable increment penalty contact reported.
    contact_dt: f64,
    /// The energy balance's largest drift and the largest energy (its scale).
    drift: f64,
    scale: f64,
    /// Each increment's middle and the total contact force then (in blocks past
    /// `force_history::FORCE_BLOCKS` increments).
    forces: ForceHistory,
    /// The force–displacement curve, at most [`CURVE_SAMPLES`] samples, one every
    /// `curve_stride` output rows.
    curve: Vec<CurveSample>,
    curve_stride: usize,
    /// Output rows so far.
    rows: usize,
    /// The contact force at the last increment.
    pub final_force: [f64; 3],
    peak: f64,
    /// Seconds of the first increment.
    pub first_seconds: f64,
    traffic0: Option<Traffic>,
    t_steady: Instant,
    /// Where penalty contact lowered the increment below the elements' limit: the smallest
    /// ratio and the first time.
    lowest_ratio: f64,
    lowered_from: f64,
    /// A fixed `run.dt` above the penalty contact's stable increment: the largest ratio and
    /// when it first happened.
    over_ratio: f64,
    over_from: f64,
    /// Kinetic over internal energy: at the end of a quasi-static ramp, the last, and the
    /// largest from half the ramp on.
    ke_ie: [f64; 3],
    /// A quasi-static run's ramp time (NaN otherwise).
    pub ramp: f64,
}

impl<'a> Account<'a> {
    /// The account of a run of `run` whose elements allow `element_dt`; an error when there is
    /// no increment at all (no elements and no `run.dt`).
    pub fn new(run: &'a RunSpec, element_dt: f64) -> Result<Self> {
        let dt = run.dt.unwrap_or(element_dt);
        if !dt.is_finite() {
            return Err(Error::BadParameter {
                name: "run.dt",
                value: "none".into(),
                expected: "a scene without elements needs a fixed increment",
            });
        }
        Ok(Self {
            run,
            element_dt,
            dt,
            k: 0,
            pen: 0.0,
            contact_dt: f64::INFINITY,
            // the balance error is judged against the largest energy of the run: early on,
            // when every energy is still near zero, the first contact's round-off would read as
            // a large fraction
            drift: 0.0,
            scale: 0.0,
            forces: ForceHistory::default(),
            curve: Vec::new(),
            curve_stride: 1,
            rows: 0,
            final_force: [0.0; 3],
            peak: 0.0,
            first_seconds: 0.0,
            traffic0: None,
            t_steady: Instant::now(),
            lowest_ratio: 1.0,
            lowered_from: f64::NAN,
            over_ratio: 1.0,
            over_from: f64::NAN,
            ke_ie: [f64::NAN, f64::NAN, 0.0],
            ramp: f64::NAN,
        })
    }

    /// Whether a run at `time` has time left.
    pub fn running(&self, time: f64) -> bool {
        time < self.run.end_time * (1.0 - 1e-12)
    }

    /// Whether an increment of `step` from `time` is the run's last.
    pub fn is_last(&self, time: f64, step: f64) -> bool {
        time + step >= self.run.end_time * (1.0 - 1e-12)
    }

    /// The next increment from `time` (the last one shortened to end on time), noting where
    /// contact has lowered it below the elements' limit.
    pub fn step(&mut self, time: f64) -> f64 {
        // the next end: a deck step's, else the run's
        let end = self
            .run
            .step_ends
            .iter()
            .copied()
            .find(|&t| t > time + 1e-12 * self.run.end_time)
            .unwrap_or(self.run.end_time);
        let step = self.dt.min(end - time);
        // (round-off of the combined formula aside)
        if self.run.dt.is_none() && self.dt < self.element_dt * (1.0 - 1e-12) {
            self.lowest_ratio = self.lowest_ratio.min(self.dt / self.element_dt);
            if self.lowered_from.is_nan() && self.dt < 0.999 * self.element_dt {
                self.lowered_from = time;
            }
        }
        step
    }

    /// Counts an increment that reached `time` (`t_step`: when it started), reports progress,
    /// and after the first one starts the steady-state clock and traffic.
    pub fn counted(
        &mut self,
        time: f64,
        t_step: Instant,
        device: &Device,
        progress: &mut dyn FnMut(&Progress),
    ) {
        self.k += 1;
        progress(&Progress {
            increment: self.k as u64,
            estimated: (self.k as u64)
                .saturating_add(super::increments_for(self.run.end_time - time, self.dt)),
            time,
            end_time: self.run.end_time,
        });
        if self.k == 1 {
            self.first_seconds = t_step.elapsed().as_secs_f64();
            self.traffic0 = device.traffic();
            self.t_steady = Instant::now();
        }
    }

    /// Penalty contact's stable increment `stable` and largest overclosure after an increment
    /// of `step` from `t_start`: the increment that follows both limits (a node carries its
    /// elements' and its contact springs' stiffness together: the frequencies add in square,
    /// 1/dt² = 1/dt_e² + 1/(safety·dt_c)², the same safety on both; and a spring that switches
    /// on and off must stay at ω·dt ≤ 2·contact_safety, where central differences do not pump
    /// energy), or with a fixed `run.dt` how far it exceeds the contact's.
    pub fn penalty_limit(&mut self, stable: f64, overclosure: f64, step: f64, t_start: f64) {
        self.contact_dt = self.contact_dt.min(stable);
        if self.run.dt.is_some() && step > stable * (1.0 + 1e-9) {
            if self.over_from.is_nan() {
                self.over_from = t_start;
            }
            self.over_ratio = self.over_ratio.max(step / stable);
        }
        if self.run.dt.is_none() {
            self.dt = crate::combined_increment(
                self.element_dt,
                stable,
                self.run.safety,
                self.run.contact_safety,
            );
        }
        self.overclosure(overclosure);
    }

    /// A penetration reported (penalty or kinematic).
    pub fn overclosure(&mut self, pen: f64) {
        self.pen = self.pen.max(pen);
    }

    /// The total contact force `f` on the slaves after an increment of `step` ending at
    /// `time`: its magnitude, and whether it is the run's largest so far.
    pub fn force(&mut self, time: f64, step: f64, f: [f64; 3]) -> (f64, bool) {
        self.final_force = f;
        let force = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
        let peak = force > self.peak;
        self.peak = self.peak.max(force);
        self.forces.push(time, step, force);
        (force, peak)
    }

    /// Whether this increment writes an output row (and a curve sample).
    pub fn row(&self) -> bool {
        self.k.is_multiple_of(self.run.output_every.max(1))
    }

    /// An output row's sample of the force–displacement curve at `time` (the rigid bodies'
    /// displacements), kept when it falls on the curve's stride; a full curve keeps every
    /// other sample and doubles its stride, so that it stays within [`CURVE_SAMPLES`].
    pub fn sample(&mut self, time: f64, body_displacement: Vec<[f64; 3]>) {
        let row = self.rows;
        self.rows += 1;
        if !row.is_multiple_of(self.curve_stride) {
            return;
        }
        self.curve.push(CurveSample {
            time,
            force: self.final_force,
            body_displacement,
        });
        if self.curve.len() == CURVE_SAMPLES {
            let mut k = 0;
            self.curve.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.curve_stride *= 2;
        }
    }

    /// Kinetic and internal energy after the increment to `time`: their ratio at the end of a
    /// quasi-static ramp, at the end, and its largest from half the ramp on.
    pub fn kinetic_internal(&mut self, time: f64, [kinetic, internal]: [f64; 2]) {
        let ratio = if internal > 0.0 {
            kinetic / internal
        } else {
            f64::NAN
        };
        self.ke_ie[1] = ratio;
        if time >= self.ramp && self.ke_ie[0].is_nan() {
            self.ke_ie[0] = ratio;
        }
        if time >= 0.5 * self.ramp && ratio.is_finite() {
            self.ke_ie[2] = self.ke_ie[2].max(ratio);
        }
    }

    /// The energy balance's drift and scale after the increment to `time`; an error when the
    /// energy is no longer finite.
    pub fn energy(&mut self, drift: f64, scale: f64, balance: f64, time: f64) -> Result<()> {
        self.drift = self.drift.max(drift);
        self.scale = self.scale.max(scale);
        if !balance.is_finite() {
            return Err(Error::BadParameter {
                name: "run",
                value: format!("energy not finite at t = {time}"),
                expected: "a stable run (reduce run.dt or the penalty scale)",
            });
        }
        Ok(())
    }

    /// Seconds per increment after the first.
    pub fn seconds_per_increment(&self) -> f64 {
        self.t_steady.elapsed().as_secs_f64() / self.steady()
    }

    /// Increments after the first (at least one).
    fn steady(&self) -> f64 {
        self.k.saturating_sub(1).max(1) as f64
    }

    /// The summary of the run: what the account holds, and `ends`, what only the caller knows.
    pub fn summary(self, scene: &Scene, device: &Device, ends: Ends) -> Summary {
        let steady = self.steady();
        let traffic = match (device.traffic(), self.traffic0) {
            (Some(now), Some(then)) => now.since(&then),
            _ => Traffic::default(),
        };
        let stats = force_stats(&self.forces, self.dt);
        let curve_every = self.run.output_every.max(1) * self.curve_stride;
        let (governing_limit, increment_note) = governing_limit(
            self.run.dt.is_some(),
            self.contact_dt.is_finite(),
            self.lowest_ratio,
            self.lowered_from,
            stats.start,
            self.run.contact_safety,
        );
        let mut warnings = scene.notes();
        if self.over_ratio > 1.0 {
            warnings.push(over_increment_warning(
                self.run.dt.unwrap_or(f64::NAN),
                self.over_ratio,
                self.over_from,
                self.run.contact_safety,
            ));
        }
        warnings.extend(ends.warnings);
        let [kinetic, internal, external_work, contact_work] = ends.energies;
        Summary {
            title: scene.title.clone(),
            anchored_slaves: ends.anchored_slaves,
            unanchored_slaves: ends.unanchored_slaves,
            warnings,
            deck_notes: scene.deck_notes.clone(),
            quasi_static: scene
                .quasi_static
                .clone()
                .map(|settings| QuasiStaticSummary {
                    settings,
                    kinetic_to_internal_at_ramp_end: self.ke_ie[0],
                    kinetic_to_internal_at_end: self.ke_ie[1],
                    kinetic_to_internal_max: self.ke_ie[2],
                }),
            reference: scene.reference.clone(),
            device: ends.device,
            built: ends.built,
            increments: self.k,
            end_time: ends.end_time,
            first_increment_seconds: self.first_seconds,
            seconds_per_increment: ends.seconds_per_increment,
            element_increment: self.element_dt,
            contact_increment: self.contact_dt,
            governing_limit,
            contact_lowered_increment: 1.0 - self.lowest_ratio,
            contact_limit_from: self.lowered_from,
            increment_note,
            contact_start: stats.start,
            contact_end: stats.end,
            impact_time: stats.impact,
            release_time: stats.release,
            peak_force: self.peak,
            plateau_force: stats.plateau,
            mean_force: stats.mean,
            impulse: stats.impulse,
            final_contact_force: self.final_force,
            max_penetration: self.pen,
            energy_balance_error: if self.scale > 0.0 {
                self.drift / self.scale
            } else {
                0.0
            },
            kinetic,
            internal,
            external_work,
            contact_work,
            frictional_dissipation: ends.frictional_dissipation,
            parts: ends.parts,
            bodies: ends.bodies,
            contact_nodes: ends.contact_nodes,
            curve: self.curve,
            curve_every,
            force_history_every: self.forces.per_entry(),
            dispatches_per_increment: traffic
                .dispatches
                .iter()
                .map(|(k, v)| (k.clone(), *v as f64 / steady))
                .collect(),
            uploaded_bytes_per_increment: traffic.uploaded_bytes as f64 / steady,
            read_back_bytes_per_increment: traffic.read_back_bytes as f64 / steady,
            global_searches: ends.global_searches,
            ranks: ends.ranks,
        }
    }
}

/// What only the run itself knows at its end, for [`Account::summary`].
pub(super) struct Ends {
    /// Where it ran.
    pub device: String,
    /// What it built, in words.
    pub built: Vec<String>,
    /// The time reached.
    pub end_time: f64,
    /// Seconds per increment after the first (across ranks: the slowest rank's).
    pub seconds_per_increment: f64,
    /// Kinetic, internal, external and contact energies at the end.
    pub energies: [f64; 4],
    /// Energy friction dissipated.
    pub frictional_dissipation: f64,
    /// Each part's motion and stresses.
    pub parts: Vec<super::PartSummary>,
    /// Each rigid body's.
    pub bodies: Vec<super::BodySummary>,
    /// The slaves in contact at the end.
    pub contact_nodes: Vec<super::ContactNode>,
    /// Small sliding: slaves anchored, and those left unconstrained.
    pub anchored_slaves: usize,
    /// The slaves no anchor holds.
    pub unanchored_slaves: Vec<u32>,
    /// Warnings after the scene's notes and the fixed increment's.
    pub warnings: Vec<String>,
    /// Global searches of the penalty pairs.
    pub global_searches: u64,
    /// Each rank's share (empty in one process).
    pub ranks: Vec<super::RankSummary>,
}

/// What the contact force history (time of each increment's middle, total force) says: first
/// and last time with force, the half-plateau edges, impulse, plateau and mean force.
struct ForceStats {
    start: f64,
    end: f64,
    impact: f64,
    release: f64,
    impulse: f64,
    plateau: f64,
    mean: f64,
}

fn force_stats(history: &ForceHistory, dt: f64) -> ForceStats {
    let (first, last) = history.contact_span();
    let forces = &history.entries();
    let (impact, release, impulse, plateau) = super::half_plateau_edges(forces);
    // once merged into blocks, the impulse as summed increment by increment
    let impulse = if history.per_entry() > 1 {
        history.impulse()
    } else {
        impulse
    };
    ForceStats {
        start: first.map_or(f64::NAN, |t| t - 0.5 * dt),
        end: last.map_or(f64::NAN, |t| t + 0.5 * dt),
        impact,
        release,
        impulse,
        plateau,
        mean: if release > impact {
            let inside: f64 = forces
                .windows(2)
                .filter(|w| w[1].0 > impact && w[0].0 < release)
                .map(|w| w[1].1 * (w[1].0 - w[0].0))
                .sum();
            inside / (release - impact)
        } else {
            0.0
        },
    }
}

impl Account<'_> {
    /// `e` with what the account knows of its cause: a fixed `run.dt` over the penalty
    /// contact's stable increment (the warning a finished run would have printed) is named in a
    /// divergence or a non-finite result before the hints about overclosures and elements, and
    /// in a tunnelling node's error as what sped it up.
    pub fn explain(&self, e: Error) -> Error {
        if !(self.over_ratio > 1.0) {
            return e;
        }
        let over = over_increment_warning(
            self.run.dt.unwrap_or(f64::NAN),
            self.over_ratio,
            self.over_from,
            self.run.contact_safety,
        );
        let mut e = e;
        match &mut e {
            Error::Diverged { cause, .. } => *cause = format!("; first, {over}. Also{cause}"),
            Error::NonFiniteResult { cause, .. } => {
                *cause = format!("first, {over}; also, {cause}");
            }
            Error::Tunnelling { more, .. } => *more = format!("; what sped it up: {over}{more}"),
            Error::BadParameter {
                name: "run", value, ..
            } => *value = format!("{value}; first, {over}"),
            _ => {}
        }
        e
    }
}

/// The warning of a fixed `run_dt` that exceeded the penalty contact's stable increment by up
/// to `over_ratio`, from `over_from`.
fn over_increment_warning(run_dt: f64, over_ratio: f64, over_from: f64, safety: f64) -> String {
    format!(
        "run.dt = {run_dt:e} exceeds the penalty contact's stable increment (by up to \
         {over_ratio:.3}×, from t = {over_from:e}): central differences are unstable there and \
         the contact results cannot be trusted. Lower run.dt below it — with the automatic \
         stiffness, which follows the first increment (k ∝ 1/run.dt²), multiply the contact's \
         penalty_scale by {:.3e} or less instead (ω·Δt ≤ 1, run.contact_safety) — or, in a \
         scene with elements, leave run.dt out and the increment follows both limits",
        (safety / over_ratio).powi(2)
    )
}

/// The summary's account of the increment: its governing limit and a note in words.
fn governing_limit(
    fixed: bool,
    contact_limit: bool,
    lowest_ratio: f64,
    lowered_from: f64,
    contact_start: f64,
    safety: f64,
) -> (String, String) {
    if fixed {
        return (
            "fixed".into(),
            "the increment is fixed by run.dt; the stability limits are not applied".into(),
        );
    }
    if !contact_limit || lowered_from.is_nan() {
        let why = if contact_limit {
            "penalty contact's limit stayed far above it"
        } else {
            "no penalty pair reported a limit"
        };
        return (
            "elements".into(),
            format!("the elements' stable increment times the safety factor set it; {why}"),
        );
    }
    let lowered = format!(
        "penalty contact (its stable increment times contact_safety = {safety}) lowered the \
         increment by up to {:.1} % below the elements' from t = {lowered_from:.6e}",
        100.0 * (1.0 - lowest_ratio)
    );
    let why = if contact_start.is_nan() || lowered_from < contact_start {
        " — before any contact force acted, because the springs of slave nodes within the \
         search radius set their limit before they touch (one may close within an increment)"
    } else {
        ""
    };
    ("elements and contact".into(), format!("{lowered}{why}"))
}
