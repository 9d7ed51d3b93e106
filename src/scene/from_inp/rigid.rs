//! A deck's rigid bodies: how each moves, read from its reference node's boundary conditions,
//! initial velocity, loads, mass and rotary inertia; and an analytical surface as a `[[rigid]]`
//! body of the scene.

use std::collections::BTreeMap;

use crate::error::Result;
use crate::explicit::BodyMotion;
use crate::io::inp::{Analysis, BoundaryKind, RigidBodyDef};
use crate::io::MeshData;

use super::{refuse, DeckRigid};
use crate::scene::spec::RigidSpec;

/// The body `r` makes: its reference node's position, mass and inertia, and how its boundary
/// conditions move it (held, at a constant velocity, or free with held directions).
pub(super) fn body(
    a: &Analysis,
    r: &RigidBodyDef,
    point_mass: &BTreeMap<u32, f64>,
    mesh: &MeshData,
    two_d: bool,
) -> Result<DeckRigid> {
    let mass = point_mass.get(&r.ref_node).copied().unwrap_or(0.0);
    let inertia = a
        .rotary_inertia
        .iter()
        .filter(|(n, _, _)| *n == r.ref_node)
        .fold([[0.0; 3]; 3], |acc, (_, i, _)| {
            std::array::from_fn(|x| std::array::from_fn(|y| acc[x][y] + i[x][y]))
        });
    // per degree of freedom: held (None value) or a velocity
    let mut held = [false; 6];
    let mut velocity = [None; 3];
    for b in a
        .boundaries
        .iter()
        .filter(|b| b.nodes.contains(&r.ref_node))
    {
        for d in b.first..=b.last {
            match (b.kind, b.value == 0.0, &b.amplitude) {
                    (BoundaryKind::Displacement, true, _) => held[d - 1] = true,
                    (BoundaryKind::Velocity, _, None) if d <= 3 => velocity[d - 1] = Some(b.value),
                    _ => {
                        return refuse(
                            &b.at,
                            "a rigid body's reference node moved by a prescribed displacement, an amplitude or a rotation rate: abut moves rigid bodies held, at a constant velocity, or free",
                        )
                    }
                }
        }
    }
    if two_d {
        // a plane model moves in x–y and turns about z only
        held[2] = true;
        held[3] = held[5];
        held[4] = held[5];
    }
    let rotation_held = held[3..].iter().filter(|h| **h).count();
    if rotation_held != 0 && rotation_held != 3 {
        return refuse(
            &r.at,
            "a rigid body with some of its rotations held: abut holds all three or none",
        );
    }
    let motion = if velocity.iter().any(Option::is_some) {
        if (0..3).any(|d| velocity[d].is_none() && !held[d]) {
            return refuse(
                &r.at,
                "a rigid body with a prescribed velocity in some directions and free in others",
            );
        }
        BodyMotion::Velocity(std::array::from_fn(|d| velocity[d].unwrap_or(0.0)))
    } else if held[..3].iter().all(|h| *h) && rotation_held == 3 {
        BodyMotion::Fixed
    } else {
        BodyMotion::Free
    };
    if motion == BodyMotion::Free && mass <= 0.0 {
        return refuse(
            &r.at,
            "a free rigid body needs a mass: *MASS on its reference node",
        );
    }
    let mut v0 = [0.0; 3];
    for (n, d, v, _) in &a.initial_velocities {
        if *n == r.ref_node {
            v0[d - 1] = *v;
        }
    }
    let mut load = [0.0; 3];
    let mut moment = [0.0; 3];
    for c in a.cloads.iter().filter(|c| c.nodes.contains(&r.ref_node)) {
        if c.dof <= 3 {
            load[c.dof - 1] += c.value;
        } else {
            moment[c.dof - 4] += c.value;
        }
    }
    let rotation_locked = rotation_held > 0;
    if motion == BodyMotion::Free && !rotation_locked && (0..3).any(|d| inertia[d][d] <= 0.0) {
        return refuse(
            &r.at,
            "a free rigid body that can rotate needs *ROTARY INERTIA on its reference node",
        );
    }
    Ok(DeckRigid {
        reference: mesh.positions[r.ref_node as usize],
        mass: if mass > 0.0 {
            mass
        } else {
            super::super::build::PLACEHOLDER_MASS
        },
        massless: mass <= 0.0,
        inertia,
        motion,
        locked: [held[0], held[1], held[2]],
        rotation_locked,
        velocity: v0,
        load,
        moment,
    })
}

