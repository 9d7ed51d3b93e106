//! Recursive coordinate bisection (RCB): a model's nodes split into parts of nearly equal counts
//! by planes normal to the coordinate axes, the domain decomposition a distributed run gives
//! each rank (issue 18). Each cut is across the longest side of the box of the nodes it splits,
//! at the count that gives each side its share of the parts; the two sides are split again until
//! every side is one part. The parts are boxes that do not overlap, so the contact surface cut
//! between ranks — and what they must exchange — grows like the cut planes' areas, not like the
//! model.
//!
//! The result depends on the coordinates alone, not on the order the nodes come in (ties of a
//! coordinate broken by the other two, then by index), and is the same on every machine: only
//! comparisons of the input's own f64 values are made.

use crate::error::{Error, Result};

/// The part (0..`parts`) of each of `points`, by recursive coordinate bisection. Part sizes
/// differ by at most one node where every part can have one (`parts` ≤ the node count); with
/// more parts than nodes, every node is a part of its own and the rest are empty.
///
/// Errors: `parts` = 0 or above `u32::MAX`; a coordinate that is not finite (named by node and
/// axis).
pub fn recursive_bisection(points: &[[f64; 3]], parts: usize) -> Result<Vec<u32>> {
    if parts == 0 || parts > u32::MAX as usize {
        return Err(Error::BadParameter {
            name: "parts",
            value: parts.to_string(),
            expected: "at least 1 and at most u32::MAX",
        });
    }
    for (node, p) in points.iter().enumerate() {
        for (axis, &value) in p.iter().enumerate() {
            if !value.is_finite() {
                return Err(Error::NonFiniteCoordinate { node, axis, value });
            }
        }
    }
    let mut part = vec![0u32; points.len()];
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    // an explicit stack of (range of `order`, first part, part count): no recursion depth
    let mut stack = vec![(0..order.len(), 0usize, parts)];
    while let Some((range, first, count)) = stack.pop() {
        let nodes = &mut order[range.clone()];
        if count == 1 || nodes.is_empty() {
            for &n in nodes.iter() {
                part[n as usize] = first as u32;
            }
            continue;
        }
        if nodes.len() <= count {
            // a node per part, in coordinate order along the longest side
            let axis = longest_axis(points, nodes);
            nodes.sort_unstable_by(|&a, &b| compare(points, axis, a, b));
            for (k, &n) in nodes.iter().enumerate() {
                part[n as usize] = (first + k) as u32;
            }
            continue;
        }
        let low_parts = count / 2;
        // the low side's share of the nodes, rounded so that sizes stay within one
        let low = ((nodes.len() as u128 * low_parts as u128 + count as u128 / 2) / count as u128)
            as usize;
        let axis = longest_axis(points, nodes);
        nodes.select_nth_unstable_by(low, |&a, &b| compare(points, axis, a, b));
        let mid = range.start + low;
        stack.push((range.start..mid, first, low_parts));
        stack.push((mid..range.end, first + low_parts, count - low_parts));
    }
    Ok(part)
}

/// The axis along which `nodes` spread the most (the lowest axis on a tie).
fn longest_axis(points: &[[f64; 3]], nodes: &[u32]) -> usize {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &n in nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(points[n as usize][a]);
            hi[a] = hi[a].max(points[n as usize][a]);
        }
    }
    let mut axis = 0;
    for a in 1..3 {
        if hi[a] - lo[a] > hi[axis] - lo[axis] {
            axis = a;
        }
    }
    axis
}

/// Order of nodes `a` and `b` along `axis`, ties broken by the next axes, then by index: a total
/// order, so that the cut is the same whatever order the nodes were in.
fn compare(points: &[[f64; 3]], axis: usize, a: u32, b: u32) -> std::cmp::Ordering {
    let (p, q) = (points[a as usize], points[b as usize]);
    (0..3)
        .map(|k| (axis + k) % 3)
        .map(|k| p[k].total_cmp(&q[k]))
        .find(|o| o.is_ne())
        .unwrap_or_else(|| a.cmp(&b))
}

