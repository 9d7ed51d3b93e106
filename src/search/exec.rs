//! A search's executor behind one trait: the GPU kernels (`crate::gpu::GpuSearch`) or their CPU
//! mirrors (`crate::cpu::CpuSearch`), chosen once from the device ([`for_device`]). The stage
//! ([`super::SearchStage`]: preparation, schedule, anchors, decoding) drives either through
//! this trait and never asks which one it has.

use crate::abi::search::Anchor;
use crate::cpu::CpuSearch;
use crate::device::{Device, DeviceKind};
use crate::error::{Error, Result};
use crate::gpu::GpuSearch;
use crate::plan::{PlanPositions, PlanRan, Prepared};

/// The device work of one search: its part of the device-resident plan
/// (`plan::increment::search`), run on the executor's own buffers. Capabilities only one
/// executor has (positions in a GPU buffer) are refused by the other with an error naming why.
/// `Send` on native targets (so a `GlobalSearch` is), not in a browser, whose WebGPU objects
/// are not (`wgpu::WasmNotSend`).
pub(crate) trait SearchExec: wgpu::WasmNotSend {
    /// Runs the search's entries of one increment on `positions` (after `make_resident`): the
    /// schedule decides on the device between the local and the global search (or, small
    /// sliding, the anchors are evaluated); the status, the plan's head and (with `read_hits`)
    /// the hits come back in one wait. `global`: the host asked for a global search (or none
    /// has run), so the motion budget is left out (`PairShape::global_only`).
    fn run_plan(
        &mut self,
        positions: PlanPositions<'_>,
        read_hits: bool,
        global: bool,
    ) -> Result<PlanRan>;
    /// Small sliding: installs the slaves' anchors (before `make_resident` with `anchored`).
    fn set_anchors(&mut self, anchors: &[Anchor]) -> Result<()>;
    /// Readies device-resident increments of `prep` (see `GpuSearch::make_resident`): a fresh
    /// plan, whose first increment searches globally.
    fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame: [f32; 3],
    ) -> Result<()>;
    /// Asks the next increment to search globally.
    fn request_global(&mut self);
    /// The search tree's packed boxes after the last global search.
    fn tree_boxes(&self) -> Result<Vec<[u32; 4]>>;
    /// Folds dispatches into 2D beyond `groups` workgroups per dimension (GPU only; before
    /// `make_resident`, which plans the dispatches).
    fn set_max_workgroups_per_dim(&mut self, groups: u32);
}

/// The search executor of `device`: the one place a search chooses between GPU and CPU.
pub(crate) fn for_device(device: &Device) -> Result<Box<dyn SearchExec>> {
    Ok(match device.kind() {
        DeviceKind::Gpu(ctx) => Box::new(GpuSearch::new(ctx.clone())?),
        DeviceKind::Cpu => Box::<CpuSearch>::default(),
    })
}

impl SearchExec for GpuSearch {
    fn run_plan(
        &mut self,
        positions: PlanPositions<'_>,
        read_hits: bool,
        global: bool,
    ) -> Result<PlanRan> {
        GpuSearch::run_plan(self, positions, read_hits, global)
    }

    fn set_anchors(&mut self, anchors: &[Anchor]) -> Result<()> {
        GpuSearch::set_anchors(self, anchors)
    }

    fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame: [f32; 3],
    ) -> Result<()> {
        GpuSearch::make_resident(self, prep, interval, anchored, frame)
    }

    fn request_global(&mut self) {
        GpuSearch::request_global(self)
    }

    fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        GpuSearch::tree_boxes(self)
    }

    fn set_max_workgroups_per_dim(&mut self, groups: u32) {
        GpuSearch::set_max_workgroups_per_dim(self, groups)
    }
}

impl SearchExec for CpuSearch {
    fn run_plan(
        &mut self,
        positions: PlanPositions<'_>,
        read_hits: bool,
        global: bool,
    ) -> Result<PlanRan> {
        let PlanPositions::Host(x) = positions else {
            return Err(cpu_path("positions in a device buffer"));
        };
        CpuSearch::run_plan(self, x, read_hits, global)
    }

    fn set_anchors(&mut self, anchors: &[Anchor]) -> Result<()> {
        CpuSearch::set_anchors(self, anchors);
        Ok(())
    }

    fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame: [f32; 3],
    ) -> Result<()> {
        // the plan's slots as a GPU with WebGPU's default limit folds them
        CpuSearch::make_resident(self, prep, interval, anchored, frame, 65_535)
    }

    fn request_global(&mut self) {
        CpuSearch::request_global(self)
    }

    fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        Ok(CpuSearch::tree_boxes(self).to_vec())
    }

    fn set_max_workgroups_per_dim(&mut self, _: u32) {}
}

/// The error of a GPU-only call on the CPU path.
fn cpu_path(what: &'static str) -> Error {
    Error::BadParameter {
        name: what,
        value: "CPU path".into(),
        expected: "a GPU device",
    }
}
