//! Abaqus input decks (`.inp`): the mesh (`*NODE`, `*ELEMENT`, `*NSET`, `*ELSET` with
//! `GENERATE`, `*SURFACE` of element faces, of nodes, and analytical ones, `*INCLUDE`),
//! materials and sections (`*MATERIAL`, `*DENSITY`, `*ELASTIC`, `*DAMPING`, `*SOLID SECTION`,
//! `*SURFACE SECTION`), the contact definitions the seed's "Input File Usage" lines show
//! (`*CONTACT PAIR` with `INTERACTION=`, `SMALL SLIDING`, `MECHANICAL CONSTRAINT=KINEMATIC|
//! PENALTY`, `WEIGHT=`, `CPSET=`; `*SURFACE INTERACTION` with `*FRICTION`, `*CONTACT DAMPING`
//! and `*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD|LINEAR|EXPONENTIAL|TABULAR`; `*CONTACT
//! CONTROLS` with `GLOBTRKINC=`, `FASTLOCALTRK=`, `SCALE PENALTY=`, `CPSET=`) and what a deck
//! runs (analysis.rs: `*RIGID BODY`, `*MASS`, `*ROTARY INERTIA`, `*BOUNDARY`, `*INITIAL
//! CONDITIONS`, `*AMPLITUDE`, `*CLOAD`, `*DLOAD` gravity, `*STEP` with `*DYNAMIC, EXPLICIT`
//! or `*STATIC`, `*BULK VISCOSITY`, `*FIXED MASS SCALING`, `*OUTPUT`), which
//! [`crate::scene::Scene::from_inp`] runs. Print and file requests of other codes are read and
//! listed as not acted on; any other keyword or option is an error naming it, its file and line
//! — never silently ignored.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::io::{ElementKind, MeshData, MeshElement};
use crate::model::Schedule;
use crate::model::{
    Enforce, Facet, Friction, Kinematic, Model, NodeSetId, Pair, PairId, Penalty,
    PressureOverclosure, Sliding, Stiffness, Surface, SurfaceId,
};

mod analysis;
mod keywords;
mod to_model;

pub use analysis::{
    AmplitudeDef, Analysis, AnalyticalDef, At, BoundaryDef, BoundaryKind, CloadDef, GravityDef,
    MaterialDef, NodeOutputDef, RigidBodyDef, SectionDef, StepDef,
};
pub use to_model::{DeckModel, PairSettings};

/// `*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=…`.
#[derive(Clone, Debug, PartialEq)]
pub enum Behavior {
    /// Hard contact (the default).
    Hard,
    /// Linear: contact pressure per overclosure (penalty stiffness per unit area).
    Linear(f64),
    /// Exponential (data line: clearance c0, pressure p0).
    Exponential {
        /// Pressure at zero clearance.
        pressure: f64,
        /// Clearance at which the pressure is zero.
        clearance: f64,
    },
    /// Tabular: (pressure, overclosure) pairs as in the deck.
    Tabular(Vec<(f64, f64)>),
}

/// A `*SURFACE INTERACTION` with its sub-options.
#[derive(Clone, Debug, PartialEq)]
pub struct Interaction {
    /// Coulomb friction coefficient (`*FRICTION`), 0 if none.
    pub friction: f64,
    /// Pressure–overclosure.
    pub behavior: Behavior,
    /// `*CONTACT DAMPING, DEFINITION=CRITICAL DAMPING FRACTION`: the penalty springs' viscous
    /// damping as a fraction of critical (none: abut's default, Abaqus/Explicit's 3 %).
    pub damping: Option<f64>,
}

/// A `*CONTACT PAIR` data line with its options.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPairDef {
    /// Slave surface name (upper case).
    pub slave: String,
    /// Master surface name.
    pub master: String,
    /// Interaction name.
    pub interaction: String,
    /// `SMALL SLIDING`.
    pub small_sliding: bool,
    /// `MECHANICAL CONSTRAINT=PENALTY` (kinematic otherwise, Abaqus' default for pairs).
    pub penalty: bool,
    /// `WEIGHT=` of a balanced pair.
    pub weight: Option<f64>,
    /// `CPSET=` name.
    pub cpset: Option<String>,
    /// Deck line of the data line.
    pub line: usize,
}

