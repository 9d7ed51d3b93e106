//! What an increment reports: the penalty and kinematic reports, the fast nodes, each pair's
//! output variables, the anchoring of small-sliding pairs and the overclosure adjustment, and
//! the host's combined stable increment.

use super::*;

/// CSTATUS: the state of a slave node's contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactStatus {
    /// Not in contact.
    Open,
    /// In contact, sticking.
    Stick,
    /// In contact, slipping (frictionless contact always slips).
    Slip,
}

/// The increment of a run whose nodes carry elements and penalty springs together: the elements'
/// stable increment `element_dt` (already times `safety`) and the contact's `contact_dt`
/// (`StepReport::stable_dt`) give 1/Δt² = 1/Δt_elements² + 1/(safety·Δt_contact)² — their
/// frequencies add in square, with the same safety on both — and no more than
/// `contact_safety·Δt_contact`, so that every contact spring stays at ω·Δt ≤ 2·contact_safety,
/// where its switching on and off does not pump energy into the node (tests/scene.rs). A host
/// program that integrates its own elements calls this with its elements' increment and the
/// report's `stable_dt` (a scene run does).
pub fn combined_increment(
    element_dt: f64,
    contact_dt: f64,
    safety: f64,
    contact_safety: f64,
) -> f64 {
    let dt_c = safety * contact_dt;
    let both = 1.0 / (1.0 / (element_dt * element_dt) + 1.0 / (dt_c * dt_c)).sqrt();
    both.min(contact_safety * contact_dt)
}

/// What one increment of penalty contact gives the host.
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// Contact force on every model node (model force units), summed over the pairs.
    pub forces: Vec<[f64; 3]>,
    /// The largest increment the penalty springs allow under central differences, with the
    /// damping: the smaller of each spring's own limit 2/ω, ω² = k·(1/m_s + 1/m_master) — the
    /// compliance of each side at the contact point along the normal: a node's 1/mass, the
    /// master nodes' Σ w_j²/m_j by the load-transfer weights, or a rigid part's
    /// ([`Model::add_rigid_part`]) 1/M + (r×n)·I⁻¹·(r×n) about its centre of mass — for the
    /// springs within the search radius, and a node-wise bound on all the springs in contact
    /// together, which covers nodes shared by several springs (a master node under several
    /// slaves, both passes of a balanced pair) and counts a rigid part's springs as one body's;
    /// exact for one spring wherever it sits on the facet (to 1e-4; tests/hard_cases.rs), safe
    /// for many. It bounds the contact springs alone: a node's elements add their own frequency
    /// ([`crate::combined_increment`]); kinematic pairs (meshed or analytical masters) limit
    /// no increment. ∞ when there is none. A linear limit: a spring that switches on and off near
    /// it pumps energy into a node pressed into contact, so take at most about half of it for
    /// contact that persists, unless the contact is damped (10 % of critical lets 0.9 of it
    /// hold; tests/scene.rs).
    pub stable_dt: f64,
    /// Half the smallest remaining gap over its closing speed: an increment beyond this could
    /// carry an approaching node through its master facet in one step; ∞ when none approaches.
    pub approach_dt: f64,
    /// The largest overclosure (penetration, model length units, ≥ 0) of a slave node carrying
    /// penalty force this increment, over every pair; 0 when none. Known without asking for
    /// the output variables.
    pub max_overclosure: f64,
    /// Slave nodes in contact.
    pub active: usize,
    /// Of which slipping.
    pub slipping: usize,
    /// Searches that ran globally this increment (the schedule's choice, made on the device).
    pub global_searches: usize,
    /// Slave nodes whose walk of the search tree reached its visit cap this increment and was
    /// finished in bounded chunks (the search stayed exact; many mean a badly fitting tree).
    pub fallbacks: usize,
    /// Small and infinitesimal sliding (penalty pairs): slave nodes that got no anchor at the
    /// first increment — they project onto no master facet — and so are not constrained
    /// ([`Contact::anchoring`] names them).
    pub unanchored: usize,
    /// `stable_dt` is finite although no slave node is in contact: it is the limit of springs of
    /// slave nodes within the search radius that have not touched yet (one may close within an
    /// increment, so their limit applies before contact).
    pub stable_dt_before_contact: bool,
    /// Slave nodes (per pair; a balanced pair's master nodes in its second pass) whose
    /// velocity relative to the master near them carries them farther than their pair's search
    /// radius within this increment: the search cannot follow them, and a slave may pass
    /// through its master unseen (tunnelling). The master near a slave is the master's
    /// velocity at its contact point, or — for a slave with no facet within the radius — the
    /// velocity of the pair's reference master node ([`crate::search::SearchStage::reference_node`]); so a
    /// contact model that moves as a whole, or a slave carried along by its master, is never
    /// fast, while a slave crossing a still or opposing master is. Counted by the penalty
    /// kernels on every path (host arrays and device-resident: [`crate::IncrementStats::fast_nodes`]).
    pub fast_nodes: usize,
    /// The fastest of them.
    pub fastest: Option<FastNode>,
}

