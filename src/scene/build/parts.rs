//! The parts of a scene meshed: generated blocks, rectangles, bars, plates, lines, arcs,
//! spheres, points and mesh files, in the order of the `[[part]]` tables, with their masses,
//! velocities and held directions; and the rigid parts that move, as bodies carrying their nodes.

use super::*;
use crate::explicit::{Hex8, Integration};

/// What the parts give the solver: positions, elements, point masses, velocities, held
/// directions (per node), each part's node range, and the rigid parts that move (part index,
/// first node, node count).
pub(super) struct Meshed {
    pub x: Vec<[f64; 3]>,
    pub elements: Vec<Element>,
    pub point: Vec<f64>,
    /// Nodes contact must treat as immovable (fixed rigid parts, massless deck bodies): their
    /// point mass is a placeholder until the model's own masses are known.
    pub immovable: Vec<bool>,
    pub velocity: Vec<[f64; 3]>,
    pub fixed: Vec<[bool; 3]>,
    pub parts: Vec<PartNodes>,
    pub moving_parts: Vec<(usize, usize, usize)>,
}

/// A rigid part that moves: its name and body, and (free ones, also rigid parts of the contact
/// model) its nodes, mass and inertia.
type Moving = (
    Vec<(String, SolverBody)>,
    Vec<(Vec<u32>, f64, [[f64; 3]; 3])>,
);

