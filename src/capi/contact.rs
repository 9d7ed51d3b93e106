//! C ABI: the contact — one increment per call on the caller's arrays, its report, the output
//! variables and the state for a restart.

use super::handles::{self, Fail, Object};
use super::types::*;
use super::{copy_text, input, output, put, times};
use crate::{BodyState, Contact, ContactStatus, PairOutput};

/// The contact of a model on a device: search and enforcement of every pair, once per
/// increment. Opaque; made by `abut_contact_new`, freed by `abut_contact_free`.
pub struct AbutContact {
    _opaque: [u8; 0],
}

/// Makes the contact of `model` on `device` (pipelines compiled, buffers made); `*out` receives
/// the handle. The model and device may be freed afterwards.
///
/// # Safety
/// `out` valid for one handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_new(
    device: *const super::AbutDevice,
    model: *const super::AbutModel,
    out: *mut *mut AbutContact,
) -> AbutStatus {
    const CALL: &str = "abut_contact_new";
    if out.is_null() {
        return handles::guard(CALL, || Err(super::null(CALL, "out")));
    }
    handles::with_device_and_model(device as usize, model as usize, CALL, |d, m| {
        let c = Contact::new(d, m)?;
        let h = handles::register(Object::Contact(Box::new(c)));
        unsafe { put(out, h as *mut AbutContact, CALL, "out") }
    })
}

/// Frees a contact (null: nothing).
///
/// # Safety
/// None beyond passing a value abut gave.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_free(contact: *mut AbutContact) -> AbutStatus {
    handles::release(contact as usize, "abut_contact_free", "contact")
}

/// Copies the last error message of `contact` into `buf` (as `abut_last_error`).
///
/// # Safety
/// As `abut_last_error`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_error(
    contact: *const AbutContact,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
) -> AbutStatus {
    unsafe { super::device::handle_error(contact as usize, "abut_contact_error", buf, cap, len) }
}

/// Non-zero `yes`: compute the output variables every increment (`abut_contact_output`); off
/// by default, when only forces and the report come back.
#[unsafe(no_mangle)]
pub extern "C" fn abut_contact_request_outputs(contact: *mut AbutContact, yes: i32) -> AbutStatus {
    handles::with_contact(contact as usize, "abut_contact_request_outputs", |c| {
        c.request_outputs(yes != 0);
        Ok(())
    })
}

/// Sets the reference increment of the automatic penalty stiffness (default: the first
/// increment's `dt`).
#[unsafe(no_mangle)]
pub extern "C" fn abut_contact_set_reference_increment(
    contact: *mut AbutContact,
    dt: f64,
) -> AbutStatus {
    handles::with_contact(
        contact as usize,
        "abut_contact_set_reference_increment",
        |c| Ok(c.set_reference_increment(dt)?),
    )
}

/// One penalty increment: every penalty pair searched at positions `x` and its forces computed
/// from the gaps and the velocities `v` (at the half step before, central differences) over
/// increment `dt`. `x`, `v` and `forces` hold 3 doubles per model node, xyz interleaved, and
/// `n_nodes` must be the model's node count. `mode` (an `AbutForceMode`) writes the contact
/// forces into `forces` or adds them to what it holds. `x` and `v` are read in place (no copy
/// but the device upload); `forces` must not overlap them. The report: `abut_contact_report`.
///
/// # Safety
/// `x`, `v` and `forces` valid for `3·n_nodes` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_penalty_step(
    contact: *mut AbutContact,
    x: *const f64,
    v: *const f64,
    n_nodes: usize,
    dt: f64,
    forces: *mut f64,
    mode: i32,
) -> AbutStatus {
    const CALL: &str = "abut_contact_penalty_step";
    handles::with_contact(contact as usize, CALL, |c| {
        let mode = enum_value(
            mode,
            "abut_contact_penalty_step: mode (an AbutForceMode)",
            &[(0, AbutForceMode::Write), (1, AbutForceMode::Add)],
        )?;
        let (x, v) = unsafe { (xyz(x, n_nodes, CALL, "x")?, xyz(v, n_nodes, CALL, "v")?) };
        if forces.is_null() {
            return Err(super::null(CALL, "forces"));
        }
        let report = c.penalty_step(x, v, dt)?;
        let out = unsafe { output(forces, times(n_nodes, 3, CALL, "forces")?, CALL, "forces")? };
        let f = report.forces.as_flattened();
        match mode {
            AbutForceMode::Write => out.copy_from_slice(f),
            AbutForceMode::Add => out.iter_mut().zip(f).for_each(|(o, f)| *o += f),
        }
        Ok(())
    })
}

