//! Rigid bodies of the explicit solver: a reference point's translation and a rotation,
//! integrated with the same half-step velocities as the nodes, carrying mesh nodes (a meshed
//! rigid surface) and, through [`BodyState`], an analytical surface of the contact model.

use crate::error::{Error, Result};
use crate::geometry::V3;
use crate::kinematic::BodyState;

/// How a rigid body moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyMotion {
    /// Moved by gravity, contact and the loads on its nodes.
    Free,
    /// Held where it starts.
    Fixed,
    /// Translates at this constant velocity, without rotating.
    Velocity([f64; 3]),
}

/// A rigid body of the explicit solver.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverBody {
    /// Mass (> 0).
    pub mass: f64,
    /// Rotational inertia about the reference point, body frame (symmetric positive definite).
    pub inertia: [[f64; 3]; 3],
    /// State: reference point, rotation, half-step velocities.
    pub state: BodyState,
    /// How it moves.
    pub motion: BodyMotion,
    /// Mesh nodes it carries.
    pub nodes: Vec<u32>,
    /// Body-frame offsets of `nodes` from the reference point.
    pub offsets: Vec<[f64; 3]>,
    /// Translations held at their initial velocity (x, y, z) — symmetry planes of a model
    /// that cuts the body.
    pub locked: [bool; 3],
    /// Rotation held (the angular velocity stays zero).
    pub rotation_locked: bool,
    /// A force on the body at its reference point, model force units (beside the loads on the
    /// nodes it carries); free bodies only.
    pub load: [f64; 3],
    /// A moment on the body, model force × length units; free bodies only.
    pub moment: [f64; 3],
    /// How many mesh nodes the whole body carries (a rank's share of it carries only some of
    /// them, or none, in `nodes`).
    pub(crate) whole_nodes: usize,
}

pub(crate) fn v3(a: [f64; 3]) -> V3<f64> {
    V3::from_array(a)
}

/// `r · a` for a row-major rotation.
pub(crate) fn rotate(r: &[[f64; 3]; 3], a: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| r[i][0] * a[0] + r[i][1] * a[1] + r[i][2] * a[2])
}

/// The inertia in the model frame, R·I·Rᵀ.
pub(crate) fn world_inertia(r: &[[f64; 3]; 3], i: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            let mut s = 0.0;
            for c in 0..3 {
                for d in 0..3 {
                    s += r[a][c] * i[c][d] * r[b][d];
                }
            }
            out[a][b] = s;
        }
    }
    out
}

/// Solves the symmetric positive definite 3×3 system `m·x = b` (Cramer).
pub(crate) fn solve3(m: &[[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    [0, 1, 2].map(|k| {
        let mut mk = *m;
        for r in 0..3 {
            mk[r][k] = b[r];
        }
        det(&mk) / d
    })
}

/// The rotation exp(θ×) by Rodrigues' formula, composed in front of `r`.
pub(crate) fn rotate_by(r: &[[f64; 3]; 3], theta: [f64; 3]) -> [[f64; 3]; 3] {
    let t = v3(theta);
    let angle = t.length2().sqrt();
    if angle == 0.0 {
        return *r;
    }
    let k = t * (1.0 / angle);
    let (s, c) = angle.sin_cos();
    let k = k.to_array();
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let mut q = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            let kk: f64 = (0..3).map(|m| kx[a][m] * kx[m][b]).sum();
            q[a][b] = if a == b { 1.0 } else { 0.0 } + s * kx[a][b] + (1.0 - c) * kk;
        }
    }
    let mut out = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            out[a][b] = (0..3).map(|m| q[a][m] * r[m][b]).sum();
        }
    }
    out
}

impl SolverBody {
    /// A body of `mass` and body-frame `inertia` whose reference point is at `position`
    /// (not rotated, at rest), carrying `nodes` at their current positions `x`.
    ///
    /// Errors: a mass that is not finite and positive, an inertia that is not symmetric
    /// positive definite, a node out of range.
    pub fn new(
        mass: f64,
        inertia: [[f64; 3]; 3],
        position: [f64; 3],
        nodes: Vec<u32>,
        x: &[[f64; 3]],
        motion: BodyMotion,
    ) -> Result<Self> {
        crate::model::RigidBody {
            mass,
            inertia,
            surface: crate::model::Analytical::Sphere {
                centre: position,
                radius: 1.0,
            },
        }
        .validate(3)?;
        if let Some(&n) = nodes.iter().find(|&&n| n as usize >= x.len()) {
            return Err(Error::IndexOutOfRange {
                what: "rigid body node".into(),
                index: n as u64,
                len: x.len(),
            });
        }
        let offsets = nodes
            .iter()
            .map(|&n| (v3(x[n as usize]) - v3(position)).to_array())
            .collect();
        let mut state = BodyState::at(position);
        if let BodyMotion::Velocity(u) = motion {
            state.velocity = u;
        }
        Ok(Self {
            mass,
            inertia,
            state,
            motion,
            whole_nodes: nodes.len(),
            nodes,
            offsets,
            locked: [false; 3],
            rotation_locked: false,
            load: [0.0; 3],
            moment: [0.0; 3],
        })
    }

