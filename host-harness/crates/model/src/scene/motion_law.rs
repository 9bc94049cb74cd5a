//! `[motion]`: the commanded flange motion (MODEL.md element 1, `plant/motion_law.rs`): accelerate
//! at `accel` to `speed`, cruise; braking at `decel` starts `dead_time` after detection. Or, with
//! `stopping` (the robot's own stopping table, `stopping.rs`), the stop follows the table from a
//! stop signal sent `dead_time` (default 0) after detection.
use super::check::{num, Bound::*, Ctx, Key, Tab, Ty};
use super::model::Motion;
use super::stopping;

/// The `[motion]` table in the top level.
pub const TABLE: Key = Key::of("motion", Ty::Table("the commanded flange motion"), "the commanded flange motion");

/// V_c.
pub const SPEED: Key = Key::number("speed", "m/s", Incl(1e-4), Incl(5.0), "0.1 mm/s (a creep, not a collision) to 5 m/s, beyond the 0.05-1 m/s of the thesis and the fastest flange speeds of arms of the Viper s650 class (Table 7)", "V_c, the commanded cruise speed of the flange");
/// a_c.
pub const ACCEL: Key = Key::number("accel", "m/s^2", Incl(1e-3), Incl(500.0), "up to about 50 g, beyond what the drives of arms in the Table 7 class reach (a few 10 m/s^2)", "a_c, the commanded acceleration up to V_c");
/// d_c.
pub const DECEL: Key = Key::number("decel", "m/s^2", Incl(1e-3), Incl(500.0), "up to about 50 g, beyond any robot stop (the thesis brakes at 2-9 m/s^2)", "d_c, the braking deceleration once the robot reacts")
    .optional("required unless stopping is given");
/// DT.
pub const DEAD_TIME: Key = Key::number("dead_time", "s", Incl(0.0), Incl(1.0), "controller reaction times: 10-70 ms in the thesis, well under 1 s for any stop category 0/1 robot (ISO 13855 stopping performance)", "DT, from detection to the start of braking; with stopping, from detection to the stop signal at the robot (the table's times include the robot's reaction)")
    .optional("required with decel; with stopping, 0: the robot gets the stop signal at detection");
/// Gravity along the approach.
pub const GRAVITY: Key = Key::number("gravity", "m/s^2", Incl(-9.81), Incl(9.81), "the component of Earth gravity (9.81 m/s^2, as the thesis) along the approach", "gravity along the approach direction (9.81 for a tool moving down, -9.81 up)");
/// Start already cruising.
pub const START_AT_SPEED: Key = Key::of("start_at_speed", Ty::Bool, "flange, robot and tool already cruise at V_c at t = 0 (the Ch. 2 set-ups); accel is then unused")
    .optional("false: the motion starts from rest");

/// Hold braking until a contact has ended (Table 4's account, Ch. 2.5).
pub const BRAKE_AFTER_CONTACT: Key = Key::integer("brake_after_contact", 1, 100, "a count of tool-target contacts; Table 4's variant holds braking until the 2nd has ended", "braking does not start before tool-target contact number N has ended (a test of the thesis's account of Table 4, Ch. 2.5, not a controller: it delays the stop)")
    .optional("0: braking starts dead_time after detection");

/// The keys of `[motion]`.
pub const KEYS: &[Key] = &[SPEED, ACCEL, DECEL, DEAD_TIME, GRAVITY, START_AT_SPEED, BRAKE_AFTER_CONTACT, stopping::TABLE, super::planar::OFF_AXIS];

/// Reads `[motion]`; `tool_mass` (when valid) is held against `stopping.payload`.
pub(super) fn motion(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<Motion> {
    cx.check_keys(t, KEYS, "");
    let speed = cx.number(t, &SPEED);
    let accel = cx.number(t, &ACCEL);
    let decel = cx.maybe_number(t, &DECEL);
    let dead_time = cx.maybe_number(t, &DEAD_TIME);
    let table = cx.maybe_table(t, &stopping::TABLE).map(|st| st.map(|st| stopping::stopping(cx, &st, tool_mass)));
    let gravity = cx.number(t, &GRAVITY);
    let start_at_speed = cx.boolean(t, &START_AT_SPEED);
    // Absent reads as None without a message; an invalid value is reported and fails the load.
    let brake_after_contact = cx.integer(t, &BRAKE_AFTER_CONTACT).unwrap_or(0);
    let (speed, decel, dead_time, table) = (speed?, decel?, dead_time?, table?);
    // Either decel with dead_time, or the stopping table (dead_time then optional).
    let (decel, dead_time, stopping, payload) = match (decel, table) {
        (Some(_), Some(_)) => {
            cx.bad(t, DECEL.name, "give either decel (with dead_time) or stopping (the robot's stopping table), not both".into());
            return None;
        }
        (None, None) => {
            cx.missing(t, DECEL.name, &format!("{} (or give stopping, the robot's stopping table)", DECEL.what()));
            return None;
        }
        (Some(d), None) => {
            let Some(dt) = dead_time else {
                cx.missing(t, DEAD_TIME.name, &DEAD_TIME.what());
                return None;
            };
            (d, dt, None, None)
        }
        (None, Some(table)) => {
            let (table, payload) = table?;
            // The plant brakes from V_c with the equivalent deceleration (model/src/stopping.rs); above
            // the table nothing is known: refused, not extrapolated.
            let Some(e) = table.equivalent(speed) else {
                cx.bad(t, SPEED.name, format!(
                    "must be at most the largest speed of motion.stopping, {} m/s: the stop from a faster motion is not in the robot's data and is not extrapolated; got {}",
                    num(table.max_speed()), num(speed)
                ));
                return None;
            };
            (e.decel, dead_time.unwrap_or(0.0), Some(table), payload)
        }
    };
    Some(Motion {
        speed,
        accel: accel?,
        decel,
        dead_time,
        stopping,
        stopping_payload: payload,
        gravity: gravity?,
        start_at_speed: start_at_speed?.unwrap_or(false),
        brake_after_contact,
    })
}

/// Commanded flange travel in `t` s with no braking (trapezoid, or cruising from t = 0).
pub(super) fn cruise_travel(m: &Motion, t: f64) -> f64 {
    if m.start_at_speed {
        return m.speed * t;
    }
    let t_acc = m.speed / m.accel;
    if t <= t_acc {
        0.5 * m.accel * t * t
    } else {
        0.5 * m.speed * t_acc + m.speed * (t - t_acc)
    }
}
