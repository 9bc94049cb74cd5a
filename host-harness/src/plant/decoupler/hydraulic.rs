//! Hydraulic decoupler (Ch. 4, Fig. 70-71, 77): a main cylinder (radius R_p, area A_p) pushes
//! liquid through an orifice (area A_o) into an auxiliary cylinder whose gas, preloaded at p10 in
//! V_g0, is compressed adiabatically. With v = x_r' - x_t' (positive while the tool moves back)
//! and u = -s the piston's travel back from its front stop (s = 0; back stop at s = -L):
//! - orifice, sign-preserving (eq 46): `dp A_p = 0.5 c0 rho A_p^3 / A_o^2 * v |v|`;
//! - gas (eq 47): `p1 = p10 (V_g0 / V_g)^kappa`, `V_g = V_g0 - A_p u`;
//! - friction (eq 48): `d tanh(v / v0) + b v` (sgn regularised);
//! - force on the tool `F_hyd + F_f` (eq 53-56), end-stops as the bi-stable one.
//! Units: m, m^2, m^3, Pa, kg/m^3, N. Small-displacement stiffness `k_hyd = A_p^2 kappa p10 / V_g0`
//! (eq 63). p10 is used as the thesis does (eq 47 applied to the given pressure).
//!
//! Cost (issue 12): eq 47's `powf` was 19 % of a hydraulic run's instructions (callgrind). Over the
//! stroke, and a margin either side, the gas law is evaluated from a Chebyshev interpolant of
//! `(V_g0 / V_g)^kappa` fitted at construction ([`GasLaw`]) and checked there against `powf` to a
//! relative 1e-13; outside that interval, or where no interpolant of degree <= 24 meets the check
//! (a gas volume hardly larger than the swept one), `powf` as before. And dry friction is not
//! evaluated when d = 0 (Tables 12 and 14): its `tanh` was another 9 %.

use super::end_stop::{BackStop, FrontStop};
use crate::plant::friction::TanhFriction;
use crate::scene::Hydraulic;
use std::f64::consts::PI;

/// The cylinder, orifice and gas spring, ready to evaluate.
#[derive(Debug, Clone, Copy)]
pub struct HydraulicCylinder {
    area: f64,
    /// 0.5 c0 rho A_p^3 / A_o^2, N s^2 / m^2.
    orifice: f64,
    p10: f64,
    v_g0: f64,
    /// Smallest gas volume used, m^3: a tenth of what is left at full stroke, so a back-stop
    /// penetration cannot drive V_g to zero or below.
    v_g_min: f64,
    kappa: f64,
    gas: GasLaw,
    dry: TanhFriction,
    viscous: f64,
    /// Front end-stop at s = 0.
    pub front: FrontStop,
    /// Back end-stop at s = -L.
    pub back: BackStop,
}

/// The hydraulic force split into its parts, N (on the tool).
#[derive(Debug, Clone, Copy, Default)]
pub struct HydraulicForce {
    /// Gas pressure p1, Pa.
    pub gas_pressure: f64,
    /// p1 A_p + orifice force, N.
    pub hydraulic: f64,
    /// Dry plus viscous friction, N.
    pub friction: f64,
}

impl HydraulicCylinder {
    /// From the scene's parameters.
    pub fn new(p: &Hydraulic) -> Self {
        let area = PI * p.piston_radius * p.piston_radius;
        let a_o = PI * p.orifice_radius * p.orifice_radius;
        Self {
            area,
            orifice: 0.5 * p.discharge_coefficient * p.liquid_density * area.powi(3) / (a_o * a_o),
            p10: p.gas_pressure,
            v_g0: p.gas_volume,
            v_g_min: 0.1 * (p.gas_volume - area * p.stroke),
            kappa: p.adiabatic_exponent,
            gas: GasLaw::fit(p.gas_volume, p.adiabatic_exponent, (p.gas_volume - area * p.stroke).max(0.1 * (p.gas_volume - area * p.stroke)), p.gas_volume),
            dry: TanhFriction { mu: p.dry_friction, v0: p.friction_v0, regularised: false },
            viscous: p.viscous_friction,
            front: FrontStop::new(0.0, &p.front_stop),
            back: BackStop::new(-p.stroke, &p.back_stop),
        }
    }

