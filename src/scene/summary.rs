//! What a run reports: the summary of every part, body and contact, the force curve, the contact
//! state at the end, and each MPI rank's share.

use super::*;

/// A part's motion at the end of a run (mass-weighted means over its free nodes).
#[derive(Clone, Debug, Serialize)]
pub struct PartSummary {
    /// Part name.
    pub name: String,
    /// Mean displacement since the start.
    pub displacement: [f64; 3],
    /// Mean velocity (the last half-step's).
    pub velocity: [f64; 3],
    /// Smallest Cauchy stress component over the part's elements: xx, yy, zz, xy, yz, zx.
    pub stress_min: [f64; 6],
    /// Largest.
    pub stress_max: [f64; 6],
}

/// A rigid body's state at the end of a run.
#[derive(Clone, Debug, Serialize)]
pub struct BodySummary {
    /// Body name.
    pub name: String,
    /// Reference point.
    pub position: [f64; 3],
    /// Velocity.
    pub velocity: [f64; 3],
    /// Displacement of the reference point when the total contact force peaked.
    pub displacement_at_peak_force: [f64; 3],
}

/// One sample of a run's force–displacement curve.
#[derive(Clone, Debug, Serialize)]
pub struct CurveSample {
    /// Time.
    pub time: f64,
    /// Total contact force on the slave nodes (per radian in axisymmetric scenes).
    pub force: [f64; 3],
    /// Displacement of each rigid body's reference point, in `bodies` order.
    pub body_displacement: Vec<[f64; 3]>,
}

/// A slave node in contact at the end of a run.
#[derive(Clone, Debug, Serialize)]
pub struct ContactNode {
    /// `[[contact]]` index (balanced pairs' reverse passes report under the same index).
    pub contact: usize,
    /// Model node.
    pub node: u32,
    /// Position.
    pub position: [f64; 3],
    /// Contact pressure (force over tributary area).
    pub pressure: f64,
    /// Normal contact force magnitude.
    pub force: f64,
}

/// What a scene run measured (also written as summary.json).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The scene's title.
    pub title: String,
    /// What it is checked against.
    pub reference: Option<String>,
    /// Where it ran.
    pub device: String,
    /// What the run built: elements, bodies, contact passes.
    pub built: Vec<String>,
    /// Increments taken.
    pub increments: usize,
    /// Time reached.
    pub end_time: f64,
    /// The first increment's wall-clock seconds (pipelines, uploads, first search).
    pub first_increment_seconds: f64,
    /// Wall-clock seconds per increment after the first.
    pub seconds_per_increment: f64,
    /// The elements' stable increment times the safety factor.
    pub element_increment: f64,
    /// The smallest stable increment penalty contact reported (∞ without penalty pairs).
    pub contact_increment: f64,
    /// What set the increment: "fixed" (`run.dt`), "elements" (their stable increment times
    /// the safety factor) or "elements and contact" ([`crate::combined_increment`]).
    pub governing_limit: String,
    /// How far below the elements' increment penalty contact took it at most (a fraction, 0
    /// when it never did).
    pub contact_lowered_increment: f64,
    /// When penalty contact first lowered the increment by more than 0.1 % (NaN if never).
    pub contact_limit_from: f64,
    /// In words: what governed, by how much contact lowered the increment, and — when it did
    /// so before any contact force acted — why.
    pub increment_note: String,
    /// Small and infinitesimal sliding: slave nodes anchored to a master facet at the start,
    /// over every anchored pass.
    pub anchored_slaves: usize,
    /// Small and infinitesimal sliding: slave nodes (model node ids) that project onto no
    /// master facet at the start and so are not constrained.
    pub unanchored_slaves: Vec<u32>,
    /// What a user should know before trusting the results (also printed by `abut run`).
    pub warnings: Vec<String>,
    /// A scene read from an Abaqus deck: the keywords read and not acted on, and what abut
    /// made of the deck beyond its tables ([`crate::scene::Scene::deck_notes`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub deck_notes: Vec<String>,
    /// A deck's `*STATIC` step run as quasi-static: how, and how small the kinetic energy stayed
    /// against the internal energy.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quasi_static: Option<QuasiStaticSummary>,
    /// First time a contact force acted (start of its increment; NaN if none).
    pub contact_start: f64,
    /// Last time a contact force acted (end of its increment).
    pub contact_end: f64,
    /// Rising edge of the contact force at half its plateau (the force of an increment
    /// belongs to its midpoint; linear interpolation), for plateau-shaped histories.
    pub impact_time: f64,
    /// Falling edge at half the plateau.
    pub release_time: f64,
    /// Largest total contact force on the slave nodes.
    pub peak_force: f64,
    /// Impulse between the half-plateau edges divided by their distance.
    pub mean_force: f64,
    /// The plateau: the mean contact force over the middle half of the contact (between the
    /// first and the last increment with force); NaN without contact.
    pub plateau_force: f64,
    /// Impulse of the contact force on the slave nodes.
    pub impulse: f64,
    /// Total contact force on the slave nodes in the last increment.
    pub final_contact_force: [f64; 3],
    /// Largest overclosure met (penalty penetration; kinematic: before correction).
    pub max_penetration: f64,
    /// Energy balance error: the largest drift of the energy balance over the run relative to
    /// the largest of the kinetic, internal, external, contact and dissipated energies met
    /// in the run, or to the model's energy floor where they stay below it
    /// ([`crate::explicit::Solver::energy_floor`]: 10⁻¹² of its capacity; a model at rest
    /// reports 0, not its round-off over its round-off).
    pub energy_balance_error: f64,
    /// Final kinetic energy.
    pub kinetic: f64,
    /// Final strain energy.
    pub internal: f64,
    /// Work of external forces and prescribed motions.
    pub external_work: f64,
    /// Work of contact forces (negative: dissipated).
    pub contact_work: f64,
    /// Energy dissipated by friction (penalty pairs).
    pub frictional_dissipation: f64,
    /// Parts at the end.
    pub parts: Vec<PartSummary>,
    /// Rigid bodies at the end.
    pub bodies: Vec<BodySummary>,
    /// Slave nodes in contact at the end, with their pressures.
    pub contact_nodes: Vec<ContactNode>,
    /// The total contact force against the bodies' displacements every `curve_every`
    /// increments: a force–indentation (or crush) curve. At most 4,096 samples: a run with more
    /// output rows keeps every other one each time the curve fills (`history.csv` has every
    /// row).
    pub curve: Vec<CurveSample>,
    /// Increments between the curve's samples: `run.output_every`, times 2, 4, … once the curve
    /// filled.
    pub curve_every: usize,
    /// Increments per entry of the contact force history the force statistics (contact times,
    /// plateau, mean force, impulse) come from: 1, or 2, 4, … past 131,072 increments, where
    /// neighbouring increments are merged to keep the history's memory bounded.
    pub force_history_every: usize,
    /// GPU dispatches per increment by pass, averaged over the increments after the first
    /// (empty on the CPU path). Counted on the device: work others submit to it during the
    /// run counts too.
    pub dispatches_per_increment: BTreeMap<String, f64>,
    /// Bytes uploaded per increment after the first.
    pub uploaded_bytes_per_increment: f64,
    /// Bytes read back per increment after the first.
    pub read_back_bytes_per_increment: f64,
    /// Global searches of the penalty pairs over the run (the schedule's, decided on the device;
    /// each pass of a balanced pair counts). A distributed run: its distributed global searches.
    pub global_searches: u64,
    /// A distributed run (`abut run` under `mpirun`): what each rank held, sent and took, in
    /// rank order; empty for a single process.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ranks: Vec<RankSummary>,
}

