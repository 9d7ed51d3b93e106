//! Kinematic contact against the analytical surface of a rigid body: the slaves' resisting
//! forces act on the body as generalized forces, their masses are added to its generalized
//! mass, and the slaves follow the corrected body.

use super::{law_energy, push_target, pushed, SlaveCorrection};
use crate::error::{Error, Result};
use crate::geometry::V3;
use crate::kinematic::BodyState;
use crate::model::{Analytical, PressureOverclosure};

/// A slave the correction pushes: its place in the pair's whole slave list (the order every
/// sum over the pushed slaves runs in), its index among the slaves given here (none: another
/// rank's), its mass and area, the surface's normal at it, its overclosure and its arm from
/// the body's reference point (model frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pushed {
    /// The slave's place in the pair's whole slave list.
    pub key: u64,
    /// Its index among the slaves of this call, `None` for a slave held elsewhere.
    pub index: Option<usize>,
    /// Its lumped mass.
    pub mass: f64,
    /// Its tributary area.
    pub area: f64,
    /// The surface's unit normal at it (model frame).
    pub normal: V3<f64>,
    /// Its overclosure (positive = penetrating).
    pub overclosure: f64,
    /// Its arm from the body's reference point (model frame).
    pub arm: V3<f64>,
}

/// Every pushed slave of a pair, from this call's own (see [`rigid_pass_shared`]): the identity
/// in one process; across ranks, every rank's, gathered and ordered by [`Pushed::key`].
pub type ShareRows<'a> = dyn FnMut(Vec<Pushed>) -> Result<Vec<Pushed>> + 'a;

/// Rotates a body-frame vector into the model frame.
pub fn to_model(r: &[[f64; 3]; 3], v: V3<f64>) -> V3<f64> {
    V3::new(
        r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z,
        r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
        r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z,
    )
}

/// Rotates a model-frame vector into the body frame.
pub fn to_body(r: &[[f64; 3]; 3], v: V3<f64>) -> V3<f64> {
    V3::new(
        r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z,
        r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z,
        r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z,
    )
}

