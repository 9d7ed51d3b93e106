//! Closest points on master facets, load-transfer weights and local tangent directions.
//!
//! The routines are generic over [`Real`] so that one algorithm serves the f32 CPU mirror of the
//! shaders (`shaders/common.wgsl` holds the WGSL twin of every function here, same order of
//! operations) and the f64 reference path used by the oracle and the host passes.
//!
//! # Facet conventions
//!
//! * **Segment** (2D, nodes a→b): weights `(1−t, t)`; outward normal `(t_y, −t_x)/|t|`, i.e. on the
//!   right of a→b, which points out of a body whose boundary runs counter-clockwise.
//! * **Triangle** (nodes a, b, c): weights are the barycentric coordinates of the closest point;
//!   normal `(b−a)×(c−a)` normalised (outward when the nodes run counter-clockwise seen from
//!   outside). Closest point by Voronoi regions (Ericson, *Real-Time Collision Detection* §5.1.5),
//!   exact on edges and vertices.
//! * **Quad** (bilinear, nodes 0..3 counter-clockwise, ξ, η ∈ [−1, 1]): the facet is the bilinear
//!   patch `x(ξ,η) = Σ N_i x_i`, which need not be planar. Computed relative to node 0:
//!   (a) a Newton descent on `|x(ξ,η) − p|²` (Gauss–Newton where the Hessian is not positive
//!   definite), clamped to the parameter square, [`QUAD_ITERATIONS`] steps, each halved up to
//!   [`QUAD_HALVINGS`] times until it does not increase the distance when longer than
//!   [`QUAD_TRUST`], from the nearest point of the nearer triangle, (x0, x1, x2) or
//!   (x0, x2, x3), mapped to (ξ, η) by inverting the
//!   bilinear map in the quad's plane (exact for a planar quad, near otherwise; from the centre,
//!   full steps overshot from corner to corner on distorted quads, 2.4 % of a sweep of them);
//!   if it converges strictly inside the square, that stationary point is the answer;
//!   otherwise (b) the exact nearest points on the four straight edges (and the unconverged
//!   end point, if it is inside). For a planar quad this is the true nearest point (the orthogonal
//!   projection when it lies inside, an edge point otherwise); for a mildly warped quad the
//!   interior stationary point is the nearest point (tested against dense sampling); a
//!   severely warped quad may have a nearer edge point than its interior stationary point,
//!   which this method does not look for. Taking the converged interior point without
//!   comparing distances keeps the answer a continuous function of round-off: comparing
//!   nearly equal f32 distances would pick points up to √(2·d·δ) apart. Weights are the
//!   bilinear shape functions at (ξ, η); the normal is `x_ξ × x_η` normalised there, or the
//!   diagonal normal `(x2−x0)×(x3−x1)` where that vanishes (collapsed edge).

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Newton steps used for the interior of a quad (WGSL: `QUAD_ITERATIONS`).
pub const QUAD_ITERATIONS: u32 = 8;

/// Step halvings a quad's Newton step may take to descend (WGSL: `QUAD_HALVINGS`).
pub const QUAD_HALVINGS: u32 = 6;

/// Newton steps (in ξ, η) up to this length are taken whole, longer ones backtrack
/// (WGSL: `QUAD_TRUST`).
pub const QUAD_TRUST: f64 = 0.25;

/// A floating-point scalar the geometry runs in: `f32` (mirrors the GPU) or `f64` (reference).
pub trait Real:
    Copy
    + PartialOrd
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Conversion from f64 (rounding for f32).
    fn from_f64(v: f64) -> Self;
    /// Conversion to f64 (exact).
    fn to_f64(self) -> f64;
    /// The larger of two values (`b` when they compare equal).
    fn max_of(self, b: Self) -> Self {
        if self > b {
            self
        } else {
            b
        }
    }
    /// Absolute value.
    fn abs_of(self) -> Self {
        if self < Self::ZERO {
            -self
        } else {
            self
        }
    }
    /// The smaller of two values (`b` when they compare equal).
    fn min_of(self, b: Self) -> Self {
        if self < b {
            self
        } else {
            b
        }
    }
    /// `self` clamped to `[lo, hi]`.
    fn clamp_to(self, lo: Self, hi: Self) -> Self {
        self.max_of(lo).min_of(hi)
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn to_f64(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn from_f64(v: f64) -> Self {
        v
    }
    fn to_f64(self) -> f64 {
        self
    }
}

/// A 3-vector of [`Real`]; 2D models use z = 0.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct V3<T> {
    /// x component.
    pub x: T,
    /// y component.
    pub y: T,
    /// z component.
    pub z: T,
}

