//! Central differences for point masses on the device (`shaders/integrate.wgsl`): the integrator
//! of a host program that keeps positions, velocities and forces in device buffers and runs
//! abut's device-resident contact increment before it in the same submit.

use std::sync::Arc;

use wgpu::BufferUsages as U;

use crate::abi::groups;
use crate::abi::integrate::IntegrateParams;
use crate::abi::passes::{self, Buf};
use crate::abi::search::ITEM_WORKGROUP;
use crate::device::{Device, GpuContext};
use crate::error::{Error, Result};

/// The central-difference integrator of a range of point masses on one GPU device.
pub struct CentralDifference {
    ctx: Arc<GpuContext>,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    masses: wgpu::Buffer,
    last: Option<IntegrateParams>,
    group: Option<([wgpu::Buffer; 3], wgpu::BindGroup)>,
    n_nodes: u32,
}

impl CentralDifference {
    /// An integrator on `device` (a GPU) for nodes with masses `masses` (one per model node;
    /// zero holds a node in place).
    pub fn new(device: &Device, masses: &[f64]) -> Result<Self> {
        let Some(ctx) = device.gpu_context() else {
            return Err(Error::BadParameter {
                name: "device",
                value: "CPU path".into(),
                expected: "a GPU device (the CPU path integrates with cpu::integrate)",
            });
        };
        if let Some((i, m)) = masses
            .iter()
            .enumerate()
            .find(|(_, m)| !(m.is_finite() && **m >= 0.0))
        {
            return Err(Error::BadParameter {
                name: "mass",
                value: format!("{m} (node {i})"),
                expected: "finite and non-negative",
            });
        }
        let d = &ctx.device;
        let pipeline = ctx.pipeline(&passes::INTEGRATE, &[]);
        let params = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("integrate params"),
            size: std::mem::size_of::<IntegrateParams>() as u64,
            usage: U::UNIFORM | U::COPY_DST,
            mapped_at_creation: false,
        });
        let m32: Vec<f32> = masses.iter().map(|&m| m as f32).collect();
        let masses_buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("integrate masses"),
            size: (m32.len() as u64 * 4).max(16).next_multiple_of(16),
            usage: U::STORAGE | U::COPY_DST,
            mapped_at_creation: false,
        });
        super::upload(ctx, &masses_buffer, 0, bytemuck::cast_slice(&m32));
        Ok(Self {
            ctx: ctx.clone(),
            pipeline: pipeline?,
            params,
            masses: masses_buffer,
            last: None,
            group: None,
            n_nodes: masses.len() as u32,
        })
    }

    /// Encodes one increment `dt` of the nodes `first..first + count` under body acceleration
    /// `acceleration` into `enc`: velocities and positions updated from the forces, every force
    /// zeroed. The buffers hold one `vec4<f32>` per model node (STORAGE usage). The parameters
    /// are uploaded only when they change.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        dt: f64,
        acceleration: [f64; 3],
        range: std::ops::Range<u32>,
    ) -> Result<()> {
        if range.end > self.n_nodes || range.start > range.end {
            return Err(Error::IndexOutOfRange {
                what: "integrated node range".into(),
                index: range.end as u64,
                len: self.n_nodes as usize,
            });
        }
        let ip = IntegrateParams {
            acceleration: [
                acceleration[0] as f32,
                acceleration[1] as f32,
                acceleration[2] as f32,
                dt as f32,
            ],
            first: range.start,
            count: range.end - range.start,
            n_nodes: self.n_nodes,
            _pad: 0,
        };
        if self.last != Some(ip) {
            super::upload(&self.ctx, &self.params, 0, bytemuck::bytes_of(&ip));
            self.last = Some(ip);
        }
        let key = [positions.clone(), velocities.clone(), forces.clone()];
        if self.group.as_ref().is_none_or(|(k, _)| *k != key) {
            let group = super::bind(&self.ctx.device, &self.pipeline, &passes::INTEGRATE, |b| {
                Some(match b {
                    Buf::IntegrateParams => self.params.as_entire_binding(),
                    Buf::Positions => positions.as_entire_binding(),
                    Buf::Velocities => velocities.as_entire_binding(),
                    Buf::HostForces => forces.as_entire_binding(),
                    Buf::Masses => self.masses.as_entire_binding(),
                    _ => return None,
                })
            })?;
            self.group = Some((key, group));
        }
        let (_, group) = self.group.as_ref().expect("bound");
        super::run_pass(
            &self.ctx,
            enc,
            &groups::INTEGRATOR,
            &[(&self.pipeline, group, self.n_nodes, ITEM_WORKGROUP)],
            self.ctx.limits.max_compute_workgroups_per_dimension,
        );
        Ok(())
    }
}
