//! The GPU executor of the penalty passes of one pair, run after the search in the same
//! command encoder: nodal_normals, penalty and gather (scatter_forces, gather).

use std::sync::Arc;

use super::buffers::GrowBuffer;
use super::global_search::SharedBuffers;
use crate::abi::passes::{self, Buf};
use crate::abi::penalty::ACC_WORDS_PER_NODE;
use crate::abi::penalty::{PenaltyParams, SlaveState};
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::penalty::PenaltySetup;
use crate::plan::increment::{Entry, Kernel};
use wgpu::BufferUsages as U;

struct Pipelines {
    nodal_normals: wgpu::ComputePipeline,
    need_normals: wgpu::ComputePipeline,
    nodal_normals_needed: wgpu::ComputePipeline,
    penalty: wgpu::ComputePipeline,
    penalty_active: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    scatter_active: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    gather_active: wgpu::ComputePipeline,
    add_forces: wgpu::ComputePipeline,
    add_forces_active: wgpu::ComputePipeline,
}

struct Groups {
    nodal_normals: wgpu::BindGroup,
    need_normals: wgpu::BindGroup,
    nodal_normals_needed: wgpu::BindGroup,
    penalty: wgpu::BindGroup,
    penalty_active: wgpu::BindGroup,
    scatter: wgpu::BindGroup,
    scatter_active: wgpu::BindGroup,
    gather: wgpu::BindGroup,
    gather_active: wgpu::BindGroup,
}

/// Penalty passes of one pair on one GPU device; buffers persist (friction state) and grow.
pub struct GpuPenalty {
    ctx: Arc<GpuContext>,
    pipelines: Pipelines,
    params: wgpu::Buffer,
    normals: GrowBuffer,
    pair_nodes: wgpu::Buffer,
    adjacency: wgpu::Buffer,
    state: wgpu::Buffer,
    out: wgpu::Buffer,
    facet_nodes: wgpu::Buffer,
    acc: wgpu::Buffer,
    forces: wgpu::Buffer,
    /// The need bits per pair node and rigid slot (`NEED_*`), zero between increments.
    need: wgpu::Buffer,
    n_slaves: u32,
    /// Device-resident increments: the bind groups on the caller's buffers, keyed by the
    /// search's generation and the (velocities, forces, rows) buffers.
    resident: Option<ResidentGroups>,
    /// The parameters last uploaded for device-resident increments.
    resident_params: Option<PenaltyParams>,
}

/// The bind groups of a pair's device-resident increments.
struct ResidentGroups {
    key: (u64, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer),
    groups: Groups,
    /// add_forces and add_forces_active (they bind the caller's forces).
    add_forces: [wgpu::BindGroup; 2],
    /// The search's plan: the indirect sizes of the passes over every slave or the active ones.
    plan: wgpu::Buffer,
}

fn storage(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).next_multiple_of(16),
        usage: U::STORAGE | U::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

impl GpuPenalty {
    /// The per-slave state (carried friction force, tributary area, history), read back.
    pub fn read_state(&self) -> Result<Vec<SlaveState>> {
        let bytes = self.n_slaves as u64 * 32;
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("slave state readback"),
            size: bytes,
            usage: U::MAP_READ | U::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        enc.copy_buffer_to_buffer(&self.state, 0, &staging, 0, bytes);
        crate::device::submit(&self.ctx, enc);
        super::buffers::read_back_with(
            &self.ctx,
            &staging,
            bytes,
            "reading the penalty slave state",
            bytemuck::pod_collect_to_vec::<u8, SlaveState>,
        )
    }

    /// Replaces the per-slave state (`state.len()` must be the slave count).
    pub fn write_state(&self, state: &[SlaveState]) {
        super::upload(&self.ctx, &self.state, 0, bytemuck::cast_slice(state));
    }

