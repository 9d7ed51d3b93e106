//! The ghosts of a rank: the motion budget of its slave region, the master nodes of other ranks
//! inside it (chosen at each distributed global search), and the rank's local model and contact
//! rebuilt from its own and its ghost nodes.

use super::collectives::all_gather_fixed;
use super::*;

impl DistributedContact {
    /// The motion budget: how far any node may move between distributed global searches (half
    /// the smallest search radius).
    pub(super) fn budget(&self) -> f64 {
        0.5 * self
            .pairs
            .iter()
            .map(|p| p.radius)
            .fold(f64::INFINITY, f64::min)
    }

    /// The longest edge of this rank's local facets (at own positions `x` and the last
    /// increment's ghost positions) and of the facets all of whose nodes it owns. A facet cut
    /// between ranks and near no rank's slaves is not measured: one that stretches beyond twice
    /// the margin before it comes near a slave can still be missed.
    pub(super) fn longest_local_edge(&self, x: &[[f64; 3]]) -> f64 {
        let n_own = x.len();
        let at = |i: u32| -> Option<[f64; 3]> {
            let i = i as usize;
            if i < n_own {
                Some(x[i])
            } else {
                self.ghost_x.get(i - n_own).copied()
            }
        };
        let mut longest = 0.0f64;
        for f in self.local_facets.iter().chain(&self.own_facets) {
            let m = facet_node_count(f, u32::MAX);
            for j in 0..m {
                if let (Some(a), Some(b)) = (at(f[j]), at(f[(j + 1) % m])) {
                    let d = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
                    longest = longest.max(d);
                }
            }
        }
        longest
    }

