//! Generated geometry for scenes, tests and benchmarks: plates, spheres, polylines and point
//! clouds, deterministic for a given seed.

/// A mesh: node positions (model units) and facets (node indices).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh<F> {
    /// Node positions.
    pub positions: Vec<[f64; 3]>,
    /// Facets.
    pub facets: Vec<F>,
}

/// A small deterministic random generator (SplitMix64), so scenes need no extra crate.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// Node index of grid point (i, j) of an (nx+1)×(ny+1) node grid.
fn grid_node(i: usize, j: usize, nx: usize) -> u32 {
    (j * (nx + 1) + i) as u32
}

/// Node positions of an nx×ny plate over [0, lx]×[0, ly] at height `z(x, y)`. `jitter`
/// (fraction of a cell, < 0.5) moves interior nodes randomly to make the mesh irregular.
fn plate_nodes(
    nx: usize,
    ny: usize,
    lx: f64,
    ly: f64,
    jitter: f64,
    seed: u64,
    z: &dyn Fn(f64, f64) -> f64,
) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    let (hx, hy) = (lx / nx as f64, ly / ny as f64);
    let mut out = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            let mut x = i as f64 * hx;
            let mut y = j as f64 * hy;
            if jitter > 0.0 && i > 0 && i < nx && j > 0 && j < ny {
                x += rng.range(-jitter, jitter) * hx;
                y += rng.range(-jitter, jitter) * hy;
            }
            out.push([x, y, z(x, y)]);
        }
    }
    out
}

/// A plate of nx×ny bilinear quads over [0, lx]×[0, ly], normal +z (for a flat `z`).
pub fn plate_quads(
    nx: usize,
    ny: usize,
    lx: f64,
    ly: f64,
    jitter: f64,
    seed: u64,
    z: &dyn Fn(f64, f64) -> f64,
) -> Mesh<[u32; 4]> {
    let positions = plate_nodes(nx, ny, lx, ly, jitter, seed, z);
    let mut facets = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            facets.push([
                grid_node(i, j, nx),
                grid_node(i + 1, j, nx),
                grid_node(i + 1, j + 1, nx),
                grid_node(i, j + 1, nx),
            ]);
        }
    }
    Mesh { positions, facets }
}

/// A plate of 2·nx·ny triangles (each quad cut along alternating diagonals), normal +z.
pub fn plate_triangles(
    nx: usize,
    ny: usize,
    lx: f64,
    ly: f64,
    jitter: f64,
    seed: u64,
    z: &dyn Fn(f64, f64) -> f64,
) -> Mesh<[u32; 3]> {
    Mesh {
        positions: plate_nodes(nx, ny, lx, ly, jitter, seed, z),
        facets: grid_triangles(nx, ny),
    }
}

/// The 2·nx·ny counter-clockwise triangles of an (nx+1)×(ny+1) node grid, each quad cut along
/// alternating diagonals.
fn grid_triangles(nx: usize, ny: usize) -> Vec<[u32; 3]> {
    let mut facets = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                grid_node(i, j, nx),
                grid_node(i + 1, j, nx),
                grid_node(i + 1, j + 1, nx),
                grid_node(i, j + 1, nx),
            );
            if (i + j) % 2 == 0 {
                facets.push([a, b, c]);
                facets.push([a, c, d]);
            } else {
                facets.push([a, b, d]);
                facets.push([b, c, d]);
            }
        }
    }
    facets
}

/// A sphere of radius `r` at `centre` as a latitude–longitude quad mesh (poles as collapsed
/// quads are avoided: the polar rows are triangles), outward normals.
pub fn sphere_triangles(n_lat: usize, n_lon: usize, r: f64, centre: [f64; 3]) -> Mesh<[u32; 3]> {
    let mut positions = vec![[centre[0], centre[1], centre[2] + r]];
    for i in 1..n_lat {
        let th = std::f64::consts::PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64;
            positions.push([
                centre[0] + r * th.sin() * ph.cos(),
                centre[1] + r * th.sin() * ph.sin(),
                centre[2] + r * th.cos(),
            ]);
        }
    }
    positions.push([centre[0], centre[1], centre[2] - r]);
    let south = (positions.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut facets = Vec::new();
    for j in 0..n_lon {
        facets.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            facets.push([a, b, c]);
            facets.push([a, c, d]);
        }
    }
    for j in 0..n_lon {
        facets.push([ring(n_lat - 1, j), south, ring(n_lat - 1, j + 1)]);
    }
    Mesh { positions, facets }
}

/// A 2D polyline of `n` segments along y = f(x) for x in [0, lx], running in −x direction so
/// that the segment normals (on the right of each segment) point towards +y.
pub fn polyline(
    n: usize,
    lx: f64,
    jitter: f64,
    seed: u64,
    f: &dyn Fn(f64) -> f64,
) -> Mesh<[u32; 2]> {
    let mut rng = SplitMix64::new(seed);
    let h = lx / n as f64;
    let positions: Vec<[f64; 3]> = (0..=n)
        .map(|i| {
            let mut x = i as f64 * h;
            if jitter > 0.0 && i > 0 && i < n {
                x += rng.range(-jitter, jitter) * h;
            }
            [x, f(x), 0.0]
        })
        .collect();
    let facets = (0..n).map(|i| [(i + 1) as u32, i as u32]).collect();
    Mesh { positions, facets }
}

