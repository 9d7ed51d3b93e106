//! The device-resident penalty increment: a host program keeps positions, velocities and forces
//! in its own device buffers, and abut records the whole increment — the schedule's choice, the
//! local or global search, normals, penalty, gather, the forces added into the caller's buffer
//! and the statistics — into the caller's command encoder. No readback and no wait per
//! increment; the statistics are on the device for the host's integrator, and come back to the
//! host a few increments late through a ring of staging buffers.
//!
//! `Contact` owns the increment: each pair's search plans and encodes its passes, then its
//! penalty passes, then the pair's statistics; one executor, chosen when the `Contact` was made
//! (GPU or CPU path), runs them all.

use super::exec::Increment;
use super::report::{fast_slaves, fill_output};
use super::{positive_dt, Contact, StepReport};
use crate::abi::penalty::{PenaltyParams, NO_LIMIT};
use crate::abi::search::plan_params;
use crate::abi::search::{
    PLAN_CROWDED, PLAN_FORCE, PLAN_SEARCHED, PLAN_SINCE_GLOBAL, PLAN_TRIGGER,
};
use crate::abi::stats::IncrementStats;
use crate::error::{Error, Result};
use crate::search::SearchStage;

mod host_arrays;
pub(crate) use host_arrays::HostSchedule;

/// The caller's arrays for one device-resident increment.
///
/// Layouts, on the device and on the host alike: one `vec4<f32>` (`[f32; 4]`) per model node,
/// in model node order. `positions`: model frame, w ignored. `velocities`: the velocities at
/// the half step before the increment (central differences), w ignored. `forces`: the contact
/// forces are *added* to xyz (zero them, or fill them with the other forces, before the
/// increment); w is left alone.
pub enum ResidentIo<'a> {
    /// On a GPU device: buffers on the `Contact`'s wgpu device with STORAGE usage (made there,
    /// or by the caller on a device it gave [`crate::Device::from_wgpu`]), and the encoder the
    /// increment is recorded into. Submit it before encoding the next increment's statistics
    /// collection ([`Contact::collect_stats`]).
    Gpu {
        /// The command encoder the passes are recorded into (nothing is submitted).
        encoder: &'a mut wgpu::CommandEncoder,
        /// Node positions.
        positions: &'a wgpu::Buffer,
        /// Node velocities.
        velocities: &'a wgpu::Buffer,
        /// Node forces, summed into.
        forces: &'a wgpu::Buffer,
    },
    /// On the CPU path: the same layouts as host arrays; the increment runs at once.
    Cpu {
        /// Node positions.
        positions: &'a [[f32; 4]],
        /// Node velocities.
        velocities: &'a [[f32; 4]],
        /// Node forces, summed into.
        forces: &'a mut [[f32; 4]],
    },
}

/// Which kind of increment a `Contact` runs (fixed by its first penalty increment).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    /// The caller's device buffers or f32 arrays (`encode_increment`).
    Device,
    /// Host f64 arrays (`penalty_step`), through the same plan on abut's own arrays.
    Host,
}

impl Contact {
    /// Readies every pair for device-resident increments (the first increment does this) at
    /// `positions`: the caller's f32 buffers in the model frame (`caller_frame`), or abut's own
    /// arrays, each pair's relative to its search's frame.
    fn make_resident(&mut self, positions: &[[f64; 3]], caller_frame: bool) -> Result<()> {
        if caller_frame && (!self.kinematic.is_empty() || !self.rigid.is_empty()) {
            return Err(Error::BadParameter {
                name: "device-resident increment",
                value: "a model with kinematic pairs".into(),
                expected: "penalty pairs only (kinematic pairs correct positions on the host: \
                           kinematic_step)",
            });
        }
        if self.pairs.is_empty() {
            return Err(Error::Empty {
                what: "the model's penalty pairs".into(),
            });
        }
        let mut damping = 0.0f32;
        for (k, pr) in self.pairs.iter_mut().enumerate() {
            pr.search
                .make_resident(self.exec.search(k), positions, caller_frame)?;
            damping = damping.max(pr.setup.params.damping);
        }
        self.exec.make_resident(damping)
    }

