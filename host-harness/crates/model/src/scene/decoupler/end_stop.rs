//! `front_stop` and `back_stop`: the elastomer end-stops the bi-stable and hydraulic decouplers
//! share (eq 28-29, 37-38; `plant/decoupler/end_stop.rs`). The front stop is linear, the back stop
//! (the flange) a nonlinear contact whose damping keys are those of `scene/contact.rs`.
use super::super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::super::contact::{self, contact_damping};
use super::super::model::{DampingLaw, FrontStopLaw, LinearStop, NonlinearStop};
use crate::damping_law;

/// Damping law of the back end-stop when only a restitution is given (the thesis, eq 29/37).
pub const DEFAULT_BACK_STOP_LAW: DampingLaw = DampingLaw::HuntCrossley;

/// The `front_stop` table of a decoupler.
pub const FRONT: Key = Key::of(
    "front_stop",
    Ty::Table("{ stiffness, damping } or { stiffness, restitution }"),
    "the front end-stop where the tool rests: eq 28/38's linear law, or Hunt-Crossley with law and exponent",
);
/// The `back_stop` table of a decoupler.
pub const BACK: Key = Key::of(
    "back_stop",
    Ty::Table("{ stiffness, restitution, damping_law } or { stiffness, chi }"),
    "the nonlinear back end-stop, the flange (eq 29/37)",
);

/// k_fe.
pub const FRONT_STIFFNESS: Key = Key::number("stiffness", "N/m", Incl(1e3), Incl(1e9), "soft elastomer to a hard pad: 1e6-2.25e6 N/m in Tables 2-15; stiffer gives wrong forces at the default tolerances", "k_fe, the front stop's stiffness");
/// c_fe.
pub const FRONT_DAMPING: Key = Key::number("damping", "N s/m", Incl(0.0), Incl(1e5), "235-278 N s/m in Tables 2-15; 1e5 N s/m is beyond critical for the stiffest stop and heaviest tool in range", "c_fe, the front stop's damping")
    .optional("give restitution instead");
/// e_fe.
pub const FRONT_RESTITUTION: Key = Key::number("restitution", "", Incl(0.0), Incl(1.0), "a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)", "e_fe, converted to c_fe = 2 zeta sqrt(k_fe m_t), zeta = -ln e / sqrt(pi^2 + ln^2 e) (Table 11)")
    .optional("give damping instead");
/// k_be.
pub const BACK_STIFFNESS: Key = Key::number("stiffness", "N/m^1.5", Incl(1e3), Incl(1e10), "foam to metal on metal: 1e6-2.25e6 N/m^1.5 in Tables 2-15", "k_be, the back stop's Hertz stiffness");
/// The back stop's damping law (defaults to the thesis's).
pub const BACK_DAMPING_LAW: Key = contact::DAMPING_LAW.optional("hunt-crossley, as the thesis (eq 29/37)");

/// The front stop's law.
pub const FRONT_LAW: Key = Key::of(
    "law",
    Ty::Choice(&["linear", "hunt-crossley"]),
    "\"linear\": eq 28/38, F = k d + c d' (jumps to c d' the instant the tool lands); \"hunt-crossley\": F = k d^n (1 + alpha d' / v_in), zero at landing, with the same k (n = 1) and alpha chosen so an isolated impact loses the same energy as the linear law with these keys (restitution matched, for the tool mass)",
)
.optional("linear, as the thesis (eq 28/38)");
/// The Hunt-Crossley front stop's exponent n.
pub const FRONT_EXPONENT: Key = Key::number("exponent", "", Incl(1.0), Incl(2.0), "1 (the same static stiffness as eq 28) to 2; 1.5 is Hertz's, the back stop's", "n of the Hunt-Crossley front stop (stiffness then in N/m^n); only with law = \"hunt-crossley\"")
    .default(1.0);

