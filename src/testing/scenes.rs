//! Scenes the tests share across targets (native, and the browser's wasm32, which cannot use
//! the native tests' helpers).

use std::ops::Range;

use crate::error::{Error, Result};
use crate::mesh::plate_quads;
use crate::{Device, Enforce, Friction, Model, Pair, Penalty, Sliding, Stiffness, Surface};

/// Rounds to f32 and back: positions both paths see exactly.
fn f32r(v: f64) -> f64 {
    v as f32 as f64
}

/// A bounce scene: `n` point masses (m = 1) 1–5 cm above a 10 × 10 rigid plate of quads (huge
/// masses), meant to fall at 1 m/s onto an undamped penalty spring (k = 4·10⁵: an elastic
/// bounce, 40 increments per contact): the model, the masses' node range, the increment (s).
pub fn bounce(n: usize) -> Result<(Model, Range<u32>, f64)> {
    let side = 10;
    let plate = plate_quads(side, side, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?;
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let drops: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let (a, b) = ((i * 7919) % 997, (i * 104_729) % 991);
            [
                f32r(0.02 + 0.96 * a as f64 / 997.0),
                f32r(0.02 + 0.96 * b as f64 / 991.0),
                f32r(0.01 + 0.04 * ((i * 31) % 101) as f64 / 101.0),
            ]
        })
        .collect();
    let range = model.add_nodes(&drops, &vec![1.0; n])?;
    let set = model.add_node_set(&range.to_vec())?;
    let pen = Penalty {
        stiffness: Stiffness::Absolute(4.0e5),
        damping: 0.0,
        ..Default::default()
    };
    model.add_pair(
        Pair::new(set, master)
            .search_radius(0.1)
            .enforce(Enforce::Penalty(pen)),
    )?;
    let dt = std::f64::consts::PI / (4.0e5f64).sqrt() / 40.0;
    Ok((model, range.start..range.end, dt))
}

/// The settings of the web page's scene (`web/`): beads poured onto an inclined rigid plate.
#[derive(Clone, Debug, PartialEq)]
pub struct InclineSettings {
    /// Beads dropped (point masses of 10 g), on a square grid.
    pub beads: usize,
    /// Coulomb friction coefficient between the beads and the plate (0: frictionless).
    pub friction: f64,
    /// The penalty stiffness as a multiple of the scene's 1,000 N/m.
    pub penalty_scale: f64,
    /// The sliding formulation of the pair (finite or small).
    pub sliding: Sliding,
    /// The plate's slope (degrees).
    pub slope_deg: f64,
}

impl Default for InclineSettings {
    fn default() -> Self {
        Self {
            beads: 1024,
            friction: 0.2,
            penalty_scale: 1.0,
            sliding: Sliding::Finite,
            slope_deg: 20.0,
        }
    }
}

/// The web page's scene, built: the model (the plate's nodes first, then the beads), what the
/// page draws and the increment.
pub struct Incline {
    /// The model: a rigid 2 m × 1 m plate of 32 × 16 quads at z = 0, beads above it.
    pub model: Model,
    /// The beads' node range.
    pub beads: Range<u32>,
    /// The plate's quads (node ids), for drawing.
    pub plate_quads: Vec<[u32; 4]>,
    /// Gravity in the model frame (m/s²): 9.81 tilted by the slope, downhill along +x.
    pub gravity: [f64; 3],
    /// The increment (s): 1/20 of a contact spring's period at the stiffest scale the page
    /// offers (4): ω·Δt = 0.31, inside the damped limit of 1.24.
    pub dt: f64,
    /// Each bead's mass (kg).
    pub bead_mass: f64,
}

