//! Every shader parses and validates with naga against core WGSL (no optional capabilities),
//! has its CPU mirror, and agrees with its Rust twins on constants and struct sizes. Runs
//! without an adapter, so a shader error fails CI on any machine.

use abut::testing::abi::search::{
    GpuHit, ScanParams, SearchParams, TreeParams, EMPTY_LO, ITEM_WORKGROUP, NO_FACET, SCAN_BLOCK,
    TREE_WORKGROUP,
};
use abut::testing::abi::shaders::{source, COMMON, KERNELS};
use abut::testing::abi::status::{STATUS_COLLAPSED, STATUS_FALLBACK};

fn parse(stem: &str) -> naga::Module {
    parse_with_info(stem).0
}

fn parse_with_info(stem: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let src = source(stem).unwrap();
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{stem}.wgsl: {}", e.emit_to_string(&src)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{stem}.wgsl does not validate as core WGSL: {e:?}"));
    (module, info)
}

#[test]
fn every_kernel_validates_as_core_wgsl() {
    for (stem, _, _) in KERNELS {
        let (m, info) = parse_with_info(stem);
        assert!(!m.entry_points.is_empty(), "{stem}.wgsl has no entry point");
        for ep in &m.entry_points {
            let [x, y, z] = ep.workgroup_size;
            assert!(
                x * y * z <= 256,
                "{stem}::{}: workgroup of {} invocations exceeds the default limit",
                ep.name,
                x * y * z
            );
        }
        // the limit holds per pipeline: count the storage buffers each entry point uses
        for (k, ep) in m.entry_points.iter().enumerate() {
            let uses = info.get_entry_point(k);
            let storage = m
                .global_variables
                .iter()
                .filter(|(h, v)| {
                    matches!(v.space, naga::AddressSpace::Storage { .. }) && !uses[*h].is_empty()
                })
                .count();
            assert!(
                storage <= 8,
                "{stem}::{} binds {storage} storage buffers (default limit 8)",
                ep.name
            );
        }
    }
}

#[test]
fn every_shader_file_is_embedded_and_mirrored() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for entry in std::fs::read_dir(dir.join("shaders")).unwrap() {
        let path = entry.unwrap().path();
        let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
        if stem.ends_with("common") {
            continue;
        }
        assert!(
            KERNELS.iter().any(|(s, _, _)| *s == stem),
            "shaders/{stem}.wgsl is not in abi::shaders::KERNELS"
        );
        assert!(
            dir.join("src/cpu").join(format!("{stem}.rs")).exists(),
            "shaders/{stem}.wgsl has no CPU mirror src/cpu/{stem}.rs"
        );
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("Bindings:")
                && text.contains("Dispatch:")
                && text.contains("Invariants:"),
            "shaders/{stem}.wgsl lacks its header"
        );
    }
}

/// The literal a WGSL constant is initialised with.
fn constant(m: &naga::Module, name: &str) -> naga::Literal {
    let (_, c) = m
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no WGSL constant {name}"));
    match m.global_expressions[c.init] {
        naga::Expression::Literal(l) => l,
        ref e => panic!("{name} is {e:?}"),
    }
}

fn constant_u32(m: &naga::Module, name: &str) -> u32 {
    match constant(m, name) {
        naga::Literal::U32(v) => v,
        l => panic!("{name} is {l:?}"),
    }
}

fn constant_f32(m: &naga::Module, name: &str) -> f32 {
    match constant(m, name) {
        naga::Literal::F32(v) => v,
        l => panic!("{name} is {l:?}"),
    }
}

fn struct_size(m: &naga::Module, name: &str) -> u32 {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(m.to_ctx()).unwrap();
    let (h, _) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no WGSL struct {name}"));
    layouter[h].size
}

/// The members of WGSL struct `name`: name and byte offset, in order.
fn member_offsets(m: &naga::Module, name: &str) -> Vec<(String, u32)> {
    let t = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no WGSL struct {name}"))
        .1;
    match &t.inner {
        naga::TypeInner::Struct { members, .. } => members
            .iter()
            .map(|x| (x.name.clone().unwrap_or_default(), x.offset))
            .collect(),
        _ => panic!("{name} is no struct"),
    }
}

