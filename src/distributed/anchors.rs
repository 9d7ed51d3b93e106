//! Small sliding across ranks: each slave's anchor, found once by the local model of the rank
//! that owns the slave, kept by global node ids and put into every local model rebuilt after
//! it (the facets it names are kept in the rank's ghost region: [`DistributedContact::choose_ghosts`]).

use super::*;

impl PairTopology {
    /// Whether this pass anchors its slaves (small or infinitesimal sliding).
    pub(super) fn anchored(&self) -> bool {
        self.sliding != Sliding::Finite
    }
}

impl DistributedContact {
    /// The global id of local node `l` of the current local model.
    pub(super) fn global_of(&self, l: u32) -> u64 {
        let n_own = self.ids.len();
        match l {
            u32::MAX => NO_GLOBAL_NODE,
            l if (l as usize) < n_own => self.ids[l as usize],
            l => self.ghost_ids[l as usize - n_own],
        }
    }

    /// A fast node of the local contact, by global id and the pair it is a pass of.
    pub(super) fn fast_global(&self, f: &crate::FastNode) -> FastGlobalNode {
        FastGlobalNode {
            node: self.global_of(f.node as u32),
            pair: self
                .pairs
                .iter()
                .find(|p| p.local == Some(f.pair))
                .map_or(0, |p| p.of.0),
            distance: f.distance,
            radius: f.radius,
        }
    }

    /// After an increment: the anchors the local contact found at its first increment, for
    /// every anchored pass that had none, by global ids.
    pub(super) fn take_anchors(&mut self) -> Result<()> {
        let Some(c) = self.contact.as_ref() else {
            return Ok(());
        };
        let mut found = Vec::new();
        for (k, p) in self.pairs.iter().enumerate() {
            let (Some(id), true, None) = (p.local, p.anchored(), &p.anchors) else {
                continue;
            };
            let Some(Some(keyed)) = c.penalty_anchors(id)?.into_iter().next() else {
                continue;
            };
            let global = keyed
                .into_iter()
                .map(|a| GlobalAnchor {
                    facet: a.facet.map(|l| self.global_of(l)),
                    node: self.global_of(a.anchor.node),
                    anchor: a,
                })
                .collect();
            found.push((k, global));
        }
        for (k, a) in found {
            self.pairs[k].anchors = Some(a);
        }
        Ok(())
    }

    /// Into a new local contact `c` (its nodes numbered by `local_of`): each anchored pass's
    /// anchors once found, else the reach of the anchoring search its first increment runs.
    /// An anchored pass with slaves but no facet in the local model anchors none of them.
    pub(super) fn put_anchors(
        &mut self,
        c: Option<&mut Contact>,
        local_of: &HashMap<u64, u32>,
    ) -> Result<()> {
        let mut c = c;
        for p in self.pairs.iter_mut().filter(|p| p.anchored()) {
            let Some(id) = p.local else {
                if !p.slaves.is_empty() && p.anchors.is_none() {
                    // no master facet reaches any of them: all unanchored, for good
                    p.anchors = Some(vec![GlobalAnchor::unanchored(); p.slaves.len()]);
                }
                continue;
            };
            let Some(c) = c.as_deref_mut() else { continue };
            let Some(global) = &p.anchors else {
                c.set_anchor_reach(id, p.anchor_reach)?;
                continue;
            };
            let local = |g: u64| -> Result<u32> {
                if g == NO_GLOBAL_NODE {
                    return Ok(u32::MAX);
                }
                local_of.get(&g).copied().ok_or_else(|| {
                    bad(
                        "anchor",
                        format!("node {g}: not in this rank's local model"),
                        "the anchored facets' nodes kept as ghosts",
                    )
                })
            };
            let mut keyed = Vec::with_capacity(global.len());
            for a in global {
                let mut k = a.anchor;
                if a.facet[0] != NO_GLOBAL_NODE {
                    k.facet = [
                        local(a.facet[0])?,
                        local(a.facet[1])?,
                        local(a.facet[2])?,
                        local(a.facet[3])?,
                    ];
                    k.anchor.node = local(a.node)?;
                }
                keyed.push(k);
            }
            c.set_penalty_anchors(id, &[Some(keyed)])?;
        }
        Ok(())
    }
}

impl GlobalAnchor {
    /// A slave no facet anchors.
    fn unanchored() -> Self {
        Self {
            facet: [NO_GLOBAL_NODE; 4],
            node: NO_GLOBAL_NODE,
            anchor: KeyedAnchor::unanchored(),
        }
    }
}

/// Small sliding: one anchored pass's slaves on this rank after the first increment (see
/// [`DistributedContact::anchoring`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PassAnchoring {
    /// The pair ([`RankModel::pairs`] index).
    pub pair: usize,
    /// Whether it is a balanced pair's second pass (the slaves its master nodes).
    pub reverse: bool,
    /// This rank's slaves of the pass.
    pub slaves: usize,
    /// Those no master facet anchors (global ids, in the pass's order): they project onto no
    /// facet — beyond a free edge, or beyond the anchoring search's reach — and are not
    /// constrained.
    pub unanchored: Vec<u64>,
}

impl DistributedContact {
    /// Small and infinitesimal sliding: each anchored pass's slaves on this rank and those
    /// left unanchored, after the first increment (empty before it and for finite sliding).
    /// Not collective.
    pub fn anchoring(&self) -> Vec<PassAnchoring> {
        self.pairs
            .iter()
            .filter_map(|p| {
                let a = p.anchors.as_ref()?;
                Some(PassAnchoring {
                    pair: p.of.0,
                    reverse: p.of.1,
                    slaves: p.slaves.len(),
                    unanchored: p
                        .slaves
                        .iter()
                        .zip(a)
                        .filter(|(_, a)| a.facet[0] == NO_GLOBAL_NODE)
                        .map(|(&i, _)| self.ids[i])
                        .collect(),
                })
            })
            .collect()
    }
}
