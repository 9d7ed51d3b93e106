//! Kinematic contact against the analytical surfaces of rigid bodies across ranks: each rank
//! corrects its own slaves, and every sum over a pair's pushed slaves (the body's generalized
//! mass, the slaves' push on it, a softened law's shares) runs over every rank's, gathered and
//! taken in the pair's slave order — the single process's order, so every rank corrects the
//! body alike and every slave as one process would, bit for bit.

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::collectives::{agree, agree_and_max, all_gather};
use crate::error::{Error, Result};
use crate::explicit::KinematicCorrector;
use crate::geometry::V3;
use crate::kinematic::{rigid_pass_shared, BodyState, Pushed, SlaveCorrection, PASSES};
use crate::model::{PressureOverclosure, RigidBody};

/// Numbers per pushed slave in the gather: key, mass, area, normal, overclosure, arm.
const ROW: usize = 10;

/// One kinematic pair against a rigid body's analytical surface, as one rank holds it.
#[derive(Clone, Debug)]
pub struct RankRigidPair {
    /// The rigid body (its index among the bodies given to the correction), the same on
    /// every rank.
    pub body: usize,
    /// The body's surface, mass and inertia as the contact sees them, the same on every rank.
    pub spec: RigidBody,
    /// `None`: hard contact; else the softened law. The same on every rank.
    pub law: Option<PressureOverclosure>,
    /// This rank's slaves: indices into the arrays the correction is given.
    pub slaves: Vec<u32>,
    /// Each slave's place in the pair's whole slave list (unique over the ranks).
    pub keys: Vec<u64>,
    /// Each slave's tributary area (model area units).
    pub areas: Vec<f64>,
}

/// A rank's kinematic contact against analytical surfaces (see the module's documentation).
pub struct DistributedRigid {
    comm: SimpleCommunicator,
    masses: Vec<f64>,
    pairs: Vec<RankRigidPair>,
    /// Each pair's first correction of the last increment, per slave of this rank.
    last: Vec<Vec<SlaveCorrection>>,
    /// The largest overclosure the last increment corrected, over every rank.
    deepest: f64,
    /// Bytes this rank gave the last increment's gathers (its pushed slaves' rows).
    bytes: usize,
}

impl DistributedRigid {
    /// This rank's share over `comm` (duplicated): `masses` the lumped masses of the arrays
    /// the correction is given. Collective. Errors (on every rank): pair lists of other
    /// lengths on other ranks; a slave out of range, or keys or areas not one per slave.
    pub fn new(
        comm: &SimpleCommunicator,
        masses: Vec<f64>,
        pairs: Vec<RankRigidPair>,
    ) -> Result<Self> {
        let comm = comm.duplicate();
        let mut fault = None;
        for (k, p) in pairs.iter().enumerate() {
            if p.keys.len() != p.slaves.len() || p.areas.len() != p.slaves.len() {
                fault = Some(Error::LengthMismatch {
                    what: "rigid pair keys and areas (one per slave)",
                    expected: p.slaves.len(),
                    got: p.keys.len().min(p.areas.len()),
                });
            } else if let Some(&s) = p.slaves.iter().find(|&&s| s as usize >= masses.len()) {
                fault = Some(Error::IndexOutOfRange {
                    what: format!("slave of rigid pair {k}"),
                    index: s as u64,
                    len: masses.len(),
                });
            }
        }
        let count = pairs.len() as f64;
        let spread = agree_and_max(&comm, fault, &[count, -count])?;
        if spread[0] != -spread[1] {
            return Err(Error::BadParameter {
                name: "rigid pairs",
                value: pairs.len().to_string(),
                expected: "the same rigid pairs on every rank",
            });
        }
        let last = pairs
            .iter()
            .map(|p| vec![Default::default(); p.slaves.len()])
            .collect();
        Ok(Self {
            comm,
            masses,
            pairs,
            last,
            deepest: 0.0,
            bytes: 0,
        })
    }

    /// The largest overclosure the last increment corrected, over every rank (model length
    /// units).
    pub fn max_overclosure(&self) -> f64 {
        self.deepest
    }

