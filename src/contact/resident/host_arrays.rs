//! Host-array increments (`Contact::penalty_step`) through the device-resident plan on abut's
//! own arrays: positions uploaded relative to each pair's frame (subtracted in f64), the
//! increment recorded and submitted, and the forces, statistics and output variables read back
//! in one readback; the host's view of each pair's schedule, which leaves out a global search it
//! has proved empty.

use super::*;

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
    pub(super) forced: bool,
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
            let mut fastest: Option<crate::contact::FastNode> = None;
            for k in 0..self.pairs.len() {
                let hits = match raws.get(k) {
                    Some(raw) => raw.hits.clone(),
                    None => self.last_hits(k)?,
                };
                let pr = &self.pairs[k];
                let (_, top) = fast_slaves(pr.id, &pr.search, &hits, velocities, dt);
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
        if let Some((node, value)) = on_slave.or_else(|| crate::contact::first_non_finite(forces)) {
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
