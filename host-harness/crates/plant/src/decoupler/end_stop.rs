//! The decoupler's end-stops (eq 28-29, 37-38): elastomer layers that only push.
//!
//! Stroke coordinate s = x_t - x_r (MODEL.md): the front end-stop is at s = s_front and pushes the
//! tool back (F <= 0) when s > s_front; the back end-stop (the flange) is at s = s_back and pushes
//! the tool forward (F >= 0) when s < s_back. Units: m, m/s, N.
//!
//! The back stop uses the nonlinear law with penetration d = s_back - s and rate d' = -s'. The
//! thesis writes |x'| for the rate (eq 29, 37), which would damp during the rebound as well and
//! pull the tool onto the stop: not copied (MODEL.md).

use crate::contact::{Contact, V_IN_MIN};
use flinch_model::scene::{FrontStopLaw, LinearStop, NonlinearStop};

/// Front end-stop, pushing only: eq 28/38's linear law `F = -k d - c d'`, d = s - s_front, or the
/// Hunt-Crossley law `F = -k d^n - chi d^n d'`, chi = alpha k / v_in fixed at each landing from
/// the approach speed v_in (as the back stop's and the contact's, eq 7). The linear law jumps to
/// `-c d'` the instant the tool lands; the Hunt-Crossley force starts from zero.
#[derive(Debug, Clone, Copy)]
pub struct FrontStop {
    /// Position of the stop in s, m.
    pub at: f64,
    /// k_fe, N/m (N/m^n with the Hunt-Crossley law).
    pub stiffness: f64,
    /// c_fe, N s/m (the linear law's; with Hunt-Crossley only its restitution is used).
    pub damping: f64,
    /// The law.
    pub law: FrontStopLaw,
}

impl FrontStop {
    /// The stop at `at`.
    pub fn new(at: f64, p: &LinearStop) -> Self {
        Self { at, stiffness: p.stiffness, damping: p.damping, law: p.law }
    }

    /// True for the Hunt-Crossley law (its damping chi is fixed at each landing).
    pub fn is_hunt_crossley(&self) -> bool {
        matches!(self.law, FrontStopLaw::HuntCrossley { .. })
    }

    /// chi for a landing at approach speed `v_in` (m/s), N s/m^(n+1); 0 for the linear law. The
    /// speed is floored at [`V_IN_MIN`] as the contact's (a resting stop stays finitely damped).
    pub fn chi(&self, v_in: f64) -> f64 {
        match self.law {
            FrontStopLaw::Linear => 0.0,
            FrontStopLaw::HuntCrossley { alpha, .. } => alpha * self.stiffness / v_in.abs().max(V_IN_MIN),
        }
    }

    /// The unclamped force's sign, as a smooth function (an event function): positive while the
    /// law pushes. Linear: k d + c d'; Hunt-Crossley, per unit d^n: k + chi d'.
    pub fn push(&self, s: f64, s_dot: f64, chi: f64) -> f64 {
        match self.law {
            FrontStopLaw::Linear => self.stiffness * (s - self.at) + self.damping * s_dot,
            FrontStopLaw::HuntCrossley { .. } => self.stiffness + chi * s_dot,
        }
    }

