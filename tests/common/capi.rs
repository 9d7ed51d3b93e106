//! Helpers of the C ABI's tests (tests/capi.rs, tests/capi_errors.rs): a sheet on a plate
//! built through the Rust API and through the C ABI, status checks, C devices like Rust ones.

use abut::capi::*;
use abut::{Device, Friction, Model, Pair, Surface};
use std::ptr::{null, null_mut};

/// A sheet of `n`×`n` slave nodes (spacing `h`, mass 0.01) just above a plate of 3×3 quads
/// (span 2, the master): coordinates, masses, the plate's quads and the sheet's node ids.
pub struct Sheet {
    pub coords: Vec<[f64; 3]>,
    pub masses: Vec<f64>,
    pub quads: Vec<[u32; 4]>,
    pub slaves: Vec<u32>,
}

pub fn sheet(n: usize, h: f64) -> Sheet {
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

pub fn rust_model(s: &Sheet, mu: f64) -> Model {
    let mut m = Model::new_3d();
    m.add_nodes(&s.coords, &s.masses).unwrap();
    let plate = m.add_surface(Surface::quads(&s.quads)).unwrap();
    let set = m.add_node_set(&s.slaves).unwrap();
    m.add_pair(Pair::new(set, plate).friction(Friction::coulomb(mu)))
        .unwrap();
    m
}

/// The same model through the C ABI; returns the handle.
pub fn c_model(s: &Sheet, mu: f64) -> *mut AbutModel {
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
pub fn ok(s: AbutStatus) {
    assert_eq!(s, AbutStatus::Ok, "{}", last_error());
}

pub fn last_error() -> String {
    let mut buf = vec![0u8; 1024];
    let mut len = 0;
    unsafe { abut_last_error(buf.as_mut_ptr(), buf.len(), &mut len) };
    String::from_utf8_lossy(&buf[..len.min(1023)]).into_owned()
}

/// Asserts `s` is `want` and the thread's last error contains every one of `words`.
#[track_caller]
pub fn fails(s: AbutStatus, want: AbutStatus, words: &[&str]) {
    let msg = last_error();
    assert_eq!(s, want, "{msg}");
    for w in words {
        assert!(msg.contains(w), "'{msg}' does not name '{w}'");
    }
}

/// A C device like `d` (the CPU path, or the same adapter by backend and name).
pub fn c_device(d: &Device) -> *mut AbutDevice {
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

pub fn devices() -> Vec<Device> {
    super::devices()
}

/// One penalty increment through the C ABI on the caller's arrays.
pub fn c_step(
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
pub fn advance(s: &Sheet, x: &mut [[f64; 3]], v: &mut [[f64; 3]], f: &[[f64; 3]], dt: f64) {
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

pub fn start_velocities(s: &Sheet) -> Vec<[f64; 3]> {
    let mut v = vec![[0.0; 3]; s.coords.len()];
    for &n in &s.slaves {
        v[n as usize] = [0.8, -0.3, -0.05];
    }
    v
}
