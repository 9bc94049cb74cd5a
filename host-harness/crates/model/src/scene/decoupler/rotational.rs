//! `[decoupler.rotational]` (kind = "bistable"): the thesis's 2-D rotational module (Ch. 3.5,
//! Fig. 63-66; `plant/planar/rotational_stage.rs`): the bi-stable mechanism of `[decoupler]` on a
//! guide carried by a stage that turns about the flange's axis, held by two retaining springs, the
//! tool offset from the guide so that an impact turns the stage. The table's presence makes the
//! module rotational; every bi-stable key keeps its meaning along the guide. Units: m, kg m^2,
//! N m/rad, N m. The thesis prints none of these values (docs/validation.md lists them as open).

use crate::scene::check::{Bound::*, Ctx, Key, Tab, Ty};
use crate::scene::model::Stage;

/// The table.
pub const TABLE: Key = Key::of("rotational", Ty::Table("the rotating stage of the 2-D module"), "the rotating stage of the thesis's 2-D module (Ch. 3.5): makes the bi-stable module rotational (planar plant, docs/planar.md)")
    .optional("a 1-D bi-stable module");
/// J.
pub const INERTIA: Key = Key::number("inertia", "kg m^2", Incl(1e-7), Incl(1.0), "a 10 g ring (1e-7) to a 10 kg plate at 0.3 m", "the stage's and the tool's moment of inertia about their own axes (the tool's mass m_t at its offset is added by the plant)");
/// l.
pub const LEVER: Key = Key::number("lever", "m", Incl(-0.2), Incl(0.2), "within a hand-sized module; negative puts the tool ahead of the stage's axis (it locks: a test case)", "l = cursor offset + a (Fig. 66): from the stage's axis to the tool's axis along the guide, tool on its front stop, positive when the tool trails the axis (the yield direction points away from it)");
/// b.
pub const OFFSET_B: Key = Key::number("offset_b", "m", Incl(-0.1), Incl(0.1), "within a hand-sized module", "b (Fig. 66): the tool's axis across the guide, positive on the side R(-90 deg) u; it turns the stage at theta = 90 deg, where the push runs along the guide");
/// r_t.
pub const TOOL_RADIUS: Key = Key::number("tool_radius", "m", Incl(0.0), Incl(0.05), "a point to a 100 mm disc", "the tool's contact outline, a disc about its axis (0: a point)")
    .default(0.0);
/// k_phi.
pub const STIFFNESS: Key = Key::number("stiffness", "N m/rad", Incl(0.0), Incl(100.0), "two springs k_s at radius r_s give 2 k_s r_s^2: 0.02 for 100 N/m at 10 mm", "k_phi, the retaining springs' rate about the stage's axis (Fig. 65)");
/// M0.
pub const PRELOAD: Key = Key::number("preload", "N m", Incl(0.0), Incl(10.0), "holds the stage against the path's acceleration; 0.02 for a 0.1 kg tool at 40 mm under 5 m/s^2", "M0, the retaining springs' preload: the moment needed to start turning the stage (reached within about 1 deg of rest, smooth)")
    .default(0.0);
/// Bearing friction.
pub const BEARING_TORQUE: Key = Key::number("bearing_torque", "N m", Incl(0.0), Incl(0.01), "ball and axial roller bearings of a hand-sized stage: 1e-4-1e-2 N m; more makes the regularised bearing friction too stiff to integrate in reasonable time", "the stage bearings' friction moment, regularised M tanh(phi' / 0.01 rad/s)")
    .default(0.0);

/// The keys of `[decoupler.rotational]`.
pub const KEYS: &[Key] = &[INERTIA, LEVER, OFFSET_B, TOOL_RADIUS, STIFFNESS, PRELOAD, BEARING_TORQUE];

/// Reads `[decoupler.rotational]`.
pub(in crate::scene) fn stage(cx: &mut Ctx, t: &Tab) -> Option<Stage> {
    cx.check_keys(t, KEYS, "");
    let inertia = cx.number(t, &INERTIA);
    let lever = cx.number(t, &LEVER);
    let offset_b = cx.number(t, &OFFSET_B);
    let tool_radius = cx.number(t, &TOOL_RADIUS);
    let stiffness = cx.number(t, &STIFFNESS);
    let preload = cx.number(t, &PRELOAD);
    let bearing_torque = cx.number(t, &BEARING_TORQUE);
    let s = Stage {
        inertia: inertia?,
        lever: lever?,
        offset_b: offset_b?,
        tool_radius: tool_radius?,
        stiffness: stiffness?,
        preload: preload?,
        bearing_torque: bearing_torque?,
    };
    if s.lever.hypot(s.offset_b) <= s.tool_radius {
        cx.bad(t, LEVER.name, format!("the tool's outline (tool_radius = {} m) covers the stage's axis (lever, offset_b): no moment would turn the stage", s.tool_radius));
        return None;
    }
    Some(s)
}
