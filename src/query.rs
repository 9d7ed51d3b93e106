//! Point queries: the nearest facet of a surface to arbitrary points, through the global
//! search's kernels (GPU or CPU path), without building a contact pair.
//!
//! ```
//! use abut::query::{Feature, PointQuery};
//! use abut::{Device, Surface};
//! // the unit square as two triangles, and two points above and below it
//! let nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
//! let square = Surface::triangles(&[[0, 1, 2], [0, 2, 3]]);
//! let mut q = PointQuery::new(&Device::cpu(), 3, &nodes, square, 2, 1.0).unwrap();
//! let hits = q.query(&nodes, &[[0.2, 0.7, 0.25], [1.5, 0.5, -0.1]]).unwrap();
//! let a = hits[0].as_ref().unwrap();
//! assert_eq!((a.facet, a.feature), (1, Feature::Face));
//! assert!((a.signed_distance - 0.25).abs() < 1e-6);
//! let b = hits[1].as_ref().unwrap(); // beside the edge x = 1, below the plane
//! assert_eq!(b.feature, Feature::Edge);
//! assert!((b.distance - (0.25f64 + 0.01).sqrt()).abs() < 1e-6 && b.signed_distance < 0.0);
//! ```

use crate::device::Device;
use crate::error::{Error, Result};
use crate::geometry::{closest_on_facet, V3};
use crate::model::{Model, Surface};
use crate::search::GlobalSearch;

/// Where on its facet the nearest point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// Inside the facet (3D), or inside the segment (2D).
    Face,
    /// On an edge of the facet, not at a corner (3D).
    Edge,
    /// At a node of the facet.
    Vertex,
}

/// The nearest point of the surface to one query point, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointHit {
    /// The facet (index into the surface's facets; ties: the lowest).
    pub facet: u32,
    /// The nearest point on it, model units.
    pub point: [f64; 3],
    /// The facet's unit normal at that point.
    pub normal: [f64; 3],
    /// Distance from the query point to `point` (≥ 0).
    pub distance: f64,
    /// `distance` with the sign of the side: negative behind the facet (against its normal).
    /// Unlike the gap along the normal, its magnitude is the distance at edges and vertices too.
    pub signed_distance: f64,
    /// Where on the facet `point` lies.
    pub feature: Feature,
    /// The facet nodes' weights at `point` (shape functions; unused slots 0).
    pub weights: [f64; 4],
}

/// Weights below this are a point off that node's side (a point on an edge or at a vertex).
const ON_FEATURE: f64 = 1e-9;

/// Repeated nearest-facet queries of a fixed number of points against one surface, whose nodes
/// may move between queries. Built once (pipelines, buffers), then one global search per query.
pub struct PointQuery {
    search: GlobalSearch,
    surface: crate::model::MasterSurface,
    n_nodes: usize,
    n_points: usize,
    positions: Vec<[f64; 3]>,
}

impl PointQuery {
    /// A query of `n_points` points against `surface` (facets over `nodes`, model units, `dim` 2
    /// or 3) within `radius` on `device`: points with no facet within `radius` get `None`.
    pub fn new(
        device: &Device,
        dim: u32,
        nodes: &[[f64; 3]],
        surface: Surface,
        n_points: usize,
        radius: f64,
    ) -> Result<Self> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::BadParameter {
                name: "query radius",
                value: radius.to_string(),
                expected: "must be finite and positive",
            });
        }
        let mut model = match dim {
            2 => Model::new_2d(),
            3 => Model::new_3d(),
            _ => {
                return Err(Error::BadParameter {
                    name: "dimension",
                    value: dim.to_string(),
                    expected: "2 or 3",
                })
            }
        };
        if dim == 2 {
            let flat: Vec<[f64; 2]> = nodes.iter().map(|x| [x[0], x[1]]).collect();
            model.add_nodes_2d(&flat, &vec![1.0; nodes.len()])?;
        } else {
            model.add_nodes(nodes, &vec![1.0; nodes.len()])?;
        }
        let s = model.add_surface(surface)?;
        // the query points, as slave nodes at the surface's first node until the first query
        let start = nodes.first().copied().unwrap_or([0.0; 3]);
        let at = vec![start; n_points];
        if dim == 2 {
            let flat: Vec<[f64; 2]> = at.iter().map(|x| [x[0], x[1]]).collect();
            model.add_nodes_2d(&flat, &vec![1.0; n_points])?;
        } else {
            model.add_nodes(&at, &vec![1.0; n_points])?;
        }
        let points: Vec<u32> = (nodes.len()..nodes.len() + n_points)
            .map(|n| n as u32)
            .collect();
        let surface = model.surface(s)?.clone();
        let search = GlobalSearch::from_parts(device, &model, surface.clone(), points, radius)?;
        Ok(Self {
            search,
            surface,
            n_nodes: nodes.len(),
            n_points,
            positions: model.positions().to_vec(),
        })
    }

    /// The nearest facet within the radius of each of `points`, with the surface's nodes at
    /// `nodes` (the same count as at construction).
    pub fn query(
        &mut self,
        nodes: &[[f64; 3]],
        points: &[[f64; 3]],
    ) -> Result<Vec<Option<PointHit>>> {
        if nodes.len() != self.n_nodes {
            return Err(Error::LengthMismatch {
                what: "surface nodes",
                expected: self.n_nodes,
                got: nodes.len(),
            });
        }
        if points.len() != self.n_points {
            return Err(Error::LengthMismatch {
                what: "query points",
                expected: self.n_points,
                got: points.len(),
            });
        }
        self.positions[..self.n_nodes].copy_from_slice(nodes);
        self.positions[self.n_nodes..].copy_from_slice(points);
        let r = self.search.run(&self.positions)?;
        Ok(r.contacts()
            .zip(points)
            .map(|(c, p)| c.as_ref().map(|c| self.hit(c.facet, *p)))
            .collect())
    }

    /// The f64 closest point of `p` on facet `facet` and its feature.
    fn hit(&self, facet: u32, p: [f64; 3]) -> PointHit {
        let fac = &self.surface.facets[facet as usize];
        let xs: Vec<V3<f64>> = fac
            .nodes()
            .iter()
            .map(|&n| V3::from_array(self.positions[n as usize]))
            .collect();
        let q = V3::from_array(p);
        let pr = closest_on_facet(q, &xs);
        let distance = pr.dist2.sqrt();
        let gap = pr.gap(q);
        let on = pr.weights[..xs.len()]
            .iter()
            .filter(|w| w.abs() > ON_FEATURE)
            .count();
        let feature = match (xs.len(), on) {
            (_, 1) => Feature::Vertex,
            (2, _) => Feature::Face,
            (_, 2) => Feature::Edge,
            _ => Feature::Face,
        };
        PointHit {
            facet,
            point: pr.point.to_array(),
            normal: pr.normal.to_array(),
            distance,
            signed_distance: if gap < 0.0 { -distance } else { distance },
            feature,
            weights: pr.weights,
        }
    }
}
