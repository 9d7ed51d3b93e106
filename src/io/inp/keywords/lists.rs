//! What abut reads and does not act on, and what it does not model: the keyword lists.

/// Keywords abut reads and does not act on, with why.
pub(in crate::io::inp) fn ignored(kw: &str) -> Option<&'static str> {
    Some(match kw {
        "ENERGY OUTPUT" => {
            "abut writes the whole model's energies in history.csv (kinetic, internal, external and contact work, the balance)"
        }
        "SECTION PRINT" | "ENERGY PRINT" | "ENERGY FILE" => {
            "a print or file request of another code; abut writes history.csv and summary.json"
        }
        "PREPRINT" | "RESTART" | "MONITOR" | "FILE FORMAT" | "DIAGNOSTICS" => {
            "a control of Abaqus' own files and messages"
        }
        _ => return None,
    })
}

/// Keywords abut does not model, with what they are: refused before anything runs.
pub(in crate::io::inp) fn not_modelled(kw: &str) -> Option<&'static str> {
    Some(match kw {
        "PLASTIC" | "HYPERELASTIC" | "HYPERFOAM" | "VISCOELASTIC" | "CREEP"
        | "DAMAGE INITIATION" | "DAMAGE EVOLUTION" | "DEPVAR" | "USER MATERIAL" => {
            "a material model beyond linear elasticity"
        }
        "EXPANSION" | "CONDUCTIVITY" | "SPECIFIC HEAT" | "INITIAL CONDITIONS TEMPERATURE" => {
            "thermal behaviour"
        }
        "EQUATION" | "MPC" | "TIE" | "COUPLING" | "KINEMATIC" | "DISTRIBUTING"
        | "KINEMATIC COUPLING" => "a constraint between nodes",
        "CYCLIC SYMMETRY MODEL" | "TIE CYCLIC" => "cyclic symmetry",
        "SHELL SECTION"
        | "SHELL GENERAL SECTION"
        | "MEMBRANE SECTION"
        | "BEAM SECTION"
        | "BEAM GENERAL SECTION" => "a structural section (shells, membranes, beams)",
        "SPRING" | "DASHPOT" | "CONNECTOR SECTION" => "springs, dashpots and connectors",
        "HEAT TRANSFER"
        | "FREQUENCY"
        | "BUCKLE"
        | "VISCO"
        | "COUPLED TEMPERATURE-DISPLACEMENT"
        | "STEADY STATE DYNAMICS"
        | "MODAL DYNAMIC" => "an analysis procedure other than explicit dynamics",
        "CONTACT" | "CONTACT INCLUSIONS" | "CONTACT PROPERTY ASSIGNMENT" => {
            "general contact (abut reads contact pairs: *CONTACT PAIR)"
        }
        "DSLOAD" | "DSFLUX" | "DFLUX" | "CFLUX" | "TEMPERATURE" | "FILM" => {
            "a load abut does not apply (distributed surface loads, fluxes, temperatures)"
        }
        "GAP" | "CHANGE FRICTION" | "MODEL CHANGE" | "CHANGE SURFACE BEHAVIOR" => {
            "a contact option abut does not read yet"
        }
        _ => return None,
    })
}
