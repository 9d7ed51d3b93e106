//! The bandwidth bound: each kernel's compulsory bytes per slave in a steady local increment, the
//! groups' sums, and the bandwidth of a copy kernel measured on the same adapter.

use super::*;

/// Bytes each kernel of a steady penalty increment (local search) reads and writes per slave
/// node on this scene — the compulsory traffic of its storage bindings, from the layout types:
/// a node is 16 B (vec4<f32>), a hit `GpuHit` (64 B), a facet 16 B (four u32), a contact output
/// `ContactOut`, a quad facet touches 4 nodes; a plate node has 4 facets; there are about 4
/// slaves per facet and per master node (the scene's ratio).
pub(crate) fn kernel_bytes() -> Vec<(&'static str, f64)> {
    use abut::testing::abi::passes;
    // (kernel, bytes per slave); the groups that run them are in PASSES
    let node = 16.0;
    let hit = std::mem::size_of::<abut::testing::abi::search::GpuHit>() as f64;
    let out = std::mem::size_of::<abut::testing::abi::penalty::ContactOut>() as f64;
    let facet = 16.0;
    let per_master = 0.25; // master nodes (or facets) per slave
    let nodes = 1.0 + per_master; // slaves and master nodes, per slave
    vec![
        // the caller's positions in (16 B) and the frame's nodes out (16 B), per node
        (passes::TO_LOCAL.entry, 32.0 * nodes),
        // positions now and at the last global search, of slaves and master nodes
        (
            passes::MOTION.entry,
            (2.0 * node) * (1.0 + per_master) + 4.0,
        ),
        // the hit in and out, the tracked node's 4 facets with their 4 nodes
        (
            passes::LOCAL_SEARCH.entry,
            2.0 * hit + 4.0 * (facet + 4.0 * node) + 4.0,
        ),
        // per master node: its facets and their nodes, the normal out
        (
            passes::NODAL_NORMALS.entry,
            per_master * (4.0 * (facet + 4.0 * node) + node),
        ),
        // hit, node, velocity, the facet's 4 nodes and normals, state in/out, output out
        (
            passes::PENALTY.entry,
            hit + 2.0 * node + 8.0 * node + 2.0 * 32.0 + out,
        ),
        // each slave in contact: its output's force, status and bound shares (28 B), its hit's
        // weights and facet (20 B) and the facet's pair nodes; the 32 B fixed-point sums of each
        // master node read and written once (the atomics of the slaves sharing a node meet in
        // cache)
        (
            passes::SCATTER_FORCES.entry,
            28.0 + 20.0 + facet + per_master * 2.0 * 32.0,
        ),
        // each pair node: its pair-node record, its sums in and its force and bound row out;
        // a slave node also reads its own output (28 B)
        (
            passes::GATHER.entry,
            (node + 32.0 + node + 28.0) + per_master * (node + 32.0 + node),
        ),
        // each pair node: its record (16 B), its force (16 B), the caller's force read and
        // written (32 B) and its bound row (8 B)
        (passes::ADD_FORCES.entry, 72.0 * nodes),
    ]
}

/// Compulsory bytes per slave of `group` in a steady local increment: the sum over its kernels,
/// the schedule's one invocation counted as nothing. A kernel with no declared bytes is an error
/// naming it (a group changed and this table did not).
pub(crate) fn group_bytes(group: &Group, kb: &[(&'static str, f64)]) -> Result<f64, String> {
    group
        .passes
        .iter()
        .filter(|p| p.entry != abut::testing::abi::passes::SCHEDULE.entry)
        .map(|p| {
            kb.iter()
                .find(|e| e.0 == p.entry)
                .map(|e| e.1)
                .ok_or_else(|| {
                    format!(
                        "no compulsory bytes declared for kernel '{}' (group '{}')",
                        p.entry, group.label
                    )
                })
        })
        .sum()
}

/// The compute passes (groups, as the increment records them) of a steady penalty increment.
pub(super) const PASSES: [&Group; 4] = [
    &groups::TO_LOCAL_MOTION_SCHEDULE,
    &groups::LOCAL,
    &groups::NORMALS_PENALTY,
    &groups::SCATTER_GATHER_ADD,
];

/// The bandwidth of a copy kernel on `device` (bytes read + written per second), or of a host
/// memory copy on the CPU path.
pub(crate) fn copy_bandwidth(device: &Device) -> f64 {
    const BYTES: usize = 64 << 20;
    let Some((d, q)) = device.wgpu() else {
        let src = vec![1u8; BYTES];
        let mut dst = vec![0u8; BYTES];
        dst.copy_from_slice(&src);
        let t = Instant::now();
        for _ in 0..5 {
            dst.copy_from_slice(std::hint::black_box(&src));
            std::hint::black_box(&mut dst);
        }
        return 5.0 * 2.0 * BYTES as f64 / t.elapsed().as_secs_f64();
    };
    let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("copy"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<storage, read> src: array<vec4<u32>>;
             @group(0) @binding(1) var<storage, read_write> dst: array<vec4<u32>>;
             @compute @workgroup_size(256)
             fn main(@builtin(global_invocation_id) g: vec3<u32>) {
                 let i = g.x + g.y * 65535u * 256u;
                 if (i < arrayLength(&dst)) { dst[i] = src[i]; }
             }"
            .into(),
        ),
    });
    let pipe = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("copy"),
        layout: None,
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let size = (BYTES as u64).min(d.limits().max_storage_buffer_binding_size / 16 * 16);
    let buf = |usage| {
        d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage,
            mapped_at_creation: false,
        })
    };
    let src = buf(wgpu::BufferUsages::STORAGE);
    let dst = buf(wgpu::BufferUsages::STORAGE);
    let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: src.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: dst.as_entire_binding(),
            },
        ],
    });
    let groups = (size / 16).div_ceil(256) as u32;
    let run = |reps: usize| {
        let mut enc = d.create_command_encoder(&Default::default());
        for _ in 0..reps {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        }
        q.submit([enc.finish()]);
        let _ = d.poll(wgpu::PollType::wait_indefinitely());
    };
    run(1);
    let t = Instant::now();
    run(5);
    5.0 * 2.0 * size as f64 / t.elapsed().as_secs_f64()
}