/// Builds the web page's scene from `s`: beads of 10 g on a jittered grid 2–20 cm above the
/// uphill half of the plate, falling onto it with 30 % of critical contact damping, then
/// sliding downhill (friction below tan(slope)) or staying (above).
pub fn incline(s: &InclineSettings) -> Result<Incline> {
    // the increment below is fixed for the stiffest scale the page offers: a stiffer spring
    // (a query parameter, say) would run past its stable limit, so it is refused by name
    let checks: [(&'static str, f64, bool, &'static str); 4] = [
        (
            "beads",
            s.beads as f64,
            (1..=65_536).contains(&s.beads),
            "1 to 65,536",
        ),
        (
            "friction",
            s.friction,
            (0.0..=2.0).contains(&s.friction),
            "a Coulomb coefficient from 0 to 2",
        ),
        (
            "penalty_scale",
            s.penalty_scale,
            s.penalty_scale > 0.0 && s.penalty_scale <= 4.0,
            "above 0 and at most 4 (the increment is set for 4)",
        ),
        (
            "slope_deg",
            s.slope_deg,
            (0.0..=60.0).contains(&s.slope_deg),
            "0 to 60 degrees",
        ),
    ];
    for (name, value, ok, expected) in checks {
        if !ok {
            return Err(Error::BadParameter {
                name,
                value: value.to_string(),
                expected,
            });
        }
    }
    let (nx, ny, lx, ly) = (32, 16, 2.0, 1.0);
    let plate = plate_quads(nx, ny, lx, ly, 0.0, 0, &|_, _| 0.0);
    let mut model = Model::new_3d();
    model.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])?;
    let master = model.add_surface(Surface::quads(&plate.facets))?;
    let side = (s.beads as f64).sqrt().ceil().max(1.0) as usize;
    let drops: Vec<[f64; 3]> = (0..s.beads)
        .map(|i| {
            let (a, b) = (i % side, i / side);
            let jx = ((i * 7919) % 997) as f64 / 997.0 - 0.5;
            let jy = ((i * 104_729) % 991) as f64 / 991.0 - 0.5;
            [
                f32r(0.1 + 0.7 * (a as f64 + 0.5 + 0.4 * jx) / side as f64),
                f32r(0.1 + 0.8 * (b as f64 + 0.5 + 0.4 * jy) / side as f64),
                f32r(0.02 + 0.18 * ((i * 31) % 101) as f64 / 101.0),
            ]
        })
        .collect();
    let bead_mass = 0.01;
    let range = model.add_nodes(&drops, &vec![bead_mass; s.beads])?;
    let set = model.add_node_set(&range.to_vec())?;
    let k0 = 1000.0;
    let pen = Penalty {
        stiffness: Stiffness::Absolute(k0 * s.penalty_scale),
        damping: 0.3,
        ..Default::default()
    };
    let friction = if s.friction > 0.0 {
        Friction::coulomb(s.friction)
    } else {
        Friction::Frictionless
    };
    model.add_pair(
        Pair::new(set, master)
            .search_radius(0.25)
            .sliding(s.sliding)
            .friction(friction)
            .enforce(Enforce::Penalty(pen)),
    )?;
    let omega_max = (4.0 * k0 / bead_mass).sqrt();
    let dt = 2.0 * std::f64::consts::PI / omega_max / 20.0;
    let slope = s.slope_deg.to_radians();
    Ok(Incline {
        model,
        beads: range.start..range.end,
        plate_quads: plate.facets,
        gravity: [9.81 * slope.sin(), 0.0, -9.81 * slope.cos()],
        dt,
        bead_mass,
    })
}

/// A host program's own device buffers for `n` nodes, `vec4<f32>` each (STORAGE, COPY_DST,
/// COPY_SRC): positions, velocities, forces; an error on the CPU path.
pub fn node_buffers(device: &Device, n: usize) -> Result<[wgpu::Buffer; 3]> {
    let (d, _) = device.wgpu().ok_or_else(|| Error::BadParameter {
        name: "device",
        value: device.to_string(),
        expected: "a GPU device, whose buffers the caller's increment reads",
    })?;
    let make = |label| {
        d.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (n * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    };
    Ok([
        make("test positions"),
        make("test velocities"),
        make("test forces"),
    ])
}

/// The largest difference between two passes' hits of one increment (`a` against `b`, slave
/// by slave): an error naming the first slave whose facet, tracked node or slave differ; else
/// the largest difference of the closest point, gap, normal, distance and weights.
pub fn hits_difference(
    a: &[crate::abi::search::GpuHit],
    b: &[crate::abi::search::GpuHit],
) -> std::result::Result<f32, String> {
    if a.len() != b.len() {
        return Err(format!("{} hits against {}", a.len(), b.len()));
    }
    let mut worst = 0.0f32;
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        if (p.facet, p.node, p.slave) != (q.facet, q.node, q.slave) {
            return Err(format!(
                "slave {i}: facet {}, node {}, slave {} against facet {}, node {}, slave {}",
                p.facet, p.node, p.slave, q.facet, q.node, q.slave
            ));
        }
        let floats = |h: &crate::abi::search::GpuHit| {
            let mut v = [0.0f32; 12];
            v[..4].copy_from_slice(&h.point_gap);
            v[4..8].copy_from_slice(&h.normal_dist);
            v[8..].copy_from_slice(&h.weights);
            v
        };
        for (x, y) in floats(p).iter().zip(floats(q)) {
            worst = worst.max((x - y).abs());
        }
    }
    Ok(worst)
}

