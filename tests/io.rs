//! Meshes and decks in, results out: Gmsh files written by Gmsh itself (ASCII and binary,
//! `tests/data/gmsh/make_meshes.py`), Abaqus decks exercising every supported keyword and
//! option (`tests/data/inp/`) ending in contact pairs abut runs, bad files named by file and
//! line, and VTK output read back by an independent reader (meshio, installed by `.ci/run`).

mod common;

use common::devices;

use std::path::{Path, PathBuf};

use abut::io::{gmsh, inp, vtk, ElementKind};
use abut::model::Facet;
use abut::{Contact, Device, Enforce, Model, Pair, Penalty, Sliding, Stiffness, Surface};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(p)
}

/// Area-weighted normal (sum of facet normal × area) and total area of facets.
fn normal_and_area(f: &[Facet], x: &[[f64; 3]]) -> ([f64; 3], f64) {
    let p = |n: u32| x[n as usize];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (mut n, mut area) = ([0.0; 3], 0.0);
    for facet in f {
        let v = match *facet {
            Facet::Triangle([a, b, c]) => cross(sub(p(b), p(a)), sub(p(c), p(a))).map(|c| 0.5 * c),
            Facet::Quad([a, b, c, d]) => cross(sub(p(c), p(a)), sub(p(d), p(b))).map(|c| 0.5 * c),
            Facet::Segment([a, b]) => {
                let t = sub(p(b), p(a));
                [t[1], -t[0], 0.0]
            }
        };
        area += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        for a in 0..3 {
            n[a] += v[a];
        }
    }
    (n, area)
}

#[test]
fn gmsh_ascii_and_binary_files_read_the_same_box() {
    let a = gmsh::read(&data("gmsh/box_tets.msh"), 3).unwrap();
    let b = gmsh::read(&data("gmsh/box_tets_binary.msh"), 3).unwrap();
    assert_eq!(a.positions.len(), b.positions.len());
    assert_eq!(a.elements.len(), b.elements.len());
    assert_eq!(a.node_labels, b.node_labels);
    for (p, q) in a.positions.iter().zip(&b.positions) {
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-12);
        }
    }
    assert_eq!(a.elements, b.elements);
    // the volume of the box from its tetrahedra
    let tets: Vec<_> = a
        .elements
        .iter()
        .filter(|e| e.kind == ElementKind::Tet4)
        .collect();
    assert!(tets.len() > 20, "{} tetrahedra", tets.len());
    let v: f64 = tets.iter().map(|e| e.measure(&a.positions)).sum();
    assert!((v - 0.5).abs() < 1e-9, "volume {v}");
    // physical groups by name, faces outward
    for (name, z, nz) in [("top", 0.5, 1.0), ("bottom", 0.0, -1.0)] {
        let f = a.surface(name).unwrap();
        let (n, area) = normal_and_area(&f, &a.positions);
        assert!((area - 1.0).abs() < 1e-9, "{name}: area {area}");
        assert!(
            (n[2] - nz).abs() < 1e-9 && n[0].abs() < 1e-9,
            "{name}: normal {n:?}"
        );
        assert!(a.node_sets[name]
            .iter()
            .all(|&k| (a.positions[k as usize][2] - z).abs() < 1e-12));
    }
    // the boundary of the volume group: area 2·1 + 4·0.5, closed (normals sum to zero)
    let f = a.surface("block").unwrap();
    let (n, area) = normal_and_area(&f, &a.positions);
    assert!(
        (area - 4.0).abs() < 1e-9 && n.iter().all(|c| c.abs() < 1e-9),
        "{area} {n:?}"
    );
}

#[test]
fn gmsh_plate_and_plane_meshes() {
    let plate = gmsh::read(&data("gmsh/plate_quads.msh"), 3).unwrap();
    assert!(plate
        .elements
        .iter()
        .all(|e| e.kind == ElementKind::Quad4 || e.kind == ElementKind::Line2));
    let f = plate.surface("plate").unwrap();
    let (n, area) = normal_and_area(&f, &plate.positions);
    assert!(
        (area - 4.0).abs() < 1e-9 && (n[2].abs() - 4.0).abs() < 1e-9,
        "{area} {n:?}"
    );
    let rect = gmsh::read(&data("gmsh/rect_2d.msh"), 2).unwrap();
    let body: f64 = rect.element_sets["body"]
        .iter()
        .map(|&e| rect.elements[e as usize].measure(&rect.positions))
        .sum();
    assert!((body - 0.5).abs() < 1e-12);
    for (name, ny) in [("top", 1.0), ("bottom", -1.0)] {
        let f = rect.surface(name).unwrap();
        let (n, len) = normal_and_area(&f, &rect.positions);
        assert!(
            (len - 1.0).abs() < 1e-12 && (n[1] - ny).abs() < 1e-12,
            "{name}: {n:?} {len}"
        );
    }
    // read as 3D, the plane mesh's triangles are facets, not plane elements
    let as3d = gmsh::read(&data("gmsh/rect_2d.msh"), 3).unwrap();
    assert!(as3d.elements.iter().any(|e| e.kind == ElementKind::Tri3));
    // a 3D mesh cannot be read as 2D
    let e = gmsh::read(&data("gmsh/box_tets.msh"), 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("box_tets.msh") && e.contains("2D"), "{e}");
}

