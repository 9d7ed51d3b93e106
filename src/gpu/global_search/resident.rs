//! The search part of a device-resident increment on the GPU: every pass encoded into the
//! caller's command encoder, the choice between the local and the global search made on the
//! device (`schedule.wgsl`) and carried out through indirect dispatches, nothing read back.

use super::{scan_level, GpuSearch, UNIFORM_STRIDE};
use crate::error::{Error, Result};
use crate::passes::{self, Buf};
use crate::search::layout::*;
use crate::search::Prepared;
use crate::status::Owner;
use wgpu::BufferUsages as U;

/// The dispatch slots of a search's plan: each names the byte offset of its live indirect
/// arguments in the plan buffer.
#[derive(Clone, Debug, Default)]
struct Slots {
    /// Local increments: one invocation per slave (local_search).
    local_slaves: u64,
    /// Global: one per word of the cell counts (clear_counts, copy_starts).
    cell_words: u64,
    /// Global: one per facet (bin_count, bin_scatter).
    facets: u64,
    /// Global: one per block of each level of the cell scan.
    cell_levels: Vec<u64>,
    /// Global: one per block of each level of the work-item scan.
    work_levels: Vec<u64>,
    /// Global: one per slave (nearest_count, nearest_facet).
    slaves: u64,
    /// Global: one invocation (nearest_args).
    one: u64,
    /// Global: one per watched node (set_reference).
    motion_nodes: u64,
}

/// What a search keeps for its device-resident increments.
pub(crate) struct ResidentSearch {
    schedule: wgpu::ComputePipeline,
    clear_counts: wgpu::ComputePipeline,
    set_reference: wgpu::ComputePipeline,
    /// Scan parameters of the cell levels (sized for the cell capacity) and of the work levels.
    cell_scan_params: wgpu::Buffer,
    work_scan_params: wgpu::Buffer,
    cell_levels: ScanLevels,
    work_levels: ScanLevels,
    slots: Slots,
    groups: Option<Groups>,
    n_nodes: u32,
    n_motion_nodes: u32,
    n_slaves: u32,
    anchored: bool,
}

struct Groups {
    /// The search's bind groups' generation these were built against.
    generation: u64,
    schedule: wgpu::BindGroup,
    clear_counts: wgpu::BindGroup,
    set_reference: wgpu::BindGroup,
    scan_blocks: Vec<wgpu::BindGroup>,
    scan_add: Vec<wgpu::BindGroup>,
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
    cell_levels: &ScanLevels,
    work_levels: &ScanLevels,
    n_nodes_watched: u32,
    max_dim: u32,
) -> Result<(Vec<u32>, Slots)> {
    let mut plan = vec![0u32; PLAN_WORDS];
    plan[PLAN_INTERVAL] = interval;
    plan[PLAN_NONFINITE] = u32::MAX;
    plan[PLAN_BOX..PLAN_BOX + 3].fill(u32::MAX);
    plan[PLAN_PARAMS..PLAN_PARAMS + 24].copy_from_slice(bytemuck::cast_slice(&[*params]));
    let (g, l) = (SLOT_GLOBAL, SLOT_LOCAL);
    let iw = ITEM_WORKGROUP;
    let mut slots = Slots {
        local_slaves: add_slot(&mut plan, params.n_slaves, iw, l, max_dim)?,
        cell_words: add_slot(&mut plan, params.cell_capacity + 1, iw, g, max_dim)?,
        facets: add_slot(&mut plan, params.n_facets, iw, g, max_dim)?,
        ..Default::default()
    };
    for level in &cell_levels.levels {
        slots
            .cell_levels
            .push(add_slot(&mut plan, level.1, SCAN_BLOCK, g, max_dim)?);
    }
    for level in &work_levels.levels {
        slots
            .work_levels
            .push(add_slot(&mut plan, level.1, SCAN_BLOCK, g, max_dim)?);
    }
    slots.slaves = add_slot(&mut plan, params.n_slaves, iw, g, max_dim)?;
    slots.one = add_slot(&mut plan, 1, 1, g, max_dim)?;
    slots.motion_nodes = add_slot(&mut plan, n_nodes_watched, iw, g, max_dim)?;
    Ok((plan, slots))
}

