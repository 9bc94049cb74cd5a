//! Dry friction of a slide, two ways (eq 31, 41, 48). Units: N, m/s.
//!
//! - [`TanhFriction`], regularised: `F = F_max tanh(v / v0)` (the sgn() of eq 48 smoothed the same
//!   way). Table 15 gives v0 = 1e-3 m/s, and that is the floor: smaller values are raised to it and
//!   the run says so. Near v = 0 the force changes at a rate F_max / v0 per m/s, which forces the
//!   solver into tiny steps through every stick phase (docs/accuracy.md, issue 12).
//! - [`Slide`], Coulomb as Tables 4, 8, 11 and 13 write it (v0 = 0): a hybrid state (Karnopp,
//!   "Computer simulation of stick-slip friction in mechanical dynamic systems", 1985). While
//!   *sticking*, the two sides move together and the friction is whatever force keeps them so
//!   ([`required`]), as long as its magnitude stays below mu |F_n|; while *slipping* in direction d,
//!   the force is -d mu |F_n| (opposing the relative velocity). The switches are located events
//!   (`flinch-sim`): stick -> slip when the required force reaches the limit ([`Slide::event`]), slip
//!   -> stick or reversal when the relative velocity reaches zero ([`Slide::decide`] chooses). One
//!   coefficient for sticking and sliding: the thesis gives one mu.

/// Smallest regularisation velocity used, m/s (Table 15's own value).
pub const V0_MIN: f64 = 1e-3;

/// Friction opposing a relative velocity.
#[derive(Debug, Clone, Copy)]
pub struct TanhFriction {
    /// mu, or 1 when the magnitude is given directly in N.
    pub mu: f64,
    /// Effective regularisation velocity, m/s (>= V0_MIN).
    pub v0: f64,
    /// True when the scene's v0 was below V0_MIN and was raised.
    pub regularised: bool,
}

impl TanhFriction {
    /// mu and the scene's v0 (raised to V0_MIN if smaller).
    pub fn new(mu: f64, v0: f64) -> Self {
        Self { mu, v0: v0.max(V0_MIN), regularised: v0 < V0_MIN }
    }

    /// Friction force for normal force `normal` (N, its magnitude is used) and the velocity `v`
    /// the force acts along (positive `v` gives a positive force), N.
    pub fn force(&self, normal: f64, v: f64) -> f64 {
        self.mu * normal.abs() * (v / self.v0).tanh()
    }
}

/// How far past zero the relative velocity must go, against the slip, before a slip is taken to
/// have ended, m/s: the slip event fires at `d v = -SLIP_END`, so that it starts strictly positive
/// (at +SLIP_END) right after a break-away at v = 0, and a reversal is never missed. 1e-12 m/s
/// over any run of the scenes' length moves a body by less than 1e-12 m.
pub const SLIP_END: f64 = 1e-12;

/// The hybrid state of a Coulomb slide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Slide {
    /// Both sides move together, at relative position `s` (m).
    Stick {
        /// The relative position held, m.
        s: f64,
    },
    /// Slipping with relative velocity of sign `dir` (+1 or -1).
    Slip {
        /// +1 or -1.
        dir: f64,
    },
}

/// The friction that keeps the relative acceleration zero, N: with relative acceleration
/// `a0 + b F` under a friction force F on the moving side (b > 0, the sum of the inverse masses),
/// F = -a0 / b.
pub fn required(a0: f64, b: f64) -> f64 {
    -a0 / b
}

impl Slide {
    /// The friction force on the slide for limit `limit` = mu |F_n| (N) and required force `req`
    /// (N, used while sticking).
    pub fn force(&self, limit: f64, req: f64) -> f64 {
        match *self {
            Self::Stick { .. } => req,
            Self::Slip { dir } => -dir * limit,
        }
    }

    /// The event function of the current state: positive while it holds. Sticking: `limit -
    /// |req|`; slipping: `dir v + SLIP_END` for relative velocity `v`.
    pub fn event(&self, limit: f64, req: f64, v: f64) -> f64 {
        match *self {
            Self::Stick { .. } => limit - req.abs(),
            Self::Slip { dir } => dir * v + SLIP_END,
        }
    }

    /// The state to take at relative position `s` where the relative velocity is (about) zero,
    /// or where sticking has just failed: stick if the required force is strictly inside the
    /// limit, else slip the way the unresisted relative acceleration `a0` goes (positive when `a0`
    /// is 0, where the limit is 0 too and no force acts either way).
    pub fn decide(s: f64, limit: f64, req: f64, a0: f64) -> Self {
        if req.abs() < limit {
            Self::Stick { s }
        } else {
            Self::Slip { dir: if a0 < 0.0 { -1.0 } else { 1.0 } }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coulomb_limit_is_regularised_not_divided_by_zero() {
        let f = TanhFriction::new(0.2, 0.0);
        assert!(f.regularised);
        assert!(f.force(10.0, 0.0) == 0.0);
        assert!((f.force(10.0, 1.0) - 2.0).abs() < 1e-9);
        assert!(f.force(10.0, -1e-12).is_finite());
    }

    #[test]
    fn karnopp_states() {
        // Required force inside the limit sticks; at or beyond it slips the way a0 pushes, and the
        // sliding force then opposes that direction with the full limit.
        assert_eq!(Slide::decide(0.01, 2.0, 1.9, -3.8), Slide::Stick { s: 0.01 });
        assert_eq!(Slide::decide(0.01, 2.0, 2.0, -4.0), Slide::Slip { dir: -1.0 });
        let slip = Slide::decide(0.0, 2.0, -2.5, 5.0);
        assert_eq!(slip, Slide::Slip { dir: 1.0 });
        assert_eq!(slip.force(2.0, -2.5), -2.0);
        // A break-away starts the slip event strictly positive, so the event is armed at once.
        assert!(slip.event(2.0, -2.5, 0.0) > 0.0);
        // Zero normal force: nothing holds and nothing resists.
        assert_eq!(Slide::decide(0.0, 0.0, 0.0, 0.0).force(0.0, 0.0), 0.0);
        assert_eq!(required(-4.0, 2.0), 2.0);
    }
}
