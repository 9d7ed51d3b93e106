//! The GPU increment executor: each pair's `GpuSearch` and `GpuPenalty`, the increment's
//! statistics (`GpuIncrement`), and the buffers of host-array increments. One increment is one
//! list of dispatch groups recorded into one compute pass.

use super::{not_resident, HostResults, Increment, IncrementExec, PairRaw};
use crate::abi::passes::Buf;
use crate::abi::penalty::{ContactOut, SlaveState};
use crate::abi::search::{GpuHit, PLAN_SLOTS};
use crate::abi::stats::{IncrementStats, STATS_BYTES};
use crate::abi::status::STATUS_WORDS;
use crate::contact::ResidentIo;
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::gpu::{GpuIncrement, GpuPenalty, GpuSearch, GroupWork};
use crate::penalty::PenaltySetup;
use crate::plan::increment::Entry;
use crate::search::SearchExec;
use std::sync::Arc;

mod split;

/// One pair's kernels.
struct GpuPair {
    search: GpuSearch,
    penalty: GpuPenalty,
}

/// abut's own buffers of host-array increments: positions (one buffer per pair, relative to its
/// search's frame), velocities, forces, and the staging buffer everything read back goes through.
struct HostBuffers {
    x: Vec<wgpu::Buffer>,
    v: wgpu::Buffer,
    f: wgpu::Buffer,
    staging: wgpu::Buffer,
}

