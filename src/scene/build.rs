//! From a checked [`Scene`] to the solver and the contact model: generated meshes, their faces
//! (nodes, facets and tributary areas), rigid bodies, boundary conditions and pairs; the parts'
//! meshes and the rigid parts that move are `parts.rs`.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::explicit::{
    Amplitude, BodyMotion, Element, LoadCurve, Material, Motion, Prescribed, Solver, SolverBody,
};
use crate::io::inp::SurfaceDef;
use crate::io::{ElementKind, MeshData};
use crate::mesh::rect_triangles_on;
use crate::mesh::{arc_segments, block_tets_on, graded, graded_with_core, plate_quads};
use crate::mesh::{polyline, sphere_triangles};
use crate::model::Schedule;
use crate::model::{
    Analytical, Enforce, Facet, Friction, Kinematic, Model, Pair, Penalty, RigidBody, RigidPair,
    Sliding, Stiffness, Surface,
};

use super::spec::{axis_of, bad, PartSpec, Scene};

/// How much heavier than the model's heaviest other node (or free body) the contact model makes
/// the nodes of fixed rigid parts and fixed or moving rigid bodies, so that contact treats them
/// as immovable whatever the unit system: a ratio, not a mass.
pub const IMMOVABLE_RATIO: f64 = 1e12;

/// A mass standing in for an immovable node or body until the model's own masses are known
/// (and for the solver's body of a massless deck body, whose motion is prescribed): replaced
/// by [`IMMOVABLE_RATIO`] times the heaviest other mass before contact sees it.
pub(crate) const PLACEHOLDER_MASS: f64 = 1.0;

mod parts;
pub(crate) use parts::centroid_and_inertia;
use parts::Meshed;

/// A part's nodes and how to find its faces.
#[derive(Clone, Debug)]
pub struct PartNodes {
    /// Part name.
    pub name: String,
    /// First model node.
    pub base: usize,
    /// Node count.
    pub count: usize,
    /// Element count.
    pub elements: usize,
    /// A deck's part: each of its elements' solver elements (first index, count; none for a
    /// surface element), in the part's element order.
    pub deck_elements: Vec<(usize, usize)>,
    grid: Grid,
}