    /// Records one device-resident penalty increment of increment `dt` (seconds; the penalty
    /// parameters are uploaded only when it changes) into `io`: every pair's schedule, search,
    /// penalty and gather, the forces summed into the caller's force array and the increment's
    /// statistics into [`Contact::stats_buffer`]. On a GPU nothing is submitted, read back or
    /// waited for; on the CPU path the increment runs at once. The first call readies the pairs
    /// (pipelines, buffers sized for the model — not for positions — and the frame and anchors
    /// from the model's positions). Penalty pairs only; a `Contact` that runs device-resident
    /// increments no longer runs host-array ones ([`Contact::penalty_step`]). The caller's
    /// positions are absolute f32: far from the origin they carry fewer digits of a gap (at
    /// 300 model sizes, about 10⁻⁵ of the size) — host arrays, subtracted in f64, do not.
    /// Slaves moving farther than the search radius relative to the master near them are
    /// counted in the statistics ([`crate::IncrementStats::fast_nodes`]).
    pub fn encode_increment(&mut self, io: ResidentIo<'_>, dt: f64) -> Result<()> {
        self.begin_device_increment(dt)?;
        let params = self.pair_params(dt);
        let inc = Increment {
            pairs: &self.pairs,
            params: &params,
            local_only: &[],
        };
        self.exec.record(io, &inc)
    }

    /// The GPU against its CPU mirror, entry by entry: one device-resident increment (as
    /// [`Contact::encode_increment`], on abut's own encoder, submitted and waited for) whose
    /// first `first_gpu` entries — kernels of one pair, in the order the increment runs them —
    /// run on the CPU mirrors and the rest on this GPU, every buffer the increment writes
    /// (each pair's search, penalty and statistics arrays and the caller's forces) read back
    /// before and written back after. Returns how many entries the increment has (`first_gpu`
    /// at or beyond it runs all of them on the CPU). When the two executors disagree, the
    /// smallest split that reproduces the CPU's result names the first kernel that diverges.
    /// The caller's buffers need COPY_SRC (and COPY_DST for the forces). Errors on the CPU path,
    /// leaving the `Contact` as it was.
    pub fn run_split(
        &mut self,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        dt: f64,
        first_gpu: usize,
    ) -> Result<usize> {
        // refused before anything is made resident: the Contact stays as it was
        if self.exec.context().is_none() {
            return Err(super::exec::no_split_on_cpu());
        }
        self.begin_device_increment(dt)?;
        let mut twin =
            super::exec::cpu::CpuExec::twin(&self.pairs, self.n_nodes, &self.initial_positions)?;
        let params = self.pair_params(dt);
        let inc = Increment {
            pairs: &self.pairs,
            params: &params,
            local_only: &[],
        };
        self.exec
            .run_split(positions, velocities, forces, &inc, first_gpu, &mut twin)
    }

    /// The checks before a device-resident increment of `dt`; the first readies the pairs.
    fn begin_device_increment(&mut self, dt: f64) -> Result<()> {
        positive_dt(dt)?;
        if let Some(pr) = self
            .pairs
            .iter()
            .find(|pr| pr.setup.rigid.0.is_some() || pr.setup.rigid.1.is_some())
        {
            return Err(Error::BadParameter {
                name: "encode_increment",
                value: format!("pair {} on a rigid part", pr.id.0),
                expected: "host-array increments (penalty_step): a rigid part's position and rotation are read from the host's positions",
            });
        }
        match self.mode {
            None => {
                let x = self.initial_positions.clone();
                self.make_resident(&x, true)?;
                self.mode = Some(Mode::Device);
            }
            Some(Mode::Device) => {}
            Some(Mode::Host) => {
                return Err(Error::BadParameter {
                    name: "encode_increment",
                    value: "a Contact running host-array increments (penalty_step)".into(),
                    expected: "one kind of increment per Contact (make another for device buffers)",
                })
            }
        }
        Ok(())
    }

