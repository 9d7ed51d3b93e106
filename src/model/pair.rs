//! Contact pairs: a slave node set against a master surface, and how contact is enforced.

use super::{NodeSetId, SurfaceId};
use crate::error::{Error, Result};

/// A contact pair: the nodes of `slave` against the facets of `master`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    /// The slave node set.
    pub slave: NodeSetId,
    /// The master surface.
    pub master: SurfaceId,
    /// Search radius (model units): a slave node farther than this from every master facet has
    /// no contact partner. `None` takes one mean facet size of the master surface.
    pub search_radius: Option<f64>,
    /// How contact is enforced.
    pub enforce: Enforce,
    /// Tangential behaviour.
    pub friction: Friction,
    /// Balanced master–slave: the slave nodes' own surface and the weight of the
    /// slave-on-master pass (the master-on-slave pass gets 1 − weight). `None`: pure
    /// master–slave.
    pub balanced: Option<(SurfaceId, f64)>,
    /// Sliding formulation.
    pub sliding: Sliding,
    /// When the search runs globally; `None`: the defaults (every 100 increments, every 4 for
    /// self-contact, budget ½ of the radius, fast local tracking).
    pub schedule: Option<Schedule>,
    /// The fraction of each contact's penalty force a pure pair applies (1 unless set): one
    /// pass of a balanced pair stated as a pure pair of its own, as a rank of a distributed
    /// model does (a balanced pair's weights come from [`Pair::balanced`]).
    pub pass_weight: f64,
    /// The order a penalty pair keeps its slave nodes in inside abut (Morton unless set);
    /// invisible to the caller, who gets every per-slave result in node-set order.
    pub slave_order: SlaveOrder,
    /// The global search's structure (chosen from the master's facet sizes and the radius
    /// unless set).
    pub search_structure: SearchStructure,
}

/// The structure the global search finds each slave node's nearest facet in. Both give the
/// same contact (facet, point, gap, normal, weights, tracked node) bit for bit; they differ
/// in work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SearchStructure {
    /// The seed's bucket sort: the facets binned by counting sort into a hashed grid of cells
    /// sized to the largest facet (at the model's positions), a slave's cells visited in rings
    /// outward and pruned by the best distance so far. Its work follows the gap where facets
    /// are of one size; where sizes vary, small facets crowd the cells (a crowded walk falls
    /// back to every facet in bounded chunks).
    Buckets,
    /// A bounding-box tree over the facets, refitted at every global search and walked nearer
    /// child first, pruned by the best distance so far: work that follows the gap whatever the
    /// facet sizes and the radius.
    Tree,
    /// The faster of the two as measured: [`SearchStructure::Tree`] on every device and scene
    /// `abut bench --search` has measured (`crate::search::SearchStage::set_search_structure`
    /// gives the figures).
    #[default]
    Auto,
}

/// The order a penalty pair keeps its slave nodes (and their hits, penalty state and outputs)
/// in on the device and the CPU path. The caller never sees it: outputs, penalty states, saved
/// states, reports and forces come back in the node set's order, with the same bits either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SlaveOrder {
    /// Morton (Z-curve) order of the slave nodes' positions in the model when the contact is
    /// built: slaves next to each other in memory are next to each other in space, so the
    /// passes over them read the same master facets and nodes together.
    #[default]
    Morton,
    /// The node set's order, as given.
    Given,
}

/// The sliding formulation (seed: "Sliding formulation", "Small-sliding tracking approach").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Sliding {
    /// Any relative motion: searched every increment (global on a schedule, local between).
    #[default]
    Finite,
    /// One global search at the start anchors each slave node on its nearest facet; the
    /// tangent plane there turns with the facet; load transfer stays at the anchor. No search
    /// afterwards.
    Small,
    /// As small sliding, but the plane's orientation never changes either (Abaqus' small
    /// sliding with NLGEOM=NO).
    Infinitesimal,
}

/// Contact constraint enforcement ("Contact constraint enforcement methods" in the seed).
#[derive(Clone, Debug, PartialEq)]
pub enum Enforce {
    /// Penalty springs between slave nodes and master facets, computed on the GPU.
    Penalty(Penalty),
    /// The kinematic predictor/corrector, run on the host from the search's results.
    Kinematic(Kinematic),
}

/// Kinematic enforcement settings.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Kinematic {
    /// `None`: hard contact (no penetration after the correction). `Some(law)`: softened
    /// contact, the correction leaves each slave node at the overclosure where the law's
    /// force balances the resisting force.
    pub softened: Option<PressureOverclosure>,
}

