//! What the solver says when a run goes wrong: the blow-up hint naming the node, the increment and
//! the contact overclosure behind it, the increment hint, and the divergence check.

use super::*;

/// The energy floor's share of the model's capacity (see [`Solver::energy_floor`]).
pub const ENERGY_FLOOR: f64 = 1e-12;

impl Solver {
    /// The largest of the kinetic, internal, external, contact and dissipated energies now
    /// (energy units).
    pub fn energy_scale(&self) -> f64 {
        let e = &self.energy;
        e.kinetic
            .abs()
            .max(e.internal.abs())
            .max(e.external_work.abs())
            .max(e.contact_work.abs())
            .max(e.damping.abs())
    }

    /// What to look at when the solution runs away: the largest overclosure contact resolved
    /// so far and when (an initial one resolved within one increment strains the elements
    /// under it), and the elements' stable increment.
    pub fn blow_up_hint(&self) -> String {
        let (h, at) = self.worst_overclosure;
        let increment = self.increment_hint();
        if h > 0.0 {
            format!(
                "; contact resolved an overclosure of {h:e} at increment {at}: an overclosure \
                 resolved within one increment strains the elements under it (an initial one: \
                 remove it from the mesh, or move the slave nodes onto the master strain-free \
                 first: `adjust_overclosure = true` in a scene's [run], \
                 Contact::adjust_initial_overclosure in code); else {increment}"
            )
        } else {
            format!(
                "; no contact overclosure was resolved: {increment}, the loads and the material"
            )
        }
    }

    /// What to check of the time increment: the one in force at the last step against the
    /// limits there were — the elements' stable increment, the penalty contact's — or why
    /// there was none.
    pub(super) fn increment_hint(&self) -> String {
        let (dt, contact) = self.last_increment;
        if dt == 0.0 {
            return "no increment has been taken yet".into();
        }
        let elements = if self.elements.is_empty() {
            "no elements limit it (the model has none)".to_string()
        } else {
            format!(
                "the elements' stable increment is {:e}",
                self.stable_increment()
            )
        };
        let contact = if contact.is_nan() {
            String::new()
        } else if contact.is_finite() {
            format!(
                ", the penalty contact's {contact:e} (take at most about half of it for \
                 contact that persists)"
            )
        } else {
            ", no penalty spring within reach limited it".to_string()
        };
        format!("check the increment in force, {dt:e}: {elements}{contact}")
    }

