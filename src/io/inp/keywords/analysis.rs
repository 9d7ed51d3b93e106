//! The keywords of a deck's bodies and materials beyond elasticity: `*RIGID BODY`, analytical
//! surfaces, `*MASS`, `*ROTARY INERTIA`, `*SURFACE SECTION`, `*DAMPING`; the requests abut
//! reads but does not act on.

use super::super::analysis::*;
use super::super::*;

/// A finite number, or an error naming what it is.
pub(super) fn finite(l: &Line, s: &str, what: &str) -> Result<f64> {
    let v: f64 = num(l, s, what)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(l, format!("{what} {s} is not finite")))
    }
}

/// A degree of freedom 1–6.
pub(super) fn dof(l: &Line, s: &str) -> Result<usize> {
    let d: usize = num(l, s, "degree of freedom")?;
    if (1..=6).contains(&d) {
        Ok(d)
    } else {
        Err(err(l, format!("degree of freedom {d}: expected 1 to 6")))
    }
}

impl Parser {
    pub(in crate::io::inp) fn at(&self, l: &Line) -> At {
        At {
            file: l.file.display().to_string(),
            line: l.number,
        }
    }

    pub(in crate::io::inp) fn step_mut(&mut self, l: &Line, kw: &str) -> Result<&mut StepDef> {
        if !self.in_step {
            return Err(err(l, format!("*{kw} belongs in a *STEP")));
        }
        Ok(self.deck.analysis.steps.last_mut().expect("a step is open"))
    }

    /// `*RIGID BODY`.
    pub(in crate::io::inp) fn on_rigid_body(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(
            l,
            kw,
            opts,
            &[
                "REF NODE",
                "ELSET",
                "PIN NSET",
                "TIE NSET",
                "ANALYTICAL SURFACE",
            ],
        )?;
        let Some(r) = opts.get("REF NODE") else {
            return Err(err(l, "*RIGID BODY needs REF NODE="));
        };
        let ref_node = self.members(l, r, true)?;
        let [ref_node] = ref_node[..] else {
            return Err(err(l, format!("REF NODE={r}: expected one node")));
        };
        let elements = match opts.get("ELSET") {
            Some(e) => self.members(l, e, false)?,
            None => Vec::new(),
        };
        let elset = opts.get("ELSET").map(|e| e.to_uppercase());
        let mut nodes = Vec::new();
        for k in ["PIN NSET", "TIE NSET"] {
            if let Some(s) = opts.get(k) {
                nodes.extend(self.members(l, s, true)?);
            }
        }
        let analytical = opts.get("ANALYTICAL SURFACE").map(|s| s.to_uppercase());
        if elements.is_empty() && nodes.is_empty() && analytical.is_none() {
            return Err(err(
                l,
                "*RIGID BODY needs ELSET=, PIN NSET=, TIE NSET= or ANALYTICAL SURFACE=",
            ));
        }
        let at = self.at(l);
        self.deck.analysis.rigid_bodies.push(RigidBodyDef {
            ref_node,
            elset,
            elements,
            nodes,
            analytical,
            at,
        });
        Ok(())
    }

