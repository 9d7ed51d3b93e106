//! The frame of the search kernels: coordinates are stored relative to an origin near the
//! master in f32, so a small mesh far from the model origin keeps its precision. The host
//! chooses the origin when a search is made resident and when its master has travelled far
//! (`search::SearchStage::rebase_if_far`); the device takes the master's box in that frame at
//! every global search (`schedule.wgsl`).

use crate::error::{Error, Result};

/// The origin of the frame for a master within `[lo, hi]` (model units) searched within
/// `radius`, in `dim` dimensions: the master's lower corner snapped down to a multiple of a
/// power of two q about 1/16 of the master's extent (of the radius, for a master of no extent),
/// so that coordinates with few significant bits (structured meshes, nodes exactly on edges)
/// stay exact in it and exact ties stay ties. It comes from the master's own extent, not from
/// the radius, so that a search radius far larger than the master (10⁶ model sizes, say) does
/// not turn the gaps into round-off.
pub fn origin(lo: [f64; 3], hi: [f64; 3], radius: f64, dim: u32) -> Result<[f64; 3]> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(Error::BadParameter {
            name: "search radius",
            value: radius.to_string(),
            expected: "must be finite and positive",
        });
    }
    let axes = dim as usize;
    let master_span = (0..axes).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let q = 2f64.powi(
        ((if master_span > 0.0 {
            master_span
        } else {
            radius
        }) / 16.0)
            .log2()
            .floor() as i32,
    );
    let mut frame = [0.0; 3];
    for a in 0..axes {
        frame[a] = (lo[a] / q).floor() * q;
    }
    Ok(frame)
}
