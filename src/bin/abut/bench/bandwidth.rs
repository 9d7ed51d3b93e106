//! The bandwidth bound: each kernel's compulsory bytes per slave in a steady local increment, the
//! groups' sums, and the bandwidth of a copy kernel measured on the same adapter.

use super::*;

/// The bench scene's contact surface: a plate of quads with about four slaves per facet.
pub(crate) const PLATE: abut::testing::abi::traffic::Topology =
    abut::testing::abi::traffic::Topology {
        masters_per_slave: 0.25,
        facets_per_node: 4.0,
        nodes_per_facet: 4.0,
    };

/// Bytes each kernel of a steady penalty increment (local search) reads and writes per slave
/// node on the bench scene when the share `near` of the slaves is within the search radius —
/// derived from the passes' declared traffic (`abi::traffic`), for every declared kernel.
pub(crate) fn kernel_bytes(near: f64) -> Vec<(&'static str, f64)> {
    use abut::testing::abi::traffic::{bytes_per_slave, DECLARED};
    DECLARED
        .iter()
        .filter_map(|p| Some((p.entry, bytes_per_slave(p, &PLATE, near)?)))
        .collect()
}

/// Compulsory bytes per slave of `group` in a steady local increment: the sum over the kernels
/// a local increment runs (`abi::traffic::NOT_LOCAL` left out). A kernel with no declared
/// traffic is an error naming it (a group gained a pass whose traffic `abi::traffic` does not
/// declare).
pub(crate) fn group_bytes(group: &Group, kb: &[(&'static str, f64)]) -> Result<f64, String> {
    use abut::testing::abi::traffic::NOT_LOCAL;
    group
        .passes
        .iter()
        .filter(|p| !NOT_LOCAL.contains(p))
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
    &groups::MOTION_SCHEDULE,
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
