//! What each element of a deck is: deformable (its section), rigid (its body) or a surface
//! element; what abut does not model among them refused by the `*ELEMENT` line.

use std::collections::BTreeMap;

use crate::error::Result;
use crate::io::inp::{At, Deck};
use crate::io::ElementKind;

use super::{refuse, Role};

/// Each element's role, or an error naming the first element abut cannot run.
pub(super) fn roles(
    deck: &Deck,
    material_index: &BTreeMap<String, usize>,
    whole: &At,
    notes: &mut Vec<String>,
) -> Result<Vec<Option<Role>>> {
    let a = &deck.analysis;
    let mesh = &deck.mesh;
    let mut role: Vec<Option<Role>> = vec![None; mesh.elements.len()];
    for s in &a.sections {
        let Some(els) = mesh.element_sets.get(&s.elset) else {
            return refuse(
                &s.at,
                format!("*SOLID SECTION: element set {} is not defined", s.elset),
            );
        };
        for &e in els {
            if role[e as usize].is_some() {
                return refuse(
                    &s.at,
                    format!(
                        "element {} is in two sections",
                        mesh.elements[e as usize].label
                    ),
                );
            }
            role[e as usize] = Some(Role::Deformable(material_index[&s.material], s.thickness));
        }
    }
    for &e in &a.surface_elements {
        if role[e as usize].is_some() {
            return refuse(
                whole,
                format!(
                    "element {} has a *SURFACE SECTION and a *SOLID SECTION",
                    mesh.elements[e as usize].label
                ),
            );
        }
        role[e as usize] = Some(Role::Surface);
    }
    for (k, r) in a.rigid_bodies.iter().enumerate() {
        for &e in &r.elements {
            role[e as usize] = Some(Role::Rigid(k));
        }
    }
    let at_element = |e: usize| -> (String, At) {
        match a.element_block(e as u32) {
            Some((t, at)) => (t.to_string(), at.clone()),
            None => (String::new(), whole.clone()),
        }
    };
    for (k, (e, r)) in mesh.elements.iter().zip(&role).enumerate() {
        let (ty, at) = at_element(k);
        match r {
            None => {
                return refuse(
                    &at,
                    format!("element {} (TYPE={ty}) has no *SOLID SECTION and is in no *RIGID BODY", e.label),
                )
            }
            Some(Role::Deformable(..)) if matches!(e.kind, ElementKind::Tri3 | ElementKind::Quad4) => {
                return refuse(
                    &at,
                    format!("element {} (TYPE={ty}): shells and membranes are not modelled by abut", e.label),
                )
            }
            Some(Role::Deformable(..))
                if e.kind == ElementKind::Hex8
                    && !matches!(ty.to_ascii_uppercase().as_str(), "C3D8" | "C3D8R") =>
            {
                return refuse(
                    &at,
                    format!("element {} (TYPE={ty}): incompatible modes are not modelled by abut (its deformable hexahedra are C3D8, selectively reduced, and C3D8R, one point with hourglass stiffness)", e.label),
                )
            }
            _ => {}
        }
    }
    if let Some(&e) = a
        .plane_stress
        .iter()
        .find(|&&e| matches!(role[e as usize], Some(Role::Deformable(..))))
    {
        return refuse(
            &at_element(e as usize).1,
            format!("element {}: plane stress (CPS3, CPS4(R)) is not modelled by abut (its plane elements are plane strain, CPE, or axisymmetric, CAX)", mesh.elements[e as usize].label),
        );
    }
    if mesh
        .elements
        .iter()
        .zip(&role)
        .any(|(e, r)| e.kind == ElementKind::Quad4In2d && matches!(r, Some(Role::Deformable(..))))
    {
        notes.push(
            "plane quadrilaterals (CPE4(R), CAX4(R)) run as two linear triangles each".into(),
        );
    }
    Ok(role)
}
