//! Issue 33: abut's kernels in a real browser. Built for wasm32 and run by
//! `wasm-bindgen-test-runner` in headless Chromium, whose WebGPU adapter is SwiftShader (a CPU
//! implementation, like lavapipe): 300 point masses fall onto a rigid plate and bounce back, each
//! increment the device-resident penalty increment and the WGSL integrator recorded on the
//! page's device with nothing read back, against the CPU path compiled into the same page (the
//! same code and f32 arithmetic as natively): the search's hits and the contact forces after
//! every increment (copied aside on the device, read once at the end), then the masses' positions and velocities after
//! the WGSL integrator, to the tolerances `tests/resident.rs` uses on lavapipe and llvmpipe (on
//! Chromium 156 all three are the CPU path's bits; the log gives the differences). Native
//! builds compile nothing here.
#![cfg(target_arch = "wasm32")]

use abut::device::DeviceKind;
use abut::{CentralDifference, Contact, Device, ResidentIo};
use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

wasm_bindgen_test_configure!(run_in_browser);

/// Masses dropped.
const MASSES: usize = 300;
/// Increments run (62 ms): every mass has hit the plate and come back up.
const STEPS: usize = 500;

/// `buffer`'s first `size` bytes, copied to a mapped buffer and awaited: the browser delivers
/// the mapping when the page yields, so nothing blocks.
async fn read(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Vec<u8> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("web test readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([enc.finish()]);
    let (tx, rx) = futures_channel::oneshot::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    let _ = device.poll(wgpu::PollType::Poll);
    rx.await
        .expect("the mapping's callback")
        .expect("the mapping");
    let data = staging
        .slice(..)
        .get_mapped_range()
        .expect("a mapped range")
        .to_vec();
    staging.unmap();
    data
}

#[wasm_bindgen_test]
async fn bouncing_masses_in_the_browser_equal_the_cpu_path() {
    let (model, range, dt) = abut::testing::scenes::bounce(MASSES).unwrap();
    let n = model.positions().len();
    let masses = model.masses().to_vec();
    let (x0, v0) = abut::testing::scenes::bounce_start(&model, &range);
    // the CPU path, compiled into the page: the contact forces and hits of every increment,
    // then where the masses end
    let cpu = abut::testing::scenes::bounce_cpu(&model, &range, dt, STEPS).unwrap();
    let forces_cpu: Vec<[f32; 4]> = cpu.forces.concat();
    let hits_cpu = &cpu.hits;
    let (xc, vc) = (&cpu.positions, &cpu.velocities);
    // the page's WebGPU device, asked for without blocking
    let g = Device::request(wgpu::Backends::BROWSER_WEBGPU)
        .await
        .expect("a WebGPU adapter (Chromium: --enable-unsafe-webgpu)");
    let (d, q) = g.wgpu().unwrap();
    let [bx, bv, bf] = abut::testing::scenes::node_buffers(&g, n).unwrap();
    q.write_buffer(&bx, 0, bytemuck::cast_slice(&x0));
    q.write_buffer(&bv, 0, bytemuck::cast_slice(&v0));
    let mut c = Contact::new(&g, &model).unwrap();
    let mut integ = CentralDifference::new(&g, &masses).unwrap();
    // each increment's contact forces copied aside on the device, read once at the end
    let row = (n * 16) as u64;
    let history = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("forces of every increment"),
        size: row * STEPS as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    // and the search's hits (one pass: 64 bytes per slave), made on the first increment
    let mut hit_history: Option<(wgpu::Buffer, u64)> = None;
    for k in 0..STEPS {
        let mut enc = d.create_command_encoder(&Default::default());
        let io = ResidentIo::Gpu {
            encoder: &mut enc,
            positions: &bx,
            velocities: &bv,
            forces: &bf,
        };
        c.encode_increment(io, dt).unwrap();
        enc.copy_buffer_to_buffer(&bf, 0, &history, k as u64 * row, row);
        let passes = abut::testing::resident_hits_buffers(&c);
        assert_eq!(passes.len(), 1, "the bounce has one penalty pass");
        let (hits, bytes) = passes[0];
        let (store, _) = hit_history.get_or_insert_with(|| {
            let b = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hits of every increment"),
                size: bytes * STEPS as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (b, bytes)
        });
        enc.copy_buffer_to_buffer(hits, 0, store, k as u64 * bytes, bytes);
        integ
            .encode(&mut enc, &bx, &bv, &bf, dt, [0.0; 3], range.clone())
            .unwrap();
        q.submit([enc.finish()]);
    }
    let x: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(d, q, &bx, (n * 16) as u64).await);
    let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(d, q, &bv, (n * 16) as u64).await);
    let forces: Vec<[f32; 4]> =
        bytemuck::pod_collect_to_vec(&read(d, q, &history, row * STEPS as u64).await);
    let (store, hit_row) = hit_history.expect("hits");
    let hits: Vec<abut::testing::abi::search::GpuHit> =
        bytemuck::pod_collect_to_vec(&read(d, q, &store, hit_row * STEPS as u64).await);
    if let DeviceKind::Gpu(ctx) = g.kind() {
        ctx.take_uncaptured("the bounce in the browser").unwrap();
    }
    // the forces after every increment, to the tolerance tests/resident.rs uses natively (3·10⁻⁵
    // of the largest force); on Chromium 156's SwiftShader they are the CPU path's bits, and
    // the log says so
    let scale = forces_cpu
        .iter()
        .flat_map(|f| f[..3].iter())
        .fold(0.0f32, |a, f| a.max(f.abs()));
    assert!(scale > 0.0, "no contact force at all");
    for (j, (a, b)) in forces.iter().zip(&forces_cpu).enumerate() {
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 3e-5 * scale,
                "{g}: increment {}, node {}: force {a:?} against the CPU path's {b:?}",
                j / n,
                j % n
            );
        }
    }
    // the search's hits after every increment: the same facet and tracked node for every
    // slave, the closest point, gap, normal and weights to 10⁻⁵ (tests/resident_hits.rs)
    let per = hit_row as usize / 64;
    let mut worst_hit = 0.0f32;
    for (k, expected) in hits_cpu.iter().enumerate() {
        let got = &hits[k * per..(k + 1) * per];
        let diff = abut::testing::scenes::hits_difference(got, expected)
            .unwrap_or_else(|e| panic!("{g}: increment {k}: {e}"));
        worst_hit = worst_hit.max(diff);
    }
    assert!(worst_hit <= 1e-5, "{g}: hits differ by {worst_hit:e}");
    let worst = |p: &[[f32; 4]], q: &[[f32; 4]]| {
        p.iter()
            .zip(q)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0f32, f32::max)
    };
    wasm_bindgen_test::console_log!(
        "{g}: {STEPS} increments; largest difference from the CPU path: hits {worst_hit:e}, forces {:e}, positions {:e}, velocities {:e}",
        worst(&forces, &forces_cpu),
        worst(&x, xc),
        worst(&v, vc)
    );
    let mut bounced = 0;
    for i in range.start as usize..range.end as usize {
        for a in 0..3 {
            assert!(
                (v[i][a] - vc[i][a]).abs() < 1e-3,
                "{g}: node {i} velocity {:?} against the CPU path's {:?}",
                v[i],
                vc[i]
            );
            assert!(
                (x[i][a] - xc[i][a]).abs() < 1e-5,
                "{g}: node {i} position {:?} against the CPU path's {:?}",
                x[i],
                xc[i]
            );
        }
        bounced += usize::from(vc[i][2] > 0.5);
    }
    // the comparison is not of masses at rest: they have hit the plate and come back up
    assert!(
        bounced * 10 > MASSES * 9,
        "{bounced} of {MASSES} masses rebounded"
    );
}

/// What waits for the device — the host-array increment, which reads its forces back — is
/// refused in a browser with an error naming the readback, not left to hang the page.
#[wasm_bindgen_test]
async fn a_blocking_readback_is_refused_by_name_in_the_browser() {
    let (model, _, dt) = abut::testing::scenes::bounce(20).unwrap();
    let g = Device::request(wgpu::Backends::BROWSER_WEBGPU)
        .await
        .expect("a WebGPU adapter");
    let mut c = Contact::new(&g, &model).unwrap();
    let x = model.positions().to_vec();
    let v = vec![[0.0; 3]; x.len()];
    let err = c.penalty_step(&x, &v, dt).unwrap_err().to_string();
    assert!(
        err.contains("readback") && err.contains("browser"),
        "the error does not name the readback: {err}"
    );
}
