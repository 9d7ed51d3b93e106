//! Abaqus input decks (`.inp`): the mesh (`*NODE`, `*ELEMENT`, `*NSET`, `*ELSET` with
//! `GENERATE`, `*SURFACE` of element faces and of nodes, `*INCLUDE`), densities for lumped
//! masses (`*MATERIAL`, `*DENSITY`, `*ELASTIC`, `*SOLID SECTION`) and the contact definitions the
//! seed's "Input File Usage" lines show: `*CONTACT PAIR` (`INTERACTION=`, `SMALL SLIDING`,
//! `MECHANICAL CONSTRAINT=KINEMATIC|PENALTY`, `WEIGHT=`, `CPSET=`), `*SURFACE INTERACTION` with
//! `*FRICTION` and `*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD|LINEAR|EXPONENTIAL|TABULAR`,
//! `*CONTACT CONTROLS` (`GLOBTRKINC=`, `FASTLOCALTRK=`, `SCALE PENALTY=`, `CPSET=`) and
//! `*STEP, NLGEOM=YES|NO` (small against infinitesimal sliding), `*DYNAMIC, EXPLICIT`,
//! `*END STEP`, `*HEADING`. Any other keyword or option is an error naming it, its file and
//! line — never silently ignored.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::io::{ElementKind, MeshData, MeshElement};
use crate::model::Schedule;
use crate::model::{
    Enforce, Facet, Friction, Kinematic, Model, NodeSetId, Pair, PairId, Penalty,
    PressureOverclosure, Sliding, Stiffness, Surface, SurfaceId,
};

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
        "S3" | "S3R" | "R3D3" | "M3D3" => ElementKind::Tri3,
        "S4" | "S4R" | "R3D4" | "M3D4" | "M3D4R" => ElementKind::Quad4,
        "CPE3" | "CPS3" => ElementKind::Tri3In2d,
        "CPE4" | "CPE4R" | "CPS4" | "CPS4R" => ElementKind::Quad4In2d,
        "T2D2" | "R2D2" | "T3D2" | "RAX2" => ElementKind::Line2,
        other => {
            return Err(err(
                l,
                format!("*ELEMENT: TYPE={other} is not supported by abut (C3D4, C3D8(R/I), S3(R), S4(R), R3D3, R3D4, M3D3, M3D4(R), CPE3, CPS3, CPE4(R), CPS4(R), CAX3, CAX4(R), T2D2, R2D2, RAX2, T3D2)"),
            ))
        }
    };
    Ok((kind, false))
}

