//! The GPU executor of the global search: the tree's refit and the nearest-facet passes in one
//! command encoder and one submit.

use std::sync::Arc;

use super::buffers::{read_back, read_back_with, GrowBuffer};
use crate::abi::groups;
use crate::abi::passes::{self, Buf};
use crate::abi::search::{box_words, BEST_WORDS};
use crate::abi::search::{
    tree_passes, Anchor, FrameParams, GpuHit, ScanLevels, ScanParams, SearchParams, TreeParams,
    ITEM_WORKGROUP, SCAN_BLOCK, TREE_WORKGROUP,
};
use crate::abi::status::STATUS_WORDS;
use crate::abi::status::{owned_runs, Owner};
use crate::cpu::CpuWorkspace;
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::plan::{Prepared, Step, STEPS};
use wgpu::BufferUsages as U;

mod resident;

const STATUS_BYTES: u64 = (STATUS_WORDS * 4) as u64;

/// The search's buffers that later passes of the same increment bind.
pub struct SharedBuffers<'a> {
    /// Grid-local node positions (w: mass).
    pub nodes: &'a wgpu::Buffer,
    /// Active facets.
    pub facets: &'a wgpu::Buffer,
    /// One hit per slave.
    pub hits: &'a wgpu::Buffer,
    /// Status words.
    pub status: &'a wgpu::Buffer,
}

/// Readback layout: status words, then the hits.
const READBACK_HITS_OFFSET: u64 = STATUS_BYTES.next_multiple_of(16);
/// Uniform offsets must be multiples of this (WebGPU's default alignment).
const UNIFORM_STRIDE: u64 = 256;

struct Pipelines {
    tree_refit: wgpu::ComputePipeline,
    scan_blocks: wgpu::ComputePipeline,
    scan_add: wgpu::ComputePipeline,
    walk_start: wgpu::ComputePipeline,
    nearest_walk: wgpu::ComputePipeline,
    nearest_args: wgpu::ComputePipeline,
    nearest_chunks: wgpu::ComputePipeline,
    nearest_ties: wgpu::ComputePipeline,
    nearest_crowded: wgpu::ComputePipeline,
    nearest_facet: wgpu::ComputePipeline,
    local_search: wgpu::ComputePipeline,
    motion: wgpu::ComputePipeline,
    to_local: wgpu::ComputePipeline,
    anchor: wgpu::ComputePipeline,
}

struct BindGroups {
    anchor: wgpu::BindGroup,
    local_search: wgpu::BindGroup,
    motion: wgpu::BindGroup,
    /// One per refit pass of the tree.
    tree_refit: Vec<wgpu::BindGroup>,
    walk_start: wgpu::BindGroup,
    nearest_walk: wgpu::BindGroup,
    work_scan_blocks: Vec<wgpu::BindGroup>,
    work_scan_add: Vec<wgpu::BindGroup>,
    nearest_args: wgpu::BindGroup,
    nearest_chunks: wgpu::BindGroup,
    nearest_ties: wgpu::BindGroup,
    nearest_crowded: wgpu::BindGroup,
    nearest_facet: wgpu::BindGroup,
}

struct Buffers {
    params: wgpu::Buffer,
    /// `TreeParams` of each refit pass, one every `UNIFORM_STRIDE` bytes.
    tree_params: GrowBuffer,
    nodes: GrowBuffer,
    facets: GrowBuffer,
    slaves: GrowBuffer,
    /// The slaves' positions and node ids in walk order (`walk_start`).
    walk_points: GrowBuffer,
    /// The search tree's leaf order.
    order: GrowBuffer,
    /// The search tree's boxes.
    boxes: GrowBuffer,
    status: wgpu::Buffer,
    status_reset: wgpu::Buffer,
    hits: GrowBuffer,
    readback: GrowBuffer,
    reference: GrowBuffer,
    adjacency: GrowBuffer,
    motion_nodes: GrowBuffer,
    anchors: GrowBuffer,
    /// Nearest-facet work items: chunk counts per slave, scanned (all scan levels).
    work: GrowBuffer,
    /// Scan parameters of each level of `work`.
    work_scan_params: GrowBuffer,
    /// Nearest-facet record per slave (4 words).
    best: GrowBuffer,
    /// The indirect dispatch of the nearest-facet work items (x, y, z).
    args: wgpu::Buffer,
    /// The device-resident plan (`PLAN_*` words); to_local raises the master box into it.
    plan: wgpu::Buffer,
}