/// The box (lowest and highest corner) of each part's nodes, `None` for an empty part.
pub fn part_boxes(points: &[[f64; 3]], part: &[u32], parts: usize) -> Vec<Option<[[f64; 3]; 2]>> {
    let mut boxes: Vec<Option<[[f64; 3]; 2]>> = vec![None; parts];
    for (p, &k) in points.iter().zip(part) {
        let b = boxes[k as usize].get_or_insert([*p, *p]);
        for a in 0..3 {
            b[0][a] = b[0][a].min(p[a]);
            b[1][a] = b[1][a].max(p[a]);
        }
    }
    boxes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible cloud of `n` points in a 3 × 2 × 1 box (SplitMix64).
    fn cloud(n: usize, seed: u64) -> Vec<[f64; 3]> {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as f64 / u64::MAX as f64
        };
        (0..n)
            .map(|_| [3.0 * next(), 2.0 * next(), next()])
            .collect()
    }

    #[test]
    fn parts_are_balanced_and_cover_every_node() {
        for n in [1usize, 2, 7, 100, 1001] {
            let pts = cloud(n, n as u64);
            for parts in 1..=9 {
                let p = recursive_bisection(&pts, parts).unwrap();
                let mut sizes = vec![0usize; parts];
                for &k in &p {
                    sizes[k as usize] += 1;
                }
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                if n >= parts {
                    assert!(hi - lo <= 1, "n {n}, {parts} parts: sizes {sizes:?}");
                } else {
                    // a node per part, the rest empty
                    assert_eq!(*hi, 1, "n {n}, {parts} parts: sizes {sizes:?}");
                    assert_eq!(sizes.iter().filter(|&&s| s == 1).count(), n);
                }
            }
        }
    }

    #[test]
    fn the_first_cut_is_a_plane_across_the_longest_side() {
        let pts = cloud(500, 3);
        let p = recursive_bisection(&pts, 2).unwrap();
        // x is the longest side (3 against 2 and 1): part 0 lies wholly below part 1
        let max0 = (0..pts.len())
            .filter(|&i| p[i] == 0)
            .map(|i| pts[i][0])
            .fold(f64::MIN, f64::max);
        let min1 = (0..pts.len())
            .filter(|&i| p[i] == 1)
            .map(|i| pts[i][0])
            .fold(f64::MAX, f64::min);
        assert!(max0 <= min1, "{max0} > {min1}");
        // and with four parts, the boxes of the parts do not overlap
        let p = recursive_bisection(&pts, 4).unwrap();
        let boxes = part_boxes(&pts, &p, 4);
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (boxes[i].unwrap(), boxes[j].unwrap());
                let apart = (0..3).any(|k| a[1][k] <= b[0][k] || b[1][k] <= a[0][k]);
                assert!(apart, "parts {i} and {j} overlap: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn the_partition_depends_on_the_coordinates_not_the_order() {
        let pts = cloud(300, 11);
        // reversed, and a grid with many equal coordinates
        let rev: Vec<[f64; 3]> = pts.iter().rev().copied().collect();
        let a = recursive_bisection(&pts, 5).unwrap();
        let b = recursive_bisection(&rev, 5).unwrap();
        for i in 0..pts.len() {
            assert_eq!(a[i], b[pts.len() - 1 - i], "node {i}");
        }
        let grid: Vec<[f64; 3]> = (0..64)
            .map(|i| [(i % 4) as f64, ((i / 4) % 4) as f64, (i / 16) as f64])
            .collect();
        let g = recursive_bisection(&grid, 8).unwrap();
        assert_eq!(g, recursive_bisection(&grid, 8).unwrap());
        let mut sizes = [0; 8];
        for &k in &g {
            sizes[k as usize] += 1;
        }
        assert_eq!(sizes, [8; 8]);
    }

    #[test]
    fn bad_input_is_named() {
        assert!(matches!(
            recursive_bisection(&cloud(3, 1), 0),
            Err(Error::BadParameter { name: "parts", .. })
        ));
        let mut pts = cloud(5, 2);
        pts[3][1] = f64::NAN;
        assert!(matches!(
            recursive_bisection(&pts, 2),
            Err(Error::NonFiniteCoordinate {
                node: 3,
                axis: 1,
                ..
            })
        ));
        assert_eq!(recursive_bisection(&[], 3).unwrap(), Vec::<u32>::new());
    }
}