#[test]
fn wgsl_twins_match_rust() {
    let m = parse("nearest_facet");
    assert_eq!(constant_u32(&m, "ITEM_WORKGROUP"), ITEM_WORKGROUP);
    assert_eq!(constant_u32(&m, "NO_FACET"), NO_FACET);
    assert_eq!(
        constant_u32(&m, "HIT_BESIDE_FREE_EDGE"),
        abut::testing::abi::search::HIT_BESIDE_FREE_EDGE
    );
    assert_eq!(
        constant_u32(&m, "HIT_WALKED"),
        abut::testing::abi::search::HIT_WALKED
    );
    assert_eq!(
        constant_u32(&m, "HIT_COUNT"),
        abut::testing::abi::search::HIT_COUNT
    );
    assert_eq!(
        constant_f32(&parse("local_search"), "SKIN_ROUNDOFF"),
        abut::testing::abi::search::SKIN_ROUNDOFF
    );
    assert_eq!(constant_u32(&m, "NO_NODE"), abut::model::NO_NODE);
    // the free-edge extension zone and the penalty's heavy-share cut, f32 twins
    assert_eq!(
        constant_f32(&m, "EXTENSION_ZONE"),
        abut::testing::cpu::common::EXTENSION_ZONE
    );
    assert_eq!(
        constant_f32(&parse("penalty"), "HEAVY_SHARE"),
        abut::testing::abi::penalty::HEAVY_SHARE
    );
    assert_eq!(
        constant_u32(&m, "QUAD_ITERATIONS"),
        abut::geometry::QUAD_ITERATIONS
    );
    assert_eq!(
        constant_u32(&m, "STATUS_FALLBACK") as usize,
        STATUS_FALLBACK
    );
    assert_eq!(
        constant_u32(&m, "CANDIDATE_CHUNK"),
        abut::testing::cpu::nearest_facet::CANDIDATE_CHUNK
    );
    assert_eq!(
        constant_u32(&m, "WALK_VISITS"),
        abut::testing::cpu::nearest_facet::WALK_VISITS
    );
    assert_eq!(
        constant_u32(&m, "BEST_WORDS") as usize,
        abut::testing::abi::search::BEST_WORDS
    );
    assert!(source("nearest_facet").unwrap().contains(&format!(
        "PRUNE_SLACK: f32 = {:?}",
        abut::testing::cpu::nearest_facet::PRUNE_SLACK
    )));
    let t = parse("tree");
    assert_eq!(constant_u32(&t, "TREE_WORKGROUP"), TREE_WORKGROUP);
    // the packed boxes' codes and the walks' groups
    assert_eq!(
        constant_u32(&t, "BOX_TOP"),
        abut::testing::abi::boxes::BOX_TOP
    );
    assert_eq!(
        constant_f32(&t, "BOX_BIAS"),
        abut::testing::abi::boxes::BOX_BIAS
    );
    assert_eq!(
        constant_u32(&parse("nearest_facet"), "WALK_GROUP"),
        abut::testing::abi::search::WALK_GROUP
    );
    assert_eq!(
        constant_u32(&t, "STATUS_COLLAPSED") as usize,
        STATUS_COLLAPSED
    );
    assert_eq!(
        struct_size(&t, "TreeParams") as usize,
        std::mem::size_of::<TreeParams>()
    );
    assert!(COMMON.contains(&format!("EMPTY_LO: f32 = {EMPTY_LO:.1e}")));
    assert_eq!(
        constant_u32(&m, "STATUS_CROWDED") as usize,
        abut::testing::abi::status::STATUS_CROWDED
    );
    let g = parse("gather");
    for (name, word) in [
        (
            "STATUS_FORCE_SCALE",
            abut::testing::abi::status::STATUS_FORCE_SCALE,
        ),
        (
            "STATUS_ROW_SCALE",
            abut::testing::abi::status::STATUS_ROW_SCALE,
        ),
    ] {
        assert_eq!(constant_u32(&g, name) as usize, word, "{name}");
    }
    let (_, bits) = g
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("FIXED_BITS"))
        .expect("FIXED_BITS in gather.wgsl");
    assert!(matches!(
        g.global_expressions[bits.init],
        naga::Expression::Literal(naga::Literal::I32(v)) if v == abut::testing::cpu::gather::FIXED_BITS
    ));
    assert_eq!(
        struct_size(&m, "SearchParams") as usize,
        std::mem::size_of::<SearchParams>()
    );
    assert_eq!(
        struct_size(&m, "Hit") as usize,
        std::mem::size_of::<GpuHit>()
    );
    // member by member: the scatter reads the facet and the weights, the first 32 bytes
    let rust = [
        ("facet", std::mem::offset_of!(GpuHit, facet)),
        ("node", std::mem::offset_of!(GpuHit, node)),
        ("candidates", std::mem::offset_of!(GpuHit, candidates)),
        ("slave", std::mem::offset_of!(GpuHit, slave)),
        ("weights", std::mem::offset_of!(GpuHit, weights)),
        ("point_gap", std::mem::offset_of!(GpuHit, point_gap)),
        ("normal_dist", std::mem::offset_of!(GpuHit, normal_dist)),
    ]
    .map(|(n, o)| (n.to_string(), o as u32));
    assert_eq!(member_offsets(&m, "Hit"), rust.to_vec());
    assert!(std::mem::offset_of!(GpuHit, weights) + 16 <= 32);
    let s = parse("scan");
    assert_eq!(constant_u32(&s, "SCAN_BLOCK"), SCAN_BLOCK);
    assert_eq!(
        struct_size(&s, "ScanParams") as usize,
        std::mem::size_of::<ScanParams>()
    );
    assert!(COMMON.contains(&format!(
        "QUAD_CONVERGED: f32 = {:e}",
        abut::geometry::QUAD_CONVERGED
    )));
}