    /// Force on the tool, N (<= 0); `chi` is this landing's (Hunt-Crossley only).
    pub fn force(&self, s: f64, s_dot: f64, chi: f64) -> f64 {
        if s <= self.at {
            return 0.0;
        }
        let d = s - self.at;
        match self.law {
            FrontStopLaw::Linear => (-self.stiffness * d - self.damping * s_dot).min(0.0),
            FrontStopLaw::HuntCrossley { exponent, .. } => {
                let dn = if exponent == 1.0 { d } else { d.powf(exponent) };
                (-(self.stiffness * dn + chi * dn * s_dot)).min(0.0)
            }
        }
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
    use flinch_model::scene::{ContactDamping, DampingLaw};

    #[test]
    fn front_stop_pushes_only() {
        let f = FrontStop::new(0.015, &LinearStop { stiffness: 1e6, damping: 278.0, law: FrontStopLaw::Linear });
        assert_eq!(f.force(0.014, 0.0, 0.0), 0.0);
        assert!(f.force(0.0151, 0.0, 0.0) < 0.0);
        // Leaving fast: the damper would pull; the stop does not.
        assert_eq!(f.force(0.01501, -10.0, 0.0), 0.0);
    }

    /// eq 28's values of Table 12 (k_fe = 1e6 N/m, c_fe = 235 N s/m) and its 0.5 kg tool.
    fn pair() -> (FrontStop, FrontStop) {
        let lin = LinearStop { stiffness: 1e6, damping: 235.0, law: FrontStopLaw::Linear };
        let zeta = 235.0 / (2.0 * (1e6_f64 * 0.5).sqrt());
        let e = flinch_model::damping_law::linear_restitution(zeta);
        let alpha = flinch_model::damping_law::hunt_crossley_alpha(e, 1.0);
        let hc = LinearStop { law: FrontStopLaw::HuntCrossley { exponent: 1.0, alpha, restitution: e }, ..lin };
        (FrontStop::new(0.0, &lin), FrontStop::new(0.0, &hc))
    }

    #[test]
    fn hunt_crossley_front_stop_never_pulls() {
        let (_, hc) = pair();
        let chi = hc.chi(0.15);
        for d in [1e-9, 1e-6, 1e-4, 1e-3] {
            for v in [-100.0, -1.0, -0.15, -1e-3, 0.0, 0.15, 10.0] {
                let f = hc.force(d, v, chi);
                assert!(f <= 0.0, "pulls at d {d}, d' {v}: {f}");
            }
        }
        // Rebounding faster than v_in / alpha: the damping would pull; the stop lets go instead.
        assert_eq!(hc.force(1e-5, -100.0, chi), 0.0);
        assert!(hc.push(1e-5, -100.0, chi) < 0.0);
        assert_eq!(hc.force(-1e-6, 1.0, chi), 0.0);
    }

    #[test]
    fn hunt_crossley_front_stop_has_no_jump_at_contact_onset() {
        // Issue 15: landing at 0.147 m/s, eq 28 jumps to c_fe s' = 34.5 N; Hunt-Crossley starts at 0.
        let (lin, hc) = pair();
        let (v, d) = (0.147, 1e-9);
        let chi = hc.chi(v);
        let f_lin = -lin.force(d, v, 0.0);
        let f_hc = -hc.force(d, v, chi);
        assert!((f_lin - 235.0 * v).abs() < 0.01, "{f_lin}");
        assert!(f_hc < 1e-3 * f_lin, "{f_hc} vs {f_lin}");
        // Same static stiffness (n = 1): at rest both push k d.
        assert!((lin.force(1e-5, 0.0, 0.0) - hc.force(1e-5, 0.0, chi)).abs() < 1e-9);
    }

    /// Integrates a free tool of mass m landing on the stop at v_in (semi-implicit Euler, 1e-8 s
    /// steps) and returns its exit speed and the largest force.
    fn land(stop: &FrontStop, m: f64, v_in: f64) -> (f64, f64) {
        let chi = stop.chi(v_in);
        let (mut s, mut v, mut peak) = (0.0_f64, v_in, 0.0_f64);
        let dt = 1e-8;
        for _ in 0..10_000_000 {
            let f = stop.force(s, v, chi);
            peak = peak.max(-f);
            v += f / m * dt;
            s += v * dt;
            if s <= 0.0 && v < 0.0 {
                break;
            }
        }
        (-v, peak)
    }

    #[test]
    fn hunt_crossley_front_stop_dissipates_what_the_linear_one_does() {
        let (lin, hc) = pair();
        for v_in in [0.05, 0.147, 0.5] {
            let (out_lin, peak_lin) = land(&lin, 0.5, v_in);
            let (out_hc, peak_hc) = land(&hc, 0.5, v_in);
            // Both lose energy, the same fraction (restitution matched, speed-independent).
            assert!(out_hc < v_in && out_lin < v_in);
            assert!((out_hc / v_in - out_lin / v_in).abs() < 5e-3, "v_in {v_in}: e {} vs {}", out_hc / v_in, out_lin / v_in);
            // No jump, but not a smaller peak: the same loss is taken later in the impact, where
            // the spring force is already large (about 16 % more at these values).
            assert!(peak_hc > peak_lin && peak_hc < 1.3 * peak_lin, "{peak_hc} vs {peak_lin}");
        }
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
