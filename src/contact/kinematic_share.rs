//! A kinematic pair's search for a distributed run, which corrects its slaves itself with
//! every rank's share of the master nodes' sums: each slave's facet at the predicted
//! positions, and the pair's per-slave state carried into a rebuilt local model.

use super::report::fast_slaves;
use super::{Contact, KinematicRun};
use crate::error::{Error, Result};
use crate::kinematic::facets_from;
use crate::model::PairId;
use crate::FastNode;

/// Small sliding: an anchored slave's plane (normal, weights, overclosure) as the search gave
/// it; none where it has no anchor.
pub(crate) type AnchorPlane = Option<([f64; 3], [f64; 4], f64)>;

/// A kinematic pair's contacts at the predicted positions, as its corrections use them.
pub(crate) struct KinematicContacts {
    /// The pair's slaves (model node ids), in the order of the node set.
    pub slaves: Vec<u32>,
    /// Each slave's facet (its nodes, model node ids; `u32::MAX` pads), none where it has no
    /// contact (no facet within the radius, beside a free edge, behind one).
    pub facets: Vec<Option<[u32; 4]>>,
    /// Each slave's tributary area.
    pub areas: Vec<f64>,
    /// Slaves that moved farther than the radius relative to the master near them, and the
    /// fastest.
    pub fast: (usize, Option<FastNode>),
    /// Small sliding: each anchored slave's plane at the predicted positions (normal, weights,
    /// overclosure), which its one correction uses as it is.
    pub anchored: Option<Vec<AnchorPlane>>,
}

impl Contact {
    fn kinematic_run(&mut self, pair: PairId) -> Result<&mut KinematicRun> {
        self.kinematic
            .iter_mut()
            .find(|k| k.id == pair)
            .ok_or(Error::UnknownId {
                what: "kinematic pair",
                id: pair.0,
            })
    }

    /// Kinematic pair `pair` (pure, finite sliding) searched at the predicted positions `x`
    /// (velocities `v`, increment `dt`, for the fast nodes): each slave's facet.
    pub(crate) fn kinematic_contacts(
        &mut self,
        pair: PairId,
        x: &[[f64; 3]],
        v: &[[f64; 3]],
        dt: f64,
    ) -> Result<KinematicContacts> {
        let kr = self.kinematic_run(pair)?;
        let result = kr.search.step(x)?;
        let order = 0..result.raw.len();
        let fast = fast_slaves(kr.id, &kr.search, &result.raw, order, v, dt);
        let pad = |f: u32| {
            let nodes = kr.master.facets[f as usize].nodes();
            let mut padded = [u32::MAX; 4];
            padded[..nodes.len()].copy_from_slice(nodes);
            padded
        };
        // small sliding, pure: the anchors' planes as the search gives them (`anchored_pass`)
        let (facets, anchored) = if kr.anchored && kr.back.is_none() {
            let contacts: Vec<_> = result.contacts().collect();
            (
                contacts.iter().map(|c| c.map(|c| pad(c.facet))).collect(),
                Some(
                    contacts
                        .iter()
                        .map(|c| c.map(|c| (c.normal, c.weights, -c.gap)))
                        .collect(),
                ),
            )
        } else {
            let facets = facets_from(&result, &mut kr.behind.0);
            (facets.into_iter().map(|f| f.map(pad)).collect(), None)
        };
        Ok(KinematicContacts {
            slaves: kr.slaves.clone(),
            facets,
            areas: kr.areas.clone(),
            fast,
            anchored,
        })
    }

    /// Kinematic pair `pair`'s behind-a-free-edge flag of each slave (node set order), for
    /// [`Contact::set_kinematic_behind`] on a rebuilt local model.
    pub(crate) fn kinematic_behind(&mut self, pair: PairId) -> Result<Vec<bool>> {
        Ok(self.kinematic_run(pair)?.behind.0.clone())
    }

    /// Sets what [`Contact::kinematic_behind`] gave (one flag per slave).
    pub(crate) fn set_kinematic_behind(&mut self, pair: PairId, behind: &[bool]) -> Result<()> {
        let kr = self.kinematic_run(pair)?;
        if behind.len() != kr.behind.0.len() {
            return Err(Error::LengthMismatch {
                what: "behind-a-free-edge flags (one per slave)",
                expected: kr.behind.0.len(),
                got: behind.len(),
            });
        }
        kr.behind.0.copy_from_slice(behind);
        Ok(())
    }
}
