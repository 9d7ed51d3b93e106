//! Adapter choice: the environment narrows it, a missing adapter is an error for `gpu()` and a
//! CPU fallback with a notice for `auto()`, `ABUT_BACKEND` selects the path, and every device
//! says what it is. One test, so that changing the environment races with nothing.

use abut::{Device, Error};

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
            // WGPU_BACKEND narrows: each backend found alone is chosen alone
            for d in Device::all_gpus().into_iter().flatten() {
                let b = d.backend_name();
                let only = with_env(&[("WGPU_BACKEND", Some(&b))], Device::gpu).unwrap();
                assert_eq!(only.backend_name(), b);
            }
        }
        Err(e) if !require => eprintln!("\n*** SKIPPED the GPU half: {e} ***\n"),
        Err(e) => panic!("ABUT_REQUIRE_ADAPTER=1 but Device::gpu() failed: {e}"),
    }
}
