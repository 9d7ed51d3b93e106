//! A search's resident arrays on the CPU path: the preparation, frame, plan words and chunk
//! dispatch a device-resident increment's kernels read and write (`cpu::increment` runs them,
//! entry by entry, as the GPU does `gpu::global_search::resident`), laid out as the GPU's
//! buffers are, so that a split increment can hand them over role by role.

use super::{CpuSearch, CpuWorkspace};
use crate::abi::passes::Buf;
use crate::abi::search::*;
use crate::abi::status::STATUS_WORDS;
use crate::error::{Error, Result};
use crate::plan::increment::{initial_plan, PairShape, Slots};
use crate::plan::{PlanRan, Prepared};

/// What a CPU search keeps for its device-resident increments.
#[derive(Clone, Debug)]
pub(crate) struct CpuResident {
    /// The preparation at the model's positions: constants, nodes (updated in place) and masses.
    prep: Prepared,
    frame: FrameParams,
    /// The plan words (`PLAN_*`), as the GPU's plan buffer holds them.
    plan: Vec<u32>,
    /// The nearest-facet chunk dispatch (x, y, z).
    args: [u32; 3],
    anchored: bool,
    /// The plan's dispatch slots.
    slots: Slots,
}

/// A resident search's arrays, borrowed for one kernel (`cpu::increment`).
pub(crate) struct SearchArrays<'a> {
    /// The pair's constants and its nodes in the frame (updated in place).
    pub prep: &'a mut Prepared,
    /// The frame the caller's positions are relative to.
    pub frame: &'a FrameParams,
    /// The plan words.
    pub plan: &'a mut [u32],
    /// The chunk dispatch.
    pub args: &'a mut [u32; 3],
    /// Small sliding's anchors (empty otherwise).
    pub anchors: &'a [Anchor],
    /// Everything else the kernels write.
    pub ws: &'a mut CpuWorkspace,
}

