//! Positions kept in the caller's own wgpu buffer: a device made from the caller's wgpu device,
//! increments that upload nothing, the same contacts as from host slices while the whole model
//! drifts (the device fits the frame's box around the master at every global search), and clear
//! errors for unusable buffers.

mod common;

use abut::mesh::{plate_quads, point_cloud};
use abut::search::Trigger;
use abut::*;
use common::{facet_distance, gpus};
use wgpu::BufferUsages as U;

/// The caller's own device: made with wgpu directly, on the adapter abut's tests use.
fn callers_device(like: &Device) -> Device {
    let backend = like.backend_name();
    let backends = if backend == "gl" {
        wgpu::Backends::GL
    } else {
        wgpu::Backends::VULKAN
    };
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.enumerate_adapters(backends))
        .into_iter()
        .next()
        .expect("adapter");
    let mut limits = wgpu::Limits::downlevel_defaults();
    limits.max_storage_buffers_per_shader_stage = 8;
    limits.max_compute_workgroup_size_x = 256;
    limits.max_compute_invocations_per_workgroup = 256;
    limits.max_compute_workgroups_per_dimension = 65_535;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: limits,
        ..Default::default()
    }))
    .expect("device");
    Device::from_wgpu(device, queue).expect("abut accepts the caller's device")
}

fn to_f32(x: &[[f64; 3]]) -> Vec<[f32; 4]> {
    x.iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect()
}

#[test]
fn positions_on_the_device_give_the_host_results() {
    let n = 20;
    let h = 1.0 / n as f64;
    let plate = plate_quads(n, n, 1.0, 1.0, 0.2, 1, &|x, y| {
        0.02 * (3.0 * x).sin() * (2.0 * y).cos()
    });
    let cloud = point_cloud(2000, [0.2, 0.1, -0.01], [0.5, 0.9, 0.01], 2);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m
        .add_pair(Pair::new(set, s).search_radius(2.0 * h))
        .unwrap();
    let master = m.surface(s).unwrap().clone();
    let first = r.start as usize;
    // away from the origin, so that the frame's origin is not zero: a device increment
    // subtracts it in f32, a host one has it subtracted in f64 beforehand
    let base: Vec<[f64; 3]> = m
        .positions()
        .iter()
        .map(|p| [p[0] + 37.5, p[1] - 21.25, p[2]])
        .collect();
    // slaves slide; from increment 40 on, the whole model drifts in +x, out of the box the
    // first search fitted
    let at = |k: usize| {
        let drift = if k >= 40 { 0.05 * (k - 39) as f64 } else { 0.0 };
        let mut x = base.clone();
        for (i, q) in x.iter_mut().enumerate() {
            if i >= first {
                q[0] += 0.3 * (0.3 * h / 0.3 * k as f64).sin();
            }
            q[0] += drift;
        }
        x
    };
    for g in gpus() {
        let dev = callers_device(g);
        let (wd, wq) = dev.wgpu().unwrap();
        let buffer = wd.create_buffer(&wgpu::BufferDescriptor {
            label: Some("caller's positions"),
            size: (m.positions().len() * 16) as u64,
            usage: U::STORAGE | U::COPY_DST | U::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut on_host = GlobalSearch::new(&dev, &m, p).unwrap();
        let mut on_device = GlobalSearch::new(&dev, &m, p).unwrap();
        // a global search every 10 increments: the drift alone (the whole model, master
        // included) uses up no motion budget, which is measured relative to the master
        let every_10 = Schedule {
            interval: 10,
            ..on_host.schedule()
        };
        on_host.set_schedule(every_10).unwrap();
        on_device.set_schedule(every_10).unwrap();
        on_host.step(&at(0)).unwrap();
        let first = on_device.step(&at(0)).unwrap();
        assert_ne!(
            first.frame, [0.0; 3],
            "the frame's origin should be away from zero"
        );
        let mut drifting_globals = 0;
        for k in 1..60 {
            let x = at(k);
            wq.write_buffer(&buffer, 0, bytemuck::cast_slice(&to_f32(&x))); // the caller's own update
            let a = on_host.step(&x).unwrap();
            // every fifth increment from host positions, the others from the buffer: each
            // kind of run leaves the frame the other expects
            let b = if k % 5 == 0 {
                on_device.step(&x).unwrap()
            } else {
                on_device.step_device(&buffer, true).unwrap()
            };
            assert_eq!(a.stats.trigger, b.stats.trigger, "{g} k={k}");
            if k >= 40 && !matches!(b.stats.trigger, Trigger::Local) {
                drifting_globals += 1;
            }
            let mut compared = 0;
            for (i, (ha, hb)) in a.contacts().zip(b.contacts()).enumerate() {
                match (ha, hb) {
                    (Some(ha), Some(hb)) => {
                        compared += 1;
                        if ha.facet != hb.facet {
                            let da = facet_distance(&master, &x, a.slaves[i], ha.facet);
                            let db = facet_distance(&master, &x, a.slaves[i], hb.facet);
                            assert!(
                                (da - db).abs() < 1e-5,
                                "{g} k={k}: slave {i}: facets {} and {} not a tie",
                                ha.facet,
                                hb.facet
                            );
                        }
                        assert!(
                            (ha.distance - hb.distance).abs() < 1e-5,
                            "{g} k={k}: distance {} vs {}",
                            ha.distance,
                            hb.distance
                        );
                        // in the model's frame: a run in the wrong frame moves every point
                        let off =
                            (0..3).fold(0.0f64, |d, c| d.max((ha.point[c] - hb.point[c]).abs()));
                        assert!(
                            off < 1e-4,
                            "{g} k={k}: slave {i}: point {:?} vs {:?}",
                            ha.point,
                            hb.point
                        );
                    }
                    (None, None) => {}
                    (Some(h), None) | (None, Some(h)) => assert!(
                        (h.distance - 2.0 * h_radius(&h)).abs() < 1e-5,
                        "{g} k={k}: slave {i} found by one side only at {}",
                        h.distance
                    ),
                }
            }
            assert!(compared > 1000, "{g} k={k}: {compared}");
        }
        assert!(
            drifting_globals >= 1,
            "{g}: the schedule should have searched globally during the drift"
        );
        // without hits: nothing read back but the status
        let quiet = on_device.step_device(&buffer, false).unwrap();
        assert!(quiet.is_empty());
        // an unusable buffer is an error, not a panic
        let small = wd.create_buffer(&wgpu::BufferDescriptor {
            label: Some("small"),
            size: 64,
            usage: U::STORAGE | U::COPY_SRC,
            mapped_at_creation: false,
        });
        let e = on_device.step_device(&small, false).unwrap_err();
        assert!(e.to_string().contains("device positions"), "{e}");
        let mut fresh = GlobalSearch::new(&dev, &m, p).unwrap();
        assert!(
            fresh.step_device(&buffer, false).is_err(),
            "needs a host increment first"
        );
    }
    let mut cpu = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    cpu.step(&at(0)).unwrap();
    assert!(Device::cpu().wgpu().is_none());
    let _ = &mut cpu;
}

/// The radius of this scene's pair (2 h), for the found-by-one-side check.
fn h_radius(_: &ContactPoint) -> f64 {
    1.0 / 20.0
}
