//! The search part of a device-resident increment on the GPU: every pass encoded into the
//! caller's command encoder, the choice between the local and the global search made on the
//! device (`schedule.wgsl`) and carried out through indirect dispatches, nothing read back.

use super::{scan_level, tree_pass, GpuSearch, STATUS_BYTES, UNIFORM_STRIDE};
use crate::abi::passes::{self, Buf};
use crate::abi::search::*;
use crate::error::{Error, Result};
use crate::plan::increment::{initial_plan, Entry, Kernel, PairShape, Slots};
use crate::plan::Prepared;
use wgpu::BufferUsages as U;

/// What a search keeps for its device-resident increments.
pub(crate) struct ResidentSearch {
    schedule: wgpu::ComputePipeline,
    set_reference: wgpu::ComputePipeline,
    active_mark: wgpu::ComputePipeline,
    active_compact: wgpu::ComputePipeline,
    /// Scan parameters of the work levels.
    work_scan_params: wgpu::Buffer,
    work_levels: ScanLevels,
    /// Refit passes of the tree.
    tree_passes: usize,
    /// Self-contact: the crowding pass runs.
    self_contact: bool,
    /// The bucket search's pipelines and scan parameters (`None` with the tree).
    buckets: Option<BucketPipes>,
    slots: Slots,
    groups: Option<Groups>,
    n_nodes: u32,
    n_motion_nodes: u32,
    n_slaves: u32,
    anchored: bool,
    /// The origin to_local subtracts in the increments' frame (f32, model units).
    pub(super) frame_origin: [f32; 3],
}

/// The bucket search's pipelines (`buckets.wgsl`) and the scan parameters of its bucket words.
struct BucketPipes {
    clear: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    fill: wgpu::ComputePipeline,
    walk: wgpu::ComputePipeline,
    crowded: wgpu::ComputePipeline,
    scan_params: wgpu::Buffer,
    levels: usize,
}

/// The bucket search's bind groups.
struct BucketGroups {
    clear: wgpu::BindGroup,
    count: wgpu::BindGroup,
    fill: wgpu::BindGroup,
    walk: wgpu::BindGroup,
    crowded: wgpu::BindGroup,
    scan_blocks: Vec<wgpu::BindGroup>,
    scan_add: Vec<wgpu::BindGroup>,
}

/// The bind groups of a search's device-resident passes: every pass that reads `SearchParams`
/// binds the plan's params words (so the schedule's grid is what it sees, with no copy).
struct Groups {
    /// The search's bind groups' generation these were built against.
    generation: u64,
    schedule: wgpu::BindGroup,
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
    active_mark: wgpu::BindGroup,
    active_compact: wgpu::BindGroup,
    work_scan_blocks: Vec<wgpu::BindGroup>,
    work_scan_add: Vec<wgpu::BindGroup>,
    /// The bucket search's (`None` with the tree).
    buckets: Option<BucketGroups>,
    /// The passes that read the caller's positions buffer, on that buffer.
    positions: Option<(wgpu::Buffer, PositionGroups)>,
}

/// The bind groups of the passes that read the caller's positions (built once per buffer).
struct PositionGroups {
    to_local: wgpu::BindGroup,
    motion: wgpu::BindGroup,
}