struct Parser {
    deck: Deck,
    /// Node label → index.
    node_index: BTreeMap<u64, u32>,
    /// Element label → index.
    element_index: BTreeMap<u64, u32>,
    /// Materials: name → density.
    densities: BTreeMap<String, f64>,
    /// (elset, material, thickness) of each *SOLID SECTION.
    sections: Vec<(String, String, f64, Line)>,
    /// Whether the deck's plane elements are axisymmetric (set by the first one).
    plane_axisymmetric: Option<bool>,
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

fn parse_lines(lines: &[Line]) -> Result<Deck> {
    let mut p = Parser {
        deck: Deck {
            nlgeom: true,
            ..Default::default()
        },
        node_index: BTreeMap::new(),
        element_index: BTreeMap::new(),
        densities: BTreeMap::new(),
        sections: Vec::new(),
        plane_axisymmetric: None,
    };
    let mut i = 0;
    let mut current_material: Option<String> = None;
    let mut current_interaction: Option<String> = None;
    let mut in_step = false;
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
        match kw.as_str() {
            "HEADING" => only(l, &kw, &opts, &[])?,
            "NODE" => {
                only(l, &kw, &opts, &["NSET"])?;
                let mut set = Vec::new();
                for d in data {
                    let f = fields(d);
                    if f.len() < 3 || f.len() > 4 {
                        return Err(err(d, "*NODE: expected label, x, y[, z]"));
                    }
                    let label: u64 = num(d, f[0], "node label")?;
                    let mut x = [0.0f64; 3];
                    for (a, s) in f[1..].iter().enumerate() {
                        x[a] = num(d, s, "coordinate")?;
                        if !x[a].is_finite() {
                            return Err(err(
                                d,
                                format!("node {label}: coordinate {s} is not finite"),
                            ));
                        }
                    }
                    if p.node_index.contains_key(&label) {
                        return Err(err(d, format!("node {label} is defined twice")));
                    }
                    let idx = p.deck.mesh.positions.len() as u32;
                    p.node_index.insert(label, idx);
                    p.deck.mesh.node_labels.push(label);
                    p.deck.mesh.positions.push(x);
                    set.push(idx);
                }
                if let Some(name) = opts.get("NSET") {
                    p.deck
                        .mesh
                        .node_sets
                        .entry(name.to_uppercase())
                        .or_default()
                        .extend(set);
                }
            }
            "ELEMENT" => {
                only(l, &kw, &opts, &["TYPE", "ELSET"])?;
                let Some(t) = opts.get("TYPE") else {
                    return Err(err(l, "*ELEMENT needs TYPE="));
                };
                let (kind, axisymmetric) = element_kind(l, t)?;
                let n = kind.node_count();
                let mut set = Vec::new();
                // an element's nodes may continue on the next line after a trailing comma
                let mut k = 0;
                while k < data.len() {
                    let d = &data[k];
                    let mut f: Vec<String> = fields(d).iter().map(|s| s.to_string()).collect();
                    while d.text.ends_with(',') && k + 1 < data.len() && f.len() < n + 1 {
                        k += 1;
                        f.extend(fields(&data[k]).iter().map(|s| s.to_string()));
                    }
                    if f.len() != n + 1 {
                        return Err(err(
                            d,
                            format!("*ELEMENT, TYPE={t}: expected a label and {n} nodes, found {} values", f.len()),
                        ));
                    }
                    let label: u64 = num(d, &f[0], "element label")?;
                    let mut nodes = Vec::with_capacity(n);
                    for s in &f[1..] {
                        nodes.push(p.node(d, num(d, s, "node label")?)?);
                    }
                    let mut sorted = nodes.clone();
                    sorted.sort_unstable();
                    if sorted.windows(2).any(|w| w[0] == w[1]) {
                        return Err(err(d, format!("element {label}: a node appears twice")));
                    }
                    if p.element_index.contains_key(&label) {
                        return Err(err(d, format!("element {label} is defined twice")));
                    }
                    if axisymmetric {
                        if let Some(&bad) = nodes
                            .iter()
                            .find(|&&n| p.deck.mesh.positions[n as usize][0] < 0.0)
                        {
                            return Err(err(
                                d,
                                format!(
                                    "element {label} (TYPE={t}): node {} is at x = {} < 0 (x is the radius of an axisymmetric element)",
                                    p.deck.mesh.node_labels[bad as usize],
                                    p.deck.mesh.positions[bad as usize][0]
                                ),
                            ));
                        }
                    }
                    if kind.is_planar()
                        && *p.plane_axisymmetric.get_or_insert(axisymmetric) != axisymmetric
                    {
                        return Err(err(
                            d,
                            format!("element {label} (TYPE={t}): a deck's plane elements are either all axisymmetric (CAX) or none (CPE, CPS)"),
                        ));
                    }
                    let idx = p.deck.mesh.elements.len() as u32;
                    p.element_index.insert(label, idx);
                    p.deck.mesh.elements.push(MeshElement {
                        kind,
                        nodes,
                        label,
                        axisymmetric,
                    });
                    set.push(idx);
                    k += 1;
                }
                if let Some(name) = opts.get("ELSET") {
                    p.deck
                        .mesh
                        .element_sets
                        .entry(name.to_uppercase())
                        .or_default()
                        .extend(set);
                }
            }
            "NSET" | "ELSET" => {
                let nodes = kw == "NSET";
                only(l, &kw, &opts, &[&kw, "GENERATE"])?;
                let Some(name) = opts.get(&kw) else {
                    return Err(err(l, format!("*{kw} needs {kw}=name")));
                };
                let mut set = Vec::new();
                for d in data {
                    let f = fields(d);
                    if opts.contains_key("GENERATE") {
                        if f.len() < 2 || f.len() > 3 {
                            return Err(err(d, "GENERATE: expected first, last[, increment]"));
                        }
                        let a: u64 = num(d, f[0], "first")?;
                        let b: u64 = num(d, f[1], "last")?;
                        let s: u64 = if f.len() == 3 {
                            num(d, f[2], "increment")?
                        } else {
                            1
                        };
                        if s == 0 || b < a {
                            return Err(err(
                                d,
                                "GENERATE: needs first ≤ last and a positive increment",
                            ));
                        }
                        let mut v = a;
                        while v <= b {
                            set.extend(p.members(d, &v.to_string(), nodes)?);
                            // the last label may be u64::MAX: stop instead of wrapping
                            let Some(next) = v.checked_add(s) else { break };
                            v = next;
                        }
                    } else {
                        for s in f {
                            set.extend(p.members(d, s, nodes)?);
                        }
                    }
                }
                let sets = if nodes {
                    &mut p.deck.mesh.node_sets
                } else {
                    &mut p.deck.mesh.element_sets
                };
                // each member once, in the order first given (a set that names itself, or
                // nodes listed twice, does not grow)
                let members = sets.entry(name.to_uppercase()).or_default();
                let mut seen: std::collections::HashSet<u32> = members.iter().copied().collect();
                members.extend(set.into_iter().filter(|m| seen.insert(*m)));
            }
            "SURFACE" => {
                only(l, &kw, &opts, &["NAME", "TYPE"])?;
                let Some(name) = opts.get("NAME") else {
                    return Err(err(l, "*SURFACE needs NAME="));
                };
                let ty = opts
                    .get("TYPE")
                    .map_or("ELEMENT".to_string(), |t| t.to_uppercase());
                let def = match ty.as_str() {
                    "ELEMENT" => {
                        let mut facets = Vec::new();
                        for d in data {
                            let f = fields(d);
                            if f.is_empty() || f.len() > 2 {
                                return Err(err(
                                    d,
                                    "*SURFACE, TYPE=ELEMENT: expected element or set[, face]",
                                ));
                            }
                            let els = p.members(d, f[0], false)?;
                            let face = f.get(1).map(|s| s.to_uppercase());
                            for e in els {
                                facets.extend(
                                    p.deck
                                        .mesh
                                        .element_faces(e, face.as_deref())
                                        .map_err(|m| err(d, m))?,
                                );
                            }
                        }
                        if data.iter().all(|d| fields(d).len() == 1) {
                            // no face given: the free faces of the elements named
                            facets = crate::io::free_faces(&facets);
                        }
                        SurfaceDef::Faces(facets)
                    }
                    "NODE" => {
                        let mut nodes = Vec::new();
                        let mut areas = Vec::new();
                        for d in data {
                            let f = fields(d);
                            if f.is_empty() || f.len() > 2 {
                                return Err(err(
                                    d,
                                    "*SURFACE, TYPE=NODE: expected node or set[, area]",
                                ));
                            }
                            let a: f64 = if f.len() == 2 {
                                num(d, f[1], "area")?
                            } else {
                                1.0
                            };
                            if !(a.is_finite() && a > 0.0) {
                                return Err(err(d, format!("area {a} must be positive")));
                            }
                            for n in p.members(d, f[0], true)? {
                                nodes.push(n);
                                areas.push(a);
                            }
                        }
                        SurfaceDef::Nodes(nodes, areas)
                    }
                    other => {
                        return Err(err(
                            l,
                            format!(
                                "*SURFACE: TYPE={other} is not supported by abut (ELEMENT, NODE)"
                            ),
                        ))
                    }
                };
                p.deck.surfaces.insert(name.to_uppercase(), def);
            }
            "MATERIAL" => {
                only(l, &kw, &opts, &["NAME"])?;
                let Some(name) = opts.get("NAME") else {
                    return Err(err(l, "*MATERIAL needs NAME="));
                };
                current_material = Some(name.to_uppercase());
            }
            "DENSITY" | "ELASTIC" => {
                only(l, &kw, &opts, &[])?;
                let Some(m) = current_material.clone() else {
                    return Err(err(l, format!("*{kw} outside a *MATERIAL")));
                };
                let Some(d) = data.first() else {
                    return Err(err(l, format!("*{kw} needs a data line")));
                };
                let f = fields(d);
                let v: f64 = num(d, f.first().copied().unwrap_or(""), &kw.to_lowercase())?;
                if !(v.is_finite() && v > 0.0) {
                    return Err(err(d, format!("*{kw}: {v} must be positive")));
                }
                if kw == "DENSITY" {
                    p.densities.insert(m, v);
                }
            }
            "SOLID SECTION" => {
                only(l, &kw, &opts, &["ELSET", "MATERIAL"])?;
                let (Some(e), Some(m)) = (opts.get("ELSET"), opts.get("MATERIAL")) else {
                    return Err(err(l, "*SOLID SECTION needs ELSET= and MATERIAL="));
                };
                let t = match data
                    .first()
                    .and_then(|d| fields(d).first().map(|s| (d, s.to_string())))
                {
                    Some((d, s)) => num(d, &s, "thickness")?,
                    None => 1.0,
                };
                p.sections
                    .push((e.to_uppercase(), m.to_uppercase(), t, l.clone()));
            }
            "SURFACE INTERACTION" => {
                only(l, &kw, &opts, &["NAME"])?;
                let Some(name) = opts.get("NAME") else {
                    return Err(err(l, "*SURFACE INTERACTION needs NAME="));
                };
                let name = name.to_uppercase();
                p.deck.interactions.insert(
                    name.clone(),
                    Interaction {
                        friction: 0.0,
                        behavior: Behavior::Hard,
                    },
                );
                current_interaction = Some(name);
            }
            "FRICTION" => {
                only(l, &kw, &opts, &[])?;
                let Some(name) = current_interaction.clone() else {
                    return Err(err(l, "*FRICTION outside a *SURFACE INTERACTION"));
                };
                let Some(d) = data.first() else {
                    return Err(err(l, "*FRICTION needs the friction coefficient"));
                };
                let mu: f64 = num(
                    d,
                    fields(d).first().copied().unwrap_or(""),
                    "friction coefficient",
                )?;
                if !(mu.is_finite() && mu >= 0.0) {
                    return Err(err(
                        d,
                        format!("friction coefficient {mu} must not be negative"),
                    ));
                }
                p.deck
                    .interactions
                    .get_mut(&name)
                    .expect("inserted")
                    .friction = mu;
            }
            "SURFACE BEHAVIOR" => {
                only(l, &kw, &opts, &["PRESSURE-OVERCLOSURE"])?;
                let Some(name) = current_interaction.clone() else {
                    return Err(err(l, "*SURFACE BEHAVIOR outside a *SURFACE INTERACTION"));
                };
                let po = opts
                    .get("PRESSURE-OVERCLOSURE")
                    .map_or("HARD".to_string(), |s| s.to_uppercase());
                let values: Vec<f64> = data
                    .iter()
                    .flat_map(|d| fields(d).into_iter().map(move |s| (d, s)))
                    .map(|(d, s)| num(d, s, "pressure-overclosure value"))
                    .collect::<Result<_>>()?;
                let at = data.first().unwrap_or(l);
                let behavior = match po.as_str() {
                    "HARD" => Behavior::Hard,
                    "LINEAR" if values.len() == 1 => Behavior::Linear(values[0]),
                    // Abaqus' data line: clearance c0 at zero pressure, pressure p0 at contact
                    "EXPONENTIAL" if values.len() == 2 => Behavior::Exponential {
                        clearance: values[0],
                        pressure: values[1],
                    },
                    "TABULAR" if values.len() >= 4 && values.len().is_multiple_of(2) => {
                        Behavior::Tabular(values.chunks(2).map(|c| (c[0], c[1])).collect())
                    }
                    "LINEAR" | "EXPONENTIAL" | "TABULAR" => {
                        return Err(err(at, format!("PRESSURE-OVERCLOSURE={po}: wrong number of values ({}): LINEAR takes the slope, EXPONENTIAL pressure and clearance, TABULAR pressure, overclosure pairs", values.len())))
                    }
                    other => {
                        return Err(err(l, format!("PRESSURE-OVERCLOSURE={other} is not supported by abut (HARD, LINEAR, EXPONENTIAL, TABULAR)")))
                    }
                };
                p.deck
                    .interactions
                    .get_mut(&name)
                    .expect("inserted")
                    .behavior = behavior;
            }
            "CONTACT PAIR" => {
                only(
                    l,
                    &kw,
                    &opts,
                    &[
                        "INTERACTION",
                        "SMALL SLIDING",
                        "MECHANICAL CONSTRAINT",
                        "WEIGHT",
                        "CPSET",
                    ],
                )?;
                let Some(inter) = opts.get("INTERACTION") else {
                    return Err(err(l, "*CONTACT PAIR needs INTERACTION="));
                };
                let penalty = match opts.get("MECHANICAL CONSTRAINT").map(|s| s.to_uppercase()) {
                    None => false,
                    Some(s) if s == "KINEMATIC" => false,
                    Some(s) if s == "PENALTY" => true,
                    Some(other) => {
                        return Err(err(l, format!("MECHANICAL CONSTRAINT={other} is not supported by abut (KINEMATIC, PENALTY)")))
                    }
                };
                let weight = match opts.get("WEIGHT") {
                    Some(w) => {
                        let w: f64 = num(l, w, "WEIGHT")?;
                        if !(0.0..=1.0).contains(&w) {
                            return Err(err(l, format!("WEIGHT={w} must lie in [0, 1]")));
                        }
                        Some(w)
                    }
                    None => None,
                };
                if data.is_empty() {
                    return Err(err(
                        l,
                        "*CONTACT PAIR needs a data line: slave surface, master surface",
                    ));
                }
                for d in data {
                    let f = fields(d);
                    if f.len() != 2 {
                        return Err(err(
                            d,
                            "*CONTACT PAIR: expected slave surface, master surface",
                        ));
                    }
                    p.deck.pairs.push(ContactPairDef {
                        slave: f[0].to_uppercase(),
                        master: f[1].to_uppercase(),
                        interaction: inter.to_uppercase(),
                        small_sliding: opts.contains_key("SMALL SLIDING"),
                        penalty,
                        weight,
                        cpset: opts.get("CPSET").map(|s| s.to_uppercase()),
                        line: d.number,
                    });
                }
            }
            "CONTACT CONTROLS" => {
                only(
                    l,
                    &kw,
                    &opts,
                    &["CPSET", "GLOBTRKINC", "FASTLOCALTRK", "SCALE PENALTY"],
                )?;
                let mut c = Controls {
                    cpset: opts.get("CPSET").map(|s| s.to_uppercase()),
                    ..Default::default()
                };
                if let Some(v) = opts.get("GLOBTRKINC") {
                    let n: u32 = num(l, v, "GLOBTRKINC")?;
                    if n == 0 {
                        return Err(err(l, "GLOBTRKINC must be positive"));
                    }
                    c.global_interval = Some(n);
                }
                if let Some(v) = opts.get("FASTLOCALTRK") {
                    c.wide_local = match v.to_uppercase().as_str() {
                        "NO" => true,
                        "YES" => false,
                        other => {
                            return Err(err(l, format!("FASTLOCALTRK={other}: expected YES or NO")))
                        }
                    };
                }
                if let Some(v) = opts.get("SCALE PENALTY") {
                    let s: f64 = num(l, v, "SCALE PENALTY")?;
                    if !(s.is_finite() && s > 0.0) {
                        return Err(err(l, format!("SCALE PENALTY={s} must be positive")));
                    }
                    c.penalty_scale = Some(s);
                }
                if !data.is_empty() {
                    return Err(err(
                        &data[0],
                        "*CONTACT CONTROLS takes no data lines in abut",
                    ));
                }
                p.deck.controls.push(c);
            }
            "STEP" => {
                only(l, &kw, &opts, &["NLGEOM", "NAME"])?;
                if in_step {
                    return Err(err(l, "*STEP inside a step (missing *END STEP)"));
                }
                in_step = true;
                p.deck.nlgeom = match opts.get("NLGEOM").map(|s| s.to_uppercase()) {
                    None => true,
                    Some(s) if s == "YES" => true,
                    Some(s) if s == "NO" => false,
                    Some(other) => {
                        return Err(err(l, format!("NLGEOM={other}: expected YES or NO")))
                    }
                };
            }
            "DYNAMIC" => {
                only(l, &kw, &opts, &["EXPLICIT"])?;
                if !opts.contains_key("EXPLICIT") {
                    return Err(err(
                        l,
                        "*DYNAMIC: abut reads explicit steps only (*DYNAMIC, EXPLICIT)",
                    ));
                }
                // positional data: initial increment (may be empty), time period
                if let Some(d) = data.first() {
                    let f: Vec<&str> = d.text.split(',').map(str::trim).collect();
                    if let Some(t) = f.get(1).filter(|s| !s.is_empty()) {
                        p.deck.time_period = Some(num(d, t, "time period")?);
                    }
                }
            }
            "END STEP" => {
                only(l, &kw, &opts, &[])?;
                if !in_step {
                    return Err(err(l, "*END STEP without *STEP"));
                }
                in_step = false;
            }
            other => {
                return Err(err(l, format!("keyword *{other} is not supported by abut")));
            }
        }
        if !matches!(
            kw.as_str(),
            "HEADING"
                | "NODE"
                | "ELEMENT"
                | "NSET"
                | "ELSET"
                | "SURFACE"
                | "CONTACT PAIR"
                | "DENSITY"
                | "ELASTIC"
                | "SOLID SECTION"
                | "FRICTION"
                | "SURFACE BEHAVIOR"
                | "DYNAMIC"
                | "CONTACT CONTROLS"
        ) && !data.is_empty()
        {
            return Err(err(&data[0], format!("*{kw} takes no data lines")));
        }
        i = j;
    }
    // lumped masses from the sections
    let mut masses = vec![0.0; p.deck.mesh.positions.len()];
    for (elset, material, thickness, l) in &p.sections {
        let Some(&rho) = p.densities.get(material) else {
            return Err(err(
                l,
                format!("*SOLID SECTION: material {material} has no *DENSITY"),
            ));
        };
        let Some(els) = p.deck.mesh.element_sets.get(elset) else {
            return Err(err(
                l,
                format!("*SOLID SECTION: element set {elset} is not defined"),
            ));
        };
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
            if !p.deck.surfaces.contains_key(s) {
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
    /// The model with every contact pair: nodes with the sections' lumped masses (`default_mass`
    /// where no section gives one, e.g. rigid surfaces), 2D when every element is planar.
    /// Penalty pairs take `LINEAR` slopes as stiffness per area, `EXPONENTIAL` and `TABULAR`
    /// as laws (hard: the automatic stiffness, scaled by `SCALE PENALTY`); kinematic pairs take
    /// non-hard behaviours as softened contact. `SMALL SLIDING` is small sliding with NLGEOM
    /// and infinitesimal without. `GLOBTRKINC` and `FASTLOCALTRK` set the pair's schedule.
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
            let SurfaceDef::Faces(master_faces) = &self.surfaces[&pair.master] else {
                return Err(Error::BadParameter {
                    name: "*CONTACT PAIR master surface",
                    value: pair.master.clone(),
                    expected: "an element-based surface (a node-based surface can only be a slave)",
                });
            };
            let master = out
                .model
                .add_surface(Surface::from_facets(master_faces.clone()))?;
            out.surfaces.insert(pair.master.clone(), master);
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
                    ..Default::default()
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
            let mut p = Pair::new(slave, master)
                .enforce(enforce)
                .friction(if inter.friction > 0.0 {
                    Friction::coulomb(inter.friction)
                } else {
                    Friction::Frictionless
                })
                .sliding(match (pair.small_sliding, self.nlgeom) {
                    (false, _) => Sliding::Finite,
                    (true, true) => Sliding::Small,
                    (true, false) => Sliding::Infinitesimal,
                });
            if controls.global_interval.is_some() || controls.wide_local {
                let d = Schedule::default_for(pair.slave == pair.master);
                p = p.schedule(Schedule {
                    interval: controls.global_interval.unwrap_or(d.interval),
                    wide_local: controls.wide_local,
                    ..d
                });
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
