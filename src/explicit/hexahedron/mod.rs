//! The 8-node hexahedron of the explicit solver, in Abaqus/Explicit's two forms:
//!
//! - **C3D8, selectively reduced**: the deviatoric strain at the 2×2×2 Gauss points, the
//!   volumetric strain once, at the centroid — no volumetric locking, no hourglass modes;
//! - **C3D8R, reduced**: one point at the centroid, with Flanagan–Belytschko hourglass
//!   stiffness on the four hourglass modes.
//!
//! Both St Venant–Kirchhoff (Green–Lagrange strain, second Piola–Kirchhoff stress) so they stay
//! right under large rotation, or linear strain for NLGEOM=NO. The selectively reduced form is
//! energy-consistent: its strain energy is `Σ_p W_p μ|dev E_p|² + ½ K V0 (tr E_0)²` (W_p the
//! Gauss weight × |J|, E_0 the centroid strain, K the bulk modulus) and its nodal forces are that
//! energy's exact gradient, so a uniform strain (the patch test) is reproduced exactly.
//! The hourglass forces use the Flanagan–Belytschko vectors γ, orthogonal to every linear field
//! of the reference element, so neither a uniform strain nor a rigid motion excites them.

use super::elements::Material;

/// Natural coordinates of the nodes in Abaqus' C3D8 order.
const CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The hourglass stiffness coefficient κ of C3D8R (LS-DYNA's default `QH` for its
/// Flanagan–Belytschko stiffness form; Abaqus' stiffness-type controls are of this order): the
/// hourglass modes get κ times an element's mean membrane stiffness.
pub const HOURGLASS_STIFFNESS: f64 = 0.1;

/// How a hexahedron is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// C3D8: deviatoric at 2×2×2 points, volumetric at the centroid.
    Selective,
    /// C3D8R: one point, with hourglass stiffness.
    Reduced,
}

/// An 8-node hexahedron: its nodes, reference gradients and material.
#[derive(Clone, Debug, PartialEq)]
pub struct Hex8 {
    /// Node indices (Abaqus' C3D8 order, positive volume).
    pub nodes: [u32; 8],
    /// How it is integrated.
    pub integration: Integration,
    /// Reference volume.
    pub volume0: f64,
    /// Reference shape-function gradients averaged over the element (at the centroid of a
    /// parallelepiped).
    pub grad0: [[f64; 3]; 8],
    /// Selective: the gradients at each Gauss point and its weight × |J| (volume share).
    gauss: Vec<([[f64; 3]; 8], f64)>,
    /// Reduced: the four Flanagan–Belytschko hourglass vectors (one entry per node).
    hourglass: [[f64; 8]; 4],
    /// Reduced: the hourglass stiffness (force per length of hourglass displacement).
    hourglass_stiffness: f64,
    /// The element's stable increment (see [`Hex8::stable_increment`]).
    stable: f64,
    /// Material.
    pub material: Material,
}

/// Shape-function derivatives in natural coordinates at `p`.
fn natural_gradients(p: [f64; 3]) -> [[f64; 3]; 8] {
    let mut d = [[0.0; 3]; 8];
    for (a, c) in CORNERS.iter().enumerate() {
        let f = [1.0 + c[0] * p[0], 1.0 + c[1] * p[1], 1.0 + c[2] * p[2]];
        d[a] = [
            0.125 * c[0] * f[1] * f[2],
            0.125 * c[1] * f[0] * f[2],
            0.125 * c[2] * f[0] * f[1],
        ];
    }
    d
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Gradients in space at natural point `p` of the element at positions `xs`, and |J|.
fn spatial_gradients(xs: &[[f64; 3]; 8], p: [f64; 3]) -> ([[f64; 3]; 8], f64) {
    let dn = natural_gradients(p);
    // J_ij = Σ_a x_a,i ∂N_a/∂ξ_j
    let mut j = [[0.0; 3]; 3];
    for (x, d) in xs.iter().zip(&dn) {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += x[r] * d[c];
            }
        }
    }
    let det = det3(&j);
    // ∇N = J⁻ᵀ ∂N/∂ξ: with the cofactor matrix C of J, J⁻ᵀ = C / det
    let mut cof = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            cof[r][c] = j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1];
        }
    }
    let mut g = [[0.0; 3]; 8];
    for (ga, d) in g.iter_mut().zip(&dn) {
        for (r, gr) in ga.iter_mut().enumerate() {
            *gr = (0..3).map(|c| cof[r][c] * d[c]).sum::<f64>() / det;
        }
    }
    (g, det)
}