impl Scene {
    /// Meshes every `[[part]]` in order.
    pub(super) fn mesh_parts(&self) -> Result<Meshed> {
        let two_d = self.is_2d();
        let mut x: Vec<[f64; 3]> = Vec::new();
        let mut elements = Vec::new();
        let mut point = Vec::new();
        let mut immovable = Vec::new();
        let mut velocity = Vec::new();
        let mut fixed = Vec::new();
        let mut parts = Vec::new();
        let mut moving_parts = Vec::new();
        for p in &self.part {
            let base = x.len();
            let n_el = elements.len();
            let mut deck_map = Vec::new();
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
                    let (mesh, surfaces) = if let Some(piece) = &p.deck {
                        (piece.mesh.clone(), piece.surfaces.clone())
                    } else if file.ends_with(".msh") {
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
                    if let (Some(piece), false) = (&p.deck, rigid) {
                        deck_map = deck_elements(piece, base, &x, &mut elements, &p.name)?;
                    } else if !rigid {
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
                            if e.kind == ElementKind::Hex8 {
                                // a mesh file's hexahedra: C3D8, selectively reduced
                                let n: [u32; 8] = std::array::from_fn(|i| e.nodes[i] + base as u32);
                                let mirrored = [n[4], n[5], n[6], n[7], n[0], n[1], n[2], n[3]];
                                let hex = Hex8::new(n, &x, mat, Integration::Selective)
                                    .or_else(|| {
                                        Hex8::new(mirrored, &x, mat, Integration::Selective)
                                    })
                                    .ok_or_else(|| bad_el(k))?;
                                elements.push(Element::Hex8(Box::new(hex)));
                                continue;
                            }
                            if !matches!(
                                e.kind,
                                ElementKind::Tet4 | ElementKind::Tri3In2d | ElementKind::Quad4In2d
                            ) {
                                continue; // boundary facets and lines: surfaces only
                            }
                            let els = continuum(e, base, &x, mat, p.thickness, axisymmetric)
                                .ok_or_else(|| if axisymmetric { bad_axi(k) } else { bad_el(k) })?;
                            elements.extend(els);
                        }
                        if elements.len() == n_el && p.deck.is_none() {
                            return Err(Error::BadParameter {
                                name: "part.file",
                                value: format!("{file} (part {})", p.name),
                                expected: "a deformable mesh part needs tetrahedra or hexahedra (3D) or plane triangles or quadrilaterals (2D)",
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
            let moving = match p.deck.as_ref().and_then(|d| d.rigid.as_ref()) {
                Some(r) => r.motion != BodyMotion::Fixed,
                None => rigid && p.motion.as_deref().is_some_and(|m| m != "fixed"),
            };
            if moving {
                moving_parts.push((parts.len(), base, count));
            }
            if let Some(piece) = &p.deck {
                // the deck's own masses, velocities and held directions, node by node
                // a fixed body, or one without a mass (its motion prescribed), is immovable
                let body_mass = piece
                    .rigid
                    .as_ref()
                    .map(|r| (moving && !r.massless).then_some(r.mass));
                for &m in &piece.point_mass {
                    let (mass, still) = match body_mass {
                        Some(Some(b)) => (b, false),
                        Some(None) => (PLACEHOLDER_MASS, true),
                        None => (m, false),
                    };
                    point.push(mass);
                    immovable.push(still);
                }
                velocity.extend(
                    piece
                        .velocity
                        .iter()
                        .map(|&v| if rigid { [0.0; 3] } else { v }),
                );
                fixed.extend(piece.fixed.iter().map(|f| {
                    let mut held = if rigid && !moving { [true; 3] } else { *f };
                    if two_d {
                        held[2] = true;
                    }
                    held
                }));
                parts.push(PartNodes {
                    name: p.name.clone(),
                    base,
                    count,
                    elements: elements.len() - n_el,
                    deck_elements: std::mem::take(&mut deck_map),
                    grid,
                });
                continue;
            }
            point.extend(std::iter::repeat_n(
                if moving {
                    // the body's mass on every node: the effective mass contact sees
                    p.mass
                } else if rigid {
                    PLACEHOLDER_MASS
                } else if p.shape == "points" {
                    p.mass
                } else {
                    0.0
                },
                count,
            ));
            immovable.extend(std::iter::repeat_n(rigid && !moving, count));
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
                deck_elements: Vec::new(),
                grid,
            });
        }
        Ok(Meshed {
            x,
            elements,
            point,
            immovable,
            velocity,
            fixed,
            parts,
            moving_parts,
        })
    }

    /// The heaviest node contact may move (`masses` of the model's nodes, those marked
    /// `immovable` left out) or free analytical body: what an immovable mass is scaled from
    /// ([`IMMOVABLE_RATIO`] times it), so that it is immovable in any unit system. 1 when there
    /// is none.
    pub(super) fn heaviest_movable(&self, masses: &[f64], immovable: &[bool]) -> f64 {
        let nodes = masses
            .iter()
            .zip(immovable)
            .filter(|(_, &still)| !still)
            .map(|(&m, _)| m);
        let bodies = self
            .rigid
            .iter()
            .filter(|r| !matches!(r.motion.as_deref(), Some("fixed" | "velocity")))
            .map(|r| r.mass);
        let heaviest = nodes.chain(bodies).fold(0.0, f64::max);
        if heaviest > 0.0 && heaviest.is_finite() {
            heaviest
        } else {
            1.0
        }
    }

    /// The rigid parts that move (`moving_parts` of [`Meshed`], at positions `x`): bodies
    /// carrying the part's nodes (after the analytical bodies, whose indices are the contact
    /// model's), and the free ones as rigid parts of the contact model too (springs on them see
    /// the body).
    pub(super) fn moving_bodies(
        &self,
        moving_parts: &[(usize, usize, usize)],
        x: &[[f64; 3]],
    ) -> Result<Moving> {
        // rigid parts that move: bodies carrying the part's nodes (after the analytical bodies,
        // whose indices are the contact model's)
        let mut meshed_bodies = Vec::new();
        // free ones are rigid parts of the contact model too: springs on them see the body
        let mut free_parts = Vec::new();
        for &(k, base, count) in moving_parts {
            let p = &self.part[k];
            let nodes: Vec<u32> = (base as u32..(base + count) as u32).collect();
            if let Some(r) = p.deck.as_ref().and_then(|d| d.rigid.as_ref()) {
                // a deck's body: its reference node, mass and inertia as the deck gives them
                if r.motion == BodyMotion::Free {
                    free_parts.push((nodes.clone(), r.mass, r.inertia));
                }
                let mut body = SolverBody::new(r.mass, r.inertia, r.reference, nodes, x, r.motion)?;
                body.state.velocity = r.velocity;
                body.locked = r.locked;
                body.rotation_locked = r.rotation_locked;
                body.load = r.load;
                body.moment = r.moment;
                meshed_bodies.push((p.name.clone(), body));
                continue;
            }
            let (c, inertia) = centroid_and_inertia(&nodes, x, p.mass);
            let motion = match p.motion.as_deref() {
                Some("velocity") => BodyMotion::Velocity(p.velocity),
                _ => BodyMotion::Free,
            };
            if motion == BodyMotion::Free {
                free_parts.push((nodes.clone(), p.mass, inertia));
            }
            let mut body = SolverBody::new(p.mass, inertia, c, nodes, x, motion)?;
            body.state.velocity = p.velocity;
            meshed_bodies.push((p.name.clone(), body));
        }
        Ok((meshed_bodies, free_parts))
    }
}

/// The deformable elements of a deck's part (first node `base`, positions `x`), and where each
/// of the part's elements went among them (first, count): each with its
/// section's material, thickness (plane elements) or cross-section area (trusses); a plane
/// quadrilateral as two triangles; a hexahedron selectively reduced or, its type asking,
/// reduced with hourglass stiffness.
fn deck_elements(
    piece: &super::super::from_inp::DeckPiece,
    base: usize,
    x: &[[f64; 3]],
    elements: &mut Vec<Element>,
    name: &str,
) -> Result<Vec<(usize, usize)>> {
    let mut map = Vec::with_capacity(piece.mesh.elements.len());
    for (k, e) in piece.mesh.elements.iter().enumerate() {
        let first = elements.len();
        if !piece.deformable[k] {
            map.push((first, 0));
            continue;
        }
        let (mat, t) = (piece.materials[k], piece.thickness[k]);
        let bad = || {
            Error::BadParameter {
            name: "element",
            value: format!("element {} of part {name}", e.label),
            expected: "an element with positive length, area or volume (axisymmetric: every node at x ≥ 0)",
        }
        };
        match e.kind {
            ElementKind::Line2 => {
                let n = [e.nodes[0], e.nodes[1]].map(|i| i + base as u32);
                elements.push(Element::bar(n, x, t, mat).ok_or_else(bad)?);
            }
            ElementKind::Tet4 | ElementKind::Tri3In2d | ElementKind::Quad4In2d => {
                let els = continuum(e, base, x, mat, t, e.axisymmetric).ok_or_else(bad)?;
                elements.extend(els);
            }
            ElementKind::Hex8 => {
                let integration = if piece.reduced[k] {
                    Integration::Reduced
                } else {
                    Integration::Selective
                };
                let n: [u32; 8] = std::array::from_fn(|i| e.nodes[i] + base as u32);
                // nodes 1–4 and 5–8 swapped when the deck numbers the element inside out
                let mirrored = [n[4], n[5], n[6], n[7], n[0], n[1], n[2], n[3]];
                let hex = Hex8::new(n, x, mat, integration)
                    .or_else(|| Hex8::new(mirrored, x, mat, integration))
                    .ok_or_else(bad)?;
                elements.push(Element::Hex8(Box::new(hex)));
            }
            _ => return Err(bad()),
        }
        map.push((first, elements.len() - first));
    }
    Ok(map)
}

/// The solver's elements of mesh element `e` (its nodes from `base`): a tetrahedron, a plane
/// triangle of `thickness` (or axisymmetric), a plane quadrilateral as two triangles — each
/// turned to a positive volume or area; `None` when one has none.
fn continuum(
    e: &crate::io::MeshElement,
    base: usize,
    x: &[[f64; 3]],
    mat: Material,
    thickness: f64,
    axisymmetric: bool,
) -> Option<Vec<Element>> {
    let n: Vec<u32> = e.nodes.iter().map(|&i| i + base as u32).collect();
    if e.kind == ElementKind::Tet4 {
        let t = [n[0], n[1], n[2], n[3]];
        return Some(vec![
            Element::tet4(t, x, mat).or_else(|| Element::tet4([t[0], t[2], t[1], t[3]], x, mat))?
        ]);
    }
    let tris: Vec<[u32; 3]> = if n.len() == 3 {
        vec![[n[0], n[1], n[2]]]
    } else {
        vec![[n[0], n[1], n[2]], [n[0], n[2], n[3]]]
    };
    tris.into_iter()
        .map(|t| {
            if axisymmetric {
                // x is the radius: no node left of the axis
                Element::axi3(t, x, mat).or_else(|| Element::axi3([t[0], t[2], t[1]], x, mat))
            } else {
                Element::tri3(t, x, thickness, mat)
                    .or_else(|| Element::tri3([t[0], t[2], t[1]], x, thickness, mat))
            }
        })
        .collect()
}

/// The centroid of `nodes` and the inertia about it of `mass` shared equally among them (kept
/// positive definite for flat sets): a moving rigid part's reference point and inertia.
pub(crate) fn centroid_and_inertia(
    nodes: &[u32],
    x: &[[f64; 3]],
    mass: f64,
) -> ([f64; 3], [[f64; 3]; 3]) {
    let count = nodes.len();
    let mut c = [0.0; 3];
    for &n in nodes {
        for a in 0..3 {
            c[a] += x[n as usize][a] / count as f64;
        }
    }
    // inertia of the nodes as equal point masses about their centroid
    let mut inertia = [[0.0; 3]; 3];
    for &n in nodes {
        let r = [0, 1, 2].map(|a| x[n as usize][a] - c[a]);
        let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        for a in 0..3 {
            for b in 0..3 {
                let d = if a == b { r2 } else { 0.0 };
                inertia[a][b] += mass / count as f64 * (d - r[a] * r[b]);
            }
        }
    }
    // a flat part has no inertia about its normal's perpendiculars only in the limit:
    // keep it positive definite
    let tr = inertia[0][0] + inertia[1][1] + inertia[2][2];
    for (a, row) in inertia.iter_mut().enumerate() {
        row[a] += 1e-6 * tr.max(mass * 1e-12);
    }
    (c, inertia)
}
