//! Where abut runs: a GPU adapter chosen in one place, or the CPU path.
//!
//! Choice, in order: a discrete, integrated or virtual GPU; then a software adapter (Vulkan
//! lavapipe before GL llvmpipe); then, for [`Device::auto`], the CPU path with a notice on
//! stderr. `WGPU_BACKEND` (e.g. `vulkan`, `gl`) restricts the backends, `WGPU_ADAPTER_NAME`
//! keeps adapters whose name contains it (case-insensitive), and `ABUT_BACKEND=cpu` selects
//! the CPU path outright.

use std::fmt;
use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

mod adapters;
mod pipelines;
mod profiler;

pub(crate) use adapters::instance_flags;
use adapters::required_limits;
#[cfg(not(target_arch = "wasm32"))]
use adapters::{ranked, ranked_adapters, search_detail};
pub(crate) use profiler::{submit, Profiler};

/// A wgpu device with the adapter facts abut reports. Shared by every search on it.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, driver, backend, type.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was created with.
    pub limits: wgpu::Limits,
    /// Errors wgpu raised outside an error scope (kept instead of panicking).
    pub uncaptured: Arc<Mutex<Vec<String>>>,
    /// What the executors have dispatched and moved so far (see [`Traffic`]).
    pub traffic: Arc<Mutex<Traffic>>,
    /// GPU timestamps around each compute pass, when switched on
    /// ([`Device::enable_timestamps`]) on an adapter with `TIMESTAMP_QUERY`.
    pub(crate) profiler: Mutex<Option<profiler::Profiler>>,
    /// The compute pipelines compiled on this device, by pass and constants.
    pub(crate) pipelines: Mutex<pipelines::PipelineCache>,
}

/// Running totals of what the GPU executors did on one device: compute passes and their
/// dispatches, workgroups, and bytes moved between host and device. Take a snapshot before
/// and after a stretch of work ([`Device::traffic`]) and subtract ([`Traffic::since`]).
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "solver", derive(serde::Serialize))]
pub struct Traffic {
    /// Dispatches per compute pass, by the pass's label.
    pub dispatches: std::collections::BTreeMap<String, u64>,
    /// Workgroups launched.
    pub workgroups: u64,
    /// Bytes written from the host into device buffers.
    pub uploaded_bytes: u64,
    /// Bytes read back from the device.
    pub read_back_bytes: u64,
    /// Command submissions.
    pub submits: u64,
    /// Times the host blocked until the device finished (a readback's map, a timestamp read).
    pub waits: u64,
    /// Bytes read from the lagged statistics ring of device-resident increments (mapped a few
    /// increments late, never waited for).
    pub lagged_read_bytes: u64,
    /// GPU time per compute pass, by label, in nanoseconds (timestamp queries; empty unless
    /// [`Device::enable_timestamps`] succeeded).
    pub pass_ns: std::collections::BTreeMap<String, f64>,
    /// Shader modules compiled (each kernel file at most once per device).
    pub shader_modules_compiled: u64,
    /// Compute pipelines compiled (each pass and constants at most once per device, however
    /// many pairs, contacts and searches use it).
    pub pipelines_compiled: u64,
}

/// The entries of `now` that grew since `then`, by how much.
fn map_since<T>(
    now: &std::collections::BTreeMap<String, T>,
    then: &std::collections::BTreeMap<String, T>,
) -> std::collections::BTreeMap<String, T>
where
    T: Copy + Default + PartialOrd + std::ops::Sub<Output = T>,
{
    now.iter()
        .map(|(k, &v)| (k.clone(), v - then.get(k).copied().unwrap_or_default()))
        .filter(|(_, v)| *v > T::default())
        .collect()
}

impl Traffic {
    /// What happened after `earlier` (a snapshot of the same device).
    pub fn since(&self, earlier: &Traffic) -> Traffic {
        Traffic {
            dispatches: map_since(&self.dispatches, &earlier.dispatches),
            workgroups: self.workgroups - earlier.workgroups,
            uploaded_bytes: self.uploaded_bytes - earlier.uploaded_bytes,
            read_back_bytes: self.read_back_bytes - earlier.read_back_bytes,
            submits: self.submits - earlier.submits,
            waits: self.waits - earlier.waits,
            lagged_read_bytes: self.lagged_read_bytes - earlier.lagged_read_bytes,
            pass_ns: map_since(&self.pass_ns, &earlier.pass_ns),
            shader_modules_compiled: self.shader_modules_compiled - earlier.shader_modules_compiled,
            pipelines_compiled: self.pipelines_compiled - earlier.pipelines_compiled,
        }
    }

