//! A scene's contact pairs written as a deck: each pair's surfaces, its interaction (friction,
//! pressure–overclosure, contact damping), the pair with its options and its controls.

use std::fmt::Write as _;

use crate::error::Result;
use crate::scene::build::Built;
use crate::scene::spec::Scene;

use super::{deck_name, faces, unsupported};

/// The surfaces (into `surfaces`, surface elements into the returned pair's first string) and
/// the interactions and pairs (the second) of `scene`'s contacts; `rigid_sets`: each rigid part's
/// element set.
pub(super) fn pairs(
    scene: &Scene,
    built: &Built,
    rigid_sets: &[Option<String>],
    label: &mut usize,
    surfaces: &mut String,
) -> Result<(String, String)> {
    let x = &built.solver.x;
    let mut pairs = String::new();
    let mut sfm = String::new();
    for (k, c) in scene.contact.iter().enumerate() {
        if c.search_radius.is_some() {
            return unsupported(format!(
                "[[contact]] {}: search_radius (no deck keyword)",
                k + 1
            ));
        }
        let find = |name: &str| {
            scene
                .part
                .iter()
                .position(|p| p.name == name)
                .map(|i| (&built.parts[i], i))
        };
        let Some((sp, si)) = find(&c.slave) else {
            return unsupported(format!("[[contact]] {}: slave {}", k + 1, c.slave));
        };
        let sface = sp.face(&c.slave_face, x)?;
        let slave = faces::surface(
            built,
            sp,
            &c.slave_face,
            &sface,
            surfaces,
            &mut sfm,
            label,
            rigid_sets[si].as_deref(),
        )?;
        if let Some(r) = scene.rigid.iter().find(|r| r.name == c.master) {
            // an analytical master: hard kinematic contact, as abut's rigid pairs are
            writeln!(
                pairs,
                "*SURFACE INTERACTION, NAME=I{n}\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n*CONTACT PAIR, INTERACTION=I{n}, MECHANICAL CONSTRAINT=KINEMATIC\n{slave}, {}",
                deck_name(&r.name),
                n = k + 1
            )
            .ok();
            continue;
        }
        let (Some((mp, mi)), Some(master_face)) = (find(&c.master), c.master_face.as_deref())
        else {
            return unsupported(format!("[[contact]] {}: master {}", k + 1, c.master));
        };
        let mface = mp.face(master_face, x)?;
        let master = faces::surface(
            built,
            mp,
            master_face,
            &mface,
            surfaces,
            &mut sfm,
            label,
            rigid_sets[mi].as_deref(),
        )?;
        let kinematic = c.enforce.as_deref() == Some("kinematic");
        let inter = format!("I{}", k + 1);
        writeln!(pairs, "*SURFACE INTERACTION, NAME={inter}").ok();
        if c.friction > 0.0 {
            writeln!(pairs, "*FRICTION\n{:?}", c.friction).ok();
        }
        let slope = match (c.stiffness, c.stiffness_per_area) {
            (Some(kn), _) => {
                let a = sface.areas.first().copied().unwrap_or(1.0);
                if sface.areas.iter().any(|&x| x != a) || (kn / a) * a != kn {
                    return unsupported(format!(
                        "[[contact]] {}: an absolute stiffness on slaves of different areas",
                        k + 1
                    ));
                }
                Some(kn / a)
            }
            (_, Some(kp)) => Some(kp),
            _ => None,
        };
        match slope {
            Some(s) if !kinematic => writeln!(
                pairs,
                "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{s:?}"
            )
            .ok(),
            _ => writeln!(pairs, "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD").ok(),
        };
        if let Some(d) = c.damping {
            writeln!(
                pairs,
                "*CONTACT DAMPING, DEFINITION=CRITICAL DAMPING FRACTION\n{d:?}"
            )
            .ok();
        }
        let mut options = format!(
            "INTERACTION={inter}, MECHANICAL CONSTRAINT={}, CPSET=P{}",
            if kinematic { "KINEMATIC" } else { "PENALTY" },
            k + 1
        );
        match c.sliding.as_deref() {
            None | Some("finite") => {}
            Some(s) => {
                if (s == "small") != scene.run.nlgeom {
                    return unsupported(format!("[[contact]] {}: sliding = \"{s}\" with nlgeom = {} (a deck's small sliding is small with NLGEOM, infinitesimal without)", k + 1, scene.run.nlgeom));
                }
                options += ", SMALL SLIDING";
            }
        }
        if let Some(w) = c.balanced {
            write!(options, ", WEIGHT={w:?}").ok();
        }
        writeln!(pairs, "*CONTACT PAIR, {options}\n{slave}, {master}").ok();
        let mut controls = Vec::new();
        if let Some(s) = c.penalty_scale.filter(|s| *s != 1.0) {
            controls.push(format!("SCALE PENALTY={s:?}"));
        }
        if let Some(i) = c.search_interval {
            controls.push(format!("GLOBTRKINC={i}"));
        }
        if !controls.is_empty() {
            writeln!(
                pairs,
                "*CONTACT CONTROLS, CPSET=P{}, {}",
                k + 1,
                controls.join(", ")
            )
            .ok();
        }
    }
    Ok((sfm, pairs))
}