/// Contact between two Gmsh meshes: the plate's nodes lowered 0.01 into the box's top face,
/// penalty with a fixed stiffness: each node over the box is pushed up by k·0.01, on every
/// device.
#[test]
fn gmsh_meshes_in_contact() {
    let box_ = gmsh::read(&data("gmsh/box_tets.msh"), 3).unwrap();
    let plate = gmsh::read(&data("gmsh/plate_quads.msh"), 3).unwrap();
    let mut m = Model::new_3d();
    m.add_nodes(&box_.positions, &vec![1.0; box_.positions.len()])
        .unwrap();
    let top = m
        .add_surface(Surface::from_facets(box_.surface("top").unwrap()))
        .unwrap();
    let lowered: Vec<[f64; 3]> = plate
        .positions
        .iter()
        .map(|p| [p[0], p[1], p[2] - 0.01])
        .collect();
    let r = m.add_nodes(&lowered, &vec![1.0; lowered.len()]).unwrap();
    let set = m.add_node_set(&r.to_vec()).unwrap();
    let k = 1000.0;
    m.add_pair(
        Pair::new(set, top)
            .search_radius(0.05)
            .enforce(Enforce::Penalty(Penalty {
                stiffness: Stiffness::Absolute(k),
                ..Default::default()
            })),
    )
    .unwrap();
    let inside = lowered
        .iter()
        .filter(|p| p[0] > 1e-9 && p[0] < 1.0 - 1e-9 && p[1] > 1e-9 && p[1] < 1.0 - 1e-9)
        .count();
    assert!(inside >= 9, "{inside} plate nodes over the box");
    let v = vec![[0.0; 3]; m.positions().len()];
    for d in devices() {
        let mut c = Contact::new(&d, &m).unwrap();
        let rep = c.penalty_step(m.positions(), &v, 1e-4).unwrap();
        let pushed: Vec<f64> = (r.start as usize..m.positions().len())
            .map(|i| rep.forces[i][2])
            .filter(|f| *f != 0.0)
            .collect();
        let pushed_at: Vec<[f64; 3]> = (r.start as usize..m.positions().len())
            .filter(|&i| rep.forces[i][2] != 0.0)
            .map(|i| m.positions()[i])
            .collect();
        // exactly the nodes over the box's top are pushed, by k·0.01: those within the search
        // radius beyond its free edges are beside them, not in contact
        assert_eq!(pushed.len(), inside, "{d}: pushed at {pushed_at:?}");
        assert!(
            pushed.iter().all(|f| (f - k * 0.01).abs() < 1e-3),
            "{d}: {pushed:?}"
        );
    }
}