    /// Takes the penalty pipelines from the device's cache (friction compiled in or out, each
    /// variant once per device) and creates the pair's buffers.
    pub fn new(ctx: Arc<GpuContext>, setup: &PenaltySetup, n_nodes: usize) -> Result<Self> {
        let d = &ctx.device;
        let limits = &ctx.limits;
        let friction = [("FRICTION", if setup.friction { 1.0 } else { 0.0 })];
        let pipelines = Pipelines {
            nodal_normals: ctx.pipeline(&passes::NODAL_NORMALS, &[])?,
            need_normals: ctx.pipeline(&passes::NEED_NORMALS, &[])?,
            nodal_normals_needed: ctx.pipeline(&passes::NODAL_NORMALS_NEEDED, &[])?,
            penalty: ctx.pipeline(&passes::PENALTY, &friction)?,
            penalty_active: ctx.pipeline(&passes::PENALTY_ACTIVE, &friction)?,
            scatter: ctx.pipeline(&passes::SCATTER_FORCES, &[])?,
            scatter_active: ctx.pipeline(&passes::SCATTER_FORCES_ACTIVE, &[])?,
            gather: ctx.pipeline(&passes::GATHER, &[])?,
            gather_active: ctx.pipeline(&passes::GATHER_ACTIVE, &[])?,
            add_forces: ctx.pipeline(&passes::ADD_FORCES, &[])?,
            add_forces_active: ctx.pipeline(&passes::ADD_FORCES_ACTIVE, &[])?,
        };
        let n_slaves = setup.areas.len() as u32;
        let n_pair_nodes = setup.pair_nodes.len() as u32;
        let check = |what: &str, bytes: u64| -> Result<u64> {
            let allowed = limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size);
            if bytes > allowed {
                return Err(Error::TooLarge {
                    what: format!("GPU buffer '{what}'"),
                    needed: bytes,
                    allowed,
                });
            }
            Ok(bytes)
        };
        let out_bytes = check("contact outputs", n_slaves as u64 * 64)?;
        let pair_nodes = storage(
            d,
            "pair nodes",
            check("pair nodes", n_pair_nodes as u64 * 16)?,
            U::empty(),
        );
        super::upload(
            &ctx,
            &pair_nodes,
            0,
            bytemuck::cast_slice(&setup.pair_nodes),
        );
        let adjacency = storage(
            d,
            "adjacency",
            check("adjacency", setup.adjacency.len() as u64 * 4)?,
            U::empty(),
        );
        super::upload(&ctx, &adjacency, 0, bytemuck::cast_slice(&setup.adjacency));
        // COPY_SRC: read back to carry it into another Contact (`Contact::penalty_states`)
        let state = storage(d, "slave state", n_slaves as u64 * 32, U::COPY_SRC);
        super::upload(
            &ctx,
            &state,
            0,
            bytemuck::cast_slice(&setup.initial_state()),
        );
        let facet_nodes = storage(
            d,
            "facet pair nodes",
            check("facet pair nodes", setup.facet_nodes.len() as u64 * 16)?,
            U::empty(),
        );
        super::upload(
            &ctx,
            &facet_nodes,
            0,
            bytemuck::cast_slice(&setup.facet_nodes),
        );
        let acc_bytes = check(
            "fixed-point force sums",
            n_pair_nodes as u64 * (4 * ACC_WORDS_PER_NODE) as u64,
        )?;
        Ok(Self {
            params: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("penalty params"),
                size: std::mem::size_of::<PenaltyParams>() as u64,
                usage: U::UNIFORM | U::COPY_DST,
                mapped_at_creation: false,
            }),
            normals: GrowBuffer::new(
                d,
                "nodal normals",
                n_nodes as u64 * 16,
                U::STORAGE | U::COPY_DST | U::COPY_SRC,
            ),
            pair_nodes,
            adjacency,
            state,
            out: storage(d, "contact outputs", out_bytes, U::COPY_SRC),
            facet_nodes,
            acc: storage(d, "fixed-point force sums", acc_bytes, U::COPY_SRC),
            forces: storage(d, "pair forces", n_pair_nodes as u64 * 16, U::COPY_SRC),
            // zeroed at creation (wgpu), cleared by add_forces after each increment
            need: storage(d, "need bits", n_pair_nodes as u64 * 4, U::COPY_SRC),
            pipelines,
            n_slaves,
            resident: None,
            resident_params: None,
            ctx,
        })
    }

    /// The per-slave results (`ContactOut`), for the output variables.
    pub(crate) fn out_buffer(&self) -> &wgpu::Buffer {
        &self.out
    }

    /// Readies the penalty part of a device-resident increment after its search (`search`,
    /// whose bind groups are at `generation`): `params` uploaded when they change, the bind groups
    /// on the caller's `velocities` (`vec4<f32>` per model node, the half step before) and
    /// `forces` (`vec4<f32>` per model node, xyz summed into), on `rows` and on the increment's
    /// `stats` (add_forces raises the largest row there) built once per set of buffers.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn prepare_resident(
        &mut self,
        search: &SharedBuffers<'_>,
        generation: u64,
        params: &PenaltyParams,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        rows: &wgpu::Buffer,
        stats: &wgpu::Buffer,
    ) -> Result<()> {
        if self.resident_params.as_ref() != Some(params) {
            super::upload(&self.ctx, &self.params, 0, bytemuck::bytes_of(params));
            self.resident_params = Some(*params);
        }
        let key = (
            generation,
            velocities.clone(),
            forces.clone(),
            rows.clone(),
            stats.clone(),
        );
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            let scope = self
                .ctx
                .device
                .push_error_scope(wgpu::ErrorFilter::Validation);
            let made = self.build_resident_groups(search, velocities, forces, rows, stats);
            if let Some(e) = self.ctx.scope_error(scope) {
                return Err(Error::Gpu {
                    during: "binding the caller's buffers".into(),
                    message: e.to_string(),
                });
            }
            let (groups, add_forces) = made?;
            self.resident = Some(ResidentGroups {
                key,
                groups,
                add_forces,
                plan: search.plan.clone(),
            });
        }
        Ok(())
    }

    /// The buffer of role `buf` that the penalty passes write (`None` otherwise): what a split
    /// increment hands over.
    pub(crate) fn role_buffer(&self, buf: Buf) -> Option<&wgpu::Buffer> {
        Some(match buf {
            Buf::Normals => &self.normals.buffer,
            Buf::State => &self.state,
            Buf::Out => &self.out,
            Buf::Acc => &self.acc,
            Buf::Forces => &self.forces,
            Buf::Need => &self.need,
            _ => return None,
        })
    }

    /// The dispatch of entry `e` if it is a penalty kernel (after `prepare_resident`): normals,
    /// penalty, the fixed-point gather, and each pair node's force added into the caller's buffer
    /// and its bound row into the rows.
    pub(crate) fn dispatch(&self, e: &Entry) -> Option<super::Dispatch<'_>> {
        let r = self.resident.as_ref()?;
        let (g, p) = (&r.groups, &self.pipelines);
        let (pipe, group) = match e.kernel {
            Kernel::NodalNormals => (&p.nodal_normals, &g.nodal_normals),
            Kernel::NeedNormals => (&p.need_normals, &g.need_normals),
            Kernel::NodalNormalsNeeded => (&p.nodal_normals_needed, &g.nodal_normals_needed),
            Kernel::Penalty => (&p.penalty, &g.penalty),
            Kernel::PenaltyActive => (&p.penalty_active, &g.penalty_active),
            Kernel::ScatterForces => (&p.scatter, &g.scatter),
            Kernel::ScatterForcesActive => (&p.scatter_active, &g.scatter_active),
            Kernel::Gather => (&p.gather, &g.gather),
            Kernel::GatherActive => (&p.gather_active, &g.gather_active),
            Kernel::AddForces => (&p.add_forces, &r.add_forces[0]),
            Kernel::AddForcesActive => (&p.add_forces_active, &r.add_forces[1]),
            _ => return None,
        };
        match e.size {
            // the search's slot: every slave after a global search, the active ones after a
            // local one, zero workgroups otherwise
            crate::plan::increment::Size::Slot(offset) => {
                Some(super::Dispatch::Indirect(pipe, group, &r.plan, offset))
            }
            size => super::direct_dispatch(pipe, group, size),
        }
    }

    fn build_resident_groups(
        &self,
        s: &SharedBuffers<'_>,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        rows: &wgpu::Buffer,
        stats: &wgpu::Buffer,
    ) -> Result<(Groups, [wgpu::BindGroup; 2])> {
        let groups = self.groups_with(s, velocities)?;
        let add = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
            super::bind(&self.ctx.device, pipe, pass, |buf| {
                Some(match buf {
                    Buf::PenaltyParams => self.params.as_entire_binding(),
                    Buf::PairNodes => self.pair_nodes.as_entire_binding(),
                    Buf::Hits => s.hits.as_entire_binding(),
                    Buf::Status => s.status.as_entire_binding(),
                    Buf::Forces => self.forces.as_entire_binding(),
                    Buf::HostForces => forces.as_entire_binding(),
                    Buf::Rows => rows.as_entire_binding(),
                    Buf::Stats => stats.as_entire_binding(),
                    Buf::Need => self.need.as_entire_binding(),
                    _ => return None,
                })
            })
        };
        let p = &self.pipelines;
        let add_forces = [
            add(&p.add_forces, &passes::ADD_FORCES)?,
            add(&p.add_forces_active, &passes::ADD_FORCES_ACTIVE)?,
        ];
        Ok((groups, add_forces))
    }

    /// The bind groups of the slave and pair-node passes, velocities from the caller's
    /// `velocities`.
    fn groups_with(&self, s: &SharedBuffers<'_>, velocities: &wgpu::Buffer) -> Result<Groups> {
        let d = &self.ctx.device;
        let p = &self.pipelines;
        // the buffer of each role: the pair's own, or the search's shared ones
        let resource = |buf: Buf| {
            Some(match buf {
                Buf::PenaltyParams => self.params.as_entire_binding(),
                Buf::Nodes => s.nodes.as_entire_binding(),
                Buf::Facets => s.facets.as_entire_binding(),
                Buf::Hits => s.hits.as_entire_binding(),
                Buf::Status => s.status.as_entire_binding(),
                Buf::Velocities => velocities.as_entire_binding(),
                Buf::Normals => self.normals.buffer.as_entire_binding(),
                Buf::PairNodes => self.pair_nodes.as_entire_binding(),
                Buf::PairAdjacency => self.adjacency.as_entire_binding(),
                Buf::FacetNodes => self.facet_nodes.as_entire_binding(),
                Buf::State => self.state.as_entire_binding(),
                Buf::Out => self.out.as_entire_binding(),
                Buf::Acc => self.acc.as_entire_binding(),
                Buf::Forces => self.forces.as_entire_binding(),
                Buf::Need => self.need.as_entire_binding(),
                _ => return None,
            })
        };
        let group = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
            super::bind(d, pipe, pass, resource)
        };
        Ok(Groups {
            nodal_normals: group(&p.nodal_normals, &passes::NODAL_NORMALS)?,
            need_normals: group(&p.need_normals, &passes::NEED_NORMALS)?,
            nodal_normals_needed: group(&p.nodal_normals_needed, &passes::NODAL_NORMALS_NEEDED)?,
            penalty: group(&p.penalty, &passes::PENALTY)?,
            penalty_active: group(&p.penalty_active, &passes::PENALTY_ACTIVE)?,
            scatter: group(&p.scatter, &passes::SCATTER_FORCES)?,
            scatter_active: group(&p.scatter_active, &passes::SCATTER_FORCES_ACTIVE)?,
            gather: group(&p.gather, &passes::GATHER)?,
            gather_active: group(&p.gather_active, &passes::GATHER_ACTIVE)?,
        })
    }
}
