//! The GPU executors: the search's, the penalty's and the increment's kernels on buffers that
//! only grow, and the recording of a plan's entries as dispatches (direct, or indirect from
//! what the device decided).

pub(crate) mod buffers;
mod global_search;
mod increment;
mod integrate;
mod penalty;

pub use global_search::{GpuSearch, SharedBuffers};
pub(crate) use increment::GpuIncrement;
pub use increment::STATS_RING;
pub use integrate::CentralDifference;
pub use penalty::GpuPenalty;

/// One dispatch of a compute pass: pipeline, its bind group, items, items per workgroup.
pub(crate) type Work<'a> = (&'a wgpu::ComputePipeline, &'a wgpu::BindGroup, u32, u32);

/// Records one compute pass running `work` in order, each dispatch folded into 2D beyond
/// `max_dim` workgroups per dimension.
pub(crate) fn run_pass(
    ctx: &crate::device::GpuContext,
    enc: &mut wgpu::CommandEncoder,
    group: &'static crate::abi::groups::Group,
    work: &[Work<'_>],
    max_dim: u32,
) {
    let label = group.label;
    if let Ok(mut t) = ctx.traffic.lock() {
        *t.dispatches.entry(label.to_string()).or_default() += work.len() as u64;
        t.workgroups += work
            .iter()
            .map(|&(_, _, n, per)| n.div_ceil(per.max(1)) as u64)
            .sum::<u64>();
    }
    let mut profiler = ctx.profiler.lock().ok();
    let mut pass = begin_pass(&mut profiler, enc, label);
    for &(pipe, group, n, per) in work {
        let (x, y) = crate::abi::search::fold_dispatch(n, per, max_dim);
        pass.set_pipeline(pipe);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// One dispatch among others of a device-resident increment: direct (pipeline, bind group,
/// items, items per workgroup), or indirect from the (x, y, z) words at a byte offset of a buffer.
pub(crate) enum Dispatch<'a> {
    /// Workgroups known when recording.
    Direct(Work<'a>),
    /// Workgroups the device wrote.
    Indirect(
        &'a wgpu::ComputePipeline,
        &'a wgpu::BindGroup,
        &'a wgpu::Buffer,
        u64,
    ),
}

/// The dispatch of a plan entry of `size` with `pipe` and `group`: direct for items known when
/// recording, indirect from the search's `plan` words or chunk `args` for what the device
/// decides.
pub(crate) fn entry_dispatch<'a>(
    pipe: &'a wgpu::ComputePipeline,
    group: &'a wgpu::BindGroup,
    size: crate::plan::increment::Size,
    plan: &'a wgpu::Buffer,
    args: &'a wgpu::Buffer,
) -> Dispatch<'a> {
    use crate::plan::increment::Size;
    match size {
        Size::Items(n, per) => Dispatch::Direct((pipe, group, n, per)),
        Size::Slot(offset) => Dispatch::Indirect(pipe, group, plan, offset),
        Size::Chunks => Dispatch::Indirect(pipe, group, args, 0),
    }
}

/// The dispatch of a plan entry of `size` that is known when recording (`None` for a size the
/// device decides: only a search's kernels have those).
pub(crate) fn direct_dispatch<'a>(
    pipe: &'a wgpu::ComputePipeline,
    group: &'a wgpu::BindGroup,
    size: crate::plan::increment::Size,
) -> Option<Dispatch<'a>> {
    match size {
        crate::plan::increment::Size::Items(n, per) => {
            Some(Dispatch::Direct((pipe, group, n, per)))
        }
        _ => None,
    }
}

/// A declared group (`abi::groups`) and the dispatches recorded under its label.
pub(crate) type GroupWork<'a> = (&'static crate::abi::groups::Group, Vec<Dispatch<'a>>);

/// Appends `work` to the last group when it is `group` (consecutive entries of one group are
/// recorded, timed and counted together), else opens a new one.
pub(crate) fn push_grouped<'a>(
    groups: &mut Vec<GroupWork<'a>>,
    group: &'static crate::abi::groups::Group,
    work: Dispatch<'a>,
) {
    match groups.last_mut() {
        Some((g, w)) if std::ptr::eq(*g, group) => w.push(work),
        _ => groups.push((group, vec![work])),
    }
}

