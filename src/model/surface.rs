//! Master surfaces: facets, their validation, node→facet adjacency, nodal normals and sizes.

use crate::error::{Error, Result};
use crate::geometry::V3;

/// Marks an unused node slot of a facet (WGSL: `NO_NODE`).
pub const NO_NODE: u32 = u32::MAX;

/// One master facet, by node indices into the model's node array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facet {
    /// 2-node segment (2D models).
    Segment([u32; 2]),
    /// 3-node triangle (3D models), nodes counter-clockwise seen from outside.
    Triangle([u32; 3]),
    /// 4-node bilinear quad (3D models), nodes counter-clockwise seen from outside.
    Quad([u32; 4]),
}

impl Facet {
    /// The node indices, unused slots filled with [`NO_NODE`].
    pub fn padded(&self) -> [u32; 4] {
        match *self {
            Facet::Segment([a, b]) => [a, b, NO_NODE, NO_NODE],
            Facet::Triangle([a, b, c]) => [a, b, c, NO_NODE],
            Facet::Quad(q) => q,
        }
    }
    /// The node indices.
    pub fn nodes(&self) -> &[u32] {
        match self {
            Facet::Segment(n) => n,
            Facet::Triangle(n) => n,
            Facet::Quad(n) => n,
        }
    }
    /// "segment", "triangle" or "quad".
    pub fn kind(&self) -> &'static str {
        match self {
            Facet::Segment(_) => "segment",
            Facet::Triangle(_) => "triangle",
            Facet::Quad(_) => "quad",
        }
    }
}

/// A master surface as the user describes it: a list of facets.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Surface {
    /// The facets, in the order that defines their ids (0, 1, …).
    pub facets: Vec<Facet>,
}

impl Surface {
    /// A 2D surface of 2-node segments.
    pub fn segments(segments: &[[u32; 2]]) -> Self {
        Self {
            facets: segments.iter().map(|&s| Facet::Segment(s)).collect(),
        }
    }
    /// A 3D surface of triangles.
    pub fn triangles(tris: &[[u32; 3]]) -> Self {
        Self {
            facets: tris.iter().map(|&t| Facet::Triangle(t)).collect(),
        }
    }
    /// A 3D surface of bilinear quads.
    pub fn quads(quads: &[[u32; 4]]) -> Self {
        Self {
            facets: quads.iter().map(|&q| Facet::Quad(q)).collect(),
        }
    }
    /// A surface from any list of facets (triangles and quads may be mixed in 3D).
    pub fn from_facets(facets: Vec<Facet>) -> Self {
        Self { facets }
    }
}

/// Why a facet was excluded from the search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DegenerateFacet {
    /// Facet id within its surface.
    pub facet: u32,
    /// Its area (3D) or length (2D) at validation, in model units.
    pub measure: f64,
}

/// A validated master surface with the data the search and enforcement need.
#[derive(Clone, Debug)]
pub struct MasterSurface {
    /// The facets as given, ids 0..n.
    pub facets: Vec<Facet>,
    /// Facets excluded from the search because their area (or length) is zero relative to their
    /// size: reported here, never searched.
    pub degenerate: Vec<DegenerateFacet>,
    /// Ids of the facets that take part in the search, increasing.
    pub active: Vec<u32>,
    /// Node→facet adjacency (CSR): the facets of node `n` are
    /// `node_facets[node_facet_start[n]..node_facet_start[n + 1]]`, increasing, active only.
    pub node_facet_start: Vec<u32>,
    /// See `node_facet_start`.
    pub node_facets: Vec<u32>,
    /// Smoothed unit nodal normals (area-weighted mean of the active facets' normals at the
    /// node), one per model node; zero for nodes on no active facet.
    pub nodal_normals: Vec<[f64; 3]>,
    /// Characteristic length of each facet (longest edge), model units.
    pub facet_size: Vec<f64>,
    /// Area of each facet (length in 2D) at validation, model units.
    pub facet_area: Vec<f64>,
}

