//! Elements of the small explicit solver: 2-node bars, 3-node plane-strain triangles, 4-node
//! tetrahedra and 8-node hexahedra (their own module, [`super::hexahedron`]), linear elastic in
//! forms that stay right under large rotation: bars are corotational (engineering strain (l − L0)/L0 along the current axis, so a 1D wave is exactly
//! the linear one whatever its amplitude), triangles and tetrahedra St Venant–Kirchhoff
//! (Green–Lagrange strain, second Piola–Kirchhoff stress).
//!
//! Long file: the element kinds are one enum, and its two `impl` blocks (geometry, masses and
//! stable lengths; internal forces with bulk viscosity) match on every kind, so each formula
//! sits beside the other kinds' and beside the shared strain and stress helpers at the end.

use super::hexahedron::Hex8;
use crate::geometry::V3;

/// Linear elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus.
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Density (mass per volume; per length for bars, per area for plane-strain triangles of
    /// unit thickness the volume is area × thickness).
    pub density: f64,
}

impl Material {
    /// Lamé's first parameter λ.
    pub fn lambda(&self) -> f64 {
        let (e, nu) = (self.young, self.poisson);
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    }
    /// Shear modulus μ.
    pub fn mu(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }
    /// Dilatational (P-wave) speed √((λ + 2μ)/ρ), the speed the stable increment is set by.
    pub fn p_wave_speed(&self) -> f64 {
        ((self.lambda() + 2.0 * self.mu()) / self.density).sqrt()
    }
}

/// An element: its nodes, reference geometry and material.
#[derive(Clone, Debug, PartialEq)]
pub enum Element {
    /// 2-node corotational bar of cross-section `area` (uniaxial stress σ = E·(l − L0)/L0
    /// along the current axis).
    Bar {
        /// Node indices.
        nodes: [u32; 2],
        /// Cross-section area.
        area: f64,
        /// Reference length.
        length0: f64,
        /// Material.
        material: Material,
    },
    /// 3-node plane-strain triangle (x–y plane) of out-of-plane `thickness`.
    Tri3 {
        /// Node indices (counter-clockwise).
        nodes: [u32; 3],
        /// Thickness.
        thickness: f64,
        /// Reference area.
        area0: f64,
        /// Reference shape-function gradients (x, y) of the three nodes.
        grad: [[f64; 2]; 3],
        /// Axisymmetric (x = radius, y = axis): the nodes' reference radii. The element is then
        /// per radian (its "thickness" is its centroid's reference radius) and small-strain,
        /// with the hoop strain u_r/r at the centroid.
        hoop: Option<[f64; 3]>,
        /// Material.
        material: Material,
    },
    /// 4-node tetrahedron.
    Tet4 {
        /// Node indices (positive volume).
        nodes: [u32; 4],
        /// Reference volume.
        volume0: f64,
        /// Reference shape-function gradients of the four nodes.
        grad: [[f64; 3]; 4],
        /// Material.
        material: Material,
    },
    /// 8-node hexahedron, selectively reduced (C3D8) or one-point with hourglass stiffness
    /// (C3D8R): see [`Hex8`].
    Hex8(Box<Hex8>),
}

fn sub(a: [f64; 3], b: [f64; 3]) -> V3<f64> {
    V3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2])
}

impl Element {
    /// A bar between `nodes` at reference positions `x`.
    pub fn bar(nodes: [u32; 2], x: &[[f64; 3]], area: f64, material: Material) -> Option<Self> {
        let l = sub(x[nodes[1] as usize], x[nodes[0] as usize])
            .length2()
            .sqrt();
        (l > 0.0).then_some(Element::Bar {
            nodes,
            area,
            length0: l,
            material,
        })
    }