/// The positions each pair's search reads: the caller's one buffer, or one per pair.
#[derive(Clone, Copy)]
enum Positions<'a> {
    Shared(&'a wgpu::Buffer),
    PerPair(&'a [wgpu::Buffer]),
}

/// The GPU executor of a `Contact`'s penalty increments.
pub(crate) struct GpuExec {
    ctx: Arc<GpuContext>,
    n_nodes: usize,
    pairs: Vec<GpuPair>,
    /// The increment's statistics (after `make_resident`).
    inc: Option<Box<GpuIncrement>>,
    /// Host-array increments' buffers (made by the first).
    host: Option<HostBuffers>,
}

/// Bytes of a pair's output readback: status, plan words up to its slots, hits, outputs.
fn pair_raw_bytes(n_slaves: usize) -> u64 {
    (STATUS_WORDS * 4 + PLAN_SLOTS * 4) as u64
        + n_slaves as u64
            * (std::mem::size_of::<GpuHit>() + std::mem::size_of::<ContactOut>()) as u64
}

impl GpuExec {
    /// An executor on `ctx` for a model of `n_nodes` nodes, with no pair yet.
    pub(super) fn new(ctx: Arc<GpuContext>, n_nodes: usize) -> Self {
        Self {
            ctx,
            n_nodes,
            pairs: Vec::new(),
            inc: None,
            host: None,
        }
    }

    /// The statistics' executor, once resident.
    fn inc(&mut self) -> Result<&mut GpuIncrement> {
        self.inc.as_deref_mut().ok_or_else(not_resident)
    }

    /// Records one increment into `encoder`: every pair's schedule, search, penalty and gather
    /// and the statistics (into the lagged ring when `ring`).
    fn record_on(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        positions: Positions<'_>,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        inc: &Increment<'_>,
        ring: bool,
    ) -> Result<()> {
        let max_dim = self.prepare(positions, velocities, forces, inc)?;
        let entries = self.entries(inc)?;
        self.inc()?.begin(encoder);
        for pair in &self.pairs {
            pair.search.resident_copies(encoder);
        }
        self.record_entries(encoder, &entries, max_dim)?;
        let stats = self.inc()?;
        if ring {
            stats.end(encoder);
        }
        stats.take_uncaptured()
    }

    /// What may allocate or upload before an increment is recorded: the caller's buffers
    /// checked, bind groups on them, the penalty parameters. Returns the folding limit.
    fn prepare(
        &mut self,
        positions: Positions<'_>,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        inc: &Increment<'_>,
    ) -> Result<u32> {
        for (what, b) in [("device velocities", velocities), ("device forces", forces)] {
            if b.size() < self.n_nodes as u64 * 16
                || !b.usage().contains(wgpu::BufferUsages::STORAGE)
            {
                return Err(Error::BadParameter {
                    name: what,
                    value: format!("buffer of {} bytes, usage {:?}", b.size(), b.usage()),
                    expected: "one vec4<f32> per model node and STORAGE usage",
                });
            }
        }
        let stats = self.inc.as_deref_mut().ok_or_else(not_resident)?;
        let mut max_dim = u32::MAX;
        for (k, (pair, params)) in self.pairs.iter_mut().zip(inc.params).enumerate() {
            pair.search.prepare_resident(match positions {
                Positions::PerPair(b) => &b[k],
                Positions::Shared(b) => b,
            })?;
            max_dim = max_dim.min(pair.search.max_workgroups_per_dim());
            let (shared, generation) = pair.search.shared_buffers();
            pair.penalty.prepare_resident(
                &shared,
                generation,
                params,
                velocities,
                forces,
                stats.rows(),
                stats.stats(),
            )?;
        }
        Ok(max_dim)
    }

    /// The increment's entries for `inc`'s pairs (`plan::increment`).
    fn entries(&self, inc: &Increment<'_>) -> Result<Vec<Entry>> {
        inc.entries(|k, n_pair_nodes, local_only| {
            self.pairs
                .get(k)?
                .search
                .pair_shape(n_pair_nodes, local_only)
        })
    }

    /// Records `entries` into one compute pass: each entry's dispatch from the search, penalty
    /// or statistics kernels of its pair, under its group's label.
    fn record_entries(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entries: &[Entry],
        max_dim: u32,
    ) -> Result<()> {
        let stats = self.inc.as_deref().ok_or_else(not_resident)?;
        let mut groups: Vec<GroupWork<'_>> = Vec::new();
        for e in entries {
            let pair = &self.pairs[e.pair];
            let work = pair
                .search
                .dispatch(e)
                .or_else(|| pair.penalty.dispatch(e))
                .or_else(|| stats.dispatch(e))
                .ok_or_else(|| Error::Gpu {
                    during: "recording a device-resident increment".into(),
                    message: format!(
                        "no dispatch for {} of pair {}",
                        e.kernel.pass().entry,
                        e.pair
                    ),
                })?;
            crate::gpu::push_grouped(&mut groups, e.group, work);
        }
        crate::gpu::record_groups(
            &self.ctx,
            encoder,
            "device-resident increment",
            &groups,
            max_dim,
        );
        Ok(())
    }

    /// abut's own buffers for host-array increments of `inc`'s pairs.
    fn host_buffers(&self, inc: &Increment<'_>) -> HostBuffers {
        let n = self.n_nodes as u64;
        let buffer = |label, size: u64, usage| {
            self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16).next_multiple_of(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let state = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let outputs: u64 = inc
            .pairs
            .iter()
            .map(|p| pair_raw_bytes(p.setup.areas.len()))
            .sum();
        HostBuffers {
            x: (0..inc.pairs.len())
                .map(|_| buffer("positions", n * 16, state))
                .collect(),
            v: buffer("velocities", n * 16, state),
            f: buffer("forces", n * 16, state),
            staging: buffer(
                "increment readback",
                n * 16 + STATS_BYTES + n * 4 + 64 * inc.pairs.len() as u64 + outputs,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }

    /// The host-array increment on `host`.
    fn host_increment_on(
        &mut self,
        host: &HostBuffers,
        inc: &Increment<'_>,
        x: &[Vec<[f32; 4]>],
        v: &[[f32; 4]],
        outputs: bool,
        rows: bool,
    ) -> Result<HostResults> {
        let ctx = self.ctx.clone();
        for (b, xk) in host.x.iter().zip(x) {
            crate::gpu::upload(&ctx, b, 0, bytemuck::cast_slice(xk));
        }
        crate::gpu::upload(&ctx, &host.v, 0, bytemuck::cast_slice(v));
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("penalty increment"),
            });
        enc.clear_buffer(&host.f, 0, None);
        self.record_on(
            &mut enc,
            Positions::PerPair(&host.x),
            &host.v,
            &host.f,
            inc,
            false,
        )?;
        let staging = &host.staging;
        let forces_bytes = self.n_nodes as u64 * 16;
        enc.copy_buffer_to_buffer(&host.f, 0, staging, 0, forces_bytes);
        enc.copy_buffer_to_buffer(self.inc()?.stats(), 0, staging, forces_bytes, STATS_BYTES);
        let mut offset = forces_bytes + STATS_BYTES;
        let rows_bytes = if rows { self.n_nodes as u64 * 4 } else { 0 };
        if rows {
            enc.copy_buffer_to_buffer(self.inc()?.rows(), 0, staging, offset, rows_bytes);
        }
        let rows_at = offset as usize;
        offset += rows_bytes;
        // every pair's schedule words
        let heads = offset;
        for pair in &self.pairs {
            enc.copy_buffer_to_buffer(pair.search.resident_outputs().1, 0, staging, offset, 64);
            offset += 64;
        }
        let mut layout = Vec::new();
        if outputs {
            for (pair, pr) in self.pairs.iter().zip(inc.pairs) {
                let ns = pr.setup.areas.len() as u64;
                let (status, plan, hits) = pair.search.resident_outputs();
                let start = offset;
                for (src, bytes) in [
                    (status, (STATUS_WORDS * 4) as u64),
                    (plan, (PLAN_SLOTS * 4) as u64),
                    (hits, ns * 64),
                    (pair.penalty.out_buffer(), ns * 64),
                ] {
                    if bytes > 0 {
                        enc.copy_buffer_to_buffer(src, 0, staging, offset, bytes);
                    }
                    offset += bytes;
                }
                layout.push((start, ns as usize));
            }
        }
        crate::device::submit(&ctx, enc);
        let bytes = crate::gpu::buffers::read_back(&ctx, staging, offset, "penalty increment")?;
        ctx.take_uncaptured("penalty increment")?;
        let forces: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..forces_bytes as usize]);
        let st: IncrementStats = bytemuck::pod_read_unaligned(
            &bytes[forces_bytes as usize..(forces_bytes + STATS_BYTES) as usize],
        );
        let plans: Vec<Vec<u32>> = (0..self.pairs.len())
            .map(|k| {
                let o = heads as usize + 64 * k;
                bytemuck::pod_collect_to_vec(&bytes[o..o + 64])
            })
            .collect();
        let raws = layout
            .into_iter()
            .map(|(start, ns)| {
                let mut o = start as usize;
                let mut take = |len: usize| {
                    let s = &bytes[o..o + len];
                    o += len;
                    s
                };
                let status: [u32; STATUS_WORDS] =
                    bytemuck::pod_read_unaligned(take(STATUS_WORDS * 4));
                let plan: Vec<u32> = bytemuck::pod_collect_to_vec(take(PLAN_SLOTS * 4));
                let hits: Vec<GpuHit> = bytemuck::pod_collect_to_vec(take(ns * 64));
                let out: Vec<ContactOut> = bytemuck::pod_collect_to_vec(take(ns * 64));
                PairRaw {
                    status,
                    plan,
                    hits,
                    out,
                }
            })
            .collect();
        let rows = bytemuck::pod_collect_to_vec(&bytes[rows_at..rows_at + rows_bytes as usize]);
        Ok((forces, st, raws, plans, rows))
    }
}

