//! The direct-submit search (`GlobalSearch::run` and `step`, kinematic pairs, point queries, the
//! anchoring search): the schedule's choice made on the host, the executor run and its hits read
//! back; positions from the caller's device buffer; a search split between the CPU mirror and the
//! GPU.

use super::*;

impl GlobalSearch {
    /// The schedule's choice for the next increment: `Some(trigger)` for a global search,
    /// `None` for the local search.
    pub(super) fn decide(&self) -> Option<Trigger> {
        if self.sliding != crate::model::Sliding::Finite {
            return if self.anchors.is_none() {
                Some(Trigger::First)
            } else {
                None
            };
        }
        if self.frame.is_none() {
            Some(Trigger::First)
        } else if self.since_global + 1 >= self.schedule.interval {
            Some(Trigger::Interval)
        } else if self.self_contact && self.crowded {
            Some(Trigger::Crowded)
        } else {
            None
        }
    }

    /// Runs one increment, global (`Some(trigger)`) or local (`None`); a local increment whose
    /// motion budget is used up is run again globally.
    pub(super) fn execute(
        &mut self,
        positions: &[[f64; 3]],
        mut global: Option<Trigger>,
    ) -> Result<(SearchResult, [u32; STATUS_WORDS])> {
        let mut anchored_first = false;
        loop {
            // small sliding's first increment: the global search alone, to anchor the slaves,
            // reaching as far as the pair allows; then the same increment from the anchors
            let anchoring = self.sliding != crate::model::Sliding::Finite && self.anchors.is_none();
            let prepared = match global {
                Some(_) if anchoring => {
                    let reach = self.anchoring_radius(positions);
                    let own = std::mem::replace(&mut self.radius, reach);
                    let prepared = self.prepare(positions);
                    self.radius = own;
                    prepared?
                }
                Some(_) => self.prepare(positions)?,
                None => self.prepare_local(positions)?,
            };
            let local = global.is_none();
            let (raw, status) = match &mut self.executor {
                Executor::Gpu(g) => g.run_mode(&prepared, local, true)?,
                Executor::Cpu(c) => c.run_mode(&prepared, local)?,
            };
            if local && Status(status).budget_exceeded() {
                global = Some(Trigger::Budget);
                continue;
            }
            match global {
                Some(_) => {
                    self.frame = Some((prepared.grid, prepared.params));
                    self.since_global = 0;
                    self.crowded = Status(status).crowded() > 0;
                }
                None => self.since_global += 1,
            }
            let anchored = self.anchors.is_some();
            let trigger = if anchored_first {
                Trigger::First
            } else {
                global.unwrap_or(if anchored {
                    Trigger::Anchored
                } else {
                    Trigger::Local
                })
            };
            if anchoring {
                let anchors = self.build_anchors(positions, &raw);
                match &mut self.executor {
                    Executor::Gpu(g) => g.set_anchors(&anchors)?,
                    Executor::Cpu(c) => c.set_anchors(&anchors),
                }
                self.anchors = Some(anchors);
                global = None;
                anchored_first = true;
                continue;
            }
            return Ok((
                self.finish(prepared.grid.frame, prepared.grid, raw, trigger, &status),
                status,
            ));
        }
    }

    /// One increment like [`GlobalSearch::step`], with the positions read from the caller's own
    /// buffer on this search's GPU (one `vec4<f32>` per model node, model frame; usage
    /// STORAGE, and COPY_SRC for the rare refit below): nothing is uploaded, and the hits are
    /// read back only when `read_hits` (otherwise `contacts` is empty; the status words and the
    /// bin total, 96 bytes, always come back). The frame is the last global search's grid: the first
    /// increment must be a host one ([`GlobalSearch::step`] or `run`). If a master node leaves
    /// the grid's box, the buffer is read back once, the grid refitted and the increment run
    /// again (`Trigger::Frame`). Needs a GPU device made with [`Device::from_wgpu`] on the
    /// buffer's device (or one of abut's own, for buffers it made).
    pub fn step_device(
        &mut self,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<SearchResult> {
        if self.frame.is_none() {
            return Err(Error::BadParameter {
                name: "step_device",
                value: "no global search yet".into(),
                expected: "a first increment from host positions (step or run)",
            });
        }
        let mut global = self.decide();
        loop {
            let prepared = self.prepare_device(global.is_none())?;
            let local = global.is_none();
            let Executor::Gpu(g) = &mut self.executor else {
                return Err(Error::BadParameter {
                    name: "step_device",
                    value: "CPU path".into(),
                    expected: "a GPU device",
                });
            };
            g.set_device_positions(Some(positions.clone()));
            let run = g.run_mode(&prepared, local, read_hits);
            g.set_device_positions(None);
            let (raw, status) = run?;
            if Status(status).frame_stale() {
                let host = g.read_positions(positions, prepared.n_nodes)?;
                return Ok(self.execute(&host, Some(Trigger::Frame))?.0);
            }
            if local && Status(status).budget_exceeded() {
                global = Some(Trigger::Budget);
                continue;
            }
            match global {
                Some(_) => {
                    self.since_global = 0;
                    self.crowded = Status(status).crowded() > 0;
                }
                None => self.since_global += 1,
            }
            return Ok(self.finish(
                prepared.grid.frame,
                prepared.grid,
                raw,
                global.unwrap_or(Trigger::Local),
                &status,
            ));
        }
    }

    /// Runs `STEPS[..first_gpu_step]` on the CPU mirror and the rest on this search's GPU,
    /// handing the intermediate buffers over: when GPU and CPU disagree, the first split that
    /// reproduces the CPU result names the step that diverges. On the CPU path it is `run`.
    pub fn run_split(
        &mut self,
        positions: &[[f64; 3]],
        first_gpu_step: usize,
    ) -> Result<SearchResult> {
        let prepared = self.prepare(positions)?;
        let first = first_gpu_step.min(STEPS.len());
        let (raw, status) = match &mut self.executor {
            Executor::Gpu(g) => {
                let mut cpu = CpuSearch::default();
                let ws = cpu.run_prefix(&prepared, first)?;
                g.run_split(&prepared, first, ws)?
            }
            Executor::Cpu(c) => c.run_mode(&prepared, false)?,
        };
        self.frame = Some((prepared.grid, prepared.params));
        self.since_global = 0;
        Ok(self.finish(
            prepared.grid.frame,
            prepared.grid,
            raw,
            Trigger::Requested,
            &status,
        ))
    }
}
