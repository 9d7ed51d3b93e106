//! Kinematic contact on the host: the predictor/corrector of the seed ("Kinematic contact
//! algorithm"), hard or softened, against meshed masters (pure or balanced) and against the
//! analytical surfaces of rigid bodies. Runs in f64 on the search's facet choices.
//!
//! For each penetrating slave node s (overclosure h along the master normal n, at load-transfer
//! weights w_j), the resisting force that closes it over the increment is
//! `f_s = m_s·(h − h_s)/dt²` with h_s = 0 (hard) or the overclosure at which the softened law
//! balances the force the contact transmits (the master's motion takes a share of the push, so
//! that force is the two-body one, `m*·(h − h_s)/dt²`, not `f_s`). Forces `−w_j·f_s·n` and
//! masses `w_j·m_s` go to the master nodes, whose acceleration correction is `Δa_j = F_j/(m_j + Σ w_j m_s)`; the slave moves by
//! `(h − h_s)·n + Σ_j w_j·Δa_j·dt²`, so it ends on the corrected master (to first order in the
//! facet's rotation; the correction is repeated on the corrected geometry, [`PASSES`] times in
//! all) and the momentum of slave and masters is unchanged. Positions and velocities are
//! corrected together, `Δv = Δx/dt`. The method does not restrict the stable increment.
//!
//! Known behaviour (seed, Figure 38.2.3–1): only slave nodes are kept out of the master; with a
//! coarse slave mesh, master nodes can still penetrate between slave nodes. Balanced pairs run
//! the correction both ways and weight the two.

use crate::geometry::{closest_on_facet, V3};
use crate::model::{MasterSurface, PressureOverclosure};
use crate::search::SearchResult;

mod correct;
use correct::InProcess;
#[cfg(feature = "mpi")]
pub(crate) use correct::NodeSums;
pub(crate) use correct::{correct_touches, Touch};
mod rigid;
pub use rigid::{rigid_pass, rigid_pass_shared, to_body, to_model, Pushed, ShareRows};

/// Correction passes of a meshed pair per increment (the first from the search, the others
/// re-projecting onto the same facets at the corrected positions).
pub const PASSES: usize = 3;

/// The host's state of a rigid body: predicted on entry to `kinematic_step`, corrected on exit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Position of the reference point.
    pub position: [f64; 3],
    /// Rotation from the body frame to the model frame (rows).
    pub rotation: [[f64; 3]; 3],
    /// Velocity of the reference point.
    pub velocity: [f64; 3],
    /// Angular velocity (model frame).
    pub angular_velocity: [f64; 3],
}

impl BodyState {
    /// A body at `position`, not rotated, at rest.
    pub fn at(position: [f64; 3]) -> Self {
        Self {
            position,
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        }
    }
}

/// What one slave node's correction was.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SlaveCorrection {
    /// Overclosure before the correction (model length; positive = penetrating).
    pub overclosure: f64,
    /// The overclosure the correction aimed at (0 for hard contact).
    pub target: f64,
    /// Resisting force `m·(h − h_s)/dt²` along the normal.
    pub force: f64,
    /// Normal used.
    pub normal: [f64; 3],
    /// Elastic energy of a softened law at the target overclosure (0 for hard contact).
    pub energy: f64,
    /// Force the correction actually applied to the slave, `m·Δx/dt²` (model frame): the
    /// resisting force less what the master's motion took up.
    pub applied: [f64; 3],
}

/// Overclosure that balances a softened law: the h' in [start, h] with
/// `m·(h − h')/dt² = p(h')·A` (bisection; the left side falls and the right side rises with h').
pub fn softened_target(law: &PressureOverclosure, h: f64, mass: f64, area: f64, dt: f64) -> f64 {
    let start = law.start();
    if h <= start {
        return h;
    }
    let (mut lo, mut hi) = (start, h);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        let g = mass * (h - mid) / (dt * dt) - law.pressure(mid).0 * area;
        if g > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Whether a slave at overclosure `h` is pushed at all: past the law's start (softened) or
/// penetrating (hard).
pub(crate) fn pushed(law: Option<&PressureOverclosure>, h: f64) -> bool {
    h > law.map_or(0.0, |l| l.start())
}

/// The overclosure a correction should leave for a slave at overclosure `h` (0 for hard
/// contact, the softened law's balance otherwise), or `None` when it needs no push. `mass` is
/// the slave's effective (two-body) mass: the force the contact transmits for a push of
/// `h − h'` is `mass·(h − h')/dt²`.
pub(crate) fn push_target(
    law: Option<&PressureOverclosure>,
    h: f64,
    mass: f64,
    area: f64,
    dt: f64,
) -> Option<f64> {
    match law {
        None => (h > 0.0).then_some(0.0),
        Some(l) => {
            let target = softened_target(l, h, mass, area, dt);
            (h > target).then_some(target)
        }
    }
}

/// Elastic energy per area of a law up to overclosure h (trapezoids on a fine partition for
/// the exponential law, exact for tabular).
pub fn law_energy(law: &PressureOverclosure, h: f64) -> f64 {
    let start = law.start();
    if h <= start {
        return 0.0;
    }
    let n = 200;
    let dh = (h - start) / n as f64;
    (0..n)
        .map(|k| {
            let a = start + k as f64 * dh;
            0.5 * (law.pressure(a).0 + law.pressure(a + dh).0) * dh
        })
        .sum()
}

/// The geometry of one slave's contact for a pass: normal, load-transfer weights,
/// overclosure, and the facet's nodes.
pub struct SlaveGeometry<'a> {
    /// Unit normal along which the slave is pushed.
    pub normal: V3<f64>,
    /// Load-transfer weights of the facet's nodes.
    pub weights: [f64; 4],
    /// Overclosure (positive = penetrating).
    pub overclosure: f64,
    /// The facet's nodes.
    pub nodes: &'a [u32],
}

