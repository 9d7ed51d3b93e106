// penalty.wgsl — penalty contact force, friction and outputs of each slave node.
// CPU mirror: src/cpu/penalty.rs.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 nodes (xyz in the frame, w mass), 2 vel (xyz),
//           3 facets, 4 hits (the search's results), 5 normals (smoothed nodal normals, per
//           model node, from nodal_normals), 6 state (SlaveState per slave, read-write),
//           7 out (ContactOut per slave), 8 status (atomic words: overflow read, increments
//           and counts reduced; from ACTIVE_LIST the active slaves, active.wgsl).
// Dispatch: penalty one invocation per slave node (global increments, small sliding),
//           penalty_active one per active slave (local increments, indirect from the plan's
//           ACTIVE_SLOT); ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: the contact normal N is the smoothed normal interpolated with the load-transfer
//             weights (continuous across facet edges) and the gap is measured along it; the
//             force on the slave is F_n·N + F_t and the master nodes get −w_j times it (gather),
//             so momentum is conserved to round-off. The override FRICTION = false removes all
//             friction work. Nothing runs when the search overflowed or the motion budget
//             was used up (the increment will run again). A slave whose hit carries
//             HIT_BESIDE_FREE_EDGE is off the master's facets: open, no force; one that was
//             beside a free edge below the facet's plane (state.history.y) stays open until
//             its gap is positive. A rigid side (pp.master_body / slave_body, w > 0) counts
//             with its body's compliance at the contact point and as one share of the bound.
//             Increments are positive f32, reduced with atomicMin on their bits (order-
//             preserving for positive floats), so the result is deterministic.
//             Every slave is tested for fast motion (count_fast: STATUS_FAST, STATUS_FAST_RATIO; its
//             velocity relative to the master near it times dt against pp.search_radius).
//             A rigid slave part's springs take 1/slave_share of its effective mass each in
//             the automatic stiffness, so the body on all of them has one slave's frequency.
//             Every spring within the search radius also writes its shares of the node-wise
//             frequency bound (bound_light, bound_heavy, heavy bits in status; gather sums
//             them per node; the derivation is in contact.rs). A spring in contact raises
//             STATUS_FORCE_SCALE and STATUS_ROW_SCALE to its largest force component and bound
//             share (integer max of non-negative f32 bits): the gather's fixed-point scales.
//             Those status words are reduced in the workgroup first (wg_words: workgroup
//             atomics), then raised with one global atomic per word and workgroup, not one per
//             spring: integer sums, maxima and minima, so the words do not depend on the order.
//             Every invocation reaches the entry points' two barriers.

override FRICTION: bool = true;

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> vel: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> hits: array<Hit>;
@group(0) @binding(5) var<storage, read> normals: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> state: array<SlaveState>;
@group(0) @binding(7) var<storage, read_write> out: array<ContactOut>;
@group(0) @binding(8) var<storage, read_write> status: array<atomic<u32>>;

// The status words a spring raises, by slot of `wg_words`: three counts (added), four largest
// values (non-negative f32 bits, integer max) and two increments (positive f32 bits, integer
// min). Each slot starts at its operation's identity and is raised into its status word by one
// invocation, once per workgroup.
const WG_FAST: u32 = 0u;        // STATUS_FAST
const WG_ACTIVE: u32 = 1u;      // STATUS_ACTIVE
const WG_SLIPPING: u32 = 2u;    // STATUS_SLIPPING
const WG_FAST_RATIO: u32 = 3u;  // STATUS_FAST_RATIO
const WG_OVERCLOSURE: u32 = 4u; // STATUS_MAX_OVERCLOSURE
const WG_FORCE_SCALE: u32 = 5u; // STATUS_FORCE_SCALE
const WG_ROW_SCALE: u32 = 6u;   // STATUS_ROW_SCALE
const WG_DT_STABLE: u32 = 7u;   // STATUS_DT_STABLE
const WG_DT_APPROACH: u32 = 8u; // STATUS_DT_APPROACH
const WG_WORDS: u32 = 9u;
const WG_FIRST_MAX: u32 = 3u;
const WG_FIRST_MIN: u32 = 7u;
const WG_MIN_IDENTITY: u32 = 0xffffffffu;
var<workgroup> wg_words: array<atomic<u32>, 9>;

