//! The GPU executor of a search: its buffers and pipelines, its part of a device-resident
//! increment (`resident`), and a search run on its own (`plan`).

use std::sync::Arc;

use super::buffers::{read_back, read_back_with, GrowBuffer};
use crate::abi::passes::{self, Buf};
use crate::abi::search::{box_words, BEST_WORDS};
use crate::abi::search::{
    tree_passes, Anchor, FrameParams, GpuHit, ScanLevels, ScanParams, TreeParams,
};
use crate::abi::status::STATUS_WORDS;
use crate::device::GpuContext;
use crate::error::{Error, Result};
use crate::plan::Prepared;
use wgpu::BufferUsages as U;

mod plan;
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
    /// Status words (then the active slaves).
    pub status: &'a wgpu::Buffer,
    /// The plan words (the indirect sizes of the passes over the slaves).
    pub plan: &'a wgpu::Buffer,
}

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

struct Buffers {
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
    /// The status words, then the active slaves (`ACTIVE_LIST`: count, slave indices).
    status: GrowBuffer,
    /// The status words' reset image (copied over the status words, not the active slaves).
    status_reset: wgpu::Buffer,
    hits: GrowBuffer,
    readback: GrowBuffer,
    reference: GrowBuffer,
    /// Per slave, its skin (`Buf::Skins`).
    skins: GrowBuffer,
    adjacency: GrowBuffer,
    motion_nodes: GrowBuffer,
    anchors: GrowBuffer,
    /// Nearest-facet work items: chunk counts per slave, scanned (all scan levels).
    work: GrowBuffer,
    /// Nearest-facet record per slave (4 words).
    best: GrowBuffer,
    /// The indirect dispatch of the nearest-facet work items (x, y, z).
    args: wgpu::Buffer,
    /// The device-resident plan (`PLAN_*` words); to_local raises the master box into it.
    plan: wgpu::Buffer,
    /// The bucket search's grid (`abi::buckets::BucketLayout`; unused with the tree).
    grid: GrowBuffer,
}

/// The global search on one GPU device; its buffers grow as needed and are reused.
pub struct GpuSearch {
    ctx: Arc<GpuContext>,
    pipelines: Pipelines,
    buffers: Buffers,
    /// Tree levels the buffers were sized for (`None` before `make_resident`).
    tree_levels: Option<u32>,
    /// Workgroups per dispatch dimension before folding into y (the device limit, or lower
    /// for tests of the folding).
    max_workgroups_per_dim: u32,
    /// Bumped whenever a buffer is replaced (bind groups on the old ones are stale).
    generation: u64,
    /// abut's positions buffer for host positions (`run_plan`), made by the first.
    host_positions: Option<wgpu::Buffer>,
    frame: wgpu::Buffer,
    /// The pair's constant arrays still have to be uploaded (first run, or buffers replaced).
    static_dirty: bool,
    /// Device-resident increments: their pipelines, plan slots and bind groups.
    resident: Option<Box<resident::ResidentSearch>>,
    /// The hits last read back, shared with the result returned: the next readback reuses
    /// the allocation when the caller has dropped that result.
    hits_cache: Arc<Vec<GpuHit>>,
}

