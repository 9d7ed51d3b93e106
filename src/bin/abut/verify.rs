//! `abut verify`: the VERIFICATION.md cases through the scene files (built in), each quantity
//! printed against its exact value with the error and the tolerance.

use std::f64::consts::PI;

use abut::scene::{run, Scene, Summary};
use abut::Device;

/// One checked quantity.
struct Check {
    what: &'static str,
    measured: f64,
    exact: f64,
    /// Allowed |measured − exact|.
    allowed: f64,
    /// How the tolerance reads.
    tolerance: String,
}

impl Check {
    fn relative(what: &'static str, measured: f64, exact: f64, rel: f64) -> Self {
        Check {
            what,
            measured,
            exact,
            allowed: rel * exact.abs(),
            tolerance: format!("{:.3} %", rel * 100.0),
        }
    }
    fn absolute(what: &'static str, measured: f64, exact: f64, abs: f64, how: String) -> Self {
        Check {
            what,
            measured,
            exact,
            allowed: abs,
            tolerance: how,
        }
    }
    fn ok(&self) -> bool {
        (self.measured - self.exact).abs() <= self.allowed
    }
}

/// A verification case: its scene and what it checks.
pub struct Case {
    /// Short name for `--case`.
    pub name: &'static str,
    section: &'static str,
    scene: &'static str,
    checks: fn(&Summary) -> Vec<Check>,
}

fn truss(s: &Summary) -> Vec<Check> {
    let (e, rho, a, l, v0, gap) = (200e9f64, 7800.0, 0.2, 2.0, 1.5, 1e-3);
    let c = (e / rho).sqrt();
    let dt = s.element_increment;
    let t0 = gap / v0;
    vec![
        Check::absolute("impact time [s]", s.impact_time, t0, dt, "one dt".into()),
        Check::absolute(
            "release time [s]",
            s.release_time,
            t0 + 2.0 * l / c,
            dt,
            "one dt".into(),
        ),
        Check::relative("mean force [N]", s.mean_force, rho * c * v0 * a, 0.01),
        Check::relative(
            "impulse [N s]",
            s.impulse,
            rho * c * v0 * a * 2.0 * l / c,
            0.01,
        ),
        Check::relative("rebound speed [m/s]", s.parts[0].velocity[2], v0, 0.01),
    ]
}

fn bars(s: &Summary) -> Vec<Check> {
    let (a, l, v0) = (4.0f64, 10.0, 0.1);
    let dt = s.element_increment;
    vec![
        Check::absolute("impact time", s.impact_time, 1.0, dt, "one dt".into()),
        Check::absolute(
            "release time",
            s.release_time,
            1.0 + 2.0 * l,
            dt,
            "one dt".into(),
        ),
        Check::relative("mean force", s.mean_force, v0 * a, 0.01),
        Check::relative("rebound speed", -s.parts[0].velocity[0], v0, 0.01),
    ]
}

fn patch(s: &Summary) -> Vec<Check> {
    let p = 0.01 / (1.0 / 1e6 + 1.0 / 1e8);
    let worst = s
        .parts
        .iter()
        .flat_map(|q| [q.stress_min[1], q.stress_max[1]])
        .fold(-p, |w, sy| {
            if (sy + p).abs() > (w + p).abs() {
                sy
            } else {
                w
            }
        });
    vec![Check::relative("worst sigma_yy [Pa]", -worst, p, 0.015)]
}

fn cylinder(s: &Summary) -> Vec<Check> {
    let e_star = 1.0 / (1.0 - 0.09);
    let p = 2.0 * s.final_contact_force[1].abs();
    let b = (4.0 * p / (PI * e_star)).sqrt();
    let xs = abut::mesh::graded(0.0, 2.0, 40, 1.08);
    let last = s
        .contact_nodes
        .iter()
        .map(|c| c.node as usize - 40 * 41)
        .max()
        .unwrap_or(1);
    let facet = xs[last + 1] - xs[last];
    let peak = s
        .contact_nodes
        .iter()
        .map(|c| c.pressure)
        .fold(0.0, f64::max);
    vec![
        Check::absolute(
            "half-width (last node in)",
            xs[last],
            b,
            facet,
            "one facet".into(),
        ),
        Check::relative("peak pressure", peak, 2.0 * p / (PI * b), 0.15),
    ]
}

/// The sphere's force–indentation curve over δ ∈ [δmax/2, δmax] against F = (4/3)·E*·√R·δ^1.5:
/// the least-squares stiffness, the sample farthest from it, and the force at δmax.
fn sphere(s: &Summary) -> Vec<Check> {
    let (e_star, r, d_max) = (1.0 / (1.0 - 0.09), 1.0f64, 0.0025f64);
    let k = 4.0 / 3.0 * e_star * r.sqrt();
    // per radian → whole circumference; indentation = the sphere's descent
    let samples: Vec<(f64, f64)> = s
        .curve
        .iter()
        .map(|c| (-c.body_displacement[0][1], 2.0 * PI * c.force[1].abs()))
        .filter(|(d, _)| *d >= 0.5 * d_max)
        .collect();
    let (num, den) = samples.iter().fold((0.0, 0.0), |(n, d), (x, f)| {
        (n + f * x.powf(1.5), d + x.powf(3.0))
    });
    let worst = samples
        .iter()
        .map(|(x, f)| f / x.powf(1.5))
        .fold(k, |w, v| if (v - k).abs() > (w - k).abs() { v } else { w });
    vec![
        Check::relative("F/delta^1.5, least squares", num / den, k, 0.02),
        Check::relative("F/delta^1.5, worst sample", worst, k, 0.02),
        Check::relative(
            "force at delta_max",
            2.0 * PI * s.final_contact_force[1].abs(),
            k * d_max.powf(1.5),
            0.02,
        ),
    ]
}

