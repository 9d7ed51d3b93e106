//! The GPU executor: shader composition, a workspace of buffers that only grows, pipelines,
//! and the global search's dispatch sequence (one encoder, one submit, one readback).

pub(crate) mod buffers;
mod global_search;
mod penalty;
pub mod shaders;

pub use global_search::{AfterSearch, GpuSearch, SharedBuffers};
pub use penalty::GpuPenalty;

/// One dispatch of a compute pass: pipeline, its bind group, items, items per workgroup.
pub(crate) type Work<'a> = (&'a wgpu::ComputePipeline, &'a wgpu::BindGroup, u32, u32);

/// Records one compute pass running `work` in order, each dispatch folded into 2D beyond
/// `max_dim` workgroups per dimension.
pub(crate) fn run_pass(
    traffic: &std::sync::Mutex<crate::device::Traffic>,
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    work: &[Work<'_>],
    max_dim: u32,
) {
    if let Ok(mut t) = traffic.lock() {
        *t.dispatches.entry(label.to_string()).or_default() += work.len() as u64;
        t.workgroups += work
            .iter()
            .map(|&(_, _, n, per)| n.div_ceil(per.max(1)) as u64)
            .sum::<u64>();
    }
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    for &(pipe, group, n, per) in work {
        let (x, y) = crate::search::layout::fold_dispatch(n, per, max_dim);
        pass.set_pipeline(pipe);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
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

/// Submits `commands`, counting the submission.
pub(crate) fn submit(ctx: &crate::device::GpuContext, commands: wgpu::CommandBuffer) {
    if let Ok(mut t) = ctx.traffic.lock() {
        t.submits += 1;
    }
    ctx.queue.submit([commands]);
}

/// A bind group for group 0 of `pipeline` with `resources` at the given binding numbers.
pub(crate) fn bind_group_at(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    resources: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .iter()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: *i,
            resource: r.clone(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// A bind group for group 0 of `pipeline` with `resources` at bindings 0, 1, 2, …
pub(crate) fn bind_group(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    resources: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let numbered: Vec<(u32, wgpu::BindingResource)> = resources
        .iter()
        .cloned()
        .enumerate()
        .map(|(i, r)| (i as u32, r))
        .collect();
    bind_group_at(device, pipeline, &numbered)
}
