//! Closest points, weights and normals: triangles against parry3d, quads against their
//! triangle split (planar) and dense sampling (warped), segments, tangent directions.

use abut::geometry::*;
use parry3d::math::Vector as PVec;
use parry3d::query::PointQuery;
use proptest::prelude::*;

fn v(a: [f64; 3]) -> V3<f64> {
    V3::from_array(a)
}

fn coord() -> impl Strategy<Value = f64> {
    -2.0f64..2.0
}

fn point() -> impl Strategy<Value = [f64; 3]> {
    [coord(), coord(), coord()]
}

fn reproduces(weights: &[f64], x: &[V3<f64>], p: V3<f64>, tol: f64) -> bool {
    let mut s = V3::zero();
    for (w, xi) in weights.iter().zip(x) {
        s = s + *xi * *w;
    }
    (s - p).length2().sqrt() <= tol
}

proptest! {
    // A fixed seed: the same 2,000 cases on every run, so CI is reproducible. A random run once
    // drew a strongly distorted planar quad where Newton from the quad's centre overshot from
    // corner to corner and the projection missed an interior minimum (0.018 against the
    // triangles' 0.007); Newton now starts from the nearer triangle, and
    // `distorted_planar_quads_match_their_triangles` sweeps that neighbourhood.
    #![proptest_config(ProptestConfig {
        cases: 2000,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0ab0_7015),
        ..ProptestConfig::default()
    })]

    #[test]
    fn triangle_matches_parry(a in point(), b in point(), c in point(), p in point()) {
        let (a, b, c, p) = (v(a), v(b), v(c), v(p));
        prop_assume!((b - a).cross(c - a).length2() > 1e-4);
        let r = closest_on_triangle(p, a, b, c);
        let f = |x: V3<f64>| PVec::new(x.x as f32, x.y as f32, x.z as f32);
        let tri = parry3d::shape::Triangle::new(f(a), f(b), f(c));
        let q = tri.project_local_point(f(p), false).point;
        let d_parry = ((q.x as f64 - p.x).powi(2) + (q.y as f64 - p.y).powi(2) + (q.z as f64 - p.z).powi(2)).sqrt();
        prop_assert!((r.dist2.sqrt() - d_parry).abs() < 2e-5, "abut {} parry {}", r.dist2.sqrt(), d_parry);
        let w = r.weights;
        prop_assert!(w[..3].iter().all(|&w| w >= -1e-12) && (w[0] + w[1] + w[2] - 1.0).abs() < 1e-12 && w[3] == 0.0);
        prop_assert!(reproduces(&w[..3], &[a, b, c], r.point, 1e-12));
        prop_assert!((r.normal.length2() - 1.0).abs() < 1e-12);
        // f32 twin (the CPU mirror) agrees to round-off
        let g = |x: V3<f64>| V3::new(x.x as f32, x.y as f32, x.z as f32);
        let r32 = closest_on_triangle(g(p), g(a), g(b), g(c));
        prop_assert!((r32.dist2.sqrt() as f64 - r.dist2.sqrt()).abs() < 1e-5);
    }

    /// A planar convex quad is the union of its two triangles: same nearest distance.
    #[test]
    fn planar_quad_matches_its_triangles(cx in -1.0f64..1.0, cy in -1.0f64..1.0, r in [0.2f64..1.0, 0.2f64..1.0, 0.2f64..1.0, 0.2f64..1.0],
                                          th in [0.0f64..1.2, 0.0f64..1.2, 0.0f64..1.2, 0.0f64..1.2], tilt in [-1.0f64..1.0, -1.0f64..1.0], p in point()) {
        // vertices on a star around (cx, cy) at increasing angles: a convex-ish, CCW quad
        let mut x = [V3::zero(); 4];
        for k in 0..4 {
            let ang = k as f64 * std::f64::consts::FRAC_PI_2 + th[k] * 0.5;
            let (px, py) = (cx + r[k] * ang.cos(), cy + r[k] * ang.sin());
            x[k] = V3::new(px, py, tilt[0] * px + tilt[1] * py);
        }
        // keep it convex
        for k in 0..4 {
            let e0 = x[(k + 1) % 4] - x[k];
            let e1 = x[(k + 2) % 4] - x[(k + 1) % 4];
            prop_assume!(e0.cross(e1).z > 0.05);
        }
        let p = v(p);
        let q = closest_on_quad(p, x);
        let t = closest_on_triangle(p, x[0], x[1], x[2]).dist2.min(closest_on_triangle(p, x[0], x[2], x[3]).dist2);
        prop_assert!((q.dist2.sqrt() - t.sqrt()).abs() < 1e-9, "quad {} triangles {}", q.dist2.sqrt(), t.sqrt());
        let w = q.weights;
        prop_assert!(w.iter().all(|&w| w >= -1e-12) && (w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        prop_assert!(reproduces(&w, &x, q.point, 1e-9));
        prop_assert!((q.normal.length2() - 1.0).abs() < 1e-9 && q.normal.z > 0.0);
    }

    /// A mildly warped quad: the nearest point is at least as near as dense sampling finds,
    /// and not farther than sampling's resolution allows.
    #[test]
    fn warped_quad_against_dense_sampling(h in [-0.15f64..0.15, -0.15f64..0.15, -0.15f64..0.15, -0.15f64..0.15], p in point()) {
        let x = [V3::new(0.0, 0.0, h[0]), V3::new(1.0, 0.0, h[1]), V3::new(1.1, 0.9, h[2]), V3::new(-0.1, 1.0, h[3])];
        let p = v(p);
        let q = closest_on_quad(p, x);
        let n = 200;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                let w = quad_shape(-1.0 + 2.0 * i as f64 / n as f64, -1.0 + 2.0 * j as f64 / n as f64);
                let s = x[0] * w[0] + x[1] * w[1] + x[2] * w[2] + x[3] * w[3];
                best = best.min((s - p).length2());
            }
        }
        let (d, ds) = (q.dist2.sqrt(), best.sqrt());
        prop_assert!(d <= ds + 1e-12, "found {d}, sampling {ds}");
        prop_assert!(d >= ds - 0.01, "found {d}, sampling {ds}: sampling spacing is 0.0055");
        prop_assert!(reproduces(&q.weights, &x, q.point, 1e-9));
    }
}

