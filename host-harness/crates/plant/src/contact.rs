//! Nonlinear contact (eq 5-7, 29/37, 51): for penetration d > 0,
//! `F = k d^1.5 + chi d^1.5 d'`, never negative (a contact pushes, it never pulls), zero for d <= 0.
//! Units: k in N/m^1.5, chi in N s/m^2.5, d in m, d' in m/s, F in N.
//!
//! A human body region (ISO/TS 15066 Annex A, `flinch_model::body`) is a *linear* undamped spring instead:
//! `F = k d` for d > 0, k in N/m, chi = 0 ([`Contact::linear`]); it never pulls either.
//!
//! chi is fixed per contact at its onset from the approach velocity v_in (eq 7 and the other laws
//! in [`super::damping_law`]), or given directly (Table 12).

use flinch_model::damping_law;
use flinch_model::scene::ContactDamping;

pub use flinch_model::damping_law::V_IN_MIN;

/// One contact pair: its stiffness and how its damping is set.
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// k, N/m^1.5 (Hertz) or N/m (linear).
    pub stiffness: f64,
    /// alpha (chi = alpha k / v_in) or a fixed chi.
    damping: Damping,
    /// `F = k d` instead of `k d^1.5` (a body region of ISO/TS 15066 Annex A).
    pub linear: bool,
}

#[derive(Debug, Clone, Copy)]
enum Damping {
    Alpha(f64),
    Chi(f64),
}

impl Contact {
    /// From a stiffness and a damping specification.
    pub fn new(stiffness: f64, d: &ContactDamping) -> Self {
        let damping = match *d {
            ContactDamping::Restitution { restitution, law } => Damping::Alpha(damping_law::alpha(law, restitution)),
            ContactDamping::FixedChi(chi) => Damping::Chi(chi),
        };
        Self { stiffness, damping, linear: false }
    }

    /// The undamped linear spring of ISO/TS 15066 Annex A's body model: `F = k d`, k in N/m.
    pub fn linear(stiffness: f64) -> Self {
        Self { stiffness, damping: Damping::Chi(0.0), linear: true }
    }

    /// chi for a contact that began with approach velocity `v_in` (m/s).
    pub fn chi(&self, v_in: f64) -> f64 {
        match self.damping {
            Damping::Alpha(a) => damping_law::chi(a, self.stiffness, v_in),
            Damping::Chi(chi) => chi,
        }
    }

    /// Contact force for penetration `d` and penetration rate `d_dot`, with damping `chi`, N >= 0.
    pub fn force(&self, d: f64, d_dot: f64, chi: f64) -> f64 {
        if d <= 0.0 {
            return 0.0;
        }
        let dn = if self.linear { d } else { d * d.sqrt() };
        (self.stiffness * dn + chi * dn * d_dot).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flinch_model::scene::DampingLaw;

    fn c() -> Contact {
        Contact::new(1e8, &ContactDamping::Restitution { restitution: 0.65, law: DampingLaw::HuntCrossley })
    }

    #[test]
    fn negative_penetration_gives_no_force_and_no_nan() {
        // d^1.5 of a negative d would be NaN: the law must not evaluate it.
        let f = c().force(-1e-3, 5.0, 1e6);
        assert_eq!(f, 0.0);
    }

    #[test]
    fn never_pulls_on_separation() {
        let cc = c();
        let chi = cc.chi(0.05);
        assert_eq!(cc.force(1e-6, -100.0, chi), 0.0);
        assert!(cc.force(1e-6, 0.0, chi) > 0.0);
    }

    #[test]
    fn linear_law_is_k_d_and_never_pulls() {
        let l = Contact::linear(75e3);
        assert_eq!(l.chi(1.0), 0.0);
        assert_eq!(l.force(2e-3, 0.5, 0.0), 150.0);
        assert_eq!(l.force(-1e-3, 0.5, 0.0), 0.0);
        assert_eq!(l.force(1e-3, -100.0, l.chi(1.0)), 75.0);
    }

    #[test]
    fn chi_stays_finite_as_approach_velocity_vanishes() {
        let cc = c();
        let chi0 = cc.chi(0.0);
        assert!(chi0.is_finite());
        assert_eq!(chi0, cc.chi(V_IN_MIN / 10.0));
        assert!(cc.chi(1.0) < chi0);
    }
}
