//! C ABI: the model (nodes, surfaces, node sets, pairs, rigid bodies and parts).

use super::handles::{self, Fail, Object};
use super::types::*;
use super::{input, put, times, ABUT_NO_NODE};
use crate::model::Schedule;
use crate::model::{Facet, NodeSetId, SurfaceId};
use crate::{
    Analytical, BodyId, Enforce, Friction, Kinematic, Model, Pair, Penalty, PressureOverclosure,
    RigidBody, RigidPair, Sliding, Stiffness, Surface,
};

/// A model: nodes with masses, surfaces, node sets, pairs, rigid bodies and parts. Opaque; made
/// by `abut_model_new`, freed by `abut_model_free`. A contact copies what it needs from it.
pub struct AbutModel {
    _opaque: [u8; 0],
}

/// Makes an empty model of `dim` (2 or 3) dimensions; `*out` receives the handle.
///
/// # Safety
/// `out` valid for one handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_new(dim: u32, out: *mut *mut AbutModel) -> AbutStatus {
    const CALL: &str = "abut_model_new";
    handles::guard(CALL, || {
        if out.is_null() {
            return Err(super::null(CALL, "out"));
        }
        let model = match dim {
            2 => Model::new_2d(),
            3 => Model::new_3d(),
            _ => {
                return Err(Fail::new(
                    AbutStatus::BadValue,
                    format!("{CALL}: dim = {dim}; a model has 2 or 3 dimensions"),
                ))
            }
        };
        let h = handles::register(Object::Model(Box::new(model)));
        unsafe { put(out, h as *mut AbutModel, CALL, "out") }
    })
}

/// Frees a model (null: nothing). Contacts made from it stay usable.
///
/// # Safety
/// None beyond passing a value abut gave.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_free(model: *mut AbutModel) -> AbutStatus {
    handles::release(model as usize, "abut_model_free", "model")
}

/// Copies the last error message of `model` into `buf` (as `abut_last_error`).
///
/// # Safety
/// As `abut_last_error`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_error(
    model: *const AbutModel,
    buf: *mut u8,
    cap: usize,
    len: *mut usize,
) -> AbutStatus {
    unsafe { super::device::handle_error(model as usize, "abut_model_error", buf, cap, len) }
}

/// `*count` receives the number of nodes in the model.
///
/// # Safety
/// `count` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_node_count(
    model: *const AbutModel,
    count: *mut usize,
) -> AbutStatus {
    const CALL: &str = "abut_model_node_count";
    handles::with_model(model as usize, CALL, |m| unsafe {
        put(count, m.positions().len(), CALL, "count")
    })
}

/// Adds `n` nodes: `coords` holds `dim` values per node (x, y[, z]) interleaved, `masses` one
/// positive mass per node. `*first` (may be null) receives the first new node's id; the nodes
/// are numbered on from it. Errors name the node and value (NaN, infinite, non-positive mass).
///
/// # Safety
/// `coords` valid for `dim·n` doubles, `masses` for `n`; `first` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_nodes(
    model: *mut AbutModel,
    coords: *const f64,
    masses: *const f64,
    n: usize,
    first: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_nodes";
    handles::with_model(model as usize, CALL, |m| {
        let dim = m.dim() as usize;
        let c = unsafe { input(coords, times(n, dim, CALL, "coords")?, CALL, "coords")? };
        let masses = unsafe { input(masses, n, CALL, "masses")? };
        let range = if dim == 2 {
            let p: Vec<[f64; 2]> = c.chunks_exact(2).map(|q| [q[0], q[1]]).collect();
            m.add_nodes_2d(&p, masses)?
        } else {
            let p: Vec<[f64; 3]> = c.chunks_exact(3).map(|q| [q[0], q[1], q[2]]).collect();
            m.add_nodes(&p, masses)?
        };
        if !first.is_null() {
            unsafe { put(first, range.start, CALL, "first")? };
        }
        Ok(())
    })
}

