//! The search tree's shape, fixed per pair on the host: the active facets in Morton order of
//! their centroids, the leaves of a complete binary tree whose boxes the kernels refit at every
//! global search (`shaders/tree.wgsl`).
//!
//! A surface's topology does not change during a run, so facets next to each other on it stay
//! next to each other however it moves or deforms: the order taken once keeps each subtree a
//! compact patch of surface, and refitting the boxes (exact, one pass per six levels) costs far
//! less than binning or sorting again. The search stays exact whatever the order; only its work
//! grows if a patch is torn far apart.

/// Levels below the root of a tree over `n` leaves: the least `L` with `2^L ≥ n`.
pub fn levels(n: usize) -> u32 {
    n.max(1).next_power_of_two().trailing_zeros()
}

/// Spreads the low 21 bits of `x` to every third bit.
fn spread3(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f00000000ffff;
    x = (x | x << 16) & 0x1f0000ff0000ff;
    x = (x | x << 8) & 0x100f00f00f00f00f;
    x = (x | x << 4) & 0x10c30c30c30c30c3;
    (x | x << 2) & 0x1249249249249249
}

/// Spreads the low 32 bits of `x` to every second bit.
fn spread2(x: u64) -> u64 {
    let mut x = x & 0xffff_ffff;
    x = (x | x << 16) & 0x0000ffff0000ffff;
    x = (x | x << 8) & 0x00ff00ff00ff00ff;
    x = (x | x << 4) & 0x0f0f0f0f0f0f0f0f;
    x = (x | x << 2) & 0x3333333333333333;
    (x | x << 1) & 0x5555555555555555
}

