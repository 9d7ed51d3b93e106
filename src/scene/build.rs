//! From a checked [`Scene`] to the solver and the contact model: generated meshes, their faces
//! (nodes, facets and tributary areas), rigid bodies, boundary conditions and pairs.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::explicit::{BodyMotion, Element, Material, Motion, Prescribed, Solver, SolverBody};
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

/// Mass given to the nodes of fixed rigid parts and to fixed or moving rigid bodies in the
/// contact model, so that kinematic contact treats them as immovable.
pub const IMMOVABLE_MASS: f64 = 1e12;

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
        let mut x: Vec<[f64; 3]> = Vec::new();
        let mut elements = Vec::new();
        let mut point = Vec::new();
        let mut velocity = Vec::new();
        let mut fixed = Vec::new();
        let mut parts = Vec::new();
        let mut moving_parts = Vec::new();
        for p in &self.part {
            let base = x.len();
            let n_el = elements.len();
            let mut rigid = false;
            let grid = match p.shape.as_str() {
                "block" => {
                    let mat = material(self, p);
                    let mesh = block_tets_on([coords(p, 0), coords(p, 1), coords(p, 2)]);
                    x.extend(&mesh.positions);
                    for t in &mesh.facets {
                        let tet = t.map(|n| n + base as u32);
                        elements.push(Element::tet4(tet, &x, mat).ok_or_else(|| {
                            Error::BadParameter {
                                name: "part",
                                value: p.name.clone(),
                                expected: "a block with positive volumes",
                            }
                        })?);
                    }
                    Grid::Block([p.divisions[0], p.divisions[1], p.divisions[2]])
                }
                "rect" => {
                    let mat = material(self, p);
                    let mesh = rect_triangles_on(&coords(p, 0), &coords(p, 1));
                    x.extend(mesh.positions.iter().map(|q| [q[0], q[1], 0.0]));
                    for t in &mesh.facets {
                        let tri = t.map(|n| n + base as u32);
                        let el = if p.axisymmetric {
                            Element::axi3(tri, &x, mat)
                        } else {
                            Element::tri3(tri, &x, p.thickness, mat)
                        };
                        elements.push(el.ok_or_else(|| Error::BadParameter {
                            name: "part",
                            value: p.name.clone(),
                            expected:
                                "a rectangle with positive areas (and x ≥ 0 when axisymmetric)",
                        })?);
                    }
                    let t = if p.axisymmetric {
                        f64::NAN
                    } else {
                        p.thickness
                    };
                    Grid::Rect([p.divisions[0], p.divisions[1]], t)
                }
                "bar" => {
                    let mat = material(self, p);
                    let axis = (0..3).find(|&a| p.size[a] != 0.0).expect("checked");
                    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                    let half = 0.5 * p.area.sqrt();
                    let ts = graded(0.0, 1.0, p.divisions[0], p.grading[0]);
                    for t in &ts {
                        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                            let mut q = [0, 1, 2].map(|a| p.origin[a] + t * p.size[a]);
                            q[u] += su * half;
                            q[v] += sv * half;
                            x.push(q);
                        }
                    }
                    for k in 0..p.divisions[0] as u32 {
                        for c in 0..4 {
                            let nodes = [base as u32 + 4 * k + c, base as u32 + 4 * (k + 1) + c];
                            elements.push(Element::bar(nodes, &x, 0.25 * p.area, mat).ok_or_else(
                                || Error::BadParameter {
                                    name: "part",
                                    value: p.name.clone(),
                                    expected: "a bar with positive element lengths",
                                },
                            )?);
                        }
                    }
                    Grid::Bar(axis)
                }
                "plate" => {
                    rigid = true;
                    let mesh = plate_quads(
                        p.divisions[0],
                        p.divisions[1],
                        p.size[0],
                        p.size[1],
                        0.0,
                        0,
                        &|_, _| 0.0,
                    );
                    x.extend(
                        mesh.positions
                            .iter()
                            .map(|q| [q[0] + p.origin[0], q[1] + p.origin[1], p.origin[2]]),
                    );
                    Grid::Plate([p.divisions[0], p.divisions[1]])
                }
                "line" => {
                    rigid = true;
                    let mesh = polyline(p.divisions[0], p.size[0], 0.0, 0, &|_| 0.0);
                    x.extend(
                        mesh.positions
                            .iter()
                            .map(|q| [q[0] + p.origin[0], q[1] + p.origin[1], 0.0]),
                    );
                    Grid::Facets(
                        mesh.facets.iter().map(|&s| Facet::Segment(s)).collect(),
                        "y+",
                    )
                }
                "arc" => {
                    rigid = true;
                    let mesh = arc_segments(
                        p.origin,
                        p.radius,
                        p.angles[0].to_radians(),
                        p.angles[1].to_radians(),
                        p.divisions[0],
                        p.grading[0],
                    );
                    x.extend(&mesh.positions);
                    Grid::Facets(
                        mesh.facets.iter().map(|&s| Facet::Segment(s)).collect(),
                        "out",
                    )
                }
                "sphere" => {
                    rigid = true;
                    let mesh = sphere_triangles(p.divisions[0], p.divisions[1], p.radius, p.origin);
                    x.extend(&mesh.positions);
                    Grid::Facets(
                        mesh.facets.iter().map(|&t| Facet::Triangle(t)).collect(),
                        "out",
                    )
                }
                "mesh" => {
                    rigid = p.rigid;
                    let file = p.file.as_deref().expect("checked");
                    let path = match &self.base_dir {
                        Some(d) if std::path::Path::new(file).is_relative() => d.join(file),
                        _ => std::path::PathBuf::from(file),
                    };
                    let dim = p.dimension.unwrap_or(if two_d { 2 } else { 3 });
                    let (mesh, surfaces) = if file.ends_with(".msh") {
                        (crate::io::gmsh::read(&path, dim)?, BTreeMap::new())
                    } else {
                        let d = crate::io::inp::read(&path)?;
                        (d.mesh, d.surfaces)
                    };
                    x.extend(
                        mesh.positions
                            .iter()
                            .map(|q| [0, 1, 2].map(|a| q[a] + p.origin[a])),
                    );
                    let axisymmetric = p.axisymmetric || mesh.is_axisymmetric();
                    if axisymmetric && !two_d {
                        return Err(Error::BadParameter {
                            name: "part.file",
                            value: format!("{file} (part {})", p.name),
                            expected: "axisymmetric elements (CAX3, CAX4(R)) in a 2D scene: set dimension = 2 or axisymmetric = true on the part",
                        });
                    }
                    if !rigid {
                        let mat = material(self, p);
                        let bad_el = |k: usize| Error::BadParameter {
                            name: "part.file",
                            value: format!(
                                "element {} of {} (part {})",
                                mesh.elements[k].label, file, p.name
                            ),
                            expected: "elements with positive volume or area",
                        };
                        let bad_axi = |k: usize| {
                            Error::BadParameter {
                            name: "part.file",
                            value: format!(
                                "element {} of {} (part {})",
                                mesh.elements[k].label, file, p.name
                            ),
                            expected: "axisymmetric elements with positive area and every node at x ≥ 0 (x is the radius, after the part's origin)",
                        }
                        };
                        for (k, e) in mesh.elements.iter().enumerate() {
                            let n: Vec<u32> = e.nodes.iter().map(|&i| i + base as u32).collect();
                            match e.kind {
                                ElementKind::Tet4 => {
                                    let t = [n[0], n[1], n[2], n[3]];
                                    let el = Element::tet4(t, &x, mat)
                                        .or_else(|| Element::tet4([t[0], t[2], t[1], t[3]], &x, mat))
                                        .ok_or_else(|| bad_el(k))?;
                                    elements.push(el);
                                }
                                ElementKind::Tri3In2d | ElementKind::Quad4In2d => {
                                    let tris: Vec<[u32; 3]> = if n.len() == 3 {
                                        vec![[n[0], n[1], n[2]]]
                                    } else {
                                        vec![[n[0], n[1], n[2]], [n[0], n[2], n[3]]]
                                    };
                                    for t in tris {
                                        let el = if axisymmetric {
                                            // x is the radius: no node left of the axis
                                            Element::axi3(t, &x, mat)
                                                .or_else(|| Element::axi3([t[0], t[2], t[1]], &x, mat))
                                                .ok_or_else(|| bad_axi(k))?
                                        } else {
                                            Element::tri3(t, &x, p.thickness, mat)
                                                .or_else(|| Element::tri3([t[0], t[2], t[1]], &x, p.thickness, mat))
                                                .ok_or_else(|| bad_el(k))?
                                        };
                                        elements.push(el);
                                    }
                                }
                                ElementKind::Hex8 => {
                                    return Err(Error::BadParameter {
                                        name: "part.file",
                                        value: format!("{file} (part {}) has hexahedra", p.name),
                                        expected: "tetrahedra for a deformable mesh part (the solver's 3D element); hexahedra can be rigid or give surfaces",
                                    })
                                }
                                _ => {} // boundary facets and lines: surfaces only
                            }
                        }
                        if elements.len() == n_el {
                            return Err(Error::BadParameter {
                                name: "part.file",
                                value: format!("{file} (part {})", p.name),
                                expected: "a deformable mesh part needs tetrahedra (3D) or plane triangles or quadrilaterals (2D)",
                            });
                        }
                    }
                    let t = if axisymmetric { f64::NAN } else { p.thickness };
                    Grid::Mesh(Box::new((mesh, surfaces, t)))
                }
                _ => {
                    x.extend(&p.points);
                    Grid::Points(p.area)
                }
            };
            let count = x.len() - base;
            let moving = rigid && p.motion.as_deref().is_some_and(|m| m != "fixed");
            if moving {
                moving_parts.push((parts.len(), base, count));
            }
            point.extend(std::iter::repeat_n(
                if moving {
                    // the body's mass on every node: the effective mass contact sees
                    p.mass
                } else if rigid {
                    IMMOVABLE_MASS
                } else if p.shape == "points" {
                    p.mass
                } else {
                    0.0
                },
                count,
            ));
            velocity.extend(std::iter::repeat_n(
                if rigid { [0.0; 3] } else { p.velocity },
                count,
            ));
            let mut free = [!rigid || moving; 3];
            if two_d {
                free[2] = false;
            }
            if let Grid::Bar(axis) = grid {
                // bars carry load along their axis only
                free = [false; 3];
                free[axis] = true;
            }
            fixed.extend(std::iter::repeat_n(free.map(|f| !f), count));
            parts.push(PartNodes {
                name: p.name.clone(),
                base,
                count,
                elements: elements.len() - n_el,
                grid,
            });
        }
        let mut solver = Solver::new(x.clone(), elements, &point)?;
        // the parts' held directions, beside what the solver holds itself (axis nodes)
        for (held, part) in solver.fixed.iter_mut().zip(&fixed) {
            for a in 0..3 {
                held[a] |= part[a];
            }
        }
        solver.v = velocity;
        // rigid parts that move: bodies carrying the part's nodes (after the analytical bodies,
        // whose indices are the contact model's)
        let mut meshed_bodies = Vec::new();
        // free ones are rigid parts of the contact model too: springs on them see the body
        let mut free_parts = Vec::new();
        for &(k, base, count) in &moving_parts {
            let p = &self.part[k];
            let nodes: Vec<u32> = (base as u32..(base + count) as u32).collect();
            let mut c = [0.0; 3];
            for &n in &nodes {
                for a in 0..3 {
                    c[a] += x[n as usize][a] / count as f64;
                }
            }
            // inertia of the nodes as equal point masses about their centroid
            let mut inertia = [[0.0; 3]; 3];
            for &n in &nodes {
                let r = [0, 1, 2].map(|a| x[n as usize][a] - c[a]);
                let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                for a in 0..3 {
                    for b in 0..3 {
                        let d = if a == b { r2 } else { 0.0 };
                        inertia[a][b] += p.mass / count as f64 * (d - r[a] * r[b]);
                    }
                }
            }
            // a flat part has no inertia about its normal's perpendiculars only in the limit:
            // keep it positive definite
            let tr = inertia[0][0] + inertia[1][1] + inertia[2][2];
            for (a, row) in inertia.iter_mut().enumerate() {
                row[a] += 1e-6 * tr.max(p.mass * 1e-12);
            }
            let motion = match p.motion.as_deref() {
                Some("velocity") => BodyMotion::Velocity(p.velocity),
                _ => BodyMotion::Free,
            };
            if motion == BodyMotion::Free {
                free_parts.push((nodes.clone(), p.mass, inertia));
            }
            let mut body = SolverBody::new(p.mass, inertia, c, nodes, &x, motion)?;
            body.state.velocity = p.velocity;
            meshed_bodies.push((p.name.clone(), body));
        }
        solver.gravity = self.run.gravity;
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
                        solver.prescribe(Prescribed {
                            node: n,
                            dof: a,
                            motion: Motion::Ramp {
                                displacement: u[a],
                                duration: b.ramp,
                            },
                        })?;
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
            let heavy = if motion == BodyMotion::Free {
                1.0
            } else {
                IMMOVABLE_MASS
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
