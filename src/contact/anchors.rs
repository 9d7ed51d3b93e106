//! What a distributed run carries into a rank's local contact and sets on it: small and
//! infinitesimal sliding's anchors (penalty or kinematic) taken out of one Contact and put into
//! another over the same slaves, keyed by model node ids (a local model rebuilt with other
//! ghosts keeps the anchors its first search found); and the penalty searches' frames, chosen
//! from the whole master.

use super::Contact;
use crate::error::{Error, Result};
use crate::model::PairId;
use crate::search::KeyedAnchor;

impl Contact {
    /// Small sliding: the anchors of each pass of pair `pair` (two for a balanced penalty
    /// pair; one for a kinematic pair), each in the node set's order and keyed by model node ids; `None` for a pass not
    /// anchored yet (before the first increment, or finite sliding).
    pub(crate) fn penalty_anchors(&self, pair: PairId) -> Result<Vec<Option<Vec<KeyedAnchor>>>> {
        // a kinematic pair: one pass, in the node set's order
        if let Some(kr) = self.kinematic.iter().find(|k| k.id == pair) {
            return Ok(vec![kr.search.keyed_anchors()]);
        }
        Ok(self
            .penalty_runs(pair)?
            .into_iter()
            .map(|k| {
                let p = &self.pairs[k];
                p.search.keyed_anchors().map(|a| p.map.to_caller(&a))
            })
            .collect())
    }

    /// Small sliding: installs anchors found by another Contact over the same slaves (as
    /// [`Contact::penalty_anchors`] gives them; `None` leaves a pass to anchor at its first
    /// increment). Before the first increment. Errors: an unknown pair, a count of passes or
    /// slaves other than the pair's, a facet the pass's master does not hold.
    pub(crate) fn set_penalty_anchors(
        &mut self,
        pair: PairId,
        anchors: &[Option<Vec<KeyedAnchor>>],
    ) -> Result<()> {
        if let Some(kr) = self.kinematic.iter_mut().find(|k| k.id == pair) {
            if let [Some(a)] = anchors {
                kr.search.set_keyed_anchors(a)?;
            }
            return Ok(());
        }
        let runs = self.penalty_runs(pair)?;
        if runs.len() != anchors.len() {
            return Err(Error::LengthMismatch {
                what: "anchors (one list per pass of the pair)",
                expected: runs.len(),
                got: anchors.len(),
            });
        }
        for (&k, a) in runs.iter().zip(anchors) {
            if let Some(a) = a {
                let p = &mut self.pairs[k];
                if a.len() != p.output.slaves.len() {
                    return Err(Error::LengthMismatch {
                        what: "anchors (one per slave of the pass)",
                        expected: p.output.slaves.len(),
                        got: a.len(),
                    });
                }
                let a = p.map.to_pass(a);
                p.search.set_keyed_anchors(&a)?;
            }
        }
        Ok(())
    }

    /// Small sliding: how far the anchoring search of each pass of penalty pair `pair`
    /// reaches (as [`crate::search::SearchStage::set_anchor_reach`]; `None`: every master
    /// facet). Before the first increment.
    pub(crate) fn set_anchor_reach(&mut self, pair: PairId, reach: Option<f64>) -> Result<()> {
        if let Some(kr) = self.kinematic.iter_mut().find(|k| k.id == pair) {
            kr.search.set_anchor_reach(reach);
            return Ok(());
        }
        for k in self.penalty_runs(pair)? {
            self.pairs[k].search.set_anchor_reach(reach);
        }
        Ok(())
    }

    /// The frame of each penalty pass of pair `pair`: `origin`, chosen where the whole master's
    /// extent was `span` (see `SearchStage::give_frame`).
    pub(crate) fn give_search_frame(
        &mut self,
        pair: PairId,
        origin: [f64; 3],
        span: f64,
    ) -> Result<()> {
        for k in self.penalty_runs(pair)? {
            self.pairs[k].search.give_frame(origin, span);
        }
        Ok(())
    }
}
