//! A scene written as an Abaqus deck ([`Scene::to_inp`], `abut inp SCENE`): the built model —
//! every node and element as the scene meshed them, sections, rigid bodies with reference nodes,
//! point masses, surfaces (surface elements where a face is not an element's own), boundary
//! conditions, amplitudes, loads and contact pairs — and one `*DYNAMIC, EXPLICIT` step with the
//! run's controls. Read back by [`Scene::from_inp`], the deck gives the scene's history bit for
//! bit; what has no deck form (analytical rigid bodies, a search radius, contact safety, mesh
//! parts) is an error naming it.

use std::fmt::Write as _;

use crate::error::{Error, Result};
use crate::explicit::Element;
use crate::model::Facet;

use super::build::{Face, PartNodes};
use super::spec::Scene;

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
        // the faces each contact uses, to write as surfaces
        let mut surfaces = String::new();
        let mut surface_name = |part: &PartNodes,
                                face: &str,
                                f: &Face,
                                out: &mut String,
                                label: &mut usize,
                                rigid_set: Option<&str>|
         -> Result<String> {
            let name = format!("{}-{}", deck_name(&part.name), deck_name(face));
            if f.facets.is_empty() {
                writeln!(surfaces, "*SURFACE, NAME={name}, TYPE=NODE").ok();
                for (n, a) in f.nodes.iter().zip(&f.areas) {
                    writeln!(surfaces, "{}, {a:?}", n + 1).ok();
                }
                return Ok(name);
            }
            if let Some(set) = rigid_set {
                writeln!(surfaces, "*SURFACE, NAME={name}\n{set}, SPOS").ok();
                return Ok(name);
            }
            if f.facets.iter().all(|f| matches!(f, Facet::Segment(_))) {
                // a plane part's edges: its triangles' faces
                writeln!(surfaces, "*SURFACE, NAME={name}").ok();
                for facet in &f.facets {
                    let [a, b] = match *facet {
                        Facet::Segment(s) => s,
                        _ => [u32::MAX; 2],
                    };
                    let found = built.solver.elements.iter().enumerate().find_map(|(k, e)| {
                        let n = e.nodes();
                        (n.len() == 3)
                            .then(|| {
                                (0..3)
                                    .find(|&s| n[s] == a && n[(s + 1) % 3] == b)
                                    .map(|s| (k, s))
                            })
                            .flatten()
                    });
                    let Some((k, s)) = found else {
                        return unsupported(format!(
                            "face {face} of part {}: an edge that is no element's face",
                            part.name
                        ));
                    };
                    writeln!(surfaces, "{}, S{}", k + 1, s + 1).ok();
                }
                return Ok(name);
            }
            // a solid's or bar's face: surface elements on its nodes, in the face's order
            let set = format!("{name}-SFM");
            for (kind, arity) in [("SFM3D3", 3), ("SFM3D4", 4)] {
                let facets: Vec<&Facet> = f
                    .facets
                    .iter()
                    .filter(|f| f.nodes().len() == arity)
                    .collect();
                if facets.is_empty() {
                    continue;
                }
                writeln!(out, "*ELEMENT, TYPE={kind}, ELSET={set}").ok();
                for facet in facets {
                    *label += 1;
                    let nodes: Vec<String> =
                        facet.nodes().iter().map(|n| (n + 1).to_string()).collect();
                    writeln!(out, "{label}, {}", nodes.join(", ")).ok();
                }
            }
            if f.facets.iter().any(|f| f.nodes().len() == 3)
                && f.facets.iter().any(|f| f.nodes().len() == 4)
            {
                return unsupported(format!("face {face} of part {}: triangles and quadrilaterals together (their order would not survive)", part.name));
            }
            writeln!(out, "*SURFACE SECTION, ELSET={set}").ok();
            writeln!(surfaces, "*SURFACE, NAME={name}\n{set}, SPOS").ok();
            Ok(name)
        };
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
                        label += 1;
                        writeln!(elements, "*ELEMENT, TYPE=MASS, ELSET={set}-MASS\n{label}, {r}\n*MASS, ELSET={set}-MASS\n{:?}", spec.mass).ok();
                        label += 1;
                        let i = inertia;
                        writeln!(
                            elements,
                            "*ELEMENT, TYPE=ROTARYI, ELSET={set}-INERTIA\n{label}, {r}\n*ROTARY INERTIA, ELSET={set}-INERTIA\n{:?}, {:?}, {:?}, {:?}, {:?}, {:?}",
                            i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]
                        )
                        .ok();
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
                for (kind, group) in [("bar", 0), ("tri", 1), ("axi", 2), ("tet", 3)] {
                    let els: Vec<&&Element> = by_part[k]
                        .iter()
                        .filter(|e| match e {
                            Element::Bar { .. } => group == 0,
                            Element::Tri3 { hoop: None, .. } => group == 1,
                            Element::Tri3 { hoop: Some(_), .. } => group == 2,
                            Element::Tet4 { .. } => group == 3,
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
        let mut analytical = String::new();
        for r in &self.rigid {
            extra_nodes.push(r.point);
            let node = x.len() + extra_nodes.len();
            let name = deck_name(&r.name);
            let p = r.point;
            let rad = r.radius;
            writeln!(
                analytical,
                "*SURFACE, TYPE=REVOLUTION, NAME={name}\n{:?}, {:?}, {:?}, {:?}, {:?}, {:?}\nSTART, 0.0, {rad:?}\nCIRCL, {rad:?}, 0.0, 0.0, 0.0\nCIRCL, 0.0, {:?}, 0.0, 0.0",
                p[0], p[1], p[2], p[0], p[1], p[2] + 1.0, -rad
            )
            .ok();
            writeln!(
                analytical,
                "*RIGID BODY, REF NODE={node}, ANALYTICAL SURFACE={name}"
            )
            .ok();
            let i = r.inertia.unwrap_or_else(|| {
                let i = 0.4 * r.mass * r.radius * r.radius;
                [[i, 0.0, 0.0], [0.0, i, 0.0], [0.0, 0.0, i]]
            });
            label += 1;
            writeln!(analytical, "*ELEMENT, TYPE=MASS, ELSET={name}-MASS\n{label}, {node}\n*MASS, ELSET={name}-MASS\n{:?}", r.mass).ok();
            label += 1;
            writeln!(
                analytical,
                "*ELEMENT, TYPE=ROTARYI, ELSET={name}-INERTIA\n{label}, {node}\n*ROTARY INERTIA, ELSET={name}-INERTIA\n{:?}, {:?}, {:?}, {:?}, {:?}, {:?}",
                i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]
            )
            .ok();
            match r.motion.as_deref() {
                Some("fixed") => {
                    writeln!(model_bc, "{node}, ENCASTRE").ok();
                }
                Some("velocity") => {
                    writeln!(model_bc, "{node}, 4, 6").ok();
                    for (a, va) in r.velocity.iter().enumerate() {
                        writeln!(
                            step_bc,
                            "*BOUNDARY, TYPE=VELOCITY\n{node}, {}, {}, {va:?}",
                            a + 1,
                            a + 1
                        )
                        .ok();
                    }
                }
                _ => {
                    for f in &r.fix {
                        match super::spec::axis_of(f) {
                            Some(a) => writeln!(model_bc, "{node}, {}, {}", a + 1, a + 1).ok(),
                            None => writeln!(model_bc, "{node}, 4, 6").ok(),
                        };
                    }
                    for (a, va) in r.velocity.iter().enumerate().filter(|(_, va)| **va != 0.0) {
                        writeln!(
                            analytical,
                            "*INITIAL CONDITIONS, TYPE=VELOCITY\n{node}, {}, {va:?}",
                            a + 1
                        )
                        .ok();
                    }
                    let mut loads = Vec::new();
                    for (a, l) in r
                        .load
                        .unwrap_or_default()
                        .iter()
                        .enumerate()
                        .filter(|(_, l)| **l != 0.0)
                    {
                        loads.push(format!("{node}, {}, {l:?}", a + 1));
                    }
                    for (a, m) in r
                        .moment
                        .unwrap_or_default()
                        .iter()
                        .enumerate()
                        .filter(|(_, m)| **m != 0.0)
                    {
                        loads.push(format!("{node}, {}, {m:?}", a + 4));
                    }
                    if !loads.is_empty() {
                        writeln!(step_bc, "*CLOAD\n{}", loads.join("\n")).ok();
                    }
                }
            }
        }
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
        let mut pairs = String::new();
        let mut sfm = String::new();
        for (k, c) in self.contact.iter().enumerate() {
            if c.search_radius.is_some() {
                return unsupported(format!(
                    "[[contact]] {}: search_radius (no deck keyword)",
                    k + 1
                ));
            }
            let find = |name: &str| {
                self.part
                    .iter()
                    .position(|p| p.name == name)
                    .map(|i| (&built.parts[i], i))
            };
            let Some((sp, si)) = find(&c.slave) else {
                return unsupported(format!("[[contact]] {}: slave {}", k + 1, c.slave));
            };
            let sface = sp.face(&c.slave_face, x)?;
            if let Some(r) = self.rigid.iter().find(|r| r.name == c.master) {
                // an analytical master: hard kinematic contact, as abut's rigid pairs are
                let slave = surface_name(
                    sp,
                    &c.slave_face,
                    &sface,
                    &mut sfm,
                    &mut label,
                    rigid_sets[si].as_deref(),
                )?;
                writeln!(
                    pairs,
                    "*SURFACE INTERACTION, NAME=I{n}\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n*CONTACT PAIR, INTERACTION=I{n}, MECHANICAL CONSTRAINT=KINEMATIC\n{slave}, {}",
                    deck_name(&r.name),
                    n = k + 1
                )
                .ok();
                continue;
            }
            let Some((mp, mi)) = find(&c.master) else {
                return unsupported(format!("[[contact]] {}: master {}", k + 1, c.master));
            };
            let master_face = c.master_face.as_deref().expect("checked");
            let mface = mp.face(master_face, x)?;
            let slave = surface_name(
                sp,
                &c.slave_face,
                &sface,
                &mut sfm,
                &mut label,
                rigid_sets[si].as_deref(),
            )?;
            let master = surface_name(
                mp,
                master_face,
                &mface,
                &mut sfm,
                &mut label,
                rigid_sets[mi].as_deref(),
            )?;
            let kinematic = c.enforce.as_deref() == Some("kinematic");
            let inter = format!("I{}", k + 1);
            writeln!(pairs, "*SURFACE INTERACTION, NAME={inter}").ok();
            if c.friction > 0.0 {
                writeln!(pairs, "*FRICTION\n{:?}", c.friction).ok();
            }
            let slope = match (c.stiffness, c.stiffness_per_area) {
                (Some(kn), _) => {
                    let a = sface.areas.first().copied().unwrap_or(1.0);
                    if sface.areas.iter().any(|&x| x != a) || (kn / a) * a != kn {
                        return unsupported(format!(
                            "[[contact]] {}: an absolute stiffness on slaves of different areas",
                            k + 1
                        ));
                    }
                    Some(kn / a)
                }
                (_, Some(kp)) => Some(kp),
                _ => None,
            };
            match slope {
                Some(s) if !kinematic => writeln!(
                    pairs,
                    "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{s:?}"
                )
                .ok(),
                _ => writeln!(pairs, "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD").ok(),
            };
            if let Some(d) = c.damping {
                writeln!(
                    pairs,
                    "*CONTACT DAMPING, DEFINITION=CRITICAL DAMPING FRACTION\n{d:?}"
                )
                .ok();
            }
            let mut options = format!(
                "INTERACTION={inter}, MECHANICAL CONSTRAINT={}, CPSET=P{}",
                if kinematic { "KINEMATIC" } else { "PENALTY" },
                k + 1
            );
            match c.sliding.as_deref() {
                None | Some("finite") => {}
                Some(s) => {
                    if (s == "small") != self.run.nlgeom {
                        return unsupported(format!("[[contact]] {}: sliding = \"{s}\" with nlgeom = {} (a deck's small sliding is small with NLGEOM, infinitesimal without)", k + 1, self.run.nlgeom));
                    }
                    options += ", SMALL SLIDING";
                }
            }
            if let Some(w) = c.balanced {
                write!(options, ", WEIGHT={w:?}").ok();
            }
            writeln!(pairs, "*CONTACT PAIR, {options}\n{slave}, {master}").ok();
            let mut controls = Vec::new();
            if let Some(s) = c.penalty_scale.filter(|s| *s != 1.0) {
                controls.push(format!("SCALE PENALTY={s:?}"));
            }
            if let Some(i) = c.search_interval {
                controls.push(format!("GLOBTRKINC={i}"));
            }
            if !controls.is_empty() {
                writeln!(
                    pairs,
                    "*CONTACT CONTROLS, CPSET=P{}, {}",
                    k + 1,
                    controls.join(", ")
                )
                .ok();
            }
        }
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