/// The caller's `3·n` doubles at `p` as points (no copy).
unsafe fn xyz<'a>(p: *const f64, n: usize, call: &str, arg: &str) -> Result<&'a [[f64; 3]], Fail> {
    let flat = unsafe { input(p, times(n, 3, call, arg)?, call, arg)? };
    Ok(bytemuck::cast_slice(flat))
}

/// As [`xyz`], writable.
unsafe fn xyz_mut<'a>(
    p: *mut f64,
    n: usize,
    call: &str,
    arg: &str,
) -> Result<&'a mut [[f64; 3]], Fail> {
    let flat = unsafe { output(p, times(n, 3, call, arg)?, call, arg)? };
    Ok(bytemuck::cast_slice_mut(flat))
}

fn body_in(b: &AbutBodyState) -> BodyState {
    let r = b.rotation;
    BodyState {
        position: b.position,
        rotation: [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]],
        velocity: b.velocity,
        angular_velocity: b.angular_velocity,
    }
}

fn body_out(b: &BodyState) -> AbutBodyState {
    AbutBodyState {
        position: b.position,
        rotation: *b.rotation.as_flattened().first_chunk::<9>().expect("3×3"),
        velocity: b.velocity,
        angular_velocity: b.angular_velocity,
    }
}

/// One kinematic increment: `x` the positions the host predicted for the end of the increment
/// without contact and `v` the velocities that took it there (3 doubles per node, `n_nodes`
/// the model's node count); `bodies` the predicted states of the model's `n_bodies` rigid bodies
/// (may be null when there are none). Every kinematic pair is searched at `x` and its
/// penetrating slave nodes corrected: `x`, `v` and `bodies` are corrected in place. The report:
/// `abut_contact_kinematic_report`.
///
/// # Safety
/// `x` and `v` valid for `3·n_nodes` doubles, not overlapping; `bodies` null or valid for
/// `n_bodies` states.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_kinematic_step(
    contact: *mut AbutContact,
    x: *mut f64,
    v: *mut f64,
    n_nodes: usize,
    bodies: *mut AbutBodyState,
    n_bodies: usize,
    dt: f64,
) -> AbutStatus {
    const CALL: &str = "abut_contact_kinematic_step";
    handles::with_contact(contact as usize, CALL, |c| {
        let x = unsafe { xyz_mut(x, n_nodes, CALL, "x")? };
        let v = unsafe { xyz_mut(v, n_nodes, CALL, "v")? };
        let mut states = bodies_in(bodies, n_bodies, CALL)?;
        c.kinematic_step(x, v, &mut states, dt)?;
        if n_bodies > 0 {
            let out = unsafe { output(bodies, n_bodies, CALL, "bodies")? };
            for (o, s) in out.iter_mut().zip(&states) {
                *o = body_out(s);
            }
        }
        Ok(())
    })
}

fn bodies_in(p: *const AbutBodyState, n: usize, call: &str) -> Result<Vec<BodyState>, Fail> {
    if n == 0 {
        return Ok(Vec::new());
    }
    let b = unsafe { input(p, n, call, "bodies")? };
    Ok(b.iter().map(body_in).collect())
}

/// Moves every initially overclosed slave node onto its master, strain-free, as Abaqus adjusts
/// initial positions: call once with the initial positions `x` (corrected in place), the bodies'
/// states and the first increment. `*max_distance` (may be null) receives the largest move.
///
/// # Safety
/// `x` valid for `3·n_nodes` doubles; `bodies` null or valid for `n_bodies`; `max_distance`
/// null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_adjust_initial_overclosure(
    contact: *mut AbutContact,
    x: *mut f64,
    n_nodes: usize,
    bodies: *const AbutBodyState,
    n_bodies: usize,
    dt: f64,
    max_distance: *mut f64,
) -> AbutStatus {
    const CALL: &str = "abut_contact_adjust_initial_overclosure";
    handles::with_contact(contact as usize, CALL, |c| {
        let x = unsafe { xyz_mut(x, n_nodes, CALL, "x")? };
        let states = bodies_in(bodies, n_bodies, CALL)?;
        let r = c.adjust_initial_overclosure(x, &states, dt)?;
        if !max_distance.is_null() {
            unsafe { put(max_distance, r.max_distance, CALL, "max_distance")? };
        }
        Ok(())
    })
}

