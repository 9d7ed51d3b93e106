//! An Abaqus deck as a scene ([`Scene::from_inp`]): its sections' elements as deformable parts
//! (elements that share nodes in one part), each `*RIGID BODY` as a rigid part moving as its
//! reference node's boundary conditions say, the point masses not on an element as a part of
//! their own; boundary conditions, initial velocities, loads and amplitudes on the parts' nodes
//! (`placing.rs`), through the steps in order (`steps.rs`); the contact pairs as the deck
//! defines them; the steps' controls as the run's; the node output requests. What abut does not
//! model is refused here, naming the definition's file and line; what it reads and does not act
//! on is listed in [`Scene::deck_notes`].

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::explicit::{Amplitude, BodyMotion, LoadCurve, Material, Prescribed};
use crate::io::inp::{At, Deck, PairSettings, SurfaceDef};
use crate::io::MeshData;

use super::spec::{ContactSpec, MaterialSpec, PartSpec, RunSpec, Scene};

mod pieces;
mod placing;
mod quasi_static;
mod rigid;
mod roles;
mod specs;
mod steps;

/// A part of a deck: its mesh (node indices local to the part) and what the deck says about
/// its elements and nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeckPiece {
    /// Nodes, elements, sets (restricted to the part) in deck order.
    pub mesh: MeshData,
    /// The deck's surfaces, restricted to the part's nodes.
    pub surfaces: BTreeMap<String, SurfaceDef>,
    /// Each element's material (deformable parts).
    pub materials: Vec<Material>,
    /// Whether each element is deformable (not a surface element).
    pub deformable: Vec<bool>,
    /// Each element's thickness (plane elements) or cross-section area (trusses).
    pub thickness: Vec<f64>,
    /// Whether each element's type asks for reduced integration (C3D8R: one point with
    /// hourglass control; C3D8 is selectively reduced).
    pub reduced: Vec<bool>,
    /// Each node's initial velocity.
    pub velocity: Vec<[f64; 3]>,
    /// Each node's point mass (`*MASS`).
    pub point_mass: Vec<f64>,
    /// Each node's constant load (`*CLOAD`).
    pub loads: Vec<[f64; 3]>,
    /// Each node's held translations.
    pub fixed: Vec<[bool; 3]>,
    /// Prescribed motions (node indices local to the part).
    pub prescribed: Vec<Prescribed>,
    /// Loads on their own curves (node indices local to the part).
    pub load_curves: Vec<LoadCurve>,
    /// A rigid part: its body.
    pub rigid: Option<DeckRigid>,
    /// Each node's deck index (for messages and the history).
    pub deck_nodes: Vec<u32>,
}

/// The rigid body a `*RIGID BODY` makes of its elements.
#[derive(Clone, Debug, PartialEq)]
pub struct DeckRigid {
    /// Its reference node's position.
    pub reference: [f64; 3],
    /// Mass (`*MASS` on the reference node); a stand-in when it has none (`massless`).
    pub mass: f64,
    /// The deck gives it no mass (a fixed body, or one whose motion is prescribed): contact
    /// treats it as immovable.
    pub massless: bool,
    /// Inertia about the reference node (`*ROTARY INERTIA`).
    pub inertia: [[f64; 3]; 3],
    /// How it moves, from its reference node's boundary conditions.
    pub motion: BodyMotion,
    /// Held translations of a free body.
    pub locked: [bool; 3],
    /// Rotation held (all three rotational degrees of freedom fixed).
    pub rotation_locked: bool,
    /// Initial velocity (`*INITIAL CONDITIONS` on the reference node).
    pub velocity: [f64; 3],
    /// Constant force and moment (`*CLOAD` on the reference node).
    pub load: [f64; 3],
    /// Constant moment.
    pub moment: [f64; 3],
}

fn refuse<T>(at: &At, message: impl Into<String>) -> Result<T> {
    Err(Error::Parse {
        file: at.file.clone(),
        line: at.line,
        message: message.into(),
    })
}

/// What each deck element is.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    /// In a section: material index and thickness.
    Deformable(usize, f64),
    /// In rigid body k.
    Rigid(usize),
    /// A surface element (`*SURFACE SECTION`): a surface on the nodes of another part.
    Surface,
}

