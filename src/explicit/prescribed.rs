//! Prescribed motion: a node's velocity or displacement along an axis as a function of time;
//! loads on their own curves.

/// A curve of time scaling a prescribed value: Abaqus' `*AMPLITUDE`, tabular (linear between
/// points) or smooth step (a quintic between points, zero rate at each). Before the first point
/// it holds the first value, after the last the last.
#[derive(Clone, Debug, PartialEq)]
pub struct Amplitude {
    /// Smooth step (quintic 10ξ³ − 15ξ⁴ + 6ξ⁵ between points); linear otherwise.
    pub smooth: bool,
    /// (time, value) points, time increasing.
    pub points: Vec<(f64, f64)>,
}

impl Amplitude {
    /// Abaqus/Explicit's default for a value given in a step without an amplitude: applied at
    /// once (1 from the start).
    pub fn step() -> Self {
        Self {
            smooth: false,
            points: vec![(0.0, 1.0)],
        }
    }

    /// The amplitude at time `t`.
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        let Some(&(t0, a0)) = p.first() else {
            return 1.0;
        };
        if t <= t0 {
            return a0;
        }
        for w in p.windows(2) {
            let ((ta, a), (tb, b)) = (w[0], w[1]);
            if t <= tb {
                let xi = if tb > ta { (t - ta) / (tb - ta) } else { 1.0 };
                return a + (b - a) * self.shape(xi);
            }
        }
        p[p.len() - 1].1
    }

    /// The rate of [`Amplitude::value`] at time `t` (0 outside the points; at a point, the
    /// segment's before it).
    pub fn rate(&self, t: f64) -> f64 {
        for w in self.points.windows(2) {
            let ((ta, a), (tb, b)) = (w[0], w[1]);
            if t > ta && t <= tb && tb > ta {
                let xi = (t - ta) / (tb - ta);
                let ds = if self.smooth {
                    30.0 * xi * xi * (1.0 - xi) * (1.0 - xi)
                } else {
                    1.0
                };
                return (b - a) * ds / (tb - ta);
            }
        }
        0.0
    }

    fn shape(&self, xi: f64) -> f64 {
        if self.smooth {
            xi * xi * xi * (10.0 - 15.0 * xi + 6.0 * xi * xi)
        } else {
            xi
        }
    }

    /// The integral of [`Amplitude::value`] from 0 to `t` (a velocity amplitude's
    /// displacement per unit value), exact for both definitions.
    pub fn integral(&self, t: f64) -> f64 {
        let p = &self.points;
        let Some(&(t0, a0)) = p.first() else {
            return t;
        };
        if t <= 0.0 {
            return 0.0;
        }
        // before the first point: its value
        let mut sum = a0 * t.min(t0).max(0.0);
        for w in p.windows(2) {
            let ((ta, a), (tb, b)) = (w[0], w[1]);
            let (lo, hi) = (ta.max(0.0), tb.min(t));
            if hi <= lo || tb <= ta {
                continue;
            }
            // ∫ a + (b − a)·s(ξ) dt, with ∫ s dξ = ξ²/2 (linear) or 5ξ⁴/2 − 3ξ⁵ + ξ⁶
            // (smooth step)
            let h = tb - ta;
            let antiderivative = |x: f64| {
                let xi = (x - ta) / h;
                let s = if self.smooth {
                    xi.powi(4) * (2.5 - 3.0 * xi + xi * xi)
                } else {
                    0.5 * xi * xi
                };
                a * x + (b - a) * h * s
            };
            sum += antiderivative(hi) - antiderivative(lo);
        }
        let (tn, an) = p[p.len() - 1];
        if t > tn {
            sum += an * (t - tn.max(0.0));
        }
        sum
    }
}