    /// Piston area A_p, m^2.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// Gas pressure at stroke coordinate s, Pa (eq 47).
    pub fn gas_pressure(&self, s: f64) -> f64 {
        let v_g = (self.v_g0 + self.area * s).max(self.v_g_min);
        match self.gas.eval(v_g) {
            Some(r) => self.p10 * r,
            None => self.p10 * (self.v_g0 / v_g).powf(self.kappa),
        }
    }

    /// eq 47 with `powf` always (the interpolant's check, and the tests').
    pub fn gas_pressure_exact(&self, s: f64) -> f64 {
        let v_g = (self.v_g0 + self.area * s).max(self.v_g_min);
        self.p10 * (self.v_g0 / v_g).powf(self.kappa)
    }

    /// Forces on the tool at s and s' = x_t' - x_r'.
    pub fn force(&self, s: f64, s_dot: f64) -> HydraulicForce {
        let v = -s_dot;
        let p1 = self.gas_pressure(s);
        HydraulicForce {
            gas_pressure: p1,
            hydraulic: p1 * self.area + self.orifice * v * v.abs(),
            friction: if self.dry.mu > 0.0 { self.dry.force(1.0, v) } else { 0.0 } + self.viscous * v,
        }
    }

    /// Equivalent stiffness at the front stop, N/m (eq 63).
    pub fn k_hyd(&self) -> f64 {
        self.area * self.area * self.kappa * self.p10 / self.v_g0
    }
}

/// Largest degree of the gas law's interpolant.
const GAS_DEGREE_MAX: usize = 24;
/// Relative accuracy the interpolant must reach against `powf` to be used.
const GAS_RTOL: f64 = 1e-13;

/// `(V_g0 / V_g)^kappa` on [lo, hi] as a Chebyshev series (Clenshaw), or nothing.
#[derive(Debug, Clone, Copy)]
pub struct GasLaw {
    lo: f64,
    hi: f64,
    /// 2 / (hi - lo).
    scale: f64,
    degree: usize,
    coef: [f64; GAS_DEGREE_MAX + 1],
}

impl GasLaw {
    /// Fits on the gas volumes from `v_end` (full stroke) to `v_g0` (front stop), widened by 5 % of
    /// the swept volume either side for the end-stops' penetrations (never below half of `v_end`),
    /// with the lowest degree (16, 20 or 24) whose interpolant is within [`GAS_RTOL`] of `powf` at 64
    /// points between the nodes; degree 0 (always `powf`) if none is.
    pub fn fit(v_g0: f64, kappa: f64, v_end: f64, v_front: f64) -> Self {
        let swept = v_front - v_end;
        let lo = (v_end - 0.05 * swept).max(0.5 * v_end);
        let hi = v_front + 0.05 * swept;
        let exact = |v: f64| (v_g0 / v).powf(kappa);
        let mut law = Self { lo, hi, scale: 2.0 / (hi - lo), degree: 0, coef: [0.0; GAS_DEGREE_MAX + 1] };
        if !(lo > 0.0 && hi > lo && kappa.is_finite() && v_g0 > 0.0) {
            return law;
        }
        for n in [16, 20, GAS_DEGREE_MAX] {
            let m = n + 1;
            let mut coef = [0.0; GAS_DEGREE_MAX + 1];
            let f: Vec<f64> = (0..m).map(|k| {
                let x = (std::f64::consts::PI * (k as f64 + 0.5) / m as f64).cos();
                exact(lo + 0.5 * (x + 1.0) * (hi - lo))
            }).collect();
            for (j, c) in coef.iter_mut().enumerate().take(m) {
                let sum: f64 = f.iter().enumerate().map(|(k, fk)| fk * (std::f64::consts::PI * j as f64 * (k as f64 + 0.5) / m as f64).cos()).sum();
                *c = 2.0 * sum / m as f64;
            }
            coef[0] *= 0.5;
            let trial = Self { degree: n, coef, ..law };
            let ok = (0..=64).all(|i| {
                let v = lo + (hi - lo) * (i as f64 + 0.37) / 65.0;
                let (a, e) = (trial.series(v), exact(v));
                (a - e).abs() <= GAS_RTOL * e
            });
            if ok {
                law = trial;
                break;
            }
        }
        law
    }

    /// Degree of the interpolant in use (0: none, `powf` everywhere).
    pub fn degree(&self) -> usize {
        self.degree
    }

