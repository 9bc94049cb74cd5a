//! Reads `[decoupler]`: `kind` picks the mechanism's reader (in its own file).

use super::kind::{KIND, RIGID_KEYS};
use super::{bistable, hydraulic, linear};
use crate::scene::check::{Ctx, Tab};
use crate::scene::model::Decoupler;

#[derive(Clone, Copy)]
enum DecKind {
    Rigid,
    Linear,
    Bistable,
    Hydraulic,
}

/// Reads `[decoupler]` (a new decoupler adds its arm here); the tool mass converts a front-stop restitution to a damping, and the
/// tool's weight enters the bi-stable's rest check.
pub(in crate::scene) fn decoupler(
    cx: &mut Ctx,
    t: &Tab,
    tool_mass: Option<f64>,
    gravity: Option<f64>,
) -> Option<Decoupler> {
    let kinds = [DecKind::Rigid, DecKind::Linear, DecKind::Bistable, DecKind::Hydraulic];
    // The allowed keys depend on the kind: without a valid kind only the kind is reported.
    match cx.choice(t, &KIND, &kinds)? {
        DecKind::Rigid => {
            cx.check_keys(t, RIGID_KEYS, " for kind = \"rigid\"");
            Some(Decoupler::Rigid)
        }
        DecKind::Linear => {
            cx.check_keys(t, linear::KEYS, " for kind = \"linear\"");
            linear::linear(cx, t).map(Decoupler::Linear)
        }
        DecKind::Bistable => {
            cx.check_keys(t, bistable::KEYS, " for kind = \"bistable\"");
            bistable::bistable(cx, t, tool_mass, gravity).map(Decoupler::Bistable)
        }
        DecKind::Hydraulic => {
            cx.check_keys(t, hydraulic::KEYS, " for kind = \"hydraulic\"");
            hydraulic::hydraulic(cx, t, tool_mass).map(Decoupler::Hydraulic)
        }
    }
}
