//! A rank's model checked before anything is exchanged: ids, lengths, facets and radii, each
//! error naming the item.

use super::*;

pub(super) fn validate(model: &RankModel) -> Result<Validated> {
    let n = model.ids.len();
    if model.positions.len() != n || model.masses.len() != n {
        return Err(Error::LengthMismatch {
            what: "positions and masses (one per owned node)",
            expected: n,
            got: model.positions.len().min(model.masses.len()),
        });
    }
    let mut index = HashMap::with_capacity(n);
    for (i, &g) in model.ids.iter().enumerate() {
        if g == NO_GLOBAL_NODE || index.insert(g, i).is_some() {
            return Err(bad(
                "global node id",
                g.to_string(),
                "unique on the rank, not u64::MAX",
            ));
        }
        if !(model.masses[i] > 0.0 && model.masses[i].is_finite()) {
            return Err(Error::BadMass {
                node: i,
                mass: model.masses[i],
            });
        }
        for (axis, &value) in model.positions[i].iter().enumerate() {
            if !value.is_finite() {
                return Err(Error::NonFiniteCoordinate {
                    node: i,
                    axis,
                    value,
                });
            }
        }
    }
    let mut slaves_of = Vec::with_capacity(model.pairs.len());
    for (k, p) in model.pairs.iter().enumerate() {
        if !(p.search_radius > 0.0 && p.search_radius.is_finite()) {
            return Err(bad(
                "search_radius",
                p.search_radius.to_string(),
                "finite and positive",
            ));
        }
        if let Some(r) = p.anchor_reach.filter(|r| !(*r > 0.0 && r.is_finite())) {
            return Err(bad(
                "anchor_reach",
                format!("{r} (pair {k})"),
                "finite and positive, or none",
            ));
        }
        if let Some(keys) = &p.slave_keys {
            if keys.len() != p.slaves.len() {
                return Err(Error::LengthMismatch {
                    what: "slave keys (one per slave of the pair)",
                    expected: p.slaves.len(),
                    got: keys.len(),
                });
            }
        }
        if p.search_interval == 0 {
            return Err(bad("search_interval", "0".into(), "at least 1"));
        }
        if let Some(a) = &p.slave_areas {
            if a.len() != p.slaves.len() {
                return Err(Error::LengthMismatch {
                    what: "slave areas (one per slave of the pair)",
                    expected: p.slaves.len(),
                    got: a.len(),
                });
            }
            if let Some(j) = a.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(bad(
                    "slave area",
                    format!("{} (slave {} of pair {k})", a[j], p.slaves[j]),
                    "finite and positive",
                ));
            }
        }
        let facets = p
            .facets
            .iter()
            .chain(p.balanced.iter().flat_map(|b| &b.slave_facets));
        for f in facets {
            let m = super::facet_node_count(f, NO_GLOBAL_NODE);
            let (fits, expected) = if model.two_d {
                (
                    m == 2,
                    "a segment in a 2D model: [a, b, NO_GLOBAL_NODE, NO_GLOBAL_NODE]",
                )
            } else {
                (m > 2, "a triangle or a quad in a 3D model")
            };
            if !fits || f[..m].contains(&NO_GLOBAL_NODE) {
                return Err(bad("master facet", format!("{f:?} of pair {k}"), expected));
            }
        }
        if let Some(b) = &p.balanced {
            if !(b.weight.is_finite() && (0.0..=1.0).contains(&b.weight)) {
                return Err(bad(
                    "balanced weight",
                    format!("{} (pair {k})", b.weight),
                    "must lie in [0, 1]",
                ));
            }
        }
        let mut slaves = Vec::with_capacity(p.slaves.len());
        for &g in &p.slaves {
            slaves.push(*index.get(&g).ok_or_else(|| {
                bad(
                    "slave node",
                    format!("global id {g} of pair {k}"),
                    "a node this rank owns",
                )
            })?);
        }
        slaves_of.push(slaves);
    }
    Ok((index, slaves_of))
}
