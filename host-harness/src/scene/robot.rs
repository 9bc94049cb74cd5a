//! `[robot]`: the robot's compliance at the flange, a base-excited mass (eq 33,
//! `plant/robot.rs`); absent, the robot is rigid.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::Robot;

/// The `[robot]` table in the top level.
pub const TABLE: Key = Key::of(
    "robot",
    Ty::Table("the robot compliance; omit it for a rigid robot"),
    "the robot compliance",
)
.optional("a rigid robot: x_r = x_c");

/// m_r.
pub const MASS: Key = Key::number("mass", "kg", Incl(0.1), Incl(500.0), "effective mass at the flange: 8.4 kg for the Viper s650 (Table 7), a few hundred kg for the largest arms", "m_r, the robot's effective mass at the flange");
/// k_r.
pub const STIFFNESS: Key = Key::number("stiffness", "N/m", Incl(1e3), Incl(1e8), "flange stiffness of arms: 2.3e5 N/m for the Viper s650 (Table 7), 1e5-1e7 N/m for industrial arms", "k_r, the robot's stiffness at the flange along the approach");
/// c_r.
pub const DAMPING: Key = Key::number("damping", "N s/m", Incl(0.0), Incl(1e5), "71 N s/m for the Viper s650 (Table 7); 1e5 N s/m is beyond critical for the stiffest, heaviest arm in range", "c_r, the robot's damping at the flange");

/// The keys of `[robot]`.
pub const KEYS: &[Key] = &[MASS, STIFFNESS, DAMPING];

/// Reads `[robot]`.
pub(super) fn robot(cx: &mut Ctx, t: &Tab) -> Option<Robot> {
    cx.check_keys(t, KEYS, "");
    let mass = cx.number(t, &MASS);
    let stiffness = cx.number(t, &STIFFNESS);
    let damping = cx.number(t, &DAMPING);
    Some(Robot {
        mass: mass?,
        stiffness: stiffness?,
        damping: damping?,
    })
}
