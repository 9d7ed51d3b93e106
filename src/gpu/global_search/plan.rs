//! A search alone on the GPU: its part of the device-resident plan (`plan::increment::search`)
//! recorded on an encoder of its own — on abut's positions buffer (host positions uploaded) or
//! the caller's — and the status words, the plan's head and (when asked) the hits read back in
//! one wait (`GlobalSearch::step`, `run` and `step_device`, kinematic pairs, point queries,
//! the anchoring search).

use super::*;
use crate::abi::search::PLAN_SLOTS;
use crate::plan::{PlanPositions, PlanRan};

/// Bytes of the plan's head read back: its words up to the dispatch slots.
const PLAN_HEAD_BYTES: u64 = (PLAN_SLOTS * 4) as u64;

impl GpuSearch {
    /// Runs the search's entries of one increment on `positions` (after `make_resident`),
    /// submits and reads back the status words, the plan's head and, with `read_hits`, the hits;
    /// `global`: the host knows the increment searches globally (no motion budget).
    pub(crate) fn run_plan(
        &mut self,
        positions: PlanPositions<'_>,
        read_hits: bool,
        global: bool,
    ) -> Result<PlanRan> {
        let mut shape = self
            .pair_shape(0, false)
            .ok_or_else(|| Error::BadParameter {
                name: "search",
                value: "not made resident".into(),
                expected: "make_resident first",
            })?;
        shape.global_only = global;
        let n_nodes = shape.n_nodes as u64;
        let (buffer, origin) = match positions {
            PlanPositions::Host(x) => {
                if x.len() as u64 != n_nodes {
                    return Err(Error::LengthMismatch {
                        what: "search positions (one per model node)",
                        expected: n_nodes as usize,
                        got: x.len(),
                    });
                }
                let b = self.host_positions_buffer(n_nodes);
                super::super::upload(&self.ctx, &b, 0, bytemuck::cast_slice(x));
                (b, [0.0; 3])
            }
            PlanPositions::Buffer(b, origin) => (b.clone(), origin),
        };
        // this run's origin, and the increments' own back after it (writes are ordered
        // with the submits between them)
        let own = self.resident.as_ref().map_or([0.0; 3], |r| r.frame_origin);
        let frame = |o: [f32; 3]| FrameParams {
            origin: [o[0], o[1], o[2], 0.0],
            n_nodes: n_nodes as u32,
            _pad: [0; 3],
        };
        let set_frame = |s: &Self, o| {
            super::super::upload(&s.ctx, &s.frame, 0, bytemuck::bytes_of(&frame(o)));
        };
        if origin != own {
            set_frame(self, origin);
        }
        self.prepare_resident(&buffer)?;
        let entries = crate::plan::increment::search(0, &shape);
        let ran = self.run_entries(&entries, shape.n_slaves, read_hits);
        if origin != own {
            set_frame(self, own);
        }
        ran
    }

    /// One global search of `prep` as it is (its params and its nodes, already in the frame):
    /// made resident on it and the host-sized global entries run (`plan::increment::
    /// prepared_global`), the hits read back. For tests of the kernels on inputs they prepared.
    #[doc(hidden)]
    pub fn run_prepared(&mut self, prep: &Prepared) -> Result<Arc<Vec<GpuHit>>> {
        self.make_resident(prep, 1, false, [0.0; 3])?;
        let unread = self.host_positions_buffer(prep.n_nodes as u64);
        self.prepare_resident(&unread)?;
        let entries = crate::plan::increment::prepared_global(&prep.params);
        Ok(self.run_entries(&entries, prep.params.n_slaves, true)?.hits)
    }

    /// abut's positions buffer for `n_nodes` nodes (made, or remade larger, when needed).
    fn host_positions_buffer(&mut self, n_nodes: u64) -> wgpu::Buffer {
        let need = (n_nodes * 16).max(16);
        if let Some(b) = self.host_positions.as_ref().filter(|b| b.size() >= need) {
            return b.clone();
        }
        let b = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("search positions"),
            size: need,
            usage: U::STORAGE | U::COPY_DST,
            mapped_at_creation: false,
        });
        self.host_positions = Some(b.clone());
        b
    }

    /// Records `entries` after the status reset, submits, and reads back the status words, the
    /// plan's head and (with `read_hits`) the hits of `n_slaves` slaves.
    fn run_entries(
        &mut self,
        entries: &[crate::plan::increment::Entry],
        n_slaves: u32,
        read_hits: bool,
    ) -> Result<PlanRan> {
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("search"),
            });
        self.resident_copies(&mut enc);
        let mut groups: Vec<crate::gpu::GroupWork<'_>> = Vec::new();
        for e in entries {
            let work = self.dispatch(e).ok_or_else(|| Error::Gpu {
                during: "recording a search".into(),
                message: format!("no dispatch for {}", e.kernel.pass().entry),
            })?;
            crate::gpu::push_grouped(&mut groups, e.group, work);
        }
        crate::gpu::record_groups(
            &self.ctx,
            &mut enc,
            "search",
            &groups,
            self.max_workgroups_per_dim,
        );
        drop(groups);
        let hits_bytes = if read_hits {
            n_slaves as u64 * std::mem::size_of::<GpuHit>() as u64
        } else {
            0
        };
        let total = STATUS_BYTES + PLAN_HEAD_BYTES + hits_bytes;
        let b = &mut self.buffers;
        b.readback
            .ensure(&self.ctx.device, &self.ctx.limits, total)?;
        let staging = &b.readback.buffer;
        enc.copy_buffer_to_buffer(&b.status.buffer, 0, staging, 0, STATUS_BYTES);
        enc.copy_buffer_to_buffer(&b.plan, 0, staging, STATUS_BYTES, PLAN_HEAD_BYTES);
        if hits_bytes > 0 {
            let at = STATUS_BYTES + PLAN_HEAD_BYTES;
            enc.copy_buffer_to_buffer(&b.hits.buffer, 0, staging, at, hits_bytes);
        }
        crate::device::submit(&self.ctx, enc);
        let mut hits = std::mem::take(&mut self.hits_cache);
        let (status, plan) =
            read_back_with(&self.ctx, staging, total, "search readback", |bytes| {
                let (status, rest) = bytes.split_at(STATUS_BYTES as usize);
                let (plan, raw) = rest.split_at(PLAN_HEAD_BYTES as usize);
                if read_hits {
                    let h = Arc::make_mut(&mut hits);
                    h.resize(
                        raw.len() / std::mem::size_of::<GpuHit>(),
                        bytemuck::Zeroable::zeroed(),
                    );
                    bytemuck::cast_slice_mut::<GpuHit, u8>(h).copy_from_slice(raw);
                }
                let status: [u32; STATUS_WORDS] = bytemuck::pod_read_unaligned(status);
                (status, bytemuck::pod_collect_to_vec::<u8, u32>(plan))
            })?;
        self.ctx.take_uncaptured("search")?;
        let hits = if read_hits {
            self.hits_cache = hits.clone();
            hits
        } else {
            self.hits_cache = hits;
            Arc::default()
        };
        Ok(PlanRan { status, plan, hits })
    }
}
