//! Small and infinitesimal sliding: the anchors found once by a global search (each slave's
//! facet, weights and tangent plane in f64), the reach of the anchoring search, and the slaves
//! left unanchored.

use super::*;

impl SearchStage {
    /// Sets the sliding formulation (before the first increment).
    pub fn set_sliding(&mut self, sliding: crate::model::Sliding) {
        self.sliding = sliding;
    }

    /// Small sliding: how far the anchoring search reaches — `Some(r)`: facets within `r` of a
    /// slave (the pair's stated search radius); `None` (the default of a search made with
    /// [`GlobalSearch::from_parts`], and of a pair without a radius): every master facet, so
    /// every slave that projects onto the master is anchored however far it starts. Before the
    /// first increment.
    pub fn set_anchor_reach(&mut self, reach: Option<f64>) {
        self.anchor_reach = reach;
    }

    /// Small sliding: the slave nodes (model node ids) that got no anchor at the first
    /// increment — none of the master's facets lies along their normal from the slave (beyond
    /// a free edge) or within the anchoring search's reach — and so are not constrained; empty
    /// for finite sliding and before the first increment.
    pub fn unanchored(&self) -> Vec<u32> {
        match &self.anchors {
            Some(a) => a
                .iter()
                .zip(self.slave_ids.iter())
                .filter(|(a, _)| a.facet == NO_FACET)
                .map(|(_, &s)| s)
                .collect(),
            None => Vec::new(),
        }
    }

    /// The reach of the anchoring search at `positions`: the stated one, or one that holds
    /// every master facet from every slave (twice the diagonal of their common box).
    pub(super) fn anchoring_radius(&self, positions: &[[f64; 3]]) -> f64 {
        if let Some(r) = self.anchor_reach {
            return r;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let master_nodes = self.master.nodes();
        for x in master_nodes
            .iter()
            .chain(self.slave_ids.iter())
            .filter_map(|&n| positions.get(n as usize))
        {
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
        let d2: f64 = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum();
        // within f32 (the kernels square the radius), and never below the search's own
        (2.0 * d2.sqrt()).min(1.0e18).max(self.radius)
    }

    /// Small sliding: the anchors (after the first increment).
    pub fn anchors(&self) -> Option<&[layout::Anchor]> {
        self.anchors.as_deref()
    }

    /// Small sliding: each slave's anchor from the first global search, in f64 — the nearest
    /// point X0 on its facet, its weights, the smoothed normal N(X0) and the facet's own normal
    /// there. A slave projects onto the surface when it lies along the facet's normal from X0,
    /// or when X0 is on an edge or vertex the facet shares with another (a ridge); otherwise
    /// (beyond a free edge) it gets no anchor and no constraint.
    pub(super) fn build_anchors(
        &self,
        positions: &[[f64; 3]],
        raw: &[GpuHit],
    ) -> Vec<layout::Anchor> {
        let frozen = if self.sliding == crate::model::Sliding::Infinitesimal {
            layout::ANCHOR_FROZEN
        } else {
            0
        };
        raw.iter()
            .zip(self.slave_ids.iter())
            .map(|(h, &s)| {
                let none = layout::Anchor {
                    facet: NO_FACET,
                    node: u32::MAX,
                    flags: frozen,
                    _pad: 0,
                    weights: [0.0; 4],
                    normal0: [0.0; 4],
                    facet_normal0: [0.0; 4],
                };
                if h.facet == NO_FACET {
                    return none;
                }
                let f = self.master.active[h.facet as usize];
                let nodes = self.master.facets[f as usize].nodes();
                let xs: Vec<crate::geometry::V3<f64>> = nodes
                    .iter()
                    .map(|&n| crate::geometry::V3::from_array(positions[n as usize]))
                    .collect();
                let p = crate::geometry::V3::from_array(positions[s as usize]);
                let pr = crate::geometry::closest_on_facet(p, &xs);
                let dist = pr.dist2.sqrt();
                let size = self.master.facet_size[f as usize];
                let orthogonal = dist <= 1e-9 * size || pr.gap(p).abs() >= (1.0 - 1e-9) * dist;
                let on: Vec<u32> = nodes
                    .iter()
                    .zip(&pr.weights)
                    .filter(|(_, w)| **w > 1e-9)
                    .map(|(n, _)| *n)
                    .collect();
                let shared = match on.len() {
                    // on an edge: shared with another facet (a ridge, not a free edge)
                    2 => self.edge_facets(on[0], on[1]) >= 2,
                    // at a vertex: an interior one (every edge around it shared)
                    1 => self.master.facets_of_node(on[0]).iter().all(|&g| {
                        let gn = self.master.facets[g as usize].nodes();
                        let k = gn.iter().position(|&n| n == on[0]).unwrap_or(0);
                        let (prev, next) =
                            (gn[(k + gn.len() - 1) % gn.len()], gn[(k + 1) % gn.len()]);
                        (gn.len() == 2 || self.edge_facets(on[0], prev) >= 2)
                            && self.edge_facets(on[0], next) >= 2
                    }),
                    _ => false,
                };
                if !(orthogonal || shared) {
                    return none;
                }
                let mut n0 = crate::geometry::V3::<f64>::zero();
                for (k, &n) in nodes.iter().enumerate() {
                    n0 = n0
                        + crate::geometry::V3::from_array(self.master.nodal_normals[n as usize])
                            * pr.weights[k];
                }
                let n0 = n0.normalize_or_zero();
                let mut w = [0.0f32; 4];
                for k in 0..4 {
                    w[k] = pr.weights[k] as f32;
                }
                layout::Anchor {
                    facet: h.facet,
                    node: h.node,
                    flags: frozen,
                    _pad: 0,
                    weights: w,
                    normal0: [n0.x as f32, n0.y as f32, n0.z as f32, size as f32],
                    facet_normal0: [
                        pr.normal.x as f32,
                        pr.normal.y as f32,
                        pr.normal.z as f32,
                        0.0,
                    ],
                }
            })
            .collect()
    }

    /// Active facets containing both nodes `a` and `b` (2 for an interior edge, 1 for a free
    /// one; for 2D segments, facets containing node `a` when `a` is a segment end).
    pub(super) fn edge_facets(&self, a: u32, b: u32) -> usize {
        let fa = self.master.facets_of_node(a);
        if self.dim == 2 {
            return fa.len();
        }
        fa.iter()
            .filter(|&&g| self.master.facets[g as usize].nodes().contains(&b))
            .count()
    }
}

/// Small sliding: one slave's anchor keyed by model node ids — its facet by that facet's nodes
/// — so that it can be carried into another search over the same slave against a master
/// holding the same facet under other indices (a distributed run's rebuilt local model).
#[cfg(feature = "mpi")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct KeyedAnchor {
    /// The anchored facet's nodes (model node ids, as the master surface lists them; `u32::MAX`
    /// pads a triangle or a segment); all `u32::MAX` when the slave is unanchored.
    pub facet: [u32; 4],
    /// The anchor with its facet index left as the search that found it numbered it (its
    /// `node` is a model node id).
    pub anchor: layout::Anchor,
}

#[cfg(feature = "mpi")]
impl SearchStage {
    /// Small sliding: each slave's anchor keyed by model node ids, in this search's slave
    /// order ([`Self::slaves`]); `None` before the first increment and for finite sliding.
    pub(crate) fn keyed_anchors(&self) -> Option<Vec<KeyedAnchor>> {
        let anchors = self.anchors.as_ref()?;
        Some(
            anchors
                .iter()
                .map(|a| KeyedAnchor {
                    facet: if a.facet == NO_FACET {
                        [u32::MAX; 4]
                    } else {
                        self.facets[a.facet as usize]
                    },
                    anchor: *a,
                })
                .collect(),
        )
    }