impl GpuSearch {
    /// Takes the search pipelines from the device's cache (compiled on first use) and creates the
    /// (small) initial workspace on `ctx`.
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
            tree_params: GrowBuffer::new(
                device,
                "tree params",
                4 * UNIFORM_STRIDE,
                U::UNIFORM | U::COPY_DST,
            ),
            nodes: GrowBuffer::new(device, "nodes", 0, storage | U::COPY_SRC),
            facets: GrowBuffer::new(device, "facets", 0, storage),
            slaves: GrowBuffer::new(device, "slaves", 0, storage),
            walk_points: GrowBuffer::new(device, "walk points", 0, storage | U::COPY_SRC),
            order: GrowBuffer::new(device, "tree order", 0, storage),
            boxes: GrowBuffer::new(device, "tree boxes", 0, storage | U::COPY_SRC),
            status: GrowBuffer::new(device, "status", STATUS_BYTES, storage | U::COPY_SRC),
            status_reset: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("status reset image"),
                size: STATUS_BYTES,
                usage: U::COPY_SRC | U::COPY_DST,
                mapped_at_creation: false,
            }),
            hits: GrowBuffer::new(device, "hits", 0, storage | U::COPY_SRC),
            readback: GrowBuffer::new(device, "readback", 0, U::MAP_READ | U::COPY_DST),
            reference: GrowBuffer::new(device, "reference positions", 0, storage | U::COPY_SRC),
            skins: GrowBuffer::new(device, "skins", 0, storage | U::COPY_SRC),
            adjacency: GrowBuffer::new(device, "node facets", 0, storage),
            motion_nodes: GrowBuffer::new(device, "motion nodes", 0, storage),
            anchors: GrowBuffer::new(device, "anchors", 0, storage),
            work: GrowBuffer::new(device, "nearest-facet work items", 0, storage | U::COPY_SRC),
            best: GrowBuffer::new(device, "nearest-facet records", 0, storage | U::COPY_SRC),
            args: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nearest-facet dispatch"),
                size: 16,
                usage: U::STORAGE | U::INDIRECT | U::COPY_SRC | U::COPY_DST,
                mapped_at_creation: false,
            }),
            plan: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("device-resident plan"),
                size: (crate::abi::search::PLAN_WORDS * 4) as u64,
                usage: U::STORAGE | U::INDIRECT | U::UNIFORM | U::COPY_SRC | U::COPY_DST,
                mapped_at_creation: false,
            }),
            grid: GrowBuffer::new(device, "bucket grid", 16, storage | U::COPY_SRC),
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
            tree_levels: None,
            max_workgroups_per_dim: ctx_limit,
            hits_cache: Arc::default(),
            generation: 0,
            host_positions: None,
            frame: ctx_frame,
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
            self.generation += 1;
        }
        super::upload(
            &self.ctx,
            &self.buffers.anchors.buffer,
            0,
            bytemuck::cast_slice(anchors),
        );
        Ok(())
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
        replaced |= b
            .status
            .ensure(d, l, STATUS_BYTES + 4 * (prep.slaves.len() as u64 + 1))?;
        replaced |= b.reference.ensure(d, l, (prep.n_nodes * 16) as u64)?;
        replaced |= b.skins.ensure(d, l, (prep.slaves.len() * 16) as u64)?;
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
        let work = ScanLevels::new(prep.slaves.len() as u32 + 1);
        replaced |= b.work.ensure(d, l, work.words as u64 * 4)?;
        replaced |= b
            .best
            .ensure(d, l, (prep.slaves.len() * BEST_WORDS * 4) as u64)?;
        if prep.params.flags & crate::abi::search::FLAG_BUCKETS != 0 {
            let words = crate::abi::buckets::BucketLayout::new(prep.params.n_facets).words;
            replaced |= b.grid.ensure(d, l, words as u64 * 4)?;
        }
        self.static_dirty |= replaced;
        if replaced || self.tree_levels != Some(levels) {
            self.generation += 1;
        }
        self.tree_levels = Some(levels);
        Ok(())
    }

    /// The buffer this search holds for each role a pass binds (the scan's are per level).
    /// The buffer of role `buf` that a device-resident increment writes (`None` for a role
    /// it only reads): what a split increment hands over.
    pub(crate) fn role_buffer(&self, buf: Buf) -> Option<&wgpu::Buffer> {
        let b = &self.buffers;
        Some(match buf {
            Buf::Nodes => &b.nodes.buffer,
            Buf::Status | Buf::Active => &b.status.buffer,
            Buf::Hits => &b.hits.buffer,
            Buf::Reference => &b.reference.buffer,
            Buf::Skins => &b.skins.buffer,
            Buf::Plan => &b.plan,
            Buf::Args => &b.args,
            Buf::Boxes => &b.boxes.buffer,
            Buf::Work => &b.work.buffer,
            Buf::Best => &b.best.buffer,
            Buf::WalkPoints => &b.walk_points.buffer,
            Buf::Grid => &b.grid.buffer,
            _ => return None,
        })
    }

    /// Where role `buf` starts in its [`Self::role_buffer`], bytes: the active slaves follow the
    /// status words.
    pub(crate) fn role_offset(buf: Buf) -> u64 {
        if buf == Buf::Active {
            STATUS_BYTES
        } else {
            0
        }
    }

    fn resource(&self, buf: Buf) -> Option<wgpu::BindingResource<'_>> {
        let b = &self.buffers;
        Some(match buf {
            Buf::FrameParams => self.frame.as_entire_binding(),
            Buf::Nodes => b.nodes.buffer.as_entire_binding(),
            Buf::Facets => b.facets.buffer.as_entire_binding(),
            Buf::Slaves => b.slaves.buffer.as_entire_binding(),
            Buf::WalkPoints => b.walk_points.buffer.as_entire_binding(),
            Buf::Adjacency => b.adjacency.buffer.as_entire_binding(),
            Buf::Order => b.order.buffer.as_entire_binding(),
            Buf::Boxes => b.boxes.buffer.as_entire_binding(),
            Buf::Status => b.status.buffer.as_entire_binding(),
            Buf::Hits => b.hits.buffer.as_entire_binding(),
            Buf::Reference => b.reference.buffer.as_entire_binding(),
            Buf::Skins => b.skins.buffer.as_entire_binding(),
            Buf::MotionNodes => b.motion_nodes.buffer.as_entire_binding(),
            Buf::Anchors => b.anchors.buffer.as_entire_binding(),
            Buf::Work => b.work.buffer.as_entire_binding(),
            Buf::Best => b.best.buffer.as_entire_binding(),
            Buf::Args => b.args.as_entire_binding(),
            Buf::Plan => b.plan.as_entire_binding(),
            Buf::Grid => b.grid.buffer.as_entire_binding(),
            _ => return None,
        })
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
            status: &self.buffers.status.buffer,
            plan: &self.buffers.plan,
        }
    }

    /// Reads back the search tree's packed boxes after the last global search (one per heap
    /// node, `abi::boxes`). A debugging and testing aid (it allocates and waits).
    pub fn tree_boxes(&self) -> Result<Vec<[u32; 4]>> {
        let Some(levels) = self.tree_levels else {
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
