//! The scene tables a deck fills: a part of the deck, a contact pair as the deck defines it, the
//! run controls of its step.

use std::sync::Arc;

use super::DeckPiece;
use crate::io::inp::PairSettings;
use crate::scene::spec::{
    default_bulk_linear, default_bulk_quadratic, default_contact_safety, default_core,
    default_every, default_grading, default_max_increments, default_safety, ContactSpec, PartSpec,
    RunSpec,
};

impl PartSpec {
    /// A part of the deck `file`: shape "mesh", its mesh and state in `piece`.
    pub(in crate::scene) fn deck_part(name: String, file: &str, piece: Arc<DeckPiece>) -> Self {
        Self {
            name,
            shape: "mesh".into(),
            material: None,
            origin: [0.0; 3],
            size: [0.0; 3],
            divisions: [0; 3],
            grading: default_grading(),
            grading_core: default_core(),
            area: 1.0,
            thickness: 1.0,
            radius: 0.0,
            angles: [0.0; 2],
            points: Vec::new(),
            mass: 0.0,
            velocity: [0.0; 3],
            file: Some(file.to_string()),
            rigid: false,
            dimension: None,
            deck: Some(piece),
            axisymmetric: false,
            motion: None,
        }
    }
}

impl ContactSpec {
    /// A deck's `*CONTACT PAIR`: the slave surface on one part against the master surface on
    /// another (or the same), balanced at `weight` when given.
    pub(in crate::scene) fn deck_pair(
        slave: String,
        slave_face: String,
        master: String,
        master_face: String,
        weight: Option<f64>,
        settings: PairSettings,
    ) -> Self {
        let kinematic = matches!(settings.enforce, crate::model::Enforce::Kinematic(_));
        Self {
            slave,
            slave_face,
            master,
            master_face: Some(master_face),
            enforce: Some(if kinematic { "kinematic" } else { "penalty" }.into()),
            friction: 0.0,
            sliding: None,
            balanced: weight,
            penalty_scale: None,
            stiffness: None,
            stiffness_per_area: None,
            damping: None,
            search_interval: None,
            search_radius: None,
            search_structure: None,
            deck: Some(settings),
        }
    }
}

impl RunSpec {
    /// The run controls of a deck's step running to `end_time`, the rest at the scene defaults.
    pub(in crate::scene) fn for_deck(end_time: f64) -> Self {
        Self {
            end_time,
            step_ends: Vec::new(),
            safety: default_safety(),
            contact_safety: default_contact_safety(),
            dt: None,
            gravity: [0.0; 3],
            damping: 0.0,
            bulk_viscosity: default_bulk_linear(),
            bulk_viscosity_quadratic: default_bulk_quadratic(),
            nlgeom: true,
            output_every: default_every(),
            vtk_every: 0,
            adjust_overclosure: false,
            max_increments: default_max_increments(),
        }
    }
}
