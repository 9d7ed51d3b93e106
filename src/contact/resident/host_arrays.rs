//! Host-array increments (`Contact::penalty_step`) through the device-resident plan on abut's
//! own arrays: positions uploaded relative to each pair's frame (subtracted in f64), the
//! increment recorded and submitted, and the forces, statistics and output variables read back
//! in one readback; the host's view of each pair's schedule, which leaves out a global search it
//! has proved empty.

use super::*;

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
    fn surely_local(&self, search: &SearchStage, positions: &[[f64; 3]]) -> bool {
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
    fn update(&mut self, plan: &[u32], search: &SearchStage, positions: &[[f64; 3]]) {
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
            self.mode = Some(Mode::Host);
        }
        // each pair's positions relative to its search's frame (a pair whose nodes travelled
        // far from it gets a new one, and a global search)
        let mut xs = Vec::with_capacity(self.pairs.len());
        for (k, pr) in self.pairs.iter_mut().enumerate() {
            if pr.search.rebase_if_far(self.exec.search(k), positions)? {
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
        // the rigid parts where the positions have them, or as given from the whole bodies
        match &self.given_parts {
            Some(states) => {
                for (p, s) in self.parts.iter_mut().zip(states) {
                    p.state = *s;
                }
            }
            None => {
                for p in &mut self.parts {
                    p.update(positions);
                }
            }
        }
        let params = self.pair_params(dt);
        let inc = Increment {
            pairs: &self.pairs,
            params: &params,
            local_only: &local_only,
        };
        let (forces, st, raws, plans, rows) =
            self.exec
                .host_increment(&inc, &xs, &v, outputs, self.rows.wanted)?;
        self.rows.take(rows, st.damping);
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
                    None => self
                        .exec
                        .last_hits(k, self.pairs[k].search.slaves().len())?,
                };
                let pr = &self.pairs[k];
                let order = pr.map.caller_sequence(hits.len());
                let (_, top) = fast_slaves(pr.id, &pr.search, &hits, order, velocities, dt);
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
            p.output.slaves.iter().find_map(|&s| {
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
                std::sync::Arc::new(raw.hits),
                &raw.status,
                &params,
                raw.plan[PLAN_TRIGGER],
                first,
            );
            // the caller reads them in the node set's order
            let (out, areas) = (
                pr.map.to_caller(&raw.out),
                pr.map.to_caller(&pr.setup.areas),
            );
            let result = pr.map.result_to_caller(result);
            fill_output(&mut pr.output, &out, &areas, result);
        }
        Ok(())
    }
}
