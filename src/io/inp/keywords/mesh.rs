//! The mesh keywords: `*NODE`, `*ELEMENT`, `*NSET` / `*ELSET` and `*SURFACE`.

use super::super::*;

impl Parser {
    /// `*NODE` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_node(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NSET"])?;
        let mut set = Vec::new();
        for d in data {
            let f = fields(d);
            if f.len() < 3 || f.len() > 4 {
                return Err(err(d, "*NODE: expected label, x, y[, z]"));
            }
            let label: u64 = num(d, f[0], "node label")?;
            let mut x = [0.0f64; 3];
            for (a, s) in f[1..].iter().enumerate() {
                x[a] = num(d, s, "coordinate")?;
                if !x[a].is_finite() {
                    return Err(err(
                        d,
                        format!("node {label}: coordinate {s} is not finite"),
                    ));
                }
            }
            if self.node_index.contains_key(&label) {
                return Err(err(d, format!("node {label} is defined twice")));
            }
            let idx = self.deck.mesh.positions.len() as u32;
            self.node_index.insert(label, idx);
            self.deck.mesh.node_labels.push(label);
            self.deck.mesh.positions.push(x);
            set.push(idx);
        }
        if let Some(name) = opts.get("NSET") {
            self.deck
                .mesh
                .node_sets
                .entry(name.to_uppercase())
                .or_default()
                .extend(set);
        }
        Ok(())
    }

    /// `*ELEMENT` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_element(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["TYPE", "ELSET"])?;
        let Some(t) = opts.get("TYPE") else {
            return Err(err(l, "*ELEMENT needs TYPE="));
        };
        if matches!(t.to_uppercase().as_str(), "MASS" | "ROTARYI") {
            // one-node elements carrying *MASS or *ROTARY INERTIA: their nodes, by ELSET
            let Some(set) = opts.get("ELSET") else {
                return Err(err(
                    l,
                    format!("*ELEMENT, TYPE={t} needs ELSET= (for *MASS or *ROTARY INERTIA)"),
                ));
            };
            let mut nodes = Vec::new();
            for d in data {
                let f = fields(d);
                if f.len() != 2 {
                    return Err(err(
                        d,
                        format!("*ELEMENT, TYPE={t}: expected a label and a node"),
                    ));
                }
                let _: u64 = num(d, f[0], "element label")?;
                nodes.push(self.node(d, num(d, f[1], "node label")?)?);
            }
            self.deck.analysis.mass_sets.insert(set.to_uppercase());
            self.point_sets
                .entry(set.to_uppercase())
                .or_default()
                .extend(nodes);
            return Ok(());
        }
        let (kind, axisymmetric) = element_kind(l, t)?;
        let at = self.at(l);
        let first = self.deck.mesh.elements.len() as u32;
        self.deck
            .analysis
            .element_blocks
            .push((first, t.to_uppercase(), at));
        let n = kind.node_count();
        let mut set = Vec::new();
        // an element's nodes may continue on the next line after a trailing comma
        let mut k = 0;
        while k < data.len() {
            let d = &data[k];
            let mut f: Vec<String> = fields(d).iter().map(|s| s.to_string()).collect();
            while d.text.ends_with(',') && k + 1 < data.len() && f.len() < n + 1 {
                k += 1;
                f.extend(fields(&data[k]).iter().map(|s| s.to_string()));
            }
            if f.len() != n + 1 {
                return Err(err(
                    d,
                    format!(
                        "*ELEMENT, TYPE={t}: expected a label and {n} nodes, found {} values",
                        f.len()
                    ),
                ));
            }
            let label: u64 = num(d, &f[0], "element label")?;
            let mut nodes = Vec::with_capacity(n);
            for s in &f[1..] {
                nodes.push(self.node(d, num(d, s, "node label")?)?);
            }
            let mut sorted = nodes.clone();
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) {
                return Err(err(d, format!("element {label}: a node appears twice")));
            }
            if self.element_index.contains_key(&label) {
                return Err(err(d, format!("element {label} is defined twice")));
            }
            if axisymmetric {
                if let Some(&bad) = nodes
                    .iter()
                    .find(|&&n| self.deck.mesh.positions[n as usize][0] < 0.0)
                {
                    return Err(err(
                        d,
                        format!(
                            "element {label} (TYPE={t}): node {} is at x = {} < 0 (x is the radius of an axisymmetric element)",
                            self.deck.mesh.node_labels[bad as usize],
                            self.deck.mesh.positions[bad as usize][0]
                        ),
                    ));
                }
            }
            if kind.is_planar()
                && *self.plane_axisymmetric.get_or_insert(axisymmetric) != axisymmetric
            {
                return Err(err(
                    d,
                    format!("element {label} (TYPE={t}): a deck's plane elements are either all axisymmetric (CAX) or none (CPE, CPS)"),
                ));
            }
            let idx = self.deck.mesh.elements.len() as u32;
            self.element_index.insert(label, idx);
            if t.to_uppercase().starts_with("CPS") {
                self.deck.analysis.plane_stress.push(idx);
            }
            self.deck.mesh.elements.push(MeshElement {
                kind,
                nodes,
                label,
                axisymmetric,
            });
            set.push(idx);
            k += 1;
        }
        if let Some(name) = opts.get("ELSET") {
            self.deck
                .mesh
                .element_sets
                .entry(name.to_uppercase())
                .or_default()
                .extend(set);
        }
        Ok(())
    }

    /// `*NSET | *ELSET` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_nset(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        let nodes = kw == "NSET";
        only(l, kw, opts, &[kw, "GENERATE"])?;
        let Some(name) = opts.get(kw) else {
            return Err(err(l, format!("*{kw} needs {kw}=name")));
        };
        let mut set = Vec::new();
        for d in data {
            let f = fields(d);
            if opts.contains_key("GENERATE") {
                if f.len() < 2 || f.len() > 3 {
                    return Err(err(d, "GENERATE: expected first, last[, increment]"));
                }
                let a: u64 = num(d, f[0], "first")?;
                let b: u64 = num(d, f[1], "last")?;
                let s: u64 = if f.len() == 3 {
                    num(d, f[2], "increment")?
                } else {
                    1
                };
                if s == 0 || b < a {
                    return Err(err(
                        d,
                        "GENERATE: needs first ≤ last and a positive increment",
                    ));
                }
                let mut v = a;
                while v <= b {
                    set.extend(self.members(d, &v.to_string(), nodes)?);
                    // the last label may be u64::MAX: stop instead of wrapping
                    let Some(next) = v.checked_add(s) else { break };
                    v = next;
                }
            } else {
                for s in f {
                    set.extend(self.members(d, s, nodes)?);
                }
            }
        }
        let sets = if nodes {
            &mut self.deck.mesh.node_sets
        } else {
            &mut self.deck.mesh.element_sets
        };
        // each member once, in the order first given (a set that names itself, or
        // nodes listed twice, does not grow)
        let members = sets.entry(name.to_uppercase()).or_default();
        let mut seen: std::collections::HashSet<u32> = members.iter().copied().collect();
        members.extend(set.into_iter().filter(|m| seen.insert(*m)));
        Ok(())
    }

    /// `*SURFACE` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_surface(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NAME", "TYPE", "FILLET RADIUS"])?;
        let Some(name) = opts.get("NAME") else {
            return Err(err(l, "*SURFACE needs NAME="));
        };
        if opts.contains_key("FILLET RADIUS") {
            return Err(err(
                l,
                "*SURFACE, FILLET RADIUS=: abut's analytical surfaces have no fillets",
            ));
        }
        let ty = opts
            .get("TYPE")
            .map_or("ELEMENT".to_string(), |t| t.to_uppercase());
        let def = match ty.as_str() {
            "ELEMENT" => {
                let mut facets = Vec::new();
                for d in data {
                    let f = fields(d);
                    if f.is_empty() || f.len() > 2 {
                        return Err(err(
                            d,
                            "*SURFACE, TYPE=ELEMENT: expected element or set[, face]",
                        ));
                    }
                    let els = self.members(d, f[0], false)?;
                    let face = f.get(1).map(|s| s.to_uppercase());
                    for e in els {
                        facets.extend(
                            self.deck
                                .mesh
                                .element_faces(e, face.as_deref())
                                .map_err(|m| err(d, m))?,
                        );
                    }
                }
                if data.iter().all(|d| fields(d).len() == 1) {
                    // no face given: the free faces of the elements named
                    facets = crate::io::free_faces(&facets);
                }
                SurfaceDef::Faces(facets)
            }
            "NODE" => {
                let mut nodes = Vec::new();
                let mut areas = Vec::new();
                for d in data {
                    let f = fields(d);
                    if f.is_empty() || f.len() > 2 {
                        return Err(err(d, "*SURFACE, TYPE=NODE: expected node or set[, area]"));
                    }
                    let a: f64 = if f.len() == 2 {
                        num(d, f[1], "area")?
                    } else {
                        1.0
                    };
                    if !(a.is_finite() && a > 0.0) {
                        return Err(err(d, format!("area {a} must be positive")));
                    }
                    for n in self.members(d, f[0], true)? {
                        nodes.push(n);
                        areas.push(a);
                    }
                }
                SurfaceDef::Nodes(nodes, areas)
            }
            "REVOLUTION" | "SEGMENTS" | "CYLINDER" => {
                let def = self.analytical_surface(l, &ty, data)?;
                self.deck
                    .analysis
                    .analytical
                    .insert(name.to_uppercase(), def);
                return Ok(());
            }
            other => {
                return Err(err(
                    l,
                    format!("*SURFACE: TYPE={other} is not supported by abut (ELEMENT, NODE, REVOLUTION, SEGMENTS, CYLINDER)"),
                ))
            }
        };
        self.deck.surfaces.insert(name.to_uppercase(), def);
        Ok(())
    }
}