    /// An error naming the first input of the increment `dt` about to run that is not finite
    /// (or a damping that is negative, an increment not positive): the increment, gravity,
    /// damping, bulk viscosity, a node's load, a load curve's value, a body's load or moment —
    /// set through the library, say, mid-run. Caught before the increment uses it, so the
    /// message names it and not what it would blow up.
    pub(super) fn check_increment(&self, dt: f64) -> Result<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::BadParameter {
                name: "dt",
                value: dt.to_string(),
                expected: "must be finite and positive",
            });
        }
        self.check_inputs()
    }

    /// The inputs an increment takes from the solver's fields (see [`Self::check_increment`]).
    fn check_inputs(&self) -> Result<()> {
        // the message is only made when there is one: nothing allocated per increment
        let bad = |name: &'static str, value: String| {
            Err(Error::BadParameter {
                name,
                value: format!(
                    "{value} before increment {} (t = {:e})",
                    self.increments + 1,
                    self.time
                ),
                expected: "finite (and a damping not negative)",
            })
        };
        let finite = |v: &[f64; 3]| v.iter().all(|c| c.is_finite());
        if !finite(&self.gravity) {
            return bad("gravity", format!("{:?}", self.gravity));
        }
        for (name, v) in [
            ("damping", self.damping),
            ("bulk_viscosity", self.bulk_viscosity),
            ("bulk_viscosity_quadratic", self.bulk_viscosity_quadratic),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, format!("{v:e}"));
            }
        }
        if let Some((i, l)) = self.loads.iter().enumerate().find(|(_, l)| !finite(l)) {
            return bad("loads", format!("{l:?} on node {i}"));
        }
        if let Some(c) = self.load_curves.iter().find(|c| !c.value.is_finite()) {
            return bad(
                "load_curves",
                format!("{:e} on node {} direction {}", c.value, c.node, c.dof),
            );
        }
        for (k, b) in self.bodies.iter().enumerate() {
            if !(finite(&b.load) && finite(&b.moment)) {
                return bad(
                    "bodies",
                    format!("body {k}: load {:?}, moment {:?}", b.load, b.moment),
                );
            }
        }
        Ok(())
    }

    /// The element that sets [`Solver::stable_increment`] (the first of the smallest) and that
    /// increment, safety factor and bulk viscosity included; `None` without elements.
    pub fn governing_element(&self) -> Option<(usize, f64)> {
        let b = (self.bulk_viscosity, self.bulk_viscosity_quadratic);
        self.elements
            .iter()
            .map(|e| {
                let z = e.bulk_damping_ratio(&self.x, &self.v, b);
                self.safety * (e.stable_increment() * ((1.0 + z * z).sqrt() - z))
            })
            .enumerate()
            // f64::min's rule: a NaN increment is passed over
            .fold(None, |best: Option<(usize, f64)>, (k, dt)| match best {
                None if !dt.is_nan() => Some((k, dt)),
                Some((_, d)) if dt < d => Some((k, dt)),
                _ => best,
            })
    }

    /// Remembers the largest overclosure contact has resolved, and when.
    pub(super) fn note_overclosure(&mut self, h: f64) {
        if h > self.worst_overclosure.0 {
            self.worst_overclosure = (h, self.increments);
        }
    }

    /// An error naming the first node whose position or velocity is not finite or beyond
    /// single precision (the contact search's range): the solution has blown up.
    pub(super) fn check_diverged(&self) -> Result<()> {
        let limit = f32::MAX as f64;
        let bad = |v: &[f64; 3]| (0..3).find(|&a| !(v[a].abs() <= limit));
        let found = (0..self.x.len()).find_map(|i| {
            bad(&self.x[i])
                .map(|a| {
                    (
                        i,
                        format!("position ({})", ["x", "y", "z"][a]),
                        self.x[i][a],
                    )
                })
                .or_else(|| {
                    bad(&self.v[i]).map(|a| {
                        (
                            i,
                            format!("velocity ({})", ["x", "y", "z"][a]),
                            self.v[i][a],
                        )
                    })
                })
        });
        let Some((node, what, value)) = found else {
            return Ok(());
        };
        let cause = self.blow_up_hint();
        Err(Error::Diverged {
            increment: self.increments,
            time: self.time,
            node,
            what,
            value,
            cause,
        })
    }

    /// The energy balance error: the change of [`Energy::balance`] since the first increment,
    /// relative to the largest of the kinetic, internal, external, contact and dissipated
    /// energies now, or to [`Solver::energy_floor`] where they are all below it (a model at
    /// rest, whose energies are round-off).
    pub fn balance_error(&self) -> f64 {
        let floor = self.floor0.unwrap_or_else(|| self.energy_floor());
        self.energy_drift() / self.energy_scale().max(floor).max(1e-300)
    }

    /// The least energy the balance error is measured against (energy units): 10⁻¹² of the
    /// model's capacity — its elements' Young's modulus times their reference volume, plus the
    /// work its gravity and constant loads on free directions would do over its size (the
    /// diagonal of its nodes' box now; [`Solver::balance_error`] takes it at the first
    /// increment). Energies below it are round-off in any unit system: a
    /// body at rest reports no error, where relative to its own round-off it reported one of
    /// order 1.
    pub fn energy_floor(&self) -> f64 {
        let stiffness: f64 = self
            .elements
            .iter()
            .map(|e| e.mass() * e.material().young / e.material().density)
            .sum();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &self.x {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let size = (0..3)
            .map(|a| (hi[a] - lo[a]).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt();
        let mut pull = 0.0;
        for (i, held) in self.fixed.iter().enumerate() {
            for a in (0..3).filter(|&a| !held[a]) {
                let load = self.loads.get(i).map_or(0.0, |l| l[a]);
                pull += (self.mass[i] * self.gravity[a]).abs() + load.abs();
            }
        }
        for b in self.bodies.iter().filter(|b| b.motion == BodyMotion::Free) {
            for a in 0..3 {
                pull += (b.mass * self.gravity[a]).abs() + b.load[a].abs();
            }
        }
        let floor = ENERGY_FLOOR * (stiffness + pull * size);
        if floor.is_finite() {
            floor
        } else {
            0.0
        }
    }

    /// The change of [`Energy::balance`] since the first increment (energy units): what
    /// [`Solver::balance_error`] divides by [`Solver::energy_scale`].
    pub fn energy_drift(&self) -> f64 {
        (self.energy.balance() - self.balance0.unwrap_or(0.0)).abs()
    }
}
