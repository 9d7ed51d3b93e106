//! The architecture measured from the code (issue 32; docs/ARCHITECTURE.md states the figures):
//! import cycles between the top-level modules of `src/`, runtime downcasts between the
//! executors, the places that branch on GPU or CPU, and files over 600 lines. Each figure may
//! only fall: a change that adds a cycle, a downcast, a branch site or a long file without a
//! reason fails here, and a change that removes one should lower the bound below.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Lines that branch on a `Gpu(..)` / `Cpu(..)` executor variant outside `device/`.
const MAX_BRANCH_LINES: usize = 2;
/// The only files allowed to choose between the executors: the search's and the increment's
/// executor constructors.
const CHOICE_SITES: &[&str] = &["search/exec.rs", "contact/exec/mod.rs"];

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every source file of `src/`: its path under `src/` and its text without `//` comments.
fn files() -> Vec<(String, String, usize)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    sources(&root, &mut paths);
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let lines = text.lines().count();
            let code: String = text
                .lines()
                .map(|l| l.find("//").map_or(l, |i| &l[..i]))
                .collect::<Vec<_>>()
                .join("\n");
            let rel = p
                .strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (rel, code, lines)
        })
        .collect()
}

/// The top-level module of a file (`None` for `lib.rs` and the binaries).
fn top(rel: &str) -> Option<String> {
    let first = rel.split('/').next().unwrap();
    if first == "lib.rs" || first == "bin" {
        return None;
    }
    Some(first.trim_end_matches(".rs").to_string())
}

/// The top-level modules `code` names through `crate::` (paths and `use crate::{…}` groups).
fn references(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + 7..];
        if let Some(group) = rest.strip_prefix('{') {
            // the names at the group's first level
            let (mut depth, mut item, mut end) = (1, String::new(), group.len());
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            end = k;
                            break;
                        }
                    }
                    ',' if depth == 1 => {
                        out.insert(ident(item.trim()));
                        item.clear();
                    }
                    _ if depth == 1 => item.push(c),
                    _ => {}
                }
            }
            out.insert(ident(item.trim()));
            rest = &group[end..];
        } else {
            out.insert(ident(rest));
        }
    }
    // names that are items of the crate root, not modules
    out.retain(|m| !m.is_empty() && m.chars().next().unwrap().is_lowercase());
    out.remove("combined_increment");
    out
}

/// Strongly connected components of more than one module.
fn knots(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<BTreeSet<String>> {
    let nodes: BTreeSet<&String> = edges.keys().chain(edges.values().flatten()).collect();
    let reach = |from: &String| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for m in edges.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> =
        nodes.iter().map(|n| (*n, reach(n))).collect();
    let mut out: Vec<BTreeSet<String>> = Vec::new();
    for n in &nodes {
        let comp: BTreeSet<String> = nodes
            .iter()
            .filter(|m| reached[*n].contains(**m) && reached[**m].contains(*n))
            .map(|m| (*m).clone())
            .collect();
        if comp.len() > 1 && !out.contains(&comp) {
            out.push(comp);
        }
    }
    out
}

#[test]
fn the_architecture_measured_from_the_code() {
    let files = files();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, code, _) in &files {
        if let Some(m) = top(rel) {
            let e = edges.entry(m.clone()).or_default();
            e.extend(references(code).into_iter().filter(|t| *t != m));
        }
    }
    // abi is the floor: it depends on nothing else in the crate
    let abi = edges.get("abi").cloned().unwrap_or_default();
    assert!(
        abi.iter().all(|m| m == "error"),
        "abi/ imports {abi:?}: it holds the WGSL twins and nothing else"
    );
    let two: Vec<(String, String)> = edges
        .iter()
        .flat_map(|(a, bs)| bs.iter().map(move |b| (a.clone(), b.clone())))
        .filter(|(a, b)| a < b && edges.get(b).is_some_and(|s| s.contains(a)))
        .collect();
    let knots = knots(&edges);
    assert!(
        knots.is_empty(),
        "import cycles between top-level modules: {knots:?}"
    );
    let downcasts: usize = files
        .iter()
        .map(|(_, c, _)| {
            // the increment's old `mixed()` error and the accessors that handed out one
            // executor's concrete type
            ["mixed()", "(mixed)", "gpu_mut()", "cpu_mut()"]
                .iter()
                .map(|p| c.matches(p).count())
                .sum::<usize>()
                - c.matches("fn mixed()").count()
        })
        .sum();
    let branching: Vec<(&str, &str)> = files
        .iter()
        .filter(|(rel, _, _)| !rel.starts_with("device/"))
        .flat_map(|(rel, c, _)| c.lines().map(move |l| (rel.as_str(), l)))
        .filter(|(_, l)| {
            (l.contains("Gpu(") || l.contains("Cpu("))
                && (l.contains("=>") || l.contains("if let") || l.contains("let "))
        })
        .collect();
    let branch_lines = branching.len();
    for (rel, line) in &branching {
        assert!(
            CHOICE_SITES.contains(rel),
            "{rel} chooses between GPU and CPU (only {CHOICE_SITES:?} may): {}",
            line.trim()
        );
    }
    let long: Vec<(&str, usize)> = files
        .iter()
        .filter(|(_, _, n)| *n > 600)
        .map(|(rel, _, n)| (rel.as_str(), *n))
        .collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let unexplained: Vec<&str> = long
        .iter()
        .filter(|(rel, _)| {
            let text = std::fs::read_to_string(root.join(rel)).unwrap();
            !text
                .lines()
                .take_while(|l| l.starts_with("//!"))
                .any(|l| l.contains("Long file:"))
        })
        .map(|(rel, _)| *rel)
        .collect();
    let lines: usize = files.iter().map(|f| f.2).sum();
    eprintln!("src/: {} files, {lines} lines", files.len());
    eprintln!("two-module import cycles: {two:?}");
    eprintln!("knots (strongly connected modules): {knots:?}");
    eprintln!("runtime downcasts: {downcasts}; lines branching on Gpu/Cpu: {branch_lines}");
    eprintln!("files over 600 lines: {long:?}");
    eprintln!("of which without a stated reason: {unexplained:?}");
    assert_eq!(
        downcasts, 0,
        "runtime downcasts between the executors: none since the executor is chosen once"
    );
    assert!(
        branch_lines <= MAX_BRANCH_LINES,
        "{branch_lines} lines branch on Gpu/Cpu (at most {MAX_BRANCH_LINES})"
    );
    assert!(
        unexplained.is_empty(),
        "over 600 lines with no reason in the module doc (\"Long file: …\"): {unexplained:?}"
    );
}
