//! `[solver]`: how to integrate (`solver/`): the method, its tolerances, the largest step, the
//! output interval, the fidelity that sets the tolerance defaults and the simplifications allowed.
//! The defaults were measured (docs/accuracy.md, `flinch bench`).
use super::check::{num, Bound::*, Ctx, Key, Tab, Ty};
use super::model::{Fidelity, Method, Simplify, SolverSettings};

/// Default relative tolerance of the adaptive solver. Measured (docs/accuracy.md, `flinch bench`):
/// with DEFAULT_ATOL and DEFAULT_MAX_STEP every shipped scene is within 1.1e-4 of the reference on
/// peak forces and detection time (the target is 1e-2), and Tables 5-7 runs about 1,400 times
/// faster than real time on one core (rtol 1e-7 with a 1 ms cap: 1.5e-5, about 900 times).
pub const DEFAULT_RTOL: f64 = 1e-6;
/// Default absolute tolerance of the adaptive solver (m and m/s): 1e-3 of DEFAULT_RTOL, i.e.
/// relative accuracy down to 1 mm and 1 mm/s.
pub const DEFAULT_ATOL: f64 = 1e-9;
/// Default largest step (adaptive) or fixed step (fixed-step methods), s. 10 ms: at rtol 1e-6 the
/// step control sets the step wherever something happens; a 1 ms cap only added steps in free
/// flight (600 of 861 on Tables 5-7) for no measurable accuracy, while no cap at all changed
/// nothing more (docs/accuracy.md). It still keeps a step from jumping a whole short excursion.
pub const DEFAULT_MAX_STEP: f64 = 1e-2;
/// Tolerances of `fidelity = "reference"` (docs/accuracy.md: the reference the others are
/// measured against; tightening further changes no reported figure by more than 1e-6).
pub const REFERENCE_RTOL: f64 = 1e-10;
/// Absolute tolerance of `fidelity = "reference"` (m and m/s).
pub const REFERENCE_ATOL: f64 = 1e-13;
/// Relative tolerance of `fidelity = "fast"`: within 1.2e-3 of the reference on peak forces and
/// detection time on every shipped scene (docs/accuracy.md).
pub const FAST_RTOL: f64 = 1e-5;
/// Absolute tolerance of `fidelity = "fast"`.
pub const FAST_ATOL: f64 = 1e-8;
/// Default interval between recorded samples, s.
pub const DEFAULT_OUTPUT_INTERVAL: f64 = 1e-4;
/// Default integration method.
pub const DEFAULT_METHOD: Method = Method::Dopri5;

/// The `[solver]` table in the top level.
pub const TABLE: Key = Key::of("solver", Ty::Table("integration settings"), "integration settings")
    .optional("the defaults below");

/// The method.
pub const METHOD: Key = Key::of("method", Ty::Choice(&["dopri5", "rk4", "semi-implicit-euler"]), "integration method: adaptive Dormand-Prince 5(4), or fixed-step RK4 or semi-implicit Euler at max_step")
    .optional("dopri5");
/// rtol.
pub const RTOL: Key = Key::number("rtol", "", Incl(1e-12), Incl(1e-5), "tighter than 1e-12 is below what f64 resolves over a run; looser than 1e-5 (fidelity = \"fast\") loses contacts and modes (docs/accuracy.md)", "relative tolerance of the adaptive method")
    .optional("by fidelity: 1e-6 (default), 1e-5 (fast), 1e-10 (reference)");
/// atol.
pub const ATOL: Key = Key::number("atol", "", Incl(1e-15), Incl(1e-8), "tighter than 1e-15 is below f64 resolution; looser than 1e-8 (fidelity = \"fast\") loses contacts and modes (docs/accuracy.md)", "absolute tolerance on positions (m) and velocities (m/s)")
    .optional("by fidelity: 1e-9 (default), 1e-8 (fast), 1e-13 (reference)");
/// The largest (or fixed) step.
pub const MAX_STEP: Key = Key::number("max_step", "s", Incl(1e-7), Incl(0.1), "10 ms by default; below 0.1 us a fixed-step run grinds, above 0.1 s a step can jump a whole contact; also <= duration", "largest step of the adaptive method, the step of a fixed-step one; <= duration")
    .default(DEFAULT_MAX_STEP);