impl IncrementExec for GpuExec {
    fn add_pair(&mut self, setup: &PenaltySetup) -> Result<()> {
        self.pairs.push(GpuPair {
            search: GpuSearch::new(self.ctx.clone())?,
            penalty: GpuPenalty::new(self.ctx.clone(), setup, self.n_nodes)?,
        });
        Ok(())
    }

    fn search(&mut self, k: usize) -> &mut dyn SearchExec {
        &mut self.pairs[k].search
    }

    fn penalty_state(&self, k: usize) -> Result<Vec<SlaveState>> {
        self.pairs[k].penalty.read_state()
    }

    fn set_penalty_state(&mut self, k: usize, state: &[SlaveState]) {
        self.pairs[k].penalty.write_state(state)
    }

    fn make_resident(&mut self, damping: f32) -> Result<()> {
        let parts: Vec<_> = self
            .pairs
            .iter()
            .map(|p| {
                let (status, plan, _) = p.search.resident_outputs();
                (status, plan)
            })
            .collect();
        self.inc = Some(Box::new(GpuIncrement::new(
            self.ctx.clone(),
            self.n_nodes,
            damping,
            &parts,
        )?));
        Ok(())
    }

    fn record(&mut self, io: ResidentIo<'_>, inc: &Increment<'_>) -> Result<()> {
        let ResidentIo::Gpu {
            encoder,
            positions,
            velocities,
            forces,
        } = io
        else {
            return Err(wrong_io());
        };
        self.record_on(
            encoder,
            Positions::Shared(positions),
            velocities,
            forces,
            inc,
            true,
        )
    }