/// The device-resident increment's words agree between WGSL and Rust: the plan's layout, the
/// words of the params the schedule writes, the status words to_local raises, the trigger
/// codes and slot kinds, the statistics' size and the integrator's parameters; and the plan's
/// params sit where a uniform binding may start.
#[test]
fn resident_twins_match_rust() {
    use abut::testing::abi::search as l;
    let m = parse("schedule");
    for (name, v) in [
        ("PLAN_SINCE_GLOBAL", l::PLAN_SINCE_GLOBAL),
        ("PLAN_SEARCHED", l::PLAN_SEARCHED),
        ("PLAN_CROWDED", l::PLAN_CROWDED),
        ("PLAN_FORCE", l::PLAN_FORCE),
        ("PLAN_GLOBAL", l::PLAN_GLOBAL),
        ("PLAN_TRIGGER", l::PLAN_TRIGGER),
        ("PLAN_INTERVAL", l::PLAN_INTERVAL),
        ("PLAN_N_SLOTS", l::PLAN_N_SLOTS),
        ("PLAN_OTHER_NODES", l::PLAN_OTHER_NODES),
        ("PLAN_FIT_FAILED", l::PLAN_FIT_FAILED),
        ("PLAN_MAX_DIM", l::PLAN_MAX_DIM),
        ("PLAN_PARAMS", l::PLAN_PARAMS),
        ("PLAN_SLOTS", l::PLAN_SLOTS),
        ("PLAN_SLOT_WORDS", l::PLAN_SLOT_WORDS),
        ("MAX_PLAN_SLOTS", l::MAX_PLAN_SLOTS),
        // the SearchParams words the schedule writes, from the Rust struct's field offsets
        ("P_BOX_MARGIN", l::P_BOX_MARGIN),
        ("P_DIM", l::P_DIM),
        ("P_FLAGS", l::P_FLAGS),
        ("P_MASTER_LO", l::P_MASTER_LO),
        ("P_MASTER_HI", l::P_MASTER_HI),
        ("STATUS_BOX", abut::testing::abi::status::STATUS_BOX),
        (
            "STATUS_NONFINITE",
            abut::testing::abi::status::STATUS_NONFINITE,
        ),
        (
            "STATUS_FALLBACK",
            abut::testing::abi::status::STATUS_FALLBACK,
        ),
        (
            "STATUS_BUDGET_EXCEEDED",
            abut::testing::abi::status::STATUS_BUDGET_EXCEEDED,
        ),
        ("STATUS_FAST", abut::testing::abi::status::STATUS_FAST),
        (
            "STATUS_FAST_RATIO",
            abut::testing::abi::status::STATUS_FAST_RATIO,
        ),
        ("STATUS_MOTION", abut::testing::abi::status::STATUS_MOTION),
        (
            "STATUS_LOCAL_WALKS",
            abut::testing::abi::status::STATUS_LOCAL_WALKS,
        ),
        (
            "STATUS_MASTER_MOTION",
            abut::testing::abi::status::STATUS_MASTER_MOTION,
        ),
        // the active slaves follow the status words
        ("ACTIVE_LIST", abut::testing::abi::status::STATUS_WORDS),
    ] {
        assert_eq!(constant_u32(&m, name) as usize, v, "{name}");
    }
    assert_eq!(
        constant_u32(&m, "ACTIVE_SLOT") as usize,
        l::ACTIVE_SLOT,
        "ACTIVE_SLOT"
    );
    assert_eq!(
        constant_u32(&m, "ACTIVE_NODES_SLOT") as usize,
        l::ACTIVE_NODES_SLOT,
        "ACTIVE_NODES_SLOT"
    );
    for (name, v) in [
        ("SLOT_GLOBAL", l::SLOT_GLOBAL),
        ("SLOT_LOCAL", l::SLOT_LOCAL),
        ("TRIGGER_LOCAL", l::TRIGGER_LOCAL),
        ("TRIGGER_FIRST", l::TRIGGER_FIRST),
        ("TRIGGER_INTERVAL", l::TRIGGER_INTERVAL),
        ("TRIGGER_BUDGET", l::TRIGGER_BUDGET),
        ("TRIGGER_CROWDED", l::TRIGGER_CROWDED),
        ("TRIGGER_REQUESTED", l::TRIGGER_REQUESTED),
        ("FLAG_WIDE_LOCAL", l::FLAG_WIDE_LOCAL),
        ("FLAG_SELF_CONTACT", l::FLAG_SELF_CONTACT),
        ("FLAG_EVERY_SLAVE", l::FLAG_EVERY_SLAVE),
        ("FLAG_SLAVES_APART", l::FLAG_SLAVES_APART),
    ] {
        assert_eq!(constant_u32(&m, name), v, "{name}");
    }
    assert_eq!(constant_f32(&m, "SLAVE_TRACKED"), l::SLAVE_TRACKED);
    assert_eq!(constant_f32(&m, "SLAVE_WITHIN"), l::SLAVE_WITHIN);
    // the params words are bound as a uniform: their offset must be a multiple of 256 bytes
    assert_eq!((4 * l::PLAN_PARAMS) % 256, 0);
    assert!(l::PLAN_PARAMS + std::mem::size_of::<SearchParams>() / 4 <= l::PLAN_SLOTS);
    let st = parse("stats");
    assert_eq!(
        constant_u32(&st, "STAT_INCREMENT") as usize,
        abut::testing::abi::stats::STATS_WORDS - 1
    );
    assert_eq!(
        std::mem::size_of::<abut::IncrementStats>(),
        abut::testing::abi::stats::STATS_WORDS * 4
    );
    assert_eq!(constant_u32(&st, "STAT_LOCAL_WALKS") as usize, 12);
    assert_eq!(constant_u32(&st, "STAT_FAST") as usize, 15);
    assert_eq!(constant_u32(&st, "STAT_FAST_RATIO") as usize, 16);
    assert_eq!(
        constant_u32(&st, "STAT_DAMPING") as usize,
        abut::testing::abi::stats::STATS_RESET_WORDS
    );
    let i = parse("integrate");
    assert_eq!(
        struct_size(&i, "IntegrateParams") as usize,
        std::mem::size_of::<abut::testing::abi::integrate::IntegrateParams>()
    );
    // ordered bits order as the floats, and invert
    let xs = [-1e30f32, -2.5, -0.0, 0.0, 1e-30, 3.0, f32::MAX];
    for w in xs.windows(2) {
        assert!(l::ordered_bits(w[0]) <= l::ordered_bits(w[1]), "{w:?}");
    }
    for x in xs {
        assert_eq!(
            l::from_ordered_bits(l::ordered_bits(x)).to_bits(),
            x.to_bits()
        );
    }
}

