//! The C ABI (`abut::capi`, what libabut exports) called as a C host calls it: the same
//! increments as the Rust API bit for bit on the CPU path and every adapter, a restart from
//! saved state continuing bit for bit, the output variables, and every kind of bad input
//! (null, lengths, ids, freed handles, NaN, unknown enumeration values) a named error.
#![cfg(feature = "capi")]

mod common;

use abut::capi::*;
use abut::{Contact, Device, Friction, Model, Pair, Surface};
use std::ptr::{null, null_mut};

/// A sheet of `n`×`n` slave nodes (spacing `h`, mass 0.01) just above a plate of 3×3 quads
/// (span 2, the master): coordinates, masses, the plate's quads and the sheet's node ids.
struct Sheet {
    coords: Vec<[f64; 3]>,
    masses: Vec<f64>,
    quads: Vec<[u32; 4]>,
    slaves: Vec<u32>,
}

fn sheet(n: usize, h: f64) -> Sheet {
    let (mut coords, mut masses, mut quads) = (Vec::new(), Vec::new(), Vec::new());
    let p = 3;
    for j in 0..=p {
        for i in 0..=p {
            coords.push([
                -1.0 + 2.0 * i as f64 / p as f64,
                -1.0 + 2.0 * j as f64 / p as f64,
                0.0,
            ]);
            masses.push(1.0);
        }
    }
    for j in 0..p as u32 {
        for i in 0..p as u32 {
            let a = j * (p as u32 + 1) + i;
            quads.push([a, a + 1, a + p as u32 + 2, a + p as u32 + 1]);
        }
    }
    let first = coords.len() as u32;
    for j in 0..n {
        for i in 0..n {
            let c = (n as f64 - 1.0) * h / 2.0;
            coords.push([i as f64 * h - c + 0.013, j as f64 * h - c - 0.007, 0.0002]);
            masses.push(0.01);
        }
    }
    let slaves = (first..coords.len() as u32).collect();
    Sheet {
        coords,
        masses,
        quads,
        slaves,
    }
}

fn rust_model(s: &Sheet, mu: f64) -> Model {
    let mut m = Model::new_3d();
    m.add_nodes(&s.coords, &s.masses).unwrap();
    let plate = m.add_surface(Surface::quads(&s.quads)).unwrap();
    let set = m.add_node_set(&s.slaves).unwrap();
    m.add_pair(Pair::new(set, plate).friction(Friction::coulomb(mu)))
        .unwrap();
    m
}

/// The same model through the C ABI; returns the handle.
fn c_model(s: &Sheet, mu: f64) -> *mut AbutModel {
    unsafe {
        let mut m = null_mut();
        ok(abut_model_new(3, &mut m));
        let mut first = 0;
        ok(abut_model_add_nodes(
            m,
            s.coords.as_flattened().as_ptr(),
            s.masses.as_ptr(),
            s.masses.len(),
            &mut first,
        ));
        assert_eq!(first, 0);
        let (mut plate, mut set, mut pair) = (0, 0, 0);
        ok(abut_model_add_surface(
            m,
            AbutFacetKind::Quads as i32,
            s.quads.as_flattened().as_ptr(),
            s.quads.len(),
            &mut plate,
        ));
        ok(abut_model_add_node_set(
            m,
            s.slaves.as_ptr(),
            s.slaves.len(),
            null(),
            &mut set,
        ));
        let mut o = std::mem::zeroed();
        ok(abut_pair_options_default(&mut o));
        o.friction = 1;
        o.mu = mu;
        ok(abut_model_add_pair(m, set, plate, &o, &mut pair));
        m
    }
}

#[track_caller]
fn ok(s: AbutStatus) {
    assert_eq!(s, AbutStatus::Ok, "{}", last_error());
}

fn last_error() -> String {
    let mut buf = vec![0u8; 1024];
    let mut len = 0;
    unsafe { abut_last_error(buf.as_mut_ptr(), buf.len(), &mut len) };
    String::from_utf8_lossy(&buf[..len.min(1023)]).into_owned()
}

/// Asserts `s` is `want` and the thread's last error contains every one of `words`.
#[track_caller]
fn fails(s: AbutStatus, want: AbutStatus, words: &[&str]) {
    let msg = last_error();
    assert_eq!(s, want, "{msg}");
    for w in words {
        assert!(msg.contains(w), "'{msg}' does not name '{w}'");
    }
}