impl GpuSearch {
    /// Readies this search for device-resident increments: `prep` is a host preparation whose
    /// params carry the device's cell capacity and base cell size and whose nodes are in the
    /// kernels' frame; buffers are sized for the capacities (not for positions), the pair's
    /// constants, the nodes' masses and the budget's start reference uploaded, `frame_origin`
    /// subtracted by to_local from the positions it reads, and a fresh plan written.
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
        let active_mark = ctx.pipeline(&passes::ACTIVE_MARK, &[])?;
        let active_compact = ctx.pipeline(&passes::ACTIVE_COMPACT, &[])?;
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
        super::super::upload(
            &self.ctx,
            &self.buffers.reference.buffer,
            0,
            bytemuck::cast_slice(&prep.start_reference()),
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
        let buckets = if params.flags & FLAG_BUCKETS != 0 {
            let levels = crate::abi::buckets::BucketLayout::new(params.n_facets).levels;
            Some(BucketPipes {
                clear: ctx.pipeline(&passes::BUCKET_CLEAR, &[])?,
                count: ctx.pipeline(&passes::BUCKET_COUNT, &[])?,
                fill: ctx.pipeline(&passes::BUCKET_FILL, &[])?,
                walk: ctx.pipeline(&passes::BUCKET_WALK, &[])?,
                crowded: ctx.pipeline(&passes::BUCKET_CROWDED, &[])?,
                scan_params: uniform("resident bucket scan params", &levels),
                levels: levels.levels.len(),
            })
        } else {
            None
        };
        let (plan, slots) = initial_plan(
            &params,
            interval,
            prep.motion_nodes.len() as u32,
            prep.n_nodes as u32,
            self.max_workgroups_per_dim,
        )?;
        super::super::upload(
            &self.ctx,
            &self.buffers.plan,
            0,
            bytemuck::cast_slice(&plan),
        );
        self.resident = Some(Box::new(ResidentSearch {
            schedule,
            set_reference,
            active_mark,
            active_compact,
            work_scan_params,
            work_levels,
            tree_passes: tree_passes(params.tree_levels).len(),
            self_contact: params.flags & FLAG_SELF_CONTACT != 0,
            buckets,
            slots,
            groups: None,
            n_nodes: prep.n_nodes as u32,
            n_motion_nodes: prep.motion_nodes.len() as u32,
            n_slaves: params.n_slaves,
            anchored,
            frame_origin,
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
            &self.buffers.status.buffer,
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
            let buckets = match r.buckets.as_ref() {
                Some(bp) => {
                    let (scan_blocks, scan_add) =
                        scan(&bp.scan_params, &self.buffers.grid.buffer, bp.levels)?;
                    Some(BucketGroups {
                        clear: group(&bp.clear, &passes::BUCKET_CLEAR)?,
                        count: group(&bp.count, &passes::BUCKET_COUNT)?,
                        fill: group(&bp.fill, &passes::BUCKET_FILL)?,
                        walk: group(&bp.walk, &passes::BUCKET_WALK)?,
                        crowded: group(&bp.crowded, &passes::BUCKET_CROWDED)?,
                        scan_blocks,
                        scan_add,
                    })
                }
                None => None,
            };
            let groups = Groups {
                generation,
                schedule: group(&r.schedule, &passes::SCHEDULE)?,
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
                active_mark: group(&r.active_mark, &passes::ACTIVE_MARK)?,
                active_compact: group(&r.active_compact, &passes::ACTIVE_COMPACT)?,
                work_scan_blocks,
                work_scan_add,
                buckets,
                positions: None,
            };
            self.resident.as_mut().expect("resident").groups = Some(groups);
        }
        let r = self.resident.as_ref().expect("resident");
        let fresh =
            matches!(&r.groups, Some(Groups { positions: Some((b, _)), .. }) if b == positions);
        if !fresh {
            let group = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
                super::super::bind(d, pipe, pass, |buf| match buf {
                    Buf::Positions => Some(positions.as_entire_binding()),
                    other => self.resident_resource(other),
                })
            };
            let made = PositionGroups {
                to_local: group(&self.pipelines.to_local, &passes::TO_LOCAL)?,
                motion: group(&self.pipelines.motion, &passes::MOTION)?,
            };
            let r = self.resident.as_mut().expect("resident");
            if let Some(g) = r.groups.as_mut() {
                g.positions = Some((positions.clone(), made));
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
        enc.copy_buffer_to_buffer(&b.status_reset, 0, &b.status.buffer, 0, STATUS_BYTES);
    }

    /// The shape of this search's part of an increment (`None` before `make_resident`).
    pub(crate) fn pair_shape(&self, n_pair_nodes: u32, local_only: bool) -> Option<PairShape> {
        let r = self.resident.as_ref()?;
        Some(PairShape {
            anchored: r.anchored,
            self_contact: r.self_contact,
            buckets: r.buckets.is_some(),
            local_only,
            global_only: false,
            n_nodes: r.n_nodes,
            n_motion_nodes: r.n_motion_nodes,
            n_slaves: r.n_slaves,
            n_pair_nodes,
            gather_active: false,
            slots: r.slots.clone(),
        })
    }

    /// The dispatch of entry `e` if it is a search kernel (after `prepare_resident` and
    /// `resident_copies`): the pipeline and bind group of its kernel and level, sized by the
    /// entry — indirect from the plan's slot or the chunk arguments for what the device decides.
    pub(crate) fn dispatch(&self, e: &Entry) -> Option<super::super::Dispatch<'_>> {
        let r = self.resident.as_ref()?;
        let g = r.groups.as_ref()?;
        let p = &self.pipelines;
        let (pipe, group) = match e.kernel {
            Kernel::ToLocal => (&p.to_local, &g.positions.as_ref()?.1.to_local),
            Kernel::Anchor => (&p.anchor, &g.anchor),
            Kernel::Motion => (&p.motion, &g.positions.as_ref()?.1.motion),
            Kernel::Schedule => (&r.schedule, &g.schedule),
            Kernel::LocalSearch => (&p.local_search, &g.local_search),
            Kernel::TreeRefit => (&p.tree_refit, g.tree_refit.get(e.level)?),
            Kernel::WalkStart => (&p.walk_start, &g.walk_start),
            Kernel::NearestWalk => (&p.nearest_walk, &g.nearest_walk),
            Kernel::ScanBlocks => (&p.scan_blocks, g.work_scan_blocks.get(e.level)?),
            Kernel::ScanAdd => (&p.scan_add, g.work_scan_add.get(e.level)?),
            Kernel::NearestArgs => (&p.nearest_args, &g.nearest_args),
            Kernel::NearestChunks => (&p.nearest_chunks, &g.nearest_chunks),
            Kernel::NearestTies => (&p.nearest_ties, &g.nearest_ties),
            Kernel::NearestCrowded => (&p.nearest_crowded, &g.nearest_crowded),
            Kernel::NearestFacet => (&p.nearest_facet, &g.nearest_facet),
            Kernel::SetReference => (&r.set_reference, &g.set_reference),
            Kernel::ActiveMark => (&r.active_mark, &g.active_mark),
            Kernel::ActiveCompact => (&r.active_compact, &g.active_compact),
            Kernel::BucketClear => (&r.buckets.as_ref()?.clear, &g.buckets.as_ref()?.clear),
            Kernel::BucketCount => (&r.buckets.as_ref()?.count, &g.buckets.as_ref()?.count),
            Kernel::BucketScanBlocks => (
                &p.scan_blocks,
                g.buckets.as_ref()?.scan_blocks.get(e.level)?,
            ),
            Kernel::BucketScanAdd => (&p.scan_add, g.buckets.as_ref()?.scan_add.get(e.level)?),
            Kernel::BucketFill => (&r.buckets.as_ref()?.fill, &g.buckets.as_ref()?.fill),
            Kernel::BucketWalk => (&r.buckets.as_ref()?.walk, &g.buckets.as_ref()?.walk),
            Kernel::BucketCrowded => (&r.buckets.as_ref()?.crowded, &g.buckets.as_ref()?.crowded),
            _ => return None,
        };
        Some(super::super::entry_dispatch(
            pipe,
            group,
            e.size,
            &self.buffers.plan,
            &self.buffers.args,
        ))
    }
}
