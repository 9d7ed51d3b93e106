//! The search's hits of every device-resident increment, on each GPU adapter against the CPU
//! path: the same facet and tracked master node for every slave, and the closest point, gap,
//! normal and weights to f32 round-off (issue 33: the browser test compares the same on the
//! page's WebGPU adapter). 300 masses bounce on a rigid plate, as in tests/web.rs.

mod common;

use abut::testing::abi::search::{GpuHit, NO_FACET};
use abut::{CentralDifference, Contact, ResidentIo};
use common::{gpus, node_buffers};

/// Increments run: every mass hits the plate and comes back up.
const STEPS: usize = 500;

#[test]
fn the_hits_of_every_resident_increment_equal_the_cpu_paths() {
    let (model, range, dt) = abut::testing::scenes::bounce(300).unwrap();
    let n = model.positions().len();
    let (x0, v0) = abut::testing::scenes::bounce_start(&model, &range);
    // the CPU path's hits after every increment
    let cpu_hits: Vec<Vec<GpuHit>> = abut::testing::scenes::bounce_cpu(&model, &range, dt, STEPS)
        .unwrap()
        .hits;
    let contacts = cpu_hits
        .iter()
        .flatten()
        .filter(|h| h.facet != NO_FACET)
        .count();
    assert!(contacts > STEPS, "only {contacts} hits within the radius");
    for g in gpus() {
        let (d, q) = g.wgpu().unwrap();
        let [bx, bv, bf] = node_buffers(g, n);
        q.write_buffer(&bx, 0, bytemuck::cast_slice(&x0));
        q.write_buffer(&bv, 0, bytemuck::cast_slice(&v0));
        let mut c = Contact::new(g, &model).unwrap();
        let mut integ = CentralDifference::new(g, model.masses()).unwrap();
        let mut worst = 0.0f32;
        for (k, expected) in cpu_hits.iter().enumerate() {
            let mut enc = d.create_command_encoder(&Default::default());
            let io = ResidentIo::Gpu {
                encoder: &mut enc,
                positions: &bx,
                velocities: &bv,
                forces: &bf,
            };
            c.encode_increment(io, dt).unwrap();
            integ
                .encode(&mut enc, &bx, &bv, &bf, dt, [0.0; 3], range.clone())
                .unwrap();
            q.submit([enc.finish()]);
            let got = abut::testing::resident_hits(&c).unwrap();
            let diff = abut::testing::scenes::hits_difference(&got.concat(), expected)
                .unwrap_or_else(|e| panic!("{g}: increment {k}: {e}"));
            worst = worst.max(diff);
        }
        eprintln!("{g}: {STEPS} increments, largest hit difference from the CPU path {worst:e}");
        assert!(worst <= 1e-5, "{g}: hits differ by {worst:e}");
    }
}
