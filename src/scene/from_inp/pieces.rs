//! A deck cut into parts: deformable elements joined by the nodes they share, each rigid body's
//! elements and nodes, the point masses on no element; each part's mesh, sets and surfaces in
//! its own node numbering, in the order of its first node.

use std::collections::BTreeMap;

use crate::error::Result;
use crate::explicit::Material;
use crate::io::inp::{Deck, SurfaceDef};
use crate::io::MeshElement;
use crate::model::Facet;

use super::{refuse, DeckPiece, Role};

/// The parts, and where each deck node went.
pub(super) struct Split {
    /// The parts.
    pub pieces: Vec<DeckPiece>,
    /// Each deck node's part (`usize::MAX`: none).
    pub piece_of: Vec<usize>,
    /// Each deck node's index in its part.
    pub local: Vec<u32>,
    /// Each part's rigid body (index into the deck's rigid bodies).
    pub rigid_of_piece: Vec<Option<usize>>,
    /// The rigid bodies' reference nodes, with their body.
    pub ref_nodes: BTreeMap<u32, usize>,
    /// The point mass on each node that has one.
    pub point_mass: BTreeMap<u32, f64>,
}

/// Union–find over deck nodes.
fn root(parent: &mut [u32], mut a: u32) -> u32 {
    while parent[a as usize] != a {
        parent[a as usize] = parent[parent[a as usize] as usize];
        a = parent[a as usize];
    }
    a
}

fn map_facet(f: &Facet, local: &[u32]) -> Facet {
    let m = |n: u32| local[n as usize];
    match *f {
        Facet::Segment(s) => Facet::Segment(s.map(m)),
        Facet::Triangle(t) => Facet::Triangle(t.map(m)),
        Facet::Quad(q) => Facet::Quad(q.map(m)),
    }
}

