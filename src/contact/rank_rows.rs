//! What a distributed run's local model of part of the whole gives and takes beside the
//! forces: the rigid parts' states from the whole bodies, a rigid slave part's spring count
//! over the whole pair, and the node-wise bound's rows read back so that the ranks holding a
//! node can add their shares of its row (one process's bound is on the sum).

#[cfg(feature = "mpi")]
use super::Contact;
#[cfg(feature = "mpi")]
use crate::error::{Error, Result};
#[cfg(feature = "mpi")]
use crate::model::PairId;
#[cfg(feature = "mpi")]
use crate::penalty::RigidState;

/// The node-wise bound's rows of the last host-array increment, when asked for.
#[derive(Clone, Debug, Default)]
pub(super) struct NodeRows {
    /// Read them back with every host-array increment.
    pub(super) wanted: bool,
    /// Per model node, the sum of its springs' shares (1/s², f32 as the kernels sum them).
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))]
    rows: Vec<f32>,
    /// The largest contact damping ratio of the penalty pairs (the bound's damping factor).
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))]
    damping: f32,
}

impl NodeRows {
    /// Keeps an increment's rows (empty when not asked for) and damping ratio.
    pub(super) fn take(&mut self, rows: Vec<f32>, damping: f32) {
        self.rows = rows;
        self.damping = damping;
    }
}

/// The largest increment the node-wise bound allows for the largest row `omega2` (1/s²) at
/// contact damping ratio `damping`: 2/ω·(√(1+ζ²) − ζ), in f32 as the kernels compute it
/// (`finish_stats`); infinite for a row of zero.
#[cfg(feature = "mpi")]
pub(crate) fn row_increment(omega2: f32, damping: f32) -> f64 {
    if omega2 > 0.0 {
        (2.0 / omega2.sqrt() * ((1.0 + damping * damping).sqrt() - damping)) as f64
    } else {
        f64::INFINITY
    }
}

#[cfg(feature = "mpi")]
impl Contact {
    /// Reads the node-wise bound's rows back with every host-array increment
    /// ([`Contact::node_rows`]).
    pub(crate) fn request_rows(&mut self, yes: bool) {
        self.rows.wanted = yes;
    }

    /// The last host-array increment's node-wise bound rows, per model node (empty unless
    /// asked for), and the damping ratio of the bound: a rigid part's row is on its lowest
    /// node (its nodes have none of their own).
    pub(crate) fn node_rows(&self) -> (&[f32], f32) {
        (&self.rows.rows, self.rows.damping)
    }

    /// Gives the rigid parts' states (one per rigid part of the model, in its order) for the
    /// next host-array increments, instead of following them from this model's nodes.
    pub(crate) fn give_rigid_states(&mut self, states: Vec<RigidState>) -> Result<()> {
        if states.len() != self.parts.len() {
            return Err(Error::LengthMismatch {
                what: "rigid part states (one per rigid part of the model)",
                expected: self.parts.len(),
                got: states.len(),
            });
        }
        self.given_parts = Some(states);
        Ok(())
    }

    /// Pair `pair`'s slaves, when they lie on a rigid part, share the body among `slaves`
    /// springs (the whole pass's slave count over the ranks) instead of this model's.
    pub(crate) fn set_rigid_slave_share(&mut self, pair: PairId, slaves: usize) -> Result<()> {
        for k in self.penalty_runs(pair)? {
            let setup = &mut self.pairs[k].setup;
            if setup.rigid.1.is_some() {
                setup.params.slave_share = slaves.max(1) as f32;
            }
        }
        Ok(())
    }
}
