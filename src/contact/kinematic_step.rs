//! The kinematic increment: every kinematic pair's predictor/corrector (meshed, rigid and
//! anchored masters, friction), the corrections applied to the caller's arrays and bodies, and
//! the report and output variables it leaves.

use super::report::fast_slaves;
use super::*;

impl Contact {
    /// One kinematic increment (seed: "Kinematic contact algorithm"): `x` are the positions
    /// the host predicted for the end of the increment without contact and `v` the velocities
    /// that took it there (mid-increment, central differences); `bodies` the predicted states
    /// of the model's rigid bodies (index = [`BodyId`]). Every kinematic pair is searched at
    /// `x` and its penetrating slave nodes corrected (and the masters with them); `x`, `v` and
    /// `bodies` are corrected in place. Pairs are corrected in the order they were added.
    pub fn kinematic_step(
        &mut self,
        x: &mut [[f64; 3]],
        v: &mut [[f64; 3]],
        bodies: &mut [BodyState],
        dt: f64,
    ) -> Result<&KinematicReport> {
        positive_dt(dt)?;
        for (what, a) in [
            ("positions (one per model node)", x.len()),
            ("velocities (one per model node)", v.len()),
        ] {
            if a != self.n_nodes {
                return Err(Error::LengthMismatch {
                    what,
                    expected: self.n_nodes,
                    got: a,
                });
            }
        }
        validate_positions(x, 0, 3)?;
        validate_velocities(v)?;
        if let Some(r) = self.rigid.iter().find(|r| r.body.0 >= bodies.len()) {
            return Err(Error::IndexOutOfRange {
                what: "rigid body states".into(),
                index: r.body.0 as u64,
                len: bodies.len(),
            });
        }
        for r in &self.rigid {
            let b = &bodies[r.body.0];
            let values = b
                .position
                .iter()
                .chain(&b.velocity)
                .chain(&b.angular_velocity)
                .chain(b.rotation.iter().flatten());
            if let Some(v) = values.copied().find(|v| !v.is_finite()) {
                return Err(Error::BadParameter {
                    name: "rigid body state",
                    value: format!("{v} in body {}", r.body.0),
                    expected: "finite position, rotation, velocity and angular velocity",
                });
            }
        }
        let ke = |v: &[[f64; 3]], masses: &[f64]| -> f64 {
            v.iter()
                .zip(masses)
                .map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
                .sum()
        };
        let before = ke(v, &self.masses) + bodies_kinetic_energy(&self.rigid, bodies);
        let mut report = KinematicReport::default();
        let masses = &self.masses;
        for kr in &mut self.kinematic {
            let result = kr.search.step(x)?;
            let mut fast = |search: &GlobalSearch, r: &SearchResult, v: &[[f64; 3]]| {
                let order = 0..r.raw.len();
                let (count, top) = fast_slaves(kr.id, search, &r.raw, order, v, dt);
                report.fast_nodes += count;
                if let Some(t) = top.filter(|_| count > 0) {
                    if report
                        .fastest
                        .is_none_or(|f| t.distance / t.radius > f.distance / f.radius)
                    {
                        report.fastest = Some(t);
                    }
                }
            };
            fast(&kr.search, &result, v);
            let facets = facets_from(&result, &mut kr.behind.0);
            let back_facets = match &mut kr.back {
                Some((search, _, _)) => {
                    let r = search.step(x)?;
                    fast(search, &r, v);
                    Some(facets_from(&r, &mut kr.behind.1))
                }
                None => None,
            };
            let back = kr
                .back
                .as_ref()
                .zip(back_facets.as_ref())
                .map(|((search, surface, w), bf)| (bf, surface, *w, search.slaves()));
            let mut first: Option<Vec<SlaveCorrection>> = None;
            let mut normal_force: Vec<f64> = Vec::new();
            // hard contact is re-projected on the corrected geometry; a softened law is applied once
            let passes = if kr.law.is_some() || kr.anchored {
                1
            } else {
                PASSES
            };
            for _ in 0..passes {
                let mut dx = vec![[0.0; 3]; x.len()];
                let c = match &back {
                    None if kr.anchored => anchored_pass(
                        &kr.master,
                        masses,
                        &result,
                        &kr.areas,
                        kr.law.as_ref(),
                        dt,
                        &mut dx,
                    ),
                    None => meshed_pass(
                        &kr.master,
                        masses,
                        x,
                        &kr.slaves,
                        &facets,
                        &kr.areas,
                        kr.law.as_ref(),
                        dt,
                        &mut dx,
                    ),
                    Some((bf, surface, w, nodes)) => {
                        let mut dx_a = vec![[0.0; 3]; x.len()];
                        let c = meshed_pass(
                            &kr.master,
                            masses,
                            x,
                            &kr.slaves,
                            &facets,
                            &kr.areas,
                            kr.law.as_ref(),
                            dt,
                            &mut dx_a,
                        );
                        let mut dx_b = vec![[0.0; 3]; x.len()];
                        let areas_b: Vec<f64> =
                            nodes.iter().map(|&n| kr.master.tributary_area(n)).collect();
                        meshed_pass(
                            surface,
                            masses,
                            x,
                            nodes,
                            bf,
                            &areas_b,
                            kr.law.as_ref(),
                            dt,
                            &mut dx_b,
                        );
                        for i in 0..x.len() {
                            for a in 0..3 {
                                dx[i][a] = w * dx_a[i][a] + (1.0 - w) * dx_b[i][a];
                            }
                        }
                        c
                    }
                };
                for i in 0..x.len() {
                    for a in 0..3 {
                        x[i][a] += dx[i][a];
                        v[i][a] += dx[i][a] / dt;
                    }
                }
                // the normal force every pass transmitted to the slave (the friction limit's):
                // what the correction applied, not the push it aimed at, which the master's
                // motion takes its share of
                if normal_force.is_empty() {
                    normal_force = vec![0.0; c.len()];
                }
                for (f, ck) in normal_force.iter_mut().zip(&c) {
                    let along: f64 = (0..3).map(|a| ck.applied[a] * ck.normal[a]).sum();
                    *f += along.max(0.0);
                }
                first.get_or_insert(c);
            }
            let c = first.unwrap_or_default();
            let mut friction = None;
            if let (Some(mu), None, false) = (kr.friction, &back, kr.anchored) {
                let ft = friction_pass(
                    &kr.master,
                    masses,
                    x,
                    v,
                    &kr.slaves,
                    &facets,
                    &normal_force,
                    mu,
                    dt,
                );
                report.friction_force += ft
                    .force
                    .iter()
                    .map(|f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt())
                    .sum::<f64>();
                kr.dissipated += ft.dissipation;
                friction = Some(ft);
            }
            // what is left, measured on the corrected positions
            let left = if kr.anchored {
                // on the anchors' planes, moved with the corrected masters
                result
                    .contacts()
                    .zip(&kr.slaves)
                    .filter_map(|(cp, &s)| {
                        let cp = cp?;
                        let nodes = kr.master.facets[cp.facet as usize].nodes();
                        let mut x0 = [0.0; 3];
                        for (j, &n) in nodes.iter().enumerate() {
                            for a in 0..3 {
                                x0[a] += cp.weights[j] * x[n as usize][a];
                            }
                        }
                        Some(
                            -(0..3)
                                .map(|a| (x[s as usize][a] - x0[a]) * cp.normal[a])
                                .sum::<f64>(),
                        )
                    })
                    .fold(0.0f64, f64::max)
            } else {
                let mut probe = vec![[0.0; 3]; x.len()];
                let after = meshed_pass(
                    &kr.master, masses, x, &kr.slaves, &facets, &kr.areas, None, dt, &mut probe,
                );
                after.iter().map(|a| a.overclosure).fold(0.0f64, f64::max)
            };
            report.max_overclosure_after = report.max_overclosure_after.max(left);
            tally(&mut report, &c);
            fill_kinematic_output(&mut kr.output, &c, &kr.areas, Some(result));
            if let Some(ft) = &friction {
                add_kinematic_friction(&mut kr.output, ft, &kr.areas);
            }
            kr.output.frictional_dissipation = kr.dissipated;
        }
        for rr in &mut self.rigid {
            let body = &mut bodies[rr.body.0];
            let mut first: Option<Vec<SlaveCorrection>> = None;
            let passes = if rr.law.is_some() { 1 } else { PASSES };
            for _ in 0..passes {
                let c = rigid_pass(
                    &rr.spec.surface,
                    rr.spec.mass,
                    &rr.spec.inertia,
                    body,
                    masses,
                    x,
                    v,
                    &rr.slaves,
                    &rr.areas,
                    rr.law.as_ref(),
                    dt,
                )?;
                first.get_or_insert(c);
            }
            let c = first.unwrap_or_default();
            let mut xs = x.to_vec();
            let mut vs = v.to_vec();
            let mut probe = *body;
            let after = rigid_pass(
                &rr.spec.surface,
                rr.spec.mass,
                &rr.spec.inertia,
                &mut probe,
                masses,
                &mut xs,
                &mut vs,
                &rr.slaves,
                &rr.areas,
                None,
                dt,
            )?;
            let left = after.iter().map(|a| a.overclosure).fold(0.0f64, f64::max);
            report.max_overclosure_after = report.max_overclosure_after.max(left);
            tally(&mut report, &c);
            fill_kinematic_output(&mut rr.output, &c, &rr.areas, None);
        }
        report.kinetic_energy_change =
            ke(v, &self.masses) + bodies_kinetic_energy(&self.rigid, bodies) - before;
        // the corrections are abut's results: the input was finite
        for (what, values) in [("position", &*x), ("velocity", &*v)] {
            if let Some((node, value)) = first_non_finite(values) {
                return Err(Error::NonFiniteResult {
                    what: format!("kinematic contact's corrected {what}"),
                    node,
                    value,
                    cause: format!(
                        "the kinematic pass moved it from finite input (largest overclosure \
                         corrected this increment: {:e}; check the masses and the increment)",
                        report.max_overclosure
                    ),
                });
            }
        }
        self.kin_report = report;
        Ok(&self.kin_report)
    }
}