/// Records `groups` in order: all in one compute pass (WebGPU's usage scopes are per dispatch,
/// so a dispatch may read as its indirect arguments or uniform what an earlier one wrote), or,
/// with timestamps on, one compute pass per group so that each gets its own time.
pub(crate) fn record_groups(
    ctx: &crate::device::GpuContext,
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    groups: &[GroupWork<'_>],
    max_dim: u32,
) {
    if let Ok(mut t) = ctx.traffic.lock() {
        for (group, work) in groups {
            let (label, n) = (group.label, work.len() as u64);
            match t.dispatches.get_mut(label) {
                Some(c) => *c += n,
                None => {
                    t.dispatches.insert(label.to_string(), n);
                }
            }
            t.workgroups += work
                .iter()
                .map(|d| match d {
                    Dispatch::Direct((_, _, n, per)) => n.div_ceil((*per).max(1)) as u64,
                    Dispatch::Indirect(..) => 0,
                })
                .sum::<u64>();
        }
    }
    let mut profiler = ctx.profiler.lock().ok();
    let timed = profiler.as_ref().is_some_and(|p| p.is_some());
    if timed {
        for (group, work) in groups {
            let mut pass = begin_pass(&mut profiler, enc, group.label);
            let mut bound = None;
            record_work(&mut pass, work, &mut bound, max_dim);
        }
    } else {
        let mut pass = begin_pass(&mut profiler, enc, label);
        let mut bound = None;
        for (_, work) in groups {
            record_work(&mut pass, work, &mut bound, max_dim);
        }
    }
}

/// The pipeline and bind group a compute pass has set last.
type Bound<'a> = Option<(&'a wgpu::ComputePipeline, &'a wgpu::BindGroup)>;

/// Records `work` into `pass`, setting the pipeline and the bind group only where they differ
/// from what the pass has bound (`bound`, updated).
fn record_work<'a>(
    pass: &mut wgpu::ComputePass<'_>,
    work: &[Dispatch<'a>],
    bound: &mut Bound<'a>,
    max_dim: u32,
) {
    for d in work {
        let (pipe, group) = match *d {
            Dispatch::Direct((pipe, group, ..)) | Dispatch::Indirect(pipe, group, ..) => {
                (pipe, group)
            }
        };
        let (same_pipe, same_group) = bound.map_or((false, false), |(p, g)| {
            (std::ptr::eq(p, pipe), std::ptr::eq(g, group))
        });
        if !same_pipe {
            pass.set_pipeline(pipe);
        }
        if !same_group {
            pass.set_bind_group(0, group, &[]);
        }
        *bound = Some((pipe, group));
        match *d {
            Dispatch::Direct((_, _, n, per)) => {
                let (x, y) = crate::abi::search::fold_dispatch(n, per, max_dim);
                pass.dispatch_workgroups(x, y, 1);
            }
            Dispatch::Indirect(_, _, args, offset) => {
                pass.dispatch_workgroups_indirect(args, offset);
            }
        }
    }
}

/// Begins compute pass `label`, with timestamps around it when the profiler has room.
fn begin_pass<'e>(
    profiler: &mut Option<std::sync::MutexGuard<'_, Option<crate::device::Profiler>>>,
    enc: &'e mut wgpu::CommandEncoder,
    label: &str,
) -> wgpu::ComputePass<'e> {
    let writes = profiler
        .as_mut()
        .and_then(|p| p.as_mut())
        .and_then(|p| p.next(label));
    enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: writes,
    })
}

/// Writes `data` into `buffer` at `offset` through the queue, counting the bytes.
pub(crate) fn upload(
    ctx: &crate::device::GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    data: &[u8],
) {
    if let Ok(mut t) = ctx.traffic.lock() {
        t.uploaded_bytes += data.len() as u64;
    }
    ctx.queue.write_buffer(buffer, offset, data);
}

/// The bind group of `pass` on `pipeline`: each declared binding gets the buffer `resource`
/// gives for its role; a role the executor does not hold is an error naming it.
pub(crate) fn bind<'a>(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    pass: &crate::abi::passes::Pass,
    resource: impl Fn(crate::abi::passes::Buf) -> Option<wgpu::BindingResource<'a>>,
) -> crate::error::Result<wgpu::BindGroup> {
    let mut entries = Vec::with_capacity(pass.bindings.len());
    for b in pass.bindings {
        let r = resource(b.buf).ok_or_else(|| crate::error::Error::Gpu {
            during: format!("binding the buffers of {}", pass.entry),
            message: format!("no buffer for {:?} at binding {}", b.buf, b.index),
        })?;
        entries.push(wgpu::BindGroupEntry {
            binding: b.index,
            resource: r,
        });
    }
    Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(pass.entry),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    }))
}