#[derive(Clone, Debug)]
enum Grid {
    /// Tetrahedral block: cells per axis.
    Block([usize; 3]),
    /// Plane-strain rectangle: cells per axis, thickness.
    /// (Thickness NaN: axisymmetric, per radian.)
    Rect([usize; 2], f64),
    /// Bar along `axis` of cross-section area: four parallel chains of 2-node bars at the
    /// corners of a square section, node (cell k, corner c) at `4k + c`, corners
    /// counter-clockwise in the two other axes.
    Bar(usize),
    /// Quads in the x–y plane (normal +z).
    Plate([usize; 2]),
    /// Segments and triangles as generated (normals as the surface needs), and the name of
    /// the one face they make.
    Facets(Vec<Facet>, &'static str),
    /// Point masses with their slave areas.
    Points(f64),
    /// A mesh read from a file (node indices local to the part), with a deck's surfaces and
    /// the thickness of its 2D faces (NaN: axisymmetric, per radian).
    Mesh(Box<(MeshData, BTreeMap<String, SurfaceDef>, f64)>),
}

/// A face: its nodes, facets (outward normals) and each node's tributary area.
#[derive(Clone, Debug, Default)]
pub struct Face {
    /// Model nodes, increasing.
    pub nodes: Vec<u32>,
    /// Facets of the face.
    pub facets: Vec<Facet>,
    /// Tributary area (length in 2D, per unit thickness times the thickness) of each node.
    pub areas: Vec<f64>,
}

/// What a scene builds: the solver, the contact model, and per part its nodes.
#[derive(Clone, Debug)]
pub struct Built {
    /// The solver, with boundary conditions, bodies and initial velocities.
    pub solver: Solver,
    /// The contact model.
    pub model: Model,
    /// Each part's nodes.
    pub parts: Vec<PartNodes>,
    /// Each contact's slave nodes, in `[[contact]]` order.
    pub slaves: Vec<Vec<u32>>,
    /// Each `[[rigid]]` body's solver index.
    pub bodies: Vec<(String, usize)>,
}

fn material(scene: &Scene, p: &PartSpec) -> Material {
    let m = scene
        .material
        .iter()
        .find(|m| Some(&m.name) == p.material.as_ref())
        .expect("checked: deformable parts name a material");
    Material {
        young: m.young,
        poisson: m.poisson,
        density: m.density,
    }
}

impl PartNodes {
    /// The face `face` of the part at positions `x`.
    pub fn face(&self, face: &str, x: &[[f64; 3]]) -> Result<Face> {
        let base = self.base as u32;
        let mut facets: Vec<Facet> = Vec::new();
        let mut thickness = 1.0;
        let mut lone: Option<(Vec<u32>, f64)> = None;
        let wrong = || {
            Err(Error::BadParameter {
                name: "face",
                value: format!("{face} (part {})", self.name),
                expected: "a face this part's shape has",
            })
        };
        match (&self.grid, face) {
            (_, "all") if !matches!(self.grid, Grid::Mesh(_)) => {
                lone = Some(((base..base + self.count as u32).collect(), f64::NAN));
            }
            (Grid::Block(n), f) => {
                let Some((axis, plus)) = face_axis(f) else {
                    return wrong();
                };
                let id = |i: usize, j: usize, k: usize| {
                    base + (k * (n[1] + 1) * (n[0] + 1) + j * (n[0] + 1) + i) as u32
                };
                let (u, v) = match axis {
                    0 => (1, 2),
                    1 => (2, 0),
                    _ => (0, 1),
                };
                let fixed = if plus { n[axis] } else { 0 };
                let at = |a: usize, b: usize| {
                    let mut c = [0usize; 3];
                    c[axis] = fixed;
                    c[u] = a;
                    c[v] = b;
                    id(c[0], c[1], c[2])
                };
                for b in 0..n[v] {
                    for a in 0..n[u] {
                        let q = [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
                        // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis
                        facets.push(Facet::Quad(if plus { q } else { [q[0], q[3], q[2], q[1]] }));
                    }
                }
            }
            (Grid::Rect(n, t), f) => {
                thickness = *t;
                let id = |i: usize, j: usize| base + (j * (n[0] + 1) + i) as u32;
                // counter-clockwise around the rectangle: segment normals point outward
                match f {
                    "y-" => (0..n[0])
                        .for_each(|i| facets.push(Facet::Segment([id(i, 0), id(i + 1, 0)]))),
                    "x+" => (0..n[1])
                        .for_each(|j| facets.push(Facet::Segment([id(n[0], j), id(n[0], j + 1)]))),
                    "y+" => (0..n[0])
                        .for_each(|i| facets.push(Facet::Segment([id(i + 1, n[1]), id(i, n[1])]))),
                    "x-" => (0..n[1])
                        .for_each(|j| facets.push(Facet::Segment([id(0, j + 1), id(0, j)]))),
                    _ => return wrong(),
                }
            }
            (Grid::Bar(axis), f) => {
                let Some((a, plus)) = face_axis(f) else {
                    return wrong();
                };
                if a != *axis {
                    return wrong();
                }
                // the end furthest along the face's direction: a quad of the four chain ends
                let last = (self.count / 4 - 1) as u32;
                let first_is_plus = x[self.base][a] > x[self.base + 4 * last as usize][a];
                let k = if plus == first_is_plus { 0 } else { last };
                let q = [0, 1, 2, 3].map(|c| base + 4 * k + c);
                // corners run counter-clockwise about +axis; the quad faces outward
                facets.push(Facet::Quad(if plus { q } else { [q[0], q[3], q[2], q[1]] }));
            }
            (Grid::Plate(n), "z+") => {
                let id = |i: usize, j: usize| base + (j * (n[0] + 1) + i) as u32;
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        facets.push(Facet::Quad([
                            id(i, j),
                            id(i + 1, j),
                            id(i + 1, j + 1),
                            id(i, j + 1),
                        ]));
                    }
                }
            }
            (Grid::Facets(f, name), _) => {
                if face != *name {
                    return wrong();
                }
                facets = f
                    .iter()
                    .map(|f| match *f {
                        Facet::Segment([a, b]) => Facet::Segment([a + base, b + base]),
                        Facet::Triangle([a, b, c]) => {
                            Facet::Triangle([a + base, b + base, c + base])
                        }
                        Facet::Quad(q) => Facet::Quad(q.map(|n| n + base)),
                    })
                    .collect();
            }
            (Grid::Points(area), _) => {
                lone = Some(((base..base + self.count as u32).collect(), *area));
            }
            (Grid::Mesh(m), name) => {
                let (mesh, surfaces) = (&m.0, &m.1);
                thickness = m.2;
                let shift = |f: &Facet| match *f {
                    Facet::Segment(s) => Facet::Segment(s.map(|n| n + base)),
                    Facet::Triangle(t) => Facet::Triangle(t.map(|n| n + base)),
                    Facet::Quad(q) => Facet::Quad(q.map(|n| n + base)),
                };
                if name == "all" {
                    lone = Some(((base..base + self.count as u32).collect(), f64::NAN));
                } else if let Some(s) = surfaces.get(&name.to_uppercase()) {
                    match s {
                        SurfaceDef::Faces(f) => facets = f.iter().map(shift).collect(),
                        SurfaceDef::Nodes(n, a) => {
                            let nodes: Vec<u32> = n.iter().map(|&k| k + base).collect();
                            return Ok(Face {
                                nodes,
                                facets: Vec::new(),
                                areas: a.clone(),
                            });
                        }
                    }
                } else if mesh.element_sets.contains_key(name) {
                    facets = mesh.surface(name)?.iter().map(shift).collect();
                } else if let Some(n) = mesh
                    .node_sets
                    .get(name)
                    .or_else(|| mesh.node_sets.get(&name.to_uppercase()))
                {
                    lone = Some((n.iter().map(|&k| k + base).collect(), f64::NAN));
                } else if let (Some(f), "boundary") = (mesh.outer_surface(), name) {
                    facets = f.iter().map(shift).collect();
                } else {
                    return Err(Error::BadParameter {
                        name: "face",
                        value: format!("{name} (mesh part {})", self.name),
                        expected:
                            "a physical group, surface or set of the part's mesh file, boundary (the mesh's outer surface) or all",
                    });
                }
            }
            _ => return wrong(),
        }
        if let Some((nodes, area)) = lone {
            let n = nodes.len();
            let areas = if area.is_nan() {
                vec![1.0; n]
            } else {
                vec![area; n]
            };
            return Ok(Face {
                nodes,
                facets: Vec::new(),
                areas,
            });
        }
        // segments carry the part's thickness; axisymmetric (thickness NaN): per radian, each
        // node the area its linear shape function carries, ∫ N r ds = L·(2·r_near + r_far)/6,
        // so a uniform pressure gives the element's consistent nodal forces — a node on the axis
        // gets L²/6, not L/2 times the mid radius (L²/4), and its CPRESS is the pressure
        let (nodes, areas) = if thickness.is_nan() {
            crate::io::face_nodes_and_areas_per_radian(&facets, x)
        } else {
            crate::io::face_nodes_and_areas_scaled(&facets, x, &|f| match f {
                Facet::Segment(_) => thickness,
                _ => 1.0,
            })
        };
        Ok(Face {
            nodes,
            areas,
            facets,
        })
    }
}

