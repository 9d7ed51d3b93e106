//! A search's inputs in the kernels' layout: the frame fitted to the master, the parameters,
//! every node in the frame (subtracted in f64) and the pair's constant arrays.

use super::*;

impl SearchStage {
    /// Builds the kernels' input: validates positions, chooses the frame at the master,
    /// converts to f32 relative to it.
    pub fn prepare(&self, positions: &[[f64; 3]]) -> Result<Prepared> {
        if positions.len() != self.masses.len() {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.masses.len(),
                got: positions.len(),
            });
        }
        validate_positions(positions, 0, self.dim)?;
        // the master's box, from the padded active facets (unused slots repeat node 1, which
        // changes no box); four lanes of f64 per corner
        let mut lo = glam::DVec4::splat(f64::INFINITY);
        let mut hi = glam::DVec4::splat(f64::NEG_INFINITY);
        for fac in self.facets.iter() {
            let n = crate::model::facet_node_count(*fac);
            let x = |j: usize| {
                let p = positions[fac[j.min(n - 1)] as usize];
                glam::DVec4::new(p[0], p[1], p[2], 0.0)
            };
            let (x0, x1, x2, x3) = (x(0), x(1), x(2), x(3));
            lo = lo.min(x0.min(x1).min(x2.min(x3)));
            hi = hi.max(x0.max(x1).max(x2.max(x3)));
        }
        let (lo, hi) = ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
        let n_facets = self.facets.len();
        let frame = match self.given_frame {
            Some((origin, _)) => origin,
            None => crate::plan::frame::origin(lo, hi, self.radius, self.dim)?,
        };
        let nodes = self.in_frame(positions, frame)?;
        let in_frame = |x: [f64; 3]| {
            let [a, b, c] = [0, 1, 2].map(|k| (x[k] - frame[k]) as f32);
            [a, b, c, 0.0]
        };
        let buckets = self.structure == crate::model::SearchStructure::Buckets;
        let layout = crate::abi::buckets::BucketLayout::new(n_facets as u32);
        let params = SearchParams {
            radius: self.radius as f32,
            box_margin: box_margin(lo, hi, frame),
            n_facets: n_facets as u32,
            n_slaves: self.slave_ids.len() as u32,
            tree_levels: tree::levels(n_facets),
            dim: self.dim,
            max_local_iterations: layout::MAX_LOCAL_ITERATIONS,
            flags: self.flags(),
            budget: (self.schedule.budget * self.radius) as f32,
            n_motion_nodes: self.motion_nodes.len() as u32,
            ref_node: self.ref_node,
            bucket_cell: if buckets {
                (BUCKET_CELL_FACETS * self.largest_facet) as f32
            } else {
                0.0
            },
            master_lo: in_frame(lo),
            master_hi: in_frame(hi),
            bucket_bits: if buckets { layout.bits } else { 0 },
            bucket_entries: if buckets { layout.entries } else { 0 },
            _pad: [0; 2],
        };
        Ok(Prepared {
            params,
            frame,
            nodes,
            facets: self.facets.clone(),
            slaves: self.slave_ids.clone(),
            order: self.order.clone(),
            walk_order: self.walk_order.clone(),
            adjacency: self.adjacency.clone(),
            motion_nodes: self.motion_nodes.clone(),
            n_nodes: self.masses.len(),
        })
    }

    pub(super) fn flags(&self) -> u32 {
        (if self.schedule.wide_local {
            layout::FLAG_WIDE_LOCAL
        } else {
            0
        }) | (if self.self_contact {
            layout::FLAG_SELF_CONTACT
        } else {
            0
        }) | (if self.schedule.visit_every_slave {
            layout::FLAG_EVERY_SLAVE
        } else {
            0
        }) | (if self.structure == crate::model::SearchStructure::Buckets {
            layout::FLAG_BUCKETS
        } else {
            0
        }) | (if self
            .slave_ids
            .iter()
            .all(|&s| self.adjacency[s as usize] == self.adjacency[s as usize + 1])
        {
            layout::FLAG_SLAVES_APART
        } else {
            0
        })
    }

    /// Every node's position relative to `frame` in f32, with its mass; an error naming the
    /// first slave or master node whose coordinate there is beyond f32's range (finite in f64,
    /// 1e39 say, but infinite to the kernels).
    pub(super) fn in_frame(
        &self,
        positions: &[[f64; 3]],
        frame: [f64; 3],
    ) -> Result<Vec<[f32; 4]>> {
        let nodes: Vec<[f32; 4]> = positions
            .iter()
            .zip(&self.masses)
            .map(|(x, &m)| {
                [
                    (x[0] - frame[0]) as f32,
                    (x[1] - frame[1]) as f32,
                    (x[2] - frame[2]) as f32,
                    m,
                ]
            })
            .collect();
        // every coordinate finite in f32 in both frames (the common case, sequential passes):
        // nothing to name
        let finite = |x: [f32; 3]| x[0].is_finite() && x[1].is_finite() && x[2].is_finite();
        if nodes.iter().all(|x| finite([x[0], x[1], x[2]]))
            && positions
                .iter()
                .all(|x| finite([x[0] as f32, x[1] as f32, x[2] as f32]))
        {
            return Ok(nodes);
        }
        // the lowest node beyond f32 in the model frame itself, else in the search's frame
        let lowest = |beyond: &dyn Fn(usize, usize) -> bool| {
            let mut bad: Option<(usize, usize)> = None;
            for &n in self.motion_nodes.iter() {
                let n = n as usize;
                if let Some(axis) = (0..3).find(|&a| beyond(n, a)) {
                    if bad.is_none_or(|(b, _)| n < b) {
                        bad = Some((n, axis));
                    }
                }
            }
            bad
        };
        let bad = lowest(&|n, a| !(positions[n][a] as f32).is_finite())
            .or_else(|| lowest(&|n, a| !nodes[n][a].is_finite()));
        match bad {
            None => Ok(nodes),
            Some((node, axis)) => Err(Error::CoordinateOutOfRange {
                node,
                axis,
                value: positions[node][axis],
                frame: frame[axis],
            }),
        }
    }
}