impl Scene {
    /// Reads the Abaqus deck at `path` as a scene: the explicit-dynamics subset of its
    /// keywords (the module doc of [`crate::io::inp`] and of this function's module list them).
    /// Errors name the file and line of what abut does not model.
    pub fn from_inp(path: &Path) -> Result<Scene> {
        let deck = crate::io::inp::read(path)?;
        let file = path.display().to_string();
        from_deck(&deck, &file)
    }
}

fn from_deck(deck: &Deck, file: &str) -> Result<Scene> {
    let a = &deck.analysis;
    let whole = At {
        file: file.to_string(),
        line: 1,
    };
    let mut notes: Vec<String> = a.ignored.clone();
    // the one explicit step
    let Some(step) = a.steps.first() else {
        return refuse(
            &whole,
            "the deck has no *STEP: abut runs a deck's *DYNAMIC, EXPLICIT step",
        );
    };
    steps::check_controls(&a.steps)?;
    let several = a.steps.len() > 1;
    let static_step = match step.procedure.as_deref() {
        Some("DYNAMIC EXPLICIT") => false,
        Some("STATIC") => true,
        Some(p) => {
            return refuse(
                &step.at,
                format!("*STEP with *{p}: abut runs *DYNAMIC, EXPLICIT steps and *STATIC ones as quasi-static"),
            )
        }
        None => return refuse(&step.at, "*STEP without a procedure (*DYNAMIC, EXPLICIT or *STATIC)"),
    };
    for s in &a.steps {
        if !s.time_period.is_some_and(|t| t.is_finite() && t > 0.0) {
            return refuse(
                &s.at,
                "*DYNAMIC, EXPLICIT needs a positive time period (the data line's second value)",
            );
        }
    }
    let timeline = steps::Timeline::new(&a.steps);
    let end_time = timeline.end;
    let scaling = step.mass_scaling.unwrap_or(1.0);
    // materials (densities scaled)
    let mut materials: Vec<(String, Material, f64)> = Vec::new();
    let mut material_index = BTreeMap::new();
    for s in &a.sections {
        if material_index.contains_key(&s.material) {
            continue;
        }
        let Some(m) = a.materials.get(&s.material) else {
            return refuse(
                &s.at,
                format!("*SOLID SECTION: material {} is not defined", s.material),
            );
        };
        // a quasi-static run's increments do not depend on the density: without one, 1
        let density = match m.density {
            None if static_step && a.gravity.is_empty() => {
                notes.push(format!(
                    "material {}: no *DENSITY; the quasi-static run takes 1 (its increments and its static answer do not depend on it)",
                    s.material
                ));
                Some(1.0)
            }
            d => d,
        };
        let (Some(rho), Some((young, poisson))) = (density, m.elastic) else {
            return refuse(
                &m.at,
                format!(
                    "material {} needs *DENSITY and *ELASTIC for an explicit run",
                    s.material
                ),
            );
        };
        material_index.insert(s.material.clone(), materials.len());
        materials.push((
            s.material.clone(),
            Material {
                young,
                poisson,
                density: rho * scaling,
            },
            m.alpha,
        ));
    }
    if scaling != 1.0 {
        notes.push(format!(
            "{}: *FIXED MASS SCALING, FACTOR={scaling}: every density multiplied by it",
            step.at
        ));
    }
    let alphas: BTreeSet<u64> = materials.iter().map(|m| m.2.to_bits()).collect();
    if alphas.len() > 1 {
        return refuse(
            &whole,
            "materials with different *DAMPING, ALPHA=: abut applies one mass-proportional damping to the whole model",
        );
    }
    let damping = materials.first().map_or(0.0, |m| m.2);
    let mesh = &deck.mesh;
    let role = roles::roles(deck, &material_index, &whole, &mut notes)?;
    let pieces::Split {
        mut pieces,
        piece_of,
        local,
        rigid_of_piece,
        ref_nodes,
        point_mass,
    } = pieces::split(deck, &role, &materials)?;
    // rigid bodies: mass, inertia, motion from the reference node
    let quasi_static = if static_step {
        Some(quasi_static::quasi_static(
            deck,
            &role,
            &materials,
            step.time_period.unwrap_or(1.0),
            step,
        )?)
    } else {
        None
    };
    // a step's values without an amplitude: at once (explicit dynamics), or ramped by a
    // smooth step (quasi-static); an amplitude given in a static step's time, stretched to the
    // ramp's
    let amplitude = |name: &Option<String>| -> Arc<Amplitude> {
        let scale = quasi_static
            .as_ref()
            .map_or(1.0, |q| q.ramp_time / q.step_period);
        Arc::new(match (name, &quasi_static) {
            (Some(n), _) => {
                let mut c = a.amplitudes[n].curve.clone();
                for p in &mut c.points {
                    p.0 *= scale;
                }
                c
            }
            (None, Some(q)) => Amplitude {
                smooth: true,
                points: vec![(0.0, 0.0), (q.ramp_time, 1.0)],
            },
            (None, None) => Amplitude::step(),
        })
    };
    // loads of one step on one curve scale the solver's loads; else each has its own curve
    let load_amplitudes: BTreeSet<&Option<String>> =
        a.cloads.iter().map(|c| &c.amplitude).collect();
    let load_curves = several || load_amplitudes.len() > 1;
    let load_factor = match load_amplitudes.first() {
        _ if load_curves => None,
        Some(name) if name.is_some() || static_step => Some(amplitude(name)),
        _ => None,
    };
    steps::refuse_across_steps(a, &ref_nodes)?;
    // a rigid body's loads follow the one load curve (none here: they would act at once)
    if let Some(c) = a.cloads.iter().find(|c| {
        load_curves
            && (c.amplitude.is_some() || static_step)
            && c.nodes.iter().any(|n| ref_nodes.contains_key(n))
    }) {
        return refuse(
            &c.at,
            "*CLOAD on a rigid body's reference node with an amplitude, while other loads follow other curves (several steps or amplitudes): abut scales a rigid body's loads by one curve for the whole model",
        );
    }
    if several {
        notes.push(steps::note(a.steps.len(), &timeline));
    }
    // plane continuum elements, or plane trusses and rigid segments
    let two_d = mesh.elements.iter().any(|e| e.kind.is_planar())
        || a.element_blocks
            .iter()
            .any(|(_, t, _)| matches!(t.as_str(), "T2D2" | "R2D2" | "RAX2"));
    for (p, rigid) in rigid_of_piece.iter().enumerate() {
        if let Some(k) = *rigid {
            pieces[p].rigid = Some(rigid::body(
                a,
                &a.rigid_bodies[k],
                &point_mass,
                mesh,
                two_d,
            )?);
        }
    }
    let mut rigid_specs = Vec::new();
    for r in a.rigid_bodies.iter().filter(|r| r.analytical.is_some()) {
        let body = rigid::body(a, r, &point_mass, mesh, two_d)?;
        rigid_specs.push(rigid::analytical(a, r, &body, mesh)?);
    }
    // boundary conditions, initial velocities and loads on the deformable parts' nodes
    let place = placing::Place {
        a,
        mesh,
        piece_of: &piece_of,
        local: &local,
        ref_nodes: &ref_nodes,
        timeline: &timeline,
        two_d,
        several,
        load_curves,
    };
    place.boundaries(&mut pieces, &amplitude, &mut notes)?;
    place.initial_velocities(&mut pieces)?;
    place.loads(&mut pieces, &amplitude)?;
    // gravity: on every deformable element
    let mut gravity = [0.0; 3];
    for g in &a.gravity {
        let covers = match mesh.element_sets.get(&g.elset) {
            Some(set) => {
                let set: BTreeSet<u32> = set.iter().copied().collect();
                role.iter().enumerate().all(|(e, r)| {
                    !matches!(r, Some(Role::Deformable(..))) || set.contains(&(e as u32))
                })
            }
            // a set of point masses: the whole model when nothing else is deformable
            None => {
                a.mass_sets.contains(&g.elset)
                    && !role.iter().any(|r| matches!(r, Some(Role::Deformable(..))))
            }
        };
        if !covers {
            return refuse(&g.at, format!("*DLOAD, GRAV on {}: abut applies gravity to the whole model (an element set holding every deformable element)", g.elset));
        }
        for d in 0..3 {
            gravity[d] += g.acceleration[d];
        }
    }
    // parts
    let names = |p: usize| -> String {
        if let Some(k) = rigid_of_piece[p] {
            let r = &a.rigid_bodies[k];
            return r
                .elset
                .clone()
                .unwrap_or_else(|| format!("RIGID-{}", mesh.node_labels[r.ref_node as usize]));
        }
        a.sections
            .iter()
            .find(|s| {
                mesh.element_sets.get(&s.elset).is_some_and(|els| {
                    els.iter()
                        .any(|&e| piece_of[mesh.elements[e as usize].nodes[0] as usize] == p)
                })
            })
            .map_or_else(|| "POINT-MASSES".to_string(), |s| s.elset.clone())
    };
    // a section's elements in several unconnected pieces: one part each, numbered
    let mut part_names: Vec<String> = (0..pieces.len()).map(names).collect();
    for p in 0..part_names.len() {
        let same: Vec<usize> = (0..part_names.len())
            .filter(|&q| part_names[q] == part_names[p])
            .collect();
        if same.len() > 1 {
            for (k, q) in same.into_iter().enumerate() {
                part_names[q] = format!("{}-{}", part_names[q], k + 1);
            }
        }
    }
    // where each deck node went: its part and index there (node output requests)
    let mut home = vec![None; mesh.positions.len()];
    for (p, piece) in pieces.iter().enumerate() {
        for (k, &d) in piece.deck_nodes.iter().enumerate() {
            home[d as usize] = Some((p, k));
        }
    }
    // … and each deformable deck element (by label: labels are unique in a deck)
    let mut by_label = BTreeMap::new();
    for (p, piece) in pieces.iter().enumerate() {
        for (k, e) in piece.mesh.elements.iter().enumerate() {
            if piece.deformable[k] {
                by_label.insert(e.label, (p, k));
            }
        }
    }
    let element_home: Vec<Option<(usize, usize)>> = mesh
        .elements
        .iter()
        .map(|e| by_label.get(&e.label).copied())
        .collect();
    let element_labels: Vec<u64> = mesh.elements.iter().map(|e| e.label).collect();
    let (mut node_outputs, mut element_outputs) = (Vec::new(), Vec::new());
    let mut contact_outputs = Vec::new();
    for (k, s) in a.steps.iter().enumerate() {
        let when = super::deck_output::When {
            step: several.then_some(k + 1),
            from: timeline.start(k + 1),
            // a quasi-static step's answer: at the end of its hold
            at: quasi_static
                .as_ref()
                .map_or(timeline.end_of(k + 1), |q| q.ramp_time + q.hold_time),
        };
        node_outputs.extend(super::deck_output::requests(
            &s.node_outputs,
            when,
            &mesh.node_sets,
            &home,
            &mesh.node_labels,
            &mut notes,
        ));
        contact_outputs.extend(super::deck_output::contact_requests(
            &s.contact_outputs,
            when,
            !deck.pairs.is_empty(),
            &mut notes,
        ));
        element_outputs.extend(super::deck_output::element_requests(
            &s.element_outputs,
            when,
            &mesh.element_sets,
            &element_home,
            &element_labels,
            &mut notes,
        ));
    }
    let mut parts = Vec::new();
    for (p, piece) in pieces.into_iter().enumerate() {
        let rigid = piece.rigid.is_some();
        let material = (!rigid)
            .then(|| {
                piece
                    .materials
                    .iter()
                    .zip(&piece.deformable)
                    .find(|(_, d)| **d)
                    .and_then(|(m, _)| materials.iter().find(|x| x.1 == *m))
                    .map(|x| x.0.clone())
            })
            .flatten();
        // plane elements' faces carry their section's thickness
        let thickness = piece
            .mesh
            .elements
            .iter()
            .zip(&piece.thickness)
            .find(|(e, _)| e.kind.is_planar())
            .map_or(1.0, |(_, t)| *t);
        let mut spec = PartSpec::deck_part(part_names[p].clone(), file, Arc::new(piece));
        spec.thickness = thickness;
        spec.material = material;
        spec.rigid = rigid;
        spec.dimension = Some(if two_d { 2 } else { 3 });
        parts.push(spec);
    }
    // contact pairs
    let part_of_surface = |name: &str, at: &At| -> Result<String> {
        let holders: Vec<&PartSpec> = parts
            .iter()
            .filter(|p| {
                p.deck
                    .as_ref()
                    .is_some_and(|d| d.surfaces.contains_key(name))
            })
            .collect();
        match holders[..] {
            [p] => Ok(p.name.clone()),
            [] => refuse(at, format!("surface {name} has no facet or node on a part")),
            _ => refuse(
                at,
                format!(
                    "surface {name} spans several parts: abut takes a contact surface on one part"
                ),
            ),
        }
    };
    let mut contact = Vec::new();
    for pair in &deck.pairs {
        let at = At {
            file: file.to_string(),
            line: pair.line,
        };
        let settings: PairSettings = deck.pair_settings(pair);
        if rigid_specs.iter().any(|r| r.name == pair.master) {
            // against an analytical surface: hard kinematic contact, abut's rigid pairs
            let hard = matches!(
                settings.enforce,
                crate::model::Enforce::Kinematic(crate::model::Kinematic { softened: None })
            );
            if !hard || pair.weight.is_some() || settings.sliding != crate::model::Sliding::Finite {
                return refuse(
                    &at,
                    format!("*CONTACT PAIR against analytical surface {}: abut enforces it by hard kinematic contact, finite sliding, pure master–slave", pair.master),
                );
            }
            let mut c = ContactSpec::deck_pair(
                part_of_surface(&pair.slave, &at)?,
                pair.slave.clone(),
                pair.master.clone(),
                String::new(),
                None,
                settings,
            );
            c.master_face = None;
            contact.push(c);
            continue;
        }
        contact.push(ContactSpec::deck_pair(
            part_of_surface(&pair.slave, &at)?,
            pair.slave.clone(),
            part_of_surface(&pair.master, &at)?,
            pair.master.clone(),
            pair.weight,
            settings,
        ));
    }
    if step.fixed_increment.is_none()
        && !role.iter().any(|r| matches!(r, Some(Role::Deformable(..))))
    {
        return refuse(
            &step.at,
            "a deck without deformable elements has no stable increment: give one with *DYNAMIC, EXPLICIT, DIRECT USER CONTROL (the data line's first value)",
        );
    }
    let end_time = quasi_static
        .as_ref()
        .map_or(end_time, |q| q.ramp_time + q.hold_time);
    let mut run = RunSpec::for_deck(end_time);
    run.step_ends = timeline.starts.iter().skip(1).copied().collect();
    run.dt = step.fixed_increment;
    if let Some(s) = step.scale_factor {
        run.safety = s;
    }
    if let Some((b1, b2)) = step.bulk_viscosity {
        run.bulk_viscosity = b1;
        run.bulk_viscosity_quadratic = b2;
    }
    run.nlgeom = step.nlgeom;
    if quasi_static.is_some() && !step.nlgeom_written {
        notes.push(format!(
            "{}: *STEP without NLGEOM=: the *STATIC step is small-strain (NLGEOM=NO, Abaqus/Standard's and CalculiX's default; write NLGEOM=YES for large strain)",
            step.at
        ));
    }
    run.output_every = step.history_every.unwrap_or(1);
    run.vtk_every = step.field_every.unwrap_or(0);
    run.damping = damping + quasi_static.as_ref().map_or(0.0, |q| q.damping);
    if let Some(q) = &quasi_static {
        notes.push(format!(
            "{}: *STATIC run as explicit quasi-static: loads and motions ramped by a smooth step over {:.4e} (10 estimated fundamental periods of {:.4e}) and held {:.4e}, mass-proportional damping α = {:.4e}; the summary's quasi_static reports the kinetic energy against the internal energy",
            step.at, q.ramp_time, q.fundamental_period, q.hold_time, q.damping
        ));
    }
    run.gravity = gravity;
    let title = deck.heading.clone().unwrap_or_else(|| file.to_string());
    let scene = Scene {
        title,
        reference: None,
        run,
        material: materials
            .iter()
            .map(|(name, m, _)| MaterialSpec {
                name: name.clone(),
                young: m.young,
                poisson: m.poisson,
                density: m.density,
            })
            .collect(),
        part: parts,
        rigid: rigid_specs,
        boundary: Vec::new(),
        contact,
        base_dir: Path::new(file).parent().map(Path::to_path_buf),
        deck_notes: notes,
        quasi_static,
        load_factor,
        node_histories: node_outputs.iter().filter(|o| o.history).cloned().collect(),
        node_outputs: node_outputs.into_iter().filter(|o| !o.history).collect(),
        element_outputs,
        contact_outputs,
    };
    scene.check_deck()?;
    Ok(scene)
}