    /// Bytes this rank gave the last increment's gathers (its pushed slaves' rows, sent to
    /// every other rank).
    pub fn bytes_sent(&self) -> usize {
        self.bytes
    }

    /// This rank's slaves in contact after the last increment: (pair, slave index into the
    /// arrays, contact pressure, contact force), pair by pair in slave order. The pressure is
    /// the normal force the correction applied over the tributary area, as one process's
    /// CPRESS.
    pub fn contact_outputs(&self) -> Vec<(usize, u32, f64, [f64; 3])> {
        let mut out = Vec::new();
        for (k, (p, last)) in self.pairs.iter().zip(&self.last).enumerate() {
            for ((c, &s), &a) in last.iter().zip(&p.slaves).zip(&p.areas) {
                let normal: f64 = (0..3).map(|j| c.applied[j] * c.normal[j]).sum();
                let pressure = normal / a;
                if pressure > 0.0 {
                    out.push((k, s, pressure, c.applied));
                }
            }
        }
        out
    }
}

/// Every rank's pushed slaves of a pair, ordered by key; this rank's keep their index.
fn gather_pushed(comm: &SimpleCommunicator, mine: Vec<Pushed>) -> Vec<Pushed> {
    let flat: Vec<f64> = mine
        .iter()
        .flat_map(|p| {
            let (n, r) = (p.normal, p.arm);
            [
                // the key travels as its bits (any u64, exactly)
                f64::from_bits(p.key),
                p.mass,
                p.area,
                n.x,
                n.y,
                n.z,
                p.overclosure,
                r.x,
                r.y,
                r.z,
            ]
        })
        .collect();
    let (all, counts) = all_gather(comm, &flat);
    let before: usize = counts[..comm.rank() as usize].iter().sum::<usize>() / ROW;
    let mut rows: Vec<Pushed> = all
        .chunks_exact(ROW)
        .enumerate()
        .map(|(i, r)| Pushed {
            key: r[0].to_bits(),
            index: i
                .checked_sub(before)
                .and_then(|j| mine.get(j))
                .and_then(|p| p.index),
            mass: r[1],
            area: r[2],
            normal: V3::new(r[3], r[4], r[5]),
            overclosure: r[6],
            arm: V3::new(r[7], r[8], r[9]),
        })
        .collect();
    rows.sort_by_key(|p| p.key);
    rows
}

impl KinematicCorrector for DistributedRigid {
    fn has_kinematic_pairs(&self) -> bool {
        !self.pairs.is_empty()
    }

    fn agree(&mut self, fault: Option<Error>) -> Result<()> {
        agree(&self.comm, fault)
    }

    /// The single process's correction of every rigid pair in order, this rank's slaves
    /// corrected and every body alike on every rank. Collectives: two per pass of each pair
    /// (three passes hard, one softened) and one for the largest overclosure. A fault of the
    /// passes comes from the gathered slaves and the bodies, the same on every rank.
    fn correct(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<f64> {
        let comm = &self.comm;
        let mut deepest = 0.0f64;
        let mut bytes = 0;
        for (p, last) in self.pairs.iter().zip(&mut self.last) {
            let body = bodies.get_mut(p.body).ok_or(Error::IndexOutOfRange {
                what: "rigid body states".into(),
                index: p.body as u64,
                len: 0,
            })?;
            let passes = if p.law.is_some() { 1 } else { PASSES };
            for pass in 0..passes {
                let (c, _) = rigid_pass_shared(
                    &p.spec.surface,
                    (p.spec.mass, &p.spec.inertia),
                    body,
                    &self.masses,
                    (&mut *x, &mut *v),
                    (&p.slaves, &p.keys),
                    &p.areas,
                    p.law.as_ref(),
                    dt,
                    &mut |rows| {
                        bytes += 8 * ROW * rows.len() * (comm.size() as usize - 1);
                        Ok(gather_pushed(comm, rows))
                    },
                )?;
                if pass == 0 {
                    for s in c.iter().filter(|s| s.force > 0.0) {
                        deepest = deepest.max(s.overclosure);
                    }
                    *last = c;
                }
            }
        }
        self.bytes = bytes;
        self.deepest = agree_and_max(comm, None, &[deepest])?[0];
        Ok(self.deepest)
    }
}
