//! Shared test helpers: the GPU devices to test on, scene builders and result comparison.
#![allow(dead_code)]

use std::sync::OnceLock;

#[cfg(feature = "capi")]
pub mod capi;
#[cfg(feature = "solver")]
pub mod scene_toml;

use abut::geometry::{closest_on_facet, V3};
use abut::model::MasterSurface;
use abut::testing::abi::search::{GpuHit, HIT_BESIDE_FREE_EDGE};
use abut::testing::brute_force::{brute_force, OracleHit};
use abut::{Device, GlobalSearch, Model, Pair, PairId, SearchResult, SearchStructure};

/// The CPU path and every GPU adapter ([`gpus`]): the devices a test runs on.
pub fn devices() -> Vec<Device> {
    let mut all = vec![Device::cpu()];
    all.extend(gpus().iter().cloned());
    all
}

/// Every GPU adapter to run parity tests on (all backends, narrowed by `WGPU_BACKEND`).
///
/// With `ABUT_REQUIRE_ADAPTER=1` a missing adapter fails the test; with
/// `ABUT_REQUIRE_BACKENDS=vulkan,gl` each named backend must be among them. Without these,
/// a missing adapter is reported loudly and the GPU half of the test is skipped.
pub fn gpus() -> &'static [Device] {
    static DEVICES: OnceLock<Vec<Device>> = OnceLock::new();
    DEVICES.get_or_init(|| {
        let mut found = Vec::new();
        for d in Device::all_gpus() {
            match d {
                Ok(d) => found.push(d),
                Err(e) => eprintln!("note: an adapter could not be used: {e}"),
            }
        }
        let require = std::env::var("ABUT_REQUIRE_ADAPTER").is_ok_and(|v| v == "1");
        if found.is_empty() {
            if require {
                panic!("ABUT_REQUIRE_ADAPTER=1 but no GPU adapter was found");
            }
            eprintln!("\n*** SKIPPED: no GPU adapter found; GPU halves of the tests did not run ***\n");
        }
        if let Ok(list) = std::env::var("ABUT_REQUIRE_BACKENDS") {
            for want in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                assert!(
                    found.iter().any(|d| d.backend_name() == want),
                    "ABUT_REQUIRE_BACKENDS names '{want}' but no adapter of that backend was found (found: {:?})",
                    found.iter().map(|d| d.to_string()).collect::<Vec<_>>()
                );
            }
        }
        for d in &found {
            eprintln!("testing on adapter: {d}");
        }
        found
    })
}

/// Round-off tolerance of the f32 search in the kernels' frame: 32 ε_f32 times the size of
/// the region searched (the master's extent plus the radius on either side, plus the radius).
/// Points, gaps and distances are compared with it.
pub fn tolerance(r: &SearchResult, radius: f64) -> f64 {
    let [lo, hi] = r.stats.master_box;
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max) + 2.0 * radius;
    32.0 * f32::EPSILON as f64 * (extent + radius)
}

/// f64 distance from model node `node` to facet `facet`.
pub fn facet_distance(
    master: &MasterSurface,
    positions: &[[f64; 3]],
    node: u32,
    facet: u32,
) -> f64 {
    let p = V3::from_array(positions[node as usize]);
    let x: Vec<V3<f64>> = master.facets[facet as usize]
        .nodes()
        .iter()
        .map(|&n| V3::from_array(positions[n as usize]))
        .collect();
    closest_on_facet(p, &x).dist2.sqrt()
}

/// Counts of what a comparison met.
#[derive(Debug, Default)]
pub struct Compared {
    pub checked: usize,
    pub found: usize,
    pub ties: usize,
    pub radius_edge: usize,
}