impl Default for Enforce {
    fn default() -> Self {
        Enforce::Penalty(Penalty::default())
    }
}

/// Penalty enforcement settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Penalty {
    /// Normal stiffness rule.
    pub stiffness: Stiffness,
    /// Pressure–overclosure law.
    pub law: PressureOverclosure,
    /// Viscous contact damping as a fraction of critical damping of each contact spring
    /// (0 = none; [`DEFAULT_CONTACT_DAMPING`] by default); included in the stable-increment
    /// bound.
    pub damping: f64,
}

/// The default viscous damping of penalty contact, a fraction of each contact spring's critical
/// damping: 0.03, Abaqus/Explicit's default for penalty contact. It acts on the normal approach
/// velocity while a node is pressed in. Without it a contact spring is perfectly elastic: a body
/// resting or sliding on penalty springs rocks on them for ever once its settling or a change of
/// load has set it going, its nodes' normal forces swing to zero and back, and Coulomb friction,
/// proportional to them node by node, lets go where they dip — a block that should stop on an
/// incline creeps on, an elastic one hops (tests/hard_cases.rs, `penalty_friction`). 3 % takes
/// that energy out within tens of oscillations and costs 3 % of the contact's stable increment
/// (2/ω·(√(1 + ξ²) − ξ)).
pub const DEFAULT_CONTACT_DAMPING: f64 = 0.03;

impl Default for Penalty {
    fn default() -> Self {
        Self {
            stiffness: Stiffness::Auto { scale: 1.0 },
            law: PressureOverclosure::Linear,
            damping: DEFAULT_CONTACT_DAMPING,
        }
    }
}

/// How the linear penalty stiffness (force per length, per slave node) is chosen.
///
/// The automatic rule is the mass-and-increment form of LS-DYNA's `SOFT=1` contact,
/// `k = ½·SOFSCL·m*/Δt²`, with m* the effective two-body mass of the contact
/// (`1/m* = 1/m_s + Σ N_i²/m_i`, slave mass and the master nodes' masses weighted by the
/// load-transfer weights) and Δt the reference increment (the first increment's, unless set).
/// abut's `½·SOFSCL` is `scale` (1 by default): each contact spring then has
/// ω·Δt_ref = √scale. The slaves of a rigid part ([`crate::Model::add_rigid_part`]) share the
/// body's effective mass: each of its n slave springs takes m*/n of it (the body's compliance
/// at the slave times n), so the body on all n springs has ω·Δt_ref = √scale, as one slave of
/// a meshed body of the same mass spread over n nodes would — not √n times more (issue 30). At a node carried by elements at their stable increment (ω_e·Δt_ref ≈ 1.8
/// at safety 0.9) the spring is about 0.6 times the underlying element's stiffness — stiff enough
/// that a wave reaches a rigid wall within two increments and the plateau force is within 2 % of
/// ρ·c·v·A (tests/hard_cases.rs) — and it costs about 13 % of the increment where the springs
/// and the elements meet (`scene::combined_increment`: 1/Δt² = 1/Δt_e² + (ω/(2·0.9))²). A
/// scale of 0.25 (the default before) costs 4 % and delays a wave by about six increments;
/// docs/BENCHMARKS.md tabulates the trade.
/// The modulus rule is the element form of LS-DYNA's `SOFT=0` (`k = SLSFAC·K·A²/V`, here
/// `scale·E·A_s/h_m` with A_s the slave node's tributary area and h_m the master facet's size)
/// and needs the underlying material's modulus.
#[derive(Clone, Debug, PartialEq)]
pub enum Stiffness {
    /// `k = scale·m*/Δt_ref²` (see above).
    Auto {
        /// Factor on the automatic stiffness (Abaqus' "penalty scale factor").
        scale: f64,
    },
    /// `k = scale·E·A_s/h_m`.
    Modulus {
        /// Young's modulus of the underlying elements, model stress units.
        modulus: f64,
        /// Factor (LS-DYNA's SLSFAC, default 0.1).
        scale: f64,
    },
    /// A fixed stiffness, force per length, for every slave node.
    Absolute(f64),
    /// A stiffness per unit tributary area (pressure per length, Abaqus' linear
    /// pressure–overclosure slope): slave node i gets `k·A_i`, which makes a uniform pressure
    /// give a uniform overclosure. Needs the slave nodes' areas
    /// ([`crate::Model::add_node_set_with_areas`]).
    PerArea(f64),
}

