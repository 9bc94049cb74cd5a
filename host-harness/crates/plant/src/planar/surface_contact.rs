//! The tool-surface contact's Coulomb friction in the plane (issue 30). The normal force is the 1-D
//! contact's (`crate::contact`: Hertz / Hunt-Crossley, eq 5-7, never pulls); along the tangent t the
//! friction is regularised Coulomb, f = -mu N tanh(v_t / v0), v_t the tool's slip velocity along
//! t (the target does not move along t: a fixed surface, or a free object sliding along m only),
//! v0 = `crate::friction::V0_MIN` = 1 mm/s. Units: N, m/s.
//!
//! Why regularised: the contact's stick-slip (Karnopp) in the plane is not built (docs/planar.md);
//! at v0 = 1 mm/s a sticking contact creeps at well under 1 mm/s under a force below mu N.

use crate::friction::{TanhFriction, V0_MIN};

/// The contact's friction.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceFriction {
    law: TanhFriction,
}

impl SurfaceFriction {
    /// Coefficient `mu` (0: frictionless).
    pub fn new(mu: f64) -> Self {
        Self { law: TanhFriction::new(mu, V0_MIN) }
    }

    /// The friction on the tool along t, N, for the normal force `normal` (N) and the slip
    /// velocity `slip_v` (m/s, along t). Exactly 0 without friction or without contact.
    pub fn force(&self, normal: f64, slip_v: f64) -> f64 {
        if self.law.mu == 0.0 || normal == 0.0 {
            return 0.0;
        }
        -self.law.force(normal, slip_v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_opposes_the_slip_and_is_bounded_by_mu_n() {
        let f = SurfaceFriction::new(0.3);
        assert!(f.force(10.0, 0.1) < 0.0 && f.force(10.0, -0.1) > 0.0);
        assert!((f.force(10.0, 1.0).abs() - 3.0).abs() < 1e-9);
        assert!(f.force(10.0, 1e9).abs() <= 3.0);
        assert_eq!(f.force(0.0, 1.0), 0.0);
        assert_eq!(SurfaceFriction::new(0.0).force(10.0, 1.0), 0.0);
    }
}
