//! The parts of a device-resident increment that belong to no one pair, on the GPU: the rows of
//! the node-wise bound summed over the pairs, the increment's statistics reduced on the device,
//! and a ring of staging buffers that lets the host read those statistics a few increments late
//! without ever waiting.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use crate::abi::passes::{self, Buf};
use crate::abi::stats::{IncrementStats, STATS_BYTES, STATS_RESET_WORDS};
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::plan::increment::{Entry, Kernel};
use wgpu::BufferUsages as U;

/// Staging buffers in the statistics ring: how many increments the host may fall behind before
/// an increment's statistics are dropped from it (the device buffer always has the latest).
pub const STATS_RING: usize = 8;

/// The state of one staging buffer of the ring.
const FREE: u8 = 0;
const COPIED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

struct Slot {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
}

/// One pair's bind group of the statistics pass.
struct PairGroups {
    pair_stats: wgpu::BindGroup,
}

/// Rows, statistics and their ring for the device-resident increments of one `Contact`.
pub(crate) struct GpuIncrement {
    ctx: Arc<GpuContext>,
    pair_stats: wgpu::ComputePipeline,
    finish_stats: wgpu::ComputePipeline,
    finish_group: wgpu::BindGroup,
    /// f32 per model node: the node-wise bound's rows, summed over the pairs of an increment.
    rows: wgpu::Buffer,
    /// The increment's statistics (`IncrementStats`).
    stats: wgpu::Buffer,
    /// The reset values of the statistics' first words.
    stats_image: wgpu::Buffer,
    pairs: Vec<PairGroups>,
    ring: Vec<Slot>,
    /// Increments whose statistics found no free staging buffer.
    pub(crate) dropped: u64,
}

