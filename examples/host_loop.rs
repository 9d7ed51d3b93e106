//! The host loop every language's example runs (examples/c, cpp, fortran, python), here in
//! Rust through the Rust API: the reference their forces are compared with, bit for bit.
//!
//! The model: a sheet of 8 × 8 point masses (spacing 0.1, mass 0.01) joined by springs
//! (stiffness 200, rest length 0.1) along the grid lines, thrown at (1, 0.25, −0.2) from 1 mm
//! above a fixed plate of 4 × 4 quads (span 2) under gravity 9.81; penalty contact with
//! Coulomb friction μ = 0.3 and half of critical damping (so that the sheet lands and slides
//! rather than bouncing); 600 increments of 1e-4. Each increment the host sums its own
//! forces (springs, then gravity), abut adds the contact forces into the same array, and the
//! host takes a central-difference step. The order of every floating-point operation is the
//! same in each language's loop, so each writes the same bytes.
//!
//! `cargo run --release --example host_loop -- [cpu|vulkan|gl|auto] [forces.bin]`: writes
//! every increment's forces (f64, xyz per node, little-endian) to `forces.bin` when given.

use abut::{Backend, Contact, Device, Enforce, Friction, Model, Pair, Penalty, Surface};
use std::io::Write;

/// Plate quads per side, sheet nodes per side.
const PLATE: usize = 4;
const SHEET: usize = 8;
const H: f64 = 0.1;
const KS: f64 = 200.0;
const G: f64 = 9.81;
const DT: f64 = 1e-4;
const STEPS: usize = 600;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let device = match args.get(1).map(String::as_str).unwrap_or("cpu") {
        "cpu" => Device::cpu(),
        "vulkan" => Device::choose(Backend::Vulkan, None)?,
        "gl" => Device::choose(Backend::Gl, None)?,
        _ => Device::auto()?,
    };
    let mut out = match args.get(2) {
        Some(p) => Some(std::io::BufWriter::new(std::fs::File::create(p)?)),
        None => None,
    };

    // the model: plate nodes, then sheet nodes
    let mut x: Vec<[f64; 3]> = Vec::new();
    let mut m: Vec<f64> = Vec::new();
    for j in 0..=PLATE {
        for i in 0..=PLATE {
            x.push([-1.0 + 0.5 * i as f64, -1.0 + 0.5 * j as f64, 0.0]);
            m.push(1.0);
        }
    }
    let mut quads = Vec::new();
    for j in 0..PLATE as u32 {
        for i in 0..PLATE as u32 {
            let a = j * (PLATE as u32 + 1) + i;
            quads.push([a, a + 1, a + PLATE as u32 + 2, a + PLATE as u32 + 1]);
        }
    }
    let first = x.len();
    for j in 0..SHEET {
        for i in 0..SHEET {
            x.push([H * i as f64 - 0.35, H * j as f64 - 0.35, 0.001]);
            m.push(0.01);
        }
    }
    let n = x.len();
    let sheet: Vec<u32> = (first as u32..n as u32).collect();
    // springs: along x (row by row), then along y
    let mut springs = Vec::new();
    for j in 0..SHEET {
        for i in 0..SHEET - 1 {
            springs.push((first + j * SHEET + i, first + j * SHEET + i + 1));
        }
    }
    for j in 0..SHEET - 1 {
        for i in 0..SHEET {
            springs.push((first + j * SHEET + i, first + (j + 1) * SHEET + i));
        }
    }

    let mut model = Model::new_3d();
    model.add_nodes(&x, &m)?;
    let plate = model.add_surface(Surface::quads(&quads))?;
    let slaves = model.add_node_set(&sheet)?;
    let penalty = Penalty {
        damping: 0.5,
        ..Penalty::default()
    };
    model.add_pair(
        Pair::new(slaves, plate)
            .friction(Friction::coulomb(0.3))
            .enforce(Enforce::Penalty(penalty)),
    )?;
    let mut contact = Contact::new(&device, &model)?;

    let mut v = vec![[0.0; 3]; n];
    for k in first..n {
        v[k] = [1.0, 0.25, -0.2];
    }
    let (mut touching, mut most) = (0, 0);
    for _ in 0..STEPS {
        // the host's forces: springs (each + onto i, then each − onto j), then gravity
        let mut f = vec![[0.0; 3]; n];
        let mut fs = Vec::with_capacity(springs.len());
        for &(i, j) in &springs {
            let d = [x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let s = KS * (l - H) / l;
            fs.push([s * d[0], s * d[1], s * d[2]]);
        }
        for (&(i, _), g) in springs.iter().zip(&fs) {
            for a in 0..3 {
                f[i][a] += g[a];
            }
        }
        for (&(_, j), g) in springs.iter().zip(&fs) {
            for a in 0..3 {
                f[j][a] -= g[a];
            }
        }
        for k in first..n {
            f[k][2] -= m[k] * G;
        }
        // abut adds the contact forces (what the C ABI's ABUT_FORCE_MODE_ADD does)
        let report = contact.penalty_step(&x, &v, DT)?;
        for (fk, ck) in f.iter_mut().zip(&report.forces) {
            for a in 0..3 {
                fk[a] += ck[a];
            }
        }
        touching += (report.active > 0) as usize;
        most = most.max(report.active);
        if let Some(o) = out.as_mut() {
            for fk in &f {
                for c in fk {
                    o.write_all(&c.to_le_bytes())?;
                }
            }
        }
        // central differences on the sheet (the plate is fixed)
        for k in first..n {
            for a in 0..3 {
                v[k][a] += DT * f[k][a] / m[k];
                x[k][a] += DT * v[k][a];
            }
        }
    }
    let c = x[first..]
        .iter()
        .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
    let k = (n - first) as f64;
    println!(
        "rust on {device}: {STEPS} increments, in contact in {touching}, at most {most} nodes; \
         sheet centre ({:.6}, {:.6}, {:.6})",
        c[0] / k,
        c[1] / k,
        c[2] / k
    );
    Ok(())
}
