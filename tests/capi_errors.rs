//! Bad input across the C ABI (`abut::capi`, what libabut exports): null pointers and handles,
//! freed and wrong-kind handles, lengths, ids out of range, NaN, unknown enumeration values,
//! bad saved states — each a named error with its status, never a crash.
#![cfg(feature = "capi")]

mod common;

use abut::capi::*;
use common::capi::*;
use std::ptr::{null, null_mut};

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