impl CpuSearch {
    /// Readies this search for device-resident increments (see `GpuSearch::make_resident`);
    /// the plan's slots folded beyond `max_dim` workgroups, as a GPU with that limit folds them.
    pub(crate) fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame_origin: [f32; 3],
        max_dim: u32,
    ) -> Result<()> {
        let (plan, slots) = initial_plan(
            &prep.params,
            interval,
            prep.motion_nodes.len() as u32,
            prep.n_nodes as u32,
            max_dim,
        )?;
        self.ws.boxes.resize(
            crate::abi::search::box_words(prep.params.tree_levels),
            [0; 4],
        );
        self.ws.corners.resize(
            crate::abi::search::box_words(prep.params.tree_levels),
            [[0.0; 4]; 2],
        );
        super::hits_mut(&mut self.ws.hits).resize(prep.slaves.len(), GpuHit::miss(0, 0));
        self.ws.grid.clear();
        if prep.params.flags & FLAG_BUCKETS != 0 {
            let words = crate::abi::buckets::BucketLayout::new(prep.params.n_facets).words;
            self.ws.grid.resize(words as usize, 0);
        }
        self.ws.reference = prep.start_reference();
        // no active slave until the first global search
        self.ws.active.clear();
        self.ws.active.resize(prep.slaves.len() + 1, 0);
        self.resident = Some(Box::new(CpuResident {
            prep: prep.clone(),
            frame: FrameParams {
                origin: [frame_origin[0], frame_origin[1], frame_origin[2], 0.0],
                n_nodes: prep.n_nodes as u32,
                _pad: [0; 3],
            },
            plan,
            args: [0; 3],
            anchored,
            slots,
        }));
        Ok(())
    }

    /// The shape of this search's part of an increment (`None` before `make_resident`).
    pub(crate) fn pair_shape(&self, n_pair_nodes: u32, local_only: bool) -> Option<PairShape> {
        let r = self.resident.as_ref()?;
        Some(PairShape {
            anchored: r.anchored,
            self_contact: r.prep.params.flags & FLAG_SELF_CONTACT != 0,
            buckets: r.prep.params.flags & FLAG_BUCKETS != 0,
            local_only,
            global_only: false,
            n_nodes: r.prep.n_nodes as u32,
            n_motion_nodes: r.prep.motion_nodes.len() as u32,
            n_slaves: r.prep.slaves.len() as u32,
            n_pair_nodes,
            gather_active: false,
            slots: r.slots.clone(),
        })
    }

    /// The arrays of a resident search (`None` before `make_resident`).
    pub(crate) fn arrays(&mut self) -> Option<SearchArrays<'_>> {
        let r = self.resident.as_deref_mut()?;
        Some(SearchArrays {
            prep: &mut r.prep,
            frame: &r.frame,
            plan: &mut r.plan,
            args: &mut r.args,
            anchors: self.anchors.as_deref().unwrap_or(&[]),
            ws: &mut self.ws,
        })
    }

    /// The status words, plan and hits of the last device-resident increment.
    pub(crate) fn resident_outputs(&self) -> ([u32; STATUS_WORDS], &[u32], &[GpuHit]) {
        let plan = self
            .resident
            .as_ref()
            .map_or(&[][..], |r| r.plan.as_slice());
        (self.ws.status, plan, &self.ws.hits)
    }

    /// The bytes of the array holding role `buf` of a resident search (`None` for a role it
    /// does not write, or before `make_resident`), every array sized as the GPU's buffer of
    /// the same role is used: the arrays a split increment hands over.
    pub(crate) fn role_bytes(&mut self, buf: Buf) -> Option<&mut [u8]> {
        let r = self.resident.as_deref_mut()?;
        let ws = &mut self.ws;
        let n = r.prep.slaves.len();
        ws.work
            .resize(ScanLevels::new(n as u32 + 1).words as usize, 0);
        ws.best.resize(n * BEST_WORDS, 0);
        ws.walk_points.resize(n, [0; 4]);
        ws.active.resize(n + 1, 0);
        Some(match buf {
            Buf::Nodes => bytemuck::cast_slice_mut(&mut r.prep.nodes),
            Buf::Status => bytemuck::cast_slice_mut(&mut ws.status),
            Buf::Hits => bytemuck::cast_slice_mut(super::hits_mut(&mut ws.hits)),
            Buf::Reference => bytemuck::cast_slice_mut(&mut ws.reference),
            Buf::Skins => {
                ws.skins.resize(n, [0.0; 4]);
                bytemuck::cast_slice_mut(&mut ws.skins)
            }
            Buf::Plan => bytemuck::cast_slice_mut(&mut r.plan),
            Buf::Args => bytemuck::cast_slice_mut(&mut r.args),
            Buf::Boxes => bytemuck::cast_slice_mut(&mut ws.boxes),
            Buf::Work => bytemuck::cast_slice_mut(&mut ws.work),
            Buf::Best => bytemuck::cast_slice_mut(&mut ws.best),
            Buf::WalkPoints => bytemuck::cast_slice_mut(&mut ws.walk_points),
            Buf::Active => bytemuck::cast_slice_mut(&mut ws.active),
            Buf::Grid => bytemuck::cast_slice_mut(&mut ws.grid),
            _ => return None,
        })
    }

    /// Runs the search's entries of one increment (`plan::increment::search`) on `positions`
    /// (one `[f32; 4]` per model node, relative to the frame), each through its kernel's mirror
    /// (`cpu::increment`), as `GpuSearch::run_plan` does on a GPU (`global`: no motion budget).
    pub(crate) fn run_plan(
        &mut self,
        positions: &[[f32; 4]],
        read_hits: bool,
        global: bool,
    ) -> Result<PlanRan> {
        let mut shape = self.pair_shape(0, false).ok_or_else(not_resident)?;
        shape.global_only = global;
        if positions.len() != shape.n_nodes as usize {
            return Err(Error::LengthMismatch {
                what: "search positions (one per model node)",
                expected: shape.n_nodes as usize,
                got: positions.len(),
            });
        }
        self.ws.status = crate::abi::status::reset_image();
        // host positions are relative to the frame already; the increments' own origin back
        // after the run
        let r = self.resident.as_deref_mut().ok_or_else(not_resident)?;
        let own = std::mem::replace(&mut r.frame.origin, [0.0; 4]);
        let mut ran = Ok(());
        for e in crate::plan::increment::search(0, &shape) {
            let arrays = self.arrays().ok_or_else(not_resident)?;
            ran = super::increment::run_entry(&e, positions, arrays, None);
            if ran.is_err() {
                break;
            }
        }
        let r = self.resident.as_deref_mut().ok_or_else(not_resident)?;
        r.frame.origin = own;
        ran?;
        Ok(PlanRan {
            status: self.ws.status,
            plan: r.plan[..PLAN_SLOTS].to_vec(),
            hits: if read_hits {
                self.ws.hits.clone()
            } else {
                Default::default()
            },
        })
    }

    /// One global search of `prep` as it is (its params and its nodes, already in the frame),
    /// as `GpuSearch::run_prepared` runs it: the host-sized global entries
    /// (`plan::increment::prepared_global`). For tests of the kernels on inputs they prepared.
    #[doc(hidden)]
    pub fn run_prepared(&mut self, prep: &Prepared) -> Result<std::sync::Arc<Vec<GpuHit>>> {
        self.make_resident(prep, 1, false, [0.0; 3], 65_535)?;
        self.ws.status = crate::abi::status::reset_image();
        for e in crate::plan::increment::prepared_global(&prep.params) {
            let arrays = self.arrays().ok_or_else(not_resident)?;
            super::increment::run_entry(&e, &[], arrays, None)?;
        }
        Ok(self.ws.hits.clone())
    }

    /// Asks the next device-resident increment to search globally.
    pub(crate) fn request_global(&mut self) {
        if let Some(r) = self.resident.as_mut() {
            r.plan[PLAN_FORCE] = 1;
        }
    }
}

/// The error of a search run before it was made resident.
fn not_resident() -> Error {
    Error::BadParameter {
        name: "search",
        value: "not made resident".into(),
        expected: "make_resident first",
    }
}