#[test]
fn penalty_twins_match_rust() {
    use abut::testing::abi::penalty::*;
    let m = parse("penalty");
    assert_eq!(
        struct_size(&m, "PenaltyParams") as usize,
        std::mem::size_of::<PenaltyParams>()
    );
    assert_eq!(
        struct_size(&m, "SlaveState") as usize,
        std::mem::size_of::<SlaveState>()
    );
    assert_eq!(
        struct_size(&m, "ContactOut") as usize,
        std::mem::size_of::<ContactOut>()
    );
    // member by member: the scatter and the gather read the first 32 bytes alone
    let rust = [
        ("force", std::mem::offset_of!(ContactOut, force)),
        ("status", std::mem::offset_of!(ContactOut, status)),
        ("dissipation", std::mem::offset_of!(ContactOut, dissipation)),
        ("bound_light", std::mem::offset_of!(ContactOut, bound_light)),
        ("bound_heavy", std::mem::offset_of!(ContactOut, bound_heavy)),
        ("tangential", std::mem::offset_of!(ContactOut, tangential)),
        ("normal_gap", std::mem::offset_of!(ContactOut, normal_gap)),
    ]
    .map(|(n, o)| (n.to_string(), o as u32));
    assert_eq!(member_offsets(&m, "ContactOut"), rust.to_vec());
    assert!(std::mem::offset_of!(ContactOut, bound_heavy) + 4 <= 32);
    for (name, v) in [
        ("NO_SLAVE", NO_SLAVE),
        ("CSTATUS_OPEN", CSTATUS_OPEN),
        ("CSTATUS_STICK", CSTATUS_STICK),
        ("CSTATUS_SLIP", CSTATUS_SLIP),
        ("LAW_LINEAR", LAW_LINEAR),
        ("LAW_EXPONENTIAL", LAW_EXPONENTIAL),
        ("LAW_TABULAR", LAW_TABULAR),
        ("STIFFNESS_AUTO", STIFFNESS_AUTO),
        ("STIFFNESS_MODULUS", STIFFNESS_MODULUS),
        ("STIFFNESS_ABSOLUTE", STIFFNESS_ABSOLUTE),
        ("PENALTY_ANCHORED", PENALTY_ANCHORED),
        ("PENALTY_SLAVES_APART", PENALTY_SLAVES_APART),
        ("NEED_NORMAL", NEED_NORMAL),
        ("NEED_FORCE", NEED_FORCE),
        ("STAT_OMEGA2", abut::testing::abi::stats::STAT_OMEGA2 as u32),
        (
            "STATUS_DT_STABLE",
            abut::testing::abi::status::STATUS_DT_STABLE as u32,
        ),
        (
            "STATUS_DT_APPROACH",
            abut::testing::abi::status::STATUS_DT_APPROACH as u32,
        ),
        (
            "STATUS_ACTIVE",
            abut::testing::abi::status::STATUS_ACTIVE as u32,
        ),
        (
            "STATUS_SLIPPING",
            abut::testing::abi::status::STATUS_SLIPPING as u32,
        ),
    ] {
        assert_eq!(constant_u32(&m, name), v, "{name}");
    }
    let (_, c) = m
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("NO_LIMIT"))
        .unwrap();
    match m.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::F32(v)) => assert_eq!(v, NO_LIMIT),
        ref e => panic!("NO_LIMIT is {e:?}"),
    }
    assert_eq!(
        m.overrides
            .iter()
            .filter(|(_, o)| o.name.as_deref() == Some("FRICTION"))
            .count(),
        1
    );
}

