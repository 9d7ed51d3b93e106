//! The search part of a device-resident increment on the CPU path: the same plan as the GPU's
//! (`gpu::global_search::resident`), pass for pass through the mirrors, on f32 host arrays laid
//! out as the caller's device buffers would be.

use super::{anchor, local_search, motion, run_step, schedule, to_local, CpuSearch};
use crate::abi::search::*;
use crate::abi::status::STATUS_WORDS;
use crate::error::{Error, Result};
use crate::plan::{Prepared, STEPS};

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
}

impl CpuSearch {
    /// Readies this search for device-resident increments (see `GpuSearch::make_resident`).
    pub(crate) fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame_origin: [f32; 3],
    ) {
        let plan = fresh_plan(&prep.params, interval);
        self.ws.boxes.resize(
            crate::abi::search::box_words(prep.params.tree_levels),
            [0; 4],
        );
        self.ws.corners.resize(
            crate::abi::search::box_words(prep.params.tree_levels),
            [[0.0; 4]; 2],
        );
        super::hits_mut(&mut self.ws.hits).resize(prep.slaves.len(), GpuHit::miss(0, 0));
        self.ws.reference = prep.nodes.clone();
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
        }));
    }

    /// The status words, plan and hits of the last device-resident increment.
    pub(crate) fn resident_outputs(&self) -> ([u32; STATUS_WORDS], &[u32], &[GpuHit]) {
        let plan = self
            .resident
            .as_ref()
            .map_or(&[][..], |r| r.plan.as_slice());
        (self.ws.status, plan, &self.ws.hits)
    }

    /// The plan words of the device-resident increments (the statistics read them).
    pub(crate) fn resident_plan_mut(&mut self) -> Option<&mut [u32]> {
        self.resident.as_mut().map(|r| r.plan.as_mut_slice())
    }

    /// Asks the next device-resident increment to search globally.
    pub(crate) fn request_global(&mut self) {
        if let Some(r) = self.resident.as_mut() {
            r.plan[PLAN_FORCE] = 1;
        }
    }

    /// One device-resident increment's search on the CPU: `positions` as the caller's device
    /// buffer would hold them (`[f32; 4]` per model node, model frame). Returns the status words
    /// and the grid-local nodes and hits the penalty passes read; `plan` words are updated as
    /// the GPU's are.
    pub(crate) fn step_resident(
        &mut self,
        positions: &[[f32; 4]],
    ) -> Result<([u32; STATUS_WORDS], &Prepared, &[GpuHit])> {
        let Some(r) = self.resident.as_mut() else {
            return Err(Error::BadParameter {
                name: "device-resident increment",
                value: "a search not made resident".into(),
                expected: "make_resident first",
            });
        };
        if positions.len() < r.prep.n_nodes {
            return Err(Error::LengthMismatch {
                what: "device positions (one vec4 per model node)",
                expected: r.prep.n_nodes,
                got: positions.len(),
            });
        }
        let mut status = self.ws.status;
        crate::abi::status::reset(&mut status, crate::abi::status::Owner::Search);
        let mut params: SearchParams = bytemuck::pod_read_unaligned(bytemuck::cast_slice(
            &r.plan[PLAN_PARAMS..PLAN_PARAMS + 24],
        ));
        let prep = &mut r.prep;
        to_local::to_local(
            &params,
            &r.frame,
            positions,
            &mut prep.nodes,
            &prep.adjacency,
            &mut status,
        );
        if r.anchored {
            let anchors = self.anchors.as_deref().unwrap_or(&[]);
            anchor::anchor(
                &params,
                &prep.nodes,
                &prep.facets,
                &prep.slaves,
                anchors,
                &mut status,
                super::hits_mut(&mut self.ws.hits),
                &prep.adjacency,
            );
            self.ws.status = status;
            return Ok((status, &r.prep, &self.ws.hits));
        }
        motion::motion(
            &params,
            &prep.nodes,
            &self.ws.reference,
            &prep.motion_nodes,
            &mut status,
            &self.ws.hits,
        );
        schedule::schedule(&mut r.plan, &mut status, &mut r.args);
        params = plan_params(&r.plan);
        if r.plan[PLAN_GLOBAL] == 0 {
            local_search::local_search(
                &params,
                &prep.nodes,
                &prep.facets,
                &prep.slaves,
                &prep.adjacency,
                &mut status,
                super::hits_mut(&mut self.ws.hits),
            );
        } else {
            prep.params = params;
            self.ws.status = status;
            for step in STEPS {
                run_step(step, &params, prep, &mut self.ws);
            }
            status = self.ws.status;
            motion::set_reference(
                &params,
                &prep.nodes,
                &mut self.ws.reference,
                &prep.motion_nodes,
            );
        }
        self.ws.status = status;
        Ok((status, &r.prep, &self.ws.hits))
    }
}
