//! The hexahedron's tests: rigid motion, the patch test, forces as the energy's gradient,
//! hourglass modes, the stable increment, refused elements.

use super::*;

const STEEL: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
};

/// A brick of sides (a, b, c), slightly skewed so no gradient is axis-aligned by accident.
fn brick(skew: f64) -> Vec<[f64; 3]> {
    CORNERS
        .iter()
        .map(|c| {
            let p = [
                0.5 * (c[0] + 1.0) * 2.0,
                0.5 * (c[1] + 1.0) * 1.5,
                0.5 * (c[2] + 1.0),
            ];
            [
                p[0] + skew * p[1] * p[2],
                p[1] + 0.5 * skew * p[0],
                p[2] - skew * p[0] * p[1],
            ]
        })
        .collect()
}

fn nodes() -> [u32; 8] {
    std::array::from_fn(|a| a as u32)
}

fn forces(h: &Hex8, x: &[[f64; 3]], nlgeom: bool) -> (Vec<[f64; 3]>, f64) {
    let mut f = vec![[0.0; 3]; 8];
    let w = h.add_internal_forces(x, &mut f, nlgeom);
    (f, w)
}

#[test]
fn rigid_motion_gives_no_force_and_no_energy() {
    let x = brick(0.1);
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let moved: Vec<[f64; 3]> = x
        .iter()
        .map(|p| {
            [
                c * p[0] - s * p[1] + 3.0,
                s * p[0] + c * p[1] - 1.0,
                p[2] + 2.0,
            ]
        })
        .collect();
    for integration in [Integration::Selective, Integration::Reduced] {
        let h = Hex8::new(nodes(), &x, STEEL, integration).unwrap();
        let (f, w) = forces(&h, &moved, true);
        let scale = STEEL.young * h.volume0;
        assert!(w.abs() < 1e-12 * scale, "{integration:?}: energy {w}");
        for fa in f {
            for v in fa {
                assert!(v.abs() < 1e-9 * scale, "{integration:?}: force {v}");
            }
        }
    }
}

#[test]
fn uniform_strain_is_reproduced_exactly() {
    // the patch test of one element: x = A·X gives S = C:E everywhere, the energy V0·W(E),
    // and the forces are those of that uniform stress
    let x = brick(0.15);
    let a = [
        [1.01, 0.004, -0.002],
        [0.003, 0.995, 0.001],
        [-0.001, 0.002, 1.02],
    ];
    let moved: Vec<[f64; 3]> = x
        .iter()
        .map(|p| std::array::from_fn(|r| (0..3).map(|c| a[r][c] * p[c]).sum()))
        .collect();
    let e = strain(&a, true);
    let (s, w) = hooke(&e, STEEL.lambda(), STEEL.mu());
    for integration in [Integration::Selective, Integration::Reduced] {
        let h = Hex8::new(nodes(), &x, STEEL, integration).unwrap();
        let (f, energy) = forces(&h, &moved, true);
        approx::assert_relative_eq!(energy, w * h.volume0, max_relative = 1e-10);
        let mut expect = vec![[0.0; 3]; 8];
        h.add_stress_forces(&mut expect, &a, &s, &h.grad0, h.volume0);
        for (got, want) in f.iter().zip(&expect) {
            for r in 0..3 {
                approx::assert_abs_diff_eq!(got[r], want[r], epsilon = 1e-9 * STEEL.young);
            }
        }
        let sigma = h.stress(&moved, true);
        let want = push_forward(&s, &a);
        for r in 0..3 {
            for c in 0..3 {
                approx::assert_abs_diff_eq!(
                    sigma[r][c],
                    want[r][c],
                    epsilon = 1e-6 * STEEL.young * 1e-3
                );
            }
        }
    }
}

