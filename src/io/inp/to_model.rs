//! A parsed deck to abut's `Model`: its nodes, masses, surfaces and contact pairs with their
//! interactions and controls.

use super::*;

/// How a `*CONTACT PAIR` is enforced: what its interaction, its controls and the step make of
/// it.
#[derive(Clone, Debug, PartialEq)]
pub struct PairSettings {
    /// Penalty (`MECHANICAL CONSTRAINT=PENALTY`) or kinematic, with the pressure–overclosure law.
    pub enforce: Enforce,
    /// `*FRICTION`.
    pub friction: Friction,
    /// `SMALL SLIDING`: small with NLGEOM, infinitesimal without; finite otherwise.
    pub sliding: Sliding,
    /// `*CONTACT CONTROLS`' `GLOBTRKINC` and `FASTLOCALTRK`, when given.
    pub schedule: Option<Schedule>,
}

/// What [`Deck::to_model`] built: the model and, per `*CONTACT PAIR`, its pair.
#[derive(Clone, Debug)]
pub struct DeckModel {
    /// The contact model (every deck node, in deck order).
    pub model: Model,
    /// The pair of each `*CONTACT PAIR` data line, in deck order.
    pub pairs: Vec<PairId>,
    /// Each surface's id, when it was used as a master or balanced slave surface.
    pub surfaces: BTreeMap<String, SurfaceId>,
    /// Each slave node set.
    pub slave_sets: BTreeMap<String, NodeSetId>,
}

impl Deck {
    /// How `pair` is enforced. Penalty pairs take `LINEAR` slopes as stiffness per area,
    /// `EXPONENTIAL` and `TABULAR` as laws (hard: the automatic stiffness, scaled by `SCALE
    /// PENALTY`); kinematic pairs take non-hard behaviours as softened contact.
    pub fn pair_settings(&self, pair: &ContactPairDef) -> PairSettings {
        let controls = self
            .controls
            .iter()
            .filter(|c| c.cpset.is_none() || c.cpset == pair.cpset)
            .fold(Controls::default(), |a, c| Controls {
                cpset: None,
                global_interval: c.global_interval.or(a.global_interval),
                wide_local: c.wide_local || a.wide_local,
                penalty_scale: c.penalty_scale.or(a.penalty_scale),
            });
        let inter = &self.interactions[&pair.interaction];
        let law = |b: &Behavior| match b {
            Behavior::Hard | Behavior::Linear(_) => PressureOverclosure::Linear,
            Behavior::Exponential {
                pressure,
                clearance,
            } => PressureOverclosure::Exponential {
                clearance: *clearance,
                pressure: *pressure,
            },
            Behavior::Tabular(t) => {
                PressureOverclosure::Tabular(t.iter().map(|&(p, h)| (h, p)).collect())
            }
        };
        let enforce = if pair.penalty {
            Enforce::Penalty(Penalty {
                stiffness: match inter.behavior {
                    Behavior::Linear(k) => Stiffness::PerArea(k),
                    _ => Stiffness::Auto {
                        scale: controls.penalty_scale.unwrap_or(1.0),
                    },
                },
                law: law(&inter.behavior),
                damping: inter
                    .damping
                    .unwrap_or(crate::model::DEFAULT_CONTACT_DAMPING),
            })
        } else {
            Enforce::Kinematic(Kinematic {
                softened: match &inter.behavior {
                    Behavior::Hard => None,
                    Behavior::Linear(k) => Some(PressureOverclosure::linear(*k)),
                    b => Some(law(b)),
                },
            })
        };
        let schedule = (controls.global_interval.is_some() || controls.wide_local).then(|| {
            let d = Schedule::default_for(pair.slave == pair.master);
            Schedule {
                interval: controls.global_interval.unwrap_or(d.interval),
                wide_local: controls.wide_local,
                ..d
            }
        });
        PairSettings {
            enforce,
            friction: if inter.friction > 0.0 {
                Friction::coulomb(inter.friction)
            } else {
                Friction::Frictionless
            },
            sliding: match (pair.small_sliding, self.nlgeom) {
                (false, _) => Sliding::Finite,
                (true, true) => Sliding::Small,
                (true, false) => Sliding::Infinitesimal,
            },
            schedule,
        }
    }

    /// The model with every contact pair: nodes with the sections' lumped masses (`default_mass`
    /// where no section gives one, e.g. rigid surfaces), 2D when every element is planar; each
    /// pair as [`Deck::pair_settings`] says.
    pub fn to_model(&self, default_mass: f64) -> Result<DeckModel> {
        let planar = !self.mesh.elements.is_empty()
            && self
                .mesh
                .elements
                .iter()
                .all(|e| e.kind.is_planar() || e.kind == ElementKind::Line2);
        let mut model = if planar {
            Model::new_2d()
        } else {
            Model::new_3d()
        };
        let masses: Vec<f64> = self
            .masses
            .iter()
            .map(|&m| if m > 0.0 { m } else { default_mass })
            .collect();
        model.add_nodes(&self.mesh.positions, &masses)?;
        let mut out = DeckModel {
            model,
            pairs: Vec::new(),
            surfaces: BTreeMap::new(),
            slave_sets: BTreeMap::new(),
        };
        for pair in &self.pairs {
            let slave = match &self.surfaces[&pair.slave] {
                SurfaceDef::Nodes(n, a) => out.model.add_node_set_with_areas(n, a)?,
                SurfaceDef::Faces(f) => {
                    // an axisymmetric deck's areas are per radian
                    let (nodes, areas) = if self.mesh.is_axisymmetric() {
                        crate::io::face_nodes_and_areas_per_radian(f, &self.mesh.positions)
                    } else {
                        crate::io::face_nodes_and_areas(f, &self.mesh.positions)
                    };
                    out.model.add_node_set_with_areas(&nodes, &areas)?
                }
            };
            out.slave_sets.insert(pair.slave.clone(), slave);
            let Some(SurfaceDef::Faces(master_faces)) = self.surfaces.get(&pair.master) else {
                return Err(Error::BadParameter {
                    name: "*CONTACT PAIR master surface",
                    value: pair.master.clone(),
                    expected: "an element-based surface (a node-based surface can only be a slave; an analytical surface needs a rigid body: Scene::from_inp)",
                });
            };
            let master = out
                .model
                .add_surface(Surface::from_facets(master_faces.clone()))?;
            out.surfaces.insert(pair.master.clone(), master);
            let set = self.pair_settings(pair);
            let mut p = Pair::new(slave, master)
                .enforce(set.enforce)
                .friction(set.friction)
                .sliding(set.sliding);
            if let Some(schedule) = set.schedule {
                p = p.schedule(schedule);
            }
            if let Some(w) = pair.weight {
                let SurfaceDef::Faces(f) = &self.surfaces[&pair.slave] else {
                    return Err(Error::BadParameter {
                        name: "*CONTACT PAIR, WEIGHT",
                        value: pair.slave.clone(),
                        expected: "a balanced pair needs an element-based slave surface",
                    });
                };
                let s = out.model.add_surface(Surface::from_facets(f.clone()))?;
                out.surfaces.insert(pair.slave.clone(), s);
                p = p.balanced(s, w);
            }
            out.pairs.push(out.model.add_pair(p)?);
        }
        Ok(out)
    }
}
