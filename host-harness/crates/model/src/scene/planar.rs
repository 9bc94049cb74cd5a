//! The planar keys (issue 30, docs/planar.md): `motion.off_axis_deg`, `target.surface_angle_deg`,
//! `target.friction_mu` and `solver.plant`, read into [`Planar`] (`plant/planar/`).
//!
//! Angles in degrees, counter-clockwise positive, in the plane of motion. u is the decoupler's axis
//! at rest (from the flange to the tool, +x of the 1-D plant). beta = `motion.off_axis_deg` is the
//! angle from u to the flange's commanded velocity e_p; theta = `target.surface_angle_deg` is the
//! thesis's (Fig. 68a): the surface's outward normal is n = R(theta - 90 deg) u, so theta = -90 is the
//! 1-D surface (n = -u, the tool pushed straight back) and theta = 0 a surface parallel to the guide.
//! Defaults keep every 1-D scene 1-D: neither key, beta = 0 and theta = -90; beta only, the surface
//! faces the motion (theta = beta - 90); theta only, the motion is along -n (beta = theta + 90).

use super::check::{num, Bound::*, Ctx, Key, Tab, Ty};
use super::model::{Decoupler, FrictionLaw, Planar, Stage, Target, TargetKind};

/// beta.
pub const OFF_AXIS: Key = Key::number("off_axis_deg", "deg", Incl(-180.0), Incl(180.0), "any direction in the plane of motion", "beta, the angle from the decoupler's axis (at rest) to the flange's commanded velocity, counter-clockwise (planar plant, docs/planar.md)")
    .optional("0 (along the axis), or theta + 90 when target.surface_angle_deg is given");
/// theta.
pub const SURFACE_ANGLE: Key = Key::number("surface_angle_deg", "deg", Incl(-180.0), Incl(180.0), "any orientation of the surface in the plane of motion (Fig. 68a)", "theta of Fig. 68a, the angle between the impacted surface and the decoupler's axis: the outward normal is R(theta - 90 deg) u (-90: head-on, the 1-D surface) (planar plant, docs/planar.md)")
    .optional("facing the motion: motion.off_axis_deg - 90 (-90 without it, the 1-D surface)");
/// Coulomb friction at the tool-target contact.
pub const CONTACT_MU: Key = Key::number("friction_mu", "", Incl(0.0), Incl(1.5), "PTFE on steel about 0.04 to rubber on steel about 1.2", "Coulomb friction coefficient between the tool and the target, regularised mu N tanh(v / 1 mm/s) (planar plant)")
    .optional("a frictionless contact, as every 1-D scene");
/// Which plant runs the scene.
pub const PLANT: Key = Key::of("plant", Ty::Choice(&["1d", "planar"]), "\"1d\" or \"planar\": the plant that runs the scene; an axial scene runs the 1-D plant unless \"planar\" is asked for (the equivalence test does), a scene with planar keys only the planar one")
    .optional("\"1d\" for an axial scene, \"planar\" when a planar key is set");

/// The smallest e_p . (-n) accepted: below it the flange moves along the surface or away from it.
pub const MIN_CLOSING: f64 = 0.02;

/// Reads the planar keys of `[motion]`, `[target]` and `[solver]`; `None` (reported) when invalid,
/// `Some(None)` for a 1-D scene.
pub(super) fn planar(cx: &mut Ctx, motion: Option<&Tab>, target: Option<&Tab>, solver: Option<&Tab>, stage: Option<Option<Stage>>) -> Option<Option<Planar>> {
    let stage = stage?;
    let beta = match motion { Some(t) => cx.maybe_number(t, &OFF_AXIS)?, None => None };
    let (theta, mu) = match target {
        Some(t) => (cx.maybe_number(t, &SURFACE_ANGLE)?, cx.maybe_number(t, &CONTACT_MU)?),
        None => (None, None),
    };
    let plant = match solver { Some(t) => cx.maybe_choice(t, &PLANT, &[false, true])?, None => None };
    let any_key = beta.is_some() || theta.is_some() || mu.is_some() || stage.is_some();
    if plant == Some(false) && any_key {
        if let Some(s) = solver {
            cx.bad(s, PLANT.name, "must be \"planar\" (or left out) when motion.off_axis_deg, target.surface_angle_deg, target.friction_mu or [decoupler.rotational] is set: the 1-D plant cannot run them".into());
        }
        return None;
    }
    if !any_key && plant != Some(true) {
        return Some(None);
    }
    let (beta, theta) = match (beta, theta) {
        (None, None) => (0.0, -90.0),
        (Some(b), None) => (b, wrap_deg(b - 90.0)),
        (None, Some(t)) => (wrap_deg(t + 90.0), t),
        (Some(b), Some(t)) => (b, t),
    };
    let p = Planar { off_axis_deg: beta, surface_angle_deg: theta, contact_mu: mu.unwrap_or(0.0), rotational: stage };
    let closing = p.closing();
    if closing < MIN_CLOSING {
        let (tab, key) = match (target, motion) {
            (Some(t), _) if t.has(SURFACE_ANGLE.name) => (t, SURFACE_ANGLE.name),
            (_, Some(m)) => (m, OFF_AXIS.name),
            _ => return None,
        };
        cx.bad(tab, key, format!(
            "the flange must move towards the surface: with motion.off_axis_deg = {} and target.surface_angle_deg = {} it closes the gap at {} of its speed (at least {} needed: it moves along the surface or away from it)",
            num(beta), num(theta), num((closing * 1e4).round() / 1e4), num(MIN_CLOSING)
        ));
        return None;
    }
    Some(Some(p))
}

/// The gap is closed along the normal: the commanded travel (`cruise`, m, unbraked in `duration`)
/// times e_p . (-n) must exceed it.
pub(super) fn check_gap(cx: &mut Ctx, target: &Tab, p: &Planar, cruise: f64, duration: f64, gap: f64) {
    let travel = cruise * p.closing();
    if gap >= travel {
        cx.bad(target, "gap", format!(
            "the commanded motion closes only {} m of it along the surface's normal in duration = {} s (motion.off_axis_deg and target.surface_angle_deg), so the tool never reaches the target; must be < {} m, got {}",
            num(travel), num(duration), num(travel), num(gap)
        ));
    }
}

/// An angle wrapped to (-180, 180], deg.
pub fn wrap_deg(a: f64) -> f64 {
    let w = a.rem_euclid(360.0);
    if w > 180.0 { w - 360.0 } else { w }
}

/// The rotational module runs against a fixed obstacle with a regularised (or no) slide friction:
/// its stage angle takes the state slots a free object would use, and the guide's stick-slip in a
/// turning frame is not built (docs/planar.md).
pub(super) fn check_rotational(cx: &mut Ctx, decoupler: &Tab, p: &Planar, d: &Decoupler, target: &Target) {
    if p.rotational.is_none() {
        return;
    }
    if !matches!(target.kind, TargetKind::Obstacle) {
        cx.bad(decoupler, "rotational", "needs target.kind = \"obstacle\": the 2-D module is modelled against a fixed surface (the thesis's beam, Fig. 67)".into());
    }
    if let Decoupler::Bistable(b) = d {
        if b.friction.is_some_and(|f| f.law == FrictionLaw::StickSlip) {
            cx.bad(decoupler, "rotational", "needs decoupler.friction.law = \"regularised\" (v0 > 0): the guide's stick-slip on a turning stage is not modelled".into());
        }
    }
}