#[test]
fn segment_points_weights_and_normal() {
    let (a, b) = (V3::new(1.0, 0.0, 0.0), V3::new(3.0, 0.0, 0.0));
    let r = closest_on_segment(V3::new(1.5, 2.0, 0.0), a, b);
    assert_eq!(r.point, V3::new(1.5, 0.0, 0.0));
    assert_eq!(r.weights, [0.75, 0.25, 0.0, 0.0]);
    assert_eq!(r.normal, V3::new(0.0, -1.0, 0.0)); // right of a→b
    assert_eq!(r.gap(V3::new(1.5, 2.0, 0.0)), -2.0);
    let end = closest_on_segment(V3::new(5.0, 1.0, 0.0), a, b);
    assert_eq!(end.point, b);
    assert_eq!(end.dist2, 5.0);
}

#[test]
fn gap_is_signed_by_the_facet_normal() {
    let (a, b, c) = (
        V3::new(0.0, 0.0, 0.0),
        V3::new(1.0, 0.0, 0.0),
        V3::new(0.0, 1.0, 0.0),
    );
    let above = V3::new(0.2, 0.2, 0.5);
    let below = V3::new(0.2, 0.2, -0.5);
    assert_eq!(closest_on_triangle(above, a, b, c).gap(above), 0.5);
    assert_eq!(closest_on_triangle(below, a, b, c).gap(below), -0.5);
}

/// A planar quad on a star around `c` (corner k at angle k·π/2 + th[k]/2, radius r[k]) in
/// the plane z = tilt·(x, y).
fn star_quad(c: [f64; 2], r: [f64; 4], th: [f64; 4], tilt: [f64; 2]) -> [V3<f64>; 4] {
    let mut x = [V3::zero(); 4];
    for k in 0..4 {
        let ang = k as f64 * std::f64::consts::FRAC_PI_2 + th[k] * 0.5;
        let (px, py) = (c[0] + r[k] * ang.cos(), c[1] + r[k] * ang.sin());
        x[k] = V3::new(px, py, tilt[0] * px + tilt[1] * py);
    }
    x
}

