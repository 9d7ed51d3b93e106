//! A deck's output requests, written at each step's end as CSV with Abaqus' variable names: one
//! file per request, one row per node or element (the deck's label).
//!
//! - Nodes (`*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`): `time,node,U1,U2,U3,…` — `U`
//!   (displacement), `V` (velocity, at the last half increment), `RF` (reaction: the force the
//!   supports put on the node), `CF` (the concentrated load in force, amplitude applied),
//!   `COORD` (current position).
//! - Elements (`*EL PRINT`, `*ELEMENT OUTPUT`, `*EL FILE`): `time,element,S11,…` — `S` (the
//!   Cauchy stress, S11, S22, S33, S12, S13, S23; a plane quadrilateral's two triangles
//!   averaged by mass) and `ELSE` (the element's strain energy).
//! - Contact (`*CONTACT PRINT`, `*CONTACT OUTPUT`, `*CONTACT FILE`): `time,node,CPRESS,…` for
//!   every slave node — `CSTRESS` (CPRESS, CSHEAR1, CSHEAR2), `CDISP` (COPEN), `CSTATUS`
//!   (0 open, 1 stick, 2 slip).
//!
//! A `*NODE OUTPUT` after `*OUTPUT, HISTORY` is a time series instead: its rows at every history
//! row of its step. The time column is the run's total time (a quasi-static step's: the explicit
//! run's). The variables abut does not write are named in the deck notes.

use std::io::Write as _;
use std::path::Path;

use super::build::PartNodes;
use crate::explicit::Solver;
use crate::io::inp::NodeOutputDef;

/// The element variables abut writes, with their columns.
pub const ELEMENT_VARIABLES: [(&str, &[&str]); 2] = [
    ("S", &["S11", "S22", "S33", "S12", "S13", "S23"]),
    ("ELSE", &["ELSE"]),
];

/// One element output request as the run writes it.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementOutput {
    /// The file name under the output directory (`el-print-EALL.csv`).
    pub file: String,
    /// Each element: its part (scene order), its index among the part's elements, its deck
    /// label.
    pub elements: Vec<(usize, usize, u64)>,
    /// The variables, in the request's order (of [`ELEMENT_VARIABLES`]).
    pub variables: Vec<String>,
    /// When it is written: its step's end (total time).
    pub at_time: f64,
}

/// The contact variables abut writes, with their columns.
pub const CONTACT_VARIABLES: [(&str, &[&str]); 3] = [
    ("CSTRESS", &["CPRESS", "CSHEAR1", "CSHEAR2"]),
    ("CDISP", &["COPEN"]),
    ("CSTATUS", &["CSTATUS"]),
];

/// One contact output request as the run writes it: every slave node.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactOutput {
    /// The file name under the output directory (`contact-print-ALL.csv`).
    pub file: String,
    /// The variables, in the request's order (of [`CONTACT_VARIABLES`]).
    pub variables: Vec<String>,
    /// When it is written: its step's end (total time).
    pub at_time: f64,
}

/// The node variables abut writes, with what each is.
pub const VARIABLES: [(&str, &str); 5] = [
    ("U", "displacement"),
    ("V", "velocity"),
    ("RF", "reaction force"),
    ("CF", "concentrated load"),
    ("COORD", "current position"),
];

/// One node output request as the run writes it.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeOutput {
    /// The file name under the output directory (`node-print-NOUT.csv`).
    pub file: String,
    /// Each node: its part (scene order), its index in the part, its deck label.
    pub nodes: Vec<(usize, usize, u64)>,
    /// The variables, in the request's order (of [`VARIABLES`]).
    pub variables: Vec<String>,
    /// When it is written: its step's end (total time).
    pub at_time: f64,
    /// Its step's start (total time).
    pub from_time: f64,
    /// A history request (after `*OUTPUT, HISTORY`): a row at every history row of its step.
    pub history: bool,
}

/// A step's place on the run's time line, for its requests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct When {
    /// The step's number, in the file names when the deck has several.
    pub step: Option<usize>,
    /// Its start (total time).
    pub from: f64,
    /// When its requests are written: its end (a quasi-static step's: the hold's end).
    pub at: f64,
}

/// The variables of request `d` abut writes (of `names`); the others named in `notes`.
fn written(d: &NodeOutputDef, names: &[&str], notes: &mut Vec<String>) -> Vec<String> {
    let (kept, left): (Vec<String>, Vec<String>) = d
        .variables
        .iter()
        .cloned()
        .partition(|v| names.contains(&v.as_str()));
    if !left.is_empty() {
        notes.push(format!(
            "{}: *{}: {} not written (abut writes {})",
            d.at,
            d.keyword,
            left.join(", "),
            names.join(", ")
        ));
    }
    kept
}