/// `*CONTACT CONTROLS` settings (for all pairs, or for a `CPSET`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Controls {
    /// `CPSET=` they apply to (all pairs when `None`).
    pub cpset: Option<String>,
    /// `GLOBTRKINC=`: a global search every this many increments.
    pub global_interval: Option<u32>,
    /// `FASTLOCALTRK=NO`: the wider local search.
    pub wide_local: bool,
    /// `SCALE PENALTY=`: penalty scale factor.
    pub penalty_scale: Option<f64>,
}

/// A surface: element faces or nodes.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceDef {
    /// Element-based: facets (model node indices, outward).
    Faces(Vec<Facet>),
    /// Node-based: nodes and their areas.
    Nodes(Vec<u32>, Vec<f64>),
}

/// A parsed deck.
#[derive(Clone, Debug, Default)]
pub struct Deck {
    /// Nodes, elements and sets (names upper case).
    pub mesh: MeshData,
    /// Surfaces by name.
    pub surfaces: BTreeMap<String, SurfaceDef>,
    /// Interactions by name.
    pub interactions: BTreeMap<String, Interaction>,
    /// Contact pairs in deck order.
    pub pairs: Vec<ContactPairDef>,
    /// Contact controls in deck order.
    pub controls: Vec<Controls>,
    /// `*STEP, NLGEOM=` (Abaqus/Explicit's default is YES).
    pub nlgeom: bool,
    /// `*DYNAMIC, EXPLICIT` time period, when given.
    pub time_period: Option<f64>,
    /// Lumped nodal masses from `*SOLID SECTION` densities (0 where none).
    pub masses: Vec<f64>,
    /// `*HEADING`'s first data line, when given.
    pub heading: Option<String>,
    /// What the deck asks to run: materials, sections, rigid bodies, boundary conditions,
    /// loads, the step (read by [`crate::scene::Scene::from_inp`]).
    pub analysis: Analysis,
}

/// One logical line of a deck.
#[derive(Clone, Debug)]
struct Line {
    file: PathBuf,
    number: usize,
    text: String,
}

fn err(l: &Line, message: impl Into<String>) -> Error {
    Error::Parse {
        file: l.file.display().to_string(),
        line: l.number,
        message: message.into(),
    }
}

/// Reads `path` with its `*INCLUDE`s expanded (relative to the including file), comments and
/// blank lines dropped.
fn read_lines(path: &Path, depth: usize, out: &mut Vec<Line>) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    })?;
    lines_of(&text, path, depth, out)
}

fn lines_of(text: &str, path: &Path, depth: usize, out: &mut Vec<Line>) -> Result<()> {
    for (k, raw) in text.lines().enumerate() {
        let t = raw.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        let l = Line {
            file: path.to_path_buf(),
            number: k + 1,
            text: t.to_string(),
        };
        if t.starts_with('*') {
            let (kw, opts) = keyword(&l)?;
            if kw == "INCLUDE" {
                let Some(file) = opts.get("INPUT") else {
                    return Err(err(&l, "*INCLUDE needs INPUT=file"));
                };
                if depth > 16 {
                    return Err(err(&l, "*INCLUDE nested more than 16 deep"));
                }
                let target = path
                    .parent()
                    .unwrap_or(Path::new("."))
                    .join(file.trim_matches('"'));
                read_lines(&target, depth + 1, out)?;
                continue;
            }
        }
        out.push(l);
    }
    Ok(())
}

/// The keyword (upper case, spaces squeezed) and its options (NAME → value, "" for flags).
fn keyword(l: &Line) -> Result<(String, BTreeMap<String, String>)> {
    let mut parts = l.text[1..].split(',');
    let kw = parts
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase();
    if kw.is_empty() {
        return Err(err(l, "a keyword line without a keyword"));
    }
    let mut opts = BTreeMap::new();
    for p in parts {
        let p = p.trim();
        if p.is_empty() {
            continue;
        }
        let (k, v) = match p.split_once('=') {
            Some((k, v)) => (k.trim(), v.trim()),
            None => (p, ""),
        };
        let k = k
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_uppercase();
        opts.insert(k, v.to_string());
    }
    Ok((kw, opts))
}