    /// A plane-strain triangle; `None` when its reference area is not positive.
    pub fn tri3(
        nodes: [u32; 3],
        x: &[[f64; 3]],
        thickness: f64,
        material: Material,
    ) -> Option<Self> {
        let p: Vec<[f64; 3]> = nodes.iter().map(|&n| x[n as usize]).collect();
        let area = 0.5
            * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]));
        if !(area > 0.0) {
            return None;
        }
        let mut grad = [[0.0; 2]; 3];
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            grad[i] = [
                (p[j][1] - p[k][1]) / (2.0 * area),
                (p[k][0] - p[j][0]) / (2.0 * area),
            ];
        }
        Some(Element::Tri3 {
            nodes,
            thickness,
            area0: area,
            grad,
            material,
            hoop: None,
        })
    }

    /// An axisymmetric triangle (x = radius ≥ 0, y = axis), per radian of circumference,
    /// small-strain; `None` when its reference area is not positive or it lies on the axis.
    pub fn axi3(nodes: [u32; 3], x: &[[f64; 3]], material: Material) -> Option<Self> {
        let r0 = nodes.map(|n| x[n as usize][0]);
        let r_bar = (r0[0] + r0[1] + r0[2]) / 3.0;
        if !(r_bar > 0.0) || r0.iter().any(|r| *r < 0.0) {
            return None;
        }
        let mut el = Self::tri3(nodes, x, r_bar, material)?;
        if let Element::Tri3 { hoop, .. } = &mut el {
            *hoop = Some(r0);
        }
        Some(el)
    }

    fn is_axisymmetric(&self) -> bool {
        matches!(self, Element::Tri3 { hoop: Some(_), .. })
    }

    /// The nodes of an axisymmetric element that lie on the axis (reference radius 0, or below
    /// 1e-9 of the element's largest radius); none for other elements. The solver holds them
    /// radially.
    pub fn axis_nodes(&self) -> Vec<u32> {
        match self {
            Element::Tri3 {
                nodes,
                hoop: Some(r0),
                ..
            } => {
                let top = r0.iter().cloned().fold(0.0, f64::max);
                (0..3)
                    .filter(|&j| r0[j].abs() <= 1e-9 * top)
                    .map(|j| nodes[j])
                    .collect()
            }
            _ => Vec::new(),
        }
    }

    /// A tetrahedron; `None` when its reference volume is not positive.
    pub fn tet4(nodes: [u32; 4], x: &[[f64; 3]], material: Material) -> Option<Self> {
        let p: Vec<V3<f64>> = nodes
            .iter()
            .map(|&n| V3::from_array(x[n as usize]))
            .collect();
        let (a, b, c) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
        let vol6 = a.dot(b.cross(c));
        if !(vol6 > 0.0) {
            return None;
        }
        // gradients of the barycentric coordinates: rows of the inverse of [a b c]ᵀ
        let g1 = b.cross(c) * (1.0 / vol6);
        let g2 = c.cross(a) * (1.0 / vol6);
        let g3 = a.cross(b) * (1.0 / vol6);
        let g0 = (g1 + g2 + g3) * -1.0;
        Some(Element::Tet4 {
            nodes,
            volume0: vol6 / 6.0,
            grad: [g0.to_array(), g1.to_array(), g2.to_array(), g3.to_array()],
            material,
        })
    }

    /// The element's nodes.
    pub fn nodes(&self) -> &[u32] {
        match self {
            Element::Bar { nodes, .. } => nodes,
            Element::Tri3 { nodes, .. } => nodes,
            Element::Tet4 { nodes, .. } => nodes,
            Element::Hex8(h) => &h.nodes,
        }
    }

    /// Its material.
    pub fn material(&self) -> &Material {
        match self {
            Element::Bar { material, .. }
            | Element::Tri3 { material, .. }
            | Element::Tet4 { material, .. } => material,
            Element::Hex8(h) => &h.material,
        }
    }

    /// Reference mass (density × reference measure).
    pub fn mass(&self) -> f64 {
        match self {
            Element::Bar {
                area,
                length0,
                material,
                ..
            } => material.density * area * length0,
            Element::Tri3 {
                thickness,
                area0,
                material,
                ..
            } => material.density * thickness * area0,
            Element::Tet4 {
                volume0, material, ..
            } => material.density * volume0,
            Element::Hex8(h) => h.material.density * h.volume0,
        }
    }

    /// Stable increment of the element alone: a characteristic length over the wave speed (E
    /// for bars, the P-wave speed otherwise). For triangles and tetrahedra the length is
    /// 1/√(Σ_i |∇N_i|²), which bounds the lumped-mass element's highest frequency from above
    /// (trace bound: ω² ≤ n·c²·Σ|∇N_i|²/n), so the increment is safe; for a bar it is exact.
    pub fn stable_increment(&self) -> f64 {
        match self {
            Element::Bar {
                length0, material, ..
            } => length0 / (material.young / material.density).sqrt(),
            Element::Tri3 {
                grad,
                material,
                hoop,
                thickness,
                ..
            } => {
                // the hoop strain's "gradient" N_i/r̄ = 1/(3 r̄) counts like the others
                let h = if hoop.is_some() {
                    3.0 / (9.0 * thickness * thickness)
                } else {
                    0.0
                };
                let s: f64 = grad.iter().map(|g| g[0] * g[0] + g[1] * g[1]).sum::<f64>() + h;
                1.0 / (s.sqrt() * material.p_wave_speed())
            }
            Element::Tet4 { grad, material, .. } => {
                let s: f64 = grad
                    .iter()
                    .map(|g| g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
                    .sum();
                1.0 / (s.sqrt() * material.p_wave_speed())
            }
            Element::Hex8(h) => h.stable_increment(),
        }
    }

    /// Adds the element's internal forces at positions `x` to `f` (the forces the element
    /// exerts on its nodes) and returns its strain energy.
    pub fn add_internal_forces(&self, x: &[[f64; 3]], f: &mut [[f64; 3]]) -> f64 {
        self.add_internal_forces_with(x, f, true)
    }

    /// As [`Element::add_internal_forces`], with `nlgeom` false for small-strain kinematics
    /// (Abaqus' NLGEOM=NO): triangles and tetrahedra use the linear strain sym(∇u) and the
    /// reference gradients — exact for the linear theory the verification solutions assume,
    /// wrong under large rotation. Bars are corotational either way.
    pub fn add_internal_forces_with(
        &self,
        x: &[[f64; 3]],
        f: &mut [[f64; 3]],
        nlgeom: bool,
    ) -> f64 {
        if let Element::Hex8(h) = self {
            return h.add_internal_forces(x, f, nlgeom);
        }
        if (!nlgeom || self.is_axisymmetric()) && !matches!(self, Element::Bar { .. }) {
            let (sigma, w) = self.small_strain_stress(x);
            let (grad, vol): (Vec<[f64; 3]>, f64) = match self {
                Element::Tri3 {
                    grad,
                    area0,
                    thickness,
                    ..
                } => (
                    grad.iter().map(|g| [g[0], g[1], 0.0]).collect(),
                    area0 * thickness,
                ),
                Element::Tet4 { grad, volume0, .. } => (grad.to_vec(), *volume0),
                Element::Bar { .. } | Element::Hex8(_) => unreachable!(),
            };
            let dims = if matches!(self, Element::Tri3 { .. }) {
                2
            } else {
                3
            };
            let hoop_grad = match self {
                Element::Tri3 {
                    hoop: Some(_),
                    thickness,
                    ..
                } => 1.0 / (3.0 * thickness),
                _ => 0.0,
            };
            for (k, &n) in self.nodes().iter().enumerate() {
                for r in 0..dims {
                    let s: f64 = (0..3).map(|c| sigma[r][c] * grad[k][c]).sum();
                    f[n as usize][r] -= vol * s;
                }
                // axisymmetric: the hoop stress works on the radial displacement
                f[n as usize][0] -= vol * sigma[2][2] * hoop_grad;
            }
            return w * vol;
        }
        match self {
            Element::Bar {
                nodes,
                area,
                length0,
                material,
            } => {
                let d = sub(x[nodes[1] as usize], x[nodes[0] as usize]);
                let l = d.length2().sqrt();
                // engineering strain along the current axis; axial force σ·A
                let e = (l - length0) / length0;
                let t = d * (material.young * e * area / l);
                for a in 0..3 {
                    f[nodes[0] as usize][a] += t.to_array()[a];
                    f[nodes[1] as usize][a] -= t.to_array()[a];
                }
                0.5 * material.young * e * e * area * length0
            }
            Element::Tri3 {
                nodes,
                thickness,
                area0,
                grad,
                material,
                ..
            } => {
                // F (2×2) = Σ x_i ⊗ ∇N_i
                let mut ff = [[0.0; 2]; 2];
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..2 {
                        for c in 0..2 {
                            ff[r][c] += x[n as usize][r] * grad[k][c];
                        }
                    }
                }
                let (s, w) = stvk_2d(&ff, material);
                // P = F S; f_i = −V0 P ∇N_i
                let vol = area0 * thickness;
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..2 {
                        let mut p_g = 0.0;
                        for c in 0..2 {
                            let p_rc: f64 = (0..2).map(|m| ff[r][m] * s[m][c]).sum();
                            p_g += p_rc * grad[k][c];
                        }
                        f[n as usize][r] -= vol * p_g;
                    }
                }
                w * vol
            }
            Element::Tet4 {
                nodes,
                volume0,
                grad,
                material,
            } => {
                let mut ff = [[0.0; 3]; 3];
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..3 {
                        for c in 0..3 {
                            ff[r][c] += x[n as usize][r] * grad[k][c];
                        }
                    }
                }
                let (s, w) = stvk_3d(&ff, material);
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..3 {
                        let mut p_g = 0.0;
                        for c in 0..3 {
                            let p_rc: f64 = (0..3).map(|m| ff[r][m] * s[m][c]).sum();
                            p_g += p_rc * grad[k][c];
                        }
                        f[n as usize][r] -= volume0 * p_g;
                    }
                }
                w * volume0
            }
            Element::Hex8(_) => unreachable!("hexahedra returned above"),
        }
    }
}