fn impact(s: &Summary) -> Vec<Check> {
    let (e_star, m, v) = (1.0 / (1.0 - 0.09), 4.0 * 1.6375, 0.01f64);
    let d = (15.0 * m * v * v / (16.0 * e_star)).powf(0.4);
    vec![
        Check::relative(
            "contact time",
            s.contact_end - s.contact_start,
            2.9432 * d / v,
            0.05,
        ),
        Check::relative(
            "peak force (quarter)",
            s.peak_force,
            4.0 / 3.0 * e_star * d.powf(1.5) / 4.0,
            0.05,
        ),
    ]
}

fn incline(s: &Summary) -> Vec<Check> {
    let (th, mu, g) = (30f64.to_radians(), 0.2, 9.81);
    let a = g * (th.sin() - mu * th.cos());
    let dt = s.end_time / s.increments as f64;
    let tol = mu * s.max_penetration + a * dt;
    vec![Check::absolute(
        "distance at 1 s [m]",
        s.parts[0].displacement[0],
        0.5 * a,
        tol,
        format!("{tol:.2e} m (pre-slip + v dt)"),
    )]
}

fn stability(s: &Summary) -> Vec<Check> {
    let bound = 2.0 * (1.0f64 / 1e4).sqrt();
    let h = 9.81 / 1e4;
    vec![
        Check::relative("reported increment [s]", s.contact_increment, bound, 1e-5),
        Check::absolute(
            "max overclosure at 0.99x [m]",
            s.max_penetration,
            h,
            0.2 * h,
            "bounded: 20 %".into(),
        ),
    ]
}

/// Every case, in VERIFICATION.md's order.
pub const CASES: &[Case] = &[
    Case {
        name: "bars",
        section: "§1",
        scene: include_str!("../../../scenes/bar_impact.toml"),
        checks: bars,
    },
    Case {
        name: "truss",
        section: "§1",
        scene: include_str!("../../../scenes/truss_wall.toml"),
        checks: truss,
    },
    Case {
        name: "patch",
        section: "§2",
        scene: include_str!("../../../scenes/patch_test.toml"),
        checks: patch,
    },
    Case {
        name: "cylinder",
        section: "§3",
        scene: include_str!("../../../scenes/hertz_cylinder.toml"),
        checks: cylinder,
    },
    Case {
        name: "sphere",
        section: "§3",
        scene: include_str!("../../../scenes/hertz_sphere.toml"),
        checks: sphere,
    },
    Case {
        name: "impact",
        section: "§3",
        scene: include_str!("../../../scenes/hertz_impact.toml"),
        checks: impact,
    },
    Case {
        name: "incline",
        section: "§4",
        scene: include_str!("../../../scenes/incline.toml"),
        checks: incline,
    },
    Case {
        name: "stability",
        section: "§5",
        scene: include_str!("../../../scenes/penalty_stability.toml"),
        checks: stability,
    },
];

/// The run settings a case's exact answer depends on, against the scene defaults (Abaqus'):
/// bulk viscosity and the penalty contacts' damping.
fn settings(scene: &Scene) -> String {
    use abut::scene::{DEFAULT_BULK_VISCOSITY, DEFAULT_BULK_VISCOSITY_QUADRATIC};
    let r = &scene.run;
    let bulk = if r.bulk_viscosity == DEFAULT_BULK_VISCOSITY
        && r.bulk_viscosity_quadratic == DEFAULT_BULK_VISCOSITY_QUADRATIC
    {
        "(the default, Abaqus/Explicit's)"
    } else {
        "(the case's own: its exact answer assumes it)"
    };
    let damping: Vec<String> = scene
        .contact
        .iter()
        .filter(|c| c.enforce.as_deref() != Some("kinematic"))
        .map(|c| {
            let d = c.damping.unwrap_or(abut::DEFAULT_CONTACT_DAMPING);
            format!("{d}")
        })
        .collect();
    format!(
        "bulk viscosity linear {} quadratic {} {bulk}; penalty contact damping {}",
        r.bulk_viscosity,
        r.bulk_viscosity_quadratic,
        if damping.is_empty() {
            "— (no penalty pair)".to_string()
        } else {
            format!("{} of critical", damping.join(", "))
        }
    )
}

/// Runs the cases named in `only` (all when empty) on `device`; returns whether all passed.
pub fn verify(device: &Device, only: &[String]) -> abut::Result<bool> {
    println!("abut verify: VERIFICATION.md through scenes/ on {device}");
    let mut all = true;
    for case in CASES {
        if !only.is_empty() && !only.iter().any(|o| o == case.name) {
            continue;
        }
        let scene = Scene::parse(case.scene)?;
        let s = run(&scene, device, None)?;
        println!(
            "\n{} {} [{}]: {} increments, {:.3} ms per increment (first {:.1} ms)",
            case.section,
            scene.title,
            case.name,
            s.increments,
            1e3 * s.seconds_per_increment,
            1e3 * s.first_increment_seconds
        );
        println!("  settings: {}", settings(&scene));
        println!(
            "  {:<30} {:>13} {:>13} {:>10}  {:<24}",
            "quantity", "measured", "exact", "error", "tolerance"
        );
        for c in (case.checks)(&s) {
            let ok = c.ok();
            all &= ok;
            println!(
                "  {:<30} {:>13.6e} {:>13.6e} {:>9.3}%  {:<24} {}",
                c.what,
                c.measured,
                c.exact,
                100.0 * (c.measured - c.exact) / c.exact,
                c.tolerance,
                if ok { "ok" } else { "FAIL" }
            );
        }
    }
    println!(
        "\n{}",
        if all {
            "all within tolerance"
        } else {
            "SOME CASES FAILED"
        }
    );
    Ok(all)
}
