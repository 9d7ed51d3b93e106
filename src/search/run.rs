//! A search run on its own (`GlobalSearch::step`, `run` and `step_device`, kinematic pairs,
//! point queries, a `Contact`'s overclosure check): the search's part of the device-resident
//! plan, made resident by the first call at the host's positions, the schedule decided on the
//! device, and what the caller needs read back — the one search path there is.

use super::*;
use crate::plan::PlanPositions;

impl SearchStage {
    /// Positions checked as a search reads them: one per model node, finite, in the model's
    /// dimension.
    fn check(&self, positions: &[[f64; 3]]) -> Result<()> {
        if positions.len() != self.masses.len() {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.masses.len(),
                got: positions.len(),
            });
        }
        validate_positions(positions, 0, self.dim)
    }

    /// One increment of tracking on `exec` (see [`GlobalSearch::step`]): made resident at
    /// `positions` by the first (small sliding anchors its slaves there), the frame moved when
    /// the master has travelled far from it, the positions handed over relative to it
    /// (subtracted in f64), the plan run and its hits read back.
    pub(crate) fn step(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
    ) -> Result<SearchResult> {
        self.check(positions)?;
        self.step_asked(exec, positions, false)
    }

    /// [`Self::step`], with a global search asked for when `asked`.
    fn step_asked(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
        asked: bool,
    ) -> Result<SearchResult> {
        let moved = if self.resident_origin.is_none() {
            self.make_resident(exec, positions, false)?;
            false
        } else {
            self.rebase_if_far(exec, positions)?
        };
        if asked {
            exec.request_global();
        }
        let x = self.in_frame(positions, self.resident_frame())?;
        // the schedule surely searches globally: asked, moved, or the first increment
        let global = asked || moved || self.runs == 0;
        let ran = exec.run_plan(PlanPositions::Host(&x), true, global)?;
        let mut result = self.plan_result(ran);
        if moved && result.stats.trigger == Trigger::Requested {
            result.stats.trigger = Trigger::Frame;
        }
        Ok(result)
    }

    /// A global search on `exec` whatever the schedule (see [`GlobalSearch::run`]).
    pub(crate) fn run_on(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
    ) -> Result<SearchResult> {
        self.check(positions)?;
        let mut result = self.step_asked(exec, positions, true)?;
        if !self.is_anchored() {
            result.stats.trigger = Trigger::Requested;
        }
        Ok(result)
    }

    /// [`GlobalSearch::step_device`] on `exec`.
    fn step_device(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<SearchResult> {
        let Some(origin) = self.resident_origin else {
            return Err(Error::BadParameter {
                name: "step_device",
                value: "no increment yet".into(),
                expected: "a first increment from host positions (step or run)",
            });
        };
        let frame = origin.map(|o| o as f32);
        let ran = exec.run_plan(
            PlanPositions::Buffer(positions, frame),
            read_hits,
            self.runs == 0,
        )?;
        Ok(self.plan_result(ran))
    }

    /// The result of one run of the plan: its hits relative to the frame, its trigger from the
    /// plan's words (the first increment after `make_resident` is the first of an anchored
    /// search).
    fn plan_result(&mut self, ran: crate::plan::PlanRan) -> SearchResult {
        let first = self.runs == 0;
        self.runs += 1;
        let params = layout::plan_params(&ran.plan);
        let trigger = ran.plan[layout::PLAN_TRIGGER];
        self.resident_result(ran.hits, &ran.status, &params, trigger, first)
    }
}

impl GlobalSearch {
    /// One increment like [`GlobalSearch::step`], with the positions read from the caller's own
    /// buffer on this search's GPU (one `vec4<f32>` per model node, model frame, STORAGE
    /// usage): nothing is uploaded, the kernels subtract the frame's origin in f32, and the
    /// hits are read back only when `read_hits` (otherwise `raw` is empty; the status words and
    /// the plan's head always come back). The frame is the one the first increment fitted: that
    /// one must be a host one ([`GlobalSearch::step`] or `run`); the device refits the box
    /// around the master at every global search, but a master that travels far from the
    /// frame's origin loses f32 precision (a host increment moves the frame). Needs a GPU
    /// device made with [`Device::from_wgpu`] on the buffer's device (or one of abut's own, for
    /// buffers it made).
    pub fn step_device(
        &mut self,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<SearchResult> {
        let (stage, exec) = self.parts();
        stage.step_device(exec, positions, read_hits)
    }
}
