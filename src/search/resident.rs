//! The search's side of a device-resident increment: made resident once, its frame moved when
//! the master travels far, and its result read from the increment's hits and words.

use super::*;

impl SearchStage {
    /// Readies this search for device-resident increments at `positions` (the master's box is
    /// taken on the device at every global search). The kernels work relative to the frame's
    /// origin the host chooses at `positions` (near the master, snapped to a power of two:
    /// `crate::plan::frame::origin`): the positions the increments read are in the model frame
    /// when `caller_frame` (the caller's f32 buffers; the kernels subtract the origin in f32),
    /// or already relative to the origin (host arrays and a search run alone, subtracted in f64
    /// by the host). Small sliding anchors its slaves here, by a global search at `positions`,
    /// as its first increment would.
    pub(crate) fn make_resident(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
        caller_frame: bool,
    ) -> Result<()> {
        let anchored = self.is_anchored();
        match &self.anchors {
            None if anchored => self.anchor(exec, positions)?,
            // carried from another search over the same slaves (`set_keyed_anchors`)
            Some(anchors) if anchored => exec.set_anchors(anchors)?,
            _ => {}
        }
        let prep = self.prepare(positions)?;
        let origin = prep.frame;
        let frame = if caller_frame {
            origin.map(|o| o as f32)
        } else {
            [0.0; 3]
        };
        let interval = self.schedule.interval;
        self.resident_origin = Some(origin);
        self.resident_span = match self.given_frame {
            Some((_, span)) => span,
            None => self.master_span(positions),
        };
        self.runs = 0;
        exec.make_resident(&prep, interval, anchored, frame)
    }

    /// Small sliding: anchors the slaves by one global search at `positions` reaching as far
    /// as the pair allows ([`Self::anchoring_radius`]) — the search's plan without anchors, at
    /// that radius, its first increment global — whose hits become the anchors, installed in
    /// `exec` (in a browser that search runs on the CPU path: a readback cannot be waited for).
    fn anchor(&mut self, exec: &mut dyn SearchExec, positions: &[[f64; 3]]) -> Result<()> {
        let reach = self.anchoring_radius(positions);
        let own = std::mem::replace(&mut self.radius, reach);
        let prep = self.prepare(positions);
        self.radius = own;
        let prep = prep?;
        // in a browser nothing may wait for the device: the anchors' one search runs on the
        // CPU path there (the kernels' mirrors, from the same host positions)
        #[cfg(target_arch = "wasm32")]
        let mut cpu = crate::cpu::CpuSearch::default();
        #[cfg(target_arch = "wasm32")]
        let finder: &mut dyn SearchExec = &mut cpu;
        #[cfg(not(target_arch = "wasm32"))]
        let finder: &mut dyn SearchExec = &mut *exec;
        finder.make_resident(&prep, 1, false, [0.0; 3])?;
        let x = self.in_frame(positions, prep.frame)?;
        let ran = finder.run_plan(crate::plan::PlanPositions::Host(&x), true, true)?;
        let anchors = self.build_anchors(positions, &ran.hits);
        exec.set_anchors(&anchors)?;
        self.anchors = Some(anchors);
        Ok(())
    }

    /// Readies a second executor (`exec`, the CPU twin of a split increment) as this search's
    /// was made resident: the same preparation, frame, schedule and anchors (the arrays the
    /// increments write are the twin's to take from the first).
    pub(crate) fn make_twin_resident(
        &self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
        caller_frame: bool,
    ) -> Result<()> {
        let prep = self.prepare(positions)?;
        let frame = if caller_frame {
            self.resident_frame().map(|o| o as f32)
        } else {
            [0.0; 3]
        };
        if let Some(anchors) = &self.anchors {
            exec.set_anchors(anchors)?;
        }
        exec.make_resident(&prep, self.schedule.interval, self.is_anchored(), frame)
    }

    /// Where the master nodes start in the watched nodes: after the slaves, unless the slaves
    /// are master nodes themselves (self-contact), when every watched node is one.
    pub(super) fn master_start(&self) -> usize {
        if self.self_contact {
            0
        } else {
            self.slave_ids.len()
        }
    }

