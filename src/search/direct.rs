//! The direct-submit search (`GlobalSearch::run` and `step`, kinematic pairs, point queries, the
//! anchoring search): the schedule's choice made on the host, the executor run and its hits read
//! back; positions from the caller's device buffer; a search split between the CPU mirror and the
//! GPU.

use super::*;

impl SearchStage {
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
    pub(crate) fn execute(
        &mut self,
        exec: &mut dyn SearchExec,
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
            let (raw, status) = exec.run_mode(&prepared, local)?;
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
                exec.set_anchors(&anchors)?;
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
}

impl GlobalSearch {
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
        let (stage, exec) = self.parts();
        stage.step_device(exec, positions, read_hits)
    }

    /// Runs `STEPS[..first_gpu_step]` on the CPU mirror and the rest on this search's GPU,
    /// handing the intermediate buffers over: when GPU and CPU disagree, the first split that
    /// reproduces the CPU result names the step that diverges. On the CPU path it is `run`.
    pub fn run_split(
        &mut self,
        positions: &[[f64; 3]],
        first_gpu_step: usize,
    ) -> Result<SearchResult> {
        let (stage, exec) = self.parts();
        stage.run_split(exec, positions, first_gpu_step)
    }
}

impl SearchStage {
    /// [`GlobalSearch::step_device`] on `exec`.
    fn step_device(
        &mut self,
        exec: &mut dyn SearchExec,
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
            let (raw, status) = exec.run_on_buffer(&prepared, local, positions, read_hits)?;
            if Status(status).frame_stale() {
                let host = exec.read_positions(positions, prepared.n_nodes)?;
                return Ok(self.execute(exec, &host, Some(Trigger::Frame))?.0);
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

    /// [`GlobalSearch::run_split`] on `exec`.
    fn run_split(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
        first_gpu_step: usize,
    ) -> Result<SearchResult> {
        let prepared = self.prepare(positions)?;
        let (raw, status) = exec.run_split(&prepared, first_gpu_step)?;
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