/// Pressure as a function of overclosure h = −gap (positive when penetrating).
#[derive(Clone, Debug, PartialEq)]
pub enum PressureOverclosure {
    /// Force `k·h` for h > 0 (k from [`Stiffness`]).
    Linear,
    /// Abaqus' exponential law: contact from clearance `c0`, pressure
    /// `p = p0/(e−1)·(h/c0 + 1)·(exp(h/c0 + 1) − 1)` for h > −c0, so p(0) = p0.
    Exponential {
        /// Clearance at which contact starts (> 0), model length units.
        clearance: f64,
        /// Pressure at zero clearance (> 0), model stress units.
        pressure: f64,
    },
    /// Piecewise-linear pressure through (overclosure, pressure) points with increasing
    /// overclosure, the first at pressure 0 (a negative first overclosure is a clearance);
    /// extrapolated with the last slope. At most [`MAX_TABLE_POINTS`] points.
    Tabular(Vec<(f64, f64)>),
}

impl PressureOverclosure {
    /// A linear pressure–overclosure law, pressure = `slope`·overclosure (the two-point table
    /// (0, 0), (1, slope), extrapolated with its slope): the linear softened law of kinematic
    /// contact, where pressures need their own slope.
    pub fn linear(slope: f64) -> Self {
        Self::Tabular(vec![(0.0, 0.0), (1.0, slope)])
    }

    /// Checks the law's parameters.
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::BadParameter {
                    name,
                    value: v.to_string(),
                    expected: "must be finite and positive",
                })
            }
        };
        match self {
            Self::Linear => {}
            Self::Exponential {
                clearance,
                pressure,
            } => {
                positive("exponential clearance", *clearance)?;
                positive("exponential pressure", *pressure)?;
            }
            Self::Tabular(t) => {
                if t.len() < 2 || t.len() > MAX_TABLE_POINTS {
                    return Err(Error::BadParameter {
                        name: "pressure-overclosure table",
                        value: format!("{} points", t.len()),
                        expected: "needs 2 to 16 points",
                    });
                }
                let ok = t
                    .iter()
                    .all(|(h, p)| h.is_finite() && p.is_finite() && *p >= 0.0)
                    && t.windows(2).all(|w| w[1].0 > w[0].0 && w[1].1 >= w[0].1)
                    && t[0].1 == 0.0;
                if !ok {
                    return Err(Error::BadParameter {
                        name: "pressure-overclosure table",
                        value: format!("{t:?}"),
                        expected:
                            "needs increasing overclosures, non-decreasing pressures, the first 0",
                    });
                }
            }
        }
        Ok(())
    }

    /// Pressure (force per area) and its derivative at overclosure `h` (f64 reference; the
    /// linear law has no pressure form and gives 0).
    pub fn pressure(&self, h: f64) -> (f64, f64) {
        match self {
            Self::Linear => (0.0, 0.0),
            Self::Exponential {
                clearance,
                pressure,
            } => {
                let x = h / clearance + 1.0;
                if x <= 0.0 {
                    return (0.0, 0.0);
                }
                let e1 = std::f64::consts::E - 1.0;
                let ex = x.min(60.0).exp();
                (
                    pressure / e1 * x * (ex - 1.0),
                    pressure / (e1 * clearance) * ((ex - 1.0) + x * ex),
                )
            }
            Self::Tabular(t) => {
                if h <= t[0].0 {
                    return (0.0, 0.0);
                }
                let n = t.len();
                let k = (0..n - 1).find(|&k| h < t[k + 1].0).unwrap_or(n - 2);
                let slope = (t[k + 1].1 - t[k].1) / (t[k + 1].0 - t[k].0);
                (t[k].1 + slope * (h - t[k].0), slope)
            }
        }
    }

    /// Overclosure at which the law starts to push (0 for linear, −clearance for exponential,
    /// the first table point for tabular).
    pub fn start(&self) -> f64 {
        match self {
            Self::Linear => 0.0,
            Self::Exponential { clearance, .. } => -clearance,
            Self::Tabular(t) => t[0].0,
        }
    }
}

/// Points a tabular pressure–overclosure law may have (WGSL: `MAX_TABLE_POINTS`).
pub const MAX_TABLE_POINTS: usize = 16;

