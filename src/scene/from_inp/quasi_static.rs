//! A deck's `*STATIC` step as explicit quasi-static: its pace from the model's fundamental
//! period.

use crate::error::Result;
use crate::explicit::Material;
use crate::io::inp::{Deck, StepDef};

use super::{refuse, Role};
use crate::scene::spec::QuasiStatic;

/// How a `*STATIC` step runs: the fundamental period estimated as 4·L/c over the deformable
/// elements' extent L and the slowest bar wave c = √(E/ρ), the ramp ten of them, the hold five,
/// damping α = 2π/period.
pub(super) fn quasi_static(
    deck: &Deck,
    role: &[Option<Role>],
    materials: &[(String, Material, f64)],
    step_period: f64,
    step: &StepDef,
) -> Result<QuasiStatic> {
    let mesh = &deck.mesh;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut slowest = f64::INFINITY;
    for (e, r) in mesh.elements.iter().zip(role) {
        let Some(Role::Deformable(m, _)) = r else {
            continue;
        };
        let mat = materials[*m].1;
        slowest = slowest.min((mat.young / mat.density).sqrt());
        for &n in &e.nodes {
            for d in 0..3 {
                lo[d] = lo[d].min(mesh.positions[n as usize][d]);
                hi[d] = hi[d].max(mesh.positions[n as usize][d]);
            }
        }
    }
    let extent = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    if !(extent > 0.0 && slowest.is_finite() && slowest > 0.0) {
        return refuse(
            &step.at,
            "a *STATIC step needs deformable elements (their extent and wave speed set its pace)",
        );
    }
    if !(step_period.is_finite() && step_period > 0.0) {
        return refuse(&step.at, "*STATIC: the time period must be positive");
    }
    let period = 4.0 * extent / slowest;
    Ok(QuasiStatic {
        step_period,
        fundamental_period: period,
        ramp_time: 10.0 * period,
        hold_time: 5.0 * period,
        damping: 2.0 * std::f64::consts::PI / period,
    })
}
