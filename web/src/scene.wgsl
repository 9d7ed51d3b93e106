// scene.wgsl — draws the page's scene from the buffers abut's increment works in (no copies):
// the plate coloured by contact pressure, the beads as shaded discs.
//
// Bindings: 0 view (uniform View), 1 positions (vec4<f32> per model node, the increment's),
//           2 forces (vec4<f32> per node: the last increment's contact forces), 3 quads
//           (vec4<u32> per plate quad: its node ids), 4 areas (f32 per plate node: its
//           tributary area, m², a quarter of each quad around it).
// Draws: plate_vs with 6 vertices per quad (two triangles); bead_vs with 6 vertices per bead
//        instance (a camera-facing square, the disc cut out in bead_fs).
// Invariants: reads only; a bead's node is view.first_bead + instance index.

struct View {
    view_proj: mat4x4<f32>,
    right: vec4<f32>,          // camera right in the model frame (xyz)
    up: vec4<f32>,             // camera up in the model frame (xyz)
    // x: the contact pressure at the top of the colour ramp (Pa), y: bead radius (m), z: first
    // bead (as f32)
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> forces: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> quads: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> areas: array<f32>;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec3<f32>,
    @location(1) disc: vec2<f32>,
}

// blue (no pressure) through green and yellow to red (full scale)
fn ramp(t: f32) -> vec3<f32> {
    let s = clamp(t, 0.0, 1.0);
    return clamp(vec3<f32>(1.5 - abs(4.0 * s - 3.0), 1.5 - abs(4.0 * s - 2.0), 1.5 - abs(4.0 * s - 1.0)),
                 vec3<f32>(0.0), vec3<f32>(1.0));
}

@vertex
fn plate_vs(@builtin(vertex_index) vi: u32) -> Out {
    let corners = array<u32, 6>(0u, 1u, 2u, 0u, 2u, 3u);
    let q = quads[vi / 6u];
    let node = q[corners[vi % 6u]];
    let p = positions[node].xyz;
    let f = length(forces[node].xyz);
    let pressure = f / areas[node];
    var out: Out;
    out.clip = view.view_proj * vec4<f32>(p, 1.0);
    out.colour = mix(vec3<f32>(0.16, 0.18, 0.24), ramp(pressure / view.params.x), select(0.0, 1.0, f > 0.0));
    out.disc = vec2<f32>(0.0);
    return out;
}

@vertex
fn bead_vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> Out {
    let offsets = array<vec2<f32>, 6>(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                                      vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let node = u32(view.params.z) + ii;
    let o = offsets[vi];
    let r = view.params.y;
    let p = positions[node].xyz + r * (o.x * view.right.xyz + o.y * view.up.xyz);
    let touching = length(forces[node].xyz) > 0.0;
    var out: Out;
    out.clip = view.view_proj * vec4<f32>(p, 1.0);
    out.colour = select(vec3<f32>(0.75, 0.78, 0.85), vec3<f32>(1.0, 0.55, 0.1), touching);
    out.disc = o;
    return out;
}

@fragment
fn plate_fs(v: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(v.colour, 1.0);
}

@fragment
fn bead_fs(v: Out) -> @location(0) vec4<f32> {
    let r2 = dot(v.disc, v.disc);
    if (r2 > 1.0) { discard; }
    let shade = 0.45 + 0.55 * sqrt(1.0 - r2) - 0.2 * v.disc.y;
    return vec4<f32>(v.colour * shade, 1.0);
}
