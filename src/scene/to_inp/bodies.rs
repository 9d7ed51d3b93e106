//! A scene's analytical rigid spheres written as a deck: a reference node at the centre, the
//! surface of revolution about it, the body's mass and inertia, how it moves, its loads.

use std::fmt::Write as _;

use crate::scene::spec::{axis_of, RigidSpec};

use super::deck_name;

/// The `*SURFACE, TYPE=REVOLUTION` and `*RIGID BODY` of each sphere in `rigid` (reference nodes
/// appended to `extra_nodes` after the model's `n_nodes`), their model-data boundary
/// conditions into `model_bc` and their step's into `step_bc`.
pub(super) fn spheres(
    rigid: &[RigidSpec],
    n_nodes: usize,
    extra_nodes: &mut Vec<[f64; 3]>,
    label: &mut usize,
    model_bc: &mut String,
    step_bc: &mut String,
) -> String {
    let mut analytical = String::new();
    for r in rigid {
        extra_nodes.push(r.point);
        let node = n_nodes + extra_nodes.len();
        let name = deck_name(&r.name);
        let p = r.point;
        let rad = r.radius;
        writeln!(
            analytical,
            "*SURFACE, TYPE=REVOLUTION, NAME={name}\n{:?}, {:?}, {:?}, {:?}, {:?}, {:?}\nSTART, 0.0, {rad:?}\nCIRCL, {rad:?}, 0.0, 0.0, 0.0\nCIRCL, 0.0, {:?}, 0.0, 0.0",
            p[0], p[1], p[2], p[0], p[1], p[2] + 1.0, -rad
        )
        .ok();
        writeln!(
            analytical,
            "*RIGID BODY, REF NODE={node}, ANALYTICAL SURFACE={name}"
        )
        .ok();
        let i = r.inertia.unwrap_or_else(|| {
            let i = 0.4 * r.mass * r.radius * r.radius;
            [[i, 0.0, 0.0], [0.0, i, 0.0], [0.0, 0.0, i]]
        });
        analytical += &mass_and_inertia(label, node, &name, r.mass, i);
        match r.motion.as_deref() {
            Some("fixed") => {
                writeln!(model_bc, "{node}, ENCASTRE").ok();
            }
            Some("velocity") => {
                writeln!(model_bc, "{node}, 4, 6").ok();
                for (a, va) in r.velocity.iter().enumerate() {
                    writeln!(
                        step_bc,
                        "*BOUNDARY, TYPE=VELOCITY\n{node}, {}, {}, {va:?}",
                        a + 1,
                        a + 1
                    )
                    .ok();
                }
            }
            _ => {
                for f in &r.fix {
                    match axis_of(f) {
                        Some(a) => writeln!(model_bc, "{node}, {}, {}", a + 1, a + 1).ok(),
                        None => writeln!(model_bc, "{node}, 4, 6").ok(),
                    };
                }
                for (a, va) in r.velocity.iter().enumerate().filter(|(_, va)| **va != 0.0) {
                    writeln!(
                        analytical,
                        "*INITIAL CONDITIONS, TYPE=VELOCITY\n{node}, {}, {va:?}",
                        a + 1
                    )
                    .ok();
                }
                let mut loads = Vec::new();
                for (a, l) in r
                    .load
                    .unwrap_or_default()
                    .iter()
                    .enumerate()
                    .filter(|(_, l)| **l != 0.0)
                {
                    loads.push(format!("{node}, {}, {l:?}", a + 1));
                }
                for (a, m) in r
                    .moment
                    .unwrap_or_default()
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| **m != 0.0)
                {
                    loads.push(format!("{node}, {}, {m:?}", a + 4));
                }
                if !loads.is_empty() {
                    writeln!(step_bc, "*CLOAD\n{}", loads.join("\n")).ok();
                }
            }
        }
    }
    analytical
}

/// A point mass and a rotary inertia on reference node `node` (elements `*label + 1` and
/// `*label + 2`, sets `SET-MASS` and `SET-INERTIA`).
pub(super) fn mass_and_inertia(
    label: &mut usize,
    node: usize,
    set: &str,
    mass: f64,
    i: [[f64; 3]; 3],
) -> String {
    *label += 2;
    format!(
        "*ELEMENT, TYPE=MASS, ELSET={set}-MASS\n{}, {node}\n*MASS, ELSET={set}-MASS\n{mass:?}\n\
         *ELEMENT, TYPE=ROTARYI, ELSET={set}-INERTIA\n{}, {node}\n*ROTARY INERTIA, ELSET={set}-INERTIA\n\
         {:?}, {:?}, {:?}, {:?}, {:?}, {:?}\n",
        *label - 1,
        *label,
        i[0][0],
        i[1][1],
        i[2][2],
        i[0][1],
        i[0][2],
        i[1][2]
    )
}