/// The global search on one GPU device; its buffers grow as needed and are reused.
pub struct GpuSearch {
    ctx: Arc<GpuContext>,
    pipelines: Pipelines,
    buffers: Buffers,
    bind_groups: Option<BindGroups>,
    /// Tree levels the bind groups and tree parameters were built for.
    tree_levels: Option<u32>,
    /// Number of work-item scan levels the bind groups were built for.
    work_levels: usize,
    /// Workgroups per dispatch dimension before folding into y (the device limit, or lower
    /// for tests of the folding).
    max_workgroups_per_dim: u32,
    /// A global search has run (its hits are what a local search starts from).
    searched: bool,
    /// Bumped whenever the bind groups (and so possibly the buffers) are rebuilt.
    generation: u64,
    /// The caller's positions buffer for the next run (positions kept on the device).
    device_positions: Option<wgpu::Buffer>,
    /// Bind group of to_local for that buffer, with the generation it was built at.
    to_local_group: Option<(wgpu::Buffer, u64, wgpu::BindGroup)>,
    frame: wgpu::Buffer,
    /// Small sliding: local increments run the anchor kernel instead of the local search.
    anchored: bool,
    /// The pair's constant arrays still have to be uploaded (first run, or buffers replaced).
    static_dirty: bool,
    /// Device-resident increments: their pipelines, plan slots and bind groups.
    resident: Option<Box<resident::ResidentSearch>>,
    /// The hits last read back, shared with the result returned: the next readback reuses
    /// the allocation when the caller has dropped that result.
    hits_cache: Arc<Vec<GpuHit>>,
}