    /// Small sliding: installs anchors found by another search over the same slaves (in this
    /// search's slave order, as [`Self::keyed_anchors`] gives them), each facet looked up by
    /// its nodes; the first increment then anchors nothing. Before the first increment.
    /// Errors: a count other than the slaves', or a facet this master does not hold (naming
    /// the slave).
    pub(crate) fn set_keyed_anchors(&mut self, keyed: &[KeyedAnchor]) -> Result<()> {
        if keyed.len() != self.slave_ids.len() {
            return Err(Error::LengthMismatch {
                what: "anchors (one per slave)",
                expected: self.slave_ids.len(),
                got: keyed.len(),
            });
        }
        let index: std::collections::HashMap<[u32; 4], u32> = self
            .facets
            .iter()
            .enumerate()
            .map(|(k, f)| (*f, k as u32))
            .collect();
        let mut anchors = Vec::with_capacity(keyed.len());
        for (k, a) in keyed.iter().enumerate() {
            let mut anchor = a.anchor;
            anchor.facet = if a.facet == [u32::MAX; 4] {
                NO_FACET
            } else {
                *index.get(&a.facet).ok_or_else(|| Error::BadParameter {
                    name: "anchor",
                    value: format!("slave node {}: facet {:?}", self.slave_ids[k], a.facet),
                    expected: "a facet of this search's master surface",
                })?
            };
            anchors.push(anchor);
        }
        self.anchors = Some(anchors);
        Ok(())
    }
}

#[cfg(feature = "mpi")]
impl KeyedAnchor {
    /// A slave anchored nowhere (not constrained).
    pub(crate) fn unanchored() -> Self {
        Self {
            facet: [u32::MAX; 4],
            anchor: layout::Anchor {
                facet: NO_FACET,
                node: u32::MAX,
                flags: 0,
                _pad: 0,
                weights: [0.0; 4],
                normal0: [0.0; 4],
                facet_normal0: [0.0; 4],
            },
        }
    }
}