/// A C device like `d` (the CPU path, or the same adapter by backend and name).
fn c_device(d: &Device) -> *mut AbutDevice {
    let mut out = null_mut();
    unsafe {
        match d.wgpu() {
            None => ok(abut_device_new(
                AbutDeviceKind::Cpu as i32,
                0,
                null(),
                &mut out,
            )),
            Some((dev, _)) => {
                let backend = match d.backend_name().as_str() {
                    "vulkan" => AbutBackend::Vulkan,
                    "gl" => AbutBackend::Gl,
                    "metal" => AbutBackend::Metal,
                    "dx12" => AbutBackend::Dx12,
                    _ => AbutBackend::Any,
                };
                let name = std::ffi::CString::new(dev.adapter_info().name).unwrap();
                ok(abut_device_new(
                    AbutDeviceKind::Gpu as i32,
                    backend as i32,
                    name.as_ptr(),
                    &mut out,
                ));
            }
        }
    }
    out
}

fn devices() -> Vec<Device> {
    let mut all = vec![Device::cpu()];
    all.extend(common::gpus().iter().cloned());
    all
}

/// One penalty increment through the C ABI on the caller's arrays.
fn c_step(
    c: *mut AbutContact,
    x: &[[f64; 3]],
    v: &[[f64; 3]],
    dt: f64,
    f: &mut [[f64; 3]],
    mode: AbutForceMode,
) -> AbutStatus {
    let n = x.len();
    let (x, v) = (x.as_flattened().as_ptr(), v.as_flattened().as_ptr());
    let f = f.as_flattened_mut().as_mut_ptr();
    unsafe { abut_contact_penalty_step(c, x, v, n, dt, f, mode as i32) }
}

/// The host loop of the examples, one increment: forces on the sheet from the contact, a
/// body force pressing it onto the plate; central differences on the sheet.
fn advance(s: &Sheet, x: &mut [[f64; 3]], v: &mut [[f64; 3]], f: &[[f64; 3]], dt: f64) {
    for &n in &s.slaves {
        let n = n as usize;
        let m = s.masses[n];
        for a in 0..3 {
            let g = if a == 2 { -200.0 * m } else { 0.0 };
            v[n][a] += dt * (f[n][a] + g) / m;
            x[n][a] += dt * v[n][a];
        }
    }
}

fn start_velocities(s: &Sheet) -> Vec<[f64; 3]> {
    let mut v = vec![[0.0; 3]; s.coords.len()];
    for &n in &s.slaves {
        v[n as usize] = [0.8, -0.3, -0.05];
    }
    v
}

