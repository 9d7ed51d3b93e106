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

use super::{positive_dt, Contact, PenaltyExec};
use crate::cpu::{gather, stats};
use crate::error::{Error, Result};
use crate::gpu::GpuIncrement;
use crate::search::layout::{IncrementStats, STATS_RESET_WORDS};

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
        stats: [u32; 16],
        /// Statistics not yet collected.
        queue: Vec<IncrementStats>,
    },
}

impl Contact {
    /// Readies every pair for device-resident increments (the first increment does this).
    fn make_resident(&mut self) -> Result<()> {
        if !self.kinematic.is_empty() || !self.rigid.is_empty() {
            return Err(Error::BadParameter {
                name: "device-resident increment",
                value: "a model with kinematic pairs".into(),
                expected: "penalty pairs only (kinematic pairs correct positions on the host: \
                           kinematic_step)",
            });
        }
        let mut damping = 0.0f32;
        for pr in &mut self.pairs {
            pr.search.make_resident(&self.initial_positions)?;
            damping = damping.max(pr.setup.params.damping);
        }
        let resident = match self.pairs.first_mut().map(|p| &mut p.exec) {
            Some(PenaltyExec::Gpu(p0)) => {
                let ctx = p0.context();
                let mut parts = Vec::new();
                for pr in &mut self.pairs {
                    let n = pr.setup.pair_nodes.len() as u32;
                    let g = pr.search.gpu_mut().ok_or_else(mixed)?;
                    let (status, plan) = g.status_and_plan();
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
                let mut first = [0u32; 16];
                first[..STATS_RESET_WORDS].copy_from_slice(&stats::reset_image());
                first[14] = damping.to_bits();
                Resident::Cpu {
                    rows: vec![0.0; self.n_nodes],
                    stats: first,
                    queue: Vec::new(),
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
    /// increments no longer runs host-array ones ([`Contact::penalty_step`]).
    pub fn encode_increment(&mut self, io: ResidentIo<'_>, dt: f64) -> Result<()> {
        positive_dt(dt)?;
        if self.resident.is_none() {
            self.make_resident()?;
        }
        if let Some(needed) = self.grow_to.take() {
            for pr in &mut self.pairs {
                match pr.search.gpu_mut() {
                    Some(g) => g.grow_resident_entries(needed)?,
                    None => {
                        if let Some(c) = pr.search.cpu_mut() {
                            c.grow_resident_entries(needed);
                        }
                    }
                }
            }
        }
        let dt_ref = *self.dt_ref.get_or_insert(dt);
        let n_nodes = self.n_nodes;
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
                for pr in self.pairs.iter_mut() {
                    let pp = pr.setup.params(dt, dt_ref);
                    let g = pr.search.gpu_mut().ok_or_else(mixed)?;
                    g.prepare_resident(positions)?;
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
                    groups.extend(g.resident_dispatches());
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
                inc.end(encoder);
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
                words[..STATS_RESET_WORDS].copy_from_slice(&stats::reset_image());
                for pr in &mut self.pairs {
                    let pp = pr.setup.params(dt, dt_ref);
                    let c = pr.search.cpu_mut().ok_or_else(mixed)?;
                    let (mut status, prep, hits) = c.step_resident(positions)?;
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
                queue.push(bytemuck::cast(*words));
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
        crate::gpu::submit(&ctx, encoder);
        Ok(())
    }

    /// The device buffer of the last device-resident increment's statistics
    /// ([`IncrementStats`], 64 bytes, STORAGE | COPY_SRC): a host integrator running on the
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
    /// path, every increment since the last call. A spill seen here grows the bin entries at the
    /// next increment; a non-finite coordinate is an error naming the node.
    pub fn collect_stats(&mut self) -> Result<Vec<IncrementStats>> {
        let out = match self.resident.as_mut() {
            Some(Resident::Gpu(inc)) => inc.collect()?,
            Some(Resident::Cpu { queue, .. }) => std::mem::take(queue),
            None => Vec::new(),
        };
        for s in &out {
            if s.spilled > 0 {
                self.grow_to = Some(self.grow_to.unwrap_or(0).max(s.needed_entries));
            }
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

    /// Increments whose statistics found no free staging buffer of the ring (the host fell more
    /// than `STATS_RING` increments behind); their statistics were on the device all the same.
    pub fn dropped_stats(&self) -> u64 {
        match &self.resident {
            Some(Resident::Gpu(inc)) => inc.dropped,
            _ => 0,
        }
    }

    /// Asks the next device-resident increment of every pair to search globally (a 4-byte upload
    /// per pair on a GPU).
    pub fn request_global_search(&mut self) {
        for pr in &mut self.pairs {
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
