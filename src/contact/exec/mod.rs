//! The executor of a `Contact`'s penalty increments, chosen once when the `Contact` is made
//! ([`for_device`]): on a GPU, each pair's search and penalty kernels with the increment's
//! statistics passes (`gpu.rs`); on the CPU path, their mirrors over host arrays (`cpu.rs`).
//! It owns every pair's device resources — the search's, the penalty's, the statistics and
//! abut's own arrays for host-array increments — so that `Contact` drives one increment
//! through one trait and never asks which executor it has.

pub(crate) mod cpu;
mod gpu;

use super::{PairRun, ResidentIo};
use crate::abi::passes::Buf;
use crate::abi::penalty::{ContactOut, PenaltyParams, SlaveState, PENALTY_SLAVES_APART};
use crate::abi::search::{GpuHit, MAX_RIGID_SLOTS};
use crate::abi::stats::IncrementStats;
use crate::abi::status::STATUS_WORDS;
use crate::device::{Device, DeviceKind, GpuContext};
use crate::error::{Error, Result};
use crate::penalty::PenaltySetup;
use crate::plan::increment::{Entry, PairShape};
use crate::search::SearchExec;
use std::sync::Arc;

/// What one pair's increment left, read back for its output variables.
pub(crate) struct PairRaw {
    /// The pair's status words.
    pub status: [u32; STATUS_WORDS],
    /// The plan's words up to the end of its params.
    pub plan: Vec<u32>,
    /// One hit per slave.
    pub hits: Vec<GpuHit>,
    /// One penalty result per slave.
    pub out: Vec<ContactOut>,
}

/// What a host-array increment reads back: the forces (one `[f32; 4]` per model node), the
/// statistics, each pair's raw results (when outputs were asked for), each pair's schedule
/// words, and the node-wise bound's rows per model node (when asked for; else empty).
pub(crate) type HostResults = (
    Vec<[f32; 4]>,
    IncrementStats,
    Vec<PairRaw>,
    Vec<Vec<u32>>,
    Vec<f32>,
);

/// One increment's inputs beside the caller's arrays: the pairs (their stages and setups, in
/// the executor's pair order), their penalty parameters this increment, and which pairs the
/// host has proved will search locally (their global search is not recorded; empty: none).
pub(crate) struct Increment<'a> {
    /// The pairs of the `Contact`.
    pub pairs: &'a [PairRun],
    /// Each pair's penalty parameters.
    pub params: &'a [PenaltyParams],
    /// Per pair: the schedule surely chooses the local search.
    pub local_only: &'a [bool],
}

impl Increment<'_> {
    /// The increment's entries (`plan::increment`), each pair's search shape from
    /// `shape(k, n_pair_nodes, local_only)` (`None`: pair `k` is not resident).
    pub(crate) fn entries(
        &self,
        shape: impl Fn(usize, u32, bool) -> Option<PairShape>,
    ) -> Result<Vec<Entry>> {
        let shapes = self
            .pairs
            .iter()
            .enumerate()
            .map(|(k, pr)| {
                let local_only = self.local_only.get(k).copied().unwrap_or(false);
                let mut s = shape(k, pr.setup.pair_nodes.len() as u32, local_only)?;
                // the active slaves' gather when the slaves are no master nodes and the other
                // pair nodes are what the plan's slot counts (PLAN_OTHER_NODES)
                let rigid_slots = pr.setup.pair_nodes.len() - pr.setup.n_nodes;
                s.gather_active = pr.setup.params.flags & PENALTY_SLAVES_APART != 0
                    && pr.setup.n_nodes as u32 == s.n_motion_nodes
                    && rigid_slots as u32 <= MAX_RIGID_SLOTS;
                Some(s)
            })
            .collect::<Option<Vec<_>>>()
            .ok_or_else(not_resident)?;
        Ok(crate::plan::increment::increment(&shapes))
    }
}

/// The error of an increment before the pairs were made resident.
pub(crate) fn not_resident() -> Error {
    Error::BadParameter {
        name: "device-resident increment",
        value: "pairs not made resident".into(),
        expected: "the first increment readies them",
    }
}

/// The error of a split increment on the CPU path, which has nothing to split.
pub(crate) fn no_split_on_cpu() -> Error {
    Error::BadParameter {
        name: "run_split",
        value: "CPU path".into(),
        expected: "a GPU device (a split runs part of an increment on each executor)",
    }
}

