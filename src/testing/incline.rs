//! The web page's scene run (`web/`): the beads-on-an-incline scene of [`crate::testing::scenes`],
//! advanced increment by increment on the CPU path or device-resident on a GPU — the same
//! sequence of calls either way, so the page (WebGPU), its native twin (`examples/page_scene`)
//! and the tests compare like with like.

use crate::abi::integrate::IntegrateParams;
use crate::error::Result;
use crate::{CentralDifference, Contact, Device, ResidentIo};

use super::scenes::{node_buffers, Incline};

/// The starting state of every node, `vec4<f32>` each: positions (rounded to f32) and
/// velocities (zero).
fn start(scene: &Incline) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let x = scene
        .model
        .positions()
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect::<Vec<_>>();
    let v = vec![[0.0f32; 4]; x.len()];
    (x, v)
}

/// The scene on the CPU path: host arrays, one increment at a time.
pub struct InclineCpu {
    contact: Contact,
    params: IntegrateParams,
    masses: Vec<f32>,
    /// Node positions (m), `vec4<f32>` per node.
    pub positions: Vec<[f32; 4]>,
    /// Node velocities at the last half step (m/s).
    pub velocities: Vec<[f32; 4]>,
    forces: Vec<[f32; 4]>,
    /// The contact forces of the last increment (N), before the integrator zeroed them.
    pub last_forces: Vec<[f32; 4]>,
}

impl InclineCpu {
    /// Readies `scene` on the CPU path.
    pub fn new(scene: &Incline) -> Result<Self> {
        let (positions, velocities) = start(scene);
        let n = positions.len();
        let g = scene.gravity;
        Ok(Self {
            contact: Contact::new(&Device::cpu(), &scene.model)?,
            params: IntegrateParams {
                acceleration: [g[0] as f32, g[1] as f32, g[2] as f32, scene.dt as f32],
                first: scene.beads.start,
                count: scene.beads.end - scene.beads.start,
                n_nodes: n as u32,
                _pad: 0,
            },
            masses: scene.model.masses().iter().map(|&m| m as f32).collect(),
            positions,
            velocities,
            forces: vec![[0.0; 4]; n],
            last_forces: vec![[0.0; 4]; n],
        })
    }

    /// Runs `increments` increments of `dt` (s): contact, then the central-difference update.
    pub fn advance(&mut self, increments: usize, dt: f64) -> Result<()> {
        for _ in 0..increments {
            let io = ResidentIo::Cpu {
                positions: &self.positions,
                velocities: &self.velocities,
                forces: &mut self.forces,
            };
            self.contact.encode_increment(io, dt)?;
            self.last_forces.copy_from_slice(&self.forces);
            crate::cpu::integrate::integrate(
                &self.params,
                &mut self.positions,
                &mut self.velocities,
                &mut self.forces,
                &self.masses,
            );
        }
        self.contact.collect_stats()?;
        Ok(())
    }
}

/// The scene device-resident on a GPU: positions, velocities and forces in device buffers,
/// each increment recorded into the caller's encoder, nothing read back.
pub struct InclineGpu {
    contact: Contact,
    integrator: CentralDifference,
    gravity: [f64; 3],
    beads: std::ops::Range<u32>,
    /// Node positions (`vec4<f32>` per node; STORAGE, COPY_SRC).
    pub positions: wgpu::Buffer,
    /// Node velocities.
    pub velocities: wgpu::Buffer,
    forces: wgpu::Buffer,
    /// The contact forces of the last increment recorded, copied before the integrator zeroes
    /// them (for drawing and reading).
    pub last_forces: wgpu::Buffer,
    /// Node count.
    pub n_nodes: usize,
}

impl InclineGpu {
    /// Readies `scene` on `device` (a GPU) and uploads its start.
    pub fn new(device: &Device, scene: &Incline) -> Result<Self> {
        let (x, v) = start(scene);
        let n = x.len();
        let [positions, velocities, forces] = node_buffers(device, n)?;
        let [last_forces, ..] = node_buffers(device, n)?;
        if let Some((_, q)) = device.wgpu() {
            q.write_buffer(&positions, 0, bytemuck::cast_slice(&x));
            q.write_buffer(&velocities, 0, bytemuck::cast_slice(&v));
        }
        Ok(Self {
            contact: Contact::new(device, &scene.model)?,
            integrator: CentralDifference::new(device, scene.model.masses())?,
            gravity: scene.gravity,
            beads: scene.beads.clone(),
            positions,
            velocities,
            forces,
            last_forces,
            n_nodes: n,
        })
    }

    /// Records `increments` increments of `dt` (s) into `enc`; the last one's contact forces
    /// are copied to [`Self::last_forces`].
    pub fn encode(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        increments: usize,
        dt: f64,
    ) -> Result<()> {
        for k in 0..increments {
            let io = ResidentIo::Gpu {
                encoder: enc,
                positions: &self.positions,
                velocities: &self.velocities,
                forces: &self.forces,
            };
            self.contact.encode_increment(io, dt)?;
            if k + 1 == increments {
                let bytes = (self.n_nodes * 16) as u64;
                enc.copy_buffer_to_buffer(&self.forces, 0, &self.last_forces, 0, bytes);
            }
            self.integrator.encode(
                enc,
                &self.positions,
                &self.velocities,
                &self.forces,
                dt,
                self.gravity,
                self.beads.clone(),
            )?;
        }
        Ok(())
    }

    /// The statistics the device has finished since the last call (checks for non-finite
    /// coordinates; call after submitting).
    pub fn collect(&mut self) -> Result<()> {
        self.contact.collect_stats().map(|_| ())
    }
}

/// The numbers the page and its native twin compare at the end: beads still on the plate
/// (0 ≤ x ≤ 2 m, z > −1 cm), the beads' mean position (m), the total normal contact force
/// of the last increment (N).
pub fn summary(scene: &Incline, positions: &[[f32; 4]], forces: &[[f32; 4]]) -> [f64; 5] {
    let beads = scene.beads.start as usize..scene.beads.end as usize;
    let count = beads.len().max(1) as f64;
    let mut on = 0.0;
    let mut mean = [0.0f64; 3];
    let mut normal = 0.0;
    for i in beads {
        let p = positions[i];
        if (0.0..=2.0).contains(&p[0]) && p[2] > -0.01 {
            on += 1.0;
        }
        for a in 0..3 {
            mean[a] += p[a] as f64 / count;
        }
        normal += forces[i][2] as f64;
    }
    [on, mean[0], mean[1], mean[2], normal]
}