/// The deck's parts, elements of `role`, deformable ones with their `materials`.
pub(super) fn split(
    deck: &Deck,
    role: &[Option<Role>],
    materials: &[(String, Material, f64)],
) -> Result<Split> {
    let a = &deck.analysis;
    let mesh = &deck.mesh;
    let n_nodes = mesh.positions.len();
    // pieces: deformable elements joined by shared nodes; each rigid body one piece
    let mut parent: Vec<u32> = (0..n_nodes as u32).collect();
    let mut in_element = vec![false; n_nodes];
    for e in &mesh.elements {
        for &n in &e.nodes {
            in_element[n as usize] = true;
        }
        for w in e.nodes.windows(2) {
            let (x, y) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[x.max(y) as usize] = x.min(y);
        }
    }
    let ref_nodes: BTreeMap<u32, usize> = a
        .rigid_bodies
        .iter()
        .enumerate()
        .map(|(k, r)| (r.ref_node, k))
        .collect();
    for r in &a.rigid_bodies {
        if in_element[r.ref_node as usize] {
            return refuse(
                &r.at,
                "*RIGID BODY: its REF NODE is a node of an element (give it a node of its own)",
            );
        }
        let mut members: Vec<u32> = r
            .elements
            .iter()
            .flat_map(|&e| mesh.elements[e as usize].nodes.clone())
            .collect();
        members.extend(&r.nodes);
        for w in members.windows(2) {
            let (x, y) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[x.max(y) as usize] = x.min(y);
        }
    }
    let point_mass: BTreeMap<u32, f64> = {
        let mut m = BTreeMap::new();
        for (n, v, _) in &a.point_masses {
            *m.entry(*n).or_insert(0.0) += v;
        }
        m
    };
    // a piece per root, in the order of their first node; free point masses together
    let mut piece_of_root: BTreeMap<u32, usize> = BTreeMap::new();
    let mut piece_nodes: Vec<Vec<u32>> = Vec::new();
    let mut free_points = Vec::new();
    let mut piece_of = vec![usize::MAX; n_nodes];
    for n in 0..n_nodes as u32 {
        let member = in_element[n as usize] || a.rigid_bodies.iter().any(|r| r.nodes.contains(&n));
        if !member {
            if point_mass.contains_key(&n) && !ref_nodes.contains_key(&n) {
                free_points.push(n);
            }
            continue;
        }
        let r = root(&mut parent, n);
        let k = *piece_of_root.entry(r).or_insert_with(|| {
            piece_nodes.push(Vec::new());
            piece_nodes.len() - 1
        });
        piece_nodes[k].push(n);
        piece_of[n as usize] = k;
    }
    if !free_points.is_empty() {
        piece_nodes.push(free_points);
    }
    // in the order of their first node: a deck written part by part keeps its parts' order
    piece_nodes.sort_by_key(|nodes| nodes[0]);
    for (k, nodes) in piece_nodes.iter().enumerate() {
        for &n in nodes {
            piece_of[n as usize] = k;
        }
    }
    // the rigid body of each piece
    let mut rigid_of_piece: Vec<Option<usize>> = vec![None; piece_nodes.len()];
    for (k, r) in a.rigid_bodies.iter().enumerate() {
        let first = r
            .elements
            .first()
            .map(|&e| mesh.elements[e as usize].nodes[0])
            .or(r.nodes.first().copied());
        let Some(first) = first else { continue };
        let p = piece_of[first as usize];
        if rigid_of_piece[p].is_some_and(|o| o != k) {
            return refuse(&r.at, "two *RIGID BODY definitions share nodes");
        }
        rigid_of_piece[p] = Some(k);
    }
    let mut pieces: Vec<DeckPiece> = Vec::new();
    let mut local = vec![u32::MAX; n_nodes];
    for (k, nodes) in piece_nodes.iter().enumerate() {
        for (i, &n) in nodes.iter().enumerate() {
            local[n as usize] = i as u32;
        }
        let mut piece = DeckPiece {
            deck_nodes: nodes.clone(),
            velocity: vec![[0.0; 3]; nodes.len()],
            point_mass: nodes
                .iter()
                .map(|n| point_mass.get(n).copied().unwrap_or(0.0))
                .collect(),
            loads: vec![[0.0; 3]; nodes.len()],
            fixed: vec![[false; 3]; nodes.len()],
            ..Default::default()
        };
        piece.mesh.positions = nodes.iter().map(|&n| mesh.positions[n as usize]).collect();
        piece.mesh.node_labels = nodes
            .iter()
            .map(|&n| mesh.node_labels[n as usize])
            .collect();
        let mut element_local = BTreeMap::new();
        for (e, el) in mesh.elements.iter().enumerate() {
            if piece_of[el.nodes[0] as usize] != k {
                continue;
            }
            element_local.insert(e as u32, piece.mesh.elements.len() as u32);
            piece.mesh.elements.push(MeshElement {
                kind: el.kind,
                nodes: el.nodes.iter().map(|&n| local[n as usize]).collect(),
                label: el.label,
                axisymmetric: el.axisymmetric,
            });
            piece
                .deformable
                .push(matches!(role[e], Some(Role::Deformable(..))));
            // C3D8R and the like: the type's trailing R (reduced integration)
            piece.reduced.push(
                a.element_block(e as u32)
                    .is_some_and(|(ty, _)| ty.to_ascii_uppercase().ends_with('R')),
            );
            match role[e] {
                Some(Role::Deformable(m, t)) => {
                    piece.materials.push(materials[m].1);
                    piece.thickness.push(t);
                }
                _ => {
                    piece.materials.push(Material {
                        young: 0.0,
                        poisson: 0.0,
                        density: 0.0,
                    });
                    piece.thickness.push(1.0);
                }
            }
        }
        for (name, set) in &mesh.node_sets {
            let s: Vec<u32> = set
                .iter()
                .filter(|&&n| piece_of[n as usize] == k)
                .map(|&n| local[n as usize])
                .collect();
            if !s.is_empty() {
                piece.mesh.node_sets.insert(name.clone(), s);
            }
        }
        for (name, set) in &mesh.element_sets {
            let s: Vec<u32> = set
                .iter()
                .filter_map(|e| element_local.get(e).copied())
                .collect();
            if !s.is_empty() {
                piece.mesh.element_sets.insert(name.clone(), s);
            }
        }
        for (name, def) in &deck.surfaces {
            let inside = |n: &u32| piece_of[*n as usize] == k;
            let mapped = match def {
                SurfaceDef::Faces(f) => {
                    let f: Vec<Facet> = f
                        .iter()
                        .filter(|f| f.nodes().iter().all(inside))
                        .map(|f| map_facet(f, &local))
                        .collect();
                    (!f.is_empty()).then_some(SurfaceDef::Faces(f))
                }
                SurfaceDef::Nodes(n, ar) => {
                    let (n, ar): (Vec<u32>, Vec<f64>) = n
                        .iter()
                        .zip(ar)
                        .filter(|(n, _)| inside(n))
                        .map(|(n, a)| (local[*n as usize], *a))
                        .unzip();
                    (!n.is_empty()).then_some(SurfaceDef::Nodes(n, ar))
                }
            };
            if let Some(s) = mapped {
                piece.surfaces.insert(name.clone(), s);
            }
        }
        pieces.push(piece);
    }
    Ok(Split {
        pieces,
        piece_of,
        local,
        rigid_of_piece,
        ref_nodes,
        point_mass,
    })
}