/// The device work of a `Contact`'s penalty increments. Pair `k` is the `Contact`'s k-th
/// penalty pass (a balanced pair has two). `Send` where [`SearchExec`] is.
pub(crate) trait IncrementExec: wgpu::WasmNotSend {
    /// Adds the executors of the next pair (its search's and its penalty's, for `setup`).
    fn add_pair(&mut self, setup: &PenaltySetup) -> Result<()>;
    /// Pair `k`'s search executor (for its stage to drive).
    fn search(&mut self, k: usize) -> &mut dyn SearchExec;
    /// Pair `k`'s per-slave penalty state (read back on a GPU).
    fn penalty_state(&self, k: usize) -> Result<Vec<SlaveState>>;
    /// Replaces pair `k`'s per-slave penalty state (as long as its slaves).
    fn set_penalty_state(&mut self, k: usize, state: &[SlaveState]);
    /// Readies the increment's statistics once every pair's search is resident (`damping`: the
    /// largest penalty damping, for the stable increment).
    fn make_resident(&mut self, damping: f32) -> Result<()>;
    /// Records (GPU) or runs (CPU path) one device-resident increment on the caller's arrays
    /// `io`, its statistics copied into the lagged ring.
    fn record(&mut self, io: ResidentIo<'_>, inc: &Increment<'_>) -> Result<()>;
    /// One host-array increment on abut's own arrays: positions `x` (per pair, relative to its
    /// search's frame), velocities `v`; the forces, statistics, schedule words and (with
    /// `outputs`) each pair's raw results and (with `rows`) the node-wise bound's rows come back
    /// in one readback.
    fn host_increment(
        &mut self,
        inc: &Increment<'_>,
        x: &[Vec<[f32; 4]>],
        v: &[[f32; 4]],
        outputs: bool,
        rows: bool,
    ) -> Result<HostResults>;
    /// One device-resident increment on the caller's GPU buffers, its entries `..first_gpu`
    /// run by `twin` (a CPU executor whose pairs were made resident as these) and the rest
    /// here, every role the increment writes ([`HANDED_OVER`]) read back into the twin
    /// before and written back after; submitted and waited for. Returns the number of entries.
    /// The CPU path refuses it.
    #[allow(clippy::too_many_arguments)]
    fn run_split(
        &mut self,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        inc: &Increment<'_>,
        first_gpu: usize,
        twin: &mut cpu::CpuExec,
    ) -> Result<usize>;
    /// Pair `k`'s hits of the last increment (`n_slaves` of them).
    fn last_hits(&self, k: usize, n_slaves: usize) -> Result<Vec<GpuHit>>;
    /// Pair `k`'s device buffer of hits (`None` on the CPU path).
    fn hits_buffer(&self, k: usize) -> Option<&wgpu::Buffer>;
    /// Asks pair `k`'s next increment to search globally.
    fn request_global(&mut self, k: usize);
    /// The GPU this executor records on (`None` on the CPU path).
    fn context(&self) -> Option<Arc<GpuContext>>;
    /// The device buffer of the last device-resident increment's statistics.
    fn stats_buffer(&self) -> Option<&wgpu::Buffer>;
    /// The statistics of the increments finished since the last call, oldest first.
    fn collect_stats(&mut self) -> Result<Vec<IncrementStats>>;
    /// Increments whose statistics found the ring (or queue) full.
    fn dropped_stats(&self) -> u64;
}

/// Every role a device-resident increment writes, per pair (`true`) or once (`false`): what a
/// split increment hands from one executor to the other. `tests` check it against the passes'
/// declared access.
pub(crate) const HANDED_OVER: [(Buf, bool); 22] = [
    (Buf::Nodes, true),
    (Buf::Status, true),
    (Buf::Active, true),
    (Buf::Hits, true),
    (Buf::Reference, true),
    (Buf::Skins, true),
    (Buf::Plan, true),
    (Buf::Args, true),
    (Buf::Boxes, true),
    (Buf::Work, true),
    (Buf::Best, true),
    (Buf::WalkPoints, true),
    (Buf::Grid, true),
    (Buf::Normals, true),
    (Buf::State, true),
    (Buf::Out, true),
    (Buf::Acc, true),
    (Buf::Forces, true),
    (Buf::Need, true),
    (Buf::Rows, false),
    (Buf::Stats, false),
    (Buf::HostForces, false),
];

/// The increment executor of `device` for a model of `n_nodes` nodes: the one place a
/// `Contact` chooses between GPU and CPU.
pub(crate) fn for_device(device: &Device, n_nodes: usize) -> Box<dyn IncrementExec> {
    match device.kind() {
        DeviceKind::Gpu(ctx) => Box::new(gpu::GpuExec::new(ctx.clone(), n_nodes)),
        DeviceKind::Cpu => Box::new(cpu::CpuExec::new(n_nodes)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abi::passes::Access;
    use crate::plan::increment::Kernel;

    /// A `Contact` and a `GlobalSearch` can move to another thread on native targets (the
    /// executors' traits ask for `WasmNotSend`: `Send` there, nothing in a browser, whose
    /// WebGPU objects are not `Send`).
    #[test]
    fn contacts_and_searches_are_send_on_native_targets() {
        fn send<T: Send>() {}
        send::<crate::Contact>();
        send::<crate::GlobalSearch>();
    }

    /// Every buffer an increment's kernel may write is handed over by a split increment, so
    /// that a split at any entry leaves each executor what the other wrote.
    #[test]
    fn a_split_hands_over_every_role_the_increment_writes() {
        for k in Kernel::ALL {
            for b in k.pass().bindings {
                let buf = match b.buf {
                    // the scan's data is the work items
                    Buf::ScanData => Buf::Work,
                    other => other,
                };
                if b.access == Access::ReadWrite {
                    assert!(
                        HANDED_OVER.iter().any(|(h, _)| *h == buf),
                        "{} writes {:?}, which a split does not hand over",
                        k.pass().entry,
                        b.buf
                    );
                }
            }
        }
    }
}
