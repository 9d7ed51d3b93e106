//! The search part of a device-resident increment on the GPU: every pass encoded into the
//! caller's command encoder, the choice between the local and the global search made on the
//! device (`schedule.wgsl`) and carried out through indirect dispatches, nothing read back.

use super::{scan_level, tree_pass, GpuSearch, UNIFORM_STRIDE};
use crate::abi::groups;
use crate::abi::passes::{self, Buf};
use crate::abi::search::*;
use crate::error::{Error, Result};
use crate::plan::Prepared;
use wgpu::BufferUsages as U;

/// The dispatch slots of a search's plan: each names the byte offset of its live indirect
/// arguments in the plan buffer.
#[derive(Clone, Debug, Default)]
struct Slots {
    /// Local increments: one invocation per slave (local_search).
    local_slaves: u64,
    /// Global: one per node of each refit pass's bottom level (tree_refit).
    tree_passes: Vec<u64>,
    /// Global: one per block of each level of the work-item scan.
    work_levels: Vec<u64>,
    /// Global: one per slave (nearest_walk, nearest_crowded, nearest_facet).
    slaves: u64,
    /// Global: one per group of `WALK_GROUP` slaves (walk_start).
    slave_groups: u64,
    /// Global: one invocation (nearest_args).
    one: u64,
    /// Global: one per watched node (set_reference).
    motion_nodes: u64,
}

/// What a search keeps for its device-resident increments.
pub(crate) struct ResidentSearch {
    schedule: wgpu::ComputePipeline,
    set_reference: wgpu::ComputePipeline,
    /// Scan parameters of the work levels.
    work_scan_params: wgpu::Buffer,
    work_levels: ScanLevels,
    /// Refit passes of the tree.
    tree_passes: usize,
    /// Self-contact: the crowding pass runs.
    self_contact: bool,
    slots: Slots,
    groups: Option<Groups>,
    n_nodes: u32,
    n_motion_nodes: u32,
    n_slaves: u32,
    anchored: bool,
}

/// The bind groups of a search's device-resident passes: every pass that reads `SearchParams`
/// binds the plan's params words (so the schedule's grid is what it sees, with no copy).
struct Groups {
    /// The search's bind groups' generation these were built against.
    generation: u64,
    schedule: wgpu::BindGroup,
    motion: wgpu::BindGroup,
    anchor: wgpu::BindGroup,
    local_search: wgpu::BindGroup,
    tree_refit: Vec<wgpu::BindGroup>,
    walk_start: wgpu::BindGroup,
    nearest_walk: wgpu::BindGroup,
    nearest_args: wgpu::BindGroup,
    nearest_chunks: wgpu::BindGroup,
    nearest_ties: wgpu::BindGroup,
    nearest_crowded: wgpu::BindGroup,
    nearest_facet: wgpu::BindGroup,
    set_reference: wgpu::BindGroup,
    work_scan_blocks: Vec<wgpu::BindGroup>,
    work_scan_add: Vec<wgpu::BindGroup>,
    /// to_local on the caller's positions buffer.
    to_local: Option<(wgpu::Buffer, wgpu::BindGroup)>,
}

/// Appends a slot of `items` items, `per` per workgroup, of `kind` to the plan words; returns
/// the byte offset of its live arguments.
fn add_slot(plan: &mut [u32], items: u32, per: u32, kind: u32, max_dim: u32) -> Result<u64> {
    let k = plan[PLAN_N_SLOTS] as usize;
    if k >= MAX_PLAN_SLOTS {
        return Err(Error::Gpu {
            during: "planning a device-resident increment".into(),
            message: format!("more than {MAX_PLAN_SLOTS} dispatch slots"),
        });
    }
    let (x, y) = fold_dispatch(items, per, max_dim);
    let s = PLAN_SLOTS + k * PLAN_SLOT_WORDS;
    plan[s..s + 8].copy_from_slice(&[0, 0, 0, 0, x, y, 1, kind]);
    plan[PLAN_N_SLOTS] += 1;
    Ok(4 * s as u64)
}