impl MasterSurface {
    /// Validates `surface` against the model's nodes and derives adjacency, normals and sizes.
    ///
    /// Errors name the facet: out-of-range nodes, repeated nodes, facet kinds foreign to the
    /// dimension, an empty surface, or one whose facets are all degenerate.
    pub fn build(surface: &Surface, positions: &[[f64; 3]], dim: u32) -> Result<Self> {
        if surface.facets.is_empty() {
            return Err(Error::Empty {
                what: "surface".into(),
            });
        }
        let n_nodes = positions.len();
        let mut degenerate = Vec::new();
        let mut active = Vec::new();
        let mut facet_size = Vec::with_capacity(surface.facets.len());
        let mut facet_area = Vec::with_capacity(surface.facets.len());
        let mut facet_normals = Vec::with_capacity(surface.facets.len());
        for (f, facet) in surface.facets.iter().enumerate() {
            let is_2d = matches!(facet, Facet::Segment(_));
            if is_2d != (dim == 2) {
                return Err(Error::WrongDimension {
                    facet: f,
                    kind: facet.kind(),
                    dim,
                });
            }
            let nodes = facet.nodes();
            for (k, &n) in nodes.iter().enumerate() {
                if n as usize >= n_nodes {
                    return Err(Error::IndexOutOfRange {
                        what: format!("surface facet {f}, node slot {k}"),
                        index: n as u64,
                        len: n_nodes,
                    });
                }
                if nodes[..k].contains(&n) {
                    return Err(Error::RepeatedNode { facet: f, node: n });
                }
            }
            let x: Vec<V3<f64>> = nodes
                .iter()
                .map(|&n| V3::from_array(positions[n as usize]))
                .collect();
            let size = (0..x.len())
                .map(|i| (x[(i + 1) % x.len()] - x[i]).length2().sqrt())
                .fold(0.0f64, f64::max);
            // Area vector (3D) or length (2D) of the facet.
            let (measure, normal_area) = match x.len() {
                2 => {
                    let t = x[1] - x[0];
                    let len = t.length2().sqrt();
                    (len, V3::new(t.y, -t.x, 0.0))
                }
                3 => {
                    let a = (x[1] - x[0]).cross(x[2] - x[0]) * 0.5;
                    (a.length2().sqrt(), a)
                }
                _ => {
                    let a = (x[2] - x[0]).cross(x[3] - x[1]) * 0.5;
                    (a.length2().sqrt(), a)
                }
            };
            // Relative threshold: below f32 round-off of the facet's own size.
            let scale = if dim == 2 { size } else { size * size };
            let is_degenerate = !(measure > 1e-6 * scale) || size == 0.0;
            facet_size.push(size);
            facet_area.push(measure);
            if is_degenerate {
                degenerate.push(DegenerateFacet {
                    facet: f as u32,
                    measure,
                });
                facet_normals.push(V3::zero());
            } else {
                active.push(f as u32);
                facet_normals.push(normal_area);
            }
        }
        if active.is_empty() {
            return Err(Error::AllFacetsDegenerate {
                count: surface.facets.len(),
            });
        }
        // Node→facet adjacency, counting sort by node (stable: facet ids increase).
        let mut count = vec![0u32; n_nodes + 1];
        for &f in &active {
            for &n in surface.facets[f as usize].nodes() {
                count[n as usize + 1] += 1;
            }
        }
        for i in 0..n_nodes {
            count[i + 1] += count[i];
        }
        let node_facet_start = count.clone();
        let mut cursor = count;
        let mut node_facets = vec![0u32; *node_facet_start.last().unwrap_or(&0) as usize];
        let mut normal_sum = vec![V3::<f64>::zero(); n_nodes];
        for &f in &active {
            for &n in surface.facets[f as usize].nodes() {
                node_facets[cursor[n as usize] as usize] = f;
                cursor[n as usize] += 1;
                normal_sum[n as usize] = normal_sum[n as usize] + facet_normals[f as usize];
            }
        }
        let nodal_normals = normal_sum
            .into_iter()
            .map(|v| v.normalize_or_zero().to_array())
            .collect();
        Ok(Self {
            facets: surface.facets.clone(),
            degenerate,
            active,
            node_facet_start,
            node_facets,
            nodal_normals,
            facet_size,
            facet_area,
        })
    }

    /// The active facets of node `n` (increasing ids; empty for nodes on none, including
    /// nodes added to the model after the surface).
    pub fn facets_of_node(&self, n: u32) -> &[u32] {
        if n as usize + 1 >= self.node_facet_start.len() {
            return &[];
        }
        let s = self.node_facet_start[n as usize] as usize;
        let e = self.node_facet_start[n as usize + 1] as usize;
        &self.node_facets[s..e]
    }

    /// Mean area (length in 2D) of the active facets, model units.
    pub fn mean_facet_area(&self) -> f64 {
        let sum: f64 = self
            .active
            .iter()
            .map(|&f| self.facet_area[f as usize])
            .sum();
        sum / self.active.len() as f64
    }

    /// Tributary area (length in 2D) of node `n` on this surface: each active facet's area
    /// shared equally among its nodes, model units (0 for nodes on no active facet).
    pub fn tributary_area(&self, n: u32) -> f64 {
        self.facets_of_node(n)
            .iter()
            .map(|&f| self.facet_area[f as usize] / self.facets[f as usize].nodes().len() as f64)
            .sum()
    }

    /// Nodes of the active facets, increasing.
    pub fn nodes(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .active
            .iter()
            .flat_map(|&f| self.facets[f as usize].nodes().to_vec())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Mean characteristic length of the active facets, model units.
    pub fn mean_facet_size(&self) -> f64 {
        let sum: f64 = self
            .active
            .iter()
            .map(|&f| self.facet_size[f as usize])
            .sum();
        sum / self.active.len() as f64
    }
}

/// Number of nodes of a padded facet (WGSL twin: `facet_node_count` in common.wgsl).
pub fn facet_node_count(f: [u32; 4]) -> usize {
    if f[2] == NO_NODE {
        2
    } else if f[3] == NO_NODE {
        3
    } else {
        4
    }
}