    /// The largest extent of the master's nodes along an axis at `positions` (model length
    /// units; the search radius for a master of no extent): what the frame's reach is measured
    /// in — the master's own size, never the radius, so that a large radius does not let the
    /// master travel far from the frame's origin.
    pub(super) fn master_span(&self, positions: &[[f64; 3]]) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &n in &self.motion_nodes[self.master_start()..] {
            let x = positions[n as usize];
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
        let span = (0..self.dim as usize)
            .map(|a| hi[a] - lo[a])
            .fold(0.0, f64::max);
        if span > 0.0 && span.is_finite() {
            span
        } else {
            self.radius
        }
    }

    /// Host arrays: when a node of the master has travelled more than 16 times the master's own
    /// extent ([`Self::master_span`], not the search radius) from the frame's origin (f32 would
    /// lose precision there, and contact is only ever near the master), the frame moves to the
    /// origin the host chooses at `positions` and the next increment searches globally, which resets
    /// everything that was relative to the old origin. Returns whether it moved.
    pub(crate) fn rebase_if_far(
        &mut self,
        exec: &mut dyn SearchExec,
        positions: &[[f64; 3]],
    ) -> Result<bool> {
        let o = self.resident_frame();
        // a frame the caller gives moves when the caller moves it
        if let Some((origin, span)) = self.given_frame {
            if origin == o {
                return Ok(false);
            }
            self.resident_origin = Some(origin);
            self.resident_span = span;
            exec.request_global();
            return Ok(true);
        }
        let reach = 16.0 * self.resident_span;
        let masters = &self.motion_nodes[self.master_start()..];
        let far = masters.iter().any(|&n| {
            let x = positions[n as usize];
            (0..3).any(|a| (x[a] - o[a]).abs() > reach)
        });
        if !far {
            return Ok(false);
        }
        let prep = self.prepare(positions)?;
        if prep.frame == o {
            return Ok(false);
        }
        self.resident_origin = Some(prep.frame);
        self.resident_span = self.master_span(positions);
        exec.request_global();
        Ok(true)
    }

    /// The search result of a device-resident increment from its hits (relative to
    /// the resident origin), status words, params and trigger code.
    pub(crate) fn resident_result(
        &self,
        raw: Arc<Vec<GpuHit>>,
        status: &[u32; STATUS_WORDS],
        params: &SearchParams,
        trigger: u32,
        first: bool,
    ) -> SearchResult {
        let origin = self.resident_origin.unwrap_or([0.0; 3]);
        let master_box = [params.master_lo, params.master_hi]
            .map(|c| [0, 1, 2].map(|a| origin[a] + c[a] as f64));
        let trigger = if self.sliding != crate::model::Sliding::Finite {
            if first {
                Trigger::First
            } else {
                Trigger::Anchored
            }
        } else {
            match trigger {
                layout::TRIGGER_FIRST => Trigger::First,
                layout::TRIGGER_INTERVAL => Trigger::Interval,
                layout::TRIGGER_BUDGET => Trigger::Budget,
                layout::TRIGGER_CROWDED => Trigger::Crowded,
                layout::TRIGGER_REQUESTED => Trigger::Requested,
                _ => Trigger::Local,
            }
        };
        self.finish(origin, master_box, raw, trigger, status)
    }

    /// The origin of the device-resident frame (model units).
    pub(crate) fn resident_frame(&self) -> [f64; 3] {
        self.resident_origin.unwrap_or([0.0; 3])
    }

    /// Gives the frame's origin and the master's extent it stands for (see
    /// `SearchStage::given_frame`): used from the next increment that makes the search
    /// resident, and a change of it from an increment on is a rebase (a global search), as
    /// [`Self::rebase_if_far`] makes one.
    #[cfg(feature = "mpi")]
    pub(crate) fn give_frame(&mut self, origin: [f64; 3], span: f64) {
        self.given_frame = Some((origin, span));
    }
}
