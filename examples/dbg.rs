use abut::geometry::*;
use abut::mesh::*;
fn main() {
    let mut rng = SplitMix64::new(11);
    let mut plate = plate_quads(40, 40, 1.0, 1.0, 0.25, 5, &|_, _| 0.0);
    for x in &mut plate.positions { x[2] = rng.range(-0.01, 0.01); }
    let slaves = point_cloud(20_000, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05], 9);
    let p = slaves[8160];
    // find nearest facet by f64
    let mut best = (f64::MAX, 0);
    for (k, q) in plate.facets.iter().enumerate() {
        let x: Vec<V3<f64>> = q.iter().map(|&n| V3::from_array(plate.positions[n as usize])).collect();
        let pr = closest_on_facet(V3::from_array(p), &x);
        if pr.dist2 < best.0 { best = (pr.dist2, k); }
    }
    let q = plate.facets[best.1];
    let x: Vec<V3<f64>> = q.iter().map(|&n| V3::from_array(plate.positions[n as usize])).collect();
    let pr = closest_on_facet(V3::from_array(p), &x);
    println!("f64: facet {} point {:?} d {}", best.1, pr.point, pr.dist2.sqrt());
    let xf: Vec<V3<f32>> = x.iter().map(|v| V3::new(v.x as f32, v.y as f32, v.z as f32)).collect();
    let pf = closest_on_facet(V3::new(p[0] as f32, p[1] as f32, p[2] as f32), &xf);
    println!("f32: point {:?} d {}", pf.point, pf.dist2.sqrt());
    // dense sampling
    let mut bd = f64::MAX; let mut bp = (0.0,0.0);
    let n = 2000;
    for i in 0..=n { for j in 0..=n {
        let xi = -1.0 + 2.0 * i as f64 / n as f64; let eta = -1.0 + 2.0 * j as f64 / n as f64;
        let w = quad_shape(xi, eta);
        let pt = x[0]*w[0] + x[1]*w[1] + x[2]*w[2] + x[3]*w[3];
        let d = (pt - V3::from_array(p)).length2();
        if d < bd { bd = d; bp = (xi, eta); }
    }}
    println!("dense: d {} at {:?}", bd.sqrt(), bp);
    println!("p {:?} x {:?}", p, x);
    for o in [[-0.0625f64, -0.0625, -0.0625], [-0.05, -0.05, -0.06], [-0.1,-0.1,-0.1]] {
        let xf: Vec<V3<f32>> = x.iter().map(|v| V3::new((v.x - o[0]) as f32, (v.y-o[1]) as f32, (v.z-o[2]) as f32)).collect();
        let pf = closest_on_facet(V3::new((p[0]-o[0]) as f32, (p[1]-o[1]) as f32, (p[2]-o[2]) as f32), &xf);
        println!("local f32 {:?}: point {} {} {} d {}", o, pf.point.x as f64 + o[0], pf.point.y as f64 + o[1], pf.point.z as f64 + o[2], pf.dist2.sqrt());
    }
}
#[allow(dead_code)]
fn unused() {}
