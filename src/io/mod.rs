//! Meshes and decks in, results out: Gmsh `.msh` (version 4.1, ASCII and binary) and Abaqus
//! `.inp` meshes with their sets and surfaces, Abaqus contact definitions, and the contact state
//! as VTK XML (`.vtu` per frame, `.pvd` series) for ParaView. Errors name the file, the line
//! (where the format has lines) and what was expected.

pub mod gmsh;
pub mod inp;
pub mod vtk;

use std::collections::BTreeMap;

use crate::geometry::V3;
use crate::model::Facet;

/// The element shapes abut reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ElementKind {
    /// 2-node line (a 2D boundary segment, truss or rigid line).
    Line2,
    /// 3-node triangle in 3D (a shell or rigid facet).
    Tri3,
    /// 4-node quadrilateral in 3D (a shell or rigid facet).
    Quad4,
    /// 3-node plane triangle (2D continuum, x–y plane).
    Tri3In2d,
    /// 4-node plane quadrilateral (2D continuum, x–y plane).
    Quad4In2d,
    /// 4-node tetrahedron.
    Tet4,
    /// 8-node hexahedron.
    Hex8,
}

impl ElementKind {
    /// Nodes per element.
    pub fn node_count(self) -> usize {
        match self {
            ElementKind::Line2 => 2,
            ElementKind::Tri3 | ElementKind::Tri3In2d => 3,
            ElementKind::Quad4 | ElementKind::Quad4In2d | ElementKind::Tet4 => 4,
            ElementKind::Hex8 => 8,
        }
    }

    /// Whether the element is a 2D continuum element.
    pub fn is_planar(self) -> bool {
        matches!(self, ElementKind::Tri3In2d | ElementKind::Quad4In2d)
    }

    /// Faces (continuum) or sides (shells) in the file format's numbering, as local node
    /// indices: Abaqus' S1… for continuum elements, SPOS for shells.
    fn faces(self) -> &'static [&'static [usize]] {
        match self {
            ElementKind::Line2 => &[&[0, 1]],
            ElementKind::Tri3 => &[&[0, 1, 2]],
            ElementKind::Quad4 => &[&[0, 1, 2, 3]],
            ElementKind::Tri3In2d => &[&[0, 1], &[1, 2], &[2, 0]],
            ElementKind::Quad4In2d => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            ElementKind::Tet4 => &[&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]],
            ElementKind::Hex8 => &[
                &[0, 1, 2, 3],
                &[4, 7, 6, 5],
                &[0, 4, 5, 1],
                &[1, 5, 6, 2],
                &[2, 6, 7, 3],
                &[3, 7, 4, 0],
            ],
        }
    }
}

/// One element read from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshElement {
    /// Shape.
    pub kind: ElementKind,
    /// Node indices (into [`MeshData::positions`]).
    pub nodes: Vec<u32>,
    /// The element's label (tag) in the file.
    pub label: u64,
    /// Declared axisymmetric by its file (Abaqus CAX3, CAX4, CAX4R): x is the radius (≥ 0), y
    /// the axis, and the element stands for the ring it sweeps (per radian).
    pub axisymmetric: bool,
}

impl MeshElement {
    /// The radius of the element's centroid at `x` (its x coordinate): what an axisymmetric
    /// element's area is multiplied by for its volume per radian.
    pub fn centroid_radius(&self, x: &[[f64; 3]]) -> f64 {
        self.centroid(x).x
    }

    /// Volume (area for planar and shell elements, length for lines) at `x`.
    pub fn measure(&self, x: &[[f64; 3]]) -> f64 {
        let p = |k: usize| V3::from_array(x[self.nodes[k] as usize]);
        let tri =
            |a: usize, b: usize, c: usize| 0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length2().sqrt();
        let tet = |a: usize, b: usize, c: usize, d: usize| {
            ((p(b) - p(a)).dot((p(c) - p(a)).cross(p(d) - p(a))) / 6.0).abs()
        };
        match self.kind {
            ElementKind::Line2 => (p(1) - p(0)).length2().sqrt(),
            ElementKind::Tri3 | ElementKind::Tri3In2d => tri(0, 1, 2),
            ElementKind::Quad4 | ElementKind::Quad4In2d => tri(0, 1, 2) + tri(0, 2, 3),
            ElementKind::Tet4 => tet(0, 1, 2, 3),
            // five tetrahedra of the hexahedron
            ElementKind::Hex8 => {
                tet(0, 1, 3, 4)
                    + tet(1, 2, 3, 6)
                    + tet(1, 4, 5, 6)
                    + tet(3, 4, 6, 7)
                    + tet(1, 3, 4, 6)
            }
        }
    }

