//! A Contact's state as bytes, for a host program's restart file.
//!
//! The bytes hold what a penalty increment carries from one increment to the next and cannot
//! find again from positions: the reference increment of the automatic stiffness and every
//! penalty pass's per-slave state (friction force carried over, tributary area, frictional
//! dissipation, behind-a-free-edge flag). Restored into a Contact built from the same model,
//! the increments after it give the same forces as the run that saved it, bit for bit
//! (tests/capi.rs, on the CPU path and the adapters) — the first increment after a restore
//! searches globally where the saved run may have tracked locally, and both find the same
//! nearest facet. Not held: small and infinitesimal sliding anchors (found again at the
//! restart's positions) and the kinematic pairs' running dissipation total (an output).

use super::Contact;
use crate::abi::penalty::SlaveState;
use crate::error::{Error, Result};

/// The first bytes of a saved state: the format's name and version.
const MAGIC: &[u8; 8] = b"abutst01";

/// Bytes of one slave's saved state (eight f32).
const SLAVE_BYTES: usize = std::mem::size_of::<SlaveState>();

impl Contact {
    /// The contact's state as bytes (little-endian; see the module doc for what it holds):
    /// with [`Contact::restore_state`] on a Contact built from the same model, a restart
    /// continues bit for bit. Reads the penalty state back from the device on a GPU.
    pub fn save_state(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&self.dt_ref.unwrap_or(f64::NAN).to_le_bytes());
        out.extend_from_slice(&(self.pairs.len() as u64).to_le_bytes());
        for (k, p) in self.pairs.iter().enumerate() {
            // in the node set's order, whatever order the pass keeps
            let states = p.map.to_caller(&self.exec.penalty_state(k)?);
            out.extend_from_slice(&(p.id.0 as u64).to_le_bytes());
            out.extend_from_slice(&(states.len() as u64).to_le_bytes());
            for s in &states {
                for x in s.tangential_area.iter().chain(&s.history) {
                    out.extend_from_slice(&x.to_le_bytes());
                }
            }
        }
        Ok(out)
    }

    /// Restores a state [`Contact::save_state`] gave, on a Contact built from the same model.
    /// Errors (nothing changed): bytes that are not a saved state, or one saved from a model
    /// with other penalty pairs or other slave counts (naming the pair).
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<()> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(MAGIC.len())? != MAGIC {
            return Err(bad("does not start with abut's state marker (abutst01)"));
        }
        let dt_ref = f64::from_le_bytes(r.array()?);
        let passes = u64::from_le_bytes(r.array()?);
        if passes != self.pairs.len() as u64 {
            return Err(Error::LengthMismatch {
                what: "saved contact state: penalty passes (the model's pairs)",
                expected: self.pairs.len(),
                got: passes as usize,
            });
        }
        let mut all = Vec::with_capacity(self.pairs.len());
        for p in &self.pairs {
            let id = u64::from_le_bytes(r.array()?);
            if id != p.id.0 as u64 {
                return Err(Error::UnknownId {
                    what: "saved contact state: penalty pair",
                    id: id as usize,
                });
            }
            let n = u64::from_le_bytes(r.array()?) as usize;
            if n != p.output.slaves.len() {
                return Err(Error::LengthMismatch {
                    what: "saved contact state: slaves of a penalty pass",
                    expected: p.output.slaves.len(),
                    got: n,
                });
            }
            let raw = r.take(n.checked_mul(SLAVE_BYTES).ok_or_else(|| bad("overflows"))?)?;
            let states: Vec<SlaveState> = raw
                .chunks_exact(SLAVE_BYTES)
                .map(|c| {
                    let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
                    SlaveState {
                        tangential_area: [f(0), f(1), f(2), f(3)],
                        history: [f(4), f(5), f(6), f(7)],
                    }
                })
                .collect();
            all.push(states);
        }
        if r.at != bytes.len() {
            return Err(bad("has bytes after the last pass"));
        }
        if !(dt_ref.is_nan() || dt_ref.is_finite() && dt_ref > 0.0) {
            return Err(bad("has a reference increment that is not positive"));
        }
        for (k, s) in all.iter().enumerate().take(self.pairs.len()) {
            let s = self.pairs[k].map.to_pass(s);
            self.exec.set_penalty_state(k, &s);
        }
        self.dt_ref = (!dt_ref.is_nan()).then_some(dt_ref);
        Ok(())
    }
}

fn bad(what: &'static str) -> Error {
    Error::BadParameter {
        name: "saved contact state",
        value: what.into(),
        expected: "the bytes Contact::save_state gave, whole",
    }
}

/// Reads a saved state front to back.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| bad("ends early"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        Ok(self.take(N)?.try_into().expect("N bytes taken"))
    }
}