/// Compares two searches of the same scene (e.g. GPU against the CPU mirror): the same facet
/// for every query that is not a tie (two facets within `tol` in f64), points, gaps, distances
/// and normals within `tol`, weights within `tol / facet size`.
pub fn assert_same_search(
    a: &SearchResult,
    b: &SearchResult,
    master: &MasterSurface,
    positions: &[[f64; 3]],
    radius: f64,
    tol: f64,
    what: &str,
) -> Compared {
    assert_eq!(a.slaves, b.slaves);
    let mut c = Compared::default();
    for (i, (x, y)) in a.contacts().zip(b.contacts()).enumerate() {
        let node = a.slaves[i];
        c.checked += 1;
        match (x, y) {
            (None, None) => {}
            (Some(h), None) | (None, Some(h)) => {
                assert!(
                    (h.distance - radius).abs() <= tol,
                    "{what}: slave {i} (node {node}) found by one side only, at distance {} (radius {radius})",
                    h.distance
                );
                c.radius_edge += 1;
            }
            (Some(h), Some(k)) => {
                c.found += 1;
                assert!(
                    (h.distance - k.distance).abs() <= tol,
                    "{what}: slave {i}: distance {} vs {}",
                    h.distance,
                    k.distance
                );
                if h.facet != k.facet {
                    let dh = facet_distance(master, positions, node, h.facet);
                    let dk = facet_distance(master, positions, node, k.facet);
                    assert!((dh - dk).abs() <= tol, "{what}: slave {i} (node {node}): facet {} ({dh}) vs {} ({dk}) is not a tie", h.facet, k.facet);
                    c.ties += 1;
                    continue;
                }
                let size = master.facet_size[h.facet as usize];
                for a in 0..3 {
                    assert!(
                        (h.point[a] - k.point[a]).abs() <= tol,
                        "{what}: slave {i}: point {:?} vs {:?}",
                        h.point,
                        k.point
                    );
                }
                assert!(
                    (h.gap - k.gap).abs() <= tol,
                    "{what}: slave {i}: gap {} vs {}",
                    h.gap,
                    k.gap
                );
                for w in 0..4 {
                    assert!(
                        (h.weights[w] - k.weights[w]).abs() <= 4.0 * tol / size,
                        "{what}: slave {i}: weights {:?} vs {:?}",
                        h.weights,
                        k.weights
                    );
                }
                if h.distance > 1e3 * tol {
                    // the normal of a quad varies over the facet: compare where the point is well defined
                    for a in 0..3 {
                        assert!(
                            (h.normal[a] - k.normal[a]).abs() <= 1e-3,
                            "{what}: slave {i}: normal {:?} vs {:?}",
                            h.normal,
                            k.normal
                        );
                    }
                }
                assert_eq!(
                    h.tracked_node, k.tracked_node,
                    "{what}: slave {i}: tracked node"
                );
            }
        }
    }
    c
}

/// Compares a search with the brute-force f64 oracle on the slaves `which` (indices into the
/// node set): ties (second-nearest facet within `tol`) may pick either facet.
pub fn assert_matches_oracle(
    r: &SearchResult,
    master: &MasterSurface,
    positions: &[[f64; 3]],
    radius: f64,
    tol: f64,
    which: &[usize],
    what: &str,
) -> Compared {
    let nodes: Vec<u32> = which.iter().map(|&i| r.slaves[i]).collect();
    let oracle: Vec<Option<OracleHit>> = brute_force(master, positions, &nodes, radius);
    let mut c = Compared::default();
    for (k, &i) in which.iter().enumerate() {
        c.checked += 1;
        match (&r.contact(i), &oracle[k]) {
            (None, None) => {}
            (Some(h), None) => {
                assert!(
                    (h.distance - radius).abs() <= tol,
                    "{what}: slave {i} found at {} but the oracle finds nothing within {radius}",
                    h.distance
                );
                c.radius_edge += 1;
            }
            (None, Some(o)) => {
                assert!(
                    (o.contact.distance - radius).abs() <= tol,
                    "{what}: slave {i} missed; the oracle finds facet {} at {}",
                    o.contact.facet,
                    o.contact.distance
                );
                c.radius_edge += 1;
            }
            (Some(h), Some(o)) => {
                c.found += 1;
                let oc = &o.contact;
                assert!(
                    (h.distance - oc.distance).abs() <= tol,
                    "{what}: slave {i}: distance {} vs oracle {}",
                    h.distance,
                    oc.distance
                );
                if h.facet != oc.facet {
                    assert!(
                        o.second_distance - oc.distance <= 2.0 * tol,
                        "{what}: slave {i}: facet {} but the oracle's {} is nearer by {}",
                        h.facet,
                        oc.facet,
                        o.second_distance - oc.distance
                    );
                    c.ties += 1;
                    continue;
                }
                for a in 0..3 {
                    assert!(
                        (h.point[a] - oc.point[a]).abs() <= tol,
                        "{what}: slave {i}: point {:?} vs oracle {:?}",
                        h.point,
                        oc.point
                    );
                }
                assert!(
                    (h.gap - oc.gap).abs() <= tol,
                    "{what}: slave {i}: gap {} vs oracle {}",
                    h.gap,
                    oc.gap
                );
                assert_eq!(
                    h.tracked_node, oc.tracked_node,
                    "{what}: slave {i}: tracked node"
                );
            }
        }
    }
    c
}

