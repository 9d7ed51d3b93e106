//! The checks of a scene file, one function per table: every value in range and every name
//! found before anything is built, each error naming the key, the value and the entry.

use std::collections::HashSet;

use super::spec::*;
use crate::error::Result;

impl Scene {
    /// Every table in turn: the run, the parts (names unique across parts and rigid bodies),
    /// the materials, the rigid bodies, the boundaries and the contacts.
    pub(super) fn check(&self) -> std::result::Result<(), Located> {
        self.check_run()
            .map_err(|error| Located { error, entry: None })?;
        let two_d = self.is_2d();
        let mut names = HashSet::new();
        for (i, p) in self.part.iter().enumerate() {
            self.check_part(p, two_d, &mut names)
                .map_err(|error| Located {
                    error,
                    entry: Some(("part", i)),
                })?;
        }
        for (i, m) in self.material.iter().enumerate() {
            self.check_material(m).map_err(|error| Located {
                error,
                entry: Some(("material", i)),
            })?;
        }
        for (i, b) in self.rigid.iter().enumerate() {
            self.check_rigid(b, &mut names).map_err(|error| Located {
                error,
                entry: Some(("rigid", i)),
            })?;
        }
        for (i, b) in self.boundary.iter().enumerate() {
            self.check_boundary(b).map_err(|error| Located {
                error,
                entry: Some(("boundary", i)),
            })?;
        }
        for (i, c) in self.contact.iter().enumerate() {
            self.check_contact(c).map_err(|error| Located {
                error,
                entry: Some(("contact", i)),
            })?;
        }
        Ok(())
    }

