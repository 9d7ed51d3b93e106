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

use super::{fill_output, positive_dt, Contact, PenaltyExec, StepReport};
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

/// abut's own arrays of host-array increments run through the device-resident plan.
pub(crate) enum HostArrays {
    /// On a GPU: positions (one buffer per pair, relative to its search's frame), velocities,
    /// forces, and the staging buffer everything read back goes through.
    Gpu {
        x: Vec<wgpu::Buffer>,
        v: wgpu::Buffer,
        f: wgpu::Buffer,
        staging: wgpu::Buffer,
    },
    /// On the CPU path: the same as host arrays.
    Cpu {
        x: Vec<Vec<[f32; 4]>>,
        v: Vec<[f32; 4]>,
        f: Vec<[f32; 4]>,
    },
}

/// What the host knows of a pair's schedule in host-array increments (its plan's words, read
/// back with every increment's forces): enough to tell when the device's schedule will surely
/// choose the local search, so that the global search's dispatches — which would get zero
/// workgroups — need not be recorded. The device still decides; the host only leaves out what
/// it has proved empty.
#[derive(Clone, Debug, Default)]
pub(crate) struct HostSchedule {
    /// Increments since the last global search.
    since_global: u32,
    /// A global search has run.
    searched: bool,
    /// Self-contact slaves were crowded at the last global search.
    crowded: bool,
    /// A global search was asked for (a new frame).
    forced: bool,
    /// Positions of the watched nodes at the last global search (model units).
    reference: Vec<[f64; 3]>,
    /// The pair's reference master node's position then ([`GlobalSearch::reference_node`]):
    /// the device measures every displacement relative to it.
    reference_node_at: [f64; 3],
}

impl HostSchedule {
    /// Whether the schedule of `search` will choose the local search at `positions`: not the
    /// first or a requested increment, the interval not come round, no crowding, and every
    /// watched node (tracked slaves included, which the device does not count) has moved less
    /// than half the budget relative to the reference master node since the last global
    /// search — the device's measure (motion.wgsl) — with a margin for f32 round-off.
    fn surely_local(&self, search: &GlobalSearch, positions: &[[f64; 3]]) -> bool {
        let sched = search.schedule();
        if !self.searched
            || self.forced
            || self.since_global + 1 >= sched.interval
            || (search.is_self_contact() && self.crowded)
            || self.reference.len() != search.motion_nodes().len()
        {
            return false;
        }
        let budget = sched.budget * search.radius();
        let limit = (0.49 * budget).powi(2);
        let xr = positions[search.reference_node() as usize];
        let base = [0, 1, 2].map(|a| xr[a] - self.reference_node_at[a]);
        search
            .motion_nodes()
            .iter()
            .zip(&self.reference)
            .all(|(&n, r)| {
                let x = positions[n as usize];
                (0..3).map(|a| (x[a] - r[a] - base[a]).powi(2)).sum::<f64>() < limit
            })
    }