fn tally(report: &mut KinematicReport, c: &[SlaveCorrection]) {
    for s in c {
        if s.force > 0.0 {
            report.active += 1;
            report.total_force += s.force;
            report.max_overclosure = report.max_overclosure.max(s.overclosure);
        }
    }
}

/// Books a kinematic pair's friction in its outputs: CSHEAR1/2 (the friction force along the
/// contact's tangent directions over the tributary area), the slave's total force, CFS, and the
/// stick or slip state of each slave in contact.
fn add_kinematic_friction(o: &mut PairOutput, ft: &FrictionCorrection, areas: &[f64]) {
    for k in 0..o.force.len().min(ft.force.len()) {
        let f = ft.force[k];
        if o.cstatus[k] == Some(ContactStatus::Slip) && ft.stick[k] {
            o.cstatus[k] = Some(ContactStatus::Stick);
        }
        if f == [0.0; 3] {
            continue;
        }
        let (t1, t2) = crate::geometry::tangent_directions(V3::from_array(o.normal[k]));
        let f3 = V3::from_array(f);
        o.cshear1[k] = f3.dot(t1) / areas[k];
        o.cshear2[k] = f3.dot(t2) / areas[k];
        for a in 0..3 {
            o.force[k][a] += f[a];
            o.cfs[a] += f[a];
        }
    }
}