/// Adds a master surface of `n_facets` facets of `kind` (an `AbutFacetKind`): `nodes` holds
/// `kind` node ids per facet (2, 3 or 4; a fourth id of `ABUT_NO_NODE` makes a triangle).
/// Facets are oriented by their node order (outward normal by the right-hand rule in 3D; the
/// segment's left in 2D). `*id` receives the surface id. Errors name the facet and node.
///
/// # Safety
/// `nodes` valid for `kind·n_facets` ids; `id` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_surface(
    model: *mut AbutModel,
    kind: i32,
    nodes: *const u32,
    n_facets: usize,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_surface";
    handles::with_model(model as usize, CALL, |m| {
        let per = enum_value(
            kind,
            "abut_model_add_surface: kind (an AbutFacetKind)",
            &[(2, 2usize), (3, 3), (4, 4)],
        )?;
        let ids = unsafe { input(nodes, times(n_facets, per, CALL, "nodes")?, CALL, "nodes")? };
        let facets: Vec<Facet> = ids
            .chunks_exact(per)
            .map(|f| match f {
                [a, b] => Facet::Segment([*a, *b]),
                [a, b, c] => Facet::Triangle([*a, *b, *c]),
                [a, b, c, d] if *d == ABUT_NO_NODE => Facet::Triangle([*a, *b, *c]),
                _ => Facet::Quad([f[0], f[1], f[2], f[3]]),
            })
            .collect();
        let s = m.add_surface(Surface::from_facets(facets))?;
        unsafe { put(id, s.0 as u32, CALL, "id") }
    })
}

/// Adds a node set of `n` node ids (the slave nodes of a pair). `areas` (may be null) gives
/// each node's tributary area (length in 2D), which pressures and the per-area stiffness need;
/// without it a node's area is the mean master facet area. `*id` receives the set id.
///
/// # Safety
/// `nodes` valid for `n` ids, `areas` null or valid for `n` doubles; `id` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_node_set(
    model: *mut AbutModel,
    nodes: *const u32,
    n: usize,
    areas: *const f64,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_node_set";
    handles::with_model(model as usize, CALL, |m| {
        let nodes = unsafe { input(nodes, n, CALL, "nodes")? };
        let set = if areas.is_null() {
            m.add_node_set(nodes)?
        } else {
            let a = unsafe { input(areas, n, CALL, "areas")? };
            m.add_node_set_with_areas(nodes, a)?
        };
        unsafe { put(id, set.0 as u32, CALL, "id") }
    })
}

/// Fills `options` with the defaults of a pair (see `AbutPairOptions`).
///
/// # Safety
/// `options` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_pair_options_default(options: *mut AbutPairOptions) -> AbutStatus {
    const CALL: &str = "abut_pair_options_default";
    handles::guard(CALL, || unsafe {
        put(options, default_options(), CALL, "options")
    })
}

/// The defaults of a pair, as `abut_pair_options_default` gives them.
pub(crate) fn default_options() -> AbutPairOptions {
    let schedule = Schedule::default_for(false);
    AbutPairOptions {
        enforcement: AbutEnforcement::Penalty as i32,
        stiffness: AbutStiffness::Auto as i32,
        stiffness_value: 0.0,
        stiffness_scale: 1.0,
        law: AbutLaw {
            kind: AbutLawKind::Default as i32,
            clearance: 0.0,
            pressure: 0.0,
            slope: 0.0,
            table: std::ptr::null(),
            table_points: 0,
        },
        damping: crate::DEFAULT_CONTACT_DAMPING,
        friction: 0,
        mu: 0.0,
        mu_kinetic: f64::NAN,
        decay: 0.0,
        stick_stiffness: 1.0,
        sliding: AbutSliding::Finite as i32,
        search_radius: 0.0,
        has_schedule: 0,
        schedule_interval: schedule.interval,
        schedule_budget: schedule.budget,
        schedule_wide_local: 0,
        balanced: 0,
        balanced_surface: 0,
        balanced_weight: 0.5,
        pass_weight: 1.0,
    }
}

/// The law an `AbutLaw` states (`None`: the Default kind).
unsafe fn law_of(law: &AbutLaw, call: &str) -> Result<Option<PressureOverclosure>, Fail> {
    use AbutLawKind as L;
    let kind = enum_value(
        law.kind,
        &format!("{call}: law.kind (an AbutLawKind)"),
        &[
            (0, L::Default),
            (1, L::Exponential),
            (2, L::Tabular),
            (3, L::Slope),
        ],
    )?;
    let law = match kind {
        L::Default => return Ok(None),
        L::Exponential => PressureOverclosure::Exponential {
            clearance: law.clearance,
            pressure: law.pressure,
        },
        L::Slope => PressureOverclosure::linear(law.slope),
        L::Tabular => {
            let n = times(law.table_points, 2, call, "law.table")?;
            let t = unsafe { input(law.table, n, call, "law.table")? };
            PressureOverclosure::Tabular(t.chunks_exact(2).map(|p| (p[0], p[1])).collect())
        }
    };
    law.validate()?;
    Ok(Some(law))
}

