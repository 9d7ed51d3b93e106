//! The one loop of a scene run, for one process and for MPI ranks alike: each increment's
//! step chosen by the [`Account`], taken by a [`Ranks`] (the solver with its contact, or this
//! rank's share with the distributed contact and the halo), its limits and sums handed back to
//! the account, and its outputs written.

use std::time::Instant;

use super::account::Account;
use super::Progress;
use crate::device::Device;
use crate::error::Result;

/// What an increment's contact asks of the next one's length.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Limits {
    /// Penalty contact's stable increment and largest overclosure (model units), when the run
    /// has penalty pairs.
    pub penalty: Option<(f64, f64)>,
    /// Kinematic contact's largest overclosure, when the run has kinematic pairs.
    pub kinematic: Option<f64>,
}

/// An increment's totals over the whole model (summed in rank order across ranks).
#[derive(Clone, Debug, Default)]
pub(super) struct Sums {
    /// The contact force on the slave nodes, model units.
    pub force: [f64; 3],
    /// The energy balance's drift since the start, the largest energy (its scale) and the
    /// balance itself.
    pub drift: f64,
    /// See `drift`.
    pub scale: f64,
    /// See `drift`.
    pub balance: f64,
    /// On output rows: each rigid body's displacement from its start (empty where a run has
    /// none).
    pub moved: Vec<[f64; 3]>,
    /// Kinetic and internal energy.
    pub kinetic_internal: [f64; 2],
}

/// How a run steps and adds up: one process, or this rank of N.
pub(super) trait Ranks {
    /// The model's time now.
    fn time(&self) -> f64;
    /// Takes the increment of length `step` that the account has counted `k` before (`last`:
    /// the run's last, whose contact outputs the summary reads); an error names a node that
    /// moved past its search radius.
    fn advance(&mut self, step: f64, k: usize, last: bool) -> Result<Limits>;
    /// After the account counted the increment: what the ranks agree on of its timing.
    fn counted(&mut self, _account: &mut Account<'_>) {}
    /// The increment's totals (with the parts' motion when `row`).
    fn sums(&mut self, row: bool) -> Result<Sums>;
    /// Writes what the increment outputs: a history row when `row` (`force`: the contact
    /// force's magnitude), a VTK frame every so many increments; `peak`: the contact force
    /// peaked here.
    fn output(&mut self, k: usize, row: bool, force: f64, peak: bool) -> Result<()>;
}

/// Runs `ranks` to the end time, the account taking each increment in.
pub(super) fn run(
    account: &mut Account<'_>,
    ranks: &mut dyn Ranks,
    device: &Device,
    progress: &mut dyn FnMut(&Progress),
) -> Result<()> {
    while account.running(ranks.time()) {
        let step = account.step(ranks.time());
        let last = account.is_last(ranks.time(), step);
        let t_step = Instant::now();
        let t_start = ranks.time();
        let limits = ranks
            .advance(step, account.k, last)
            .map_err(|e| account.explain(e))?;
        account.counted(ranks.time(), t_step, device, progress);
        ranks.counted(account);
        if let Some((stable, overclosure)) = limits.penalty {
            account.penalty_limit(stable, overclosure, step, t_start);
        }
        if let Some(overclosure) = limits.kinematic {
            account.overclosure(overclosure);
        }
        let row = account.row();
        let sums = ranks.sums(row)?;
        let time = ranks.time();
        let (force, peak) = account.force(time, step, sums.force);
        if row {
            account.sample(time, sums.moved);
        }
        account
            .energy(sums.drift, sums.scale, sums.balance, time)
            .map_err(|e| account.explain(e))?;
        account.kinetic_internal(time, sums.kinetic_internal);
        ranks.output(account.k, row, force, peak)?;
    }
    Ok(())
}
