//! abut's C ABI (feature `capi`): the functions of `include/abut.h`, built into `libabut.so`
//! and `libabut.a` by the `capi/` crate, and the Fortran module `capi/fortran/abut.f90` over them.
//!
//! Conventions every function keeps (the header's preamble says the same to C programmers):
//! - every call returns an [`AbutStatus`]; on failure the message, naming the item at fault as
//!   the Rust error does, is kept per handle (`abut_*_error`) and per thread (`abut_last_error`);
//! - handles are opaque and checked (`handles.rs`): null, freed and wrong-kind handles are named
//!   errors; a panic is caught at the boundary;
//! - arrays are the caller's, f64 and xyz interleaved, read (or written) during the call only;
//!   abut keeps no pointer the caller passed;
//! - a handle may be used from any thread; calls on one handle take turns.

mod contact;
mod device;
mod handles;
mod model;
pub mod types;

pub use contact::*;
pub use device::*;
pub use model::*;
pub use types::*;

use handles::Fail;

/// A node id that names no node: the fourth node of a triangle in a quad array.
pub const ABUT_NO_NODE: u32 = u32::MAX;

/// The library's version, major·10000 + minor·100 + patch.
#[unsafe(no_mangle)]
pub extern "C" fn abut_version() -> u32 {
    let p = |s: &str| s.parse::<u32>().unwrap_or(0);
    p(env!("CARGO_PKG_VERSION_MAJOR")) * 10000
        + p(env!("CARGO_PKG_VERSION_MINOR")) * 100
        + p(env!("CARGO_PKG_VERSION_PATCH"))
}

/// Copies the last error message of this thread (any call, any handle, or a call that failed
/// before it found its handle) into `buf`: at most `cap` − 1 bytes of UTF-8 and a NUL. `len`
/// (may be null) receives the message's full length in bytes, so a caller can size `buf`.
/// `buf` may be null when `cap` is 0. An empty message: no error yet on this thread.
///
/// # Safety
/// `buf` must be valid for `cap` bytes; `len` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_last_error(buf: *mut u8, cap: usize, len: *mut usize) -> AbutStatus {
    handles::guard("abut_last_error", || {
        let m = handles::last_error(0, "abut_last_error")?;
        copy_text(&m, buf, cap, len, "abut_last_error")
    })
}

/// Copies `text` into the caller's `buf` of `cap` bytes (truncated, NUL-terminated), its full
/// length into `len` (nullable).
pub(crate) unsafe fn copy_text(
    text: &str,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
    call: &str,
) -> Result<(), Fail> {
    if !len.is_null() {
        unsafe { len.write(text.len()) };
    }
    if cap == 0 {
        return Ok(());
    }
    if buf.is_null() {
        return Err(null(call, "buf"));
    }
    let n = text.len().min(cap - 1);
    unsafe {
        std::ptr::copy_nonoverlapping(text.as_ptr(), buf, n);
        buf.add(n).write(0);
    }
    Ok(())
}

/// The error for a null `arg` of `call`.
pub(crate) fn null(call: &str, arg: &str) -> Fail {
    Fail::new(
        AbutStatus::NullPointer,
        format!("{call}: argument {arg} is null"),
    )
}

/// The caller's array `p` of `len` items as a slice (argument `arg` of `call`): null and
/// misaligned pointers are errors.
pub(crate) unsafe fn input<'a, T>(
    p: *const T,
    len: usize,
    call: &str,
    arg: &str,
) -> Result<&'a [T], Fail> {
    aligned(p, call, arg)?;
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// As [`input`], writable.
pub(crate) unsafe fn output<'a, T>(
    p: *mut T,
    len: usize,
    call: &str,
    arg: &str,
) -> Result<&'a mut [T], Fail> {
    aligned(p, call, arg)?;
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

fn aligned<T>(p: *const T, call: &str, arg: &str) -> Result<(), Fail> {
    if p.is_null() {
        return Err(null(call, arg));
    }
    if !(p as usize).is_multiple_of(std::mem::align_of::<T>()) {
        return Err(Fail::new(
            AbutStatus::BadValue,
            format!(
                "{call}: argument {arg} is not aligned to {} bytes",
                std::mem::align_of::<T>()
            ),
        ));
    }
    Ok(())
}

/// Writes `value` to the caller's `p` (argument `arg` of `call`).
pub(crate) unsafe fn put<T>(p: *mut T, value: T, call: &str, arg: &str) -> Result<(), Fail> {
    aligned(p, call, arg)?;
    unsafe { p.write(value) };
    Ok(())
}

/// `n`·`k` for array lengths, or the error naming `arg`.
pub(crate) fn times(n: usize, k: usize, call: &str, arg: &str) -> Result<usize, Fail> {
    n.checked_mul(k).ok_or_else(|| {
        Fail::new(
            AbutStatus::Length,
            format!("{call}: argument {arg}: {n} entries of {k} overflow"),
        )
    })
}