/// Every declared pass (`abut::testing::abi::passes`) matches its WGSL entry point as naga reflects it: the same
/// bindings (numbers, uniform or storage, read or read-write) and nothing else used, and a
/// workgroup covering the declared items; and every entry point of every kernel is declared.
#[test]
fn pass_declarations_match_the_shaders() {
    use abut::testing::abi::passes::{Access, Items, PASSES};
    for pass in &PASSES {
        let what = format!("{}::{}", pass.stem, pass.entry);
        let (m, info) = parse_with_info(pass.stem);
        let k = m
            .entry_points
            .iter()
            .position(|e| e.name == pass.entry)
            .unwrap_or_else(|| panic!("{what}: no such entry point"));
        let uses = info.get_entry_point(k);
        let mut used: Vec<(u32, Access)> = m
            .global_variables
            .iter()
            .filter(|(h, _)| !uses[*h].is_empty())
            .filter_map(|(_, v)| {
                let rb = v.binding.as_ref()?;
                assert_eq!(rb.group, 0, "{what}: group {}", rb.group);
                let access = match v.space {
                    naga::AddressSpace::Uniform => Access::Uniform,
                    naga::AddressSpace::Storage { access } => {
                        if access.contains(naga::StorageAccess::STORE) {
                            Access::ReadWrite
                        } else {
                            Access::Read
                        }
                    }
                    ref s => panic!("{what}: binding {} in {s:?}", rb.binding),
                };
                Some((rb.binding, access))
            })
            .collect();
        used.sort_by_key(|u| u.0);
        let declared: Vec<(u32, Access)> =
            pass.bindings.iter().map(|b| (b.index, b.access)).collect();
        assert_eq!(
            used, declared,
            "{what}: bindings used by the WGSL vs declared"
        );
        let [x, y, z] = m.entry_points[k].workgroup_size;
        let per = match pass.items {
            Items::ScanBlocks => x * y * z * constant_u32(&m, "SCAN_PER_THREAD"),
            _ => x * y * z,
        };
        assert_eq!(per, pass.per_workgroup, "{what}: items per workgroup");
    }
    for (stem, _, _) in KERNELS {
        let m = parse(stem);
        for ep in &m.entry_points {
            assert!(
                PASSES.iter().any(|p| p.stem == stem && p.entry == ep.name),
                "{stem}::{} is not declared in abut::testing::abi::passes",
                ep.name
            );
        }
    }
}