    /// The data of an analytical surface: its points and profile.
    pub(in crate::io::inp) fn analytical_surface(
        &mut self,
        l: &Line,
        kind: &str,
        data: &[Line],
    ) -> Result<AnalyticalDef> {
        // a and b (REVOLUTION, CYLINDER), then c (CYLINDER)
        let wanted = match kind {
            "SEGMENTS" => 0,
            "REVOLUTION" => 6,
            _ => 9,
        };
        let mut values: Vec<f64> = Vec::new();
        let mut k = 0;
        while k < data.len() && values.len() < wanted {
            for s in fields(&data[k]) {
                values.push(finite(&data[k], s, "coordinate")?);
            }
            k += 1;
        }
        let points: Vec<[f64; 3]> = values
            .chunks(3)
            .filter(|c| c.len() == 3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let mut profile = Vec::new();
        for d in &data[k..] {
            let f = fields(d);
            let word = f.first().map(|w| w.to_uppercase()).unwrap_or_default();
            let want = match word.as_str() {
                "START" | "LINE" => 2,
                "CIRCL" => 4,
                other => {
                    return Err(err(
                        d,
                        format!("*SURFACE, TYPE={kind}: segment {other} is not supported by abut (START, LINE, CIRCL)"),
                    ))
                }
            };
            if f.len() != want + 1 {
                return Err(err(d, format!("{word}: expected {want} values")));
            }
            let v = f[1..]
                .iter()
                .map(|s| finite(d, s, "coordinate"))
                .collect::<Result<Vec<f64>>>()?;
            profile.push((word, v));
        }
        if profile.first().is_none_or(|p| p.0 != "START") {
            return Err(err(
                l,
                format!("*SURFACE, TYPE={kind}: the profile begins with START"),
            ));
        }
        let at = self.at(l);
        Ok(AnalyticalDef {
            kind: kind.to_string(),
            points,
            profile,
            at,
        })
    }

    /// `*MASS` and `*ROTARY INERTIA` on the `TYPE=MASS` / `TYPE=ROTARYI` elements of `ELSET`.
    pub(in crate::io::inp) fn on_mass(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["ELSET"])?;
        let Some(e) = opts.get("ELSET") else {
            return Err(err(l, format!("*{kw} needs ELSET=")));
        };
        let Some(nodes) = self.point_sets.get(&e.to_uppercase()).cloned() else {
            return Err(err(
                l,
                format!("*{kw}: ELSET={e} is not a set of TYPE=MASS or TYPE=ROTARYI elements"),
            ));
        };
        let Some(d) = data.first() else {
            return Err(err(l, format!("*{kw} needs a data line")));
        };
        let f = fields(d);
        let at = self.at(l);
        if kw == "MASS" {
            let m = finite(d, f.first().copied().unwrap_or(""), "mass")?;
            if m <= 0.0 {
                return Err(err(d, format!("*MASS: {m} must be positive")));
            }
            for n in nodes {
                self.deck.analysis.point_masses.push((n, m, at.clone()));
            }
        } else {
            let v: Vec<f64> = f
                .iter()
                .map(|s| finite(d, s, "rotary inertia"))
                .collect::<Result<_>>()?;
            if v.len() < 3 || v.len() > 6 {
                return Err(err(
                    d,
                    "*ROTARY INERTIA: expected I11, I22, I33[, I12, I13, I23]",
                ));
            }
            let g = |k: usize| v.get(k).copied().unwrap_or(0.0);
            let i = [[g(0), g(3), g(4)], [g(3), g(1), g(5)], [g(4), g(5), g(2)]];
            for n in nodes {
                self.deck.analysis.rotary_inertia.push((n, i, at.clone()));
            }
        }
        Ok(())
    }

    /// `*SURFACE SECTION, ELSET=`: surface elements (SFM3D3, SFM3D4(R)) that carry a surface and
    /// nothing else.
    pub(in crate::io::inp) fn on_surface_section(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["ELSET", "DENSITY"])?;
        let Some(e) = opts.get("ELSET") else {
            return Err(err(l, "*SURFACE SECTION needs ELSET="));
        };
        if opts.contains_key("DENSITY") {
            return Err(err(
                l,
                "*SURFACE SECTION, DENSITY=: massive surface elements are not modelled by abut",
            ));
        }
        let els = self.members(l, e, false)?;
        self.deck.analysis.surface_elements.extend(els);
        Ok(())
    }

    /// `*DAMPING, ALPHA=` in a material.
    pub(in crate::io::inp) fn on_damping(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["ALPHA"])?;
        let Some(m) = self.current_material.clone() else {
            return Err(err(l, "*DAMPING outside a *MATERIAL"));
        };
        let Some(a) = opts.get("ALPHA") else {
            return Err(err(
                l,
                "*DAMPING: abut models mass-proportional damping only (ALPHA=)",
            ));
        };
        let a = finite(l, a, "ALPHA")?;
        if a < 0.0 {
            return Err(err(l, format!("*DAMPING: ALPHA={a} must not be negative")));
        }
        self.material_mut(&m, l).alpha = a;
        Ok(())
    }

    pub(in crate::io::inp) fn material_mut(&mut self, name: &str, l: &Line) -> &mut MaterialDef {
        let at = self.at(l);
        self.deck
            .analysis
            .materials
            .entry(name.to_string())
            .or_insert_with(|| MaterialDef {
                at,
                ..Default::default()
            })
    }

    /// Requests abut reads and does not act on: they are listed in the summary.
    pub(in crate::io::inp) fn on_ignored(&mut self, l: &Line, kw: &str, why: &str) {
        let at = self.at(l);
        self.deck
            .analysis
            .ignored
            .push(format!("{at}: *{kw}: {why}"));
    }
}