    /// Total dispatches.
    pub fn total_dispatches(&self) -> u64 {
        self.dispatches.values().sum()
    }
}

impl fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuContext")
            .field("info", &self.info)
            .finish()
    }
}

/// A graphics API to take a GPU adapter from ([`Device::choose`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Vulkan (Linux, Windows, Android; Mesa's lavapipe is a software Vulkan adapter).
    Vulkan,
    /// OpenGL / OpenGL ES (Mesa's llvmpipe is a software GL adapter).
    Gl,
    /// Metal (macOS, iOS).
    Metal,
    /// Direct3D 12 (Windows).
    Dx12,
    /// Any of them, the best adapter first.
    Any,
}

impl Backend {
    #[cfg(not(target_arch = "wasm32"))]
    fn wgpu(self) -> wgpu::Backends {
        match self {
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
            Backend::Metal => wgpu::Backends::METAL,
            Backend::Dx12 => wgpu::Backends::DX12,
            Backend::Any => wgpu::Backends::all(),
        }
    }
}

/// Which executor a [`Device`] runs.
#[derive(Clone, Debug)]
pub enum DeviceKind {
    /// A wgpu adapter.
    Gpu(Arc<GpuContext>),
    /// The CPU mirror of the kernels.
    Cpu,
}

/// A place to run contact searches: a GPU adapter or the CPU path. Always printable.
#[derive(Clone, Debug)]
pub struct Device {
    kind: DeviceKind,
}