/// One pass of a meshed pair: slaves `slaves` against the facets `facet_of` (None: no
/// partner) of `master`, at positions `x`, the geometry recomputed in f64 on those facets.
/// Adds the corrections to `dx` (dense, per node) and returns the per-slave corrections.
#[allow(clippy::too_many_arguments)]
pub fn meshed_pass(
    master: &MasterSurface,
    masses: &[f64],
    x: &[[f64; 3]],
    slaves: &[u32],
    facet_of: &[Option<u32>],
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
    dx: &mut [[f64; 3]],
) -> Vec<SlaveCorrection> {
    let geometry: Vec<Option<SlaveGeometry>> = slaves
        .iter()
        .zip(facet_of)
        .map(|(&s, f)| {
            let nodes = master.facets[(*f)? as usize].nodes();
            let xs: Vec<V3<f64>> = nodes
                .iter()
                .map(|&n| V3::from_array(x[n as usize]))
                .collect();
            let p = V3::from_array(x[s as usize]);
            let pr = closest_on_facet(p, &xs);
            Some(SlaveGeometry {
                normal: pr.normal,
                weights: pr.weights,
                overclosure: -pr.gap(p),
                nodes,
            })
        })
        .collect();
    correct(masses, slaves, &geometry, areas, law, dt, dx)
}

/// Small sliding's pass: the geometry is each slave's anchor (fixed weights, the tangent
/// plane's normal and gap) from the search result.
#[allow(clippy::too_many_arguments)]
pub fn anchored_pass(
    master: &MasterSurface,
    masses: &[f64],
    search: &SearchResult,
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
    dx: &mut [[f64; 3]],
) -> Vec<SlaveCorrection> {
    let geometry: Vec<Option<SlaveGeometry>> = search
        .contacts()
        .map(|c| {
            let c = c?;
            Some(SlaveGeometry {
                normal: V3::from_array(c.normal),
                weights: c.weights,
                overclosure: -c.gap,
                nodes: master.facets[c.facet as usize].nodes(),
            })
        })
        .collect();
    correct(masses, &search.slaves, &geometry, areas, law, dt, dx)
}

/// The correction of the module docs for the slaves' geometry, in one process.
fn correct(
    masses: &[f64],
    slaves: &[u32],
    geometry: &[Option<SlaveGeometry>],
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
    dx: &mut [[f64; 3]],
) -> Vec<SlaveCorrection> {
    let touch: Vec<Touch> = slaves
        .iter()
        .zip(geometry)
        .enumerate()
        .filter_map(|(k, (&s, g))| {
            let g = g.as_ref()?;
            let mut nodes = [u32::MAX; 4];
            nodes[..g.nodes.len()].copy_from_slice(g.nodes);
            Some(Touch {
                key: k as u64,
                slave: k,
                node: s as usize,
                nodes,
                count: g.nodes.len(),
                normal: g.normal,
                weights: g.weights,
                overclosure: g.overclosure,
            })
        })
        .collect();
    let sums = InProcess(masses.len());
    correct_touches(&touch, slaves.len(), masses, areas, law, dt, &sums, dx)
}

/// What the kinematic friction of one pair did in one increment ([`friction_pass`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionCorrection {
    /// Each slave's friction force (model frame; zero where it is not in contact or does not
    /// slide relative to the master).
    pub force: Vec<[f64; 3]>,
    /// Each slave's state: `true` where the force stopped its slip within the increment
    /// (stick), `false` where the Coulomb limit capped it (slip) or there was none.
    pub stick: Vec<bool>,
    /// The kinetic energy the friction corrections removed, Σ ½·m·(|v|² − |v + Δv|²) over the
    /// nodes they changed (model energy units, ≥ 0): the frictional dissipation.
    pub dissipation: f64,
}