/// `*report` receives what the last penalty increment gave.
///
/// # Safety
/// `report` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_report(
    contact: *const AbutContact,
    report: *mut AbutReport,
) -> AbutStatus {
    const CALL: &str = "abut_contact_report";
    handles::with_contact(contact as usize, CALL, |c| {
        let r = c.report();
        let f = r.fastest;
        let out = AbutReport {
            stable_dt: r.stable_dt,
            approach_dt: r.approach_dt,
            max_overclosure: r.max_overclosure,
            active: r.active as u64,
            slipping: r.slipping as u64,
            global_searches: r.global_searches as u64,
            fallbacks: r.fallbacks as u64,
            unanchored: r.unanchored as u64,
            fast_nodes: r.fast_nodes as u64,
            fastest_node: f.map_or(-1, |f| f.node as i64),
            fastest_pair: f.map_or(0, |f| f.pair.0 as u32),
            fastest_distance: f.map_or(0.0, |f| f.distance),
            fastest_radius: f.map_or(0.0, |f| f.radius),
            stable_dt_before_contact: r.stable_dt_before_contact as i32,
        };
        unsafe { put(report, out, CALL, "report") }
    })
}

/// `*report` receives what the last kinematic increment did.
///
/// # Safety
/// `report` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_kinematic_report(
    contact: *const AbutContact,
    report: *mut AbutKinematicReport,
) -> AbutStatus {
    const CALL: &str = "abut_contact_kinematic_report";
    handles::with_contact(contact as usize, CALL, |c| {
        let r = c.kinematic_report();
        let f = r.fastest;
        let out = AbutKinematicReport {
            active: r.active as u64,
            max_overclosure: r.max_overclosure,
            max_overclosure_after: r.max_overclosure_after,
            kinetic_energy_change: r.kinetic_energy_change,
            total_force: r.total_force,
            friction_force: r.friction_force,
            fast_nodes: r.fast_nodes as u64,
            fastest_node: f.map_or(-1, |f| f.node as i64),
            fastest_distance: f.map_or(0.0, |f| f.distance),
            fastest_radius: f.map_or(0.0, |f| f.radius),
        };
        unsafe { put(report, out, CALL, "report") }
    })
}

/// Copies the warnings of the last penalty and kinematic increments (fast nodes, unanchored
/// slaves, chunked tree walks), one per line, into `buf` as `abut_last_error` copies text; an
/// empty text: none. `*count` (may be null) receives their number.
///
/// # Safety
/// `buf` valid for `cap` bytes; `len`, `count` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_warnings(
    contact: *const AbutContact,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
    count: *mut usize,
) -> AbutStatus {
    const CALL: &str = "abut_contact_warnings";
    handles::with_contact(contact as usize, CALL, |c| {
        let mut w = c.report().warnings();
        w.extend(c.kinematic_report().warnings());
        if !count.is_null() {
            unsafe { put(count, w.len(), CALL, "count")? };
        }
        unsafe { copy_text(&w.join("\n"), buf, cap, len, CALL) }
    })
}

/// The output of pass `pass` of pair `pair` of `kind`.
fn find_output<'a>(
    c: &'a Contact,
    kind: i32,
    pair: u32,
    pass: u32,
    call: &str,
) -> Result<&'a PairOutput, Fail> {
    let kind = enum_value(
        kind,
        &format!("{call}: kind (an AbutPairKind)"),
        &[(0, AbutPairKind::Meshed), (1, AbutPairKind::Rigid)],
    )?;
    let outputs: Vec<&PairOutput> = match kind {
        AbutPairKind::Meshed => c
            .outputs()
            .into_iter()
            .filter(|(id, _)| id.0 == pair as usize)
            .map(|(_, o)| o)
            .collect(),
        AbutPairKind::Rigid => c
            .rigid_outputs()
            .into_iter()
            .filter(|(id, _)| id.0 == pair as usize)
            .map(|(_, o)| o)
            .collect(),
    };
    if outputs.is_empty() {
        return Err(Fail::new(
            AbutStatus::OutOfRange,
            format!("{call}: pair {pair} has no outputs (no such pair of this kind)"),
        ));
    }
    let n = outputs.len();
    outputs.get(pass as usize).copied().ok_or_else(|| {
        Fail::new(
            AbutStatus::OutOfRange,
            format!("{call}: pass {pass} of pair {pair}: the pair has {n} pass(es)"),
        )
    })
}