/// The bounce's start (`vec4<f32>` per node): the model's positions, and the masses in
/// `range` falling at 1 m/s.
pub fn bounce_start(model: &Model, range: &Range<u32>) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let x: Vec<[f32; 4]> = model
        .positions()
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect();
    let mut v = vec![[0.0f32; 4]; x.len()];
    for v in &mut v[range.start as usize..range.end as usize] {
        v[2] = -1.0;
    }
    (x, v)
}

/// A bounce run on the CPU path, increment by increment.
pub struct BounceRun {
    /// Each increment's contact forces (N), every node.
    pub forces: Vec<Vec<[f32; 4]>>,
    /// Each increment's hits, the passes' concatenated.
    pub hits: Vec<Vec<crate::abi::search::GpuHit>>,
    /// The positions after the last increment.
    pub positions: Vec<[f32; 4]>,
    /// The velocities after the last increment.
    pub velocities: Vec<[f32; 4]>,
}

/// Runs the bounce (`model`, masses `range`, increment `dt` in s) for `steps` increments on
/// the CPU path: the device-resident increment on host arrays, then the integrator's mirror.
pub fn bounce_cpu(model: &Model, range: &Range<u32>, dt: f64, steps: usize) -> Result<BounceRun> {
    let (mut x, mut v) = bounce_start(model, range);
    let n = x.len();
    let mut f = vec![[0.0f32; 4]; n];
    let mut c = crate::Contact::new(&Device::cpu(), model)?;
    let m32: Vec<f32> = model.masses().iter().map(|&m| m as f32).collect();
    let ip = crate::abi::integrate::IntegrateParams {
        acceleration: [0.0, 0.0, 0.0, dt as f32],
        first: range.start,
        count: range.end - range.start,
        n_nodes: n as u32,
        _pad: 0,
    };
    let mut run = BounceRun {
        forces: Vec::with_capacity(steps),
        hits: Vec::with_capacity(steps),
        positions: Vec::new(),
        velocities: Vec::new(),
    };
    for _ in 0..steps {
        let io = crate::ResidentIo::Cpu {
            positions: &x,
            velocities: &v,
            forces: &mut f,
        };
        c.encode_increment(io, dt)?;
        run.forces.push(f.clone());
        run.hits.push(c.pass_hits()?.concat());
        crate::cpu::integrate::integrate(&ip, &mut x, &mut v, &mut f, &m32);
    }
    run.positions = x;
    run.velocities = v;
    Ok(run)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The page's settings outside what its fixed increment allows are refused by name.
    #[test]
    fn the_page_scene_refuses_settings_by_name() {
        assert!(incline(&InclineSettings::default()).is_ok());
        for (bad, name) in [
            (
                InclineSettings {
                    penalty_scale: 8.0,
                    ..Default::default()
                },
                "penalty_scale",
            ),
            (
                InclineSettings {
                    penalty_scale: f64::NAN,
                    ..Default::default()
                },
                "penalty_scale",
            ),
            (
                InclineSettings {
                    beads: 0,
                    ..Default::default()
                },
                "beads",
            ),
            (
                InclineSettings {
                    friction: -0.1,
                    ..Default::default()
                },
                "friction",
            ),
        ] {
            let err = incline(&bad).err().expect("refused").to_string();
            assert!(err.contains(name), "{err}");
        }
    }
}