/// Distorted planar convex quads — the one a random run drew (where Newton from the centre
/// missed the interior minimum) and a sweep of corner radii 0.1–1 (ratios up to 10), angles,
/// tilts and points around them, points just off the plane in particular — project exactly as
/// their two triangles do, in f64 and in the kernels' f32.
#[test]
fn distorted_planar_quads_match_their_triangles() {
    let recorded = star_quad(
        [0.048640138434842196, -0.5750136668763839],
        [
            0.8246866870354782,
            0.3378355036850574,
            0.2,
            0.407149921225526,
        ],
        [
            1.196906008979994,
            0.9774992755858142,
            0.0,
            0.23399682665874535,
        ],
        [-0.159923193438523, -0.7568252451123284],
    );
    let p = V3::new(
        0.42292735566954803,
        -0.18099066632884964,
        0.07827633505777112,
    );
    let tri = |x: &[V3<f64>; 4], p: V3<f64>| {
        closest_on_triangle(p, x[0], x[1], x[2])
            .dist2
            .min(closest_on_triangle(p, x[0], x[2], x[3]).dist2)
            .sqrt()
    };
    let q = closest_on_quad(p, recorded).dist2.sqrt();
    assert!(
        (q - tri(&recorded, p)).abs() < 1e-12,
        "recorded case: quad {q}"
    );
    let mut rng = abut::mesh::SplitMix64::new(16);
    let (mut checked, mut worst32) = (0, 0.0f64);
    while checked < 20_000 {
        let c = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let r = [0; 4].map(|_| rng.range(0.1, 1.0));
        let th = [0; 4].map(|_| rng.range(0.0, 1.2));
        let tilt = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let x = star_quad(c, r, th, tilt);
        let convex = (0..4).all(|k| {
            let e0 = x[(k + 1) % 4] - x[k];
            let e1 = x[(k + 2) % 4] - x[(k + 1) % 4];
            e0.cross(e1).z > 0.02
        });
        if !convex {
            continue;
        }
        // a point near the quad: on its plane's normal through a point of it, or anywhere
        let w = [0; 4].map(|_| rng.range(0.0, 1.0));
        let sum: f64 = w.iter().sum();
        let on = (0..4).fold(V3::zero(), |a, k| a + x[k] * (w[k] / sum));
        let nrm = (x[2] - x[0]).cross(x[3] - x[1]).normalize_or_zero();
        let p = if checked % 2 == 0 {
            on + nrm * rng.range(-0.05, 0.05)
                + V3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0)
        } else {
            V3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            )
        };
        let q = closest_on_quad(p, x);
        let t = tri(&x, p);
        assert!(
            (q.dist2.sqrt() - t).abs() < 1e-9,
            "quad {x:?}, point {p:?}: quad {} triangles {t}",
            q.dist2.sqrt()
        );
        let f = |a: V3<f64>| V3::new(a.x as f32, a.y as f32, a.z as f32);
        let q32 = closest_on_quad(f(p), x.map(f)).dist2.sqrt() as f64;
        worst32 = worst32.max((q32 - t).abs());
        checked += 1;
    }
    assert!(worst32 < 1e-5, "f32: worst difference {worst32}");
}

#[test]
fn collapsed_quad_edge_has_a_normal_and_no_nan() {
    // nodes 2 and 3 coincide: a triangle in quad form
    let x: [V3<f64>; 4] = [
        V3::new(0.0, 0.0, 0.0),
        V3::new(1.0, 0.0, 0.0),
        V3::new(0.5, 1.0, 0.0),
        V3::new(0.5, 1.0, 0.0),
    ];
    for p in [
        V3::new(0.5, 1.0, 0.3),
        V3::new(0.4, 0.3, -0.2),
        V3::new(2.0, 2.0, 1.0),
    ] {
        let q = closest_on_quad(p, x);
        assert!(
            q.dist2.is_finite() && q.point.x.is_finite() && q.weights.iter().all(|w| w.is_finite())
        );
        assert!((q.normal.z - 1.0).abs() < 1e-12, "normal {:?}", q.normal);
    }
}

#[test]
fn tangent_directions_follow_the_convention() {
    let n = V3::<f64>::new(0.0, 0.0, 1.0);
    let (t1, t2) = tangent_directions(n);
    assert!((t1.x - 1.0).abs() < 1e-15 && (t2.y - 1.0).abs() < 1e-15);
    // normal along x: t1 from the z axis
    let (t1, t2) = tangent_directions(V3::<f64>::new(1.0, 0.0, 0.0));
    assert_eq!(t1, V3::<f64>::new(0.0, 0.0, 1.0));
    assert_eq!(t2, V3::<f64>::new(0.0, -1.0, 0.0));
    // just outside 0.1° of x: still the x axis
    let a = 0.2f64.to_radians();
    let (t1, _) = tangent_directions(V3::<f64>::new(a.cos(), a.sin(), 0.0));
    assert!(t1.x.abs() > 0.0 && t1.z == 0.0);
    for n in [
        V3::<f64>::new(0.3, -0.4, 0.866),
        V3::<f64>::new(-0.6, 0.0, 0.8),
    ] {
        let n = n.normalize_or_zero();
        let (t1, t2) = tangent_directions(n);
        assert!(t1.dot(n).abs() < 1e-12 && t2.dot(n).abs() < 1e-12 && t1.dot(t2).abs() < 1e-12);
        assert!((t1.length2() - 1.0).abs() < 1e-12 && (t2.length2() - 1.0).abs() < 1e-12);
    }
}