fn face_axis(face: &str) -> Option<(usize, bool)> {
    let axis = axis_of(face.get(..1)?)?;
    match face.get(1..) {
        Some("+") => Some((axis, true)),
        Some("-") => Some((axis, false)),
        _ => None,
    }
}

fn coords(p: &PartSpec, axis: usize) -> Vec<f64> {
    graded_with_core(
        p.origin[axis],
        p.size[axis],
        p.divisions[axis],
        p.grading[axis],
        p.grading_core[axis],
    )
}

impl Scene {
    /// Builds the solver, the contact model and the parts' node ranges.
    pub fn build(&self) -> Result<Built> {
        let two_d = self.is_2d();
        let meshed: Meshed = self.mesh_parts()?;
        let (x, parts, moving_parts) = (meshed.x, meshed.parts, meshed.moving_parts);
        let mut solver = Solver::new(x.clone(), meshed.elements, &meshed.point)?;
        // immovable nodes: the ratio times the heaviest other node or free body
        let heaviest = self.heaviest_movable(&solver.mass, &meshed.immovable);
        for (m, &still) in solver.mass.iter_mut().zip(&meshed.immovable) {
            if still {
                *m = IMMOVABLE_RATIO * heaviest;
            }
        }
        // the parts' held directions, beside what the solver holds itself (axis nodes)
        for (held, part) in solver.fixed.iter_mut().zip(&meshed.fixed) {
            for a in 0..3 {
                held[a] |= part[a];
            }
        }
        solver.v = meshed.velocity;
        let (meshed_bodies, free_parts) = self.moving_bodies(&moving_parts, &x)?;
        solver.gravity = self.run.gravity;
        solver.load_factor = self.load_factor.clone();
        solver.safety = self.run.safety;
        solver.damping = self.run.damping;
        solver.bulk_viscosity = self.run.bulk_viscosity;
        solver.bulk_viscosity_quadratic = self.run.bulk_viscosity_quadratic;
        solver.nlgeom = self.run.nlgeom;
        let part = |name: &str| {
            parts
                .iter()
                .find(|p: &&PartNodes| p.name == name)
                .expect("checked")
        };
        for b in &self.boundary {
            let face = part(&b.part).face(&b.face, &x)?;
            for d in &b.fix {
                let a = axis_of(d).expect("checked");
                for &n in &face.nodes {
                    solver.fixed[n as usize][a] = true;
                }
            }
            if let Some(u) = b.displacement {
                let dirs: Vec<usize> = if b.directions.is_empty() {
                    (0..3).filter(|&a| u[a] != 0.0).collect()
                } else {
                    b.directions
                        .iter()
                        .map(|d| axis_of(d).expect("checked"))
                        .collect()
                };
                for &n in &face.nodes {
                    for &a in &dirs {
                        // Abaqus' smooth step from 0 to 1 over the ramp time, as a deck's
                        // *AMPLITUDE, DEFINITION=SMOOTH STEP gives it
                        let motion = Motion::Amplitude {
                            value: u[a],
                            amplitude: std::sync::Arc::new(Amplitude {
                                smooth: true,
                                points: vec![(0.0, 0.0), (b.ramp, 1.0)],
                            }),
                            velocity: false,
                        };
                        solver.prescribe(Prescribed::new(n, a, motion))?;
                    }
                }
            }
            if let Some(load) = b.load {
                let total: f64 = face.areas.iter().sum();
                for (&n, &a) in face.nodes.iter().zip(&face.areas) {
                    for d in 0..3 {
                        solver.loads[n as usize][d] += load[d] * a / total;
                    }
                }
            }
        }
        // a deck's loads and prescribed motions, node by node
        for (spec, nodes) in self.part.iter().zip(&parts) {
            let Some(piece) = &spec.deck else { continue };
            for (i, l) in piece.loads.iter().enumerate() {
                for d in 0..3 {
                    solver.loads[nodes.base + i][d] += l[d];
                }
            }
            for p in &piece.prescribed {
                solver.prescribe(Prescribed {
                    node: nodes.base as u32 + p.node,
                    ..p.clone()
                })?;
            }
            for c in &piece.load_curves {
                solver.load_curves.push(LoadCurve {
                    node: nodes.base as u32 + c.node,
                    ..c.clone()
                });
            }
        }
        let mut model = if two_d {
            Model::new_2d()
        } else {
            Model::new_3d()
        };
        model.add_nodes(&x, &solver.mass)?;
        for (nodes, mass, inertia) in &free_parts {
            model.add_rigid_part(nodes, *mass, *inertia)?;
        }
        let mut bodies = Vec::new();
        for r in &self.rigid {
            let motion = match r.motion.as_deref() {
                Some("fixed") => BodyMotion::Fixed,
                Some("velocity") => BodyMotion::Velocity(r.velocity),
                _ => BodyMotion::Free,
            };
            let d = r.direction;
            let surface = match r.surface.as_str() {
                "plane" => Analytical::Plane {
                    point: [0.0; 3],
                    normal: d,
                },
                "line" => Analytical::Line {
                    point: [0.0; 2],
                    normal: [d[0], d[1]],
                },
                "sphere" => Analytical::Sphere {
                    centre: [0.0; 3],
                    radius: r.radius,
                },
                "circle" => Analytical::Circle {
                    centre: [0.0; 2],
                    radius: r.radius,
                },
                _ => Analytical::Cylinder {
                    point: [0.0; 3],
                    axis: d,
                    radius: r.radius,
                },
            };
            let inertia = r.inertia.unwrap_or_else(|| {
                let i = if matches!(r.surface.as_str(), "sphere" | "circle" | "cylinder") {
                    0.4 * r.mass * r.radius * r.radius
                } else {
                    r.mass
                };
                [[i, 0.0, 0.0], [0.0, i, 0.0], [0.0, 0.0, i]]
            });
            // a fixed or moving body: the ratio times the heaviest of it and the rest
            let heavy = if motion == BodyMotion::Free {
                1.0
            } else {
                IMMOVABLE_RATIO * heaviest.max(r.mass) / r.mass
            };
            model.add_rigid_body(RigidBody {
                mass: r.mass * heavy,
                inertia: inertia.map(|row| row.map(|c| c * heavy)),
                surface,
            })?;
            let mut body = SolverBody::new(r.mass, inertia, r.point, Vec::new(), &x, motion)?;
            if motion == BodyMotion::Free {
                body.state.velocity = r.velocity;
            }
            for f in &r.fix {
                match axis_of(f) {
                    Some(a) => body.locked[a] = true,
                    None => body.rotation_locked = true,
                }
            }
            body.load = r.load.unwrap_or([0.0; 3]);
            body.moment = r.moment.unwrap_or([0.0; 3]);
            bodies.push((r.name.clone(), solver.add_body(body)?));
        }
        for (name, body) in meshed_bodies {
            bodies.push((name, solver.add_body(body)?));
        }
        let mut slaves = Vec::new();
        for c in &self.contact {
            let sface = part(&c.slave).face(&c.slave_face, &x)?;
            let set = model.add_node_set_with_areas(&sface.nodes, &sface.areas)?;
            slaves.push(sface.nodes.clone());
            if let Some(k) = self.rigid.iter().position(|r| r.name == c.master) {
                model.add_rigid_pair(RigidPair {
                    slave: set,
                    body: crate::model::BodyId(k),
                    softened: None,
                })?;
                continue;
            }
            let mface = part(&c.master).face(c.master_face.as_deref().expect("checked"), &x)?;
            if mface.facets.is_empty() {
                return bad(
                    "contact.master_face",
                    format!("{:?} (master {})", c.master_face, c.master),
                    "a face with facets (a bar end or point set cannot be a master surface)",
                );
            }
            let surf = model.add_surface(Surface::from_facets(mface.facets))?;
            if let Some(deck) = &c.deck {
                let mut pair = Pair::new(set, surf)
                    .enforce(deck.enforce.clone())
                    .friction(deck.friction.clone())
                    .sliding(deck.sliding);
                if let Some(schedule) = deck.schedule {
                    pair = pair.schedule(schedule);
                }
                if let Some(w) = c.balanced {
                    let s = model.add_surface(Surface::from_facets(sface.facets))?;
                    pair = pair.balanced(s, w);
                }
                model.add_pair(pair)?;
                continue;
            }
            let enforce = match c.enforce.as_deref() {
                Some("kinematic") => Enforce::Kinematic(Kinematic::default()),
                _ => Enforce::Penalty(Penalty {
                    stiffness: match (c.stiffness, c.stiffness_per_area) {
                        (Some(k), _) => Stiffness::Absolute(k),
                        (_, Some(k)) => Stiffness::PerArea(k),
                        _ => Stiffness::Auto {
                            scale: c.penalty_scale.unwrap_or(1.0),
                        },
                    },
                    damping: c.damping.unwrap_or(crate::model::DEFAULT_CONTACT_DAMPING),
                    ..Penalty::default()
                }),
            };
            let friction = if c.friction > 0.0 {
                Friction::coulomb(c.friction)
            } else {
                Friction::Frictionless
            };
            let sliding = match c.sliding.as_deref() {
                Some("small") => Sliding::Small,
                Some("infinitesimal") => Sliding::Infinitesimal,
                _ => Sliding::Finite,
            };
            let mut pair = Pair::new(set, surf)
                .enforce(enforce)
                .friction(friction)
                .sliding(sliding);
            if let Some(r) = c.search_radius {
                pair = pair.search_radius(r);
            }
            pair = pair.search_structure(match c.search_structure.as_deref() {
                Some("tree") => crate::model::SearchStructure::Tree,
                Some("buckets") => crate::model::SearchStructure::Buckets,
                _ => crate::model::SearchStructure::Auto,
            });
            if let Some(k) = c.search_interval {
                pair = pair.schedule(Schedule {
                    interval: k,
                    ..Schedule::default_for(false)
                });
            }
            if let Some(w) = c.balanced {
                if sface.facets.is_empty() {
                    return bad(
                        "contact.balanced",
                        format!("slave face {} of {}", c.slave_face, c.slave),
                        "a balanced pair needs a slave face with facets",
                    );
                }
                let s = model.add_surface(Surface::from_facets(sface.facets))?;
                pair = pair.balanced(s, w);
            }
            model.add_pair(pair)?;
        }
        Ok(Built {
            solver,
            model,
            parts,
            slaves,
            bodies,
        })
    }
}