    /// New ghosts for own positions `x`: the send lists, the ghosts' ids and masses. Returns
    /// the ghosts' global ids (by source rank, then in the order sent) and the bytes sent.
    /// Three collectives: each rank's slave box with its longest local edge (facets that
    /// stretched since the start widen every rank's ghost margin, never narrowed), then the
    /// ghosts' ids and masses with their counts.
    pub(super) fn choose_ghosts(&mut self, x: &[[f64; 3]]) -> (Vec<u64>, usize) {
        let size = self.comm.size() as usize;
        // this rank's slaves' box (none: an inverted box, which contains nothing once grown)
        // and its longest local edge; the margin is added once every rank's edge is known
        // (min(x) − grow is min(x − grow) to the bit: rounding is monotone)
        let mut mine = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            self.longest_local_edge(x),
        ];
        let mut cover = |p: [f64; 3]| {
            for a in 0..3 {
                mine[a] = mine[a].min(p[a]);
                mine[3 + a] = mine[3 + a].max(p[a]);
            }
        };
        for p in &self.pairs {
            for &s in &p.slaves {
                cover(x[s]);
            }
        }
        // small sliding: the anchored facets stay in the local model (with the facets around
        // them) however far they are from the slave (at own positions now, ghosts' last)
        let ghost_of: HashMap<u64, usize> = self
            .ghost_ids
            .iter()
            .enumerate()
            .map(|(k, &g)| (g, k))
            .collect();
        for a in self
            .pairs
            .iter()
            .filter_map(|p| p.anchors.as_ref())
            .flatten()
        {
            for &g in a.facet.iter().filter(|&&g| g != NO_GLOBAL_NODE) {
                if let Some(&i) = self.index.get(&g) {
                    cover(x[i]);
                } else if let Some(&k) = ghost_of.get(&g) {
                    cover(self.ghost_x[k]);
                }
            }
        }
        let boxes = all_gather_fixed(&self.comm, &mine);
        let longest = boxes.chunks_exact(7).map(|b| b[6]).fold(0.0f64, f64::max);
        self.h_max = self.h_max.max(longest);
        let mut grow = self.pairs.iter().map(|p| p.radius).fold(0.0f64, f64::max)
            + 2.0 * self.budget()
            + 2.0 * self.h_max;
        // small sliding not anchored yet: as far as the anchoring search reaches, with the
        // facets around the facet it finds (no reach stated: every master node)
        for p in self
            .pairs
            .iter()
            .filter(|p| p.anchored() && p.anchors.is_none())
        {
            grow = grow.max(p.anchor_reach.unwrap_or(f64::INFINITY) + 2.0 * self.h_max);
        }
        let me = self.comm.rank() as usize;
        self.send = vec![Vec::new(); size];
        for r in (0..size).filter(|&r| r != me) {
            let b = &boxes[7 * r..7 * r + 6];
            let (lo, hi) = (
                [b[0] - grow, b[1] - grow, b[2] - grow],
                [b[3] + grow, b[4] + grow, b[5] + grow],
            );
            if b[0] > b[3] {
                // a rank without slaves needs no ghosts
                continue;
            }
            for &i in &self.master_nodes {
                if (0..3).all(|a| x[i][a] >= lo[a] && x[i][a] <= hi[a]) {
                    self.send[r].push(i);
                }
            }
        }
        // each ghost's id and mass (its bits), in one exchange
        let out: Vec<Vec<u64>> = self
            .send
            .iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&i| [self.ids[i], self.masses[i].to_bits()])
                    .collect()
            })
            .collect();
        let came = exchange(&self.comm, &out);
        self.recv = came.iter().map(|l| l.len() / 2).collect();
        let pairs = came.iter().flat_map(|l| l.chunks_exact(2));
        self.ghost_masses = pairs.clone().map(|c| f64::from_bits(c[1])).collect();
        let ids = pairs.map(|c| c[0]).collect();
        let sent: usize = self.send.iter().map(Vec::len).sum();
        (ids, 16 * sent + 56)
    }

    /// The local model of own nodes at `x` and ghosts at `gx` (global ids `ghost_ids`), and its
    /// contact (none when this rank has no slave near any facet).
    pub(super) fn build_local(
        &mut self,
        x: &[[f64; 3]],
        gx: &[[f64; 3]],
        ghost_ids: &[u64],
    ) -> Result<()> {
        let n_own = self.ids.len();
        let mut local_of: HashMap<u64, u32> = HashMap::with_capacity(n_own + ghost_ids.len());
        for (&g, &i) in &self.index {
            local_of.insert(g, i as u32);
        }
        for (k, &g) in ghost_ids.iter().enumerate() {
            local_of.insert(g, (n_own + k) as u32);
        }
        let mut model = if self.two_d {
            Model::new_2d()
        } else {
            Model::new_3d()
        };
        let positions: Vec<[f64; 3]> = x.iter().chain(gx).copied().collect();
        model.add_nodes(&positions, &self.local_masses())?;
        // the rigid parts it holds nodes of (their states come from the whole parts)
        self.parts.add_to(&mut model, &local_of)?;
        // the friction each slave carries, from the contact being replaced (same slaves, same
        // order: a slave never changes rank)
        let mut carried = Vec::with_capacity(self.pairs.len());
        for p in self.pairs.iter_mut() {
            carried.push(match (self.contact.as_mut(), p.local) {
                (Some(c), Some(id)) if p.kinematic.is_some() => {
                    // a kinematic pair carries its slaves' behind-a-free-edge flags
                    p.behind = Some(c.kinematic_behind(id)?);
                    None
                }
                (Some(c), Some(id)) => Some(c.penalty_states(id)?),
                _ => None,
            });
        }
        let mut any = false;
        let mut local_facets = Vec::new();
        for p in self.pairs.iter_mut() {
            p.local = None;
            if p.slaves.is_empty() {
                continue;
            }
            let facets: Vec<Facet> = p
                .facets
                .iter()
                .filter_map(|f| {
                    let m = facet_node_count(f, NO_GLOBAL_NODE);
                    let mut l = [u32::MAX; 4];
                    for j in 0..m {
                        l[j] = *local_of.get(&f[j])?;
                    }
                    Some(facet_of(l, m))
                })
                .collect();
            if facets.is_empty() {
                continue;
            }
            local_facets.extend(facets.iter().map(|f| {
                let n = f.nodes();
                let at = |j: usize| n.get(j).copied().unwrap_or(u32::MAX);
                [at(0), at(1), at(2), at(3)]
            }));
            let surf = model.add_surface(Surface::from_facets(facets.clone()))?;
            let slaves: Vec<u32> = p.slaves.iter().map(|&s| s as u32).collect();
            let set = model.add_node_set_with_areas(&slaves, &p.areas)?;
            // the single process's schedule: its interval, the defaults otherwise
            let on_surface: std::collections::HashSet<u32> =
                facets.iter().flat_map(|f| f.nodes().to_vec()).collect();
            let self_contact = slaves.iter().any(|s| on_surface.contains(s));
            let schedule = Schedule {
                interval: p.interval,
                ..Schedule::default_for(self_contact)
            };
            p.local = Some(
                model.add_pair(
                    Pair::new(set, surf)
                        .schedule(schedule)
                        .sliding(p.sliding)
                        .search_radius(p.radius)
                        .enforce(match &p.kinematic {
                            Some(k) => Enforce::Kinematic(k.clone()),
                            None => Enforce::Penalty(p.penalty.clone()),
                        })
                        .friction(p.friction.clone())
                        .pass_weight(if p.kinematic.is_some() {
                            // a kinematic pass is weighed by the correction itself
                            1.0
                        } else {
                            p.weight
                        }),
                )?,
            );
            any = true;
        }
        self.contact = if any {
            let mut c = Contact::new(&self.device, &model)?;
            c.request_outputs(self.outputs);
            // the rows of the bound: a node's and a body's are summed over the ranks
            c.request_rows(true);
            if self.parts.len() > 0 {
                for (k, p) in self.pairs.iter().enumerate() {
                    if let (Some(id), None) = (p.local, &p.kinematic) {
                        c.set_rigid_slave_share(id, self.parts.pass_slaves(k))?;
                    }
                }
            }
            if let Some(dt) = self.dt_ref {
                c.set_reference_increment(dt)?;
            }
            for (p, states) in self.pairs.iter().zip(carried) {
                if let (Some(id), Some(s)) = (p.local, states) {
                    c.set_penalty_states(id, &s)?;
                }
                if let (Some(id), Some(b)) = (p.local, &p.behind) {
                    c.set_kinematic_behind(id, b)?;
                }
            }
            Some(c)
        } else {
            None
        };
        let mut contact = self.contact.take();
        let put = self.put_anchors(contact.as_mut(), &local_of);
        self.contact = contact;
        put?;
        self.anchor = positions;
        self.local_facets = local_facets;
        Ok(())
    }
}