/// Tangential behaviour.
#[derive(Clone, Debug, PartialEq)]
pub enum Friction {
    /// No friction (no friction work is dispatched).
    Frictionless,
    /// Coulomb friction with elastic stick (tangential penalty of `stick_stiffness` × the
    /// normal stiffness). With `mu_kinetic` < `mu` the coefficient decays with slip rate:
    /// `μ = μ_k + (μ − μ_k)·exp(−decay·|v_slip|)` (Abaqus' exponential decay).
    Coulomb {
        /// Static friction coefficient.
        mu: f64,
        /// Kinetic coefficient (equal to `mu` for plain Coulomb).
        mu_kinetic: f64,
        /// Decay coefficient, time per length.
        decay: f64,
        /// Tangential stiffness as a fraction of the normal stiffness.
        stick_stiffness: f64,
    },
}

impl Friction {
    /// Plain Coulomb friction with coefficient `mu` and stick stiffness equal to the normal one.
    pub fn coulomb(mu: f64) -> Self {
        Friction::Coulomb {
            mu,
            mu_kinetic: mu,
            decay: 0.0,
            stick_stiffness: 1.0,
        }
    }
}

impl Pair {
    /// A pair of `slave` nodes against the `master` surface: penalty enforcement with the
    /// automatic stiffness, frictionless.
    pub fn new(slave: NodeSetId, master: SurfaceId) -> Self {
        Self {
            slave,
            master,
            search_radius: None,
            enforce: Enforce::default(),
            friction: Friction::Frictionless,
            balanced: None,
            schedule: None,
            sliding: Sliding::Finite,
            pass_weight: 1.0,
            slave_order: SlaveOrder::Morton,
            search_structure: SearchStructure::Auto,
        }
    }

    /// Sets the global search's structure ([`SearchStructure`]); results do not depend on it.
    pub fn search_structure(mut self, structure: SearchStructure) -> Self {
        self.search_structure = structure;
        self
    }

    /// Sets the order the pair keeps its slave nodes in inside abut (penalty enforcement;
    /// a kinematic pair keeps the node set's). Results do not depend on it.
    pub fn slave_order(mut self, order: SlaveOrder) -> Self {
        self.slave_order = order;
        self
    }

    /// Sets the fraction (in [0, 1]) of each contact's penalty force this pure pair applies:
    /// with the same pair's other pass as a second pure pair weighted 1 − `weight` (master
    /// nodes against the slave surface, each with its tributary area on the master), the two
    /// make the balanced pair of [`Pair::balanced`]. Penalty enforcement only.
    pub fn pass_weight(mut self, weight: f64) -> Self {
        self.pass_weight = weight;
        self
    }

    /// Sets the sliding formulation.
    pub fn sliding(mut self, sliding: Sliding) -> Self {
        self.sliding = sliding;
        self
    }

    /// Sets when the search runs globally (Abaqus' *CONTACT CONTROLS).
    pub fn schedule(mut self, schedule: Schedule) -> Self {
        self.schedule = Some(schedule);
        self
    }

    /// Makes the pair balanced: `slave_surface` is the surface the slave nodes lie on, and
    /// the two passes are weighted `weight` (slave on master) and `1 − weight` (master on
    /// slave); ½ is the usual choice.
    pub fn balanced(mut self, slave_surface: SurfaceId, weight: f64) -> Self {
        self.balanced = Some((slave_surface, weight));
        self
    }

    /// Sets the search radius (model units, finite and positive).
    pub fn search_radius(mut self, radius: f64) -> Self {
        self.search_radius = Some(radius);
        self
    }

    /// Sets the enforcement method.
    pub fn enforce(mut self, enforce: Enforce) -> Self {
        self.enforce = enforce;
        self
    }

    /// Sets the tangential behaviour.
    pub fn friction(mut self, friction: Friction) -> Self {
        self.friction = friction;
        self
    }