/// The words of a fresh plan for `params` (the device's grid, flags and capacities) and a
/// schedule interval, with its dispatch slots.
fn initial_plan(
    params: &SearchParams,
    interval: u32,
    work_levels: &ScanLevels,
    n_nodes_watched: u32,
    max_dim: u32,
) -> Result<(Vec<u32>, Slots)> {
    let mut plan = fresh_plan(params, interval);
    let (g, l) = (SLOT_GLOBAL, SLOT_LOCAL);
    let iw = ITEM_WORKGROUP;
    let mut slots = Slots {
        local_slaves: add_slot(&mut plan, params.n_slaves, iw, l, max_dim)?,
        ..Default::default()
    };
    for tp in tree_passes(params.tree_levels) {
        slots.tree_passes.push(add_slot(
            &mut plan,
            1 << tp.bottom,
            TREE_WORKGROUP,
            g,
            max_dim,
        )?);
    }
    for level in &work_levels.levels {
        slots
            .work_levels
            .push(add_slot(&mut plan, level.1, SCAN_BLOCK, g, max_dim)?);
    }
    slots.slaves = add_slot(&mut plan, params.n_slaves, iw, g, max_dim)?;
    slots.slave_groups = add_slot(
        &mut plan,
        params.n_slaves.div_ceil(WALK_GROUP),
        iw,
        g,
        max_dim,
    )?;
    slots.one = add_slot(&mut plan, 1, 1, g, max_dim)?;
    slots.motion_nodes = add_slot(&mut plan, n_nodes_watched, iw, g, max_dim)?;
    Ok((plan, slots))
}