/// The indices of `points` (`dim` = 2 or 3 coordinates used) in Morton order of their
/// positions quantised in cubic cells over their bounding box (21 bits of its longest side per
/// axis in 3D, 32 in 2D); ties (equal codes) by index, so the order is deterministic.
pub fn morton_order(points: &[[f64; 3]], dim: u32) -> Vec<u32> {
    let axes = if dim == 2 { 2 } else { 3 };
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for a in 0..axes {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let bits = if axes == 2 { 32 } else { 21 };
    let top = ((1u64 << bits) - 1) as f64;
    // one scale for every axis (cubic cells): a flat or tilted surface is then cut into square
    // patches, not into thin slabs across it along its shortest axis
    let span = (0..axes).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let q = |a: usize| {
                if span > 0.0 && span.is_finite() {
                    (((p[a] - lo[a]) / span) * top).clamp(0.0, top) as u64
                } else {
                    0
                }
            };
            let code = if axes == 2 {
                spread2(q(0)) | spread2(q(1)) << 1
            } else {
                spread3(q(0)) | spread3(q(1)) << 1 | spread3(q(2)) << 2
            };
            (code, i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The leaf slots of a complete binary tree of `levels(points.len())` levels over `points`
/// (`dim` = 2 or 3 coordinates used): each node's points split at their median along the
/// longest side of their bounding box, the lower half (rounded up) to the left child, so every
/// subtree is a compact patch however flat or tilted the surface. Slots a subtree does not
/// fill hold `u32::MAX` (no facet). Deterministic: equal coordinates are ordered by index.
pub fn leaf_order(points: &[[f64; 3]], dim: u32) -> Vec<u32> {
    let axes = if dim == 2 { 2 } else { 3 };
    let levels = levels(points.len());
    let mut slots = vec![u32::MAX; 1 << levels];
    let mut idx: Vec<u32> = (0..points.len() as u32).collect();
    // (first slot, slot count, the points' range in idx)
    let mut todo = vec![(0usize, 1usize << levels, 0usize, idx.len())];
    while let Some((slot, width, a, b)) = todo.pop() {
        let part = &mut idx[a..b];
        if part.len() <= 1 || width == 1 {
            slots[slot..slot + part.len()].copy_from_slice(part);
            continue;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &i in part.iter() {
            for ax in 0..axes {
                lo[ax] = lo[ax].min(points[i as usize][ax]);
                hi[ax] = hi[ax].max(points[i as usize][ax]);
            }
        }
        let axis = (0..axes)
            .max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y])))
            .unwrap_or(0);
        let half = part.len().div_ceil(2);
        part.select_nth_unstable_by(half - 1, |&x, &y| {
            points[x as usize][axis]
                .total_cmp(&points[y as usize][axis])
                .then(x.cmp(&y))
        });
        let w = width / 2;
        todo.push((slot, w, a, a + half));
        todo.push((slot + w, w, a + half, b));
    }
    slots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_boxes_never_overestimate_a_distance() {
        use crate::abi::boxes::*;
        let margin = 32.0 * f32::EPSILON * 3.7;
        let (step, inv) = box_step(margin);
        assert_eq!(step * inv, 1.0);
        assert!(step <= margin && 2.0 * step > margin);
        assert_eq!(box_step(0.0), (2f32.powi(-100), 2f32.powi(100)));
        // distance² from p to [lo, hi] per axis, in f64
        let d2 = |p: [f32; 3], lo: [f32; 3], hi: [f32; 3]| -> f64 {
            (0..3)
                .map(|a| {
                    let d = (lo[a] as f64 - p[a] as f64)
                        .max(p[a] as f64 - hi[a] as f64)
                        .max(0.0);
                    d * d
                })
                .sum()
        };
        let mut rng = crate::mesh::SplitMix64::new(7);
        // the grid reaches ±2^20 steps ≈ ±8 here: boxes and points inside and far beyond it
        for _ in 0..20_000 {
            let scale = [1e-3, 1.0, 3.7, 50.0, 1e30][(rng.next_u64() % 5) as usize];
            let mut v = || rng.range(-scale, scale) as f32;
            let (a, b): ([f32; 3], [f32; 3]) = ([v(), v(), v()], [v(), v(), v()]);
            let p = [v(), v(), v()];
            let lo: [f32; 3] = std::array::from_fn(|i| a[i].min(b[i]));
            let hi: [f32; 3] = std::array::from_fn(|i| a[i].max(b[i]));
            let packed = pack(lo.map(|x| code_lo(x, inv)), hi.map(|x| code_hi(x, inv)));
            assert!(!is_empty(packed));
            let (qlo, qhi) = unpack(packed, step);
            let q = p.map(|x| point(x, step));
            assert!(
                d2(q, qlo, qhi) <= d2(p, lo, hi),
                "overestimated: p {p:?}, box {lo:?}..{hi:?}"
            );
            for i in 0..3 {
                // inside the grid: holds the box, at most one step wider
                if lo[i].abs() < 1_048_000.0 * step {
                    assert!(qlo[i] <= lo[i] && lo[i] - qlo[i] <= step);
                }
                if hi[i].abs() < 1_048_000.0 * step {
                    assert!(qhi[i] >= hi[i] && qhi[i] - hi[i] <= step);
                }
            }
        }
        // the codes are those of the library's floor and ceil (the shaders' builtins)
        let mut rng = crate::mesh::SplitMix64::new(8);
        for k in 0..100_000 {
            let x = match k % 4 {
                0 => rng.range(-4.0, 4.0) as f32,
                1 => (rng.range(-20.0, 20.0) as f32).round() * step,
                2 => rng.range(-1e9, 1e9) as f32,
                _ => f32::from_bits(rng.next_u64() as u32),
            };
            if !x.is_finite() {
                continue;
            }
            let lo = ((x * inv).floor() + BOX_BIAS).clamp(0.0, (BOX_TOP - 1) as f32) as u32;
            let hi = ((x * inv).ceil() + BOX_BIAS).clamp(1.0, BOX_TOP as f32) as u32;
            assert_eq!((code_lo(x, inv), code_hi(x, inv)), (lo, hi), "{x:e}");
        }
        assert!(is_empty(EMPTY));
        assert_eq!(codes(EMPTY), ([BOX_TOP; 3], [0; 3]));
        let c = [3, 1 << 20, BOX_TOP - 1];
        assert_eq!(codes(pack(c, [1, 77, BOX_TOP])), (c, [1, 77, BOX_TOP]));
    }

    #[test]
    fn levels_cover_the_leaves() {
        assert_eq!(levels(0), 0);
        assert_eq!(levels(1), 0);
        assert_eq!(levels(2), 1);
        assert_eq!(levels(3), 2);
        assert_eq!(levels(1024), 10);
        assert_eq!(levels(1025), 11);
    }

    #[test]
    fn leaf_order_splits_the_longest_side_at_the_median() {
        // 5 points on a line along y: 3 to the left subtree (slots 0..4), 2 to the right
        let pts: Vec<[f64; 3]> = [3.0, 0.0, 4.0, 1.0, 2.0]
            .iter()
            .map(|&y| [0.0, y, 0.0])
            .collect();
        let slots = leaf_order(&pts, 3);
        assert_eq!(slots.len(), 8);
        assert_eq!(slots, vec![1, 3, 4, u32::MAX, 0, u32::MAX, 2, u32::MAX]);
        // every point exactly once
        let pts: Vec<[f64; 3]> = (0..1000)
            .map(|i| [(i % 37) as f64, (i % 11) as f64 * 0.01, 0.0])
            .collect();
        let mut seen: Vec<u32> = leaf_order(&pts, 2)
            .into_iter()
            .filter(|&i| i != u32::MAX)
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..1000).collect::<Vec<u32>>());
    }

    #[test]
    fn morton_order_follows_the_z_curve() {
        // a 4×4 grid of points: the Z curve visits each 2×2 quadrant in turn
        let pts: Vec<[f64; 3]> = (0..16)
            .map(|i| [(i % 4) as f64, (i / 4) as f64, 0.0])
            .collect();
        let order = morton_order(&pts, 2);
        assert_eq!(
            order,
            vec![0, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15]
        );
        // 3D: the first octant's 8 corners come first
        let pts: Vec<[f64; 3]> = (0..64)
            .map(|i| [(i % 4) as f64, (i / 4 % 4) as f64, (i / 16) as f64])
            .collect();
        let order = morton_order(&pts, 3);
        let mut first: Vec<u32> = order[..8].to_vec();
        first.sort_unstable();
        assert_eq!(first, vec![0, 1, 4, 5, 16, 17, 20, 21]);
        // equal points: by index
        assert_eq!(morton_order(&[[1.0; 3]; 3], 3), vec![0, 1, 2]);
    }
}