fn fields(l: &Line) -> Vec<&str> {
    l.text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect()
}

fn num<T: std::str::FromStr>(l: &Line, s: &str, what: &str) -> Result<T> {
    s.parse::<T>()
        .map_err(|_| err(l, format!("{what}: expected a number, found {s:?}")))
}

fn only(l: &Line, kw: &str, opts: &BTreeMap<String, String>, allowed: &[&str]) -> Result<()> {
    if let Some(k) = opts.keys().find(|k| !allowed.contains(&k.as_str())) {
        return Err(err(
            l,
            format!("*{kw}: option {k} is not supported by abut"),
        ));
    }
    Ok(())
}

/// The shape of an element type, and whether it is axisymmetric.
fn element_kind(l: &Line, t: &str) -> Result<(ElementKind, bool)> {
    let axi = match t.to_uppercase().as_str() {
        "CAX3" => Some(ElementKind::Tri3In2d),
        "CAX4" | "CAX4R" => Some(ElementKind::Quad4In2d),
        _ => None,
    };
    if let Some(k) = axi {
        return Ok((k, true));
    }
    let kind = match t.to_uppercase().as_str() {
        "C3D4" => ElementKind::Tet4,
        "C3D8" | "C3D8R" | "C3D8I" => ElementKind::Hex8,
        "S3" | "S3R" | "R3D3" | "M3D3" | "SFM3D3" => ElementKind::Tri3,
        "S4" | "S4R" | "R3D4" | "M3D4" | "M3D4R" | "SFM3D4" | "SFM3D4R" => ElementKind::Quad4,
        "CPE3" | "CPS3" => ElementKind::Tri3In2d,
        "CPE4" | "CPE4R" | "CPS4" | "CPS4R" => ElementKind::Quad4In2d,
        "T2D2" | "R2D2" | "T3D2" | "RAX2" => ElementKind::Line2,
        other @ ("C3D20" | "C3D20R" | "C3D10" | "C3D10M" | "C3D15" | "C3D6" | "CAX6" | "CAX8"
        | "CAX8R" | "CPE6" | "CPE8" | "CPE8R" | "CPS6" | "CPS8" | "CPS8R" | "S8" | "S8R"
        | "STRI65" | "M3D8" | "M3D8R" | "M3D6") => {
            return Err(err(
                l,
                format!("*ELEMENT: TYPE={other} (a quadratic or wedge element) is not supported by abut: its elements are linear (C3D4, C3D8(R), CPE3, CPE4(R), CAX3, T3D2; Abaqus/Explicit has no C3D20 either)"),
            ))
        }
        other => {
            return Err(err(
                l,
                format!("*ELEMENT: TYPE={other} is not supported by abut (C3D4, C3D8(R/I), S3(R), S4(R), R3D3, R3D4, M3D3, M3D4(R), SFM3D3, SFM3D4(R), CPE3, CPS3, CPE4(R), CPS4(R), CAX3, CAX4(R), T2D2, R2D2, RAX2, T3D2)"),
            ))
        }
    };
    Ok((kind, false))
}

struct Parser {
    deck: Deck,
    /// The `*MATERIAL` the material keywords after it belong to.
    current_material: Option<String>,
    /// The `*SURFACE INTERACTION` the interaction keywords after it belong to.
    current_interaction: Option<String>,
    /// Inside `*STEP` … `*END STEP`.
    in_step: bool,
    /// The step's last `*OUTPUT` was `HISTORY` (the requests after it are history output).
    output_history: bool,
    /// Node label → index.
    node_index: BTreeMap<u64, u32>,
    /// Element label → index.
    element_index: BTreeMap<u64, u32>,
    /// Whether the deck's plane elements are axisymmetric (set by the first one).
    plane_axisymmetric: Option<bool>,
    /// The nodes of the `TYPE=MASS` and `TYPE=ROTARYI` elements of each `ELSET=`.
    point_sets: BTreeMap<String, Vec<u32>>,
}

impl Parser {
    fn node(&self, l: &Line, label: u64) -> Result<u32> {
        self.node_index.get(&label).copied().ok_or_else(|| {
            err(
                l,
                format!("node {label} is not defined (define *NODE first)"),
            )
        })
    }

