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

use super::report::{fast_slaves, fill_output};
use super::{positive_dt, Contact, PenaltyExec, StepReport};
use crate::abi::penalty::{ContactOut, NO_LIMIT};
use crate::abi::search::plan_params;
use crate::abi::search::{
    GpuHit, PLAN_CROWDED, PLAN_FORCE, PLAN_SEARCHED, PLAN_SINCE_GLOBAL, PLAN_SLOTS, PLAN_TRIGGER,
};
use crate::abi::stats::{IncrementStats, STATS_BYTES, STATS_RESET_WORDS, STATS_WORDS};
use crate::abi::status::STATUS_WORDS;
use crate::cpu::{gather, stats};
use crate::error::{Error, Result};
use crate::gpu::{GpuIncrement, STATS_RING};
use crate::search::GlobalSearch;

mod host_arrays;
pub(crate) use host_arrays::{HostArrays, HostSchedule};

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

/// What a `Contact` keeps for its device-resident increments.
pub(crate) enum Resident {
    Gpu(Box<GpuIncrement>),
    Cpu {
        /// The node-wise bound's rows per model node.
        rows: Vec<f32>,
        /// The statistics words (`IncrementStats`).
        stats: [u32; STATS_WORDS],
        /// Statistics not yet collected (at most `STATS_RING`, as on a GPU).
        queue: Vec<IncrementStats>,
        /// Increments whose statistics found the queue full.
        dropped: u64,
    },
}

/// Which kind of increment a `Contact` runs (fixed by its first penalty increment).
pub(crate) enum Mode {
    /// The caller's device buffers or f32 arrays (`encode_increment`).
    Device,
    /// Host f64 arrays (`penalty_step`), through the same plan on abut's own buffers.
    Host(Box<HostArrays>),
}

