//! The initial-overclosure adjustment: every initially overclosed slave moved onto its master,
//! strain-free, before the first increment.

use super::*;

impl Contact {
    /// Moves every initially overclosed slave node of every pair (penalty, kinematic, rigid)
    /// onto its master, strain-free, as Abaqus adjusts initial positions: call once with the
    /// initial positions (and the first increment, for the energy report). Velocities are
    /// untouched.
    pub fn adjust_initial_overclosure(
        &mut self,
        x: &mut [[f64; 3]],
        bodies: &[BodyState],
        dt: f64,
    ) -> Result<OverclosureReport> {
        positive_dt(dt)?;
        if x.len() != self.n_nodes {
            return Err(Error::LengthMismatch {
                what: "positions (one per model node)",
                expected: self.n_nodes,
                got: x.len(),
            });
        }
        validate_positions(x, 0, 3)?;
        let mut rep = OverclosureReport::default();
        let mut found = Vec::new();
        for (k, pr) in self.pairs.iter_mut().enumerate() {
            // slaves in the node set's order: the order they are moved in, and reported
            let result = pr.search.run_on(self.exec.search(k), x)?;
            found.push(pr.map.result_to_caller(result));
        }
        for kr in &mut self.kinematic {
            found.push(kr.search.run(x)?);
        }
        let np = self.pairs.len();
        let masses = &self.masses;
        let record = |rep: &mut OverclosureReport, node: u32, h: f64| {
            rep.moved.push((node, h));
            rep.max_distance = rep.max_distance.max(h);
            rep.energy_avoided += 0.5 * masses[node as usize] * (h / dt) * (h / dt);
        };
        for (i, result) in found.iter().enumerate() {
            let master = match i.checked_sub(np) {
                None => self.pairs[i].search.master(),
                Some(j) => self.kinematic[j].search.master(),
            };
            for (&s, c) in result.slaves.iter().zip(result.contacts()) {
                let Some(c) = c else { continue };
                let nodes = master.facets[c.facet as usize].nodes();
                let xs: Vec<V3<f64>> = nodes
                    .iter()
                    .map(|&n| V3::from_array(x[n as usize]))
                    .collect();
                let p = V3::from_array(x[s as usize]);
                let pr = closest_on_facet(p, &xs);
                let gap = pr.gap(p);
                if gap < 0.0 {
                    let moved = p - pr.normal * gap;
                    x[s as usize] = moved.to_array();
                    record(&mut rep, s, -gap);
                }
            }
        }
        for rr in &self.rigid {
            let Some(b) = bodies.get(rr.body.0) else {
                return Err(Error::IndexOutOfRange {
                    what: "rigid body states".into(),
                    index: rr.body.0 as u64,
                    len: bodies.len(),
                });
            };
            let xb = V3::from_array(b.position);
            for &s in &rr.slaves {
                let p = V3::from_array(x[s as usize]);
                let local = crate::kinematic::to_body(&b.rotation, p - xb);
                let (gap, nb) = rr.spec.surface.gap(local);
                if gap < 0.0 {
                    let n = crate::kinematic::to_model(&b.rotation, nb);
                    x[s as usize] = (p - n * gap).to_array();
                    record(&mut rep, s, -gap);
                }
            }
        }
        Ok(rep)
    }
}