    /// Members of a set named by `item`, or the single label `item` itself.
    fn members(&self, l: &Line, item: &str, nodes: bool) -> Result<Vec<u32>> {
        if let Ok(label) = item.parse::<u64>() {
            return if nodes {
                Ok(vec![self.node(l, label)?])
            } else {
                self.element_index
                    .get(&label)
                    .map(|&e| vec![e])
                    .ok_or_else(|| err(l, format!("element {label} is not defined")))
            };
        }
        let name = item.to_uppercase();
        let sets = if nodes {
            &self.deck.mesh.node_sets
        } else {
            &self.deck.mesh.element_sets
        };
        sets.get(&name).cloned().ok_or_else(|| {
            err(
                l,
                format!(
                    "{} set {name} is not defined",
                    if nodes { "node" } else { "element" }
                ),
            )
        })
    }
}

/// Parses the deck at `path` (with its `*INCLUDE`s).
pub fn read(path: &Path) -> Result<Deck> {
    let mut lines = Vec::new();
    read_lines(path, 0, &mut lines)?;
    parse_lines(&lines)
}

/// Parses deck text (`name` is used in messages; `*INCLUDE` paths are relative to it).
pub fn parse(text: &str, name: &Path) -> Result<Deck> {
    let mut lines = Vec::new();
    lines_of(text, name, 0, &mut lines)?;
    parse_lines(&lines)
}

/// Whether keyword `kw` has data lines.
fn takes_data(kw: &str) -> bool {
    !matches!(
        kw,
        "MATERIAL"
            | "SURFACE INTERACTION"
            | "END STEP"
            | "RIGID BODY"
            | "DAMPING"
            | "FIXED MASS SCALING"
            | "OUTPUT"
            | "SURFACE SECTION"
    )
}