#[test]
fn c_abi_increments_equal_the_rust_apis_bit_for_bit_on_every_device() {
    let s = sheet(7, 0.11);
    let dt = 2e-4;
    for d in devices() {
        let mut rust = Contact::new(&d, &rust_model(&s, 0.3)).unwrap();
        rust.request_outputs(true);
        let (dev, model) = (c_device(&d), c_model(&s, 0.3));
        let mut c = null_mut();
        unsafe {
            ok(abut_contact_new(dev, model, &mut c));
            ok(abut_device_free(dev));
            ok(abut_model_free(model));
            ok(abut_contact_request_outputs(c, 1));
        }
        let (mut xr, mut vr) = (s.coords.clone(), start_velocities(&s));
        let (mut xc, mut vc) = (xr.clone(), vr.clone());
        let mut fc = vec![[0.0; 3]; xr.len()];
        let mut touched = 0;
        for inc in 0..120 {
            let fr = rust.penalty_step(&xr, &vr, dt).unwrap().forces.clone();
            ok(c_step(c, &xc, &vc, dt, &mut fc, AbutForceMode::Write));
            let bits = |f: &[[f64; 3]]| {
                f.as_flattened()
                    .iter()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&fr),
                bits(&fc),
                "{d}: forces differ at increment {inc}"
            );
            let mut rep = AbutReport::default();
            unsafe { ok(abut_contact_report(c, &mut rep)) };
            let r = rust.report();
            assert_eq!(rep.active, r.active as u64);
            assert_eq!(rep.slipping, r.slipping as u64);
            assert_eq!(rep.stable_dt.to_bits(), r.stable_dt.to_bits());
            assert_eq!(rep.fast_nodes, r.fast_nodes as u64);
            touched += (rep.active > 0) as usize;
            // the output variables through the C arrays are the Rust ones
            let mut len = 0;
            unsafe {
                ok(abut_contact_output_len(
                    c,
                    AbutPairKind::Meshed as i32,
                    0,
                    0,
                    &mut len,
                ))
            };
            let (_, o) = rust.outputs()[0];
            assert_eq!(len, o.slaves.len());
            let (mut cpress, mut copen, mut cstatus) =
                (vec![0.0; len], vec![0.0; len], vec![9; len]);
            let arrays = AbutOutputArrays {
                len,
                slaves: null_mut(),
                cstatus: cstatus.as_mut_ptr(),
                copen: copen.as_mut_ptr(),
                cpress: cpress.as_mut_ptr(),
                cshear1: null_mut(),
                cshear2: null_mut(),
                normal: null_mut(),
                force: null_mut(),
            };
            let mut totals = AbutOutputTotals::default();
            unsafe {
                ok(abut_contact_output(
                    c,
                    AbutPairKind::Meshed as i32,
                    0,
                    0,
                    &arrays,
                    &mut totals,
                ))
            };
            assert_eq!(bits(&[totals.cfn]), bits(&[o.cfn]));
            assert_eq!(bits(&[totals.cfs]), bits(&[o.cfs]));
            for k in 0..len {
                assert_eq!(cpress[k].to_bits(), o.cpress[k].to_bits());
                assert_eq!(copen[k].to_bits(), o.copen[k].to_bits());
                let want = match o.cstatus[k] {
                    None => -1,
                    Some(abut::ContactStatus::Open) => 0,
                    Some(abut::ContactStatus::Stick) => 1,
                    Some(abut::ContactStatus::Slip) => 2,
                };
                assert_eq!(cstatus[k], want);
            }
            advance(&s, &mut xr, &mut vr, &fr, dt);
            advance(&s, &mut xc, &mut vc, &fc, dt);
        }
        assert!(
            touched > 30,
            "{d}: the sheet was in contact for {touched} increments"
        );
        // adding to the host's forces adds
        let mut fa = vec![[1.5; 3]; xc.len()];
        let before = rust.penalty_step(&xr, &vr, dt).unwrap().forces.clone();
        ok(c_step(c, &xc, &vc, dt, &mut fa, AbutForceMode::Add));
        unsafe { ok(abut_contact_free(c)) };
        for (a, b) in fa.iter().zip(&before) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), (1.5 + b[k]).to_bits());
            }
        }
    }
}

/// Runs `incs` increments of the sheet through the C ABI on `c` from `x`, `v`; returns every
/// increment's forces.
fn run_c(
    c: *mut AbutContact,
    s: &Sheet,
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    incs: usize,
    dt: f64,
) -> Vec<Vec<u64>> {
    let mut f = vec![[0.0; 3]; x.len()];
    let mut all = Vec::new();
    for _ in 0..incs {
        ok(c_step(c, x, v, dt, &mut f, AbutForceMode::Write));
        all.push(f.as_flattened().iter().map(|x| x.to_bits()).collect());
        advance(s, x, v, &f, dt);
    }
    all
}

