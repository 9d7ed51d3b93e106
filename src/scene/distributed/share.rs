//! A rank's contact share of a scene's model: its own slaves of each pair (meshed or against
//! an analytical surface) and the master facets it owns, by global node ids.

use crate::distributed::{RankBalance, RankPair, RankRigidPair, NO_GLOBAL_NODE};
use crate::error::Result;
use crate::model::{Enforce, Facet, Model, Penalty, Schedule};

/// The facets of `facets` this rank owns (those whose first node it owns), by global ids.
fn owned_facets(facets: &[Facet], part: &[u32], me: u32) -> Vec<[u64; 4]> {
    let mut out = Vec::new();
    for f in facets {
        let ids: [u64; 4] = match f {
            Facet::Triangle(n) => [n[0] as u64, n[1] as u64, n[2] as u64, NO_GLOBAL_NODE],
            Facet::Quad(n) => n.map(|k| k as u64),
            Facet::Segment(n) => [n[0] as u64, n[1] as u64, NO_GLOBAL_NODE, NO_GLOBAL_NODE],
        };
        if part[ids[0] as usize] == me {
            out.push(ids);
        }
    }
    out
}

/// This rank's contact share of `model`'s pairs.
pub(super) fn rank_pairs(model: &Model, part: &[u32], me: u32) -> Result<Vec<RankPair>> {
    let mut out = Vec::new();
    for pair in model.pairs() {
        let (penalty, kinematic) = match &pair.enforce {
            Enforce::Penalty(p) => (p.clone(), None),
            Enforce::Kinematic(kin) => (Penalty::default(), Some(kin.clone())),
        };
        let master = model.surface(pair.master)?;
        let set = model.node_set(pair.slave)?;
        let areas = model.node_set_areas(pair.slave)?;
        let mine: Vec<usize> = (0..set.len())
            .filter(|&j| part[set[j] as usize] == me)
            .collect();
        let master_nodes = master.nodes();
        let self_contact = set.iter().any(|s| master_nodes.binary_search(s).is_ok());
        let schedule = pair
            .schedule
            .unwrap_or_else(|| Schedule::default_for(self_contact));
        out.push(RankPair {
            slaves: mine.iter().map(|&j| set[j] as u64).collect(),
            facets: owned_facets(&master.facets, part, me),
            search_radius: pair
                .search_radius
                .unwrap_or_else(|| master.mean_facet_size()),
            penalty,
            friction: pair.friction.clone(),
            search_interval: schedule.interval,
            slave_areas: areas.map(|a| mine.iter().map(|&j| a[j]).collect()),
            balanced: match pair.balanced {
                Some((s, weight)) => Some(RankBalance {
                    slave_facets: owned_facets(&model.surface(s)?.facets, part, me),
                    weight,
                }),
                None => None,
            },
            sliding: pair.sliding,
            anchor_reach: pair.search_radius,
            kinematic,
            slave_keys: Some(mine.iter().map(|&j| j as u64).collect()),
        });
    }
    Ok(out)
}

/// This rank's share of `model`'s pairs against analytical surfaces: its own slaves (local
/// indices through `local_of`), each with its place in the pair's node set.
pub(super) fn rank_rigid_pairs(
    model: &Model,
    part: &[u32],
    me: u32,
    local_of: &[u32],
) -> Result<Vec<RankRigidPair>> {
    let mut out = Vec::new();
    for rp in model.rigid_pairs() {
        let set = model.node_set(rp.slave)?;
        let areas = model.node_set_areas(rp.slave)?;
        let mine: Vec<usize> = (0..set.len())
            .filter(|&j| part[set[j] as usize] == me)
            .collect();
        out.push(RankRigidPair {
            body: rp.body.0,
            spec: model.body(rp.body)?.clone(),
            law: rp.softened.clone(),
            slaves: mine.iter().map(|&j| local_of[set[j] as usize]).collect(),
            keys: mine.iter().map(|&j| j as u64).collect(),
            areas: mine.iter().map(|&j| areas.map_or(1.0, |a| a[j])).collect(),
        });
    }
    Ok(out)
}
