//! A storage buffer that only grows, and blocking readback.

use crate::error::{Error, Result};

/// A device buffer with a capacity in bytes; [`GrowBuffer::ensure`] reallocates (larger) only
/// when asked for more, and says so, so that bind groups are rebuilt only then.
pub struct GrowBuffer {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    label: &'static str,
    usage: wgpu::BufferUsages,
    /// Whether the buffer is bound as storage (and so limited by the binding size).
    storage: bool,
}

impl GrowBuffer {
    /// A buffer of at least `bytes` (at least 256) with `usage`.
    pub fn new(
        device: &wgpu::Device,
        label: &'static str,
        bytes: u64,
        usage: wgpu::BufferUsages,
    ) -> Self {
        let storage = usage.contains(wgpu::BufferUsages::STORAGE);
        Self {
            buffer: create(device, label, bytes, usage),
            label,
            usage,
            storage,
        }
    }

    /// Capacity in bytes.
    pub fn capacity(&self) -> u64 {
        self.buffer.size()
    }

    /// Makes room for `bytes`; returns true when the buffer was replaced. Errors when the
    /// device's binding or buffer size limit is too small.
    pub fn ensure(
        &mut self,
        device: &wgpu::Device,
        limits: &wgpu::Limits,
        bytes: u64,
    ) -> Result<bool> {
        let allowed = if self.storage {
            limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size)
        } else {
            limits.max_buffer_size
        };
        if bytes > allowed {
            return Err(Error::TooLarge {
                what: format!("GPU buffer '{}'", self.label),
                needed: bytes,
                allowed,
            });
        }
        if bytes <= self.capacity() {
            return Ok(false);
        }
        let grown = (bytes + bytes / 4).min(allowed);
        self.buffer = create(device, self.label, grown, self.usage);
        Ok(true)
    }
}

fn create(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let size = bytes.max(256).next_multiple_of(16);
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// Reads `len` bytes from byte `from` of each of `sources` `(buffer, from, len)` back, in
/// order, concatenated: one staging buffer, one encoder of copies, one submit, one wait.
pub(crate) fn copy_back(
    ctx: &crate::device::GpuContext,
    sources: &[(&wgpu::Buffer, u64, u64)],
    during: &str,
) -> Result<Vec<u8>> {
    let total: u64 = sources.iter().map(|s| s.2).sum();
    if total == 0 {
        return Ok(Vec::new());
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(during),
        size: total,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some(during),
        });
    let mut offset = 0;
    for &(b, from, len) in sources {
        if len > 0 {
            enc.copy_buffer_to_buffer(b, from, &staging, offset, len);
        }
        offset += len;
    }
    crate::device::submit(ctx, enc);
    read_back(ctx, &staging, total, during)
}

/// Maps `buffer` (MAP_READ) for `bytes`, waits, copies the bytes out and unmaps.
pub fn read_back(
    ctx: &crate::device::GpuContext,
    buffer: &wgpu::Buffer,
    bytes: u64,
    during: &str,
) -> Result<Vec<u8>> {
    read_back_with(ctx, buffer, bytes, during, <[u8]>::to_vec)
}

/// Like [`read_back`], handing the mapped bytes to `take` instead of copying them first (one
/// copy of a large readback instead of two).
pub fn read_back_with<T>(
    ctx: &crate::device::GpuContext,
    buffer: &wgpu::Buffer,
    bytes: u64,
    during: &str,
    take: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    // a browser's thread cannot wait for the device: refused by name rather than left to hang
    #[cfg(target_arch = "wasm32")]
    {
        let _ = (ctx, buffer, take);
        Err(Error::BadParameter {
            name: "readback",
            value: format!("{bytes} bytes waited for during {during}"),
            expected: "no waiting in a browser: the device-resident increment \
                       (Contact::encode_increment) and the caller's own awaited readbacks",
        })
    }
    #[cfg(not(target_arch = "wasm32"))]
    map_and_take(ctx, buffer, bytes, during, take)
}

/// Maps `buffer` for `bytes`, waits and hands the mapped bytes to `take` (natively).
#[cfg(not(target_arch = "wasm32"))]
fn map_and_take<T>(
    ctx: &crate::device::GpuContext,
    buffer: &wgpu::Buffer,
    bytes: u64,
    during: &str,
    take: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    if let Ok(mut t) = ctx.traffic.lock() {
        t.read_back_bytes += bytes;
        t.waits += 1;
    }
    let device = &ctx.device;
    let slice = buffer.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::DeviceLost {
            during: during.into(),
            message: e.to_string(),
        })?;
    let mapped = rx.recv().map_err(|e| Error::DeviceLost {
        during: during.into(),
        message: e.to_string(),
    })?;
    mapped.map_err(|e| Error::DeviceLost {
        during: during.into(),
        message: e.to_string(),
    })?;
    let view = slice.get_mapped_range().map_err(|e| Error::DeviceLost {
        during: during.into(),
        message: e.to_string(),
    })?;
    let out = take(&view);
    drop(view);
    buffer.unmap();
    Ok(out)
}