    fn series(&self, v: f64) -> f64 {
        let x = (v - self.lo) * self.scale - 1.0;
        let x2 = 2.0 * x;
        let (mut b1, mut b2) = (0.0, 0.0);
        for j in (1..=self.degree).rev() {
            let b0 = self.coef[j] + x2 * b1 - b2;
            b2 = b1;
            b1 = b0;
        }
        self.coef[0] + x * b1 - b2
    }

    /// `(V_g0 / v)^kappa` if `v` is inside the fitted interval and an interpolant is in use.
    #[inline]
    pub fn eval(&self, v: f64) -> Option<f64> {
        (self.degree > 0 && v >= self.lo && v <= self.hi).then(|| self.series(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ContactDamping, DampingLaw, LinearStop, NonlinearStop};

    pub fn table12() -> Hydraulic {
        Hydraulic {
            stroke: 0.023, piston_radius: 0.020, orifice_radius: 0.008, gas_pressure: 1000.0,
            gas_volume: 7.63e-5, discharge_coefficient: 3.0, liquid_density: 900.0,
            dry_friction: 0.0, viscous_friction: 0.5, adiabatic_exponent: 1.4, friction_v0: 1e-3,
            front_stop: LinearStop { stiffness: 1e6, damping: 235.0, law: crate::scene::FrontStopLaw::Linear },
            back_stop: NonlinearStop { stiffness: 1e6, damping: ContactDamping::Restitution { restitution: 0.3, law: DampingLaw::HuntCrossley } },
        }
    }

    #[test]
    fn orifice_resists_the_relative_motion_both_ways() {
        let h = HydraulicCylinder::new(&table12());
        let rest = h.force(-0.01, 0.0).hydraulic;
        // Tool moving back (s' < 0): pushed forward harder; moving forward: held back.
        assert!(h.force(-0.01, -1.0).hydraulic > rest);
        assert!(h.force(-0.01, 1.0).hydraulic < rest);
        assert!((h.force(-0.01, -1.0).hydraulic - rest + rest - h.force(-0.01, 1.0).hydraulic - 2.0 * h.orifice).abs() < 1e-9);
    }

    #[test]
    fn gas_stiffens_with_travel_and_never_reaches_zero_volume() {
        let h = HydraulicCylinder::new(&table12());
        assert!(h.gas_pressure(-0.02) > h.gas_pressure(-0.01));
        let p = h.gas_pressure(-1.0);
        assert!(p.is_finite() && p > 0.0);
    }

    #[test]
    fn gas_interpolant_matches_powf_over_the_stroke_and_beyond() {
        // Table 12, and gas volumes from 20x down to 1.0001x the swept volume (the validator's
        // floor is "larger than"), kappa 1 to 1.67: within 1e-13 of powf wherever the interpolant
        // is used, and powf outside it; the pressure is continuous across the interval's ends to
        // the same accuracy.
        for (ratio, kappa) in [(2.64, 1.4), (20.0, 1.4), (1.5, 1.67), (1.2, 1.0), (1.01, 1.4), (1.0001, 1.4)] {
            let mut p = table12();
            let a = PI * p.piston_radius * p.piston_radius;
            p.gas_volume = ratio * a * p.stroke;
            p.adiabatic_exponent = kappa;
            let h = HydraulicCylinder::new(&p);
            let mut worst = 0.0f64;
            for i in 0..=20_000 {
                let s = -1.3 * p.stroke + 1.4 * p.stroke * i as f64 / 20_000.0;
                let (fast, exact) = (h.gas_pressure(s), h.gas_pressure_exact(s));
                assert!(fast.is_finite() && fast > 0.0);
                worst = worst.max((fast - exact).abs() / exact);
            }
            assert!(worst <= 1e-13, "V_g0 = {ratio} A L, kappa {kappa}: {worst:e} (degree {})", h.gas.degree());
            // The shipped scenes' (2.64) and larger gas volumes are interpolated; near the swept
            // volume the singularity at V_g = 0 is too close for degree 24, and powf is used.
            assert_eq!(h.gas.degree() > 0, ratio >= 2.0, "V_g0 = {ratio} A L: degree {}", h.gas.degree());
        }
    }

    #[test]
    fn eq63_stiffness() {
        // eq 63 with Table 12: A_p^2 kappa p10 / V_g0 = 28.97 N/m. The thesis prints 27.28 N/m
        // (Ch. 4.4); its inputs as printed give 28.97.
        let k = HydraulicCylinder::new(&table12()).k_hyd();
        assert!((k - 28.97).abs() < 0.01, "{k}");
    }
}
