//! A deck's node output requests (`*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`), written at the
//! step's end as CSV with Abaqus' variable names: one file per request, one row per node,
//! `time,node,U1,U2,U3,…` (the node is the deck's label). The variables abut writes: `U`
//! (displacement), `V` (velocity, at the last half increment), `RF` (reaction: the force the
//! supports put on the node), `CF` (the concentrated load in force, amplitude applied) and
//! `COORD` (current position); the others are named in the deck notes as not written.

use std::io::Write as _;
use std::path::Path;

use super::build::PartNodes;
use crate::explicit::Solver;
use crate::io::inp::NodeOutputDef;

/// The variables abut writes, with what each is.
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
}

/// The step's requests as outputs: each request's nodes found in the parts (`home`: each deck
/// node's part and index there, none for a node in no part, `labels` the deck's labels), its
/// variables kept when abut writes them; what is left out is said in `notes`.
pub(super) fn requests(
    defs: &[NodeOutputDef],
    node_sets: &std::collections::BTreeMap<String, Vec<u32>>,
    home: &[Option<(usize, usize)>],
    labels: &[u64],
    notes: &mut Vec<String>,
) -> Vec<NodeOutput> {
    let mut outputs: Vec<NodeOutput> = Vec::new();
    for d in defs {
        let (variables, left): (Vec<String>, Vec<String>) = d
            .variables
            .iter()
            .cloned()
            .partition(|v| VARIABLES.iter().any(|(n, _)| n == v));
        if !left.is_empty() {
            notes.push(format!(
                "{}: *{}: {} not written (abut writes {})",
                d.at,
                d.keyword,
                left.join(", "),
                VARIABLES.map(|(n, _)| n).join(", ")
            ));
        }
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
        let stem = format!(
            "{}-{}",
            d.keyword.to_ascii_lowercase().replace(' ', "-"),
            d.nset.as_deref().unwrap_or("ALL")
        );
        let same = outputs.iter().filter(|o| o.file.starts_with(&stem)).count();
        let file = if same == 0 {
            format!("{stem}.csv")
        } else {
            format!("{stem}-{}.csv", same + 1)
        };
        notes.push(format!(
            "{}: *{}: {} of {} nodes at the step's end, in {file} (with --output)",
            d.at,
            d.keyword,
            variables.join(", "),
            nodes.len()
        ));
        outputs.push(NodeOutput {
            file,
            nodes,
            variables,
        });
    }
    outputs
}

/// Writes every request's file under `dir`: the solver's state now, displacements from `x0`.
pub(super) fn write(
    dir: &Path,
    outputs: &[NodeOutput],
    parts: &[PartNodes],
    solver: &Solver,
    x0: &[[f64; 3]],
) -> std::io::Result<()> {
    let factor = solver
        .load_factor
        .as_ref()
        .map_or(1.0, |f| f.value(solver.time));
    for o in outputs {
        let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join(&o.file))?);
        let mut header = vec!["time".to_string(), "node".to_string()];
        for v in &o.variables {
            header.extend((1..=3).map(|k| format!("{v}{k}")));
        }
        writeln!(w, "{}", header.join(","))?;
        for &(part, local, label) in &o.nodes {
            let n = parts[part].base + local;
            let mut row = vec![format!("{:e}", solver.time), label.to_string()];
            for v in &o.variables {
                let value: [f64; 3] = match v.as_str() {
                    "U" => std::array::from_fn(|a| solver.x[n][a] - x0[n][a]),
                    "V" => solver.v[n],
                    "RF" => solver.reaction[n],
                    "CF" => solver.loads[n].map(|l| factor * l),
                    _ => solver.x[n],
                };
                row.extend(value.iter().map(|x| format!("{x:e}")));
            }
            writeln!(w, "{}", row.join(","))?;
        }
        w.flush()?;
    }
    Ok(())
}