// The status word of slot w of `wg_words`.
fn wg_status_word(w: u32) -> u32 {
    switch (w) {
        case 0u: { return STATUS_FAST; }
        case 1u: { return STATUS_ACTIVE; }
        case 2u: { return STATUS_SLIPPING; }
        case 3u: { return STATUS_FAST_RATIO; }
        case 4u: { return STATUS_MAX_OVERCLOSURE; }
        case 5u: { return STATUS_FORCE_SCALE; }
        case 6u: { return STATUS_ROW_SCALE; }
        case 7u: { return STATUS_DT_STABLE; }
        default: { return STATUS_DT_APPROACH; }
    }
}

// Each slot at its operation's identity (before the first barrier).
fn words_start(li: u32) {
    if (li < WG_WORDS) {
        atomicStore(&wg_words[li], select(0u, WG_MIN_IDENTITY, li >= WG_FIRST_MIN));
    }
}

// Each slot raised into its status word (after the second barrier), where a spring moved it.
fn words_finish(li: u32) {
    if (li >= WG_WORDS) { return; }
    let v = atomicLoad(&wg_words[li]);
    let word = wg_status_word(li);
    if (li < WG_FIRST_MAX) {
        if (v != 0u) { atomicAdd(&status[word], v); }
    } else if (li < WG_FIRST_MIN) {
        if (v != 0u) { atomicMax(&status[word], v); }
    } else if (v != WG_MIN_IDENTITY) {
        atomicMin(&status[word], v);
    }
}

const E_MINUS_1: f32 = 1.7182818;

// Force, tangent stiffness and stored energy of the pressure–overclosure law at overclosure h.
struct LawValue {
    force: f32,
    stiffness: f32,
    energy: f32,
}

fn table_point(k: u32) -> vec2<f32> {
    let v = pp.table[k / 2u];
    if (k % 2u == 0u) { return v.xy; }
    return v.zw;
}

fn law(h: f32, k: f32, area: f32) -> LawValue {
    var r = LawValue(0.0, 0.0, 0.0);
    if (pp.law == LAW_LINEAR) {
        r.stiffness = k;
        if (h > 0.0) {
            r.force = k * h;
            r.energy = 0.5 * k * h * h;
        }
    } else if (pp.law == LAW_EXPONENTIAL) {
        let x = min(max(h, 0.0) / pp.clearance + 1.0, 60.0);
        let ex = exp(x);
        r.stiffness = area * pp.pressure / (E_MINUS_1 * pp.clearance) * ((ex - 1.0) + x * ex);
        let xh = h / pp.clearance + 1.0;
        if (xh > 0.0) {
            let xc = min(xh, 60.0);
            let e2 = exp(xc);
            r.force = area * pp.pressure / E_MINUS_1 * xc * (e2 - 1.0);
            r.energy = area * pp.pressure * pp.clearance / E_MINUS_1 * ((xc - 1.0) * e2 + 1.0 - 0.5 * xc * xc);
        }
    } else {
        // tabular: slope of the segment holding max(h, h0); force and energy where h > h0
        let n = pp.table_len;
        let h_eval = max(h, table_point(0u).x);
        var energy = 0.0;
        var force = 0.0;
        var slope = 0.0;
        for (var s = 0u; s + 1u < n; s++) {
            let a = table_point(s);
            let b = table_point(s + 1u);
            let sl = (b.y - a.y) / (b.x - a.x);
            let last = s + 2u == n;
            if (h_eval >= a.x && (h_eval < b.x || last)) {
                slope = sl;
            }
            if (h > a.x) {
                let top = select(min(h, b.x), h, last);
                let p_top = a.y + sl * (top - a.x);
                energy += 0.5 * (a.y + p_top) * (top - a.x);
                force = p_top;
            }
        }
        r.stiffness = area * slope;
        r.force = area * force;
        r.energy = area * energy;
    }
    return r;
}