#[test]
fn abaqus_deck_with_hex_and_tet_faces_runs_balanced_penalty_contact() {
    let deck = inp::read(&data("inp/two_blocks_penalty.inp")).unwrap();
    assert_eq!(deck.mesh.positions.len(), 18 + 8);
    assert_eq!(deck.mesh.element_sets["BASEALL"], vec![0, 1, 2, 3]);
    assert_eq!(deck.mesh.node_sets["BASETOPNODES"].len(), 9);
    assert_eq!(deck.mesh.node_sets["ALLNODES"].len(), 26);
    assert!(deck.nlgeom && deck.time_period == Some(1e-3));
    // lumped masses: the base and the block on it, 4 m³ each, of steel
    let total: f64 = deck.masses.iter().sum();
    assert!((total - 7800.0 * 8.0).abs() < 1e-6, "{total}");
    // faces: the base's top (S2 of the hexahedra) and the cube's bottom (S1 of two tetrahedra),
    // both outward
    let x = &deck.mesh.positions;
    let inp::SurfaceDef::Faces(top) = &deck.surfaces["BASETOP"] else {
        panic!()
    };
    let (n, a) = normal_and_area(top, x);
    assert!(
        (a - 4.0).abs() < 1e-12 && (n[2] - 4.0).abs() < 1e-12,
        "{n:?}"
    );
    let inp::SurfaceDef::Faces(bot) = &deck.surfaces["CUBEBOT"] else {
        panic!()
    };
    let (n, a) = normal_and_area(bot, x);
    assert!(
        (a - 4.0).abs() < 1e-12 && (n[2] + 4.0).abs() < 1e-12,
        "{n:?}"
    );
    let built = deck.to_model(1.0).unwrap();
    let pair = built.model.pair(built.pairs[0]).unwrap();
    assert!(
        matches!(pair.friction, abut::Friction::Coulomb { mu, .. } if (mu - 0.3).abs() < 1e-12)
    );
    assert!(matches!(&pair.enforce, Enforce::Penalty(p) if p.stiffness == Stiffness::PerArea(1e6)));
    assert_eq!(pair.balanced.map(|b| b.1), Some(0.5));
    let s = pair.schedule.unwrap();
    assert!(s.interval == 10 && s.wide_local);
    // one increment: the block is 0.01 into the base over the whole 2 × 2 interface; each
    // pass pushes with half of k·area·overclosure over its slave nodes' areas (4 in all on
    // either side), so the block gets 2 × ½·1e6·4·0.01 = 4e4 upwards
    let v = vec![[0.0; 3]; x.len()];
    for d in devices() {
        let mut c = Contact::new(&d, &built.model).unwrap();
        let rep = c.penalty_step(x, &v, 1e-5).unwrap();
        let cube: f64 = (18..26).map(|i| rep.forces[i][2]).sum();
        let all: f64 = rep.forces.iter().map(|f| f[2]).sum();
        assert!((cube - 4e4).abs() < 4.0, "{d}: force on the block {cube}");
        assert!(all.abs() < 1e-2, "{d}: momentum {all}");
    }
}

#[test]
fn abaqus_deck_small_sliding_laws_and_node_surfaces() {
    let deck = inp::read(&data("inp/small_sliding_kinematic.inp")).unwrap();
    assert!(!deck.nlgeom);
    let built = deck.to_model(1e12).unwrap();
    let pairs: Vec<_> = built
        .pairs
        .iter()
        .map(|&p| built.model.pair(p).unwrap().clone())
        .collect();
    // NLGEOM=NO: small sliding is infinitesimal
    assert_eq!(pairs[0].sliding, Sliding::Infinitesimal);
    assert!(matches!(pairs[0].enforce, Enforce::Kinematic(ref k) if k.softened.is_none()));
    assert_eq!(pairs[1].sliding, Sliding::Finite);
    match &pairs[1].enforce {
        Enforce::Penalty(p) => {
            assert_eq!(p.stiffness, Stiffness::Auto { scale: 2.0 });
            assert_eq!(
                p.law,
                abut::PressureOverclosure::Exponential {
                    clearance: 0.05,
                    pressure: 1000.0
                }
            );
        }
        e => panic!("{e:?}"),
    }
    match &pairs[2].enforce {
        Enforce::Penalty(p) => assert_eq!(
            p.law,
            abut::PressureOverclosure::Tabular(vec![(0.0, 0.0), (0.01, 1000.0), (0.02, 5000.0)])
        ),
        e => panic!("{e:?}"),
    }
    assert_eq!(
        built.model.node_set_areas(pairs[0].slave).unwrap(),
        Some(&[0.25, 0.25][..])
    );
    // the kinematic pair runs: node 5 (0.02 below the plate) is put back on it
    let mut only = Model::new_3d();
    only.add_nodes(&deck.mesh.positions, &[1e12, 1e12, 1e12, 1e12, 1.0, 1.0])
        .unwrap();
    let inp::SurfaceDef::Faces(f) = &deck.surfaces["PLATETOP"] else {
        panic!()
    };
    let s = only.add_surface(Surface::from_facets(f.clone())).unwrap();
    let set = only.add_node_set(&[4, 5]).unwrap();
    only.add_pair(
        Pair::new(set, s)
            .search_radius(0.1)
            .enforce(pairs[0].enforce.clone())
            .sliding(Sliding::Infinitesimal),
    )
    .unwrap();
    for d in devices() {
        let mut c = Contact::new(&d, &only).unwrap();
        let mut x = deck.mesh.positions.clone();
        let mut v = vec![[0.0; 3]; x.len()];
        c.kinematic_step(&mut x, &mut v, &mut [], 1e-3).unwrap();
        assert!(
            x[4][2].abs() < 1e-7 && (x[5][2] - 0.05).abs() < 1e-12,
            "{d}: {:?} {:?}",
            x[4],
            x[5]
        );
    }
}

