//! Hydraulic decoupler (Ch. 4, Fig. 70-71, 77): a main cylinder (radius R_p, area A_p) pushes
//! liquid through an orifice (area A_o) into an auxiliary cylinder whose gas, preloaded at p10 in
//! V_g0, is compressed adiabatically. With v = x_r' - x_t' (positive while the tool moves back)
//! and u = -s the piston's travel back from its front stop (s = 0; back stop at s = -L):
//! - orifice, sign-preserving (eq 46): `dp A_p = 0.5 c0 rho A_p^3 / A_o^2 * v |v|`;
//! - gas (eq 47): `p1 = p10 (V_g0 / V_g)^kappa`, `V_g = V_g0 - A_p u`;
//! - friction (eq 48): `d tanh(v / v0) + b v` (sgn regularised);
//! - force on the tool `F_hyd + F_f` (eq 53-56), end-stops as the bi-stable one.
//!
//! Units: m, m^2, m^3, Pa, kg/m^3, N. Small-displacement stiffness `k_hyd = A_p^2 kappa p10 / V_g0`
//! (eq 63). p10 is used as the thesis does (eq 47 applied to the given pressure).
//!
//! Cost (issue 12, callgrind on Table 12): eq 47's `powf` is about 19 % of a run's instructions
//! and stays: a Chebyshev interpolant of `(V_g0 / V_g)^kappa` accurate to 1e-13 needed degree 16
//! and cost more per evaluation than glibc's `pow` (docs/accuracy.md). Dry friction is not
//! evaluated when d = 0 (Tables 12 and 14): its `tanh` was 9 % of the run.

use super::end_stop::{BackStop, FrontStop};
use crate::friction::TanhFriction;
use flinch_model::scene::Hydraulic;
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

#[cfg(test)]
mod tests {
    use super::*;
    use flinch_model::scene::{ContactDamping, DampingLaw, LinearStop, NonlinearStop};

    pub fn table12() -> Hydraulic {
        Hydraulic {
            stroke: 0.023, piston_radius: 0.020, orifice_radius: 0.008, gas_pressure: 1000.0,
            gas_volume: 7.63e-5, discharge_coefficient: 3.0, liquid_density: 900.0,
            dry_friction: 0.0, viscous_friction: 0.5, adiabatic_exponent: 1.4, friction_v0: 1e-3,
            front_stop: LinearStop { stiffness: 1e6, damping: 235.0, law: flinch_model::scene::FrontStopLaw::Linear },
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
    fn eq63_stiffness() {
        // eq 63 with Table 12: A_p^2 kappa p10 / V_g0 = 28.97 N/m. The thesis prints 27.28 N/m
        // (Ch. 4.4); its inputs as printed give 28.97.
        let k = HydraulicCylinder::new(&table12()).k_hyd();
        assert!((k - 28.97).abs() < 0.01, "{k}");
    }
}