fn parse_lines(lines: &[Line]) -> Result<Deck> {
    let mut p = Parser {
        deck: Deck {
            nlgeom: true,
            ..Default::default()
        },
        node_index: BTreeMap::new(),
        element_index: BTreeMap::new(),
        plane_axisymmetric: None,
        point_sets: BTreeMap::new(),
        current_material: None,
        current_interaction: None,
        in_step: false,
        output_history: false,
    };
    let mut i = 0;
    while i < lines.len() {
        let l = &lines[i];
        if !l.text.starts_with('*') {
            return Err(err(
                l,
                format!("a data line outside any keyword: {:?}", l.text),
            ));
        }
        let (kw, opts) = keyword(l)?;
        // the data lines of this keyword
        let mut j = i + 1;
        while j < lines.len() && !lines[j].text.starts_with('*') {
            j += 1;
        }
        let data = &lines[i + 1..j];
        if let Some(why) = keywords::ignored(&kw) {
            p.on_ignored(l, &kw, why);
            i = j;
            continue;
        }
        match kw.as_str() {
            "HEADING" => {
                only(l, &kw, &opts, &[])?;
                p.deck.heading = data.first().map(|d| d.text.clone());
            }
            "NODE" => p.on_node(l, &kw, &opts, data)?,
            "ELEMENT" => p.on_element(l, &kw, &opts, data)?,
            "NSET" | "ELSET" => p.on_nset(l, &kw, &opts, data)?,
            "SURFACE" => p.on_surface(l, &kw, &opts, data)?,
            "MATERIAL" => p.on_material(l, &kw, &opts, data)?,
            "DENSITY" | "ELASTIC" => p.on_density(l, &kw, &opts, data)?,
            "DAMPING" => p.on_damping(l, &kw, &opts, data)?,
            "SOLID SECTION" => p.on_solid_section(l, &kw, &opts, data)?,
            "SURFACE SECTION" => p.on_surface_section(l, &kw, &opts, data)?,
            "CONTACT DAMPING" => p.on_contact_damping(l, &kw, &opts, data)?,
            "SURFACE INTERACTION" => p.on_surface_interaction(l, &kw, &opts, data)?,
            "FRICTION" => p.on_friction(l, &kw, &opts, data)?,
            "SURFACE BEHAVIOR" => p.on_surface_behavior(l, &kw, &opts, data)?,
            "CONTACT PAIR" => p.on_contact_pair(l, &kw, &opts, data)?,
            "CONTACT CONTROLS" => p.on_contact_controls(l, &kw, &opts, data)?,
            "RIGID BODY" => p.on_rigid_body(l, &kw, &opts, data)?,
            "MASS" | "ROTARY INERTIA" => p.on_mass(l, &kw, &opts, data)?,
            "BOUNDARY" => p.on_boundary(l, &kw, &opts, data)?,
            "INITIAL CONDITIONS" => p.on_initial_conditions(l, &kw, &opts, data)?,
            "AMPLITUDE" => p.on_amplitude(l, &kw, &opts, data)?,
            "CLOAD" => p.on_cload(l, &kw, &opts, data)?,
            "DLOAD" => p.on_dload(l, &kw, &opts, data)?,
            "BULK VISCOSITY" => p.on_bulk_viscosity(l, &kw, &opts, data)?,
            "FIXED MASS SCALING" => p.on_fixed_mass_scaling(l, &kw, &opts, data)?,
            "OUTPUT" => p.on_output(l, &kw, &opts, data)?,
            "NODE PRINT" | "NODE OUTPUT" | "NODE FILE" | "EL PRINT" | "ELEMENT OUTPUT"
            | "EL FILE" | "CONTACT PRINT" | "CONTACT OUTPUT" | "CONTACT FILE" => {
                p.on_node_output(l, &kw, &opts, data)?
            }
            "STEP" => p.on_step(l, &kw, &opts, data)?,
            "DYNAMIC" | "STATIC" => p.on_dynamic(l, &kw, &opts, data)?,
            "END STEP" => p.on_end_step(l, &kw, &opts, data)?,
            other => {
                return Err(err(
                    l,
                    match keywords::not_modelled(other) {
                        Some(what) => {
                            format!("keyword *{other} ({what}) is not modelled by abut")
                        }
                        None => format!("keyword *{other} is not supported by abut"),
                    },
                ));
            }
        }
        if !takes_data(&kw) && !data.is_empty() {
            return Err(err(&data[0], format!("*{kw} takes no data lines")));
        }
        i = j;
    }
    // lumped masses from the sections
    let mut masses = vec![0.0; p.deck.mesh.positions.len()];
    for sec in &p.deck.analysis.sections {
        // a material without density lumps no mass (Deck::to_model gives such nodes its
        // default; Scene::from_inp refuses it in a dynamic step)
        let Some(rho) = p
            .deck
            .analysis
            .materials
            .get(&sec.material)
            .and_then(|m| m.density)
        else {
            continue;
        };
        let Some(els) = p.deck.mesh.element_sets.get(&sec.elset) else {
            return Err(Error::Parse {
                file: sec.at.file.clone(),
                line: sec.at.line,
                message: format!("*SOLID SECTION: element set {} is not defined", sec.elset),
            });
        };
        let thickness = &sec.thickness;
        for &e in els {
            let el = &p.deck.mesh.elements[e as usize];
            // an axisymmetric element's mass is per radian: its area times its centroid's radius
            let x = &p.deck.mesh.positions;
            let m = rho
                * el.measure(x)
                * if el.axisymmetric {
                    el.centroid_radius(x)
                } else if el.kind.is_planar() {
                    *thickness
                } else {
                    1.0
                };
            for &n in &el.nodes {
                masses[n as usize] += m / el.nodes.len() as f64;
            }
        }
    }
    p.deck.masses = masses;
    for pair in &p.deck.pairs {
        for s in [&pair.slave, &pair.master] {
            let analytical_master = s == &pair.master && p.deck.analysis.analytical.contains_key(s);
            if !p.deck.surfaces.contains_key(s) && !analytical_master {
                return Err(Error::Parse {
                    file: lines
                        .first()
                        .map_or(String::new(), |l| l.file.display().to_string()),
                    line: pair.line,
                    message: format!("*CONTACT PAIR: surface {s} is not defined"),
                });
            }
        }
        if !p.deck.interactions.contains_key(&pair.interaction) {
            return Err(Error::Parse {
                file: lines
                    .first()
                    .map_or(String::new(), |l| l.file.display().to_string()),
                line: pair.line,
                message: format!(
                    "*CONTACT PAIR: interaction {} is not defined",
                    pair.interaction
                ),
            });
        }
    }
    Ok(p.deck)
}