    fn centroid(&self, x: &[[f64; 3]]) -> V3<f64> {
        let mut c = V3::new(0.0, 0.0, 0.0);
        for &n in &self.nodes {
            c = c + V3::from_array(x[n as usize]);
        }
        c * (1.0 / self.nodes.len() as f64)
    }
}

/// A mesh read from a file: nodes, elements and named sets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Node positions (model units).
    pub positions: Vec<[f64; 3]>,
    /// Each node's label (tag) in the file.
    pub node_labels: Vec<u64>,
    /// Elements.
    pub elements: Vec<MeshElement>,
    /// Node sets by name (indices into `positions`).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Element sets by name (indices into `elements`).
    pub element_sets: BTreeMap<String, Vec<u32>>,
}

impl MeshData {
    /// Whether any element is axisymmetric ([`MeshElement::axisymmetric`]).
    pub fn is_axisymmetric(&self) -> bool {
        self.elements.iter().any(|e| e.axisymmetric)
    }
}

pub(crate) fn facet_of(nodes: Vec<u32>) -> Facet {
    match nodes.len() {
        2 => Facet::Segment([nodes[0], nodes[1]]),
        3 => Facet::Triangle([nodes[0], nodes[1], nodes[2]]),
        _ => Facet::Quad([nodes[0], nodes[1], nodes[2], nodes[3]]),
    }
}

/// The outward normal direction of facet `f` (not normalised; 2D segments: their right-hand
/// normal, abut's convention).
fn facet_normal(f: &Facet, x: &[[f64; 3]]) -> V3<f64> {
    let p = |n: u32| V3::from_array(x[n as usize]);
    match *f {
        Facet::Segment([a, b]) => {
            let t = p(b) - p(a);
            let t = t.to_array();
            V3::new(t[1], -t[0], 0.0)
        }
        Facet::Triangle([a, b, c]) => (p(b) - p(a)).cross(p(c) - p(a)),
        Facet::Quad([a, b, c, d]) => (p(c) - p(a)).cross(p(d) - p(b)),
    }
}

fn reversed(f: Facet) -> Facet {
    match f {
        Facet::Segment([a, b]) => Facet::Segment([b, a]),
        Facet::Triangle([a, b, c]) => Facet::Triangle([a, c, b]),
        Facet::Quad([a, b, c, d]) => Facet::Quad([a, d, c, b]),
    }
}

impl MeshData {
    /// The face `face` of element `e` as a facet whose normal points out of the element
    /// (continuum faces "S1", "S2", …; shells and rigid facets "SPOS" or "SNEG"; `None`: every
    /// face). Errors describe a face the element does not have.
    pub fn element_faces(&self, e: u32, face: Option<&str>) -> Result<Vec<Facet>, String> {
        let el = &self.elements[e as usize];
        let faces = el.kind.faces();
        let shell = matches!(
            el.kind,
            ElementKind::Tri3 | ElementKind::Quad4 | ElementKind::Line2
        );
        // a 2D line's positive side is to its left (Abaqus: the direction from node 1 to node
        // 2 turned 90° counterclockwise); abut's segments face right of their direction
        let line = el.kind == ElementKind::Line2;
        let pick: Vec<(usize, bool)> = match face {
            None => (0..faces.len()).map(|k| (k, line)).collect(),
            Some("SPOS") if shell => vec![(0, line)],
            Some("SNEG") if shell => vec![(0, !line)],
            Some(s) if !shell && s.starts_with('S') => {
                let k: usize = s[1..]
                    .parse()
                    .map_err(|_| format!("face {s}: expected S1…S{}", faces.len()))?;
                if k == 0 || k > faces.len() {
                    return Err(format!(
                        "element {}: a {:?} has faces S1…S{}, not {s}",
                        el.label,
                        el.kind,
                        faces.len()
                    ));
                }
                vec![(k - 1, false)]
            }
            Some(s) => {
                return Err(format!(
                    "element {}: face {s} is not one of {}",
                    el.label,
                    if shell {
                        "SPOS, SNEG".to_string()
                    } else {
                        format!("S1…S{}", faces.len())
                    }
                ))
            }
        };
        let c = el.centroid(&self.positions);
        Ok(pick
            .into_iter()
            .map(|(k, flip)| {
                let f = facet_of(faces[k].iter().map(|&i| el.nodes[i]).collect());
                let f = if shell {
                    f
                } else {
                    // continuum faces point away from the element's centroid
                    let n = facet_normal(&f, &self.positions);
                    let mid = V3::from_array(self.positions[f.nodes()[0] as usize]);
                    if n.dot(mid - c) < 0.0 {
                        reversed(f)
                    } else {
                        f
                    }
                };
                if flip {
                    reversed(f)
                } else {
                    f
                }
            })
            .collect())
    }