/// The Rust pair `options` state for `slave` against `master`.
pub(crate) fn pair_from(
    slave: u32,
    master: u32,
    o: &AbutPairOptions,
    call: &str,
) -> Result<Pair, Fail> {
    let mut pair = Pair::new(NodeSetId(slave as usize), SurfaceId(master as usize));
    let law = unsafe { law_of(&o.law, call)? };
    let enforcement = enum_value(
        o.enforcement,
        &format!("{call}: options.enforcement (an AbutEnforcement)"),
        &[
            (0, AbutEnforcement::Penalty),
            (1, AbutEnforcement::Kinematic),
        ],
    )?;
    pair.enforce = match enforcement {
        AbutEnforcement::Kinematic => Enforce::Kinematic(Kinematic { softened: law }),
        AbutEnforcement::Penalty => {
            use AbutStiffness as S;
            let rule = enum_value(
                o.stiffness,
                &format!("{call}: options.stiffness (an AbutStiffness)"),
                &[
                    (0, S::Auto),
                    (1, S::Modulus),
                    (2, S::Absolute),
                    (3, S::PerArea),
                ],
            )?;
            Enforce::Penalty(Penalty {
                stiffness: match rule {
                    S::Auto => Stiffness::Auto {
                        scale: o.stiffness_scale,
                    },
                    S::Modulus => Stiffness::Modulus {
                        modulus: o.stiffness_value,
                        scale: o.stiffness_scale,
                    },
                    S::Absolute => Stiffness::Absolute(o.stiffness_value),
                    S::PerArea => Stiffness::PerArea(o.stiffness_value),
                },
                law: law.unwrap_or(PressureOverclosure::Linear),
                damping: o.damping,
            })
        }
    };
    pair.friction = match o.friction {
        0 => Friction::Frictionless,
        1 => Friction::Coulomb {
            mu: o.mu,
            mu_kinetic: if o.mu_kinetic.is_nan() {
                o.mu
            } else {
                o.mu_kinetic
            },
            decay: o.decay,
            stick_stiffness: o.stick_stiffness,
        },
        f => {
            return Err(Fail::new(
                AbutStatus::BadValue,
                format!("{call}: options.friction = {f}; 0 (frictionless) or 1 (Coulomb)"),
            ))
        }
    };
    pair.sliding = enum_value(
        o.sliding,
        &format!("{call}: options.sliding (an AbutSliding)"),
        &[
            (0, Sliding::Finite),
            (1, Sliding::Small),
            (2, Sliding::Infinitesimal),
        ],
    )?;
    if o.search_radius != 0.0 {
        pair.search_radius = Some(o.search_radius);
    }
    if o.has_schedule != 0 {
        pair.schedule = Some(Schedule {
            interval: o.schedule_interval,
            budget: o.schedule_budget,
            wide_local: o.schedule_wide_local != 0,
            visit_every_slave: false,
        });
    }
    if o.balanced != 0 {
        pair.balanced = Some((SurfaceId(o.balanced_surface as usize), o.balanced_weight));
    }
    pair.pass_weight = o.pass_weight;
    Ok(pair)
}

/// Adds a contact pair: the nodes of node set `slave` against master surface `master`, with
/// `options` (null: the defaults). A self-contact pair is a surface's own nodes against it.
/// `*id` receives the pair id. Errors name the option at fault.
///
/// # Safety
/// `options` null or valid (its law's table valid for the call); `id` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_pair(
    model: *mut AbutModel,
    slave: u32,
    master: u32,
    options: *const AbutPairOptions,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_pair";
    handles::with_model(model as usize, CALL, |m| {
        let o = if options.is_null() {
            default_options()
        } else {
            unsafe { *input(options, 1, CALL, "options")?.first().expect("one") }
        };
        let p = m.add_pair(pair_from(slave, master, &o, CALL)?)?;
        unsafe { put(id, p.0 as u32, CALL, "id") }
    })
}

