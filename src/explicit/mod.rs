//! The small explicit solver that uses abut the way a host program would: central differences
//! with lumped masses, St Venant–Kirchhoff bars, plane-strain triangles and tetrahedra, point
//! masses, rigid bodies carrying mesh nodes and analytical surfaces, gravity, fixed and
//! prescribed motions, mass-proportional damping and linear bulk viscosity, penalty and
//! kinematic contact through [`crate::Contact`], and energy bookkeeping with the balance error.

mod corrector;
mod diagnostics;
pub mod elements;
pub mod hexahedron;
mod prescribed;
mod rigid;

pub use prescribed::{Amplitude, LoadCurve, Motion, Prescribed};

pub use corrector::KinematicCorrector;
pub use elements::{Element, Material};
pub use hexahedron::{Hex8, Integration};
pub use rigid::{BodyMotion, ResultantRow, SolverBody};

use crate::contact::Contact;
use crate::error::{Error, Result};
use crate::kinematic::BodyState;

/// Energies since the start (model units).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// Kinetic energy at the start of the last increment (the mean of the half-step
    /// velocities around it).
    pub kinetic: f64,
    /// Strain energy now.
    pub internal: f64,
    /// Work done by gravity, loads and prescribed motions: the forces that hold prescribed
    /// degrees of freedom of nodes, and rigid bodies fixed or moved at a set velocity, on their
    /// paths.
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
    /// Prescribed motions of single degrees of freedom.
    pub prescribed: Vec<Prescribed>,
    /// Rigid bodies. Body k is the contact model's `BodyId(k)` when the model has one: bodies
    /// carrying analytical surfaces come first, in the model's order.
    pub bodies: Vec<SolverBody>,
    /// Gravity (acceleration).
    pub gravity: [f64; 3],
    /// Constant external forces per node.
    pub loads: Vec<[f64; 3]>,
    /// Loads on single degrees of freedom, each on its own curve and window (added to `loads`).
    pub load_curves: Vec<LoadCurve>,
    /// A curve of time scaling `loads` and the bodies' loads and moments (a quasi-static run's
    /// smooth ramp); none: the loads as they are.
    pub load_factor: Option<std::sync::Arc<Amplitude>>,
    /// Mass-proportional damping coefficient α (force −α·m·v).
    pub damping: f64,
    /// Linear bulk viscosity b1 (Abaqus' default is 0.06, scenes' too; 0 = none).
    pub bulk_viscosity: f64,
    /// Quadratic bulk viscosity b2, acting in compression only (Abaqus' default is 1.2, scenes'
    /// too; 0 = none).
    pub bulk_viscosity_quadratic: f64,
    /// Large-strain kinematics (true, the default) or small strain (Abaqus' NLGEOM=NO, see
    /// [`Element::add_internal_forces_with`]).
    pub nlgeom: bool,
    /// Safety factor on the elements' stable increment.
    pub safety: f64,
    /// Time reached.
    pub time: f64,
    /// Energies.
    pub energy: Energy,
    /// Contact force on each node in the last increment (penalty forces, and kinematic
    /// corrections as the forces m·Δv/dt that would make them).
    pub contact_force: Vec<[f64; 3]>,
    /// Contact force on each rigid body in the last increment (the resultant on its nodes and
    /// its analytical surface). Free bodies only: a fixed or moving body's kinematic reaction
    /// is not seen here (the contact model holds it immovable); its slaves' contact forces give it.
    pub body_contact_force: Vec<[f64; 3]>,
    /// The force the supports put on each node in the last increment (Abaqus' RF): at a held
    /// degree of freedom the opposite of every other force on it (internal, bulk viscosity,
    /// loads, gravity, penalty contact), at a prescribed one the force that makes the motion;
    /// zero at free ones.
    pub reaction: Vec<[f64; 3]>,
    started: bool,
    /// Increments taken.
    increments: u64,
    /// The largest overclosure contact resolved so far (kinematic pairs: before the
    /// correction; penalty: carried with force), the increment and the node's pair report.
    worst_overclosure: (f64, u64),
    /// The increment of the last step (0 before the first), and the penalty contact's stable
    /// increment it reported (∞: none limited it; NaN: no penalty contact ran).
    last_increment: (f64, f64),
    balance0: Option<f64>,
    /// [`Solver::energy_floor`] at the first increment.
    floor0: Option<f64>,
    /// (external, contact, damping) power at the last step's time, and the increment since.
    last_power: Option<([f64; 3], f64)>,
    /// The body each node is carried by.
    carried: Vec<Option<u32>>,
    /// The nodes and elements whose energies this solver counts (`None`: all). A rank of a
    /// distributed run counts its own nodes and elements only; the run adds the ranks' up.
    pub(crate) counted: Option<(Vec<bool>, Vec<bool>)>,
    /// Whether the bodies' kinetic energy counts here (false on all ranks of a distributed run
    /// but one: every rank moves the held bodies alike).
    pub(crate) bodies_counted: bool,
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
        for (k, e) in elements.iter().enumerate() {
            if let Some(&n) = e.nodes().iter().find(|&&n| n as usize >= x.len()) {
                return Err(Error::IndexOutOfRange {
                    what: format!("node of element {k}"),
                    index: n as u64,
                    len: x.len(),
                });
            }
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
        // nodes on the axis of axisymmetric elements (reference radius 0) move along it only:
        // u_r = 0 there by symmetry; left free, round-off walks them to negative radii
        let mut fixed = vec![[false; 3]; n];
        for e in &elements {
            for node in e.axis_nodes() {
                fixed[node as usize][0] = true;
            }
        }
        Ok(Self {
            v: vec![[0.0; 3]; n],
            fixed,
            prescribed: Vec::new(),
            bodies: Vec::new(),
            loads: vec![[0.0; 3]; n],
            load_curves: Vec::new(),
            load_factor: None,
            x,
            mass,
            elements,
            gravity: [0.0; 3],
            damping: 0.0,
            bulk_viscosity: 0.0,
            bulk_viscosity_quadratic: 0.0,
            nlgeom: true,
            safety: 0.9,
            time: 0.0,
            energy: Energy::default(),
            contact_force: vec![[0.0; 3]; n],
            body_contact_force: Vec::new(),
            reaction: vec![[0.0; 3]; n],
            started: false,
            increments: 0,
            worst_overclosure: (0.0, 0),
            last_increment: (0.0, f64::NAN),
            balance0: None,
            floor0: None,
            last_power: None,
            carried: vec![None; n],
            counted: None,
            bodies_counted: true,
        })
    }

    /// Adds a rigid body; its nodes are moved with it from now on (their own masses and
    /// fixed flags no longer count). Returns its index. Errors: a node carried twice or
    /// belonging to an element.
    pub fn add_body(&mut self, body: SolverBody) -> Result<usize> {
        let k = self.bodies.len();
        for &n in &body.nodes {
            let n_us = n as usize;
            if n_us >= self.x.len() {
                return Err(Error::IndexOutOfRange {
                    what: "rigid body node".into(),
                    index: n as u64,
                    len: self.x.len(),
                });
            }
            if self.carried[n_us].is_some() || self.elements.iter().any(|e| e.nodes().contains(&n))
            {
                return Err(Error::BadParameter {
                    name: "rigid body node",
                    value: n.to_string(),
                    expected: "a node of no element and of no other body",
                });
            }
        }
        for &n in &body.nodes {
            self.carried[n as usize] = Some(k as u32);
        }
        body.place_nodes(&mut self.x, &mut self.v);
        self.bodies.push(body);
        self.body_contact_force.push([0.0; 3]);
        Ok(k)
    }

    /// Prescribes the motion of one degree of freedom. Errors: the node out of range or
    /// carried by a rigid body, a direction beyond z.
    pub fn prescribe(&mut self, p: Prescribed) -> Result<()> {
        let n = p.node as usize;
        if n >= self.x.len() || p.dof > 2 {
            return Err(Error::IndexOutOfRange {
                what: format!("prescribed node (direction {})", p.dof),
                index: p.node as u64,
                len: self.x.len(),
            });
        }
        if self.carried[n].is_some() {
            return Err(Error::BadParameter {
                name: "prescribed node",
                value: p.node.to_string(),
                expected: "a node not carried by a rigid body (prescribe the body's motion)",
            });
        }
        self.prescribed.push(p);
        Ok(())
    }

    /// The states of the rigid bodies (for [`Contact::kinematic_step`]).
    pub fn body_states(&self) -> Vec<BodyState> {
        self.bodies.iter().map(|b| b.state).collect()
    }

    /// The largest stable increment of the elements, times the safety factor and each
    /// element's bulk viscosity reduction √(1+ξ²) − ξ, ξ = b1 − b2²·(L/c)·min(0, ε̇_vol) at the
    /// current velocities (Abaqus' form; ξ = b1 at rest) (∞ with no elements).
    pub fn stable_increment(&self) -> f64 {
        self.governing_element().map_or(f64::INFINITY, |(_, dt)| dt)
    }

    /// The Cauchy stress of element `k` now (small-strain stress with `nlgeom` off).
    pub fn stress(&self, k: usize) -> [[f64; 3]; 3] {
        let e = &self.elements[k];
        if self.nlgeom {
            e.stress(&self.x)
        } else {
            e.small_strain_stress_at(&self.x)
        }
    }

    /// Internal forces at the current positions, and the strain energy.
    pub fn internal_forces(&self) -> (Vec<[f64; 3]>, f64) {
        let mut f = vec![[0.0; 3]; self.x.len()];
        let w = self
            .elements
            .iter()
            .enumerate()
            .map(|(k, e)| {
                let w = e.add_internal_forces_with(&self.x, &mut f, self.nlgeom);
                match &self.counted {
                    Some((_, elements)) if !elements[k] => 0.0,
                    _ => w,
                }
            })
            .sum();
        (f, w)
    }

    fn advance(
        &mut self,
        dt: f64,
        mut contact: Option<&mut Contact>,
        given: Option<&[[f64; 3]]>,
        corrector: Option<&mut dyn KinematicCorrector>,
    ) -> Result<()> {
        // a rank of a distributed run goes on through the increment's exchanges with its fault
        // (the arithmetic on bad input harms nothing) and returns it where the ranks agree, so
        // that none is left waiting in an exchange it would have skipped
        let deferred = match self.check_increment(dt) {
            Err(e) if corrector.is_none() => return Err(e),
            early => early.err(),
        };
        let (mut f_int, internal) = self.internal_forces();
        let n = self.x.len();
        // bulk viscosity acts with the half-step velocities (the last ones known); its power is
        // booked with the velocities at this step's time, like the damping's
        let mut bulk = vec![[0.0; 3]; n];
        if self.bulk_viscosity > 0.0 || self.bulk_viscosity_quadratic > 0.0 {
            let b = (self.bulk_viscosity, self.bulk_viscosity_quadratic);
            for e in &self.elements {
                e.add_bulk_viscosity(&self.x, &self.v, b, &mut bulk);
            }
            for i in 0..n {
                for a in 0..3 {
                    f_int[i][a] += bulk[i][a];
                }
            }
        }
        self.increments += 1;
        self.last_increment = (dt, f64::NAN);
        let mut penalty = given.map_or_else(|| vec![[0.0; 3]; n], <[_]>::to_vec);
        if let Some(c) = contact.as_deref_mut() {
            if c.has_penalty_pairs() {
                let r = c.penalty_step(&self.x, &self.v, dt)?;
                self.last_increment.1 = r.stable_dt;
                self.note_overclosure(r.max_overclosure);
                penalty = r.forces.clone();
            }
        }
        // velocity update (the first moves by half an increment), prediction of positions
        let dv_scale = if self.started { dt } else { 0.5 * dt };
        let v_old = self.v.clone();
        let bodies_old: Vec<BodyState> = self.body_states();
        let mut ext = vec![[0.0; 3]; n];
        let mut damp = vec![[0.0; 3]; n];
        let factor = self
            .load_factor
            .as_ref()
            .map_or(1.0, |f| f.value(self.time));
        let curves = self.curve_loads(dt);
        for i in 0..n {
            if self.carried[i].is_some() {
                continue;
            }
            for a in 0..3 {
                if self.fixed[i][a] {
                    self.v[i][a] = 0.0;
                    self.reaction[i][a] = -(f_int[i][a]
                        + factor * self.loads[i][a]
                        + curves.get(i).map_or(0.0, |c| c[a])
                        + self.mass[i] * self.gravity[a]
                        + penalty[i][a]);
                    continue;
                }
                ext[i][a] = factor * self.loads[i][a] + self.mass[i] * self.gravity[a];
                if let Some(c) = curves.get(i) {
                    ext[i][a] += c[a];
                }
                damp[i][a] = -self.damping * self.mass[i] * self.v[i][a];
                self.v[i][a] += dv_scale * (f_int[i][a] + ext[i][a] + penalty[i][a] + damp[i][a])
                    / self.mass[i];
            }
        }
        // prescribed degrees of freedom: the velocity that reaches the prescribed displacement
        // exactly; the force that makes it counts as external
        for p in &self.prescribed {
            // a window that has ended leaves no reaction behind
            self.reaction[p.node as usize][p.dof] = 0.0;
        }
        for p in &self.prescribed {
            if !p.acts(self.time, dt) {
                continue;
            }
            let (i, a) = (p.node as usize, p.dof);
            let target = p.motion.displacement(self.time + dt);
            let u = match p.origin {
                // the total displacement from the reference, from where the node is at the
                // increment's start
                Some(x0) => (x0 + target - self.x[i][a]) / dt,
                None => (target - p.motion.displacement(self.time)) / dt,
            };
            let support = self.mass[i] * (u - self.v[i][a]) / dv_scale;
            ext[i][a] += support;
            self.reaction[i][a] = support;
            self.v[i][a] = u;
        }
        for i in 0..n {
            if self.carried[i].is_none() {
                for a in 0..3 {
                    self.x[i][a] += dt * self.v[i][a];
                }
            }
        }
        // rigid bodies: gravity, loads and penalty forces on their nodes (force and moment about
        // the reference point, at the start of the increment)
        let mut body_ext = vec![([0.0; 3], [0.0; 3]); self.bodies.len()];
        // a rank's share of the model counts its own nodes' forces on a body (the ranks' shares
        // add up to the body's), and one rank its kinetic energy
        let mut corrector = corrector;
        let mut both =
            self.body_resultants_of(&[&penalty, &self.loads], corrector.as_deref_mut())?;
        let (body_loads, body_pen) = (
            both.pop().unwrap_or_default(),
            both.pop().unwrap_or_default(),
        );
        for (k, b) in self.bodies.iter_mut().enumerate() {
            let (fp, mp) = body_pen[k];
            let (fl, ml) = body_loads[k];
            let ml = [0, 1, 2].map(|a| factor * (ml[a] + b.moment[a]));
            let g = self.gravity.map(|g| g * b.mass);
            let f_ext = [0, 1, 2].map(|a| factor * (fl[a] + b.load[a]) + g[a]);
            let moving = b.motion == BodyMotion::Free;
            // the body's own loads and weight act on every rank alike: one counts their work
            let whole = if self.bodies_counted { 1.0 } else { 0.0 };
            body_ext[k] = if moving {
                (f_ext.map(|f| whole * f), ml.map(|m| whole * m))
            } else {
                ([0.0; 3], [0.0; 3])
            };
            b.accelerate(
                [0, 1, 2].map(|a| f_ext[a] + fp[a]),
                [0, 1, 2].map(|a| ml[a] + mp[a]),
                dv_scale,
            );
            b.advance(dt);
            b.place_nodes(&mut self.x, &mut self.v);
        }
        // kinematic contact corrects the predicted state; it acts as the force m·Δv/dv_scale
        // would have in the velocity update
        let mut kinematic = vec![[0.0; 3]; n];
        let mut body_kin = vec![([0.0; 3], [0.0; 3]); self.bodies.len()];
        // the predicted state, before contact searches it (agreed over a corrector's ranks)
        let corrector = corrector
            .or(contact.map(|c| c as &mut dyn KinematicCorrector))
            .filter(|c| c.has_kinematic_pairs());
        let diverged = deferred.or_else(|| self.check_diverged().err());
        let diverged = match (&corrector, diverged) {
            (None, Some(e)) => return Err(e),
            (_, d) => d,
        };
        if let Some(c) = corrector {
            c.agree(diverged)?;
            {
                let v_pred = self.v.clone();
                let x_pred = self.x.clone();
                let pred: Vec<BodyState> = self.body_states();
                let mut states = pred.clone();
                let h = c.correct(&mut self.x, &mut self.v, &mut states, dt)?;
                self.note_overclosure(h);
                for i in 0..n {
                    for a in 0..3 {
                        // a held direction stays where it is: its support takes the correction
                        if self.fixed[i][a] && self.carried[i].is_none() {
                            self.x[i][a] = x_pred[i][a];
                            self.v[i][a] = v_pred[i][a];
                        }
                        kinematic[i][a] = self.mass[i] * (self.v[i][a] - v_pred[i][a]) / dv_scale;
                    }
                }
                // the corrections of the carried nodes, as impulses on their bodies
                let impulses = self.body_resultants(&kinematic, Some(&mut *c))?;
                for (k, b) in self.bodies.iter_mut().enumerate() {
                    // corrections of the analytical surface, and of the carried nodes taken
                    // as an impulse on the body
                    let mut dv = [0.0; 3];
                    let mut dw = [0.0; 3];
                    for a in 0..3 {
                        dv[a] = states[k].velocity[a] - pred[k].velocity[a];
                        dw[a] = states[k].angular_velocity[a] - pred[k].angular_velocity[a];
                    }
                    let (j, h) = impulses[k];
                    let iw = rigid::world_inertia(&b.state.rotation, &b.inertia);
                    let from_nodes = rigid::solve3(&iw, h);
                    let mut force = [0.0; 3];
                    let mut moment = [0.0; 3];
                    let lw = rigid::rotate(&iw, dw);
                    // the body's own correction is every rank's: one counts its work
                    let whole = if self.bodies_counted { 1.0 } else { 0.0 };
                    for a in 0..3 {
                        force[a] = whole * b.mass * dv[a] / dv_scale + j[a];
                        moment[a] = whole * lw[a] / dv_scale + h[a];
                    }
                    body_kin[k] = (force, moment);
                    if b.motion == BodyMotion::Free {
                        for a in 0..3 {
                            b.state.velocity[a] =
                                pred[k].velocity[a] + dv[a] + dv_scale * j[a] / b.mass;
                            b.state.angular_velocity[a] =
                                pred[k].angular_velocity[a] + dw[a] + dv_scale * from_nodes[a];
                        }
                        b.hold();
                        b.state.position = bodies_old[k].position;
                        b.state.rotation = bodies_old[k].rotation;
                        b.advance(dt);
                    }
                    b.place_nodes(&mut self.x, &mut self.v);
                    for &i in &b.nodes {
                        kinematic[i as usize] = [0.0; 3];
                    }
                }
            }
        }
        for i in 0..n {
            for a in 0..3 {
                self.contact_force[i][a] = penalty[i][a] + kinematic[i][a];
            }
        }
        for (k, (fp, _)) in body_pen.iter().enumerate() {
            self.body_contact_force[k] = [0, 1, 2].map(|a| fp[a] + body_kin[k].0[a]);
        }
        // energies at this step's time: velocities there are the mean of the half-step ones
        // around it (at the start, the initial velocity)
        let (mut kinetic, mut p_ext, mut p_con, mut p_damp) = (0.0, 0.0, 0.0, 0.0);
        let now = |old: f64, new: f64| if self.started { 0.5 * (old + new) } else { old };
        for i in 0..n {
            let uncounted = self.counted.as_ref().is_some_and(|(nodes, _)| !nodes[i]);
            if self.carried[i].is_some() || uncounted {
                continue;
            }
            for a in 0..3 {
                let v_now = now(v_old[i][a], self.v[i][a]);
                kinetic += 0.5 * self.mass[i] * v_now * v_now;
                p_ext += ext[i][a] * v_now;
                p_con += (penalty[i][a] + kinematic[i][a]) * v_now;
                p_damp -= (damp[i][a] + bulk[i][a]) * v_now;
            }
        }
        for (k, b) in self.bodies.iter().enumerate() {
            // a free body of mesh nodes split over ranks: every rank has its whole resultants,
            // one counts their work
            if self.counted.is_some() && b.free_meshed() && !self.bodies_counted {
                continue;
            }
            let v_now = [0, 1, 2].map(|a| now(bodies_old[k].velocity[a], b.state.velocity[a]));
            let w_now = [0, 1, 2].map(|a| {
                now(
                    bodies_old[k].angular_velocity[a],
                    b.state.angular_velocity[a],
                )
            });
            if self.bodies_counted {
                kinetic += b.kinetic(v_now, w_now);
            }
            let (fp, mp) = body_pen[k];
            let (fk, mk) = body_kin[k];
            let (fe, me) = body_ext[k];
            // a body held on a prescribed path (fixed, or at a set velocity) is driven by
            // whatever holds it there: against contact, gravity and its loads together, so the
            // drive and those external forces do, on it, the negative of the contact's power
            let held = b.motion != BodyMotion::Free;
            for a in 0..3 {
                let contact = (fp[a] + fk[a]) * v_now[a] + (mp[a] + mk[a]) * w_now[a];
                p_ext += fe[a] * v_now[a] + me[a] * w_now[a];
                if held {
                    p_ext -= contact;
                }
                p_con += contact;
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
        if self.floor0.is_none() {
            self.floor0 = Some(self.energy_floor());
        }
        self.check_diverged()
    }
}
