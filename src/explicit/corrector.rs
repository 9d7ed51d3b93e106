//! The solver's increments and what corrects their predicted state kinematically (the seed's
//! predictor/corrector): a [`Contact`]'s kinematic pairs in one process, or a rank's share of
//! them across ranks.

use super::rigid::{fold_rows, ResultantRow};
use super::Solver;
use crate::contact::Contact;
use crate::error::{Error, Result};
use crate::kinematic::BodyState;

/// A body's resultant force and moment (about its reference point).
type Resultant = ([f64; 3], [f64; 3]);

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

    /// Rows of the resultants of free rigid bodies of mesh nodes (`(body, rows)`: the body's
    /// index, its rows at this rank's nodes, each keyed by its place in this rank's share of
    /// the body's nodes) made every rank's: each list gathered over the ranks and ordered by
    /// the node's place in the whole body, so that its sum is one process's. One process has
    /// them all already.
    fn share_body_rows(
        &mut self,
        rows: Vec<(usize, Vec<ResultantRow>)>,
    ) -> Result<Vec<Vec<ResultantRow>>> {
        Ok(rows.into_iter().map(|(_, r)| r).collect())
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

    /// Each rigid body's resultant force and moment (about its reference point) of the nodal
    /// forces `f` at the current positions: over the nodes this rank counts, and for a free
    /// body of mesh nodes split over ranks over every rank's, through `share`.
    pub(super) fn body_resultants<'c>(
        &self,
        f: &[[f64; 3]],
        share: Option<&mut (dyn KinematicCorrector + 'c)>,
    ) -> Result<Vec<Resultant>> {
        Ok(self.body_resultants_of(&[f], share)?.remove(0))
    }

    /// [`Self::body_resultants`] of each of `forces`, every split body's rows of them all
    /// shared in one exchange (one gather across ranks, not one per force array).
    pub(super) fn body_resultants_of<'c>(
        &self,
        forces: &[&[[f64; 3]]],
        share: Option<&mut (dyn KinematicCorrector + 'c)>,
    ) -> Result<Vec<Vec<Resultant>>> {
        let own = self.counted.as_ref().map(|(nodes, _)| nodes.as_slice());
        let mut out: Vec<Vec<_>> = forces
            .iter()
            .map(|f| {
                self.bodies
                    .iter()
                    .map(|b| b.resultant(&self.x, f, own))
                    .collect()
            })
            .collect();
        let split: Vec<usize> = (0..self.bodies.len())
            .filter(|&k| own.is_some() && self.bodies[k].free_meshed())
            .collect();
        if split.is_empty() {
            return Ok(out);
        }
        let Some(share) = share else {
            return Err(Error::BadParameter {
                name: "free rigid body",
                value: "of mesh nodes, split over ranks".into(),
                expected: "a rank share that sums its resultants over the ranks",
            });
        };
        // (force array, body) of each list, in the order shared
        let lists: Vec<(usize, usize)> = (0..forces.len())
            .flat_map(|a| split.iter().map(move |&k| (a, k)))
            .collect();
        let rows = lists
            .iter()
            .map(|&(a, k)| (k, self.bodies[k].resultant_rows(&self.x, forces[a], own)))
            .collect();
        for (&(a, k), rows) in lists.iter().zip(share.share_body_rows(rows)?) {
            out[a][k] = fold_rows(&rows);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explicit::{BodyMotion, SolverBody};

    /// A rank's corrector that records what the solver asked of it.
    #[derive(Default)]
    struct Recorder {
        /// Whether it has kinematic pairs (else it only gathers the bodies' rows: a free meshed
        /// body under penalty contact).
        kinematic: bool,
        /// Body-row exchanges (each a gather across ranks).
        gathers: usize,
        /// The fault agreed on, as text.
        agreed: Option<String>,
    }

    impl KinematicCorrector for Recorder {
        fn has_kinematic_pairs(&self) -> bool {
            self.kinematic
        }

        fn agree(&mut self, fault: Option<Error>) -> Result<()> {
            self.agreed = fault.as_ref().map(|e| e.to_string());
            fault.map_or(Ok(()), Err)
        }

        fn share_body_rows(
            &mut self,
            rows: Vec<(usize, Vec<ResultantRow>)>,
        ) -> Result<Vec<Vec<ResultantRow>>> {
            self.gathers += 1;
            Ok(rows.into_iter().map(|(_, r)| r).collect())
        }

        fn correct(
            &mut self,
            _: &mut [[f64; 3]],
            _: &mut [[f64; 3]],
            _: &mut [BodyState],
            _: f64,
        ) -> Result<f64> {
            Ok(0.0)
        }
    }

    /// Spoils a solver's input; returns the increment to take.
    type Spoil = fn(&mut Solver) -> f64;

    /// A rank's share: two nodes on a free body, one free node; counted as a rank's.
    fn rank_share() -> Solver {
        let x = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let mut s = Solver::new(x.clone(), Vec::new(), &[1.0; 3]).unwrap();
        let i = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let body = SolverBody::new(2.0, i, [0.5, 0.0, 0.0], vec![0, 1], &x, BodyMotion::Free);
        s.add_body(body.unwrap()).unwrap();
        s.counted = Some((vec![true; 3], Vec::new()));
        s
    }

    /// A fault found before the increment (a bad load, gravity or damping set on one rank, a
    /// bad increment) does not return before the increment's exchanges: the rank goes through
    /// the body-row gather every other rank makes and returns the fault where the ranks agree
    /// (the corrector's agreement; with no kinematic pair, the caller's after the step) — else
    /// the others would wait in a gather this rank skipped, for ever. Without a corrector it
    /// returns at once, as before.
    #[test]
    fn a_fault_before_the_increment_is_agreed_after_every_exchange() {
        let cases: [(&str, Spoil); 4] = [
            ("loads", |s| {
                s.loads[2] = [f64::NAN, 0.0, 0.0];
                1e-3
            }),
            ("gravity", |s| {
                s.gravity = [0.0, 0.0, f64::INFINITY];
                1e-3
            }),
            ("damping", |s| {
                s.damping = -1.0;
                1e-3
            }),
            ("dt", |_| f64::NAN),
        ];
        for ((name, spoil), kinematic) in cases.into_iter().flat_map(|c| [(c, true), (c, false)]) {
            let mut s = rank_share();
            let dt = spoil(&mut s);
            let mut rank = Recorder {
                kinematic,
                ..Recorder::default()
            };
            let err = s
                .step_with_forces_and(dt, &[[0.0; 3]; 3], &mut rank)
                .expect_err(name);
            assert!(err.to_string().contains(name), "{name}: {err}");
            assert_eq!(rank.gathers, 1, "{name}: the resultants' gather made");
            if kinematic {
                let agreed = rank.agreed.as_deref().unwrap_or_default();
                assert!(agreed.contains(name), "{name}: agreed on {agreed:?}");
            }
            let mut one = rank_share();
            spoil(&mut one);
            assert!(one.step(dt, None).is_err(), "{name}");
        }
    }
}
