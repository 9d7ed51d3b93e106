//! Criterion benches of abut's kernels, on every adapter found and the CPU mirror: the global
//! search (tree_refit → nearest_facet), a tracked increment
//! (motion + local_search) and a penalty increment (search, then nodal_normals + penalty,
//! scatter_forces and gather), on a plate of 2,500 quads with 10,000 slave nodes around it.
//! The speed-against-error report is `abut bench`; this is the statistics of single kernels.
//!
//! `cargo bench --bench kernels` (criterion's options follow `--`).

use abut::mesh::{plate_quads, point_cloud};
use abut::{Contact, Device, Enforce, GlobalSearch, Model, Pair, PairId, Penalty, Surface};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn scene() -> (Model, PairId) {
    let side = 50;
    let h = 1.0 / side as f64;
    let plate = plate_quads(side, side, 1.0, 1.0, 0.1, 3, &|x, y| {
        0.02 * (5.0 * x).sin() * y
    });
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![1e12; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let cloud = point_cloud(10_000, [0.0, 0.0, -0.02 - h], [1.0, 1.0, 0.02 + h], 5);
    let r = m.add_nodes(&cloud, &vec![1.0; cloud.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pair = m
        .add_pair(
            Pair::new(set, s)
                .search_radius(2.0 * h)
                .enforce(Enforce::Penalty(Penalty::default())),
        )
        .unwrap();
    (m, pair)
}

fn devices() -> Vec<Device> {
    let mut d: Vec<Device> = Device::all_gpus()
        .into_iter()
        .filter_map(|d| d.ok())
        .collect();
    d.push(Device::cpu());
    d
}

fn kernels(c: &mut Criterion) {
    let (model, pair) = scene();
    let x = model.positions().to_vec();
    let v = vec![[0.0; 3]; x.len()];
    let mut g = c.benchmark_group("global search (5 kernels)");
    g.sample_size(10);
    for d in devices() {
        let mut s = GlobalSearch::new(&d, &model, pair).unwrap();
        s.run(&x).unwrap();
        g.bench_function(BenchmarkId::from_parameter(d.backend_name()), |b| {
            b.iter(|| s.run(&x).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("tracked increment (motion + local_search)");
    g.sample_size(10);
    for d in devices() {
        let mut s = GlobalSearch::new(&d, &model, pair).unwrap();
        s.step(&x).unwrap();
        g.bench_function(BenchmarkId::from_parameter(d.backend_name()), |b| {
            b.iter(|| s.step(&x).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("penalty increment (tracked search + 6 kernels)");
    g.sample_size(10);
    for d in devices() {
        let mut contact = Contact::new(&d, &model).unwrap();
        contact.penalty_step(&x, &v, 1e-4).unwrap();
        g.bench_function(BenchmarkId::from_parameter(d.backend_name()), |b| {
            b.iter(|| contact.penalty_step(&x, &v, 1e-4).unwrap().active)
        });
    }
    g.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