/// A slave node that moves farther than its pair's search radius relative to the master near
/// it within one increment ([`StepReport::fast_nodes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FastNode {
    /// The model node.
    pub node: usize,
    /// Its pair (a meshed pair's id).
    pub pair: PairId,
    /// Its speed relative to the master near it times the increment, model length units.
    pub distance: f64,
    /// The pair's search radius.
    pub radius: f64,
}

/// Small or infinitesimal sliding: what one pass of a pair anchored at the first increment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Anchoring {
    /// The pair.
    pub pair: PairId,
    /// The slave nodes of this pass (the master's nodes for a balanced pair's second pass).
    pub slaves: usize,
    /// Of which anchored to a master facet.
    pub anchored: usize,
    /// The others (model node ids): they project onto no master facet — beyond a free edge,
    /// or beyond the pair's stated search radius — and are not constrained.
    pub unanchored: Vec<u32>,
}

/// Contact output variables of one pair after an increment (when requested).
#[derive(Clone, Debug, Default)]
pub struct PairOutput {
    /// The slave nodes, in node-set order.
    pub slaves: Vec<u32>,
    /// CSTATUS per slave.
    pub cstatus: Vec<Option<ContactStatus>>,
    /// COPEN: gap along the contact normal (model length units; negative = penetration).
    pub copen: Vec<f64>,
    /// CPRESS: normal force over the tributary area.
    pub cpress: Vec<f64>,
    /// CSHEAR1: friction force along t1 over the tributary area.
    pub cshear1: Vec<f64>,
    /// CSHEAR2: friction force along t2 over the tributary area.
    pub cshear2: Vec<f64>,
    /// The contact normal used at each slave (smoothed master normal).
    pub normal: Vec<[f64; 3]>,
    /// Total contact force on each slave node.
    pub force: Vec<[f64; 3]>,
    /// CFN: resultant normal contact force on the slaves.
    pub cfn: [f64; 3],
    /// CFS: resultant friction force on the slaves.
    pub cfs: [f64; 3],
    /// Elastic energy stored in the contact springs.
    pub contact_energy: f64,
    /// Frictional dissipation since the start.
    pub frictional_dissipation: f64,
    /// The search result of this increment (contact points, facets, weights).
    pub search: Option<SearchResult>,
}

/// What one kinematic increment did.
#[derive(Clone, Debug, Default)]
pub struct KinematicReport {
    /// Slave nodes corrected (over all kinematic and rigid pairs, first pass).
    pub active: usize,
    /// Largest overclosure before the correction.
    pub max_overclosure: f64,
    /// Largest overclosure left after it, measured again on the corrected positions (hard
    /// contact: round-off; softened: the law's equilibrium overclosure).
    pub max_overclosure_after: f64,
    /// Change of kinetic energy made by the corrections (negative: the energy kinematic contact
    /// dissipates at impact).
    pub kinetic_energy_change: f64,
    /// Sum over slaves of the resisting force magnitudes (first pass).
    pub total_force: f64,
    /// Sum over slaves of the kinematic friction force magnitudes (pairs with friction).
    pub friction_force: f64,
    /// Slave nodes of meshed kinematic pairs that the velocities (the predictor's) carry
    /// farther than their pair's search radius relative to the master near them within this
    /// increment, by [`StepReport::fast_nodes`]'s rule.
    pub fast_nodes: usize,
    /// The fastest of them.
    pub fastest: Option<FastNode>,
}

/// The strain-free adjustment of initially overclosed slave nodes.
#[derive(Clone, Debug, Default)]
pub struct OverclosureReport {
    /// (node, distance moved) of every node moved.
    pub moved: Vec<(u32, f64)>,
    /// Largest distance moved.
    pub max_distance: f64,
    /// Kinetic energy the first kinematic increment would have injected had the overclosure
    /// been resolved then, Σ ½·m·(h/dt)²: the cost the adjustment avoids.
    pub energy_avoided: f64,
}