/// The `[[rigid]]` body of an analytical surface: a sphere (`TYPE=REVOLUTION`: a profile of
/// arcs about one centre on the axis, from the top pole to the bottom one, so that its normal —
/// the direction of travel turned 90° counterclockwise — points out), centred on the body's
/// reference node.
pub(super) fn analytical(
    a: &Analysis,
    r: &RigidBodyDef,
    body: &DeckRigid,
    mesh: &MeshData,
) -> Result<RigidSpec> {
    let name = r.analytical.clone().unwrap_or_default();
    let Some(s) = a.analytical.get(&name) else {
        return refuse(
            &r.at,
            format!("*RIGID BODY: analytical surface {name} is not defined"),
        );
    };
    let sphere = || -> Option<f64> {
        if s.kind != "REVOLUTION" || s.points.len() != 2 {
            return None;
        }
        let (start, arcs) = s.profile.split_first()?;
        let (r0, z0) = (start.1[0], start.1[1]);
        if r0 != 0.0 || arcs.is_empty() {
            return None;
        }
        let radius = z0.abs();
        // every segment an arc about (0, 0) of that radius, ending on the axis below
        let mut last = (r0, z0);
        for (word, v) in arcs {
            let (re, ze, rc, zc) = (v.first()?, v.get(1)?, v.get(2)?, v.get(3)?);
            if word != "CIRCL" || *rc != 0.0 || *zc != 0.0 {
                return None;
            }
            if ((re * re + ze * ze).sqrt() - radius).abs() > 1e-9 * radius || *re < 0.0 {
                return None;
            }
            last = (*re, *ze);
        }
        (z0 > 0.0 && last.0 == 0.0 && last.1 == -z0).then_some(radius)
    };
    let Some(radius) = sphere() else {
        return refuse(
            &s.at,
            format!("analytical surface {name}: abut reads spheres (TYPE=REVOLUTION, arcs about the local origin from the top pole to the bottom one) so far"),
        );
    };
    let centre = s.points[0];
    let reference = mesh.positions[r.ref_node as usize];
    if centre != reference {
        return refuse(
            &s.at,
            format!("analytical surface {name}: its centre {centre:?} is not its body's reference node {reference:?}"),
        );
    }
    let motion = match body.motion {
        BodyMotion::Fixed => "fixed",
        BodyMotion::Velocity(_) => "velocity",
        BodyMotion::Free => "free",
    };
    let velocity = match body.motion {
        BodyMotion::Velocity(v) => v,
        _ => body.velocity,
    };
    let mut fix: Vec<String> = ["x", "y", "z"]
        .iter()
        .zip(body.locked)
        .filter(|(_, l)| *l)
        .map(|(n, _)| n.to_string())
        .collect();
    if body.rotation_locked {
        fix.push("rotation".into());
    }
    Ok(RigidSpec {
        name,
        surface: "sphere".into(),
        point: reference,
        direction: [0.0; 3],
        radius,
        mass: body.mass,
        inertia: Some(body.inertia),
        motion: Some(motion.into()),
        velocity,
        fix: if body.motion == BodyMotion::Free {
            fix
        } else {
            Vec::new()
        },
        load: (body.load != [0.0; 3]).then_some(body.load),
        moment: (body.moment != [0.0; 3]).then_some(body.moment),
    })
}
