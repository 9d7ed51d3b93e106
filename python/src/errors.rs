//! Exceptions for the library's errors, the guard every call runs in, and the checks of the
//! numpy arrays abut reads and writes in place.

use abut_rs as abut;
use numpy::{PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    _abut,
    AbutError,
    PyException,
    "An error of the abut library."
);
create_exception!(
    _abut,
    LengthError,
    AbutError,
    "An array's length does not match."
);
create_exception!(
    _abut,
    OutOfRangeError,
    AbutError,
    "An id or index names nothing."
);
create_exception!(
    _abut,
    BadValueError,
    AbutError,
    "A value is not allowed (NaN, ≤ 0, unknown name)."
);
create_exception!(
    _abut,
    GeometryError,
    AbutError,
    "A surface's facets cannot be used."
);
create_exception!(
    _abut,
    DeviceError,
    AbutError,
    "No adapter, or the GPU failed."
);
create_exception!(
    _abut,
    ContactError,
    AbutError,
    "The contact failed during an increment."
);
create_exception!(
    _abut,
    IoError,
    AbutError,
    "A file could not be read or parsed."
);

/// The Python exception for a library error.
pub(crate) fn raise(e: abut::Error) -> PyErr {
    use abut::error::ErrorKind as K;
    let m = e.to_string();
    match e.kind() {
        K::Length => LengthError::new_err(m),
        K::OutOfRange => OutOfRangeError::new_err(m),
        K::BadValue => BadValueError::new_err(m),
        K::Geometry => GeometryError::new_err(m),
        K::Device => DeviceError::new_err(m),
        K::Contact => ContactError::new_err(m),
        K::Io => IoError::new_err(m),
    }
}

/// Runs `f`, turning a library error into its exception and a panic into an `AbutError`.
pub(crate) fn guarded<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(AbutError::new_err(format!(
                "{what}: internal error (panic): {msg}"
            )))
        }
    }
}

pub(crate) fn bad(msg: String) -> PyErr {
    BadValueError::new_err(msg)
}

/// Checks that an array is (n, 3) and C-contiguous, as abut reads it in place.
fn check_points(shape: &[usize], c_contiguous: bool, what: &str) -> PyResult<()> {
    if shape.len() != 2 || shape[1] != 3 {
        return Err(LengthError::new_err(format!(
            "{what}: shape {shape:?}, expected (n, 3)"
        )));
    }
    if !c_contiguous {
        return Err(bad(format!(
            "{what}: not C-contiguous (pass numpy.ascontiguousarray(...); abut uses it in place)"
        )));
    }
    Ok(())
}

/// An (n, 3) float64 C-contiguous array as points, in place.
pub(crate) fn points<'a>(a: &'a PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<&'a [[f64; 3]]> {
    check_points(a.shape(), a.is_c_contiguous(), what)?;
    let flat = a.as_slice().map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(bytemuck::cast_slice(flat))
}

/// As [`points`], writable.
pub(crate) fn points_mut<'a>(
    a: &'a mut PyReadwriteArray2<'_, f64>,
    what: &str,
) -> PyResult<&'a mut [[f64; 3]]> {
    check_points(a.shape(), a.is_c_contiguous(), what)?;
    let flat = a.as_slice_mut().map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(bytemuck::cast_slice_mut(flat))
}