/// A quasi-static run's settings and its kinetic energy against its internal energy.
#[derive(Clone, Debug, Serialize)]
pub struct QuasiStaticSummary {
    /// How it ran.
    pub settings: super::spec::QuasiStatic,
    /// Kinetic over internal energy at the end of the ramp.
    pub kinetic_to_internal_at_ramp_end: f64,
    /// Kinetic over internal energy at the end of the run.
    pub kinetic_to_internal_at_end: f64,
    /// The largest kinetic over internal energy from half the ramp on (before, both are near
    /// zero and their ratio says nothing).
    pub kinetic_to_internal_max: f64,
}

/// One rank of a distributed run.
#[derive(Clone, Debug, Serialize)]
pub struct RankSummary {
    /// Nodes the rank owns.
    pub own_nodes: usize,
    /// Halo nodes: other ranks' nodes of its elements, their state received every increment.
    pub halo_nodes: usize,
    /// Elements it computes (every element with a node of its own: cut elements on each of
    /// their ranks).
    pub elements: usize,
    /// Contact ghosts at the end: other ranks' master nodes near its slaves.
    pub contact_ghosts: usize,
    /// Its slave nodes (all pairs, both passes of a balanced pair).
    pub slaves: usize,
    /// Bytes it sent per increment, mean over the run: the halo exchange.
    pub halo_bytes_per_increment: f64,
    /// Bytes it sent per increment, mean over the run: contact (ghost state out, ghost forces
    /// back, the regions and ghost lists of distributed global searches).
    pub contact_bytes_per_increment: f64,
    /// Wall-clock seconds per increment after the first on this rank.
    pub seconds_per_increment: f64,
    /// Local contact models built (`abut::distributed::DistributedContact::rebuilds`, feature
    /// `mpi`).
    pub contact_rebuilds: u64,
    /// MPI collectives per increment, mean over the run (the same on every rank): 7 for an
    /// increment between distributed global searches with contact (4 of the contact's, the
    /// solver's agreement, the halo and the sums), 3 with none; a distributed global search
    /// adds 3 and an output row 1.
    pub collectives_per_increment: f64,
    /// The rank's peak resident memory at the end of the run, bytes (its process's high-water
    /// mark; `None` where the system does not say: Linux only).
    pub peak_resident_bytes: Option<u64>,
}