/// The file of request `d` (of step `step` when the deck has several), numbered after the
/// `taken` files of the same stem: `node-print-NOUT.csv`, `el-print-EALL-step2-2.csv`, …
fn file_name<'a>(
    d: &NodeOutputDef,
    step: Option<usize>,
    taken: impl Iterator<Item = &'a String>,
) -> String {
    let stem = format!(
        "{}-{}{}",
        d.keyword.to_ascii_lowercase().replace(' ', "-"),
        d.nset.as_deref().unwrap_or("ALL"),
        step.map(|k| format!("-step{k}")).unwrap_or_default()
    );
    match taken.filter(|f| f.starts_with(&stem)).count() {
        0 => format!("{stem}.csv"),
        same => format!("{stem}-{}.csv", same + 1),
    }
}

/// A step's requests as outputs written at `at_time` (`step`: its number, in the file names,
/// when the deck has several): each request's nodes found in the parts (`home`: each deck
/// node's part and index there, none for a node in no part, `labels` the deck's labels), its
/// variables kept when abut writes them; what is left out is said in `notes`.
pub(super) fn requests(
    defs: &[NodeOutputDef],
    when: When,
    node_sets: &std::collections::BTreeMap<String, Vec<u32>>,
    home: &[Option<(usize, usize)>],
    labels: &[u64],
    notes: &mut Vec<String>,
) -> Vec<NodeOutput> {
    let mut outputs: Vec<NodeOutput> = Vec::new();
    for d in defs {
        let variables = written(d, &VARIABLES.map(|(n, _)| n), notes);
        let all: Vec<u32>;
        let set = match &d.nset {
            Some(name) => match node_sets.get(name) {
                Some(s) => s,
                None => {
                    notes.push(format!(
                        "{}: *{}: node set {name} is not defined; nothing written",
                        d.at, d.keyword
                    ));
                    continue;
                }
            },
            None => {
                all = (0..home.len() as u32).collect();
                &all
            }
        };
        let mut nodes = Vec::new();
        let mut outside = 0;
        for &n in set {
            match home[n as usize] {
                Some((part, local)) => nodes.push((part, local, labels[n as usize])),
                None => outside += 1,
            }
        }
        if outside > 0 {
            notes.push(format!(
                "{}: *{}: {outside} nodes of the set are on no element, body or mass; not written",
                d.at, d.keyword
            ));
        }
        if variables.is_empty() || nodes.is_empty() {
            continue;
        }
        let file = file_name(d, when.step, outputs.iter().map(|o| &o.file));
        let at = if d.history {
            "at every history row of the step".to_string()
        } else {
            format!("at the step's end ({:e})", when.at)
        };
        notes.push(format!(
            "{}: *{}: {} of {} nodes {at}, in {file} (with --output)",
            d.at,
            d.keyword,
            variables.join(", "),
            nodes.len()
        ));
        outputs.push(NodeOutput {
            file,
            nodes,
            variables,
            at_time: when.at,
            from_time: when.from,
            history: d.history,
        });
    }
    outputs
}

/// Each request due by the solver's time (its step ended) after the first `done`, as its file
/// name and text: the solver's state now, displacements from `x0`. The run keeps them and
/// writes them with its other outputs once it has succeeded.
pub(super) fn due(
    outputs: &[NodeOutput],
    done: usize,
    parts: &[PartNodes],
    solver: &Solver,
    x0: &[[f64; 3]],
) -> Vec<(String, String)> {
    let mut files = Vec::new();
    for o in outputs.iter().skip(done) {
        if solver.time < o.at_time * (1.0 - 1e-12) {
            break;
        }
        let text = header(o) + &rows(o, parts, solver, x0);
        files.push((o.file.clone(), text));
    }
    files
}

/// A node request's header line.
pub(super) fn header(o: &NodeOutput) -> String {
    let mut header = vec!["time".to_string(), "node".to_string()];
    for v in &o.variables {
        header.extend((1..=3).map(|k| format!("{v}{k}")));
    }
    header.join(",") + "\n"
}

