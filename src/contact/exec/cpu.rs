//! The CPU increment executor: each pair's search and penalty mirrors, the increment's
//! statistics words and their queue, and abut's own arrays for host-array increments — the
//! GPU's increment pass for pass on f32 host arrays laid out as its buffers are.

use super::{HostResults, Increment, IncrementExec, PairRaw};
use crate::abi::penalty::SlaveState;
use crate::abi::search::{GpuHit, PLAN_SLOTS};
use crate::abi::stats::{IncrementStats, STATS_RESET_WORDS, STATS_WORDS};
use crate::contact::ResidentIo;
use crate::cpu::{gather, stats, CpuPenalty, CpuSearch};
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::gpu::STATS_RING;
use crate::penalty::PenaltySetup;
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

/// abut's own arrays of host-array increments: positions per pair, velocities, forces.
struct HostArrays {
    x: Vec<Vec<[f32; 4]>>,
    v: Vec<[f32; 4]>,
    f: Vec<[f32; 4]>,
}

/// The CPU executor of a `Contact`'s penalty increments.
pub(crate) struct CpuExec {
    n_nodes: usize,
    pairs: Vec<CpuPair>,
    resident: Option<Resident>,
    host: Option<HostArrays>,
}

impl CpuExec {
    /// An executor for a model of `n_nodes` nodes, with no pair yet.
    pub(super) fn new(n_nodes: usize) -> Self {
        Self {
            n_nodes,
            pairs: Vec::new(),
            resident: None,
            host: None,
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
        let r = self.resident.as_mut().ok_or_else(not_resident)?;
        r.rows.iter_mut().for_each(|x| *x = 0.0);
        r.stats[..STATS_RESET_WORDS].copy_from_slice(&crate::abi::stats::reset_image());
        for (k, ((pair, pr), pp)) in self
            .pairs
            .iter_mut()
            .zip(inc.pairs)
            .zip(inc.params)
            .enumerate()
        {
            let x = positions.get(k).unwrap_or(&positions[0]);
            let (mut status, prep, hits) = pair.search.step_resident(x)?;
            pair.penalty
                .run(&pr.setup, pp, prep, velocities, hits, &mut status);
            gather::add_forces(
                pp,
                &pr.setup.pair_nodes,
                &pair.penalty.forces,
                forces,
                &mut r.rows,
            );
            let plan = pair.search.resident_plan_mut().ok_or_else(not_resident)?;
            stats::pair_stats(&status, plan, &mut r.stats);
        }
        for pr in inc.pairs {
            stats::bound_max(&pr.setup.pair_nodes, &r.rows, &mut r.stats);
        }
        stats::finish_stats(&mut r.stats);
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

    fn make_resident(&mut self, _: &[crate::contact::PairRun], damping: f32) -> Result<()> {
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
    ) -> Result<HostResults> {
        let n = self.n_nodes;
        let mut host = self.host.take().unwrap_or_else(|| HostArrays {
            x: vec![vec![[0.0; 4]; n]; inc.pairs.len()],
            v: vec![[0.0; 4]; n],
            f: vec![[0.0; 4]; n],
        });
        for (a, xk) in host.x.iter_mut().zip(x) {
            a.copy_from_slice(xk);
        }
        host.v.copy_from_slice(v);
        host.f.iter_mut().for_each(|f| *f = [0.0; 4]);
        let xs: Vec<&[[f32; 4]]> = host.x.iter().map(|x| x.as_slice()).collect();
        let ran = self.run(&xs, &host.v, &mut host.f, inc, false);
        let forces = host.f.clone();
        self.host = Some(host);
        ran?;
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
        Ok((forces, st, raws, plans))
    }

    fn last_hits(&self, k: usize, n_slaves: usize) -> Result<Vec<GpuHit>> {
        Ok(self.pairs[k].search.resident_outputs().2[..n_slaves].to_vec())
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

/// The error of an increment before the pairs were made resident.
fn not_resident() -> Error {
    Error::BadParameter {
        name: "device-resident increment",
        value: "pairs not made resident".into(),
        expected: "the first increment readies them",
    }
}
