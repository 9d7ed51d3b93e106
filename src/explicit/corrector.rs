//! The solver's increments and what corrects their predicted state kinematically (the seed's
//! predictor/corrector): a [`Contact`]'s kinematic pairs in one process, or a rank's share of
//! them across ranks.

use super::Solver;
use crate::contact::Contact;
use crate::error::{Error, Result};
use crate::kinematic::BodyState;

/// A kinematic corrector of the increment the solver predicted.
pub trait KinematicCorrector {
    /// Whether it corrects anything (the same answer on every rank of a distributed run).
    fn has_kinematic_pairs(&self) -> bool;

    /// Agrees on a fault found in the predicted state before it is corrected: one process
    /// returns it; a rank of a distributed run returns it on every rank (any rank's), so that
    /// none is left waiting in the correction's exchanges.
    fn agree(&mut self, fault: Option<Error>) -> Result<()> {
        fault.map_or(Ok(()), Err)
    }

    /// Corrects the predicted positions `x`, velocities `v` and rigid bodies `bodies` (index
    /// = body id) of an increment `dt` in place; returns the largest overclosure it corrected
    /// (model length units).
    fn correct(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<f64>;
}

impl KinematicCorrector for Contact {
    fn has_kinematic_pairs(&self) -> bool {
        Contact::has_kinematic_pairs(self)
    }

    fn correct(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<f64> {
        Ok(self.kinematic_step(x, v, bodies, dt)?.max_overclosure)
    }
}

impl Solver {
    /// One central-difference increment of `dt` (the first moves velocities by half an
    /// increment, Abaqus' start), with penalty forces and kinematic corrections from
    /// `contact` when given.
    pub fn step(&mut self, dt: f64, contact: Option<&mut Contact>) -> Result<()> {
        self.advance(dt, contact, None, None)
    }

    /// One increment as [`Solver::step`], with contact forces the host computed itself (one per
    /// node, taken as penalty forces: in the velocity update, the contact work and
    /// [`Solver::contact_force`]) — a distributed contact's, say.
    pub fn step_with_forces(&mut self, dt: f64, contact_forces: &[[f64; 3]]) -> Result<()> {
        if contact_forces.len() != self.x.len() {
            return Err(Error::LengthMismatch {
                what: "contact forces (one per node)",
                expected: self.x.len(),
                got: contact_forces.len(),
            });
        }
        self.advance(dt, None, Some(contact_forces), None)
    }

    /// [`Solver::step_with_forces`], the predicted state then corrected by `corrector` (a
    /// distributed run's kinematic contact, say).
    pub fn step_with_forces_and(
        &mut self,
        dt: f64,
        contact_forces: &[[f64; 3]],
        corrector: &mut dyn KinematicCorrector,
    ) -> Result<()> {
        if contact_forces.len() != self.x.len() {
            return Err(Error::LengthMismatch {
                what: "contact forces (one per node)",
                expected: self.x.len(),
                got: contact_forces.len(),
            });
        }
        self.advance(dt, None, Some(contact_forces), Some(corrector))
    }
}