impl<T: Real> V3<T> {
    /// A vector from its components.
    pub fn new(x: T, y: T, z: T) -> Self {
        Self { x, y, z }
    }
    /// The zero vector.
    pub fn zero() -> Self {
        Self::new(T::ZERO, T::ZERO, T::ZERO)
    }
    /// A vector from an array.
    pub fn from_array(a: [T; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
    /// The components as an array.
    pub fn to_array(self) -> [T; 3] {
        [self.x, self.y, self.z]
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product.
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Squared length.
    pub fn length2(self) -> T {
        self.dot(self)
    }
    /// Unit vector, or zero when the length is zero.
    pub fn normalize_or_zero(self) -> Self {
        let l2 = self.length2();
        if l2 > T::ZERO {
            self * (T::ONE / l2.sqrt())
        } else {
            Self::zero()
        }
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<T: Real> Sub for V3<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<T: Real> Mul<T> for V3<T> {
    type Output = Self;
    fn mul(self, s: T) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

/// The nearest point of a facet to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection<T> {
    /// The nearest point on the facet (same frame as the input).
    pub point: V3<T>,
    /// Load-transfer weights of the facet's nodes at `point` (shape functions; unused slots 0).
    pub weights: [T; 4],
    /// Unit facet normal at `point` (zero if the facet has collapsed to zero area).
    pub normal: V3<T>,
    /// Squared distance from the query point to `point`.
    pub dist2: T,
}

impl<T: Real> Projection<T> {
    /// Signed gap along the facet normal: `(p − point)·normal`; positive outside (open).
    pub fn gap(&self, p: V3<T>) -> T {
        (p - self.point).dot(self.normal)
    }
}

/// `a / b`, or 0 when `b` is 0 (guards facets that collapse while the model deforms).
fn div_or_zero<T: Real>(a: T, b: T) -> T {
    if b != T::ZERO {
        a / b
    } else {
        T::ZERO
    }
}

/// Nearest point to `p` on the 2D segment a→b (z ignored and returned as 0).
pub fn closest_on_segment<T: Real>(p: V3<T>, a: V3<T>, b: V3<T>) -> Projection<T> {
    let ab = V3::new(b.x - a.x, b.y - a.y, T::ZERO);
    let ap = V3::new(p.x - a.x, p.y - a.y, T::ZERO);
    let t = div_or_zero(ap.dot(ab), ab.length2()).clamp_to(T::ZERO, T::ONE);
    let point = V3::new(a.x + ab.x * t, a.y + ab.y * t, T::ZERO);
    let normal = V3::new(ab.y, -ab.x, T::ZERO).normalize_or_zero();
    let d = V3::new(p.x - point.x, p.y - point.y, T::ZERO);
    Projection {
        point,
        weights: [T::ONE - t, t, T::ZERO, T::ZERO],
        normal,
        dist2: d.length2(),
    }
}

/// Nearest point to `p` on triangle (a, b, c), with barycentric weights.
pub fn closest_on_triangle<T: Real>(p: V3<T>, a: V3<T>, b: V3<T>, c: V3<T>) -> Projection<T> {
    let ab = b - a;
    let ac = c - a;
    let normal = ab.cross(ac).normalize_or_zero();
    let (point, w) = triangle_region(p, a, b, c, ab, ac);
    Projection {
        point,
        weights: [w[0], w[1], w[2], T::ZERO],
        normal,
        dist2: (p - point).length2(),
    }
}

/// Voronoi-region walk of Ericson §5.1.5: nearest point and barycentric weights.
fn triangle_region<T: Real>(
    p: V3<T>,
    a: V3<T>,
    b: V3<T>,
    c: V3<T>,
    ab: V3<T>,
    ac: V3<T>,
) -> (V3<T>, [T; 3]) {
    let (zero, one) = (T::ZERO, T::ONE);
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= zero && d2 <= zero {
        return (a, [one, zero, zero]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= zero && d4 <= d3 {
        return (b, [zero, one, zero]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= zero && d1 >= zero && d3 <= zero {
        let v = div_or_zero(d1, d1 - d3);
        return (a + ab * v, [one - v, v, zero]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= zero && d5 <= d6 {
        return (c, [zero, zero, one]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= zero && d2 >= zero && d6 <= zero {
        let w = div_or_zero(d2, d2 - d6);
        return (a + ac * w, [one - w, zero, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= zero && (d4 - d3) >= zero && (d5 - d6) >= zero {
        let w = div_or_zero(d4 - d3, (d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [zero, one - w, w]);
    }
    let denom = va + vb + vc;
    let v = div_or_zero(vb, denom);
    let w = div_or_zero(vc, denom);
    (a + ab * v + ac * w, [one - v - w, v, w])
}

/// Bilinear shape functions of a quad at (ξ, η), nodes counter-clockwise from (−1, −1).
pub fn quad_shape<T: Real>(xi: T, eta: T) -> [T; 4] {
    let q = T::from_f64(0.25);
    let (xm, xp, em, ep) = (T::ONE - xi, T::ONE + xi, T::ONE - eta, T::ONE + eta);
    [q * xm * em, q * xp * em, q * xp * ep, q * xm * ep]
}

/// Newton steps smaller than this (in ξ, η) count as converged (WGSL: `QUAD_CONVERGED`).
pub const QUAD_CONVERGED: f64 = 1e-4;

/// (ξ, η) of a point q in or near the plane of the quad y0..y3, by inverting the bilinear map
/// there (exact for a planar quad: the root of a quadratic, taken in its stable form, nearer
/// to the parameter square), clamped to the square (WGSL: `quad_parameters`).
fn quad_parameters<T: Real>(q: V3<T>, y: &[V3<T>; 4]) -> (T, T) {
    let (zero, one, two) = (T::ZERO, T::ONE, T::from_f64(2.0));
    let e = y[1] - y[0];
    let f = y[3] - y[0];
    let g = y[0] - y[1] + y[2] - y[3];
    let h = q - y[0];
    let n = (y[2] - y[0]).cross(y[3] - y[1]);
    let c2 = |a: V3<T>, b: V3<T>| a.cross(b).dot(n);
    // y(u, v) = y0 + e·u + f·v + g·u·v in the plane: k2·v² + k1·v + k0 = 0
    let k2 = c2(g, f);
    let k1 = c2(e, f) + c2(h, g);
    let k0 = c2(h, e);
    let sq = (k1 * k1 - T::from_f64(4.0) * k0 * k2).max_of(zero).sqrt();
    let t = if k1 >= zero { -k1 - sq } else { -k1 + sq };
    let va = div_or_zero(two * k0, t);
    let vb = div_or_zero(t, two * k2);
    let outside = |v: T| (-v).max_of(v - one).max_of(zero);
    let v = if k2 == zero || outside(va) <= outside(vb) {
        va
    } else {
        vb
    };
    let ev = e + g * v;
    let u = div_or_zero((h - f * v).dot(ev), ev.dot(ev));
    (
        (u + u - one).clamp_to(-one, one),
        (v + v - one).clamp_to(-one, one),
    )
}

/// Nearest point to `p` on the bilinear quad x0..x3 (see the module docs for the method).
pub fn closest_on_quad<T: Real>(p: V3<T>, x: [V3<T>; 4]) -> Projection<T> {
    quad_projection(p, x, true)
}

/// [`closest_on_quad`], stopping Newton at a fixed point (`stop`) or taking every step.
fn quad_projection<T: Real>(p: V3<T>, x: [V3<T>; 4], stop: bool) -> Projection<T> {
    let q = T::from_f64(0.25);
    let (one, zero) = (T::ONE, T::ZERO);
    // Work relative to node 0: round-off then scales with the facet, not the frame.
    let y = [V3::zero(), x[1] - x[0], x[2] - x[0], x[3] - x[0]];
    let pl = p - x[0];
    // y(ξ,η) = c0 + cx ξ + ce η + cxe ξη
    let c0 = (y[1] + y[2] + y[3]) * q;
    let cx = (y[1] + y[2] - y[3]) * q;
    let ce = (y[2] + y[3] - y[1]) * q;
    let cxe = (y[2] - y[1] - y[3]) * q;
    // Newton starts from the nearest point of the nearer triangle, (y0, y1, y2) or
    // (y0, y2, y3), mapped to (ξ, η) by inverting the bilinear map in the quad's plane: the
    // answer itself for a planar quad, near it otherwise. From the centre, Newton can overshoot
    // from corner to corner on a distorted quad and end on the boundary, missing an interior
    // minimum.
    let t1 = closest_on_triangle(pl, y[0], y[1], y[2]);
    let t2 = closest_on_triangle(pl, y[0], y[2], y[3]);
    let start = if t2.dist2 < t1.dist2 {
        t2.point
    } else {
        t1.point
    };
    let (mut xi, mut eta) = quad_parameters(start, &y);
    let residual = |xi: T, eta: T| c0 + cx * xi + ce * eta + cxe * (xi * eta) - pl;
    let mut f = residual(xi, eta).length2();
    let mut step = one;
    let bits = |v: T| v.to_f64().to_bits();
    for _ in 0..QUAD_ITERATIONS {
        let before = (bits(xi), bits(eta), bits(f));
        let r = residual(xi, eta);
        let gx = cx + cxe * eta;
        let ge = ce + cxe * xi;
        let a11 = gx.dot(gx);
        let a22 = ge.dot(ge);
        let b1 = gx.dot(r);
        let b2 = ge.dot(r);
        // Newton on |y − p|²/2 (y_ξη = cxe gives the off-diagonal term r·cxe); where that
        // Hessian is not positive definite, the Gauss–Newton one.
        let mut a12 = gx.dot(ge) + r.dot(cxe);
        let mut det = a11 * a22 - a12 * a12;
        if !(det > zero) {
            a12 = gx.dot(ge);
            det = a11 * a22 - a12 * a12;
        }
        let dxi = div_or_zero(a22 * b1 - a12 * b2, det);
        let deta = div_or_zero(a11 * b2 - a12 * b1, det);
        // a step within QUAD_TRUST is taken whole (near the answer, where comparing f32
        // distances would stall on round-off); a longer one backtracks: the whole step, or the
        // first of its halves, quarters, … that does not increase |y − p|² (a full step can
        // overshoot from corner to corner on a distorted quad); none: stay, unconverged
        let whole = dxi.abs_of().max_of(deta.abs_of()) <= T::from_f64(QUAD_TRUST);
        let mut s = one;
        step = one;
        for _ in 0..QUAD_HALVINGS {
            let nxi = (xi - dxi * s).clamp_to(-one, one);
            let neta = (eta - deta * s).clamp_to(-one, one);
            let nf = residual(nxi, neta).length2();
            if whole || nf <= f {
                step = (nxi - xi).abs_of().max_of((neta - eta).abs_of());
                xi = nxi;
                eta = neta;
                f = nf;
                break;
            }
            s = s * T::from_f64(0.5);
        }
        // a fixed point: the next steps start from the same (ξ, η, f) and leave them and the
        // step as this one did, so stopping here changes no bit
        if stop && (bits(xi), bits(eta), bits(f)) == before {
            break;
        }
    }
    let mut best_point = c0 + cx * xi + ce * eta + cxe * (xi * eta);
    let mut best_d2 = (pl - best_point).length2();
    let mut best_xi = xi;
    let mut best_eta = eta;
    // A converged stationary point strictly inside is the answer; otherwise the minimum lies
    // on the boundary: compare with the exact nearest points of the four straight edges.
    let strictly_inside = xi.abs_of() < one && eta.abs_of() < one;
    if !(strictly_inside && step < T::from_f64(QUAD_CONVERGED)) {
        // A clamped end point lies on an edge, where that edge's exact nearest point is at
        // least as near: only an unconverged interior end point stays a candidate.
        let mut have = strictly_inside;
        for e in 0..4usize {
            let a = y[e];
            let b = y[(e + 1) % 4];
            let ab = b - a;
            let t = div_or_zero((pl - a).dot(ab), ab.length2()).clamp_to(zero, one);
            let point = a + ab * t;
            let d2 = (pl - point).length2();
            if !have || d2 < best_d2 {
                have = true;
                let s = t + t - one; // runs from −1 to 1 along the edge
                let (exi, eeta) = match e {
                    0 => (s, -one),
                    1 => (one, s),
                    2 => (-s, one),
                    _ => (-one, -s),
                };
                best_point = point;
                best_d2 = d2;
                best_xi = exi;
                best_eta = eeta;
            }
        }
    }
    let gx = cx + cxe * best_eta;
    let ge = ce + cxe * best_xi;
    let mut normal = gx.cross(ge).normalize_or_zero();
    if normal.length2() == zero {
        normal = y[2].cross(y[3] - y[1]).normalize_or_zero();
    }
    Projection {
        point: best_point + x[0],
        weights: quad_shape(best_xi, best_eta),
        normal,
        dist2: best_d2,
    }
}

/// Nearest point on a facet given by 2, 3 or 4 node positions.
pub fn closest_on_facet<T: Real>(p: V3<T>, x: &[V3<T>]) -> Projection<T> {
    match x.len() {
        2 => closest_on_segment(p, x[0], x[1]),
        3 => closest_on_triangle(p, x[0], x[1], x[2]),
        _ => closest_on_quad(p, [x[0], x[1], x[2], x[3]]),
    }
}

/// cos(0.1°): a normal closer than this to the global x axis takes t1 from the z axis
/// (WGSL: `COS_TENTH_DEGREE`, the same value rounded to f32).
pub const COS_TENTH_DEGREE: f64 = 0.999_998_476_913_287_3;

/// Local tangent directions (t1, t2) at a contact point with unit normal `n`, by the standard
/// convention: t1 is the projection of the global x axis onto the tangent plane, or of the
/// global z axis when x lies within 0.1° of `n`; t2 = n × t1.
pub fn tangent_directions<T: Real>(n: V3<T>) -> (V3<T>, V3<T>) {
    let (zero, one) = (T::ZERO, T::ONE);
    let axis = if n.x.abs_of() > T::from_f64(COS_TENTH_DEGREE) {
        V3::new(zero, zero, one)
    } else {
        V3::new(one, zero, zero)
    };
    let t1 = (axis - n * axis.dot(n)).normalize_or_zero();
    (t1, n.cross(t1))
}

/// Local tangent directions of a contact normal in f32 (the kernel's convention), for outputs.
pub fn tangents_f32(n: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let (t1, t2) = tangent_directions(V3::new(n[0], n[1], n[2]));
    (t1.to_array(), t2.to_array())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn bits<T: Real>(r: &Projection<T>) -> Vec<u64> {
        let v = |a: V3<T>| [a.x, a.y, a.z].map(|c| c.to_f64().to_bits());
        let mut out = v(r.point).to_vec();
        out.extend(v(r.normal));
        out.extend(r.weights.map(|w| w.to_f64().to_bits()));
        out.push(r.dist2.to_f64().to_bits());
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2048, ..ProptestConfig::default() })]
        /// Stopping Newton at a fixed point changes no bit of the projection, in f32 and f64:
        /// on flat, warped, distorted and degenerate quads (nodes anywhere in a cube, one
        /// collapsed onto another), from points on, near and far from them.
        #[test]
        fn a_fixed_point_stops_newton_without_changing_a_bit(
            nodes in prop::collection::vec(-1.0f64..1.0, 12),
            warp in 0.0f64..1.0,
            p in prop::collection::vec(-3.0f64..3.0, 3),
            collapse in 0usize..6,
        ) {
            // a unit square warped out of its plane and distorted by `nodes`
            let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            let mut x: Vec<[f64; 3]> = (0..4)
                .map(|k| {
                    let d = &nodes[3 * k..3 * k + 3];
                    [square[k][0] + 0.4 * d[0], square[k][1] + 0.4 * d[1], warp * d[2]]
                })
                .collect();
            if collapse < 4 {
                x[collapse] = x[(collapse + 1) % 4];
            }
            let q = [x[0], x[1], x[2], x[3]].map(|a| V3::new(a[0], a[1], a[2]));
            let pt = V3::new(p[0], p[1], 0.2 * p[2]);
            prop_assert_eq!(
                bits(&quad_projection(pt, q, true)),
                bits(&quad_projection(pt, q, false))
            );
            let q32 = q.map(|a| V3::new(a.x as f32, a.y as f32, a.z as f32));
            let p32 = V3::new(pt.x as f32, pt.y as f32, pt.z as f32);
            prop_assert_eq!(
                bits(&quad_projection(p32, q32, true)),
                bits(&quad_projection(p32, q32, false))
            );
        }
    }
}
