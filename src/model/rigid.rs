//! Rigid bodies with analytical surfaces, and kinematic pairs of slave nodes against them.

use super::{NodeSetId, PressureOverclosure};
use crate::error::{Error, Result};
use crate::geometry::V3;

/// Id of a rigid body within its model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BodyId(pub usize);

/// Id of a rigid pair within its model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RigidPairId(pub usize);

/// An analytical rigid surface, in the body's frame (its reference point is the origin).
/// Slave nodes stay on the side the outward normal points to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Analytical {
    /// 3D plane through `point` with outward unit `normal`.
    Plane {
        /// A point of the plane.
        point: [f64; 3],
        /// Outward normal (normalised on use).
        normal: [f64; 3],
    },
    /// 3D sphere; slaves stay outside.
    Sphere {
        /// Centre.
        centre: [f64; 3],
        /// Radius (> 0).
        radius: f64,
    },
    /// 3D infinite cylinder; slaves stay outside.
    Cylinder {
        /// A point of the axis.
        point: [f64; 3],
        /// Axis direction (normalised on use).
        axis: [f64; 3],
        /// Radius (> 0).
        radius: f64,
    },
    /// 2D line (z = 0) through `point` with outward in-plane `normal`.
    Line {
        /// A point of the line.
        point: [f64; 2],
        /// Outward normal.
        normal: [f64; 2],
    },
    /// 2D circle; slaves stay outside.
    Circle {
        /// Centre.
        centre: [f64; 2],
        /// Radius (> 0).
        radius: f64,
    },
}

impl Analytical {
    /// Signed gap (outside positive) and outward unit normal at the point nearest `p`
    /// (body frame).
    pub fn gap(&self, p: V3<f64>) -> (f64, V3<f64>) {
        match *self {
            Analytical::Plane { point, normal } => {
                let n = V3::from_array(normal).normalize_or_zero();
                ((p - V3::from_array(point)).dot(n), n)
            }
            Analytical::Line { point, normal } => {
                let n = V3::new(normal[0], normal[1], 0.0).normalize_or_zero();
                ((p - V3::new(point[0], point[1], 0.0)).dot(n), n)
            }
            Analytical::Sphere { centre, radius } => radial(p - V3::from_array(centre), radius),
            Analytical::Circle { centre, radius } => {
                let d = p - V3::new(centre[0], centre[1], 0.0);
                radial(V3::new(d.x, d.y, 0.0), radius)
            }
            Analytical::Cylinder {
                point,
                axis,
                radius,
            } => {
                let a = V3::from_array(axis).normalize_or_zero();
                let d = p - V3::from_array(point);
                radial(d - a * d.dot(a), radius)
            }
        }
    }

    fn is_2d(&self) -> bool {
        matches!(self, Analytical::Line { .. } | Analytical::Circle { .. })
    }
}

fn radial(d: V3<f64>, radius: f64) -> (f64, V3<f64>) {
    let len = d.length2().sqrt();
    // on the axis or centre the direction is undefined: take +z (or +y in-plane)
    let n = if len > 0.0 {
        d * (1.0 / len)
    } else {
        V3::new(0.0, 0.0, 1.0)
    };
    (len - radius, n)
}

/// A rigid body: mass, inertia about its reference point (body frame, at zero rotation) and
/// the analytical surface it carries. Its motion is the host's; `Contact::kinematic_step`
/// corrects the predicted state it is given.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBody {
    /// Mass (> 0).
    pub mass: f64,
    /// Rotational inertia about the reference point, body frame (symmetric positive definite).
    pub inertia: [[f64; 3]; 3],
    /// The surface.
    pub surface: Analytical,
}