    /// Takes in the plan's words after an increment at `positions`.
    fn update(&mut self, plan: &[u32], search: &GlobalSearch, positions: &[[f64; 3]]) {
        self.since_global = plan[PLAN_SINCE_GLOBAL];
        self.searched = plan[PLAN_SEARCHED] != 0;
        self.crowded = plan[PLAN_CROWDED] != 0;
        self.forced = plan[PLAN_FORCE] != 0;
        if self.searched && self.since_global == 0 {
            self.reference = search
                .motion_nodes()
                .iter()
                .map(|&n| positions[n as usize])
                .collect();
            self.reference_node_at = positions[search.reference_node() as usize];
        }
    }
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

/// What one pair's increment left, read back for its output variables.
struct PairRaw {
    status: [u32; STATUS_WORDS],
    /// The plan's words up to the end of its params.
    plan: Vec<u32>,
    hits: Vec<GpuHit>,
    out: Vec<ContactOut>,
}

/// What a host-array increment reads back: the forces, the statistics, each pair's raw results
/// (with outputs) and each pair's schedule words.
type HostResults = (Vec<[f32; 4]>, IncrementStats, Vec<PairRaw>, Vec<Vec<u32>>);

/// Bytes of a pair's output readback: status, plan words up to its slots, hits, outputs.
fn pair_raw_bytes(n_slaves: usize) -> u64 {
    (STATUS_WORDS * 4 + PLAN_SLOTS * 4) as u64
        + n_slaves as u64
            * (std::mem::size_of::<GpuHit>() + std::mem::size_of::<ContactOut>()) as u64
}

impl Contact {
    /// The host-array increment (`penalty_step`, inputs validated) through the device-resident
    /// plan on abut's own arrays: positions uploaded relative to the frame's origin (subtracted
    /// in f64), the increment recorded and submitted, the forces, the statistics and (when asked
    /// for) the pairs' output variables read back in one wait.
    pub(crate) fn host_increment(
        &mut self,
        positions: &[[f64; 3]],
        velocities: &[[f64; 3]],
        dt: f64,
    ) -> Result<()> {
        if self.mode.is_none() {
            self.make_resident(positions, false)?;
            let n = self.n_nodes;
            let arrays = match self.pairs.first().map(|p| &p.exec) {
                Some(PenaltyExec::Gpu(p)) => {
                    let ctx = p.context();
                    let buffer = |label, size: u64, usage| {
                        ctx.device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some(label),
                            size: size.max(16).next_multiple_of(16),
                            usage,
                            mapped_at_creation: false,
                        })
                    };
                    let state = wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC;
                    let outputs: u64 = self
                        .pairs
                        .iter()
                        .map(|p| pair_raw_bytes(p.setup.areas.len()))
                        .sum();
                    HostArrays::Gpu {
                        x: (0..self.pairs.len())
                            .map(|_| buffer("positions", n as u64 * 16, state))
                            .collect(),
                        v: buffer("velocities", n as u64 * 16, state),
                        f: buffer("forces", n as u64 * 16, state),
                        staging: buffer(
                            "increment readback",
                            n as u64 * 16 + STATS_BYTES + 64 * self.pairs.len() as u64 + outputs,
                            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        ),
                    }
                }
                _ => HostArrays::Cpu {
                    x: vec![vec![[0.0; 4]; n]; self.pairs.len()],
                    v: vec![[0.0; 4]; n],
                    f: vec![[0.0; 4]; n],
                },
            };
            self.mode = Some(Mode::Host(Box::new(arrays)));
        }
        // each pair's positions relative to its search's frame (a pair whose nodes travelled
        // far from it gets a new one, and a global search)
        let mut xs = Vec::with_capacity(self.pairs.len());
        for pr in &mut self.pairs {
            if pr.search.rebase_if_far(positions)? {
                pr.schedule.forced = true;
            }
            let o = pr.search.resident_frame();
            xs.push(
                positions
                    .iter()
                    .map(|p| {
                        [
                            (p[0] - o[0]) as f32,
                            (p[1] - o[1]) as f32,
                            (p[2] - o[2]) as f32,
                            0.0,
                        ]
                    })
                    .collect::<Vec<[f32; 4]>>(),
            );
        }
        let v: Vec<[f32; 4]> = velocities
            .iter()
            .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0])
            .collect();
        let outputs = self.want_outputs;
        let local_only: Vec<bool> = self
            .pairs
            .iter()
            .map(|pr| !pr.search.is_anchored() && pr.schedule.surely_local(&pr.search, positions))
            .collect();
        // the rigid parts where the positions have them
        for p in &mut self.parts {
            p.update(positions);
        }
        let mut mode = self.mode.take();
        let done = self.host_arrays_increment(&mut mode, &xs, &v, &local_only, dt, outputs);
        self.mode = mode;
        let (forces, st, raws, plans) = done?;
        for (pr, plan) in self.pairs.iter_mut().zip(&plans) {
            pr.schedule.update(plan, &pr.search, positions);
        }
        self.host_increments += 1;
        let limit = |v: f32| {
            if v >= NO_LIMIT {
                f64::INFINITY
            } else {
                v as f64
            }
        };
        self.report = StepReport {
            forces: forces
                .iter()
                .map(|f| [f[0] as f64, f[1] as f64, f[2] as f64])
                .collect(),
            stable_dt: limit(st.stable_dt),
            approach_dt: limit(st.approach_dt),
            max_overclosure: st.max_overclosure as f64,
            active: st.active as usize,
            slipping: st.slipping as usize,
            global_searches: st.global_searches as usize,
            fallbacks: st.fallbacks as usize,
            unanchored: self.pairs.iter().map(|p| p.search.unanchored().len()).sum(),
            stable_dt_before_contact: st.active == 0 && limit(st.stable_dt).is_finite(),
            ..Default::default()
        };
        self.global_total += st.global_searches as u64;
        self.report.fast_nodes = st.fast_nodes as usize;
        if st.fast_nodes > 0 {
            // the kernels counted them; name the fastest from this increment's hits
            let mut fastest: Option<super::FastNode> = None;
            for k in 0..self.pairs.len() {
                let hits = match raws.get(k) {
                    Some(raw) => raw.hits.clone(),
                    None => self.last_hits(k)?,
                };
                let pr = &self.pairs[k];
                let (_, top) = super::fast_slaves(pr.id, &pr.search, &hits, velocities, dt);
                if let Some(t) = top {
                    if fastest.is_none_or(|f| t.distance / t.radius > f.distance / f.radius) {
                        fastest = Some(t);
                    }
                }
            }
            self.report.fastest = fastest;
        }
        // name the slave whose contact gave it (its master nodes share the value), else the node
        let forces = &self.report.forces;
        let on_slave = self.pairs.iter().find_map(|p| {
            p.search.slaves().iter().find_map(|&s| {
                let f = forces[s as usize];
                f.iter().find(|c| !c.is_finite()).map(|&c| (s as usize, c))
            })
        });
        if let Some((node, value)) = on_slave.or_else(|| super::first_non_finite(forces)) {
            let pairs: Vec<String> = self
                .pairs
                .iter()
                .filter(|p| {
                    p.search.slaves().contains(&(node as u32))
                        || p.search
                            .master()
                            .facets
                            .iter()
                            .any(|f| f.nodes().contains(&(node as u32)))
                })
                .map(|p| p.id.0.to_string())
                .collect();
            return Err(Error::NonFiniteResult {
                what: format!("penalty contact force (pair {})", pairs.join(", ")),
                node,
                value,
                cause: format!(
                    "from finite input: position {:?}, velocity {:?}, increment {dt:e}; the \
                     kernels work in f32, where a speed, stiffness or force beyond 3.4e38 \
                     overflows",
                    positions[node], velocities[node]
                ),
            });
        }
        let first = self.host_increments == 1;
        for (pr, raw) in self.pairs.iter_mut().zip(raws) {
            let params = plan_params(&raw.plan);
            let result = pr.search.resident_result(
                raw.hits,
                &raw.status,
                &params,
                raw.plan[PLAN_TRIGGER],
                first,
            );
            fill_output(&mut pr.output, &raw.out, &pr.setup.areas, result);
        }
        Ok(())
    }

    /// The raw hits of pair run `k` after the last host-array increment (read back from the
    /// GPU when it has them).
    fn last_hits(&self, k: usize) -> Result<Vec<GpuHit>> {
        let pr = &self.pairs[k];
        let ns = pr.search.slaves().len();
        match (&pr.exec, pr.search.gpu()) {
            (PenaltyExec::Gpu(p), Some(g)) => {
                let bytes = (ns * std::mem::size_of::<GpuHit>()) as u64;
                if bytes == 0 {
                    return Ok(Vec::new());
                }
                let ctx = p.context();
                let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("hits readback"),
                    size: bytes,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut enc = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("hits readback"),
                    });
                enc.copy_buffer_to_buffer(g.resident_outputs().2, 0, &staging, 0, bytes);
                crate::device::submit(&ctx, enc);
                let raw = crate::gpu::buffers::read_back(&ctx, &staging, bytes, "hits readback")?;
                Ok(bytemuck::pod_collect_to_vec(&raw))
            }
            _ => {
                let c = pr.search.cpu().ok_or_else(mixed)?;
                Ok(c.resident_outputs().2[..ns].to_vec())
            }
        }
    }

    /// Runs one increment on abut's own arrays `mode` (positions `x`, per pair relative to its
    /// search's frame, velocities `v`); returns the forces, the statistics and, with `outputs`,
    /// each pair's raw results.
    fn host_arrays_increment(
        &mut self,
        mode: &mut Option<Mode>,
        x: &[Vec<[f32; 4]>],
        v: &[[f32; 4]],
        local_only: &[bool],
        dt: f64,
        outputs: bool,
    ) -> Result<HostResults> {
        let Some(Mode::Host(arrays)) = mode else {
            return Err(mixed());
        };
        let n = self.n_nodes;
        match arrays.as_mut() {
            HostArrays::Gpu {
                x: xb,
                v: vb,
                f: fb,
                staging,
            } => {
                let ctx = match self.pairs.first().map(|p| &p.exec) {
                    Some(PenaltyExec::Gpu(p)) => p.context(),
                    _ => return Err(mixed()),
                };
                for (b, xk) in xb.iter().zip(x) {
                    crate::gpu::upload(&ctx, b, 0, bytemuck::cast_slice(xk));
                }
                crate::gpu::upload(&ctx, vb, 0, bytemuck::cast_slice(v));
                let mut enc = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("penalty increment"),
                    });
                enc.clear_buffer(fb, 0, None);
                self.record(
                    ResidentIo::Gpu {
                        encoder: &mut enc,
                        positions: &xb[0],
                        velocities: vb,
                        forces: fb,
                    },
                    PairPositions::Gpu(xb),
                    local_only,
                    dt,
                    false,
                )?;
                let forces_bytes = n as u64 * 16;
                enc.copy_buffer_to_buffer(fb, 0, staging, 0, forces_bytes);
                let Some(Resident::Gpu(inc)) = &self.resident else {
                    return Err(mixed());
                };
                enc.copy_buffer_to_buffer(inc.stats(), 0, staging, forces_bytes, STATS_BYTES);
                let mut offset = forces_bytes + STATS_BYTES;
                // every pair's schedule words
                let heads = offset;
                for pr in &self.pairs {
                    let g = pr.search.gpu().ok_or_else(mixed)?;
                    enc.copy_buffer_to_buffer(g.resident_outputs().1, 0, staging, offset, 64);
                    offset += 64;
                }
                let mut layout = Vec::new();
                if outputs {
                    for pr in &self.pairs {
                        let g = pr.search.gpu().ok_or_else(mixed)?;
                        let PenaltyExec::Gpu(p) = &pr.exec else {
                            return Err(mixed());
                        };
                        let ns = pr.setup.areas.len() as u64;
                        let (status, plan, hits) = g.resident_outputs();
                        let start = offset;
                        for (src, bytes) in [
                            (status, (STATUS_WORDS * 4) as u64),
                            (plan, (PLAN_SLOTS * 4) as u64),
                            (hits, ns * 64),
                            (p.out_buffer(), ns * 64),
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
                let bytes =
                    crate::gpu::buffers::read_back(&ctx, staging, offset, "penalty increment")?;
                ctx.take_uncaptured("penalty increment")?;
                let forces: Vec<[f32; 4]> =
                    bytemuck::pod_collect_to_vec(&bytes[..forces_bytes as usize]);
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
                Ok((forces, st, raws, plans))
            }
            HostArrays::Cpu {
                x: xa,
                v: va,
                f: fa,
            } => {
                for (a, xk) in xa.iter_mut().zip(x) {
                    a.copy_from_slice(xk);
                }
                va.copy_from_slice(v);
                fa.iter_mut().for_each(|f| *f = [0.0; 4]);
                self.record(
                    ResidentIo::Cpu {
                        positions: &xa[0],
                        velocities: va,
                        forces: fa,
                    },
                    PairPositions::Cpu(xa),
                    local_only,
                    dt,
                    false,
                )?;
                let Some(Resident::Cpu { stats: words, .. }) = &self.resident else {
                    return Err(mixed());
                };
                let st: IncrementStats = bytemuck::cast(*words);
                let mut plans = Vec::new();
                for pr in &mut self.pairs {
                    let c = pr.search.cpu_mut().ok_or_else(mixed)?;
                    plans.push(c.resident_outputs().1[..16].to_vec());
                }
                let mut raws = Vec::new();
                if outputs {
                    for pr in &mut self.pairs {
                        let c = pr.search.cpu_mut().ok_or_else(mixed)?;
                        let (status, plan, hits) = c.resident_outputs();
                        let PenaltyExec::Cpu(p) = &pr.exec else {
                            return Err(mixed());
                        };
                        raws.push(PairRaw {
                            status,
                            plan: plan[..PLAN_SLOTS].to_vec(),
                            hits: hits.to_vec(),
                            out: p.out.clone(),
                        });
                    }
                }
                Ok((fa.clone(), st, raws, plans))
            }
        }
    }
}
