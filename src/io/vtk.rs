//! The contact state as VTK XML for ParaView: one `.vtu` (UnstructuredGrid, ASCII) per frame
//! and a `.pvd` collection over the frames.
//!
//! A frame's points are every model node at its current position. Its cells are the master
//! facets of every pair (lines, triangles, quads) followed by one vertex per slave node.
//! Point data, per slave node (zero elsewhere): `CSTATUS` (0 open, 1 stick, 2 slip; −1 not a
//! slave), `COPEN`, `CPRESS`, `CSHEAR1`, `CSHEAR2`, `CFORCE` (the contact force on the node,
//! 3 components). Cell data: `FACET_FORCE`, the contact force the slaves put on each master
//! facet (the reaction of their forces; zero on the vertex cells), and `KIND` (0 master facet,
//! 1 slave vertex).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::contact::{Contact, ContactStatus, PairOutput};
use crate::error::{Error, Result};
use crate::model::{Facet, Model};

/// One frame of contact output, ready to write.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Every model node's position.
    pub positions: Vec<[f64; 3]>,
    /// Master facets.
    pub facets: Vec<Facet>,
    /// Contact force on each master facet.
    pub facet_force: Vec<[f64; 3]>,
    /// Slave nodes, each once.
    pub slaves: Vec<u32>,
    /// Per model node: CSTATUS code (−1 not a slave).
    pub cstatus: Vec<i32>,
    /// Per model node: COPEN.
    pub copen: Vec<f64>,
    /// Per model node: CPRESS.
    pub cpress: Vec<f64>,
    /// Per model node: CSHEAR1.
    pub cshear1: Vec<f64>,
    /// Per model node: CSHEAR2.
    pub cshear2: Vec<f64>,
    /// Per model node: contact force.
    pub force: Vec<[f64; 3]>,
}

fn finite(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

impl Frame {
    /// The frame of `contact`'s last increment (its outputs must have been requested:
    /// [`Contact::request_outputs`]) at `positions`.
    pub fn from_contact(model: &Model, contact: &Contact, positions: &[[f64; 3]]) -> Result<Self> {
        let n = positions.len();
        let mut f = Frame {
            positions: positions.to_vec(),
            cstatus: vec![-1; n],
            copen: vec![0.0; n],
            cpress: vec![0.0; n],
            cshear1: vec![0.0; n],
            cshear2: vec![0.0; n],
            force: vec![[0.0; 3]; n],
            ..Default::default()
        };
        let mut add = |o: &PairOutput, facets: Option<&[Facet]>| {
            let base = f.facets.len();
            if let Some(fs) = facets {
                f.facets.extend_from_slice(fs);
                f.facet_force
                    .extend(std::iter::repeat_n([0.0; 3], fs.len()));
            }
            for (i, &s) in o.slaves.iter().enumerate() {
                let s = s as usize;
                if f.cstatus[s] < 0 {
                    f.slaves.push(s as u32);
                    f.cstatus[s] = 0;
                }
                let status = match o.cstatus.get(i).copied().flatten() {
                    Some(ContactStatus::Stick) => 1,
                    Some(ContactStatus::Slip) => 2,
                    _ => 0,
                };
                f.cstatus[s] = f.cstatus[s].max(status);
                if let Some(&g) = o.copen.get(i) {
                    f.copen[s] = finite(g);
                }
                f.cpress[s] += o.cpress.get(i).copied().map_or(0.0, finite);
                f.cshear1[s] += o.cshear1.get(i).copied().map_or(0.0, finite);
                f.cshear2[s] += o.cshear2.get(i).copied().map_or(0.0, finite);
                let fs = o.force.get(i).copied().unwrap_or([0.0; 3]);
                for a in 0..3 {
                    f.force[s][a] += finite(fs[a]);
                }
                if facets.is_some() {
                    if let Some(c) = o.search.as_ref().and_then(|r| r.contact(i)) {
                        let k = base + c.facet as usize;
                        if k < f.facet_force.len() {
                            for a in 0..3 {
                                f.facet_force[k][a] -= finite(fs[a]);
                            }
                        }
                    }
                }
            }
        };
        for (id, o) in contact.outputs() {
            let pair = model.pair(id)?;
            let forward = model.node_set(pair.slave)? == o.slaves.as_slice();
            let surface = if forward {
                pair.master
            } else {
                pair.balanced.map(|(s, _)| s).unwrap_or(pair.master)
            };
            let facets = model.surface(surface)?.facets.clone();
            add(o, Some(&facets));
        }
        for (_, o) in contact.rigid_outputs() {
            add(o, None);
        }
        Ok(f)
    }

    /// The frame as VTK XML UnstructuredGrid text.
    pub fn to_vtu(&self) -> String {
        let mut s = String::new();
        let n_cells = self.facets.len() + self.slaves.len();
        let _ = writeln!(s, "<?xml version=\"1.0\"?>");
        let _ = writeln!(s, "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">");
        let _ = writeln!(s, "<UnstructuredGrid>");
        let _ = writeln!(
            s,
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n_cells}\">",
            self.positions.len()
        );
        let _ = writeln!(s, "<Points>");
        array3(&mut s, "Points", self.positions.iter());
        let _ = writeln!(s, "</Points>");
        let _ = writeln!(s, "<Cells>");
        let mut conn = String::new();
        let mut offsets = String::new();
        let mut types = String::new();
        let mut off = 0usize;
        for f in &self.facets {
            for n in f.nodes() {
                let _ = write!(conn, "{n} ");
            }
            off += f.nodes().len();
            let _ = write!(offsets, "{off} ");
            let _ = write!(
                types,
                "{} ",
                match f {
                    Facet::Segment(_) => 3,
                    Facet::Triangle(_) => 5,
                    Facet::Quad(_) => 9,
                }
            );
        }
        for &sl in &self.slaves {
            let _ = write!(conn, "{sl} ");
            off += 1;
            let _ = write!(offsets, "{off} ");
            types.push_str("1 ");
        }
        let _ = writeln!(
            s,
            "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n{}\n</DataArray>",
            conn.trim_end()
        );
        let _ = writeln!(
            s,
            "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n{}\n</DataArray>",
            offsets.trim_end()
        );
        let _ = writeln!(
            s,
            "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n{}\n</DataArray>",
            types.trim_end()
        );
        let _ = writeln!(s, "</Cells>");
        let _ = writeln!(s, "<PointData Scalars=\"CPRESS\" Vectors=\"CFORCE\">");
        let _ = writeln!(
            s,
            "<DataArray type=\"Int32\" Name=\"CSTATUS\" format=\"ascii\">\n{}\n</DataArray>",
            join(self.cstatus.iter())
        );
        for (name, v) in [
            ("COPEN", &self.copen),
            ("CPRESS", &self.cpress),
            ("CSHEAR1", &self.cshear1),
            ("CSHEAR2", &self.cshear2),
        ] {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">\n{}\n</DataArray>",
                join(v.iter().map(|x| fmt(*x)))
            );
        }
        array3(&mut s, "CFORCE", self.force.iter());
        let _ = writeln!(s, "</PointData>");
        let _ = writeln!(s, "<CellData Vectors=\"FACET_FORCE\">");
        let zeros = vec![[0.0; 3]; self.slaves.len()];
        array3(&mut s, "FACET_FORCE", self.facet_force.iter().chain(&zeros));
        let kinds = std::iter::repeat_n(0, self.facets.len())
            .chain(std::iter::repeat_n(1, self.slaves.len()));
        let _ = writeln!(
            s,
            "<DataArray type=\"Int32\" Name=\"KIND\" format=\"ascii\">\n{}\n</DataArray>",
            join(kinds)
        );
        let _ = writeln!(s, "</CellData>");
        let _ = writeln!(s, "</Piece>\n</UnstructuredGrid>\n</VTKFile>");
        s
    }

    /// Writes the frame to `path` (`.vtu`).
    pub fn write(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.to_vtu()).map_err(|e| Error::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        })
    }
}

