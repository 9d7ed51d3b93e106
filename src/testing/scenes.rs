//! Scenes the tests share across targets (native, and the browser's wasm32, which cannot use
//! the native tests' helpers).

use std::ops::Range;

use crate::error::{Error, Result};
use crate::mesh::plate_quads;
use crate::{Device, Enforce, Model, Pair, Penalty, Stiffness, Surface};

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
