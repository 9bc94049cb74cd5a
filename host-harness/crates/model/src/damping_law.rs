//! Damping laws of the nonlinear contact (eq 5-7): chi = alpha(e) * k / v_in, where alpha depends
//! only on the requested restitution e. Units: chi in N s / m^2.5 when k is in N / m^1.5 and v_in
//! in m/s.
//!
//! For an isolated impact with `F = k d^1.5 (1 + alpha d' / v_in)` the achieved restitution depends
//! on alpha alone (scale d by the peak penetration and t by d_max / v_in). [`achieved_restitution`]
//! integrates that dimensionless impact; `Exact` inverts it, so the requested e is what comes out.
//! Eq 7 (Hunt-Crossley, as the thesis) cannot go below about 0.5 however small e is: MODEL.md.

use crate::scene::{ContactDamping, DampingLaw};
use std::sync::OnceLock;

/// Largest alpha used: alpha grows without bound as e -> 0 for Flores, Gonthier and Exact. Capping
/// it keeps the contact ODE integrable; at this cap the achieved restitution is already below 0.01
/// (tested in `exact_reaches_small_restitution`).
pub const ALPHA_MAX: f64 = 200.0;

/// Approach velocities below this are raised to it when chi is computed, m/s. chi = alpha k / v_in
/// grows without bound as v_in -> 0 (a grazing or resting contact); the floor keeps the damping
/// finite, and only weakens it for contacts that approach slower than 1 mm/s.
pub const V_IN_MIN: f64 = 1e-3;

/// chi = alpha k / v_in for a contact of stiffness `k` that began with approach velocity `v_in`
/// (m/s), v_in floored at [`V_IN_MIN`]; the plant's contacts (`plant/contact.rs`) and the loader's
/// step estimate (`scene/budget.rs`) both use it.
#[inline]
pub fn chi(alpha: f64, stiffness: f64, v_in: f64) -> f64 {
    alpha * stiffness / v_in.abs().max(V_IN_MIN)
}

/// chi of a contact given by the scene's damping specification (a restitution and its law, or a
/// fixed chi), at approach velocity `v_in`.
pub fn contact_chi(stiffness: f64, d: &ContactDamping, v_in: f64) -> f64 {
    match *d {
        ContactDamping::Restitution { restitution, law } => chi(alpha(law, restitution), stiffness, v_in),
        ContactDamping::FixedChi(c) => c,
    }
}

/// alpha(e) for a law; `e` in [0, 1].
pub fn alpha(law: DampingLaw, e: f64) -> f64 {
    let e = e.clamp(0.0, 1.0);
    let a = match law {
        DampingLaw::HuntCrossley => 1.5 * (1.0 - e),
        DampingLaw::LankaraniNikravesh => 0.75 * (1.0 - e * e),
        DampingLaw::Flores => if e > 0.0 { 8.0 * (1.0 - e) / (5.0 * e) } else { ALPHA_MAX },
        DampingLaw::Gonthier => if e > 0.0 { (1.0 - e * e) / e } else { ALPHA_MAX },
        DampingLaw::Exact => exact_alpha(e),
    };
    a.min(ALPHA_MAX)
}

/// Restitution achieved by an isolated impact of the law with damping `alpha` (e = -d'_out / d'_in).
///
/// Dimensionless impact: u'' = -(5/4) u^1.5 (1 + alpha u'), u(0) = 0, u'(0) = 1 (the 5/4 makes the
/// undamped peak u = 1). Integrated with RK4 at a fixed step fine enough for 1e-6 in e; ends when u
/// returns to 0 or the contact force vanishes and u' < 0 (the clamp of a non-adhesive contact).
pub fn achieved_restitution(alpha: f64) -> f64 {
    impact(|u, w| 1.25 * u * u.sqrt() * (1.0 + alpha * w), 1e-4 / (1.0 + alpha).sqrt())
}

