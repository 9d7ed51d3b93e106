//! The C ABI (`abut::capi`, what libabut exports) called as a C host calls it: the same
//! penalty and kinematic increments as the Rust API bit for bit on the CPU path and every
//! adapter, the output variables, and a restart from saved state continuing bit for bit. Bad
//! input: tests/capi_errors.rs.
#![cfg(feature = "capi")]

mod common;

use abut::capi::*;
use abut::{Contact, Device, Friction, Model, Pair, Surface};
use common::capi::*;
use std::ptr::{null, null_mut};

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

#[test]
fn the_combined_increment_is_the_rust_one_and_refuses_what_is_not_positive() {
    for (e, c) in [
        (1e-5, 3e-5),
        (2e-6, 1e-6),
        (1e-4, f64::INFINITY),
        (f64::INFINITY, 5e-5),
    ] {
        let mut dt = 0.0;
        unsafe { ok(abut_combined_increment(e, c, 0.9, 0.5, &mut dt)) };
        assert_eq!(
            dt.to_bits(),
            abut::combined_increment(e, c, 0.9, 0.5).to_bits()
        );
    }
    let mut dt = 0.0;
    let s = unsafe { abut_combined_increment(1e-5, f64::NAN, 0.9, 0.5, &mut dt) };
    fails(s, AbutStatus::BadValue, &["contact_dt = NaN"]);
    let s = unsafe { abut_combined_increment(1e-5, 1e-5, 0.0, 0.5, &mut dt) };
    fails(s, AbutStatus::BadValue, &["safety = 0"]);
    let s = unsafe { abut_combined_increment(1e-5, 1e-5, 0.9, 0.5, null_mut()) };
    fails(s, AbutStatus::NullPointer, &["dt"]);
}
