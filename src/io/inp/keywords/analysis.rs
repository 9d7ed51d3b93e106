//! The keywords of what a deck runs: `*RIGID BODY`, `*MASS`, `*ROTARY INERTIA`, `*DAMPING`,
//! `*BOUNDARY`, `*INITIAL CONDITIONS`, `*AMPLITUDE`, `*CLOAD`, `*DLOAD`, `*BULK VISCOSITY`,
//! `*FIXED MASS SCALING`, `*STATIC`, `*OUTPUT`, and the requests abut reads but does not act on.

use super::super::analysis::*;
use super::super::*;

/// A finite number, or an error naming what it is.
fn finite(l: &Line, s: &str, what: &str) -> Result<f64> {
    let v: f64 = num(l, s, what)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(l, format!("{what} {s} is not finite")))
    }
}

/// A degree of freedom 1–6.
fn dof(l: &Line, s: &str) -> Result<usize> {
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

    /// `*BOUNDARY` (model data, or in a step).
    pub(in crate::io::inp) fn on_boundary(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["AMPLITUDE", "TYPE", "OP"])?;
        let kind = match opts.get("TYPE").map(|s| s.to_uppercase()).as_deref() {
            None | Some("DISPLACEMENT") => BoundaryKind::Displacement,
            Some("VELOCITY") => BoundaryKind::Velocity,
            Some(other) => {
                return Err(err(
                    l,
                    format!(
                        "*BOUNDARY: TYPE={other} is not supported by abut (DISPLACEMENT, VELOCITY)"
                    ),
                ))
            }
        };
        if let Some(op) = opts.get("OP").map(|s| s.to_uppercase()) {
            if op != "MOD" {
                return Err(err(
                    l,
                    format!("*BOUNDARY: OP={op} is not supported by abut (OP=MOD, the default)"),
                ));
            }
        }
        let amplitude = opts.get("AMPLITUDE").map(|s| s.to_uppercase());
        if let Some(a) = &amplitude {
            if !self.deck.analysis.amplitudes.contains_key(a) {
                return Err(err(l, format!("*BOUNDARY: amplitude {a} is not defined")));
            }
        }
        for d in data {
            // positional: "set, 2, , 0.1" leaves the last dof empty (the first)
            let mut f: Vec<&str> = d.text.split(',').map(str::trim).collect();
            while f.last().is_some_and(|s| s.is_empty()) {
                f.pop();
            }
            if f.len() < 2 || f.len() > 4 || f[0].is_empty() || f[1].is_empty() {
                return Err(err(
                    d,
                    "*BOUNDARY: expected node or set, first dof[, last dof[, value]] or node or set, ENCASTRE|PINNED|XSYMM|…",
                ));
            }
            let nodes = self.members(d, f[0], true)?;
            let at = self.at(d);
            let mut push = |first: usize, last: usize, value: f64| {
                self.deck.analysis.boundaries.push(BoundaryDef {
                    nodes: nodes.clone(),
                    first,
                    last,
                    value,
                    kind,
                    amplitude: amplitude.clone(),
                    in_step: self.in_step,
                    at: at.clone(),
                });
            };
            if let Some(ranges) = boundary_type(&f[1].to_uppercase()) {
                if f.len() > 2 {
                    return Err(err(d, format!("*BOUNDARY: {} takes no more values", f[1])));
                }
                for &(a, b) in ranges {
                    push(a, b, 0.0);
                }
                continue;
            }
            let first = dof(d, f[1])?;
            let last = match f.get(2).filter(|s| !s.is_empty()) {
                Some(s) => dof(d, s)?,
                None => first,
            };
            if last < first {
                return Err(err(
                    d,
                    format!("*BOUNDARY: last dof {last} before first {first}"),
                ));
            }
            let value = match f.get(3) {
                Some(s) => finite(d, s, "value")?,
                None => 0.0,
            };
            push(first, last, value);
        }
        Ok(())
    }

    /// `*INITIAL CONDITIONS, TYPE=VELOCITY`.
    pub(in crate::io::inp) fn on_initial_conditions(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["TYPE"])?;
        let ty = opts
            .get("TYPE")
            .map(|s| s.to_uppercase())
            .unwrap_or_default();
        if ty != "VELOCITY" {
            return Err(err(
                l,
                format!("*INITIAL CONDITIONS: TYPE={ty} is not supported by abut (VELOCITY)"),
            ));
        }
        for d in data {
            let f = fields(d);
            if f.len() != 3 {
                return Err(err(
                    d,
                    "*INITIAL CONDITIONS, TYPE=VELOCITY: expected node or set, dof, value",
                ));
            }
            let axis = dof(d, f[1])?;
            if axis > 3 {
                return Err(err(
                    d,
                    "*INITIAL CONDITIONS, TYPE=VELOCITY: abut takes translational velocities (dof 1–3)",
                ));
            }
            let v = finite(d, f[2], "velocity")?;
            let at = self.at(d);
            for n in self.members(d, f[0], true)? {
                self.deck
                    .analysis
                    .initial_velocities
                    .push((n, axis, v, at.clone()));
            }
        }
        Ok(())
    }

    /// `*AMPLITUDE, NAME=, DEFINITION=TABULAR|SMOOTH STEP`.
    pub(in crate::io::inp) fn on_amplitude(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NAME", "DEFINITION", "TIME", "VALUE"])?;
        let Some(name) = opts.get("NAME") else {
            return Err(err(l, "*AMPLITUDE needs NAME="));
        };
        let smooth = match opts.get("DEFINITION").map(|s| s.to_uppercase()).as_deref() {
            None | Some("TABULAR") => false,
            Some("SMOOTH STEP") => true,
            Some(other) => {
                return Err(err(
                    l,
                    format!("*AMPLITUDE: DEFINITION={other} is not supported by abut (TABULAR, SMOOTH STEP)"),
                ))
            }
        };
        for (k, want) in [("TIME", "STEP TIME"), ("VALUE", "RELATIVE")] {
            if let Some(v) = opts.get(k).map(|s| s.to_uppercase()) {
                if v != want {
                    return Err(err(
                        l,
                        format!("*AMPLITUDE: {k}={v} is not supported by abut ({k}={want})"),
                    ));
                }
            }
        }
        let mut values = Vec::new();
        for d in data {
            for s in fields(d) {
                values.push((finite(d, s, "amplitude")?, d));
            }
        }
        if values.len() % 2 != 0 || values.is_empty() {
            return Err(err(l, "*AMPLITUDE: expected (time, value) pairs"));
        }
        let points: Vec<(f64, f64)> = values.chunks(2).map(|c| (c[0].0, c[1].0)).collect();
        if let Some(w) = values
            .chunks(2)
            .collect::<Vec<_>>()
            .windows(2)
            .find(|w| w[1][0].0 <= w[0][0].0)
        {
            return Err(err(
                w[1][0].1,
                format!(
                    "*AMPLITUDE {name}: times must increase ({} after {})",
                    w[1][0].0, w[0][0].0
                ),
            ));
        }
        let at = self.at(l);
        self.deck
            .analysis
            .amplitudes
            .insert(name.to_uppercase(), AmplitudeDef { smooth, points, at });
        Ok(())
    }

    /// `*CLOAD`.
    pub(in crate::io::inp) fn on_cload(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["AMPLITUDE", "OP"])?;
        let amplitude = opts.get("AMPLITUDE").map(|s| s.to_uppercase());
        if let Some(a) = &amplitude {
            if !self.deck.analysis.amplitudes.contains_key(a) {
                return Err(err(l, format!("*CLOAD: amplitude {a} is not defined")));
            }
        }
        for d in data {
            let f = fields(d);
            if f.len() != 3 {
                return Err(err(d, "*CLOAD: expected node or set, dof, magnitude"));
            }
            let nodes = self.members(d, f[0], true)?;
            let dof = dof(d, f[1])?;
            let value = finite(d, f[2], "magnitude")?;
            let at = self.at(d);
            self.deck.analysis.cloads.push(CloadDef {
                nodes,
                dof,
                value,
                amplitude: amplitude.clone(),
                at,
            });
        }
        Ok(())
    }

    /// `*DLOAD` (type `GRAV` only).
    pub(in crate::io::inp) fn on_dload(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["OP"])?;
        for d in data {
            let f = fields(d);
            let ty = f.get(1).map(|s| s.to_uppercase()).unwrap_or_default();
            if ty != "GRAV" {
                return Err(err(
                    d,
                    format!("*DLOAD: load type {ty} is not supported by abut (GRAV)"),
                ));
            }
            if f.len() != 6 {
                return Err(err(d, "*DLOAD, GRAV: expected elset, GRAV, g, nx, ny, nz"));
            }
            let g = finite(d, f[2], "gravity")?;
            let n: Vec<f64> = f[3..6]
                .iter()
                .map(|s| finite(d, s, "direction"))
                .collect::<Result<_>>()?;
            // a magnitude and a direction: the direction normalised (as given when it already
            // is a unit vector to round-off)
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len == 0.0 {
                return Err(err(d, "*DLOAD, GRAV: the direction is zero"));
            }
            let scale = if (len - 1.0).abs() <= 4.0 * f64::EPSILON {
                1.0
            } else {
                1.0 / len
            };
            let at = self.at(d);
            self.deck.analysis.gravity.push(GravityDef {
                elset: f[0].to_uppercase(),
                acceleration: [g * (n[0] * scale), g * (n[1] * scale), g * (n[2] * scale)],
                at,
            });
        }
        Ok(())
    }

    /// `*BULK VISCOSITY` in a step.
    pub(in crate::io::inp) fn on_bulk_viscosity(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &[])?;
        let Some(d) = data.first() else {
            return Err(err(l, "*BULK VISCOSITY needs a data line (b1, b2)"));
        };
        let f = fields(d);
        let b1 = finite(d, f.first().copied().unwrap_or("0.06"), "b1")?;
        let b2 = finite(d, f.get(1).copied().unwrap_or("1.2"), "b2")?;
        self.step_mut(l, kw)?.bulk_viscosity = Some((b1, b2));
        Ok(())
    }

    /// `*FIXED MASS SCALING, FACTOR=` over the whole model.
    pub(in crate::io::inp) fn on_fixed_mass_scaling(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["FACTOR"])?;
        let Some(f) = opts.get("FACTOR") else {
            return Err(err(
                l,
                "*FIXED MASS SCALING: abut takes FACTOR= over the whole model (not DT= or TYPE=)",
            ));
        };
        let f = finite(l, f, "FACTOR")?;
        if f <= 0.0 {
            return Err(err(
                l,
                format!("*FIXED MASS SCALING: FACTOR={f} must be positive"),
            ));
        }
        self.step_mut(l, kw)?.mass_scaling = Some(f);
        Ok(())
    }

    /// `*OUTPUT, FIELD|HISTORY`: its frequency in increments; time-based output is listed as
    /// not acted on.
    pub(in crate::io::inp) fn on_output(
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
                "FIELD",
                "HISTORY",
                "FREQUENCY",
                "NUMBER INTERVAL",
                "TIME INTERVAL",
                "VARIABLE",
                "OP",
                "TIME MARKS",
            ],
        )?;
        let field = opts.contains_key("FIELD");
        let every = match opts.get("FREQUENCY") {
            Some(f) => Some(num::<usize>(l, f, "FREQUENCY")?.max(1)),
            None => None,
        };
        let step = self.step_mut(l, kw)?;
        match (every, field) {
            (Some(n), true) => step.field_every = Some(n),
            (Some(n), false) => step.history_every = Some(n),
            (None, _) => {
                let what = if field {
                    "FIELD without FREQUENCY=: no contact frames"
                } else {
                    "HISTORY without FREQUENCY=: a history row every increment"
                };
                self.on_ignored(
                    l,
                    &format!("OUTPUT, {what}"),
                    "abut counts output in increments",
                );
            }
        }
        Ok(())
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