impl GpuSearch {
    /// Readies this search for device-resident increments: `prep` is a host preparation whose
    /// params carry the device's cell capacity and base cell size and whose nodes are in the
    /// kernels' frame; buffers are sized for the capacities (not for positions), the pair's
    /// constants and the nodes' masses uploaded, `frame_origin` subtracted by to_local from the
    /// positions it reads, and a fresh plan written.
    /// `anchored`: small sliding (anchors already set; increments evaluate them).
    pub(crate) fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
        frame_origin: [f32; 3],
    ) -> Result<()> {
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        let schedule = ctx.pipeline(&passes::SCHEDULE, &[])?;
        let set_reference = ctx.pipeline(&passes::SET_REFERENCE, &[])?;
        let params = prep.params;
        let work_levels = ScanLevels::new(params.n_slaves + 1);
        let sized = prep.clone();
        self.ensure_buffers(&sized)?;
        self.upload_static(prep);
        for (i, tp) in tree_passes(params.tree_levels).iter().enumerate() {
            super::super::upload(
                &self.ctx,
                &self.buffers.tree_params.buffer,
                i as u64 * UNIFORM_STRIDE,
                bytemuck::bytes_of(tp),
            );
        }
        super::super::upload(
            &self.ctx,
            &self.buffers.nodes.buffer,
            0,
            bytemuck::cast_slice(&prep.nodes),
        );
        let frame = FrameParams {
            origin: [frame_origin[0], frame_origin[1], frame_origin[2], 0.0],
            n_nodes: prep.n_nodes as u32,
            _pad: [0; 3],
        };
        super::super::upload(&self.ctx, &self.frame, 0, bytemuck::bytes_of(&frame));
        let uniform = |label, levels: &ScanLevels| {
            let buffer = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: levels.levels.len() as u64 * UNIFORM_STRIDE,
                usage: U::UNIFORM | U::COPY_DST,
                mapped_at_creation: false,
            });
            for i in 0..levels.levels.len() {
                super::super::upload(
                    &self.ctx,
                    &buffer,
                    i as u64 * UNIFORM_STRIDE,
                    bytemuck::bytes_of(&levels.params(i)),
                );
            }
            buffer
        };
        let work_scan_params = uniform("resident work scan params", &work_levels);
        let (plan, slots) = initial_plan(
            &params,
            interval,
            &work_levels,
            prep.motion_nodes.len() as u32,
            self.max_workgroups_per_dim,
        )?;
        super::super::upload(
            &self.ctx,
            &self.buffers.plan,
            0,
            bytemuck::cast_slice(&plan),
        );
        if self.bind_groups.is_none() {
            self.bind_groups = Some(self.bind_groups(&sized)?);
            self.tree_levels = Some(params.tree_levels);
            self.work_levels = work_levels.levels.len();
            self.generation += 1;
        }
        self.anchored = anchored;
        self.resident = Some(Box::new(ResidentSearch {
            schedule,
            set_reference,
            work_scan_params,
            work_levels,
            tree_passes: tree_passes(params.tree_levels).len(),
            self_contact: params.flags & FLAG_SELF_CONTACT != 0,
            slots,
            groups: None,
            n_nodes: prep.n_nodes as u32,
            n_motion_nodes: prep.motion_nodes.len() as u32,
            n_slaves: params.n_slaves,
            anchored,
        }));
        Ok(())
    }

    /// Asks the next device-resident increment to search globally (one small upload).
    pub(crate) fn request_global(&self) {
        super::super::upload(
            &self.ctx,
            &self.buffers.plan,
            4 * PLAN_FORCE as u64,
            bytemuck::bytes_of(&1u32),
        );
    }

    /// The status, plan and hits buffers (read back for the output variables).
    pub(crate) fn resident_outputs(&self) -> (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer) {
        (
            &self.buffers.status,
            &self.buffers.plan,
            &self.buffers.hits.buffer,
        )
    }

    /// The plan's params words as a uniform binding.
    fn plan_params(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffers.plan,
            offset: 4 * PLAN_PARAMS as u64,
            size: wgpu::BufferSize::new(std::mem::size_of::<SearchParams>() as u64),
        })
    }

    /// The buffer of each role in a device-resident pass.
    fn resident_resource(&self, buf: Buf) -> Option<wgpu::BindingResource<'_>> {
        match buf {
            Buf::SearchParams => Some(self.plan_params()),
            other => self.resource(other),
        }
    }

    fn resident_groups(&mut self, positions: &wgpu::Buffer) -> Result<()> {
        let generation = self.generation;
        let r = self.resident.as_ref().expect("resident");
        let stale = r.groups.as_ref().is_none_or(|g| g.generation != generation);
        let d = &self.ctx.device;
        if stale {
            let scan = |params: &wgpu::Buffer, data: &wgpu::Buffer, n: usize| {
                let level = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass, i: usize| {
                    super::super::bind(d, pipe, pass, |buf| match buf {
                        Buf::ScanParams => Some(scan_level(params, i)),
                        Buf::ScanData => Some(data.as_entire_binding()),
                        _ => None,
                    })
                };
                let blocks = (0..n)
                    .map(|i| level(&self.pipelines.scan_blocks, &passes::SCAN_BLOCKS, i))
                    .collect::<Result<Vec<_>>>()?;
                let add = (0..n)
                    .map(|i| level(&self.pipelines.scan_add, &passes::SCAN_ADD, i))
                    .collect::<Result<Vec<_>>>()?;
                Ok::<_, Error>((blocks, add))
            };
            let (work_scan_blocks, work_scan_add) = scan(
                &r.work_scan_params,
                &self.buffers.work.buffer,
                r.work_levels.levels.len(),
            )?;
            let group = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
                super::super::bind(d, pipe, pass, |buf| self.resident_resource(buf))
            };
            let p = &self.pipelines;
            let tree_refit = (0..r.tree_passes)
                .map(|i| {
                    super::super::bind(d, &p.tree_refit, &passes::TREE_REFIT, |buf| match buf {
                        Buf::TreeParams => Some(tree_pass(&self.buffers.tree_params.buffer, i)),
                        other => self.resident_resource(other),
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            let groups = Groups {
                generation,
                schedule: group(&r.schedule, &passes::SCHEDULE)?,
                motion: group(&p.motion, &passes::MOTION)?,
                anchor: group(&p.anchor, &passes::ANCHOR)?,
                local_search: group(&p.local_search, &passes::LOCAL_SEARCH)?,
                tree_refit,
                walk_start: group(&p.walk_start, &passes::WALK_START)?,
                nearest_walk: group(&p.nearest_walk, &passes::NEAREST_WALK)?,
                nearest_args: group(&p.nearest_args, &passes::NEAREST_ARGS)?,
                nearest_chunks: group(&p.nearest_chunks, &passes::NEAREST_CHUNKS)?,
                nearest_ties: group(&p.nearest_ties, &passes::NEAREST_TIES)?,
                nearest_crowded: group(&p.nearest_crowded, &passes::NEAREST_CROWDED)?,
                nearest_facet: group(&p.nearest_facet, &passes::NEAREST_FACET)?,
                set_reference: group(&r.set_reference, &passes::SET_REFERENCE)?,
                work_scan_blocks,
                work_scan_add,
                to_local: None,
            };
            self.resident.as_mut().expect("resident").groups = Some(groups);
        }
        let r = self.resident.as_ref().expect("resident");
        let fresh =
            matches!(&r.groups, Some(Groups { to_local: Some((b, _)), .. }) if b == positions);
        if !fresh {
            let group = super::super::bind(
                d,
                &self.pipelines.to_local,
                &passes::TO_LOCAL,
                |buf| match buf {
                    Buf::Positions => Some(positions.as_entire_binding()),
                    other => self.resident_resource(other),
                },
            )?;
            let r = self.resident.as_mut().expect("resident");
            if let Some(g) = r.groups.as_mut() {
                g.to_local = Some((positions.clone(), group));
            }
        }
        Ok(())
    }

    /// Readies the search part of a device-resident increment on the caller's positions
    /// (`vec4<f32>` per model node, model frame, STORAGE usage): checks the buffer, builds the
    /// bind groups it needs (once per buffer).
    pub(crate) fn prepare_resident(&mut self, positions: &wgpu::Buffer) -> Result<()> {
        let Some(r) = self.resident.as_ref() else {
            return Err(Error::BadParameter {
                name: "device-resident increment",
                value: "a search not made resident".into(),
                expected: "make_resident first",
            });
        };
        let need = r.n_nodes as u64 * 16;
        if positions.size() < need || !positions.usage().contains(U::STORAGE) {
            return Err(Error::BadParameter {
                name: "device positions",
                value: format!(
                    "buffer of {} bytes, usage {:?}",
                    positions.size(),
                    positions.usage()
                ),
                expected: "one vec4<f32> per model node and STORAGE usage",
            });
        }
        self.resident_groups(positions)
    }

    /// Encodes the copy before the increment's compute pass: every status word reset (the
    /// search's and the penalty passes' that follow it in the same increment), in one copy.
    pub(crate) fn resident_copies(&self, enc: &mut wgpu::CommandEncoder) {
        let b = &self.buffers;
        enc.copy_buffer_to_buffer(&b.status_reset, 0, &b.status, 0, b.status.size());
    }

    /// The dispatches of the search part of one device-resident increment (after
    /// `prepare_resident` and `resident_copies`): the positions into the local frame, then
    /// (finite sliding) the motion budget, the schedule and the local or the global search
    /// through the plan's indirect dispatches, or (small sliding) the anchors. `local_only`:
    /// the caller knows the schedule will choose the local search (host arrays, whose host
    /// checks the same rules with margin), so the global search's dispatches, which would get
    /// zero workgroups, are not recorded at all.
    pub(crate) fn resident_dispatches(&self, local_only: bool) -> Vec<super::super::GroupWork<'_>> {
        use super::super::Dispatch::{Direct, Indirect};
        let r = self.resident.as_ref().expect("resident");
        let g = r.groups.as_ref().expect("prepared");
        let (p, b) = (&self.pipelines, &self.buffers);
        let iw = ITEM_WORKGROUP;
        let to_local = &g.to_local.as_ref().expect("prepared").1;
        if r.anchored {
            return vec![(
                &groups::TO_LOCAL_ANCHOR,
                vec![
                    Direct((&p.to_local, to_local, r.n_nodes, iw)),
                    Direct((&p.anchor, &g.anchor, r.n_slaves, iw)),
                ],
            )];
        }
        let s = &r.slots;
        let plan = &b.plan;
        let mut global: Vec<_> = s
            .tree_passes
            .iter()
            .zip(&g.tree_refit)
            .map(|(&slot, group)| Indirect(&p.tree_refit, group, plan, slot))
            .collect();
        global.push(Indirect(&p.walk_start, &g.walk_start, plan, s.slave_groups));
        global.push(Indirect(&p.nearest_walk, &g.nearest_walk, plan, s.slaves));
        for (i, &slot) in s.work_levels.iter().enumerate() {
            global.push(Indirect(&p.scan_blocks, &g.work_scan_blocks[i], plan, slot));
        }
        for i in (0..s.work_levels.len().saturating_sub(1)).rev() {
            global.push(Indirect(
                &p.scan_add,
                &g.work_scan_add[i],
                plan,
                s.work_levels[i],
            ));
        }
        global.push(Indirect(&p.nearest_args, &g.nearest_args, plan, s.one));
        global.push(Indirect(&p.nearest_chunks, &g.nearest_chunks, &b.args, 0));
        global.push(Indirect(&p.nearest_ties, &g.nearest_ties, &b.args, 0));
        if r.self_contact {
            global.push(Indirect(
                &p.nearest_crowded,
                &g.nearest_crowded,
                plan,
                s.slaves,
            ));
        }
        global.push(Indirect(&p.nearest_facet, &g.nearest_facet, plan, s.slaves));
        global.push(Indirect(
            &r.set_reference,
            &g.set_reference,
            plan,
            s.motion_nodes,
        ));
        let mut groups = vec![
            (
                &groups::TO_LOCAL_MOTION_SCHEDULE,
                vec![
                    Direct((&p.to_local, to_local, r.n_nodes, iw)),
                    Direct((&p.motion, &g.motion, r.n_motion_nodes, iw)),
                    Direct((&r.schedule, &g.schedule, 1, 1)),
                ],
            ),
            (
                &groups::LOCAL,
                vec![Indirect(
                    &p.local_search,
                    &g.local_search,
                    plan,
                    s.local_slaves,
                )],
            ),
        ];
        if !local_only {
            groups.push((&groups::GLOBAL_SEARCH, global));
        }
        groups
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plan's slots hold the largest search there can be: a tree of 32 levels (one refit
    /// pass per level, 33) and the most slaves a u32 counts (four scan levels); with one level
    /// fewer per pass this was where 16 slots ran out.
    #[test]
    fn the_largest_search_fits_the_plan() {
        for (levels, slaves) in [(0, 1), (17, 1_000_000), (32, u32::MAX - 1)] {
            let params = SearchParams {
                tree_levels: levels,
                n_slaves: slaves,
                ..bytemuck::Zeroable::zeroed()
            };
            let work = ScanLevels::new(slaves + 1);
            let (plan, slots) = initial_plan(&params, 100, &work, slaves, 65_535)
                .unwrap_or_else(|e| panic!("{levels} levels, {slaves} slaves: {e}"));
            assert_eq!(slots.tree_passes.len(), levels as usize + 1);
            assert!(plan[PLAN_N_SLOTS] as usize <= MAX_PLAN_SLOTS);
        }
    }
}