// First local tangent direction by the standard convention (twin of geometry::tangent_directions).
fn tangent_t1(n: vec3<f32>) -> vec3<f32> {
    var axis = vec3<f32>(1.0, 0.0, 0.0);
    if (abs(n.x) > COS_TENTH_DEGREE) { axis = vec3<f32>(0.0, 0.0, 1.0); }
    return normalize_or_zero(axis - n * dot(axis, n));
}

// The master's velocity at a contact point: the facet's nodes by the load-transfer weights (the
// same sum, in the same order, as the penalty pass's own).
fn facet_velocity(fac: vec4<u32>, w: vec4<f32>) -> vec3<f32> {
    var vm = vec3<f32>(0.0);
    for (var j = 0u; j < facet_node_count(fac); j++) { vm += w[j] * vel[fac[j]].xyz; }
    return vm;
}

// The fast-node test: slave s's velocity relative to the master near it, `v_master`, carrying
// it farther than the search radius within the increment is counted (STATUS_FAST) and its
// ratio to the radius kept if largest (STATUS_FAST_RATIO, non-negative f32 bits).
fn count_fast(s: u32, v_master: vec3<f32>) {
    let reach = length(vel[s].xyz - v_master) * pp.dt;
    if (reach > pp.search_radius) {
        atomicAdd(&wg_words[WG_FAST], 1u);
        atomicMax(&wg_words[WG_FAST_RATIO], bitcast<u32>(reach / pp.search_radius));
    }
}

@compute @workgroup_size(64)
fn penalty(@builtin(workgroup_id) wg: vec3<u32>,
           @builtin(num_workgroups) nwg: vec3<u32>,
           @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    words_start(li);
    workgroupBarrier();
    if (i < pp.n_slaves && atomicLoad(&status[STATUS_BUDGET_EXCEEDED]) == 0u) {
        spring(i, hits[i]);
    }
    workgroupBarrier();
    words_finish(li);
}

// Local increments: the active slaves only. An untracked one (visited with FLAG_EVERY_SLAVE)
// is left as the global increment's penalty pass left it: no facet, open, its state and
// output the same bits this pass would write again (its fast-node test is the global
// increment's: the motion budget asks for one before it can come within the radius).
@compute @workgroup_size(64)
fn penalty_active(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    words_start(li);
    workgroupBarrier();
    active_spring(k);
    workgroupBarrier();
    words_finish(li);
}

// Active slave k's spring, if it is one and tracked.
fn active_spring(k: u32) {
    if (k >= atomicLoad(&status[ACTIVE_LIST])) { return; }
    if (atomicLoad(&status[STATUS_BUDGET_EXCEEDED]) != 0u) { return; }
    let i = atomicLoad(&status[ACTIVE_LIST + 1u + k]);
    let hit = hits[i];
    if (hit.node == NO_NODE) { return; }
    spring(i, hit);
}

