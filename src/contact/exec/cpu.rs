//! The CPU increment executor: each pair's search and penalty mirrors and the increment's
//! statistics words and their queue — the GPU's increment entry by entry on f32 host arrays laid
//! out as its buffers are (host-array increments run on the host's own f32 copies).

use super::{not_resident, HostResults, Increment, IncrementExec, PairRaw};
use crate::abi::passes::Buf;
use crate::abi::penalty::SlaveState;
use crate::abi::search::{GpuHit, PLAN_SLOTS};
use crate::abi::stats::{IncrementStats, STATS_RESET_WORDS, STATS_WORDS};
use crate::contact::ResidentIo;
use crate::cpu::increment::{run_entry, PenaltyArrays};
use crate::cpu::{CpuPenalty, CpuSearch};
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::gpu::STATS_RING;
use crate::penalty::PenaltySetup;
use crate::plan::increment::Entry;
use crate::search::SearchExec;
use std::sync::Arc;

/// One pair's mirrors.
struct CpuPair {
    search: CpuSearch,
    penalty: CpuPenalty,
}

/// What the increments keep beside the pairs once resident.
struct Resident {
    /// The node-wise bound's rows per model node.
    rows: Vec<f32>,
    /// The statistics words (`IncrementStats`).
    stats: [u32; STATS_WORDS],
    /// Statistics not yet collected (at most `STATS_RING`, as on a GPU).
    queue: Vec<IncrementStats>,
    /// Increments whose statistics found the queue full.
    dropped: u64,
}

/// The CPU executor of a `Contact`'s penalty increments.
pub(crate) struct CpuExec {
    n_nodes: usize,
    pairs: Vec<CpuPair>,
    resident: Option<Resident>,
}

impl CpuExec {
    /// An executor for a model of `n_nodes` nodes, with no pair yet.
    pub(super) fn new(n_nodes: usize) -> Self {
        Self {
            n_nodes,
            pairs: Vec::new(),
            resident: None,
        }
    }

    /// Runs one increment on the arrays (positions per pair, or one array for all), its
    /// statistics queued when `ring`.
    fn run(
        &mut self,
        positions: &[&[[f32; 4]]],
        velocities: &[[f32; 4]],
        forces: &mut [[f32; 4]],
        inc: &Increment<'_>,
        ring: bool,
    ) -> Result<()> {
        let n_nodes = self.n_nodes;
        for (what, len) in [
            (
                "device positions (one vec4 per model node)",
                positions.first().map_or(0, |x| x.len()),
            ),
            (
                "device velocities (one vec4 per model node)",
                velocities.len(),
            ),
            ("device forces (one vec4 per model node)", forces.len()),
        ] {
            if len != n_nodes {
                return Err(Error::LengthMismatch {
                    what,
                    expected: n_nodes,
                    got: len,
                });
            }
        }
        let entries = self.entries(inc)?;
        self.reset()?;
        self.run_entries(&entries, positions, velocities, forces, inc)?;
        let r = self.resident.as_mut().ok_or_else(not_resident)?;
        if ring {
            if r.queue.len() < STATS_RING {
                r.queue.push(bytemuck::cast(r.stats));
            } else {
                r.dropped += 1;
            }
        }
        Ok(())
    }
}

impl CpuExec {
    /// The CPU twin of `pairs`' executor for a split increment: the same pairs made resident
    /// at `positions` (the model's) in the caller's frame, their arrays to be read back from
    /// the other executor.
    pub(crate) fn twin(
        pairs: &[crate::contact::PairRun],
        n_nodes: usize,
        positions: &[[f64; 3]],
    ) -> Result<Self> {
        let mut twin = Self::new(n_nodes);
        for (k, pr) in pairs.iter().enumerate() {
            twin.add_pair(&pr.setup)?;
            pr.search
                .make_twin_resident(twin.search(k), positions, true)?;
        }
        twin.make_resident(0.0)?;
        Ok(twin)
    }

    /// The increment's entries for `inc`'s pairs (`plan::increment`).
    pub(super) fn entries(&self, inc: &Increment<'_>) -> Result<Vec<Entry>> {
        inc.entries(|k, n_pair_nodes, local_only| {
            self.pairs
                .get(k)?
                .search
                .pair_shape(n_pair_nodes, local_only)
        })
    }

    /// What the GPU's copies do before its compute pass: every status word, the rows and the
    /// statistics reset.
    pub(super) fn reset(&mut self) -> Result<()> {
        for p in &mut self.pairs {
            p.search.arrays().ok_or_else(not_resident)?.ws.status =
                crate::abi::status::reset_image();
        }
        let r = self.resident.as_mut().ok_or_else(not_resident)?;
        r.rows.iter_mut().for_each(|x| *x = 0.0);
        r.stats[..STATS_RESET_WORDS].copy_from_slice(&crate::abi::stats::reset_image());
        Ok(())
    }

    /// Runs `entries` in order, each through its kernel's mirror (`cpu::increment`), on the
    /// positions of each pair's search (one array for all, or one per pair).
    pub(super) fn run_entries(
        &mut self,
        entries: &[Entry],
        positions: &[&[[f32; 4]]],
        velocities: &[[f32; 4]],
        forces: &mut [[f32; 4]],
        inc: &Increment<'_>,
    ) -> Result<()> {
        let r = self.resident.as_mut().ok_or_else(not_resident)?;
        for e in entries {
            let k = e.pair;
            let pair = &mut self.pairs[k];
            let search = pair.search.arrays().ok_or_else(not_resident)?;
            run_entry(
                e,
                positions.get(k).unwrap_or(&positions[0]),
                search,
                Some(PenaltyArrays {
                    penalty: &mut pair.penalty,
                    setup: &inc.pairs[k].setup,
                    params: &inc.params[k],
                    velocities,
                    forces,
                    rows: &mut r.rows,
                    stats: &mut r.stats,
                }),
            )?;
        }
        Ok(())
    }