    pub(crate) fn validate(&self) -> Result<()> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::BadParameter {
                    name,
                    value: v.to_string(),
                    expected: "must be finite and positive",
                })
            }
        };
        let non_negative = |name: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(Error::BadParameter {
                    name,
                    value: v.to_string(),
                    expected: "must be finite and not negative",
                })
            }
        };
        if let Some(r) = self.search_radius {
            positive("search_radius", r)?;
        }
        match &self.enforce {
            Enforce::Penalty(p) => {
                match p.stiffness {
                    Stiffness::Auto { scale } => positive("penalty scale", scale)?,
                    Stiffness::Modulus { modulus, scale } => {
                        positive("penalty modulus", modulus)?;
                        positive("penalty scale", scale)?;
                    }
                    Stiffness::Absolute(k) | Stiffness::PerArea(k) => {
                        positive("penalty stiffness", k)?
                    }
                }
                non_negative("penalty damping", p.damping)?;
                p.law.validate()?;
            }
            Enforce::Kinematic(k) => {
                if let Some(law) = &k.softened {
                    law.validate()?;
                    if matches!(law, PressureOverclosure::Linear) {
                        return Err(Error::BadParameter {
                            name: "softened law",
                            value: "Linear".into(),
                            expected:
                                "softened kinematic contact needs an exponential or tabular law",
                        });
                    }
                }
                if !matches!(self.friction, Friction::Frictionless)
                    && (self.balanced.is_some() || self.sliding != Sliding::Finite)
                {
                    return Err(Error::BadParameter {
                        name: "friction",
                        value: format!("{:?}", self.friction),
                        expected: "kinematic friction on pure finite-sliding pairs (balanced and small-sliding kinematic pairs are frictionless; use penalty enforcement there)",
                    });
                }
            }
        }
        if self.pass_weight != 1.0 {
            if !(self.pass_weight.is_finite() && (0.0..=1.0).contains(&self.pass_weight)) {
                return Err(Error::BadParameter {
                    name: "pass weight",
                    value: self.pass_weight.to_string(),
                    expected: "must lie in [0, 1]",
                });
            }
            if self.balanced.is_some() || !matches!(self.enforce, Enforce::Penalty(_)) {
                return Err(Error::BadParameter {
                    name: "pass weight",
                    value: self.pass_weight.to_string(),
                    expected: "a pure penalty pair (a balanced pair weighs its passes itself)",
                });
            }
        }
        if let Some((_, w)) = self.balanced {
            if !(w.is_finite() && (0.0..=1.0).contains(&w)) {
                return Err(Error::BadParameter {
                    name: "balanced weight",
                    value: w.to_string(),
                    expected: "must lie in [0, 1]",
                });
            }
        }
        if let Friction::Coulomb {
            mu,
            mu_kinetic,
            decay,
            stick_stiffness,
        } = self.friction
        {
            non_negative("friction coefficient", mu)?;
            non_negative("kinetic friction coefficient", mu_kinetic)?;
            non_negative("friction decay", decay)?;
            positive("stick stiffness", stick_stiffness)?;
            if mu_kinetic > mu {
                return Err(Error::BadParameter {
                    name: "kinetic friction coefficient",
                    value: mu_kinetic.to_string(),
                    expected: "must not exceed the static coefficient",
                });
            }
        }
        Ok(())
    }
}

/// When a pair searches globally (seed: "Finite-sliding tracking", "Tracking approach for
/// self-contact pairs"; Abaqus' *CONTACT CONTROLS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// A global search every this many increments (the first increment always searches
    /// globally). Defaults: 100 for two-surface pairs, 4 for self-contact.
    pub interval: u32,
    /// Motion budget as a fraction of the search radius: when a slave node out of contact (no
    /// facet within the radius at the last increment) or a master node has moved more than
    /// half of `budget·radius` since the last global search (the two together could have used
    /// it up), the increment searches globally; slaves with a facet within the radius are
    /// followed by the local search. The global search tracks every slave within the tracking
    /// radius, `(1 + budget)·radius`, so a slave is found the increment it comes within the
    /// radius, and the local increments visit only the tracked slaves. Default 0.5.
    pub budget: f64,
    /// The slightly more expensive local search: also the facets around every node of the
    /// nearest facet found around the tracked node (Abaqus' FAST LOCAL TRACKING=NO). The fast
    /// walk can settle on a node none of whose facets is the nearest (obtuse triangles); this
    /// one does not (measured in tests/tracking.rs).
    pub wide_local: bool,
    /// Local increments visit every slave, tracked or not, instead of only the active slaves
    /// (those the last global search left tracked). The results are the same bits: this is
    /// the baseline the active-slave compaction is tested and measured against. Default false.
    pub visit_every_slave: bool,
}

impl Schedule {
    /// The defaults for a two-surface pair (`self_contact` false) or a self-contact pair.
    pub fn default_for(self_contact: bool) -> Self {
        Self {
            interval: if self_contact { 4 } else { 100 },
            budget: 0.5,
            wide_local: false,
            visit_every_slave: false,
        }
    }
}