/// A prescribed motion of one degree of freedom.
#[derive(Clone, Debug, PartialEq)]
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
    /// A displacement `value`·a(t), or a velocity `value`·a(t) (Abaqus' `*BOUNDARY` with
    /// `AMPLITUDE=`, `TYPE=DISPLACEMENT|VELOCITY`).
    Amplitude {
        /// The value the amplitude scales.
        value: f64,
        /// The curve a(t).
        amplitude: std::sync::Arc<Amplitude>,
        /// The value is a velocity (its displacement the amplitude's integral).
        velocity: bool,
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
            Motion::Amplitude {
                value,
                ref amplitude,
                velocity,
            } => {
                if velocity {
                    value * amplitude.value(t)
                } else {
                    value * amplitude.rate(t)
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
            Motion::Amplitude {
                value,
                ref amplitude,
                velocity,
            } => {
                if velocity {
                    value * amplitude.integral(t)
                } else if t <= 0.0 {
                    // a displacement applied at once still starts from where the node is
                    0.0
                } else {
                    value * amplitude.value(t)
                }
            }
        }
    }
}

/// A degree of freedom whose motion is prescribed.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescribed {
    /// Node index.
    pub node: u32,
    /// Direction: 0 = x, 1 = y, 2 = z.
    pub dof: usize,
    /// The motion.
    pub motion: Motion,
    /// When it acts (total time): an increment whose midpoint lies in `[from, until)`; the
    /// degree of freedom is free outside (a deck step's boundary condition, removed or
    /// replaced in a later step). `(−∞, ∞)`: always.
    pub active: (f64, f64),
    /// `Some(x0)`: the motion is the total displacement from the reference coordinate `x0`
    /// (Abaqus' displacement boundary condition in a later step), each increment reaching
    /// `x0 + displacement(t + dt)` from where the node is; `None`: the motion's own increments.
    pub origin: Option<f64>,
}

impl Prescribed {
    /// `motion` on direction `dof` of `node`, always, by its own increments.
    pub fn new(node: u32, dof: usize, motion: Motion) -> Self {
        Self {
            node,
            dof,
            motion,
            active: (f64::NEG_INFINITY, f64::INFINITY),
            origin: None,
        }
    }

    /// Whether it acts over the increment of `dt` from `t`.
    pub fn acts(&self, t: f64, dt: f64) -> bool {
        let mid = t + 0.5 * dt;
        mid >= self.active.0 && mid < self.active.1
    }
}

/// A concentrated load on one degree of freedom following its own curve over a window of
/// time (a deck's `*CLOAD` of one step, or one of several amplitudes).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadCurve {
    /// Node index.
    pub node: u32,
    /// Direction: 0 = x, 1 = y, 2 = z.
    pub dof: usize,
    /// The magnitude (force) the curve scales.
    pub value: f64,
    /// The curve, in total time.
    pub amplitude: std::sync::Arc<Amplitude>,
    /// When it acts (total time, as [`Prescribed::active`]).
    pub active: (f64, f64),
}

impl LoadCurve {
    /// The load as it acted up to time `t` (the end of an increment or a step: 0 unless
    /// `from < t ≤ until`).
    pub fn until(&self, t: f64) -> f64 {
        if t > self.active.0 && t <= self.active.1 {
            self.value * self.amplitude.value(t)
        } else {
            0.0
        }
    }

    /// The load at the start `t` of an increment of `dt` (0 outside its window).
    pub fn at(&self, t: f64, dt: f64) -> f64 {
        let mid = t + 0.5 * dt;
        if mid >= self.active.0 && mid < self.active.1 {
            self.value * self.amplitude.value(t)
        } else {
            0.0
        }
    }
}

impl super::Solver {
    /// The curve loads at the start of an increment of `dt`, per node (empty when there are
    /// none).
    pub fn curve_loads(&self, dt: f64) -> Vec<[f64; 3]> {
        if self.load_curves.is_empty() {
            return Vec::new();
        }
        let mut f = vec![[0.0; 3]; self.x.len()];
        for c in &self.load_curves {
            f[c.node as usize][c.dof] += c.at(self.time, dt);
        }
        f
    }

    /// The curve loads as they acted up to now (a step's, at its end), per node (empty when
    /// there are none).
    pub fn curve_loads_until_now(&self) -> Vec<[f64; 3]> {
        if self.load_curves.is_empty() {
            return Vec::new();
        }
        let mut f = vec![[0.0; 3]; self.x.len()];
        for c in &self.load_curves {
            f[c.node as usize][c.dof] += c.until(self.time);
        }
        f
    }
}