    /// Each pair's penalty parameters for an increment of `dt` (the first fixes the reference
    /// increment), with the rigid parts' states relative to the pair's frame.
    pub(super) fn pair_params(&mut self, dt: f64) -> Vec<PenaltyParams> {
        let dt_ref = *self.dt_ref.get_or_insert(dt);
        let rigid_states: Vec<crate::penalty::RigidState> =
            self.parts.iter().map(|p| p.state).collect();
        self.pairs
            .iter()
            .map(|pr| {
                let mut pp = pr.setup.params(dt, dt_ref);
                pr.setup
                    .set_rigid(&mut pp, &rigid_states, pr.search.resident_frame());
                pp
            })
            .collect()
    }

    /// Records and submits one device-resident increment with abut's own encoder (one submit,
    /// no wait): [`Contact::encode_increment`] for callers that do not batch it with their own
    /// passes. Errors on the CPU path (use `encode_increment` with [`ResidentIo::Cpu`]).
    pub fn submit_increment(
        &mut self,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        dt: f64,
    ) -> Result<()> {
        let Some(ctx) = self.exec.context() else {
            return Err(Error::BadParameter {
                name: "submit_increment",
                value: "CPU path".into(),
                expected: "a GPU device (on the CPU path: encode_increment with ResidentIo::Cpu)",
            });
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("device-resident increment"),
            });
        self.encode_increment(
            ResidentIo::Gpu {
                encoder: &mut encoder,
                positions,
                velocities,
                forces,
            },
            dt,
        )?;
        crate::device::submit(&ctx, encoder);
        Ok(())
    }

    /// The device buffer of the last device-resident increment's statistics
    /// ([`IncrementStats`], 76 bytes, STORAGE | COPY_SRC): a host integrator running on the
    /// device binds it to read `stable_dt` there. `None` on the CPU path and before the first
    /// increment.
    pub fn stats_buffer(&self) -> Option<&wgpu::Buffer> {
        self.exec.stats_buffer()
    }

    /// The statistics of the device-resident increments the device has finished since the last
    /// call, oldest first, without waiting: on a GPU, those whose staging buffers it has mapped
    /// (a few increments late; call this only after submitting what was encoded); on the CPU
    /// path, every increment since the last call. A non-finite coordinate is an error naming the
    /// node.
    pub fn collect_stats(&mut self) -> Result<Vec<IncrementStats>> {
        let out = self.exec.collect_stats()?;
        for s in &out {
            if s.nonfinite_node != u32::MAX {
                return Err(Error::BadParameter {
                    name: "device positions",
                    value: format!(
                        "a NaN or infinite coordinate at node {} (increment {})",
                        s.nonfinite_node, s.increment
                    ),
                    expected: "finite coordinates",
                });
            }
        }
        Ok(out)
    }

    /// Increments whose statistics found no free staging buffer of the ring, or (CPU path) the
    /// queue of uncollected ones full: the host fell more than the ring's eight increments behind
    /// ([`Contact::collect_stats`]); on a GPU their statistics were on the device all the same.
    pub fn dropped_stats(&self) -> u64 {
        self.exec.dropped_stats()
    }

    /// Each pass's hits of the last penalty increment, in the pass's slave order: on the CPU
    /// path at once, on a GPU read back and waited for (tests; not in a browser).
    pub(crate) fn pass_hits(&self) -> Result<Vec<Vec<crate::abi::search::GpuHit>>> {
        (0..self.pairs.len())
            .map(|k| self.exec.last_hits(k, self.pairs[k].search.slaves().len()))
            .collect()
    }

    /// Each pass's device buffer of hits with the bytes its slaves' hits take (64 per slave);
    /// empty on the CPU path (tests copy them aside after each increment).
    pub(crate) fn pass_hits_buffers(&self) -> Vec<(&wgpu::Buffer, u64)> {
        (0..self.pairs.len())
            .filter_map(|k| {
                let bytes = self.pairs[k].search.slaves().len() as u64 * 64;
                self.exec.hits_buffer(k).map(|b| (b, bytes))
            })
            .collect()
    }

    /// Asks the next penalty increment (device-resident or host-array) of every pair to search
    /// globally (a 4-byte upload per pair on a GPU).
    pub fn request_global_search(&mut self) {
        for (k, pr) in self.pairs.iter_mut().enumerate() {
            pr.schedule.forced = true;
            self.exec.request_global(k);
        }
    }
}