#[test]
fn a_restart_from_saved_state_continues_bit_for_bit_on_every_device() {
    let s = sheet(6, 0.12);
    let dt = 2e-4;
    for d in devices() {
        let make = || {
            let (dev, model) = (c_device(&d), c_model(&s, 0.4));
            let mut c = null_mut();
            unsafe {
                ok(abut_contact_new(dev, model, &mut c));
                ok(abut_device_free(dev));
                ok(abut_model_free(model));
            }
            c
        };
        // saved after 87 increments (sliding in stick and slip, off a global search's
        // increment), restored into a new contact, continued for 60
        let whole = make();
        let (mut x, mut v) = (s.coords.clone(), start_velocities(&s));
        run_c(whole, &s, &mut x, &mut v, 87, dt);
        let mut size = 0;
        unsafe { ok(abut_contact_state_size(whole, &mut size)) };
        let mut saved = vec![0u8; size];
        unsafe { ok(abut_contact_save_state(whole, saved.as_mut_ptr(), size)) };
        let (mut x2, mut v2) = (x.clone(), v.clone());
        let (x_saved, v_saved) = (x.clone(), v.clone());
        let rest = run_c(whole, &s, &mut x, &mut v, 60, dt);
        let restarted = make();
        unsafe { ok(abut_contact_restore_state(restarted, saved.as_ptr(), size)) };
        let again = run_c(restarted, &s, &mut x2, &mut v2, 60, dt);
        assert!(
            rest.iter().flatten().any(|&b| f64::from_bits(b) != 0.0),
            "{d}: contact after the restart"
        );
        for (k, (a, b)) in rest.iter().zip(&again).enumerate() {
            assert_eq!(a, b, "{d}: increment {k} after the restart differs");
        }
        // without the state (a fresh contact), the friction history is lost: not the same
        let fresh = make();
        let (mut x3, mut v3) = (x_saved.clone(), v_saved.clone());
        let lost = run_c(fresh, &s, &mut x3, &mut v3, 60, dt);
        assert_ne!(rest, lost, "{d}: the saved state made no difference");
        // bad states are named and change nothing
        unsafe {
            fails(
                abut_contact_restore_state(fresh, saved.as_ptr(), size - 1),
                AbutStatus::BadValue,
                &["saved contact state", "ends early"],
            );
            let mut junk = saved.clone();
            junk[0] = b'x';
            fails(
                abut_contact_restore_state(fresh, junk.as_ptr(), size),
                AbutStatus::BadValue,
                &["marker"],
            );
            fails(
                abut_contact_save_state(fresh, saved.as_mut_ptr(), size - 1),
                AbutStatus::Length,
                &["cap"],
            );
            for c in [whole, restarted, fresh] {
                ok(abut_contact_free(c));
            }
        }
    }
}

#[test]
fn a_state_saved_from_another_model_is_refused_naming_the_pass() {
    let (a, b) = (sheet(4, 0.1), sheet(5, 0.1));
    let mut ca = Contact::new(&Device::cpu(), &rust_model(&a, 0.2)).unwrap();
    let mut cb = Contact::new(&Device::cpu(), &rust_model(&b, 0.2)).unwrap();
    ca.penalty_step(&a.coords, &start_velocities(&a), 1e-4)
        .unwrap();
    let saved = ca.save_state().unwrap();
    let e = cb.restore_state(&saved).unwrap_err().to_string();
    assert!(
        e.contains("slaves of a penalty pass") && e.contains("25") && e.contains("16"),
        "{e}"
    );
    cb.restore_state(&cb.save_state().unwrap()).unwrap();
}

