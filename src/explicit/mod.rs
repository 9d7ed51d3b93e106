//! The small explicit solver that uses abut the way a host program would: central differences
//! with lumped masses, St Venant–Kirchhoff bars, plane-strain triangles and tetrahedra, point
//! masses, gravity, fixed degrees of freedom, mass-proportional damping, penalty and kinematic
//! contact through [`crate::Contact`], and energy bookkeeping with the balance error.

pub mod elements;

pub use elements::{Element, Material};

use crate::contact::Contact;
use crate::error::{Error, Result};

/// Energies since the start (model units).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// Kinetic energy at the start of the last increment (the mean of the half-step
    /// velocities around it).
    pub kinetic: f64,
    /// Strain energy now.
    pub internal: f64,
    /// Work done by gravity and external forces.
    pub external_work: f64,
    /// Work done by contact: penalty forces, and kinematic corrections taken as the forces
    /// m·Δv/dt that would make them (negative: dissipated).
    pub contact_work: f64,
    /// Energy removed by damping.
    pub damping: f64,
}

impl Energy {
    /// Total energy minus the work put in: constant for an exact integrator.
    pub fn balance(&self) -> f64 {
        self.kinetic + self.internal - self.external_work - self.contact_work + self.damping
    }
}

/// The state and model of an explicit run.
#[derive(Clone, Debug)]
pub struct Solver {
    /// Positions (model units).
    pub x: Vec<[f64; 3]>,
    /// Velocities, at the half step before the current positions.
    pub v: Vec<[f64; 3]>,
    /// Lumped nodal masses.
    pub mass: Vec<f64>,
    /// Elements.
    pub elements: Vec<Element>,
    /// Fixed degrees of freedom per node.
    pub fixed: Vec<[bool; 3]>,
    /// Gravity (acceleration).
    pub gravity: [f64; 3],
    /// Constant external forces per node.
    pub loads: Vec<[f64; 3]>,
    /// Mass-proportional damping coefficient α (force −α·m·v).
    pub damping: f64,
    /// Safety factor on the elements' stable increment.
    pub safety: f64,
    /// Time reached.
    pub time: f64,
    /// Energies.
    pub energy: Energy,
    /// Contact force on each node in the last increment (penalty forces, and kinematic
    /// corrections as the forces m·Δv/dt that would make them).
    pub contact_force: Vec<[f64; 3]>,
    started: bool,
    balance0: Option<f64>,
    /// (external, contact, damping) power at the last step's time, and the increment since.
    last_power: Option<([f64; 3], f64)>,
}

impl Solver {
    /// A solver over nodes at `x` with `elements`; nodal masses are the elements' lumped masses
    /// (equal shares) plus `point_masses` (one per node, 0 for none). Errors name a node with
    /// no mass.
    pub fn new(x: Vec<[f64; 3]>, elements: Vec<Element>, point_masses: &[f64]) -> Result<Self> {
        if point_masses.len() != x.len() {
            return Err(Error::LengthMismatch {
                what: "point masses (one per node)",
                expected: x.len(),
                got: point_masses.len(),
            });
        }
        let mut mass = point_masses.to_vec();
        for e in &elements {
            let share = e.mass() / e.nodes().len() as f64;
            for &n in e.nodes() {
                mass[n as usize] += share;
            }
        }
        if let Some(n) = mass.iter().position(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(Error::BadMass {
                node: n,
                mass: mass[n],
            });
        }
        let n = x.len();
        Ok(Self {
            v: vec![[0.0; 3]; n],
            fixed: vec![[false; 3]; n],
            loads: vec![[0.0; 3]; n],
            x,
            mass,
            elements,
            gravity: [0.0; 3],
            damping: 0.0,
            safety: 0.9,
            time: 0.0,
            energy: Energy::default(),
            contact_force: vec![[0.0; 3]; n],
            started: false,
            balance0: None,
            last_power: None,
        })
    }

    /// The largest stable increment of the elements, times the safety factor (∞ with none).
    pub fn stable_increment(&self) -> f64 {
        self.safety
            * self
                .elements
                .iter()
                .map(Element::stable_increment)
                .fold(f64::INFINITY, f64::min)
    }

