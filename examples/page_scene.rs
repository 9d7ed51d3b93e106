//! The web page's scene (web/) run natively: the numbers the page must end with, and the time
//! per increment on the CPU path and each GPU adapter, for the page test (web/test_page.py)
//! and docs/BENCHMARKS.md.
//!
//! `cargo run --release --example page_scene -- <beads> <friction> <penalty scale>
//! <finite|small> <frames> <increments per frame> [cpu|all]`: prints one JSON object: the
//! settings, then per device its adapter, the wall time of the first frame and the mean of the
//! rest per increment (ms; on a GPU each frame one submit and one readback of forces and
//! positions, as the page does), and the summary the page reports (beads on the plate, their
//! mean x, y, z in m, the total normal contact force in N).

use abut::testing::incline::{summary, InclineCpu, InclineGpu};
use abut::testing::scenes::{incline, InclineSettings};
use abut::{Device, Sliding};
use std::time::Instant;

/// Maps `bytes` of `buffer` (MAP_READ) and waits.
fn read(d: &wgpu::Device, buffer: &wgpu::Buffer, bytes: u64) -> Vec<[f32; 4]> {
    let slice = buffer.slice(..bytes);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    d.poll(wgpu::PollType::wait_indefinitely())
        .expect("the readback");
    let out = bytemuck::pod_collect_to_vec(&slice.get_mapped_range().expect("mapped"));
    buffer.unmap();
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let settings = InclineSettings {
        beads: arg(1, "1024").parse()?,
        friction: arg(2, "0.2").parse()?,
        penalty_scale: arg(3, "1").parse()?,
        sliding: if arg(4, "finite") == "small" {
            Sliding::Small
        } else {
            Sliding::Finite
        },
        ..Default::default()
    };
    let frames: usize = arg(5, "300").parse()?;
    let per_frame: usize = arg(6, "20").parse()?;
    let gpus = arg(7, "all") == "all";
    let scene = incline(&settings)?;
    let mut rows = Vec::new();
    let row = |name: &str, first: f64, rest: f64, s: [f64; 5]| {
        format!(
            "{{\"device\":\"{name}\",\"first_ms_per_increment\":{first},\
             \"ms_per_increment\":{rest},\"summary\":[{},{},{},{},{}]}}",
            s[0], s[1], s[2], s[3], s[4]
        )
    };
    // the CPU path
    let mut cpu = InclineCpu::new(&scene)?;
    let mut times = Vec::new();
    for _ in 0..frames {
        let t = Instant::now();
        cpu.advance(per_frame, scene.dt)?;
        times.push(t.elapsed().as_secs_f64() * 1e3 / per_frame as f64);
    }
    let s = summary(&scene, &cpu.positions, &cpu.last_forces);
    let rest = times[1..].iter().sum::<f64>() / (times.len() - 1).max(1) as f64;
    rows.push(row("cpu", times[0], rest, s));
    if gpus {
        for g in Device::all_gpus().into_iter().flatten() {
            let (d, q) = g.wgpu().expect("a GPU");
            let mut run = InclineGpu::new(&g, &scene)?;
            let n = run.n_nodes as u64 * 16;
            let staging = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("page scene readback"),
                size: 2 * n,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut times = Vec::new();
            let mut last = Vec::new();
            for _ in 0..frames {
                let t = Instant::now();
                let mut enc = d.create_command_encoder(&Default::default());
                run.encode(&mut enc, per_frame, scene.dt)?;
                enc.copy_buffer_to_buffer(&run.last_forces, 0, &staging, 0, n);
                enc.copy_buffer_to_buffer(&run.positions, 0, &staging, n, n);
                q.submit([enc.finish()]);
                last = read(d, &staging, 2 * n);
                run.collect()?;
                times.push(t.elapsed().as_secs_f64() * 1e3 / per_frame as f64);
            }
            let (f, x) = last.split_at(run.n_nodes);
            let s = summary(&scene, x, f);
            let rest = times[1..].iter().sum::<f64>() / (times.len() - 1).max(1) as f64;
            rows.push(row(&g.to_string(), times[0], rest, s));
        }
    }
    println!(
        "{{\"beads\":{},\"friction\":{},\"penalty_scale\":{},\"sliding\":\"{}\",\"frames\":{frames},\
         \"increments_per_frame\":{per_frame},\"dt\":{},\"devices\":[{}]}}",
        settings.beads,
        settings.friction,
        settings.penalty_scale,
        arg(4, "finite"),
        scene.dt,
        rows.join(",")
    );
    Ok(())
}
