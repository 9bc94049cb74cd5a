//! Regularised Coulomb friction `F = F_max tanh(v / v0)` (eq 31, 41, 48 with the sgn() of eq 48
//! smoothed the same way). Units: N, m/s.
//!
//! Tables 4 and 8 give v0 = 0, the Coulomb limit, which an ODE cannot integrate (the force jumps at
//! v = 0 and sticking needs a set-valued law). Table 15 gives v0 = 1e-3 m/s for the same prototype,
//! so that is the floor: smaller values are raised to it and the run says so.

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
}
