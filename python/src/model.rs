//! `abut.Model`: nodes, surfaces, node sets, pairs, rigid bodies and parts.

use crate::errors::{bad, guarded, raise, LengthError};
use abut_rs as abut;
use abut_rs::model::{Facet, NodeSetId, SurfaceId};
use abut_rs::{
    Analytical, BodyId, Enforce, Friction, Kinematic, Pair, Penalty, PressureOverclosure,
    RigidBody, RigidPair, Sliding, Stiffness, Surface,
};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A model: nodes with masses, surfaces, node sets, pairs, rigid bodies and parts.
#[pyclass(module = "abut._abut")]
pub(crate) struct Model {
    pub(crate) inner: abut::Model,
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
            p.schedule = schedule.map(|(interval, budget, wide_local)| abut::model::Schedule {
                interval,
                budget,
                wide_local,
                visit_every_slave: false,
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