/// `*len` receives the number of slaves in pass `pass` (0; 1 for a balanced pair's
/// master-on-slave pass) of pair `pair` of `kind` (an `AbutPairKind`): the length of the
/// arrays `abut_contact_output` fills. 0 before the pair's first increment.
///
/// # Safety
/// `len` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_output_len(
    contact: *const AbutContact,
    kind: i32,
    pair: u32,
    pass: u32,
    len: *mut usize,
) -> AbutStatus {
    const CALL: &str = "abut_contact_output_len";
    handles::with_contact(contact as usize, CALL, |c| {
        let o = find_output(c, kind, pair, pass, CALL)?;
        unsafe { put(len, o.slaves.len(), CALL, "len") }
    })
}

/// Fills the caller's `arrays` (any pointer null: skipped; `arrays->len` must be
/// `abut_contact_output_len`'s count) and `*totals` (may be null) with the output variables of
/// pass `pass` of pair `pair` of `kind` after the last increment: CSTATUS, COPEN, CPRESS,
/// CSHEAR1/2, normals, forces; CFN, CFS, contact energy, frictional dissipation. Penalty pairs
/// need `abut_contact_request_outputs` first.
///
/// # Safety
/// `arrays` valid, each non-null pointer in it valid for its length; `totals` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_output(
    contact: *const AbutContact,
    kind: i32,
    pair: u32,
    pass: u32,
    arrays: *const AbutOutputArrays,
    totals: *mut AbutOutputTotals,
) -> AbutStatus {
    const CALL: &str = "abut_contact_output";
    handles::with_contact(contact as usize, CALL, |c| {
        let o = find_output(c, kind, pair, pass, CALL)?;
        let a = unsafe { input(arrays, 1, CALL, "arrays")?[0] };
        let n = o.slaves.len();
        if a.len != n {
            return Err(Fail::new(
                AbutStatus::Length,
                format!(
                    "{CALL}: arrays.len = {}, but pass {pass} of pair {pair} has {n} slaves",
                    a.len
                ),
            ));
        }
        unsafe {
            fill(a.slaves, &o.slaves, n, 1, "arrays.slaves", |s, d| d[0] = *s)?;
            fill(a.cstatus, &o.cstatus, n, 1, "arrays.cstatus", |s, d| {
                d[0] = match s {
                    None => AbutCstatus::Unknown,
                    Some(ContactStatus::Open) => AbutCstatus::Open,
                    Some(ContactStatus::Stick) => AbutCstatus::Stick,
                    Some(ContactStatus::Slip) => AbutCstatus::Slip,
                } as i32
            })?;
            for (p, src, what) in [
                (a.copen, &o.copen, "arrays.copen"),
                (a.cpress, &o.cpress, "arrays.cpress"),
                (a.cshear1, &o.cshear1, "arrays.cshear1"),
                (a.cshear2, &o.cshear2, "arrays.cshear2"),
            ] {
                fill(p, src, n, 1, what, |s, d| d[0] = *s)?;
            }
            fill(a.normal, &o.normal, n, 3, "arrays.normal", |s, d| {
                d.copy_from_slice(s)
            })?;
            fill(a.force, &o.force, n, 3, "arrays.force", |s, d| {
                d.copy_from_slice(s)
            })?;
        }
        if !totals.is_null() {
            let t = AbutOutputTotals {
                cfn: o.cfn,
                cfs: o.cfs,
                contact_energy: o.contact_energy,
                frictional_dissipation: o.frictional_dissipation,
            };
            unsafe { put(totals, t, CALL, "totals")? };
        }
        Ok(())
    })
}