/// The slaves of `search` (pair `pair`) whose velocity relative to the master near them
/// carries them farther than the pair's search radius within `dt`: their count, and the slave
/// with the largest relative motion over the radius whether or not it is fast (`None` without
/// slaves). The master near a slave is its velocity at the slave's contact point in `hits` (the
/// kernels' raw hits, one per slave: the facet's nodes weighted by the load-transfer weights),
/// or, for a slave with no facet within the radius, the pair's reference master node's
/// ([`crate::search::SearchStage::reference_node`]). The penalty kernels apply the same rule in f32
/// (`STATUS_FAST`); this is its f64 twin, for kinematic pairs and to name the fastest slave.
/// `order` visits the slaves (indices into `hits`) in the caller's order, so that of equally
/// fast slaves the first in the node set is named.
pub(super) fn fast_slaves(
    pair: PairId,
    search: &SearchStage,
    hits: &[crate::abi::search::GpuHit],
    order: impl Iterator<Item = usize>,
    velocities: &[[f64; 3]],
    dt: f64,
) -> (usize, Option<FastNode>) {
    let radius = search.radius();
    let facets = search.kernel_facets();
    let reference = search.reference_node();
    let (mut count, mut fastest) = (0, None::<FastNode>);
    for k in order {
        let (Some(&slave), Some(h)) = (search.slaves().get(k), hits.get(k)) else {
            continue;
        };
        let mut vm = [0.0; 3];
        if h.facet != crate::abi::search::NO_FACET {
            let fac = facets[h.facet as usize];
            for j in 0..crate::model::facet_node_count(fac) {
                let v = velocities[fac[j] as usize];
                for a in 0..3 {
                    vm[a] += h.weights[j] as f64 * v[a];
                }
            }
        } else if reference != crate::model::NO_NODE {
            vm = velocities[reference as usize];
        } else {
            continue;
        }
        let v = velocities[slave as usize];
        let rel = [v[0] - vm[0], v[1] - vm[1], v[2] - vm[2]];
        let distance = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt() * dt;
        if distance > radius {
            count += 1;
        }
        if fastest.is_none_or(|f| distance / radius > f.distance / f.radius) {
            fastest = Some(FastNode {
                node: slave as usize,
                pair,
                distance,
                radius,
            });
        }
    }
    (count, fastest)
}

pub(super) fn fill_output(
    o: &mut PairOutput,
    outs: &[ContactOut],
    areas: &[f32],
    search: SearchResult,
) {
    let n = outs.len();
    o.cstatus.clear();
    o.copen.clear();
    o.cpress.clear();
    o.cshear1.clear();
    o.cshear2.clear();
    o.normal.clear();
    o.force.clear();
    o.cfn = [0.0; 3];
    o.cfs = [0.0; 3];
    o.contact_energy = 0.0;
    o.frictional_dissipation = 0.0;
    for (k, c) in outs.iter().enumerate().take(n) {
        let found = search.contact(k).is_some();
        o.cstatus
            .push(found.then_some(match c.status & CSTATUS_MASK {
                CSTATUS_STICK => ContactStatus::Stick,
                CSTATUS_SLIP => ContactStatus::Slip,
                s => {
                    debug_assert_eq!(s, CSTATUS_OPEN);
                    ContactStatus::Open
                }
            }));
        let area = areas[k] as f64;
        let nrm = [c.normal_gap[0], c.normal_gap[1], c.normal_gap[2]];
        let (t1, t2) = crate::geometry::tangents_f32(nrm);
        let ft = [
            c.tangential[0] as f64,
            c.tangential[1] as f64,
            c.tangential[2] as f64,
        ];
        o.copen.push(c.normal_gap[3] as f64);
        o.cpress.push(c.force[3] as f64 / area);
        o.cshear1
            .push((0..3).map(|a| ft[a] * t1[a] as f64).sum::<f64>() / area);
        o.cshear2
            .push((0..3).map(|a| ft[a] * t2[a] as f64).sum::<f64>() / area);
        o.normal.push(nrm.map(|x| x as f64));
        o.force
            .push([c.force[0] as f64, c.force[1] as f64, c.force[2] as f64]);
        for a in 0..3 {
            o.cfn[a] += c.force[3] as f64 * nrm[a] as f64;
            o.cfs[a] += ft[a];
        }
        o.contact_energy += c.tangential[3] as f64;
        o.frictional_dissipation += c.dissipation as f64;
    }
    o.search = Some(search);
}
