//! Gmsh meshes (MSH 4.1, ASCII and binary; parsed by the mshio crate): nodes, elements
//! (2-node lines, 3-node triangles, 4-node quadrilaterals, tetrahedra, hexahedra; points are
//! skipped) and physical groups as named element and node sets (`$PhysicalNames`, which mshio
//! leaves alone, are read here; an unnamed group is called `physical <dim> <tag>`).
//!
//! Triangles and quadrilaterals are plane continuum elements in a mesh read as 2D and facets
//! (shells, rigid surfaces, boundary faces) in one read as 3D.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use crate::error::{Error, Result};
use crate::io::{ElementKind, MeshData, MeshElement};
use crate::model::Facet;

fn perr(file: &str, message: impl Into<String>) -> Error {
    Error::Parse {
        file: file.to_string(),
        line: 0,
        message: message.into(),
    }
}

/// Reads the mesh at `path` as a `dim`-dimensional mesh (2 or 3).
pub fn read(path: &Path, dim: u32) -> Result<MeshData> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    })?;
    parse(&bytes, &path.display().to_string(), dim)
}

/// `$PhysicalNames`: (dim, tag) → name. The section is ASCII in binary files too.
fn physical_names(bytes: &[u8], file: &str) -> Result<HashMap<(i32, i32), String>> {
    let mut out = HashMap::new();
    let Some(start) = find(bytes, b"$PhysicalNames") else {
        return Ok(out);
    };
    let Some(end) = find(&bytes[start..], b"$EndPhysicalNames") else {
        return Err(perr(file, "$PhysicalNames without $EndPhysicalNames"));
    };
    let text = String::from_utf8_lossy(&bytes[start..start + end]);
    let mut lines = text.lines().skip(1);
    let n: usize = lines
        .next()
        .and_then(|l| l.trim().parse().ok())
        .ok_or_else(|| perr(file, "$PhysicalNames: expected the number of names"))?;
    for k in 0..n {
        let l = lines.next().ok_or_else(|| {
            perr(
                file,
                format!("$PhysicalNames: expected {n} names, found {k}"),
            )
        })?;
        let mut it = l.trim().splitn(3, char::is_whitespace);
        let (Some(d), Some(t), Some(name)) = (it.next(), it.next(), it.next()) else {
            return Err(perr(
                file,
                format!("$PhysicalNames: expected dim tag \"name\", found {l:?}"),
            ));
        };
        let (Ok(d), Ok(t)) = (d.parse::<i32>(), t.parse::<i32>()) else {
            return Err(perr(
                file,
                format!("$PhysicalNames: expected dim tag \"name\", found {l:?}"),
            ));
        };
        out.insert((d, t), name.trim().trim_matches('"').to_string());
    }
    Ok(out)
}

fn find(h: &[u8], n: &[u8]) -> Option<usize> {
    h.windows(n.len()).position(|w| w == n)
}

