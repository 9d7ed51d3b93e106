//! Finding and opening adapters: the environment's filters (`WGPU_BACKEND`,
//! `WGPU_ADAPTER_NAME`), the adapters ranked best first, the instance flags, and the limits
//! abut asks a device for.

use super::{Error, Result};

/// What the environment narrowed the adapters to, for the error that none was found.
#[cfg(not(target_arch = "wasm32"))]
pub(super) fn search_detail() -> String {
    let mut d = Vec::new();
    if let Ok(b) = std::env::var("WGPU_BACKEND") {
        d.push(format!("WGPU_BACKEND={b}"));
    }
    if let Ok(n) = std::env::var("WGPU_ADAPTER_NAME") {
        d.push(format!("WGPU_ADAPTER_NAME={n}"));
    }
    if d.is_empty() {
        String::new()
    } else {
        format!(": {}", d.join(", "))
    }
}

/// wgpu's default instance flags without `VALIDATION_INDIRECT_CALL`, then the environment's
/// `WGPU_*` flags (`WGPU_VALIDATION_INDIRECT_CALL=1` turns it back on). That validation makes
/// wgpu add a compute dispatch of its own, with its barriers, before every indirect dispatch —
/// about twenty per device-resident increment, paid on the host when recording and on the device
/// even when the arguments are zero. Every indirect argument abut dispatches is written by its own
/// shaders within the limits by construction (the plan's slots folded on the host to the device's
/// workgroups per dimension, the nearest-facet arguments folded in `nearest_args`); the fold is
/// tested over the whole range of counts in `tests/bounded_work.rs`.
pub(crate) fn instance_flags() -> wgpu::InstanceFlags {
    let mut flags = wgpu::InstanceFlags::default();
    flags.remove(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
    flags.with_env()
}

/// Adapters of `backends` that can run compute shaders, filtered by the environment
/// (`WGPU_BACKEND` narrows `backends` further, `WGPU_ADAPTER_NAME` the names), best first.
#[cfg(not(target_arch = "wasm32"))]
pub(super) fn ranked_adapters(backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let backends = wgpu::Backends::from_env().map_or(backends, |env| env & backends);
    let name = std::env::var("WGPU_ADAPTER_NAME")
        .ok()
        .map(|n| n.to_lowercase());
    ranked(backends, name.as_deref())
}

/// Adapters of `backends` that can run compute shaders and whose lowercased name contains
/// `name` (already lowercase), best first.
#[cfg(not(target_arch = "wasm32"))]
pub(super) fn ranked(backends: wgpu::Backends, name: Option<&str>) -> Vec<wgpu::Adapter> {
    if backends.is_empty() {
        return Vec::new();
    }
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    desc.flags = instance_flags();
    let instance = wgpu::Instance::new(desc);
    let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
    adapters.retain(|a| {
        let info = a.get_info();
        let compute = a
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS);
        compute && name.is_none_or(|n| info.name.to_lowercase().contains(n))
    });
    adapters.sort_by_key(|a| {
        let info = a.get_info();
        let ty = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Other => 3,
            wgpu::DeviceType::Cpu => 4,
        };
        let be = match info.backend {
            wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 0,
            _ => 1,
        };
        (ty, be)
    });
    adapters
}

/// The limits abut asks for, checked against what an adapter or device offers (`have`):
/// WebGPU's compute defaults, storage bindings as large as offered (the workspace grows into
/// them). The error names the first limit that falls short.
pub(super) fn required_limits(have: &wgpu::Limits, adapter: &str) -> Result<wgpu::Limits> {
    let mut need = wgpu::Limits::downlevel_defaults();
    need.max_storage_buffers_per_shader_stage = 8;
    need.max_compute_workgroup_size_x = 256;
    need.max_compute_invocations_per_workgroup = 256;
    need.max_compute_workgroups_per_dimension = 65_535;
    need.max_storage_buffer_binding_size = have.max_storage_buffer_binding_size;
    need.max_buffer_size = have.max_buffer_size;
    let mut failed = None;
    need.check_limits_with_fail_fn(have, true, |name, needed, available| {
        failed = Some((name, needed, available));
    });
    if let Some((limit, needed, available)) = failed {
        return Err(Error::AdapterLimit {
            adapter: adapter.to_string(),
            limit,
            available,
            needed,
        });
    }
    Ok(need)
}
