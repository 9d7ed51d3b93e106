//! A scene written as an Abaqus deck ([`Scene::to_inp`], `abut inp SCENE`): the built model —
//! every node and element as the scene meshed them, sections, rigid bodies with reference nodes,
//! point masses, surfaces (surface elements where a face is not an element's own), boundary
//! conditions, amplitudes, loads and contact pairs — and one `*DYNAMIC, EXPLICIT` step with the
//! run's controls. Read back by [`Scene::from_inp`], the deck gives the scene's history bit for
//! bit; what has no deck form (analytical rigid bodies, a search radius, contact safety, mesh
//! parts) is an error naming it.

use std::fmt::Write as _;

use crate::error::{Error, Result};
use crate::explicit::{Element, Integration};
use crate::model::Facet;

use super::spec::Scene;

mod bodies;
mod contact;
mod faces;

fn unsupported<T>(what: String) -> Result<T> {
    Err(Error::BadParameter {
        name: "scene",
        value: what,
        expected: "a scene with a deck form (abut inp): generated parts, point masses, faces, boundaries and contact pairs without search radius",
    })
}

/// A deck name for `s`: upper case, `+` and `-` spelt out.
fn deck_name(s: &str) -> String {
    s.to_uppercase()
        .replace('+', "POS")
        .replace('-', "NEG")
        .replace(' ', "_")
}

/// Data lines of at most 8 values.
fn lines_of(values: &[String]) -> String {
    values.chunks(8).map(|c| c.join(", ") + "\n").collect()
}

/// A magnitude and a direction whose product is `g` exactly where round-off allows.
fn magnitude_direction(g: [f64; 3]) -> (f64, [f64; 3]) {
    let m = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let mut n = g.map(|c| c / m);
    for a in 0..3 {
        // nudge the direction's component by an ulp or two until m·n is g
        for _ in 0..4 {
            let p = m * n[a];
            if p == g[a] {
                break;
            }
            n[a] = if p < g[a] {
                f64::from_bits(if n[a] >= 0.0 {
                    n[a].to_bits() + 1
                } else {
                    n[a].to_bits() - 1
                })
            } else {
                f64::from_bits(if n[a] > 0.0 {
                    n[a].to_bits() - 1
                } else {
                    n[a].to_bits() + 1
                })
            };
        }
    }
    (m, n)
}

