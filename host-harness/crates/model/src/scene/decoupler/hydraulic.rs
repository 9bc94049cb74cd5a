//! `kind = "hydraulic"`: a hydraulic cylinder with an orifice and a gas spring (eq 46-56, Tables 12
//! and 14; `plant/decoupler/hydraulic.rs`). Travel u >= 0 is measured back from the front stop.
use super::super::check::{approx, num, Bound::*, Ctx, Key, Tab};
use super::super::model::Hydraulic;
use super::end_stop::{self, end_stops};
use super::kind::KIND;

/// Adiabatic exponent of air (eq 47).
pub const DEFAULT_ADIABATIC_EXPONENT: f64 = 1.4;
/// Velocity regularising sgn() in the hydraulic dry friction (eq 48), m/s.
pub const DEFAULT_HYDRAULIC_FRICTION_V0: f64 = 1e-3;

/// L.
pub const STROKE: Key = Key::number("stroke", "m", Incl(1e-3), Incl(0.2), "a hand-sized module: 0.023 m in Tables 12 and 14", "L, the piston stroke");
/// R_p.
pub const PISTON_RADIUS: Key = Key::number("piston_radius", "m", Incl(1e-3), Incl(0.1), "a hand-sized module: 0.02 m in Tables 12 and 14", "R_p, the main cylinder's radius");
/// R_o.
pub const ORIFICE_RADIUS: Key = Key::number("orifice_radius", "m", Incl(1e-5), Incl(0.1), "0.008 m in Tables 12 and 14; must also be < piston_radius", "R_o, the orifice's radius (< R_p)");
/// p10.
pub const GAS_PRESSURE: Key = Key::number("gas_pressure", "Pa", Incl(100.0), Incl(1e7), "1000 Pa in Tables 12 and 14; 100 bar is the top of small gas springs", "p10, the gas preload pressure at the front stop");
/// V_g0.
pub const GAS_VOLUME: Key = Key::number("gas_volume", "m^3", Incl(1e-9), Incl(1e-2), "7.63e-5 m^3 in Tables 12 and 14; 10 litres is far beyond a hand-sized module", "V_g0, the gas volume at the front stop (> pi R_p^2 L)");
/// c0.
pub const DISCHARGE_COEFFICIENT: Key = Key::number("discharge_coefficient", "", Incl(0.1), Incl(10.0), "3.0 in Tables 12 and 14 (eq 50)", "c0, the orifice's discharge coefficient (eq 50)");
/// rho_L.
pub const LIQUID_DENSITY: Key = Key::number("liquid_density", "kg/m^3", Incl(500.0), Incl(2000.0), "hydraulic oils 850-900 kg/m^3, water 1000, glycerol 1260; 900 in Tables 12 and 14", "rho_L, the liquid's density");
/// d.
pub const DRY_FRICTION: Key = Key::number("dry_friction", "N", Incl(0.0), Incl(1000.0), "seal friction: 0-0.2 N in Tables 12 and 14; the solver gives up near 4000 N", "d, the seals' dry friction (eq 48)");
/// b.
pub const VISCOUS_FRICTION: Key = Key::number("viscous_friction", "N s/m", Incl(0.0), Incl(1e4), "0.5 N s/m in Tables 12 and 14", "b, the viscous friction (eq 48)");
/// kappa: 1 is isothermal, 5/3 a monatomic gas: nothing outside is a gas.
pub const ADIABATIC_EXPONENT: Key = Key::number("adiabatic_exponent", "", Incl(1.0), Incl(5.0 / 3.0), "1 is isothermal, 5/3 a monatomic gas: nothing outside is a gas", "kappa, the gas's adiabatic exponent (eq 47)")
    .default(DEFAULT_ADIABATIC_EXPONENT);
/// v0 of the dry friction.
pub const FRICTION_V0: Key = Key::number("friction_v0", "m/s", Incl(1e-5), Incl(0.1), "regularisation of sgn() (eq 48), 1e-3 m/s by default; below 1e-5 m/s the solver grinds", "the velocity regularising sgn() in the dry friction (eq 48)")
    .default(DEFAULT_HYDRAULIC_FRICTION_V0);

/// The keys of a hydraulic decoupler.
pub const KEYS: &[Key] = &[
    KIND,
    STROKE,
    PISTON_RADIUS,
    ORIFICE_RADIUS,
    GAS_PRESSURE,
    GAS_VOLUME,
    DISCHARGE_COEFFICIENT,
    LIQUID_DENSITY,
    DRY_FRICTION,
    VISCOUS_FRICTION,
    ADIABATIC_EXPONENT,
    FRICTION_V0,
    end_stop::FRONT,
    end_stop::BACK,
];

