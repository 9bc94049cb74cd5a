//! The decoupler's end-stops (eq 28-29, 37-38): elastomer layers that only push.
//!
//! Stroke coordinate s = x_t - x_r (MODEL.md): the front end-stop is at s = s_front and pushes the
//! tool back (F <= 0) when s > s_front; the back end-stop (the flange) is at s = s_back and pushes
//! the tool forward (F >= 0) when s < s_back. Units: m, m/s, N.
//!
//! The back stop uses the nonlinear law with penetration d = s_back - s and rate d' = -s'. The
//! thesis writes |x'| for the rate (eq 29, 37), which would damp during the rebound as well and
//! pull the tool onto the stop: not copied (MODEL.md).

use crate::plant::contact::Contact;
use crate::scene::{LinearStop, NonlinearStop};

/// Linear front end-stop `F = -k (s - s_front) - c s'` (eq 28/38), clamped so it never pulls.
#[derive(Debug, Clone, Copy)]
pub struct FrontStop {
    /// Position of the stop in s, m.
    pub at: f64,
    /// k_fe, N/m.
    pub stiffness: f64,
    /// c_fe, N s/m.
    pub damping: f64,
}

impl FrontStop {
    /// The stop at `at`.
    pub fn new(at: f64, p: &LinearStop) -> Self {
        Self { at, stiffness: p.stiffness, damping: p.damping }
    }

    /// Force on the tool, N (<= 0).
    pub fn force(&self, s: f64, s_dot: f64) -> f64 {
        if s <= self.at {
            return 0.0;
        }
        (-self.stiffness * (s - self.at) - self.damping * s_dot).min(0.0)
    }
}

/// Nonlinear back end-stop `F = k d^1.5 + chi d^1.5 d'` (eq 29/37), d = s_back - s.
#[derive(Debug, Clone, Copy)]
pub struct BackStop {
    /// Position of the stop in s, m (negative).
    pub at: f64,
    /// The contact law.
    pub contact: Contact,
}

impl BackStop {
    /// The stop at `at`.
    pub fn new(at: f64, p: &NonlinearStop) -> Self {
        Self { at, contact: Contact::new(p.stiffness, &p.damping) }
    }

    /// Penetration d, m (positive inside the stop).
    pub fn penetration(&self, s: f64) -> f64 {
        self.at - s
    }

    /// Force on the tool, N (>= 0), with `chi` fixed at this contact's onset.
    pub fn force(&self, s: f64, s_dot: f64, chi: f64) -> f64 {
        self.contact.force(self.penetration(s), -s_dot, chi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ContactDamping, DampingLaw};

    #[test]
    fn front_stop_pushes_only() {
        let f = FrontStop::new(0.015, &LinearStop { stiffness: 1e6, damping: 278.0 });
        assert_eq!(f.force(0.014, 0.0), 0.0);
        assert!(f.force(0.0151, 0.0) < 0.0);
        // Leaving fast: the damper would pull; the stop does not.
        assert_eq!(f.force(0.01501, -10.0), 0.0);
    }

    #[test]
    fn back_stop_does_not_damp_the_rebound_into_a_pull() {
        let b = BackStop::new(-0.015, &NonlinearStop { stiffness: 1e6, damping: ContactDamping::Restitution { restitution: 0.6, law: DampingLaw::HuntCrossley } });
        let chi = b.contact.chi(0.3);
        // Rebounding (s' > 0, d' < 0) fast: force drops to zero, never negative.
        assert_eq!(b.force(-0.0151, 50.0, chi), 0.0);
        // Entering (s' < 0): damping adds.
        assert!(b.force(-0.0151, -0.3, chi) > b.force(-0.0151, 0.0, chi));
    }
}