impl Scene {
    /// The scene as an Abaqus deck (text): the model as [`Scene::build`] makes it and one
    /// explicit step. [`Scene::from_inp`] reads it back into the same model.
    pub fn to_inp(&self) -> Result<String> {
        if let Some(r) = self.rigid.iter().find(|r| r.surface != "sphere") {
            return unsupported(format!(
                "[[rigid]] {}: analytical {} surfaces are not written to decks yet (spheres are)",
                r.name, r.surface
            ));
        }
        if self.run.contact_safety != super::spec::RunSpec::for_deck(1.0).contact_safety {
            return unsupported("run.contact_safety (no deck keyword)".into());
        }
        if self.run.adjust_overclosure {
            return unsupported("run.adjust_overclosure (no deck keyword in abut's reader)".into());
        }
        let built = self.build()?;
        let x = &built.solver.x;
        let two_d = self.is_2d();
        let mut out = String::new();
        let mut model_bc = String::new();
        let mut step_bc = String::new();
        let mut extra_nodes: Vec<[f64; 3]> = Vec::new();
        let mut label = 0usize;
        let mut deformable_sets = Vec::new();
        let mut mass_sets = Vec::new();
        writeln!(out, "*HEADING\n{}", self.title).ok();
        writeln!(
            out,
            "** written by abut from a scene; abut run reads it back"
        )
        .ok();
        // elements, part by part
        let mut elements = String::new();
        let part_of_element = |e: &Element| -> usize {
            let n = e.nodes()[0] as usize;
            built
                .parts
                .iter()
                .position(|p| n >= p.base && n < p.base + p.count)
                .expect("every element is on a part")
        };
        let mut by_part: Vec<Vec<&Element>> = vec![Vec::new(); built.parts.len()];
        for e in &built.solver.elements {
            by_part[part_of_element(e)].push(e);
        }
        // the faces each contact uses, written as surfaces
        let mut surfaces = String::new();
        let mut rigid_sets: Vec<Option<String>> = vec![None; built.parts.len()];
        for (k, (spec, part)) in self.part.iter().zip(&built.parts).enumerate() {
            let set = deck_name(&spec.name);
            if spec.shape == "mesh" {
                return unsupported(format!("part {}: mesh parts are not written to decks (their file is the deck's source)", spec.name));
            }
            if spec.is_rigid() {
                // the rigid part's facets as rigid elements, on a body with a reference node
                let face = match spec.shape.as_str() {
                    "plate" => "z+",
                    "line" => "y+",
                    _ => "out",
                };
                let facets = part.face(face, x)?.facets;
                for (kind, arity) in [("R2D2", 2), ("R3D3", 3), ("R3D4", 4)] {
                    let f: Vec<&Facet> =
                        facets.iter().filter(|f| f.nodes().len() == arity).collect();
                    if f.is_empty() {
                        continue;
                    }
                    writeln!(elements, "*ELEMENT, TYPE={kind}, ELSET={set}").ok();
                    for facet in f {
                        label += 1;
                        // a rigid segment's SPOS is left of node 1 → 2: written end first
                        let mut order = facet.nodes().to_vec();
                        if arity == 2 {
                            order.reverse();
                        }
                        let nodes: Vec<String> =
                            order.iter().map(|n| (n + 1).to_string()).collect();
                        writeln!(elements, "{label}, {}", nodes.join(", ")).ok();
                    }
                }
                let nodes: Vec<u32> = (part.base as u32..(part.base + part.count) as u32).collect();
                let (c, inertia) = super::build::centroid_and_inertia(&nodes, x, spec.mass);
                extra_nodes.push(c);
                let r = x.len() + extra_nodes.len();
                writeln!(elements, "*RIGID BODY, REF NODE={r}, ELSET={set}").ok();
                match spec.motion.as_deref() {
                    None | Some("fixed") => {
                        writeln!(model_bc, "{r}, ENCASTRE").ok();
                    }
                    Some(m) => {
                        elements +=
                            &bodies::mass_and_inertia(&mut label, r, &set, spec.mass, inertia);
                        let v = spec.velocity;
                        if m == "velocity" {
                            writeln!(model_bc, "{r}, 4, 6").ok();
                            for (a, va) in v.iter().enumerate() {
                                writeln!(
                                    step_bc,
                                    "*BOUNDARY, TYPE=VELOCITY\n{r}, {}, {}, {va:?}",
                                    a + 1,
                                    a + 1
                                )
                                .ok();
                            }
                        }
                        for (a, va) in v.iter().enumerate().filter(|(_, va)| **va != 0.0) {
                            writeln!(
                                elements,
                                "*INITIAL CONDITIONS, TYPE=VELOCITY\n{r}, {}, {va:?}",
                                a + 1
                            )
                            .ok();
                        }
                    }
                }
                rigid_sets[k] = Some(set);
                continue;
            }
            if spec.shape == "points" {
                writeln!(elements, "*ELEMENT, TYPE=MASS, ELSET={set}").ok();
                for n in part.base..part.base + part.count {
                    label += 1;
                    writeln!(elements, "{label}, {}", n + 1).ok();
                }
                writeln!(elements, "*MASS, ELSET={set}\n{:?}", spec.mass).ok();
                mass_sets.push(set.clone());
            } else {
                // deformable elements as the scene built them, and their section
                let mut section = None;
                let groups = [
                    ("bar", 0),
                    ("tri", 1),
                    ("axi", 2),
                    ("tet", 3),
                    ("hex", 4),
                    ("hexr", 5),
                ];
                for (kind, group) in groups {
                    let els: Vec<&&Element> = by_part[k]
                        .iter()
                        .filter(|e| match e {
                            Element::Bar { .. } => group == 0,
                            Element::Tri3 { hoop: None, .. } => group == 1,
                            Element::Tri3 { hoop: Some(_), .. } => group == 2,
                            Element::Tet4 { .. } => group == 3,
                            Element::Hex8(h) => match h.integration {
                                Integration::Selective => group == 4,
                                Integration::Reduced => group == 5,
                            },
                        })
                        .collect();
                    if els.is_empty() {
                        continue;
                    }
                    let ty = match kind {
                        "bar" if two_d => "T2D2",
                        "bar" => "T3D2",
                        "tri" => "CPE3",
                        "axi" => "CAX3",
                        "hex" => "C3D8",
                        "hexr" => "C3D8R",
                        _ => "C3D4",
                    };
                    writeln!(elements, "*ELEMENT, TYPE={ty}, ELSET={set}").ok();
                    for e in els {
                        label += 1;
                        let nodes: Vec<String> =
                            e.nodes().iter().map(|n| (n + 1).to_string()).collect();
                        writeln!(elements, "{label}, {}", nodes.join(", ")).ok();
                        let value = match e {
                            Element::Bar { area, .. } => Some(*area),
                            Element::Tri3 {
                                thickness,
                                hoop: None,
                                ..
                            } => Some(*thickness),
                            _ => None,
                        };
                        if section.is_some_and(|s: Option<f64>| s != value) {
                            return unsupported(format!(
                                "part {}: elements of different sections",
                                spec.name
                            ));
                        }
                        section = Some(value);
                    }
                }
                let material = spec.material.as_deref().unwrap_or_default();
                writeln!(
                    elements,
                    "*SOLID SECTION, ELSET={set}, MATERIAL={}",
                    deck_name(material)
                )
                .ok();
                if let Some(Some(v)) = section {
                    writeln!(elements, "{v:?}").ok();
                }
                deformable_sets.push(set.clone());
            }
            // a node set of the part, its held directions and its initial velocity
            writeln!(
                elements,
                "*NSET, NSET={set}-NODES, GENERATE\n{}, {}, 1",
                part.base + 1,
                part.base + part.count
            )
            .ok();
            for a in 0..3 {
                if two_d && a == 2 {
                    continue;
                }
                let held: Vec<usize> = (part.base..part.base + part.count)
                    .filter(|&n| built.solver.fixed[n][a])
                    .collect();
                if held.len() == part.count && self.boundary.iter().all(|b| b.part != spec.name) {
                    writeln!(model_bc, "{set}-NODES, {}, {}", a + 1, a + 1).ok();
                }
            }
            for (a, va) in spec
                .velocity
                .iter()
                .enumerate()
                .filter(|(_, va)| **va != 0.0)
            {
                writeln!(
                    elements,
                    "*INITIAL CONDITIONS, TYPE=VELOCITY\n{set}-NODES, {}, {va:?}",
                    a + 1
                )
                .ok();
            }
        }
        // analytical spheres: a reference node at the centre, the surface of revolution about it
        let analytical = bodies::spheres(
            &self.rigid,
            x.len(),
            &mut extra_nodes,
            &mut label,
            &mut model_bc,
            &mut step_bc,
        );
        // held directions a [[boundary]] does not give (a bar's lateral ones) on parts with
        // boundaries: node by node
        for (spec, part) in self.part.iter().zip(&built.parts) {
            if spec.is_rigid() || !self.boundary.iter().any(|b| b.part == spec.name) {
                continue;
            }
            let from_boundaries: Vec<[bool; 3]> = {
                let mut h = vec![[false; 3]; part.count];
                for b in self.boundary.iter().filter(|b| b.part == spec.name) {
                    let face = part.face(&b.face, x)?;
                    for d in &b.fix {
                        let a = super::spec::axis_of(d).expect("checked");
                        for &n in &face.nodes {
                            h[n as usize - part.base][a] = true;
                        }
                    }
                }
                h
            };
            for n in part.base..part.base + part.count {
                for a in 0..3 {
                    if two_d && a == 2 {
                        continue;
                    }
                    if built.solver.fixed[n][a] && !from_boundaries[n - part.base][a] {
                        writeln!(model_bc, "{}, {}, {}", n + 1, a + 1, a + 1).ok();
                    }
                }
            }
        }
        // nodes: the model's, then the reference nodes
        writeln!(out, "*NODE").ok();
        for (k, p) in x.iter().chain(&extra_nodes).enumerate() {
            writeln!(out, "{}, {:?}, {:?}, {:?}", k + 1, p[0], p[1], p[2]).ok();
        }
        out += &elements;
        out += &analytical;
        // materials
        for m in &self.material {
            writeln!(
                out,
                "*MATERIAL, NAME={}\n*DENSITY\n{:?}\n*ELASTIC\n{:?}, {:?}",
                deck_name(&m.name),
                m.density,
                m.young,
                m.poisson
            )
            .ok();
            if self.run.damping != 0.0 {
                writeln!(out, "*DAMPING, ALPHA={:?}", self.run.damping).ok();
            }
        }
        if self.run.damping != 0.0 && self.material.is_empty() {
            return unsupported(
                "run.damping without a material (a deck gives it per material)".into(),
            );
        }
        // boundaries: fixes as model data, displacements and loads in the step
        let mut amplitudes = String::new();
        for (k, b) in self.boundary.iter().enumerate() {
            let part = built
                .parts
                .iter()
                .find(|p| p.name == b.part)
                .expect("checked");
            let face = part.face(&b.face, x)?;
            let set = format!("B{}", k + 1);
            writeln!(out, "*NSET, NSET={set}").ok();
            out += &lines_of(
                &face
                    .nodes
                    .iter()
                    .map(|n| (n + 1).to_string())
                    .collect::<Vec<_>>(),
            );
            for d in &b.fix {
                let a = super::spec::axis_of(d).expect("checked") + 1;
                writeln!(model_bc, "{set}, {a}, {a}").ok();
            }
            if let Some(u) = b.displacement {
                let dirs: Vec<usize> = if b.directions.is_empty() {
                    (0..3).filter(|&a| u[a] != 0.0).collect()
                } else {
                    b.directions
                        .iter()
                        .map(|d| super::spec::axis_of(d).expect("checked"))
                        .collect()
                };
                writeln!(
                    amplitudes,
                    "*AMPLITUDE, NAME=RAMP{}, DEFINITION=SMOOTH STEP\n0.0, 0.0, {:?}, 1.0",
                    k + 1,
                    b.ramp
                )
                .ok();
                for a in dirs {
                    writeln!(
                        step_bc,
                        "*BOUNDARY, AMPLITUDE=RAMP{}\n{set}, {}, {}, {:?}",
                        k + 1,
                        a + 1,
                        a + 1,
                        u[a]
                    )
                    .ok();
                }
            }
            if let Some(load) = b.load {
                let total: f64 = face.areas.iter().sum();
                writeln!(step_bc, "*CLOAD").ok();
                for (&n, &ar) in face.nodes.iter().zip(&face.areas) {
                    for (d, l) in load.iter().enumerate().filter(|(_, l)| **l != 0.0) {
                        writeln!(step_bc, "{}, {}, {:?}", n + 1, d + 1, l * ar / total).ok();
                    }
                }
            }
        }
        out += &amplitudes;
        if !model_bc.is_empty() {
            writeln!(out, "*BOUNDARY").ok();
            out += &model_bc;
        }
        // contact: surfaces, interactions, pairs
        let (sfm, pairs) = contact::pairs(self, &built, &rigid_sets, &mut label, &mut surfaces)?;
        out += &sfm;
        out += &surfaces;
        out += &pairs;
        // the sets gravity acts on (model data, before the step)
        let r = &self.run;
        let gravity_set = if r.gravity == [0.0; 3] {
            None
        } else if deformable_sets.is_empty() {
            mass_sets.first().cloned()
        } else {
            writeln!(out, "*ELSET, ELSET=ALL-DEFORMABLE").ok();
            out += &lines_of(&deformable_sets);
            Some("ALL-DEFORMABLE".to_string())
        };
        // the step
        writeln!(
            out,
            "*STEP, NAME=RUN, NLGEOM={}",
            if r.nlgeom { "YES" } else { "NO" }
        )
        .ok();
        match r.dt {
            Some(dt) => writeln!(
                out,
                "*DYNAMIC, EXPLICIT, DIRECT USER CONTROL, SCALE FACTOR={:?}\n{dt:?}, {:?}",
                r.safety, r.end_time
            )
            .ok(),
            None => writeln!(
                out,
                "*DYNAMIC, EXPLICIT, SCALE FACTOR={:?}\n, {:?}",
                r.safety, r.end_time
            )
            .ok(),
        };
        writeln!(
            out,
            "*BULK VISCOSITY\n{:?}, {:?}",
            r.bulk_viscosity, r.bulk_viscosity_quadratic
        )
        .ok();
        if r.gravity != [0.0; 3] {
            let (m, n) = magnitude_direction(r.gravity);
            let Some(set) = gravity_set else {
                return unsupported(
                    "gravity on a scene without deformable parts or point masses".into(),
                );
            };
            writeln!(
                out,
                "*DLOAD\n{set}, GRAV, {m:?}, {:?}, {:?}, {:?}",
                n[0], n[1], n[2]
            )
            .ok();
        }
        out += &step_bc;
        writeln!(out, "*OUTPUT, HISTORY, FREQUENCY={}", r.output_every).ok();
        if r.vtk_every > 0 {
            writeln!(out, "*OUTPUT, FIELD, FREQUENCY={}", r.vtk_every).ok();
        }
        writeln!(out, "*END STEP").ok();
        Ok(out)
    }
}