impl Element {
    /// The deformation gradient at positions `x` (3×3; plane-strain triangles have F_zz = 1,
    /// bars the stretch along their axis and the identity across it, rotated with the axis
    /// approximated as the reference axis' stretch only).
    fn deformation_gradient(&self, x: &[[f64; 3]]) -> [[f64; 3]; 3] {
        let mut ff = [[0.0; 3]; 3];
        match self {
            Element::Bar { .. } => unreachable!("bars have no full deformation gradient"),
            Element::Tri3 { nodes, grad, .. } => {
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..2 {
                        for c in 0..2 {
                            ff[r][c] += x[n as usize][r] * grad[k][c];
                        }
                    }
                }
                ff[2][2] = 1.0;
            }
            Element::Tet4 { nodes, grad, .. } => {
                for (k, &n) in nodes.iter().enumerate() {
                    for r in 0..3 {
                        for c in 0..3 {
                            ff[r][c] += x[n as usize][r] * grad[k][c];
                        }
                    }
                }
            }
            Element::Hex8(h) => ff = h.centroid_deformation(x),
        }
        ff
    }

    /// Small-strain stress C:sym(F − I) (plane strain: ε_zz = 0) and strain energy density.
    fn small_strain_stress(&self, x: &[[f64; 3]]) -> ([[f64; 3]; 3], f64) {
        let ff = self.deformation_gradient(x);
        let m = match self {
            Element::Tri3 { material, .. } | Element::Tet4 { material, .. } => material,
            Element::Hex8(h) => &h.material,
            Element::Bar { .. } => unreachable!("bars are corotational"),
        };
        let mut eps = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                let id = if r == c { 1.0 } else { 0.0 };
                eps[r][c] = 0.5 * (ff[r][c] + ff[c][r]) - id;
            }
        }
        if let Element::Tri3 {
            hoop: Some(r0),
            thickness,
            nodes,
            ..
        } = self
        {
            // ε_θθ = u_r / r at the centroid
            eps[2][2] = (0..3)
                .map(|i| (x[nodes[i] as usize][0] - r0[i]) / (3.0 * thickness))
                .sum::<f64>();
        }
        let (l, mu) = (m.lambda(), m.mu());
        let tr = eps[0][0] + eps[1][1] + eps[2][2];
        let mut s = [[0.0; 3]; 3];
        let mut ee = 0.0;
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] = 2.0 * mu * eps[r][c] + if r == c { l * tr } else { 0.0 };
                ee += eps[r][c] * eps[r][c];
            }
        }
        (s, 0.5 * l * tr * tr + mu * ee)
    }

    /// Stress at positions `x` with small-strain kinematics (see
    /// [`Element::add_internal_forces_with`]); bars as [`Element::stress`].
    pub fn small_strain_stress_at(&self, x: &[[f64; 3]]) -> [[f64; 3]; 3] {
        match self {
            Element::Bar { .. } => self.stress(x),
            Element::Hex8(h) => h.stress(x, false),
            _ => self.small_strain_stress(x).0,
        }
    }

    /// Cauchy stress at positions `x` (model stress units, model frame). Plane-strain
    /// triangles include σ_zz; a bar's stress is uniaxial along its current axis.
    pub fn stress(&self, x: &[[f64; 3]]) -> [[f64; 3]; 3] {
        if let Element::Hex8(h) = self {
            return h.stress(x, true);
        }
        if self.is_axisymmetric() {
            return self.small_strain_stress(x).0;
        }
        if let Element::Bar {
            nodes,
            length0,
            material,
            ..
        } = self
        {
            let d = sub(x[nodes[1] as usize], x[nodes[0] as usize]);
            let l = d.length2().sqrt();
            // the area change of a bar is not modelled
            let sigma = material.young * (l - length0) / length0;
            let u = d * (1.0 / l);
            let u = u.to_array();
            let mut s = [[0.0; 3]; 3];
            for r in 0..3 {
                for c in 0..3 {
                    s[r][c] = sigma * u[r] * u[c];
                }
            }
            return s;
        }
        let ff = self.deformation_gradient(x);
        let m = match self {
            Element::Tri3 { material, .. } | Element::Tet4 { material, .. } => material,
            Element::Hex8(h) => &h.material,
            Element::Bar { .. } => unreachable!(),
        };
        // S from the full 3D St Venant–Kirchhoff law (E_zz = 0 in plane strain)
        let (s, _) = stvk_3d(&ff, m);
        let det = ff[0][0] * (ff[1][1] * ff[2][2] - ff[1][2] * ff[2][1])
            - ff[0][1] * (ff[1][0] * ff[2][2] - ff[1][2] * ff[2][0])
            + ff[0][2] * (ff[1][0] * ff[2][1] - ff[1][1] * ff[2][0]);
        let mut sigma = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                let mut acc = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        acc += ff[r][a] * s[a][b] * ff[c][b];
                    }
                }
                sigma[r][c] = acc / det;
            }
        }
        sigma
    }

    /// The volumetric strain rate at velocities `v` (1/s; negative in compression): a bar's
    /// axial rate along its current axis, a continuum element's Σ v_i·∇N_i.
    pub fn volumetric_rate(&self, x: &[[f64; 3]], v: &[[f64; 3]]) -> f64 {
        match self {
            Element::Bar { nodes, length0, .. } => {
                let d = sub(x[nodes[1] as usize], x[nodes[0] as usize]);
                let u = d * (1.0 / d.length2().sqrt());
                sub(v[nodes[1] as usize], v[nodes[0] as usize]).dot(u) / length0
            }
            Element::Tri3 { nodes, grad, .. } => nodes
                .iter()
                .zip(grad)
                .map(|(&n, g)| v[n as usize][0] * g[0] + v[n as usize][1] * g[1])
                .sum(),
            Element::Tet4 { nodes, grad, .. } => nodes
                .iter()
                .zip(grad)
                .map(|(&n, g)| (0..3).map(|r| v[n as usize][r] * g[r]).sum::<f64>())
                .sum(),
            Element::Hex8(h) => h
                .nodes
                .iter()
                .zip(&h.grad0)
                .map(|(&n, g)| (0..3).map(|r| v[n as usize][r] * g[r]).sum::<f64>())
                .sum(),
        }
    }

    /// Adds bulk viscosity at velocities `v` to `f` in Abaqus' form, the pressure
    /// `b1·ρ·c·L·ε̇_vol` (linear) plus `ρ·(b2·L·ε̇_vol)²` in compression only (quadratic), with L
    /// the element's stable length and c its wave speed, and returns its power (≤ 0: it only
    /// dissipates).
    pub fn add_bulk_viscosity(
        &self,
        x: &[[f64; 3]],
        v: &[[f64; 3]],
        (b1, b2): (f64, f64),
        f: &mut [[f64; 3]],
    ) -> f64 {
        let c_len = self.stable_increment();
        let rate = self.volumetric_rate(x, v);
        match self {
            Element::Bar {
                nodes,
                area,
                length0,
                material,
            } => {
                let d = sub(x[nodes[1] as usize], x[nodes[0] as usize]);
                let u = d * (1.0 / d.length2().sqrt());
                let c = length0 / c_len;
                let p = viscous_pressure(material.density, c, *length0, rate, b1, b2);
                let t = (u * (p * area)).to_array();
                for a in 0..3 {
                    f[nodes[0] as usize][a] += t[a];
                    f[nodes[1] as usize][a] -= t[a];
                }
                -p * area * length0 * rate
            }
            Element::Tri3 {
                nodes,
                thickness,
                area0,
                grad,
                material,
                ..
            } => {
                let g = grad.map(|g| [g[0], g[1], 0.0]);
                let c = material.p_wave_speed();
                let p = viscous_pressure(material.density, c, c_len * c, rate, b1, b2);
                volumetric_dashpot(nodes, &g, area0 * thickness, p, rate, f)
            }
            Element::Tet4 {
                nodes,
                volume0,
                grad,
                material,
            } => {
                let c = material.p_wave_speed();
                let p = viscous_pressure(material.density, c, c_len * c, rate, b1, b2);
                volumetric_dashpot(nodes, grad, *volume0, p, rate, f)
            }
            Element::Hex8(h) => {
                let c = h.material.p_wave_speed();
                let p = viscous_pressure(h.material.density, c, c_len * c, rate, b1, b2);
                volumetric_dashpot(&h.nodes, &h.grad0, h.volume0, p, rate, f)
            }
        }
    }

    /// The fraction of critical damping bulk viscosity gives the element's highest mode at
    /// velocities `v` (Abaqus: ξ = b1 − b2²·(L/c)·min(0, ε̇_vol)), which lowers its stable
    /// increment to `stable_increment()·(√(1 + ξ²) − ξ)`.
    pub fn bulk_damping_ratio(&self, x: &[[f64; 3]], v: &[[f64; 3]], (b1, b2): (f64, f64)) -> f64 {
        if b2 == 0.0 {
            return b1;
        }
        b1 - b2 * b2 * self.stable_increment() * self.volumetric_rate(x, v).min(0.0)
    }
}