/// A node request's rows now: the solver's state, displacements from `x0`.
pub(super) fn rows(
    o: &NodeOutput,
    parts: &[PartNodes],
    solver: &Solver,
    x0: &[[f64; 3]],
) -> String {
    let factor = solver
        .load_factor
        .as_ref()
        .map_or(1.0, |f| f.value(solver.time));
    // the curves' loads as they acted up to now (a step's at its end)
    let curves = solver.curve_loads_until_now();
    let mut text = String::new();
    for &(part, local, label) in &o.nodes {
        let Some(n) = parts.get(part).map(|p| p.base + local) else {
            continue;
        };
        let mut row = vec![format!("{:e}", solver.time), label.to_string()];
        for v in &o.variables {
            let value: [f64; 3] = match v.as_str() {
                "U" => std::array::from_fn(|a| solver.x[n][a] - x0[n][a]),
                "V" => solver.v[n],
                "RF" => solver.reaction[n],
                "CF" => std::array::from_fn(|a| {
                    factor * solver.loads[n][a] + curves.get(n).map_or(0.0, |c| c[a])
                }),
                _ => solver.x[n],
            };
            row.extend(value.iter().map(|x| format!("{x:e}")));
        }
        text += &row.join(",");
        text.push('\n');
    }
    text
}

/// Writes the kept files under `dir`.
pub(super) fn write(dir: &Path, files: &[(String, String)]) -> std::io::Result<()> {
    for (name, text) in files {
        let mut w = std::fs::File::create(dir.join(name))?;
        w.write_all(text.as_bytes())?;
    }
    Ok(())
}

/// A step's element requests as outputs written at `at_time` (as [`requests`]): each
/// request's deformable elements found in the parts (`home`: each deck element's part and index
/// there, none for an element that is not a deformable part's), its variables kept when abut
/// writes them.
pub(super) fn element_requests(
    defs: &[NodeOutputDef],
    when: When,
    element_sets: &std::collections::BTreeMap<String, Vec<u32>>,
    home: &[Option<(usize, usize)>],
    labels: &[u64],
    notes: &mut Vec<String>,
) -> Vec<ElementOutput> {
    let mut outputs: Vec<ElementOutput> = Vec::new();
    let names: Vec<&str> = ELEMENT_VARIABLES.iter().map(|(n, _)| *n).collect();
    for d in defs {
        let variables = written(d, &names, notes);
        let all: Vec<u32>;
        let set = match &d.nset {
            Some(name) => match element_sets.get(name) {
                Some(s) => s,
                None => {
                    notes.push(format!(
                        "{}: *{}: element set {name} is not defined; nothing written",
                        d.at, d.keyword
                    ));
                    continue;
                }
            },
            None => {
                all = (0..home.len() as u32).collect();
                &all
            }
        };
        let elements: Vec<(usize, usize, u64)> = set
            .iter()
            .filter_map(|&e| home[e as usize].map(|(p, k)| (p, k, labels[e as usize])))
            .collect();
        if elements.len() < set.len() {
            notes.push(format!(
                "{}: *{}: {} elements of the set are rigid or surface elements; not written",
                d.at,
                d.keyword,
                set.len() - elements.len()
            ));
        }
        if variables.is_empty() || elements.is_empty() {
            continue;
        }
        let file = file_name(d, when.step, outputs.iter().map(|o| &o.file));
        notes.push(format!(
            "{}: *{}: {} of {} elements at the step's end ({:e}), in {file} (with --output)",
            d.at,
            d.keyword,
            variables.join(", "),
            elements.len(),
            when.at
        ));
        outputs.push(ElementOutput {
            file,
            elements,
            variables,
            at_time: when.at,
        });
    }
    outputs
}

