//! The cost of one penalty increment called from Rust, the reference for the C and Python
//! bindings' overhead (examples/c/overhead.c, the Python driver benches/bindings_overhead.py
//! runs all three and writes the table of docs/BENCHMARKS.md).
//!
//! The model, the same in each language: a square grid of `slaves` nodes (spacing 1, mass 1)
//! 0.01 into a plate of quads at twice the spacing (so every slave is in contact), penalty
//! contact with friction 0.3; the positions stay put, so every increment does the same work.
//!
//! `cargo run --release --example overhead -- [cpu|vulkan|gl] <slaves> <increments>`: prints
//! one line, `rust <slaves> <first call, s> <mean of the rest, s>`.

use abut::{Backend, Contact, Device, Friction, Model, Pair, Surface};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let device = match args.get(1).map(String::as_str).unwrap_or("cpu") {
        "vulkan" => Device::choose(Backend::Vulkan, None)?,
        "gl" => Device::choose(Backend::Gl, None)?,
        _ => Device::cpu(),
    };
    let want: usize = args.get(2).map_or(Ok(1000), |s| s.parse())?;
    let reps: usize = args.get(3).map_or(Ok(10), |s| s.parse())?;
    let side = (want as f64).sqrt().round() as usize;
    let plate = side / 2 + 1;
    let mut x = Vec::new();
    for j in 0..=plate {
        for i in 0..=plate {
            x.push([2.0 * i as f64 - 1.0, 2.0 * j as f64 - 1.0, 0.0]);
        }
    }
    let mut quads = Vec::new();
    for j in 0..plate as u32 {
        for i in 0..plate as u32 {
            let a = j * (plate as u32 + 1) + i;
            quads.push([a, a + 1, a + plate as u32 + 2, a + plate as u32 + 1]);
        }
    }
    let first = x.len();
    for j in 0..side {
        for i in 0..side {
            x.push([i as f64, j as f64, -0.01]);
        }
    }
    let n = x.len();
    let mut model = Model::new_3d();
    model.add_nodes(&x, &vec![1.0; n])?;
    let surface = model.add_surface(Surface::quads(&quads))?;
    let slaves: Vec<u32> = (first as u32..n as u32).collect();
    let set = model.add_node_set(&slaves)?;
    model.add_pair(Pair::new(set, surface).friction(Friction::coulomb(0.3)))?;
    let mut contact = Contact::new(&device, &model)?;
    let v = vec![[0.0; 3]; n];
    let mut f = vec![[0.0; 3]; n];
    let mut times = Vec::new();
    for _ in 0..reps + 1 {
        let t = Instant::now();
        let r = contact.penalty_step(&x, &v, 1e-3)?;
        // what a Rust host does with the forces: take them into its own array
        f.copy_from_slice(&r.forces);
        times.push(t.elapsed().as_secs_f64());
    }
    assert!(f.iter().any(|g| g[2] != 0.0), "the slaves are in contact");
    let rest = &times[1..];
    println!(
        "rust {} {:.6e} {:.6e}",
        side * side,
        times[0],
        rest.iter().sum::<f64>() / rest.len() as f64
    );
    Ok(())
}