/// A model with one pair: `master` facets over `positions`, and `slaves` as extra nodes.
pub fn scene(
    dim: u32,
    positions: &[[f64; 3]],
    surface: abut::Surface,
    slaves: &[[f64; 3]],
    radius: f64,
) -> (Model, PairId) {
    let mut m = if dim == 2 {
        Model::new_2d()
    } else {
        Model::new_3d()
    };
    m.add_nodes(positions, &vec![1.0; positions.len()]).unwrap();
    let s = m.add_surface(surface).unwrap();
    let r = m.add_nodes(slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(radius)).unwrap();
    (m, p)
}

/// Runs the search of `pair` on `device` with both structures ([`Both`]): the tree's result,
/// the buckets' checked to give the same contacts bit for bit.
pub fn run(device: &Device, model: &Model, pair: PairId) -> SearchResult {
    let mut s = Both::new(device, model, pair).unwrap();
    s.run(model.positions()).unwrap()
}

/// A hit without its count of facets projected (which follows the structure's work): the
/// contact both structures must give bit for bit.
pub fn contact_bits(h: &GpuHit) -> GpuHit {
    GpuHit {
        candidates: h.candidates & HIT_BESIDE_FREE_EDGE,
        ..*h
    }
}

/// Asserts that two searches of the same scene found the same contacts bit for bit (every hit
/// word but the count of facets projected), in the same frame.
pub fn assert_same_contacts(a: &SearchResult, b: &SearchResult, what: &str) {
    assert_eq!(a.frame, b.frame, "{what}: frames");
    assert_eq!(a.raw.len(), b.raw.len(), "{what}: hits");
    for (i, (x, y)) in a.raw.iter().zip(b.raw.iter()).enumerate() {
        assert_eq!(contact_bits(x), contact_bits(y), "{what}: slave {i}");
    }
}

/// The global search of one pair with both structures, the tree and the buckets, on one
/// device: each run runs both and checks that they give the same contacts bit for bit (or the
/// same error), and returns the tree's result.
pub struct Both {
    /// The tree's search.
    pub tree: GlobalSearch,
    /// The buckets' search.
    pub buckets: GlobalSearch,
    device: String,
}

impl Both {
    /// Both searches of `pair` on `device`.
    pub fn new(device: &Device, model: &Model, pair: PairId) -> abut::Result<Self> {
        let mut tree = GlobalSearch::new(device, model, pair)?;
        tree.set_search_structure(SearchStructure::Tree);
        let mut buckets = GlobalSearch::new(device, model, pair)?;
        buckets.set_search_structure(SearchStructure::Buckets);
        Ok(Self {
            tree,
            buckets,
            device: device.to_string(),
        })
    }

    /// Folds both searches' dispatches beyond `groups` workgroups per dimension.
    pub fn set_max_workgroups_per_dim(&mut self, groups: u32) {
        self.tree.set_max_workgroups_per_dim(groups);
        self.buckets.set_max_workgroups_per_dim(groups);
    }

    /// A global search with both structures at `positions`: the tree's result.
    pub fn run(&mut self, positions: &[[f64; 3]]) -> abut::Result<SearchResult> {
        let t = self.tree.run(positions);
        let b = self.buckets.run(positions);
        self.compare(t, b)
    }

    /// An increment of tracking with both structures at `positions` (`GlobalSearch::step`):
    /// the tree's result.
    pub fn step(&mut self, positions: &[[f64; 3]]) -> abut::Result<SearchResult> {
        let t = self.tree.step(positions);
        let b = self.buckets.step(positions);
        self.compare(t, b)
    }

    fn compare(
        &self,
        t: abut::Result<SearchResult>,
        b: abut::Result<SearchResult>,
    ) -> abut::Result<SearchResult> {
        let what = format!("tree vs buckets on {}", self.device);
        match (&t, &b) {
            (Ok(t), Ok(b)) => {
                assert_same_contacts(t, b, &what);
                assert_eq!(t.stats.trigger, b.stats.trigger, "{what}: triggers");
                let (c, d) = (t.stats.collapsed_facets, b.stats.collapsed_facets);
                assert_eq!(c, d, "{what}: collapsed facets");
                assert_eq!(t.stats.structure, SearchStructure::Tree);
                assert_eq!(b.stats.structure, SearchStructure::Buckets);
            }
            (Err(x), Err(y)) => assert_eq!(x.to_string(), y.to_string(), "{what}"),
            _ => panic!("{what}: {:?} vs {:?}", t.as_ref().err(), b.as_ref().err()),
        }
        t
    }
}

