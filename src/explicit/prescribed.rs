//! Prescribed motion: a node's velocity or displacement along an axis as a function of time.

/// A prescribed motion of one degree of freedom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// Constant velocity (model length per time).
    Velocity(f64),
    /// A smooth ramp to `displacement` over `duration`, then held: velocity
    /// (Δ/T)·(1 − cos 2πt/T), which starts and ends at zero acceleration.
    Ramp {
        /// Total displacement.
        displacement: f64,
        /// Ramp time.
        duration: f64,
    },
}

impl Motion {
    /// Velocity at time `t`.
    pub fn velocity(&self, t: f64) -> f64 {
        match *self {
            Motion::Velocity(v) => v,
            Motion::Ramp {
                displacement,
                duration,
            } => {
                if t >= duration || t < 0.0 {
                    0.0
                } else {
                    displacement / duration
                        * (1.0 - (2.0 * std::f64::consts::PI * t / duration).cos())
                }
            }
        }
    }

    /// Displacement at time `t` (the integral of [`Motion::velocity`] from 0).
    pub fn displacement(&self, t: f64) -> f64 {
        match *self {
            Motion::Velocity(v) => v * t,
            Motion::Ramp {
                displacement,
                duration,
            } => {
                let tau = t.clamp(0.0, duration) / duration;
                displacement
                    * (tau
                        - (2.0 * std::f64::consts::PI * tau).sin() / (2.0 * std::f64::consts::PI))
            }
        }
    }
}

/// A degree of freedom whose motion is prescribed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prescribed {
    /// Node index.
    pub node: u32,
    /// Direction: 0 = x, 1 = y, 2 = z.
    pub dof: usize,
    /// The motion.
    pub motion: Motion,
}