// Slave i's spring from its hit.
fn spring(i: u32, hit: Hit) {
    var o: ContactOut;
    o.force = vec4<f32>(0.0);
    o.tangential = vec4<f32>(0.0);
    o.normal_gap = vec4<f32>(0.0);
    o.status = CSTATUS_OPEN;
    o.dissipation = 0.0;
    o.bound_light = 0.0;
    o.bound_heavy = 0.0;
    var dt_stable = NO_LIMIT;
    var dt_approach = NO_LIMIT;
    let area = state[i].tangential_area.w;
    o.dissipation = state[i].history.x;
    // no partner, or beside a free edge of the master (off its facets): no contact; a node
    // beside it and below the facet's plane is remembered as behind the edge (history.y)
    let beside = (hit.candidates & HIT_BESIDE_FREE_EDGE) != 0u;
    if (hit.facet == NO_FACET || beside) {
        // fast-node test against the reference master node, or (beside a free edge) the
        // facet's velocity at the point
        if (hit.facet != NO_FACET) {
            count_fast(hit.slave, facet_velocity(facets[hit.facet], hit.weights));
        } else if (pp.ref_node != NO_NODE) {
            count_fast(hit.slave, vel[pp.ref_node].xyz);
        }
        state[i].tangential_area = vec4<f32>(0.0, 0.0, 0.0, area);
        let behind = select(0.0, 1.0, beside && hit.point_gap.w < 0.0);
        state[i].history = vec4<f32>(o.dissipation, behind, 0.0, 0.0);
        out[i] = o;
        return;
    }
    let s = hit.slave;
    let fac = facets[hit.facet];
    let n = facet_node_count(fac);
    var nsum = vec3<f32>(0.0);
    var vm = vec3<f32>(0.0);
    var inv_mm = 0.0;
    var h_facet = 0.0;
    var share = vec4<f32>(0.0);   // |w_j|/√m_j: each master node's share of the motion
    for (var j = 0u; j < n; j++) {
        let w = hit.weights[j];
        let node = fac[j];
        nsum += w * normals[node].xyz;
        vm += w * vel[node].xyz;
        inv_mm += w * w / nodes[node].w;
        share[j] = abs(w) / sqrt(nodes[node].w);
        h_facet = max(h_facet, length(nodes[fac[(j + 1u) % n]].xyz - nodes[node].xyz));
    }
    count_fast(s, vm);
    var nrm = normalize_or_zero(nsum);
    if (dot(nrm, nrm) == 0.0) { nrm = hit.normal_dist.xyz; }
    let p = nodes[s].xyz;
    var gap = dot(p - hit.point_gap.xyz, nrm);
    if ((pp.flags & PENALTY_ANCHORED) != 0u) {
        // small sliding: the anchor's tangent plane
        nrm = hit.normal_dist.xyz;
        gap = hit.point_gap.w;
    }
    // a node that came from behind a free edge, still below the surface, stays behind it until
    // it rises above: pushing it out would launch it with energy it never had
    if (state[i].history.y != 0.0 && gap < 0.0) {
        state[i].tangential_area = vec4<f32>(0.0, 0.0, 0.0, area);
        out[i] = o;
        return;
    }
    // a rigid side counts as one body: its compliance at the contact point along the normal
    // (mass and rotational inertia), one share in the node-wise bound
    var inv_ms = 1.0 / nodes[s].w;
    if (pp.master_body.w > 0.0) {
        inv_mm = body_compliance(pp.master_body, pp.master_inv_inertia, hit.point_gap.xyz, nrm);
        share = vec4<f32>(sqrt(inv_mm), 0.0, 0.0, 0.0);
    }
    if (pp.slave_body.w > 0.0) {
        inv_ms = body_compliance(pp.slave_body, pp.slave_inv_inertia, p, nrm);
    }
    let m_eff = 1.0 / (inv_ms + inv_mm);
    var k = pp.stiffness;
    if (pp.stiffness_mode == STIFFNESS_AUTO) {
        // a rigid slave part's slaves share its effective mass (slave_share = n; 1 otherwise)
        let m_auto = 1.0 / (inv_ms * pp.slave_share + inv_mm);
        k = pp.stiffness * m_auto / (pp.dt_ref * pp.dt_ref);   // stiffness: AUTO_STIFFNESS·scale
    } else if (pp.stiffness_mode == STIFFNESS_MODULUS) {
        k = pp.stiffness * pp.modulus * area / h_facet;
    } else if (pp.stiffness_mode == STIFFNESS_PER_AREA) {
        k = pp.stiffness * area;
    }
    let lv = law(-gap, k, area);
    let v_rel = vel[s].xyz - vm;
    let v_close = -dot(v_rel, nrm);
    // stable increment of this spring (with damping), and the approach limit
    let omega = sqrt(lv.stiffness / m_eff);
    let z = pp.damping;
    if (omega > 0.0) {
        dt_stable = 2.0 / omega * (sqrt(1.0 + z * z) - z);
    }
    if (gap > 0.0 && v_close > 0.0) {
        dt_approach = 0.5 * gap / v_close;
    }
    // node-wise bound: Cauchy–Schwarz weighted 1 at light nodes, share/cut at heavy ones
    var k_row = pp.weight * lv.stiffness;
    if (FRICTION) { k_row *= max(1.0, pp.stick_stiffness); }
    let share_s = sqrt(inv_ms);
    var top = share_s;
    for (var j = 0u; j < n; j++) { top = max(top, share[j]); }
    let cut = HEAVY_SHARE * top;
    var q = 0.0;
    var heavy = 0.0;
    var mask = 0u;
    if (share_s >= cut) { q += share_s * share_s; } else {
        q += share_s * cut;
        heavy = max(heavy, share_s);
        mask |= HEAVY_SLAVE;
    }
    for (var j = 0u; j < n; j++) {
        let u = share[j];
        if (u == 0.0) { continue; }
        if (u >= cut) { q += u * u; } else {
            q += u * cut;
            heavy = max(heavy, u);
            mask |= 1u << (HEAVY_SHIFT + j);
        }
    }
    o.bound_light = k_row * q;
    o.bound_heavy = k_row * q * (heavy / cut);
    o.normal_gap = vec4<f32>(nrm, gap);
    var f_t = vec3<f32>(0.0);
    if (lv.force > 0.0) {
        let c = 2.0 * z * sqrt(lv.stiffness * m_eff);
        let f_n = max(0.0, lv.force + c * v_close);
        o.status = CSTATUS_SLIP;
        if (FRICTION) {
            // carried friction force, rotated into the current tangent plane
            var t_prev = state[i].tangential_area.xyz;
            let mag = length(t_prev);
            t_prev = normalize_or_zero(t_prev - nrm * dot(t_prev, nrm)) * mag;
            let v_t = v_rel - nrm * dot(v_rel, nrm);
            let k_t = pp.stick_stiffness * lv.stiffness;
            let trial = t_prev - k_t * pp.dt * v_t;
            let mu = pp.mu_kinetic + (pp.mu - pp.mu_kinetic) * exp(-pp.decay * length(v_t));
            let limit = mu * f_n;
            let t_len = length(trial);
            if (t_len <= limit) {
                f_t = trial;
                o.status = CSTATUS_STICK;
            } else {
                f_t = trial * (limit / t_len);
                if (k_t > 0.0) { o.dissipation += pp.weight * limit * (t_len - limit) / k_t; }
            }
            if (k_t > 0.0) { o.tangential.w = 0.5 * dot(f_t, f_t) / k_t; }
        }
        // a balanced pair's pass contributes its weight's share
        let w = pp.weight;
        o.force = vec4<f32>(w * (f_n * nrm + f_t), w * f_n);
        o.tangential = vec4<f32>(w * f_t, w * (o.tangential.w + lv.energy));
        atomicAdd(&wg_words[WG_ACTIVE], 1u);
        if (o.status == CSTATUS_SLIP) { atomicAdd(&wg_words[WG_SLIPPING], 1u); }
        // non-negative f32 bits order as the values: an integer max is the float max
        atomicMax(&wg_words[WG_OVERCLOSURE], bitcast<u32>(max(-gap, 0.0)));
    }
    state[i].tangential_area = vec4<f32>(f_t, area);
    state[i].history = vec4<f32>(o.dissipation, 0.0, 0.0, 0.0);
    atomicMin(&wg_words[WG_DT_STABLE], bitcast<u32>(dt_stable));
    atomicMin(&wg_words[WG_DT_APPROACH], bitcast<u32>(dt_approach));
    o.status |= mask;
    if ((o.status & CSTATUS_MASK) != CSTATUS_OPEN) {
        // the fixed-point scales of the gather: the largest magnitudes it will sum
        let a = abs(o.force.xyz);
        atomicMax(&wg_words[WG_FORCE_SCALE], bitcast<u32>(max(a.x, max(a.y, a.z))));
        atomicMax(&wg_words[WG_ROW_SCALE], bitcast<u32>(max(o.bound_light, o.bound_heavy)));
    }
    out[i] = o;
}