/// The largest orifice damping over the tool mass, D / m_t, 1/m (see `hydraulic`).
pub const MAX_ORIFICE_LOCK: f64 = 1e9;

/// Reads a hydraulic decoupler: the orifice inside the piston, the gas never driven to zero volume.
pub(in super::super) fn hydraulic(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<Hydraulic> {
    let stroke = cx.number(t, &STROKE);
    let piston_radius = cx.number(t, &PISTON_RADIUS);
    let orifice_radius = cx.number(t, &ORIFICE_RADIUS);
    let gas_pressure = cx.number(t, &GAS_PRESSURE);
    let gas_volume = cx.number(t, &GAS_VOLUME);
    let discharge_coefficient = cx.number(t, &DISCHARGE_COEFFICIENT);
    let liquid_density = cx.number(t, &LIQUID_DENSITY);
    let dry_friction = cx.number(t, &DRY_FRICTION);
    let viscous_friction = cx.number(t, &VISCOUS_FRICTION);
    let adiabatic_exponent = cx.number(t, &ADIABATIC_EXPONENT);
    let friction_v0 = cx.number(t, &FRICTION_V0);
    let (front_stop, back_stop) = end_stops(cx, t, tool_mass);

    if let (Some(rp), Some(ro)) = (piston_radius, orifice_radius) {
        if ro >= rp {
            cx.bad(
                t,
                ORIFICE_RADIUS.name,
                format!(
                    "must be < decoupler.piston_radius = {} m, got {}",
                    num(rp),
                    num(ro)
                ),
            );
            return None;
        }
    }
    // The orifice's flow force is D v^2 with D = rho A_p^3 / (2 c0^2 A_o^2) (eq 49-50): a tiny
    // orifice under a wide piston locks it, and the rate 2 D v / m_t outgrows anything the
    // integrator can span (R_o = 1e-5 m under Table 14's piston hit the step limit at 0.33 s; R_p =
    // 0.1 m over R_o = 5e-4 m too). Measured (release): D / m_t = 2e8 1/m ran in 2.4e6 steps, 2.1e9 ran, 5.2e10
    // failed; the cap is 1e9 (the shipped modules: 51).
    if let (Some(rp), Some(ro), Some(rho), Some(c0), Some(mt)) = (piston_radius, orifice_radius, liquid_density, discharge_coefficient, tool_mass) {
        let (ap, ao) = (std::f64::consts::PI * rp * rp, std::f64::consts::PI * ro * ro);
        let d = rho * ap.powi(3) / (2.0 * c0 * c0 * ao * ao);
        if d / mt > MAX_ORIFICE_LOCK {
            cx.bad(
                t,
                ORIFICE_RADIUS.name,
                format!(
                    "the orifice locks the piston: its flow force D v^2 has D = liquid_density A_p^3 / (2 c0^2 A_o^2) = {} N s^2/m^2, {} 1/m over the tool mass, beyond the {} 1/m the integrator can span (the shipped modules: 51); enlarge orifice_radius or model the module as rigid, got {}",
                    approx(d),
                    approx(d / mt),
                    num(MAX_ORIFICE_LOCK),
                    num(ro)
                ),
            );
            return None;
        }
    }
    if let (Some(rp), Some(l), Some(vg)) = (piston_radius, stroke, gas_volume) {
        let swept = std::f64::consts::PI * rp * rp * l;
        if swept >= vg {
            cx.bad(
                t,
                GAS_VOLUME.name,
                format!(
                    "must be > the volume the piston sweeps, pi * piston_radius^2 * stroke = {} m^3 (else the gas is driven to zero volume), got {}",
                    approx(swept),
                    num(vg)
                ),
            );
            return None;
        }
    }
    Some(Hydraulic {
        stroke: stroke?,
        piston_radius: piston_radius?,
        orifice_radius: orifice_radius?,
        gas_pressure: gas_pressure?,
        gas_volume: gas_volume?,
        discharge_coefficient: discharge_coefficient?,
        liquid_density: liquid_density?,
        dry_friction: dry_friction?,
        viscous_friction: viscous_friction?,
        adiabatic_exponent: adiabatic_exponent?,
        friction_v0: friction_v0?,
        front_stop: front_stop?,
        back_stop: back_stop?,
    })
}
