//! A run's length checked before it starts: more than `run.max_increments` increments is
//! refused, naming what sets the increment — `run.dt`, or the element with the smallest stable
//! increment, by its label in the deck its part came from.

use super::build::PartNodes;
use super::Scene;
use crate::error::{Error, Result};
use crate::explicit::Solver;

/// Refuses a run that would take more than `run.max_increments` increments of `dt`, naming
/// what sets the increment: `run.dt`, or the element with the smallest stable increment (its
/// part, and its label in the deck a deck's part came from, else its index within the part) —
/// a sliver announces itself here, before the run, not as an estimate of 10¹¹ increments on a
/// progress bar. Every MPI rank builds the same model, so every rank refuses alike.
pub(super) fn check_length(
    scene: &Scene,
    solver: &Solver,
    parts: &[PartNodes],
    dt: f64,
) -> Result<()> {
    let increments = scene.run.end_time / dt;
    if !(increments > scene.run.max_increments as f64) {
        return Ok(());
    }
    let cause = match (scene.run.dt, solver.governing_element()) {
        (Some(fixed), _) => format!("run.dt = {}", super::check::num(fixed)),
        (None, Some((k, _))) => governing_name(scene, parts, k),
        (None, None) => "no element sets it".into(),
    };
    Err(Error::BadParameter {
        name: "run.end_time",
        value: format!(
            "{} over increments of {}: {} increments; {cause}",
            super::check::num(scene.run.end_time),
            super::check::num(dt),
            super::check::num(increments.ceil()),
        ),
        expected: "a run of at most run.max_increments increments (10^8 by default): \
                   remesh the element, or raise run.max_increments to run this long",
    })
}

/// Names solver element `k`, the one that sets the increment: its part and its deck label (a
/// deck's part) or its index within the part.
fn governing_name(scene: &Scene, parts: &[PartNodes], k: usize) -> String {
    let mut first = 0;
    let Some((j, p)) = parts.iter().enumerate().find(|(_, p)| {
        first += p.elements;
        k < first
    }) else {
        return format!("model element {k} sets it");
    };
    let deck = scene.part.get(j).and_then(|spec| spec.deck.as_ref());
    let label = deck.and_then(|piece| {
        let at = p
            .deck_elements
            .iter()
            .position(|&(f, n)| (f..f + n).contains(&k))?;
        piece.mesh.elements.get(at).map(|e| e.label)
    });
    match label {
        Some(label) => format!(
            "element {label} of part {} (model element {k}) sets it",
            p.name
        ),
        None => format!(
            "element {} of part {} (model element {k}) sets it",
            k + p.elements - first,
            p.name
        ),
    }
}
