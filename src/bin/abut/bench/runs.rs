//! The runs the report is made of: the bench scene, its exact and f64 reference trajectories, one
//! configuration measured on one device, and the search alone against parry3d.

use super::*;

pub(crate) fn scene(c: &Config) -> abut::Result<BenchScene> {
    let side = ((c.slaves as f64 / 4.0).sqrt().round() as usize).max(4);
    let h = 1.0 / side as f64;
    let dt = 1e-3;
    // each mass falls a quarter of a facet per increment and lands between increments 2 and 10;
    // slow: rests on the plate, 0.1 % of a facet into it, and slides 1 % of a facet per increment
    let v0 = if c.slow { 0.0 } else { 0.25 * h / dt };
    let u = if c.slow {
        0.01 * h
    } else {
        (0.25 * h).min(0.4 / INCREMENTS as f64)
    } / dt;
    let plate = plate_quads(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?;
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let mut rng = SplitMix64::new(7);
    let travel = u * dt * INCREMENTS as f64;
    let mut pos = Vec::with_capacity(c.slaves);
    let mut z0 = Vec::with_capacity(c.slaves);
    let mut near = Vec::with_capacity(c.slaves);
    for k in 0..c.slaves {
        let fall = rng.range(2.0, 10.0);
        let z = if c.slow { -1e-3 * h } else { v0 * dt * fall };
        pos.push([rng.range(0.02, 0.98 - travel), rng.range(0.02, 0.98), z]);
        // the share c.near falls, spread evenly over the masses; the others hang at 1 + z,
        // hundreds of facets above the plate
        let falls = ((k + 1) as f64 * c.near).floor() > (k as f64 * c.near).floor();
        if !falls {
            pos[k][2] += 1.0;
        }
        near.push(falls);
        z0.push(pos[k][2]);
    }
    let range = model.add_nodes(&pos, &vec![1.0; c.slaves])?;
    let set = model.add_node_set(&range.to_vec())?;
    let enforce = match c.enforce {
        Enf::Penalty => Enforce::Penalty(Penalty {
            stiffness: Stiffness::Auto { scale: c.scale },
            ..Default::default()
        }),
        Enf::Kinematic => Enforce::Kinematic(Kinematic::default()),
    };
    let schedule = Schedule {
        interval: match c.interval {
            Interval::Every(n) => n,
            Interval::Budget => u32::MAX,
        },
        visit_every_slave: c.every_slave,
        ..Schedule::default_for(false)
    };
    model.add_pair(
        Pair::new(set, master)
            .search_radius(RADIUS * h)
            .enforce(enforce)
            .sliding(if c.small {
                Sliding::Small
            } else {
                Sliding::Finite
            })
            .schedule(schedule)
            .slave_order(c.slave_order),
    )?;
    Ok(BenchScene {
        model,
        first: range.start as usize,
        h,
        dt,
        v0,
        u,
        z0,
        near,
    })
}

/// The exact height at time t of a mass released at z0 falling at v0: free flight, then a
/// half-sine on the penalty spring of circular frequency ω and a rebound at v0 (penalty), or
/// a landing that stops it (kinematic).
pub(super) fn exact_z(z0: f64, v0: f64, omega: Option<f64>, t: f64) -> f64 {
    let t_hit = z0 / v0;
    if t <= t_hit {
        return z0 - v0 * t;
    }
    match omega {
        None => 0.0,
        Some(w) => {
            let s = t - t_hit;
            if s <= std::f64::consts::PI / w {
                -(v0 / w) * (w * s).sin()
            } else {
                v0 * (s - std::f64::consts::PI / w)
            }
        }
    }
}

/// The same central-difference run in f64 with exact geometry (flat plate z = 0, linear
/// spring k or a kinematic stop): the final heights.
pub(super) fn f64_reference(sc: &BenchScene, k: Option<f64>) -> Vec<f64> {
    sc.z0
        .iter()
        .map(|&z0| {
            let (mut z, mut v) = (z0, -sc.v0);
            for _ in 0..INCREMENTS {
                if let Some(k) = k {
                    v += sc.dt * k * (-z).max(0.0);
                }
                z += sc.dt * v;
                if k.is_none() && z < 0.0 {
                    z = 0.0;
                    v = 0.0;
                }
            }
            z
        })
        .collect()
}

/// Runs configuration `c` on `device`.
pub(super) fn measure(device: &Device, c: &Config) -> abut::Result<Row> {
    let sc = scene(c)?;
    let timed = device.enable_timestamps(true);
    let mut contact = Contact::new(device, &sc.model)?;
    let n = c.slaves;
    let mut x = sc.model.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    for vi in &mut v[sc.first..] {
        *vi = [sc.u, 0.0, -sc.v0];
    }
    // k of the automatic rule on a rigid master: AUTO_STIFFNESS·scale·m/dt² (m = 1)
    let k = abut::testing::abi::penalty::AUTO_STIFFNESS * c.scale / (sc.dt * sc.dt);
    let omega = (c.enforce == Enf::Penalty).then(|| k.sqrt());
    let mut touched = vec![false; n];
    let mut deepest = vec![0.0f64; n];
    let mut first_ms = 0.0;
    let mut traffic0 = None;
    let mut t_steady = Instant::now();
    for step in 0..INCREMENTS {
        let t = Instant::now();
        match c.enforce {
            Enf::Penalty => {
                let r = contact.penalty_step(&x, &v, sc.dt)?;
                for (j, i) in (sc.first..x.len()).enumerate() {
                    let f = r.forces[i];
                    if f[2] != 0.0 {
                        touched[j] = true;
                    }
                    for a in 0..3 {
                        v[i][a] += sc.dt * f[a];
                        x[i][a] += sc.dt * v[i][a];
                    }
                    deepest[j] = deepest[j].min(x[i][2]);
                }
            }
            Enf::Kinematic => {
                for i in sc.first..x.len() {
                    for a in 0..3 {
                        x[i][a] += sc.dt * v[i][a];
                    }
                }
                let before: Vec<f64> = v[sc.first..].iter().map(|w| w[2]).collect();
                contact.kinematic_step(&mut x, &mut v, &mut [], sc.dt)?;
                for (j, i) in (sc.first..x.len()).enumerate() {
                    if v[i][2] != before[j] {
                        touched[j] = true;
                    }
                    deepest[j] = deepest[j].min(x[i][2]);
                }
            }
        }
        if step == 0 {
            first_ms = 1e3 * t.elapsed().as_secs_f64();
            traffic0 = device.traffic();
            t_steady = Instant::now();
        }
    }
    let steady_ms = 1e3 * t_steady.elapsed().as_secs_f64() / (INCREMENTS - 1) as f64;
    let traffic = match (device.traffic(), traffic0) {
        (Some(a), Some(b)) => a.since(&b),
        _ => abut::Traffic::default(),
    };
    let per = (INCREMENTS - 1) as f64;
    let t_end = sc.dt * INCREMENTS as f64;
    let reference = f64_reference(&sc, omega.map(|_| k));
    let mut e = Errors::default();
    let (mut ke, mut ke_exact, mut ke0) = (0.0, 0.0, 0.0);
    for j in 0..n {
        let i = sc.first + j;
        let z = x[i][2];
        let ze = exact_z(sc.z0[j], sc.v0, omega, t_end);
        e.position = e.position.max((z - ze).abs() / sc.h);
        e.vs_f64 = e.vs_f64.max((z - reference[j]).abs() / sc.h);
        let (dv, dv_exact) = (
            v[i][2] + sc.v0,
            if omega.is_some() { 2.0 * sc.v0 } else { sc.v0 },
        );
        e.impulse = e.impulse.max((dv - dv_exact).abs() / dv_exact);
        match omega {
            Some(w) => {
                let pen = sc.v0 / w;
                e.penetration = e.penetration.max((-deepest[j] - pen).abs() / pen);
            }
            None => e.penetration = e.penetration.max(-deepest[j] / sc.h),
        }
        if !touched[j] || z < -2.0 * omega.map_or(sc.h, |w| sc.v0 / w) {
            e.missed += 1;
        }
        ke += 0.5 * v[i][2] * v[i][2];
        ke_exact += 0.5 * if omega.is_some() { sc.v0 * sc.v0 } else { 0.0 };
        ke0 += 0.5 * sc.v0 * sc.v0;
    }
    e.energy = (ke - ke_exact).abs() / ke0;
    Ok(Row {
        device: device.to_string(),
        backend: device.backend_name(),
        config: *c,
        label: c.label(),
        increments: INCREMENTS,
        first_ms,
        steady_ms,
        gpu_ms: timed.then(|| traffic.pass_ns.values().sum::<f64>() / per / 1e6),
        pass_ms: traffic
            .pass_ns
            .iter()
            .map(|(k, v)| (k.clone(), v / per / 1e6))
            .collect(),
        ns_per_slave: steady_ms * 1e6 / n as f64,
        errors: e,
        dispatches: traffic.total_dispatches() as f64 / per,
        uploaded_bytes: traffic.uploaded_bytes as f64 / per,
        read_back_bytes: traffic.read_back_bytes as f64 / per,
    })
}

/// A search-only row: abut's global search and parry3d's nearest-point queries on the same
/// plate (quads split into triangles) and the same points.
#[derive(Clone, Debug, Serialize)]
pub(super) struct SearchRow {
    pub(super) slaves: usize,
    pub(super) facets: usize,
    pub(super) who: String,
    pub(super) first_ms: f64,
    pub(super) steady_ms: f64,
    pub(super) ns_per_slave: f64,
    /// Largest difference of the distance found to parry's, in facet sizes.
    pub(super) max_distance_difference: f64,
}

pub(super) fn search_rows(devices: &[Device], slaves: usize) -> abut::Result<Vec<SearchRow>> {
    use parry3d::math::Vector as PVec;
    use parry3d::query::PointQuery;
    let sc = scene(&Config::base(slaves))?;
    let pos = sc.model.positions();
    let plate: Vec<[f64; 3]> = pos[..sc.first].to_vec();
    let side = ((plate.len() as f64).sqrt() as usize) - 1;
    let mut tris = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let id = |i: usize, j: usize| (j * (side + 1) + i) as u32;
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let radius = RADIUS * sc.h;
    let verts: Vec<PVec> = plate
        .iter()
        .map(|p| PVec::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let queries: Vec<PVec> = pos[sc.first..]
        .iter()
        .map(|p| PVec::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let run_parry = || {
        let mesh = parry3d::shape::TriMesh::new(verts.clone(), tris.clone()).expect("valid mesh");
        // the same question abut answers: the nearest point within the search radius
        queries
            .iter()
            .map(|&q| {
                mesh.project_local_point_with_max_dist(q, false, radius as f32)
                    .map_or(f64::INFINITY, |p| (p.point - q).length() as f64)
            })
            .collect::<Vec<f64>>()
    };
    let t = Instant::now();
    let parry = run_parry();
    let first = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _ = run_parry();
    let steady = t.elapsed().as_secs_f64();
    let mut rows = vec![SearchRow {
        slaves,
        facets: side * side,
        who: "parry3d 0.31 TriMesh (build + project, 1 CPU thread)".into(),
        first_ms: 1e3 * first,
        steady_ms: 1e3 * steady,
        ns_per_slave: 1e9 * steady / slaves as f64,
        max_distance_difference: 0.0,
    }];
    for d in devices {
        let pair = abut::PairId(0);
        let mut s = GlobalSearch::new(d, &sc.model, pair)?;
        let t = Instant::now();
        let r = s.run(pos)?;
        let first = t.elapsed().as_secs_f64();
        let reps = 3;
        let t = Instant::now();
        for _ in 0..reps {
            s.run(pos)?;
        }
        let steady = t.elapsed().as_secs_f64() / reps as f64;
        // found by both: the distances; by one side only: agreement when it is at the radius
        let mut worst = 0.0f64;
        for (j, hit) in r.contacts().enumerate() {
            let p = parry[j];
            let diff = match (hit, p.is_finite()) {
                (Some(h), true) => (h.distance - p).abs(),
                (Some(h), false) => (h.distance - radius).abs(),
                (None, true) => (p - radius).abs(),
                (None, false) => 0.0,
            };
            worst = worst.max(diff / sc.h);
        }
        rows.push(SearchRow {
            slaves,
            facets: side * side,
            who: format!("abut global search, {d}"),
            first_ms: 1e3 * first,
            steady_ms: 1e3 * steady,
            ns_per_slave: 1e9 * steady / slaves as f64,
            max_distance_difference: worst,
        });
    }
    Ok(rows)
}
