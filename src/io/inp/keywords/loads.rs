//! The keywords of a deck's loads: `*BOUNDARY`, `*INITIAL CONDITIONS`, `*AMPLITUDE`,
//! `*CLOAD`, `*DLOAD` (gravity).

use super::super::analysis::*;
use super::super::*;
use super::analysis::{dof, finite};

impl Parser {
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
        if self.op_new(l, kw, opts)? {
            self.step_mut(l, kw)?.boundary_new = true;
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
                    step: self.step_number(),
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
        self.deck.analysis.amplitudes.insert(
            name.to_uppercase(),
            AmplitudeDef {
                curve: crate::explicit::Amplitude { smooth, points },
                at,
            },
        );
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
        if self.op_new(l, kw, opts)? {
            self.step_mut(l, kw)?.cload_new = true;
        }
        let amplitude = opts.get("AMPLITUDE").map(|s| s.to_uppercase());
        if let Some(a) = &amplitude {
            if !self.deck.analysis.amplitudes.contains_key(a) {
                return Err(err(l, format!("*CLOAD: amplitude {a} is not defined")));
            }
        }
        let step = self.step_number();
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
                step,
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
                step: self.step_number(),
                at,
            });
        }
        Ok(())
    }

    /// The step being read (1 for the first `*STEP`), or 0 in the model data.
    pub(in crate::io::inp) fn step_number(&self) -> usize {
        if self.in_step {
            self.deck.analysis.steps.len()
        } else {
            0
        }
    }

    /// `OP=`: whether it is `NEW` (in a step: what earlier steps gave is removed); `MOD`, the
    /// default, is false; anything else an error.
    fn op_new(&self, l: &Line, kw: &str, opts: &BTreeMap<String, String>) -> Result<bool> {
        match opts.get("OP").map(|s| s.to_uppercase()).as_deref() {
            None | Some("MOD") => Ok(false),
            Some("NEW") if self.in_step => Ok(true),
            Some("NEW") => Err(err(l, format!("*{kw}: OP=NEW belongs in a step"))),
            Some(op) => Err(err(
                l,
                format!("*{kw}: OP={op} is not supported by abut (MOD, the default, or NEW)"),
            )),
        }
    }
}
