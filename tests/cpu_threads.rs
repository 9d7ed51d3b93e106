//! The CPU path runs its kernels' invocations on all cores (rayon), and its results are the
//! same bits on one thread and on many: global searches (walks cut off and finished by many
//! chunks, self-contact), local searches and penalty increments with friction.

use abut::mesh::{plate_quads, point_cloud, sphere_triangles};
use abut::model::Stiffness;
use abut::{Contact, Device, Enforce, Friction, GlobalSearch, Model, Pair, Penalty, Surface};

/// Runs `f` on a rayon pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn bytes<T: bytemuck::Pod>(v: &[T]) -> Vec<u8> {
    bytemuck::cast_slice(v).to_vec()
}

/// A dense plate (40 × 40 quads, 3,000 slaves over it, a narrow and a wide radius), a
/// self-contact sphere, and slaves at a sphere's centre whose walks are cut off: global then
/// local searches.
fn searches() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for radius in [0.05, 3.0] {
        let plate = plate_quads(40, 40, 1.0, 1.0, 0.1, 7, &|x, y| 0.02 * (9.0 * x * y).sin());
        let mut m = Model::new_3d();
        m.add_nodes(&plate.positions, &vec![1.0; plate.positions.len()])
            .unwrap();
        let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
        let slaves = point_cloud(3_000, [0.0, 0.0, -0.05], [1.0, 1.0, 0.1], 8);
        let r = m.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
        let set = m.add_node_set(&r.to_vec()).unwrap();
        let p = m.add_pair(Pair::new(set, s).search_radius(radius)).unwrap();
        let mut search = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
        let mut x = m.positions().to_vec();
        let g = search.run(&x).unwrap();
        out.push(bytes(&g.raw));
        out.push(g.stats.candidates.to_le_bytes().to_vec());
        for k in 0..3 {
            for xi in &mut x[r.start as usize..] {
                xi[0] += 0.003 * (k + 1) as f64;
            }
            let l = search.step(&x).unwrap();
            out.push(bytes(&l.raw));
            out.push(l.stats.local_iterations.to_le_bytes().to_vec());
        }
    }
    // self-contact: a sphere's own nodes against its own facets
    let sphere = sphere_triangles(24, 48, 1.0, [0.0; 3]);
    let mut m = Model::new_3d();
    m.add_nodes(&sphere.positions, &vec![1.0; sphere.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&sphere.facets)).unwrap();
    let all: Vec<u32> = (0..sphere.positions.len() as u32).collect();
    let set = m.add_node_set(&all).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(0.3)).unwrap();
    let mut search = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    let g = search.run(m.positions()).unwrap();
    out.push(bytes(&g.raw));
    // slaves near the centre of a sphere of 20,000 triangles: every facet nearly as far, the
    // walks reach their cap and the chunks (several per slave) finish them
    let sphere = sphere_triangles(100, 100, 1.0, [0.0; 3]);
    let mut m = Model::new_3d();
    m.add_nodes(&sphere.positions, &vec![1.0; sphere.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::triangles(&sphere.facets)).unwrap();
    let inside = point_cloud(300, [-0.01; 3], [0.01; 3], 9);
    let r = m.add_nodes(&inside, &vec![1.0; inside.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let p = m.add_pair(Pair::new(set, s).search_radius(2.0)).unwrap();
    let mut search = GlobalSearch::new(&Device::cpu(), &m, p).unwrap();
    let g = search.run(m.positions()).unwrap();
    assert_eq!(g.stats.fallbacks, 300, "the walks were not cut off");
    out.push(bytes(&g.raw));
    out
}

/// Point masses pressed into a plate with penalty and Coulomb friction over a few increments:
/// forces, stable increments and counters.
fn penalty_increments() -> Vec<Vec<u8>> {
    let plate = plate_quads(20, 20, 1.0, 1.0, 0.0, 0, &|_, _| 0.0);
    let mut m = Model::new_3d();
    m.add_nodes(&plate.positions, &vec![2.0; plate.positions.len()])
        .unwrap();
    let s = m.add_surface(Surface::quads(&plate.facets)).unwrap();
    let slaves = point_cloud(2_000, [0.02, 0.02, -0.01], [0.98, 0.98, 0.01], 11);
    let r = m.add_nodes(&slaves, &vec![1.0; slaves.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let pen = Penalty {
        stiffness: Stiffness::Absolute(1.0e4),
        damping: 0.05,
        ..Default::default()
    };
    m.add_pair(
        Pair::new(set, s)
            .search_radius(0.1)
            .enforce(Enforce::Penalty(pen))
            .friction(Friction::coulomb(0.4)),
    )
    .unwrap();
    let mut contact = Contact::new(&Device::cpu(), &m).unwrap();
    let mut x = m.positions().to_vec();
    let mut v = vec![[0.0; 3]; x.len()];
    for vi in &mut v[r.start as usize..] {
        *vi = [0.3, -0.2, -0.5];
    }
    let mut out = Vec::new();
    for _ in 0..5 {
        let rep = contact.penalty_step(&x, &v, 1e-3).unwrap();
        let f: Vec<f64> = rep.forces.iter().flatten().copied().collect();
        out.push(bytes(&f));
        out.push(
            [rep.stable_dt, rep.approach_dt, rep.max_overclosure]
                .iter()
                .flat_map(|d| d.to_le_bytes())
                .collect(),
        );
        out.push(
            [rep.active as u64, rep.slipping as u64, u64::MAX]
                .iter()
                .flat_map(|c| c.to_le_bytes())
                .collect(),
        );
        for i in r.start as usize..x.len() {
            for a in 0..3 {
                x[i][a] += 1e-3 * v[i][a];
            }
        }
    }
    out
}

#[test]
fn searches_are_the_same_bits_on_one_thread_and_many() {
    let one = on_threads(1, searches);
    for threads in [2, 4, 7] {
        let many = on_threads(threads, searches);
        assert_eq!(one.len(), many.len());
        for (k, (a, b)) in one.iter().zip(&many).enumerate() {
            assert!(a == b, "output {k} differs between 1 and {threads} threads");
        }
    }
}

#[test]
fn penalty_increments_are_the_same_bits_on_one_thread_and_many() {
    let one = on_threads(1, penalty_increments);
    // the counter records end with u64::MAX; their first word is the active count
    let active = one
        .iter()
        .filter(|o| o.len() == 24 && o[16..] == [0xff; 8])
        .map(|o| u64::from_le_bytes(o[..8].try_into().unwrap()))
        .max()
        .unwrap();
    assert!(
        active > 100,
        "{active} active contacts: too few to be a test"
    );
    for threads in [2, 4, 7] {
        let many = on_threads(threads, penalty_increments);
        for (k, (a, b)) in one.iter().zip(&many).enumerate() {
            assert!(a == b, "output {k} differs between 1 and {threads} threads");
        }
    }
}
