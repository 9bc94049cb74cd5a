//! `[decoupler]`: what holds the tool on the flange (MODEL.md element 3, `plant/decoupler/`).
//! `kind` picks the mechanism; each mechanism's keys are in its own file, named as its plant file.
//! A rigid decoupler (the tool fastened to the flange) has no key but `kind`.
pub mod bistable;
pub mod end_stop;
pub mod hydraulic;
pub mod linear;

use super::check::{Ctx, Key, Tab, Ty};
use super::model::Decoupler;

/// The `[decoupler]` table in the top level.
pub const TABLE: Key = Key::of("decoupler", Ty::Table("what holds the tool on the flange"), "what holds the tool on the flange");

/// The mechanism; a new decoupler adds its name here and its arm in [`decoupler`].
pub const KIND: Key = Key::of(
    "kind",
    Ty::Choice(&["rigid", "linear", "bistable", "hydraulic"]),
    "the mechanism: \"rigid\" (no decoupler), \"linear\" (eq 17, 23), \"bistable\" (eq 24-42), \"hydraulic\" (eq 46-56)",
);

/// The keys of a rigid decoupler.
pub const RIGID_KEYS: &[Key] = &[KIND];

#[derive(Clone, Copy)]
enum DecKind {
    Rigid,
    Linear,
    Bistable,
    Hydraulic,
}

/// Reads `[decoupler]`; the tool mass converts a front-stop restitution to a damping, and the
/// tool's weight enters the bi-stable's rest check.
pub(super) fn decoupler(
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
