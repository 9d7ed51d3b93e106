//! What a rank's contact reports of its slaves: the per-slave outputs of the last increment
//! (pressure and force of each slave in contact) and the energy friction dissipated.

use super::*;

/// A slave node of this rank in contact after the last increment (see
/// [`DistributedContact::request_outputs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlaveOutput {
    /// The pair ([`RankModel::pairs`] index; a balanced pair's two passes both report here).
    pub pair: usize,
    /// Whether it is a balanced pair's second pass (the slave a master node).
    pub reverse: bool,
    /// The slave's global node id.
    pub node: u64,
    /// Contact pressure (force over tributary area).
    pub pressure: f64,
    /// The contact force on the slave.
    pub force: [f64; 3],
}

impl DistributedContact {
    /// Whether the next increments compute per-slave outputs for [`Self::contact_outputs`]
    /// (as [`Contact::request_outputs`]; off by default).
    pub fn request_outputs(&mut self, on: bool) {
        self.outputs = on;
        if let Some(c) = self.contact.as_mut() {
            c.request_outputs(on);
        }
    }

    /// This rank's slaves in contact after the last increment (outputs requested before it), in
    /// pass order and each pass's slave order; and the energy its slaves' friction has
    /// dissipated since the start (carried through the rebuilds; every increment, requested or
    /// not, on the CPU path; with outputs on a GPU).
    pub fn contact_outputs(&self) -> (Vec<SlaveOutput>, f64) {
        let (mut list, mut dissipated) = (Vec::new(), 0.0);
        // kinematic pairs: the corrections of the last increment, their friction's energy
        for p in self.pairs.iter().filter(|p| p.kinematic.is_some()) {
            dissipated += p.dissipated;
            for (&i, &(pressure, force)) in p.slaves.iter().zip(&p.corrections) {
                self.push_output(&mut list, p, i, pressure, force);
            }
        }
        let Some(c) = self.contact.as_ref() else {
            return (list, dissipated);
        };
        let outs = c.outputs();
        for p in self.pairs.iter().filter(|p| p.kinematic.is_none()) {
            let Some(id) = p.local else { continue };
            for (_, o) in outs.iter().filter(|(k, _)| *k == id) {
                dissipated += o.frictional_dissipation;
                for (k, &i) in p.slaves.iter().enumerate() {
                    let pressure = o.cpress.get(k).copied().unwrap_or(0.0);
                    let force = o.force.get(k).copied().unwrap_or([0.0; 3]);
                    self.push_output(&mut list, p, i, pressure, force);
                }
            }
        }
        (list, dissipated)
    }

    /// Own slave `i` of pass `p` into `list` when it is in contact (a positive pressure).
    fn push_output(
        &self,
        list: &mut Vec<SlaveOutput>,
        p: &PairTopology,
        i: usize,
        pressure: f64,
        force: [f64; 3],
    ) {
        if pressure > 0.0 {
            list.push(SlaveOutput {
                pair: p.of.0,
                reverse: p.of.1,
                node: self.ids[i],
                pressure,
                force,
            });
        }
    }
}
