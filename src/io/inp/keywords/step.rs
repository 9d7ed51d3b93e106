//! The keywords of a deck's step controls: `*BULK VISCOSITY`, `*FIXED MASS SCALING`,
//! `*OUTPUT`, and the node output requests (`*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`).

use super::super::*;
use super::analysis::finite;

impl Parser {
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
        self.output_history = !field;
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

    /// `*NODE PRINT`, `*NODE OUTPUT`, `*NODE FILE`, the element requests `*EL PRINT`,
    /// `*ELEMENT OUTPUT`, `*EL FILE` and the contact ones `*CONTACT PRINT`, `*CONTACT OUTPUT`,
    /// `*CONTACT FILE`: the set and the variables (one or more data lines of names); frequency,
    /// surface and print layout options are read and left to abut (it writes the variables at
    /// the step's end, contact ones for every slave node).
    pub(in crate::io::inp) fn on_node_output(
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
            &[
                "NSET",
                "ELSET",
                "SLAVE",
                "MASTER",
                "SURFACE",
                "CPSET",
                "POSITION",
                "DIRECTIONS",
                "FREQUENCY",
                "FREQUENCYF",
                "TOTALS",
                "GLOBAL",
                "OUTPUT",
                "TIME INTERVAL",
                "NUMBER INTERVAL",
                "TIME MARKS",
                "SUMMARY",
                "VARIABLE",
            ],
        )?;
        let variables: Vec<String> = data
            .iter()
            .flat_map(fields)
            .filter(|f| !f.is_empty())
            .map(|f| f.to_ascii_uppercase())
            .collect();
        let at = self.at(l);
        let elements = kw.starts_with("EL");
        let set = opts
            .get(if elements { "ELSET" } else { "NSET" })
            .map(|s| s.to_ascii_uppercase());
        let def = NodeOutputDef {
            keyword: kw.to_string(),
            nset: set,
            variables,
            history: self.output_history && kw.ends_with("OUTPUT"),
            at,
        };
        let step = self.step_mut(l, kw)?;
        if kw.starts_with("CONTACT") {
            step.contact_outputs.push(def);
        } else if elements {
            step.element_outputs.push(def);
        } else {
            step.node_outputs.push(def);
        }
        Ok(())
    }
}
