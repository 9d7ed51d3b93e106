//! Rigid parts on the host: each part's centre of mass and inverse rotational inertia in the
//! model frame, followed from its nodes' positions every host-array increment, for the penalty
//! springs on it ([`crate::penalty::RigidState`]).

use crate::geometry::V3;
use crate::model::Model;
use crate::penalty::RigidState;

/// One rigid part: its nodes, the reference frame its rotation is read from, and its state.
#[derive(Clone, Debug)]
pub(crate) struct RigidPartRun {
    nodes: Vec<u32>,
    /// Three nodes spanning the part (a, the farthest from a, the farthest from the line a–b).
    triple: [u32; 3],
    /// The frame (columns) of `triple` at the model's positions.
    frame0: [[f64; 3]; 3],
    /// Inverse inertia at the model's positions, model frame.
    inv_inertia0: [[f64; 3]; 3],
    /// Planar model: the frame's third axis is z.
    planar: bool,
    /// The state at the last positions given.
    pub(super) state: RigidState,
}

fn v(x: &[[f64; 3]], n: u32) -> V3<f64> {
    V3::from_array(x[n as usize])
}

/// An orthonormal frame (columns) from a, b, c: e1 along b − a, e2 towards c in the plane,
/// e3 = e1 × e2; planar: e3 = z. Degenerate spans fall back to the standard axes.
fn frame(x: &[[f64; 3]], t: [u32; 3], planar: bool) -> [[f64; 3]; 3] {
    let (a, b, c) = (v(x, t[0]), v(x, t[1]), v(x, t[2]));
    let d = b - a;
    let l = d.length2().sqrt();
    if l == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let e1 = d * (1.0 / l);
    let (e2, e3) = if planar {
        let e3 = V3::new(0.0, 0.0, 1.0);
        (e3.cross(e1), e3)
    } else {
        let w = c - a;
        let w = w - e1 * w.dot(e1);
        let lw = w.length2().sqrt();
        let e2 = if lw > 1e-9 * l {
            w * (1.0 / lw)
        } else {
            // collinear: any perpendicular (a rotation about the line is not seen)
            let (t1, _) = crate::geometry::tangent_directions(e1);
            t1
        };
        (e2, e1.cross(e2))
    };
    let (e1, e2, e3) = (e1.to_array(), e2.to_array(), e3.to_array());
    [0, 1, 2].map(|r| [e1[r], e2[r], e3[r]])
}

fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|r| [0, 1, 2].map(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

fn transpose(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|r| [0, 1, 2].map(|c| a[c][r]))
}

/// The inverse of a symmetric positive-definite 3 × 3 matrix (checked when the part was added).
fn inverse(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let cof = [
        [c(1, 2, 1, 2), -c(1, 2, 0, 2), c(1, 2, 0, 1)],
        [-c(0, 2, 1, 2), c(0, 2, 0, 2), -c(0, 2, 0, 1)],
        [c(0, 1, 1, 2), -c(0, 1, 0, 2), c(0, 1, 0, 1)],
    ];
    let det = m[0][0] * cof[0][0] + m[0][1] * cof[0][1] + m[0][2] * cof[0][2];
    // the adjugate is the cofactors' transpose
    [0, 1, 2].map(|r| [0, 1, 2].map(|c| cof[c][r] / det))
}

fn centroid(x: &[[f64; 3]], nodes: &[u32]) -> [f64; 3] {
    let mut s = V3::new(0.0, 0.0, 0.0);
    for &n in nodes {
        s = s + v(x, n);
    }
    (s * (1.0 / nodes.len() as f64)).to_array()
}

impl RigidPartRun {
    /// The model's rigid parts at the model's positions.
    pub(super) fn all(model: &Model) -> Vec<Self> {
        let planar = model.dim() == 2;
        model
            .rigid_parts()
            .iter()
            .map(|p| Self::of(p, model.positions(), planar))
            .collect()
    }