/// Parses MSH 4.1 `bytes` (named `file` in messages) as a `dim`-dimensional mesh.
pub fn parse(bytes: &[u8], file: &str, dim: u32) -> Result<MeshData> {
    if dim != 2 && dim != 3 {
        return Err(Error::BadParameter {
            name: "gmsh dimension",
            value: dim.to_string(),
            expected: "2 or 3",
        });
    }
    let names = physical_names(bytes, file)?;
    let msh = mshio::parse_msh_bytes(bytes).map_err(|e| {
        // mshio's message names the section and what it expected; the byte offset of where it
        // stopped gives the line
        let msg = e.to_string();
        perr(
            file,
            format!(
                "not a valid MSH 4.1 file: {}",
                msg.lines().take(6).collect::<Vec<_>>().join(" / ")
            ),
        )
    })?;
    let mut mesh = MeshData::default();
    let Some(nodes) = &msh.data.nodes else {
        return Err(perr(file, "no $Nodes section"));
    };
    let mut index = HashMap::<u64, u32>::new();
    let mut next_tag = nodes.min_node_tag;
    for block in &nodes.node_blocks {
        let mut tags = vec![0u64; block.nodes.len()];
        match &block.node_tags {
            Some(map) => {
                for (&t, &i) in map {
                    if i >= tags.len() {
                        return Err(perr(
                            file,
                            format!("node tag {t}: index {i} beyond its block"),
                        ));
                    }
                    tags[i] = t;
                }
            }
            None => {
                for t in tags.iter_mut() {
                    *t = next_tag;
                    next_tag += 1;
                }
            }
        }
        for (t, n) in tags.into_iter().zip(&block.nodes) {
            for (axis, v) in [n.x, n.y, n.z].iter().enumerate() {
                if !v.is_finite() {
                    return Err(perr(
                        file,
                        format!("node {t}: coordinate {axis} is not finite"),
                    ));
                }
            }
            if dim == 2 && n.z != 0.0 {
                return Err(perr(
                    file,
                    format!("node {t}: z = {} in a mesh read as 2D", n.z),
                ));
            }
            if index.insert(t, mesh.positions.len() as u32).is_some() {
                return Err(perr(file, format!("node {t} is defined twice")));
            }
            mesh.positions.push([n.x, n.y, n.z]);
            mesh.node_labels.push(t);
        }
    }
    // physical tags of each entity
    let mut physical = HashMap::<(i32, i32), Vec<i32>>::new();
    if let Some(e) = &msh.data.entities {
        for p in &e.points {
            physical.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &e.curves {
            physical.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &e.surfaces {
            physical.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &e.volumes {
            physical.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    let Some(elements) = &msh.data.elements else {
        return Err(perr(file, "no $Elements section"));
    };
    use mshio::mshfile::ElementType as T;
    for block in &elements.element_blocks {
        let kind = match (block.element_type, dim) {
            (T::Pnt, _) => continue,
            (T::Lin2, _) => ElementKind::Line2,
            (T::Tri3, 2) => ElementKind::Tri3In2d,
            (T::Qua4, 2) => ElementKind::Quad4In2d,
            (T::Tri3, _) => ElementKind::Tri3,
            (T::Qua4, _) => ElementKind::Quad4,
            (T::Tet4, 3) => ElementKind::Tet4,
            (T::Hex8, 3) => ElementKind::Hex8,
            (other, _) => {
                return Err(perr(
                    file,
                    format!("element type {other:?} (entity {} of dimension {}) is not supported by abut in a {dim}D mesh (lines, triangles, quadrilaterals; tetrahedra and hexahedra in 3D)", block.entity_tag, block.entity_dim),
                ))
            }
        };
        let groups: Vec<String> = physical
            .get(&(block.entity_dim, block.entity_tag))
            .map(|tags| {
                tags.iter()
                    .map(|&t| {
                        names
                            .get(&(block.entity_dim, t))
                            .cloned()
                            .unwrap_or_else(|| format!("physical {} {t}", block.entity_dim))
                    })
                    .collect()
            })
            .unwrap_or_default();
        for el in &block.elements {
            if el.nodes.len() != kind.node_count() {
                return Err(perr(
                    file,
                    format!(
                        "element {}: {} nodes, a {kind:?} has {}",
                        el.element_tag,
                        el.nodes.len(),
                        kind.node_count()
                    ),
                ));
            }
            let mut nodes = Vec::with_capacity(el.nodes.len());
            for t in &el.nodes {
                nodes.push(*index.get(t).ok_or_else(|| {
                    perr(
                        file,
                        format!("element {}: node {t} is not defined", el.element_tag),
                    )
                })?);
            }
            let mut s = nodes.clone();
            s.sort_unstable();
            if s.windows(2).any(|w| w[0] == w[1]) {
                return Err(perr(
                    file,
                    format!("element {}: a node appears twice", el.element_tag),
                ));
            }
            let e = mesh.elements.len() as u32;
            mesh.elements.push(MeshElement {
                kind,
                nodes: nodes.clone(),
                label: el.element_tag,
                axisymmetric: false,
            });
            for g in &groups {
                mesh.element_sets.entry(g.clone()).or_default().push(e);
                mesh.node_sets.entry(g.clone()).or_default().extend(&nodes);
            }
        }
    }
    for v in mesh.node_sets.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    Ok(mesh)
}

impl MeshData {
    /// The facets of the surface named `name`: its line, triangle or quadrilateral elements
    /// (a physical group of the boundary), each turned to face out of the volume or plane
    /// element it bounds when there is one; for a group of volume or plane elements, their
    /// free faces. Errors: no element set of that name, or one without such elements.
    pub fn surface(&self, name: &str) -> Result<Vec<Facet>> {
        let Some(set) = self.element_sets.get(name) else {
            return Err(Error::BadParameter {
                name: "surface",
                value: name.to_string(),
                expected: "the name of an element set (a physical group) of the mesh",
            });
        };
        let bodies: Vec<u32> = set
            .iter()
            .copied()
            .filter(|&e| {
                matches!(
                    self.elements[e as usize].kind,
                    ElementKind::Tet4
                        | ElementKind::Hex8
                        | ElementKind::Tri3In2d
                        | ElementKind::Quad4In2d
                )
            })
            .collect();
        if !bodies.is_empty() {
            return Ok(self.boundary(Some(&bodies)));
        }
        // boundary elements: oriented by the body elements that own them
        let mut owner = BTreeMap::<Vec<u32>, u32>::new();
        for (e, el) in self.elements.iter().enumerate() {
            if matches!(
                el.kind,
                ElementKind::Tet4
                    | ElementKind::Hex8
                    | ElementKind::Tri3In2d
                    | ElementKind::Quad4In2d
            ) {
                for f in self.element_faces(e as u32, None).unwrap_or_default() {
                    let mut k = f.nodes().to_vec();
                    k.sort_unstable();
                    owner.insert(k, e as u32);
                }
            }
        }
        let mut out = Vec::new();
        for &e in set {
            let el = &self.elements[e as usize];
            if !matches!(
                el.kind,
                ElementKind::Line2 | ElementKind::Tri3 | ElementKind::Quad4
            ) {
                continue;
            }
            let mut k = el.nodes.clone();
            k.sort_unstable();
            let facet = match owner.get(&k) {
                // the owner's face with the same nodes is already outward
                Some(&o) => self
                    .element_faces(o, None)
                    .unwrap_or_default()
                    .into_iter()
                    .find(|f| {
                        let mut fk = f.nodes().to_vec();
                        fk.sort_unstable();
                        fk == k
                    })
                    .expect("the owner has this face"),
                None => super::facet_of(el.nodes.clone()),
            };
            out.push(facet);
        }
        if out.is_empty() {
            return Err(Error::BadParameter {
                name: "surface",
                value: name.to_string(),
                expected:
                    "a set of line, triangle or quadrilateral elements, or of volume elements",
            });
        }
        Ok(out)
    }
}