    /// Translational plus rotational kinetic energy at velocity `v` and angular velocity `w`.
    pub(crate) fn kinetic(&self, v: [f64; 3], w: [f64; 3]) -> f64 {
        let iw = world_inertia(&self.state.rotation, &self.inertia);
        let lw = rotate(&iw, w);
        0.5 * self.mass * v3(v).length2() + 0.5 * v3(w).dot(v3(lw))
    }

    /// Updates the half-step velocities by `h` under force `f` and moment `m` about the
    /// reference point (free bodies; fixed and prescribed ones keep theirs).
    pub(crate) fn accelerate(&mut self, f: [f64; 3], m: [f64; 3], h: f64) {
        if self.motion != BodyMotion::Free {
            return;
        }
        let iw = world_inertia(&self.state.rotation, &self.inertia);
        let w = self.state.angular_velocity;
        let gyro = v3(w).cross(v3(rotate(&iw, w))).to_array();
        let alpha = solve3(&iw, [0, 1, 2].map(|a| m[a] - gyro[a]));
        for a in 0..3 {
            self.state.velocity[a] += h * f[a] / self.mass;
            self.state.angular_velocity[a] += h * alpha[a];
        }
        self.hold();
    }

    /// Zeroes the locked velocity components.
    pub(crate) fn hold(&mut self) {
        for a in 0..3 {
            if self.locked[a] {
                self.state.velocity[a] = 0.0;
            }
        }
        if self.rotation_locked {
            self.state.angular_velocity = [0.0; 3];
        }
    }

    /// Moves the body by `dt` at its velocities.
    pub(crate) fn advance(&mut self, dt: f64) {
        for a in 0..3 {
            self.state.position[a] += dt * self.state.velocity[a];
        }
        let w = self.state.angular_velocity;
        self.state.rotation = rotate_by(&self.state.rotation, [w[0] * dt, w[1] * dt, w[2] * dt]);
    }

    /// Puts the carried nodes where the body is, with its velocities.
    pub(crate) fn place_nodes(&self, x: &mut [[f64; 3]], v: &mut [[f64; 3]]) {
        let s = &self.state;
        for (&n, off) in self.nodes.iter().zip(&self.offsets) {
            let (xn, r) = self.node_at(*off);
            let n = n as usize;
            x[n] = xn;
            let wr = v3(s.angular_velocity).cross(v3(r)).to_array();
            for a in 0..3 {
                v[n][a] = s.velocity[a] + wr[a];
            }
        }
    }

    /// The resultant force and moment (about the reference point) of nodal forces `f` on the
    /// carried nodes at positions `x`.
    /// Only the nodes `counted` marks, when given (a rank's own nodes: the ranks' shares add up
    /// to the body's).
    pub(crate) fn resultant(
        &self,
        x: &[[f64; 3]],
        f: &[[f64; 3]],
        counted: Option<&[bool]>,
    ) -> ([f64; 3], [f64; 3]) {
        fold_rows(&self.resultant_rows(x, f, counted))
    }

    /// The rows [`Self::resultant`] adds, in the order of the body's nodes: each counted node
    /// with a force (a zero force changes no sum: left out).
    pub(crate) fn resultant_rows(
        &self,
        x: &[[f64; 3]],
        f: &[[f64; 3]],
        counted: Option<&[bool]>,
    ) -> Vec<ResultantRow> {
        let mut rows = Vec::new();
        for (k, &n) in self.nodes.iter().enumerate() {
            if counted.is_some_and(|c| !c[n as usize]) || f[n as usize] == [0.0; 3] {
                continue;
            }
            let fi = v3(f[n as usize]);
            let mi = (v3(x[n as usize]) - v3(self.state.position)).cross(fi);
            rows.push((k as u32, fi.to_array(), mi.to_array()));
        }
        rows
    }
}

/// One node's share of a body's resultant: its place in the body's nodes, its force, and the
/// force's moment about the body's reference point.
pub type ResultantRow = (u32, [f64; 3], [f64; 3]);

/// The resultant force and moment of `rows`, added in their order.
pub(crate) fn fold_rows(rows: &[ResultantRow]) -> ([f64; 3], [f64; 3]) {
    let mut force = V3::new(0.0, 0.0, 0.0);
    let mut moment = V3::new(0.0, 0.0, 0.0);
    for (_, f, m) in rows {
        force = force + v3(*f);
        moment = moment + v3(*m);
    }
    (force.to_array(), moment.to_array())
}

impl SolverBody {
    /// Where the body puts nodes at body-frame `offsets` now (as [`Self::place_nodes`] puts
    /// its own): a whole body's nodes on a rank that carries only some of them.
    #[cfg(feature = "mpi")]
    pub(crate) fn positions_of(&self, offsets: &[[f64; 3]]) -> Vec<[f64; 3]> {
        offsets.iter().map(|off| self.node_at(*off).0).collect()
    }

    /// A node at body-frame offset `off` now: its position, and the offset turned into the
    /// model frame (the one arithmetic [`Self::place_nodes`] and `positions_of` share, so a
    /// node has the same bits whichever placed it).
    fn node_at(&self, off: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let s = &self.state;
        let r = rotate(&s.rotation, off);
        ([0, 1, 2].map(|a| s.position[a] + r[a]), r)
    }

    /// Whether this body is free and carries mesh nodes (split over ranks, its resultants need
    /// every rank's nodes).
    pub(crate) fn free_meshed(&self) -> bool {
        self.motion == BodyMotion::Free && self.whole_nodes > 0
    }
}
