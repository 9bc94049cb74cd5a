//! `[controller]`: the robot controller of firmware-in-the-loop runs (`flinch hil`, `flinch-hil`):
//! inputs sampled once per scan cycle, the firmware ticking at its own period.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::{Controller, DEFAULT_BRAKE_DECEL_MPS2, DEFAULT_BRAKE_DELAY_S};

/// True when `x` seconds is a whole number of microseconds (the firmware's clock counts them).
pub fn whole_us(x: f64) -> bool {
    ((x * 1e6) - (x * 1e6).round()).abs() <= 1e-6 * (x * 1e6).abs().max(1.0)
}

/// The `[controller]` table in the top level.
pub const TABLE: Key = Key::of(
    "controller",
    Ty::Table("the robot controller for `flinch hil`"),
    "the robot controller for firmware-in-the-loop runs",
)
.optional("a plain run; `flinch hil` takes --scan-cycle and --tick instead");

/// Scan cycle.
pub const SCAN_CYCLE: Key = Key::number("scan_cycle", "s", Incl(1e-5), Incl(0.1), "robot controller cycles: 10 us to 100 ms (safety PLCs scan in 1-20 ms)", "the robot controller's scan cycle: inputs are sampled once per cycle");
/// Phase of the first sample.
pub const PHASE: Key = Key::number("phase", "of a scan cycle", Incl(0.0), Excl(1.0), "a phase is a fraction of one cycle", "phase of the first sample within a scan cycle");
/// Firmware tick.
pub const FIRMWARE_TICK: Key = Key::number("firmware_tick", "s", Incl(1e-6), Incl(0.01), "the firmware ticks at 1 us to 10 ms", "the firmware's tick period");

/// Brake engagement delay of a category-0 stop.
pub const BRAKE_DELAY: Key = Key::number("brake_delay", "s", Incl(0.0), Incl(1.0), "holding brakes engage in tens of ms (Pilz PRBT 6: 80 ms); a stop category 0 robot stops well within 1 s (ISO 13855 stopping performance)", "category-0 stop (the firmware's escalation output removes drive power): from power removal to the brakes acting; the arm coasts meanwhile (plant/brake.rs)")
    .optional("0.08 s, the Pilz PRBT 6 brake engagement time (plant/brake.rs)");
/// Braking deceleration of a category-0 stop.
pub const BRAKE_DECEL: Key = Key::number("brake_decel", "m/s^2", Excl(0.0), Incl(500.0), "up to about 50 g, the bound of motion.decel", "category-0 stop: the arm's deceleration once its brakes act (plant/brake.rs); a motion.stopping table with category = 0 is used instead when given")
    .optional("5 m/s^2, from the UR5/CB3 category-0 stop of its slowest joint (plant/brake.rs)");

/// The robot's reaction once its controller has seen the stop (issue 26 item 2).
pub const REACTION_TIME: Key = Key::number("reaction_time", "s", Incl(0.0), Incl(1.0), "a robot's reaction to a stop it has read (brake engage, drive delay) takes ms to tens of ms; it is part of motion.dead_time, at most 1 s", "from the controller's scan sample that sees the stop to the start of braking (with motion.stopping: to the stop signal the table starts from): brake engagement, drive delay. `flinch hil` forms its dead time as board latency + the wait for the next scan sample (up to scan_cycle) + reaction_time")
    .optional("motion.dead_time - scan_cycle: the scene's DT read as one scan cycle plus the robot's reaction (0 when DT is shorter than one scan, with a warning)");

/// The keys of `[controller]`.
pub const KEYS: &[Key] = &[SCAN_CYCLE, PHASE, FIRMWARE_TICK, BRAKE_DELAY, BRAKE_DECEL, REACTION_TIME];

/// Reads `[controller]`.
pub(super) fn controller(cx: &mut Ctx, t: &Tab) -> Option<Controller> {
    cx.check_keys(t, KEYS, "");
    let scan_cycle = cx.number(t, &SCAN_CYCLE);
    let phase = cx.number(t, &PHASE);
    let firmware_tick = cx.number(t, &FIRMWARE_TICK);
    if let Some(x) = firmware_tick.filter(|&x| !whole_us(x)) {
        cx.bad(t, FIRMWARE_TICK.name, format!("a whole number of microseconds (the firmware's clock counts them), got {x}"));
        return None;
    }
    let brake_delay = cx.maybe_number(t, &BRAKE_DELAY);
    let brake_decel = cx.maybe_number(t, &BRAKE_DECEL);
    let reaction_time = cx.maybe_number(t, &REACTION_TIME);
    Some(Controller {
        scan_cycle: scan_cycle?,
        phase: phase?,
        firmware_tick: firmware_tick?,
        brake_delay: brake_delay?.unwrap_or(DEFAULT_BRAKE_DELAY_S),
        brake_decel: brake_decel?.unwrap_or(DEFAULT_BRAKE_DECEL_MPS2),
        reaction_time: reaction_time?,
    })
}