#[test]
fn bad_input_across_the_c_abi_gives_named_errors_never_a_crash() {
    let s = sheet(3, 0.2);
    let n = s.coords.len();
    unsafe {
        // handles: null, freed, wrong kind, never made
        let mut m = null_mut();
        fails(
            abut_model_new(4, &mut m),
            AbutStatus::BadValue,
            &["dim = 4"],
        );
        fails(
            abut_model_new(3, null_mut()),
            AbutStatus::NullPointer,
            &["abut_model_new", "out"],
        );
        fails(
            abut_model_add_nodes(null_mut(), null(), null(), 0, null_mut()),
            AbutStatus::NullPointer,
            &["model handle is null"],
        );
        let model = c_model(&s, 0.0);
        ok(abut_model_free(model));
        fails(
            abut_model_add_nodes(
                model,
                s.coords.as_flattened().as_ptr(),
                s.masses.as_ptr(),
                1,
                null_mut(),
            ),
            AbutStatus::BadHandle,
            &["abut_model_add_nodes", "not live", "freed"],
        );
        fails(abut_model_free(model), AbutStatus::BadHandle, &["not live"]);
        fails(
            abut_model_add_nodes(0xdead0 as *mut AbutModel, null(), null(), 0, null_mut()),
            AbutStatus::BadHandle,
            &["not live"],
        );
        let model = c_model(&s, 0.0);
        fails(
            abut_contact_penalty_step(
                model as *mut AbutContact,
                null(),
                null(),
                0,
                1.0,
                null_mut(),
                0,
            ),
            AbutStatus::BadHandle,
            &["is a model, not a contact"],
        );
        let mut msg = vec![0u8; 256];
        let mut len = 0;
        ok(abut_model_error(
            model,
            msg.as_mut_ptr(),
            msg.len(),
            &mut len,
        ));
        assert!(String::from_utf8_lossy(&msg[..len]).contains("not a contact"));
        // truncation: the full length is told, the buffer holds what fits and a NUL
        let mut small = [0xffu8; 8];
        ok(abut_model_error(
            model,
            small.as_mut_ptr(),
            small.len(),
            &mut len,
        ));
        assert!(len > 8 && small[7] == 0);

        // model input: null arrays, NaN, bad masses, out-of-range ids, repeated nodes
        fails(
            abut_model_add_nodes(model, null(), s.masses.as_ptr(), 1, null_mut()),
            AbutStatus::NullPointer,
            &["coords"],
        );
        let nan = [0.0, f64::NAN, 1.0];
        fails(
            abut_model_add_nodes(model, nan.as_ptr(), [1.0].as_ptr(), 1, null_mut()),
            AbutStatus::BadValue,
            &["coordinate 1", "NaN"],
        );
        fails(
            abut_model_add_nodes(model, [0.0; 3].as_ptr(), [-1.0].as_ptr(), 1, null_mut()),
            AbutStatus::BadValue,
            &["mass -1"],
        );
        let mut id = 0;
        let far = [0u32, 1, 2, 99];
        fails(
            abut_model_add_surface(model, 4, far.as_ptr(), 1, &mut id),
            AbutStatus::OutOfRange,
            &["99"],
        );
        fails(
            abut_model_add_surface(model, 5, far.as_ptr(), 1, &mut id),
            AbutStatus::BadValue,
            &["AbutFacetKind", "5"],
        );
        let rep = [0u32, 1, 1, 2];
        fails(
            abut_model_add_surface(model, 4, rep.as_ptr(), 1, &mut id),
            AbutStatus::Geometry,
            &["node 1", "more than once"],
        );
        fails(
            abut_model_add_node_set(model, [0u32, 500].as_ptr(), 2, null(), &mut id),
            AbutStatus::OutOfRange,
            &["500"],
        );
        fails(
            abut_model_add_node_set(
                model,
                [0u32, 1].as_ptr(),
                2,
                [1.0, f64::NAN].as_ptr(),
                &mut id,
            ),
            AbutStatus::BadValue,
            &["tributary area", "entry 1"],
        );
        fails(
            abut_model_add_pair(model, 7, 0, null(), &mut id),
            AbutStatus::OutOfRange,
            &["7"],
        );
        fails(
            abut_model_add_pair(model, 0, 3, null(), &mut id),
            AbutStatus::OutOfRange,
            &["3"],
        );
        let mut o = std::mem::zeroed();
        ok(abut_pair_options_default(&mut o));
        o.enforcement = 9;
        fails(
            abut_model_add_pair(model, 0, 0, &o, &mut id),
            AbutStatus::BadValue,
            &["options.enforcement", "9"],
        );
        ok(abut_pair_options_default(&mut o));
        o.friction = 1;
        o.mu = f64::NAN;
        fails(
            abut_model_add_pair(model, 0, 0, &o, &mut id),
            AbutStatus::BadValue,
            &["friction"],
        );
        ok(abut_pair_options_default(&mut o));
        o.law.kind = AbutLawKind::Tabular as i32;
        o.law.table_points = 2;
        fails(
            abut_model_add_pair(model, 0, 0, &o, &mut id),
            AbutStatus::NullPointer,
            &["law.table"],
        );
        ok(abut_pair_options_default(&mut o));
        o.search_radius = -1.0;
        fails(
            abut_model_add_pair(model, 0, 0, &o, &mut id),
            AbutStatus::BadValue,
            &["radius"],
        );
        let surf = AbutAnalytical {
            kind: 0,
            point: [0.0; 3],
            direction: [0.0; 3],
            radius: 0.0,
        };
        let eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        fails(
            abut_model_add_rigid_body(model, 1.0, eye.as_ptr(), &surf, &mut id),
            AbutStatus::BadValue,
            &["plane"],
        );
        fails(
            abut_model_add_rigid_body(model, 1.0, null(), &surf, &mut id),
            AbutStatus::NullPointer,
            &["inertia"],
        );
        fails(
            abut_model_add_rigid_pair(model, 0, 4, null(), &mut id),
            AbutStatus::OutOfRange,
            &["4"],
        );
        fails(
            abut_model_add_rigid_part(model, [0u32, 0].as_ptr(), 2, 1.0, eye.as_ptr(), null_mut()),
            AbutStatus::BadValue,
            &["node 0"],
        );

        // devices
        let mut dev = null_mut();
        fails(
            abut_device_new(7, 0, null(), &mut dev),
            AbutStatus::BadValue,
            &["AbutDeviceKind"],
        );
        fails(
            abut_device_new(2, 42, null(), &mut dev),
            AbutStatus::BadValue,
            &["AbutBackend", "42"],
        );
        let nowhere = std::ffi::CString::new("no adapter has this name").unwrap();
        fails(
            abut_device_new(2, 0, nowhere.as_ptr(), &mut dev),
            AbutStatus::Device,
            &["no adapter has this name"],
        );
        ok(abut_device_new(
            AbutDeviceKind::Cpu as i32,
            0,
            null(),
            &mut dev,
        ));

        // the contact: lengths, NaN, dt, ids, passes, modes, outputs not asked for
        let mut c = null_mut();
        fails(
            abut_contact_new(dev, null(), &mut c),
            AbutStatus::NullPointer,
            &["model handle is null"],
        );
        fails(
            abut_contact_new(model as *const AbutDevice, model, &mut c),
            AbutStatus::BadHandle,
            &["is a model, not a device"],
        );
        ok(abut_contact_new(dev, model, &mut c));
        let (x, v) = (s.coords.as_flattened().to_vec(), vec![0.0; 3 * n]);
        let mut f = vec![0.0; 3 * n];
        let step = |c, x: &[f64], v: &[f64], n, dt, f: &mut [f64], mode| {
            abut_contact_penalty_step(c, x.as_ptr(), v.as_ptr(), n, dt, f.as_mut_ptr(), mode)
        };
        fails(
            step(c, &x, &v, n - 1, 1e-4, &mut f, 0),
            AbutStatus::Length,
            &[
                "positions (one per model node)",
                &format!("expected {n}"),
                &format!("got {}", n - 1),
            ],
        );
        let mut xn = x.clone();
        xn[3 * 5 + 2] = f64::INFINITY;
        fails(
            step(c, &xn, &v, n, 1e-4, &mut f, 0),
            AbutStatus::BadValue,
            &["node 5", "coordinate 2", "inf"],
        );
        let mut vn = v.clone();
        vn[4] = f64::NAN;
        fails(
            step(c, &x, &vn, n, 1e-4, &mut f, 0),
            AbutStatus::BadValue,
            &["NaN"],
        );
        fails(
            step(c, &x, &v, n, 0.0, &mut f, 0),
            AbutStatus::BadValue,
            &["dt"],
        );
        fails(
            step(c, &x, &v, n, f64::NAN, &mut f, 0),
            AbutStatus::BadValue,
            &["dt"],
        );
        fails(
            step(c, &x, &v, n, 1e-4, &mut f, 3),
            AbutStatus::BadValue,
            &["AbutForceMode"],
        );
        fails(
            abut_contact_penalty_step(c, x.as_ptr(), v.as_ptr(), n, 1e-4, null_mut(), 0),
            AbutStatus::NullPointer,
            &["forces"],
        );
        fails(
            abut_contact_penalty_step(c, x.as_ptr(), null(), n, 1e-4, f.as_mut_ptr(), 0),
            AbutStatus::NullPointer,
            &["argument v"],
        );
        let odd = (x.as_ptr() as *const u8).add(1) as *const f64;
        fails(
            abut_contact_penalty_step(c, odd, v.as_ptr(), n, 1e-4, f.as_mut_ptr(), 0),
            AbutStatus::BadValue,
            &["aligned"],
        );
        ok(step(c, &x, &v, n, 1e-4, &mut f, 0));
        let mut len = 0;
        fails(
            abut_contact_output_len(c, 0, 3, 0, &mut len),
            AbutStatus::OutOfRange,
            &["pair 3"],
        );
        fails(
            abut_contact_output_len(c, 0, 0, 1, &mut len),
            AbutStatus::OutOfRange,
            &["pass 1", "1 pass"],
        );
        fails(
            abut_contact_output_len(c, 1, 0, 0, &mut len),
            AbutStatus::OutOfRange,
            &["pair 0"],
        );
        fails(
            abut_contact_output_len(c, 2, 0, 0, &mut len),
            AbutStatus::BadValue,
            &["AbutPairKind"],
        );
        ok(abut_contact_output_len(c, 0, 0, 0, &mut len));
        let mut cpress = vec![0.0; len];
        let mut arrays = AbutOutputArrays {
            len,
            slaves: null_mut(),
            cstatus: null_mut(),
            copen: null_mut(),
            cpress: cpress.as_mut_ptr(),
            cshear1: null_mut(),
            cshear2: null_mut(),
            normal: null_mut(),
            force: null_mut(),
        };
        fails(
            abut_contact_output(c, 0, 0, 0, &arrays, null_mut()),
            AbutStatus::BadValue,
            &["arrays.cpress", "abut_contact_request_outputs"],
        );
        arrays.len = len + 1;
        fails(
            abut_contact_output(c, 0, 0, 0, &arrays, null_mut()),
            AbutStatus::Length,
            &["arrays.len"],
        );
        let mut bodies = [AbutBodyState {
            position: [0.0; 3],
            rotation: eye,
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        }];
        let (mut xk, mut vk) = (x.clone(), v.clone());
        fails(
            abut_contact_kinematic_step(
                c,
                xk.as_mut_ptr(),
                vk.as_mut_ptr(),
                n,
                null_mut(),
                1,
                1e-4,
            ),
            AbutStatus::NullPointer,
            &["bodies"],
        );
        fails(
            abut_contact_kinematic_step(
                c,
                xk.as_mut_ptr(),
                vk.as_mut_ptr(),
                n + 1,
                bodies.as_mut_ptr(),
                1,
                1e-4,
            ),
            AbutStatus::Length,
            &["positions (one per model node)"],
        );
        ok(abut_contact_kinematic_step(
            c,
            xk.as_mut_ptr(),
            vk.as_mut_ptr(),
            n,
            null_mut(),
            0,
            1e-4,
        ));
        fails(
            abut_contact_set_reference_increment(c, -1.0),
            AbutStatus::BadValue,
            &["dt"],
        );
        let mut buf = [0u8; 4];
        fails(
            abut_contact_restore_state(c, buf.as_mut_ptr(), 4),
            AbutStatus::BadValue,
            &["saved contact state"],
        );
        fails(
            abut_contact_restore_state(c, null(), 4),
            AbutStatus::NullPointer,
            &["buf"],
        );
        ok(abut_contact_error(c, buf.as_mut_ptr(), buf.len(), &mut len));
        assert!(len > 0);
        ok(abut_contact_free(c));
        fails(
            abut_contact_report(c, &mut AbutReport::default()),
            AbutStatus::BadHandle,
            &["abut_contact_report", "not live"],
        );
        fails(abut_contact_free(c), AbutStatus::BadHandle, &["not live"]);
        ok(abut_device_free(dev));
        ok(abut_model_free(model));
        ok(abut_contact_free(null_mut()));
    }
}

