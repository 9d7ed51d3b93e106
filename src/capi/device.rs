//! C ABI: the device (a GPU adapter or the CPU path).

use super::handles::{self, Object};
use super::types::{enum_value, AbutBackend, AbutDeviceKind, AbutStatus};
use super::{copy_text, put};
use crate::{Backend, Device};
use std::ffi::CStr;

/// A device: a GPU adapter or the CPU path. Opaque; made by `abut_device_new`, freed by
/// `abut_device_free`. A contact made on it keeps what it needs, so the device may be freed
/// before its contacts.
pub struct AbutDevice {
    _opaque: [u8; 0],
}

/// Makes a device: `kind` an `AbutDeviceKind`; for `ABUT_DEVICE_KIND_GPU`, `backend` an
/// `AbutBackend` and `name` (may be null: any) text the adapter's name must contain,
/// case-insensitive. `*out` receives the handle. Errors: no such adapter
/// (`ABUT_STATUS_DEVICE`, naming what was asked).
///
/// # Safety
/// `name` null or a NUL-terminated string; `out` valid for one handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_device_new(
    kind: i32,
    backend: i32,
    name: *const std::ffi::c_char,
    out: *mut *mut AbutDevice,
) -> AbutStatus {
    const CALL: &str = "abut_device_new";
    handles::guard(CALL, || {
        if out.is_null() {
            return Err(super::null(CALL, "out"));
        }
        use AbutDeviceKind as K;
        let kind = enum_value(
            kind,
            "abut_device_new: kind (an AbutDeviceKind)",
            &[(0, K::Auto), (1, K::Cpu), (2, K::Gpu)],
        )?;
        let device = match kind {
            K::Auto => Device::auto()?,
            K::Cpu => Device::cpu(),
            K::Gpu => {
                use AbutBackend as B;
                let b = enum_value(
                    backend,
                    "abut_device_new: backend (an AbutBackend)",
                    &[
                        (0, B::Any),
                        (1, B::Vulkan),
                        (2, B::Gl),
                        (3, B::Metal),
                        (4, B::Dx12),
                    ],
                )?;
                let backend = match b {
                    B::Any => Backend::Any,
                    B::Vulkan => Backend::Vulkan,
                    B::Gl => Backend::Gl,
                    B::Metal => Backend::Metal,
                    B::Dx12 => Backend::Dx12,
                };
                let name = if name.is_null() {
                    None
                } else {
                    Some(unsafe { CStr::from_ptr(name) }.to_str().map_err(|_| {
                        handles::Fail::new(
                            AbutStatus::BadValue,
                            "abut_device_new: name is not UTF-8",
                        )
                    })?)
                };
                Device::choose(backend, name)?
            }
        };
        let h = handles::register(Object::Device(device));
        unsafe { put(out, h as *mut AbutDevice, CALL, "out") }
    })
}

/// Frees a device (null: nothing). Its contacts stay usable.
///
/// # Safety
/// None beyond passing a value abut gave (a freed or foreign handle is a named error).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_device_free(device: *mut AbutDevice) -> AbutStatus {
    handles::release(device as usize, "abut_device_free", "device")
}

/// Describes the device (adapter name and backend, or "CPU path") into `buf` as
/// `abut_last_error` copies text; `len` (may be null) receives the full length.
///
/// # Safety
/// `buf` valid for `cap` bytes; `len` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_device_describe(
    device: *const AbutDevice,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
) -> AbutStatus {
    const CALL: &str = "abut_device_describe";
    handles::with_device(device as usize, CALL, |d| unsafe {
        copy_text(&d.to_string(), buf, cap, len, CALL)
    })
}

/// `*is_gpu` receives 1 for a GPU adapter, 0 for the CPU path.
///
/// # Safety
/// `is_gpu` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_device_is_gpu(
    device: *const AbutDevice,
    is_gpu: *mut i32,
) -> AbutStatus {
    const CALL: &str = "abut_device_is_gpu";
    handles::with_device(device as usize, CALL, |d| unsafe {
        put(is_gpu, d.is_gpu() as i32, CALL, "is_gpu")
    })
}

/// Copies the last error message of `device` into `buf` (as `abut_last_error`).
///
/// # Safety
/// As `abut_last_error`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_device_error(
    device: *const AbutDevice,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
) -> AbutStatus {
    unsafe { handle_error(device as usize, "abut_device_error", buf, cap, len) }
}

/// The last error of any handle into the caller's buffer.
pub(crate) unsafe fn handle_error(
    handle: usize,
    call: &str,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
) -> AbutStatus {
    handles::guard(call, || {
        if handle == 0 {
            return Err(super::null(call, "handle"));
        }
        let m = handles::last_error(handle, call)?;
        unsafe { copy_text(&m, buf, cap, len, call) }
    })
}
