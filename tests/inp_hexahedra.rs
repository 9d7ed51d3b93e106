//! Issue 37: decks of deformable hexahedra (C3D8 selectively reduced, C3D8R one point with
//! hourglass stiffness) run as they are, and their node, element and contact output requests
//! are written with Abaqus' names. Two blocks pressed together by loads on the upper one's top, as a `*STATIC`
//! deck, meshed with distorted hexahedra: the static answer is exact for the elements (a
//! uniform stress passes the patch test) and for the linear pressure–overclosure law, so the
//! displacements and reactions are checked against it.

mod common;

use abut::scene::run;
use abut::Device;
use common::scene_toml::{boundary, deck, fixed, part_of, SceneToml};

/// Young's moduli of the blocks and the contact's pressure–overclosure slope (per area).
const E_LOWER: f64 = 2000.0;
const E_UPPER: f64 = 500.0;
const K_CONTACT: f64 = 2.0e4;
/// The total load on the upper block's top (downwards).
const LOAD: f64 = 4.0;

/// Two unit-square blocks, heights 1 (lower, z ∈ [0, 1]) and 0.5 (upper, z ∈ [1, 1.5]), each
/// `n × n × n` hexahedra of `ty_lower` / `ty_upper`, interior nodes moved off the grid so the
/// elements around them are not boxes; the lower base held in z (and one corner in x and y, a neighbour in y),
/// the upper top loaded by `LOAD` as the nodal forces of a uniform pressure, with the upper
/// block's bottom as the slave surface (by element faces) on the lower block's top. ν = 0: the
/// stress is uniaxial and the static answer exact.
fn blocks_deck(n: usize, ty_lower: &str, ty_upper: &str, extra: &str) -> String {
    let mut s = String::from("*HEADING\nhexahedral blocks pressed together\n*NODE, NSET=ALL\n");
    let per_side = n + 1;
    let per_block = per_side * per_side * per_side;
    let id = |block: usize, i: usize, j: usize, k: usize| {
        block * per_block + (k * per_side + j) * per_side + i + 1
    };
    for (block, (z0, h)) in [(0.0, 1.0), (1.0, 0.5)].into_iter().enumerate() {
        for k in 0..per_side {
            for j in 0..per_side {
                for i in 0..per_side {
                    let (mut x, mut y, mut z) = (
                        i as f64 / n as f64,
                        j as f64 / n as f64,
                        z0 + h * k as f64 / n as f64,
                    );
                    let inside = |c: usize| c > 0 && c < n;
                    if inside(i) && inside(j) && inside(k) {
                        // interior nodes moved off the grid (the blocks' faces stay regular,
                        // so the loads and the contact interface are uniform)
                        x += 0.07 / n as f64 * (1.0 + (k as f64 * 1.3).sin());
                        y -= 0.05 / n as f64;
                        z += 0.06 * h / n as f64 * (x - 0.5);
                    }
                    s += &format!("{}, {x:?}, {y:?}, {z:?}\n", id(block, i, j, k));
                }
            }
        }
    }
    let mut label = 0;
    for (block, name, ty) in [(0, "LOWER", ty_lower), (1, "UPPER", ty_upper)] {
        s += &format!("*ELEMENT, TYPE={ty}, ELSET={name}\n");
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    label += 1;
                    let c = |di: usize, dj: usize, dk: usize| id(block, i + di, j + dj, k + dk);
                    s += &format!(
                        "{label}, {}, {}, {}, {}, {}, {}, {}, {}\n",
                        c(0, 0, 0),
                        c(1, 0, 0),
                        c(1, 1, 0),
                        c(0, 1, 0),
                        c(0, 0, 1),
                        c(1, 0, 1),
                        c(1, 1, 1),
                        c(0, 1, 1)
                    );
                }
            }
        }
    }
    // the lower block's top faces (S2: nodes 5-8) and the upper block's bottom ones (S1)
    s += "*ELSET, ELSET=LOWER-TOP\n";
    for e in (n * n * (n - 1) + 1)..=(n * n * n) {
        s += &format!("{e}\n");
    }
    s += "*ELSET, ELSET=UPPER-BOTTOM\n";
    for e in 1..=(n * n) {
        s += &format!("{}\n", n * n * n + e);
    }
    s += "*SURFACE, NAME=MASTER\nLOWER-TOP, S2\n*SURFACE, NAME=SLAVE\nUPPER-BOTTOM, S1\n";
    s += "*NSET, NSET=BASE\n";
    for j in 0..per_side {
        for i in 0..per_side {
            s += &format!("{}\n", id(0, i, j, 0));
        }
    }
    s += "*NSET, NSET=TOP\n";
    for j in 0..per_side {
        for i in 0..per_side {
            s += &format!("{}\n", id(1, i, j, n));
        }
    }
    s += &format!(
        "*MATERIAL, NAME=STIFF\n*ELASTIC\n{E_LOWER:?}, 0.0\n*MATERIAL, NAME=SOFT\n*ELASTIC\n{E_UPPER:?}, 0.0\n"
    );
    s +=
        "*SOLID SECTION, ELSET=LOWER, MATERIAL=STIFF\n*SOLID SECTION, ELSET=UPPER, MATERIAL=SOFT\n";
    s += &format!(
        "*SURFACE INTERACTION, NAME=SOFTENED\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{K_CONTACT:?}\n"
    );
    s += "*CONTACT PAIR, INTERACTION=SOFTENED, MECHANICAL CONSTRAINT=PENALTY\nSLAVE, MASTER\n";
    s += &format!(
        "*BOUNDARY\nBASE, 3, 3\n{}, 1, 2\n{}, 2, 2\n",
        id(0, 0, 0, 0),
        id(0, n, 0, 0)
    );
    // the upper block slides on nothing: its top held in x and y keeps it from drifting
    s += "*BOUNDARY\nTOP, 1, 2\n";
    s += "*STEP\n*STATIC\n1.0, 1.0\n*CLOAD\n";
    let cell = 1.0 / (n * n) as f64;
    for j in 0..per_side {
        for i in 0..per_side {
            let share = |c: usize| if c == 0 || c == n { 0.5 } else { 1.0 };
            s += &format!(
                "{}, 3, {:?}\n",
                id(1, i, j, n),
                -LOAD * cell * share(i) * share(j)
            );
        }
    }
    s += "*NODE PRINT, NSET=TOP\nU, RF\n*NODE PRINT, NSET=BASE\nRF, NT\n";
    s += extra;
    s += "*END STEP\n";
    s
}