impl Device {
    #[cfg(not(target_arch = "wasm32"))]
    /// The best available device: a GPU adapter if there is one, else the CPU path (with a
    /// notice on stderr). `ABUT_BACKEND=cpu` forces the CPU path, `ABUT_BACKEND=gpu` makes a
    /// missing adapter an error.
    pub fn auto() -> Result<Self> {
        match std::env::var("ABUT_BACKEND").as_deref() {
            Ok("cpu") => return Ok(Self::cpu()),
            Ok("gpu") => return Self::gpu(),
            _ => {}
        }
        match Self::gpu() {
            Ok(d) => Ok(d),
            Err(Error::NoAdapter { detail }) => {
                eprintln!("abut: no GPU adapter found{detail}; running on the CPU path (slow)");
                Ok(Self::cpu())
            }
            Err(e) => Err(e),
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    /// The best GPU adapter, or [`Error::NoAdapter`].
    pub fn gpu() -> Result<Self> {
        let mut last_err = None;
        // GL is only probed when no Vulkan/Metal/DX12 adapter exists (probing it is slow and
        // noisy on headless machines).
        let mut adapters = ranked_adapters(wgpu::Backends::PRIMARY);
        if adapters.is_empty() {
            adapters = ranked_adapters(wgpu::Backends::GL);
        }
        for adapter in adapters {
            match GpuContext::new(adapter) {
                Ok(ctx) => return Ok(Self::from_context(ctx)),
                Err(e) => last_err = Some(e),
            }
        }
        Err(last_err.unwrap_or_else(|| Error::NoAdapter {
            detail: search_detail(),
        }))
    }

    #[cfg(not(target_arch = "wasm32"))]
    /// The best GPU adapter of `backend` whose name contains `name` (case-insensitive; `None`:
    /// any name), chosen in code: the environment's `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` do
    /// not apply. [`Error::NoAdapter`] names what was asked when there is none. The device
    /// prints its name and backend (`lavapipe` and `llvmpipe` are told apart by the backend).
    pub fn choose(backend: Backend, name: Option<&str>) -> Result<Self> {
        let name = name.map(str::to_lowercase);
        let mut last_err = None;
        for adapter in ranked(backend.wgpu(), name.as_deref()) {
            match GpuContext::new(adapter) {
                Ok(ctx) => return Ok(Self::from_context(ctx)),
                Err(e) => last_err = Some(e),
            }
        }
        Err(last_err.unwrap_or_else(|| Error::NoAdapter {
            detail: format!(
                ": backend {backend:?}{}",
                name.map_or(String::new(), |n| format!(", name containing \"{n}\""))
            ),
        }))
    }

    #[cfg(not(target_arch = "wasm32"))]
    /// Every usable GPU adapter, best first (tests run their parity checks on each).
    pub fn all_gpus() -> Vec<Result<Self>> {
        ranked_adapters(wgpu::Backends::all())
            .into_iter()
            .map(|a| GpuContext::new(a).map(Self::from_context))
            .collect()
    }

    /// A GPU adapter of `backends` that runs compute shaders, the one wgpu picks for high
    /// performance, without blocking: the way to a device where nothing may wait on the GPU — a
    /// browser's WebGPU (`wgpu::Backends::BROWSER_WEBGPU`) — or in an async host. The
    /// environment's `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` do not apply. Errors as
    /// [`Device::gpu`]'s: [`Error::NoAdapter`] (none, or none with compute shaders),
    /// [`Error::AdapterLimit`], [`Error::RequestDevice`].
    pub async fn request(backends: wgpu::Backends) -> Result<Self> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        desc.flags = instance_flags();
        let instance = wgpu::Instance::new(desc);
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        };
        let adapter = instance
            .request_adapter(&options)
            .await
            .map_err(|e| Error::NoAdapter {
                detail: format!(": backends {backends:?}: {e}"),
            })?;
        let compute = adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS);
        if !compute {
            return Err(Error::NoAdapter {
                detail: format!(
                    ": backends {backends:?}: {} runs no compute shaders",
                    adapter.get_info().name
                ),
            });
        }
        Ok(Self::from_context(GpuContext::request(adapter).await?))
    }

    /// A device on the caller's own wgpu device and queue, so that searches can read positions
    /// the caller keeps in its own buffers. Errors when the device's limits fall short of what
    /// abut needs (8 storage buffers per stage, workgroups of 256, 65,535 per dimension).
    pub fn from_wgpu(device: wgpu::Device, queue: wgpu::Queue) -> Result<Self> {
        let info = device.adapter_info();
        let limits = device.limits();
        required_limits(&limits, &info.name)?;
        // the caller's uncaptured-error handler is left alone: abut's own operations run in
        // error scopes and report through them
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        Ok(Self::from_context(GpuContext::assemble(
            device, queue, info, limits, uncaptured,
        )))
    }

    /// The wgpu device and queue of a GPU device (to make buffers on it), `None` on the CPU path.
    pub fn wgpu(&self) -> Option<(&wgpu::Device, &wgpu::Queue)> {
        match &self.kind {
            DeviceKind::Gpu(c) => Some((&c.device, &c.queue)),
            DeviceKind::Cpu => None,
        }
    }

    /// The CPU path.
    pub fn cpu() -> Self {
        Self {
            kind: DeviceKind::Cpu,
        }
    }

    fn from_context(ctx: GpuContext) -> Self {
        Self {
            kind: DeviceKind::Gpu(Arc::new(ctx)),
        }
    }

    /// Switches GPU timestamps around every compute pass on or off; their durations then
    /// accumulate in [`Traffic::pass_ns`]. Returns whether timestamps are on: false on the CPU
    /// path and on adapters without `TIMESTAMP_QUERY` (time by the wall clock there). Each
    /// submission then waits for its timestamps: for measuring, not for production runs.
    pub fn enable_timestamps(&self, on: bool) -> bool {
        let DeviceKind::Gpu(c) = &self.kind else {
            return false;
        };
        let Ok(mut p) = c.profiler.lock() else {
            return false;
        };
        if !on
            || !c
                .device
                .features()
                .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            *p = None;
            return false;
        }
        if p.is_none() {
            *p = Some(Profiler::new(&c.device));
        }
        true
    }

    /// A snapshot of what the GPU executors have dispatched and moved on this device so far
    /// (`None` on the CPU path, which dispatches nothing).
    pub fn traffic(&self) -> Option<Traffic> {
        match self.kind() {
            DeviceKind::Gpu(ctx) => Some(ctx.traffic.lock().map(|t| t.clone()).unwrap_or_default()),
            DeviceKind::Cpu => None,
        }
    }

    /// Submits an encoder the host recorded abut's passes into (device-resident increments,
    /// `gpu::CentralDifference`), counting it in [`Traffic`] and, with timestamps on
    /// ([`Device::enable_timestamps`]), reading the passes' times (which waits). The host may
    /// as well submit with its own queue; then nothing is counted. Errors on the CPU path.
    pub fn submit(&self, encoder: wgpu::CommandEncoder) -> Result<()> {
        match &self.kind {
            DeviceKind::Gpu(ctx) => {
                submit(ctx, encoder);
                Ok(())
            }
            DeviceKind::Cpu => Err(Error::BadParameter {
                name: "submit",
                value: "CPU path".into(),
                expected: "a GPU device",
            }),
        }
    }

    /// The executor behind this device.
    pub fn kind(&self) -> &DeviceKind {
        &self.kind
    }

    /// The GPU context of a GPU device (`None` on the CPU path), for what only a GPU does.
    pub(crate) fn gpu_context(&self) -> Option<&Arc<GpuContext>> {
        match &self.kind {
            DeviceKind::Gpu(ctx) => Some(ctx),
            DeviceKind::Cpu => None,
        }
    }

    /// True for a GPU adapter.
    pub fn is_gpu(&self) -> bool {
        matches!(self.kind, DeviceKind::Gpu(_))
    }

    /// The backend's short name: "vulkan", "gl", "metal", "dx12", or "cpu".
    pub fn backend_name(&self) -> String {
        match &self.kind {
            DeviceKind::Gpu(c) => c.info.backend.to_str().to_string(),
            DeviceKind::Cpu => "cpu".into(),
        }
    }
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            DeviceKind::Gpu(c) => {
                let i = &c.info;
                write!(
                    f,
                    "{} ({:?}, {} backend, driver {} {})",
                    i.name,
                    i.device_type,
                    i.backend.to_str(),
                    i.driver,
                    i.driver_info
                )
            }
            DeviceKind::Cpu => write!(f, "CPU path (abut's CPU mirror of the kernels, f32)"),
        }
    }
}