impl GpuSearch {
    /// Compiles the pipelines and creates the (small) initial workspace on `ctx`.
    pub fn new(ctx: Arc<GpuContext>) -> Result<Self> {
        let ctx_limit = ctx.limits.max_compute_workgroups_per_dimension;
        let device = &ctx.device;
        let ctx_frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame params"),
            size: std::mem::size_of::<FrameParams>() as u64,
            usage: U::UNIFORM | U::COPY_DST,
            mapped_at_creation: false,
        });
        let pipeline = |pass: &'static passes::Pass| ctx.pipeline(pass, &[]);
        let pipelines = Pipelines {
            tree_refit: pipeline(&passes::TREE_REFIT)?,
            scan_blocks: pipeline(&passes::SCAN_BLOCKS)?,
            scan_add: pipeline(&passes::SCAN_ADD)?,
            walk_start: pipeline(&passes::WALK_START)?,
            nearest_walk: pipeline(&passes::NEAREST_WALK)?,
            nearest_args: pipeline(&passes::NEAREST_ARGS)?,
            nearest_chunks: pipeline(&passes::NEAREST_CHUNKS)?,
            nearest_ties: pipeline(&passes::NEAREST_TIES)?,
            nearest_crowded: pipeline(&passes::NEAREST_CROWDED)?,
            nearest_facet: pipeline(&passes::NEAREST_FACET)?,
            local_search: pipeline(&passes::LOCAL_SEARCH)?,
            motion: pipeline(&passes::MOTION)?,
            to_local: pipeline(&passes::TO_LOCAL)?,
            anchor: pipeline(&passes::ANCHOR)?,
        };
        let storage = U::STORAGE | U::COPY_DST;
        let buffers = Buffers {
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("search params"),
                size: std::mem::size_of::<SearchParams>() as u64,
                usage: U::UNIFORM | U::COPY_DST,
                mapped_at_creation: false,
            }),
            tree_params: GrowBuffer::new(
                device,
                "tree params",
                4 * UNIFORM_STRIDE,
                U::UNIFORM | U::COPY_DST,
            ),
            nodes: GrowBuffer::new(device, "nodes", 0, storage | U::COPY_SRC),
            facets: GrowBuffer::new(device, "facets", 0, storage),
            slaves: GrowBuffer::new(device, "slaves", 0, storage),
            walk_points: GrowBuffer::new(device, "walk points", 0, storage),
            order: GrowBuffer::new(device, "tree order", 0, storage),
            boxes: GrowBuffer::new(device, "tree boxes", 0, storage | U::COPY_SRC),
            status: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("status"),
                size: STATUS_BYTES,
                usage: storage | U::COPY_SRC,
                mapped_at_creation: false,
            }),
            status_reset: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("status reset image"),
                size: STATUS_BYTES,
                usage: U::COPY_SRC | U::COPY_DST,
                mapped_at_creation: false,
            }),
            hits: GrowBuffer::new(device, "hits", 0, U::STORAGE | U::COPY_SRC),
            readback: GrowBuffer::new(device, "readback", 0, U::MAP_READ | U::COPY_DST),
            reference: GrowBuffer::new(device, "reference positions", 0, storage),
            adjacency: GrowBuffer::new(device, "node facets", 0, storage),
            motion_nodes: GrowBuffer::new(device, "motion nodes", 0, storage),
            anchors: GrowBuffer::new(device, "anchors", 0, storage),
            work: GrowBuffer::new(device, "nearest-facet work items", 0, storage),
            work_scan_params: GrowBuffer::new(
                device,
                "work scan params",
                4 * UNIFORM_STRIDE,
                U::UNIFORM | U::COPY_DST,
            ),
            best: GrowBuffer::new(device, "nearest-facet records", 0, storage),
            args: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nearest-facet dispatch"),
                size: 16,
                usage: U::STORAGE | U::INDIRECT,
                mapped_at_creation: false,
            }),
            plan: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("device-resident plan"),
                size: (crate::abi::search::PLAN_WORDS * 4) as u64,
                usage: U::STORAGE | U::INDIRECT | U::UNIFORM | U::COPY_SRC | U::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        super::upload(
            &ctx,
            &buffers.status_reset,
            0,
            bytemuck::cast_slice(&crate::abi::status::reset_image()),
        );
        Ok(Self {
            ctx,
            pipelines,
            buffers,
            bind_groups: None,
            tree_levels: None,
            work_levels: 0,
            max_workgroups_per_dim: ctx_limit,
            searched: false,
            hits_cache: Arc::default(),
            generation: 0,
            device_positions: None,
            to_local_group: None,
            frame: ctx_frame,
            anchored: false,
            static_dirty: true,
            resident: None,
        })
    }

    /// Small sliding: installs the slaves' anchors; from then on local runs evaluate them
    /// (the anchor kernel) instead of searching.
    pub fn set_anchors(&mut self, anchors: &[Anchor]) -> Result<()> {
        let bytes = std::mem::size_of_val(anchors) as u64;
        if self
            .buffers
            .anchors
            .ensure(&self.ctx.device, &self.ctx.limits, bytes)?
        {
            self.bind_groups = None;
        }
        super::upload(
            &self.ctx,
            &self.buffers.anchors.buffer,
            0,
            bytemuck::cast_slice(anchors),
        );
        self.anchored = true;
        Ok(())
    }

    /// Takes the positions of the next runs from the caller's buffer (one `vec4<f32>` per model
    /// node, model frame, STORAGE usage) instead of uploading them; `None` goes back to uploads.
    pub fn set_device_positions(&mut self, buffer: Option<wgpu::Buffer>) {
        self.device_positions = buffer;
    }

    /// Folds dispatches into 2D beyond `groups` workgroups per dimension (at most the device
    /// limit), so that tests can exercise the folding with small problems.
    pub fn set_max_workgroups_per_dim(&mut self, groups: u32) {
        self.max_workgroups_per_dim =
            groups.clamp(1, self.ctx.limits.max_compute_workgroups_per_dimension);
    }

    /// Makes every buffer large enough for `prep`; drops the bind groups if one was replaced.
    fn ensure_buffers(&mut self, prep: &Prepared) -> Result<()> {
        let (d, l) = (&self.ctx.device, &self.ctx.limits);
        let b = &mut self.buffers;
        let hits_bytes = (prep.slaves.len() * std::mem::size_of::<GpuHit>()) as u64;
        let mut replaced = false;
        let levels = prep.params.tree_levels;
        replaced |=
            b.tree_params
                .ensure(d, l, tree_passes(levels).len() as u64 * UNIFORM_STRIDE)?;
        replaced |= b.nodes.ensure(d, l, (prep.n_nodes * 16) as u64)?;
        replaced |= b.facets.ensure(d, l, (prep.facets.len() * 16) as u64)?;
        replaced |= b.slaves.ensure(d, l, (prep.slaves.len() * 8) as u64)?;
        replaced |= b
            .walk_points
            .ensure(d, l, (prep.slaves.len() * 16) as u64)?;
        replaced |= b.order.ensure(d, l, (prep.order.len() * 4).max(4) as u64)?;
        replaced |= b.boxes.ensure(d, l, box_words(levels) as u64 * 16)?;
        replaced |= b.hits.ensure(d, l, hits_bytes)?;
        replaced |= b.reference.ensure(d, l, (prep.n_nodes * 16) as u64)?;
        replaced |= b.anchors.ensure(
            d,
            l,
            (prep.slaves.len() * std::mem::size_of::<Anchor>()) as u64,
        )?;
        replaced |= b
            .adjacency
            .ensure(d, l, (prep.adjacency.len() * 4) as u64)?;
        replaced |= b
            .motion_nodes
            .ensure(d, l, (prep.motion_nodes.len() * 4) as u64)?;
        let work = work_levels(prep);
        replaced |= b.work.ensure(d, l, work.words as u64 * 4)?;
        replaced |= b
            .work_scan_params
            .ensure(d, l, work.levels.len() as u64 * UNIFORM_STRIDE)?;
        replaced |= b
            .best
            .ensure(d, l, (prep.slaves.len() * BEST_WORDS * 4) as u64)?;
        b.readback.ensure(d, l, READBACK_HITS_OFFSET + hits_bytes)?;
        self.static_dirty |= replaced;
        if replaced || self.tree_levels != Some(levels) || self.work_levels != work.levels.len() {
            self.bind_groups = None;
        }
        Ok(())
    }

    /// The buffer this search holds for each role a pass binds (the scan's are per level).
    fn resource(&self, buf: Buf) -> Option<wgpu::BindingResource<'_>> {
        let b = &self.buffers;
        Some(match buf {
            Buf::SearchParams => b.params.as_entire_binding(),
            Buf::FrameParams => self.frame.as_entire_binding(),
            Buf::Nodes => b.nodes.buffer.as_entire_binding(),
            Buf::Facets => b.facets.buffer.as_entire_binding(),
            Buf::Slaves => b.slaves.buffer.as_entire_binding(),
            Buf::WalkPoints => b.walk_points.buffer.as_entire_binding(),
            Buf::Adjacency => b.adjacency.buffer.as_entire_binding(),
            Buf::Order => b.order.buffer.as_entire_binding(),
            Buf::Boxes => b.boxes.buffer.as_entire_binding(),
            Buf::Status => b.status.as_entire_binding(),
            Buf::Hits => b.hits.buffer.as_entire_binding(),
            Buf::Reference => b.reference.buffer.as_entire_binding(),
            Buf::MotionNodes => b.motion_nodes.buffer.as_entire_binding(),
            Buf::Anchors => b.anchors.buffer.as_entire_binding(),
            Buf::Work => b.work.buffer.as_entire_binding(),
            Buf::Best => b.best.buffer.as_entire_binding(),
            Buf::Args => b.args.as_entire_binding(),
            Buf::Plan => b.plan.as_entire_binding(),
            _ => return None,
        })
    }

    fn bind_groups(&self, prep: &Prepared) -> Result<BindGroups> {
        let d = &self.ctx.device;
        let b = &self.buffers;
        let p = &self.pipelines;
        let group = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass| {
            super::bind(d, pipe, pass, |buf| self.resource(buf))
        };
        // the bind groups of every level of a scan (blocks, then add) over `data`
        let scan = |params: &wgpu::Buffer, data: &wgpu::Buffer, n: usize| {
            let level = |pipe: &wgpu::ComputePipeline, pass: &passes::Pass, i: usize| {
                super::bind(d, pipe, pass, |buf| match buf {
                    Buf::ScanParams => Some(scan_level(params, i)),
                    Buf::ScanData => Some(data.as_entire_binding()),
                    _ => None,
                })
            };
            let blocks = (0..n)
                .map(|i| level(&p.scan_blocks, &passes::SCAN_BLOCKS, i))
                .collect::<Result<Vec<_>>>()?;
            let add = (0..n)
                .map(|i| level(&p.scan_add, &passes::SCAN_ADD, i))
                .collect::<Result<Vec<_>>>()?;
            Ok::<_, Error>((blocks, add))
        };
        let n_work_levels = work_levels(prep).levels.len();
        let (work_scan_blocks, work_scan_add) =
            scan(&b.work_scan_params.buffer, &b.work.buffer, n_work_levels)?;
        let tree_refit = (0..tree_passes(prep.params.tree_levels).len())
            .map(|i| {
                super::bind(d, &p.tree_refit, &passes::TREE_REFIT, |buf| match buf {
                    Buf::TreeParams => Some(tree_pass(&b.tree_params.buffer, i)),
                    other => self.resource(other),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(BindGroups {
            anchor: group(&p.anchor, &passes::ANCHOR)?,
            local_search: group(&p.local_search, &passes::LOCAL_SEARCH)?,
            motion: group(&p.motion, &passes::MOTION)?,
            tree_refit,
            walk_start: group(&p.walk_start, &passes::WALK_START)?,
            nearest_walk: group(&p.nearest_walk, &passes::NEAREST_WALK)?,
            work_scan_blocks,
            work_scan_add,
            nearest_args: group(&p.nearest_args, &passes::NEAREST_ARGS)?,
            nearest_chunks: group(&p.nearest_chunks, &passes::NEAREST_CHUNKS)?,
            nearest_ties: group(&p.nearest_ties, &passes::NEAREST_TIES)?,
            nearest_crowded: group(&p.nearest_crowded, &passes::NEAREST_CROWDED)?,
            nearest_facet: group(&p.nearest_facet, &passes::NEAREST_FACET)?,
        })
    }

    /// Runs a global search. Returns the hits.
    pub fn run(&mut self, prep: &Prepared) -> Result<Arc<Vec<GpuHit>>> {
        Ok(self.run_with(prep, 0, None, true, false)?.0)
    }

    /// Runs a global search (`local` false) or the motion check and the local search, in one
    /// submit. Returns the hits (empty unless `read_hits`) and the status words.
    pub(crate) fn run_mode(
        &mut self,
        prep: &Prepared,
        local: bool,
        read_hits: bool,
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        if local && !self.searched {
            return Err(Error::BadParameter {
                name: "local search",
                value: "before any global search".into(),
                expected: "a global search first",
            });
        }
        self.run_with(prep, 0, None, read_hits, local)
    }

    /// Runs the steps `STEPS[first..]` on the GPU, starting from the CPU mirror's state after
    /// `STEPS[..first]` (`preload`, required when `first > 0`): the GPU half of a split run,
    /// which finds the first step where the two executors diverge.
    pub fn run_split(
        &mut self,
        prep: &Prepared,
        first: usize,
        preload: &CpuWorkspace,
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        self.run_with(prep, first, Some(preload), true, false)
    }

    /// Runs the search steps `STEPS[first..]` (or the local search) in one command encoder and
    /// submit, reading back once. Returns the hits (empty unless `read_hits`) and the status
    /// words.
    pub(crate) fn run_with(
        &mut self,
        prep: &Prepared,
        first: usize,
        preload: Option<&CpuWorkspace>,
        read_hits: bool,
        local: bool,
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        self.ensure_buffers(prep)?;
        if let Some(src) = self.device_positions.clone() {
            let need = prep.n_nodes as u64 * 16;
            if src.size() < need || !src.usage().contains(U::STORAGE) {
                return Err(Error::BadParameter {
                    name: "device positions",
                    value: format!("buffer of {} bytes, usage {:?}", src.size(), src.usage()),
                    expected: "needs one vec4<f32> per model node and STORAGE usage",
                });
            }
            let frame = FrameParams {
                origin: [
                    prep.grid.frame[0] as f32,
                    prep.grid.frame[1] as f32,
                    prep.grid.frame[2] as f32,
                    0.0,
                ],
                n_nodes: prep.n_nodes as u32,
                _pad: [0; 3],
            };
            super::upload(&self.ctx, &self.frame, 0, bytemuck::bytes_of(&frame));
        }
        if self.device_positions.is_none() {
            super::upload(
                &self.ctx,
                &self.buffers.nodes.buffer,
                0,
                bytemuck::cast_slice(&prep.nodes),
            );
        }
        self.upload_static(prep);
        for (i, tp) in tree_passes(prep.params.tree_levels).iter().enumerate() {
            super::upload(
                &self.ctx,
                &self.buffers.tree_params.buffer,
                i as u64 * UNIFORM_STRIDE,
                bytemuck::bytes_of(tp),
            );
        }
        let work = work_levels(prep);
        for i in 0..work.levels.len() {
            super::upload(
                &self.ctx,
                &self.buffers.work_scan_params.buffer,
                i as u64 * UNIFORM_STRIDE,
                bytemuck::bytes_of(&work.params(i)),
            );
        }
        if let Some(ws) = preload {
            super::upload(
                &self.ctx,
                &self.buffers.boxes.buffer,
                0,
                bytemuck::cast_slice(&ws.boxes),
            );
            super::upload(
                &self.ctx,
                &self.buffers.status,
                0,
                bytemuck::cast_slice(&ws.status),
            );
        }
        if self.bind_groups.is_none() {
            self.bind_groups = Some(self.bind_groups(prep)?);
            self.tree_levels = Some(prep.params.tree_levels);
            self.work_levels = work_levels(prep).levels.len();
            self.generation += 1;
        }
        if let Some(src) = self.device_positions.clone() {
            let fresh = matches!(&self.to_local_group, Some((b, g, _)) if *b == src && *g == self.generation);
            if !fresh {
                let group = super::bind(
                    &self.ctx.device,
                    &self.pipelines.to_local,
                    &passes::TO_LOCAL,
                    |buf| match buf {
                        Buf::Positions => Some(src.as_entire_binding()),
                        other => self.resource(other),
                    },
                )?;
                self.to_local_group = Some((src, self.generation, group));
            }
        }
        super::upload(
            &self.ctx,
            &self.buffers.params,
            0,
            bytemuck::bytes_of(&prep.params),
        );
        if !read_hits {
            let status = self.submit(&prep.params, prep, first, false, &mut Vec::new(), local)?;
            return Ok((Arc::default(), status));
        }
        let mut hits = std::mem::take(&mut self.hits_cache);
        if Arc::get_mut(&mut hits).is_none() {
            hits = Arc::default(); // the last result is still held: a fresh allocation
        }
        let out = Arc::get_mut(&mut hits).expect("unique");
        let status = self.submit(&prep.params, prep, first, true, out, local)?;
        if !local {
            self.searched = true;
        }
        self.hits_cache = hits.clone();
        Ok((hits, status))
    }

    /// Uploads the pair's constants (facets, slaves, adjacency, motion nodes) once, and again
    /// only into buffers that were just replaced.
    fn upload_static(&mut self, prep: &Prepared) {
        if !self.static_dirty {
            return;
        }
        let b = &self.buffers;
        super::upload(
            &self.ctx,
            &b.adjacency.buffer,
            0,
            bytemuck::cast_slice(&prep.adjacency),
        );
        super::upload(
            &self.ctx,
            &b.motion_nodes.buffer,
            0,
            bytemuck::cast_slice(&prep.motion_nodes),
        );
        super::upload(
            &self.ctx,
            &b.facets.buffer,
            0,
            bytemuck::cast_slice(&prep.facets),
        );
        super::upload(
            &self.ctx,
            &b.slaves.buffer,
            0,
            bytemuck::cast_slice(&prep.slaves),
        );
        super::upload(
            &self.ctx,
            &b.slaves.buffer,
            (prep.slaves.len() * 4) as u64,
            bytemuck::cast_slice(&prep.walk_order),
        );
        super::upload(
            &self.ctx,
            &b.order.buffer,
            0,
            bytemuck::cast_slice(&prep.order),
        );
        self.static_dirty = false;
    }

    /// The search buffers later passes bind, and the generation of the bind groups on them.
    pub(crate) fn shared_buffers(&self) -> (SharedBuffers<'_>, u64) {
        (self.shared(), self.generation)
    }

    /// Workgroups per dispatch dimension before folding.
    pub(crate) fn max_workgroups_per_dim(&self) -> u32 {
        self.max_workgroups_per_dim
    }

    /// The search buffers later passes bind.
    fn shared(&self) -> SharedBuffers<'_> {
        SharedBuffers {
            nodes: &self.buffers.nodes.buffer,
            facets: &self.buffers.facets.buffer,
            hits: &self.buffers.hits.buffer,
            status: &self.buffers.status,
        }
    }

    /// Reads the caller's positions buffer back as f64 (the rare refit of a device-positions
    /// increment).
    pub fn read_positions(&self, buffer: &wgpu::Buffer, n_nodes: usize) -> Result<Vec<[f64; 3]>> {
        if !buffer.usage().contains(U::COPY_SRC) {
            return Err(Error::BadParameter {
                name: "device positions",
                value: format!("usage {:?}", buffer.usage()),
                expected: "COPY_SRC, so the grid can be refitted",
            });
        }
        let d = &self.ctx.device;
        let bytes = n_nodes as u64 * 16;
        let staging = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("positions readback"),
            size: bytes.max(16),
            usage: U::MAP_READ | U::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("positions readback"),
        });
        enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
        crate::device::submit(&self.ctx, enc);
        let raw = read_back(&self.ctx, &staging, bytes, "positions readback")?;
        let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&raw);
        Ok(v.iter()
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect())
    }

    /// Reads back the search tree's packed boxes after the last global search (one per heap
    /// node, `abi::boxes`). A debugging and testing aid (it allocates and waits).
    pub fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        let Some(levels) = self.tree_levels.filter(|_| self.searched) else {
            return Err(Error::Gpu {
                during: "reading the search tree".into(),
                message: "no search has run".into(),
            });
        };
        let d = &self.ctx.device;
        let bytes = box_words(levels) as u64 * 16;
        let staging = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tree readback"),
            size: bytes,
            usage: U::MAP_READ | U::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("tree readback"),
        });
        enc.copy_buffer_to_buffer(&self.buffers.boxes.buffer, 0, &staging, 0, bytes);
        crate::device::submit(&self.ctx, enc);
        let raw = read_back(&self.ctx, &staging, bytes, "tree readback")?;
        Ok(bytemuck::pod_collect_to_vec(&raw))
    }

    /// Encodes the steps `STEPS[first..]`, submits once and reads back the status words and,
    /// when `read_hits`, the hits into `hits` (resized to one per slave).
    fn submit(
        &self,
        params: &SearchParams,
        prep: &Prepared,
        first: usize,
        read_hits: bool,
        hits: &mut Vec<GpuHit>,
        local: bool,
    ) -> Result<[u32; STATUS_WORDS]> {
        let n_slaves = prep.slaves.len();
        let (device, b, p) = (&self.ctx.device, &self.buffers, &self.pipelines);
        let bg = self
            .bind_groups
            .as_ref()
            .expect("bind groups built before submit");
        let max_dim = self.max_workgroups_per_dim;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("global search"),
        });
        if first == 0 {
            reset_status(&mut enc, &b.status_reset, &b.status, Owner::Search);
        }
        let dispatch = |enc: &mut wgpu::CommandEncoder,
                        group: &'static groups::Group,
                        work: &[super::Work<'_>]| {
            super::run_pass(&self.ctx, enc, group, work, max_dim)
        };
        if let Some((_, _, group)) = &self.to_local_group {
            if self.device_positions.is_some() {
                dispatch(
                    &mut enc,
                    &groups::DIRECT_TO_LOCAL,
                    &[(&p.to_local, group, prep.n_nodes as u32, ITEM_WORKGROUP)],
                );
            }
        }
        let steps: &[Step] = if local { &[] } else { &STEPS[first..] };
        if local && self.anchored {
            dispatch(
                &mut enc,
                &groups::DIRECT_ANCHOR,
                &[(&p.anchor, &bg.anchor, params.n_slaves, ITEM_WORKGROUP)],
            );
        } else if local {
            dispatch(
                &mut enc,
                &groups::DIRECT_LOCAL,
                &[
                    (
                        &p.motion,
                        &bg.motion,
                        prep.motion_nodes.len() as u32,
                        ITEM_WORKGROUP,
                    ),
                    (
                        &p.local_search,
                        &bg.local_search,
                        params.n_slaves,
                        ITEM_WORKGROUP,
                    ),
                ],
            );
        }
        for step in steps {
            match step {
                Step::TreeRefit => {
                    let passes = tree_passes(params.tree_levels);
                    let work: Vec<super::Work<'_>> = passes
                        .iter()
                        .zip(&bg.tree_refit)
                        .map(|(tp, g)| (&p.tree_refit, g, 1u32 << tp.bottom, TREE_WORKGROUP))
                        .collect();
                    dispatch(&mut enc, &groups::DIRECT_TREE_REFIT, &work);
                }
                Step::NearestFacet => {
                    let work = work_levels(prep);
                    let mut seq = vec![
                        (
                            &p.walk_start,
                            &bg.walk_start,
                            params.n_slaves.div_ceil(crate::abi::search::WALK_GROUP),
                            ITEM_WORKGROUP,
                        ),
                        (
                            &p.nearest_walk,
                            &bg.nearest_walk,
                            params.n_slaves,
                            ITEM_WORKGROUP,
                        ),
                    ];
                    scan_work(p, &work, &bg.work_scan_blocks, &bg.work_scan_add, &mut seq);
                    seq.push((&p.nearest_args, &bg.nearest_args, 1, 1));
                    dispatch(&mut enc, &groups::DIRECT_WALK_SCAN, &seq);
                    let chunks = [
                        (&p.nearest_chunks, &bg.nearest_chunks, 0),
                        (&p.nearest_ties, &bg.nearest_ties, 0),
                    ];
                    super::run_indirect_pass(
                        &self.ctx,
                        &mut enc,
                        &groups::DIRECT_CHUNKS,
                        &chunks,
                        &b.args,
                    );
                    let mut last = Vec::new();
                    if params.flags & crate::abi::search::FLAG_SELF_CONTACT != 0 {
                        last.push((
                            &p.nearest_crowded,
                            &bg.nearest_crowded,
                            params.n_slaves,
                            ITEM_WORKGROUP,
                        ));
                    }
                    last.push((
                        &p.nearest_facet,
                        &bg.nearest_facet,
                        params.n_slaves,
                        ITEM_WORKGROUP,
                    ));
                    dispatch(&mut enc, &groups::DIRECT_NEAREST, &last);
                }
            }
        }
        if !local && first < STEPS.len() {
            // the frame of this global search is the reference of the motion budget
            enc.copy_buffer_to_buffer(
                &b.nodes.buffer,
                0,
                &b.reference.buffer,
                0,
                (prep.n_nodes * 16) as u64,
            );
        }
        let hits_bytes = if read_hits {
            (n_slaves * std::mem::size_of::<GpuHit>()) as u64
        } else {
            0
        };
        enc.copy_buffer_to_buffer(&b.status, 0, &b.readback.buffer, 0, STATUS_BYTES);
        if hits_bytes > 0 {
            enc.copy_buffer_to_buffer(
                &b.hits.buffer,
                0,
                &b.readback.buffer,
                READBACK_HITS_OFFSET,
                hits_bytes,
            );
        }
        crate::device::submit(&self.ctx, enc);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu {
                during: "contact increment".into(),
                message: e.to_string(),
            });
        }
        let status = read_back_with(
            &self.ctx,
            &b.readback.buffer,
            READBACK_HITS_OFFSET + hits_bytes,
            "global search readback",
            |bytes| {
                let status: [u32; STATUS_WORDS] =
                    bytemuck::pod_read_unaligned(&bytes[..STATUS_BYTES as usize]);
                let raw = &bytes[READBACK_HITS_OFFSET as usize..];
                hits.resize(
                    raw.len() / std::mem::size_of::<GpuHit>(),
                    bytemuck::Zeroable::zeroed(),
                );
                bytemuck::cast_slice_mut::<GpuHit, u8>(hits).copy_from_slice(raw);
                status
            },
        )?;
        self.ctx.take_uncaptured("contact increment")?;
        Ok(status)
    }
}