/// The largest eigenvalue of the symmetric positive semi-definite Σ_a g_a g_aᵀ (bounded from
/// above by its trace, refined by the Gershgorin row sums when they are smaller).
fn gradient_norm_bound(g: &[[f64; 3]; 8]) -> f64 {
    let mut m = [[0.0; 3]; 3];
    for ga in g {
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] += ga[r] * ga[c];
            }
        }
    }
    let trace = m[0][0] + m[1][1] + m[2][2];
    let gershgorin = (0..3)
        .map(|r| (0..3).map(|c| m[r][c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    trace.min(gershgorin)
}

impl Hex8 {
    /// A hexahedron on `nodes` at reference positions `x`; `None` when its Jacobian is not
    /// positive at the centroid and every Gauss point (an inverted, degenerate or badly
    /// distorted element).
    pub fn new(
        nodes: [u32; 8],
        x: &[[f64; 3]],
        material: Material,
        integration: Integration,
    ) -> Option<Self> {
        let xs = nodes.map(|n| x[n as usize]);
        if !(spatial_gradients(&xs, [0.0; 3]).1 > 0.0) {
            return None;
        }
        let s = 1.0 / 3f64.sqrt();
        let mut gauss = Vec::with_capacity(8);
        for c in CORNERS {
            let (g, det) = spatial_gradients(&xs, [c[0] * s, c[1] * s, c[2] * s]);
            if !(det > 0.0) {
                return None;
            }
            gauss.push((g, det));
        }
        let volume0: f64 = gauss.iter().map(|(_, w)| w).sum();
        // the mean gradient (1/V0)∫∇N dV (Flanagan–Belytschko's uniform gradient): with it a
        // uniform stress gives the exact nodal forces on a distorted element too
        let grad0: [[f64; 3]; 8] = std::array::from_fn(|a| {
            std::array::from_fn(|i| gauss.iter().map(|(g, w)| g[a][i] * w).sum::<f64>() / volume0)
        });
        // Flanagan–Belytschko: γ_α = h_α − Σ_i (h_α·X_i) ∇N_i(0)
        let base: [[f64; 8]; 4] = [
            CORNERS.map(|c| c[1] * c[2]),
            CORNERS.map(|c| c[0] * c[2]),
            CORNERS.map(|c| c[0] * c[1]),
            CORNERS.map(|c| c[0] * c[1] * c[2]),
        ];
        let hourglass = base.map(|h| {
            let hx: [f64; 3] =
                std::array::from_fn(|i| (0..8).map(|a| h[a] * xs[a][i]).sum::<f64>());
            std::array::from_fn(|a| h[a] - (0..3).map(|i| hx[i] * grad0[a][i]).sum::<f64>())
        });
        let g2: f64 = grad0.iter().flatten().map(|g| g * g).sum();
        let hourglass_stiffness = HOURGLASS_STIFFNESS * material.mu() * volume0 * g2 / 8.0;
        // ω² ≤ (8/(ρV0))·(stiffness bound): the volumetric part ½K·V0·(tr ε)² ≤
        // ½(3λ + 2μ)·V0·λmax(Σ g gᵀ)·|u|²; the deviatoric part μ·Σ_p W_p|ε_p|² ≤
        // μ·Σ_p W_p·λmax(Σ g_p g_pᵀ)·|u|²; the hourglass ½k·Σ_α|q_α|² ≤ ½k·Σ_α|γ_α|²·|u|².
        let (l, mu) = (material.lambda(), material.mu());
        let volumetric = (3.0 * l + 2.0 * mu) * volume0 * gradient_norm_bound(&grad0);
        let rest = match integration {
            Integration::Selective => {
                2.0 * mu
                    * gauss
                        .iter()
                        .map(|(g, w)| w * gradient_norm_bound(g))
                        .sum::<f64>()
            }
            Integration::Reduced => {
                // the one-point deviatoric part is already in the volumetric bound's (3λ + 2μ)
                hourglass_stiffness * hourglass.iter().flatten().map(|g| g * g).sum::<f64>()
            }
        };
        let omega2 = 8.0 * (volumetric + rest) / (material.density * volume0);
        Some(Hex8 {
            nodes,
            integration,
            volume0,
            grad0,
            gauss: match integration {
                Integration::Selective => gauss,
                Integration::Reduced => Vec::new(),
            },
            hourglass,
            hourglass_stiffness,
            stable: 2.0 / omega2.sqrt(),
            material,
        })
    }

    /// Stable increment of the element alone (time): 2/ω with ω² the Rayleigh bound above on
    /// the lumped-mass element's highest frequency, so the increment is safe; a cube of side h
    /// of the selectively reduced form gets about 0.6·h/c (ν = 0).
    pub fn stable_increment(&self) -> f64 {
        self.stable
    }

    /// The deformation gradient at positions `x` with the gradients `g`.
    fn deformation(&self, x: &[[f64; 3]], g: &[[f64; 3]; 8]) -> [[f64; 3]; 3] {
        let mut ff = [[0.0; 3]; 3];
        for (&n, ga) in self.nodes.iter().zip(g) {
            let xn = x[n as usize];
            for r in 0..3 {
                for c in 0..3 {
                    ff[r][c] += xn[r] * ga[c];
                }
            }
        }
        ff
    }

    /// The element's mean deformation gradient (Σ x_a ⊗ ḡ_a).
    pub fn centroid_deformation(&self, x: &[[f64; 3]]) -> [[f64; 3]; 3] {
        self.deformation(x, &self.grad0)
    }

    /// Adds `−w·A·S·g_a` to each node's force (A = F, or the identity for small strain).
    fn add_stress_forces(
        &self,
        f: &mut [[f64; 3]],
        a: &[[f64; 3]; 3],
        s: &[[f64; 3]; 3],
        g: &[[f64; 3]; 8],
        w: f64,
    ) {
        let mut p = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                p[r][c] = (0..3).map(|m| a[r][m] * s[m][c]).sum();
            }
        }
        for (&n, ga) in self.nodes.iter().zip(g) {
            for r in 0..3 {
                f[n as usize][r] -= w * (0..3).map(|c| p[r][c] * ga[c]).sum::<f64>();
            }
        }
    }

    /// Adds the element's internal forces at positions `x` to `f` and returns its strain
    /// energy (hourglass energy included); `nlgeom` false for small-strain kinematics.
    pub fn add_internal_forces(&self, x: &[[f64; 3]], f: &mut [[f64; 3]], nlgeom: bool) -> f64 {
        let m = &self.material;
        let (l, mu) = (m.lambda(), m.mu());
        let bulk = l + 2.0 * mu / 3.0;
        let f0 = self.centroid_deformation(x);
        let e0 = strain(&f0, nlgeom);
        let push = |ff: &[[f64; 3]; 3]| if nlgeom { *ff } else { IDENTITY };
        match self.integration {
            Integration::Reduced => {
                let (s, w) = hooke(&e0, l, mu);
                self.add_stress_forces(f, &push(&f0), &s, &self.grad0, self.volume0);
                // hourglass: q_α = Σ_a γ_αa x_a (γ is orthogonal to every linear field)
                let mut energy = w * self.volume0;
                for gamma in &self.hourglass {
                    let mut q = [0.0; 3];
                    for (&n, g) in self.nodes.iter().zip(gamma) {
                        for r in 0..3 {
                            q[r] += g * x[n as usize][r];
                        }
                    }
                    for (&n, g) in self.nodes.iter().zip(gamma) {
                        for r in 0..3 {
                            f[n as usize][r] -= self.hourglass_stiffness * g * q[r];
                        }
                    }
                    energy +=
                        0.5 * self.hourglass_stiffness * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
                }
                energy
            }
            Integration::Selective => {
                let tr0 = e0[0][0] + e0[1][1] + e0[2][2];
                let pressure = bulk * tr0;
                let mut energy = 0.5 * bulk * tr0 * tr0 * self.volume0;
                let volumetric = scaled(&IDENTITY, pressure);
                self.add_stress_forces(f, &push(&f0), &volumetric, &self.grad0, self.volume0);
                for (g, w) in &self.gauss {
                    let fp = self.deformation(x, g);
                    let dev = deviator(&strain(&fp, nlgeom));
                    energy += w * mu * dot(&dev, &dev);
                    self.add_stress_forces(f, &push(&fp), &scaled(&dev, 2.0 * mu), g, *w);
                }
                energy
            }
        }
    }

    /// The second Piola–Kirchhoff (or, small strain, the Cauchy) stress at each integration
    /// point with its deformation gradient and volume share.
    fn point_stresses(&self, x: &[[f64; 3]], nlgeom: bool) -> Vec<(Mat3, Mat3, f64)> {
        let m = &self.material;
        let (l, mu) = (m.lambda(), m.mu());
        let f0 = self.centroid_deformation(x);
        let e0 = strain(&f0, nlgeom);
        match self.integration {
            Integration::Reduced => vec![(hooke(&e0, l, mu).0, f0, self.volume0)],
            Integration::Selective => {
                let tr0 = e0[0][0] + e0[1][1] + e0[2][2];
                let bulk = l + 2.0 * mu / 3.0;
                self.gauss
                    .iter()
                    .map(|(g, w)| {
                        let fp = self.deformation(x, g);
                        let mut s = scaled(&deviator(&strain(&fp, nlgeom)), 2.0 * mu);
                        for (r, row) in s.iter_mut().enumerate() {
                            row[r] += bulk * tr0;
                        }
                        (s, fp, *w)
                    })
                    .collect()
            }
        }
    }

    /// The volume-averaged Cauchy stress at positions `x` (model stress units, model frame);
    /// with `nlgeom` false the small-strain stress.
    pub fn stress(&self, x: &[[f64; 3]], nlgeom: bool) -> [[f64; 3]; 3] {
        let mut sigma = [[0.0; 3]; 3];
        for (s, ff, w) in self.point_stresses(x, nlgeom) {
            let cauchy = if nlgeom { push_forward(&s, &ff) } else { s };
            for r in 0..3 {
                for c in 0..3 {
                    sigma[r][c] += cauchy[r][c] * w / self.volume0;
                }
            }
        }
        sigma
    }
}