    /// The free faces (those belonging to one element only) of the volume and planar elements
    /// in `set` (all elements when `None`), outward: a body's boundary as a surface.
    pub fn boundary(&self, set: Option<&[u32]>) -> Vec<Facet> {
        let all: Vec<u32> = (0..self.elements.len() as u32).collect();
        let mut faces = Vec::new();
        for &e in set.unwrap_or(&all) {
            if matches!(
                self.elements[e as usize].kind,
                ElementKind::Tet4
                    | ElementKind::Hex8
                    | ElementKind::Tri3In2d
                    | ElementKind::Quad4In2d
            ) {
                faces.extend(self.element_faces(e, None).unwrap_or_default());
            }
        }
        free_faces(&faces)
    }
}

impl MeshData {
    /// The mesh's surface without naming a group: the free faces of its volume or plane
    /// elements, outward, when it has any (a body's boundary); else its triangles and
    /// quadrilaterals as they are (a surface mesh — Gmsh's curve and point elements left out);
    /// else its lines (a 2D curve). `None` for a mesh of points only.
    pub fn outer_surface(&self) -> Option<Vec<Facet>> {
        let body = self.elements.iter().any(|e| {
            matches!(
                e.kind,
                ElementKind::Tet4
                    | ElementKind::Hex8
                    | ElementKind::Tri3In2d
                    | ElementKind::Quad4In2d
            )
        });
        if body {
            return Some(self.boundary(None));
        }
        for kinds in [
            &[ElementKind::Tri3, ElementKind::Quad4][..],
            &[ElementKind::Line2][..],
        ] {
            let facets: Vec<Facet> = self
                .elements
                .iter()
                .filter(|e| kinds.contains(&e.kind))
                .map(|e| facet_of(e.nodes.clone()))
                .collect();
            if !facets.is_empty() {
                return Some(facets);
            }
        }
        None
    }
}

/// The facets of `faces` that occur once (by their node sets): the boundary of a set of
/// continuum elements' faces.
pub fn free_faces(faces: &[Facet]) -> Vec<Facet> {
    let key = |f: &Facet| {
        let mut k = f.nodes().to_vec();
        k.sort_unstable();
        k
    };
    let mut count = BTreeMap::<Vec<u32>, usize>::new();
    for f in faces {
        *count.entry(key(f)).or_default() += 1;
    }
    faces
        .iter()
        .filter(|f| count[&key(f)] == 1)
        .copied()
        .collect()
}

/// The nodes of `facets` (increasing) and each one's tributary area (facet areas shared
/// equally among their nodes; lengths in 2D).
pub fn face_nodes_and_areas(facets: &[Facet], x: &[[f64; 3]]) -> (Vec<u32>, Vec<f64>) {
    face_nodes_and_areas_scaled(facets, x, &|_| 1.0)
}

/// As [`face_nodes_and_areas`], each facet's area multiplied by `scale(facet)` (a segment's
/// out-of-plane thickness, or its radius per radian when axisymmetric).
pub fn face_nodes_and_areas_scaled(
    facets: &[Facet],
    x: &[[f64; 3]],
    scale: &dyn Fn(&Facet) -> f64,
) -> (Vec<u32>, Vec<f64>) {
    let mut area = BTreeMap::<u32, f64>::new();
    for f in facets {
        // |normal| is a segment's length, twice a triangle's area, and twice a planar quad's
        // area (the cross product of its diagonals; planar quads)
        let n = facet_normal(f, x).length2().sqrt();
        let a = scale(f)
            * if matches!(f, Facet::Segment(_)) {
                n
            } else {
                0.5 * n
            };
        for &n in f.nodes() {
            *area.entry(n).or_default() += a / f.nodes().len() as f64;
        }
    }
    (
        area.keys().copied().collect(),
        area.values().copied().collect(),
    )
}

/// The nodes of the segments in `facets` (increasing) and each one's area per radian about the
/// y axis (x is the radius): the area its linear shape function carries, ∫ N r ds =
/// L·(2·r_near + r_far)/6, so that a uniform pressure gives an axisymmetric element's consistent
/// nodal forces — a node on the axis gets L²/6, and its pressure is the pressure. Facets other
/// than segments are left out.
pub fn face_nodes_and_areas_per_radian(facets: &[Facet], x: &[[f64; 3]]) -> (Vec<u32>, Vec<f64>) {
    let mut area = BTreeMap::<u32, f64>::new();
    for f in facets {
        if let Facet::Segment([a, b]) = f {
            let (xa, xb) = (x[*a as usize], x[*b as usize]);
            let l = ((xb[0] - xa[0]).powi(2) + (xb[1] - xa[1]).powi(2)).sqrt();
            *area.entry(*a).or_default() += l * (2.0 * xa[0] + xb[0]) / 6.0;
            *area.entry(*b).or_default() += l * (xa[0] + 2.0 * xb[0]) / 6.0;
        }
    }
    area.into_iter().unzip()
}