/// The Rust analytical surface `a` states.
pub(crate) fn analytical_from(a: &AbutAnalytical, call: &str) -> Result<Analytical, Fail> {
    use AbutSurfaceKind as K;
    let kind = enum_value(
        a.kind,
        &format!("{call}: surface.kind (an AbutSurfaceKind)"),
        &[
            (0, K::Plane),
            (1, K::Sphere),
            (2, K::Cylinder),
            (3, K::Line),
            (4, K::Circle),
        ],
    )?;
    let (p, d) = (a.point, a.direction);
    Ok(match kind {
        K::Plane => Analytical::Plane {
            point: p,
            normal: d,
        },
        K::Sphere => Analytical::Sphere {
            centre: p,
            radius: a.radius,
        },
        K::Cylinder => Analytical::Cylinder {
            point: p,
            axis: d,
            radius: a.radius,
        },
        K::Line => Analytical::Line {
            point: [p[0], p[1]],
            normal: [d[0], d[1]],
        },
        K::Circle => Analytical::Circle {
            centre: [p[0], p[1]],
            radius: a.radius,
        },
    })
}

fn inertia_from(i: &[f64]) -> [[f64; 3]; 3] {
    [[i[0], i[1], i[2]], [i[3], i[4], i[5]], [i[6], i[7], i[8]]]
}

/// Adds a rigid body of `mass` and `inertia` (9 values, row by row, about its reference point)
/// carrying the analytical `surface`; `*id` receives the body id (its index in the body-state
/// array of `abut_contact_kinematic_step`).
///
/// # Safety
/// `inertia` valid for 9 doubles; `surface` and `id` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_rigid_body(
    model: *mut AbutModel,
    mass: f64,
    inertia: *const f64,
    surface: *const AbutAnalytical,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_rigid_body";
    handles::with_model(model as usize, CALL, |m| {
        let i = unsafe { input(inertia, 9, CALL, "inertia")? };
        let s = unsafe { input(surface, 1, CALL, "surface")? };
        let body = RigidBody {
            mass,
            inertia: inertia_from(i),
            surface: analytical_from(&s[0], CALL)?,
        };
        let b = m.add_rigid_body(body)?;
        unsafe { put(id, b.0 as u32, CALL, "id") }
    })
}

/// Adds a kinematic pair of node set `slave` against rigid body `body`'s analytical surface;
/// `softened` (may be null: hard contact) a softened law. `*id` receives the rigid pair id.
///
/// # Safety
/// `softened` null or valid; `id` valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_rigid_pair(
    model: *mut AbutModel,
    slave: u32,
    body: u32,
    softened: *const AbutLaw,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_rigid_pair";
    handles::with_model(model as usize, CALL, |m| {
        let softened = if softened.is_null() {
            None
        } else {
            unsafe { law_of(&input(softened, 1, CALL, "softened")?[0], CALL)? }
        };
        let p = m.add_rigid_pair(RigidPair {
            slave: NodeSetId(slave as usize),
            body: BodyId(body as usize),
            softened,
        })?;
        unsafe { put(id, p.0 as u32, CALL, "id") }
    })
}

/// Declares `n` nodes one rigid part of `mass` and `inertia` (9 values, row by row, about the
/// nodes' centroid): the penalty stiffness and stable increment then treat its slaves as one
/// body. `*id` (may be null) receives the part id.
///
/// # Safety
/// `nodes` valid for `n` ids, `inertia` for 9 doubles; `id` null or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn abut_model_add_rigid_part(
    model: *mut AbutModel,
    nodes: *const u32,
    n: usize,
    mass: f64,
    inertia: *const f64,
    id: *mut u32,
) -> AbutStatus {
    const CALL: &str = "abut_model_add_rigid_part";
    handles::with_model(model as usize, CALL, |m| {
        let nodes = unsafe { input(nodes, n, CALL, "nodes")? };
        let i = unsafe { input(inertia, 9, CALL, "inertia")? };
        let p = m.add_rigid_part(nodes, mass, inertia_from(i))?;
        if !id.is_null() {
            unsafe { put(id, p.0 as u32, CALL, "id")? };
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests;