/// Keywords abut reads and does not act on, with why.
pub(in crate::io::inp) fn ignored(kw: &str) -> Option<&'static str> {
    Some(match kw {
        "NODE OUTPUT" | "ELEMENT OUTPUT" | "CONTACT OUTPUT" | "ENERGY OUTPUT" => {
            "abut writes its own variables (history.csv: energies, contact force, each part's motion; VTK frames: CPRESS, COPEN, CSTATUS, CSHEAR, CFN)"
        }
        "NODE PRINT" | "EL PRINT" | "NODE FILE" | "EL FILE" | "CONTACT PRINT" | "CONTACT FILE"
        | "SECTION PRINT" | "ENERGY PRINT" | "ENERGY FILE" => {
            "a print or file request of another code; abut writes history.csv and summary.json"
        }
        "PREPRINT" | "RESTART" | "MONITOR" | "FILE FORMAT" | "DIAGNOSTICS" => {
            "a control of Abaqus' own files and messages"
        }
        _ => return None,
    })
}

/// Keywords abut does not model, with what they are: refused before anything runs.
pub(in crate::io::inp) fn not_modelled(kw: &str) -> Option<&'static str> {
    Some(match kw {
        "PLASTIC" | "HYPERELASTIC" | "HYPERFOAM" | "VISCOELASTIC" | "CREEP"
        | "DAMAGE INITIATION" | "DAMAGE EVOLUTION" | "DEPVAR" | "USER MATERIAL" => {
            "a material model beyond linear elasticity"
        }
        "EXPANSION" | "CONDUCTIVITY" | "SPECIFIC HEAT" | "INITIAL CONDITIONS TEMPERATURE" => {
            "thermal behaviour"
        }
        "EQUATION" | "MPC" | "TIE" | "COUPLING" | "KINEMATIC" | "DISTRIBUTING"
        | "KINEMATIC COUPLING" => "a constraint between nodes",
        "CYCLIC SYMMETRY MODEL" | "TIE CYCLIC" => "cyclic symmetry",
        "SHELL SECTION"
        | "SHELL GENERAL SECTION"
        | "MEMBRANE SECTION"
        | "BEAM SECTION"
        | "BEAM GENERAL SECTION" => "a structural section (shells, membranes, beams)",
        "SPRING" | "DASHPOT" | "CONNECTOR SECTION" => "springs, dashpots and connectors",
        "HEAT TRANSFER"
        | "FREQUENCY"
        | "BUCKLE"
        | "VISCO"
        | "COUPLED TEMPERATURE-DISPLACEMENT"
        | "STEADY STATE DYNAMICS"
        | "MODAL DYNAMIC" => "an analysis procedure other than explicit dynamics",
        "CONTACT" | "CONTACT INCLUSIONS" | "CONTACT PROPERTY ASSIGNMENT" => {
            "general contact (abut reads contact pairs: *CONTACT PAIR)"
        }
        "DSLOAD" | "DSFLUX" | "DFLUX" | "CFLUX" | "TEMPERATURE" | "FILM" => {
            "a load abut does not apply (distributed surface loads, fluxes, temperatures)"
        }
        "GAP" | "CHANGE FRICTION" | "MODEL CHANGE" | "CHANGE SURFACE BEHAVIOR" => {
            "a contact option abut does not read yet"
        }
        _ => return None,
    })
}
