//! A deck's boundary conditions, initial velocities and loads placed on its deformable parts'
//! nodes: as held or prescribed degrees of freedom and loads on one curve for a deck of one
//! step, as windows of the run's time line ([`super::steps`]) for several steps or loads on
//! several amplitudes. Rigid bodies take theirs from their reference node ([`super::rigid`]).

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::error::Result;
use crate::explicit::{Amplitude, LoadCurve, Motion, Prescribed};
use crate::io::inp::{Analysis, At, BoundaryKind};
use crate::io::MeshData;

use super::steps::{self, Timeline};
use super::{refuse, DeckPiece};

/// Where the deck's nodes went and how its steps lie.
pub(super) struct Place<'a> {
    /// The deck's analysis data.
    pub a: &'a Analysis,
    /// The deck's mesh.
    pub mesh: &'a MeshData,
    /// Each deck node's part (`usize::MAX`: none).
    pub piece_of: &'a [usize],
    /// Each deck node's index in its part.
    pub local: &'a [u32],
    /// The rigid bodies' reference nodes.
    pub ref_nodes: &'a BTreeMap<u32, usize>,
    /// The steps' times.
    pub timeline: &'a Timeline,
    /// A plane model (z is not a degree of freedom).
    pub two_d: bool,
    /// The deck has several steps.
    pub several: bool,
    /// Loads on their own curves (several steps or several amplitudes).
    pub load_curves: bool,
}

/// A named amplitude's curve in step time (none: the deck's default).
type AmplitudeOf<'a> = dyn Fn(&Option<String>) -> Arc<Amplitude> + 'a;

impl Place<'_> {
    /// Node `n`'s part and index there when it is a deformable part's (none: a reference node
    /// or a node on nothing); an error for a node carried by a rigid body.
    fn on_deformable(
        &self,
        pieces: &[DeckPiece],
        n: u32,
        at: &At,
        what: &str,
    ) -> Result<Option<(usize, usize)>> {
        let p = self.piece_of[n as usize];
        if self.ref_nodes.contains_key(&n) || p == usize::MAX {
            return Ok(None);
        }
        if pieces[p].rigid.is_some() {
            return refuse(
                at,
                format!(
                    "{what} on node {} of a rigid body: hold, move or load its reference node",
                    self.mesh.node_labels[n as usize]
                ),
            );
        }
        Ok(Some((p, self.local[n as usize] as usize)))
    }

    /// `*BOUNDARY`: held degrees of freedom and prescribed motions; rotations (and z in a plane
    /// model) left out, noted.
    pub fn boundaries(
        &self,
        pieces: &mut [DeckPiece],
        amplitude: &AmplitudeOf,
        notes: &mut Vec<String>,
    ) -> Result<()> {
        let a = self.a;
        let dropped = a
            .boundaries
            .iter()
            .any(|b| b.last > 3 || (self.two_d && b.last == 3));
        if dropped {
            notes.push("*BOUNDARY on degrees of freedom a solid node does not have (rotations, or z in a plane model): not applied, as Abaqus does".into());
        }
        if self.several {
            let windows = steps::boundary_windows(a, self.timeline, self.two_d, amplitude);
            for ((n, axis), windows) in windows {
                let at = a
                    .boundaries
                    .iter()
                    .find(|b| b.nodes.contains(&n))
                    .map_or(&a.steps[0].at, |b| &b.at);
                let Some((p, i)) = self.on_deformable(pieces, n, at, "*BOUNDARY")? else {
                    continue;
                };
                let x0 = pieces[p].mesh.positions[i][axis];
                for w in windows {
                    if w.fixed {
                        pieces[p].fixed[i][axis] = true;
                        continue;
                    }
                    let mut m = Prescribed::new(i as u32, axis, w.motion);
                    m.active = w.active;
                    m.origin = w.total.then_some(x0);
                    pieces[p].prescribed.push(m);
                }
            }
            return Ok(());
        }
        for b in &a.boundaries {
            for &n in &b.nodes {
                let Some((p, i)) = self.on_deformable(pieces, n, &b.at, "*BOUNDARY")? else {
                    continue;
                };
                for d in b.first..=b.last.min(if self.two_d { 2 } else { 3 }) {
                    let axis = d - 1;
                    if b.value == 0.0 && b.kind == BoundaryKind::Displacement {
                        pieces[p].fixed[i][axis] = true;
                    } else {
                        pieces[p].prescribed.push(Prescribed::new(
                            i as u32,
                            axis,
                            Motion::Amplitude {
                                value: b.value,
                                amplitude: amplitude(&b.amplitude),
                                velocity: b.kind == BoundaryKind::Velocity,
                            },
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// `*INITIAL CONDITIONS, TYPE=VELOCITY` on deformable nodes.
    pub fn initial_velocities(&self, pieces: &mut [DeckPiece]) -> Result<()> {
        for (n, d, v, at) in &self.a.initial_velocities {
            let p = self.piece_of[*n as usize];
            if self.ref_nodes.contains_key(n) || p == usize::MAX {
                continue;
            }
            if pieces[p].rigid.is_some() {
                return refuse(at, "*INITIAL CONDITIONS on a node of a rigid body: give its reference node the velocity");
            }
            pieces[p].velocity[self.local[*n as usize] as usize][d - 1] = *v;
        }
        Ok(())
    }

    /// `*CLOAD` on deformable nodes' translations: summed into the parts' loads (one curve
    /// for all), or each on its own curve and window.
    pub fn loads(&self, pieces: &mut [DeckPiece], amplitude: &AmplitudeOf) -> Result<()> {
        let a = self.a;
        for c in &a.cloads {
            for &n in &c.nodes {
                let Some((p, i)) = self.on_deformable(pieces, n, &c.at, "*CLOAD")? else {
                    continue;
                };
                if c.dof > 3 {
                    return refuse(&c.at, format!("*CLOAD on node {}: loads go on deformable nodes' translations or a rigid body's reference node", self.mesh.node_labels[n as usize]));
                }
                if !self.load_curves {
                    pieces[p].loads[i][c.dof - 1] += c.value;
                }
            }
        }
        if !self.load_curves {
            return Ok(());
        }
        for ((n, axis), windows) in steps::load_windows(a, self.timeline, amplitude) {
            let p = self.piece_of[n as usize];
            if self.ref_nodes.contains_key(&n) || p == usize::MAX {
                continue;
            }
            let i = self.local[n as usize];
            for w in windows {
                pieces[p].load_curves.push(LoadCurve {
                    node: i,
                    dof: axis,
                    value: w.value,
                    amplitude: w.amplitude,
                    active: w.active,
                });
            }
        }
        Ok(())
    }
}