#[test]
fn forces_are_the_gradient_of_the_energy() {
    // a central difference of the energy against the force, on a deformed, skewed element
    let x = brick(0.2);
    let moved: Vec<[f64; 3]> = x
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let k = k as f64;
            [
                p[0] + 0.01 * (k * 0.7).sin(),
                p[1] + 0.02 * (k * 1.3).cos(),
                p[2] - 0.015 * (k * 0.4).sin(),
            ]
        })
        .collect();
    for nlgeom in [true, false] {
        for integration in [Integration::Selective, Integration::Reduced] {
            let h = Hex8::new(nodes(), &x, STEEL, integration).unwrap();
            let (f, _) = forces(&h, &moved, nlgeom);
            let d = 1e-7;
            for a in 0..8 {
                for r in 0..3 {
                    let mut plus = moved.clone();
                    plus[a][r] += d;
                    let mut minus = moved.clone();
                    minus[a][r] -= d;
                    let dw =
                        (forces(&h, &plus, nlgeom).1 - forces(&h, &minus, nlgeom).1) / (2.0 * d);
                    approx::assert_relative_eq!(
                        -dw,
                        f[a][r],
                        max_relative = 1e-5,
                        epsilon = 1e-6 * STEEL.young
                    );
                }
            }
        }
    }
}

#[test]
fn the_reduced_element_resists_its_hourglass_modes_and_the_selective_has_none() {
    let x = brick(0.0);
    for (k, integration) in [Integration::Selective, Integration::Reduced]
        .into_iter()
        .enumerate()
    {
        let h = Hex8::new(nodes(), &x, STEEL, integration).unwrap();
        // the x-displacement pattern ξη: zero strain at the centroid
        let moved: Vec<[f64; 3]> = x
            .iter()
            .zip(CORNERS)
            .map(|(p, c)| [p[0] + 1e-4 * c[0] * c[1], p[1], p[2]])
            .collect();
        let (_, w) = forces(&h, &moved, true);
        assert!(w > 0.0, "{integration:?}");
        if k == 1 {
            // only the hourglass stiffness holds it: softer than the selectively reduced
            // element (whose bending of this mode is already too stiff: shear locking)
            let full = Hex8::new(nodes(), &x, STEEL, Integration::Selective).unwrap();
            let (_, wf) = forces(&full, &moved, true);
            assert!(w < wf, "{w} vs {wf}");
        }
    }
}

#[test]
fn the_stable_increment_is_below_the_elements_highest_frequency_limit() {
    // a cube of side h: the one-point element's highest mode is the uniform dilatation,
    // ω² = 4(3λ + 2μ)/(ρh²); the increment must not pass 2/ω, and not be far below it
    let h = 0.5;
    let x: Vec<[f64; 3]> = CORNERS
        .iter()
        .map(|c| c.map(|v| 0.5 * h * (v + 1.0)))
        .collect();
    let (l, mu) = (STEEL.lambda(), STEEL.mu());
    let exact = 2.0 / (4.0 * (3.0 * l + 2.0 * mu) / (STEEL.density * h * h)).sqrt();
    for integration in [Integration::Selective, Integration::Reduced] {
        let e = Hex8::new(nodes(), &x, STEEL, integration).unwrap();
        let dt = e.stable_increment();
        assert!(
            dt <= exact * (1.0 + 1e-12),
            "{integration:?}: {dt} > {exact}"
        );
        assert!(dt > 0.5 * exact, "{integration:?}: {dt} ≪ {exact}");
    }
}

#[test]
fn an_inverted_or_collapsed_element_is_refused() {
    let x = brick(0.0);
    let mirrored = [4, 5, 6, 7, 0, 1, 2, 3];
    assert!(Hex8::new(mirrored, &x, STEEL, Integration::Selective).is_none());
    let mut flat = x.clone();
    for p in flat.iter_mut().skip(4) {
        p[2] = 0.0;
    }
    assert!(Hex8::new(nodes(), &flat, STEEL, Integration::Reduced).is_none());
}