fn fill_kinematic_output(
    o: &mut PairOutput,
    c: &[SlaveCorrection],
    areas: &[f64],
    search: Option<SearchResult>,
) {
    o.cstatus = c
        .iter()
        .map(|s| {
            Some(if s.force > 0.0 {
                ContactStatus::Slip
            } else {
                ContactStatus::Open
            })
        })
        .collect();
    o.copen = c
        .iter()
        .map(|s| if s.force > 0.0 { -s.target } else { f64::NAN })
        .collect();
    let applied_normal =
        |s: &SlaveCorrection| (0..3).map(|a| s.applied[a] * s.normal[a]).sum::<f64>();
    o.cpress = c
        .iter()
        .zip(areas)
        .map(|(s, a)| applied_normal(s) / a)
        .collect();
    o.cshear1 = vec![0.0; c.len()];
    o.cshear2 = vec![0.0; c.len()];
    o.normal = c.iter().map(|s| s.normal).collect();
    o.force = c.iter().map(|s| s.applied).collect();
    o.cfn = [0.0; 3];
    for f in &o.force {
        for a in 0..3 {
            o.cfn[a] += f[a];
        }
    }
    o.cfs = [0.0; 3];
    o.contact_energy = c.iter().map(|s| s.energy).sum();
    o.frictional_dissipation = 0.0;
    o.search = search;
}

/// Kinetic energy of the rigid bodies the rigid pairs act on (each counted once), translation
/// and rotation.
fn bodies_kinetic_energy(rigid: &[RigidRun], bodies: &[BodyState]) -> f64 {
    let mut seen = std::collections::BTreeSet::new();
    rigid
        .iter()
        .filter(|r| seen.insert(r.body.0))
        .map(|r| {
            let b = &bodies[r.body.0];
            let (m, i, rot, w) = (
                r.spec.mass,
                &r.spec.inertia,
                &b.rotation,
                b.angular_velocity,
            );
            // ω·(R I Rᵀ)ω = (Rᵀω)·I(Rᵀω)
            let wb: Vec<f64> = (0..3)
                .map(|a| (0..3).map(|k| rot[k][a] * w[k]).sum())
                .collect();
            let rot_ke: f64 = (0..3)
                .map(|a| (0..3).map(|c| wb[a] * i[a][c] * wb[c]).sum::<f64>())
                .sum();
            0.5 * m * b.velocity.iter().map(|c| c * c).sum::<f64>() + 0.5 * rot_ke
        })
        .sum()
}
