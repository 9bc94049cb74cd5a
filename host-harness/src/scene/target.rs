//! `[target]`: what the tool runs into, a fixed obstacle or a free object (`plant/target.rs`), and
//! the tool-target contact (`plant/contact.rs`; the damping keys are in `contact.rs`).
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::contact::{self, contact_damping};
use super::model::{Target, TargetKind};

/// The `[target]` table in the top level.
pub const TABLE: Key = Key::of("target", Ty::Table("what the tool runs into"), "what the tool runs into");

/// Obstacle or object.
pub const KIND: Key = Key::of("kind", Ty::Choice(&["obstacle", "object"]), "\"obstacle\" (fixed) or \"object\" (free, needs mass)");
/// Gap at t = 0.
pub const GAP: Key = Key::number("gap", "m", Incl(1e-6), Incl(2.0), "1 um to 2 m, within the reach of an arm; 0.005-0.15 m in the thesis", "gap between the tool and the target at t = 0; the motion must close it within duration");
/// k_c.
pub const STIFFNESS: Key = Key::number("stiffness", "N/m^1.5", Incl(1e3), Incl(1e10), "Hertz contact from foam (1e3 N/m^1.5) to metal on metal; 1e3-1e8 in the thesis", "k_c, the Hertz contact stiffness of tool and target (eq 5)");
/// m_p.
pub const MASS: Key = Key::number("mass", "kg", Incl(1e-3), Incl(1000.0), "1 g to 1 t; 0.136-0.25 kg in Tables 4-15", "m_p, the free object's mass (kind = \"object\" only)");
/// Floor friction under a free object.
pub const FLOOR_FRICTION: Key = Key::number("floor_friction", "", Incl(0.0), Incl(1.0), "dry friction coefficients: 0 (ice) to about 1 (rubber on concrete)", "Coulomb friction coefficient between a free object and the floor (kind = \"object\" only)")
    .optional("no floor friction");

/// The keys of an obstacle.
pub const OBSTACLE_KEYS: &[Key] = &[KIND, GAP, STIFFNESS, contact::RESTITUTION, contact::DAMPING_LAW, contact::CHI];
/// The keys of a free object.
pub const OBJECT_KEYS: &[Key] = &[KIND, GAP, STIFFNESS, contact::RESTITUTION, contact::DAMPING_LAW, contact::CHI, MASS, FLOOR_FRICTION];

#[derive(Clone, Copy)]
enum K {
    Obstacle,
    Object,
}

/// Reads `[target]`.
pub(super) fn target(cx: &mut Ctx, t: &Tab) -> Option<Target> {
    let kind = cx.choice(t, &KIND, &[K::Obstacle, K::Object]);
    match kind {
        Some(K::Obstacle) => cx.check_keys(t, OBSTACLE_KEYS, " for kind = \"obstacle\""),
        Some(K::Object) => cx.check_keys(t, OBJECT_KEYS, " for kind = \"object\""),
        None => {}
    }
    let gap = cx.number(t, &GAP);
    let stiffness = cx.number(t, &STIFFNESS);
    let damping = contact_damping(cx, t, None);
    let kind = match kind? {
        K::Obstacle => TargetKind::Obstacle,
        K::Object => {
            let mass = cx.number(t, &MASS);
            let floor_friction = cx.maybe_number(t, &FLOOR_FRICTION)?;
            TargetKind::Object {
                mass: mass?,
                floor_friction,
            }
        }
    };
    Some(Target {
        kind,
        gap: gap?,
        stiffness: stiffness?,
        damping: damping?,
    })
}