impl GpuIncrement {
    /// The rows and statistics of a model of `n_nodes` nodes whose penalty pairs have the
    /// largest damping ratio `damping`; each pair given as (status, plan).
    pub(crate) fn new(
        ctx: Arc<GpuContext>,
        n_nodes: usize,
        damping: f32,
        pairs: &[(&wgpu::Buffer, &wgpu::Buffer)],
    ) -> Result<Self> {
        let d = &ctx.device;
        let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
        let made = (|| -> Result<Self> {
            let (pair_stats, finish_stats) = (
                ctx.pipeline(&passes::PAIR_STATS, &[])?,
                ctx.pipeline(&passes::FINISH_STATS, &[])?,
            );
            let buffer = |label, size: u64, usage| {
                d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size.max(16).next_multiple_of(16),
                    usage,
                    mapped_at_creation: false,
                })
            };
            let rows = buffer(
                "bound rows",
                n_nodes as u64 * 4,
                U::STORAGE | U::COPY_DST | U::COPY_SRC,
            );
            let stats = buffer(
                "increment statistics",
                STATS_BYTES,
                U::STORAGE | U::COPY_DST | U::COPY_SRC,
            );
            let stats_image = buffer(
                "statistics reset image",
                STATS_BYTES,
                U::COPY_SRC | U::COPY_DST,
            );
            let first = crate::abi::stats::first_image(damping);
            super::upload(&ctx, &stats, 0, bytemuck::cast_slice(&first));
            super::upload(&ctx, &stats_image, 0, bytemuck::cast_slice(&first));
            let finish_group = super::bind(d, &finish_stats, &passes::FINISH_STATS, |b| match b {
                Buf::Stats => Some(stats.as_entire_binding()),
                _ => None,
            })?;
            let mut groups = Vec::new();
            for &(status, plan) in pairs {
                let resource = |b| {
                    Some(match b {
                        Buf::Status => status.as_entire_binding(),
                        Buf::Plan => plan.as_entire_binding(),
                        Buf::Stats => stats.as_entire_binding(),
                        _ => return None,
                    })
                };
                groups.push(PairGroups {
                    pair_stats: super::bind(d, &pair_stats, &passes::PAIR_STATS, resource)?,
                });
            }
            let ring = (0..STATS_RING)
                .map(|_| Slot {
                    buffer: buffer("statistics ring", STATS_BYTES, U::MAP_READ | U::COPY_DST),
                    state: Arc::new(AtomicU8::new(FREE)),
                })
                .collect();
            Ok(Self {
                ctx: ctx.clone(),
                pair_stats,
                finish_stats,
                finish_group,
                rows,
                stats,
                stats_image,
                pairs: groups,
                ring,
                dropped: 0,
            })
        })();
        if let Some(e) = ctx.scope_error(scope) {
            return Err(Error::Gpu {
                during: "making the device-resident statistics".into(),
                message: e.to_string(),
            });
        }
        made
    }

    /// Errors wgpu raised outside error scopes while the increment was encoded.
    pub(crate) fn take_uncaptured(&self) -> Result<()> {
        self.ctx.take_uncaptured("device-resident increment")
    }

    /// The rows buffer the pairs' add_forces sum into.
    pub(crate) fn rows(&self) -> &wgpu::Buffer {
        &self.rows
    }

    /// The statistics buffer (`IncrementStats`, 76 bytes, STORAGE | COPY_SRC).
    pub(crate) fn stats(&self) -> &wgpu::Buffer {
        &self.stats
    }

    /// Encodes the start of an increment: the rows zeroed, the statistics reset.
    pub(crate) fn begin(&self, enc: &mut wgpu::CommandEncoder) {
        enc.clear_buffer(&self.rows, 0, None);
        enc.copy_buffer_to_buffer(
            &self.stats_image,
            0,
            &self.stats,
            0,
            4 * STATS_RESET_WORDS as u64,
        );
    }

    /// The buffer of role `buf` that the statistics passes write (`None` otherwise).
    pub(crate) fn role_buffer(&self, buf: Buf) -> Option<&wgpu::Buffer> {
        match buf {
            Buf::Rows => Some(&self.rows),
            Buf::Stats => Some(&self.stats),
            _ => None,
        }
    }

    /// The dispatch of entry `e` if it is a statistics kernel: a pair's status words into the
    /// statistics (after its passes), the stable increment.
    pub(crate) fn dispatch(&self, e: &Entry) -> Option<super::Dispatch<'_>> {
        let (pipe, group) = match e.kernel {
            Kernel::PairStats => (&self.pair_stats, &self.pairs.get(e.pair)?.pair_stats),
            Kernel::FinishStats => (&self.finish_stats, &self.finish_group),
            _ => return None,
        };
        super::direct_dispatch(pipe, group, e.size)
    }

    /// Encodes, after the increment's compute pass, a copy of the statistics into a free staging
    /// buffer of the ring (none free: dropped, and counted).
    pub(crate) fn end(&mut self, enc: &mut wgpu::CommandEncoder) {
        match self
            .ring
            .iter()
            .find(|s| s.state.load(Ordering::Acquire) == FREE)
        {
            Some(slot) => {
                enc.copy_buffer_to_buffer(&self.stats, 0, &slot.buffer, 0, STATS_BYTES);
                slot.state.store(COPIED, Ordering::Release);
            }
            None => self.dropped += 1,
        }
    }

    /// The statistics of increments whose staging buffers the device has finished with, in
    /// increment order, without waiting: staging copied by increments submitted since the last
    /// call is asked to map (so call this only after submitting what was encoded), and the
    /// device is polled once, not waited on.
    pub(crate) fn collect(&mut self) -> Result<Vec<IncrementStats>> {
        for slot in &self.ring {
            if slot.state.load(Ordering::Acquire) == COPIED {
                slot.state.store(MAPPING, Ordering::Release);
                let state = slot.state.clone();
                slot.buffer
                    .slice(..)
                    .map_async(wgpu::MapMode::Read, move |r| {
                        state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
                    });
            }
        }
        self.ctx
            .device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| Error::DeviceLost {
                during: "polling the statistics ring".into(),
                message: e.to_string(),
            })?;
        let mut out = Vec::new();
        for slot in &self.ring {
            match slot.state.load(Ordering::Acquire) {
                MAPPED => {
                    let stats: IncrementStats = {
                        let view = slot.buffer.slice(..).get_mapped_range().map_err(|e| {
                            Error::DeviceLost {
                                during: "reading the statistics ring".into(),
                                message: e.to_string(),
                            }
                        })?;
                        bytemuck::pod_read_unaligned(&view[..STATS_BYTES as usize])
                    };
                    slot.buffer.unmap();
                    slot.state.store(FREE, Ordering::Release);
                    if let Ok(mut t) = self.ctx.traffic.lock() {
                        t.lagged_read_bytes += STATS_BYTES;
                    }
                    out.push(stats);
                }
                FAILED => {
                    slot.state.store(FREE, Ordering::Release);
                    return Err(Error::DeviceLost {
                        during: "mapping the statistics ring".into(),
                        message: "the map failed".into(),
                    });
                }
                _ => {}
            }
        }
        out.sort_by_key(|s| s.increment);
        Ok(out)
    }
}