/// The keys of `front_stop`.
pub const FRONT_KEYS: &[Key] = &[FRONT_STIFFNESS, FRONT_DAMPING, FRONT_RESTITUTION, FRONT_LAW, FRONT_EXPONENT];
/// The keys of `back_stop`.
pub const BACK_KEYS: &[Key] = &[BACK_STIFFNESS, contact::RESTITUTION, BACK_DAMPING_LAW, contact::CHI];

/// Damping ratio of a linear oscillator whose restitution is `e`.
pub(in super::super) fn zeta_from_restitution(e: f64) -> f64 {
    if e <= 0.0 {
        return 1.0;
    }
    let l = e.ln();
    -l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
}

/// The `front_stop` (linear, or Hunt-Crossley) and `back_stop` (nonlinear) tables, both required.
pub(super) fn end_stops(
    cx: &mut Ctx,
    t: &Tab,
    tool_mass: Option<f64>,
) -> (Option<LinearStop>, Option<NonlinearStop>) {
    let front_stop = cx.table(t, &FRONT);
    let front_stop = front_stop.and_then(|s| linear_stop(cx, &s, tool_mass));
    let back_stop = cx.table(t, &BACK);
    let back_stop = back_stop.and_then(|s| nonlinear_stop(cx, &s));
    (front_stop, back_stop)
}

fn linear_stop(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<LinearStop> {
    cx.check_keys(t, FRONT_KEYS, "");
    let stiffness = cx.number(t, &FRONT_STIFFNESS);
    let hunt_crossley = cx.maybe_choice(t, &FRONT_LAW, &[false, true])?.unwrap_or(false);
    let exponent = if hunt_crossley {
        cx.number(t, &FRONT_EXPONENT)?
    } else {
        if t.has(FRONT_EXPONENT.name) {
            cx.bad(t, FRONT_EXPONENT.name, "only with law = \"hunt-crossley\" (eq 28's linear law has no exponent)".into());
            return None;
        }
        1.0
    };
    let (k, damping, asked_e) = match (t.has(FRONT_DAMPING.name), t.has(FRONT_RESTITUTION.name)) {
        (true, true) => {
            cx.bad(
                t,
                FRONT_RESTITUTION.name,
                "give either damping (N s/m) or restitution, not both".into(),
            );
            return None;
        }
        (false, false) => {
            cx.missing(
                t,
                FRONT_DAMPING.name,
                "damping (N s/m >= 0), or restitution in [0, 1] converted with the tool mass",
            );
            return None;
        }
        (true, false) => {
            let damping = cx.number(t, &FRONT_DAMPING);
            if hunt_crossley && exponent != 1.0 {
                cx.bad(t, FRONT_DAMPING.name, format!("with exponent = {exponent} give restitution instead: c_fe's restitution is defined for eq 28's linear spring, exponent 1"));
                return None;
            }
            (stiffness?, damping?, None)
        }
        (false, true) => {
            let e = cx.number(t, &FRONT_RESTITUTION)?;
            let (k, m) = (stiffness?, tool_mass?);
            (k, 2.0 * zeta_from_restitution(e) * (k * m).sqrt(), Some(e))
        }
    };
    let law = if hunt_crossley {
        // The restitution to match: the one asked, or the one eq 28 achieves with c_fe and the
        // tool mass (clamped so it never pulls, as the plant models it).
        let e = match asked_e {
            Some(e) => e,
            None => damping_law::linear_restitution(damping / (2.0 * (k * tool_mass?).sqrt())),
        };
        FrontStopLaw::HuntCrossley { exponent, alpha: damping_law::hunt_crossley_alpha(e, exponent), restitution: e }
    } else {
        FrontStopLaw::Linear
    };
    Some(LinearStop { stiffness: k, damping, law })
}

fn nonlinear_stop(cx: &mut Ctx, t: &Tab) -> Option<NonlinearStop> {
    cx.check_keys(t, BACK_KEYS, "");
    let stiffness = cx.number(t, &BACK_STIFFNESS);
    let damping = contact_damping(cx, t, Some(DEFAULT_BACK_STOP_LAW));
    Some(NonlinearStop {
        stiffness: stiffness?,
        damping: damping?,
    })
}