/// Positions or velocities as the kernels' `vec4<f32>` per node.
pub fn vec4(a: &[[f64; 3]]) -> Vec<[f32; 4]> {
    a.iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0])
        .collect()
}

/// A host program's own device buffers for `n` nodes (`abut::testing::scenes::node_buffers`);
/// panics on the CPU path.
pub fn node_buffers(device: &Device, n: usize) -> [wgpu::Buffer; 3] {
    abut::testing::scenes::node_buffers(device, n).expect("a GPU device")
}

/// Reads `bytes` of `buffer` back (the test's own readback, not abut's).
pub fn read_buffer(device: &Device, buffer: &wgpu::Buffer, bytes: u64) -> Vec<u8> {
    let (d, q) = device.wgpu().expect("a GPU device");
    let staging = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = d.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
    q.submit([enc.finish()]);
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.unwrap());
    d.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let out = slice.get_mapped_range().unwrap().to_vec();
    staging.unmap();
    out
}

/// Rounds a point to f32 and back: positions every path sees exactly.
pub fn f32r(p: [f64; 3]) -> [f64; 3] {
    p.map(|v| v as f32 as f64)
}

/// A small deterministic hash of `i` and `salt` in [0, 1).
pub fn unit(i: usize, salt: u64) -> f64 {
    let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// The forces and statistics of `steps` device-resident increments of `c` on `d` (a model of
/// `n` nodes), increment k at the positions and velocities `state(k)`, over `dt`: on an adapter
/// through the caller's device buffers, on the CPU path through host arrays.
pub fn resident_run(
    d: &Device,
    c: &mut abut::Contact,
    n: usize,
    steps: usize,
    state: &dyn Fn(usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>),
    dt: f64,
) -> Vec<(Vec<[f32; 4]>, Vec<u8>)> {
    use abut::testing::abi::stats::STATS_BYTES;
    use abut::ResidentIo;
    let bufs = d.is_gpu().then(|| node_buffers(d, n));
    let mut out = Vec::new();
    for k in 0..steps {
        let (x, v) = state(k);
        match &bufs {
            Some([bx, bv, bf]) => {
                let (dev, q) = d.wgpu().unwrap();
                q.write_buffer(bx, 0, bytemuck::cast_slice(&vec4(&x)));
                q.write_buffer(bv, 0, bytemuck::cast_slice(&vec4(&v)));
                let mut enc = dev.create_command_encoder(&Default::default());
                enc.clear_buffer(bf, 0, None);
                let io = ResidentIo::Gpu {
                    encoder: &mut enc,
                    positions: bx,
                    velocities: bv,
                    forces: bf,
                };
                c.encode_increment(io, dt).unwrap();
                q.submit([enc.finish()]);
                let f = bytemuck::pod_collect_to_vec(&read_buffer(d, bf, (n * 16) as u64));
                let st = read_buffer(d, c.stats_buffer().unwrap(), STATS_BYTES);
                out.push((f, st));
            }
            None => {
                let mut f = vec![[0.0f32; 4]; n];
                let io = ResidentIo::Cpu {
                    positions: &vec4(&x),
                    velocities: &vec4(&v),
                    forces: &mut f,
                };
                c.encode_increment(io, dt).unwrap();
                let st = c.collect_stats().unwrap();
                out.push((f, bytemuck::bytes_of(&st[0]).to_vec()));
            }
        }
    }
    out
}

/// A flat master of unit size at height 0 and node mass 2: a 16×16 quad plate in 3D, a
/// 40-segment polyline in 2D; the model, the surface and the facet size.
pub fn flat_master(dim: u32) -> (Model, abut::SurfaceId, f64) {
    use abut::mesh::{plate_quads, polyline};
    use abut::Surface;
    if dim == 3 {
        let plate = plate_quads(16, 16, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![2.0; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        (m, s, 1.0 / 16.0)
    } else {
        let line = polyline(40, 1.0, 0.0, 0, &|_| 0.0);
        let mut m = Model::new_2d();
        m.add_nodes(&line.positions, &vec![2.0; line.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::segments(&line.facets)).unwrap();
        (m, s, 1.0 / 40.0)
    }
}
