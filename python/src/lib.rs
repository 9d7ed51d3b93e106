//! `abut._abut`: the Rust API on numpy arrays (the `abut` package in python/abut/ re-exports it
//! with its docs and type stubs).
//!
//! Arrays: positions, velocities and forces are (n, 3) float64; C-contiguous inputs are read in
//! place (no copy), others are refused with a named error rather than copied silently. Every
//! call runs inside `catch_unwind`: a panic becomes an `abut.AbutError`, never an abort. Errors
//! are raised as the subclass of `abut.AbutError` for their kind, carrying the library's message.

use abut_rs as abut;
use abut_rs::model::{Facet, NodeSetId, SurfaceId};
use abut_rs::{
    Analytical, BodyId, BodyState, Enforce, Friction, Kinematic, Pair, Penalty,
    PressureOverclosure, RigidBody, RigidPair, Sliding, Stiffness, Surface,
};
use numpy::{
    IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2,
    PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

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
fn raise(e: abut::Error) -> PyErr {
    use abut::Error as E;
    let m = e.to_string();
    match e {
        E::LengthMismatch { .. } => LengthError::new_err(m),
        E::IndexOutOfRange { .. } | E::UnknownId { .. } => OutOfRangeError::new_err(m),
        E::NonFiniteCoordinate { .. }
        | E::CoordinateOutOfRange { .. }
        | E::BadMass { .. }
        | E::BadParameter { .. }
        | E::Empty { .. }
        | E::DuplicateNode { .. } => BadValueError::new_err(m),
        E::RepeatedNode { .. }
        | E::AllFacetsDegenerate { .. }
        | E::WrongDimension { .. }
        | E::NonPlanarNode { .. } => GeometryError::new_err(m),
        E::NoAdapter { .. }
        | E::AdapterLimit { .. }
        | E::TooLarge { .. }
        | E::RequestDevice { .. }
        | E::Gpu { .. }
        | E::DeviceLost { .. } => DeviceError::new_err(m),
        E::NonFiniteResult { .. } | E::Tunnelling { .. } | E::Diverged { .. } => {
            ContactError::new_err(m)
        }
        E::Parse { .. } | E::Io { .. } => IoError::new_err(m),
    }
}

/// Runs `f`, turning a library error into its exception and a panic into an `AbutError`.
fn guarded<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
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

fn bad(msg: String) -> PyErr {
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
fn points<'a>(a: &'a PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<&'a [[f64; 3]]> {
    check_points(a.shape(), a.is_c_contiguous(), what)?;
    let flat = a.as_slice().map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(bytemuck::cast_slice(flat))
}

/// As [`points`], writable.
fn points_mut<'a>(
    a: &'a mut PyReadwriteArray2<'_, f64>,
    what: &str,
) -> PyResult<&'a mut [[f64; 3]]> {
    check_points(a.shape(), a.is_c_contiguous(), what)?;
    let flat = a.as_slice_mut().map_err(|e| bad(format!("{what}: {e}")))?;
    Ok(bytemuck::cast_slice_mut(flat))
}

/// A device: a GPU adapter or the CPU path.
#[pyclass(module = "abut._abut", frozen)]
struct Device {
    inner: abut::Device,
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

/// A model: nodes with masses, surfaces, node sets, pairs, rigid bodies and parts.
#[pyclass(module = "abut._abut")]
struct Model {
    inner: abut::Model,
}

/// The law `law` states: None, ("exponential", clearance, pressure), ("tabular", [(h, p), …])
/// or ("slope", k).
fn law_from(law: Option<&Bound<'_, PyAny>>) -> PyResult<Option<PressureOverclosure>> {
    let Some(law) = law.filter(|l| !l.is_none()) else {
        return Ok(None);
    };
    let kind: String = law.get_item(0)?.extract()?;
    let l = match kind.as_str() {
        "exponential" => PressureOverclosure::Exponential {
            clearance: law.get_item(1)?.extract()?,
            pressure: law.get_item(2)?.extract()?,
        },
        "tabular" => PressureOverclosure::Tabular(law.get_item(1)?.extract()?),
        "slope" => PressureOverclosure::linear(law.get_item(1)?.extract()?),
        o => {
            return Err(bad(format!(
                "law {o:?}: one of \"exponential\", \"tabular\", \"slope\" (or None)"
            )))
        }
    };
    l.validate().map_err(raise)?;
    Ok(Some(l))
}

#[pymethods]
impl Model {
    /// An empty model of `dim` (2 or 3) dimensions.
    #[new]
    #[pyo3(signature = (dim = 3))]
    fn new(dim: u32) -> PyResult<Self> {
        let inner = match dim {
            2 => abut::Model::new_2d(),
            3 => abut::Model::new_3d(),
            _ => return Err(bad(format!("dim = {dim}: a model has 2 or 3 dimensions"))),
        };
        Ok(Self { inner })
    }

    /// The number of nodes.
    #[getter]
    fn node_count(&self) -> usize {
        self.inner.positions().len()
    }