/// Writes `src` (`k` values per entry, by `each`) into the caller's `dst` unless it is null;
/// `src` must hold one entry per slave (`n`): a variable the last increment did not compute is
/// an error, not a silently untouched array.
unsafe fn fill<S, D: Copy>(
    dst: *mut D,
    src: &[S],
    n: usize,
    k: usize,
    what: &str,
    each: impl Fn(&S, &mut [D]),
) -> Result<(), Fail> {
    if dst.is_null() {
        return Ok(());
    }
    let call = "abut_contact_output";
    if src.len() != n {
        return Err(Fail::new(
            AbutStatus::BadValue,
            format!(
                "{call}: {what}: not computed at the last increment (penalty pairs compute \
                 their output variables after abut_contact_request_outputs)"
            ),
        ));
    }
    let out = unsafe { output(dst, times(src.len(), k, call, what)?, call, what)? };
    for (s, d) in src.iter().zip(out.chunks_exact_mut(k)) {
        each(s, d);
    }
    Ok(())
}

/// `*bytes` receives the size of the contact's saved state (`abut_contact_save_state`).
///
/// # Safety
/// `bytes` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_state_size(
    contact: *const AbutContact,
    bytes: *mut usize,
) -> AbutStatus {
    const CALL: &str = "abut_contact_state_size";
    handles::with_contact(contact as usize, CALL, |c| {
        let n = c.save_state()?.len();
        unsafe { put(bytes, n, CALL, "bytes") }
    })
}

/// Saves the contact's state (the penalty pairs' per-slave friction and history, the reference
/// increment) into the caller's `buf` of `cap` bytes (at least `abut_contact_state_size`'s): a
/// restart file's share of abut. `abut_contact_restore_state` on a contact built from the same
/// model continues the run bit for bit.
///
/// # Safety
/// `buf` valid for `cap` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_save_state(
    contact: *const AbutContact,
    buf: *mut u8,
    cap: usize,
) -> AbutStatus {
    const CALL: &str = "abut_contact_save_state";
    handles::with_contact(contact as usize, CALL, |c| {
        let s = c.save_state()?;
        if cap < s.len() {
            return Err(Fail::new(
                AbutStatus::Length,
                format!("{CALL}: cap = {cap} bytes, the state needs {}", s.len()),
            ));
        }
        let out = unsafe { output(buf, s.len(), CALL, "buf")? };
        out.copy_from_slice(&s);
        Ok(())
    })
}

/// Restores a state `abut_contact_save_state` gave (`len` bytes at `buf`). Errors, with nothing
/// changed: bytes that are not a state, or a state of a model with other pairs or slaves.
///
/// # Safety
/// `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_contact_restore_state(
    contact: *mut AbutContact,
    buf: *const u8,
    len: usize,
) -> AbutStatus {
    const CALL: &str = "abut_contact_restore_state";
    handles::with_contact(contact as usize, CALL, |c| {
        let s = unsafe { input(buf, len, CALL, "buf")? };
        Ok(c.restore_state(s)?)
    })
}

/// The increment for nodes that carry elements and penalty springs together (the host's vote
/// for its next increment): from the elements' stable increment `element_dt` (already times
/// `safety`) and the contact's `contact_dt` (`AbutReport::stable_dt`),
/// 1/Δt² = 1/Δt_elements² + 1/(safety·Δt_contact)², and no more than
/// `contact_safety·Δt_contact`. Typical factors: `safety` 0.9, `contact_safety` 0.5. `*dt`
/// receives it (∞ when neither limits).
///
/// # Safety
/// `dt` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_combined_increment(
    element_dt: f64,
    contact_dt: f64,
    safety: f64,
    contact_safety: f64,
    dt: *mut f64,
) -> AbutStatus {
    const CALL: &str = "abut_combined_increment";
    handles::guard(CALL, || {
        for (name, value) in [
            ("element_dt", element_dt),
            ("contact_dt", contact_dt),
            ("safety", safety),
            ("contact_safety", contact_safety),
        ] {
            if !(value > 0.0) {
                return Err(Fail::new(
                    AbutStatus::BadValue,
                    format!("{CALL}: {name} = {value}: must be positive (∞ for no limit)"),
                ));
            }
        }
        let out = crate::combined_increment(element_dt, contact_dt, safety, contact_safety);
        unsafe { put(dt, out, CALL, "dt") }
    })
}