/// Coulomb friction of a kinematic pair, after its normal correction (Abaqus' kinematic
/// friction): each slave in contact gets the tangential force that would stop its relative slip
/// within the increment, `m*·|v_t|/Δt` with the two-body mass `1/m* = 1/m_s + Σ w_j²/m_j`, but no
/// more than `μ(|v_t|)·f_n` — `f_n` the normal force the corrections transmitted to the slave,
/// over their passes — opposite to the slip on the slave and by the weights on its master facet's nodes. `v` (corrected for the normal) and `x`
/// move by the tangential velocity change (and its `Δt`). Stick is exact (no elastic pre-slip);
/// the coefficient decays with slip rate as the penalty's does. Returns each slave's friction
/// force and state and the energy dissipated.
#[allow(clippy::too_many_arguments)]
pub fn friction_pass(
    master: &MasterSurface,
    masses: &[f64],
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    slaves: &[u32],
    facet_of: &[Option<u32>],
    normal_force: &[f64],
    mu: (f64, f64, f64),
    dt: f64,
) -> FrictionCorrection {
    let mut out = FrictionCorrection {
        force: vec![[0.0; 3]; slaves.len()],
        stick: vec![false; slaves.len()],
        dissipation: 0.0,
    };
    // forces first (every slave on the same velocities), then the changes
    let mut dv = vec![V3::<f64>::zero(); x.len()];
    for (k, (&s, f)) in slaves.iter().zip(facet_of).enumerate() {
        let (Some(f), Some(&f_n)) = (f, normal_force.get(k)) else {
            continue;
        };
        if f_n <= 0.0 {
            continue;
        }
        let nodes = master.facets[*f as usize].nodes();
        let (ft, weights, stick) = slave_friction(mu, (x, v, masses), s as usize, nodes, f_n, dt);
        out.stick[k] = stick;
        let Some(ft) = ft else { continue };
        out.force[k] = ft.to_array();
        dv[s as usize] = dv[s as usize] + ft * (dt / masses[s as usize]);
        for (j, &m) in nodes.iter().enumerate() {
            dv[m as usize] = dv[m as usize] - ft * (weights[j] * dt / masses[m as usize]);
        }
    }
    for (i, d) in dv.iter().enumerate() {
        out.dissipation += change_velocity((x, v), masses[i], i, d.to_array(), dt);
    }
    out
}

/// One slave's Coulomb friction ([`friction_pass`]): slave `s` on the facet of `nodes` at
/// positions `x`, velocities `v`, masses `masses`, pressed by the normal force `f_n`. Returns
/// its tangential force (none where it does not slide relative to the facet), the facet's
/// weights at it, and whether the force stops its slip (stick).
pub(crate) fn slave_friction(
    (mu_s, mu_k, decay): (f64, f64, f64),
    (x, v, masses): (&[[f64; 3]], &[[f64; 3]], &[f64]),
    s: usize,
    nodes: &[u32],
    f_n: f64,
    dt: f64,
) -> (Option<V3<f64>>, [f64; 4], bool) {
    let xs: Vec<V3<f64>> = nodes
        .iter()
        .map(|&n| V3::from_array(x[n as usize]))
        .collect();
    let pr = closest_on_facet(V3::from_array(x[s]), &xs);
    let n = pr.normal;
    let mut v_rel = V3::from_array(v[s]);
    let mut inv_m = 1.0 / masses[s];
    for (j, &m) in nodes.iter().enumerate() {
        v_rel = v_rel - V3::from_array(v[m as usize]) * pr.weights[j];
        inv_m += pr.weights[j] * pr.weights[j] / masses[m as usize];
    }
    let v_t = v_rel - n * v_rel.dot(n);
    let speed = v_t.length2().sqrt();
    if speed == 0.0 {
        return (None, pr.weights, true);
    }
    let mu = mu_k + (mu_s - mu_k) * (-decay * speed).exp();
    let stick = speed / (inv_m * dt);
    let f = stick.min(mu * f_n);
    (Some(v_t * (-f / speed)), pr.weights, stick <= mu * f_n)
}

/// Node `i` (mass `m`) moved by the velocity change `d` over the increment `dt` (`v += d`,
/// `x += d·dt`; nothing where `d` is zero); returns the kinetic energy it removed.
pub(crate) fn change_velocity(
    (x, v): (&mut [[f64; 3]], &mut [[f64; 3]]),
    m: f64,
    i: usize,
    d: [f64; 3],
    dt: f64,
) -> f64 {
    if d == [0.0; 3] {
        return 0.0;
    }
    let before = V3::from_array(v[i]).length2();
    for a in 0..3 {
        v[i][a] += d[a];
        x[i][a] += d[a] * dt;
    }
    0.5 * m * (before - V3::from_array(v[i]).length2())
}

/// The facet of each slave from a search result. A slave beside a free edge of the master is
/// off its facets: no contact. `behind` (one flag per slave, kept between increments) marks a
/// slave that was beside a free edge below the facet's plane: while it stays below the surface
/// it gets no contact either (it came from behind the edge, and correcting it onto the surface
/// would launch it); it clears when the slave rises above.
pub fn facets_from(search: &SearchResult, behind: &mut [bool]) -> Vec<Option<u32>> {
    search
        .contacts()
        .zip(behind.iter_mut())
        .map(|(c, behind)| {
            let c = c?;
            if c.beside_free_edge {
                *behind = c.gap < 0.0;
                return None;
            }
            if *behind && c.gap < 0.0 {
                return None;
            }
            *behind = false;
            Some(c.facet)
        })
        .collect()
}