#[test]
fn abaqus_plane_strain_faces() {
    let deck = inp::read(&data("inp/plane_strain.inp")).unwrap();
    let x = &deck.mesh.positions;
    let inp::SurfaceDef::Faces(top) = &deck.surfaces["TOP"] else {
        panic!()
    };
    let (n, len) = normal_and_area(top, x);
    assert!(
        (len - 2.0).abs() < 1e-12 && (n[1] - 2.0).abs() < 1e-12,
        "{n:?}"
    );
    let inp::SurfaceDef::Faces(outline) = &deck.surfaces["OUTLINE"] else {
        panic!()
    };
    let (n, len) = normal_and_area(outline, x);
    assert_eq!(outline.len(), 6);
    assert!(
        (len - 6.0).abs() < 1e-12 && n.iter().all(|c| c.abs() < 1e-12),
        "{n:?} {len}"
    );
    assert!(deck.to_model(1.0).unwrap().model.dim() == 2);
}

#[test]
fn bad_decks_name_the_file_line_and_what_was_expected() {
    let cases: &[(&str, &str, usize)] = &[
        ("*NODE\n1, 0, 0, 0\n*BOUNDARY, TYPE=ACCELERATION\n1, 1, 3\n", "TYPE=ACCELERATION is not supported", 3),
        ("*NODE\n1, 0, 0, 0\n*BOUNDARY\n1, 7\n", "degree of freedom 7", 4),
        ("*NODE\n1, 0, 0, 0\n*TIE, NAME=T\nA, B\n", "*TIE (a constraint between nodes) is not modelled", 3),
        ("*NODE\n1, 0, 0, 0\n*CONTACT PAIR, INTERACTION=I, TYPE=MORTAR\nA, B\n", "TYPE=MORTAR", 3),
        ("*NODE, NSET=A, SYSTEM=R\n1, 0, 0, 0\n", "option SYSTEM", 1),
        ("*NODE\n1, 0, zero, 0\n", "expected a number", 2),
        ("*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n", "node 2 is not defined", 4),
        ("*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT, TYPE=C3D10\n1,1,2,3,4\n", "TYPE=C3D10", 6),
        ("*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n*SURFACE, NAME=S\n1, S7\n", "S7", 9),
        ("*NODE\n1,0,0,0\n*NSET, NSET=A, GENERATE\n5, 1\n", "GENERATE", 4),
        ("*SURFACE INTERACTION, NAME=I\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=SCALE FACTOR\n", "SCALE FACTOR", 2),
        ("*SURFACE INTERACTION, NAME=I\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL\n0.1\n", "wrong number of values", 3),
        ("*CONTACT CONTROLS, HOURGLASS=NO\n", "HOURGLASS", 1),
        ("*STEP, NLGEOM=MAYBE\n", "NLGEOM=MAYBE", 1),
        ("*SURFACE INTERACTION, NAME=I\n*CONTACT PAIR, INTERACTION=I\nA, B\n", "surface A is not defined", 3),
        ("*NODE\n1, 0, 0, 0\n*INCLUDE, INPUT=missing.inc\n", "missing.inc", 0),
        ("1, 0, 0, 0\n", "outside any keyword", 1),
    ];
    for (text, what, line) in cases {
        let e = inp::parse(text, Path::new("deck.inp"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(what), "{what}: {e}");
        if *line > 0 {
            assert!(
                e.starts_with(&format!("deck.inp:{line}:")),
                "{what}: line {line}: {e}"
            );
        }
    }
    // a set that names itself does not grow (24 times: 2^24 members once), members given
    // twice are kept once, and GENERATE up to the largest label stops instead of wrapping
    let mut deck = String::from("*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n*NSET, NSET=A\n1, 2, 2, 1\n");
    for _ in 0..24 {
        deck.push_str("*NSET, NSET=A\nA, A, 3\n");
    }
    let d = inp::parse(&deck, Path::new("self.inp")).unwrap();
    let a = &d.mesh.node_sets["A"];
    assert_eq!(a.len(), 3, "{a:?}");
    let e = inp::parse(
        "*NODE\n1,0,0,0\n*NSET, NSET=B, GENERATE\n18446744073709551614, 18446744073709551615\n",
        Path::new("wrap.inp"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("node 18446744073709551614"), "{e}");
    let d = inp::parse(
        "*NODE\n1,0,0,0\n2,0,0,1\n*NSET, NSET=C, GENERATE\n1, 2, 18446744073709551615\n",
        Path::new("step.inp"),
    )
    .unwrap();
    assert_eq!(
        d.mesh.node_sets["C"].len(),
        1,
        "an increment past the end stops"
    );
    let e = gmsh::parse(
        b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n",
        "bad.msh",
        3,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("bad.msh") && e.contains("MSH"), "{e}");
    let e = gmsh::parse(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "old.msh", 3)
        .unwrap_err()
        .to_string();
    assert!(e.contains("old.msh"), "{e}");
}

/// Writes a series of contact frames from a deck's contact and reads it back with meshio
/// (an independent reader), comparing the arrays with what abut computed.
#[test]
fn vtk_series_is_read_back_by_an_independent_reader() {
    let deck = inp::read(&data("inp/two_blocks_penalty.inp")).unwrap();
    let built = deck.to_model(1.0).unwrap();
    let x = deck.mesh.positions.clone();
    let v = vec![[0.0; 3]; x.len()];
    let mut c = Contact::new(&Device::cpu(), &built.model).unwrap();
    c.request_outputs(true);
    let dir = std::env::temp_dir().join(format!("abut-vtk-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut series = vtk::Series::new(&dir, "contact").unwrap();
    let mut frames = Vec::new();
    for k in 0..3 {
        // the cube sinks a little further each frame
        let xk: Vec<[f64; 3]> = x
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if i >= 18 {
                    [p[0], p[1], p[2] - 0.002 * k as f64]
                } else {
                    *p
                }
            })
            .collect();
        c.penalty_step(&xk, &v, 1e-5).unwrap();
        let f = vtk::Frame::from_contact(&built.model, &c, &xk).unwrap();
        series.add(1e-5 * k as f64, &f).unwrap();
        frames.push(f);
    }
    // the facets take the reaction of their slaves' forces (both passes of the balanced pair)
    for f in &frames {
        let facet_sum: f64 = f.facet_force.iter().map(|v| v[2]).sum();
        let slave_sum: f64 = f.force.iter().map(|v| v[2]).sum();
        let scale: f64 = f.force.iter().map(|v| v[2].abs()).sum();
        assert!(
            scale > 1e4 && (facet_sum + slave_sum).abs() < 1e-6 * scale,
            "{facet_sum} {slave_sum}"
        );
    }
    let require = std::env::var("ABUT_REQUIRE_VTK_READER").is_ok_and(|v| v == "1");
    let out = std::process::Command::new("python3")
        .arg(data("vtk/read_back.py"))
        .arg(&dir)
        .arg("contact")
        .output();
    let out = match out {
        Ok(o) if o.status.success() => o,
        other => {
            let why = match other {
                Ok(o) => String::from_utf8_lossy(&o.stderr).to_string(),
                Err(e) => e.to_string(),
            };
            assert!(
                !require,
                "ABUT_REQUIRE_VTK_READER=1 but python3 + meshio failed: {why}"
            );
            eprintln!("\n*** SKIPPED: the VTK read-back needs python3 with meshio ({why}) ***\n");
            return;
        }
    };
    let got: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let times: Vec<f64> = got["times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(times, vec![0.0, 1e-5, 2e-5]);
    for (k, f) in frames.iter().enumerate() {
        let g = &got["frames"][k];
        assert_eq!(g["points"].as_u64().unwrap() as usize, f.positions.len());
        let facets = f.facets.len() as u64;
        let cells = &g["cells"];
        let n_quads = cells["quad"].as_u64().unwrap_or(0) + cells["triangle"].as_u64().unwrap_or(0);
        assert_eq!(n_quads, facets, "{cells}");
        assert_eq!(cells["vertex"].as_u64().unwrap() as usize, f.slaves.len());
        assert_eq!(
            g["cstatus_slaves"].as_u64().unwrap() as usize,
            f.slaves.len()
        );
        let in_contact = f.cstatus.iter().filter(|&&s| s > 0).count();
        assert_eq!(
            g["cstatus_in_contact"].as_u64().unwrap() as usize,
            in_contact
        );
        assert!(in_contact >= 5);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + b.abs());
        assert!(close(
            g["cpress_sum"].as_f64().unwrap(),
            f.cpress.iter().sum()
        ));
        assert!(close(
            g["copen_min"].as_f64().unwrap(),
            f.copen.iter().cloned().fold(f64::INFINITY, f64::min)
        ));
        for a in 0..3 {
            assert!(close(
                g["cforce_sum"][a].as_f64().unwrap(),
                f.force.iter().map(|v| v[a]).sum()
            ));
            assert!(close(
                g["facet_force_sum"][a].as_f64().unwrap(),
                f.facet_force.iter().map(|v| v[a]).sum()
            ));
        }
        assert!(close(
            g["z_sum"].as_f64().unwrap(),
            f.positions.iter().map(|p| p[2]).sum()
        ));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