/// One isolated impact of a pushing-only contact law, dimensionless: u'' = -g(u, u'), u(0) = 0,
/// u'(0) = 1, RK4 at step `h`; returns the exit speed -u' when u returns to 0 or the force has
/// vanished on the way out (the clamp: the bodies then separate at constant speed).
fn impact(g: impl Fn(f64, f64) -> f64, h: f64) -> f64 {
    let f = |u: f64, w: f64| -g(u.max(0.0), w).max(0.0);
    let (mut u, mut w, mut t) = (0.0_f64, 1.0_f64, 0.0);
    // Bounded: an undamped impact lasts about pi time units; heavy damping stretches it.
    while t < 1e3 {
        let (k1u, k1w) = (w, f(u, w));
        let (k2u, k2w) = (w + 0.5 * h * k1w, f(u + 0.5 * h * k1u, w + 0.5 * h * k1w));
        let (k3u, k3w) = (w + 0.5 * h * k2w, f(u + 0.5 * h * k2u, w + 0.5 * h * k2w));
        let (k4u, k4w) = (w + h * k3w, f(u + h * k3u, w + h * k3w));
        let un = u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        let wn = w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        t += h;
        if un <= 0.0 {
            let frac = u / (u - un);
            return -(w + frac * (wn - w));
        }
        if wn < 0.0 && g(un, wn) <= 0.0 {
            return -wn;
        }
        u = un;
        w = wn;
    }
    0.0
}

/// Restitution of an isolated impact on eq 28's linear spring-damper `F = k d + c d'` clamped so it
/// never pulls (as `plant/decoupler/end_stop.rs` models it), damping ratio `zeta = c / (2 sqrt(k m))`.
/// Scaled by the undamped natural frequency it is u'' = -(u + 2 zeta u'): e depends on zeta alone.
/// The clamp lets go before u returns to 0 (where the damper would pull the leaving body back), so
/// e is above the textbook exp(-zeta pi / sqrt(1 - zeta^2)).
pub fn linear_restitution(zeta: f64) -> f64 {
    let z = zeta.max(0.0);
    impact(|u, w| u + 2.0 * z * w, 1e-4 / (1.0 + z))
}

/// Restitution of an isolated impact on the Hunt-Crossley law `F = k d^n (1 + alpha d' / v_in)`:
/// scaled so the undamped peak is u = 1, u'' = -((n + 1) / 2) u^n (1 + alpha u'), so e depends on
/// alpha and n alone (whatever k, the mass and v_in).
pub fn hunt_crossley_restitution(alpha: f64, n: f64) -> f64 {
    let c = 0.5 * (n + 1.0);
    impact(|u, w| c * u.powf(n) * (1.0 + alpha * w), 1e-4 / (1.0 + alpha).sqrt())
}

/// alpha of the Hunt-Crossley law with exponent `n` whose isolated impact achieves restitution `e`
/// (bisection on the monotone e(alpha), to 1e-6 in e), capped at [`ALPHA_MAX`].
pub fn hunt_crossley_alpha(e: f64, n: f64) -> f64 {
    let e = e.clamp(0.0, 1.0);
    if e >= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, ALPHA_MAX);
    if hunt_crossley_restitution(hi, n) >= e {
        return hi;
    }
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        let em = hunt_crossley_restitution(m, n);
        if (em - e).abs() < 1e-6 {
            return m;
        }
        if em > e { lo = m } else { hi = m }
    }
    0.5 * (lo + hi)
}

/// (alpha, e) pairs on a log grid of alpha, e decreasing; built once.
fn table() -> &'static [(f64, f64)] {
    static TABLE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let n = 121;
        let (lo, hi) = (1e-4_f64.ln(), ALPHA_MAX.ln());
        let mut v = Vec::with_capacity(n + 1);
        v.push((0.0, 1.0));
        for i in 0..n {
            let a = (lo + (hi - lo) * i as f64 / (n - 1) as f64).exp();
            v.push((a, achieved_restitution(a)));
        }
        v
    })
}