impl GpuSearch {
    /// Readies this search for device-resident increments: `prep` is a host preparation at the
    /// model's positions whose params carry the device's cell capacity and base cell size;
    /// buffers are sized for the capacities (not for positions), the pair's constants and the
    /// nodes' masses uploaded, the frame fixed at `prep`'s grid origin and a fresh plan written.
    /// `anchored`: small sliding (anchors already set; increments evaluate them).
    pub(crate) fn make_resident(
        &mut self,
        prep: &Prepared,
        interval: u32,
        anchored: bool,
    ) -> Result<()> {
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
        let made = (|| -> Result<_> {
            let module = |stem| super::super::module(d, stem);
            let (sched, count, motion) =
                (module("schedule")?, module("bin_count")?, module("motion")?);
            let pipe = |m, p| super::super::pipeline(d, m, p, &[]);
            Ok((
                pipe(&sched, &passes::SCHEDULE),
                pipe(&count, &passes::CLEAR_COUNTS),
                pipe(&motion, &passes::SET_REFERENCE),
            ))
        })();
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu {
                during: "compiling the device-resident pipelines".into(),
                message: e.to_string(),
            });
        }
        let (schedule, clear_counts, set_reference) = made?;
        let mut params = prep.params;
        if self.presize {
            self.entry_capacity = crate::cpu::presized_capacity(prep, self.entry_capacity);
        }
        params.entry_capacity = self.entry_capacity;
        params.flags |= FLAG_RESIDENT;
        let cell_levels = ScanLevels::new(params.cell_capacity + 1);
        let work_levels = ScanLevels::new(params.n_slaves + 1);
        // buffers sized for the capacity: a grid fitted on the device never needs more
        let mut sized = prep.clone();
        sized.params.n_cells = params.cell_capacity;
        self.ensure_buffers(&sized, &cell_levels)?;
        self.upload_static(prep);
        super::super::upload(
            &self.ctx,
            &self.buffers.nodes.buffer,
            0,
            bytemuck::cast_slice(&prep.nodes),
        );
        let frame = FrameParams {
            origin: [
                prep.grid.origin[0] as f32,
                prep.grid.origin[1] as f32,
                prep.grid.origin[2] as f32,
                0.0,
            ],
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
        let cell_scan_params = uniform("resident cell scan params", &cell_levels);
        let work_scan_params = uniform("resident work scan params", &work_levels);
        let (plan, slots) = initial_plan(
            &params,
            interval,
            &cell_levels,
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
        super::super::upload(
            &self.ctx,
            &self.buffers.params,
            0,
            bytemuck::bytes_of(&params),
        );
        if self.bind_groups.is_none() {
            self.bind_groups = Some(self.bind_groups(&cell_levels, &sized)?);
            self.scan_levels = cell_levels.levels.len();
            self.work_levels = work_levels.levels.len();
            self.generation += 1;
        }
        self.anchored = anchored;
        self.resident = Some(Box::new(ResidentSearch {
            schedule,
            clear_counts,
            set_reference,
            cell_scan_params,
            work_scan_params,
            cell_levels,
            work_levels,
            slots,
            groups: None,
            n_nodes: prep.n_nodes as u32,
            n_motion_nodes: prep.motion_nodes.len() as u32,
            n_slaves: params.n_slaves,
            anchored,
        }));
        self.resident_params = Some((params, sized));
        Ok(())
    }

    /// Grows the bin entries to hold `needed` (a spill seen in the statistics) and tells the
    /// plan; the spilled increments were exact, this makes the next ones fast again.
    pub(crate) fn grow_resident_entries(&mut self, needed: u32) -> Result<()> {
        let Some((mut params, sized)) = self.resident_params.clone() else {
            return Ok(());
        };
        if needed <= self.entry_capacity {
            return Ok(());
        }
        self.entry_capacity = crate::cpu::grown_capacity(needed);
        params.entry_capacity = self.entry_capacity;
        let words = crate::cpu::entry_words(self.entry_capacity, sized.facets.len()) as u64;
        if self
            .buffers
            .entries
            .ensure(&self.ctx.device, &self.ctx.limits, words * 4)?
        {
            self.bind_groups = None;
        }
        let levels = ScanLevels::new(params.cell_capacity + 1);
        if self.bind_groups.is_none() {
            self.bind_groups = Some(self.bind_groups(&levels, &sized)?);
            self.generation += 1;
        }
        // the plan's copy of the params is what the passes see
        super::super::upload(
            &self.ctx,
            &self.buffers.plan,
            4 * (PLAN_PARAMS + 10) as u64,
            bytemuck::bytes_of(&params.entry_capacity),
        );
        self.resident_params = Some((params, sized));
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

    /// The status and plan buffers (the increment's statistics read them).
    pub(crate) fn status_and_plan(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.buffers.status, &self.buffers.plan)
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
            let (scan_blocks, scan_add) = scan(
                &r.cell_scan_params,
                &self.buffers.scan.buffer,
                r.cell_levels.levels.len(),
            )?;
            let (work_scan_blocks, work_scan_add) = scan(
                &r.work_scan_params,
                &self.buffers.work.buffer,
                r.work_levels.levels.len(),
            )?;
            let group = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
                super::super::bind(d, pipe, pass, |buf| self.resource(buf))
            };
            let groups = Groups {
                generation,
                schedule: group(&r.schedule, &passes::SCHEDULE)?,
                clear_counts: group(&r.clear_counts, &passes::CLEAR_COUNTS)?,
                set_reference: group(&r.set_reference, &passes::SET_REFERENCE)?,
                scan_blocks,
                scan_add,
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
                    other => self.resource(other),
                },
            )?;
            let r = self.resident.as_mut().expect("resident");
            if let Some(g) = r.groups.as_mut() {
                g.to_local = Some((positions.clone(), group));
            }
        }
        Ok(())
    }

    /// Encodes the search part of one device-resident increment into `enc`: the caller's
    /// positions (`vec4<f32>` per model node, model frame, STORAGE usage) into the local frame,
    /// then (finite sliding) the motion budget, the schedule, and the local or the global search
    /// through the plan's indirect dispatches, or (small sliding) the anchors. Nothing is read
    /// back and nothing waits.
    pub(crate) fn encode_resident(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        positions: &wgpu::Buffer,
    ) -> Result<()> {
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
        self.resident_groups(positions)?;
        let r = self.resident.as_ref().expect("resident");
        let g = r.groups.as_ref().expect("groups built");
        let bg = self.bind_groups.as_ref().expect("bind groups built");
        let (p, b, ctx) = (&self.pipelines, &self.buffers, &self.ctx);
        let max_dim = self.max_workgroups_per_dim;
        let iw = ITEM_WORKGROUP;
        super::reset_status(enc, &b.status_reset, &b.status, Owner::Search);
        let to_local = &g.to_local.as_ref().expect("to_local bound").1;
        if r.anchored {
            super::super::run_pass(
                ctx,
                enc,
                "to_local + anchor",
                &[
                    (&p.to_local, to_local, r.n_nodes, iw),
                    (&p.anchor, &bg.anchor, r.n_slaves, iw),
                ],
                max_dim,
            );
            return Ok(());
        }
        super::super::run_pass(
            ctx,
            enc,
            "to_local + motion + schedule",
            &[
                (&p.to_local, to_local, r.n_nodes, iw),
                (&p.motion, &bg.motion, r.n_motion_nodes, iw),
                (&r.schedule, &g.schedule, 1, 1),
            ],
            max_dim,
        );
        // the schedule's params (the fitted grid) are what every later pass reads
        enc.copy_buffer_to_buffer(
            &b.plan,
            4 * PLAN_PARAMS as u64,
            &b.params,
            0,
            std::mem::size_of::<SearchParams>() as u64,
        );
        let s = &r.slots;
        let mut global: Vec<super::super::IndirectWork<'_>> = vec![
            (&p.local_search, &bg.local_search, s.local_slaves),
            (&r.clear_counts, &g.clear_counts, s.cell_words),
            (&p.bin_count, &bg.bin_count, s.facets),
        ];
        for (i, &slot) in s.cell_levels.iter().enumerate() {
            global.push((&p.scan_blocks, &g.scan_blocks[i], slot));
        }
        for i in (0..s.cell_levels.len().saturating_sub(1)).rev() {
            global.push((&p.scan_add, &g.scan_add[i], s.cell_levels[i]));
        }
        global.push((&p.copy_starts, &bg.copy_starts, s.cell_words));
        global.push((&p.bin_scatter, &bg.bin_scatter, s.facets));
        global.push((&p.nearest_count, &bg.nearest_count, s.slaves));
        for (i, &slot) in s.work_levels.iter().enumerate() {
            global.push((&p.scan_blocks, &g.work_scan_blocks[i], slot));
        }
        for i in (0..s.work_levels.len().saturating_sub(1)).rev() {
            global.push((&p.scan_add, &g.work_scan_add[i], s.work_levels[i]));
        }
        global.push((&p.nearest_args, &bg.nearest_args, s.one));
        super::super::run_indirect_pass(ctx, enc, "local or global search", &global, &b.plan);
        let mut chunks = vec![
            (&p.nearest_chunks, &bg.nearest_chunks, 0),
            (&p.nearest_ties, &bg.nearest_ties, 0),
        ];
        if self
            .resident_params
            .as_ref()
            .is_some_and(|(q, _)| q.flags & FLAG_SELF_CONTACT != 0)
        {
            chunks.push((&p.nearest_crowded, &bg.nearest_crowded, 0));
        }
        super::super::run_indirect_pass(ctx, enc, "nearest_facet: chunks", &chunks, &b.args);
        super::super::run_indirect_pass(
            ctx,
            enc,
            "nearest_facet + set_reference",
            &[
                (&p.nearest_facet, &bg.nearest_facet, s.slaves),
                (&r.set_reference, &g.set_reference, s.motion_nodes),
            ],
            &b.plan,
        );
        Ok(())
    }
}