/// The bulk viscosity pressure (tension positive, as the rate): `b1·ρ·c·L·ε̇` plus, in
/// compression (ε̇ < 0), `−ρ·(b2·L·ε̇)²`; its product with the rate is never negative.
fn viscous_pressure(density: f64, c: f64, length: f64, rate: f64, b1: f64, b2: f64) -> f64 {
    let quadratic = if rate < 0.0 {
        density * (b2 * length * rate).powi(2)
    } else {
        0.0
    };
    b1 * density * c * length * rate - quadratic
}

/// Bulk viscosity of a continuum element of reference volume `vol`: the pressure `p` (from
/// [`viscous_pressure`] at the volumetric rate `rate` = Σ v_i·∇N_i) applied as −vol·p·∇N_i;
/// returns its power (≤ 0).
fn volumetric_dashpot(
    nodes: &[u32],
    grad: &[[f64; 3]],
    vol: f64,
    p: f64,
    rate: f64,
    f: &mut [[f64; 3]],
) -> f64 {
    for (&n, g) in nodes.iter().zip(grad) {
        for r in 0..3 {
            f[n as usize][r] -= vol * p * g[r];
        }
    }
    -vol * p * rate
}

/// Second Piola–Kirchhoff stress and strain energy density of St Venant–Kirchhoff in plane
/// strain (E_zz = 0).
fn stvk_2d(ff: &[[f64; 2]; 2], m: &Material) -> ([[f64; 2]; 2], f64) {
    let mut e = [[0.0; 2]; 2];
    for r in 0..2 {
        for c in 0..2 {
            let ftf: f64 = (0..2).map(|k| ff[k][r] * ff[k][c]).sum();
            e[r][c] = 0.5 * (ftf - if r == c { 1.0 } else { 0.0 });
        }
    }
    let (l, mu) = (m.lambda(), m.mu());
    let tr = e[0][0] + e[1][1];
    let mut s = [[0.0; 2]; 2];
    let mut ee = 0.0;
    for r in 0..2 {
        for c in 0..2 {
            s[r][c] = 2.0 * mu * e[r][c] + if r == c { l * tr } else { 0.0 };
            ee += e[r][c] * e[r][c];
        }
    }
    (s, 0.5 * l * tr * tr + mu * ee)
}

/// Second Piola–Kirchhoff stress and strain energy density of St Venant–Kirchhoff.
fn stvk_3d(ff: &[[f64; 3]; 3], m: &Material) -> ([[f64; 3]; 3], f64) {
    let mut e = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            let ftf: f64 = (0..3).map(|k| ff[k][r] * ff[k][c]).sum();
            e[r][c] = 0.5 * (ftf - if r == c { 1.0 } else { 0.0 });
        }
    }
    let (l, mu) = (m.lambda(), m.mu());
    let tr = e[0][0] + e[1][1] + e[2][2];
    let mut s = [[0.0; 3]; 3];
    let mut ee = 0.0;
    for r in 0..3 {
        for c in 0..3 {
            s[r][c] = 2.0 * mu * e[r][c] + if r == c { l * tr } else { 0.0 };
            ee += e[r][c] * e[r][c];
        }
    }
    (s, 0.5 * l * tr * tr + mu * ee)
}