/// alpha such that an isolated impact achieves restitution `e` (table, then secant refinement).
fn exact_alpha(e: f64) -> f64 {
    let t = table();
    if e >= 1.0 {
        return 0.0;
    }
    let last = t[t.len() - 1];
    if e <= last.1 {
        return last.0;
    }
    let i = t.iter().position(|&(_, ei)| ei < e).unwrap_or(t.len() - 1);
    let (mut a0, mut e0) = t[i - 1];
    let (mut a1, mut e1) = t[i];
    // Secant on e(alpha) - e, bracketed; a few iterations reach 1e-9.
    for _ in 0..30 {
        let a = a0 + (e - e0) * (a1 - a0) / (e1 - e0);
        let ea = achieved_restitution(a);
        if (ea - e).abs() < 1e-9 {
            return a;
        }
        if ea > e { (a0, e0) = (a, ea) } else { (a1, e1) = (a, ea) }
    }
    0.5 * (a0 + a1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_restitution_matches_the_textbook_when_undamped_and_exceeds_it_when_clamped() {
        assert!((linear_restitution(0.0) - 1.0).abs() < 1e-6);
        // Unclamped Kelvin-Voigt: exp(-zeta pi / sqrt(1 - zeta^2)); the clamp lets go before the
        // damper would pull the leaving body back, so a little less is lost.
        for z in [0.05, 0.1, 0.2] {
            let textbook = (-z * std::f64::consts::PI / (1.0 - z * z).sqrt()).exp();
            let e = linear_restitution(z);
            assert!(e > textbook && e < textbook + 0.1, "zeta {z}: {e} vs {textbook}");
        }
    }

    #[test]
    fn hunt_crossley_alpha_achieves_the_asked_restitution_for_any_exponent() {
        for n in [1.0, 1.5, 2.0] {
            for e in [0.2, 0.5, 0.8, 0.95] {
                let a = hunt_crossley_alpha(e, n);
                let got = hunt_crossley_restitution(a, n);
                assert!((got - e).abs() < 1e-4, "n {n}, e {e}: alpha {a} gives {got}");
            }
        }
        // n = 1.5 is the contact law's: the same function as `achieved_restitution`.
        assert!((hunt_crossley_restitution(0.7, 1.5) - achieved_restitution(0.7)).abs() < 1e-6);
    }

    #[test]
    fn undamped_impact_is_elastic() {
        assert!((achieved_restitution(0.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn hunt_crossley_cannot_go_below_about_half() {
        // MODEL.md: asking e = 0.1 of eq 7 gives about 0.52.
        let e = achieved_restitution(alpha(DampingLaw::HuntCrossley, 0.1));
        assert!((0.50..0.55).contains(&e), "{e}");
    }

    #[test]
    fn exact_achieves_what_is_asked() {
        for i in 1..=20 {
            let e = i as f64 / 20.0;
            let got = achieved_restitution(alpha(DampingLaw::Exact, e));
            assert!((got - e).abs() < 1e-4, "asked {e}, got {got}");
        }
    }

    #[test]
    fn exact_reaches_small_restitution() {
        assert!(achieved_restitution(ALPHA_MAX) < 0.01);
        assert!(achieved_restitution(alpha(DampingLaw::Exact, 0.0)) < 0.01);
    }

    #[test]
    fn every_law_is_monotone_and_finite_over_e() {
        for law in [DampingLaw::HuntCrossley, DampingLaw::LankaraniNikravesh, DampingLaw::Flores, DampingLaw::Gonthier, DampingLaw::Exact] {
            let mut prev = f64::INFINITY;
            for i in 0..=20 {
                let a = alpha(law, i as f64 / 20.0);
                assert!(a.is_finite() && a >= 0.0);
                assert!(a <= prev + 1e-12, "{law:?} not decreasing at e = {}", i as f64 / 20.0);
                prev = a;
            }
            assert!(alpha(law, 1.0).abs() < 1e-12, "{law:?} must not damp at e = 1");
        }
    }
}