/// Positions of each pair's search, when they differ (host arrays: each relative to its own
/// frame); otherwise the increment's one positions array serves every pair.
#[derive(Clone, Copy)]
enum PairPositions<'a> {
    Shared,
    Gpu(&'a [wgpu::Buffer]),
    Cpu(&'a [Vec<[f32; 4]>]),
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
        let mut damping = 0.0f32;
        for pr in &mut self.pairs {
            pr.search.make_resident(positions, caller_frame)?;
            damping = damping.max(pr.setup.params.damping);
        }
        let resident = match self.pairs.first_mut().map(|p| &mut p.exec) {
            Some(PenaltyExec::Gpu(p0)) => {
                let ctx = p0.context();
                let mut parts = Vec::new();
                for pr in &mut self.pairs {
                    let n = pr.setup.pair_nodes.len() as u32;
                    let g = pr.search.gpu_mut().ok_or_else(mixed)?;
                    let (status, plan, _) = g.resident_outputs();
                    let PenaltyExec::Gpu(p) = &pr.exec else {
                        return Err(mixed());
                    };
                    parts.push((
                        status.clone(),
                        plan.clone(),
                        p.pair_nodes_buffer().clone(),
                        n,
                    ));
                }
                let refs: Vec<_> = parts.iter().map(|(s, p, n, c)| (s, p, n, *c)).collect();
                Resident::Gpu(Box::new(GpuIncrement::new(
                    ctx,
                    self.n_nodes,
                    damping,
                    &refs,
                )?))
            }
            Some(PenaltyExec::Cpu(_)) => {
                let first = crate::abi::stats::first_image(damping);
                Resident::Cpu {
                    rows: vec![0.0; self.n_nodes],
                    stats: first,
                    queue: Vec::new(),
                    dropped: 0,
                }
            }
            None => {
                return Err(Error::Empty {
                    what: "the model's penalty pairs".into(),
                })
            }
        };
        self.resident = Some(resident);
        Ok(())
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
            Some(Mode::Host(_)) => {
                return Err(Error::BadParameter {
                    name: "encode_increment",
                    value: "a Contact running host-array increments (penalty_step)".into(),
                    expected: "one kind of increment per Contact (make another for device buffers)",
                })
            }
        }
        self.record(io, PairPositions::Shared, &[], dt, true)
    }

    /// Records (GPU) or runs (CPU path) one increment through the plan; `pair_x` overrides the
    /// positions per pair; `ring`: copy the statistics into the lagged ring.
    fn record(
        &mut self,
        io: ResidentIo<'_>,
        pair_x: PairPositions<'_>,
        local_only: &[bool],
        dt: f64,
        ring: bool,
    ) -> Result<()> {
        let dt_ref = *self.dt_ref.get_or_insert(dt);
        let n_nodes = self.n_nodes;
        let rigid_states: Vec<crate::penalty::RigidState> =
            self.parts.iter().map(|p| p.state).collect();
        match (io, self.resident.as_mut()) {
            (
                ResidentIo::Gpu {
                    encoder,
                    positions,
                    velocities,
                    forces,
                },
                Some(Resident::Gpu(inc)),
            ) => {
                for (what, b) in [("device velocities", velocities), ("device forces", forces)] {
                    if b.size() < n_nodes as u64 * 16
                        || !b.usage().contains(wgpu::BufferUsages::STORAGE)
                    {
                        return Err(Error::BadParameter {
                            name: what,
                            value: format!("buffer of {} bytes, usage {:?}", b.size(), b.usage()),
                            expected: "one vec4<f32> per model node and STORAGE usage",
                        });
                    }
                }
                inc.begin(encoder);
                let mut max_dim = u32::MAX;
                // what may allocate or upload first: bind groups on the caller's buffers, params
                for (k, pr) in self.pairs.iter_mut().enumerate() {
                    let mut pp = pr.setup.params(dt, dt_ref);
                    pr.setup
                        .set_rigid(&mut pp, &rigid_states, pr.search.resident_frame());
                    let g = pr.search.gpu_mut().ok_or_else(mixed)?;
                    g.prepare_resident(match pair_x {
                        PairPositions::Gpu(b) => &b[k],
                        _ => positions,
                    })?;
                    max_dim = max_dim.min(g.max_workgroups_per_dim());
                    let (shared, generation) = g.shared_buffers();
                    let PenaltyExec::Gpu(p) = &mut pr.exec else {
                        return Err(mixed());
                    };
                    p.prepare_resident(&shared, generation, &pp, velocities, forces, inc.rows())?;
                }
                // then the copies (resets) and one compute pass for every pair's dispatches
                let mut groups = Vec::new();
                for (k, pr) in self.pairs.iter().enumerate() {
                    let g = pr.search.gpu().ok_or_else(mixed)?;
                    let PenaltyExec::Gpu(p) = &pr.exec else {
                        return Err(mixed());
                    };
                    g.resident_copies(encoder);
                    groups
                        .extend(g.resident_dispatches(local_only.get(k).copied().unwrap_or(false)));
                    groups.extend(p.resident_dispatches());
                    groups.push(inc.pair_dispatch(k));
                }
                groups.push(inc.finish_dispatch());
                crate::gpu::record_groups(
                    inc.context(),
                    encoder,
                    "device-resident increment",
                    &groups,
                    max_dim,
                );
                drop(groups);
                if ring {
                    inc.end(encoder);
                }
                inc.take_uncaptured()
            }
            (
                ResidentIo::Cpu {
                    positions,
                    velocities,
                    forces,
                },
                Some(Resident::Cpu {
                    rows,
                    stats: words,
                    queue,
                    dropped,
                }),
            ) => {
                for (what, len) in [
                    (
                        "device positions (one vec4 per model node)",
                        positions.len(),
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
                rows.iter_mut().for_each(|r| *r = 0.0);
                words[..STATS_RESET_WORDS].copy_from_slice(&crate::abi::stats::reset_image());
                for (k, pr) in self.pairs.iter_mut().enumerate() {
                    let mut pp = pr.setup.params(dt, dt_ref);
                    pr.setup
                        .set_rigid(&mut pp, &rigid_states, pr.search.resident_frame());
                    let c = pr.search.cpu_mut().ok_or_else(mixed)?;
                    let (mut status, prep, hits) = c.step_resident(match pair_x {
                        PairPositions::Cpu(x) => &x[k],
                        _ => positions,
                    })?;
                    let PenaltyExec::Cpu(p) = &mut pr.exec else {
                        return Err(mixed());
                    };
                    p.run(&pr.setup, &pp, prep, velocities, hits, &mut status);
                    gather::add_forces(&pp, &pr.setup.pair_nodes, &p.forces, forces, rows);
                    let plan = c.resident_plan_mut().ok_or_else(mixed)?;
                    stats::pair_stats(&status, plan, words);
                }
                for pr in &self.pairs {
                    stats::bound_max(&pr.setup.pair_nodes, rows, words);
                }
                stats::finish_stats(words);
                if ring {
                    if queue.len() < STATS_RING {
                        queue.push(bytemuck::cast(*words));
                    } else {
                        *dropped += 1;
                    }
                }
                Ok(())
            }
            _ => Err(Error::BadParameter {
                name: "device-resident increment",
                value: "GPU buffers on the CPU path, or host arrays on a GPU device".into(),
                expected: "ResidentIo::Gpu on a GPU device, ResidentIo::Cpu on the CPU path",
            }),
        }
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
        let ctx = match self.pairs.first().map(|p| &p.exec) {
            Some(PenaltyExec::Gpu(p)) => p.context(),
            _ => return Err(mixed()),
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
    /// ([`IncrementStats`], 72 bytes, STORAGE | COPY_SRC): a host integrator running on the
    /// device binds it to read `stable_dt` there. `None` on the CPU path and before the first
    /// increment.
    pub fn stats_buffer(&self) -> Option<&wgpu::Buffer> {
        match &self.resident {
            Some(Resident::Gpu(inc)) => Some(inc.stats()),
            _ => None,
        }
    }

    /// The statistics of the device-resident increments the device has finished since the last
    /// call, oldest first, without waiting: on a GPU, those whose staging buffers it has mapped
    /// (a few increments late; call this only after submitting what was encoded); on the CPU
    /// path, every increment since the last call. A non-finite coordinate is an error naming the
    /// node.
    pub fn collect_stats(&mut self) -> Result<Vec<IncrementStats>> {
        let out = match self.resident.as_mut() {
            Some(Resident::Gpu(inc)) => inc.collect()?,
            Some(Resident::Cpu { queue, .. }) => std::mem::take(queue),
            None => Vec::new(),
        };
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
    /// queue of uncollected ones full: the host fell more than [`STATS_RING`] increments behind
    /// ([`Contact::collect_stats`]); on a GPU their statistics were on the device all the same.
    pub fn dropped_stats(&self) -> u64 {
        match &self.resident {
            Some(Resident::Gpu(inc)) => inc.dropped,
            Some(Resident::Cpu { dropped, .. }) => *dropped,
            _ => 0,
        }
    }

    /// Asks the next penalty increment (device-resident or host-array) of every pair to search
    /// globally (a 4-byte upload per pair on a GPU).
    pub fn request_global_search(&mut self) {
        for pr in &mut self.pairs {
            pr.schedule.forced = true;
            if let Some(g) = pr.search.gpu_mut() {
                g.request_global();
            } else if let Some(c) = pr.search.cpu_mut() {
                c.request_global();
            }
        }
    }
}

fn mixed() -> Error {
    Error::Gpu {
        during: "device-resident increment".into(),
        message: "the pairs' executors run on different devices".into(),
    }
}