fn fmt(x: f64) -> String {
    // shortest text that reads back to the same f64
    format!("{:?}", finite(x))
}

fn join<T: std::fmt::Display>(it: impl Iterator<Item = T>) -> String {
    let mut s = String::new();
    for v in it {
        let _ = write!(s, "{v} ");
    }
    s.trim_end().to_string()
}

fn array3<'a>(s: &mut String, name: &str, it: impl Iterator<Item = &'a [f64; 3]>) {
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
    );
    let mut line = String::new();
    for v in it {
        let _ = write!(line, "{} {} {} ", fmt(v[0]), fmt(v[1]), fmt(v[2]));
    }
    let _ = writeln!(s, "{}\n</DataArray>", line.trim_end());
}

/// A time series of frames: `NAME_0000.vtu`, … and `NAME.pvd` in a directory.
#[derive(Clone, Debug)]
pub struct Series {
    dir: PathBuf,
    name: String,
    frames: Vec<(f64, String)>,
}

impl Series {
    /// A series named `name` in `dir` (created if missing).
    pub fn new(dir: &Path, name: &str) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| Error::Io {
            file: dir.display().to_string(),
            message: e.to_string(),
        })?;
        Ok(Self {
            dir: dir.to_path_buf(),
            name: name.to_string(),
            frames: Vec::new(),
        })
    }

    /// Writes `frame` at `time` and rewrites the `.pvd` collection so that it always lists
    /// exactly the frames written so far.
    pub fn add(&mut self, time: f64, frame: &Frame) -> Result<()> {
        let file = format!("{}_{:04}.vtu", self.name, self.frames.len());
        frame.write(&self.dir.join(&file))?;
        self.frames.push((time, file));
        let mut s = String::new();
        let _ = writeln!(s, "<?xml version=\"1.0\"?>");
        let _ = writeln!(
            s,
            "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">"
        );
        let _ = writeln!(s, "<Collection>");
        for (t, f) in &self.frames {
            let _ = writeln!(
                s,
                "<DataSet timestep=\"{}\" part=\"0\" file=\"{f}\"/>",
                fmt(*t)
            );
        }
        let _ = writeln!(s, "</Collection>\n</VTKFile>");
        let pvd = self.dir.join(format!("{}.pvd", self.name));
        std::fs::write(&pvd, s).map_err(|e| Error::Io {
            file: pvd.display().to_string(),
            message: e.to_string(),
        })
    }

    /// Frames written so far: (time, file name).
    pub fn frames(&self) -> &[(f64, String)] {
        &self.frames
    }
}