    /// Adds nodes at `coords` ((n, dim) float64) with `masses` ((n,) float64); returns the first
    /// new node's id.
    fn add_nodes(
        &mut self,
        coords: PyReadonlyArray2<'_, f64>,
        masses: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<u32> {
        guarded("Model.add_nodes", || {
            let dim = self.inner.dim() as usize;
            if coords.shape()[1] != dim {
                return Err(LengthError::new_err(format!(
                    "coords: shape {:?}, expected (n, {dim})",
                    coords.shape()
                )));
            }
            let c = coords.as_array();
            let m = masses.as_array().to_vec();
            let r = if dim == 2 {
                let p: Vec<[f64; 2]> = c.rows().into_iter().map(|r| [r[0], r[1]]).collect();
                self.inner.add_nodes_2d(&p, &m)
            } else {
                let p: Vec<[f64; 3]> = c.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
                self.inner.add_nodes(&p, &m)
            };
            Ok(r.map_err(raise)?.start)
        })
    }

    /// Adds a master surface of facets ((k, 2) segments, (k, 3) triangles or (k, 4) quads of
    /// node ids; a fourth id of 0xFFFFFFFF makes a triangle); returns its id.
    fn add_surface(&mut self, facets: PyReadonlyArray2<'_, u32>) -> PyResult<usize> {
        guarded("Model.add_surface", || {
            let f = facets.as_array();
            let per = f.shape()[1];
            let list: Vec<Facet> = f
                .rows()
                .into_iter()
                .map(|r| match per {
                    2 => Ok(Facet::Segment([r[0], r[1]])),
                    3 => Ok(Facet::Triangle([r[0], r[1], r[2]])),
                    4 if r[3] == u32::MAX => Ok(Facet::Triangle([r[0], r[1], r[2]])),
                    4 => Ok(Facet::Quad([r[0], r[1], r[2], r[3]])),
                    _ => Err(LengthError::new_err(format!(
                        "facets: shape {:?}, expected (k, 2), (k, 3) or (k, 4)",
                        f.shape()
                    ))),
                })
                .collect::<PyResult<_>>()?;
            Ok(self
                .inner
                .add_surface(Surface::from_facets(list))
                .map_err(raise)?
                .0)
        })
    }

    /// Adds a node set (slave nodes); `areas` ((n,) float64) their tributary areas. Returns its id.
    #[pyo3(signature = (nodes, areas = None))]
    fn add_node_set(
        &mut self,
        nodes: PyReadonlyArray1<'_, u32>,
        areas: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<usize> {
        guarded("Model.add_node_set", || {
            let n = nodes.as_array().to_vec();
            let r = match areas {
                None => self.inner.add_node_set(&n),
                Some(a) => self
                    .inner
                    .add_node_set_with_areas(&n, &a.as_array().to_vec()),
            };
            Ok(r.map_err(raise)?.0)
        })
    }

    /// Adds a contact pair of node set `slave` against surface `master` (a surface's own nodes
    /// against it: self-contact); returns its id. See the package docs for every option.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (slave, master, *, enforcement = "penalty", stiffness = "auto",
        stiffness_value = 0.0, stiffness_scale = 1.0, law = None,
        damping = abut::DEFAULT_CONTACT_DAMPING, mu = None, mu_kinetic = None, decay = 0.0,
        stick_stiffness = 1.0, sliding = "finite", search_radius = None, schedule = None,
        balanced = None, pass_weight = 1.0))]
    fn add_pair(
        &mut self,
        slave: usize,
        master: usize,
        enforcement: &str,
        stiffness: &str,
        stiffness_value: f64,
        stiffness_scale: f64,
        law: Option<&Bound<'_, PyAny>>,
        damping: f64,
        mu: Option<f64>,
        mu_kinetic: Option<f64>,
        decay: f64,
        stick_stiffness: f64,
        sliding: &str,
        search_radius: Option<f64>,
        schedule: Option<(u32, f64, bool)>,
        balanced: Option<(usize, f64)>,
        pass_weight: f64,
    ) -> PyResult<usize> {
        guarded("Model.add_pair", || {
            let mut p = Pair::new(NodeSetId(slave), SurfaceId(master));
            let law = law_from(law)?;
            p.enforce = match enforcement {
                "penalty" => Enforce::Penalty(Penalty {
                    stiffness: match stiffness {
                        "auto" => Stiffness::Auto {
                            scale: stiffness_scale,
                        },
                        "modulus" => Stiffness::Modulus {
                            modulus: stiffness_value,
                            scale: stiffness_scale,
                        },
                        "absolute" => Stiffness::Absolute(stiffness_value),
                        "per_area" => Stiffness::PerArea(stiffness_value),
                        o => {
                            return Err(bad(format!(
                                "stiffness {o:?}: one of \"auto\", \"modulus\", \"absolute\", \
                                 \"per_area\""
                            )))
                        }
                    },
                    law: law.unwrap_or(PressureOverclosure::Linear),
                    damping,
                }),
                "kinematic" => Enforce::Kinematic(Kinematic { softened: law }),
                o => {
                    return Err(bad(format!(
                        "enforcement {o:?}: \"penalty\" or \"kinematic\""
                    )))
                }
            };
            if let Some(mu) = mu {
                p.friction = Friction::Coulomb {
                    mu,
                    mu_kinetic: mu_kinetic.unwrap_or(mu),
                    decay,
                    stick_stiffness,
                };
            }
            p.sliding = match sliding {
                "finite" => Sliding::Finite,
                "small" => Sliding::Small,
                "infinitesimal" => Sliding::Infinitesimal,
                o => {
                    return Err(bad(format!(
                        "sliding {o:?}: \"finite\", \"small\" or \"infinitesimal\""
                    )))
                }
            };
            p.search_radius = search_radius;
            p.schedule = schedule.map(|(interval, budget, wide_local)| abut::search::Schedule {
                interval,
                budget,
                wide_local,
            });
            p.balanced = balanced.map(|(s, w)| (SurfaceId(s), w));
            p.pass_weight = pass_weight;
            Ok(self.inner.add_pair(p).map_err(raise)?.0)
        })
    }