/// Output interval.
pub const OUTPUT_INTERVAL: Key = Key::number("output_interval", "s", Incl(0.0), Incl(1.0), "0 records every step; 0.1 ms by default; also <= duration and at most 1e7 samples", "interval between recorded samples of the time history (0: every step); <= duration")
    .default(DEFAULT_OUTPUT_INTERVAL);
/// Fidelity.
pub const FIDELITY: Key = Key::of("fidelity", Ty::Choice(&["fast", "default", "reference"]), "the accuracy asked for; sets the tolerance defaults (docs/accuracy.md)")
    .optional("default");
/// Simplifications.
pub const SIMPLIFY: Key = Key::of("simplify", Ty::List(&["rigid-robot", "no-friction"]), "parts of the model the simulator may drop, each reported in the summary")
    .optional("none: the full model");

/// The keys of `[solver]`.
pub const KEYS: &[Key] = &[METHOD, RTOL, ATOL, MAX_STEP, OUTPUT_INTERVAL, FIDELITY, SIMPLIFY, super::planar::PLANT];

/// The settings of a scene without `[solver]`.
pub(super) fn default_solver() -> SolverSettings {
    SolverSettings {
        method: DEFAULT_METHOD,
        rtol: DEFAULT_RTOL,
        atol: DEFAULT_ATOL,
        max_step: DEFAULT_MAX_STEP,
        output_interval: DEFAULT_OUTPUT_INTERVAL,
        fidelity: Fidelity::Default,
        simplify: Simplify::default(),
    }
}

/// Reads `[solver]`; steps and intervals are checked against the duration.
pub(super) fn solver(cx: &mut Ctx, t: &Tab, duration: Option<f64>) -> Option<SolverSettings> {
    cx.check_keys(t, KEYS, "");
    let d = default_solver();
    let fidelity = cx
        .maybe_choice(t, &FIDELITY, &[Fidelity::Fast, Fidelity::Default, Fidelity::Reference])
        .map(|f| f.unwrap_or(d.fidelity));
    let (rtol_default, atol_default) = match fidelity {
        Some(Fidelity::Fast) => (FAST_RTOL, FAST_ATOL),
        Some(Fidelity::Reference) => (REFERENCE_RTOL, REFERENCE_ATOL),
        _ => (d.rtol, d.atol),
    };
    if fidelity == Some(Fidelity::Reference) {
        // The reference is one fixed thing: nothing may loosen it.
        for key in [&METHOD, &RTOL, &ATOL, &SIMPLIFY] {
            if t.has(key.name) {
                cx.bad(
                    t,
                    key.name,
                    format!("must not be set with fidelity = \"reference\" (dopri5 at rtol = {}, atol = {}, the full model)", num(REFERENCE_RTOL), num(REFERENCE_ATOL)),
                );
            }
        }
    }
    let method = cx
        .maybe_choice(t, &METHOD, &[Method::Dopri5, Method::Rk4, Method::SemiImplicitEuler])
        .map(|m| m.unwrap_or(d.method));
    let rtol = cx.maybe_number(t, &RTOL).map(|x| x.unwrap_or(rtol_default));
    let atol = cx.maybe_number(t, &ATOL).map(|x| x.unwrap_or(atol_default));
    let max_step = cx.number(t, &MAX_STEP);
    let output_interval = cx.number(t, &OUTPUT_INTERVAL);
    let simplify = cx.list(t, &SIMPLIFY).map(|names| Simplify {
        rigid_robot: names.contains(&0),
        no_friction: names.contains(&1),
    });
    if let Some(dur) = duration {
        for (key, v) in [(&MAX_STEP, max_step), (&OUTPUT_INTERVAL, output_interval)] {
            if let Some(v) = v.filter(|&v| v > dur) {
                cx.bad(
                    t,
                    key.name,
                    format!("must be <= duration = {} s, got {}", num(dur), num(v)),
                );
                return None;
            }
        }
    }
    Some(SolverSettings {
        method: method?,
        rtol: rtol?,
        atol: atol?,
        max_step: max_step?,
        output_interval: output_interval?,
        fidelity: fidelity?,
        simplify: simplify?,
    })
}