/// Checks a rigid body's mass (finite, positive) and inertia (symmetric positive definite).
pub(crate) fn validate_mass_inertia(mass: f64, inertia: [[f64; 3]; 3]) -> Result<()> {
    if !(mass.is_finite() && mass > 0.0) {
        return Err(Error::BadParameter {
            name: "rigid body mass",
            value: mass.to_string(),
            expected: "must be finite and positive",
        });
    }
    let i = inertia;
    let sym = (0..3).all(|a| {
        (0..3).all(|b| {
            i[a][b].is_finite()
                && (i[a][b] - i[b][a]).abs() <= 1e-12 * (i[a][a].abs() + i[b][b].abs())
        })
    });
    let det2 = i[0][0] * i[1][1] - i[0][1] * i[1][0];
    let det3 = i[0][0] * (i[1][1] * i[2][2] - i[1][2] * i[2][1])
        - i[0][1] * (i[1][0] * i[2][2] - i[1][2] * i[2][0])
        + i[0][2] * (i[1][0] * i[2][1] - i[1][1] * i[2][0]);
    if !(sym && i[0][0] > 0.0 && det2 > 0.0 && det3 > 0.0) {
        return Err(Error::BadParameter {
            name: "rigid body inertia",
            value: format!("{i:?}"),
            expected: "must be symmetric positive definite",
        });
    }
    Ok(())
}

/// Id of a rigid part within its [`crate::Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RigidPartId(pub usize);

/// Mesh nodes that move as one rigid body — a meshed rigid surface that is free, or carried on
/// the host's rigid body. A penalty spring on its facets (or on its nodes as slaves) sees the
/// body's mass and rotational inertia at the contact point, which is what sets the spring's
/// frequency, instead of the nodes' lumped masses; and the springs on one part add up in the
/// node-wise bound as one body.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidPart {
    /// Its nodes (each in one rigid part at most).
    pub nodes: Vec<u32>,
    /// Mass (> 0).
    pub mass: f64,
    /// Rotational inertia about the nodes' centroid, in the model frame at the model's
    /// positions (symmetric positive definite).
    pub inertia: [[f64; 3]; 3],
}

impl RigidBody {
    pub(crate) fn validate(&self, dim: u32) -> Result<()> {
        validate_mass_inertia(self.mass, self.inertia)?;
        if self.surface.is_2d() != (dim == 2) {
            return Err(Error::BadParameter {
                name: "analytical surface",
                value: format!("{:?}", self.surface),
                expected:
                    "lines and circles belong in 2D models, planes, spheres and cylinders in 3D",
            });
        }
        let bad = |v: &[f64]| v.iter().any(|x| !x.is_finite());
        let (ok, what) = match self.surface {
            Analytical::Plane { point, normal } => (
                !bad(&point) && !bad(&normal) && V3::from_array(normal).length2() > 0.0,
                "plane",
            ),
            Analytical::Line { point, normal } => (
                !bad(&point) && !bad(&normal) && normal[0].hypot(normal[1]) > 0.0,
                "line",
            ),
            Analytical::Sphere { centre, radius } => (
                !bad(&centre) && radius.is_finite() && radius > 0.0,
                "sphere",
            ),
            Analytical::Circle { centre, radius } => (
                !bad(&centre) && radius.is_finite() && radius > 0.0,
                "circle",
            ),
            Analytical::Cylinder {
                point,
                axis,
                radius,
            } => (
                !bad(&point)
                    && !bad(&axis)
                    && V3::from_array(axis).length2() > 0.0
                    && radius.is_finite()
                    && radius > 0.0,
                "cylinder",
            ),
        };
        if !ok {
            return Err(Error::BadParameter {
                name: "analytical surface",
                value: what.into(),
                expected: "needs finite parameters, a non-zero direction and a positive radius",
            });
        }
        Ok(())
    }
}

/// A kinematic pair: slave nodes against a rigid body's analytical surface.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidPair {
    /// The slave nodes.
    pub slave: NodeSetId,
    /// The rigid body whose surface is the master.
    pub body: BodyId,
    /// `None`: hard contact; `Some(law)`: softened.
    pub softened: Option<PressureOverclosure>,
}
