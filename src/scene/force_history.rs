//! A run's contact force history in bounded memory: each increment's (middle, force) as it is,
//! up to [`FORCE_BLOCKS`] of them; past that, neighbouring entries are merged in pairs — each
//! entry then a block of 2, 4, 8, … increments, kept as its middle and its mean force over its
//! span — so that a run of 10⁸ increments holds as many entries as one of 10⁵. The summary's
//! force statistics (`account.rs`) read these entries: a run that fits is unchanged to the bit;
//! a longer one has them at the resolution of a block (its mean force to round-off where the
//! increment is constant, its times to a block), and its impulse summed increment by increment.
//! Where contact starts and ends is kept exactly.

/// Entries kept at most; a power of two (3 MB of history).
pub const FORCE_BLOCKS: usize = 1 << 17;

/// A finished block: its span (start, end) and the force's integral over it.
#[derive(Clone, Copy, Debug)]
struct Block {
    start: f64,
    end: f64,
    impulse: f64,
    /// The single increment's own (middle, force), for a block of one (kept as given).
    own: (f64, f64),
}

/// The force history of a run, bounded (see the module doc).
#[derive(Clone, Debug)]
pub struct ForceHistory {
    blocks: Vec<Block>,
    /// Increments per block (a power of two).
    per_block: usize,
    /// The block being filled: its start, its end so far, its impulse so far and its
    /// increments.
    open: Option<(f64, f64, f64, usize)>,
    /// The middle of the first and of the last increment with a force.
    first: Option<f64>,
    last: Option<f64>,
    cap: usize,
}

impl Default for ForceHistory {
    fn default() -> Self {
        Self::with_capacity(FORCE_BLOCKS)
    }
}

impl ForceHistory {
    /// A history that keeps at most `cap` entries (an even number ≥ 2).
    pub fn with_capacity(cap: usize) -> Self {
        let cap = cap.max(2) & !1;
        Self {
            blocks: Vec::new(),
            per_block: 1,
            open: None,
            first: None,
            last: None,
            cap,
        }
    }

    /// The increment from `time - step` to `time`, with a total contact force of magnitude
    /// `force` (≥ 0).
    pub fn push(&mut self, time: f64, step: f64, force: f64) {
        let middle = time - 0.5 * step;
        if force > 0.0 {
            self.first.get_or_insert(middle);
            self.last = Some(middle);
        }
        let (start, _, impulse, count) = self.open.take().unwrap_or((time - step, 0.0, 0.0, 0));
        let (impulse, count) = (impulse + force * step, count + 1);
        if count < self.per_block {
            self.open = Some((start, time, impulse, count));
            return;
        }
        self.blocks.push(Block {
            start,
            end: time,
            impulse,
            own: (middle, force),
        });
        if self.blocks.len() == self.cap {
            self.merge();
        }
    }

    /// Merges neighbouring blocks in pairs: half as many, twice as long.
    fn merge(&mut self) {
        let merged: Vec<Block> = self
            .blocks
            .chunks_exact(2)
            .map(|p| Block {
                start: p[0].start,
                end: p[1].end,
                impulse: p[0].impulse + p[1].impulse,
                own: (f64::NAN, f64::NAN),
            })
            .collect();
        self.blocks = merged;
        self.per_block *= 2;
    }

    /// Increments per entry: 1 until the history filled, then 2, 4, ….
    pub fn per_entry(&self) -> usize {
        self.per_block
    }

    /// The force's integral over the run, Σ force × increment (in the order they came).
    pub fn impulse(&self) -> f64 {
        let open = self.open.map_or(0.0, |o| o.2);
        self.blocks.iter().map(|b| b.impulse).sum::<f64>() + open
    }

    /// The middle of the first and of the last increment with a contact force.
    pub fn contact_span(&self) -> (Option<f64>, Option<f64>) {
        (self.first, self.last)
    }

    /// The entries (middle, force): each increment's own while they fit, else each block's
    /// middle and mean force; a block still filling at the end is the last entry.
    pub fn entries(&self) -> Vec<(f64, f64)> {
        let block = |b: &Block| {
            if self.per_block == 1 {
                b.own
            } else {
                (0.5 * (b.start + b.end), b.impulse / (b.end - b.start))
            }
        };
        let mut out: Vec<(f64, f64)> = self.blocks.iter().map(block).collect();
        // the increments of a block still filling (only once blocks hold more than one)
        if let Some((start, end, impulse, _)) = self.open.filter(|o| o.1 > o.0) {
            out.push((0.5 * (start + end), impulse / (end - start)));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::half_plateau_edges;

    /// A force pulse over `n` increments of `dt`: zero, a ramp, a plateau with ripple, zero.
    fn pulse(n: usize, dt: f64) -> Vec<(f64, f64, f64)> {
        (1..=n)
            .map(|k| {
                let t = k as f64 * dt;
                let s = k as f64 / n as f64;
                let f = if (0.2..0.8).contains(&s) {
                    (10.0 * (s - 0.2)).min(1.0) * (3.0 + 0.1 * (37.0 * s).sin())
                } else {
                    0.0
                };
                (t, dt, f)
            })
            .collect()
    }

    #[test]
    fn a_history_that_fits_is_every_increment_as_given() {
        let mut h = ForceHistory::with_capacity(64);
        let incs = pulse(63, 1e-3);
        for &(t, dt, f) in &incs {
            h.push(t, dt, f);
        }
        let want: Vec<(f64, f64)> = incs.iter().map(|&(t, dt, f)| (t - 0.5 * dt, f)).collect();
        assert_eq!(h.entries(), want);
        assert_eq!(h.per_entry(), 1);
    }

    #[test]
    fn a_longer_history_stays_bounded_and_keeps_its_statistics() {
        // the same pulse at 100 times the increments as the history holds, constant increment
        let (n, dt) = (6400 + 37, 1e-4);
        let incs = pulse(n, dt);
        let exact: Vec<(f64, f64)> = incs.iter().map(|&(t, dt, f)| (t - 0.5 * dt, f)).collect();
        let mut h = ForceHistory::with_capacity(64);
        for &(t, dt, f) in &incs {
            h.push(t, dt, f);
            assert!(h.entries().len() <= 64);
        }
        assert_eq!(h.per_entry(), 128);
        let (i0, i1, imp0, p0) = half_plateau_edges(&exact);
        let (i, r, imp, p) = half_plateau_edges(&h.entries());
        // the impulse to round-off (every block's mean times its span), the plateau to its
        // ripple, the times to a block
        assert!((imp - imp0).abs() < 1e-12 * imp0, "{imp} against {imp0}");
        let sum: f64 = incs.iter().map(|&(_, dt, f)| f * dt).sum();
        assert!((h.impulse() - sum).abs() < 1e-12 * sum);
        assert!((p - p0).abs() < 0.02 * p0, "{p} against {p0}");
        let block = 128.0 * dt;
        assert!((i - i0).abs() < block && (r - i1).abs() < block);
        // where contact starts and ends: exactly
        let first = exact.iter().find(|e| e.1 > 0.0).unwrap().0;
        let last = exact.iter().rev().find(|e| e.1 > 0.0).unwrap().0;
        assert_eq!(h.contact_span(), (Some(first), Some(last)));
    }
}