/// A 3×3 matrix, rows first.
type Mat3 = [[f64; 3]; 3];

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Green–Lagrange strain ½(FᵀF − I), or the linear strain sym(F) − I.
fn strain(ff: &[[f64; 3]; 3], nlgeom: bool) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let id = if r == c { 1.0 } else { 0.0 };
            if nlgeom {
                0.5 * ((0..3).map(|k| ff[k][r] * ff[k][c]).sum::<f64>() - id)
            } else {
                0.5 * (ff[r][c] + ff[c][r]) - id
            }
        })
    })
}

/// Isotropic linear elasticity: stress and strain energy density.
fn hooke(e: &[[f64; 3]; 3], l: f64, mu: f64) -> ([[f64; 3]; 3], f64) {
    let tr = e[0][0] + e[1][1] + e[2][2];
    let mut s = scaled(e, 2.0 * mu);
    for (r, row) in s.iter_mut().enumerate() {
        row[r] += l * tr;
    }
    (s, 0.5 * l * tr * tr + mu * dot(e, e))
}

fn deviator(e: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mean = (e[0][0] + e[1][1] + e[2][2]) / 3.0;
    let mut d = *e;
    for (r, row) in d.iter_mut().enumerate() {
        row[r] -= mean;
    }
    d
}

fn scaled(e: &[[f64; 3]; 3], k: f64) -> [[f64; 3]; 3] {
    e.map(|row| row.map(|v| v * k))
}

fn dot(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> f64 {
    (0..3)
        .map(|r| (0..3).map(|c| a[r][c] * b[r][c]).sum::<f64>())
        .sum()
}

/// Cauchy stress (1/J)·F·S·Fᵀ.
fn push_forward(s: &[[f64; 3]; 3], ff: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = det3(ff);
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let mut acc = 0.0;
            for a in 0..3 {
                for b in 0..3 {
                    acc += ff[r][a] * s[a][b] * ff[c][b];
                }
            }
            acc / det
        })
    })
}

#[cfg(test)]
mod tests;