/// Distinct errors an uncaptured-error list keeps; the rest are counted in the last entry (an
/// invalid pipeline repeats its error at every increment that uses it).
const KEPT_ERRORS: usize = 8;

/// Adds `message` to an uncaptured-error list: once, and at most [`KEPT_ERRORS`] distinct ones.
fn note_error(sink: &Mutex<Vec<String>>, message: String) {
    let Ok(mut v) = sink.lock() else { return };
    if v.contains(&message) {
        return;
    }
    if v.len() < KEPT_ERRORS {
        v.push(message);
    } else if v.len() == KEPT_ERRORS {
        v.push("and further errors".into());
    }
}

impl GpuContext {
    /// Creates a device on `adapter` with [`required_limits`], waiting for it (native targets).
    #[cfg(not(target_arch = "wasm32"))]
    fn new(adapter: wgpu::Adapter) -> Result<Self> {
        pollster::block_on(Self::request(adapter))
    }

    /// Requests a device on `adapter` with [`required_limits`], without blocking.
    async fn request(adapter: wgpu::Adapter) -> Result<Self> {
        let info = adapter.get_info();
        let limits = required_limits(&adapter.limits(), &info.name)?;
        // timestamp queries are an optional fast path of the benchmark: asked for when there
        let desc = wgpu::DeviceDescriptor {
            label: Some("abut"),
            required_limits: limits.clone(),
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            ..Default::default()
        };
        let (device, queue) =
            adapter
                .request_device(&desc)
                .await
                .map_err(|source| Error::RequestDevice {
                    adapter: info.name.clone(),
                    source,
                })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            note_error(&sink, e.to_string());
        }));
        Ok(Self::assemble(device, queue, info, limits, uncaptured))
    }

    /// A context on `device` with nothing dispatched, compiled or timed yet.
    fn assemble(
        device: wgpu::Device,
        queue: wgpu::Queue,
        info: wgpu::AdapterInfo,
        limits: wgpu::Limits,
        uncaptured: Arc<Mutex<Vec<String>>>,
    ) -> Self {
        Self {
            device,
            queue,
            info,
            limits,
            uncaptured,
            traffic: Arc::default(),
            profiler: Mutex::new(None),
            pipelines: Mutex::default(),
        }
    }

    /// The validation error `scope` caught in the operation that just ran inside it: waited for
    /// on native targets. A browser cannot wait on the GPU; there the scope's error joins the
    /// uncaptured errors when it arrives, which [`GpuContext::take_uncaptured`] reports at the
    /// increment's next check, and this returns `None`.
    pub(crate) fn scope_error(&self, scope: wgpu::ErrorScopeGuard) -> Option<wgpu::Error> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            pollster::block_on(scope.pop())
        }
        #[cfg(target_arch = "wasm32")]
        {
            let sink = self.uncaptured.clone();
            let popped = scope.pop();
            wasm_bindgen_futures::spawn_local(async move {
                if let Some(e) = popped.await {
                    note_error(&sink, e.to_string());
                }
            });
            None
        }
    }

    /// Takes the errors wgpu raised outside error scopes since the last call, as one error.
    pub fn take_uncaptured(&self, during: &str) -> Result<()> {
        let mut v = self.uncaptured.lock().map_err(|_| Error::Gpu {
            during: during.into(),
            message: "error log poisoned".into(),
        })?;
        if v.is_empty() {
            Ok(())
        } else {
            let message = v.join("; ");
            v.clear();
            Err(Error::Gpu {
                during: during.into(),
                message,
            })
        }
    }
}