    fn host_increment(
        &mut self,
        inc: &Increment<'_>,
        x: &[Vec<[f32; 4]>],
        v: &[[f32; 4]],
        outputs: bool,
        rows: bool,
    ) -> Result<HostResults> {
        let host = match self.host.take() {
            Some(h) => h,
            None => self.host_buffers(inc),
        };
        let done = self.host_increment_on(&host, inc, x, v, outputs, rows);
        self.host = Some(host);
        done
    }

    fn run_split(
        &mut self,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        inc: &Increment<'_>,
        first_gpu: usize,
        twin: &mut super::cpu::CpuExec,
    ) -> Result<usize> {
        self.split(positions, velocities, forces, inc, first_gpu, twin)
    }

    fn last_hits(&self, k: usize, n_slaves: usize) -> Result<Vec<GpuHit>> {
        let bytes = (n_slaves * std::mem::size_of::<GpuHit>()) as u64;
        let hits = self.pairs[k].search.resident_outputs().2;
        let raw = crate::gpu::buffers::copy_back(&self.ctx, &[(hits, 0, bytes)], "hits readback")?;
        Ok(bytemuck::pod_collect_to_vec(&raw))
    }

    fn hits_buffer(&self, k: usize) -> Option<&wgpu::Buffer> {
        Some(self.pairs.get(k)?.search.resident_outputs().2)
    }

    fn request_global(&mut self, k: usize) {
        self.pairs[k].search.request_global();
    }

    fn context(&self) -> Option<Arc<GpuContext>> {
        Some(self.ctx.clone())
    }

    fn stats_buffer(&self) -> Option<&wgpu::Buffer> {
        self.inc.as_ref().map(|i| i.stats())
    }

    fn collect_stats(&mut self) -> Result<Vec<IncrementStats>> {
        match self.inc.as_mut() {
            Some(i) => i.collect(),
            None => Ok(Vec::new()),
        }
    }

    fn dropped_stats(&self) -> u64 {
        self.inc.as_ref().map_or(0, |i| i.dropped)
    }
}

/// The error of host arrays given to a GPU executor.
fn wrong_io() -> Error {
    Error::BadParameter {
        name: "device-resident increment",
        value: "host arrays (ResidentIo::Cpu) on a GPU device".into(),
        expected: "ResidentIo::Gpu on a GPU device, ResidentIo::Cpu on the CPU path",
    }
}