    /// Adds a rigid body of `mass` and `inertia` ((3, 3)) carrying an analytical `surface`:
    /// ("plane", point, normal), ("sphere", centre, radius), ("cylinder", point, axis, radius),
    /// ("line", point, normal) or ("circle", centre, radius). Returns its id.
    fn add_rigid_body(
        &mut self,
        mass: f64,
        inertia: [[f64; 3]; 3],
        surface: &Bound<'_, PyAny>,
    ) -> PyResult<usize> {
        guarded("Model.add_rigid_body", || {
            let kind: String = surface.get_item(0)?.extract()?;
            let item = |k: usize| surface.get_item(k);
            let s = match kind.as_str() {
                "plane" => Analytical::Plane {
                    point: item(1)?.extract()?,
                    normal: item(2)?.extract()?,
                },
                "sphere" => Analytical::Sphere {
                    centre: item(1)?.extract()?,
                    radius: item(2)?.extract()?,
                },
                "cylinder" => Analytical::Cylinder {
                    point: item(1)?.extract()?,
                    axis: item(2)?.extract()?,
                    radius: item(3)?.extract()?,
                },
                "line" => Analytical::Line {
                    point: item(1)?.extract()?,
                    normal: item(2)?.extract()?,
                },
                "circle" => Analytical::Circle {
                    centre: item(1)?.extract()?,
                    radius: item(2)?.extract()?,
                },
                o => {
                    return Err(bad(format!(
                        "surface {o:?}: one of \"plane\", \"sphere\", \"cylinder\", \"line\", \
                         \"circle\""
                    )))
                }
            };
            let b = RigidBody {
                mass,
                inertia,
                surface: s,
            };
            Ok(self.inner.add_rigid_body(b).map_err(raise)?.0)
        })
    }

    /// Adds a kinematic pair of node set `slave` against rigid body `body`; `softened` a law
    /// as for `add_pair` (None: hard). Returns its id.
    #[pyo3(signature = (slave, body, softened = None))]
    fn add_rigid_pair(
        &mut self,
        slave: usize,
        body: usize,
        softened: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<usize> {
        guarded("Model.add_rigid_pair", || {
            let p = RigidPair {
                slave: NodeSetId(slave),
                body: BodyId(body),
                softened: law_from(softened)?,
            };
            Ok(self.inner.add_rigid_pair(p).map_err(raise)?.0)
        })
    }

    /// Declares `nodes` one rigid part of `mass` and `inertia` ((3, 3), about their centroid).
    fn add_rigid_part(
        &mut self,
        nodes: PyReadonlyArray1<'_, u32>,
        mass: f64,
        inertia: [[f64; 3]; 3],
    ) -> PyResult<usize> {
        guarded("Model.add_rigid_part", || {
            let n = nodes.as_array().to_vec();
            Ok(self
                .inner
                .add_rigid_part(&n, mass, inertia)
                .map_err(raise)?
                .0)
        })
    }
}

/// What an increment reported (penalty: `Contact.report`; kinematic: `Contact.kinematic_report`).
#[pyclass(module = "abut._abut", get_all, frozen)]
struct Report {
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
struct Contact {
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
        self.lock()?.request_outputs(yes);
        Ok(())
    }

    /// Sets the reference increment of the automatic stiffness (default: the first `dt`).
    fn set_reference_increment(&self, dt: f64) -> PyResult<()> {
        self.lock()?.set_reference_increment(dt).map_err(raise)
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

/// abut's extension module.
#[pymodule]
fn _abut(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Device>()?;
    m.add_class::<Model>()?;
    m.add_class::<Contact>()?;
    m.add_class::<Report>()?;
    m.add_function(wrap_pyfunction!(run_scene_json, m)?)?;
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