/// The static answer: the upper top goes down by the two blocks' shortening and the contact's
/// overclosure under the uniform pressure `LOAD` (unit area).
fn static_top_displacement() -> f64 {
    -(LOAD * 1.0 / E_LOWER + LOAD * 0.5 / E_UPPER + LOAD / K_CONTACT)
}

fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn hexahedral_blocks_pressed_together_reach_the_static_answer_and_print_it() {
    for (lower, upper) in [("C3D8", "C3D8"), ("C3D8R", "C3D8R"), ("C3D8", "C3D8R")] {
        let scene = deck(
            "hex-blocks.inp",
            &blocks_deck(
                3,
                lower,
                upper,
                "*EL PRINT, ELSET=UPPER\nS, ELSE, E\n*CONTACT PRINT\nCSTRESS, CDISP, CELS\n",
            ),
        )
        .unwrap();
        let dir = std::env::temp_dir().join(format!(
            "abut-inp-hex-out-{lower}-{upper}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        let summary = run(&scene, &Device::cpu(), Some(&dir)).unwrap();
        let kinds: Vec<&String> = summary
            .built
            .iter()
            .filter(|b| b.contains("hexahedron"))
            .collect();
        assert!(!kinds.is_empty(), "{:?}", summary.built);
        // every node of the top goes down by the static answer
        let (header, rows) = read_csv(&dir.join("node-print-TOP.csv"));
        assert_eq!(
            header,
            ["time", "node", "U1", "U2", "U3", "RF1", "RF2", "RF3"],
            "Abaqus' names, in the request's order"
        );
        assert_eq!(rows.len(), 16);
        let exact = static_top_displacement();
        for r in &rows {
            assert!(
                (r[4] / exact - 1.0).abs() < 1e-4,
                "{lower}/{upper}: node {} U3 {} against {exact}",
                r[1],
                r[4]
            );
        }
        // the base carries the load: its reactions sum to it; NT (a temperature) is not written
        let (header, rows) = read_csv(&dir.join("node-print-BASE.csv"));
        assert_eq!(header, ["time", "node", "RF1", "RF2", "RF3"]);
        let reaction: f64 = rows.iter().map(|r| r[4]).sum();
        assert!(
            (reaction / LOAD - 1.0).abs() < 1e-3,
            "{lower}/{upper}: base reaction {reaction}"
        );
        assert!(
            summary
                .deck_notes
                .iter()
                .any(|n| n.contains("NT not written")),
            "{:?}",
            summary.deck_notes
        );
        // the upper block's elements: the uniform stress −LOAD (unit area) along z, and their
        // strain energies adding up to σ²/(2E)·V; E (strain) is not written, and says so
        let (header, rows) = read_csv(&dir.join("el-print-UPPER.csv"));
        assert_eq!(
            header,
            ["time", "element", "S11", "S22", "S33", "S12", "S13", "S23", "ELSE"]
        );
        assert_eq!(rows.len(), 27);
        for r in &rows {
            approx::assert_relative_eq!(r[4], -LOAD, max_relative = 1e-4);
            for k in [2, 3, 5, 6, 7] {
                assert!(r[k].abs() < 1e-4 * LOAD, "{lower}/{upper}: {r:?}");
            }
        }
        let energy: f64 = rows.iter().map(|r| r[8]).sum();
        let exact_energy = LOAD * LOAD / (2.0 * E_UPPER) * 0.5;
        approx::assert_relative_eq!(energy, exact_energy, max_relative = 1e-3);
        assert!(
            summary
                .deck_notes
                .iter()
                .any(|n| n.contains("EL PRINT: E not written")),
            "{:?}",
            summary.deck_notes
        );
        // every slave node: the uniform pressure, and the overclosure p/k it takes (COPEN
        // negative, to f32's resolution of the gap)
        let (header, rows) = read_csv(&dir.join("contact-print-ALL.csv"));
        assert_eq!(
            header,
            ["time", "node", "CPRESS", "CSHEAR1", "CSHEAR2", "COPEN"]
        );
        assert_eq!(rows.len(), 16);
        for r in &rows {
            approx::assert_relative_eq!(r[2], LOAD, max_relative = 1e-4);
            approx::assert_relative_eq!(r[5], -LOAD / K_CONTACT, max_relative = 1e-3);
        }
        assert!(
            summary
                .deck_notes
                .iter()
                .any(|n| n.contains("CONTACT PRINT: CELS not written")),
            "{:?}",
            summary.deck_notes
        );
        let qs = summary.quasi_static.clone().unwrap();
        assert!(qs.kinetic_to_internal_at_end < 1e-3, "{qs:?}");
        eprintln!(
            "{lower}/{upper}: {} increments, top U3 {:.6e} (static {exact:.6e}), base reaction {reaction:.6}, KE/IE max {:.2e}",
            summary.increments, rows[0][4], qs.kinetic_to_internal_max
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn incompatible_mode_hexahedra_are_refused_by_name_and_line() {
    let text = blocks_deck(2, "C3D8", "C3D8I", "");
    let line = text
        .lines()
        .position(|l| l.starts_with("*ELEMENT, TYPE=C3D8I"))
        .unwrap()
        + 1;
    let e = deck("incompatible.inp", &text).unwrap_err().to_string();
    assert!(e.contains("incompatible modes"), "{e}");
    assert!(e.contains(&format!("incompatible.inp:{line}:")), "{e}");
}

#[test]
fn a_node_print_of_an_undefined_set_is_said_not_silently_dropped() {
    let text = blocks_deck(2, "C3D8", "C3D8", "*NODE PRINT, NSET=NOWHERE\nU\n");
    let scene = deck("nowhere.inp", &text).unwrap();
    assert!(
        scene
            .deck_notes
            .iter()
            .any(|n| n.contains("NOWHERE is not defined")),
        "{:?}",
        scene.deck_notes
    );
    assert_eq!(scene.node_outputs.len(), 2);
}

/// A scene file's mesh part of hexahedra (an Abaqus mesh file, one C3D8 block of 2 × 2 × 2
/// with its second layer numbered inside out) runs them as selectively reduced C3D8: pressed by
/// a ramped displacement of its top and damped to rest, its stress is the static one.
#[test]
fn a_mesh_files_hexahedra_run_as_c3d8() {
    let text = blocks_deck(2, "C3D8", "C3D8", "");
    // the lower block's nodes and elements only, its second layer's nodes 1–4 and 5–8 swapped
    let mut mesh = String::from("*NODE\n");
    let lines: Vec<&str> = text.lines().collect();
    let node_start = lines.iter().position(|l| l.starts_with("*NODE")).unwrap() + 1;
    for l in lines[node_start..node_start + 27].iter() {
        mesh += l;
        mesh.push('\n');
    }
    mesh += "*ELEMENT, TYPE=C3D8, ELSET=BLOCK\n";
    let el_start = lines
        .iter()
        .position(|l| l.starts_with("*ELEMENT"))
        .unwrap()
        + 1;
    for (k, l) in lines[el_start..el_start + 8].iter().enumerate() {
        let f: Vec<&str> = l.split(", ").collect();
        let order: Vec<usize> = if k >= 4 {
            vec![0, 5, 6, 7, 8, 1, 2, 3, 4]
        } else {
            (0..9).collect()
        };
        mesh += &order.iter().map(|&i| f[i]).collect::<Vec<_>>().join(", ");
        mesh.push('\n');
    }
    mesh += "*NSET, NSET=BASE\n1, 2, 3, 4, 5, 6, 7, 8, 9\n*NSET, NSET=TOP\n19, 20, 21, 22, 23, 24, 25, 26, 27\n";
    let dir = std::env::temp_dir().join(format!("abut-hex-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("block.inp"), &mesh).unwrap();
    let (young, delta) = (1000.0, 0.01);
    let mut scene = SceneToml::new("a mesh file of hexahedra", 2.0)
        .run("damping", 20.0)
        .material("soft", young, 0.0, 1.0)
        .part(
            part_of("block", "mesh")
                .with("file", "block.inp")
                .with("material", "soft"),
        )
        .boundary(fixed("block", "BASE", ["z"]))
        .boundary(
            boundary("block", "TOP")
                .with("displacement", [0.0, 0.0, -delta])
                .with("ramp", 0.5),
        )
        .scene();
    scene.base_dir = Some(dir.clone());
    let s = run(&scene, &Device::cpu(), None).unwrap();
    assert!(
        s.built.iter().any(|b| b == "8 hexahedron (C3D8) elements"),
        "{:?}",
        s.built
    );
    // St Venant–Kirchhoff (the scene's large-strain default) in uniaxial stretch λ: the Cauchy
    // stress λ·E·(λ² − 1)/2, the same in every element
    let lam = 1.0 - delta;
    let exact = lam * young * 0.5 * (lam * lam - 1.0);
    for sigma in [s.parts[0].stress_min[2], s.parts[0].stress_max[2]] {
        approx::assert_relative_eq!(sigma, exact, max_relative = 1e-3);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