    /// One whole part by itself: its nodes at `positions` (in the part's order, the same on
    /// every rank), its `mass` and `inertia` (about the nodes' centroid, model frame at those
    /// positions) — the same state, to the bit, as the part in a whole model gets from the same
    /// positions of its nodes (a distributed run's local models hold only some of them).
    #[cfg(feature = "mpi")]
    pub(crate) fn whole(
        positions: &[[f64; 3]],
        mass: f64,
        inertia: [[f64; 3]; 3],
        planar: bool,
    ) -> Self {
        let part = crate::model::RigidPart {
            nodes: (0..positions.len() as u32).collect(),
            mass,
            inertia,
        };
        Self::of(&part, positions, planar)
    }

    /// The state of the last positions given.
    #[cfg(feature = "mpi")]
    pub(crate) fn state(&self) -> RigidState {
        self.state
    }

    /// Part `p` at the positions `x` (indexed by its nodes' ids).
    fn of(p: &crate::model::RigidPart, x: &[[f64; 3]], planar: bool) -> Self {
        let a = p.nodes[0];
        let far = |from: &dyn Fn(u32) -> f64| {
            // the first of the largest, for the same choice every run
            let mut best = (a, -1.0);
            for &n in &p.nodes {
                let d = from(n);
                if d > best.1 {
                    best = (n, d);
                }
            }
            best.0
        };
        let b = far(&|n| (v(x, n) - v(x, a)).length2());
        let c = far(&|n| (v(x, n) - v(x, a)).cross(v(x, b) - v(x, a)).length2());
        let triple = [a, b, c];
        let inv_inertia0 = inverse(&p.inertia);
        Self {
            nodes: p.nodes.clone(),
            triple,
            frame0: frame(x, triple, planar),
            inv_inertia0,
            planar,
            state: RigidState {
                centre: centroid(x, &p.nodes),
                inv_mass: 1.0 / p.mass,
                inv_inertia: inv_inertia0,
            },
        }
    }

    /// Follows the part to positions `x`: its centroid, and its inverse inertia turned by the
    /// rotation R = F·F₀ᵀ of its frame (J = R·J₀·Rᵀ).
    pub(crate) fn update(&mut self, x: &[[f64; 3]]) {
        let f = frame(x, self.triple, self.planar);
        let r = mul(&f, &transpose(&self.frame0));
        self.state.centre = centroid(x, &self.nodes);
        self.state.inv_inertia = mul(&mul(&r, &self.inv_inertia0), &transpose(&r));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rotated and moved part reports its centroid and R·J₀·Rᵀ.
    #[test]
    fn follows_rotation_and_translation() {
        let mut m = Model::new_3d();
        let x0 = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 1.0, 0.5],
        ];
        m.add_nodes(&x0, &[1.0; 4]).unwrap();
        let inertia = [[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]];
        m.add_rigid_part(&[0, 1, 2, 3], 5.0, inertia).unwrap();
        let mut p = RigidPartRun::all(&m).remove(0);
        let (s, c) = (0.6f64, 0.8f64); // 36.87° about z, then moved
        let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let x: Vec<[f64; 3]> = x0
            .iter()
            .map(|q| {
                let r = [0, 1, 2].map(|i| (0..3).map(|k| rot[i][k] * q[k]).sum::<f64>());
                [r[0] + 1.0, r[1] - 2.0, r[2] + 3.0]
            })
            .collect();
        p.update(&x);
        let want = mul(&mul(&rot, &inverse(&inertia)), &transpose(&rot));
        for i in 0..3 {
            for j in 0..3 {
                assert!((p.state.inv_inertia[i][j] - want[i][j]).abs() < 1e-12);
            }
        }
        let cx = centroid(&x, &[0, 1, 2, 3]);
        assert_eq!(p.state.centre, cx);
        assert!((p.state.inv_mass - 0.2).abs() < 1e-15);
    }
}