/// The scan levels of the nearest-facet work items: one chunk count per slave and the total.
fn work_levels(prep: &Prepared) -> ScanLevels {
    ScanLevels::new(prep.slaves.len() as u32 + 1)
}

/// Refit pass `i`'s parameters in `params` (one uniform block every `UNIFORM_STRIDE` bytes).
fn tree_pass(params: &wgpu::Buffer, i: usize) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer: params,
        offset: i as u64 * UNIFORM_STRIDE,
        size: wgpu::BufferSize::new(std::mem::size_of::<TreeParams>() as u64),
    })
}

/// Scan level `i`'s parameters in `params` (one uniform block every `UNIFORM_STRIDE` bytes).
fn scan_level(params: &wgpu::Buffer, i: usize) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer: params,
        offset: i as u64 * UNIFORM_STRIDE,
        size: wgpu::BufferSize::new(std::mem::size_of::<ScanParams>() as u64),
    })
}

/// Copies the reset values of the status words `owner` resets from `image` into `status`.
pub(crate) fn reset_status(
    enc: &mut wgpu::CommandEncoder,
    image: &wgpu::Buffer,
    status: &wgpu::Buffer,
    owner: Owner,
) {
    for (first, n) in owned_runs(owner) {
        let (offset, bytes) = (4 * first as u64, 4 * n as u64);
        enc.copy_buffer_to_buffer(image, offset, status, offset, bytes);
    }
}

/// Appends the dispatches of a multi-level scan over `levels` (its bind groups per level): each
/// level's blocks upward, then the block sums added back downward.
fn scan_work<'a>(
    p: &'a Pipelines,
    levels: &ScanLevels,
    blocks: &'a [wgpu::BindGroup],
    add: &'a [wgpu::BindGroup],
    work: &mut Vec<super::Work<'a>>,
) {
    for (i, level) in levels.levels.iter().enumerate() {
        work.push((&p.scan_blocks, &blocks[i], level.1, SCAN_BLOCK));
    }
    for i in (0..levels.levels.len().saturating_sub(1)).rev() {
        work.push((&p.scan_add, &add[i], levels.levels[i].1, SCAN_BLOCK));
    }
}
