//! `abut._abut`: the Rust API on numpy arrays (the `abut` package in python/abut/ re-exports it
//! with its docs and type stubs).
//!
//! Arrays: positions, velocities and forces are (n, 3) float64; C-contiguous inputs are read in
//! place (no copy), others are refused with a named error rather than copied silently. Every
//! call that does work in the library runs inside `catch_unwind`: a panic becomes an
//! `abut.AbutError`, never an abort (the few left out build empty objects or return plain
//! values; PyO3 raises its PanicException for those, never unwinding into Python). Errors are
//! raised as the subclass of `abut.AbutError` for their kind, carrying the library's message.
mod contact;
mod device;
mod errors;
mod model;

use abut_rs as abut;
use contact::{Contact, Report};
use device::Device;
use errors::*;
use model::Model;
use pyo3::prelude::*;

/// Runs the scene file at `path` on `device` (None: Device.auto()), writing its outputs into
/// `output` (a directory); returns the run's summary as JSON text.
#[pyfunction]
#[pyo3(signature = (path, output, device = None))]
fn run_scene_json(path: &str, output: &str, device: Option<&Device>) -> PyResult<String> {
    guarded("run_scene", || {
        let scene = abut::scene::Scene::load(std::path::Path::new(path)).map_err(raise)?;
        let auto;
        let d = match device {
            Some(d) => &d.inner,
            None => {
                auto = abut::Device::auto().map_err(raise)?;
                &auto
            }
        };
        let out = std::path::Path::new(output);
        std::fs::create_dir_all(out).map_err(|e| IoError::new_err(format!("{output}: {e}")))?;
        let summary = abut::scene::run(&scene, d, Some(out)).map_err(raise)?;
        serde_json::to_string(&summary).map_err(|e| AbutError::new_err(e.to_string()))
    })
}

/// The increment for nodes that carry elements and penalty springs together: from the
/// elements' stable increment (already times `safety`) and the contact's (`Report.stable_dt`),
/// 1/dt² = 1/dt_elements² + 1/(safety·dt_contact)², at most contact_safety·dt_contact.
#[pyfunction]
#[pyo3(signature = (element_dt, contact_dt, safety = 0.9, contact_safety = 0.5))]
fn combined_increment(element_dt: f64, contact_dt: f64, safety: f64, contact_safety: f64) -> f64 {
    abut::combined_increment(element_dt, contact_dt, safety, contact_safety)
}

/// abut's extension module.
#[pymodule]
fn _abut(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Device>()?;
    m.add_class::<Model>()?;
    m.add_class::<Contact>()?;
    m.add_class::<Report>()?;
    m.add_function(wrap_pyfunction!(run_scene_json, m)?)?;
    m.add_function(wrap_pyfunction!(combined_increment, m)?)?;
    let py = m.py();
    m.add("AbutError", py.get_type::<AbutError>())?;
    m.add("LengthError", py.get_type::<LengthError>())?;
    m.add("OutOfRangeError", py.get_type::<OutOfRangeError>())?;
    m.add("BadValueError", py.get_type::<BadValueError>())?;
    m.add("GeometryError", py.get_type::<GeometryError>())?;
    m.add("DeviceError", py.get_type::<DeviceError>())?;
    m.add("ContactError", py.get_type::<ContactError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