/// `n` random points uniformly in the box [lo, hi] (z = lo\[2\] = hi\[2\] gives planar points).
pub fn point_cloud(n: usize, lo: [f64; 3], hi: [f64; 3], seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            [
                rng.range(lo[0], hi[0]),
                rng.range(lo[1], hi[1]),
                if hi[2] > lo[2] {
                    rng.range(lo[2], hi[2])
                } else {
                    lo[2]
                },
            ]
        })
        .collect()
}

/// The `n + 1` cell boundaries of `n` cells over [start, start + length], each cell `ratio`
/// times the one before it (1: uniform). A negative ratio grades from the far end: the cells
/// are smallest at `start + length`.
pub fn graded(start: f64, length: f64, n: usize, ratio: f64) -> Vec<f64> {
    graded_with_core(start, length, n, ratio, 1)
}

/// As [`graded`], with the first `core` cells at the fine end all of the finest size before
/// the sizes start to grow (`core` ≤ 1: as [`graded`]) — a uniform zone where a contact patch
/// needs it, graded beyond.
pub fn graded_with_core(start: f64, length: f64, n: usize, ratio: f64, core: usize) -> Vec<f64> {
    let r = ratio.abs();
    let flat = core.max(1) - 1;
    let sizes: Vec<f64> = (0..n)
        .map(|k| r.powi(k.saturating_sub(flat) as i32))
        .collect();
    let total: f64 = sizes.iter().sum();
    let mut out = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    out.push(0.0);
    for s in &sizes {
        acc += s;
        out.push(acc / total);
    }
    if ratio < 0.0 {
        out = out.iter().rev().map(|u| 1.0 - u).collect();
    }
    out.iter().map(|u| start + length * u).collect()
}

/// A box [0, lx]×[0, ly]×[0, lz] shifted by `origin`, as nx×ny×nz hexahedra each split into
/// six tetrahedra around its main diagonal (positive volumes).
pub fn block_tets(n: [usize; 3], l: [f64; 3], origin: [f64; 3]) -> Mesh<[u32; 4]> {
    block_tets_on([0, 1, 2].map(|a| graded(origin[a], l[a], n[a], 1.0)))
}

/// The box of hexahedra with cell boundaries `coords` per axis (increasing), each split into
/// six tetrahedra around its main diagonal (positive volumes). Node (i, j, k) has index
/// `k·(ny+1)·(nx+1) + j·(nx+1) + i`.
pub fn block_tets_on(coords: [Vec<f64>; 3]) -> Mesh<[u32; 4]> {
    let n = [0, 1, 2].map(|a| coords[a].len() - 1);
    let id =
        |i: usize, j: usize, k: usize| (k * (n[1] + 1) * (n[0] + 1) + j * (n[0] + 1) + i) as u32;
    let mut positions = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                positions.push([coords[0][i], coords[1][j], coords[2][k]]);
            }
        }
    }
    let mut facets = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let h = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ];
                for t in [
                    [0, 1, 2, 6],
                    [0, 2, 3, 6],
                    [0, 3, 7, 6],
                    [0, 7, 4, 6],
                    [0, 4, 5, 6],
                    [0, 5, 1, 6],
                ] {
                    let mut tet = [h[t[0]], h[t[1]], h[t[2]], h[t[3]]];
                    let p = |q: u32| positions[q as usize];
                    let (a, b, c, d) = (p(tet[0]), p(tet[1]), p(tet[2]), p(tet[3]));
                    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
                    let vol = u[0] * (v[1] * w[2] - v[2] * w[1])
                        - u[1] * (v[0] * w[2] - v[2] * w[0])
                        + u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if vol < 0.0 {
                        tet.swap(1, 2);
                    }
                    facets.push(tet);
                }
            }
        }
    }
    Mesh { positions, facets }
}

/// The rectangle of quads with cell boundaries `xs`, `ys` (increasing) in the x–y plane (z = 0),
/// each quad cut into two counter-clockwise triangles along alternating diagonals. Node (i, j)
/// has index `j·(nx+1) + i`.
pub fn rect_triangles_on(xs: &[f64], ys: &[f64]) -> Mesh<[u32; 3]> {
    let nx = xs.len() - 1;
    let mut positions = Vec::with_capacity(xs.len() * ys.len());
    for &y in ys {
        for &x in xs {
            positions.push([x, y, 0.0]);
        }
    }
    Mesh {
        positions,
        facets: grid_triangles(nx, ys.len() - 1),
    }
}

/// An arc of `n` segments of the circle of `radius` about `centre` (x–y plane) from angle
/// `from` to `to` (radians from +x, counter-clockwise), the segments running counter-clockwise
/// so that their normals point away from the centre. `ratio` grades the segments as
/// [`graded`] does (negative: smallest at `to`).
pub fn arc_segments(
    centre: [f64; 3],
    radius: f64,
    from: f64,
    to: f64,
    n: usize,
    ratio: f64,
) -> Mesh<[u32; 2]> {
    let positions = graded(from, to - from, n, ratio)
        .iter()
        .map(|a| {
            [
                centre[0] + radius * a.cos(),
                centre[1] + radius * a.sin(),
                0.0,
            ]
        })
        .collect();
    let facets = (0..n as u32).map(|k| [k, k + 1]).collect();
    Mesh { positions, facets }
}
