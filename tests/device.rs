//! Adapter choice: the environment narrows it, a missing adapter is an error for `gpu()` and a
//! CPU fallback with a notice for `auto()`, `ABUT_BACKEND` selects the path, `Device::choose`
//! takes a backend and a name in code whatever the environment says, and every device says
//! what it is. One test, so that changing the environment races with nothing.

use abut::mesh::plate_triangles;
use abut::{Backend, Device, Error, GlobalSearch, Model, Surface};

fn with_env<T>(vars: &[(&str, Option<&str>)], f: impl FnOnce() -> T) -> T {
    let saved: Vec<(String, Option<String>)> = vars
        .iter()
        .map(|(k, _)| (k.to_string(), std::env::var(k).ok()))
        .collect();
    for (k, v) in vars {
        match v {
            Some(v) => std::env::set_var(k, v),
            None => std::env::remove_var(k),
        }
    }
    let out = f();
    for (k, v) in saved {
        match v {
            Some(v) => std::env::set_var(&k, v),
            None => std::env::remove_var(&k),
        }
    }
    out
}

#[test]
fn adapter_choice_follows_the_environment() {
    // No adapter of the requested kind: gpu() errs naming the filter, auto() takes the CPU path.
    with_env(
        &[
            ("WGPU_ADAPTER_NAME", Some("no-such-adapter-anywhere")),
            ("ABUT_BACKEND", None),
        ],
        || {
            let e = Device::gpu().unwrap_err();
            assert!(matches!(e, Error::NoAdapter { .. }), "{e}");
            assert!(
                e.to_string()
                    .contains("WGPU_ADAPTER_NAME=no-such-adapter-anywhere"),
                "{e}"
            );
            let d = Device::auto().unwrap();
            assert!(!d.is_gpu());
            assert_eq!(d.backend_name(), "cpu");
            assert!(d.to_string().contains("CPU path"));
        },
    );
    with_env(&[("ABUT_BACKEND", Some("cpu"))], || {
        assert!(!Device::auto().unwrap().is_gpu())
    });
    let require = std::env::var("ABUT_REQUIRE_ADAPTER").is_ok_and(|v| v == "1");
    match Device::gpu() {
        Ok(d) => {
            let text = d.to_string();
            assert!(
                text.contains("backend") && text.contains("driver"),
                "{text}"
            );
            assert!(with_env(&[("ABUT_BACKEND", Some("gpu"))], || Device::auto(
            )
            .unwrap()
            .is_gpu()));
            // WGPU_BACKEND narrows: each backend found alone is chosen alone; and in code,
            // Device::choose takes that backend (and a name) whatever the environment says
            for d in Device::all_gpus().into_iter().flatten() {
                let b = d.backend_name();
                let only = with_env(&[("WGPU_BACKEND", Some(&b))], Device::gpu).unwrap();
                assert_eq!(only.backend_name(), b);
                let backend = match b.as_str() {
                    "vulkan" => Backend::Vulkan,
                    "gl" => Backend::Gl,
                    "metal" => Backend::Metal,
                    "dx12" => Backend::Dx12,
                    other => panic!("an unexpected backend {other}"),
                };
                let info = d.to_string();
                let name = info.split(" (").next().unwrap().to_string();
                let chosen = with_env(
                    &[
                        ("WGPU_BACKEND", Some("metal")),
                        ("WGPU_ADAPTER_NAME", Some("no-such-adapter-anywhere")),
                    ],
                    || Device::choose(backend, Some(&name.to_uppercase())),
                )
                .unwrap();
                assert_eq!(chosen.backend_name(), b, "{info}");
                assert!(chosen.to_string().starts_with(&name), "{chosen}");
                assert!(
                    chosen.to_string().contains(&format!("{b} backend")),
                    "{chosen}"
                );
                assert!(Device::choose(Backend::Any, Some(&name)).is_ok());
            }
            let e = Device::choose(Backend::Any, Some("no-such-adapter-anywhere")).unwrap_err();
            assert!(matches!(e, Error::NoAdapter { .. }), "{e}");
            assert!(e.to_string().contains("no-such-adapter-anywhere"), "{e}");
            // the backends CI requires are there by name of backend alone
            if let Ok(list) = std::env::var("ABUT_REQUIRE_BACKENDS") {
                for want in list.split(',').map(str::trim) {
                    let backend = match want {
                        "vulkan" => Backend::Vulkan,
                        "gl" => Backend::Gl,
                        _ => continue,
                    };
                    let d = Device::choose(backend, None).unwrap();
                    assert_eq!(d.backend_name(), want);
                    // the way in where nothing may block (a browser): the same backend's
                    // adapter, requested asynchronously, gives the same contact bit for bit
                    let wgpu_backend = match backend {
                        Backend::Vulkan => wgpu::Backends::VULKAN,
                        _ => wgpu::Backends::GL,
                    };
                    let asked = pollster::block_on(Device::request(wgpu_backend)).unwrap();
                    assert_eq!(asked.backend_name(), want, "{asked}");
                    assert_eq!(contacts(&asked), contacts(&d), "{asked}");
                }
            }
            // no backend: an error naming what was asked, not a panic
            let e = pollster::block_on(Device::request(wgpu::Backends::empty())).unwrap_err();
            assert!(matches!(e, Error::NoAdapter { .. }), "{e}");
        }
        Err(e) if !require => eprintln!("\n*** SKIPPED the GPU half: {e} ***\n"),
        Err(e) => panic!("ABUT_REQUIRE_ADAPTER=1 but Device::gpu() failed: {e}"),
    }
}

/// The contacts (debug text, so every bit shows) of 200 slaves over a wavy plate of 8 × 8 quads
/// split in two, searched on `device`.
fn contacts(device: &Device) -> Vec<String> {
    let mut plate = plate_triangles(8, 8, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    for p in &mut plate.positions {
        p[2] = 0.05 * (5.0 * p[0]).sin() * (3.0 * p[1]).cos();
    }
    let mut model = Model::new_3d();
    model
        .add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
        .unwrap();
    let master = model
        .add_surface(Surface::triangles(&plate.facets))
        .unwrap();
    let slaves: Vec<[f64; 3]> = (0..200)
        .map(|k| {
            let (x, y) = ((k % 20) as f64 / 19.0, (k / 20) as f64 / 9.0);
            [
                x,
                y,
                0.05 * (5.0 * x).sin() * (3.0 * y).cos() + 0.01 * ((k % 7) as f64 - 3.0),
            ]
        })
        .collect();
    let ids = model.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let surface = model.surface(master).unwrap().clone();
    let mut search = GlobalSearch::from_parts(device, &model, surface, ids.to_vec(), 0.2).unwrap();
    let r = search.run(model.positions()).unwrap();
    let found: Vec<String> = r.contacts().map(|c| format!("{c:?}")).collect();
    let near = found.iter().filter(|c| c.starts_with("Some")).count();
    assert!(near > 150, "{device}: {near} of 200 slaves found a facet");
    found
}
