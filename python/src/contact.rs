//! `abut.Contact` and `abut.Report`: the increments on numpy arrays, their reports, the output
//! variables and the state for a restart.

use crate::device::Device;
use crate::errors::{guarded, points, points_mut, raise, AbutError, LengthError, OutOfRangeError};
use crate::model::Model;
use abut_rs as abut;
use abut_rs::BodyState;
use numpy::{
    IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray2,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::sync::Mutex;

/// What an increment reported (penalty: `Contact.report`; kinematic: `Contact.kinematic_report`).
#[pyclass(module = "abut._abut", get_all, frozen)]
pub(crate) struct Report {
    /// Penalty: the largest stable increment of the contact springs (inf: none).
    stable_dt: f64,
    /// Penalty: half the smallest gap over its closing speed (inf: nothing approaches).
    approach_dt: f64,
    /// The largest overclosure (before the correction, for kinematic pairs).
    max_overclosure: f64,
    /// Slave nodes in contact (corrected, for kinematic pairs).
    active: usize,
    /// Of which slipping (penalty).
    slipping: usize,
    /// Slaves moving farther than their pair's search radius relative to the master.
    fast_nodes: usize,
    /// The fastest slave node (None: none), its pair, relative motion and the pair's radius.
    fastest: Option<(usize, usize, f64, f64)>,
    /// Searches that ran globally this increment (penalty).
    global_searches: usize,
    /// Small-sliding slaves left without an anchor (penalty).
    unanchored: usize,
    /// Kinematic: the largest overclosure left after the correction.
    max_overclosure_after: f64,
    /// Kinematic: the change of kinetic energy the corrections made.
    kinetic_energy_change: f64,
    /// The report's warnings, as sentences.
    warnings: Vec<String>,
}

#[pymethods]
impl Report {
    fn __repr__(&self) -> String {
        format!(
            "abut.Report(active={}, slipping={}, fast_nodes={}, stable_dt={:e}, \
             max_overclosure={:e})",
            self.active, self.slipping, self.fast_nodes, self.stable_dt, self.max_overclosure
        )
    }
}

/// The contact of a model on a device: search and enforcement of every pair, once per
/// increment.
#[pyclass(module = "abut._abut")]
pub(crate) struct Contact {
    inner: Mutex<abut::Contact>,
    nodes: usize,
}

fn bodies_from(b: Option<&PyReadwriteArray2<'_, f64>>) -> PyResult<Vec<BodyState>> {
    let Some(b) = b else { return Ok(Vec::new()) };
    if b.shape()[1] != 18 {
        return Err(LengthError::new_err(format!(
            "bodies: shape {:?}, expected (k, 18): position, rotation (9, by rows), velocity, \
             angular velocity",
            b.shape()
        )));
    }
    Ok(b.as_array()
        .rows()
        .into_iter()
        .map(|r| BodyState {
            position: [r[0], r[1], r[2]],
            rotation: [[r[3], r[4], r[5]], [r[6], r[7], r[8]], [r[9], r[10], r[11]]],
            velocity: [r[12], r[13], r[14]],
            angular_velocity: [r[15], r[16], r[17]],
        })
        .collect())
}

impl Contact {
    /// The contact, locked for one call (a panic during a call leaves it refusing the next).
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, abut::Contact>> {
        self.inner
            .lock()
            .map_err(|_| AbutError::new_err("this Contact is unusable after an internal error"))
    }
}

#[pymethods]
impl Contact {
    /// Builds the contact of `model` on `device`.
    #[new]
    fn new(device: &Device, model: &Model) -> PyResult<Self> {
        guarded("Contact", || {
            let c = abut::Contact::new(&device.inner, &model.inner).map_err(raise)?;
            Ok(Self {
                inner: Mutex::new(c),
                nodes: model.inner.positions().len(),
            })
        })
    }

    /// Computes the output variables every increment (`output`) when True.
    fn request_outputs(&self, yes: bool) -> PyResult<()> {
        guarded("Contact.request_outputs", || {
            self.lock()?.request_outputs(yes);
            Ok(())
        })
    }

    /// Sets the reference increment of the automatic stiffness (default: the first `dt`).
    fn set_reference_increment(&self, dt: f64) -> PyResult<()> {
        guarded("Contact.set_reference_increment", || {
            self.lock()?.set_reference_increment(dt).map_err(raise)
        })
    }

    /// One penalty increment at positions `x` and velocities `v` ((n, 3) float64, read in place)
    /// over `dt`. Returns the contact forces ((n, 3)): a new array, or `out` with them written
    /// (or added, with `add=True`).
    #[pyo3(signature = (x, v, dt, out = None, add = false))]
    fn penalty_step<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        v: PyReadonlyArray2<'py, f64>,
        dt: f64,
        out: Option<Bound<'py, PyArray2<f64>>>,
        add: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guarded("Contact.penalty_step", || {
            let mut c = self.lock()?;
            let r = c
                .penalty_step(points(&x, "x")?, points(&v, "v")?, dt)
                .map_err(raise)?;
            let out = match out {
                Some(o) => o,
                None => PyArray2::<f64>::zeros(py, [self.nodes, 3], false),
            };
            {
                let mut w = out.readwrite();
                let o = points_mut(&mut w, "out")?;
                if o.len() != r.forces.len() {
                    return Err(LengthError::new_err(format!(
                        "out: {} rows, the model has {} nodes",
                        o.len(),
                        r.forces.len()
                    )));
                }
                if add {
                    let o = o.as_flattened_mut().iter_mut();
                    o.zip(r.forces.as_flattened()).for_each(|(o, f)| *o += f);
                } else {
                    o.copy_from_slice(&r.forces);
                }
            }
            Ok(out)
        })
    }

    /// The report of the last penalty increment.
    #[getter]
    fn report(&self) -> PyResult<Report> {
        guarded("Contact.report", || {
            let c = self.lock()?;
            let r = c.report();
            Ok(Report {
                stable_dt: r.stable_dt,
                approach_dt: r.approach_dt,
                max_overclosure: r.max_overclosure,
                active: r.active,
                slipping: r.slipping,
                fast_nodes: r.fast_nodes,
                fastest: r.fastest.map(|f| (f.node, f.pair.0, f.distance, f.radius)),
                global_searches: r.global_searches,
                unanchored: r.unanchored,
                max_overclosure_after: 0.0,
                kinetic_energy_change: 0.0,
                warnings: r.warnings(),
            })
        })
    }

    /// One kinematic increment: `x`, `v` ((n, 3) float64, C-contiguous, writable) the predicted
    /// positions and the velocities that took them there, corrected in place; `bodies` ((k, 18):
    /// position, rotation by rows, velocity, angular velocity) the rigid bodies' predicted
    /// states, corrected in place. Returns the kinematic report.
    #[pyo3(signature = (x, v, dt, bodies = None))]
    fn kinematic_step(
        &self,
        mut x: PyReadwriteArray2<'_, f64>,
        mut v: PyReadwriteArray2<'_, f64>,
        dt: f64,
        mut bodies: Option<PyReadwriteArray2<'_, f64>>,
    ) -> PyResult<Report> {
        guarded("Contact.kinematic_step", || {
            let mut states = bodies_from(bodies.as_ref())?;
            {
                let mut c = self.lock()?;
                c.kinematic_step(
                    points_mut(&mut x, "x")?,
                    points_mut(&mut v, "v")?,
                    &mut states,
                    dt,
                )
                .map_err(raise)?;
            }
            if let Some(b) = bodies.as_mut() {
                let mut a = b.as_array_mut();
                for (mut row, s) in a.rows_mut().into_iter().zip(&states) {
                    let flat: Vec<f64> = s
                        .position
                        .iter()
                        .chain(s.rotation.as_flattened())
                        .chain(&s.velocity)
                        .chain(&s.angular_velocity)
                        .copied()
                        .collect();
                    for (d, f) in row.iter_mut().zip(flat) {
                        *d = f;
                    }
                }
            }
            self.kinematic_report()
        })
    }

    /// The report of the last kinematic increment.
    #[getter]
    fn kinematic_report(&self) -> PyResult<Report> {
        guarded("Contact.kinematic_report", || {
            let c = self.lock()?;
            let r = c.kinematic_report();
            Ok(Report {
                stable_dt: f64::INFINITY,
                approach_dt: f64::INFINITY,
                max_overclosure: r.max_overclosure,
                active: r.active,
                slipping: 0,
                fast_nodes: r.fast_nodes,
                fastest: r.fastest.map(|f| (f.node, f.pair.0, f.distance, f.radius)),
                global_searches: 0,
                unanchored: 0,
                max_overclosure_after: r.max_overclosure_after,
                kinetic_energy_change: r.kinetic_energy_change,
                warnings: r.warnings(),
            })
        })
    }

    /// Moves initially overclosed slave nodes onto their masters, strain-free (`x` corrected in
    /// place); returns the largest distance moved.
    #[pyo3(signature = (x, dt, bodies = None))]
    fn adjust_initial_overclosure(
        &self,
        mut x: PyReadwriteArray2<'_, f64>,
        dt: f64,
        bodies: Option<PyReadwriteArray2<'_, f64>>,
    ) -> PyResult<f64> {
        guarded("Contact.adjust_initial_overclosure", || {
            let states = bodies_from(bodies.as_ref())?;
            let mut c = self.lock()?;
            let r = c
                .adjust_initial_overclosure(points_mut(&mut x, "x")?, &states, dt)
                .map_err(raise)?;
            Ok(r.max_distance)
        })
    }

    /// The output variables of pass `pass_` of pair `pair` (`rigid=True`: a rigid pair) after
    /// the last increment, as a dict of numpy arrays: slaves, cstatus (-1 unknown, 0 open,
    /// 1 stick, 2 slip), copen, cpress, cshear1, cshear2, normal, force, and cfn, cfs,
    /// contact_energy, frictional_dissipation.
    #[pyo3(signature = (pair, pass_ = 0, rigid = false))]
    fn output<'py>(
        &self,
        py: Python<'py>,
        pair: usize,
        pass_: usize,
        rigid: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        guarded("Contact.output", || {
            let c = self.lock()?;
            let all: Vec<&abut::PairOutput> = if rigid {
                c.rigid_outputs()
                    .into_iter()
                    .filter(|(id, _)| id.0 == pair)
                    .map(|(_, o)| o)
                    .collect()
            } else {
                c.outputs()
                    .into_iter()
                    .filter(|(id, _)| id.0 == pair)
                    .map(|(_, o)| o)
                    .collect()
            };
            let n = all.len();
            let o = all.get(pass_).ok_or_else(|| {
                OutOfRangeError::new_err(format!(
                    "pass {pass_} of pair {pair}: it has {n} pass(es) with outputs"
                ))
            })?;
            let d = PyDict::new(py);
            d.set_item("slaves", o.slaves.clone().into_pyarray(py))?;
            let cs: Vec<i32> = o
                .cstatus
                .iter()
                .map(|s| match s {
                    None => -1,
                    Some(abut::ContactStatus::Open) => 0,
                    Some(abut::ContactStatus::Stick) => 1,
                    Some(abut::ContactStatus::Slip) => 2,
                })
                .collect();
            d.set_item("cstatus", cs.into_pyarray(py))?;
            d.set_item("copen", o.copen.clone().into_pyarray(py))?;
            d.set_item("cpress", o.cpress.clone().into_pyarray(py))?;
            d.set_item("cshear1", o.cshear1.clone().into_pyarray(py))?;
            d.set_item("cshear2", o.cshear2.clone().into_pyarray(py))?;
            let rows = |v: &[[f64; 3]]| -> PyResult<Bound<'py, PyArray2<f64>>> {
                v.as_flattened()
                    .to_vec()
                    .into_pyarray(py)
                    .reshape([v.len(), 3])
            };
            d.set_item("normal", rows(&o.normal)?)?;
            d.set_item("force", rows(&o.force)?)?;
            d.set_item("cfn", o.cfn.to_vec().into_pyarray(py))?;
            d.set_item("cfs", o.cfs.to_vec().into_pyarray(py))?;
            d.set_item("contact_energy", o.contact_energy)?;
            d.set_item("frictional_dissipation", o.frictional_dissipation)?;
            Ok(d)
        })
    }

    /// The contact's state as bytes (a restart: `restore_state` on a Contact of the same model
    /// continues bit for bit).
    fn save_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        guarded("Contact.save_state", || {
            let s = self.lock()?.save_state().map_err(raise)?;
            Ok(PyBytes::new(py, &s))
        })
    }

    /// Restores a state `save_state` gave.
    fn restore_state(&self, state: &[u8]) -> PyResult<()> {
        guarded("Contact.restore_state", || {
            self.lock()?.restore_state(state).map_err(raise)
        })
    }
}