/// Each element request due by the solver's time after the first `done`, as its file name
/// and text (as [`due`]).
pub(super) fn elements_due(
    outputs: &[ElementOutput],
    done: usize,
    parts: &[PartNodes],
    solver: &Solver,
) -> Vec<(String, String)> {
    let mut files = Vec::new();
    let mut scratch: Vec<[f64; 3]> = Vec::new();
    for o in outputs.iter().skip(done) {
        if solver.time < o.at_time * (1.0 - 1e-12) {
            break;
        }
        let mut header = vec!["time".to_string(), "element".to_string()];
        for v in &o.variables {
            let columns = ELEMENT_VARIABLES
                .iter()
                .find(|(n, _)| n == v)
                .map_or(&[][..], |(_, c)| *c);
            header.extend(columns.iter().map(|c| c.to_string()));
        }
        let mut text = header.join(",") + "\n";
        for &(part, k, label) in &o.elements {
            let (first, count) = parts
                .get(part)
                .and_then(|p| p.deck_elements.get(k))
                .copied()
                .unwrap_or((0, 0));
            let mut row = vec![format!("{:e}", solver.time), label.to_string()];
            for v in &o.variables {
                if v == "S" {
                    // the mass-weighted mean of the element's solver elements
                    let mut s = [[0.0; 3]; 3];
                    let mut weight = 0.0;
                    for i in first..first + count {
                        let (m, si) = (solver.elements[i].mass().max(1e-300), solver.stress(i));
                        weight += m;
                        for r in 0..3 {
                            for c in 0..3 {
                                s[r][c] += m * si[r][c];
                            }
                        }
                    }
                    let s = s.map(|r| r.map(|v| v / weight.max(f64::MIN_POSITIVE)));
                    let abaqus = [s[0][0], s[1][1], s[2][2], s[0][1], s[0][2], s[1][2]];
                    row.extend(abaqus.iter().map(|x| format!("{x:e}")));
                } else {
                    if scratch.is_empty() {
                        scratch = vec![[0.0; 3]; solver.x.len()];
                    }
                    let w: f64 = (first..first + count)
                        .map(|i| {
                            solver.elements[i].add_internal_forces_with(
                                &solver.x,
                                &mut scratch,
                                solver.nlgeom,
                            )
                        })
                        .sum();
                    row.push(format!("{w:e}"));
                }
            }
            text += &row.join(",");
            text.push('\n');
        }
        files.push((o.file.clone(), text));
    }
    files
}

/// A step's contact requests as outputs written at `at_time` (every slave node; `pairs`:
/// whether the deck has contact pairs, else nothing is written and the notes say so).
pub(super) fn contact_requests(
    defs: &[NodeOutputDef],
    when: When,
    pairs: bool,
    notes: &mut Vec<String>,
) -> Vec<ContactOutput> {
    let names: Vec<&str> = CONTACT_VARIABLES.iter().map(|(n, _)| *n).collect();
    let mut outputs: Vec<ContactOutput> = Vec::new();
    for d in defs {
        let variables = written(d, &names, notes);
        if !pairs {
            notes.push(format!(
                "{}: *{}: the deck has no contact pair; nothing written",
                d.at, d.keyword
            ));
            continue;
        }
        if variables.is_empty() {
            continue;
        }
        let file = file_name(d, when.step, outputs.iter().map(|o| &o.file));
        notes.push(format!(
            "{}: *{}: {} of every slave node at the step's end ({:e}), in {file} (with --output)",
            d.at,
            d.keyword,
            variables.join(", "),
            when.at
        ));
        outputs.push(ContactOutput {
            file,
            variables,
            at_time: when.at,
        });
    }
    outputs
}

/// Whether a contact request after the first `done` falls due by `time`.
pub(super) fn contact_due(outputs: &[ContactOutput], done: usize, time: f64) -> bool {
    outputs
        .get(done)
        .is_some_and(|o| time >= o.at_time * (1.0 - 1e-12))
}

/// Each contact request due by `time` after the first `done`, from the contact `frame` of the
/// last increment, as its file name and text; `label` gives a model node's deck label.
pub(super) fn contact_files(
    outputs: &[ContactOutput],
    done: usize,
    time: f64,
    frame: &crate::io::vtk::Frame,
    label: &dyn Fn(usize) -> u64,
) -> Vec<(String, String)> {
    let mut files = Vec::new();
    for o in outputs.iter().skip(done) {
        if time < o.at_time * (1.0 - 1e-12) {
            break;
        }
        let mut header = vec!["time".to_string(), "node".to_string()];
        for v in &o.variables {
            let columns = CONTACT_VARIABLES
                .iter()
                .find(|(n, _)| n == v)
                .map_or(&[][..], |(_, c)| *c);
            header.extend(columns.iter().map(|c| c.to_string()));
        }
        let mut text = header.join(",") + "\n";
        for &n in &frame.slaves {
            let n = n as usize;
            let mut row = vec![format!("{time:e}"), label(n).to_string()];
            for v in &o.variables {
                match v.as_str() {
                    "CSTRESS" => row.extend(
                        [frame.cpress[n], frame.cshear1[n], frame.cshear2[n]]
                            .iter()
                            .map(|x| format!("{x:e}")),
                    ),
                    "CDISP" => row.push(format!("{:e}", frame.copen[n])),
                    _ => row.push(frame.cstatus[n].to_string()),
                }
            }
            text += &row.join(",");
            text.push('\n');
        }
        files.push((o.file.clone(), text));
    }
    files
}
