//! The faces a scene's contacts use, written as deck surfaces: node surfaces with their areas,
//! a rigid part's own elements, a plane part's element edges, or surface elements (SFM3D3/4)
//! on a solid's or bar's face in the face's own order.

use std::fmt::Write as _;

use crate::error::Result;
use crate::model::Facet;
use crate::scene::build::{Built, Face, PartNodes};

use super::{deck_name, unsupported};

/// Writes face `face` of `part` (its nodes, facets and areas `f`) as a surface into `surfaces`
/// (surface elements into `out`, labelled on from `label`) and returns its name; `rigid_set`:
/// the element set of a rigid part's own facets.
#[allow(clippy::too_many_arguments)]
pub(super) fn surface(
    built: &Built,
    part: &PartNodes,
    face: &str,
    f: &Face,
    surfaces: &mut String,
    out: &mut String,
    label: &mut usize,
    rigid_set: Option<&str>,
) -> Result<String> {
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
            let nodes: Vec<String> = facet.nodes().iter().map(|n| (n + 1).to_string()).collect();
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
}
