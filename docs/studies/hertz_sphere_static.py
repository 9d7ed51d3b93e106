#!/usr/bin/env python3
"""Static check of scenes/hertz_sphere.toml, independent of abut.

Solves the same problem statically (numpy + scipy): a rigid sphere of radius R pressed by δ into
an axisymmetric block of constant-strain triangles (the mesh abut's `rect` part builds: the same
graded coordinates with a uniform core, the same alternating diagonals), bottom fixed, axis
radially fixed, frictionless contact on the surface nodes by an active set. It separates the
errors a force–indentation comparison against Hertz mixes up:

  linear  the gap measured at the surface nodes' original radii, as Hertz's theory does;
  geo     the gap at the nodes' displaced radii, as a finite-sliding contact in the explicit
          solver sees it: the surface slides inward under the sphere where it sits lower.

Against Hertz, F = (4/3)·E*·√R·δ^1.5, and Sneddon's exact linear solution for a sphere (Hertz's
paraboloid replaced by the sphere). Usage: python3 hertz_sphere_static.py (needs numpy, scipy).
"""
import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl


def graded_with_core(length, n, ratio, core):
    """abut::mesh::graded_with_core from 0 (finest at 0)."""
    flat = max(core, 1) - 1
    sizes = np.array([ratio ** max(k - flat, 0) for k in range(n)])
    return length * np.concatenate([[0.0], np.cumsum(sizes) / sizes.sum()])


def indent(L, n, ratio, core, delta, R=1.0, E=1.0, nu=0.3, geo=False):
    """Total force (whole circumference) at indentation delta, and the contact radius."""
    xs = graded_with_core(L, n, ratio, core)
    ys = -graded_with_core(L, n, ratio, core)[::-1]
    nx = ny = n
    X, Y = np.meshgrid(xs, ys)
    P = np.stack([X.ravel(), Y.ravel()], 1)
    nid = lambda i, j: j * (nx + 1) + i
    tris = []
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)
            tris += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    T = np.array(tris)
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.array([[lam + 2 * mu, lam, lam, 0], [lam, lam + 2 * mu, lam, 0],
                  [lam, lam, lam + 2 * mu, 0], [0, 0, 0, mu]])
    p = P[T]
    x, y = p[:, :, 0], p[:, :, 1]
    A = 0.5 * ((x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0]))
    rb = x.mean(1)
    b, c = np.zeros((len(T), 3)), np.zeros((len(T), 3))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        b[:, i] = (y[:, j] - y[:, k]) / (2 * A)
        c[:, i] = (x[:, k] - x[:, j]) / (2 * A)
    # strains (rr, zz, θθ at the centroid, rz), per radian: ∫ BᵀDB r dA with r = r̄
    B = np.zeros((len(T), 4, 6))
    B[:, 0, 0::2], B[:, 1, 1::2], B[:, 2, 0::2] = b, c, 1 / (3 * rb[:, None])
    B[:, 3, 0::2], B[:, 3, 1::2] = c, b
    Ke = np.einsum('eki,kl,elj->eij', B, D, B) * (A * rb)[:, None, None]
    dofs = np.stack([2 * T[:, 0], 2 * T[:, 0] + 1, 2 * T[:, 1], 2 * T[:, 1] + 1,
                     2 * T[:, 2], 2 * T[:, 2] + 1], 1)
    N = 2 * len(P)
    K = sp.csr_matrix((Ke.ravel(), (np.repeat(dofs, 6, 1).ravel(), np.tile(dofs, (1, 6)).ravel())),
                      shape=(N, N))
    fixed = {2 * nid(0, j) for j in range(ny + 1)}
    fixed |= {2 * nid(i, 0) for i in range(nx + 1)} | {2 * nid(i, 0) + 1 for i in range(nx + 1)}
    top = [nid(i, ny) for i in range(nx + 1)]
    ur = np.zeros(nx + 1)
    active = {0}
    for _ in range(200):
        r = xs + ur if geo else xs
        # a surface node may not rise above the sphere: u_z ≤ −(δ − (R − √(R² − r²)))
        target = -(delta - (R - np.sqrt(np.maximum(R * R - r * r, 0.0))))
        pres = {2 * top[i] + 1: target[i] for i in active}
        cons = sorted(fixed | set(pres))
        free = np.setdiff1d(np.arange(N), cons)
        u = np.zeros(N)
        for dof, v in pres.items():
            u[dof] = v
        u[free] = spl.spsolve(K[free][:, free].tocsc(), -K[free][:, cons] @ u[cons])
        react = K @ u
        ur_new = u[[2 * t for t in top]]
        moved = np.abs(ur_new - ur).max() > 1e-12
        ur = ur_new
        new = {i for i in active if react[2 * top[i] + 1] <= 0}  # the sphere only pushes
        new |= {i for i in range(nx + 1) if i not in active and xs[i] < R
                and u[2 * top[i] + 1] > target[i] + 1e-15}
        if new == active and not (geo and moved):
            break
        active = new
    force = -2 * math.pi * sum(react[2 * top[i] + 1] for i in active)
    return force, xs[max(active)]


def sneddon(delta, R=1.0, e_star=1 / 0.91):
    """Exact linear solution for a rigid sphere (not a paraboloid) on a half-space."""
    lo, hi = 1e-9, R * (1 - 1e-12)
    for _ in range(200):
        a = 0.5 * (lo + hi)
        lo, hi = (a, hi) if 0.5 * a * math.log((R + a) / (R - a)) < delta else (lo, a)
    return 0.5 * e_star * ((a * a + R * R) * math.log((R + a) / (R - a)) - 2 * a * R)


if __name__ == "__main__":
    cases = [
        # (what, L, n, ratio, core, δ)
        ("first scene: a/R = 0.22, graded 1.08 from 0.0064", 8, 60, 1.08, 1, 0.05),
        ("same, block of 32 R", 32, 78, 1.08, 1, 0.05),
        ("a/R = 0.11", 32, 78, 1.08, 1, 0.0125),
        ("scene: a/R = 0.05, core a/15 over 1.5 a", 8, 79, 1.1, 22, 0.0025),
        ("scene at δmax/2", 8, 79, 1.1, 22, 0.00125),
    ]
    print(f"{'case':<48} {'linear':>8} {'geo':>8} {'Sneddon':>8}  (error against Hertz)")
    for what, L, n, g, core, d in cases:
        hertz = 4 / 3 / 0.91 * d ** 1.5
        lin, _ = indent(L, n, g, core, d)
        geo, _ = indent(L, n, g, core, d, geo=True)
        print(f"{what:<48} {100 * (lin / hertz - 1):+7.2f}% {100 * (geo / hertz - 1):+7.2f}% "
              f"{100 * (sneddon(d) / hertz - 1):+7.2f}%")
