//! Submissions and GPU timestamps: every submit of abut goes through [`submit`], which counts
//! it and, with timestamps on (`Device::enable_timestamps`), reads back each labelled pass's
//! GPU time into the device's traffic.

/// Finishes and submits `enc`, counting the submission; with timestamps on, resolves them,
/// waits for them and adds each pass's GPU time to the device's traffic.
pub(crate) fn submit(ctx: &super::GpuContext, mut enc: wgpu::CommandEncoder) {
    if let Ok(mut t) = ctx.traffic.lock() {
        t.submits += 1;
    }
    let mut profiler = ctx.profiler.lock().ok();
    let p = profiler.as_mut().and_then(|p| p.as_mut());
    match p {
        Some(p) if !p.labels.is_empty() => {
            p.resolve(&mut enc);
            ctx.queue.submit([enc.finish()]);
            if let Ok(mut t) = ctx.traffic.lock() {
                t.waits += 1;
            }
            let times = p.read(&ctx.device, ctx.queue.get_timestamp_period());
            if let Ok(mut t) = ctx.traffic.lock() {
                for (label, ns) in times {
                    *t.pass_ns.entry(label).or_default() += ns;
                }
            }
        }
        _ => {
            ctx.queue.submit([enc.finish()]);
        }
    }
}

/// Timestamp queries around compute passes (see `Device::enable_timestamps`).
pub(crate) struct Profiler {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Labels of the passes given timestamps since the last submission, in order.
    labels: Vec<String>,
}

/// Passes with timestamps per submission (later ones go untimed).
const PROFILED_PASSES: u32 = 32;

impl Profiler {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let n = 2 * PROFILED_PASSES;
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("abut timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: n,
        });
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("abut timestamps"),
                size: 8 * n as u64,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            set,
            resolve: buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
            labels: Vec::new(),
        }
    }

    /// The timestamp writes for the next pass, labelled `label` (none once the set is full).
    pub(crate) fn next(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let k = self.labels.len() as u32;
        if k >= PROFILED_PASSES {
            return None;
        }
        self.labels.push(label.to_string());
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        let n = 2 * self.labels.len() as u32;
        enc.resolve_query_set(&self.set, 0..n, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, 8 * n as u64);
    }

    /// Waits for the resolved timestamps; (label, nanoseconds) per pass.
    fn read(&mut self, device: &wgpu::Device, period_ns: f32) -> Vec<(String, f64)> {
        let n = 2 * self.labels.len() as u64;
        let labels = std::mem::take(&mut self.labels);
        let slice = self.readback.slice(..8 * n);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        if !matches!(rx.recv(), Ok(Ok(()))) {
            return Vec::new();
        }
        let stamps: Vec<u64> = match slice.get_mapped_range() {
            Ok(view) => bytemuck::pod_collect_to_vec(&view),
            Err(_) => return Vec::new(),
        };
        self.readback.unmap();
        labels
            .into_iter()
            .enumerate()
            .map(|(k, l)| {
                let d = stamps[2 * k + 1].saturating_sub(stamps[2 * k]);
                (l, d as f64 * period_ns as f64)
            })
            .collect()
    }
}