    /// The `[run]` table, and that there is a part at all.
    fn check_run(&self) -> Result<()> {
        let r = &self.run;
        if !(r.end_time.is_finite() && r.end_time > 0.0) {
            return bad(
                "run.end_time",
                num(r.end_time),
                "must be finite and positive",
            );
        }
        for (key, v) in [
            ("run.safety", r.safety),
            ("run.contact_safety", r.contact_safety),
        ] {
            if !(v > 0.0 && v <= 1.0) {
                return bad(key, num(v), "must lie in (0, 1]");
            }
        }
        if let Some(dt) = r.dt {
            if !(dt.is_finite() && dt > 0.0) {
                return bad("run.dt", num(dt), "must be finite and positive");
            }
        }
        for (key, v) in [
            ("run.damping", r.damping),
            ("run.bulk_viscosity", r.bulk_viscosity),
            ("run.bulk_viscosity_quadratic", r.bulk_viscosity_quadratic),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(key, num(v), "must be finite and not negative");
            }
        }
        finite_values("run.gravity", &r.gravity, "run")?;
        if self.part.is_empty() {
            return bad("part", "none".into(), "a scene needs at least one [[part]]");
        }
        Ok(())
    }

    /// One `[[part]]` entry.
    fn check_part<'a>(
        &'a self,
        p: &'a PartSpec,
        two_d: bool,
        names: &mut HashSet<&'a str>,
    ) -> Result<()> {
        if !names.insert(p.name.as_str()) {
            return bad("part.name", p.name.clone(), "must be unique");
        }
        if !SHAPES.contains(&p.shape.as_str()) {
            return bad(
                "part.shape",
                format!("{} (part {})", p.shape, p.name),
                "must be block, rect, bar, plate, line, arc, sphere, points or mesh",
            );
        }
        if two_d && matches!(p.shape.as_str(), "block" | "plate" | "sphere" | "bar") {
            return bad(
                "part.shape",
                format!("{} (part {}) with 2D parts", p.shape, p.name),
                "a scene is either 2D (rect, line, arc, points) or 3D",
            );
        }
        let axes = match p.shape.as_str() {
            "block" => 3,
            "rect" | "plate" => 2,
            "bar" | "line" | "arc" => 1,
            "sphere" => 2,
            _ => 0,
        };
        if p.divisions.iter().take(axes).any(|&d| d == 0) {
            return bad(
                "part.divisions",
                format!("{:?} (part {})", p.divisions, p.name),
                "must be positive for each axis the shape uses",
            );
        }
        // the memory the part would take, estimated before anything is allocated
        let (nodes, cells) = p
            .divisions
            .iter()
            .take(axes)
            .fold((1u128, 1u128), |(n, c), &d| {
                (n * (d as u128 + 1), c * d as u128)
            });
        let bytes = nodes * BYTES_PER_NODE + cells * BYTES_PER_CELL;
        if bytes > MAX_SCENE_BYTES {
            return bad(
                "part.divisions",
                format!(
                    "{:?} (part {}): {nodes} nodes and {cells} cells, about {:.1e} bytes",
                    p.divisions, p.name, bytes as f64
                ),
                "a part must fit in 16 GiB (nodes, elements and their state)",
            );
        }
        let sized = match p.shape.as_str() {
            "block" => 3,
            "rect" | "plate" => 2,
            "line" => 1,
            _ => 0,
        };
        if p.size
            .iter()
            .take(sized)
            .any(|&s| !(s.is_finite() && s > 0.0))
        {
            return bad(
                "part.size",
                format!("{:?} (part {})", p.size, p.name),
                "must be finite and positive",
            );
        }
        let what = format!("part {}", p.name);
        finite_values("part.origin", &p.origin, &what)?;
        finite_values("part.velocity", &p.velocity, &what)?;
        finite_values("part.size", &p.size, &what)?;
        for x in &p.points {
            finite_values("part.points", x, &what)?;
        }
        if p.grading.iter().any(|g| !(g.is_finite() && g.abs() > 0.0)) {
            return bad(
                "part.grading",
                format!("{:?} (part {})", p.grading, p.name),
                "ratios must be finite and non-zero",
            );
        }
        if (0..3).any(|a| p.grading_core[a] > p.divisions[a].max(1)) {
            return bad(
                "part.grading_core",
                format!("{:?} (part {})", p.grading_core, p.name),
                "cannot exceed the divisions along the axis",
            );
        }
        if p.shape == "bar" && p.size.iter().filter(|s| **s != 0.0).count() != 1 {
            return bad(
                "part.size",
                format!("{:?} (bar {})", p.size, p.name),
                "a bar runs along one axis: exactly one non-zero component",
            );
        }
        if matches!(p.shape.as_str(), "arc" | "sphere") {
            positive("part.radius", p.radius, &what)?;
        }
        if p.shape == "points" {
            if p.points.is_empty() {
                return bad(
                    "part.points",
                    format!("part {}", p.name),
                    "points need at least one position",
                );
            }
            positive("part.mass", p.mass, &what)?;
        }
        for (key, v) in [("part.area", p.area), ("part.thickness", p.thickness)] {
            positive(key, v, &what)?;
        }
        let axi_shape = (p.shape == "rect" && p.origin[0] >= 0.0)
            || (p.shape == "mesh" && p.dimension != Some(3) && !p.rigid);
        if p.axisymmetric && !axi_shape {
            return bad(
                "part.axisymmetric",
                format!("part {}", p.name),
                "a rect part with origin x ≥ 0 (x is the radius) or a deformable 2D mesh part",
            );
        }
        if let Some(m) = p.motion.as_deref() {
            if !p.is_rigid() || !["fixed", "free", "velocity"].contains(&m) {
                return bad(
                    "part.motion",
                    format!("{m} (part {})", p.name),
                    "rigid parts only: fixed, free or velocity",
                );
            }
            if m != "fixed" {
                positive(
                    "part.mass",
                    p.mass,
                    &format!("moving rigid part {}", p.name),
                )?;
            }
        }
        if p.shape == "mesh" {
            match p.file.as_deref() {
                Some(f) if f.ends_with(".msh") || f.ends_with(".inp") => {}
                _ => {
                    return bad(
                        "part.file",
                        format!("{:?} (part {})", p.file, p.name),
                        "a mesh part needs a Gmsh .msh or Abaqus .inp file",
                    )
                }
            }
            if !matches!(p.dimension, None | Some(2) | Some(3)) {
                return bad(
                    "part.dimension",
                    format!("{:?} (part {})", p.dimension, p.name),
                    "must be 2 or 3",
                );
            }
        }
        // a deck's part of point masses alone has no material
        let deformable = matches!(p.shape.as_str(), "block" | "rect" | "bar")
            || (p.shape == "mesh"
                && !p.rigid
                && p.deck.as_ref().is_none_or(|d| d.deformable.contains(&true)));
        if deformable
            && !self
                .material
                .iter()
                .any(|m| Some(&m.name) == p.material.as_ref())
        {
            return bad(
                "part.material",
                format!("{:?} (part {})", p.material, p.name),
                "must name a [[material]]",
            );
        }
        Ok(())
    }

    /// One `[[material]]` entry.
    fn check_material(&self, m: &MaterialSpec) -> Result<()> {
        let what = format!("material {}", m.name);
        positive("material.young", m.young, &what)?;
        positive("material.density", m.density, &what)?;
        if !(m.poisson > -1.0 && m.poisson < 0.5) {
            return bad(
                "material.poisson",
                format!("{} ({what})", num(m.poisson)),
                "must lie in (−1, 0.5)",
            );
        }
        Ok(())
    }

    /// One `[[rigid]]` entry.
    fn check_rigid<'a>(&'a self, b: &'a RigidSpec, names: &mut HashSet<&'a str>) -> Result<()> {
        if !names.insert(b.name.as_str()) {
            return bad(
                "rigid.name",
                b.name.clone(),
                "must be unique among parts and bodies",
            );
        }
        if !["plane", "sphere", "cylinder", "line", "circle"].contains(&b.surface.as_str()) {
            return bad(
                "rigid.surface",
                format!("{} (body {})", b.surface, b.name),
                "must be plane, sphere, cylinder, line or circle",
            );
        }
        let what = format!("body {}", b.name);
        finite_values("rigid.point", &b.point, &what)?;
        finite_values("rigid.direction", &b.direction, &what)?;
        finite_values("rigid.velocity", &b.velocity, &what)?;
        positive("rigid.mass", b.mass, &what)?;
        if matches!(b.surface.as_str(), "sphere" | "cylinder" | "circle") {
            positive("rigid.radius", b.radius, &what)?;
        }
        if let Some(i) = &b.inertia {
            for row in i {
                finite_values("rigid.inertia", row, &what)?;
            }
        }
        if let Some(f) = b
            .fix
            .iter()
            .find(|f| axis_of(f).is_none() && *f != "rotation")
        {
            return bad("rigid.fix", f.clone(), "must be x, y, z or rotation");
        }
        if !matches!(
            b.motion.as_deref(),
            None | Some("free" | "fixed" | "velocity")
        ) {
            return bad(
                "rigid.motion",
                format!("{:?} (body {})", b.motion, b.name),
                "must be free, fixed or velocity",
            );
        }
        for (key, v) in [("rigid.load", &b.load), ("rigid.moment", &b.moment)] {
            if let Some(v) = v {
                finite_values(key, v, &what)?;
                if !matches!(b.motion.as_deref(), None | Some("free")) {
                    return bad(
                        key,
                        format!("body {} (motion {:?})", b.name, b.motion),
                        "a free body (a fixed or moving body is held on its path whatever acts on it)",
                    );
                }
            }
        }
        Ok(())
    }

    /// One `[[boundary]]` entry.
    fn check_boundary(&self, b: &BoundarySpec) -> Result<()> {
        let Some(p) = self.part.iter().find(|p| p.name == b.part) else {
            return bad("boundary.part", b.part.clone(), "must name a [[part]]");
        };
        if p.shape != "mesh" && (!FACES.contains(&b.face.as_str()) || b.face == "out") {
            return bad(
                "boundary.face",
                b.face.clone(),
                "must be x-, x+, y-, y+, z-, z+ or all",
            );
        }
        if p.is_rigid() {
            // a free rigid part takes loads (its body sums them); nothing else
            let free = p.motion.as_deref() == Some("free");
            if !free || !b.fix.is_empty() || b.displacement.is_some() || b.load.is_none() {
                return bad(
                    "boundary.part",
                    b.part.clone(),
                    "a rigid part takes only a load, and only when it is free (motion = \"free\"); fixed and moving ones are held already",
                );
            }
        }
        for d in b.fix.iter().chain(&b.directions) {
            if axis_of(d).is_none() {
                return bad(
                    "boundary.fix / boundary.directions",
                    d.clone(),
                    "must be x, y or z",
                );
            }
        }
        let what = format!("part {}, face {}", b.part, b.face);
        if let Some(d) = &b.displacement {
            finite_values("boundary.displacement", d, &what)?;
        }
        if let Some(l) = &b.load {
            finite_values("boundary.load", l, &what)?;
        }
        if b.displacement.is_some() && !(b.ramp.is_finite() && b.ramp > 0.0) {
            return bad(
                "boundary.ramp",
                format!("{} (part {})", num(b.ramp), b.part),
                "a prescribed displacement needs a positive ramp time",
            );
        }
        Ok(())
    }

    /// One `[[contact]]` entry.
    fn check_contact(&self, c: &ContactSpec) -> Result<()> {
        let Some(sp) = self.part.iter().find(|p| p.name == c.slave) else {
            return bad("contact.slave", c.slave.clone(), "must name a [[part]]");
        };
        if sp.is_rigid() && sp.motion.as_deref().is_none_or(|m| m == "fixed") {
            return bad(
                "contact.slave",
                c.slave.clone(),
                "slave nodes must move: not a fixed rigid part",
            );
        }
        if sp.shape != "mesh" && (!FACES.contains(&c.slave_face.as_str()) || c.slave_face == "out")
        {
            return bad(
                "contact.slave_face",
                c.slave_face.clone(),
                "must be x-, x+, y-, y+, z-, z+ or all",
            );
        }
        let master_part = self.part.iter().any(|p| p.name == c.master);
        let master_body = self.rigid.iter().any(|b| b.name == c.master);
        if !master_part && !master_body {
            return bad(
                "contact.master",
                c.master.clone(),
                "must name a [[part]] or a [[rigid]] body",
            );
        }
        let master_mesh = self
            .part
            .iter()
            .any(|p| p.name == c.master && p.shape == "mesh");
        if master_part {
            match c.master_face.as_deref() {
                Some(_) if master_mesh => {}
                Some(f) if FACES.contains(&f) && f != "all" => {}
                _ => {
                    return bad(
                        "contact.master_face",
                        format!("{:?} (master {})", c.master_face, c.master),
                        "a part master needs a face: x-, x+, y-, y+, z-, z+, or out",
                    )
                }
            }
        }
        if !matches!(c.enforce.as_deref(), None | Some("penalty" | "kinematic")) {
            return bad(
                "contact.enforce",
                format!("{:?}", c.enforce),
                "must be \"penalty\" or \"kinematic\"",
            );
        }
        if master_body && c.enforce.as_deref() != Some("kinematic") {
            return bad(
                "contact.enforce",
                format!("{:?} (master {})", c.enforce, c.master),
                "analytical rigid surfaces are enforced kinematically: set enforce = \"kinematic\"",
            );
        }
        if !matches!(
            c.sliding.as_deref(),
            None | Some("finite" | "small" | "infinitesimal")
        ) {
            return bad(
                "contact.sliding",
                format!("{:?}", c.sliding),
                "must be finite, small or infinitesimal",
            );
        }
        let stiffness_rules = [c.penalty_scale, c.stiffness, c.stiffness_per_area]
            .iter()
            .filter(|s| s.is_some())
            .count();
        if stiffness_rules > 1 {
            return bad(
                "contact.penalty_scale / stiffness / stiffness_per_area",
                format!("master {}", c.master),
                "give at most one stiffness rule",
            );
        }
        let what = format!("master {}", c.master);
        if let Some(k) = c.stiffness {
            positive("contact.stiffness", k, &what)?;
        }
        if let Some(k) = c.stiffness_per_area {
            positive("contact.stiffness_per_area", k, &what)?;
        }
        if let Some(f) = c.penalty_scale {
            // a factor on the default stiffness: beyond 10⁸ either way it is a typo, and
            // it would set increments far below any the run could take
            if !(f.is_finite() && (1e-8..=1e8).contains(&f)) {
                return bad(
                    "contact.penalty_scale",
                    format!("{} ({what})", num(f)),
                    "a factor on the default stiffness within 1e±8",
                );
            }
        }
        if let Some(r) = c.search_radius {
            if !(r.is_finite() && r > 0.0) {
                return bad(
                    "contact.search_radius",
                    format!("{} (master {})", num(r), c.master),
                    "must be finite and positive",
                );
            }
        }
        if !matches!(
            c.search_structure.as_deref(),
            None | Some("auto" | "tree" | "buckets")
        ) {
            return bad(
                "contact.search_structure",
                format!("{:?} (master {})", c.search_structure, c.master),
                "must be auto, tree or buckets",
            );
        }
        if c.search_interval == Some(0) {
            return bad(
                "contact.search_interval",
                format!("0 (master {})", c.master),
                "increments from one global search to the next: at least 1",
            );
        }
        if !(c.friction.is_finite() && c.friction >= 0.0) {
            return bad(
                "contact.friction",
                num(c.friction),
                "must be finite and not negative",
            );
        }
        if let Some(z) = c.damping {
            if !(z.is_finite() && (0.0..=1.0).contains(&z)) {
                return bad(
                    "contact.damping",
                    format!("{} (master {})", num(z), c.master),
                    "a fraction of critical damping in [0, 1]",
                );
            }
            if c.enforce.as_deref() == Some("kinematic") {
                return bad(
                    "contact.damping",
                    format!("{} (master {})", num(z), c.master),
                    "penalty contact only: kinematic contact has no springs to damp",
                );
            }
        }
        Ok(())
    }
}

/// A number for a message: as written where that is short (0, and magnitudes from 10⁻⁴ to
/// 10¹⁵), else in scientific notation — never the 301 digits `{}` gives 1e300.
pub(crate) fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}
