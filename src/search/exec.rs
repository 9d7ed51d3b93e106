//! A search's executor behind one trait: the GPU kernels (`crate::gpu::GpuSearch`) or their CPU
//! mirrors (`crate::cpu::CpuSearch`), chosen once from the device ([`for_device`]). The stage
//! ([`super::SearchStage`]: preparation, schedule, anchors, decoding) drives either through
//! this trait and never asks which one it has.

use crate::abi::passes::Buf;
use crate::abi::search::{Anchor, GpuHit};
use crate::abi::status::STATUS_WORDS;
use crate::cpu::CpuSearch;
use crate::device::{Device, DeviceKind};
use crate::error::{Error, Result};
use crate::gpu::GpuSearch;
use crate::plan::{Prepared, STEPS};
use std::sync::Arc;

/// What a search leaves after a run: the hits (one per slave; empty when not read back) and the
/// status words.
pub(crate) type Ran = (Arc<Vec<GpuHit>>, [u32; STATUS_WORDS]);

/// The device work of one search: each method is one kernel sequence on the executor's own
/// buffers. Capabilities only one executor has (positions in a GPU buffer) are methods that the
/// other refuses with an error naming why. `Send` on native targets (so a `GlobalSearch` is), not
/// in a browser, whose WebGPU objects are not (`wgpu::WasmNotSend`).
pub(crate) trait SearchExec: wgpu::WasmNotSend {
    /// Runs a global search (`local` false) or the motion budget and the local search (or, with
    /// anchors installed, their evaluation) on `prep`, reading the hits back.
    fn run_mode(&mut self, prep: &Prepared, local: bool) -> Result<Ran>;
    /// As [`SearchExec::run_mode`], the positions read from the caller's GPU buffer `positions`
    /// (one `vec4<f32>` per model node) instead of `prep`; the hits come back only when
    /// `read_hits`. The CPU path refuses it.
    fn run_on_buffer(
        &mut self,
        prep: &Prepared,
        local: bool,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<Ran>;
    /// Reads the caller's positions buffer back as f64 (the refit of a buffer increment).
    fn read_positions(&self, positions: &wgpu::Buffer, n_nodes: usize) -> Result<Vec<[f64; 3]>>;
    /// A global search with `STEPS[..first]` on the CPU mirror and the rest on this executor
    /// (the whole search on the CPU path).
    fn run_split(&mut self, prep: &Prepared, first: usize) -> Result<Ran>;
    /// Small sliding: installs the slaves' anchors; local runs evaluate them from then on.
    fn set_anchors(&mut self, anchors: &[Anchor]) -> Result<()>;
    /// Readies device-resident increments of `prep` (see `GpuSearch::make_resident`).
    fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame: [f32; 3],
    ) -> Result<()>;
    /// Asks the next device-resident increment to search globally.
    fn request_global(&mut self);
    /// The search tree's packed boxes after the last global search.
    fn tree_boxes(&self) -> Result<Vec<[u32; 4]>>;
    /// Folds dispatches into 2D beyond `groups` workgroups per dimension (GPU only).
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
    fn run_mode(&mut self, prep: &Prepared, local: bool) -> Result<Ran> {
        GpuSearch::run_mode(self, prep, local, true)
    }

    fn run_on_buffer(
        &mut self,
        prep: &Prepared,
        local: bool,
        positions: &wgpu::Buffer,
        read_hits: bool,
    ) -> Result<Ran> {
        self.set_device_positions(Some(positions.clone()));
        let run = GpuSearch::run_mode(self, prep, local, read_hits);
        self.set_device_positions(None);
        run
    }

    fn read_positions(&self, positions: &wgpu::Buffer, n_nodes: usize) -> Result<Vec<[f64; 3]>> {
        GpuSearch::read_positions(self, positions, n_nodes)
    }

    fn run_split(&mut self, prep: &Prepared, first: usize) -> Result<Ran> {
        let mut cpu = CpuSearch::default();
        let ws = cpu.run_prefix(prep, first.min(STEPS.len()))?;
        // what the steps before the split write: the tree's boxes and the status words
        let preload = [
            (Buf::Boxes, bytemuck::cast_slice(&ws.boxes)),
            (Buf::Status, bytemuck::cast_slice(&ws.status[..])),
        ];
        GpuSearch::run_split(self, prep, first.min(STEPS.len()), &preload)
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
    fn run_mode(&mut self, prep: &Prepared, local: bool) -> Result<Ran> {
        CpuSearch::run_mode(self, prep, local)
    }

    fn run_on_buffer(&mut self, _: &Prepared, _: bool, _: &wgpu::Buffer, _: bool) -> Result<Ran> {
        Err(cpu_path("step_device"))
    }

    fn read_positions(&self, _: &wgpu::Buffer, _: usize) -> Result<Vec<[f64; 3]>> {
        Err(cpu_path("positions in a device buffer"))
    }

    fn run_split(&mut self, prep: &Prepared, _: usize) -> Result<Ran> {
        CpuSearch::run_mode(self, prep, false)
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
