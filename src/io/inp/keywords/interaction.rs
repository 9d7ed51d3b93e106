//! The material, section, interaction, contact and step keywords: `*MATERIAL`, `*DENSITY`,
//! `*ELASTIC`, `*SOLID SECTION`, `*SURFACE INTERACTION`, `*FRICTION`, `*SURFACE BEHAVIOR`,
//! `*CONTACT PAIR`, `*CONTACT CONTROLS`, `*STEP`, `*DYNAMIC`, `*STATIC`, `*END STEP`.

use super::super::analysis::{SectionDef, StepDef};
use super::super::*;

impl Parser {
    /// `*MATERIAL` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_material(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NAME"])?;
        let Some(name) = opts.get("NAME") else {
            return Err(err(l, "*MATERIAL needs NAME="));
        };
        self.current_material = Some(name.to_uppercase());
        Ok(())
    }

    /// `*DENSITY | *ELASTIC` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_density(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        if kw == "ELASTIC" {
            if let Some(t) = opts.get("TYPE").map(|t| t.to_uppercase()) {
                if t != "ISOTROPIC" {
                    return Err(err(
                        l,
                        format!("*ELASTIC: TYPE={t} is not modelled by abut (ISOTROPIC)"),
                    ));
                }
            }
            only(l, kw, opts, &["TYPE"])?;
        } else {
            only(l, kw, opts, &[])?;
        }
        let Some(m) = self.current_material.clone() else {
            return Err(err(l, format!("*{kw} outside a *MATERIAL")));
        };
        let Some(d) = data.first() else {
            return Err(err(l, format!("*{kw} needs a data line")));
        };
        let f = fields(d);
        let v: f64 = num(d, f.first().copied().unwrap_or(""), &kw.to_lowercase())?;
        if !(v.is_finite() && v > 0.0) {
            return Err(err(d, format!("*{kw}: {v} must be positive")));
        }
        if kw == "DENSITY" {
            self.material_mut(&m, l).density = Some(v);
        } else {
            let nu: f64 = num(d, f.get(1).copied().unwrap_or("0"), "Poisson's ratio")?;
            if !(nu.is_finite() && (-1.0..0.5).contains(&nu)) {
                return Err(err(
                    d,
                    format!("*ELASTIC: Poisson's ratio {nu} must be in [-1, 0.5)"),
                ));
            }
            self.material_mut(&m, l).elastic = Some((v, nu));
        }
        Ok(())
    }

    /// `*SOLID SECTION` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_solid_section(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["ELSET", "MATERIAL"])?;
        let (Some(e), Some(m)) = (opts.get("ELSET"), opts.get("MATERIAL")) else {
            return Err(err(l, "*SOLID SECTION needs ELSET= and MATERIAL="));
        };
        let t = match data
            .first()
            .and_then(|d| fields(d).first().map(|s| (d, s.to_string())))
        {
            Some((d, s)) => num(d, &s, "thickness")?,
            None => 1.0,
        };
        let at = self.at(l);
        self.deck.analysis.sections.push(SectionDef {
            elset: e.to_uppercase(),
            material: m.to_uppercase(),
            thickness: t,
            at,
        });
        Ok(())
    }

    /// `*SURFACE INTERACTION` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_surface_interaction(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NAME"])?;
        let Some(name) = opts.get("NAME") else {
            return Err(err(l, "*SURFACE INTERACTION needs NAME="));
        };
        let name = name.to_uppercase();
        self.deck.interactions.insert(
            name.clone(),
            Interaction {
                friction: 0.0,
                behavior: Behavior::Hard,
                damping: None,
            },
        );
        self.current_interaction = Some(name);
        Ok(())
    }

    /// `*CONTACT DAMPING, DEFINITION=CRITICAL DAMPING FRACTION` in a surface interaction.
    pub(in crate::io::inp) fn on_contact_damping(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["DEFINITION"])?;
        let Some(name) = self.current_interaction.clone() else {
            return Err(err(l, "*CONTACT DAMPING outside a *SURFACE INTERACTION"));
        };
        if opts.get("DEFINITION").map(|d| d.to_uppercase()).as_deref()
            != Some("CRITICAL DAMPING FRACTION")
        {
            return Err(err(
                l,
                "*CONTACT DAMPING: abut takes DEFINITION=CRITICAL DAMPING FRACTION",
            ));
        }
        let Some(d) = data.first() else {
            return Err(err(l, "*CONTACT DAMPING needs a data line (the fraction)"));
        };
        let f: f64 = num(
            d,
            fields(d).first().copied().unwrap_or(""),
            "damping fraction",
        )?;
        if !(f.is_finite() && (0.0..=1.0).contains(&f)) {
            return Err(err(d, format!("*CONTACT DAMPING: {f} must be in [0, 1]")));
        }
        if let Some(i) = self.deck.interactions.get_mut(&name) {
            i.damping = Some(f);
        }
        Ok(())
    }

    /// `*FRICTION` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_friction(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &[])?;
        let Some(name) = self.current_interaction.clone() else {
            return Err(err(l, "*FRICTION outside a *SURFACE INTERACTION"));
        };
        let Some(d) = data.first() else {
            return Err(err(l, "*FRICTION needs the friction coefficient"));
        };
        let mu: f64 = num(
            d,
            fields(d).first().copied().unwrap_or(""),
            "friction coefficient",
        )?;
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(err(
                d,
                format!("friction coefficient {mu} must not be negative"),
            ));
        }
        self.deck
            .interactions
            .get_mut(&name)
            .expect("inserted")
            .friction = mu;
        Ok(())
    }

    /// `*SURFACE BEHAVIOR` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_surface_behavior(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["PRESSURE-OVERCLOSURE"])?;
        let Some(name) = self.current_interaction.clone() else {
            return Err(err(l, "*SURFACE BEHAVIOR outside a *SURFACE INTERACTION"));
        };
        let po = opts
            .get("PRESSURE-OVERCLOSURE")
            .map_or("HARD".to_string(), |s| s.to_uppercase());
        let values: Vec<f64> = data
            .iter()
            .flat_map(|d| fields(d).into_iter().map(move |s| (d, s)))
            .map(|(d, s)| num(d, s, "pressure-overclosure value"))
            .collect::<Result<_>>()?;
        let at = data.first().unwrap_or(l);
        let behavior = match po.as_str() {
            "HARD" => Behavior::Hard,
            "LINEAR" if values.len() == 1 => Behavior::Linear(values[0]),
            "LINEAR" if values.len() <= 3 => {
                // CalculiX's dialect: slope, then the tension at large clearance and the
                // clearance it is reached at (a regularisation abut's linear law does not have)
                self.on_ignored(
                    l,
                    "SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR: values after the slope",
                    "CalculiX's tension at large clearance; abut's linear law has no tension",
                );
                Behavior::Linear(values[0])
            }
            // Abaqus' data line: clearance c0 at zero pressure, pressure p0 at contact
            "EXPONENTIAL" if values.len() == 2 => Behavior::Exponential {
                clearance: values[0],
                pressure: values[1],
            },
            "TABULAR" if values.len() >= 4 && values.len().is_multiple_of(2) => {
                Behavior::Tabular(values.chunks(2).map(|c| (c[0], c[1])).collect())
            }
            "LINEAR" | "EXPONENTIAL" | "TABULAR" => {
                return Err(err(at, format!("PRESSURE-OVERCLOSURE={po}: wrong number of values ({}): LINEAR takes the slope, EXPONENTIAL pressure and clearance, TABULAR pressure, overclosure pairs", values.len())))
            }
            other => {
                return Err(err(l, format!("PRESSURE-OVERCLOSURE={other} is not supported by abut (HARD, LINEAR, EXPONENTIAL, TABULAR)")))
            }
        };
        self.deck
            .interactions
            .get_mut(&name)
            .expect("inserted")
            .behavior = behavior;
        Ok(())
    }

    /// `*CONTACT PAIR` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_contact_pair(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        if self.in_step && self.deck.analysis.steps.len() > 1 {
            return Err(err(
                l,
                "*CONTACT PAIR in a later step: abut's contact pairs act from the start of the run (define them in the model data or the first step)",
            ));
        }
        only(
            l,
            kw,
            opts,
            &[
                "INTERACTION",
                "SMALL SLIDING",
                "MECHANICAL CONSTRAINT",
                "WEIGHT",
                "CPSET",
                "TYPE",
            ],
        )?;
        match opts.get("TYPE").map(|t| t.to_uppercase()).as_deref() {
            None | Some("NODE TO SURFACE") => {}
            Some("SURFACE TO SURFACE") => self.on_ignored(
                l,
                "CONTACT PAIR, TYPE=SURFACE TO SURFACE",
                "abut enforces contact pairs node to surface (slave nodes on master facets), as Abaqus/Explicit's pure master–slave pairs do",
            ),
            Some(other) => {
                return Err(err(
                    l,
                    format!("*CONTACT PAIR: TYPE={other} is not supported by abut (NODE TO SURFACE, SURFACE TO SURFACE)"),
                ))
            }
        }
        let Some(inter) = opts.get("INTERACTION") else {
            return Err(err(l, "*CONTACT PAIR needs INTERACTION="));
        };
        let penalty = match opts.get("MECHANICAL CONSTRAINT").map(|s| s.to_uppercase()) {
            None => false,
            Some(s) if s == "KINEMATIC" => false,
            Some(s) if s == "PENALTY" => true,
            Some(other) => {
                return Err(err(
                    l,
                    format!(
                    "MECHANICAL CONSTRAINT={other} is not supported by abut (KINEMATIC, PENALTY)"
                ),
                ))
            }
        };
        let weight = match opts.get("WEIGHT") {
            Some(w) => {
                let w: f64 = num(l, w, "WEIGHT")?;
                if !(0.0..=1.0).contains(&w) {
                    return Err(err(l, format!("WEIGHT={w} must lie in [0, 1]")));
                }
                Some(w)
            }
            None => None,
        };
        if data.is_empty() {
            return Err(err(
                l,
                "*CONTACT PAIR needs a data line: slave surface, master surface",
            ));
        }
        for d in data {
            let f = fields(d);
            if f.len() != 2 {
                return Err(err(
                    d,
                    "*CONTACT PAIR: expected slave surface, master surface",
                ));
            }
            self.deck.pairs.push(ContactPairDef {
                slave: f[0].to_uppercase(),
                master: f[1].to_uppercase(),
                interaction: inter.to_uppercase(),
                small_sliding: opts.contains_key("SMALL SLIDING"),
                penalty,
                weight,
                cpset: opts.get("CPSET").map(|s| s.to_uppercase()),
                line: d.number,
            });
        }
        Ok(())
    }

    /// `*CONTACT CONTROLS` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_contact_controls(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        only(
            l,
            kw,
            opts,
            &["CPSET", "GLOBTRKINC", "FASTLOCALTRK", "SCALE PENALTY"],
        )?;
        let mut c = Controls {
            cpset: opts.get("CPSET").map(|s| s.to_uppercase()),
            ..Default::default()
        };
        if let Some(v) = opts.get("GLOBTRKINC") {
            let n: u32 = num(l, v, "GLOBTRKINC")?;
            if n == 0 {
                return Err(err(l, "GLOBTRKINC must be positive"));
            }
            c.global_interval = Some(n);
        }
        if let Some(v) = opts.get("FASTLOCALTRK") {
            c.wide_local = match v.to_uppercase().as_str() {
                "NO" => true,
                "YES" => false,
                other => return Err(err(l, format!("FASTLOCALTRK={other}: expected YES or NO"))),
            };
        }
        if let Some(v) = opts.get("SCALE PENALTY") {
            let s: f64 = num(l, v, "SCALE PENALTY")?;
            if !(s.is_finite() && s > 0.0) {
                return Err(err(l, format!("SCALE PENALTY={s} must be positive")));
            }
            c.penalty_scale = Some(s);
        }
        if !data.is_empty() {
            return Err(err(
                &data[0],
                "*CONTACT CONTROLS takes no data lines in abut",
            ));
        }
        self.deck.controls.push(c);
        Ok(())
    }

    /// `*STEP` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_step(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &["NLGEOM", "NAME", "INC"])?;
        if self.in_step {
            return Err(err(l, "*STEP inside a step (missing *END STEP)"));
        }
        self.in_step = true;
        self.output_history = false;
        self.deck.nlgeom = match opts.get("NLGEOM").map(|s| s.to_uppercase()) {
            None => true,
            // the option alone means YES
            Some(s) if s == "YES" || s.is_empty() => true,
            Some(s) if s == "NO" => false,
            Some(other) => return Err(err(l, format!("NLGEOM={other}: expected YES or NO"))),
        };
        let at = self.at(l);
        self.deck.analysis.steps.push(StepDef {
            name: opts.get("NAME").cloned(),
            nlgeom: self.deck.nlgeom,
            nlgeom_written: opts.contains_key("NLGEOM"),
            procedure: None,
            time_period: None,
            fixed_increment: None,
            scale_factor: None,
            bulk_viscosity: None,
            mass_scaling: None,
            history_every: None,
            field_every: None,
            node_outputs: Vec::new(),
            element_outputs: Vec::new(),
            contact_outputs: Vec::new(),
            boundary_new: false,
            cload_new: false,
            at,
        });
        Ok(())
    }

    /// `*DYNAMIC` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_dynamic(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        data: &[Line],
    ) -> Result<()> {
        if kw == "STATIC" {
            // read as written; Scene::from_inp decides how it runs
            let period = data
                .first()
                .map(|d| {
                    let f: Vec<&str> = d.text.split(',').map(str::trim).collect();
                    f.get(1)
                        .filter(|s| !s.is_empty())
                        .map(|t| num::<f64>(d, t, "time period"))
                        .transpose()
                })
                .transpose()?
                .flatten();
            let step = self.step_mut(l, kw)?;
            step.procedure = Some("STATIC".into());
            step.time_period = period.or(Some(1.0));
            // a static step without NLGEOM= is small-strain (Abaqus/Standard's and CalculiX's
            // default; Abaqus/Explicit's YES is for its own dynamic steps)
            if !step.nlgeom_written {
                step.nlgeom = false;
                self.deck.nlgeom = false;
            }
            return Ok(());
        }
        only(
            l,
            kw,
            opts,
            &[
                "EXPLICIT",
                "DIRECT USER CONTROL",
                "SCALE FACTOR",
                "ELEMENT BY ELEMENT",
            ],
        )?;
        if !opts.contains_key("EXPLICIT") {
            return Err(err(
                l,
                "*DYNAMIC: abut reads explicit steps only (*DYNAMIC, EXPLICIT)",
            ));
        }
        let scale = match opts.get("SCALE FACTOR") {
            Some(s) => {
                let v: f64 = num(l, s, "SCALE FACTOR")?;
                if !(v.is_finite() && v > 0.0 && v <= 1.0) {
                    return Err(err(
                        l,
                        format!("*DYNAMIC: SCALE FACTOR={v} must be in (0, 1]"),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        // positional data: initial (or, with DIRECT USER CONTROL, fixed) increment, time period
        let mut period = None;
        let mut first = None;
        if let Some(d) = data.first() {
            let f: Vec<&str> = d.text.split(',').map(str::trim).collect();
            if let Some(t) = f.get(1).filter(|s| !s.is_empty()) {
                period = Some(num::<f64>(d, t, "time period")?);
            }
            if let Some(t) = f.first().filter(|s| !s.is_empty()) {
                first = Some(num::<f64>(d, t, "time increment")?);
            }
        }
        self.deck.time_period = period;
        let direct = opts.contains_key("DIRECT USER CONTROL");
        if direct && first.is_none_or(|dt| !(dt.is_finite() && dt > 0.0)) {
            return Err(err(
                l,
                "*DYNAMIC, EXPLICIT, DIRECT USER CONTROL: the data line's first value, the fixed increment, must be positive",
            ));
        }
        if opts.contains_key("ELEMENT BY ELEMENT") {
            self.on_ignored(
                l,
                "DYNAMIC, ELEMENT BY ELEMENT",
                "abut's stable increment is the whole model's (never larger than the element-by-element one)",
            );
        }
        if !self.in_step {
            // a contact-only deck (Deck::to_model) may give the procedure alone
            return Ok(());
        }
        let step = self.step_mut(l, kw)?;
        step.procedure = Some("DYNAMIC EXPLICIT".into());
        step.time_period = period;
        step.scale_factor = scale;
        step.fixed_increment = if direct { first } else { None };
        Ok(())
    }

    /// `*END STEP` at line `l` with its options and data lines.
    pub(in crate::io::inp) fn on_end_step(
        &mut self,
        l: &Line,
        kw: &str,
        opts: &BTreeMap<String, String>,
        _data: &[Line],
    ) -> Result<()> {
        only(l, kw, opts, &[])?;
        if !self.in_step {
            return Err(err(l, "*END STEP without *STEP"));
        }
        self.in_step = false;
        Ok(())
    }
}
