//! `abut.Device`: a GPU adapter or the CPU path.

use crate::errors::{bad, guarded, raise};
use abut_rs as abut;
use pyo3::prelude::*;

/// A device: a GPU adapter or the CPU path.
#[pyclass(module = "abut._abut", frozen)]
pub(crate) struct Device {
    pub(crate) inner: abut::Device,
}

#[pymethods]
impl Device {
    /// The best GPU adapter, else the CPU path (ABUT_BACKEND=cpu|gpu in the environment applies).
    #[staticmethod]
    fn auto() -> PyResult<Self> {
        guarded("Device.auto", || {
            Ok(Self {
                inner: abut::Device::auto().map_err(raise)?,
            })
        })
    }

    /// The CPU path (the kernels' mirrors, on all cores).
    #[staticmethod]
    fn cpu() -> Self {
        Self {
            inner: abut::Device::cpu(),
        }
    }

    /// A GPU adapter of `backend` ("any", "vulkan", "gl", "metal", "dx12") whose name contains
    /// `name` (case-insensitive; None: any).
    #[staticmethod]
    #[pyo3(signature = (backend = "any", name = None))]
    fn gpu(backend: &str, name: Option<&str>) -> PyResult<Self> {
        let b = match backend {
            "any" => abut::Backend::Any,
            "vulkan" => abut::Backend::Vulkan,
            "gl" => abut::Backend::Gl,
            "metal" => abut::Backend::Metal,
            "dx12" => abut::Backend::Dx12,
            o => {
                return Err(bad(format!(
                    "backend {o:?}: one of \"any\", \"vulkan\", \"gl\", \"metal\", \"dx12\""
                )))
            }
        };
        guarded("Device.gpu", || {
            Ok(Self {
                inner: abut::Device::choose(b, name).map_err(raise)?,
            })
        })
    }

    /// True for a GPU adapter, False for the CPU path.
    #[getter]
    fn is_gpu(&self) -> bool {
        self.inner.is_gpu()
    }

    fn __str__(&self) -> String {
        self.inner.to_string()
    }

    fn __repr__(&self) -> String {
        format!("abut.Device({})", self.inner)
    }
}