#[test]
fn c_abi_kinematic_increments_equal_the_rust_apis_bit_for_bit() {
    // the sheet on the plate by a kinematic pair with friction; the plate's nodes on a rigid
    // plane below by a rigid pair; every node falls under gravity and the plane's body moves
    let s = sheet(5, 0.15);
    let plate_nodes: Vec<u32> = (0..16).collect();
    let (dt, eye) = (2e-4, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let mut rm = Model::new_3d();
    rm.add_nodes(&s.coords, &s.masses).unwrap();
    let plate = rm.add_surface(Surface::quads(&s.quads)).unwrap();
    let set = rm.add_node_set(&s.slaves).unwrap();
    let under = rm.add_node_set(&plate_nodes).unwrap();
    rm.add_pair(
        Pair::new(set, plate)
            .friction(Friction::coulomb(0.3))
            .enforce(abut::Enforce::Kinematic(abut::Kinematic::default())),
    )
    .unwrap();
    let plane = abut::Analytical::Plane {
        point: [0.0, 0.0, -0.002],
        normal: [0.0, 0.0, 1.0],
    };
    let body = rm
        .add_rigid_body(abut::RigidBody {
            mass: 100.0,
            inertia: eye,
            surface: plane,
        })
        .unwrap();
    rm.add_rigid_pair(abut::RigidPair {
        slave: under,
        body,
        softened: None,
    })
    .unwrap();
    let cm = c_model(&s, 0.0); // nodes, plate, sheet set (and a penalty pair, pair 0)
    let flat_eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    unsafe {
        let (mut under_c, mut pair, mut body_c) = (0, 0, 0);
        ok(abut_model_add_node_set(
            cm,
            plate_nodes.as_ptr(),
            16,
            null(),
            &mut under_c,
        ));
        let mut o = std::mem::zeroed();
        ok(abut_pair_options_default(&mut o));
        o.enforcement = AbutEnforcement::Kinematic as i32;
        o.friction = 1;
        o.mu = 0.3;
        ok(abut_model_add_pair(cm, 0, 0, &o, &mut pair));
        let surf = AbutAnalytical {
            kind: AbutSurfaceKind::Plane as i32,
            point: [0.0, 0.0, -0.002],
            direction: [0.0, 0.0, 1.0],
            radius: 0.0,
        };
        ok(abut_model_add_rigid_body(
            cm,
            100.0,
            flat_eye.as_ptr(),
            &surf,
            &mut body_c,
        ));
        ok(abut_model_add_rigid_pair(
            cm,
            under_c,
            body_c,
            null(),
            &mut pair,
        ));
    }
    for d in devices() {
        let mut rust = Contact::new(&d, &rm).unwrap();
        let dev = c_device(&d);
        let mut c = null_mut();
        unsafe {
            ok(abut_contact_new(dev, cm, &mut c));
            ok(abut_device_free(dev));
        }
        let (mut xr, mut vr) = (s.coords.clone(), start_velocities(&s));
        let (mut xc, mut vc) = (xr.clone(), vr.clone());
        let mut br = vec![abut::BodyState::at([0.0, 0.0, 0.0])];
        let mut bc = [AbutBodyState {
            position: [0.0; 3],
            rotation: flat_eye,
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        }];
        let mut corrected = 0;
        for inc in 0..80 {
            // the host's predictor: gravity on every node, the body coasting
            for (x, v) in [(&mut xr, &mut vr), (&mut xc, &mut vc)] {
                for k in 0..x.len() {
                    v[k][2] -= dt * 200.0;
                    for a in 0..3 {
                        x[k][a] += dt * v[k][a];
                    }
                }
            }
            for a in 0..3 {
                br[0].position[a] += dt * br[0].velocity[a];
                bc[0].position[a] += dt * bc[0].velocity[a];
            }
            let r = rust
                .kinematic_step(&mut xr, &mut vr, &mut br, dt)
                .unwrap()
                .clone();
            unsafe {
                ok(abut_contact_kinematic_step(
                    c,
                    xc.as_flattened_mut().as_mut_ptr(),
                    vc.as_flattened_mut().as_mut_ptr(),
                    xc.len(),
                    bc.as_mut_ptr(),
                    1,
                    dt,
                ))
            };
            let bits = |a: &[[f64; 3]]| {
                a.as_flattened()
                    .iter()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&xr), bits(&xc), "{d}: positions at increment {inc}");
            assert_eq!(bits(&vr), bits(&vc), "{d}: velocities at increment {inc}");
            assert_eq!(
                bits(&[br[0].position, br[0].velocity]),
                bits(&[bc[0].position, bc[0].velocity])
            );
            let mut kr = AbutKinematicReport::default();
            unsafe { ok(abut_contact_kinematic_report(c, &mut kr)) };
            assert_eq!(kr.active, r.active as u64);
            assert_eq!(
                kr.kinetic_energy_change.to_bits(),
                r.kinetic_energy_change.to_bits()
            );
            corrected += r.active;
            // rigid outputs through the C arrays
            let mut len = 0;
            unsafe {
                ok(abut_contact_output_len(
                    c,
                    AbutPairKind::Rigid as i32,
                    0,
                    0,
                    &mut len,
                ))
            };
            assert_eq!(len, 16);
        }
        assert!(corrected > 100, "{d}: {corrected} corrections");
        unsafe { ok(abut_contact_free(c)) };
    }
    unsafe { ok(abut_model_free(cm)) };
}