/// Solves the 6×6 system `a·u = b` by Gaussian elimination with partial pivoting.
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Result<[f64; 6]> {
    for col in 0..6 {
        let piv = (col..6)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        if a[piv][col].abs() == 0.0 {
            return Err(Error::BadParameter {
                name: "rigid body inertia",
                value: "singular".into(),
                expected: "a solvable generalized mass",
            });
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..6 {
            let f = a[r][col] / a[col][col];
            for c in col..6 {
                a[r][c] -= f * a[col][c];
            }
            b[r] -= f * b[col];
        }
    }
    let mut u = [0.0; 6];
    for r in (0..6).rev() {
        let mut s = b[r];
        for c in r + 1..6 {
            s -= a[r][c] * u[c];
        }
        u[r] = s / a[r][r];
    }
    Ok(u)
}

/// The kinematic correction of slaves against a rigid body's analytical surface. Corrects
/// `x`, `v` (slaves) and `body` in place and returns the per-slave corrections.
#[allow(clippy::too_many_arguments)]
pub fn rigid_pass(
    surface: &Analytical,
    mass: f64,
    inertia: &[[f64; 3]; 3],
    body: &mut BodyState,
    masses: &[f64],
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    slaves: &[u32],
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
) -> Result<Vec<SlaveCorrection>> {
    let keys: Vec<u64> = (0..slaves.len() as u64).collect();
    let (out, _) = rigid_pass_shared(
        surface,
        (mass, inertia),
        body,
        masses,
        (x, v),
        (slaves, &keys),
        areas,
        law,
        dt,
        &mut Ok,
    )?;
    Ok(out)
}

/// [`rigid_pass`] for some of a pair's slaves (`slaves`, each with its place in the pair's
/// whole slave list, `keys`), the others held elsewhere: `share` turns the pushed slaves here
/// into every pushed slave of the pair, ordered by key, so the body's correction is the one
/// all of them make together (the same bits wherever it is computed). Corrects `x`, `v` of
/// the slaves here and `body`; returns their corrections and the largest overclosure of any
/// pushed slave of the pair.
#[allow(clippy::too_many_arguments)]
pub fn rigid_pass_shared(
    surface: &Analytical,
    (mass, inertia): (f64, &[[f64; 3]; 3]),
    body: &mut BodyState,
    masses: &[f64],
    (x, v): (&mut [[f64; 3]], &mut [[f64; 3]]),
    (slaves, keys): (&[u32], &[u64]),
    areas: &[f64],
    law: Option<&PressureOverclosure>,
    dt: f64,
    share: &mut ShareRows,
) -> Result<(Vec<SlaveCorrection>, f64)> {
    let xb = V3::from_array(body.position);
    let r = body.rotation;
    let mut out = vec![SlaveCorrection::default(); slaves.len()];
    // the slaves pushed here, then every one of the pair's
    let mine: Vec<Pushed> = slaves
        .iter()
        .enumerate()
        .filter_map(|(k, &s)| {
            let p = V3::from_array(x[s as usize]);
            let (gap, nb) = surface.gap(to_body(&r, p - xb));
            pushed(law, -gap).then(|| Pushed {
                key: keys[k],
                index: Some(k),
                mass: masses[s as usize],
                area: areas[k],
                normal: to_model(&r, nb),
                overclosure: -gap,
                arm: p - xb,
            })
        })
        .collect();
    let candidates = share(mine)?;
    let deepest = candidates
        .iter()
        .map(|p| p.overclosure)
        .fold(0.0f64, f64::max);
    if candidates.is_empty() {
        return Ok((out, deepest));
    }
    let g = generalized_mass(mass, inertia, &r, &candidates);
    // the share of a push the contact transmits when every pushed slave pushes alike: the
    // body (slaves attached) takes back n_k·(Δa + Δα × r_k) of it
    let shares: Vec<f64> = if law.is_some() {
        let (mut f, mut m) = (V3::zero(), V3::zero());
        for p in &candidates {
            let ms = p.mass;
            f = f + p.normal * ms;
            m = m + p.arm.cross(p.normal * ms);
        }
        let u = solve6(g, [f.x, f.y, f.z, m.x, m.y, m.z])?;
        let (ua, ual) = (V3::new(u[0], u[1], u[2]), V3::new(u[3], u[4], u[5]));
        candidates
            .iter()
            .map(|p| (1.0 - p.normal.dot(ua + ual.cross(p.arm))).max(f64::MIN_POSITIVE))
            .collect()
    } else {
        vec![1.0; candidates.len()]
    };
    let (mut f, mut m) = (V3::zero(), V3::zero());
    let mut active = Vec::new();
    for (p, share) in candidates.into_iter().zip(shares) {
        let (n, h, rs, ms) = (p.normal, p.overclosure, p.arm, p.mass);
        let Some(target) = push_target(law, h, ms * share, p.area, dt) else {
            continue;
        };
        let fs = ms * (h - target) / (dt * dt);
        f = f + n * fs;
        m = m + rs.cross(n * fs);
        let Some(k) = p.index else { continue };
        out[k] = SlaveCorrection {
            overclosure: h,
            target,
            force: fs,
            normal: n.to_array(),
            energy: law.map_or(0.0, |l| law_energy(l, target) * p.area),
            applied: [0.0; 3],
        };
        active.push((k, slaves[k], n, h - target, rs));
    }
    let u = solve6(g, [f.x, f.y, f.z, m.x, m.y, m.z])?;
    let (da, dal) = (V3::new(u[0], u[1], u[2]), V3::new(u[3], u[4], u[5]));
    // reaction on the body is −f; the solve above is for the slaves' push; the body (with the
    // slaves attached) accelerates by −da, −dal
    let (da, dal) = (da * -1.0, dal * -1.0);
    for (k, s, n, push, rs) in &active {
        let d = *n * *push + (da + dal.cross(*rs)) * (dt * dt);
        out[*k].applied = (d * (masses[*s as usize] / (dt * dt))).to_array();
        for c in 0..3 {
            x[*s as usize][c] += d.to_array()[c];
            v[*s as usize][c] += d.to_array()[c] / dt;
        }
    }
    let dxb = da * (dt * dt);
    for c in 0..3 {
        body.position[c] += dxb.to_array()[c];
        body.velocity[c] += (da * dt).to_array()[c];
        body.angular_velocity[c] += (dal * dt).to_array()[c];
    }
    body.rotation = rotate(dal * (dt * dt), body.rotation);
    Ok((out, deepest))
}

/// The generalized mass (6×6, about the reference point, model frame) of a rigid body of
/// `mass` and body-frame `inertia` at rotation `r`, with the pushed slaves `attached` (their
/// mass and arm) added as point masses.
fn generalized_mass(
    mass: f64,
    inertia: &[[f64; 3]; 3],
    r: &[[f64; 3]; 3],
    attached: &[Pushed],
) -> [[f64; 6]; 6] {
    let mut m_add = 0.0;
    let mut s1 = V3::zero(); // Σ m r
    let mut i_add = [[0.0; 3]; 3];
    for p in attached {
        let (ms, rs) = (p.mass, &p.arm);
        m_add += ms;
        s1 = s1 + *rs * ms;
        let r2 = rs.length2();
        let ra = rs.to_array();
        for a in 0..3 {
            for b in 0..3 {
                i_add[a][b] += ms * (if a == b { r2 } else { 0.0 } - ra[a] * ra[b]);
            }
        }
    }
    let mut ib = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            // R I R^T
            ib[a][b] = (0..3)
                .map(|c| {
                    (0..3)
                        .map(|d| r[a][c] * inertia[c][d] * r[b][d])
                        .sum::<f64>()
                })
                .sum::<f64>()
                + i_add[a][b];
        }
    }
    let mt = mass + m_add;
    let sk = |v: V3<f64>| [[0.0, -v.z, v.y], [v.z, 0.0, -v.x], [-v.y, v.x, 0.0]];
    let ss = sk(s1);
    let mut a6 = [[0.0; 6]; 6];
    for i in 0..3 {
        a6[i][i] = mt;
        for j in 0..3 {
            a6[i][3 + j] = -ss[i][j];
            a6[3 + i][j] = ss[i][j];
            a6[3 + i][3 + j] = ib[i][j];
        }
    }
    a6
}

/// `exp(skew(θ))·R` (Rodrigues).
fn rotate(theta: V3<f64>, r: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let ang = theta.length2().sqrt();
    if ang == 0.0 {
        return r;
    }
    let k = theta * (1.0 / ang);
    let (s, c) = ang.sin_cos();
    let kk = [[0.0, -k.z, k.y], [k.z, 0.0, -k.x], [-k.y, k.x, 0.0]];
    let ka = k.to_array();
    let mut q = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            q[i][j] = if i == j { c } else { 0.0 } + s * kk[i][j] + (1.0 - c) * ka[i] * ka[j];
        }
    }
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = (0..3).map(|l| q[i][l] * r[l][j]).sum();
        }
    }
    out
}