    /// The bytes of role `buf` of pair `pair` (`None`: the increment's own), sized as the GPU's
    /// buffer of that role is used (`setup`: the pair's).
    pub(super) fn role_bytes(
        &mut self,
        pair: Option<usize>,
        buf: Buf,
        setup: &PenaltySetup,
    ) -> Option<&mut [u8]> {
        match pair {
            Some(k) => {
                let p = self.pairs.get_mut(k)?;
                match p.search.role_bytes(buf) {
                    Some(b) => Some(b),
                    None => p.penalty.role_bytes(buf, setup),
                }
            }
            None => {
                let r = self.resident.as_mut()?;
                match buf {
                    Buf::Rows => Some(bytemuck::cast_slice_mut(&mut r.rows)),
                    Buf::Stats => Some(bytemuck::cast_slice_mut(&mut r.stats)),
                    _ => None,
                }
            }
        }
    }
}

impl IncrementExec for CpuExec {
    fn add_pair(&mut self, setup: &PenaltySetup) -> Result<()> {
        self.pairs.push(CpuPair {
            search: CpuSearch::default(),
            penalty: CpuPenalty::new(setup, self.n_nodes),
        });
        Ok(())
    }

    fn search(&mut self, k: usize) -> &mut dyn SearchExec {
        &mut self.pairs[k].search
    }

    fn penalty_state(&self, k: usize) -> Result<Vec<SlaveState>> {
        Ok(self.pairs[k].penalty.state.clone())
    }

    fn set_penalty_state(&mut self, k: usize, state: &[SlaveState]) {
        self.pairs[k].penalty.state.copy_from_slice(state)
    }

    fn make_resident(&mut self, damping: f32) -> Result<()> {
        self.resident = Some(Resident {
            rows: vec![0.0; self.n_nodes],
            stats: crate::abi::stats::first_image(damping),
            queue: Vec::new(),
            dropped: 0,
        });
        Ok(())
    }

    fn record(&mut self, io: ResidentIo<'_>, inc: &Increment<'_>) -> Result<()> {
        let ResidentIo::Cpu {
            positions,
            velocities,
            forces,
        } = io
        else {
            return Err(Error::BadParameter {
                name: "device-resident increment",
                value: "GPU buffers (ResidentIo::Gpu) on the CPU path".into(),
                expected: "ResidentIo::Gpu on a GPU device, ResidentIo::Cpu on the CPU path",
            });
        };
        self.run(&[positions], velocities, forces, inc, true)
    }

    fn host_increment(
        &mut self,
        inc: &Increment<'_>,
        x: &[Vec<[f32; 4]>],
        v: &[[f32; 4]],
        outputs: bool,
        rows: bool,
    ) -> Result<HostResults> {
        // the host's arrays are the CPU path's own: the increment runs on them, summing into
        // fresh forces that are handed back
        let mut forces = vec![[0.0f32; 4]; self.n_nodes];
        let xs: Vec<&[[f32; 4]]> = x.iter().map(|x| x.as_slice()).collect();
        self.run(&xs, v, &mut forces, inc, false)?;
        let r = self.resident.as_ref().ok_or_else(not_resident)?;
        let st: IncrementStats = bytemuck::cast(r.stats);
        let plans = self
            .pairs
            .iter()
            .map(|p| p.search.resident_outputs().1[..16].to_vec())
            .collect();
        let mut raws = Vec::new();
        if outputs {
            for p in &self.pairs {
                let (status, plan, hits) = p.search.resident_outputs();
                raws.push(PairRaw {
                    status,
                    plan: plan[..PLAN_SLOTS].to_vec(),
                    hits: hits.to_vec(),
                    out: p.penalty.out.clone(),
                });
            }
        }
        let rows = if rows { r.rows.clone() } else { Vec::new() };
        Ok((forces, st, raws, plans, rows))
    }

    fn run_split(
        &mut self,
        _: &wgpu::Buffer,
        _: &wgpu::Buffer,
        _: &wgpu::Buffer,
        _: &Increment<'_>,
        _: usize,
        _: &mut CpuExec,
    ) -> Result<usize> {
        Err(super::no_split_on_cpu())
    }

    fn last_hits(&self, k: usize, n_slaves: usize) -> Result<Vec<GpuHit>> {
        Ok(self.pairs[k].search.resident_outputs().2[..n_slaves].to_vec())
    }

    fn hits_buffer(&self, _: usize) -> Option<&wgpu::Buffer> {
        None
    }

    fn request_global(&mut self, k: usize) {
        self.pairs[k].search.request_global();
    }

    fn context(&self) -> Option<Arc<GpuContext>> {
        None
    }

    fn stats_buffer(&self) -> Option<&wgpu::Buffer> {
        None
    }

    fn collect_stats(&mut self) -> Result<Vec<IncrementStats>> {
        Ok(self
            .resident
            .as_mut()
            .map(|r| std::mem::take(&mut r.queue))
            .unwrap_or_default())
    }

    fn dropped_stats(&self) -> u64 {
        self.resident.as_ref().map_or(0, |r| r.dropped)
    }
}