    /// Internal forces at the current positions, and the strain energy.
    pub fn internal_forces(&self) -> (Vec<[f64; 3]>, f64) {
        let mut f = vec![[0.0; 3]; self.x.len()];
        let w = self
            .elements
            .iter()
            .map(|e| e.add_internal_forces(&self.x, &mut f))
            .sum();
        (f, w)
    }

    /// One central-difference increment of `dt` (the first moves velocities by half an
    /// increment, Abaqus' start), with penalty forces and kinematic corrections from
    /// `contact` when given.
    pub fn step(&mut self, dt: f64, mut contact: Option<&mut Contact>) -> Result<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::BadParameter {
                name: "dt",
                value: dt.to_string(),
                expected: "must be finite and positive",
            });
        }
        let (f_int, internal) = self.internal_forces();
        let n = self.x.len();
        let mut penalty = vec![[0.0; 3]; n];
        if let Some(c) = contact.as_deref_mut() {
            if c.has_penalty_pairs() {
                penalty = c.penalty_step(&self.x, &self.v, dt)?.forces.clone();
            }
        }
        // velocity update (the first moves by half an increment), prediction of positions
        let dv_scale = if self.started { dt } else { 0.5 * dt };
        let v_old = self.v.clone();
        let mut ext = vec![[0.0; 3]; n];
        let mut damp = vec![[0.0; 3]; n];
        for i in 0..n {
            for a in 0..3 {
                if self.fixed[i][a] {
                    self.v[i][a] = 0.0;
                    continue;
                }
                ext[i][a] = self.loads[i][a] + self.mass[i] * self.gravity[a];
                damp[i][a] = -self.damping * self.mass[i] * self.v[i][a];
                self.v[i][a] += dv_scale * (f_int[i][a] + ext[i][a] + penalty[i][a] + damp[i][a])
                    / self.mass[i];
                self.x[i][a] += dt * self.v[i][a];
            }
        }
        // kinematic contact corrects the predicted state; it acts as the force m·Δv/dv_scale
        // would have in the velocity update
        let mut kinematic = vec![[0.0; 3]; n];
        if let Some(c) = contact {
            if c.has_kinematic_pairs() {
                let v_pred = self.v.clone();
                c.kinematic_step(&mut self.x, &mut self.v, &mut [], dt)?;
                for i in 0..n {
                    for a in 0..3 {
                        kinematic[i][a] = self.mass[i] * (self.v[i][a] - v_pred[i][a]) / dv_scale;
                    }
                }
            }
        }
        for i in 0..n {
            for a in 0..3 {
                self.contact_force[i][a] = penalty[i][a] + kinematic[i][a];
            }
        }
        // energies at this step's time: velocities there are the mean of the half-step ones
        // around it (at the start, the initial velocity)
        let (mut kinetic, mut p_ext, mut p_con, mut p_damp) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            for a in 0..3 {
                let v_now = if self.started {
                    0.5 * (v_old[i][a] + self.v[i][a])
                } else {
                    v_old[i][a]
                };
                kinetic += 0.5 * self.mass[i] * v_now * v_now;
                p_ext += ext[i][a] * v_now;
                p_con += (penalty[i][a] + kinematic[i][a]) * v_now;
                p_damp -= damp[i][a] * v_now;
            }
        }
        // work since the last step by the trapezoidal rule on the powers at the two times
        let power = [p_ext, p_con, p_damp];
        if let Some((last, h)) = self.last_power {
            self.energy.external_work += 0.5 * (last[0] + power[0]) * h;
            self.energy.contact_work += 0.5 * (last[1] + power[1]) * h;
            self.energy.damping += 0.5 * (last[2] + power[2]) * h;
        }
        self.last_power = Some((power, dt));
        self.started = true;
        self.time += dt;
        self.energy.internal = internal;
        self.energy.kinetic = kinetic;
        self.balance0.get_or_insert(self.energy.balance());
        Ok(())
    }

    /// The energy balance error: the change of [`Energy::balance`] since the first increment,
    /// relative to the largest of the kinetic, internal and external energies seen now.
    pub fn balance_error(&self) -> f64 {
        let e = &self.energy;
        let scale = e
            .kinetic
            .abs()
            .max(e.internal.abs())
            .max(e.external_work.abs())
            .max(e.contact_work.abs())
            .max(1e-300);
        (e.balance() - self.balance0.unwrap_or(0.0)).abs() / scale
    }
}
